#pragma once

/// @file
/// The block grid of a JPEG-coded grey image (JPEG, MJPEG: 8 x 8 pixel blocks), read from the image itself.
///
/// A block coder quantises each 8 x 8 block on its own, so the brightness jumps at the blocks' edges: the columns
/// at one offset within 8 carry more horizontal gradient than the seven others. On a camera's raw frame no offset
/// stands out. `contrast` is the mean |I(x + 1) - I(x)| at the strongest offset over the median of the other seven:
/// KITTI's 17 left images 1.02-1.07 as they are and 1.08 at half resolution, the simulator's 1.00-1.02; 1.09-1.27
/// at JPEG quality 90, 1.29-1.64 at 70, 1.44-1.93 at 50, 1.85-2.85 at 20 (the images' bottom halves, coded by
/// OpenCV's JPEG at quality Q as `ugvsense eval --perturb jpeg:Q` codes them).
///
/// Why it matters: the two images of a pair are coded on their own grids, and their blocks' edges match each other
/// at the disparities that bring the grids together (multiples of 8 px plus the grids' offset), constant down the
/// rows. SectorBuilder takes such matches for a drop's wall (SectorBuilderConfig::blockGridContrast).
///
/// Thread-safety: stateless. RT-safe: yes (no allocation).

#include "ugv/platform/image_view.hpp"

namespace ugv::vision {

struct BlockGrid {
    static constexpr int kBlockPx = 8;
    float contrast = 0.0F; ///< the strongest offset's column gradient over the median of the others (0: no image)
    int offset = 0;        ///< [px] the columns x with x % 8 == offset are the last of a block (x + 1 the next's first)
};

/// The block grid of `image` (every second row). contrast 0 for an image narrower than two blocks, 1 for a flat one,
/// infinite for flat blocks (gradient at one offset only).
[[nodiscard]] BlockGrid measureBlockGrid(ConstImageViewU8 image) noexcept;

} // namespace ugv::vision
