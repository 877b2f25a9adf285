#pragma once

/// @file
/// The one stereo-camera interface of the service. Backends: replay (a recording, replay_camera.hpp), V4L2
/// (v4l2_camera.hpp) and libcamera (libcamera_camera.hpp). The capture task calls grab() in a loop; everything a
/// backend needs is allocated in open().
///
/// Frame life: grab() fills a CameraFrame whose views stay valid until the next grab() or close() (the backend
/// owns the buffers: an mmap'ed driver buffer, a recording's frame buffer). Stamps are CLOCK_MONOTONIC exposure
/// times; sequence numbers come from the device (or the recording) and gaps mean frames the device lost.
///
/// Thread-safety: thread-bound (one capture thread). RT-safe: grab() allocates nothing; it blocks only in the
/// wait for the next frame, bounded by its timeout.

#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "ugv/platform/frame_header.hpp"
#include "ugv/platform/image_view.hpp"

namespace ugv::hal {

struct CameraFrame {
    std::uint64_t sequence = 0;
    std::int64_t leftStampNs = 0;  ///< [ns] CLOCK_MONOTONIC
    std::int64_t rightStampNs = 0; ///< [ns]
    /// Grey or BGR, as the camera delivers; the right image empty: a left-only frame (a one-camera rig, or the
    /// pair's right camera lost).
    StereoViews images;
};

enum class GrabStatus : std::uint8_t {
    Frame,        ///< `out` holds a new pair
    Timeout,      ///< no pair within the timeout (the camera may be slow or stalled)
    End,          ///< a finite source (a recording without looping) has no more frames
    Disconnected, ///< the device vanished (ENODEV, EIO) or the source failed: the caller reopens with backoff
    BadFrame,     ///< a pair arrived but was unusable (wrong size, corrupt): counted, skipped
};

/// Counters since open().
struct CameraStats {
    std::uint64_t frames = 0;         ///< pairs delivered
    std::uint64_t sequenceGaps = 0;   ///< pairs the device's sequence numbers say were lost
    std::uint64_t badFrames = 0;      ///< pairs skipped as unusable
    std::uint64_t disconnects = 0;    ///< times the source went away
    std::uint64_t leftOnlyFrames = 0; ///< frames delivered without a right image
};

class StereoCamera {
public:
    virtual ~StereoCamera() = default;
    StereoCamera() = default;
    StereoCamera(const StereoCamera&) = delete;
    StereoCamera& operator=(const StereoCamera&) = delete;
    StereoCamera(StereoCamera&&) = delete;
    StereoCamera& operator=(StereoCamera&&) = delete;

    /// Waits up to `timeout` for the next pair. RT-safe (no allocation).
    virtual GrabStatus grab(CameraFrame& out, std::chrono::nanoseconds timeout) noexcept = 0;
    /// Tries to bring a Disconnected source back (reopen the device). Not RT-safe; called with backoff.
    virtual bool reconnect() noexcept = 0;
    /// True while a pair runs on its left camera alone because the right one stopped: grab() delivers left-only
    /// frames and the caller tries reconnect() with backoff to bring the right camera back. A one-camera rig is
    /// never "lost".
    [[nodiscard]] virtual bool rightLost() const noexcept { return false; }

    /// The pixel format of every frame grab() delivers (Grey8, or Bgr8 from a colour camera).
    [[nodiscard]] virtual PixelFormat format() const noexcept = 0;
    [[nodiscard]] virtual int width() const noexcept = 0;
    [[nodiscard]] virtual int height() const noexcept = 0;
    /// The nominal frame period (from the device's frame rate or the recording) [ns].
    [[nodiscard]] virtual std::chrono::nanoseconds period() const noexcept = 0;
    [[nodiscard]] virtual CameraStats stats() const noexcept = 0;
    /// "replay /path/rec.ugvrec", "v4l2 /dev/video0+/dev/video1", ...
    [[nodiscard]] virtual const char* description() const noexcept = 0;
};

/// What the device backends (V4L2, libcamera) share: the format and size they were configured with, the nominal
/// period of the requested rate, their counters and description.
class DeviceStereoCamera : public StereoCamera {
public:
    [[nodiscard]] PixelFormat format() const noexcept final { return format_; }
    [[nodiscard]] int width() const noexcept final { return width_; }
    [[nodiscard]] int height() const noexcept final { return height_; }
    [[nodiscard]] std::chrono::nanoseconds period() const noexcept final { return period_; }
    [[nodiscard]] CameraStats stats() const noexcept final { return stats_; }
    [[nodiscard]] const char* description() const noexcept final { return description_.c_str(); }

protected:
    /// BGR frames with `colour`, else grey; `fps` > 0 (the backends' options are checked before).
    DeviceStereoCamera(bool colour, int width, int height, double fps, std::string description)
        : format_(colour ? PixelFormat::Bgr8 : PixelFormat::Grey8), width_(width), height_(height),
          period_(static_cast<std::int64_t>(std::llround(1e9 / fps))), description_(std::move(description))
    {
    }
    /// The counters the backend keeps up to date.
    [[nodiscard]] CameraStats& counters() noexcept { return stats_; }

private:
    PixelFormat format_;
    int width_;
    int height_;
    std::chrono::nanoseconds period_;
    std::string description_;
    CameraStats stats_{};
};

} // namespace ugv::hal
