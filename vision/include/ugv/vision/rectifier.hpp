#pragma once

/// @file
/// Stereo rectification of the rows the matcher needs, with remap tables computed once.

#include <cstdint>

#include <opencv2/core.hpp>

#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::vision {

struct RectifierConfig {
    /// First row of the obstacle region of interest as a fraction of the height (config roi.top_fraction).
    double roiTopFraction = 0.5;
    /// Rows above the region of interest that are rectified too, so that the matcher's block has context at
    /// its top: ROI = rows [round(height * roiTopFraction) - roiMarginRows, height) [px].
    int roiMarginRows = 8;
    /// Rectify the whole frame instead (visual checks, tools).
    bool fullFrame = false;
};

/// Outcome of Rectifier::rectify; no strings on the frame path.
enum class RectifyStatus : std::uint8_t {
    Ok,
    WrongInputSize,  ///< an input view is not the calibrated image size
    WrongOutputSize, ///< an output view is not roi().width x roi().height
};

/// Rectified pinhole projection shared by both cameras (full-frame coordinates; subtract roi().y from cy for
/// ROI rows).
struct RectifiedProjection {
    double fx = 0.0;        ///< [px]
    double fy = 0.0;        ///< [px]
    double cx = 0.0;        ///< [px]
    double cy = 0.0;        ///< [px]
    double baselineM = 0.0; ///< [m]
};

/// Rectifies the ROI rows of a stereo pair with fixed-point remap tables (CV_16SC2 + CV_16UC1, bilinear)
/// built once in create(); for an already-rectified calibration it copies the ROI rows (identity path). The right
/// image is always rectified into the left's principal point (P2 with P1's cx and cy), so that a disparity is
/// fx B / Z with no offset even for a rectification that keeps them apart (cv::stereoRectify without
/// CALIB_ZERO_DISPARITY; an already-rectified pair with the right camera's cx elsewhere: no identity path then).
/// Thread-safety: thread-bound (rectify() writes the internal buffers). RT-safe: rectify() yes (no allocation,
/// no exception for valid views: sizes are checked before OpenCV runs); create() no.
class Rectifier {
public:
    /// Builds the remap tables for the ROI rows of both cameras and allocates the internal output buffers.
    /// @return the rectifier, or an error for an invalid calibration or ROI margin.
    static Result<Rectifier, Error> create(const StereoCalibration& calib, const RectifierConfig& config);

    /// Rectifies the ROI of a pair into caller-owned buffers.
    /// @param[in] left, right   input images, imageSize() each
    /// @param[out] outLeft, outRight  roi().width x roi().height each; row r holds rectified row roi().y + r
    /// @return Ok, or which size was wrong (outputs untouched).
    RectifyStatus rectify(ConstImageViewU8 left, ConstImageViewU8 right, ImageViewU8 outLeft,
                          ImageViewU8 outRight) noexcept;
    /// As above, into the internal buffers returned by rectifiedLeft()/rectifiedRight().
    RectifyStatus rectify(ConstImageViewU8 left, ConstImageViewU8 right) noexcept;
    /// The left camera alone (the one-camera detector), into the buffer returned by rectifiedLeft(); the same rows
    /// as rectify() gives it.
    RectifyStatus rectifyLeft(ConstImageViewU8 left) noexcept;
    /// The left camera's BGR image (a colour camera, for the one-camera detector) into `out`, roi().width x
    /// roi().height: the same rows and the same fixed-point bilinear tables as the grey path (OpenCV's remap).
    RectifyStatus rectifyLeft(ConstBgrView left, BgrView out) noexcept;

    [[nodiscard]] ConstImageViewU8 rectifiedLeft() const noexcept { return outLeft_.view(); }
    [[nodiscard]] ConstImageViewU8 rectifiedRight() const noexcept { return outRight_.view(); }
    /// Rectified rows in full-frame coordinates [px].
    [[nodiscard]] Rect roi() const noexcept { return roi_; }
    /// Size of the input (and of the full rectified frame) [px].
    [[nodiscard]] cv::Size imageSize() const noexcept { return imageSize_; }
    /// Size of the rectified output, roi() width x height [px].
    [[nodiscard]] cv::Size rectifiedSize() const noexcept { return {roi_.width, roi_.height}; }
    [[nodiscard]] const RectifiedProjection& projection() const noexcept { return projection_; }
    [[nodiscard]] bool identity() const noexcept { return identity_; }

private:
    Rectifier() = default;

    cv::Size imageSize_;
    Rect roi_;
    RectifiedProjection projection_;
    bool identity_ = false;
    cv::Mat mapLeftXY_, mapLeftFrac_;   ///< CV_16SC2 / CV_16UC1, roi height rows
    cv::Mat mapRightXY_, mapRightFrac_; ///< same for the right camera
    Image<std::uint8_t> outLeft_;
    Image<std::uint8_t> outRight_;
};

} // namespace ugv::vision
