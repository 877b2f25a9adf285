#include "ugv/service/dds_bridge.hpp"

#include <cctype>

#include "ugv/ipc/dds_convert.hpp"
#include "ugv/platform/log.hpp"
#include "ugv/service/frame_pipeline.hpp"

namespace ugv::service {

namespace msg = ipc::dds::msg;

namespace {
constexpr std::int64_t kHealthPeriodNs = 1'000'000'000;
double ms(std::chrono::nanoseconds d)
{
    return static_cast<double>(d.count()) * 1e-6;
}
} // namespace

std::string rosNamespace(const adapters::ServiceConfig& config)
{
    if (!config.dds.rosNamespace.empty()) {
        return config.dds.rosNamespace;
    }
    std::string ns;
    for (const char c : config.vehicleId) {
        if (std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_') {
            ns += c;
        }
    }
    return ns.empty() || std::isdigit(static_cast<unsigned char>(ns.front())) != 0 ? "ugv_" + ns : ns;
}

ipc::dds::NetworkChange followNetworkChanges(ipc::dds::Bus& bus)
{
    const ipc::dds::NetworkChange change = bus.followNetworkChanges();
    if (change == ipc::dds::NetworkChange::Followed) {
        UGV_LOG(Ipc, Info) << ipc::dds::kNetworkFollowedNote;
    } else if (change == ipc::dds::NetworkChange::Failed) {
        UGV_LOG(Ipc, Error) << ipc::dds::kNetworkFailedPrefix << bus.lastNetworkError().message();
    }
    return change;
}

bool rejoinIfStalled(ipc::dds::Bus& bus)
{
    const ipc::dds::StallRejoin r = bus.rejoinIfStalled();
    if (r.outcome == ipc::dds::StallRejoin::Rejoined) {
        UGV_LOG(Ipc, Warn) << ipc::dds::describe(r);
    } else if (r.outcome == ipc::dds::StallRejoin::Failed) {
        UGV_LOG(Ipc, Error) << ipc::dds::describe(r);
    }
    return r.outcome != ipc::dds::StallRejoin::None;
}

ipc::dds::BusConfig busConfig(const adapters::ServiceConfig& config)
{
    ipc::dds::BusConfig b;
    b.domainId = config.dds.domainId;
    b.participantName = "ugvsense/" + config.vehicleId;
    if (!config.dds.partition.empty()) {
        b.partitions.push_back(config.dds.partition);
    }
    b.rosNamespace = rosNamespace(config);
    b.discoveryServers = config.dds.discoveryServer;
    b.sharedMemory = config.dds.sharedMemory;
    b.rosReliable = config.dds.rosReliable;
    b.security = adapters::securityOf(config);
    return b;
}

Result<std::unique_ptr<DdsBridge>, Error> DdsBridge::create(ipc::dds::Bus& bus, const adapters::ServiceConfig& config,
                                                            std::chrono::nanoseconds period)
{
    std::unique_ptr<DdsBridge> b(new DdsBridge());
    b->vehicle_ = config.vehicleId;
    b->frameId_ = rosNamespace(config) + "/" + config.dds.frameId;
    b->minDepthM_ = static_cast<float>(config.obstacles.minDepthM);
    b->clearRangeM_ = detectorConfigFrom(config).sectors.clearRangeM;
    b->periodS_ = static_cast<float>(static_cast<double>(period.count()) * 1e-9);
    b->poseMaxAgeNs_ = static_cast<std::int64_t>(config.dds.poseMaxAgeMs * 1e6);
    auto sectors = bus.writer<msg::ObstacleSectors>();
    auto scan = bus.writer<ipc::dds::ros::LaserScan_>();
    auto clearScan = bus.writer<ipc::dds::ros::LaserScan_>(ipc::dds::TopicId::RosClearScan);
    auto negatives = bus.writer<ipc::dds::ros::PointCloud2_>();
    auto health = bus.writer<msg::ServiceHealth>();
    auto pose = bus.reader<msg::VehiclePose>();
    if (!sectors || !scan || !clearScan || !negatives || !health || !pose) {
        return Unexpected(!sectors     ? sectors.error()
                          : !scan      ? scan.error()
                          : !clearScan ? clearScan.error()
                          : !negatives ? negatives.error()
                          : !health    ? health.error()
                                       : pose.error());
    }
    b->sectorsOut_ = *sectors;
    b->scanOut_ = *scan;
    b->clearScanOut_ = *clearScan;
    b->negativesOut_ = *negatives;
    b->healthOut_ = *health;
    b->poseIn_ = *pose;
    b->bus_ = &bus;
    b->securedBus_ = bus.config().security.enabled ? &bus : nullptr;
    b->health_.vehicle(config.vehicleId);
    return b;
}

void DdsBridge::onFrame(const BusFrame& frame) noexcept
{
    try {
        const std::int64_t offset = ipc::dds::realtimeOffsetNs();
        const std::int64_t captureReal = frame.message.sectors.captureStampNs + offset;
        const std::int64_t publishReal = frame.message.publishStampNs + offset;
        idle(); // the newest poses first
        ipc::dds::toDds(frame.message.sectors, frame.message.ground, vehicle_, captureReal, publishReal, sectors_);
        bool stale = true;
        const bool havePose = poses_.at(captureReal, poseMaxAgeNs_, pose_, stale);
        sectors_.pose_valid(havePose);
        sectors_.pose_stale(!havePose || stale);
        if (havePose) {
            sectors_.pose(pose_);
        }
        if (!havePose || stale) {
            stalePoses_.fetch_add(1, std::memory_order_relaxed);
        }
        const bool ok = sectorsOut_.write(sectors_);
        ipc::dds::toLaserScan(frame.message.sectors, captureReal, frameId_, 0.0F, rangeMaxM_, periodS_, scan_);
        ipc::dds::toLaserScan(frame.message.sectors, captureReal, frameId_, 0.0F, clearRangeM_, periodS_, clearScan_);
        ipc::dds::toNegativeCloud(frame.message.sectors, captureReal, frameId_, minDepthM_, cloud_);
        const bool rosOk = scanOut_.write(scan_) && clearScanOut_.write(clearScan_) && negativesOut_.write(cloud_);
        if (!ok || !rosOk) {
            writeFailures_.fetch_add(1, std::memory_order_relaxed);
        }
        framesSent_.fetch_add(1, std::memory_order_relaxed);
        latency_.record(std::chrono::nanoseconds(frame.endToEndNs));
        lastHealth_ = frame.message.health;
        busDrops_ = frame.busDrops;
    } catch (...) {
        writeFailures_.fetch_add(1, std::memory_order_relaxed); // out of memory in Fast DDS: the next frame retries
    }
}

void DdsBridge::idle() noexcept
{
    try {
        msg::VehiclePose p;
        eprosima::fastdds::dds::SampleInfo info;
        while (poseIn_.take(p, &info)) {
            if (ipc::dds::check(p) != nullptr) {
                posesRejected_.fetch_add(1, std::memory_order_relaxed);
            } else if (ipc::dds::sender(p) != vehicle_) {
                posesForeign_.fetch_add(1, std::memory_order_relaxed);
            } else if (securedBus_ != nullptr && securedBus_->writerIdentity(info) != vehicle_) {
                // Only this vehicle's own participants (its certificate, its partition) may say where it is.
                posesImpersonated_.fetch_add(1, std::memory_order_relaxed);
            } else {
                poses_.add(p);
                posesUsed_.fetch_add(1, std::memory_order_relaxed);
            }
        }
        const std::int64_t now = ipc::dds::realtimeNowNs();
        if (now - lastHealthNs_ >= kHealthPeriodNs) {
            lastHealthNs_ = now;
            publishHealth(now);
        }
        if (followNetworkChanges(*bus_) != ipc::dds::NetworkChange::None) {
            interfaceChanges_.fetch_add(1, std::memory_order_relaxed);
        }
        if (rejoinIfStalled(*bus_)) {
            stallRejoins_.fetch_add(1, std::memory_order_relaxed);
        }
    } catch (...) {
        writeFailures_.fetch_add(1, std::memory_order_relaxed);
    }
}

void DdsBridge::publishHealth(std::int64_t nowRealNs)
{
    health_.stamp_ns(nowRealNs);
    health_.latency_p50_ms(ms(latency_.p50()));
    health_.latency_p90_ms(ms(latency_.p90()));
    health_.latency_p99_ms(ms(latency_.percentile(99.0)));
    health_.latency_max_ms(ms(latency_.max()));
    health_.frames_captured(lastHealth_.framesCaptured);
    health_.frames_processed(lastHealth_.framesProcessed);
    health_.frames_dropped(lastHealth_.framesDropped);
    health_.camera_gaps(lastHealth_.cameraGaps);
    health_.deadline_misses(lastHealth_.deadlineMisses);
    health_.degraded_frames(lastHealth_.degradedFrames);
    health_.camera_reconnects(lastHealth_.cameraReconnects);
    health_.camera_state(static_cast<std::uint8_t>(lastHealth_.camera));
    health_.bus_drops(busDrops_);
    health_.rejected_messages(posesRejected_.load(std::memory_order_relaxed) +
                              posesImpersonated_.load(std::memory_order_relaxed));
    if (!healthOut_.write(health_)) {
        writeFailures_.fetch_add(1, std::memory_order_relaxed);
    }
}

DdsBridgeStats DdsBridge::stats() const noexcept
{
    return {framesSent_.load(std::memory_order_relaxed),    writeFailures_.load(std::memory_order_relaxed),
            posesUsed_.load(std::memory_order_relaxed),     posesForeign_.load(std::memory_order_relaxed),
            posesRejected_.load(std::memory_order_relaxed), posesImpersonated_.load(std::memory_order_relaxed),
            stalePoses_.load(std::memory_order_relaxed),    interfaceChanges_.load(std::memory_order_relaxed),
            stallRejoins_.load(std::memory_order_relaxed)};
}

} // namespace ugv::service
