#include "ugv/correlator/correlator_feed.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace ugv::correlator {

namespace {
constexpr double kMinusInf = -std::numeric_limits<double>::infinity();
constexpr double kPlusInf = std::numeric_limits<double>::infinity();
} // namespace

CorrelatorFeed::CorrelatorFeed(Mode mode, double periodS, double lateWindowS, Stopwatch stopwatch)
    : periodS_(periodS), lateWindowS_(std::max(0.0, lateWindowS)),
      checkpointS_(std::min(lateWindowS_ / 4.0, kCheckpointSpacingS)), stopwatch_(std::move(stopwatch))
{
    if (mode == Mode::PoseCorrected) {
        state_.correlator.emplace<PoseCorrectedCorrelator>();
    }
}

const char* CorrelatorFeed::mode() const noexcept
{
    return modeName(std::holds_alternative<PoseCorrectedCorrelator>(state_.correlator) ? Mode::PoseCorrected
                                                                                       : Mode::Original);
}

std::size_t CorrelatorFeed::storedPoints() const
{
    return std::visit([](const auto& c) { return c.storedPoints(); }, state_.correlator);
}

double CorrelatorFeed::now() const
{
    return stopwatch_ ? stopwatch_() : 0.0;
}

namespace {

/// The time of alternative I or a later one of `m`; std::visit would bring a throw path (a valueless variant).
template <std::size_t I = 0>
double timeFrom(const Message& m) noexcept
{
    if constexpr (I < std::variant_size_v<Message>) {
        if (const auto* x = std::get_if<I>(&m); x != nullptr) {
            return x->t;
        }
        return timeFrom<I + 1>(m);
    } else {
        return std::numeric_limits<double>::quiet_NaN(); // valueless: never made by our code
    }
}

} // namespace

double CorrelatorFeed::timeOf(const Message& m) noexcept
{
    return timeFrom(m);
}

double CorrelatorFeed::earliestAccepted() const noexcept
{
    if (!state_.last) {
        return kMinusInf; // nothing yet
    }
    if (checkpoints_.empty()) {
        return lastT();
    }
    return std::max(lastT() - lateWindowS_, checkpoints_.front().t);
}

bool CorrelatorFeed::isLate(const Message& message) const
{
    if (!state_.last) {
        return false;
    }
    // Without a window only an earlier time is out of order (equal times are taken as they come).
    return lateWindowS_ > 0.0 ? appliedBefore(message, *state_.last) : timeOf(message) < lastT();
}

Error CorrelatorFeed::tooLate(double t) const
{
    if (lateWindowS_ <= 0.0) {
        return Error{"", "time " + std::to_string(t) + " is before the previous message's " + std::to_string(lastT()),
                     "sort the input by time"};
    }
    if (t >= lastT() - lateWindowS_) {
        return Error{"",
                     "time " + std::to_string(t) + " is before the earliest time held for a replay (" +
                         std::to_string(earliestAccepted()) + ": the first message's, or " +
                         std::to_string(kMaxHeldMessages) + " messages held at most)",
                     "sort the input by time"};
    }
    return Error{"",
                 "time " + std::to_string(t) + " is more than the late window (" + std::to_string(lateWindowS_) +
                     " s) before the latest message's " + std::to_string(lastT()),
                 "sort the input by time, or raise the late window (correlator.late_window_s, correlate "
                 "--late-window-s)"};
}

Snapshot CorrelatorFeed::take(double t, const OnSnapshot& onSnapshot, double emitFrom)
{
    const auto t0 = now();
    Snapshot s = std::visit(
        [t](auto& c) {
            c.advance(t);
            return c.snapshot(t);
        },
        state_.correlator);
    snapshotBusyS_ += now() - t0;
    ++state_.snapshots;
    if (onSnapshot && t >= emitFrom) {
        onSnapshot(s);
    }
    return s;
}

void CorrelatorFeed::checkpoint(double t)
{
    checkpoints_.push_back(Checkpoint{t, heldBase_ + held_.size(), state_});
}

Result<void, Error> CorrelatorFeed::applyInOrder(const Message& message, double t, const OnSnapshot& onSnapshot,
                                                 double emitFrom)
{
    if (lateWindowS_ > 0.0) {
        if (std::isnan(state_.nextCheckpointT)) {
            state_.nextCheckpointT = std::floor(t / checkpointS_) * checkpointS_;
        }
        if (t >= state_.nextCheckpointT) {
            // The copy holds nextCheckpointT = its own time: a replay from it takes it again at the same place.
            checkpoint(state_.nextCheckpointT);
            state_.nextCheckpointT = (std::floor(t / checkpointS_) + 1.0) * checkpointS_;
        }
    }
    state_.last = message;
    if (std::isnan(state_.nextSnapshotT)) {
        state_.nextSnapshotT = (std::floor(t / periodS_) + 1.0) * periodS_;
    }
    for (std::size_t taken = 0; t >= state_.nextSnapshotT; ++taken) {
        if (taken == kMaxSnapshotsPerGap) { // a jump in time: on to the first boundary after t
            const double next = (std::floor(t / periodS_) + 1.0) * periodS_;
            state_.skippedSnapshots += static_cast<std::size_t>(std::llround((next - state_.nextSnapshotT) / periodS_));
            state_.nextSnapshotT = std::max(next, std::nextafter(t, kPlusInf));
            break;
        }
        take(state_.nextSnapshotT, onSnapshot, emitFrom);
        state_.nextSnapshotT += periodS_;
    }
    const auto t0 = now();
    auto done = std::visit([&message](auto& c) { return c.add(message); }, state_.correlator);
    addBusyS_ += now() - t0;
    if (done) {
        ++state_.applied;
        if (const auto* o = std::get_if<Observation>(&message)) {
            state_.ugvs[o->ugv] = UgvPose{o->ugvLat, o->ugvLon, o->ugvHeadingDeg};
        }
    }
    if (lateWindowS_ > 0.0) {
        held_.push_back(Held{t, message, static_cast<bool>(done), Held::kReplayed});
    }
    return done;
}

