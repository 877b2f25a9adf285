#pragma once

/// @file
/// The sensor noise of a grey image, learnt from the image itself, per frame.
///
/// Immerkær's operator (J. Immerkær, "Fast Noise Variance Estimation", CVIU 64(2), 1996): the 3 x 3 mask
/// [1 -2 1; -2 4 -2; 1 -2 1] is the difference of two Laplacians, blind to a local plane of brightness, and on
/// Gaussian noise of sigma its response has mean |r| = 6 sigma sqrt(2 / pi). Texture and edges add to a region's
/// response, never take from it, so the noise is read where the image is flattest: sigma of each 8 x 8 block, the
/// `quantile` of the blocks. Blocks with a clipped pixel (0 or 255: sky, a saturated pavement, black shadow) carry
/// no noise and are left out. On the simulator's images the 10 % quantile reads 0.8..0.95 of the noise it adds
/// (0.5, 1.5 and 3 grey levels on its floor texture); on KITTI's street frames it reads 0.40..0.64 grey.
///
/// Thread-safety: thread-bound (estimate() writes the block buffer). RT-safe: estimate() yes (no allocation, no
/// exception); create() no.

#include <cstdint>
#include <vector>

#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::vision {

class ImageNoise {
public:
    static constexpr int kBlock = 8;

    /// @return the estimator for images up to width x height, or an error when quantile is not in [0, 1].
    static Result<ImageNoise, Error> create(int width, int height, float quantile = 0.10F);

    /// @return the noise sigma of `image` [grey levels]; 0 when no block is unclipped (or the image is smaller than
    ///         one block plus the mask's border, or larger than create()'s size).
    [[nodiscard]] float estimate(ConstImageViewU8 image) noexcept;
    /// estimate() by the scalar reference (tests): the same value, bit for bit.
    [[nodiscard]] float estimateReference(ConstImageViewU8 image) noexcept;

private:
    ImageNoise(int width, int height, float quantile);
    [[nodiscard]] float estimateImpl(ConstImageViewU8 image, bool useSimd) noexcept;
    /// sums_ and clipped_ of the bw x bh blocks; the SIMD path (universal intrinsics) gives the same integers.
    void blockSumsReference(ConstImageViewU8 image, int bw, int bh) noexcept;
    void blockSumsSimd(ConstImageViewU8 image, int bw, int bh) noexcept;

    int width_ = 0;
    int height_ = 0;
    float quantile_ = 0.10F;
    std::vector<int> sums_;             ///< per block: sum of |r| over its pixels
    std::vector<std::uint8_t> clipped_; ///< per block: a pixel at 0 or 255
    std::vector<int> unclipped_;        ///< the unclipped blocks' sums (for the quantile)
};

} // namespace ugv::vision
