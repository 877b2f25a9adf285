#pragma once

/// @file
/// ugvsensed's core: three fixed-priority threads around the shared-memory rings, all buffers allocated by
/// create().
///
///   capture (FIFO 80)  camera.grab() -> FramePublisher (iceoryx `ugvsense/stereo/frames`, loaned chunk)
///   vision  (FIFO 70)  FrameSubscriber (queue of 1: latest pair wins, older ones dropped and counted)
///                      -> FramePipeline (rectify, detect) -> SPSC ring -> semaphore post
///   publish (FIFO 75)  SPSC ring -> SectorsMessage + health -> SectorsPublisher (`ugvsense/obstacles/sectors`)
///                      -> stage histograms, deadline check -> monitor ring (non-RT reader: printing, tests)
///                      -> SPSC ring + semaphore post -> bus (SCHED_OTHER): BusSink (DDS), when there is one
///
/// Publish is above vision: its work per frame is tens of microseconds, and a finished result must not wait for
/// the core behind the next frame's detection (below vision, on a saturated core: publish p99 6.8 ms; above: 0.05 ms,
/// `ugvsense bench --recording build/default.ugvrec --rate 60 --frames 200 --one-core`).
///
/// No thread takes a lock on the frame path: the rings are iceoryx's lock-free queues and our wait-free SPSC
/// rings; the waits are a semaphore (vision -> publish) and iceoryx's wait set (capture -> vision), bounded by a
/// timeout so that stop requests are seen. The capture thread alone does blocking I/O (the camera; a recording's
/// file reads). The deadline of a frame is `deadlineFactor` camera periods from its exposure to its sectors being
/// published; a frame past it is counted as a miss (it is still published: late sectors are flagged by their
/// capture stamp, the consumer decides).
///
/// Camera trouble: Timeout for `stallPeriods` periods marks the camera Reconnecting in the health record;
/// Disconnected reconnects with exponential backoff (100 ms .. 2 s) while the service keeps running and publishes
/// nothing new (consumers see the health record's camera state and the capture stamps age). A pair whose right
/// camera stops (StereoCamera::rightLost()) goes on with left-only frames, which the vision task runs through the
/// one-camera detector (degraded sectors); capture retries the right camera with the same backoff after a frame has
/// gone out, so a retry never delays a frame (it does take the capture thread for the device's open and set-up,
/// which allocates: the one exception to the frame path's rule, as with Disconnected).
///
/// Logging: each RT task owns an RtLogChannel (a preallocated ring of fixed records: no formatting, allocation or
/// system call on the frame path); a LogDrain thread (SCHED_OTHER, started with the tasks) formats them onto the
/// log output, the journal under systemd. Logged: camera stalls, disconnects, reconnects, end, bad and refused
/// frames; the right camera lost and back; pipeline failures; entering and leaving the degraded (ground-only) mode;
/// deadline misses, at most one line a second with the count since the last. Everything is also counted in the report
/// and health record.
///
/// Thread-safety: create/start/stop/report from one owner thread; the monitor ring has one reader. RT-safe: the
/// three task bodies after their first frame (asserted by the allocation test in test/unit/service/).

#include <semaphore.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>

#include "ugv/adapters/config.hpp"
#include "ugv/hal/stereo_camera.hpp"
#include "ugv/ipc/iceoryx_rings.hpp"
#include "ugv/ipc/sectors_message.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/log.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/platform/spsc_ring.hpp"
#include "ugv/rt/latency_histogram.hpp"
#include "ugv/rt/thread_runner.hpp"
#include "ugv/service/frame_pipeline.hpp"

