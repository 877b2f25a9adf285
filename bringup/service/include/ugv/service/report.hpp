#pragma once

/// @file
/// The latency report of a service run: human-readable (ugvsensed at exit, `ugvsense bench`) and JSON
/// (`ugvsense bench --json`). Host side, after the threads stopped: allocates freely.
///
/// JSON (top level): frames, deadline_us, deadline_misses, drops, camera_gaps, degraded, left_only, bad_frames,
/// allocations_after_warmup (null when not counted), wall_s, threads, locked_bytes (null when unknown),
/// end_to_end {p50_us, p90_us, p99_us, p999_us, max_us, count}, stages {capture, handover, rectify, detect, publish:
/// same keys}, cpu {capture, vision, publish: seconds and percent of the wall time}.

#include <cstdint>
#include <optional>
#include <string>

#include "ugv/service/service.hpp"

namespace ugv::service {

struct ReportExtras {
    std::optional<std::uint64_t> allocationsAfterWarmup; ///< summed over the three tasks, when counted
    std::optional<std::size_t> lockedBytes;              ///< VmLck at start
    int threadCount = 0;                                 ///< threads of the process at start
};

std::string formatReport(const ServiceReport& report, const ReportExtras& extras);
std::string reportJson(const ServiceReport& report, const ReportExtras& extras);

/// Threads of this process (/proc/self/status Threads:), 0 when unreadable.
int processThreadCount();

} // namespace ugv::service
