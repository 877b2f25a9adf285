#pragma once

/// @file
/// The V4L2 backend: two capture devices (left, right), one side-by-side stereo device or one camera alone (every
/// frame left-only, for the one-camera mode), MMAP streaming with a
/// small buffer ring, driver timestamps (CLOCK_MONOTONIC), GREY or YUYV (the Y bytes are the grey image),
/// left/right pairing by timestamp within a skew, dropped frames from the drivers' sequence numbers, and a vanished
/// device (ENODEV, EIO, POLLERR) reported as Disconnected; reconnect() reopens the devices (the capture task calls
/// it with backoff while the service stays up).
///
/// A pair whose right camera stops goes on with the left one: when the right device vanishes, or its frame misses
/// the left's by a period kRightMissesToLose times in a row, grab() delivers left-only frames (CameraFrame::right
/// empty) and rightLost() is true until reconnect() brings the right device back. The left camera lost is the whole
/// camera Disconnected (the one-camera mode runs on the left camera's calibration).
///
/// The OS calls go through V4l2Ops (open/close/ioctl/mmap/munmap/poll), so the backend is tested against a fake
/// device speaking the V4L2 protocol (FakeV4l2 in test/unit/hal/v4l2_camera_test.cpp): no camera or kernel module
/// exists here.
///
/// Thread-safety: thread-bound (the capture thread). RT-safe: grab() allocates nothing (buffers mapped and grey
/// images allocated at open); it blocks in poll() up to its timeout.

#include <linux/videodev2.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "ugv/hal/stereo_camera.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/result.hpp"

struct pollfd;

namespace ugv::hal {

/// The system calls the backend makes (errno semantics: -1 and errno on failure).
struct V4l2Ops {
    int (*open)(void* context, const char* path, int flags) = nullptr;
    int (*close)(void* context, int fd) = nullptr;
    // ioctl(2)'s request type is unsigned long
    int (*ioctl)(void* context, int fd, unsigned long request, void* arg) = nullptr;
    void* (*mmap)(void* context, std::size_t length, int fd, std::int64_t offset) = nullptr; ///< MAP_FAILED on error
    int (*munmap)(void* context, void* address, std::size_t length) = nullptr;
    int (*poll)(void* context, pollfd* fds, unsigned count, int timeoutMs) = nullptr;
    void* context = nullptr;
};
/// The real calls (open(2), ioctl(2), mmap(2), ...).
V4l2Ops realV4l2Ops() noexcept;

enum class V4l2Format : std::uint8_t { Grey, Yuyv };

struct V4l2Options {
    std::string leftDevice = "/dev/video0";  ///< or the side-by-side device
    std::string rightDevice = "/dev/video1"; ///< empty: side-by-side on leftDevice (left half, right half)
    bool oneCamera = false;                  ///< leftDevice alone: every frame left-only (rightDevice unused)
    int width = 640;                         ///< [px] per camera
    int height = 480;                        ///< [px]
    double fps = 30.0;                       ///< requested rate (VIDIOC_S_PARM; drivers may refuse)
    V4l2Format format = V4l2Format::Yuyv;
    /// Deliver BGR frames (Bgr8, OpenCV's BT.601 YUYV conversion) instead of the Y plane: what the one-camera
    /// detector needs to tell the ground by its colour. Needs format Yuyv.
    bool colour = false;
    int buffers = 4;          ///< MMAP buffers per device, 2..8
    double maxPairSkewMs = 5; ///< left/right stamps further apart are not a pair
};

class V4l2StereoCamera final : public DeviceStereoCamera {
public:
    /// Opens and starts the device(s). Errors name the device, the failed step and errno, and the fix.
    static Result<std::unique_ptr<V4l2StereoCamera>, Error> open(const V4l2Options& options,
                                                                 V4l2Ops ops = realV4l2Ops());
    ~V4l2StereoCamera() override;
    V4l2StereoCamera(const V4l2StereoCamera&) = delete;
    V4l2StereoCamera& operator=(const V4l2StereoCamera&) = delete;
    V4l2StereoCamera(V4l2StereoCamera&&) = delete;
    V4l2StereoCamera& operator=(V4l2StereoCamera&&) = delete;

    GrabStatus grab(CameraFrame& out, std::chrono::nanoseconds timeout) noexcept override;
    bool reconnect() noexcept override;
    [[nodiscard]] bool rightLost() const noexcept override { return rightLost_; }
    /// Frames dequeued but not paired (the other camera's frame was too far away in time).
    [[nodiscard]] std::uint64_t unpaired() const noexcept { return unpaired_; }

    static constexpr int kMaxBuffers = 8;
    static constexpr int kRightMissesToLose = 3; ///< right frames missed in a row before the right camera is lost

    /// One streaming device (internal, public for the tests' reach only through the camera).
    struct Device {
        std::string path;
        int fd = -1;
        int frameWidth = 0;       ///< the device's image width (2 w for side by side)
        std::uint32_t stride = 0; ///< bytes per line (VIDIOC_S_FMT)
        std::array<void*, kMaxBuffers> maps{};
        std::array<std::size_t, kMaxBuffers> lengths{};
        int buffers = 0;
        int held = -1; ///< index dequeued and not yet given back, -1 when none
        v4l2_buffer last{};
        bool haveSequence = false;
        std::uint32_t lastSequence = 0;
    };

private:
    V4l2StereoCamera(const V4l2Options& options, V4l2Ops ops);
    Result<void, Error> start(Device& device, int frameWidth);
    Result<void, Error> openDevice(Device& device);                ///< open, and check it is a capture device
    Result<void, Error> setFormat(Device& device, int frameWidth); ///< size, pixel format and rate
    Result<void, Error> mapBuffers(Device& device);                ///< MMAP buffers, mapped and queued
    void stop(Device& device) noexcept;
    /// A second device streams the right images (not side by side, not one camera).
    [[nodiscard]] bool hasRightDevice() const noexcept { return !sideBySide_ && !options_.oneCamera; }
    /// Dequeues the next buffer of `device` within `timeoutMs`; Frame, Timeout or Disconnected.
    GrabStatus dequeue(Device& device, int timeoutMs) noexcept;
    /// Dequeues the right frame that pairs with the held left one: Frame, BadFrame (no pair within the skew), or
    /// the failing camera's status (left_.held < 0 when it was the left camera).
    GrabStatus pairRight(int timeoutMs) noexcept;
    /// The right frame missed (`s`): true when the left frame goes out alone; marks the right camera lost.
    bool rightMissing(GrabStatus s) noexcept;
    void requeue(Device& device) noexcept;
    /// Copies columns [x0, x0 + width) of the held buffer of `device` into the left or right image: the grey (or
    /// Y) bytes, or BGR converted from YUYV with `colour`.
    bool copyImage(const Device& device, int x0, bool right) noexcept;
    /// The delivered images (the right one empty for a left-only frame).
    [[nodiscard]] StereoViews images(bool leftOnly) const noexcept;

    V4l2Options options_;
    V4l2Ops ops_;
    Device left_;
    Device right_;
    bool sideBySide_ = false;
    bool rightLost_ = false;
    int rightMisses_ = 0;          ///< right frames missed in a row
    Image<std::uint8_t> leftGrey_; ///< empty with `colour`
    Image<std::uint8_t> rightGrey_;
    Image<BgrPixel> leftBgr_; ///< empty without `colour`
    Image<BgrPixel> rightBgr_;
    std::uint64_t unpaired_ = 0;
    bool connected_ = false;
};

} // namespace ugv::hal
