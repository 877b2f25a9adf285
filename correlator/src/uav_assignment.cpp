#include "ugv/correlator/uav_assignment.hpp"

#include <cmath>

#include "ugv/correlator/gospa.hpp"
#include "ugv/correlator/measurement_model.hpp"

namespace ugv::correlator {
namespace {

constexpr double kMaxWalkSpeedMps = 2.5; ///< farther than a person walks since the last estimate: another object
constexpr double kReachSigmas = 3.0;
constexpr double kReachMaxAgeS = 20.0;       ///< an object unseen longer than this is only reached through its gate
constexpr double kForbiddenCostFactor = 1e6; ///< x the new-object cost: a pair that may not be assigned

OoiClass classOf(const UavFix& fix) noexcept
{
    return fix.cls == OoiClass::NonCombatant ? OoiClass::NonCombatant : OoiClass::Mobile;
}

} // namespace

UavAssignment::UavAssignment(const PoseCorrectedConfig& config) : config_(config) {}

void UavAssignment::add(const UavFix& fix, const LocalFrame& frame, MobileTracker& tracker, ObjectIds& ids,
                        UavAnchors& anchors)
{
    if (!pending_.empty() && pending_.front().t != fix.t) {
        flush(frame, tracker, ids, anchors);
    }
    pending_.push_back(fix);
}

std::vector<double> UavAssignment::costs(const std::vector<Eigen::Vector2d>& fixes, const std::vector<int>& candidates,
                                         const MobileTracker& tracker) const
{
    const Eigen::Matrix2d r = config_.uavSigmaM * config_.uavSigmaM * Eigen::Matrix2d::Identity();
    const double newObjectCost = config_.gateChi2 + 1.0; // above every pair: gated < gate, reached < gate + 1
    const double forbidden = kForbiddenCostFactor * newObjectCost;
    const std::size_t fixCount = fixes.size();
    const std::size_t cols = fixCount + candidates.size();
    std::vector<double> cost(fixCount * cols, forbidden);
    for (std::size_t k = 0; k < fixCount; ++k) {
        const UavFix& u = pending_[k];
        const Eigen::Vector2d& z = fixes[k];
        cost[k * cols + k] = newObjectCost;
        for (std::size_t c = 0; c < candidates.size(); ++c) {
            const MobileTracker::Mobile& m = tracker.mobiles()[static_cast<std::size_t>(candidates[c])];
            if (m.cls != classOf(u)) {
                continue;
            }
            Eigen::Vector2d p;
            Eigen::Matrix2d cov;
            tracker.predictPosition(m, u.t, p, cov);
            const double d2 = mahalanobis2(z - p, cov + r);
            const double age = u.t - m.t;
            const double reach = kMaxWalkSpeedMps * age + kReachSigmas * std::sqrt(m.p.topLeftCorner<2, 2>().trace());
            const double d = (z - m.x.head<2>()).norm();
            if (d2 < config_.gateChi2) {
                cost[k * cols + fixCount + c] = d2;
            } else if (age <= kReachMaxAgeS && d <= reach) {
                cost[k * cols + fixCount + c] = config_.gateChi2 + d / reach;
            }
        }
    }
    return cost;
}

void UavAssignment::flush(const LocalFrame& frame, MobileTracker& tracker, ObjectIds& ids, UavAnchors& anchors)
{
    if (pending_.empty()) {
        return;
    }
    const Eigen::Matrix2d r = config_.uavSigmaM * config_.uavSigmaM * Eigen::Matrix2d::Identity();
    const double forbidden = kForbiddenCostFactor * (config_.gateChi2 + 1.0);
    const std::size_t fixCount = pending_.size();
    std::vector<Eigen::Vector2d> fixes;
    for (const UavFix& u : pending_) {
        fixes.push_back(frame.toLocal(u.lat, u.lon));
    }
    std::vector<int> candidates; // mobile indices of the columns after the fixes' own "new object" columns
    for (int i = 0; i < static_cast<int>(tracker.mobiles().size()); ++i) {
        if (tracker.mobiles()[static_cast<std::size_t>(i)].alive) {
            candidates.push_back(i);
        }
    }
    const std::size_t cols = fixCount + candidates.size();
    const std::vector<double> cost = costs(fixes, candidates, tracker);
    const std::vector<int> column = solveAssignment(cost, fixCount, cols);
    for (std::size_t k = 0; k < fixCount; ++k) {
        const UavFix& u = pending_[k];
        const int c = column[k];
        const bool matched =
            c >= static_cast<int>(fixCount) && cost[k * cols + static_cast<std::size_t>(c)] < forbidden;
        int index = matched ? candidates[static_cast<std::size_t>(c) - fixCount] : -1;
        if (index < 0) {
            index = tracker.create(classOf(u), fixes[k], r, u.t, ids);
        } else {
            tracker.update(index, fixes[k], r, u.t);
        }
        tracker.markFixedByUav(index);
        anchors.fix(index, classOf(u), u.t, fixes[k]);
    }
    pending_.clear();
}

} // namespace ugv::correlator
