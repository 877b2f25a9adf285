#pragma once

/// @file
/// Ground-plane warp: the left image resampled onto the right image's pixel grid through the ground's
/// disparity model, W(x, y) = L(x + d_g, y), so that wherever the scene is flat ground W equals R.
///
/// The model d_g(x, y) = a x + b y + c (DisparityPlane) is the disparity of the LEFT pixel (x, y). A right pixel
/// xr sees the left pixel xl = xr + d_g(xl, y); for a plane this solves exactly to
/// xl = (xr + b y + c) / (1 - a), which the warp uses per pixel (roll makes a != 0, so d_g varies along a row).
/// Rows are rectified, so the interpolation is along x only: bilinear with kWarpFracBits fixed-point weights,
/// as cv::remap's INTER_LINEAR. A pixel is valid when its whole 2-tap support lies inside the left row; the
/// valid pixels of a row form one interval (the mapping is increasing in x), returned as a WarpSpan. Invalid
/// pixels are written as 0.
///
/// ROI convention: the images hold full-frame rows [y0, y0 + height); d_g is evaluated at full-frame rows.
///
/// Thread-safety: reentrant (pure functions on caller buffers). RT-safe: yes (no allocation, no exceptions).

#include <cstdint>
#include <span>

#include "ugv/platform/image_view.hpp"
#include "ugv/vision/ground_plane.hpp"

namespace ugv::vision {

/// Fractional bits of the sub-pixel source coordinate (as OpenCV's INTER_BITS).
inline constexpr int kWarpFracBits = 5;
inline constexpr int kWarpFracOne = 1 << kWarpFracBits;

/// Valid columns [begin, end) of one warped row [px]; begin == end when none.
struct WarpSpan {
    int begin = 0;
    int end = 0;
};

enum class GroundWarpStatus : std::uint8_t {
    Ok,
    SizeMismatch, ///< left and warped differ in size, or spans.size() < warped.height()
    InvalidPlane, ///< a, b or c not finite, or |a| > kMaxWarpSlope (outputs untouched)
};

/// Largest |a| accepted [px/px]; real mounts give |a| < 0.05 (B/h * sin(roll)).
inline constexpr double kMaxWarpSlope = 0.5;

/// Source-coordinate mapping of one row: left x = scale * xr + offset [px] (float, as the kernels use it).
struct WarpRowMap {
    float scale = 1.0F;
    float offset = 0.0F;
};

/// The mapping of full-frame row `yFull` for `plane` (see the file comment).
/// Thread-safety: reentrant. RT-safe: yes.
[[nodiscard]] WarpRowMap warpRowMap(const DisparityPlane& plane, int yFull) noexcept;

/// The fixed-point source coordinate round(32 * (scale * x + offset)) that both kernels use; x0 = s >> 5 and
/// the weight of x0 + 1 is s & 31. Callers must keep |offset| and x small enough for int (warp does).
/// Thread-safety: reentrant. RT-safe: yes.
[[nodiscard]] int warpSourceFixed(int x, const WarpRowMap& map) noexcept;

/// Warps `left` onto the right image grid with the universal-intrinsics kernel (128-bit) and a scalar tail.
/// @param[in]  left    rectified left ROI, full-frame rows [y0, y0 + height)
/// @param[in]  plane   ground disparity model in full-frame coordinates [px]
/// @param[in]  y0      full-frame row of the ROI's first row [px]
/// @param[out] warped  same size as left; invalid pixels 0
/// @param[out] spans   at least warped.height() entries; spans[r] = valid columns of row r
/// @return Ok, or why nothing was written.
/// Thread-safety: reentrant. RT-safe: yes.
GroundWarpStatus warpGround(ConstImageViewU8 left, const DisparityPlane& plane, int y0, ImageViewU8 warped,
                            std::span<WarpSpan> spans) noexcept;

/// The scalar reference of warpGround(): the same arithmetic, one pixel at a time (tests and benchmarks).
/// Thread-safety: reentrant. RT-safe: yes.
GroundWarpStatus warpGroundReference(ConstImageViewU8 left, const DisparityPlane& plane, int y0, ImageViewU8 warped,
                                     std::span<WarpSpan> spans) noexcept;

} // namespace ugv::vision
