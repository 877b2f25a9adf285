#include "ugv/vision/block_grid.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <limits>

namespace ugv::vision {

BlockGrid measureBlockGrid(ConstImageViewU8 image) noexcept
{
    constexpr int kBlock = BlockGrid::kBlockPx;
    if (image.data() == nullptr || image.width() < 2 * kBlock + 1 || image.height() < 1) {
        return BlockGrid{};
    }
    // Sum of |I(x + 1) - I(x)| per offset x % 8, over every second row (the blocks' edges run down every row).
    std::array<std::uint64_t, kBlock> sums{};
    const int last = (image.width() - 1) / kBlock * kBlock; // whole groups of 8 gradients: offsets count alike
    for (int y = 0; y < image.height(); y += 2) {
        const std::uint8_t* row = image.row(y);
        for (int x = 0; x < last; x += kBlock) {
            for (int k = 0; k < kBlock; ++k) {
                sums[static_cast<std::size_t>(k)] +=
                    static_cast<std::uint64_t>(std::abs(static_cast<int>(row[x + k + 1]) - row[x + k]));
            }
        }
    }
    const auto best = static_cast<std::size_t>(std::max_element(sums.begin(), sums.end()) - sums.begin());
    std::array<std::uint64_t, kBlock - 1> others{};
    for (std::size_t k = 0, n = 0; k < sums.size(); ++k) {
        if (k != best) {
            others[n++] = sums[k];
        }
    }
    std::nth_element(others.begin(), others.begin() + others.size() / 2, others.end());
    const std::uint64_t median = others[others.size() / 2];
    const std::uint64_t strongest = sums[best];
    BlockGrid grid;
    grid.offset = static_cast<int>(best);
    // Gradient at one offset only: flat blocks, all grid; none at all: a flat image, no grid to tell.
    if (median > 0U) {
        grid.contrast = static_cast<float>(strongest) / static_cast<float>(median);
    } else {
        grid.contrast = strongest > 0U ? std::numeric_limits<float>::infinity() : 1.0F;
    }
    return grid;
}

} // namespace ugv::vision
