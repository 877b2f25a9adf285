#pragma once

// Universal-intrinsics kernel of the ground-mismatch residual search (included by ground_mismatch.cpp only).
//
// One call evaluates the zero-mean SAD of one window for 16 consecutive residual disparities at once: for a
// window pixel q the 16 shifted left samples src[x0_q + d .. x0_q + d + 15] (and their right neighbours for the
// 2-tap interpolation) are two contiguous 16-byte loads, so the lanes run over residuals, not over pixels.
// The arithmetic is the scalar reference's, exactly: sample = (a (32 - f) + b f + 16) >> 5 in 16 bits
// (<= 255 * 32 + 16), e = R - sample in [-255, 255], S = sum e (|S| <= 81 * 255), cost = sum |n e - S| with
// |n e - S| <= 2 * 81 * 255 < 2^16 taken by v_absdiff (unsigned result, no overflow), summed in 16 bits while
// the partial sum provably fits (65535 / (2 * 255 n) terms) and then in 32 bits.
// 16-bit products use v_mul_wrap (one mullo): every product fits, and OpenCV 4.6's operator* / v_mul on 16-bit
// lanes saturates through a widening multiply and a pack (about 3x the instructions).
// The lane count is fixed at 16 (one 128-bit vector of uint8): OpenCV 4.6 gives our code 128-bit vectors only
// (DEPENDENCIES.md), and 16 residuals per block matches the search range granularity.

#include <algorithm>
#include <cstdint>

#include <opencv2/core.hpp>
#include <opencv2/core/hal/intrin.hpp>

#include "ground_warp.simd.hpp" // the OpenCV 4.6 shim (v_add, v_sub, v_mul, VTraits)

namespace ugv::vision::simd {

#if CV_SIMD128

inline constexpr int kResidualBlock = 16; ///< residuals per residualCosts16() call

/// cost[i] = sum_q |n e_q(d + i) - sum_q' e_q'(d + i)| for i in [0, 16), e_q(d) = right[q] - interpolated left
/// sample at base[q] + d with weight frac[q] on the right tap. Every base[q] + d + 16 must be readable.
/// @param[out] e  scratch of 2 n vectors
inline void residualCosts16(const std::uint8_t* const* base, const int* frac, const int* right, int n, int d,
                            std::uint32_t* cost, cv::v_int16x8* e) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
    constexpr int kFracBits = 5;
    const v_uint16x8 vOne = v_setall_u16(static_cast<std::uint16_t>(1 << kFracBits));
    const v_uint16x8 vHalf = v_setall_u16(static_cast<std::uint16_t>(1 << (kFracBits - 1)));
    v_int16x8 sumLo = v_setzero_s16();
    v_int16x8 sumHi = v_setzero_s16();
    for (int q = 0; q < n; ++q) {
        const std::uint8_t* p = base[q] + d;
        v_uint16x8 a0;
        v_uint16x8 a1;
        v_uint16x8 b0;
        v_uint16x8 b1;
        v_expand(v_load(p), a0, a1);
        v_expand(v_load(p + 1), b0, b1);
        const v_uint16x8 w1 = v_setall_u16(static_cast<std::uint16_t>(frac[q]));
        const v_uint16x8 w0 = v_sub(vOne, w1);
        const v_uint16x8 s0 = v_shr<kFracBits>(v_add(v_add(v_mul_wrap(a0, w0), v_mul_wrap(b0, w1)), vHalf));
        const v_uint16x8 s1 = v_shr<kFracBits>(v_add(v_add(v_mul_wrap(a1, w0), v_mul_wrap(b1, w1)), vHalf));
        const v_int16x8 r = v_setall_s16(static_cast<std::int16_t>(right[q]));
        const v_int16x8 e0 = v_sub(r, v_reinterpret_as_s16(s0));
        const v_int16x8 e1 = v_sub(r, v_reinterpret_as_s16(s1));
        e[2 * q] = e0;
        e[2 * q + 1] = e1;
        sumLo = v_add(sumLo, e0);
        sumHi = v_add(sumHi, e1);
    }
    const v_int16x8 vn = v_setall_s16(static_cast<std::int16_t>(n));
    v_uint32x4 acc0 = v_setzero_u32();
    v_uint32x4 acc1 = v_setzero_u32();
    v_uint32x4 acc2 = v_setzero_u32();
    v_uint32x4 acc3 = v_setzero_u32();
    // |n e - S| <= 2 n 255: `flush` terms fit a 16-bit lane (6 for the 7 x 3 window), then widen to 32 bits.
    const int flush = std::max(1, 65535 / (2 * 255 * n));
    int q = 0;
    while (q < n) {
        const int stop = std::min(n, q + flush);
        v_uint16x8 t0 = v_setzero_u16();
        v_uint16x8 t1 = v_setzero_u16();
        for (; q < stop; ++q) {
            t0 = v_add(t0, v_absdiff(v_mul_wrap(e[2 * q], vn), sumLo));
            t1 = v_add(t1, v_absdiff(v_mul_wrap(e[2 * q + 1], vn), sumHi));
        }
        v_uint32x4 u0;
        v_uint32x4 u1;
        v_uint32x4 u2;
        v_uint32x4 u3;
        v_expand(t0, u0, u1);
        v_expand(t1, u2, u3);
        acc0 = v_add(acc0, u0);
        acc1 = v_add(acc1, u1);
        acc2 = v_add(acc2, u2);
        acc3 = v_add(acc3, u3);
    }
    v_store(cost, acc0);
    v_store(cost + 4, acc1);
    v_store(cost + 8, acc2);
    v_store(cost + 12, acc3);
}

#endif

} // namespace ugv::vision::simd
