#pragma once

/// @file
/// A cv::Mat seen as the vision code takes its images (ugv::ImageView): the tests' one way to hand OpenCV images
/// to our kernels.

#include <cstddef>
#include <cstdint>

#include <opencv2/core.hpp>

#include "ugv/platform/image_view.hpp"

namespace ugv::test {

/// An 8-bit single-channel image, read-only.
inline ConstImageViewU8 view(const cv::Mat& m)
{
    return {m.ptr<std::uint8_t>(), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}

/// An 8-bit single-channel image, writable.
inline ImageViewU8 view(cv::Mat& m)
{
    return {m.ptr<std::uint8_t>(), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}

/// A CV_16S image (fixed-point disparities), read-only.
inline ImageView<const std::int16_t> view16(const cv::Mat& m)
{
    return {m.ptr<std::int16_t>(), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}

} // namespace ugv::test
