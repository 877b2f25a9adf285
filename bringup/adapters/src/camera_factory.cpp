#include "ugv/adapters/camera_factory.hpp"

#include "ugv/hal/libcamera_camera.hpp"
#include "ugv/hal/v4l2_camera.hpp"

namespace ugv::adapters {

namespace {

template <class Camera>
Result<std::unique_ptr<hal::StereoCamera>, Error> upcast(Result<std::unique_ptr<Camera>, Error> opened)
{
    if (!opened) {
        return Unexpected(opened.error());
    }
    return std::unique_ptr<hal::StereoCamera>(std::move(*opened));
}

} // namespace

Result<std::unique_ptr<hal::StereoCamera>, Error> openCamera(const ServiceConfig& config, const std::string& replayPath,
                                                             const hal::ReplayOptions& replay)
{
    if (!replayPath.empty()) {
        return upcast(hal::ReplayCamera::open(replayPath, replay));
    }
    switch (config.camera.backend) {
    case CameraBackend::Replay: {
        if (config.camera.replayPath.empty()) {
            return Unexpected(Error{config.sourceFile.empty() ? std::string("config") : config.sourceFile,
                                    "camera.backend is replay but camera.replay_path is empty",
                                    "set camera.replay_path, or give --replay REC"});
        }
        hal::ReplayOptions options;
        options.pace = config.camera.replayPace == ReplayPace::Recorded ? hal::ReplayPace::Recorded
                       : config.camera.replayPace == ReplayPace::Fixed  ? hal::ReplayPace::Forced
                                                                        : hal::ReplayPace::AsFastAsPossible;
        options.forcedFps = config.camera.replayFps;
        options.loop = config.camera.replayLoop;
        return upcast(hal::ReplayCamera::open(config.camera.replayPath, options));
    }
    case CameraBackend::V4l2: {
        hal::V4l2Options options;
        options.leftDevice = config.camera.leftDevice;
        options.rightDevice = config.camera.rightDevice;
        options.oneCamera = config.camera.rightDevice == kNoRightCamera;
        options.width = config.camera.width;
        options.height = config.camera.height;
        options.fps = config.camera.fps;
        options.maxPairSkewMs = config.camera.maxPairSkewMs;
        options.format =
            config.camera.format == PixelFormatChoice::Grey ? hal::V4l2Format::Grey : hal::V4l2Format::Yuyv;
        options.colour = captureInColour(config);
        return upcast(hal::V4l2StereoCamera::open(options));
    }
    case CameraBackend::Libcamera: {
        // libcamera names cameras by id (`cam --list`); a /dev/ path (the V4L2 default) means "in libcamera's order".
        const auto id = [](const std::string& device) {
            return device.rfind("/dev/", 0) == 0 ? std::string() : device;
        };
        hal::LibcameraOptions options;
        options.sideBySide = config.camera.rightDevice.empty();
        options.oneCamera = config.camera.rightDevice == kNoRightCamera;
        options.leftId = id(config.camera.leftDevice);
        options.rightId = id(config.camera.rightDevice);
        options.width = config.camera.width;
        options.height = config.camera.height;
        options.fps = config.camera.fps;
        options.maxPairSkewMs = config.camera.maxPairSkewMs;
        options.colour = captureInColour(config);
        return upcast(hal::LibcameraStereoCamera::open(options));
    }
    }
    return Unexpected(Error{"camera.backend", "unknown backend", "a bug"});
}

} // namespace ugv::adapters
