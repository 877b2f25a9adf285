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

bool insideSpan(const WarpSpan& span, int begin, int end) noexcept
{
    return begin >= span.begin && end <= span.end;
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

    const int hw = config_.windowHalfWidth;
    const int hh = config_.windowHalfHeight;
    const int n = (2 * hw + 1) * (2 * hh + 1);
    const auto threshold = static_cast<std::int64_t>(
        std::ceil(static_cast<double>(config_.mismatchThreshold) * static_cast<double>(n) * n));
    const int srcLast = w - 1; // last left column a 2-tap sample may touch
    std::array<int, kMaxWindowPixels> diff{};
    std::array<int, kMaxWindowPixels> rightValue{};
    std::array<int, kMaxWindowPixels> x0{};
    std::array<int, kMaxWindowPixels> frac{};
    std::array<const std::uint8_t*, kMaxWindowPixels> srcRow{};
    std::array<const std::uint8_t*, kMaxWindowPixels> base{};
    std::array<std::uint32_t, 256> residualCost{}; // [d - lo], d in [-127, 127]
#if CV_SIMD128
    std::array<cv::v_int16x8, 2 * kMaxWindowPixels> scratch{};
#endif

    for (int r = std::max(1, hh); r < h - std::max(1, hh); ++r) {
        const std::int16_t* g = gradient.row(r);
        for (int x = std::max(1, hw); x < w - std::max(1, hw); ++x) {
            const int gx = g[x];
            if (gx < config_.edgeThreshold || gx < g[x - 1] || gx <= g[x + 1]) {
                continue;
            }
            bool valid = true;
            for (int j = -hh; j <= hh && valid; ++j) {
                valid = insideSpan(spans[static_cast<std::size_t>(r + j)], x - hw, x + hw + 1);
            }
            if (!valid) {
                continue;
            }
            // Ground cost against the warped left.
            int k = 0;
            for (int j = -hh; j <= hh; ++j) {
                const std::uint8_t* rr = right.row(r + j);
                const std::uint8_t* wr = warped.row(r + j);
                for (int i = -hw; i <= hw; ++i, ++k) {
                    rightValue[static_cast<std::size_t>(k)] = rr[x + i];
                    diff[static_cast<std::size_t>(k)] = rr[x + i] - wr[x + i];
                }
            }
            ++counts_.tested;
            const std::int64_t groundCost = zsadScaled(diff.data(), n);
            if (groundCost <= threshold) {
                labels.row(r)[x] = static_cast<std::uint8_t>(GroundLabel::Ground);
                ++counts_.ground;
                continue;
            }
            // Residual search: the left sample positions of the window, shifted by whole pixels.
            int minX0 = std::numeric_limits<int>::max();
            int maxX0 = std::numeric_limits<int>::min();
            k = 0;
            for (int j = -hh; j <= hh; ++j) {
                const WarpRowMap map = warpRowMap(plane, y0 + r + j);
                for (int i = -hw; i <= hw; ++i, ++k) {
                    const int s = warpSourceFixed(x + i, map);
                    x0[static_cast<std::size_t>(k)] = s >> kWarpFracBits;
                    frac[static_cast<std::size_t>(k)] = s & (kWarpFracOne - 1);
                    srcRow[static_cast<std::size_t>(k)] = left.row(r + j);
                    minX0 = std::min(minX0, x0[static_cast<std::size_t>(k)]);
                    maxX0 = std::max(maxX0, x0[static_cast<std::size_t>(k)]);
                }
            }
            const int lo = std::max(config_.residualMin, -minX0);
            const int hi = std::min(config_.residualMax, srcLast - 1 - maxX0);
            std::int64_t bestCost = groundCost;
            int best = 0;
            const auto scalarCost = [&](int d) noexcept {
                for (int q = 0; q < n; ++q) {
                    const auto u = static_cast<std::size_t>(q);
                    const std::uint8_t* src = srcRow[u] + x0[u] + d;
                    const int sample =
                        (src[0] * (kWarpFracOne - frac[u]) + src[1] * frac[u] + kWarpFracOne / 2) >> kWarpFracBits;
                    diff[u] = rightValue[u] - sample;
                }
                return zsadScaled(diff.data(), n);
            };
            bool searched = false;
#if CV_SIMD128
            if constexpr (kSimd) {
                // Costs of [lo, hi] in blocks of 16 residuals; the last block is moved back to end at hi (it
                // overlaps the previous one) so that no load passes hi + 1. The scan below then takes the first
                // strict minimum in increasing d, as the reference does.
                constexpr int kBlock = simd::kResidualBlock;
                if (hi - lo + 1 >= kBlock) {
                    for (int q = 0; q < n; ++q) {
                        const auto u = static_cast<std::size_t>(q);
                        base[u] = srcRow[u] + x0[u];
                    }
                    for (int start = lo; start <= hi; start += kBlock) {
                        const int s = std::min(start, hi - kBlock + 1);
                        simd::residualCosts16(base.data(), frac.data(), rightValue.data(), n, s,
                                              &residualCost[static_cast<std::size_t>(s - lo)], scratch.data());
                    }
                    for (int d = lo; d <= hi; ++d) {
                        const std::int64_t cost = residualCost[static_cast<std::size_t>(d - lo)];
                        if (d != 0 && cost < bestCost) {
                            bestCost = cost;
                            best = d;
                        }
                    }
                    searched = true;
                }
            }
#endif
            if (!searched) {
                for (int d = lo; d <= hi; ++d) {
                    if (d == 0) {
                        continue;
                    }
                    const std::int64_t cost = scalarCost(d);
                    if (cost < bestCost) {
                        bestCost = cost;
                        best = d;
                    }
                }
            }
            GroundLabel label = GroundLabel::Unsure;
            if (static_cast<double>(bestCost) <
                static_cast<double>(config_.signRatio) * static_cast<double>(groundCost)) {
                label = best > 0 ? GroundLabel::Positive : GroundLabel::Negative;
            }
            labels.row(r)[x] = static_cast<std::uint8_t>(label);
            residuals.row(r)[x] = static_cast<std::int8_t>(best);
            switch (label) {
            case GroundLabel::Positive:
                ++counts_.positive;
                break;
            case GroundLabel::Negative:
                ++counts_.negative;
                break;
            default:
                ++counts_.unsure;
                break;
            }
        }
    }
    return GroundMismatchStatus::Ok;
}

} // namespace ugv::vision
