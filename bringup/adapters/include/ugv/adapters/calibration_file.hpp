#pragma once

/// @file
/// The stereo calibration file: OpenCV FileStorage YAML with `schema_version: 1`, in one of two forms.
///
/// Full form (written by `ugvsense calibrate`): image_width, image_height, K1, D1, K2, D2, R, T, E, F, R1, R2,
/// P1, P2, Q (opencv-matrix, dt d) and the quality figures rms_px, epipolar_px, rectified_dy_px, pairs_used,
/// pairs_rejected.
/// Already-rectified form (cameras that rectify on board, or simulation): `rectified: 1`, image_width,
/// image_height, fx, fy, cx, cy, baseline_m, and `cx_right` when the right camera's principal point is elsewhere
/// (a pair rectified without zero disparity; Middlebury's cx + doffs): the right image is then moved into the left's.
/// Both forms take an optional `mount` map {height_m, pitch_deg, roll_deg}.

#include <cstddef>
#include <string>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::adapters {

inline constexpr int kCalibrationSchemaVersion = 1;
// Physically plausible ranges: anything outside is a damaged or wrong file (a baseline of 1e-300 m passed once and
// gave 53 red sectors at 0.01 m).
inline constexpr double kMinBaselineM = 0.01;     ///< [m]
inline constexpr double kMaxBaselineM = 5.0;      ///< [m]
inline constexpr double kMinFocalPx = 10.0;       ///< [px] a 170 deg lens at 640 px wide is about 56
inline constexpr double kMaxFocalPx = 100000.0;   ///< [px]
inline constexpr double kMinMountHeightM = 0.05;  ///< [m]
inline constexpr double kMaxMountHeightM = 10.0;  ///< [m]
inline constexpr double kMaxMountPitchDeg = 45.0; ///< [deg]
inline constexpr double kMaxMountRollDeg = 30.0;  ///< [deg]
inline constexpr int kMinImageSide = 16;          ///< [px]
inline constexpr int kMaxImageSide = 16384;
inline constexpr std::size_t kMaxCalibrationBytes = 64U * 1024U; ///< a calibration file is about 3 KB       ///< [px]

/// Writes `calib` to `path` (the rectified form when calib.rectified).
/// @return an error naming the path when it cannot be written or the calibration lacks matrices.
/// Thread-safety: reentrant (different paths). RT-safe: no.
Result<void, Error> saveCalibration(const std::string& path, const vision::StereoCalibration& calib);

/// Reads and validates a calibration file. Every error names the file and key, the bad value and the fix. The text is
/// checked before OpenCV parses it (bringup/yaml_guard.hpp: at most 64 KB and 8 levels deep, no integer beyond int32);
/// a key given twice, a number outside its plausible range (the constants above), a matrix R/R1/R2 that is no
/// rotation and a P2 whose baseline is zero or positive are refused.
/// Thread-safety: reentrant. RT-safe: no.
Result<vision::StereoCalibration, Error> loadCalibration(const std::string& path);

/// A checked calibration and the text it was read from (what a recording stores).
struct CalibrationWithText {
    vision::StereoCalibration calibration;
    std::string text;
};

/// As loadCalibration(), keeping the file's text (`recording import --calib`, `record --calib`).
Result<CalibrationWithText, Error> loadCalibrationWithText(const std::string& path);

/// As loadCalibration() on the text of a calibration file (a recording's stored calibration); errors name `where`.
Result<vision::StereoCalibration, Error> parseCalibration(const std::string& text, const std::string& where);

} // namespace ugv::adapters
