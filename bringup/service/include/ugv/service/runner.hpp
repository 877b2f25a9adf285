#pragma once

/// @file
/// One run of the service, as ugvsensed's main() and `ugvsense bench` do it: config, calibration, iceoryx (a
/// running RouDi, or one inside this process), memory locking, the camera (adapters::openCamera), the Service threads,
/// a monitor loop on the calling thread (printing, stop conditions), and the report.
///
/// Thread-safety: call from the main thread. RT-safe: no (it is the non-RT side of the service).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "ugv/hal/replay_camera.hpp"
#include "ugv/service/correlator_task.hpp"
#include "ugv/service/dds_bridge.hpp"
#include "ugv/service/report.hpp"
#include "ugv/service/service.hpp"

namespace ugv::service {

enum class RouDiMode : std::uint8_t {
    External, ///< a RouDi must run (iox-roudi, the ugvsense-roudi unit): error otherwise
    Embedded, ///< start RouDi inside this process
    Auto,     ///< use a running RouDi, else start one inside this process
};

struct RunOptions {
    std::string appName = "ugvsensed";
    std::string configPath;      ///< empty: built-in defaults
    std::string replayPath;      ///< a recording to replay instead of the configured camera (camera.backend)
    std::string calibrationPath; ///< empty: the recording's own calibration, or the config's for a live camera
    hal::ReplayOptions replay;
    RouDiMode roudi = RouDiMode::External;
    std::chrono::milliseconds roudiWait{0}; ///< External: wait this long for a RouDi that is still starting
    ServiceOptions service;
    int printEvery = 0;                      ///< print one sector summary every N published frames (0: none)
    int pinAllTasksTo = -1;                  ///< >= 0: capture, vision and publish on this CPU (one-core budgets)
    const std::atomic<bool>* stop = nullptr; ///< set by a signal handler: stop now
    /// Called on the monitor (calling, non-RT) thread for each published frame, in order (`ugvsense soak` samples
    /// latency and memory with it); may be empty.
    std::function<void(const PublishedFrame&)> onPublished;
};

struct RunResult {
    ServiceReport report;
    ReportExtras extras;
    bool roudiLost = false;            ///< RouDi went away during the run (its shared memory is stale: the run stopped)
    bool visionRan = false;            ///< false: a correlator-only run (vision.enabled false)
    std::optional<DdsBridgeStats> bus; ///< dds.enabled and vision ran
    std::optional<LiveCorrelatorStats> correlator; ///< correlator.enabled
};

/// The bus and correlator lines of the report ("" when neither ran).
std::string formatBusReport(const RunResult& result);

/// Runs until the recording ends (without looping), maxFrames are published, or *stop is set. With vision.enabled
/// false (a ground station), runs only the correlator task on the bus until *stop is set.
/// @return the figures, or an error naming what failed at start (config, calibration, RouDi, recording).
Result<RunResult, Error> runService(const RunOptions& options);

/// The config with the environment overrides the service applies at start ($UGV_DDS_DOMAIN for dds.domain_id);
/// an error names the variable. `ugvsense check-config` applies them too.
Result<adapters::ServiceConfig, Error> withEnvironment(adapters::ServiceConfig config);

/// "frame 120 +2.41 m: 3 obstacle (red 0, blue 3, nearest 2.41 m at 12.3 deg negative), 50 clear, 11 unknown,
/// 31.2 ms" for a published frame.
std::string summaryLine(const PublishedFrame& frame);

} // namespace ugv::service