namespace ugv::service {

/// Instrumentation seam: called from inside a task thread (tests count that thread's allocations from its
/// steady state on). `task` is "capture", "vision" or "publish".
enum class ProbeEvent : std::uint8_t { SteadyState, Stopping };
using TaskProbe = void (*)(void* context, const char* task, ProbeEvent event);

/// What the vision task does when a frame cannot make its deadline with the full pipeline.
enum class OverloadPolicy : std::uint8_t {
    Degrade, ///< ground-plane-only sectors (no dense matching), flagged degraded; older frames are dropped anyway
    Drop,    ///< always the full pipeline; the latest-frame-wins queue drops what it cannot process
};

/// What the bus task gets of each published frame (a copy: the frame path never waits for the bus).
struct BusFrame {
    ipc::SectorsMessage message; ///< as published on iceoryx (sectors, their ground and health)
    std::int64_t endToEndNs = 0;
    bool deadlineMissed = false;
    std::uint64_t busDrops = 0; ///< frames the bus task was too slow to take, so far
};

/// The service's side of the DDS bus (bringup/service/include/ugv/service/dds_bridge.hpp), called only from the
/// low-priority "bus" task: a slow or absent network delays that task, never a frame (a test stalls it). Not noexcept:
/// a throw (Fast DDS, std::bad_alloc) reaches the bus task's exception guard (rt::ThreadRunner), which logs it and
/// restarts or disables the bus task while the frame path goes on (a test throws from it).
class BusSink {
public:
    BusSink() = default;
    virtual ~BusSink() = default;
    BusSink(const BusSink&) = delete;
    BusSink& operator=(const BusSink&) = delete;
    BusSink(BusSink&&) = delete;
    BusSink& operator=(BusSink&&) = delete;
    virtual void onFrame(const BusFrame& frame) = 0;
    /// Between frames, at least every 20 ms: read inputs (poses), publish periodic records (health).
    virtual void idle() = 0;
};

struct ServiceOptions {
    double deadlineFactor = 1.0; ///< deadline = this many camera periods from exposure to published sectors
    int stallPeriods = 10;       ///< camera periods without a frame before the camera counts as stalled
    std::uint64_t maxFrames = 0; ///< stop after this many published frames (0 = run until stopped or the end)
    int warmupFrames = 5;        ///< frames not counted in the histograms (first-touch costs)
    OverloadPolicy overload = OverloadPolicy::Degrade;
    /// Degrade when (already late) + (the full pipeline's running mean time) exceeds the deadline; after this many
    /// degraded frames in a row one full frame runs anyway, so that the mean follows the scene.
    int fullFrameEvery = 10;
    /// > 0: the vision task sleeps until this long before a frame is due (one camera period after the previous
    /// frame was published into the ring), then polls the ring without sleeping until the frame arrives, for at
    /// most twice this long, then waits as usual. A woken thread on another core (a halted vCPU most of all)
    /// takes 50-200 us to run; a polling one takes a few (measured: hand-over p99 170 -> 19..37 us across two
    /// cores with 2000 us). Costs up to twice this much CPU per frame; none while the camera is stalled.
    std::chrono::microseconds spinBeforeFrame{2000};
    BusSink* bus = nullptr; ///< the DDS side (not owned; outlives the service), or none
    /// What the tasks' exception guard does when a body throws: in practice only the bus task can (the frame-path
    /// loops are noexcept: a throw there ends the process and systemd restarts it).
    rt::RestartPolicy restart{};
    TaskProbe probe = nullptr; ///< SteadyState after a task's warmupFrames-th frame, Stopping at its end
    void* probeContext = nullptr;
};

/// Stages of one frame, in the order of its path.
enum class Stage : std::uint8_t { Capture, Handover, Rectify, Detect, Publish, EndToEnd };
inline constexpr int kStageCount = 6;
/// "capture" (exposure -> the pair copied into its chunk, about to be published), "handover" (iceoryx publish ->
/// taken by vision: the shared-memory hand-over), "rectify", "detect",
/// "publish" (-> sectors published), "end_to_end" (exposure -> sectors published).
const char* stageName(Stage stage) noexcept;

/// What the monitor sees of each published frame.
struct PublishedFrame {
    ipc::SectorsMessage message;
    std::array<std::int64_t, kStageCount> stageNs{}; ///< per Stage
    bool deadlineMissed = false;
};

struct TaskCpu {
    const char* name = "";
    double cpuSeconds = 0.0; ///< CLOCK_THREAD_CPUTIME_ID at the task's end
};

/// Figures of a run (after stop()).
struct ServiceReport {
    std::uint64_t framesCaptured = 0;
    std::uint64_t framesPublished = 0;
    std::uint64_t framesDropped = 0; ///< captured but never processed (latest frame wins) + camera gaps
    std::uint64_t cameraGaps = 0;
    std::uint64_t deadlineMisses = 0;
    std::uint64_t degradedFrames = 0;
    std::uint64_t leftOnlyFrames = 0; ///< frames of the left camera alone (one camera, or the right one lost)
    std::uint64_t badFrames = 0;      ///< malformed chunks, wrong sizes, failed stages
    std::uint64_t loanFailures = 0;
    std::uint64_t cameraReconnects = 0;
    std::uint64_t monitorDrops = 0; ///< published frames the monitor reader was too slow to see
    std::uint64_t busDrops = 0;     ///< published frames the bus task was too slow to take
    std::uint64_t taskFailures = 0; ///< task bodies that threw, logged by rt::ThreadRunner's guard
    std::chrono::nanoseconds deadline{};
    double wallSeconds = 0.0;
    std::array<rt::LatencyHistogram, kStageCount> stages{};
    /// The detect stage split by vision::VisionStage, over full-pipeline frames after warm-up (degraded ones are not
    /// in it).
    std::array<rt::LatencyHistogram, vision::kVisionStageCount> detectStages{};
    std::array<TaskCpu, 4> cpu{};
    std::string threads; ///< rt::formatReport of the tasks
};

/// The check Service::create makes first (and `ugvsense check-config`): the camera delivers frames of the
/// calibration's size. The error names the camera (or recording) and both sizes.
Result<void, Error> checkCameraSize(const hal::StereoCamera& camera, const vision::StereoCalibration& calibration);

class Service {
public:
    /// Builds the pipeline and the rings and creates the threads (held at their start gate). The iceoryx
    /// runtime must be up (ipc::startRuntime or ipc::EmbeddedRouDi). The camera's size must match the calibration.
    static Result<std::unique_ptr<Service>, Error> create(const adapters::ServiceConfig& config,
                                                          const vision::StereoCalibration& calibration,
                                                          std::unique_ptr<hal::StereoCamera> camera,
                                                          const ServiceOptions& options = {});
    ~Service();
    Service(const Service&) = delete;
    Service& operator=(const Service&) = delete;
    Service(Service&&) = delete;
    Service& operator=(Service&&) = delete;

