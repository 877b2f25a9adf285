#include "ugv/vision/image_noise.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace ugv::vision {
namespace {

constexpr int kNoiseWidth = 320;
constexpr int kNoiseHeight = 120;

std::uint8_t clampGrey(double g)
{
    return static_cast<std::uint8_t>(std::clamp(std::lround(g), 0L, 255L));
}

/// Grey 128 plus Gaussian noise of `sigma`; the first `texturedColumns` columns also carry a strong random
/// texture (uniform 40..216 before the noise), the rest is flat.
Image<std::uint8_t> noisyImage(double sigma, int texturedColumns, unsigned seed = 3)
{
    Image<std::uint8_t> image(kNoiseWidth, kNoiseHeight);
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, sigma);
    std::uniform_int_distribution<int> texture(40, 216);
    for (int y = 0; y < kNoiseHeight; ++y) {
        std::uint8_t* row = image.view().row(y);
        for (int x = 0; x < kNoiseWidth; ++x) {
            const double base = x < texturedColumns ? texture(rng) : 128.0;
            row[x] = clampGrey(base + noise(rng));
        }
    }
    return image;
}

TEST(ImageNoise, ReadsTheNoiseOfAFlatImageOverARangeOfSigmas)
{
    auto sut = ImageNoise::create(kNoiseWidth, kNoiseHeight).value();
    for (const double sigma : {0.5, 1.0, 1.5, 3.0, 6.0}) {
        const Image<std::uint8_t> image = noisyImage(sigma, 0);
        const float read = sut.estimate(image.view());
        // The 10 % quantile of 8 x 8 blocks reads a little low (the blocks' own spread) and 8-bit rounding adds
        // 1/12 grey^2: within 25 % of the noise.
        EXPECT_NEAR(read, sigma, 0.25 * sigma) << "sigma " << sigma;
    }
}

TEST(ImageNoise, TextureOverMostOfTheImageDoesNotRaiseIt)
{
    // 70 % of the columns carry texture whose Laplacian response is 40 times the noise's: the flat blocks decide.
    auto sut = ImageNoise::create(kNoiseWidth, kNoiseHeight).value();
    const float flat = sut.estimate(noisyImage(1.0, 0).view());
    const float textured = sut.estimate(noisyImage(1.0, kNoiseWidth * 7 / 10).view());
    EXPECT_NEAR(textured, flat, 0.15F);
    // ... while the median of the blocks would be the texture's: the quantile is what keeps it the noise's.
    auto median = ImageNoise::create(kNoiseWidth, kNoiseHeight, 0.5F).value();
    EXPECT_GT(median.estimate(noisyImage(1.0, kNoiseWidth * 7 / 10).view()), 10.0F);
}

TEST(ImageNoise, ClippedBlocksCarryNoNoiseAndAreLeftOut)
{
    // Half the image saturated white (a sky, a sunlit pavement): its blocks read 0 and must not pull the
    // quantile down.
    Image<std::uint8_t> image = noisyImage(2.0, 0);
    for (int y = 0; y < kNoiseHeight; ++y) {
        std::fill(image.view().row(y), image.view().row(y) + kNoiseWidth / 2, std::uint8_t{255});
    }
    auto sut = ImageNoise::create(kNoiseWidth, kNoiseHeight).value();
    EXPECT_NEAR(sut.estimate(image.view()), 2.0F, 0.5F);

    // All clipped, or smaller than one block with its border: nothing to read.
    for (int y = 0; y < kNoiseHeight; ++y) {
        std::fill(image.view().row(y), image.view().row(y) + kNoiseWidth, std::uint8_t{0});
    }
    EXPECT_EQ(sut.estimate(image.view()), 0.0F);
    const Image<std::uint8_t> tiny(9, 9);
    EXPECT_EQ(sut.estimate(tiny.view()), 0.0F);
}

TEST(ImageNoise, TheVectorPathReadsWhatTheScalarReferenceReads)
{
    // Flat, noisy, textured, clipped and a 1/254 checkerboard (the largest response, 16 x 253 a pixel), whole and
    // as odd-sized views; the quantiles 0 and 1 read the flattest and the busiest block, so a sum that overflowed
    // its lanes would show.
    std::vector<Image<std::uint8_t>> images;
    images.push_back(noisyImage(0.5, 0));
    images.push_back(noisyImage(3.0, kNoiseWidth / 3, 5));
    images.push_back(noisyImage(20.0, kNoiseWidth, 7));
    Image<std::uint8_t> clipped = noisyImage(2.0, kNoiseWidth / 2, 9);
    for (int y = 0; y < kNoiseHeight; y += 7) {
        clipped.view().row(y)[(y * 13) % kNoiseWidth] = y % 2 == 0 ? 0 : 255;
    }
    images.push_back(std::move(clipped));
    Image<std::uint8_t> checkerboard(kNoiseWidth, kNoiseHeight);
    for (int y = 0; y < kNoiseHeight; ++y) {
        for (int x = 0; x < kNoiseWidth; ++x) {
            checkerboard.view().row(y)[x] = (x + y) % 2 == 0 ? 1 : 254;
        }
    }
    images.push_back(std::move(checkerboard));
    for (const float quantile : {0.0F, 0.1F, 0.5F, 1.0F}) {
        auto sut = ImageNoise::create(kNoiseWidth, kNoiseHeight, quantile).value();
        for (std::size_t i = 0; i < images.size(); ++i) {
            const ConstImageViewU8 whole = images[i].view();
            for (const Rect& r : {Rect{0, 0, kNoiseWidth, kNoiseHeight}, Rect{3, 5, 83, 57}, Rect{1, 1, 17, 10}}) {
                const ConstImageViewU8 view = whole.sub(r);
                EXPECT_EQ(sut.estimate(view), sut.estimateReference(view))
                    << "image " << i << ", quantile " << quantile << ", view " << r.width << "x" << r.height;
            }
        }
    }
}

TEST(ImageNoise, RejectsAnImageLargerThanCreatedForAndABadQuantile)
{
    auto sut = ImageNoise::create(64, 64).value();
    EXPECT_EQ(sut.estimate(noisyImage(1.0, 0).view()), 0.0F);
    EXPECT_FALSE(ImageNoise::create(64, 64, 1.5F).has_value());
    EXPECT_FALSE(ImageNoise::create(64, 64, std::nanf("")).has_value());
    EXPECT_FALSE(ImageNoise::create(-1, 64).has_value());
}

TEST(ImageNoise, EstimateAllocatesNothingOverHundredsOfFrames)
{
    const Image<std::uint8_t> image = noisyImage(1.5, kNoiseWidth / 2);
    auto sut = ImageNoise::create(kNoiseWidth, kNoiseHeight).value();
    (void)sut.estimate(image.view());
    const ugv::test::ThreadAllocationScope scope;
    for (int i = 0; i < 300; ++i) {
        (void)sut.estimate(image.view());
    }
    EXPECT_EQ(scope.count(), 0U);
}

} // namespace
} // namespace ugv::vision
