#pragma once

/// @file
/// The task table: one row per thread of the service (name, scheduling policy, priority, CPU, period, stack),
/// the constexpr default for ugvsensed, lookup by name and validation against the running machine.
/// Config may override the table at start only (bringup/).
///
/// Thread-safety: constexpr data and reentrant functions. RT-safe: findTask yes; validation no (builds Errors).

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::rt {

enum class SchedPolicy : std::uint8_t { Fifo, Other };

/// "SCHED_FIFO" / "SCHED_OTHER". Thread-safety: reentrant. RT-safe: yes.
[[nodiscard]] const char* toString(SchedPolicy policy) noexcept;

struct TaskSpec {
    std::string_view name; ///< unique; the first 15 characters become the thread name
    SchedPolicy policy = SchedPolicy::Other;
    int priority = 0;                  ///< 1..99 for Fifo (higher runs first), 0 for Other
    int cpu = -1;                      ///< CPU to pin to, -1 = any
    std::chrono::nanoseconds period{}; ///< 0 = event-driven (woken by its input)
    std::size_t stackBytes = 0;        ///< >= PTHREAD_STACK_MIN
};

inline constexpr std::size_t kDefaultStackBytes = 256UL * 1024UL;
inline constexpr int kMinFifoPriority = 1;
inline constexpr int kMaxFifoPriority = 99;

/// ugvsensed's threads: capture > publish > vision (SCHED_FIFO), bus, correlator and logger (SCHED_OTHER).
/// The capture period is one frame at 30 fps; vision and publish run when their input arrives. Publish is above
/// vision so that a finished result leaves when it is made: below it, sectors waited behind the next frame's
/// detection on a saturated core (`ugvsense bench --rate 60 --one-core`: publish p99 6.8 ms at 60, 0.05 ms at 75).
inline constexpr std::array<TaskSpec, 6> kDefaultTaskTable{{
    {"capture", SchedPolicy::Fifo, 80, -1, std::chrono::nanoseconds(33'333'333), kDefaultStackBytes},
    {"vision", SchedPolicy::Fifo, 70, -1, std::chrono::nanoseconds(0), kDefaultStackBytes},
    {"publish", SchedPolicy::Fifo, 75, -1, std::chrono::nanoseconds(0), kDefaultStackBytes},
    {"bus", SchedPolicy::Other, 0, -1, std::chrono::nanoseconds(0), kDefaultStackBytes},
    {"correlator", SchedPolicy::Other, 0, -1, std::chrono::nanoseconds(0), kDefaultStackBytes},
    {"logger", SchedPolicy::Other, 0, -1, std::chrono::milliseconds(5), kDefaultStackBytes},
}};

/// @brief The row named `name`, if any. Thread-safety: reentrant. RT-safe: yes.
[[nodiscard]] constexpr std::optional<TaskSpec> findTask(std::span<const TaskSpec> table,
                                                         std::string_view name) noexcept
{
    for (const TaskSpec& spec : table) {
        if (spec.name == name) {
            return spec;
        }
    }
    return std::nullopt;
}

/// @brief Check one row: non-empty name, priority range for its policy, cpu in -1..cpuCount-1,
/// period >= 0, stack >= PTHREAD_STACK_MIN. The error names the task, the field, the value and the range.
/// Thread-safety: reentrant. RT-safe: no.
[[nodiscard]] Result<void, Error> validateTask(const TaskSpec& spec, int cpuCount);

/// @brief validateTask() for every row, plus unique names. Returns the first error.
[[nodiscard]] Result<void, Error> validateTaskTable(std::span<const TaskSpec> table, int cpuCount);

/// @brief As above with the online CPU count of this machine.
[[nodiscard]] Result<void, Error> validateTaskTable(std::span<const TaskSpec> table);

/// @brief sysconf(_SC_NPROCESSORS_ONLN). Thread-safety: reentrant. RT-safe: no.
[[nodiscard]] int onlineCpuCount() noexcept;

} // namespace ugv::rt
