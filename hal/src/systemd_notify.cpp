#include "ugv/hal/systemd_notify.hpp"

#include <systemd/sd-daemon.h>

#include <cstdlib>

namespace ugv::hal {

SystemdNotifier::SystemdNotifier() noexcept
{
    const char* socket = std::getenv("NOTIFY_SOCKET");
    active_ = socket != nullptr && socket[0] != '\0';
    std::uint64_t usec = 0;
    if (active_ && ::sd_watchdog_enabled(0, &usec) > 0) {
        watchdog_ = std::chrono::microseconds(static_cast<std::int64_t>(usec));
    }
}

void SystemdNotifier::ready() const noexcept
{
    if (active_) {
        (void)::sd_notify(0, "READY=1");
    }
}

void SystemdNotifier::watchdog() const noexcept
{
    if (active_) {
        (void)::sd_notify(0, "WATCHDOG=1");
    }
}

void SystemdNotifier::status(const std::string& text) const noexcept
{
    if (active_) {
        (void)::sd_notifyf(0, "STATUS=%s", text.c_str());
    }
}

void SystemdNotifier::stopping() const noexcept
{
    if (active_) {
        (void)::sd_notify(0, "STOPPING=1");
    }
}

} // namespace ugv::hal