    void start() noexcept;
    /// Stops and joins the threads. Idempotent.
    void stop() noexcept;
    /// True once the camera reported End (a finished recording) and every captured frame was handled, or
    /// maxFrames were published.
    [[nodiscard]] bool finished() const noexcept;
    /// Next frame seen by the monitor, if any (one reader thread).
    bool nextPublished(PublishedFrame& out) noexcept { return monitor_.tryPop(out); }
    [[nodiscard]] ServiceReport report() const;
    [[nodiscard]] const rt::StartReport& startReport() const noexcept { return runner_.report(); }
    [[nodiscard]] std::chrono::nanoseconds period() const noexcept { return period_; }

private:
    Service() = default;
    static void captureBody(void* self, const std::atomic<bool>& stop);
    static void visionBody(void* self, const std::atomic<bool>& stop);
    static void publishBody(void* self, const std::atomic<bool>& stop);
    static void busBody(void* self, const std::atomic<bool>& stop);
    void busLoop(const std::atomic<bool>& stop); // may throw: see BusSink
    void drainBus(); // every frame waiting for the bus, read in place; may throw: see BusSink
    /// The capture task's own state between grabs.
    struct CaptureState {
        std::chrono::nanoseconds backoff{};    ///< the next reconnect attempt's wait
        std::chrono::nanoseconds sinceFrame{}; ///< time without a frame
        std::uint64_t frames = 0;
        bool steady = false;
        bool stalled = false;      ///< logged as stalled, not yet logged as flowing again
        std::int64_t attempts = 0; ///< reconnect attempts since the camera went away
        bool rightLost = false;    ///< the pair runs on its left camera (logged), the right one retried
        std::chrono::nanoseconds rightBackoff{};
        std::int64_t nextRightAttemptNs = 0; ///< [ns] CLOCK_MONOTONIC of the next try to bring it back
    };
    void captureLoop(const std::atomic<bool>& stop) noexcept;
    void onFrame(const hal::CameraFrame& frame, CaptureState& state) noexcept;
    void onNoFrame(std::chrono::nanoseconds stall, CaptureState& state) noexcept;
    void onBadFrame() noexcept;
    void onDisconnected(std::uint64_t lastSequence, CaptureState& state) noexcept;
    /// The pair's right camera stopped (left-only frames): logs it, and tries to bring it back with backoff.
    void watchRightCamera(std::uint64_t sequence, CaptureState& state) noexcept;

