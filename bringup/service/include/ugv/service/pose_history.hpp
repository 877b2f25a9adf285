#pragma once

/// @file
/// The vehicle's recent poses (ugvsense/pose, from localisation at 2 Hz or more) and the pose at a frame's capture
/// time: linear between the two poses around it (heading the short way round), else the nearest one. Stale when
/// the nearest pose used is further than `maxAgeNs` from the capture time (localisation stopped, or lags).
///
/// Thread-safety: thread-bound (the bus task). RT-safe: no, but add() and at() allocate nothing after the first
/// `kCapacity` poses.

#include <cstdint>
#include <deque>

#include "ugv/ipc/dds_bus.hpp"

namespace ugv::service {

class PoseHistory {
public:
    static constexpr std::size_t kCapacity = 64; ///< 32 s at 2 Hz, 1.3 s at 50 Hz

    /// Keeps poses sorted by stamp (one arriving late is inserted in place); the oldest goes beyond kCapacity.
    void add(const ipc::dds::msg::VehiclePose& pose);
    /// The pose at `stampNs` (UNIX-epoch ns); false when there is none at all.
    bool at(std::int64_t stampNs, std::int64_t maxAgeNs, ipc::dds::msg::VehiclePose& out, bool& stale) const;
    [[nodiscard]] std::size_t size() const noexcept { return poses_.size(); }

private:
    std::deque<ipc::dds::msg::VehiclePose> poses_;
};

} // namespace ugv::service
