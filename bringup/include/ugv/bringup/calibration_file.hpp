#pragma once

/// @file
/// The stereo calibration file: OpenCV FileStorage YAML with `schema_version: 1`, in one of two forms.
///
/// Full form (written by `ugvsense calibrate`): image_width, image_height, K1, D1, K2, D2, R, T, E, F, R1, R2,
/// P1, P2, Q (opencv-matrix, dt d) and the quality figures rms_px, epipolar_px, rectified_dy_px, pairs_used,
/// pairs_rejected.
/// Already-rectified form (cameras that rectify on board, or simulation): `rectified: 1`, image_width,
/// image_height, fx, fy, cx, cy, baseline_m.
/// Both forms take an optional `mount` map {height_m, pitch_deg, roll_deg}.

#include <string>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::bringup {

inline constexpr int kCalibrationSchemaVersion = 1;
inline constexpr double kMaxBaselineM = 5.0;      ///< [m]
inline constexpr double kMaxMountHeightM = 10.0;  ///< [m]
inline constexpr double kMaxMountPitchDeg = 45.0; ///< [deg]
inline constexpr double kMaxMountRollDeg = 30.0;  ///< [deg]
inline constexpr int kMaxImageSide = 16384;       ///< [px]

/// Writes `calib` to `path` (the rectified form when calib.rectified).
/// @return an error naming the path when it cannot be written or the calibration lacks matrices.
/// Thread-safety: reentrant (different paths). RT-safe: no.
Result<void, Error> saveCalibration(const std::string& path, const vision::StereoCalibration& calib);

/// Reads and validates a calibration file. Every error names the file and key, the bad value and the fix.
/// Thread-safety: reentrant. RT-safe: no.
Result<vision::StereoCalibration, Error> loadCalibration(const std::string& path);

/// As loadCalibration() on the text of a calibration file (a recording's stored calibration); errors name `where`.
Result<vision::StereoCalibration, Error> parseCalibration(const std::string& text, const std::string& where);

} // namespace ugv::bringup
