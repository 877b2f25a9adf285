#pragma once

/// @file
/// Stereo calibration from chessboard image pairs: corner detection, per-camera and joint stereo calibration,
/// outlier-pair rejection, rectification and the quality figures. A pure function of the images (no file I/O).

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::vision {

/// One left/right chessboard pair. Images are 8-bit single-channel (grey).
struct CalibrationPair {
    std::string name; ///< shown in reports, e.g. "left01.jpg/right01.jpg"
    cv::Mat left;
    cv::Mat right;
};

struct CalibratorConfig {
    cv::Size innerCorners{9, 6}; ///< inner corners per row and column
    double squareM = 0.025;      ///< square side [m]
    int minPairs = 3;            ///< fewer usable pairs than this is an error
    double outlierFactor = 2.0;  ///< a pair is an outlier when its error > factor * median ...
    double outlierFloorPx = 0.3; ///< ... and > this absolute floor [px]
    int maxOutlierRounds = 3;    ///< drop-and-recalibrate rounds at most
};

/// Reprojection error of one pair in the final calibration.
struct PairError {
    std::string name;
    double errorPx = 0.0; ///< RMS over the left and right corners of the pair [px]
};

/// A pair left out of the calibration, with the reason ("board not found in left image", "size mismatch ...",
/// "outlier: error 2.10 px > 2 x median 0.40 px").
struct RejectedPair {
    std::string name;
    std::string reason;
};

struct CalibrationReport {
    StereoCalibration calibration;  ///< quality figures and pair counts filled in
    std::vector<PairError> perPair; ///< pairs used, in input order
    std::vector<RejectedPair> rejected;
    double rmsBeforeOutliersPx = 0.0; ///< RMS of the first stereo calibration, before outlier rounds [px]
    int outlierRounds = 0;            ///< recalibrations done after dropping outliers
};

/// Calibrates a stereo rig from chessboard pairs.
/// Steps: findChessboardCorners (adaptive threshold + normalise; findChessboardCornersSB as fallback) and
/// cornerSubPix (11x11); per-camera calibrateCamera for a start; stereoCalibrate refining intrinsics and
/// extrinsics jointly (CALIB_USE_INTRINSIC_GUESS, 5-coefficient model); while some pair's error exceeds
/// outlierFactor x median and outlierFloorPx, drop the worst and recalibrate if that lowers the RMS;
/// stereoRectify with CALIB_ZERO_DISPARITY and alpha 0 (only valid pixels, so the matcher never sees the
/// black border of the remap).
/// @param[in] pairs   image pairs; unusable ones are reported in `rejected`, not errors
/// @param[in] config  board geometry and outlier rule
/// @return the report, or an error when the config is invalid, fewer than minPairs pairs are usable or
///         OpenCV fails.
/// Thread-safety: reentrant. RT-safe: no (init-time tool).
Result<CalibrationReport, Error> calibrateStereo(const std::vector<CalibrationPair>& pairs,
                                                 const CalibratorConfig& config);

/// Finds and refines the inner chessboard corners in a grey image.
/// @return true and the corners (row-major, innerCorners.area() points) when the whole board is found.
/// Thread-safety: reentrant. RT-safe: no.
bool findBoardCorners(const cv::Mat& grey, cv::Size innerCorners, std::vector<cv::Point2f>& corners);

/// Mean |y_left - y_right| [px] of corresponding points after undistorting and rectifying them with
/// (K1, D1, R1, P1) and (K2, D2, R2, P2). Thread-safety: reentrant. RT-safe: no.
double meanRectifiedDy(const StereoCalibration& calib, const std::vector<std::vector<cv::Point2f>>& left,
                       const std::vector<std::vector<cv::Point2f>>& right);

} // namespace ugv::vision
