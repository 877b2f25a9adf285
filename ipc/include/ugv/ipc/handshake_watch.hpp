#pragma once
/// @file
/// Which secured handshakes never ended. Fast DDS 2.9.1 sometimes leaves the authentication of two participants that
/// join at the same moment unfinished for good: each discovered the other, neither is ever authorised or refused,
/// and no sample passes between them (measured here: 2 of 7 runs of test system.team-bus.secured beside a CPU load,
/// one pair of 5 participants stalled for 150 s while every other pair ended in 1 s). The bus watches for such pairs
/// so that a process can say so and join again (Bus::stalledHandshakes(), Bus::rejoinIfStalled()).
///
/// A handshake with a participant of another CA never ends on one side either: Fast DDS 2.9.1 refuses it on the
/// side that checks its certificate and reports nothing, ever, on the other (measured). Joining again cannot help
/// there, so each peer is noted with whether the identity token it announces in discovery names this team's CA
/// (`dds.ca.sn`, the CA's subject); only those count as stalled. The token is not checked (a rogue may name our
/// CA): the worst it can do is make a process join again at RejoinBackoff's pace.
///
/// Plain bookkeeping, fed by the participant listener: thread-safe, no Fast DDS types.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <unordered_map>
#include <unordered_set>

namespace ugv::ipc::dds {

class HandshakeWatch {
public:
    using Clock = std::chrono::steady_clock;
    /// Entries kept at most: a flood of participants that join and never answer cannot grow the table without end
    /// (the oldest unfinished ones are then forgotten, and so not reported).
    static constexpr std::size_t kMaxEntries = 4096;

    /// Handshakes (or peers) of one local participant, by the CA the peer names.
    struct ByCa {
        std::size_t sameCa = 0;  ///< with peers naming this team's CA (unfinished: stalled; joining again may help)
        std::size_t otherCa = 0; ///< with peers naming another CA or none (unfinished: refused by them)
    };

    /// `local` discovered remote participant `remote` at `at` (its handshake starts); `sameCa`: its identity token
    /// names this team's CA.
    void discovered(const std::string& local, const std::string& remote, Clock::time_point at, bool sameCa);
    /// The handshake of `local` with `remote` ended (authorised or refused).
    void ended(const std::string& local, const std::string& remote);
    /// `remote` left or was dropped by `local`.
    void removed(const std::string& local, const std::string& remote);
    /// Everything of participant `local` (deleted: a renewed bus has a new one).
    void forget(const std::string& local);
    /// `local`'s handshakes that started before `now - olderThan` and have not ended.
    [[nodiscard]] ByCa unfinished(const std::string& local, Clock::time_point now, Clock::duration olderThan) const;
    /// Every peer `local` discovered and has not lost, ended or not, by CA (tests and diagnostics).
    [[nodiscard]] ByCa peers(const std::string& local) const;
    /// How many of them are with peers of this team's CA (unfinished().sameCa).
    [[nodiscard]] std::size_t stalled(const std::string& local, Clock::time_point now, Clock::duration olderThan) const
    {
        return unfinished(local, now, olderThan).sameCa;
    }

private:
    struct Entry {
        Clock::time_point since;
        bool ended = false;
        bool sameCa = true; ///< an end reported before the discovery: unknown, and ended anyway
    };
    static std::string key(const std::string& local, const std::string& remote) { return local + '|' + remote; }
    /// `local`'s entries that started by `startedBy` (and have not ended, with `unfinishedOnly`), by CA.
    ByCa count(const std::string& local, Clock::time_point startedBy, bool unfinishedOnly) const;
    void trim();

    mutable std::mutex mutex_;
    std::unordered_map<std::string, Entry> entries_; ///< local|remote -> when discovered, and whether it ended
};

/// The GUID prefixes of the participants the secured bus refused (after a refused handshake, or at discovery when a
/// participant names another CA), whose datagrams its UDP transport then drops on arrival (shared memory is not
/// filtered: dds_bus.cpp). Fast DDS 2.9.1 answers every handshake request of a refused participant again (one a second
/// from a Fast DDS peer, as fast as an attacker likes from another) and leaks the certificate it parses from each
/// (ASan: `PKIDH::begin_handshake_reply`; measured: a ground station's RSS grew 4.4 kB/s while one participant of
/// another CA was on the network, flat without). Dropped, a refused participant costs one refusal at most. Bounded:
/// kMaxEntries, the oldest forgotten first. Thread-safe: drop() runs on Fast DDS's receive threads for every datagram
/// (no lock while the set is empty, a shared one after).
class RefusedPrefixes {
public:
    static constexpr std::size_t kPrefixBytes = 12;
    static constexpr std::size_t kMaxEntries = 1024;

    /// Refuses the participant of the kPrefixBytes-byte GUID prefix at `prefix`.
    void add(const std::uint8_t* prefix);
    /// Whether the GUID prefix at `prefix` (kPrefixBytes bytes) was refused; counts a drop when it was.
    [[nodiscard]] bool drop(const std::uint8_t* prefix) const;
    /// Datagrams drop() said to drop.
    [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

private:
    mutable std::shared_mutex mutex_;
    std::unordered_set<std::string> set_;
    std::deque<std::string> order_; ///< oldest first
    std::atomic<std::size_t> size_{0};
    mutable std::atomic<std::uint64_t> dropped_{0};
};

/// When a process whose handshakes stalled joins the bus again: at once the first time, then after 10 s, 20 s, 40 s
/// ... up to 320 s between joins while a stall persists (a peer that names this team's CA and never answers: an
/// impostor, or a Fast DDS stall that a new participant does not cure), back to at once when a check finds none.
/// A join costs every peer a new handshake (about 1 s here) and a transient-local writer its history, so a
/// long-running process (the service, a ground station) must not join every 10 s for good. Not thread-safe: one
/// owner thread.
class RejoinBackoff {
public:
    using Clock = HandshakeWatch::Clock;
    static constexpr Clock::duration kFirstWait = std::chrono::seconds(10);
    static constexpr Clock::duration kLongestWait = std::chrono::seconds(320);

    /// Whether to join again at `now`, given how many handshakes are stalled then.
    [[nodiscard]] bool due(Clock::time_point now, std::size_t stalled)
    {
        if (stalled == 0) {
            wait_ = Clock::duration::zero();
            next_ = Clock::time_point{};
            return false;
        }
        return now >= next_;
    }
    /// A join was made at `now` (whether it succeeded or not): the next one waits twice as long as the last.
    void joined(Clock::time_point now)
    {
        wait_ = wait_ == Clock::duration::zero() ? kFirstWait : std::min(wait_ * 2, kLongestWait);
        next_ = now + wait_;
    }
    /// How long after the last join the next may come (0: at once).
    [[nodiscard]] Clock::duration wait() const noexcept { return wait_; }

private:
    Clock::duration wait_{};
    Clock::time_point next_{};
};

} // namespace ugv::ipc::dds
