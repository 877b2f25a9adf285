#pragma once

/// @file
/// The replay backend: a recording (recording.hpp) delivered as a stereo camera, for hardware-in-the-loop runs of
/// the unchanged service and for latency budgets.
///
/// Pace: `Recorded` keeps the recorded frame spacing (the left stamps' differences), `Forced` delivers at
/// `forcedFps`, `AsFastAsPossible` does not wait. Each frame is due at start + offset; grab() sleeps until then
/// (clock_nanosleep, absolute, CLOCK_MONOTONIC) but never beyond its timeout (then Timeout, the frame stays
/// pending). A frame that is late already is delivered at once (the pace does not catch up by bursts: the next
/// due times move on from the late frame).
///
/// Stamps: with `restamp` (default) a delivered frame's stamps are its due time on this machine's monotonic clock,
/// as if the camera had exposed it then, so that latency from "exposure" to sectors is measured as on a live camera;
/// the right stamp keeps its recorded offset to the left one. Sequence numbers are the recorded ones (gaps
/// included), continued across loops.
///
/// End of the recording: End, or with `loop` the first frame again. A cut-off last frame (a crash while recording)
/// ends the recording like a clean end, after every complete frame. Corrupt frames are skipped and counted.
///
/// Thread-safety: thread-bound. RT-safe: grab() allocates nothing; it blocks on file reads and in the pacing
/// sleep (both bounded: the file is local, the sleep by the timeout).

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "ugv/hal/recording.hpp"
#include "ugv/hal/stereo_camera.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::hal {

enum class ReplayPace : std::uint8_t { Recorded, Forced, AsFastAsPossible };

struct ReplayOptions {
    ReplayPace pace = ReplayPace::Recorded;
    double forcedFps = 30.0; ///< for Forced, > 0
    bool loop = false;
    bool restamp = true;
};

/// Time seam: the monotonic clock and an absolute sleep (tests replace both).
struct ReplayClock {
    std::int64_t (*now)(void* context) = nullptr;
    void (*sleepUntil)(void* context, std::int64_t deadlineNs) = nullptr;
    void* context = nullptr;
};
/// CLOCK_MONOTONIC and clock_nanosleep(TIMER_ABSTIME).
ReplayClock monotonicReplayClock() noexcept;

class ReplayCamera final : public StereoCamera {
public:
    /// Opens the recording. Errors: those of RecordingReader::open, an empty recording, a bad forced rate.
    static Result<std::unique_ptr<ReplayCamera>, Error> open(const std::string& path, const ReplayOptions& options,
                                                             ReplayClock clock = monotonicReplayClock());

    GrabStatus grab(CameraFrame& out, std::chrono::nanoseconds timeout) noexcept override;
    /// A recording does not go away: rewinds to the start and returns true.
    bool reconnect() noexcept override;
    [[nodiscard]] PixelFormat format() const noexcept override { return reader_.info().format; }
    [[nodiscard]] int width() const noexcept override { return static_cast<int>(reader_.info().width); }
    [[nodiscard]] int height() const noexcept override { return static_cast<int>(reader_.info().height); }
    [[nodiscard]] std::chrono::nanoseconds period() const noexcept override { return period_; }
    [[nodiscard]] CameraStats stats() const noexcept override { return stats_; }
    [[nodiscard]] const char* description() const noexcept override { return description_.c_str(); }

    /// The calibration stored in the recording.
    [[nodiscard]] const std::string& calibrationText() const noexcept { return reader_.info().calibrationText; }
    /// Frames in the recording (complete ones) and whether its end was cut off.
    [[nodiscard]] std::uint64_t recordedFrames() const noexcept { return recordedFrames_; }
    [[nodiscard]] bool truncated() const noexcept { return truncated_; }
    /// Loops completed so far.
    [[nodiscard]] std::uint64_t loops() const noexcept { return loops_; }

private:
    ReplayCamera(RecordingReader reader, const ReplayOptions& options, ReplayClock clock,
                 std::chrono::nanoseconds period, std::uint64_t frames, bool truncated, std::string description);
    /// Peeks at the next frame's header (rewinding when looping): Frame, End (or Truncated) or IoError.
    ReadStatus peekNext() noexcept;
    /// What grab() returns when a read gave no frame: Disconnected on an I/O error (counted), End otherwise; nothing
    /// for a frame.
    std::optional<GrabStatus> failedRead(ReadStatus read) noexcept;

    RecordingReader reader_;
    ReplayOptions options_;
    ReplayClock clock_;
    std::chrono::nanoseconds period_;
    std::uint64_t recordedFrames_ = 0;
    bool truncated_ = false;
    std::string description_;
    CameraStats stats_{};
    bool pending_ = false;   ///< a frame is read and waits for its due time
    bool started_ = false;   ///< the first frame has been delivered
    std::int64_t dueNs_ = 0; ///< due time of the pending frame
    std::int64_t lastDeliveredDueNs_ = 0;
    std::int64_t lastRecordedStampNs_ = 0;
    std::uint64_t sequenceOffset_ = 0; ///< added to recorded sequences after each loop
    std::uint64_t lastSequence_ = 0;
    bool haveLastSequence_ = false;
    std::uint64_t loops_ = 0;
    bool loopStarted_ = false; ///< the reader was rewound for this frame
};

} // namespace ugv::hal
