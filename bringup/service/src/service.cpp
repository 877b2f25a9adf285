#include "ugv/service/service.hpp"

#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <utility>

#include "ugv/platform/clock.hpp"
#include "ugv/rt/task.hpp"

namespace ugv::service {

namespace {

constexpr std::chrono::milliseconds kWaitSlice{50}; ///< longest wait before a thread looks at its stop flag
constexpr std::chrono::milliseconds kMinBackoff{100};
constexpr std::chrono::milliseconds kMaxBackoff{2000};
constexpr std::int64_t kMissLogIntervalNs = 1'000'000'000; ///< at most one deadline-miss line a second

/// 1, 2, 4, 8, ...: the counts at which a repeated event is logged again (rate limiting without a clock).
bool isPowerOfTwo(std::uint64_t n) noexcept
{
    return n != 0 && (n & (n - 1)) == 0;
}

std::int64_t toUs(std::int64_t ns) noexcept
{
    return ns / 1000;
}

double threadCpuSeconds() noexcept
{
    timespec t{};
    ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

void sleepFor(std::chrono::nanoseconds d) noexcept
{
    timespec t = MonotonicClock::toTimespec(d.count()); // a duration here, not a time point
    while (::nanosleep(&t, &t) != 0 && errno == EINTR) {
    }
}

/// A wait on the semaphore of at most `d`, on CLOCK_MONOTONIC (glibc >= 2.30): a wall-clock step cannot stretch it.
void semWait(sem_t* sem, std::chrono::nanoseconds d) noexcept
{
    const timespec t = MonotonicClock::deadlineAfter(d);
    while (::sem_clockwait(sem, CLOCK_MONOTONIC, &t) != 0 && errno == EINTR) {
    }
}

} // namespace

const char* stageName(Stage stage) noexcept
{
    switch (stage) {
    case Stage::Capture:
        return "capture";
    case Stage::Handover:
        return "handover";
    case Stage::Rectify:
        return "rectify";
    case Stage::Detect:
        return "detect";
    case Stage::Publish:
        return "publish";
    case Stage::EndToEnd:
        return "end_to_end";
    }
    return "?";
}

Result<void, Error> checkCameraSize(const hal::StereoCamera& camera, const vision::StereoCalibration& calibration)
{
    if (camera.width() != calibration.imageSize.width || camera.height() != calibration.imageSize.height) {
        return Unexpected(Error{camera.description(),
                                "delivers " + std::to_string(camera.width()) + "x" + std::to_string(camera.height()) +
                                    " frames but the calibration is for " +
                                    std::to_string(calibration.imageSize.width) + "x" +
                                    std::to_string(calibration.imageSize.height),
                                "use the calibration of this camera at this resolution"});
    }
    return {};
}

Result<std::unique_ptr<Service>, Error> Service::create(const adapters::ServiceConfig& config,
                                                        const vision::StereoCalibration& calibration,
                                                        std::unique_ptr<hal::StereoCamera> camera,
                                                        const ServiceOptions& options)
{
    if (!camera) {
        return Unexpected(Error{"ugvsensed", "no camera", "a bug: pass the opened camera"});
    }
    if (auto sized = checkCameraSize(*camera, calibration); !sized) {
        return Unexpected(sized.error());
    }
    if (!(options.deadlineFactor > 0.0) || options.stallPeriods < 1 || options.warmupFrames < 0) {
        return Unexpected(Error{"ugvsensed", "deadline factor, stall periods or warm-up out of range",
                                "deadline factor > 0, stall periods >= 1, warm-up >= 0"});
    }
    adapters::ServiceConfig effective = config;
    effective.camera.width = camera->width();
    effective.camera.height = camera->height();
    auto pipeline = FramePipeline::create(calibration, effective);
    if (!pipeline) {
        return Unexpected(pipeline.error());
    }
    auto framesOut = ipc::FramePublisher::create(camera->format(), camera->width(), camera->height());
    auto framesIn = ipc::FrameSubscriber::create(1);
    auto sectorsOut = ipc::SectorsPublisher::create();
    if (!framesOut || !framesIn || !sectorsOut) {
        return Unexpected(!framesOut ? framesOut.error() : !framesIn ? framesIn.error() : sectorsOut.error());
    }

    std::unique_ptr<Service> s(new Service());
    s->options_ = options;
    s->period_ = camera->period();
    s->deadline_ = std::chrono::nanoseconds(
        static_cast<std::int64_t>(std::llround(static_cast<double>(s->period_.count()) * options.deadlineFactor)));
    s->camera_ = std::move(camera);
    s->pipeline_ = std::move(*pipeline);
    s->framesOut_ = std::move(*framesOut);
    s->framesIn_ = std::move(*framesIn);
    s->sectorsOut_ = std::move(*sectorsOut);
    if (::sem_init(&s->published_, 0, 0) != 0) {
        return Unexpected(Error{"ugvsensed", "sem_init failed", "check the system"});
    }
    if (::sem_init(&s->busReady_, 0, 0) != 0) {
        ::sem_destroy(&s->published_);
        return Unexpected(Error{"ugvsensed", "sem_init failed", "check the system"});
    }
    s->semaphoreReady_ = true;
    const vision::RectifiedProjection& projection = s->pipeline_->rectifier().projection();
    const auto hfovDeg = static_cast<float>(
        2.0 * std::atan(static_cast<double>(s->camera_->width()) / (2.0 * projection.fx)) * 180.0 / M_PI);
    initSectors(s->unknownSectors_, config.obstacles.sectorCount, hfovDeg);
    s->unknownSectors_.degraded = true;

    const std::pair<const char*, rt::TaskBody> bodies[] = {{"capture", &Service::captureBody},
                                                           {"vision", &Service::visionBody},
                                                           {"publish", &Service::publishBody},
                                                           {"bus", &Service::busBody}};
    for (const auto& [name, body] : bodies) {
        if (body == &Service::busBody && options.bus == nullptr) {
            continue;
        }
        const auto spec = rt::findTask(config.tasks, name);
        if (!spec) {
            return Unexpected(Error{"ugvsensed", std::string("task table has no '") + name + "' task",
                                    "restore the default task table"});
        }
        if (auto added = s->runner_.addTask(*spec, body, s.get()); !added) {
            return Unexpected(added.error());
        }
    }
    for (RtLogChannel* channel : {&s->captureLog_, &s->visionLog_, &s->publishLog_}) {
        if (auto added = s->logDrain_.addChannel(*channel); !added) {
            return Unexpected(added.error());
        }
    }
    s->runner_.setRestartPolicy(options.restart);
    if (auto created = s->runner_.createAll(); !created) {
        return Unexpected(created.error());
    }
    return s;
}

Service::~Service()
{
    stop();
    if (semaphoreReady_) {
        ::sem_destroy(&published_);
        ::sem_destroy(&busReady_);
    }
}

void Service::start() noexcept
{
    startNs_ = MonotonicClock::nowNs();
    if (auto started = logDrain_.start(); !started) {
        UGV_LOG(Rt, Error) << started.error().message() << "; the RT tasks' log records are written at stop";
    }
    runner_.startAll();
}

void Service::stop() noexcept
{
    runner_.requestStop();
    if (framesIn_) {
        framesIn_->wake(); // the vision task's frame wait is iceoryx's (CLOCK_REALTIME): end it, whatever the clock did
    }
    runner_.stopAll();
    logDrain_.stop();
    logDrain_.drainOnce(); // without a drain thread (it could not start), the records come out here
    if (endNs_.load(std::memory_order_relaxed) == 0) {
        endNs_.store(MonotonicClock::nowNs(), std::memory_order_relaxed);
    }
}

bool Service::finished() const noexcept
{
    const std::uint64_t published = publishedCount_.load(std::memory_order_acquire);
    if (options_.maxFrames > 0 && published >= options_.maxFrames) {
        return true;
    }
    if (!cameraEnded_.load(std::memory_order_acquire)) {
        return false;
    }
    // The last pair put into the ring was processed (the queue of one always ends with it) and everything
    // processed was published (or lost to a full hand-over ring, counted). A pair the ring refused never
    // reaches vision.
    const std::uint64_t inRing = inRing_.load(std::memory_order_acquire);
    const bool lastSeen = inRing == 0 || lastProcessedSeq_.load(std::memory_order_acquire) ==
                                             lastCapturedSeq_.load(std::memory_order_acquire);
    return lastSeen &&
           published + handoverFull_.load(std::memory_order_acquire) >= processed_.load(std::memory_order_acquire);
}

void Service::probeSteady(const char* task, std::uint64_t frames, bool& done) const noexcept
{
    if (!done && options_.probe != nullptr && frames >= static_cast<std::uint64_t>(options_.warmupFrames)) {
        options_.probe(options_.probeContext, task, ProbeEvent::SteadyState);
        done = true;
    }
}

void Service::probeStopping(const char* task) const noexcept
{
    if (options_.probe != nullptr) {
        options_.probe(options_.probeContext, task, ProbeEvent::Stopping);
    }
}

void Service::captureBody(void* self, const std::atomic<bool>& stop)
{
    static_cast<Service*>(self)->captureLoop(stop);
}
void Service::visionBody(void* self, const std::atomic<bool>& stop)
{
    static_cast<Service*>(self)->visionLoop(stop);
}
void Service::publishBody(void* self, const std::atomic<bool>& stop)
{
    static_cast<Service*>(self)->publishLoop(stop);
}
void Service::busBody(void* self, const std::atomic<bool>& stop)
{
    static_cast<Service*>(self)->busLoop(stop);
}

void Service::captureLoop(const std::atomic<bool>& stop) noexcept
{
    hal::CameraFrame frame;
    CaptureState state;
    state.backoff = kMinBackoff;
    const std::chrono::nanoseconds stall = period_ * options_.stallPeriods;
    while (!stop.load(std::memory_order_relaxed) && !cameraEnded_.load(std::memory_order_relaxed)) {
        switch (camera_->grab(frame, std::min<std::chrono::nanoseconds>(kWaitSlice, stall))) {
        case hal::GrabStatus::Frame:
            onFrame(frame, state);
            break;
        case hal::GrabStatus::Timeout:
            onNoFrame(stall, state);
            break;
        case hal::GrabStatus::BadFrame:
            onBadFrame();
            break;
        case hal::GrabStatus::End:
            cameraState_.store(static_cast<std::uint8_t>(ipc::CameraState::Stopped), std::memory_order_relaxed);
            cameraEnded_.store(true, std::memory_order_release);
            captureLog_.log(LogLevel::Info, LogCategory::Hal, "camera: end of stream after %lld frame(s)",
                            static_cast<std::int64_t>(state.frames));
            break;
        case hal::GrabStatus::Disconnected:
            onDisconnected(frame.sequence, state);
            break;
        }
    }
    probeStopping("capture");
    cpuSeconds_[0].store(threadCpuSeconds(), std::memory_order_relaxed);
}

void Service::onFrame(const hal::CameraFrame& frame, CaptureState& state) noexcept
{
    state.sinceFrame = {};
    state.backoff = kMinBackoff;
    cameraState_.store(
        static_cast<std::uint8_t>(frame.images.leftOnly() ? ipc::CameraState::LeftOnly : ipc::CameraState::Streaming),
        std::memory_order_relaxed);
    cameraGaps_.store(camera_->stats().sequenceGaps, std::memory_order_relaxed);
    if (state.stalled) {
        captureLog_.log(LogLevel::Info, LogCategory::Hal, "camera: frames again (sequence %lld)",
                        static_cast<std::int64_t>(frame.sequence));
        state.stalled = false;
    }
    // The hand-over start (right before iceoryx gets the chunk) goes in a slot per sequence, written before the
    // frame becomes visible to the vision task.
    if (framesOut_->publish(frame.sequence, frame.leftStampNs, frame.rightStampNs, frame.images,
                            &ringStampNs_[frame.sequence % kPublishSlots])) {
        lastCapturedSeq_.store(frame.sequence, std::memory_order_relaxed);
        inRing_.fetch_add(1, std::memory_order_relaxed);
    } else {
        const std::uint64_t refused = framesOut_->loanFailures();
        loanFailures_.store(refused, std::memory_order_relaxed); // e.g. a wrong size
        if (isPowerOfTwo(refused)) {
            captureLog_.log(LogLevel::Warn, LogCategory::Hal,
                            "frame %lld: the frame ring refused the pair (%lldx%lld: wrong size or format, or no free "
                            "chunk); %lld refused so far",
                            static_cast<std::int64_t>(frame.sequence), frame.images.width(), frame.images.height(),
                            static_cast<std::int64_t>(refused));
        }
    }
    captured_.fetch_add(1, std::memory_order_release);
    probeSteady("capture", ++state.frames, state.steady);
    if (frame.images.leftOnly()) {
        leftOnly_.fetch_add(1, std::memory_order_relaxed);
    }
    if (frame.images.leftOnly() || state.rightLost) {
        watchRightCamera(frame.sequence, state); // after the frame went out: a retry never delays it
    }
}

void Service::watchRightCamera(std::uint64_t sequence, CaptureState& state) noexcept
{
    const auto seq = static_cast<std::int64_t>(sequence);
    const bool lost = camera_->rightLost();
    if (lost && !state.rightLost) {
        captureLog_.log(LogLevel::Warn, LogCategory::Hal,
                        "camera: the right camera stopped at frame %lld: the one-camera mode (colour detector on the "
                        "left camera, degraded sectors) runs until it is back; retrying it (backoff %lld..%lld ms)",
                        seq, kMinBackoff.count(), kMaxBackoff.count());
        state.rightBackoff = kMinBackoff;
        state.nextRightAttemptNs = MonotonicClock::nowNs() + state.rightBackoff.count();
    } else if (!lost && state.rightLost) {
        captureLog_.log(LogLevel::Info, LogCategory::Hal,
                        "camera: the right camera is back at frame %lld: stereo again", seq);
    }
    state.rightLost = lost;
    if (!lost || MonotonicClock::nowNs() < state.nextRightAttemptNs) {
        return;
    }
    if (camera_->reconnect()) {
        reconnects_.fetch_add(1, std::memory_order_relaxed); // the next frame logs it back (rightLost() false)
    } else {
        state.rightBackoff = std::min<std::chrono::nanoseconds>(state.rightBackoff * 2, kMaxBackoff);
    }
    state.nextRightAttemptNs = MonotonicClock::nowNs() + state.rightBackoff.count();
}

void Service::onNoFrame(std::chrono::nanoseconds stall, CaptureState& state) noexcept
{
    state.sinceFrame += kWaitSlice;
    if (state.sinceFrame < stall) {
        return;
    }
    cameraState_.store(static_cast<std::uint8_t>(ipc::CameraState::Reconnecting), std::memory_order_relaxed);
    if (!state.stalled) {
        captureLog_.log(LogLevel::Warn, LogCategory::Hal, "camera: no frame for %lld ms (stalled)",
                        std::chrono::duration_cast<std::chrono::milliseconds>(state.sinceFrame).count());
        state.stalled = true;
    }
}

void Service::onBadFrame() noexcept
{
    const std::uint64_t bad = badFrames_.fetch_add(1, std::memory_order_relaxed) + 1;
    if (isPowerOfTwo(bad)) {
        captureLog_.log(LogLevel::Warn, LogCategory::Hal, "camera: a bad frame (%lld so far)",
                        static_cast<std::int64_t>(bad));
    }
}

void Service::onDisconnected(std::uint64_t lastSequence, CaptureState& state) noexcept
{
    cameraState_.store(static_cast<std::uint8_t>(ipc::CameraState::Reconnecting), std::memory_order_relaxed);
    if (state.attempts == 0) {
        captureLog_.log(LogLevel::Error, LogCategory::Hal,
                        "camera: disconnected after frame %lld; reconnecting (backoff %lld..%lld ms)",
                        static_cast<std::int64_t>(lastSequence), kMinBackoff.count(), kMaxBackoff.count());
    }
    sleepFor(state.backoff);
    ++state.attempts;
    if (camera_->reconnect()) {
        reconnects_.fetch_add(1, std::memory_order_relaxed);
        captureLog_.log(LogLevel::Info, LogCategory::Hal, "camera: reconnected after %lld attempt(s)", state.attempts);
        state.attempts = 0;
        state.backoff = kMinBackoff;
    } else {
        state.backoff = std::min<std::chrono::nanoseconds>(state.backoff * 2, kMaxBackoff);
    }
}

void Service::spinUntilFrame(std::int64_t lastRingNs, const std::atomic<bool>& stop) noexcept
{
    const std::int64_t spinNs = std::chrono::nanoseconds(options_.spinBeforeFrame).count();
    if (spinNs <= 0 || lastRingNs <= 0) {
        return;
    }
    const std::int64_t dueNs = lastRingNs + period_.count();
    std::int64_t now = MonotonicClock::nowNs();
    if (now > dueNs + spinNs) {
        return; // overdue beyond the window (a stalled camera): wait in the kernel, do not burn the core
    }
    // Sleep (in slices, to see the stop flag) until the spin window opens.
    while (now < dueNs - spinNs && !stop.load(std::memory_order_relaxed)) {
        const std::int64_t sleepNs = std::min<std::int64_t>(dueNs - spinNs - now, kWaitSlice.count() * 1'000'000);
        const timespec t = MonotonicClock::toTimespec(sleepNs); // a duration here, not a time point
        ::clock_nanosleep(CLOCK_MONOTONIC, 0, &t, nullptr);
        now = MonotonicClock::nowNs();
    }
    const std::int64_t endNs = std::max(now, dueNs) + spinNs;
    while (!framesIn_->hasData() && MonotonicClock::nowNs() < endNs && !stop.load(std::memory_order_relaxed)) {
    }
}

void Service::visionLoop(const std::atomic<bool>& stop) noexcept
{
    ipc::TakenFrame frame;
    VisionState state;
    while (!stop.load(std::memory_order_relaxed)) {
        spinUntilFrame(state.lastRingNs, stop);
        if (!takeFrame(frame)) {
            continue;
        }
        const std::int64_t takenNs = MonotonicClock::nowNs();
        const FrameHeader h = frame.header; // a copy: release() clears the frame
        if (state.haveLast && h.sequence > state.lastSequence + 1) {
            // Pairs the vision task never saw: replaced by newer ones in its queue of one, or lost by the camera.
            dropped_.fetch_add(h.sequence - state.lastSequence - 1, std::memory_order_relaxed);
        }
        state.haveLast = true;
        state.lastSequence = h.sequence;
        const bool late = state.fullMeanNs > 0.0 && static_cast<double>(takenNs - h.leftStampNs) + state.fullMeanNs >
                                                        static_cast<double>(deadline_.count());
        const bool groundOnly =
            options_.overload == OverloadPolicy::Degrade && late && state.degradedInARow < options_.fullFrameEvery;
        std::int64_t rectifiedNs = 0;
        const PipelineStatus done = pipeline_->process(frame.views, h.sequence, h.leftStampNs, rectifiedNs, groundOnly);
        const std::int64_t detectedNs = MonotonicClock::nowNs();
        logOverload(h.sequence, late, groundOnly, state);
        if (groundOnly) {
            ++state.degradedInARow;
        } else {
            state.degradedInARow = 0;
            const auto took = static_cast<double>(detectedNs - rectifiedNs);
            state.fullMeanNs = state.fullMeanNs > 0.0 ? 0.8 * state.fullMeanNs + 0.2 * took : took;
            if (done == PipelineStatus::Ok && state.frames >= static_cast<std::uint64_t>(options_.warmupFrames) &&
                pipeline_->mode() != adapters::DetectorMode::Colour &&
                !pipeline_->lastFrameLeftOnly()) { // the stereo detector's stages: it ran
                recordDetectStages(pipeline_->detector().stageTimes());
            }
        }
        countOutcome(done, h);
        state.lastRingNs = ringStampNs_[h.sequence % kPublishSlots].load(std::memory_order_acquire);
        framesIn_->release(frame);
        // The result is written once, into the slot the publish task reads it from.
        if (Handover* out = toPublish_.claim(); out != nullptr) {
            writeResult(done, h, out->message);
            out->stampNs = {h.leftStampNs, state.lastRingNs, takenNs, rectifiedNs, detectedNs}; // in Stamp order
            toPublish_.commit();
            ::sem_post(&published_);
        } else {
            handoverFull_.fetch_add(1, std::memory_order_relaxed);
        }
        lastProcessedSeq_.store(h.sequence, std::memory_order_relaxed);
        processed_.fetch_add(1, std::memory_order_release);
        probeSteady("vision", ++state.frames, state.steady);
    }
    probeStopping("vision");
    cpuSeconds_[1].store(threadCpuSeconds(), std::memory_order_relaxed);
}

bool Service::takeFrame(ipc::TakenFrame& frame) noexcept
{
    const ipc::TakeStatus status = framesIn_->take(frame, kWaitSlice);
    if (status == ipc::TakeStatus::Malformed) {
        const std::uint64_t bad = badFrames_.fetch_add(1, std::memory_order_relaxed) + 1;
        if (isPowerOfTwo(bad)) {
            visionLog_.log(LogLevel::Warn, LogCategory::Ipc, "frame ring: a malformed frame (%lld bad so far)",
                           static_cast<std::int64_t>(bad));
        }
    }
    return status != ipc::TakeStatus::Timeout && status != ipc::TakeStatus::Malformed;
}

void Service::logOverload(std::uint64_t sequence, bool late, bool groundOnly, VisionState& state) noexcept
{
    if (groundOnly && !state.overloaded) {
        visionLog_.log(LogLevel::Warn, LogCategory::Vision,
                       "frame %lld: the full pipeline would miss the %lld ms deadline: ground-plane-only sectors "
                       "(degraded) until it catches up",
                       static_cast<std::int64_t>(sequence),
                       std::chrono::duration_cast<std::chrono::milliseconds>(deadline_).count());
        state.overloaded = true;
        state.overloadStart = degraded_.load(std::memory_order_relaxed);
    } else if (!late && state.overloaded) {
        visionLog_.log(LogLevel::Info, LogCategory::Vision,
                       "frame %lld: full pipeline again after %lld degraded frame(s)",
                       static_cast<std::int64_t>(sequence),
                       static_cast<std::int64_t>(degraded_.load(std::memory_order_relaxed) - state.overloadStart));
        state.overloaded = false;
    }
}

void Service::countOutcome(PipelineStatus done, const FrameHeader& h) noexcept
{
    if (done == PipelineStatus::Ok) {
        if (pipeline_->sectors().degraded) {
            degraded_.fetch_add(1, std::memory_order_relaxed);
        }
        return;
    }
    const std::uint64_t bad = badFrames_.fetch_add(1, std::memory_order_relaxed) + 1;
    if (isPowerOfTwo(bad)) {
        visionLog_.log(LogLevel::Error, LogCategory::Vision,
                       "frame %lld: the pipeline refused the pair (status %lld); published as unknown (%lld bad "
                       "frame(s) so far)",
                       static_cast<std::int64_t>(h.sequence), static_cast<std::int64_t>(done),
                       static_cast<std::int64_t>(bad));
    }
    degraded_.fetch_add(1, std::memory_order_relaxed);
}

void Service::writeResult(PipelineStatus done, const FrameHeader& h, ipc::SectorsMessage& out) noexcept
{
    out.ground = pipeline_->ground();
    if (done == PipelineStatus::Ok) {
        out.sectors = pipeline_->sectors();
        return;
    }
    out.sectors = unknownSectors_;
    out.sectors.sequence = h.sequence;
    out.sectors.captureStampNs = h.leftStampNs;
}

ipc::HealthRecord Service::health() const noexcept
{
    ipc::HealthRecord h;
    h.framesCaptured = captured_.load(std::memory_order_relaxed);
    h.framesProcessed = processed_.load(std::memory_order_relaxed);
    h.cameraGaps = cameraGaps_.load(std::memory_order_relaxed);
    h.framesDropped = dropped_.load(std::memory_order_relaxed);
    h.deadlineMisses = misses_.load(std::memory_order_relaxed);
    h.degradedFrames = degraded_.load(std::memory_order_relaxed);
    h.cameraReconnects = reconnects_.load(std::memory_order_relaxed);
    h.lastLatencyNs = lastLatencyNs_.load(std::memory_order_relaxed);
    h.camera = static_cast<ipc::CameraState>(cameraState_.load(std::memory_order_relaxed));
    return h;
}

void Service::publishLoop(const std::atomic<bool>& stop) noexcept
{
    PublishState state;
    while (!stop.load(std::memory_order_relaxed)) {
        semWait(&published_, kWaitSlice);
        // Each result is read where the vision task wrote it, and its slot given back once it has gone out.
        for (Handover* in = toPublish_.front(); in != nullptr; in = toPublish_.front()) {
            publishOne(*in, state);
            toPublish_.release();
        }
    }
    probeStopping("publish");
    cpuSeconds_[2].store(threadCpuSeconds(), std::memory_order_relaxed);
}

void Service::publishOne(Handover& in, PublishState& state) noexcept
{
    ipc::SectorsMessage& m = in.message; // sectors and ground from the vision task; health and stamp here
    const auto at = [&in](Stamp s) { return in.stampNs[static_cast<std::size_t>(s)]; };
    m.health = health();
    const std::int64_t publishNs = MonotonicClock::nowNs();
    m.publishStampNs = publishNs;
    m.health.lastLatencyNs = publishNs - at(Stamp::Exposure);
    sectorsOut_->publish(m);
    const std::int64_t doneNs = MonotonicClock::nowNs();
    const std::int64_t endToEnd = doneNs - at(Stamp::Exposure);
    const std::array<std::int64_t, kStageCount> stageNs{at(Stamp::RingPublish) - at(Stamp::Exposure),
                                                        at(Stamp::Taken) - at(Stamp::RingPublish),
                                                        at(Stamp::Rectified) - at(Stamp::Taken),
                                                        at(Stamp::Detected) - at(Stamp::Rectified),
                                                        doneNs - at(Stamp::Detected),
                                                        endToEnd};
    const bool missed = endToEnd > deadline_.count();
    if (missed) {
        logMiss(m.sectors.sequence, endToEnd, doneNs, state);
    }
    lastLatencyNs_.store(endToEnd, std::memory_order_relaxed);
    if (state.count >= static_cast<std::uint64_t>(options_.warmupFrames)) {
        for (int s = 0; s < kStageCount; ++s) {
            histograms_[static_cast<std::size_t>(s)].record(
                std::chrono::nanoseconds(stageNs[static_cast<std::size_t>(s)]));
        }
    }
    ++state.count;
    if (PublishedFrame* seen = monitor_.claim(); seen != nullptr) {
        seen->message = m;
        seen->stageNs = stageNs;
        seen->deadlineMissed = missed;
        monitor_.commit();
    } else {
        monitorDrops_.fetch_add(1, std::memory_order_relaxed);
    }
    if (options_.bus != nullptr) {
        if (BusFrame* bus = toBus_.claim(); bus != nullptr) {
            bus->message = m;
            bus->endToEndNs = endToEnd;
            bus->deadlineMissed = missed;
            bus->busDrops = busDrops_.load(std::memory_order_relaxed);
            toBus_.commit();
            ::sem_post(&busReady_);
        } else {
            busDrops_.fetch_add(1, std::memory_order_relaxed);
        }
    }
    publishedCount_.fetch_add(1, std::memory_order_release);
    probeSteady("publish", state.count, state.steady);
    if (options_.maxFrames > 0 && state.count >= options_.maxFrames) {
        endNs_.store(doneNs, std::memory_order_relaxed);
    }
}

void Service::logMiss(std::uint64_t sequence, std::int64_t endToEndNs, std::int64_t nowNs, PublishState& state) noexcept
{
    const std::uint64_t missed = misses_.fetch_add(1, std::memory_order_relaxed) + 1;
    if (nowNs - state.lastMissLogNs < kMissLogIntervalNs) {
        return;
    }
    publishLog_.log(LogLevel::Warn, LogCategory::Rt,
                    "frame %lld missed its deadline: %lld us from exposure to sectors (deadline %lld us); %lld "
                    "miss(es) since the last report",
                    static_cast<std::int64_t>(sequence), toUs(endToEndNs), toUs(deadline_.count()),
                    static_cast<std::int64_t>(missed - state.missesLogged));
    state.lastMissLogNs = nowNs;
    state.missesLogged = missed;
}

void Service::drainBus()
{
    // In place: each frame is read from its slot and the slot given back after onFrame(), also when it throws
    // (the bus task's guard restarts the task; the frame that threw is not delivered again).
    struct Release {
        SpscRing<BusFrame, 8>& ring;
        explicit Release(SpscRing<BusFrame, 8>& slots) : ring(slots) {}
        ~Release() { ring.release(); }
        Release(const Release&) = delete;
        Release& operator=(const Release&) = delete;
        Release(Release&&) = delete;
        Release& operator=(Release&&) = delete;
    };
    for (const BusFrame* frame = toBus_.front(); frame != nullptr; frame = toBus_.front()) {
        const Release release{toBus_};
        options_.bus->onFrame(*frame);
    }
}

void Service::busLoop(const std::atomic<bool>& stop)
{
    while (!stop.load(std::memory_order_relaxed)) {
        semWait(&busReady_, std::chrono::milliseconds(20));
        drainBus();
        options_.bus->idle();
    }
    drainBus();
    cpuSeconds_[3].store(threadCpuSeconds(), std::memory_order_relaxed);
}

void Service::recordDetectStages(const vision::VisionStageTimes& times) noexcept
{
    for (std::size_t i = 0; i < detectHistograms_.size(); ++i) {
        detectHistograms_[i].record(std::chrono::nanoseconds(times.ns[i]));
    }
}

ServiceReport Service::report() const
{
    ServiceReport r;
    r.framesCaptured = captured_.load();
    r.framesPublished = publishedCount_.load();
    r.cameraGaps = cameraGaps_.load();
    r.framesDropped = dropped_.load();
    r.deadlineMisses = misses_.load();
    r.degradedFrames = degraded_.load();
    r.leftOnlyFrames = leftOnly_.load();
    r.badFrames = badFrames_.load();
    r.loanFailures = loanFailures_.load() + sectorsOut_->loanFailures() + handoverFull_.load();
    r.cameraReconnects = reconnects_.load();
    r.monitorDrops = monitorDrops_.load();
    r.busDrops = busDrops_.load();
    for (std::size_t i = 0; i < runner_.taskCount(); ++i) {
        r.taskFailures += runner_.failureCount(i);
    }
    r.deadline = deadline_;
    const std::int64_t end = endNs_.load() != 0 ? endNs_.load() : MonotonicClock::nowNs();
    r.wallSeconds = static_cast<double>(end - startNs_) * 1e-9;
    r.stages = histograms_;
    r.detectStages = detectHistograms_;
    r.cpu = {TaskCpu{"capture", cpuSeconds_[0].load()}, TaskCpu{"vision", cpuSeconds_[1].load()},
             TaskCpu{"publish", cpuSeconds_[2].load()}, TaskCpu{"bus", cpuSeconds_[3].load()}};
    r.threads = rt::formatReport(runner_.report());
    return r;
}

} // namespace ugv::service
