#include "ugv/vision/obstacle_verifier.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "obstacle_verifier.simd.hpp"

namespace ugv::vision {
namespace {

constexpr int kSub = 16;         ///< disparity fixed-point scale (StereoSGBM)
constexpr int kMaxHalfWidth = 7; ///< window up to 15 x 9
constexpr int kMaxHalfHeight = 4;
constexpr std::int16_t kInvalid = -kSub;

Error verifierConfigError(const std::string& what)
{
    return Error{"ObstacleVerifierConfig", what, "see vision/include/ugv/vision/obstacle_verifier.hpp"};
}

/// std::lround for x >= 0, inline (x - (int)x is exact: a double's fractional part is representable).
int roundNonNegative(double x) noexcept
{
    const auto i = static_cast<int>(x);
    return x - i >= 0.5 ? i + 1 : i;
}

/// The left window of one pixel, zero-mean, prepared once for its costs at several disparities: the zero-mean SAD
/// against the right image shifted by d16 / 16 px (linear interpolation along x), in 1/16 grey levels summed over
/// the window. The caller checks the bounds. Rows of simd::kWindowLanes values, zero past the window's width (the
/// layout of the universal-intrinsics kernel).
class LeftWindow {
public:
    // l16_'s rows in use are written below before any read; zeroing all of it for every candidate pixel would cost
    // more than the window.
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-member-init): written before read (above)
    LeftWindow(ConstImageViewU8 left, int x, int v, int hw, int hh) noexcept : x_(x), v_(v), hw_(hw), hh_(hh)
    {
        const int width = 2 * hw + 1;
        const int rows = 2 * hh + 1;
        int sum = 0;
        for (int j = 0; j < rows; ++j) {
            const std::uint8_t* l = left.row(v - hh + j) + x - hw;
            std::int16_t* dst = l16_ + j * kLanes;
            for (int i = 0; i < width; ++i) {
                dst[i] = static_cast<std::int16_t>(kSub * l[i]);
                sum += dst[i];
            }
            std::fill(dst + width, dst + kLanes, std::int16_t{0});
        }
        const int mean = sum / (width * rows);
        for (int j = 0; j < rows; ++j) {
            std::int16_t* dst = l16_ + j * kLanes;
            for (int i = 0; i < width; ++i) {
                dst[i] = static_cast<std::int16_t>(dst[i] - mean);
                contrast_ += std::abs(dst[i]);
            }
        }
    }
    /// Sum of |L - mean L| over the window [1/16 grey].
    [[nodiscard]] int contrast() const noexcept { return contrast_; }
    /// True when the window's match slides along x by more than `perRow` columns per row its contour moves,
    /// |sum Ix Iy| > perRow sum Ix^2 over the window of `left` (forward differences; the neighbour right of or below
    /// the window is read from the image, and at its last column or row the difference is 0).
    /// ObstacleVerifierConfig::maxSlidePerRow; 0: never.
    [[nodiscard]] bool slides(ConstImageViewU8 left, float perRow) const noexcept
    {
        if (!(perRow > 0.0F)) {
            return false;
        }
        const int lastColumn = left.width() - 1;
        int xx = 0; // at most 135 x 255^2
        int xy = 0;
        for (int y = v_ - hh_; y <= v_ + hh_; ++y) {
            const std::uint8_t* row = left.row(y);
            const std::uint8_t* below = left.row(std::min(y + 1, left.height() - 1));
            for (int c = x_ - hw_; c <= x_ + hw_; ++c) {
                const int ix = row[std::min(c + 1, lastColumn)] - row[c];
                xx += ix * ix;
                xy += ix * (below[c] - row[c]);
            }
        }
        return static_cast<double>(std::abs(xy)) > static_cast<double>(perRow) * static_cast<double>(xx);
    }

