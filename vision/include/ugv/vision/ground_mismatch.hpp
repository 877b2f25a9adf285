#pragma once

/// @file
/// Ground mismatch: where the ground-plane warp fails to explain the right image, and on which side of the
/// ground the scene lies there.
///
/// Edges are taken in the RIGHT image: the comparison happens on the right image's grid (the warped left W
/// lives there), so an edge in R guarantees texture inside the compared window without warping an edge map.
/// Only x gradients count (Sobel x, non-maximum suppressed along x): a horizontal edge does not constrain a
/// shift along the epipolar line, so it cannot reveal a disparity mismatch.
///
/// At each edge pixel the zero-mean SAD (ZSAD: immune to the cameras' gain/offset difference) of a window of R
/// against the same window of W decides ground (small) or not ground. At a mismatch, the same cost is
/// evaluated against the left image shifted by integer residual disparities r in [residualMin, residualMax]
/// around d_g (same sub-pixel weights as the warp); the best r gives the sign: r > 0 is closer than the ground
/// (larger disparity) = above ground (positive obstacle), r < 0 is below ground (negative obstacle: trench,
/// hole, drop-off). A best cost not clearly below the ground cost (occlusion, repeated texture) leaves the sign
/// unknown (Unsure).
///
/// ROI convention: images hold full-frame rows [y0, y0 + height) (see ground_warp.hpp).

#include <cstdint>
#include <span>

#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/ground_warp.hpp"

namespace ugv::vision {

/// Values of GroundMismatch::labels().
enum class GroundLabel : std::uint8_t {
    Ground = 0,      ///< edge pixel explained by the ground model
    Positive = 1,    ///< above the ground (residual disparity > 0)
    Negative = 2,    ///< below the ground (residual disparity < 0)
    Unsure = 3,      ///< not ground, sign undecided
    NotTested = 255, ///< no edge (no texture), or the window leaves the valid warp
};

struct GroundMismatchConfig {
    int width = 640;                ///< ROI width [px]
    int height = 248;               ///< ROI height [px]
    int edgeThreshold = 40;         ///< minimum |Sobel x| (3x3; 8 per grey level/px of slope)
    int windowHalfWidth = 3;        ///< window (2 hw + 1) x (2 hh + 1) [px]; 7 x 3 by default
    int windowHalfHeight = 1;       ///< [px]
    float mismatchThreshold = 6.0F; ///< mean ZSAD per window pixel above which a pixel is not ground [grey]
    int residualMin = -16;          ///< residual disparity search range [px], residualMin < 0 < residualMax
    int residualMax = 48;           ///< [px] (an obstacle's top at the ROI's top row can be ~fB/Z above d_g)
    float signRatio = 0.7F;         ///< a sign needs best cost < signRatio * ground cost
};

/// Pixel counts of the last run().
struct GroundMismatchCounts {
    int tested = 0; ///< edge pixels compared
    int ground = 0;
    int positive = 0;
    int negative = 0;
    int unsure = 0;
};

enum class GroundMismatchStatus : std::uint8_t {
    Ok,
    SizeMismatch, ///< an input is not the configured size, or spans too short
    InvalidPlane, ///< the plane is not finite or too steep (see kMaxWarpSlope)
};

/// Thread-safety: thread-bound (run() writes the internal buffers). RT-safe: run() yes; create() no.
class GroundMismatch {
public:
    /// Largest window: (2 hw + 1) (2 hh + 1) <= kMaxWindowPixels.
    static constexpr int kMaxWindowPixels = 81;

    /// Allocates the label, residual and gradient buffers.
    /// @return the stage, or an error naming the invalid config field.
    static Result<GroundMismatch, Error> create(const GroundMismatchConfig& config);

    /// Labels the ROI.
    /// @param[in] left    rectified left ROI (residual search source)
    /// @param[in] right   rectified right ROI
    /// @param[in] warped  warpGround(left, plane, y0) output, with its spans
    /// @param[in] plane   the ground model the warp used [px]; @param[in] y0 full-frame row of ROI row 0 [px]
    /// @return Ok, or why the buffers were not written.
    GroundMismatchStatus run(ConstImageViewU8 left, ConstImageViewU8 right, ConstImageViewU8 warped,
                             std::span<const WarpSpan> spans, const DisparityPlane& plane, int y0) noexcept;

    /// The scalar reference of run(): the same algorithm and arithmetic with the residual search one disparity at a
    /// time (run() evaluates 16 residuals per universal-intrinsics step). Labels, residuals and counts are
    /// bit-identical to run()'s (tests and benchmarks).
    /// Thread-safety: thread-bound. RT-safe: yes.
    GroundMismatchStatus runReference(ConstImageViewU8 left, ConstImageViewU8 right, ConstImageViewU8 warped,
                                      std::span<const WarpSpan> spans, const DisparityPlane& plane, int y0) noexcept;

    /// GroundLabel per ROI pixel of the last run.
    [[nodiscard]] ConstImageViewU8 labels() const noexcept { return labels_.view(); }
    /// Best residual disparity [px] at Positive/Negative/Unsure pixels, 0 elsewhere.
    [[nodiscard]] ImageView<const std::int8_t> residuals() const noexcept { return residuals_.view(); }
    [[nodiscard]] const GroundMismatchCounts& counts() const noexcept { return counts_; }
    [[nodiscard]] const GroundMismatchConfig& config() const noexcept { return config_; }

private:
    explicit GroundMismatch(const GroundMismatchConfig& config);
    template <bool kSimd>
    GroundMismatchStatus runImpl(ConstImageViewU8 left, ConstImageViewU8 right, ConstImageViewU8 warped,
                                 std::span<const WarpSpan> spans, const DisparityPlane& plane, int y0) noexcept;
    /// Every pixel NotTested with residual 0, and gradient_ from `right`.
    void resetAndGradient(ConstImageViewU8 right) noexcept;

    GroundMismatchConfig config_;
    Image<std::uint8_t> labels_;
    Image<std::int8_t> residuals_;
    Image<std::int16_t> gradient_; ///< |Sobel x| of the right ROI
    GroundMismatchCounts counts_;
};

} // namespace ugv::vision
