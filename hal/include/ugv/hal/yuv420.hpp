#pragma once

/// @file
/// YUV420 (I420: a full-size Y plane, then U and V at half width and half height) to BGR, as a camera's buffer
/// holds it: planes apart, rows strided, and for a side-by-side camera a crop of the columns. The libcamera backend's
/// colour path; OpenCV's BT.601 conversion, the one the V4L2 backend uses for YUYV.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "ugv/platform/image_view.hpp"

namespace ugv::hal {

/// One YUV420 image in memory (no ownership).
struct Yuv420View {
    const std::uint8_t* y = nullptr;
    const std::uint8_t* u = nullptr;
    const std::uint8_t* v = nullptr;
    std::size_t yStride = 0;      ///< bytes from one Y row to the next
    std::size_t chromaStride = 0; ///< bytes from one U (or V) row to the next
};

/// Thread-safety: thread-bound (convert() writes the scratch). RT-safe: convert() allocates nothing (the scratch is
/// made by the constructor).
class Yuv420ToBgr {
public:
    /// For width x height outputs; both even (a chroma sample covers 2 x 2 pixels).
    Yuv420ToBgr(int width, int height);

    /// Converts columns [x0, x0 + width) of `in` into `out` (width x height). Returns false, writing nothing, when
    /// `out` is not that size, x0 is odd or negative, or a plane is missing.
    bool convert(const Yuv420View& in, int x0, BgrView out) noexcept;

private:
    int width_;
    int height_;
    std::vector<std::uint8_t> packed_; ///< width x height * 3 / 2: the crop's planes packed, as cv::cvtColor wants them
};

} // namespace ugv::hal
