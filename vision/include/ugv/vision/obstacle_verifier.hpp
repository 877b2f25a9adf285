#pragma once

/// @file
/// Obstacle hypothesis test: does the matcher's disparity explain the images better than the ground does?
///
/// Semi-global matching fills weakly textured or aliased regions (far ground near the horizon, the ground seen
/// through a doorway next to a wall) with the disparity of a neighbouring strong surface. Those pixels look like
/// a nearby obstacle to the sector builder (a blob at the horizon rows with a wall's disparity is a "0.6 m tall
/// object at 1.4 m"). The test re-matches each pixel whose disparity is off the ground model by more than
/// `minResidualPx`, with a zero-mean SAD window (immune to the cameras' gain and offset difference), once at the
/// matcher's disparity and once at the ground disparity d_g(x, y), both sub-pixel (1/16 px, linear along x).
/// The obstacle hypothesis stands when cost(d) < acceptRatio * cost(d_g); otherwise the ground explains the
/// window at least as well and the pixel is marked invalid (neither obstacle nor ground support, so it can never
/// make a sector Clear). A window with too little contrast to decide is invalidated too: contrastNoiseFactor times the
/// left image's noise (ImageNoise, learnt per frame), between minContrastBelow and minContrast (minContrastBelow
/// where the disparity is below the ground's); its disparity is the
/// matcher's guess (a textureless obstacle is then seen through its textured edges, and its sectors cannot turn
/// Clear because the ground behind it is not seen; see SectorBuilderConfig::clearRangeM). So is a window the obstacle
/// wins, or a drop the re-match below finds, whose texture runs nearly along the rows (maxSlidePerRow: such a texture
/// cannot place a match along x).
/// Windows that leave the image keep the matcher's disparity.
///
/// Input and output disparity: CV_16S fixed point as cv::StereoSGBM (value / 16 = disparity [px]), invalid < 0.
/// ROI convention: the images hold full-frame rows [y0, y0 + height) and the ground plane is in full-frame
/// coordinates (see ground_warp.hpp).

#include <cstdint>
#include <utility>

#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/image_noise.hpp"

