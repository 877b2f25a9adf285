#include "ugv/vision/image_noise.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/core/hal/intrin.hpp>

#include "simd_shim.hpp"

namespace ugv::vision {
namespace {

int blocksAlong(int pixels)
{
    return std::max(0, (pixels - 2) / ImageNoise::kBlock); // the mask needs a pixel's neighbours: no border rows
}

} // namespace

Result<ImageNoise, Error> ImageNoise::create(int width, int height, float quantile)
{
    if (!(quantile >= 0.0F && quantile <= 1.0F) || width < 0 || height < 0) {
        return Unexpected(Error{"ImageNoise",
                                "quantile " + std::to_string(quantile) + " and size " + std::to_string(width) + "x" +
                                    std::to_string(height),
                                "the quantile must be in [0, 1] and the size non-negative"});
    }
    return ImageNoise(width, height, quantile);
}

ImageNoise::ImageNoise(int width, int height, float quantile)
    : width_(width), height_(height), quantile_(quantile),
      sums_(static_cast<std::size_t>(blocksAlong(width) * blocksAlong(height))), clipped_(sums_.size()),
      unclipped_(sums_.size())
{
}

float ImageNoise::estimate(ConstImageViewU8 image) noexcept
{
    return estimateImpl(image, true);
}

float ImageNoise::estimateReference(ConstImageViewU8 image) noexcept
{
    return estimateImpl(image, false);
}

void ImageNoise::blockSumsReference(ConstImageViewU8 image, int bw, int bh) noexcept
{
    const auto blocks = static_cast<std::size_t>(bw * bh);
    std::fill(sums_.begin(), sums_.begin() + static_cast<std::ptrdiff_t>(blocks), 0);
    std::fill(clipped_.begin(), clipped_.begin() + static_cast<std::ptrdiff_t>(blocks), std::uint8_t{0});
    for (int v = 1; v < 1 + bh * kBlock; ++v) {
        const std::uint8_t* a = image.row(v - 1);
        const std::uint8_t* b = image.row(v);
        const std::uint8_t* c = image.row(v + 1);
        const auto rowBlocks = static_cast<std::size_t>((v - 1) / kBlock * bw);
        for (int k = 0; k < bw; ++k) {
            int sum = 0;
            bool clipped = false;
            for (int u = 1 + k * kBlock; u < 1 + (k + 1) * kBlock; ++u) {
                const int r = (a[u - 1] - 2 * a[u] + a[u + 1]) - 2 * (b[u - 1] - 2 * b[u] + b[u + 1]) +
                              (c[u - 1] - 2 * c[u] + c[u + 1]);
                sum += std::abs(r);
                clipped = clipped || b[u] == 0U || b[u] == 255U;
            }
            const std::size_t block = rowBlocks + static_cast<std::size_t>(k);
            sums_[block] += sum;
            clipped_[block] = static_cast<std::uint8_t>(clipped_[block] != 0U || clipped);
        }
    }
}

#if CV_SIMD128
void ImageNoise::blockSumsSimd(ConstImageViewU8 image, int bw, int bh) noexcept
{
    // One block row of 8 pixels is one vector of 16-bit lanes: r in [-2040, 2040], |r| summed over the block's 8 rows
    // per lane (<= 16320), then over the lanes in 32 bits. The same integers as the reference.
    using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
    static_assert(kBlock == 8, "one block row is one v_int16x8");
    const auto secondDifference = [](const std::uint8_t* p) {
        const v_int16x8 left = v_reinterpret_as_s16(v_load_expand(p));
        const v_int16x8 centre = v_reinterpret_as_s16(v_load_expand(p + 1));
        const v_int16x8 right = v_reinterpret_as_s16(v_load_expand(p + 2));
        return simd::v_sub(simd::v_add(left, right), simd::v_add(centre, centre));
    };
    const v_uint16x8 black = v_setzero_u16();
    const v_uint16x8 white = v_setall_u16(255);
    for (int by = 0; by < bh; ++by) {
        for (int k = 0; k < bw; ++k) {
            v_uint16x8 sum = v_setzero_u16();
            v_uint16x8 clipped = v_setzero_u16();
            for (int v = 1 + by * kBlock; v < 1 + (by + 1) * kBlock; ++v) {
                const int u0 = k * kBlock; // the first pixel's left neighbour
                const v_int16x8 mid = secondDifference(image.row(v) + u0);
                const v_int16x8 r =
                    simd::v_add(simd::v_sub(secondDifference(image.row(v - 1) + u0), simd::v_add(mid, mid)),
                                secondDifference(image.row(v + 1) + u0));
                sum = simd::v_add(sum, v_abs(r));
                const v_uint16x8 centre = v_load_expand(image.row(v) + u0 + 1);
                clipped = simd::v_or(clipped, simd::v_or(simd::v_eq(centre, black), simd::v_eq(centre, white)));
            }
            const auto block = static_cast<std::size_t>(by * bw + k);
            sums_[block] = static_cast<int>(v_reduce_sum(sum));
            clipped_[block] = static_cast<std::uint8_t>(v_check_any(clipped) ? 1U : 0U);
        }
    }
}
#endif

float ImageNoise::estimateImpl(ConstImageViewU8 image, bool useSimd) noexcept
{
    if (image.data() == nullptr || image.width() > width_ || image.height() > height_) {
        return 0.0F;
    }
    const int bw = blocksAlong(image.width());
    const int bh = blocksAlong(image.height());
    const auto blocks = static_cast<std::size_t>(bw * bh);
#if CV_SIMD128
    if (useSimd) {
        blockSumsSimd(image, bw, bh);
    } else {
        blockSumsReference(image, bw, bh);
    }
#else
    static_cast<void>(useSimd);
    blockSumsReference(image, bw, bh);
#endif
    std::size_t n = 0;
    for (std::size_t k = 0; k < blocks; ++k) {
        if (clipped_[k] == 0U) {
            unclipped_[n++] = sums_[k];
        }
    }
    if (n == 0) {
        return 0.0F;
    }
    const auto nth = static_cast<std::size_t>(quantile_ * static_cast<float>(n - 1));
    std::nth_element(unclipped_.begin(), unclipped_.begin() + static_cast<std::ptrdiff_t>(nth),
                     unclipped_.begin() + static_cast<std::ptrdiff_t>(n));
    // mean |r| = 6 sigma sqrt(2 / pi) per pixel, over kBlock^2 pixels.
    const double meanAbs = static_cast<double>(unclipped_[nth]) / (kBlock * kBlock);
    return static_cast<float>(meanAbs * std::sqrt(std::numbers::pi / 2.0) / 6.0);
}

} // namespace ugv::vision
