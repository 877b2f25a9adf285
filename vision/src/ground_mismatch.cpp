#include "ugv/vision/ground_mismatch.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>

#include "ground_mismatch.simd.hpp"

namespace ugv::vision {
namespace {

/// Zero-mean SAD of n differences, scaled by n: sum |n e_i - sum e| (integer, no division on the hot path).
std::int64_t zsadScaled(const int* diff, int n) noexcept
{
    int sum = 0;
    for (int i = 0; i < n; ++i) {
        sum += diff[i];
    }
    std::int64_t cost = 0;
    for (int i = 0; i < n; ++i) {
        cost += std::abs(n * diff[i] - sum);
    }
    return cost;
}

/// The window's size, passed by value apart from the buffers: the compiler then keeps it in registers instead of
/// reloading it after every store to a buffer (an int store may be to the size, for all it knows).
struct WindowSize {
    int hw = 0; ///< half width [px]
    int hh = 0; ///< half height [px]
    int n = 0;  ///< pixels
};

/// One tested pixel's window buffers (run()'s stack scratch, reused from pixel to pixel): the right values and
/// differences of groundCost(), the left sample positions of sampleLeft() and the residual search's buffers.
struct Window {
    static constexpr int kMax = GroundMismatch::kMaxWindowPixels;
    std::array<int, kMax> diff{};
    std::array<int, kMax> rightValue{};
    std::array<int, kMax> x0{};   ///< whole-pixel left sample column under the plane [px]
    std::array<int, kMax> frac{}; ///< weight of the sample's right tap [1 / kWarpFracOne]
    std::array<const std::uint8_t*, kMax> srcRow{};
#if CV_SIMD128
    std::array<const std::uint8_t*, kMax> base{};  ///< srcRow + x0
    std::array<std::uint32_t, 256> residualCost{}; ///< [d - lo], d in [-127, 127]
    std::array<cv::v_int16x8, 2 * kMax> scratch{};
#endif
};

/// Residual disparities [lo, hi] to search [px].
struct ResidualRange {
    int lo = 0;
    int hi = 0;
};

/// The lowest cost found so far and its residual disparity [px] (0: the ground's own cost).
struct Residual {
    std::int64_t cost = 0;
    int d = 0;
};

/// Whether every row of the window around (r, x) lies inside its row's valid warp span.
bool insideSpans(std::span<const WarpSpan> spans, WindowSize size, int r, int x) noexcept
{
    for (int j = -size.hh; j <= size.hh; ++j) {
        const WarpSpan& span = spans[static_cast<std::size_t>(r + j)];
        if (x - size.hw < span.begin || x + size.hw + 1 > span.end) {
            return false;
        }
    }
    return true;
}

/// Ground cost of the window around (r, x): right against the warped left. Keeps the right values for the search.
std::int64_t groundCost(Window& win, WindowSize size, ConstImageViewU8 right, ConstImageViewU8 warped, int r,
                        int x) noexcept
{
    int k = 0;
    for (int j = -size.hh; j <= size.hh; ++j) {
        const std::uint8_t* rr = right.row(r + j);
        const std::uint8_t* wr = warped.row(r + j);
        for (int i = -size.hw; i <= size.hw; ++i, ++k) {
            win.rightValue[static_cast<std::size_t>(k)] = rr[x + i];
            win.diff[static_cast<std::size_t>(k)] = rr[x + i] - wr[x + i];
        }
    }
    return zsadScaled(win.diff.data(), size.n);
}

/// The left sample positions of the window around (r, x) under the plane, and the residuals of the config's range
/// whose shifted 2-tap samples stay inside the left row.
ResidualRange sampleLeft(Window& win, WindowSize size, ConstImageViewU8 left, const DisparityPlane& plane, int y0,
                         int r, int x, const GroundMismatchConfig& config) noexcept
{
    const int srcLast = config.width - 1; // last left column a 2-tap sample may touch
    int minX0 = std::numeric_limits<int>::max();
    int maxX0 = std::numeric_limits<int>::min();
    int k = 0;
    for (int j = -size.hh; j <= size.hh; ++j) {
        const WarpRowMap map = warpRowMap(plane, y0 + r + j);
        for (int i = -size.hw; i <= size.hw; ++i, ++k) {
            const int s = warpSourceFixed(x + i, map);
            win.x0[static_cast<std::size_t>(k)] = s >> kWarpFracBits;
            win.frac[static_cast<std::size_t>(k)] = s & (kWarpFracOne - 1);
            win.srcRow[static_cast<std::size_t>(k)] = left.row(r + j);
            minX0 = std::min(minX0, win.x0[static_cast<std::size_t>(k)]);
            maxX0 = std::max(maxX0, win.x0[static_cast<std::size_t>(k)]);
        }
    }
    return {std::max(config.residualMin, -minX0), std::min(config.residualMax, srcLast - 1 - maxX0)};
}

/// Cost of residual d: the window's left samples shifted by d pixels against the right values.
std::int64_t residualCost(Window& win, int n, int d) noexcept
{
    for (int q = 0; q < n; ++q) {
        const auto u = static_cast<std::size_t>(q);
        const std::uint8_t* src = win.srcRow[u] + win.x0[u] + d;
        const int sample =
            (src[0] * (kWarpFracOne - win.frac[u]) + src[1] * win.frac[u] + kWarpFracOne / 2) >> kWarpFracBits;
        win.diff[u] = win.rightValue[u] - sample;
    }
    return zsadScaled(win.diff.data(), n);
}

/// The reference search, one residual at a time: the first strict minimum in increasing d, d != 0.
void searchScalar(Window& win, int n, ResidualRange range, Residual& best) noexcept
{
    for (int d = range.lo; d <= range.hi; ++d) {
        if (d == 0) {
            continue;
        }
        const std::int64_t cost = residualCost(win, n, d);
        if (cost < best.cost) {
            best = Residual{cost, d};
        }
    }
}

#if CV_SIMD128
/// The search 16 residuals per universal-intrinsics step, with the reference's result; false (nothing searched) when
/// the range is shorter than one block.
bool searchSimd(Window& win, int n, ResidualRange range, Residual& best) noexcept
{
    // Costs of [lo, hi] in blocks of 16 residuals; the last block is moved back to end at hi (it overlaps the
    // previous one) so that no load passes hi + 1. The scan below then takes the first strict minimum in increasing
    // d, as the reference does.
    constexpr int kBlock = simd::kResidualBlock;
    const int lo = range.lo;
    const int hi = range.hi;
    if (hi - lo + 1 < kBlock) {
        return false;
    }
    for (int q = 0; q < n; ++q) {
        const auto u = static_cast<std::size_t>(q);
        win.base[u] = win.srcRow[u] + win.x0[u];
    }
    for (int start = lo; start <= hi; start += kBlock) {
        const int s = std::min(start, hi - kBlock + 1);
        simd::residualCosts16(win.base.data(), win.frac.data(), win.rightValue.data(), n, s,
                              &win.residualCost[static_cast<std::size_t>(s - lo)], win.scratch.data());
    }
    for (int d = lo; d <= hi; ++d) {
        const std::int64_t cost = win.residualCost[static_cast<std::size_t>(d - lo)];
        if (d != 0 && cost < best.cost) {
            best = Residual{cost, d};
        }
    }
    return true;
}
#endif

/// Counts the label of a pixel that went through the residual search (Positive, Negative or Unsure).
void countSearched(GroundMismatchCounts& counts, GroundLabel label) noexcept
{
    switch (label) {
    case GroundLabel::Positive:
        ++counts.positive;
        break;
    case GroundLabel::Negative:
        ++counts.negative;
        break;
    default:
        ++counts.unsure;
        break;
    }
}

} // namespace

GroundMismatch::GroundMismatch(const GroundMismatchConfig& config)
    : config_(config), labels_(config.width, config.height), residuals_(config.width, config.height),
      gradient_(config.width, config.height)
{
}

Result<GroundMismatch, Error> GroundMismatch::create(const GroundMismatchConfig& config)
{
    const auto fail = [](std::string what) { return Unexpected(Error{"GroundMismatchConfig", std::move(what), ""}); };
    if (config.width < 1 || config.height < 1) {
        return fail("width and height must be >= 1");
    }
    if (config.windowHalfWidth < 0 || config.windowHalfHeight < 0 ||
        (2 * config.windowHalfWidth + 1) * (2 * config.windowHalfHeight + 1) > kMaxWindowPixels) {
        return fail("window must be non-negative and at most " + std::to_string(kMaxWindowPixels) + " pixels");
    }
    if (config.residualMin >= 0 || config.residualMax <= 0 || config.residualMin < -127 || config.residualMax > 127) {
        return fail("residual range must satisfy -127 <= residualMin < 0 < residualMax <= 127");
    }
    if (!(config.mismatchThreshold > 0.0F) || !(config.signRatio > 0.0F && config.signRatio <= 1.0F) ||
        config.edgeThreshold < 0) {
        return fail("mismatchThreshold > 0, 0 < signRatio <= 1 and edgeThreshold >= 0 required");
    }
    return GroundMismatch(config);
}

GroundMismatchStatus GroundMismatch::run(ConstImageViewU8 left, ConstImageViewU8 right, ConstImageViewU8 warped,
                                         std::span<const WarpSpan> spans, const DisparityPlane& plane, int y0) noexcept
{
    return runImpl<true>(left, right, warped, spans, plane, y0);
}

GroundMismatchStatus GroundMismatch::runReference(ConstImageViewU8 left, ConstImageViewU8 right,
                                                  ConstImageViewU8 warped, std::span<const WarpSpan> spans,
                                                  const DisparityPlane& plane, int y0) noexcept
{
    return runImpl<false>(left, right, warped, spans, plane, y0);
}

void GroundMismatch::resetAndGradient(ConstImageViewU8 right) noexcept
{
    const int w = config_.width;
    const int h = config_.height;
    const ImageViewU8 labels = labels_.view();
    const ImageView<std::int8_t> residuals = residuals_.view();
    const ImageView<std::int16_t> gradient = gradient_.view();
    // |Sobel x| of the right image; 0 on the 1-pixel border.
    for (int r = 0; r < h; ++r) {
        std::int16_t* g = gradient.row(r);
        std::memset(labels.row(r), static_cast<int>(GroundLabel::NotTested), static_cast<std::size_t>(w));
        std::memset(residuals.row(r), 0, static_cast<std::size_t>(w));
        std::memset(g, 0, sizeof(std::int16_t) * static_cast<std::size_t>(w));
        if (r == 0 || r == h - 1) {
            continue;
        }
        const std::uint8_t* up = right.row(r - 1);
        const std::uint8_t* mid = right.row(r);
        const std::uint8_t* down = right.row(r + 1);
        for (int x = 1; x < w - 1; ++x) {
            const int gx = (up[x + 1] - up[x - 1]) + 2 * (mid[x + 1] - mid[x - 1]) + (down[x + 1] - down[x - 1]);
            g[x] = static_cast<std::int16_t>(std::abs(gx));
        }
    }
}

template <bool kSimd>
GroundMismatchStatus GroundMismatch::runImpl(ConstImageViewU8 left, ConstImageViewU8 right, ConstImageViewU8 warped,
                                             std::span<const WarpSpan> spans, const DisparityPlane& plane,
                                             int y0) noexcept
{
    const int w = config_.width;
    const int h = config_.height;
    const auto sizeOk = [&](ConstImageViewU8 v) { return v.width() == w && v.height() == h; };
    if (!sizeOk(left) || !sizeOk(right) || !sizeOk(warped) || spans.size() < static_cast<std::size_t>(h)) {
        return GroundMismatchStatus::SizeMismatch;
    }
    if (!std::isfinite(plane.a) || !std::isfinite(plane.b) || !std::isfinite(plane.c) ||
        std::abs(plane.a) > kMaxWarpSlope) {
        return GroundMismatchStatus::InvalidPlane;
    }
    counts_ = GroundMismatchCounts{};
    resetAndGradient(right);
    const ImageViewU8 labels = labels_.view();
    const ImageView<std::int8_t> residuals = residuals_.view();

    const int hw = config_.windowHalfWidth;
    const int hh = config_.windowHalfHeight;
    const WindowSize size{hw, hh, (2 * hw + 1) * (2 * hh + 1)};
    const auto threshold = static_cast<std::int64_t>(
        std::ceil(static_cast<double>(config_.mismatchThreshold) * static_cast<double>(size.n) * size.n));
    Window win{};
    for (int r = std::max(1, hh); r < h - std::max(1, hh); ++r) {
        const std::int16_t* g = gradient_.view().row(r);
        for (int x = std::max(1, hw); x < w - std::max(1, hw); ++x) {
            const int gx = g[x];
            if (gx < config_.edgeThreshold || gx < g[x - 1] || gx <= g[x + 1] || !insideSpans(spans, size, r, x)) {
                continue;
            }
            ++counts_.tested;
            const std::int64_t ground = groundCost(win, size, right, warped, r, x);
            if (ground <= threshold) {
                labels.row(r)[x] = static_cast<std::uint8_t>(GroundLabel::Ground);
                ++counts_.ground;
                continue;
            }
            // Residual search: the left sample positions of the window, shifted by whole pixels.
            const ResidualRange range = sampleLeft(win, size, left, plane, y0, r, x, config_);
            Residual best{ground, 0};
            bool searched = false;
#if CV_SIMD128
            if constexpr (kSimd) {
                searched = searchSimd(win, size.n, range, best);
            }
#endif
            if (!searched) {
                searchScalar(win, size.n, range, best);
            }
            GroundLabel label = GroundLabel::Unsure;
            if (static_cast<double>(best.cost) < static_cast<double>(config_.signRatio) * static_cast<double>(ground)) {
                label = best.d > 0 ? GroundLabel::Positive : GroundLabel::Negative;
            }
            labels.row(r)[x] = static_cast<std::uint8_t>(label);
            residuals.row(r)[x] = static_cast<std::int8_t>(best.d);
            countSearched(counts_, label);
        }
    }
    return GroundMismatchStatus::Ok;
}

} // namespace ugv::vision
