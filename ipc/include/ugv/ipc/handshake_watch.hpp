#pragma once
/// @file
/// Which secured handshakes never ended. Fast DDS 2.9.1 sometimes leaves the authentication of two participants that
/// join at the same moment unfinished for good: each discovered the other, neither is ever authorised or refused,
/// and no sample passes between them (measured here: 2 of 7 runs of test system.team-bus.secured beside a CPU load,
/// one pair of 5 participants stalled for 150 s while every other pair ended in 1 s). The bus watches for such pairs
/// so that a process can say so and join again (Bus::stalledHandshakes(), Bus::renew()).
///
/// Plain bookkeeping, fed by the participant listener: thread-safe, no Fast DDS types.
#include <chrono>
#include <cstddef>
#include <mutex>
#include <string>
#include <unordered_map>

namespace ugv::ipc::dds {

class HandshakeWatch {
public:
    using Clock = std::chrono::steady_clock;
    /// Entries kept at most: a flood of participants that join and never answer cannot grow the table without end
    /// (the oldest unfinished ones are then forgotten, and so not reported).
    static constexpr std::size_t kMaxEntries = 4096;

    /// `local` discovered remote participant `remote` at `at` (its handshake starts).
    void discovered(const std::string& local, const std::string& remote, Clock::time_point at);
    /// The handshake of `local` with `remote` ended (authorised or refused).
    void ended(const std::string& local, const std::string& remote);
    /// `remote` left or was dropped by `local`.
    void removed(const std::string& local, const std::string& remote);
    /// Everything of participant `local` (deleted: a renewed bus has a new one).
    void forget(const std::string& local);
    /// How many of `local`'s handshakes started before `now - olderThan` and have not ended.
    [[nodiscard]] std::size_t stalled(const std::string& local, Clock::time_point now, Clock::duration olderThan) const;

private:
    struct Entry {
        Clock::time_point since;
        bool ended = false;
    };
    static std::string key(const std::string& local, const std::string& remote) { return local + '|' + remote; }
    void trim();

    mutable std::mutex mutex_;
    std::unordered_map<std::string, Entry> entries_; ///< local|remote -> when discovered, and whether it ended
};

} // namespace ugv::ipc::dds
