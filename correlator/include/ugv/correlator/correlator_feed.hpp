#pragma once

/// @file
/// The correlator driven by a stream of messages in mission-time order, the same way for every caller: the offline
/// tool (`ugvsense correlate` on a JSON-lines file), the live task on the bus
/// (bringup/service/include/ugv/service/correlator_task.hpp) and `correlate --from-dds`. Same messages in the same
/// order give the same snapshots, by construction.
///
/// Rules: a snapshot is taken at every period boundary of mission time that a message passes (boundaries at
/// multiples of the period), at most kMaxSnapshotsPerGap for one message: the boundaries of a longer gap (a jump in
/// time) are skipped and counted (skippedSnapshots()); finish() takes the last one at the last message's time. Times
/// beyond +-kMaxTimeS are refused.
///
/// Late messages (re-sequencing): a message that comes before the latest applied one in the correlator's order
/// (appliedBefore: by time, equal times by a fixed rule) is put in its place when it is at most
/// `lateWindowS` older. The feed keeps checkpoints of the correlator (copies, taken every min(lateWindowS / 4,
/// kCheckpointSpacingS) of mission time, at multiples of it) and the messages applied since the oldest; a late
/// message rolls the state back to the newest checkpoint before it, and the messages from there are applied again,
/// merged with it in the correlator's order (on equal keys the one applied first stays first). The state is then
/// exactly that of the same messages given in that order (a test checks it). Snapshots of boundaries already given
/// out are taken again during the replay (the advance() before each is part of the correlator's state) but not
/// given out again;
/// the next boundary gives the corrected picture. An older message is refused ("sort the input by time"); with
/// lateWindowS = 0 so is any earlier one, and equal times are taken as they come.
/// Memory: one checkpoint per spacing over the window, and the messages of the window plus a spacing, capped at
/// kMaxHeldMessages (older checkpoints are dropped first, which shortens the window). A replay costs the messages
/// since its checkpoint: a batch (add of several) replays once.
///
/// Thread-safety: thread-bound. RT-safe: no.

#include <cmath>
#include <cstddef>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <variant>

#include "ugv/correlator/messages.hpp"
#include "ugv/correlator/mode.hpp"
#include "ugv/correlator/original_correlator.hpp"
#include "ugv/correlator/pose_corrected_correlator.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::correlator {

/// The last reported pose of a UGV (the map draws it).
struct UgvPose {
    double lat = 0.0;
    double lon = 0.0;
    double headingDeg = 0.0;
};

class CorrelatorFeed {
public:
    using OnSnapshot = std::function<void(const Snapshot&)>;
    using OnRefused = std::function<void(const Message&, const Error&)>;
    /// A reading [s] of the caller's monotonic clock, taken around add() and snapshot() for addSeconds() and
    /// snapshotSeconds(): the feed reads no clock of its own (mission time comes with the messages).
    using Stopwatch = std::function<double()>;

    /// Messages held for replays, at most (about 300 bytes each).
    static constexpr std::size_t kMaxHeldMessages = 500'000;
    /// Checkpoint spacing at most [s] (also lateWindowS / 4 at most): what a replay goes back beyond the message.
    static constexpr double kCheckpointSpacingS = 30.0;
    /// Snapshots one message gives out at most: a jump from t 0 to 1e9 would otherwise ask for 10^9.
    static constexpr std::size_t kMaxSnapshotsPerGap = 1000;
    /// Message times beyond +-this are refused [s] (as the JSON reader, bringup/correlate_io.hpp).
    static constexpr double kMaxTimeS = 1e10;

    /// @param mode         which correlator
    /// @param periodS      snapshot period in mission time [s], > 0
    /// @param lateWindowS  how much older than the latest applied message a message may be and still be put in its
    ///                     place [s], >= 0 (0: refused)
    /// @param stopwatch    the caller's monotonic clock for addSeconds()/snapshotSeconds(); empty: both stay 0
    CorrelatorFeed(Mode mode, double periodS, double lateWindowS = 0.0, Stopwatch stopwatch = {});

