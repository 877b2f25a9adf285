#include "ugv/ipc/handshake_watch.hpp"

#include <algorithm>
#include <iterator>

namespace ugv::ipc::dds {

void HandshakeWatch::discovered(const std::string& local, const std::string& remote, Clock::time_point at, bool sameCa)
{
    const std::lock_guard lock(mutex_);
    // An authentication reported before the discovery (or a second discovery) keeps what is known.
    entries_.try_emplace(key(local, remote), Entry{at, false, sameCa});
    trim();
}

void HandshakeWatch::ended(const std::string& local, const std::string& remote)
{
    const std::lock_guard lock(mutex_);
    auto [it, added] = entries_.try_emplace(key(local, remote), Entry{Clock::now(), true, true});
    it->second.ended = true;
    if (added) {
        trim();
    }
}

void HandshakeWatch::removed(const std::string& local, const std::string& remote)
{
    const std::lock_guard lock(mutex_);
    entries_.erase(key(local, remote));
}

void HandshakeWatch::forget(const std::string& local)
{
    const std::lock_guard lock(mutex_);
    const std::string prefix = local + '|';
    for (auto it = entries_.begin(); it != entries_.end();) {
        it = it->first.compare(0, prefix.size(), prefix) == 0 ? entries_.erase(it) : std::next(it);
    }
}

HandshakeWatch::ByCa HandshakeWatch::unfinished(const std::string& local, Clock::time_point now,
                                                Clock::duration olderThan) const
{
    return count(local, now - olderThan, true);
}

HandshakeWatch::ByCa HandshakeWatch::peers(const std::string& local) const
{
    return count(local, Clock::time_point::max(), false);
}

HandshakeWatch::ByCa HandshakeWatch::count(const std::string& local, Clock::time_point startedBy,
                                           bool unfinishedOnly) const
{
    const std::lock_guard lock(mutex_);
    const std::string prefix = local + '|';
    ByCa out;
    for (const auto& [k, e] : entries_) {
        if (!(unfinishedOnly && e.ended) && e.since <= startedBy && k.compare(0, prefix.size(), prefix) == 0) {
            ++(e.sameCa ? out.sameCa : out.otherCa);
        }
    }
    return out;
}

void HandshakeWatch::trim()
{
    while (entries_.size() > kMaxEntries) {
        // The ended entries go first (only a REMOVED would otherwise free them), then the oldest unfinished.
        auto victim = std::find_if(entries_.begin(), entries_.end(), [](const auto& e) { return e.second.ended; });
        if (victim == entries_.end()) {
            victim = std::min_element(entries_.begin(), entries_.end(),
                                      [](const auto& a, const auto& b) { return a.second.since < b.second.since; });
        }
        entries_.erase(victim);
    }
}

void RefusedPrefixes::add(const std::uint8_t* prefix)
{
    std::string key(reinterpret_cast<const char*>(prefix), kPrefixBytes);
    const std::unique_lock lock(mutex_);
    if (!set_.insert(key).second) {
        return;
    }
    order_.push_back(std::move(key));
    if (order_.size() > kMaxEntries) {
        set_.erase(order_.front());
        order_.pop_front();
    }
    size_.store(set_.size(), std::memory_order_release);
}

bool RefusedPrefixes::drop(const std::uint8_t* prefix) const
{
    if (size_.load(std::memory_order_acquire) == 0) {
        return false;
    }
    const std::string key(reinterpret_cast<const char*>(prefix), kPrefixBytes); // 12 bytes: no allocation (SSO)
    const std::shared_lock lock(mutex_);
    if (set_.count(key) == 0) {
        return false;
    }
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return true;
}

} // namespace ugv::ipc::dds
