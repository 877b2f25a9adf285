#include "ugv/vision/ground_estimator.hpp"

#include <cmath>
#include <cstddef>
#include <string>

namespace ugv::vision {
namespace {

constexpr double kD16ToPx = 1.0 / 16.0;  ///< CV_16S fixed point -> [px]
constexpr double kMinDeterminant = 1e-9; ///< relative, for degenerate samples and normal equations

/// splitmix64: tiny, allocation-free, reproducible sampling.
struct Rng {
    std::uint64_t state;
    std::uint64_t next() noexcept
    {
        std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
        z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
        z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
        return z ^ (z >> 31U);
    }
    int below(int n) noexcept { return static_cast<int>(next() % static_cast<std::uint64_t>(n)); }
};

bool finitePlane(const DisparityPlane& p) noexcept
{
    return std::isfinite(p.a) && std::isfinite(p.b) && std::isfinite(p.c);
}

} // namespace

GroundEstimator::GroundEstimator(const GroundEstimatorConfig& config)
    : config_(config), configured_(GroundPlane::fromMount(config.mount)),
      configuredDisparity_(configured_.disparityPlane(config.projection)), state_(configuredDisparity_),
      candidates_(static_cast<std::size_t>(((config.width + config.sampleStep - 1) / config.sampleStep) *
                                           ((config.height + config.sampleStep - 1) / config.sampleStep)))
{
    fallback(GroundFallbackReason::None);
}

Result<GroundEstimator, Error> GroundEstimator::create(const GroundEstimatorConfig& config)
{
    const auto fail = [](std::string what) { return Unexpected(Error{"GroundEstimatorConfig", std::move(what), ""}); };
    const RectifiedProjection& p = config.projection;
    if (!(p.fx > 0.0) || !(p.baselineM > 0.0) || !std::isfinite(p.cx) || !std::isfinite(p.cy)) {
        return fail("projection needs fx > 0, baselineM > 0 and a finite principal point");
    }
    if (!(config.mount.heightM > 0.0) || !(std::abs(config.mount.pitchDeg) < 80.0) ||
        !(std::abs(config.mount.rollDeg) < 80.0)) {
        return fail("mount needs heightM > 0 and |pitch|, |roll| < 80 deg");
    }
    if (config.width < 1 || config.height < 1 || config.sampleStep < 1 || config.y0 < 0) {
        return fail("width, height, sampleStep >= 1 and y0 >= 0 required");
    }
    if (!(config.inlierTolerancePx > 0.0) || config.ransacIterations < 1 || config.minInliers < 3 ||
        !(config.minInlierFraction >= 0.0 && config.minInlierFraction <= 1.0)) {
        return fail("tolerances > 0, ransacIterations >= 1, minInliers >= 3, minInlierFraction in [0, 1] required");
    }
    if (!(config.heightBandFraction > 0.0 && config.heightBandFraction < 1.0) || !(config.pitchBandDeg > 0.0) ||
        !(config.rollBandDeg > 0.0) || !(config.smoothing > 0.0 && config.smoothing <= 1.0)) {
        return fail("bands > 0 (height fraction below 1) and smoothing in (0, 1] required");
    }
    return GroundEstimator(config);
}

void GroundEstimator::reset() noexcept
{
    state_ = configuredDisparity_;
    fallback(GroundFallbackReason::None);
}

void GroundEstimator::fallback(GroundFallbackReason reason) noexcept
{
    state_ = configuredDisparity_;
    estimate_.plane = configured_;
    estimate_.disparity = configuredDisparity_;
    estimate_.reliable = false;
    estimate_.reason = reason;
}

int GroundEstimator::collectCandidates(ImageView<const std::int16_t> disparity) noexcept
{
    int count = 0;
    const int step = config_.sampleStep;
    for (int r = step / 2; r < config_.height; r += step) {
        const std::int16_t* row = disparity.row(r);
        const double y = config_.y0 + r;
        for (int x = step / 2; x < config_.width; x += step) {
            if (row[x] < 0) {
                continue;
            }
            const double d = row[x] * kD16ToPx;
            candidates_[static_cast<std::size_t>(count++)] =
                Candidate{static_cast<float>(x), static_cast<float>(y), static_cast<float>(d)};
        }
    }
    return count;
}

bool GroundEstimator::inBand(const DisparityPlane& plane) const noexcept
{
    if (!finitePlane(plane)) {
        return false;
    }
    const GroundPlane g = GroundPlane::fromDisparityPlane(plane, config_.projection);
    return std::isfinite(g.heightM) &&
           std::abs(g.heightM - config_.mount.heightM) <= config_.heightBandFraction * config_.mount.heightM &&
           std::abs(g.pitchDeg() - config_.mount.pitchDeg) <= config_.pitchBandDeg &&
           std::abs(g.rollDeg() - config_.mount.rollDeg) <= config_.rollBandDeg;
}

int GroundEstimator::countInliers(int count, const DisparityPlane& plane) const noexcept
{
    const auto fa = static_cast<float>(plane.a);
    const auto fb = static_cast<float>(plane.b);
    const auto fc = static_cast<float>(plane.c);
    const auto tol = static_cast<float>(config_.inlierTolerancePx);
    int inliers = 0;
    for (int i = 0; i < count; ++i) {
        const Candidate& c = candidates_[static_cast<std::size_t>(i)];
        inliers += std::abs(fa * c.x + fb * c.y + fc - c.d) < tol ? 1 : 0;
    }
    return inliers;
}

bool GroundEstimator::ransac(int count, DisparityPlane& best) noexcept
{
    Rng rng{config_.seed};
    int bestInliers = 0;
    // The last estimate (a pitching vehicle moves little between frames) and the configured plane first.
    for (const DisparityPlane& prior : {state_, configuredDisparity_}) {
        if (const int inliers = countInliers(count, prior); inliers > bestInliers) {
            bestInliers = inliers;
            best = prior;
        }
    }
    for (int it = 0; it < config_.ransacIterations; ++it) {
        const Candidate& p = candidates_[static_cast<std::size_t>(rng.below(count))];
        const Candidate& q = candidates_[static_cast<std::size_t>(rng.below(count))];
        const Candidate& s = candidates_[static_cast<std::size_t>(rng.below(count))];
        // Plane through three points, relative to p: [dx dy] [a b]^T = dd.
        const double x1 = q.x - p.x;
        const double y1 = q.y - p.y;
        const double x2 = s.x - p.x;
        const double y2 = s.y - p.y;
        const double det = x1 * y2 - x2 * y1;
        if (std::abs(det) < 1.0) { // collinear or repeated sample (coordinates are whole pixels)
            continue;
        }
        const double d1 = q.d - p.d;
        const double d2 = s.d - p.d;
        const double a = (d1 * y2 - d2 * y1) / det;
        const double b = (x1 * d2 - x2 * d1) / det;
        const DisparityPlane model{a, b, p.d - a * p.x - b * p.y};
        if (!inBand(model)) {
            continue; // not a ground: a face, a wall, a mix of both
        }
        if (const int inliers = countInliers(count, model); inliers > bestInliers) {
            bestInliers = inliers;
            best = model;
        }
    }
    return bestInliers >= 3;
}

bool GroundEstimator::refine(int count, DisparityPlane& plane, int& inliers) const noexcept
{
    // Least squares in centred coordinates: the normal equations decouple into a 2x2 system for (a, b) and
    // the mean for the offset.
    double n = 0.0;
    double sx = 0.0;
    double sy = 0.0;
    double sd = 0.0;
    forEachInlier(count, plane, [&](const Candidate& c) {
        n += 1.0;
        sx += c.x;
        sy += c.y;
        sd += c.d;
    });
    if (n < 3.0) {
        return false;
    }
    const double mx = sx / n;
    const double my = sy / n;
    const double md = sd / n;
    double sxx = 0.0;
    double sxy = 0.0;
    double syy = 0.0;
    double sxd = 0.0;
    double syd = 0.0;
    forEachInlier(count, plane, [&](const Candidate& c) {
        const double x = c.x - mx;
        const double y = c.y - my;
        const double d = c.d - md;
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
        sxd += x * d;
        syd += y * d;
    });
    const double det = sxx * syy - sxy * sxy;
    if (!(det > kMinDeterminant * sxx * syy) || !(sxx > 0.0)) {
        return false;
    }
    const double a = (sxd * syy - syd * sxy) / det;
    const double b = (syd * sxx - sxd * sxy) / det;
    plane = DisparityPlane{a, b, md - a * mx - b * my};
    inliers = static_cast<int>(n);
    return finitePlane(plane);
}

const GroundEstimate& GroundEstimator::update(ImageView<const std::int16_t> disparity) noexcept
{
    estimate_.candidates = 0;
    estimate_.inliers = 0;
    estimate_.measured = DisparityPlane{};
    if (disparity.width() != config_.width || disparity.height() != config_.height) {
        fallback(GroundFallbackReason::WrongInput);
        return estimate_;
    }
    const int count = collectCandidates(disparity);
    estimate_.candidates = count;
    if (count < config_.minInliers) {
        fallback(GroundFallbackReason::TooFewCandidates);
        return estimate_;
    }
    DisparityPlane fit;
    int inliers = 0;
    if (!ransac(count, fit) || !refine(count, fit, inliers) || !refine(count, fit, inliers)) {
        fallback(GroundFallbackReason::DegenerateFit);
        return estimate_;
    }
    estimate_.inliers = inliers;
    estimate_.measured = fit;
    if (inliers < config_.minInliers || inliers < config_.minInlierFraction * count) {
        fallback(GroundFallbackReason::TooFewInliers);
        return estimate_;
    }
    if (!inBand(fit)) {
        fallback(GroundFallbackReason::OutOfBand);
        estimate_.measured = fit;
        estimate_.inliers = inliers;
        return estimate_;
    }
    const double w = config_.smoothing;
    state_ = DisparityPlane{state_.a + w * (fit.a - state_.a), state_.b + w * (fit.b - state_.b),
                            state_.c + w * (fit.c - state_.c)};
    estimate_.plane = GroundPlane::fromDisparityPlane(state_, config_.projection);
    estimate_.disparity = state_;
    estimate_.reliable = true;
    estimate_.reason = GroundFallbackReason::None;
    return estimate_;
}

} // namespace ugv::vision