void CorrelatorFeed::prune()
{
    const double horizon = lastT() - lateWindowS_;
    while (checkpoints_.size() >= 2 && checkpoints_[1].t <= horizon) {
        checkpoints_.pop_front();
    }
    if (held_.size() > kMaxHeldMessages) {
        // Too much to replay: drop the oldest checkpoints (the window shrinks), all of them if need be.
        while (!checkpoints_.empty() && heldBase_ + held_.size() - checkpoints_.front().heldIndex > kMaxHeldMessages) {
            checkpoints_.pop_front();
        }
    }
    const std::size_t keepFrom = checkpoints_.empty() ? heldBase_ + held_.size() : checkpoints_.front().heldIndex;
    while (heldBase_ < keepFrom) {
        held_.pop_front();
        ++heldBase_;
    }
}

std::size_t CorrelatorFeed::add(std::span<const Message> batch, const OnSnapshot& onSnapshot,
                                const OnRefused& onRefused)
{
    const auto refuse = [&onRefused](const Message& m, const Error& e) {
        if (onRefused) {
            onRefused(m, e);
        }
    };
    // In the correlator's order (stable: equal keys keep the batch's order); too-late ones refused first (also a late
    // one with no checkpoint to go back to: all dropped by the cap).
    const double earliest = earliestAccepted();
    std::vector<Held> accepted;
    accepted.reserve(batch.size());
    for (std::size_t k = 0; k < batch.size(); ++k) {
        const double t = timeOf(batch[k]);
        if (!(std::abs(t) <= kMaxTimeS)) { // the readers refuse these; the order below needs finite times
            refuse(batch[k],
                   Error{"",
                         "time " + std::to_string(t) + " is not finite or beyond +-" + std::to_string(kMaxTimeS) + " s",
                         "fix the sender"});
        } else if (t < earliest || (checkpoints_.empty() && isLate(batch[k]))) {
            refuse(batch[k], tooLate(t));
        } else {
            accepted.push_back(Held{t, batch[k], false, k});
        }
    }
    std::stable_sort(accepted.begin(), accepted.end(),
                     [](const Held& a, const Held& b) { return appliedBefore(a.message, b.message); });
    if (accepted.empty()) {
        return 0;
    }
    std::size_t applied = 0;
    const auto applyFresh = [&](const Held& h, double emitFrom) {
        if (auto done = applyInOrder(h.message, h.t, onSnapshot, emitFrom); done) {
            ++applied;
        } else {
            refuse(batch[h.origin], done.error());
        }
    };
    if (!isLate(accepted.front().message)) {
        for (const Held& h : accepted) {
            applyFresh(h, kMinusInf);
        }
        prune();
        return applied;
    }

    // Re-sequencing: back to the newest checkpoint before the earliest message, then its later messages again,
    // merged with the batch. Boundaries given out before are not given out again.
    // NOLINTNEXTLINE(cppcoreguidelines-narrowing-conversions): clang-tidy 14 misreads the infinite constant (double)
    const double emitFrom = std::isnan(state_.nextSnapshotT) ? kMinusInf : state_.nextSnapshotT;
    auto from = std::find_if(checkpoints_.rbegin(), checkpoints_.rend(),
                             [&](const Checkpoint& c) { return c.t <= accepted.front().t; });
    // earliestAccepted() guarantees one (the oldest checkpoint is at or before it).
    for (const Held& h : accepted) {
        resequenced_ += isLate(h.message) ? 1U : 0U;
    }
    Checkpoint restored = std::move(*from);
    checkpoints_.erase(std::prev(from.base()), checkpoints_.end());
    const auto tailBegin = held_.begin() + static_cast<std::ptrdiff_t>(restored.heldIndex - heldBase_);
    std::vector<Held> tail(std::make_move_iterator(tailBegin), std::make_move_iterator(held_.end()));
    held_.erase(tailBegin, held_.end());
    state_ = std::move(restored.state);
    std::size_t i = 0;
    std::size_t j = 0;
    while (i < tail.size() || j < accepted.size()) {
        // On equal keys the message applied before stays first.
        if (j == accepted.size() || (i < tail.size() && !appliedBefore(accepted[j].message, tail[i].message))) {
            const Held& h = tail[i++];
            ++replayed_;
            auto done = applyInOrder(h.message, h.t, onSnapshot, emitFrom);
            if (!done && h.applied) {
                refuse(h.message, done.error());
            }
        } else {
            applyFresh(accepted[j++], emitFrom);
        }
    }
    prune();
    return applied;
}

Result<void, Error> CorrelatorFeed::add(const Message& message, const OnSnapshot& onSnapshot)
{
    std::optional<Error> error;
    const std::size_t applied =
        add(std::span<const Message>(&message, 1), onSnapshot, [&error, &message](const Message& m, const Error& e) {
            if (&m == &message) { // not a replayed message's refusal
                error = e;
            }
        });
    if (applied == 1) {
        return {};
    }
    return Unexpected(error.value_or(Error{"", "refused", ""}));
}

std::optional<Snapshot> CorrelatorFeed::finish(const OnSnapshot& onSnapshot)
{
    if (state_.applied == 0) {
        return std::nullopt;
    }
    return take(lastT(), onSnapshot, kMinusInf);
}

} // namespace ugv::correlator