namespace ugv::vision {

struct ObstacleVerifierConfig {
    int width = 640;            ///< ROI width [px]
    int height = 248;           ///< ROI height [px]
    int windowHalfWidth = 3;    ///< window (2 hw + 1) x (2 hh + 1) [px]; 7 x 5 by default
    int windowHalfHeight = 2;   ///< [px]
    float minResidualPx = 1.0F; ///< pixels with |d - d_g| at or below this are not tested [px]
    float acceptRatio = 0.85F;  ///< the obstacle stands when cost(d) < acceptRatio * cost(d_g)
    /// The window contrast, mean |L - mean(L)|, below which the test cannot decide is this many times the left
    /// image's noise sigma (ImageNoise, learnt per frame: a contrast is texture only against the camera's noise) ...
    /// 2.5: the simulator's noise of 1.5 grey reads 1.2 on its floor, so 3 grey there, where a fixed 3 was set; a
    /// fixed 3 invalidated shaded hedges and verges on KITTI (noise read 0.40..0.64 grey): 12 of 33 obstacle
    /// sectors missed on 000007_10, 8 with this rule.
    float contrastNoiseFactor = 2.5F;
    float minContrast = 3.0F; ///< ... at most this [grey] (a noisy camera must not need more texture than this) ...
    /// The same for a disparity below the ground's (a drop): the far wall of a trench is in shadow and weakly
    /// textured, but the ratio test still decides there (the fill-in this guards against is a strong
    /// surface's larger disparity spreading over the ground: above it) [grey]
    float minContrastBelow = 1.0F; ///< ... and at least this, above the ground too
    /// The aperture: a window whose match moves along x by more than this many columns per row that its texture's
    /// contour moves between the two images is invalidated off the ground (undecided, like one without contrast).
    /// That slide is |sum Ix Iy| / sum Ix^2 over the window (Ix, Iy: the left image's differences along x and y):
    /// an edge of slope s (rows per column) slides 1 / s columns per row; texture that runs across the rows (a
    /// post's edges, a face's own texture) and an edge exactly along the rows (a kerb's top seen square on) slide
    /// none. Contours do move between the images, by a fraction of a row: the cameras' different gain on a blurred or
    /// clipped edge, a rectification off by a fraction of a row. With 1/4 row and the 1 px residual tested
    /// (minResidualPx), edges flatter than slope 1/4 can fake an obstacle: on KITTI 000013_10 at half resolution a
    /// clipped stop line of slope about 1/8 matched 3-6 px above the road across 27 sectors. The below-ground
    /// re-match (belowHalfWidth) applies it too: a drop it finds on such a texture is invalid (KITTI at JPEG quality
    /// 50: 2 false drop sectors). 0 disables.
    float maxSlidePerRow = 4.0F;
    /// Below the ground the matcher's disparity is re-estimated, not only tested. The visible part of a drop at
    /// range is a strip a few rows high (a 1 m trench at 9 m: 4 rows, 0.2..1.3 px below d_g), which a 5-row
    /// window straddles: the matcher returns no or a wrong disparity there (2 px low), and the ground wins the
    /// 7 x 5 test. So a pixel below the ground is matched again with a flat window (2 bhw + 1) x (2 bhh + 1) over
    /// [d - 1 px, min(d + 3 px, d_g - minResidualPx / 2)], coarse (1/2 px) then fine (1/8 px); the best disparity
    /// replaces the matcher's when its cost < acceptRatio * the ground's best cost within d_g +- 1/2 px, else the pixel
    /// is invalid. The ground gets a search of its own because the least of many noisy costs beats one cost by chance
    /// on weak texture. Empty simulator ground, 20 frames per texture, false drop sectors per frame with the ground at
    /// d_g alone / with its search: painted floor 1.9 / 0.35, asphalt, grass and gravel 0.22 / 0.017.
    int belowHalfWidth = 7;  ///< [px] 15 x 3 by default
    int belowHalfHeight = 1; ///< [px]
    /// Only where the ground is beyond ~3 m: d_g at most this [px] (55 px with the default rig, fx B = 164 px m).
    /// Nearer, a drop's wall is tall enough for the matcher and the 7 x 5 test (the re-match still halves the
    /// range error of holes at 3-6 m, hence not 5 m). Re-matching every below-ground pixel cost up to 40 ms more
    /// on some frames of the default course; with this bound the run's detect p99 is 56 ms against 45 ms without
    /// the re-match (`toolchain/host.sh run`).
    float refineMaxGroundPx = 55.0F; ///< ObstacleDetector sets it from the rig (DetectorConfig::refineMinRangeM)
    /// The window costs with universal intrinsics (obstacle_verifier.simd.hpp, the same integers); false: the scalar
    /// reference (tests).
    bool simd = true;
};

enum class VerifyStatus : std::uint8_t {
    Ok,
    WrongInputSize, ///< an image or the disparity is not width x height: output all invalid
};

/// Pixel counts of the last run().
struct VerifyCounts {
    int tested = 0;    ///< off-ground pixels re-matched
    int rejected = 0;  ///< the ground explained them at least as well: invalidated
    int refined = 0;   ///< below the ground, re-estimated and kept
    int undecided = 0; ///< too little contrast or a texture along the rows (invalidated), or the window leaves the
                       ///< image (kept)
};

/// Thread-safety: thread-bound (run() writes the internal buffer). RT-safe: run() yes (no allocation, no
/// exception); create() no.
class ObstacleVerifier {
public:
    /// @return the verifier with its output buffer allocated, or an error naming the invalid field.
    static Result<ObstacleVerifier, Error> create(const ObstacleVerifierConfig& config);

    /// Tests every off-ground pixel of `disparity16`.
    /// @param[in] left, right   rectified ROI images, width x height each
    /// @param[in] disparity16   the matcher's ROI disparity (x16, invalid < 0), width x height
    /// @param[in] ground        ground disparity plane of this frame, full-frame coordinates
    /// @param[in] y0            full-frame row of the ROI's first row [px]
    /// @return Ok, or WrongInputSize (output all invalid).
    VerifyStatus run(ConstImageViewU8 left, ConstImageViewU8 right, ImageView<const std::int16_t> disparity16,
                     const DisparityPlane& ground, int y0) noexcept;

    /// The verified disparity of the last run (x16, invalid < 0), width x height.
    [[nodiscard]] ImageView<const std::int16_t> disparity() const noexcept { return out_.view(); }
    [[nodiscard]] const VerifyCounts& counts() const noexcept { return counts_; }
    /// The left image's noise sigma of the last run [grey] (ImageNoise) and the contrast it required [grey].
    [[nodiscard]] float noiseSigma() const noexcept { return noiseSigma_; }
    [[nodiscard]] float requiredContrast() const noexcept { return requiredContrast_; }
    [[nodiscard]] const ObstacleVerifierConfig& config() const noexcept { return config_; }

private:
    ObstacleVerifier(const ObstacleVerifierConfig& config, ImageNoise noise)
        : config_(config), out_(config.width, config.height), noise_(std::move(noise))
    {
    }
    /// The below-ground re-estimate of pixel (x, v) (see belowHalfWidth): the new disparity x16, or invalid.
    std::int16_t refineBelow(ConstImageViewU8 left, ConstImageViewU8 right, int x, int v, int d16, int dg16) noexcept;

    ObstacleVerifierConfig config_;
    Image<std::int16_t> out_;
    VerifyCounts counts_;
    ImageNoise noise_;
    float noiseSigma_ = 0.0F;
    float requiredContrast_ = 0.0F;
};

} // namespace ugv::vision