    /// The vision task's own state between frames.
    struct VisionState {
        std::int64_t lastRingNs = 0; ///< when the last frame entered the ring [ns, monotonic]
        bool haveLast = false;
        std::uint64_t lastSequence = 0;
        std::uint64_t frames = 0;
        bool steady = false;
        double fullMeanNs = 0.0; ///< running mean of the full pipeline's time (rectified -> detected) [ns]
        int degradedInARow = 0;
        bool overloaded = false;         ///< in the degraded mode (logged on entering and leaving)
        std::uint64_t overloadStart = 0; ///< degraded_ when the mode began
    };
    void visionLoop(const std::atomic<bool>& stop) noexcept;
    /// The next frame of the ring; false on a timeout or a malformed frame (counted and logged).
    bool takeFrame(ipc::TakenFrame& frame) noexcept;
    /// Logs entering and leaving the degraded (ground-plane-only) mode.
    void logOverload(std::uint64_t sequence, bool late, bool groundOnly, VisionState& state) noexcept;
    void publishLoop(const std::atomic<bool>& stop) noexcept;
    ipc::HealthRecord health() const noexcept;
    /// Calls the probe for `task` once its frame count reaches the warm-up.
    void probeSteady(const char* task, std::uint64_t frames, bool& done) const noexcept;
    void probeStopping(const char* task) const noexcept;

    /// The instants of a frame on its way to the publish task [ns, CLOCK_MONOTONIC]: the stages of the report are
    /// the differences of consecutive ones (Stage::Capture = RingPublish - Exposure, ...).
    enum class Stamp : std::uint8_t { Exposure, RingPublish, Taken, Rectified, Detected, Count };
    /// A frame's result on its way from the vision task to the publish task, written once in its ring slot: the
    /// message as it will go out (vision writes sectors and ground, publish the health record and its stamp).
    struct Handover {
        ipc::SectorsMessage message;
        std::array<std::int64_t, static_cast<std::size_t>(Stamp::Count)> stampNs{}; ///< by Stamp
    };
    /// Vision task: counts the frame's outcome (degraded, or refused by the pipeline: logged).
    void countOutcome(PipelineStatus done, const FrameHeader& h) noexcept;
    /// Vision task: the frame's sectors (or Unknown ones when the pipeline refused the pair) and ground into `out`.
    void writeResult(PipelineStatus done, const FrameHeader& h, ipc::SectorsMessage& out) noexcept;
    /// The publish task's state between frames.
    struct PublishState {
        std::uint64_t count = 0;
        bool steady = false;
        std::int64_t lastMissLogNs = std::numeric_limits<std::int64_t>::min() / 2; ///< the first miss is logged
        std::uint64_t missesLogged = 0;                                            ///< misses_ at the last miss line
    };
    /// Publish task: one result out (iceoryx, the monitor, the bus task), timed into the report.
    void publishOne(Handover& in, PublishState& state) noexcept;
    /// Publish task: counts a deadline miss, logs at most one line per kMissLogIntervalNs.
    void logMiss(std::uint64_t sequence, std::int64_t endToEndNs, std::int64_t nowNs, PublishState& state) noexcept;
    static constexpr std::size_t kPublishSlots = 64; ///< capture's ring-publish time per sequence % slots

