#pragma once

/// @file
/// Memory set-up before the RT tasks start: lock all pages (current and future) so the frame path never takes
/// a major page fault, stop glibc from returning memory to the OS or serving allocations with mmap, and touch
/// the stack so its pages are resident. Refusals (EPERM / RLIMIT_MEMLOCK too low) degrade to one warning each.
///
/// Thread-safety: lockMemory at init, from one thread; the rest reentrant. RT-safe: no (init only), except
/// prefaultStack, which is meant for the first lines of an RT thread.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ugv/rt/sys_ops.hpp"

namespace ugv::rt {

struct MemoryReport {
    bool locked = false;                    ///< mlockall(MCL_CURRENT|MCL_FUTURE) succeeded
    bool mallocTuned = false;               ///< both mallopt calls succeeded
    std::optional<std::size_t> lockedBytes; ///< VmLck of /proc/self/status after the calls [B]
    std::vector<std::string> warnings;      ///< one per refused step
};

/// @brief mlockall(MCL_CURRENT|MCL_FUTURE), mallopt(M_TRIM_THRESHOLD, -1), mallopt(M_MMAP_MAX, 0).
/// Each refusal adds a warning (and a log line) naming the call, the errno text and the fix; never fails.
[[nodiscard]] MemoryReport lockMemory(const SysOps& ops = realSysOps());

/// @brief A "Key:   N kB" line of a /proc/<pid>/status text (key without its colon: "VmLck", "VmRSS"), in bytes;
/// nullopt when absent or malformed.
[[nodiscard]] std::optional<std::size_t> statusBytes(std::string_view statusText, std::string_view key);

/// @brief The VmLck value of a /proc/<pid>/status text, in bytes; nullopt when absent or malformed.
[[nodiscard]] std::optional<std::size_t> lockedBytesFromStatus(std::string_view statusText);

/// @brief A "kB" field of this process's /proc/self/status ("VmRSS", "VmLck"), in bytes; nullopt when unreadable.
[[nodiscard]] std::optional<std::size_t> readStatusBytes(std::string_view key);

/// @brief VmLck of this process (reads /proc/self/status); nullopt when unreadable.
[[nodiscard]] std::optional<std::size_t> readLockedBytes();

/// @brief Touch `bytes` of stack below the caller (one write per page) so those pages are resident.
/// @return the number of bytes touched. Keep `bytes` well below the thread's stack size.
/// Thread-safety: reentrant. RT-safe: yes (call it at the start of the RT thread, before the loop).
std::size_t prefaultStack(std::size_t bytes) noexcept;

} // namespace ugv::rt
