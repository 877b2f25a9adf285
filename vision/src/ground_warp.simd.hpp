#pragma once

// Universal-intrinsics kernel of the ground warp (included by ground_warp.cpp only), in the function style
// of OpenCV >= 4.7 through simd_shim.hpp.

#include <cstdint>

#include <opencv2/core.hpp>
#include <opencv2/core/hal/intrin.hpp>

#include "simd_shim.hpp"

namespace ugv::vision::simd {

#if (CV_SIMD || CV_SIMD_SCALABLE)

/// Warps columns [begin, end) of one row in blocks of VTraits<v_uint8>::vlanes() pixels; every pixel in
/// [begin, end) must be valid (its 2-tap support inside `src`). Same arithmetic as the scalar reference:
/// s = round(32 * (scale * x + offset)), out = (src[s>>5] * (32 - f) + src[(s>>5)+1] * f + 16) >> 5, f = s & 31.
/// @return the first column not processed (the caller's scalar tail continues from there).
inline int warpRowSimd(const std::uint8_t* src, std::uint8_t* dst, int begin, int end, float scale,
                       float offset) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
    constexpr int kFracBits = 5;
    const int lanes8 = VTraits<v_uint8>::vlanes();
    const int lanes32 = VTraits<v_float32>::vlanes();
    int idx[VTraits<v_uint8>::max_nlanes];
    int iota[VTraits<v_int32>::max_nlanes];
    for (int i = 0; i < lanes32; ++i) {
        iota[i] = i;
    }
    const v_int32 vIota = vx_load(iota);
    const v_float32 vScale = vx_setall_f32(scale);
    const v_float32 vOffset = vx_setall_f32(offset);
    const v_float32 vOne = vx_setall_f32(static_cast<float>(1 << kFracBits));
    const v_int32 vMask = vx_setall_s32((1 << kFracBits) - 1);
    const v_uint16 vWeightOne = vx_setall_u16(static_cast<std::uint16_t>(1 << kFracBits));
    const v_uint16 vHalf = vx_setall_u16(static_cast<std::uint16_t>(1 << (kFracBits - 1)));

    int x = begin;
    for (; x <= end - lanes8; x += lanes8) {
        // Four float32 vectors cover one uint8 vector (lanes8 == 4 * lanes32 at any width).
        v_int32 s[4];
        for (int k = 0; k < 4; ++k) {
            const v_float32 fx = v_cvt_f32(v_add(vx_setall_s32(x + k * lanes32), vIota));
            s[k] = v_round(v_mul(v_add(v_mul(fx, vScale), vOffset), vOne));
            v_store(idx + k * lanes32, v_shr<kFracBits>(s[k]));
        }
        const v_uint16 f01 = v_reinterpret_as_u16(v_pack(v_and(s[0], vMask), v_and(s[1], vMask)));
        const v_uint16 f23 = v_reinterpret_as_u16(v_pack(v_and(s[2], vMask), v_and(s[3], vMask)));
        v_uint16 p0Lo;
        v_uint16 p0Hi;
        v_uint16 p1Lo;
        v_uint16 p1Hi;
        v_expand(vx_lut(src, idx), p0Lo, p0Hi);
        v_expand(vx_lut(src + 1, idx), p1Lo, p1Hi);
        // At most 255 * 32 + 16: no 16-bit overflow.
        const v_uint16 lo =
            v_shr<kFracBits>(v_add(v_add(v_mul(p0Lo, v_sub(vWeightOne, f01)), v_mul(p1Lo, f01)), vHalf));
        const v_uint16 hi =
            v_shr<kFracBits>(v_add(v_add(v_mul(p0Hi, v_sub(vWeightOne, f23)), v_mul(p1Hi, f23)), vHalf));
        v_store(dst + x, v_pack(lo, hi));
    }
    vx_cleanup();
    return x;
}

#endif

} // namespace ugv::vision::simd