    ServiceOptions options_;
    std::chrono::nanoseconds period_{};
    void spinUntilFrame(std::int64_t lastRingNs, const std::atomic<bool>& stop) noexcept;
    /// Vision task: the detector's stage times of a full-pipeline frame into the report's histograms.
    void recordDetectStages(const vision::VisionStageTimes& times) noexcept;
    std::chrono::nanoseconds deadline_{};
    std::unique_ptr<hal::StereoCamera> camera_;
    std::unique_ptr<FramePipeline> pipeline_;
    std::unique_ptr<ipc::FramePublisher> framesOut_;
    std::unique_ptr<ipc::FrameSubscriber> framesIn_;
    std::unique_ptr<ipc::SectorsPublisher> sectorsOut_;
    SpscRing<Handover, 4> toPublish_;
    SpscRing<PublishedFrame, 64> monitor_;
    SpscRing<BusFrame, 8> toBus_;
    sem_t published_{};
    sem_t busReady_{};
    bool semaphoreReady_ = false;
    std::array<std::atomic<std::int64_t>, kPublishSlots> ringStampNs_{};
    ObstacleSectors unknownSectors_{};
    rt::ThreadRunner runner_;
    RtLogChannel captureLog_{"capture"}; // written by capture only
    RtLogChannel visionLog_{"vision"};   // written by vision only
    RtLogChannel publishLog_{"publish"}; // written by publish only
    LogDrain logDrain_;                  // the channels' one reader, a SCHED_OTHER thread while the tasks run

    // Counters: each written by one thread (named), read by others (relaxed).
    std::atomic<std::uint64_t> captured_{0};                     // capture
    std::atomic<std::uint64_t> cameraGaps_{0};                   // capture
    std::atomic<std::uint64_t> reconnects_{0};                   // capture
    std::atomic<std::uint64_t> loanFailures_{0};                 // capture
    std::atomic<std::uint8_t> cameraState_{0};                   // capture (ipc::CameraState)
    std::atomic<bool> cameraEnded_{false};                       // capture
    std::atomic<std::uint64_t> lastCapturedSeq_{0};              // capture: the last pair published into the ring
    std::atomic<std::uint64_t> inRing_{0};                       // capture: pairs published into the ring
    std::atomic<std::uint64_t> lastProcessedSeq_{0};             // vision
    std::atomic<std::uint64_t> processed_{0};                    // vision
    std::atomic<std::uint64_t> dropped_{0};                      // vision
    std::atomic<std::uint64_t> badFrames_{0};                    // vision
    std::atomic<std::uint64_t> degraded_{0};                     // vision
    std::atomic<std::uint64_t> leftOnly_{0};                     // capture
    std::atomic<std::uint64_t> handoverFull_{0};                 // vision
    std::atomic<std::uint64_t> publishedCount_{0};               // publish
    std::atomic<std::uint64_t> misses_{0};                       // publish
    std::atomic<std::uint64_t> monitorDrops_{0};                 // publish
    std::atomic<std::uint64_t> busDrops_{0};                     // publish
    std::atomic<std::int64_t> lastLatencyNs_{0};                 // publish
    std::array<rt::LatencyHistogram, kStageCount> histograms_{}; // publish (read after stop)
    std::array<rt::LatencyHistogram, vision::kVisionStageCount> detectHistograms_{}; // vision (read after stop)
    std::array<std::atomic<double>, 4> cpuSeconds_{};                                // each task at its end
    std::int64_t startNs_ = 0;
    std::atomic<std::int64_t> endNs_{0};
};

} // namespace ugv::service
