#include "ugv/hal/yuv420.hpp"

#include <cstring>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace ugv::hal {

Yuv420ToBgr::Yuv420ToBgr(int width, int height)
    : width_(width), height_(height),
      packed_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3 / 2)
{
}

bool Yuv420ToBgr::convert(const Yuv420View& in, int x0, BgrView out) noexcept
{
    if (out.width() != width_ || out.height() != height_ || width_ % 2 != 0 || height_ % 2 != 0 || x0 < 0 ||
        x0 % 2 != 0 || in.y == nullptr || in.u == nullptr || in.v == nullptr) {
        return false;
    }
    const auto w = static_cast<std::size_t>(width_);
    const auto cw = w / 2;
    const auto ch = static_cast<std::size_t>(height_) / 2;
    const auto cx = static_cast<std::size_t>(x0) / 2;
    std::uint8_t* dst = packed_.data();
    for (int y = 0; y < height_; ++y, dst += w) {
        std::memcpy(dst, in.y + static_cast<std::size_t>(y) * in.yStride + static_cast<std::size_t>(x0), w);
    }
    for (const std::uint8_t* plane : {in.u, in.v}) {
        for (std::size_t y = 0; y < ch; ++y, dst += cw) {
            std::memcpy(dst, plane + y * in.chromaStride + cx, cw);
        }
    }
    try {
        // The sizes were fixed by the constructor, so cvtColor writes into `out` without allocating.
        const cv::Mat i420(height_ * 3 / 2, width_, CV_8UC1, packed_.data());
        cv::Mat bgr(height_, width_, CV_8UC3, out.data(), static_cast<std::size_t>(out.strideBytes()));
        cv::cvtColor(i420, bgr, cv::COLOR_YUV2BGR_I420);
    } catch (const cv::Exception&) {
        return false;
    }
    return true;
}

} // namespace ugv::hal
