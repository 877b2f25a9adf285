#pragma once

/// @file
/// The stop flag of the commands that run until Ctrl-C (listen, bus-send, record, correlate --from-dds): SIGINT or
/// SIGTERM sets it and the command ends cleanly (closes its recording or bus, prints its summary); a second signal
/// ends the process at once with exit code 130 (a teardown that hangs must not need kill -9).

#include <atomic>
#include <csignal>
#include <cstdlib>

namespace ugv::tool {

/// Set by SIGINT/SIGTERM once installStopHandler() ran.
inline std::atomic<bool> gStop{false}; // NOLINT(cppcoreguidelines-avoid-non-const-global-variables): the handler's flag
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

inline void installStopHandler()
{
    struct sigaction action {};
    action.sa_handler = [](int /*signal*/) {
        if (gStop.exchange(true)) {
            std::_Exit(130);
        }
    };
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGINT, &action, nullptr);
    ::sigaction(SIGTERM, &action, nullptr);
}

} // namespace ugv::tool
