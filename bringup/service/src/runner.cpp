#include "ugv/service/runner.hpp"

#include <time.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "ugv/adapters/calibration_file.hpp"
#include "ugv/adapters/camera_factory.hpp"
#include "ugv/hal/systemd_notify.hpp"
#include "ugv/ipc/iceoryx_rings.hpp"
#include "ugv/platform/clock.hpp"
#include "ugv/platform/log.hpp"
#include "ugv/rt/memory.hpp"

namespace ugv::service {

namespace {

constexpr std::chrono::milliseconds kMonitorPoll{20};
constexpr std::int64_t kRoudiCheckNs = 500'000'000; ///< how often the monitor checks that RouDi still answers

void sleepMs(std::chrono::milliseconds d)
{
    const timespec t = MonotonicClock::toTimespec(std::chrono::nanoseconds(d).count()); // a duration, not a time point
    ::nanosleep(&t, nullptr);
}

Error joinErrors(const adapters::ConfigErrors& errors)
{
    Error e = errors.front();
    for (std::size_t i = 1; i < errors.size(); ++i) {
        e.what += "; also " + errors[i].message();
    }
    return e;
}

} // namespace

std::string summaryLine(const PublishedFrame& frame)
{
    const ObstacleSectors& s = frame.message.sectors;
    int obstacles = 0;
    int clear = 0;
    int unknown = 0;
    int red = 0;
    int blue = 0;
    const Sector* nearest = nullptr;
    for (int i = 0; i < s.count; ++i) {
        const Sector& sector = s.sectors[static_cast<std::size_t>(i)];
        switch (sector.state) {
        case SectorState::Obstacle:
            ++obstacles;
            red += sector.danger == DangerClass::Red ? 1 : 0;
            blue += sector.danger == DangerClass::Blue ? 1 : 0;
            if (nearest == nullptr || sector.rangeM < nearest->rangeM) {
                nearest = &sector;
            }
            break;
        case SectorState::Clear:
            ++clear;
            break;
        case SectorState::Unknown:
            ++unknown;
            break;
        }
    }
    char text[320];
    int n = std::snprintf(text, sizeof(text), "frame %llu: %d obstacle (red %d, blue %d",
                          static_cast<unsigned long long>(s.sequence), obstacles, red, blue);
    if (nearest != nullptr) {
        n += std::snprintf(text + n, sizeof(text) - static_cast<std::size_t>(n), ", nearest %.2f m at %.1f deg %s",
                           static_cast<double>(nearest->rangeM),
                           0.5 * static_cast<double>(nearest->bearingMinDeg + nearest->bearingMaxDeg),
                           nearest->kind == ObstacleKind::Negative ? "negative" : "positive");
    }
    (void)std::snprintf(text + n, sizeof(text) - static_cast<std::size_t>(n), "), %d clear, %d unknown%s; %.1f ms%s",
                        clear, unknown, s.degraded ? " (degraded)" : "",
                        static_cast<double>(frame.stageNs[static_cast<std::size_t>(Stage::EndToEnd)]) * 1e-6,
                        frame.deadlineMissed ? " DEADLINE MISSED" : "");
    return text;
}

std::string formatBusReport(const RunResult& r)
{
    std::string out;
    char line[512];
    if (r.bus) {
        (void)std::snprintf(
            line, sizeof(line),
            "dds: %llu frame(s) sent (sectors, two LaserScans, PointCloud2), %llu write failure(s); poses %llu "
            "used, %llu of other vehicles, %llu refused, %llu in this vehicle's name by another participant; %llu "
            "frame(s) with a stale or no pose; %llu network interface change(s) followed; %llu join(s) again for a "
            "stalled secured handshake\n",
            static_cast<unsigned long long>(r.bus->framesSent), static_cast<unsigned long long>(r.bus->writeFailures),
            static_cast<unsigned long long>(r.bus->posesUsed), static_cast<unsigned long long>(r.bus->posesForeign),
            static_cast<unsigned long long>(r.bus->posesRejected),
            static_cast<unsigned long long>(r.bus->posesImpersonated),
            static_cast<unsigned long long>(r.bus->stalePoses),
            static_cast<unsigned long long>(r.bus->interfaceChanges),
            static_cast<unsigned long long>(r.bus->stallRejoins));
        out += line;
    }
    if (r.correlator) {
        const LiveCorrelatorStats& c = *r.correlator;
        (void)std::snprintf(
            line, sizeof(line),
            "correlator: %llu input(s) received, %llu applied (%llu late, put in place), %llu refused as "
            "malformed, %llu duplicate(s), %llu in another sender's name, "
            "%llu refused by the flood guard (%llu stamped ahead of this host's clock), %llu refused by the "
            "correlator; %llu list(s) published\n",
            static_cast<unsigned long long>(c.received), static_cast<unsigned long long>(c.applied),
            static_cast<unsigned long long>(c.resequenced), static_cast<unsigned long long>(c.rejected),
            static_cast<unsigned long long>(c.duplicates), static_cast<unsigned long long>(c.impersonated),
            static_cast<unsigned long long>(c.flooded), static_cast<unsigned long long>(c.aheadOfClock),
            static_cast<unsigned long long>(c.refused), static_cast<unsigned long long>(c.published));
        out += line;
    }
    return out;
}

namespace {

LiveCorrelatorOptions correlatorOptions(const adapters::ServiceConfig& config)
{
    LiveCorrelatorOptions o;
    o.mode = config.correlator.mode;
    o.periodS = config.correlator.periodS;
    o.reorderMs = config.correlator.reorderMs;
    o.lateWindowS = config.correlator.lateWindowS;
    o.startupHoldMs = config.correlator.startupHoldMs;
    o.maxRatePerSource = config.correlator.maxRatePerSource;
    o.maxClockSkewMs = config.correlator.maxClockSkewMs;
    o.logDir = config.correlator.logDir;
    o.source = config.vehicleId;
    return o;
}

/// A ground station: the correlator task alone, until *stop.
Result<RunResult, Error> runCorrelatorOnly(const adapters::ServiceConfig& config, const RunOptions& options,
                                           ipc::dds::Bus& bus)
{
    auto task = CorrelatorTask::create(bus, correlatorOptions(config), *rt::findTask(config.tasks, "correlator"));
    if (!task) {
        return Unexpected(task.error());
    }
    (*task)->start();
    const hal::SystemdNotifier systemd;
    systemd.ready();
    systemd.status("correlating on DDS domain " + std::to_string(config.dds.domainId));
    const std::chrono::nanoseconds pingEvery = systemd.watchdogInterval() / 2;
    std::int64_t lastPingNs = 0;
    const std::int64_t startNs = MonotonicClock::nowNs();
    while (!(options.stop != nullptr && options.stop->load())) {
        const std::int64_t now = MonotonicClock::nowNs();
        if (pingEvery.count() > 0 && now - lastPingNs >= pingEvery.count()) {
            systemd.watchdog();
            lastPingNs = now;
        }
        (void)followNetworkChanges(bus); // a station's link that came up after the start (vehicles: DdsBridge)
        (void)rejoinIfStalled(bus);      // a secured handshake Fast DDS left unfinished
        sleepMs(kMonitorPoll);
    }
    systemd.stopping();
    (*task)->stop();
    RunResult result;
    result.correlator = (*task)->stats();
    result.report.wallSeconds = static_cast<double>(MonotonicClock::nowNs() - startNs) * 1e-9;
    return result;
}

} // namespace

Result<adapters::ServiceConfig, Error> withEnvironment(adapters::ServiceConfig config)
{
    const auto domain = ipc::dds::domainFromEnvironment("UGV_DDS_DOMAIN");
    if (!domain) {
        return Unexpected(domain.error());
    }
    if (domain->has_value()) {
        config.dds.domainId = **domain;
    }
    return config;
}

namespace {

/// The config file's settings (the defaults without one) with the environment's overrides.
Result<adapters::ServiceConfig, Error> effectiveConfig(const RunOptions& options)
{
    adapters::ServiceConfig config;
    if (!options.configPath.empty()) {
        auto loaded = adapters::loadConfig(options.configPath);
        if (!loaded) {
            return Unexpected(joinErrors(loaded.error()));
        }
        config = std::move(*loaded);
    }
    return withEnvironment(std::move(config));
}

/// The camera (or recording) and the calibration it is used with.
struct CameraAndCalibration {
    std::unique_ptr<hal::StereoCamera> camera;
    vision::StereoCalibration calibration;
};

/// Opens the camera; a recording carries its calibration, a live camera uses the config's (or --calib).
Result<CameraAndCalibration, Error> openCameraAndCalibration(const adapters::ServiceConfig& config,
                                                             const RunOptions& options)
{
    auto camera = adapters::openCamera(config, options.replayPath, options.replay);
    if (!camera) {
        return Unexpected(camera.error());
    }
    const auto* replay = dynamic_cast<const hal::ReplayCamera*>(camera->get());
    if (replay != nullptr && replay->truncated()) {
        UGV_LOG(Hal, Warn) << replay->description() << ": the recording ends in a cut-off frame; replaying its "
                           << replay->recordedFrames() << " complete frames";
    }
    const std::string calibrationPath =
        !options.calibrationPath.empty() ? options.calibrationPath : (replay != nullptr ? "" : config.calibrationPath);
    auto calibration = calibrationPath.empty()
                           ? adapters::parseCalibration(replay->calibrationText(), std::string(replay->description()) +
                                                                                       " (its stored calibration)")
                           : adapters::loadCalibration(calibrationPath);
    if (!calibration) {
        return Unexpected(calibration.error());
    }
    return CameraAndCalibration{std::move(*camera), std::move(*calibration)};
}

/// iceoryx for frames of `camera`'s size: an embedded RouDi (returned), or the system's, which under systemd may
/// still be setting up when this unit starts, waited for up to options.roudiWait (nullptr returned).
Result<std::unique_ptr<ipc::EmbeddedRouDi>, Error> connectIceoryx(const RunOptions& options,
                                                                  const hal::StereoCamera& camera, bool embedded)
{
    if (embedded) {
        return ipc::EmbeddedRouDi::start(options.appName,
                                         packedFrameBytes(camera.format(), static_cast<std::uint32_t>(camera.width()),
                                                          static_cast<std::uint32_t>(camera.height())));
    }
    const std::int64_t waitUntilNs = MonotonicClock::nowNs() + std::chrono::nanoseconds(options.roudiWait).count();
    while (!ipc::roudiReachable() && MonotonicClock::nowNs() < waitUntilNs &&
           !(options.stop != nullptr && options.stop->load())) {
        sleepMs(kMonitorPoll);
    }
    if (auto runtime = ipc::startRuntime(options.appName); !runtime) {
        return Unexpected(runtime.error());
    }
    return std::unique_ptr<ipc::EmbeddedRouDi>{};
}

/// The service's options: the caller's, with the config file's overload policy and hand-over spin when one was given.
ServiceOptions serviceOptionsFor(const adapters::ServiceConfig& config, const RunOptions& options)
{
    ServiceOptions serviceOptions = options.service;
    if (!options.configPath.empty()) {
        serviceOptions.overload =
            config.overload.policy == adapters::OverloadChoice::Drop ? OverloadPolicy::Drop : OverloadPolicy::Degrade;
        serviceOptions.deadlineFactor = config.overload.deadlineFactor;
        serviceOptions.spinBeforeFrame = std::chrono::microseconds(config.handover.spinUs);
    }
    return serviceOptions;
}

/// The service's tasks on the DDS bus: the bridge (sectors, poses) and the correlator when the config enables it.
struct BusTasks {
    std::unique_ptr<DdsBridge> bridge;
    std::unique_ptr<CorrelatorTask> correlator;
};

Result<BusTasks, Error> createBusTasks(ipc::dds::Bus* bus, const adapters::ServiceConfig& config,
                                       std::chrono::nanoseconds period)
{
    BusTasks tasks;
    if (bus == nullptr) {
        return tasks;
    }
    auto bridge = DdsBridge::create(*bus, config, period);
    if (!bridge) {
        return Unexpected(bridge.error());
    }
    tasks.bridge = std::move(*bridge);
    if (config.correlator.enabled) {
        auto created =
            CorrelatorTask::create(*bus, correlatorOptions(config), *rt::findTask(config.tasks, "correlator"));
        if (!created) {
            return Unexpected(created.error());
        }
        tasks.correlator = std::move(*created);
    }
    // ROS 2 tools list the service as the node /<namespace>/ugvsense (ros_discovery_info). A bus that refuses it (a
    // secured bus whose permissions predate it) costs only that.
    if (auto shown = bus->announceRosNode("ugvsense"); !shown) {
        UGV_LOG(Ipc, Warn) << "not visible to ROS 2 tools: " << shown.error().message();
    }
    return tasks;
}

/// Until a stop, the service's end or RouDi's loss (result.roudiLost; only checked when it is not embedded): the
/// published frames to options.onPublished and the console, and the watchdog pinged at half its interval, only
/// when frames were published since the last ping (a stalled camera or pipeline stops the pings and systemd
/// restarts the service).
void monitor(Service& service, const RunOptions& options, const hal::SystemdNotifier& systemd, bool embedded,
             RunResult& result)
{
    const std::chrono::nanoseconds pingEvery = systemd.watchdogInterval() / 2;
    std::int64_t lastPingNs = 0;
    bool framesSincePing = false;
    PublishedFrame frame;
    std::uint64_t seen = 0;
    std::int64_t lastRoudiCheckNs = 0;
    while (!(options.stop != nullptr && options.stop->load()) && !service.finished()) {
        while (service.nextPublished(frame)) {
            ++seen;
            framesSincePing = true;
            if (options.onPublished) {
                options.onPublished(frame);
            }
            if (options.printEvery > 0 && seen % static_cast<std::uint64_t>(options.printEvery) == 0) {
                std::printf("%s\n", summaryLine(frame).c_str());
                (void)std::fflush(stdout);
            }
        }
        const std::int64_t now = MonotonicClock::nowNs();
        if (pingEvery.count() > 0 && framesSincePing && now - lastPingNs >= pingEvery.count()) {
            systemd.watchdog();
            lastPingNs = now;
            framesSincePing = false;
        }
        // RouDi gone (crashed or restarted): iceoryx 2.0 cannot re-register a running process, so stop and say so;
        // under systemd the unit's Restart= brings the service back once RouDi runs again.
        if (!embedded && now - lastRoudiCheckNs >= kRoudiCheckNs) {
            lastRoudiCheckNs = now;
            if (!ipc::roudiReachable()) {
                result.roudiLost = true;
                return;
            }
        }
        sleepMs(kMonitorPoll);
    }
}

} // namespace

Result<RunResult, Error> runService(const RunOptions& options)
{
    auto effective = effectiveConfig(options);
    if (!effective) {
        return Unexpected(effective.error());
    }
    adapters::ServiceConfig config = std::move(*effective);
    std::unique_ptr<ipc::dds::Bus> bus;
    if (config.dds.enabled) {
        auto created = ipc::dds::Bus::create(busConfig(config));
        if (!created) {
            return Unexpected(created.error());
        }
        bus = std::move(*created);
    }
    if (!config.visionEnabled) {
        return runCorrelatorOnly(config, options, *bus);
    }
    if (options.pinAllTasksTo >= 0) {
        for (rt::TaskSpec& task : config.tasks) {
            task.cpu = options.pinAllTasksTo;
        }
    }
    auto opened = openCameraAndCalibration(config, options);
    if (!opened) {
        return Unexpected(opened.error());
    }
    const bool embedded =
        options.roudi == RouDiMode::Embedded || (options.roudi == RouDiMode::Auto && !ipc::roudiReachable());
    auto roudi = connectIceoryx(options, *opened->camera, embedded);
    if (!roudi) {
        return Unexpected(roudi.error());
    }

    RunResult result;
    const rt::MemoryReport memory = rt::lockMemory();
    for (const std::string& warning : memory.warnings) {
        UGV_LOG(Rt, Warn) << warning;
    }
    result.extras.lockedBytes = memory.lockedBytes;

    ServiceOptions serviceOptions = serviceOptionsFor(config, options);
    auto busTasks = createBusTasks(bus.get(), config, opened->camera->period());
    if (!busTasks) {
        return Unexpected(busTasks.error());
    }
    serviceOptions.bus = busTasks->bridge.get();
    auto service = Service::create(config, opened->calibration, std::move(opened->camera), serviceOptions);
    if (!service) {
        return Unexpected(service.error());
    }
    for (const std::string& warning : (*service)->startReport().warnings) {
        UGV_LOG(Rt, Warn) << warning;
    }
    result.extras.threadCount = processThreadCount();
    (*service)->start();
    if (busTasks->correlator) {
        busTasks->correlator->start();
    }
    const hal::SystemdNotifier systemd;
    systemd.ready();
    systemd.status("replaying " + options.replayPath);
    monitor(**service, options, systemd, embedded, result);
    systemd.stopping();
    (*service)->stop();
    result.report = (*service)->report();
    result.visionRan = true;
    if (busTasks->bridge) {
        result.bus = busTasks->bridge->stats();
    }
    if (busTasks->correlator) {
        busTasks->correlator->stop();
        result.correlator = busTasks->correlator->stats();
    }
    if (!result.roudiLost) {
        service->reset(); // threads and iceoryx ports go before the runtime
    } else {
        (void)service->release(); // without RouDi, tearing the ports down would wait for it: the process exits instead
    }
    return result;
}

} // namespace ugv::service
