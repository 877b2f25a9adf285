#include "ugv/vision/image_noise.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <string>

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
    if (image.data() == nullptr || image.width() > width_ || image.height() > height_) {
        return 0.0F;
    }
    const int bw = blocksAlong(image.width());
    const int bh = blocksAlong(image.height());
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
