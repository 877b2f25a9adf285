#pragma once

/// @file
/// The OOI correlator on the bus: the ground station's (or a vehicle's) lowest-priority task.
///
///   ugvsense/ooi/{observations,uav,confirmations,pose_corrections}  (reliable, transient local)
///     -> check (NaN, latitude, enums, names: refused and counted) -> duplicates dropped by (sender, sequence)
///     -> flood guard per participant -> reorder buffer (time order across senders, `reorderMs` of wall time;
///        `startupHoldMs` after the first input: the histories of the team)
///     -> CorrelatorFeed (the offline tool's own driver) -> inputs.jsonl
///     -> every snapshot: snapshots.jsonl and ugvsense/ooi/correlated (reliable, transient local, keep last 1)
///
/// Same results as `ugvsense correlate` on the same messages: inputs.jsonl holds every message given to the feed,
/// in order, so `ugvsense correlate --input inputs.jsonl` writes the same snapshots.jsonl (a test checks it).
///
/// Duplicates: a sender numbers its samples; one at or below the highest number seen from that sender is a
/// duplicate (a restarted sender replaying its file, a writer's history replayed to this reader). Reliable
/// delivery is in order per writer, so nothing new is dropped; numbers must grow across a sender's restarts.
///
/// An input that arrives after later-stamped ones were applied (a UGV back from a radio dropout, a repair slower than
/// `reorderMs`) is put in its place by the feed when it is at most `lateWindowS` older than the latest: the
/// correlator is rolled back to a checkpoint and replayed (CorrelatorFeed), so the list does not depend on arrival
/// order. Older ones are refused, counted and logged. What one poll releases is one batch: one replay at most.
///
/// Flood guard: a token bucket per participant over the samples' source timestamps (`maxRatePerSource` per
/// second, a burst of one second's worth). A writer's history replayed to a late or restarted reader keeps its
/// original timestamps and passes; a participant writing faster than the rate is refused beyond it, counted. A
/// sample stamped more than `maxClockSkewMs` ahead of this host's clock is refused too (counted apart): a sender
/// could otherwise buy itself tokens by stamping its samples far apart, so the guard bounds what any participant
/// gets through by the rate times the real time elapsed (plus the skew). Hosts must keep their clocks within the
/// skew of each other (chrony / NTP); a warning names a sender that does not.
///
/// Thread-safety: thread-bound (one task). RT-safe: no; it runs at the lowest priority, never on the frame path.

#include <chrono>
#include <cstdint>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <tuple>
#include <unordered_map>

#include "ugv/correlator/correlator_feed.hpp"
#include "ugv/ipc/dds_bus.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/rt/thread_runner.hpp"

namespace ugv::service {

struct LiveCorrelatorOptions {
    correlator::Mode mode = correlator::Mode::PoseCorrected;
    double periodS = 1.0;
    double reorderMs = 2000.0;
    double lateWindowS = 300.0; ///< [s] CorrelatorFeed's late window
    /// After the first input arrives, nothing is applied for this long: a (re)started station first gathers the
    /// team's transient-local histories, which come all at once and, on a lossy link, repaired over seconds.
    double startupHoldMs = 10000.0;
    double maxRatePerSource = 2000.0;
    double maxClockSkewMs = 5000.0; ///< [ms] samples stamped further ahead of this host's clock are refused
    std::string logDir;             ///< empty: no logs
    bool publish = true;            ///< publish ugvsense/ooi/correlated (false: a viewer such as correlate --from-dds)
    std::string source = "gcs";     ///< the source name of the published list
};

struct LiveCorrelatorStats {
    std::uint64_t received = 0;     ///< samples taken from the readers
    std::uint64_t rejected = 0;     ///< refused by the checks (malformed, hostile)
    std::uint64_t duplicates = 0;   ///< (sender, sequence) seen before
    std::uint64_t impersonated = 0; ///< secured bus: named a sender other than the writer's identity (dropped)
    std::uint64_t flooded = 0;      ///< refused by the flood guard (aheadOfClock included)
    std::uint64_t aheadOfClock = 0; ///< of them: stamped more than maxClockSkewMs ahead of this host's clock
    std::uint64_t refused = 0;      ///< given to the correlator and refused (older than the window, unknown id)
    std::uint64_t resequenced = 0;  ///< applied after later-stamped inputs (put in place by a replay)
    std::uint64_t applied = 0;
    std::uint64_t published = 0; ///< correlated lists written
    std::size_t waiting = 0;     ///< in the reorder buffer now
};

class LiveCorrelator {
public:
    /// Creates the readers (and the writer), opens the logs in `logDir` (existing ones are renamed
    /// inputs.N.jsonl / snapshots.N.jsonl, never overwritten).
    static Result<std::unique_ptr<LiveCorrelator>, Error> create(ipc::dds::Bus& bus,
                                                                 const LiveCorrelatorOptions& options);

