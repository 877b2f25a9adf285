// ugvsense check-config: validate a service config file in full and print the effective config.

#include <iostream>
#include <string>

#include "ugv/adapters/calibration_file.hpp"
#include "ugv/adapters/config.hpp"
#include "ugv/hal/replay_camera.hpp"
#include "ugv/ipc/dds_bus.hpp"
#include "ugv/service/dds_bridge.hpp"
#include "ugv/service/frame_pipeline.hpp"
#include "ugv/service/runner.hpp"
#include "ugv/service/service.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"

namespace ugv::tool {

namespace {

/// The frame pipeline the service builds at start (the mount, the rectification, the detector's settings) from
/// `calibration`; false, with the error printed, when it cannot be built.
bool pipelineOk(const std::string& path, const adapters::ServiceConfig& config,
                const vision::StereoCalibration& calibration, const std::string& source)
{
    adapters::ServiceConfig effective = config;
    effective.camera.width = calibration.imageSize.width;
    effective.camera.height = calibration.imageSize.height;
    if (auto pipeline = service::FramePipeline::create(calibration, effective); !pipeline) {
        std::cerr << "error: " << source << ": " << pipeline.error().message() << '\n'
                  << path << ": the pipeline cannot be built from it; the service would refuse to start\n";
        return false;
    }
    return true;
}

/// camera.backend replay: the recording opens, its stored calibration (which the service replays with, not the
/// config's) is valid and fits its frames, and the pipeline builds from it. 0 or 1 (the error printed).
int checkRecording(const std::string& path, const adapters::ServiceConfig& config)
{
    auto replay = hal::ReplayCamera::open(config.camera.replayPath, hal::ReplayOptions{});
    if (!replay) {
        std::cerr << "error: " << replay.error().message() << '\n'
                  << path << ": the recording camera.replay_path names cannot be replayed; the service would "
                  << "refuse to start\n";
        return 1;
    }
    const auto calibration = adapters::parseCalibration((*replay)->calibrationText(),
                                                        config.camera.replayPath + " (its stored calibration)");
    if (!calibration) {
        std::cerr << "error: " << calibration.error().message() << '\n'
                  << path << ": the recording's calibration cannot be used; the service would refuse to start\n";
        return 1;
    }
    if (auto sized = service::checkCameraSize(**replay, *calibration); !sized) {
        std::cerr << "error: " << sized.error().message() << '\n'
                  << path << ": the recording's frames do not fit its calibration; the service would refuse to "
                  << "start\n";
        return 1;
    }
    if (!pipelineOk(path, config, *calibration, config.camera.replayPath)) {
        return 1;
    }
    std::cerr << config.camera.replayPath << ": OK (a recording of " << (*replay)->recordedFrames() << " frames, "
              << (*replay)->width() << "x" << (*replay)->height() << ", with its own calibration)\n";
    return 0;
}

/// A live camera: the calibration the config names is valid, of the camera's size, and the pipeline builds from
/// it. 0 or 1 (the error printed).
int checkCalibration(const std::string& path, const adapters::ServiceConfig& config)
{
    const auto calibration = adapters::loadCalibration(config.calibrationPath);
    if (!calibration) {
        std::cerr << "error: " << calibration.error().message() << '\n'
                  << path << ": the calibration it names cannot be used; the service would refuse to start\n";
        return 1;
    }
    const cv::Size size = calibration->imageSize;
    if (size.width != config.camera.width || size.height != config.camera.height) {
        std::cerr << "error: " << config.calibrationPath << ": calibrated for " << size.width << "x" << size.height
                  << " but camera.width/height in " << path << " are " << config.camera.width << "x"
                  << config.camera.height << " (fix: recalibrate at the camera resolution or fix the config)\n";
        return 1;
    }
    if (!pipelineOk(path, config, *calibration, config.calibrationPath)) {
        return 1;
    }
    std::cerr << config.calibrationPath << ": OK (" << (calibration->rectified ? "rectified" : "full") << " form, "
              << size.width << "x" << size.height << ", baseline " << calibration->baselineM() << " m)\n";
    return 0;
}

} // namespace

int runCheckConfig(int argc, char** argv)
{
    Args args("check-config", "[FILE] [--schema] [--no-calibration]",
              {{"schema", "", "print every key with its default, range and description, then exit", false},
               {"no-calibration", "", "do not load the calibration file the config names", false}});
    if (auto parsed = args.parse(argc, argv, 2); !parsed) {
        return reportUsageError("check-config", parsed.error());
    }
    if (args.helpRequested()) {
        std::cout
            << args.usage()
            << "\nFILE defaults to $UGV_CONFIG, then /etc/ugvsense/config.yaml. It also loads the calibration file the "
               "config names\n(unless --no-calibration) and checks its image size; with camera.backend replay it opens "
               "the recording\ninstead, whose stored calibration the service uses. Exit status: 0 valid, 1 invalid.\n";
        return 0;
    }
    if (args.has("schema")) {
        std::cout << adapters::formatConfig(adapters::ServiceConfig{});
        return 0;
    }
    if (args.positional().size() > 1) {
        return reportUsageError("check-config",
                                Error{"ugvsense check-config", "more than one FILE given", "give one config file"});
    }
    const std::string path = adapters::configPath(args.positional().empty() ? nullptr : args.positional()[0].c_str());
    const auto loaded = adapters::loadConfig(path);
    if (!loaded) {
        for (const auto& error : loaded.error()) {
            std::cerr << "error: " << error.message() << '\n';
        }
        std::cerr << path << ": " << loaded.error().size() << " error(s); the service would refuse to start\n";
        return 1;
    }
    const auto config = service::withEnvironment(*loaded);
    if (!config) {
        std::cerr << "error: " << config.error().message() << '\n'
                  << path << ": the environment's override is refused; the service would refuse to start\n";
        return 1;
    }
    std::cout << adapters::formatConfig(config.value());
    // The service's own checks at start (runner.cpp, service.cpp), in the same order.
    if (config->dds.enabled) {
        if (auto bus = ipc::dds::validate(service::busConfig(*config), path + " dds"); !bus) {
            std::cerr << "error: " << bus.error().message() << '\n'
                      << path << ": the bus settings are refused; the service would refuse to start\n";
            return 1;
        }
    }
    if (!config->visionEnabled) {
        std::cerr << path << ": OK (vision off: no camera and no calibration to check)\n";
        return 0;
    }
    if (!args.has("no-calibration")) {
        const int rc = config->camera.backend == adapters::CameraBackend::Replay ? checkRecording(path, *config)
                                                                                 : checkCalibration(path, *config);
        if (rc != 0) {
            return rc;
        }
    }
    std::cerr << path << ": OK\n";
    return 0;
}

} // namespace ugv::tool
