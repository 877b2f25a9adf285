#include "ugv/hal/replay_camera.hpp"

#include <cerrno>
#include <cmath>
#include <ctime>
#include <utility>

#include "ugv/platform/clock.hpp"

namespace ugv::hal {

namespace {

constexpr std::chrono::nanoseconds kFallbackPeriod{100'000'000}; ///< a one-frame recording: 10 fps

std::int64_t monotonicNow(void* /*context*/)
{
    return MonotonicClock::nowNs();
}

void sleepUntilMonotonic(void* /*context*/, std::int64_t deadlineNs)
{
    const timespec t = MonotonicClock::toTimespec(deadlineNs);
    while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, nullptr) == EINTR) {
    }
}

} // namespace

ReplayClock monotonicReplayClock() noexcept
{
    return ReplayClock{monotonicNow, sleepUntilMonotonic, nullptr};
}

ReplayCamera::ReplayCamera(RecordingReader reader, const ReplayOptions& options, ReplayClock clock,
                           std::chrono::nanoseconds period, std::uint64_t frames, bool truncated,
                           std::string description)
    : reader_(std::move(reader)), options_(options), clock_(clock), period_(period), recordedFrames_(frames),
      truncated_(truncated), description_(std::move(description))
{
}

Result<std::unique_ptr<ReplayCamera>, Error> ReplayCamera::open(const std::string& path, const ReplayOptions& options,
                                                                ReplayClock clock)
{
    if (options.pace == ReplayPace::Forced && !(options.forcedFps > 0.0 && options.forcedFps <= 1000.0)) {
        return Unexpected(Error{"replay " + path,
                                "forced rate " + std::to_string(options.forcedFps) + " fps is not in (0, 1000]",
                                "give a positive frame rate, e.g. --rate 30"});
    }
    if (clock.now == nullptr || clock.sleepUntil == nullptr) {
        return Unexpected(Error{"replay " + path, "the replay clock has no now/sleep function", "a bug: pass one"});
    }
    auto scan = scanRecording(path);
    if (!scan) {
        return Unexpected(scan.error());
    }
    if (scan->frames == 0) {
        return Unexpected(Error{path, "the recording holds no complete frame",
                                scan->trailingBytes > 0 ? "it was cut off during its first frame: record again"
                                                        : "record at least one frame"});
    }
    auto reader = RecordingReader::open(path);
    if (!reader) {
        return Unexpected(reader.error());
    }
    std::chrono::nanoseconds period = kFallbackPeriod;
    if (options.pace == ReplayPace::Forced) {
        period = std::chrono::nanoseconds(static_cast<std::int64_t>(std::llround(1e9 / options.forcedFps)));
    } else if (scan->frames > 1 && scan->lastStampNs > scan->firstStampNs) {
        period = std::chrono::nanoseconds((scan->lastStampNs - scan->firstStampNs) /
                                          static_cast<std::int64_t>(scan->frames - 1));
    }
    const char* pace = options.pace == ReplayPace::Recorded ? "recorded pace"
                       : options.pace == ReplayPace::Forced ? "forced rate"
                                                            : "as fast as possible";
    std::string description = "replay " + path + " (" + std::to_string(scan->frames) + " frames, " + pace +
                              (options.loop ? ", looping)" : ")");
    return std::unique_ptr<ReplayCamera>(new ReplayCamera(std::move(*reader), options, clock, period, scan->frames,
                                                          scan->trailingBytes > 0, std::move(description)));
}

ReadStatus ReplayCamera::peekNext() noexcept
{
    for (int attempt = 0; attempt < 2; ++attempt) {
        const ReadStatus status = reader_.peek();
        if (status == ReadStatus::Frame || status == ReadStatus::IoError || !options_.loop) {
            return status;
        }
        // End or a cut-off tail: start over, continuing the sequence numbers.
        if (!reader_.rewind()) {
            return ReadStatus::IoError;
        }
        ++loops_;
        loopStarted_ = true;
    }
    return ReadStatus::End;
}

std::optional<GrabStatus> ReplayCamera::failedRead(ReadStatus read) noexcept
{
    if (read == ReadStatus::IoError) {
        ++stats_.disconnects;
        return GrabStatus::Disconnected;
    }
    if (read != ReadStatus::Frame) {
        return GrabStatus::End;
    }
    return std::nullopt;
}

GrabStatus ReplayCamera::grab(CameraFrame& out, std::chrono::nanoseconds timeout) noexcept
{
    std::int64_t now = clock_.now(clock_.context);
    if (!pending_) {
        // The header only: the payload is read once the frame is due.
        if (const auto failed = failedRead(peekNext())) {
            return *failed;
        }
        const FrameHeader& h = reader_.peekedHeader();
        if (loopStarted_) {
            sequenceOffset_ = lastSequence_ + 1 - h.sequence;
        }
        std::int64_t due = now;
        if (started_) {
            std::int64_t step = 0;
            switch (options_.pace) {
            case ReplayPace::Recorded:
                step = loopStarted_ || h.leftStampNs < lastRecordedStampNs_ ? period_.count()
                                                                            : h.leftStampNs - lastRecordedStampNs_;
                break;
            case ReplayPace::Forced:
                step = period_.count();
                break;
            case ReplayPace::AsFastAsPossible:
                break;
            }
            due = lastDeliveredDueNs_ + step;
        }
        loopStarted_ = false;
        dueNs_ = due < now ? now : due; // late: deliver now, the pace moves on from here
        pending_ = true;
    }
    if (dueNs_ > now) {
        if (dueNs_ - now > timeout.count()) {
            clock_.sleepUntil(clock_.context, now + timeout.count());
            return GrabStatus::Timeout;
        }
        clock_.sleepUntil(clock_.context, dueNs_);
    }
    // The frame is due: read it (as a camera's readout follows its exposure). A corrupt record is skipped by the
    // reader, which then returns the next complete one.
    pending_ = false;
    if (const auto failed = failedRead(reader_.next())) {
        return *failed;
    }
    const FrameHeader& h = reader_.header();
    out.sequence = h.sequence + sequenceOffset_;
    out.leftStampNs = options_.restamp ? dueNs_ : h.leftStampNs;
    out.rightStampNs = options_.restamp ? dueNs_ + (h.rightStampNs - h.leftStampNs) : h.rightStampNs;
    out.images = reader_.views();
    if (haveLastSequence_ && out.sequence > lastSequence_ + 1) {
        stats_.sequenceGaps += out.sequence - lastSequence_ - 1;
    }
    lastSequence_ = out.sequence;
    haveLastSequence_ = true;
    lastDeliveredDueNs_ = dueNs_;
    lastRecordedStampNs_ = h.leftStampNs;
    started_ = true;
    ++stats_.frames;
    stats_.badFrames = reader_.corruptFrames();
    return GrabStatus::Frame;
}

bool ReplayCamera::reconnect() noexcept
{
    pending_ = false;
    return static_cast<bool>(reader_.rewind());
}

} // namespace ugv::hal
