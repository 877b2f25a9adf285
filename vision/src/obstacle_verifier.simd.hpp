#pragma once

// Universal-intrinsics kernel of the obstacle verifier's window cost (included by obstacle_verifier.cpp only).
//
// The lanes run over the window's columns (a window is at most 15 wide: one or two vectors of 8 per row). The
// arithmetic is the scalar reference's, exactly: right sample r = (16 - f) a + f b <= 16 * 255 in 16 bits, their
// sum per lane over at most 9 rows <= 36720 (16 bits), reduced in 32 bits; mean = sum / n; |l - (r - mean)| <= 8160
// by v_absdiff (unsigned), the two vectors of a row summed (<= 16320) and widened to 32 bits per row. Lanes past
// the window's width are masked to zero in the sum and the cost.
// 16-bit products use v_mul_wrap (one mullo): every product fits, and OpenCV 4.6's v_mul on 16-bit lanes
// saturates through a widening multiply and a pack.

#include <cstdint>

#include <opencv2/core.hpp>
#include <opencv2/core/hal/intrin.hpp>

#include "simd_shim.hpp"
#include "ugv/platform/image_view.hpp"

namespace ugv::vision::simd {

#if CV_SIMD128

inline constexpr int kWindowLanes = 16; ///< columns per window row in the left window's layout
inline constexpr int kWindowMaxRows = 9;

/// The right columns a window of `width` starting at column xi0 reads: xi0 .. xi0 + readColumns(width) - 1.
inline constexpr int readColumns(int width) noexcept
{
    return width > 8 ? 17 : 9;
}

/// sum over the window of |l - (r - mean r)|: l16 holds the zero-mean left window x16 (rows of kWindowLanes, zero
/// past `width`), r the right image at rows row0 .. row0 + rows - 1, columns xi0 + i, interpolated with weights
/// (16 - f, f). Columns xi0 .. xi0 + readColumns(width) - 1 of those rows must be readable.
inline int zeroMeanSad(const std::int16_t* l16, ConstImageViewU8 right, int row0, int rows, int xi0, int f,
                       int width) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
    alignas(16) static constexpr std::uint16_t kIota[kWindowLanes] = {0, 1, 2,  3,  4,  5,  6,  7,
                                                                      8, 9, 10, 11, 12, 13, 14, 15};
    const v_uint16x8 vWidth = v_setall_u16(static_cast<std::uint16_t>(width));
    const v_uint16x8 mask0 = v_gt(vWidth, v_load(kIota));
    const v_uint16x8 mask1 = v_gt(vWidth, v_load(kIota + 8));
    const v_uint16x8 w1 = v_setall_u16(static_cast<std::uint16_t>(f));
    const v_uint16x8 w0 = v_setall_u16(static_cast<std::uint16_t>(16 - f));
    const bool two = width > 8;
    v_uint16x8 samples[2 * kWindowMaxRows];
    v_uint16x8 sum0 = v_setzero_u16();
    v_uint16x8 sum1 = v_setzero_u16();
    for (int j = 0; j < rows; ++j) {
        const std::uint8_t* p = right.row(row0 + j) + xi0;
        const v_uint16x8 s0 =
            v_and(v_add(v_mul_wrap(v_load_expand(p), w0), v_mul_wrap(v_load_expand(p + 1), w1)), mask0);
        samples[2 * j] = s0;
        sum0 = v_add(sum0, s0);
        if (two) {
            const v_uint16x8 s1 =
                v_and(v_add(v_mul_wrap(v_load_expand(p + 8), w0), v_mul_wrap(v_load_expand(p + 9), w1)), mask1);
            samples[2 * j + 1] = s1;
            sum1 = v_add(sum1, s1);
        }
    }
    const unsigned total = v_reduce_sum(sum0) + (two ? v_reduce_sum(sum1) : 0U);
    const auto mean = static_cast<std::int16_t>(total / static_cast<unsigned>(width * rows));
    const v_int16x8 vMean = v_setall_s16(mean);
    v_uint32x4 acc = v_setzero_u32();
    for (int j = 0; j < rows; ++j) {
        const std::int16_t* l = l16 + j * kWindowLanes;
        v_uint16x8 c = v_and(v_absdiff(v_load(l), v_sub(v_reinterpret_as_s16(samples[2 * j]), vMean)), mask0);
        if (two) {
            c = v_add(c,
                      v_and(v_absdiff(v_load(l + 8), v_sub(v_reinterpret_as_s16(samples[2 * j + 1]), vMean)), mask1));
        }
        v_uint32x4 lo;
        v_uint32x4 hi;
        v_expand(c, lo, hi);
        acc = v_add(acc, v_add(lo, hi));
    }
    return static_cast<int>(v_reduce_sum(acc));
}

#endif

} // namespace ugv::vision::simd
