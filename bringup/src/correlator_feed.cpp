#include "ugv/bringup/correlator_feed.hpp"

#include <cmath>

namespace ugv::bringup {

using namespace correlator;

CorrelatorFeed::CorrelatorFeed(bool improved, double periodS) : periodS_(periodS), nextSnapshotT_(NAN)
{
    if (improved) {
        correlator_.emplace<ImprovedCorrelator>();
    }
}

const char* CorrelatorFeed::mode() const noexcept
{
    return std::holds_alternative<ImprovedCorrelator>(correlator_) ? "improved" : "original";
}

std::size_t CorrelatorFeed::storedPoints() const
{
    return std::visit([](const auto& c) { return c.storedPoints(); }, correlator_);
}

Snapshot CorrelatorFeed::take(double t, const OnSnapshot& onSnapshot)
{
    const auto t0 = std::chrono::steady_clock::now();
    Snapshot s = std::visit([t](auto& c) { return c.snapshot(t); }, correlator_);
    snapshotBusy_ += std::chrono::steady_clock::now() - t0;
    ++snapshots_;
    if (onSnapshot) {
        onSnapshot(s);
    }
    return s;
}

Result<void, Error> CorrelatorFeed::add(const Message& message, const OnSnapshot& onSnapshot)
{
    const double t = std::visit([](const auto& m) { return m.t; }, message);
    if (t < lastT_) {
        return Unexpected(
            Error{"", "time " + std::to_string(t) + " is before the previous message's " + std::to_string(lastT_),
                  "sort the input by time"});
    }
    lastT_ = t;
    if (std::isnan(nextSnapshotT_)) {
        nextSnapshotT_ = (std::floor(t / periodS_) + 1.0) * periodS_;
    }
    while (t >= nextSnapshotT_) {
        take(nextSnapshotT_, onSnapshot);
        nextSnapshotT_ += periodS_;
    }
    const auto t0 = std::chrono::steady_clock::now();
    auto done = std::visit([&message](auto& c) { return c.add(message); }, correlator_);
    addBusy_ += std::chrono::steady_clock::now() - t0;
    if (!done) {
        return done;
    }
    ++applied_;
    if (const auto* o = std::get_if<Observation>(&message)) {
        ugvs_[o->ugv] = UgvPose{o->ugvLat, o->ugvLon, o->ugvHeadingDeg};
    }
    return {};
}

std::optional<Snapshot> CorrelatorFeed::finish(const OnSnapshot& onSnapshot)
{
    if (applied_ == 0) {
        return std::nullopt;
    }
    return take(lastT_, onSnapshot);
}

} // namespace ugv::bringup
