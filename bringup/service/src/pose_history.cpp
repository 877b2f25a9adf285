#include "ugv/service/pose_history.hpp"

#include <algorithm>
#include <cmath>

namespace ugv::service {

namespace msg = ipc::dds::msg;

void PoseHistory::add(const msg::VehiclePose& pose)
{
    const auto later = std::upper_bound(poses_.begin(), poses_.end(), pose.stamp_ns(),
                                        [](std::int64_t t, const msg::VehiclePose& p) { return t < p.stamp_ns(); });
    if (later != poses_.begin() && std::prev(later)->stamp_ns() == pose.stamp_ns()) {
        *std::prev(later) = pose; // the same stamp again: the newer sample wins
        return;
    }
    poses_.insert(later, pose);
    if (poses_.size() > kCapacity) {
        poses_.pop_front();
    }
}

bool PoseHistory::at(std::int64_t stampNs, std::int64_t maxAgeNs, msg::VehiclePose& out, bool& stale) const
{
    if (poses_.empty()) {
        return false;
    }
    const auto after = std::lower_bound(poses_.begin(), poses_.end(), stampNs,
                                        [](const msg::VehiclePose& p, std::int64_t t) { return p.stamp_ns() < t; });
    if (after == poses_.begin() || after == poses_.end()) {
        out = after == poses_.end() ? poses_.back() : poses_.front();
        stale = std::llabs(out.stamp_ns() - stampNs) > maxAgeNs;
        return true;
    }
    const msg::VehiclePose& a = *std::prev(after);
    const msg::VehiclePose& b = *after;
    const double w = static_cast<double>(stampNs - a.stamp_ns()) / static_cast<double>(b.stamp_ns() - a.stamp_ns());
    const auto lerp = [w](double x, double y) { return x + w * (y - x); };
    out = w < 0.5 ? a : b; // vehicle name, covariance of the nearer one
    out.stamp_ns(stampNs);
    out.latitude_deg(lerp(a.latitude_deg(), b.latitude_deg()));
    out.longitude_deg(lerp(a.longitude_deg(), b.longitude_deg())); // poses 0.5 s apart: never across the antimeridian
    out.altitude_m(lerp(a.altitude_m(), b.altitude_m()));
    out.east_m(lerp(a.east_m(), b.east_m()));
    out.north_m(lerp(a.north_m(), b.north_m()));
    out.up_m(lerp(a.up_m(), b.up_m()));
    const double turn = std::remainder(b.heading_deg() - a.heading_deg(), 360.0); // the short way round
    double heading = std::fmod(a.heading_deg() + w * turn, 360.0);
    out.heading_deg(heading < 0.0 ? heading + 360.0 : heading);
    stale = std::min(stampNs - a.stamp_ns(), b.stamp_ns() - stampNs) > maxAgeNs;
    return true;
}

} // namespace ugv::service
