#pragma once

/// @file
/// The correlator driven by a time-ordered stream of messages, the same way for every caller: the offline tool
/// (`ugvsense correlate` on a JSON-lines file), the live task on the bus (bringup/service/correlator_task.hpp) and
/// `correlate --from-dds`. Same messages in the same order give the same snapshots, by construction.
///
/// Rules: a message older than the previous one is refused ("sort the input by time"); a snapshot is taken at every
/// period boundary of mission time that a message passes (boundaries at multiples of the period); finish() takes
/// the last one at the last message's time.
///
/// Thread-safety: thread-bound. RT-safe: no.

#include <chrono>
#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <variant>

#include "ugv/correlator/improved_correlator.hpp"
#include "ugv/correlator/original_correlator.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::bringup {

/// The last reported pose of a UGV (the map draws it).
struct UgvPose {
    double lat = 0.0;
    double lon = 0.0;
    double headingDeg = 0.0;
};

class CorrelatorFeed {
public:
    using OnSnapshot = std::function<void(const correlator::Snapshot&)>;

    /// @param improved mode improved (else original)
    /// @param periodS  snapshot period in mission time [s], > 0
    CorrelatorFeed(bool improved, double periodS);

    /// Applies one message; every period boundary it passes first gives a snapshot to `onSnapshot`.
    /// Errors: out of time order, or the correlator refused it (unknown id, ...): nothing changed.
    Result<void, Error> add(const correlator::Message& message, const OnSnapshot& onSnapshot);
    /// The snapshot at the last message's time (nullopt when none was applied); given to `onSnapshot` too.
    std::optional<correlator::Snapshot> finish(const OnSnapshot& onSnapshot);

    [[nodiscard]] std::size_t applied() const noexcept { return applied_; }
    [[nodiscard]] std::size_t snapshots() const noexcept { return snapshots_; }
    [[nodiscard]] double lastT() const noexcept { return lastT_; }
    [[nodiscard]] std::size_t storedPoints() const;
    [[nodiscard]] const std::map<std::string, UgvPose>& ugvs() const noexcept { return ugvs_; }
    [[nodiscard]] std::chrono::nanoseconds addTime() const noexcept { return addBusy_; }
    [[nodiscard]] std::chrono::nanoseconds snapshotTime() const noexcept { return snapshotBusy_; }
    [[nodiscard]] const char* mode() const noexcept;

private:
    correlator::Snapshot take(double t, const OnSnapshot& onSnapshot);

    std::variant<correlator::OriginalCorrelator, correlator::ImprovedCorrelator> correlator_;
    double periodS_;
    double lastT_ = -1e300;
    double nextSnapshotT_;
    std::size_t applied_ = 0;
    std::size_t snapshots_ = 0;
    std::map<std::string, UgvPose> ugvs_;
    std::chrono::nanoseconds addBusy_{0};
    std::chrono::nanoseconds snapshotBusy_{0};
};

} // namespace ugv::bringup