    /// Applies one message; every new period boundary it passes first gives a snapshot to `onSnapshot`.
    /// Errors: too late (see the file comment), or the correlator refused it (unknown id, ...): nothing changed.
    Result<void, Error> add(const Message& message, const OnSnapshot& onSnapshot);
    /// Applies several messages (any order; sorted by time here, stably): one replay at most. Each refused message
    /// goes to `onRefused` (also one applied before that a replay now refuses: its place in time changed).
    /// @return the number of messages of `batch` applied
    std::size_t add(std::span<const Message> batch, const OnSnapshot& onSnapshot, const OnRefused& onRefused);
    /// The snapshot at the last message's time (nullopt when none was applied); given to `onSnapshot` too.
    std::optional<Snapshot> finish(const OnSnapshot& onSnapshot);

    [[nodiscard]] std::size_t applied() const noexcept { return state_.applied; }
    [[nodiscard]] std::size_t snapshots() const noexcept { return state_.snapshots; }
    /// Period boundaries skipped because one message passed more than kMaxSnapshotsPerGap of them.
    [[nodiscard]] std::size_t skippedSnapshots() const noexcept { return state_.skippedSnapshots; }
    /// Late messages put in their place, and the messages applied again for them.
    [[nodiscard]] std::size_t resequenced() const noexcept { return resequenced_; }
    [[nodiscard]] std::size_t replayed() const noexcept { return replayed_; }
    /// The earliest time a message can have now and still be applied (-inf before the first).
    [[nodiscard]] double earliestAccepted() const noexcept;
    [[nodiscard]] std::size_t storedPoints() const;
    [[nodiscard]] const std::map<std::string, UgvPose>& ugvs() const noexcept { return state_.ugvs; }
    /// [s] spent in the correlator's add() and in advance() + snapshot(), by the stopwatch given (0 without one).
    [[nodiscard]] double addSeconds() const noexcept { return addBusyS_; }
    [[nodiscard]] double snapshotSeconds() const noexcept { return snapshotBusyS_; }
    [[nodiscard]] const char* mode() const noexcept;

private:
    /// Everything a replay restores.
    struct State {
        std::variant<OriginalCorrelator, PoseCorrectedCorrelator> correlator;
        double nextSnapshotT = NAN;
        double nextCheckpointT = NAN;
        std::size_t applied = 0;
        std::size_t snapshots = 0;
        std::size_t skippedSnapshots = 0;
        std::map<std::string, UgvPose> ugvs;
        std::optional<Message> last; ///< the last message applied (or refused by the correlator)
    };
    struct Checkpoint {
        double t = 0.0;            ///< every message before t is in `state`, none at or after it
        std::size_t heldIndex = 0; ///< absolute index of the first held message after it
        State state;
    };
    struct Held {
        static constexpr std::size_t kReplayed = static_cast<std::size_t>(-1);
        double t = 0.0;
        Message message;
        bool applied = false;           ///< the correlator took it (when last applied)
        std::size_t origin = kReplayed; ///< index in the batch being added, or kReplayed
    };

    static double timeOf(const Message& m) noexcept;
    /// The time of the last message applied (call only when there is one).
    [[nodiscard]] double lastT() const noexcept { return timeOf(*state_.last); }
    /// Applies a message not older than the last one. Snapshots of boundaries at or after `emitFrom` are given out.
    Result<void, Error> applyInOrder(const Message& message, double t, const OnSnapshot& onSnapshot, double emitFrom);
    Snapshot take(double t, const OnSnapshot& onSnapshot, double emitFrom);
    void checkpoint(double t);
    /// Drops checkpoints older than the window (or beyond kMaxHeldMessages) and the messages before the oldest.
    void prune();
    Error tooLate(double t) const;
    /// The stopwatch's time (0 without one).
    [[nodiscard]] double now() const;
    /// Before the last message in the correlator's order (appliedBefore; without a window: earlier).
    bool isLate(const Message& message) const;

    State state_;
    double periodS_;
    double lateWindowS_;
    double checkpointS_; ///< checkpoint spacing: min(lateWindowS / 4, kCheckpointSpacingS)
    std::deque<Checkpoint> checkpoints_;
    std::deque<Held> held_;    ///< the messages applied since the oldest checkpoint, in the order applied
    std::size_t heldBase_ = 0; ///< absolute index of held_.front()
    std::size_t resequenced_ = 0;
    std::size_t replayed_ = 0;
    Stopwatch stopwatch_;
    double addBusyS_ = 0.0;      ///< [s]
    double snapshotBusyS_ = 0.0; ///< [s]
};

} // namespace ugv::correlator