    /// The window's zero-mean SAD against the right image at disparity d16; `simd` false: the scalar reference.
    [[nodiscard]] int costAt(ConstImageViewU8 right, int d16, bool simd) const noexcept
    {
        // Every column of the window shares the sub-pixel fraction: column i reads right columns xi0 + i and
        // xi0 + i + 1 with the same weights ((x + i) 16 - d16 differs from the first by 16 i).
        const int xr16 = (x_ - hw_) * kSub - d16;
        const int xi0 = xr16 >> 4;
        const int f = xr16 & (kSub - 1);
        const int width = 2 * hw_ + 1;
        const int rows = 2 * hh_ + 1;
#if CV_SIMD128
        if (simd && xi0 + simd::readColumns(width) <= right.width()) {
            return simd::zeroMeanSad(l16_, right, v_ - hh_, rows, xi0, f, width);
        }
#else
        static_cast<void>(simd);
#endif
        int r16[kLanes * kMaxRows];
        int sum = 0;
        for (int j = 0; j < rows; ++j) {
            const std::uint8_t* r = right.row(v_ - hh_ + j) + xi0;
            for (int i = 0; i < width; ++i) {
                r16[j * kLanes + i] = (kSub - f) * r[i] + f * r[i + 1];
                sum += r16[j * kLanes + i];
            }
        }
        const int mean = sum / (width * rows);
        int cost = 0;
        for (int j = 0; j < rows; ++j) {
            for (int i = 0; i < width; ++i) {
                cost += std::abs(l16_[j * kLanes + i] - (r16[j * kLanes + i] - mean));
            }
        }
        return cost;
    }

private:
    static constexpr int kLanes = 16; ///< simd::kWindowLanes
    static constexpr int kMaxRows = 2 * kMaxHalfHeight + 1;
    static_assert(2 * kMaxHalfWidth + 1 <= kLanes);
#if CV_SIMD128
    static_assert(kLanes == simd::kWindowLanes && kMaxRows <= simd::kWindowMaxRows, "the kernel's layout");
#endif
    alignas(16) std::int16_t l16_[kLanes * kMaxRows];
    int contrast_ = 0;
    int x_;
    int v_;
    int hw_;
    int hh_;
};

/// True when the window of half width `hw` at column x and disparity d16 lies inside both images of width w.
bool windowInside(int x, int d16, int hw, int w) noexcept
{
    const int lo = (x - hw) * kSub - d16;
    const int hi = (x + hw) * kSub - d16;
    return x - hw >= 0 && x + hw < w && lo >= 0 && (hi >> 4) + 1 < w;
}

} // namespace

Result<ObstacleVerifier, Error> ObstacleVerifier::create(const ObstacleVerifierConfig& config)
{
    if (config.width < 1 || config.height < 1) {
        return Unexpected(verifierConfigError("ROI " + std::to_string(config.width) + "x" +
                                              std::to_string(config.height) + " is empty"));
    }
    const auto windowOk = [](int hw, int hh) {
        return hw >= 1 && hw <= kMaxHalfWidth && hh >= 0 && hh <= kMaxHalfHeight;
    };
    if (!windowOk(config.windowHalfWidth, config.windowHalfHeight) ||
        !windowOk(config.belowHalfWidth, config.belowHalfHeight)) {
        return Unexpected(verifierConfigError("window half sizes " + std::to_string(config.windowHalfWidth) + " x " +
                                              std::to_string(config.windowHalfHeight) + " and below ground " +
                                              std::to_string(config.belowHalfWidth) + " x " +
                                              std::to_string(config.belowHalfHeight) + " must be in 1..7 x 0..4"));
    }
    if (!(config.minResidualPx >= 0.0F) || !(config.acceptRatio > 0.0F && config.acceptRatio <= 1.0F) ||
        !(config.minContrast >= 0.0F) || !(config.minContrastBelow >= 0.0F) || !(config.refineMaxGroundPx >= 0.0F) ||
        !(config.contrastNoiseFactor >= 0.0F) || !(config.maxSlidePerRow >= 0.0F)) {
        return Unexpected(verifierConfigError("minResidualPx, contrastNoiseFactor, minContrast, minContrastBelow and "
                                              "maxSlidePerRow must be >= 0 and acceptRatio in (0, 1]"));
    }
    auto noise = ImageNoise::create(config.width, config.height);
    if (!noise) {
        return Unexpected(noise.error());
    }
    return ObstacleVerifier(config, std::move(*noise));
}