    /// Waits up to `timeout` for an observation (the busiest input).
    void waitForInput(std::chrono::milliseconds timeout);
    /// Takes what arrived, applies what waited long enough (steady clock `nowNs`), publishes new snapshots.
    void poll(std::int64_t nowNs);
    /// Takes what arrived, applies everything still waiting, takes and publishes the final snapshot, flushes.
    std::optional<correlator::Snapshot> finish();

    [[nodiscard]] LiveCorrelatorStats stats() const;
    [[nodiscard]] const correlator::CorrelatorFeed& feed() const noexcept { return feed_; }
    /// The latest snapshot taken (empty before the first).
    [[nodiscard]] const correlator::Snapshot& latest() const noexcept { return latest_; }
    /// Problems seen (the first ones of each kind, for the log), drained by the caller.
    std::vector<std::string> takeWarnings();

private:
    explicit LiveCorrelator(const LiveCorrelatorOptions& options);
    struct Pending {
        correlator::Message message;
        std::int64_t arrivalNs = 0;
    };
    struct Bucket {
        double tokens = 0.0;
        std::int64_t lastSourceNs = 0;
    };
    template <class Sample>
    void drain(ipc::dds::Reader<Sample>& reader, std::int64_t nowNs);
    bool admit(const std::string& sender, std::uint64_t sequence, const eprosima::fastdds::dds::SampleInfo& info);
    /// On a secured bus: whether the sample's writer writes in the partition of `name` (the only one its
    /// permissions allow it); always true on an open bus.
    bool sentByItsOwner(const std::string& name, ipc::dds::TopicId topic,
                        const eprosima::fastdds::dds::SampleInfo& info);
    void apply(std::span<const correlator::Message> batch);
    void onSnapshot(const correlator::Snapshot& s);
    /// A problem with one input: the first kMaxWarnings are kept for the log, the rest only counted.
    void warn(const std::string& text);
    /// A condition reported once per run (a flood, a sender's clock): always kept, apart from the cap.
    void warnOnce(const std::string& text);

    LiveCorrelatorOptions options_;
    correlator::CorrelatorFeed feed_;
    const ipc::dds::Bus* securedBus_ = nullptr; ///< set on a secured bus: who wrote each sample
    ipc::dds::Reader<ipc::dds::msg::OoiObservation> observations_;
    ipc::dds::Reader<ipc::dds::msg::UavObservation> uav_;
    ipc::dds::Reader<ipc::dds::msg::ConfirmationState> confirmations_;
    ipc::dds::Reader<ipc::dds::msg::PoseCorrection> corrections_;
    ipc::dds::Writer<ipc::dds::msg::CorrelatedOoiList> out_;
    /// In the correlator's order (correlator::orderKey), then sender and sequence number: the same inputs come out
    /// in the same order whatever the order they arrived in (a restarted ground station replays them as the first
    /// one did).
    std::map<std::tuple<correlator::OrderKey, std::string, std::uint64_t>, Pending> reorder_;
    std::unordered_map<std::string, std::uint64_t> highestSeq_; ///< per sender
    std::unordered_map<std::string, Bucket> buckets_;           ///< per participant (GUID prefix)
    std::ofstream inputsLog_;
    std::ofstream snapshotsLog_;
    correlator::Snapshot latest_;
    ipc::dds::msg::CorrelatedOoiList sample_;
    LiveCorrelatorStats stats_;
    std::vector<std::string> warnings_;
    std::vector<correlator::Message> batch_; ///< released by one poll
    std::uint64_t warned_ = 0;
    std::int64_t firstArrivalNs_ = 0;
};

/// The LiveCorrelator on its own thread: the task table's "correlator" row (SCHED_OTHER by default, below every
/// frame-path task), polling every 50 ms at most. stop() applies what is still waiting and takes the last snapshot.
class CorrelatorTask {
public:
    static Result<std::unique_ptr<CorrelatorTask>, Error>
    create(ipc::dds::Bus& bus, const LiveCorrelatorOptions& options, const rt::TaskSpec& spec);
    ~CorrelatorTask();
    CorrelatorTask(const CorrelatorTask&) = delete;
    CorrelatorTask& operator=(const CorrelatorTask&) = delete;
    CorrelatorTask(CorrelatorTask&&) = delete;
    CorrelatorTask& operator=(CorrelatorTask&&) = delete;
    void start() noexcept;
    /// Joins the thread, then finish(). Idempotent.
    void stop();
    /// Stats as of the last poll (any thread).
    [[nodiscard]] LiveCorrelatorStats stats() const;
    [[nodiscard]] const LiveCorrelator& correlator() const noexcept { return *live_; }

private:
    CorrelatorTask() = default;
    static void body(void* self, const std::atomic<bool>& stop);

    std::unique_ptr<LiveCorrelator> live_;
    rt::ThreadRunner runner_;
    mutable std::mutex statsMutex_; ///< the task and a reader of stats(); never on the frame path
    LiveCorrelatorStats stats_;
    bool stopped_ = false;
};

} // namespace ugv::service
