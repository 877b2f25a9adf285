#pragma once

/// @file
/// The libcamera backend (libcamera 0.0.3): two cameras (left, right), one side-by-side stereo camera, or one camera
/// alone (left-only frames, for the one-camera mode), streaming
/// YUV420 at the configured size and rate (FrameDurationLimits); the Y plane is the grey image, or with `colour` the
/// three planes are converted to BGR. Each camera's requests complete on libcamera's thread, which hands the Request
/// pointer to the capture thread through a wait-free ring and a semaphore; grab() pairs the two cameras' frames by
/// their sensor timestamps within a skew, copies (or converts) the images and requeues the requests.
///
/// With no camera present, open() fails with a clear error (tested here; no camera exists on our machines, so the
/// streaming path is untested here and is checked on the vehicle: `ugvsensed --config` with camera.backend libcamera).
/// A camera that disappears (cameraRemoved, or failed requests) makes grab() return Disconnected; reconnect() opens
/// the cameras again. Unlike the V4L2 backend, a pair whose right camera stops does not go on with the left one
/// here (the whole camera is Disconnected until both are back): that path needs a camera to test it on.
///
/// Thread-safety: thread-bound (the capture thread); the completion callback runs on libcamera's thread and only
/// touches the rings. RT-safe: grab() does not allocate in our code; libcamera's queueRequest() is not audited for
/// allocation (its own thread does the I/O).

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "ugv/hal/stereo_camera.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::hal {

struct LibcameraOptions {
    std::string leftId;      ///< libcamera camera id; empty: the first camera
    std::string rightId;     ///< empty with sideBySide false: the second camera
    bool sideBySide = false; ///< one camera delivering 2 w x h, left half then right half
    bool oneCamera = false;  ///< leftId alone: every frame left-only (rightId and sideBySide unused)
    /// Deliver BGR frames (Bgr8) converted from the YUV420 buffers (all three planes mapped; OpenCV's BT.601
    /// conversion, as V4L2's colour) instead of the Y plane; width and height must be even.
    bool colour = false;
    int width = 640;
    int height = 480;
    double fps = 30.0;
    double maxPairSkewMs = 5.0;
};

class LibcameraStereoCamera final : public DeviceStereoCamera {
public:
    /// Starts a CameraManager, acquires and configures the camera(s) and starts streaming. Errors: no camera, too
    /// few cameras, an id not found, a size or format the camera cannot deliver, a camera in use.
    static Result<std::unique_ptr<LibcameraStereoCamera>, Error> open(const LibcameraOptions& options);
    ~LibcameraStereoCamera() override;
    LibcameraStereoCamera(const LibcameraStereoCamera&) = delete;
    LibcameraStereoCamera& operator=(const LibcameraStereoCamera&) = delete;
    LibcameraStereoCamera(LibcameraStereoCamera&&) = delete;
    LibcameraStereoCamera& operator=(LibcameraStereoCamera&&) = delete;

    GrabStatus grab(CameraFrame& out, std::chrono::nanoseconds timeout) noexcept override;
    bool reconnect() noexcept override;

    struct Impl;

private:
    explicit LibcameraStereoCamera(const LibcameraOptions& options);
    Result<void, Error> start();
    void stop() noexcept;

    LibcameraOptions options_;
    std::unique_ptr<Impl> impl_;
};

} // namespace ugv::hal
