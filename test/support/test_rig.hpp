#pragma once

/// @file
/// The rigs the vision tests share, defined once:
/// - the simulator's default rig after rectification (kRigProjection: 546 px, 0.30 m baseline, 640 x 480) and the
///   rectifier's default region of interest on it (the bottom 248 rows, from row 232);
/// - a plausible calibrated pair with lens distortion and a small rotation between the cameras
///   (distortedIntrinsics, distortedCalibration), for the rectifier and the calibration file.

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::test {

constexpr int kRigWidth = 640;
constexpr int kRigHeight = 480;
constexpr int kRigRoiY0 = 232;     ///< the rectifier's default ROI: round(480 * 0.5) - 8 ...
constexpr int kRigRoiHeight = 248; ///< ... to the bottom row
constexpr vision::RectifiedProjection kRigProjection{546.0, 546.0, 319.5, 239.5, 0.30};

/// The distorted pair's image size, camera matrices and distortion (no extrinsics, no rectification).
inline vision::StereoCalibration distortedIntrinsics()
{
    vision::StereoCalibration c;
    c.imageSize = cv::Size(kRigWidth, kRigHeight);
    c.K1 = (cv::Mat_<double>(3, 3) << 540, 0, 322, 0, 541, 238, 0, 0, 1);
    c.K2 = (cv::Mat_<double>(3, 3) << 545, 0, 318, 0, 544, 243, 0, 0, 1);
    c.D1 = (cv::Mat_<double>(1, 5) << -0.12, 0.05, 0.001, -0.0005, 0);
    c.D2 = (cv::Mat_<double>(1, 5) << -0.10, 0.04, -0.0007, 0.0003, 0);
    return c;
}

/// The distorted pair with its extrinsics (0.12 m baseline, a small rotation) rectified by cv::stereoRectify.
inline vision::StereoCalibration distortedCalibration()
{
    vision::StereoCalibration c = distortedIntrinsics();
    cv::Rodrigues(cv::Vec3d(0.01, -0.02, 0.005), c.R);
    c.T = (cv::Mat_<double>(3, 1) << -0.12, 0.002, 0.001);
    cv::stereoRectify(c.K1, c.D1, c.K2, c.D2, c.imageSize, c.R, c.T, c.R1, c.R2, c.P1, c.P2, c.Q,
                      cv::CALIB_ZERO_DISPARITY, 0.0);
    return c;
}

} // namespace ugv::test
