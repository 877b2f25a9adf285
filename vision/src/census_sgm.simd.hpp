#pragma once

// Universal-intrinsics kernels of the census SGM (included by census_sgm.cpp only). Each has a scalar twin in
// census_sgm.cpp with the same saturating 8-bit arithmetic, so both give identical results.

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <type_traits>

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

/// out[width - 1 - i] = in[i] for the leading whole vectors of [0, width); @return how many (the rest is the caller's).
inline int reverseRowSimd(const std::uint8_t* in, int width, std::uint8_t* out) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
    const int lanes = VTraits<v_uint8>::vlanes();
    int x = 0;
    for (; x <= width - lanes; x += lanes) {
        v_store(out + width - x - lanes, v_reverse(vx_load(in + x)));
    }
    vx_cleanup();
    return x;
}

/// The two vector widths of the kernels over disparities: 256-bit blocks while they fit, 128-bit for the rest.
/// The disparity count is a multiple of 16, not of 32, so the native width alone would run past the end.
struct W128 {
    using U8 = cv::v_uint8x16;
    using U16 = cv::v_uint16x8;
    static constexpr int kLanes8 = 16;
    static U8 load(const std::uint8_t* p) { return cv::v_load(p); }
    static U16 load(const std::uint16_t* p) { return cv::v_load(p); }
    static U8 all(std::uint8_t v) { return cv::v_setall_u8(v); }
    static U16 all(std::uint16_t v) { return cv::v_setall_u16(v); }
};
#if CV_SIMD256
struct W256 {
    using U8 = cv::v_uint8x32;
    using U16 = cv::v_uint16x16;
    static constexpr int kLanes8 = 32;
    static U8 load(const std::uint8_t* p) { return cv::v256_load(p); }
    static U16 load(const std::uint16_t* p) { return cv::v256_load(p); }
    static U8 all(std::uint8_t v) { return cv::v256_setall_u8(v); }
    static U16 all(std::uint16_t v) { return cv::v256_setall_u16(v); }
};
#endif

/// Runs `block(W{}, k)` over [0, d) (d a multiple of 16): 256-bit blocks first where the build has them.
template <class Block>
inline void forDisparityBlocks(int d, Block&& block) noexcept
{
    int k = 0;
#if CV_SIMD256
    for (; k + W256::kLanes8 <= d; k += W256::kLanes8) {
        block(W256{}, k);
    }
#endif
    for (; k < d; k += W128::kLanes8) {
        block(W128{}, k);
    }
}

/// The running minimum of the blocks of either width (T: std::uint8_t or std::uint16_t lanes).
template <class T>
class BlockMin {
public:
    using V128 = std::conditional_t<sizeof(T) == 1, W128::U8, W128::U16>;
    void add(const V128& v) noexcept
    {
        min128_ = cv::v_min(min128_, v);
        used128_ = true;
    }
#if CV_SIMD256
    using V256 = std::conditional_t<sizeof(T) == 1, W256::U8, W256::U16>;
    void add(const V256& v) noexcept
    {
        min256_ = cv::v_min(min256_, v);
    }
#endif
    [[nodiscard]] T value() const noexcept
    {
        T result = std::numeric_limits<T>::max();
#if CV_SIMD256
        result = static_cast<T>(cv::v_reduce_min(min256_));
#endif
        return used128_ ? std::min(result, static_cast<T>(cv::v_reduce_min(min128_))) : result;
    }

private:
    V128 min128_ = W128::all(std::numeric_limits<T>::max());
    bool used128_ = false;
#if CV_SIMD256
    V256 min256_ = W256::all(std::numeric_limits<T>::max());
#endif
};

/// Cost of one left pixel (its 4 census bytes and its scaled intensity) against `d` right pixels: Hamming
/// distance plus min(|intensity difference|, clip). `right` points at the 5 reversed right planes (stride
/// `planeStride`) at the entry of disparity 0.
inline void costPixelSimd(const std::uint8_t left[5], const std::uint8_t* right, int planeStride, int d, int clip,
                          std::uint8_t* cost) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
    forDisparityBlocks(d, [&](auto w, int k) {
        using V = decltype(w);
        const auto c = v_add(v_add(v_popcount(v_xor(V::all(left[0]), V::load(right + k))),
                                   v_popcount(v_xor(V::all(left[1]), V::load(right + planeStride + k)))),
                             v_add(v_popcount(v_xor(V::all(left[2]), V::load(right + 2 * planeStride + k))),
                                   v_popcount(v_xor(V::all(left[3]), V::load(right + 3 * planeStride + k)))));
        const auto intensity = v_min(v_absdiff(V::all(left[4]), V::load(right + 4 * planeStride + k)),
                                     V::all(static_cast<std::uint8_t>(clip)));
        v_store(cost + k, v_add(c, intensity));
    });
}

/// One step of a path: out = cost + min(prev, prev[-1] + p1, prev[+1] + p1, minPrev + p2) - minPrev, 8-bit
/// saturating (prev has 255 pads on both sides). @return min over d of out.
inline std::uint8_t pathStepSimd(const std::uint8_t* prev, int minPrev, const std::uint8_t* cost, std::uint8_t* out,
                                 int d, int p1, int p2) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
    const auto bound = static_cast<std::uint8_t>(std::min(255, minPrev + p2));
    BlockMin<std::uint8_t> result;
    forDisparityBlocks(d, [&](auto w, int k) {
        using V = decltype(w);
        const auto step =
            v_add(v_min(V::load(prev + k - 1), V::load(prev + k + 1)), V::all(static_cast<std::uint8_t>(p1)));
        const auto best = v_min(v_min(V::load(prev + k), step), V::all(bound));
        const auto l = v_add(v_sub(best, V::all(static_cast<std::uint8_t>(minPrev))), V::load(cost + k));
        v_store(out + k, l);
        result.add(l);
    });
    return result.value();
}

/// sum[k] = the sum over `rows` of rows[r][k] (u8 -> u16) for k in [0, d): the row's paths (two for three paths,
/// four for five: summing only those there are, not rows of zeros).
template <std::size_t N>
inline void sumRowsSimd(const std::array<const std::uint8_t*, N>& rows, std::uint16_t* sum, int d) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
    forDisparityBlocks(d, [&](auto w, int k) {
        using V = decltype(w);
        typename V::U16 lo;
        typename V::U16 hi;
        v_expand(V::load(rows[0] + k), lo, hi);
        for (std::size_t r = 1; r < N; ++r) {
            typename V::U16 rowLo;
            typename V::U16 rowHi;
            v_expand(V::load(rows[r] + k), rowLo, rowHi);
            lo = v_add(lo, rowLo);
            hi = v_add(hi, rowHi);
        }
        v_store(sum + k, lo);
        v_store(sum + k + V::kLanes8 / 2, hi);
    });
}

/// sum[k] += a[k]; @return min over k of the new sum.
inline std::uint16_t addAndMinSimd(const std::uint8_t* a, std::uint16_t* sum, int d) noexcept
{
    using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
    BlockMin<std::uint16_t> result;
    forDisparityBlocks(d, [&](auto w, int k) {
        using V = decltype(w);
        typename V::U16 lo;
        typename V::U16 hi;
        v_expand(V::load(a + k), lo, hi);
        const auto s0 = v_add(V::load(sum + k), lo);
        const auto s1 = v_add(V::load(sum + k + V::kLanes8 / 2), hi);
        v_store(sum + k, s0);
        v_store(sum + k + V::kLanes8 / 2, s1);
        result.add(v_min(s0, s1));
    });
    return result.value();
}

#endif

} // namespace ugv::vision::simd
