#pragma once

/// @file
/// A CPU load on another core for `ugvsense soak --load-other-core`: `stress-ng --cpu 1 --taskset CPU`, started by
/// start() and ended by the destructor (SIGTERM, then reaped). Not RT-safe (spawns a process).

#include <sys/types.h>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::tool {

class OtherCoreLoad {
public:
    OtherCoreLoad() = default;
    OtherCoreLoad(const OtherCoreLoad&) = delete;
    OtherCoreLoad& operator=(const OtherCoreLoad&) = delete;
    OtherCoreLoad(OtherCoreLoad&&) = delete;
    OtherCoreLoad& operator=(OtherCoreLoad&&) = delete;
    ~OtherCoreLoad();

    /// Starts stress-ng on `cpu`, timing itself out a minute after `seconds` (should this process die without
    /// ending it). Error: stress-ng cannot be started (not installed), with the fix.
    Result<void, Error> start(int cpu, double seconds);
    /// True while the load still runs (it must last the whole soak). Once it has ended it is reaped here, and the
    /// destructor signals nothing (its pid may belong to another process by then).
    [[nodiscard]] bool running();
    /// The load's process id, 0 when none runs.
    [[nodiscard]] pid_t pid() const noexcept { return pid_; }

private:
    pid_t pid_ = 0;
};

} // namespace ugv::tool
