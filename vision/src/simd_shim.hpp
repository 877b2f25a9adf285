#pragma once

// Function-style universal intrinsics on OpenCV 4.6.
//
// OpenCV 4.6 (Debian 12) predates the function-style API (v_add, v_mul, VTraits<T>::vlanes(),
// CV_SIMD_SCALABLE) that STYLE.md asks for; this shim provides exactly those names on top of the 4.6
// operators so that our kernels are written in the new style and compile unchanged on OpenCV >= 4.7.
// (On 4.6, v_add/v_sub of 8- and 16-bit lanes saturate, as the operators do.)

#include <opencv2/core.hpp>
#include <opencv2/core/hal/intrin.hpp>

#ifndef CV_SIMD_SCALABLE
#define CV_SIMD_SCALABLE 0
#endif

namespace ugv::vision::simd {

#if (CV_VERSION_MAJOR == 4 && CV_VERSION_MINOR < 7)
// NOLINTBEGIN(readability-identifier-naming): OpenCV 4.7's names, so the kernels read the same on both
template <class V>
struct VTraits {
    static constexpr int vlanes() noexcept { return V::nlanes; }
    static constexpr int max_nlanes = V::nlanes;
};
template <class V>
inline V v_add(const V& a, const V& b)
{
    return a + b;
}
template <class V>
inline V v_sub(const V& a, const V& b)
{
    return a - b;
}
template <class V>
inline V v_mul(const V& a, const V& b)
{
    return a * b;
}
template <class V>
inline V v_and(const V& a, const V& b)
{
    return a & b;
}
template <class V>
inline V v_xor(const V& a, const V& b)
{
    return a ^ b;
}
template <class V>
inline V v_or(const V& a, const V& b)
{
    return a | b;
}
template <class V>
inline auto v_gt(const V& a, const V& b)
{
    return a > b;
}
template <class V>
inline auto v_eq(const V& a, const V& b)
{
    return a == b;
}
// NOLINTEND(readability-identifier-naming)
#else
using cv::v_add;
using cv::v_and;
using cv::v_eq;
using cv::v_gt;
using cv::v_mul;
using cv::v_or;
using cv::v_sub;
using cv::v_xor;
using cv::VTraits;
#endif

} // namespace ugv::vision::simd
