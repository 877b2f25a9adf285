#include "ugv/correlator/pose_corrected_correlator.hpp"

#include <algorithm>
#include <variant>

#include "ugv/correlator/measurement_model.hpp"
#include "ugv/correlator/rules.hpp"

namespace ugv::correlator {

PoseCorrectedCorrelator::PoseCorrectedCorrelator(const PoseCorrectedConfig& config)
    : config_(config), poses_(config), statics_(config), mobiles_(config), uav_(config), anchors_(config),
      solver_(config)
{
}

Result<void, Error> PoseCorrectedCorrelator::add(const Message& message)
{
    // UAV fixes of one instant are assigned together: the first message of a later instant ends them.
    if (uav_.pendingBefore(std::visit([](const auto& m) { return m.t; }, message))) {
        flushUav();
    }
    if (const auto* o = std::get_if<Observation>(&message)) {
        now_ = std::max(now_, o->t);
        if (!frame_) {
            frame_.emplace(o->ugvLat, o->ugvLon);
        }
        addObservation(*o);
    } else if (const auto* u = std::get_if<UavFix>(&message)) {
        now_ = std::max(now_, u->t);
        if (!frame_) {
            frame_.emplace(u->lat, u->lon);
        }
        uav_.add(*u, *frame_, mobiles_, ids_, anchors_);
    } else if (const auto* c = std::get_if<Confirm>(&message)) {
        now_ = std::max(now_, c->t);
        return confirm(*c);
    } else if (const auto* pc = std::get_if<PoseCorrection>(&message)) {
        now_ = std::max(now_, pc->t);
        poses_.addCorrection(*pc);
        rebuildStatics(); // stored observations re-project with the correction
    }
    if (now_ - lastSolveT_ >= config_.solvePeriodS) {
        lastSolveT_ = now_;
        solve();
    }
    return {};
}

void PoseCorrectedCorrelator::addObservation(const Observation& o)
{
    const int ugv = poses_.index(o.ugv);
    const RangeBearing sample{o.t, frame_->toLocal(o.ugvLat, o.ugvLon), o.ugvHeadingDeg * kRadPerDeg, o.rangeM,
                              o.bearingDeg * kRadPerDeg};
    if (rules::isMobileClass(o.cls)) {
        Eigen::Vector2d p;
        Eigen::Matrix2d cov;
        poses_.project(ugv, sample, p, &cov);
        mobiles_.add(o, p, cov, ids_);
        anchors_.observe(ugv, o.cls, sample);
    } else {
        statics_.add(o, ugv, sample, poses_, ids_);
    }
}

Result<void, Error> PoseCorrectedCorrelator::confirm(const Confirm& c)
{
    const auto found = ids_.find(c.id);
    if (!found) {
        return Unexpected(Error{"confirm", "unknown object id '" + c.id + "'", "use an id from a snapshot"});
    }
    if (found->isStatic) {
        statics_.setState(found->index, c.state);
    } else {
        mobiles_.setState(found->index, c.state);
    }
    return {};
}

void PoseCorrectedCorrelator::rebuildStatics()
{
    statics_.rebuild(poses_, ids_);
}

void PoseCorrectedCorrelator::solve()
{
    // Samples beyond the horizon fold into their object's prior first.
    const int oldestWindow = poses_.window(now_ - config_.horizonS);
    statics_.foldBeyondHorizon(oldestWindow);
    anchors_.dropBefore(oldestWindow, poses_);
    if (!solver_.estimate(statics_, poses_, anchors_)) {
        return;
    }
    rebuildStatics();
    solver_.learnNoise(statics_, poses_);
    solver_.learnPoseSpread(statics_, poses_);
    rebuildStatics();
}

void PoseCorrectedCorrelator::flushUav()
{
    uav_.flush(*frame_, mobiles_, ids_, anchors_);
    anchors_.resolve(poses_);
}

void PoseCorrectedCorrelator::advance(double t)
{
    if (frame_) { // without a frame nothing was added: no fix is pending
        flushUav();
    }
    statics_.dropTentative(t, ids_);
    statics_.markShown();
    mobiles_.timeOut(t);
}

Snapshot PoseCorrectedCorrelator::snapshot(double t) const
{
    Snapshot s;
    s.t = t;
    if (!frame_) {
        return s;
    }
    rules::Placed threats;
    rules::Placed civilians;
    statics_.publish(*frame_, poses_, s, threats);
    mobiles_.publish(t, *frame_, s, civilians, threats);
    rules::appendAlerts(s, civilians, threats);
    return s;
}

std::optional<PoseCorrectedCorrelator::PoseError> PoseCorrectedCorrelator::poseError(const std::string& ugv,
                                                                                     double t) const
{
    const auto index = poses_.find(ugv);
    if (!index) {
        return std::nullopt;
    }
    return PoseError{poses_.ugv(static_cast<std::size_t>(*index)).headingBias / kRadPerDeg, poses_.offsetAt(*index, t)};
}

std::optional<PoseCorrectedCorrelator::NoiseScale> PoseCorrectedCorrelator::noiseScale(const std::string& ugv) const
{
    const auto index = poses_.find(ugv);
    if (!index) {
        return std::nullopt;
    }
    const UgvPoseErrors::Ugv& u = poses_.ugv(static_cast<std::size_t>(*index));
    return NoiseScale{u.rangeScale, u.bearingScale};
}

} // namespace ugv::correlator