VerifyStatus ObstacleVerifier::run(ConstImageViewU8 left, ConstImageViewU8 right,
                                   ImageView<const std::int16_t> disparity16, const DisparityPlane& ground,
                                   int y0) noexcept
{
    const int w = config_.width;
    const int h = config_.height;
    const ImageView<std::int16_t> out = out_.view();
    counts_ = VerifyCounts{};
    const auto sizeOk = [w, h](auto view) { return view.data() != nullptr && view.width() == w && view.height() == h; };
    if (!sizeOk(left) || !sizeOk(right) || !sizeOk(disparity16)) {
        for (int v = 0; v < h; ++v) {
            std::fill(out.row(v), out.row(v) + w, kInvalid);
        }
        return VerifyStatus::WrongInputSize;
    }
    const int hw = config_.windowHalfWidth;
    const int hh = config_.windowHalfHeight;
    const int n = (2 * hw + 1) * (2 * hh + 1);
    const auto minResidual16 = static_cast<int>(std::lround(config_.minResidualPx * kSub));
    // The contrast a window needs: that of texture against this camera's noise, learnt from this frame.
    noiseSigma_ = noise_.estimate(left);
    requiredContrast_ = std::clamp(config_.contrastNoiseFactor * noiseSigma_,
                                   std::min(config_.minContrastBelow, config_.minContrast), config_.minContrast);
    const auto minContrast16 = static_cast<int>(std::lround(requiredContrast_ * kSub * static_cast<float>(n)));
    const auto minContrastBelow16 =
        static_cast<int>(std::lround(config_.minContrastBelow * kSub * static_cast<float>(n)));
    // cost(d) < ratio * cost(d_g), in integers: cost(d) * 1024 < ratio1024 * cost(d_g).
    const auto ratio1024 = static_cast<std::int64_t>(std::lround(config_.acceptRatio * 1024.0F));
    // A window at disparity d16 reads right columns floor(((x - hw) 16 - d16) / 16) .. that of (x + hw) + 1.
    const int bhw = config_.belowHalfWidth;
    const auto refineMaxGround16 = static_cast<int>(std::lround(config_.refineMaxGroundPx * kSub));
    const int margin = std::max(hh, config_.belowHalfHeight);
    const auto inside = [w, hw](int x, int d16) { return windowInside(x, d16, hw, w); };
    for (int v = 0; v < h; ++v) {
        const std::int16_t* in = disparity16.row(v);
        std::int16_t* dst = out.row(v);
        std::copy(in, in + w, dst);
        if (v < margin || v >= h - margin) {
            continue; // the window leaves the ROI: kept as matched
        }
        const double rowGround = ground.b * (y0 + v) + ground.c;
        for (int x = std::min(hw, bhw); x < w - std::min(hw, bhw); ++x) {
            const int d16 = in[x];
            if (d16 < 0) {
                continue;
            }
            const double dg = ground.a * x + rowGround;
            if (!(dg >= 0.0)) {
                continue; // above the ground's horizon: no ground hypothesis
            }
            const int dg16 = roundNonNegative(dg * kSub);
            if (std::abs(d16 - dg16) <= minResidual16) {
                continue;
            }
            ++counts_.tested;
            if (d16 < dg16 && dg16 <= refineMaxGround16) {
                dst[x] = refineBelow(left, right, x, v, d16, dg16);
                continue;
            }
            if (!inside(x, d16) || !inside(x, dg16)) {
                ++counts_.undecided;
                continue;
            }
            const LeftWindow window(left, x, v, hw, hh);
            if (window.contrast() < (d16 < dg16 ? minContrastBelow16 : minContrast16)) {
                dst[x] = kInvalid; // no texture to tell: the disparity is the matcher's guess
                ++counts_.undecided;
                continue;
            }
            const int atD = window.costAt(right, d16, config_.simd);
            const int atGround = window.costAt(right, dg16, config_.simd);
            const bool groundExplains = static_cast<std::int64_t>(atD) * 1024 >= ratio1024 * atGround;
            if (groundExplains || window.slides(left, config_.maxSlidePerRow)) {
                dst[x] = kInvalid;
                ++(groundExplains ? counts_.rejected : counts_.undecided);
            }
        }
    }
    return VerifyStatus::Ok;
}

