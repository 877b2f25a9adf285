#pragma once

/// @file
/// The calibration of a stereo rig as a plain value: intrinsics, extrinsics, rectification, quality figures
/// and the optional mount pose. Produced by calibrateStereo() (or read from a file by bringup/), consumed by
/// Rectifier and the later depth stages.

#include <optional>

#include <opencv2/core.hpp>

namespace ugv::vision {

/// Where the rig sits on the robot.
struct Mount {
    double heightM = 0.0;  ///< camera height above ground [m]
    double pitchDeg = 0.0; ///< pitch, positive looking down [deg]
    double rollDeg = 0.0;  ///< roll [deg]
};

/// Intrinsics, extrinsics and rectification of a stereo pair, all matrices CV_64F in OpenCV's conventions
/// (X_right = R * X_left + T; P1/P2/Q as from cv::stereoRectify).
/// `rectified == true` is the already-rectified form: the images need no remapping but, when the right camera's
/// principal point lies elsewhere (cxRight), a shift; K1, K2 = the rectified intrinsics (K2 with cxRight), D1 = D2 =
/// 0, R = R1 = R2 = I, and P1/P2/Q are derived from fx, fy, cx, cy, cxRight and the baseline.
/// Thread-safety: value type (cv::Mat shares its data on copy: clone before mutating a shared copy).
/// RT-safe: no (copying allocates); read it at init.
struct StereoCalibration {
    cv::Size imageSize;         ///< [px]
    cv::Mat K1, D1, K2, D2;     ///< camera matrices 3x3 and distortion 1xN (N in 4,5,8,12,14)
    cv::Mat R, T, E, F;         ///< 3x3, 3x1 [m], 3x3, 3x3
    cv::Mat R1, R2, P1, P2, Q;  ///< 3x3, 3x3, 3x4, 3x4, 4x4
    double rmsPx = 0.0;         ///< RMS reprojection error over both cameras [px]
    double epipolarPx = 0.0;    ///< mean epipolar error (sum of both directions per corner) [px]
    double rectifiedDyPx = 0.0; ///< mean |y_left - y_right| of corners after rectification [px]
    int pairsUsed = 0;          ///< image pairs in the final calibration
    int pairsRejected = 0;      ///< pairs rejected (no board, size mismatch, outlier, ...)
    bool rectified = false;     ///< already-rectified form (see above)
    std::optional<Mount> mount; ///< rig mount pose, when known

    /// @return |T| (the distance between the optical centres) [m].
    [[nodiscard]] double baselineM() const;
    /// @return focal length of the rectified pair, P1(0,0) [px].
    [[nodiscard]] double rectifiedFocalPx() const;
};

/// Builds the already-rectified form from its five numbers (see StereoCalibration).
/// @param[in] imageSize  image size [px]
/// @param[in] fx, fy     focal lengths [px]; @param[in] cx, cy principal point [px]
/// @param[in] baselineM  distance between the optical centres [m], > 0
/// @return the filled calibration; callers validate the numbers first (bringup/calibration_file does).
/// Thread-safety: reentrant. RT-safe: no.
StereoCalibration makeRectifiedCalibration(cv::Size imageSize, double fx, double fy, double cx, double cy,
                                           double baselineM);
/// The same with the right camera's principal point `cxRight` columns from the left's `cx` (a pair rectified without
/// zero disparity, Middlebury's `doffs` = cxRight - cx): K2 and P2 carry it, and Rectifier moves the right image
/// into the left's principal point, so that disparities are fx B / Z.
StereoCalibration makeRectifiedCalibration(cv::Size imageSize, double fx, double fy, double cx, double cy,
                                           double baselineM, double cxRight);

} // namespace ugv::vision
