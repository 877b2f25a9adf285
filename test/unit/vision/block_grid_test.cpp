#include "ugv/vision/block_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ugv/platform/image_view.hpp"

namespace ugv::vision {
namespace {

constexpr int kGridWidth = 320;
constexpr int kGridHeight = 96;

/// A random texture (uniform 100..156); with `blockStepGrey` > 0, every 8 x 8 block, the first starting at column
/// `firstColumn`, is shifted by its own random brightness within +-blockStepGrey: a block coder's quantised means.
Image<std::uint8_t> blockTexture(double blockStepGrey, int firstColumn, unsigned seed = 5)
{
    Image<std::uint8_t> image(kGridWidth, kGridHeight);
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> grey(100, 156);
    std::uniform_real_distribution<double> step(-blockStepGrey, blockStepGrey);
    std::vector<double> shift(static_cast<std::size_t>((kGridWidth / 8 + 2) * (kGridHeight / 8 + 1)));
    for (double& s : shift) {
        s = step(rng);
    }
    for (int y = 0; y < kGridHeight; ++y) {
        std::uint8_t* row = image.view().row(y);
        for (int x = 0; x < kGridWidth; ++x) {
            const int bx = (x - firstColumn + 8) / 8; // block column, the one left of firstColumn included
            const double s = shift[static_cast<std::size_t>((y / 8) * (kGridWidth / 8 + 2) + bx)];
            row[x] = static_cast<std::uint8_t>(std::clamp(std::lround(grey(rng) + s), 0L, 255L));
        }
    }
    return image;
}

TEST(BlockGrid, ARawImageShowsNoGrid)
{
    // Every offset carries the texture's gradient alike: the strongest of eight is within a few per cent of the
    // median (KITTI's frames 1.02-1.07, the simulator's 1.00-1.02).
    const BlockGrid grid = measureBlockGrid(blockTexture(0.0, 0).view());
    EXPECT_GE(grid.contrast, 1.0F);
    EXPECT_LT(grid.contrast, 1.1F);
}

TEST(BlockGrid, BlocksOfTheirOwnBrightnessShowTheGridAndWhereItsEdgesAre)
{
    // Blocks shifted by up to +-40 grey from each other (the texture's own steps are 19 grey on average): the
    // blocks' edges carry clearly more gradient. Blocks starting at column 0 end at columns 7, 15, ...: offset 7;
    // starting at column 3: offset 2.
    const BlockGrid atZero = measureBlockGrid(blockTexture(40.0, 0).view());
    EXPECT_GT(atZero.contrast, 1.3F);
    EXPECT_EQ(atZero.offset, 7);
    const BlockGrid atThree = measureBlockGrid(blockTexture(40.0, 3).view());
    EXPECT_GT(atThree.contrast, 1.3F);
    EXPECT_EQ(atThree.offset, 2);
}

TEST(BlockGrid, FlatBlocksAreAllGridAndAFlatImageHasNone)
{
    Image<std::uint8_t> blocks(kGridWidth, kGridHeight);
    Image<std::uint8_t> flat(kGridWidth, kGridHeight);
    for (int y = 0; y < kGridHeight; ++y) {
        for (int x = 0; x < kGridWidth; ++x) {
            blocks.view().row(y)[x] = static_cast<std::uint8_t>(((x / 8 + y / 8) % 2) * 100 + 50);
            flat.view().row(y)[x] = 90;
        }
    }
    EXPECT_EQ(measureBlockGrid(blocks.view()).contrast, std::numeric_limits<float>::infinity());
    EXPECT_EQ(measureBlockGrid(blocks.view()).offset, 7);
    EXPECT_EQ(measureBlockGrid(flat.view()).contrast, 1.0F);
}

TEST(BlockGrid, AnImageTooNarrowForTwoBlocksOrEmptyHasNoContrast)
{
    Image<std::uint8_t> narrow(16, 8);
    EXPECT_EQ(measureBlockGrid(narrow.view()).contrast, 0.0F);
    EXPECT_EQ(measureBlockGrid(ConstImageViewU8{}).contrast, 0.0F);
}

} // namespace
} // namespace ugv::vision
