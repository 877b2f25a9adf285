#pragma once

/// @file
/// `ugv::MonotonicClock`: CLOCK_MONOTONIC as std::chrono::nanoseconds and as int64 nanoseconds; `clockNs()`: any
/// POSIX clock as int64 nanoseconds (CLOCK_REALTIME for stamps that leave the machine).
/// clock_gettime(CLOCK_MONOTONIC) is served by the vDSO on Linux (no kernel entry), so it is cheap enough for
/// RT loops and log records.
///
/// Thread-safety: reentrant. RT-safe: yes.

#include <chrono>
#include <cstdint>
#include <ctime>

namespace ugv {

/// @brief The time of POSIX clock `clock` (CLOCK_MONOTONIC, CLOCK_REALTIME, ...) as a plain integer. [ns]
/// Thread-safety: reentrant. RT-safe: yes.
[[nodiscard]] inline std::int64_t clockNs(clockid_t clock) noexcept
{
    constexpr std::int64_t kNsPerSecond = 1'000'000'000;
    timespec ts{};
    // The system clocks with a valid pointer cannot fail on Linux.
    static_cast<void>(::clock_gettime(clock, &ts));
    return static_cast<std::int64_t>(ts.tv_sec) * kNsPerSecond + ts.tv_nsec;
}

class MonotonicClock {
public:
    /// @brief Time since an unspecified start (boot), never jumps backwards. [ns]
    /// Thread-safety: reentrant. RT-safe: yes.
    [[nodiscard]] static std::chrono::nanoseconds now() noexcept { return std::chrono::nanoseconds(nowNs()); }

    /// @brief As now(), as a plain integer for fixed-size records. [ns]
    /// Thread-safety: reentrant. RT-safe: yes.
    [[nodiscard]] static std::int64_t nowNs() noexcept { return clockNs(CLOCK_MONOTONIC); }

    /// @brief A CLOCK_MONOTONIC time point (as from nowNs()) as a timespec, for sem_clockwait,
    /// pthread_cond_clockwait and clock_nanosleep(TIMER_ABSTIME) with CLOCK_MONOTONIC. [ns]
    /// Thread-safety: reentrant. RT-safe: yes.
    [[nodiscard]] static constexpr timespec toTimespec(std::int64_t ns) noexcept
    {
        constexpr std::int64_t kNsPerSecond = 1'000'000'000;
        timespec ts{};
        ts.tv_sec = static_cast<time_t>(ns / kNsPerSecond);
        ts.tv_nsec = static_cast<decltype(ts.tv_nsec)>(ns % kNsPerSecond);
        return ts;
    }

    /// @brief The absolute CLOCK_MONOTONIC deadline `d` from now, for the waits above. Every timed wait of ours
    /// uses CLOCK_MONOTONIC: a step of the wall clock at boot (chrony, GPS) must not stretch or cut a wait.
    /// Thread-safety: reentrant. RT-safe: yes.
    [[nodiscard]] static timespec deadlineAfter(std::chrono::nanoseconds d) noexcept
    {
        return toTimespec(nowNs() + d.count());
    }
};

} // namespace ugv
