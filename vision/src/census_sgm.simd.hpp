#pragma once

// Universal-intrinsics kernels of the census SGM (included by census_sgm.cpp only). Each has a scalar twin in
// census_sgm.cpp with the same saturating 8-bit arithmetic, so both give identical results.

#include <algorithm>
#include <cstdint>

#include <opencv2/core.hpp>
#include <opencv2/core/hal/intrin.hpp>

#include "simd_shim.hpp"

namespace ugv::vision::simd {

#if (CV_SIMD || CV_SIMD_SCALABLE)

/// Centre-symmetric census of columns [0, width) of one row of a bordered image (4 columns and 3 rows of
/// border on each side; `centre` points at column 0 of the row). Writes 4 byte planes of `planeStride`.
/// @return the first column not processed (scalar tail).
inline int censusRowSimd(const std::uint8_t* centre, std::ptrdiff_t step, int width, std::uint8_t* planes,
                         int planeStride) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
    const int lanes = VTraits<v_uint8>::vlanes();
    const v_uint8 one = vx_setall_u8(1);
    int x = 0;
    for (; x <= width - lanes; x += lanes) {
        v_uint8 acc[4] = {vx_setzero_u8(), vx_setzero_u8(), vx_setzero_u8(), vx_setzero_u8()};
        int bit = 0;
        for (int dy = 0; dy <= 3; ++dy) {
            for (int dx = (dy == 0 ? 1 : -4); dx <= 4; ++dx, ++bit) {
                const v_uint8 a = vx_load(centre + dy * step + x + dx);
                const v_uint8 b = vx_load(centre - dy * step + x - dx);
                v_uint8& plane = acc[bit >> 3];
                plane = v_or(v_add_wrap(plane, plane), v_and(v_reinterpret_as_u8(v_gt(a, b)), one));
            }
        }
        for (int p = 0; p < 4; ++p) {
            v_store(planes + p * planeStride + x, acc[p]);
        }
    }
    vx_cleanup();
    return x;
}

/// Cost of one left pixel (its 4 census bytes and its scaled intensity) against `d` right pixels: Hamming
/// distance plus min(|intensity difference|, clip). `right` points at the 5 reversed right planes (stride
/// `planeStride`) at the entry of disparity 0.
inline void costPixelSimd(const std::uint8_t left[5], const std::uint8_t* right, int planeStride, int d, int clip,
                          std::uint8_t* cost) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace)
    const int lanes = VTraits<v_uint8>::vlanes();
    const v_uint8 l0 = vx_setall_u8(left[0]);
    const v_uint8 l1 = vx_setall_u8(left[1]);
    const v_uint8 l2 = vx_setall_u8(left[2]);
    const v_uint8 l3 = vx_setall_u8(left[3]);
    const v_uint8 li = vx_setall_u8(left[4]);
    const v_uint8 vClip = vx_setall_u8(static_cast<std::uint8_t>(clip));
    for (int k = 0; k < d; k += lanes) {
        const v_uint8 c = v_add(
            v_add(v_popcount(v_xor(l0, vx_load(right + k))), v_popcount(v_xor(l1, vx_load(right + planeStride + k)))),
            v_add(v_popcount(v_xor(l2, vx_load(right + 2 * planeStride + k))),
                  v_popcount(v_xor(l3, vx_load(right + 3 * planeStride + k)))));
        v_store(cost + k, v_add(c, v_min(v_absdiff(li, vx_load(right + 4 * planeStride + k)), vClip)));
    }
}

/// One step of a path: out = cost + min(prev, prev[-1] + p1, prev[+1] + p1, minPrev + p2) - minPrev, 8-bit
/// saturating (prev has 255 pads on both sides). @return min over d of out.
inline std::uint8_t pathStepSimd(const std::uint8_t* prev, int minPrev, const std::uint8_t* cost, std::uint8_t* out,
                                 int d, int p1, int p2) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace)
    const int lanes = VTraits<v_uint8>::vlanes();
    const v_uint8 vP1 = vx_setall_u8(static_cast<std::uint8_t>(p1));
    const v_uint8 vBound = vx_setall_u8(static_cast<std::uint8_t>(std::min(255, minPrev + p2)));
    const v_uint8 vMinPrev = vx_setall_u8(static_cast<std::uint8_t>(minPrev));
    v_uint8 acc = vx_setall_u8(255);
    for (int k = 0; k < d; k += lanes) {
        const v_uint8 step = v_add(v_min(vx_load(prev + k - 1), vx_load(prev + k + 1)), vP1);
        const v_uint8 best = v_min(v_min(vx_load(prev + k), step), vBound);
        const v_uint8 l = v_add(v_sub(best, vMinPrev), vx_load(cost + k));
        v_store(out + k, l);
        acc = v_min(acc, l);
    }
    return v_reduce_min(acc);
}

/// sum[k] = a[k] + b[k] + c[k] + e[k] (16-bit) for k in [0, d).
inline void sumFourSimd(const std::uint8_t* a, const std::uint8_t* b, const std::uint8_t* c, const std::uint8_t* e,
                        std::uint16_t* sum, int d) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace)
    const int lanes = VTraits<v_uint8>::vlanes();
    const int half = VTraits<v_uint16>::vlanes();
    for (int k = 0; k < d; k += lanes) {
        v_uint16 aLo;
        v_uint16 aHi;
        v_uint16 bLo;
        v_uint16 bHi;
        v_uint16 cLo;
        v_uint16 cHi;
        v_uint16 eLo;
        v_uint16 eHi;
        v_expand(vx_load(a + k), aLo, aHi);
        v_expand(vx_load(b + k), bLo, bHi);
        v_expand(vx_load(c + k), cLo, cHi);
        v_expand(vx_load(e + k), eLo, eHi);
        v_store(sum + k, v_add(v_add(aLo, bLo), v_add(cLo, eLo)));
        v_store(sum + k + half, v_add(v_add(aHi, bHi), v_add(cHi, eHi)));
    }
}

/// sum[k] += a[k]; @return min over k of the new sum.
inline std::uint16_t addAndMinSimd(const std::uint8_t* a, std::uint16_t* sum, int d) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace)
    const int lanes = VTraits<v_uint8>::vlanes();
    const int half = VTraits<v_uint16>::vlanes();
    v_uint16 acc = vx_setall_u16(0xFFFF);
    for (int k = 0; k < d; k += lanes) {
        v_uint16 lo;
        v_uint16 hi;
        v_expand(vx_load(a + k), lo, hi);
        const v_uint16 s0 = v_add(vx_load(sum + k), lo);
        const v_uint16 s1 = v_add(vx_load(sum + k + half), hi);
        v_store(sum + k, s0);
        v_store(sum + k + half, s1);
        acc = v_min(acc, v_min(s0, s1));
    }
    return v_reduce_min(acc);
}

#endif

} // namespace ugv::vision::simd
