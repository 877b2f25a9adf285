#pragma once

/// @file
/// Non-owning views of 2-D pixel buffers, and an owning image whose buffer is allocated once.
///
/// Layout matches OpenCV's cv::Mat: rows are `strideBytes` apart, pixels within a row are contiguous.
/// Modules exchange `ImageView`s so that vision/ need not know where a frame lives (camera DMA buffer,
/// shared-memory chunk, recording, cv::Mat).
///
/// Thread-safety: views are values; the pixels are as shared as the buffer they point into.
/// RT-safe: ImageView yes (no allocation); Image allocates only in its constructor.

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "ugv/platform/assert.hpp"

namespace ugv {

/// A rectangle in pixel coordinates: x, y top-left; width, height in [px].
struct Rect {
    int x = 0;
    int y = 0;
    int width = 0;
    int height = 0;

    [[nodiscard]] constexpr bool empty() const noexcept { return width <= 0 || height <= 0; }
    [[nodiscard]] constexpr bool contains(const Rect& inner) const noexcept
    {
        return inner.x >= x && inner.y >= y && inner.x + inner.width <= x + width &&
               inner.y + inner.height <= y + height;
    }
    friend constexpr bool operator==(const Rect&, const Rect&) = default;
};

template <class T>
class ImageView {
public:
    constexpr ImageView() = default;
    constexpr ImageView(T* data, int width, int height, std::ptrdiff_t strideBytes) noexcept
        : data_(data), width_(width), height_(height), strideBytes_(strideBytes)
    {
        UGV_EXPECTS(width >= 0 && height >= 0);
        UGV_EXPECTS(strideBytes >= static_cast<std::ptrdiff_t>(sizeof(T)) * width);
    }
    /// Contiguous rows.
    constexpr ImageView(T* data, int width, int height) noexcept
        : ImageView(data, width, height, static_cast<std::ptrdiff_t>(sizeof(T)) * width)
    {
    }
    /// A mutable view converts to a const one.
    template <class U>
    requires(std::is_const_v<T>&& std::is_same_v<std::remove_const_t<T>, U>)
        // NOLINTNEXTLINE(google-explicit-constructor): implicit, as T* converts to const T*
        constexpr ImageView(const ImageView<U>& other) noexcept
        : data_(other.data()), width_(other.width()), height_(other.height()), strideBytes_(other.strideBytes())
    {
    }

    [[nodiscard]] constexpr T* data() const noexcept { return data_; }
    [[nodiscard]] constexpr int width() const noexcept { return width_; }   ///< [px]
    [[nodiscard]] constexpr int height() const noexcept { return height_; } ///< [px]
    [[nodiscard]] constexpr std::ptrdiff_t strideBytes() const noexcept { return strideBytes_; }
    [[nodiscard]] constexpr bool empty() const noexcept { return data_ == nullptr || width_ == 0 || height_ == 0; }

    [[nodiscard]] T* row(int y) const noexcept
    {
        UGV_EXPECTS(y >= 0 && y < height_);
        using Byte = std::conditional_t<std::is_const_v<T>, const std::byte, std::byte>;
        return reinterpret_cast<T*>(reinterpret_cast<Byte*>(data_) + y * strideBytes_);
    }
    [[nodiscard]] T& at(int x, int y) const noexcept
    {
        UGV_EXPECTS(x >= 0 && x < width_);
        return row(y)[x];
    }
    /// The sub-rectangle `r`, which must lie inside this view.
    [[nodiscard]] ImageView sub(const Rect& r) const noexcept
    {
        UGV_EXPECTS((Rect{0, 0, width_, height_}.contains(r)));
        return r.empty() ? ImageView() : ImageView(row(r.y) + r.x, r.width, r.height, strideBytes_);
    }

private:
    T* data_ = nullptr;
    int width_ = 0;
    int height_ = 0;
    std::ptrdiff_t strideBytes_ = 0;
};

using ImageViewU8 = ImageView<std::uint8_t>;
using ConstImageViewU8 = ImageView<const std::uint8_t>;

/// One pixel of an 8-bit BGR image (cv::Mat CV_8UC3 layout: a row of such pixels is the Mat row).
struct BgrPixel {
    std::uint8_t b = 0;
    std::uint8_t g = 0;
    std::uint8_t r = 0;
};
static_assert(sizeof(BgrPixel) == 3, "BgrPixel must match CV_8UC3");

/// A view of a BGR image; width in pixels, stride in bytes (as cv::Mat::step).
using BgrView = ImageView<BgrPixel>;
using ConstBgrView = ImageView<const BgrPixel>;

/// An image that owns its pixels. The buffer is allocated by the constructor (configure time) and never
/// resized; `view()` hands out views for the frame path.
template <class T>
class Image {
public:
    Image() = default;
    Image(int width, int height) : width_(width), height_(height), pixels_(static_cast<std::size_t>(width) * height)
    {
        UGV_EXPECTS(width >= 0 && height >= 0);
    }
    [[nodiscard]] ImageView<T> view() noexcept { return {pixels_.data(), width_, height_}; }
    [[nodiscard]] ImageView<const T> view() const noexcept { return {pixels_.data(), width_, height_}; }
    [[nodiscard]] int width() const noexcept { return width_; }
    [[nodiscard]] int height() const noexcept { return height_; }

private:
    int width_ = 0;
    int height_ = 0;
    std::vector<T> pixels_;
};

} // namespace ugv