std::int16_t ObstacleVerifier::refineBelow(ConstImageViewU8 left, ConstImageViewU8 right, int x, int v, int d16,
                                           int dg16) noexcept
{
    const int hw = config_.belowHalfWidth;
    const int hh = config_.belowHalfHeight;
    const int n = (2 * hw + 1) * (2 * hh + 1);
    const int w = config_.width;
    const auto minResidual16 = static_cast<int>(std::lround(config_.minResidualPx * kSub));
    const auto minContrast16 = static_cast<int>(std::lround(config_.minContrastBelow * kSub * static_cast<float>(n)));
    const auto ratio1024 = static_cast<std::int64_t>(std::lround(config_.acceptRatio * 1024.0F));
    // [d - 1, d + 3] px, below d_g - 1/2 px: the matcher is off by ~2 px at a far wall, and a bounded search keeps
    // the cost per pixel bounded (a pixel 40 px below the ground would otherwise search 80 steps).
    const int lo = std::max(0, d16 - kSub);
    const int hi = std::min(d16 + 3 * kSub, dg16 - minResidual16 / 2);
    if (hi < lo || !windowInside(x, lo, hw, w) || !windowInside(x, dg16 + kSub / 2, hw, w)) {
        ++counts_.undecided;
        return static_cast<std::int16_t>(d16); // the window leaves the image: kept as matched
    }
    const LeftWindow window(left, x, v, hw, hh);
    if (window.contrast() < minContrast16) {
        ++counts_.undecided;
        return kInvalid; // no texture to tell
    }
    // Coarse search in 1/2 px steps, then 1/8 px steps around the coarse best.
    int best = lo;
    const int atGround = window.costAt(right, dg16, config_.simd);
    int bestCost = window.costAt(right, lo, config_.simd);
    for (int d = lo + kSub / 2; d <= hi; d += kSub / 2) {
        const int cost = window.costAt(right, d, config_.simd);
        if (cost < bestCost) {
            bestCost = cost;
            best = d;
        }
    }
    const int coarse = best;
    for (int d = std::max(lo, coarse - 6); d <= std::min(hi, coarse + 6); d += 2) {
        if (d == coarse) {
            continue;
        }
        const int cost = window.costAt(right, d, config_.simd);
        if (cost < bestCost) {
            bestCost = cost;
            best = d;
        }
    }
    // The ground gets the same freedom as the drop: its best cost within +-1/2 px of d_g (1/8 px steps). The
    // minimum of many noisy costs beats a single one by chance on weak texture (a painted floor). Searched only
    // when the drop beats d_g itself (the search can only lower the ground's cost).
    const auto beatsGround = [&](int groundCost) {
        return static_cast<std::int64_t>(bestCost) * 1024 < ratio1024 * groundCost;
    };
    bool accepted = beatsGround(atGround);
    for (int d = dg16 - kSub / 2; accepted && d <= dg16 + kSub / 2; d += 2) {
        accepted = d == dg16 || beatsGround(window.costAt(right, d, config_.simd));
    }
    if (!accepted) {
        ++counts_.rejected;
        return kInvalid;
    }
    if (window.slides(left, config_.maxSlidePerRow)) {
        ++counts_.undecided;
        return kInvalid;
    }
    ++counts_.refined;
    return static_cast<std::int16_t>(best);
}

} // namespace ugv::vision
