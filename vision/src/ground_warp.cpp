#include "ugv/vision/ground_warp.hpp"

#include <cmath>
#include <cstring>

#include <opencv2/core.hpp>

#include "ground_warp.simd.hpp"

namespace ugv::vision {
namespace {

/// Rows whose source offset exceeds this are treated as all invalid (keeps 32 * x inside int) [px].
constexpr double kMaxRowOffset = 1.0e6;

bool planeValid(const DisparityPlane& plane) noexcept
{
    return std::isfinite(plane.a) && std::isfinite(plane.b) && std::isfinite(plane.c) &&
           std::abs(plane.a) <= kMaxWarpSlope;
}

/// Valid columns of a row: 0 <= s < 32 (srcWidth - 1), an interval since s is non-decreasing in x.
WarpSpan rowSpan(const WarpRowMap& map, int width, int srcWidth) noexcept
{
    if (!(std::abs(map.offset) <= static_cast<float>(kMaxRowOffset)) || srcWidth < 2) {
        return WarpSpan{};
    }
    const int limit = (srcWidth - 1) * kWarpFracOne;
    int begin = 0;
    while (begin < width && warpSourceFixed(begin, map) < 0) {
        ++begin;
    }
    int end = width;
    while (end > begin && warpSourceFixed(end - 1, map) >= limit) {
        --end;
    }
    return WarpSpan{begin, end};
}

void warpRowScalar(const std::uint8_t* src, std::uint8_t* dst, int begin, int end, const WarpRowMap& map) noexcept
{
    for (int x = begin; x < end; ++x) {
        const int s = warpSourceFixed(x, map);
        const int x0 = s >> kWarpFracBits;
        const int f = s & (kWarpFracOne - 1);
        dst[x] = static_cast<std::uint8_t>((src[x0] * (kWarpFracOne - f) + src[x0 + 1] * f + kWarpFracOne / 2) >>
                                           kWarpFracBits);
    }
}

template <bool kSimd>
GroundWarpStatus warpImpl(ConstImageViewU8 left, const DisparityPlane& plane, int y0, ImageViewU8 warped,
                          std::span<WarpSpan> spans) noexcept
{
    if (left.width() != warped.width() || left.height() != warped.height() ||
        spans.size() < static_cast<std::size_t>(warped.height())) {
        return GroundWarpStatus::SizeMismatch;
    }
    if (!planeValid(plane)) {
        return GroundWarpStatus::InvalidPlane;
    }
    const int width = warped.width();
    for (int r = 0; r < warped.height(); ++r) {
        const WarpRowMap map = warpRowMap(plane, y0 + r);
        const WarpSpan span = rowSpan(map, width, left.width());
        spans[static_cast<std::size_t>(r)] = span;
        const std::uint8_t* src = left.row(r);
        std::uint8_t* dst = warped.row(r);
        std::memset(dst, 0, static_cast<std::size_t>(span.begin));
        std::memset(dst + span.end, 0, static_cast<std::size_t>(width - span.end));
        int x = span.begin;
#if (CV_SIMD || CV_SIMD_SCALABLE)
        if constexpr (kSimd) {
            x = simd::warpRowSimd(src, dst, span.begin, span.end, map.scale, map.offset);
        }
#endif
        warpRowScalar(src, dst, x, span.end, map);
    }
    return GroundWarpStatus::Ok;
}

} // namespace

WarpRowMap warpRowMap(const DisparityPlane& plane, int yFull) noexcept
{
    const double k = 1.0 / (1.0 - plane.a);
    return WarpRowMap{static_cast<float>(k), static_cast<float>((plane.b * yFull + plane.c) * k)};
}

int warpSourceFixed(int x, const WarpRowMap& map) noexcept
{
    const float xs = static_cast<float>(x) * map.scale + map.offset;
    return cvRound(xs * static_cast<float>(kWarpFracOne));
}

GroundWarpStatus warpGround(ConstImageViewU8 left, const DisparityPlane& plane, int y0, ImageViewU8 warped,
                            std::span<WarpSpan> spans) noexcept
{
    return warpImpl<true>(left, plane, y0, warped, spans);
}

GroundWarpStatus warpGroundReference(ConstImageViewU8 left, const DisparityPlane& plane, int y0, ImageViewU8 warped,
                                     std::span<WarpSpan> spans) noexcept
{
    return warpImpl<false>(left, plane, y0, warped, spans);
}

} // namespace ugv::vision
