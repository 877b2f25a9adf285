#pragma once

/// @file
/// systemd's notification protocol (sd_notify) for ugvsensed's unit: READY=1 once the threads run, WATCHDOG=1
/// only while frames flow (a stalled pipeline stops the pings, so systemd's WatchdogSec restarts the service),
/// STATUS= lines, STOPPING=1. Without $NOTIFY_SOCKET (not started by systemd) every call does nothing.
///
/// Thread-safety: reentrant. RT-safe: no (a datagram send per call): call from the non-RT monitor thread.

#include <chrono>
#include <string>

namespace ugv::hal {

class SystemdNotifier {
public:
    SystemdNotifier() noexcept;

    /// True when systemd (or a test) listens on $NOTIFY_SOCKET.
    [[nodiscard]] bool active() const noexcept { return active_; }
    /// WatchdogSec of the unit ($WATCHDOG_USEC), 0 when no watchdog is configured.
    [[nodiscard]] std::chrono::microseconds watchdogInterval() const noexcept { return watchdog_; }

    void ready() const noexcept;
    void watchdog() const noexcept;
    void status(const std::string& text) const noexcept;
    void stopping() const noexcept;

private:
    bool active_ = false;
    std::chrono::microseconds watchdog_{0};
};

} // namespace ugv::hal
