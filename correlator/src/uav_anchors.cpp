#include "ugv/correlator/uav_anchors.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <utility>
#include <vector>

namespace ugv::correlator {
namespace {

/// Fixes kept per object: the brackets of the observations held (one instant of fixes apart) and the recent
/// intervals that show how fast the object walks.
constexpr std::size_t kKeptFixes = 8;

} // namespace

UavAnchors::UavAnchors(const PoseCorrectedConfig& config) : config_(config) {}

void UavAnchors::observe(int ugv, OoiClass cls, const RangeBearing& sample)
{
    pending_.push_back(Held{ugv, cls, sample});
    // Without fixes nothing resolves: what waited longer than an object lives untracked is dropped.
    const double oldest = sample.t - config_.mobileTimeoutS;
    std::erase_if(pending_, [oldest](const Held& h) { return h.sample.t < oldest; });
}

void UavAnchors::fix(int object, OoiClass cls, double t, const Eigen::Vector2d& position)
{
    auto it = std::find_if(fixed_.begin(), fixed_.end(), [object](const Fixed& f) { return f.object == object; });
    if (it == fixed_.end()) {
        fixed_.push_back(Fixed{object, cls, {}});
        it = std::prev(fixed_.end());
    }
    it->cls = cls;
    it->fixes.push_back(Fix{t, position});
    if (it->fixes.size() > kKeptFixes) {
        it->fixes.erase(it->fixes.begin());
    }
}

bool UavAnchors::interpolate(const Fixed& f, double t, Eigen::Vector2d& position, double& variance, int& bracket) const
{
    const auto after = std::find_if(f.fixes.begin(), f.fixes.end(), [t](const Fix& x) { return x.t >= t; });
    if (after == f.fixes.end() || after == f.fixes.begin()) {
        return false;
    }
    const Fix& a = *std::prev(after);
    const Fix& b = *after;
    const double span = b.t - a.t;
    if (span <= 0.0) {
        return false;
    }
    // The fastest the object walked between consecutive fixes kept: the longest path it can have taken here.
    double speed = 0.0;
    for (std::size_t k = 1; k < f.fixes.size(); ++k) {
        const double dt = f.fixes[k].t - f.fixes[k - 1].t;
        if (dt > 0.0) {
            speed = std::max(speed, (f.fixes[k].position - f.fixes[k - 1].position).norm() / dt);
        }
    }
    const double tau = (t - a.t) / span;
    const double chord = (b.position - a.position).norm();
    const double path = std::max(chord, speed * span);
    // Where a walker can be: within tau x path of a and (1 - tau) x path of b, so off the chord's point by at most
    // the lens's half-width, and by at most min(tau, 1 - tau) x (path + chord) near either fix.
    const double stray =
        std::min(std::sqrt(path * path - chord * chord) / 2.0, std::min(tau, 1.0 - tau) * (path + chord));
    position = a.position + tau * (b.position - a.position);
    const double uav2 = config_.uavSigmaM * config_.uavSigmaM;
    variance = uav2 * ((1.0 - tau) * (1.0 - tau) + tau * tau) + stray * stray;
    bracket = static_cast<int>(std::distance(f.fixes.begin(), after));
    return true;
}

void UavAnchors::resolve(const UgvPoseErrors& poses)
{
    double latest = -1.0;
    for (const Fixed& f : fixed_) {
        latest = std::max(latest, f.fixes.empty() ? -1.0 : f.fixes.back().t);
    }
    if (latest < 0.0) {
        return;
    }
    std::vector<Anchor> made;
    std::map<std::pair<int, double>, std::vector<std::size_t>> groups; // (object, t of the later fix) -> made
    std::vector<Held> waiting;
    for (const Held& h : pending_) {
        if (h.sample.t > latest) {
            waiting.push_back(h); // no fix after it yet
            continue;
        }
        Eigen::Vector2d p;
        Eigen::Matrix2d measurementCov;
        Eigen::Vector2d ray;
        poses.project(h.ugv, h.sample, p, nullptr, &measurementCov, &ray);
        const Eigen::Matrix2d gateCov = measurementCov + poses.priorPoseCovariance(h.sample, ray);
        int within = 0;
        Anchor anchor;
        std::pair<int, double> key;
        for (const Fixed& f : fixed_) {
            Eigen::Vector2d position;
            double variance = 0.0;
            int bracket = 0;
            if (f.cls != h.cls || !interpolate(f, h.sample.t, position, variance, bracket)) {
                continue;
            }
            const Eigen::Matrix2d cov = gateCov + variance * Eigen::Matrix2d::Identity();
            if (mahalanobis2(p - position, cov) < config_.gateChi2) {
                ++within;
                anchor = Anchor{h.ugv, h.sample, position, variance, 1.0};
                key = {f.object, f.fixes[static_cast<std::size_t>(bracket)].t};
            }
        }
        if (within == 1) { // none: not a fixed object; several: which one is unknown
            groups[key].push_back(made.size());
            made.push_back(anchor);
        }
    }
    for (const auto& [key, members] : groups) {
        for (const std::size_t m : members) {
            made[m].shares = static_cast<double>(members.size());
        }
    }
    anchors_.insert(anchors_.end(), made.begin(), made.end());
    pending_ = std::move(waiting);
    // Objects the UAV stopped fixing: nothing held can fall between their fixes any more.
    std::erase_if(fixed_, [this, latest](const Fixed& f) {
        return f.fixes.empty() || f.fixes.back().t < latest - config_.mobileTimeoutS;
    });
}

void UavAnchors::dropBefore(int oldestWindow, const UgvPoseErrors& poses)
{
    std::erase_if(anchors_, [&](const Anchor& a) { return poses.window(a.sample.t) < oldestWindow; });
}

} // namespace ugv::correlator
