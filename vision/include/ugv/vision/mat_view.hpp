#pragma once

/// @file
/// A cv::Mat header over an ImageView's pixels, without a copy: where our views meet an OpenCV call.
///
/// Thread-safety: a header shares the view's pixels. RT-safe: yes (a header over external data allocates nothing).

#include <cstddef>
#include <cstdint>
#include <type_traits>

#include <opencv2/core.hpp>

#include "ugv/platform/image_view.hpp"

namespace ugv::vision {

/// CV_8UC1 over a grey view, CV_8UC3 over a BGR one; an empty Mat for an empty view. The view's pixels must outlive
/// the Mat. OpenCV has no const header: over a const view, only read through it (pass it as an input).
template <class T>
[[nodiscard]] cv::Mat matOver(const ImageView<T>& view) noexcept
{
    using Pixel = std::remove_const_t<T>;
    static_assert(std::is_same_v<Pixel, std::uint8_t> || std::is_same_v<Pixel, BgrPixel>, "an 8-bit grey or BGR view");
    if (view.empty()) {
        return {};
    }
    const int type = std::is_same_v<Pixel, BgrPixel> ? CV_8UC3 : CV_8UC1;
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast) NOLINTJUSTIFICATION: read-only use of a const view
    return {view.height(), view.width(), type, const_cast<Pixel*>(view.data()),
            static_cast<std::size_t>(view.strideBytes())};
}

} // namespace ugv::vision
