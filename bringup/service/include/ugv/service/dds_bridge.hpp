#pragma once

/// @file
/// The service on the DDS bus, run by its low-priority "bus" task (Service's BusSink):
///   out: ugvsense/sectors (with the pose at capture and the ground estimate), rt/<ns>/obstacle_scan (LaserScan,
///        range_max 50 m: for marking), rt/<ns>/clear_scan (LaserScan, range_max the clear range: for clearing no
///        farther than Clear promises), rt/<ns>/negative_obstacles (PointCloud2), ugvsense/health once a second;
///   in:  ugvsense/pose of this vehicle (others' poses are ignored; malformed ones refused and counted; on a secured
///        bus a pose naming this vehicle that another participant wrote is refused and counted too).
///
/// Thread-safety: thread-bound (the bus task), except stats() (relaxed atomics). RT-safe: no.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "ugv/adapters/config.hpp"
#include "ugv/ipc/dds_bus.hpp"
#include "ugv/rt/latency_histogram.hpp"
#include "ugv/service/pose_history.hpp"
#include "ugv/service/service.hpp"

namespace ugv::service {

struct DdsBridgeStats {
    std::uint64_t framesSent = 0;
    std::uint64_t writeFailures = 0;
    std::uint64_t posesUsed = 0;         ///< poses of this vehicle taken
    std::uint64_t posesForeign = 0;      ///< poses of other vehicles (ignored)
    std::uint64_t posesRejected = 0;     ///< malformed poses refused
    std::uint64_t posesImpersonated = 0; ///< secured bus: poses naming this vehicle written by another participant
    std::uint64_t stalePoses = 0;        ///< frames sent with a stale or no pose
    std::uint64_t interfaceChanges = 0;  ///< network interface changes the bus followed (or failed to: logged)
    std::uint64_t stallRejoins = 0;      ///< secured bus: joins again for a stalled handshake (or tries: logged)
};

class DdsBridge final : public BusSink {
public:
    /// `vehicle` names this vehicle in every sample; `period` is the camera's (the LaserScan's scan_time).
    static Result<std::unique_ptr<DdsBridge>, Error> create(ipc::dds::Bus& bus, const adapters::ServiceConfig& config,
                                                            std::chrono::nanoseconds period);
    void onFrame(const BusFrame& frame) noexcept override;
    void idle() noexcept override;
    [[nodiscard]] DdsBridgeStats stats() const noexcept;

private:
    DdsBridge() = default;
    void publishHealth(std::int64_t nowRealNs);

    std::string vehicle_;
    std::string frameId_;
    float rangeMaxM_ = 50.0F;
    float clearRangeM_ = 5.0F; ///< how far a Clear sector promises free ground (the detector's clearRangeM)
    float periodS_ = 0.0F;
    float minDepthM_ = 0.1F; ///< a drop's point is at least this far below the ground (obstacles.min_depth_m)
    std::int64_t poseMaxAgeNs_ = 0;
    ipc::dds::Writer<ipc::dds::msg::ObstacleSectors> sectorsOut_;
    ipc::dds::Writer<ipc::dds::ros::LaserScan_> scanOut_;
    ipc::dds::Writer<ipc::dds::ros::LaserScan_> clearScanOut_;
    ipc::dds::Writer<ipc::dds::ros::PointCloud2_> negativesOut_;
    ipc::dds::Writer<ipc::dds::msg::ServiceHealth> healthOut_;
    ipc::dds::Reader<ipc::dds::msg::VehiclePose> poseIn_;
    ipc::dds::Bus* bus_ = nullptr;              ///< follows network interface changes (idle())
    const ipc::dds::Bus* securedBus_ = nullptr; ///< the bus when secured: whose partition a pose came from
    PoseHistory poses_;
    ipc::dds::msg::ObstacleSectors sectors_;
    ipc::dds::ros::LaserScan_ scan_;
    ipc::dds::ros::LaserScan_ clearScan_;
    ipc::dds::ros::PointCloud2_ cloud_;
    ipc::dds::msg::ServiceHealth health_;
    ipc::dds::msg::VehiclePose pose_;
    rt::LatencyHistogram latency_;
    ipc::HealthRecord lastHealth_{};
    std::uint64_t busDrops_ = 0;
    std::int64_t lastHealthNs_ = 0;
    std::atomic<std::uint64_t> framesSent_{0};
    std::atomic<std::uint64_t> writeFailures_{0};
    std::atomic<std::uint64_t> posesUsed_{0};
    std::atomic<std::uint64_t> posesForeign_{0};
    std::atomic<std::uint64_t> posesRejected_{0};
    std::atomic<std::uint64_t> posesImpersonated_{0};
    std::atomic<std::uint64_t> stalePoses_{0};
    std::atomic<std::uint64_t> interfaceChanges_{0};
    std::atomic<std::uint64_t> stallRejoins_{0};
};

/// The ROS 2 namespace of the config: dds.ros_namespace, else vehicle_id's letters, digits and _ (ugv-1 -> ugv1).
std::string rosNamespace(const adapters::ServiceConfig& config);
/// Bus::followNetworkChanges() with its outcome logged (a vehicle's bus task, a ground station's main loop).
ipc::dds::NetworkChange followNetworkChanges(ipc::dds::Bus& bus);
/// Bus::rejoinIfStalled() with its outcome logged (the same two places). @return whether it joined again or tried
bool rejoinIfStalled(ipc::dds::Bus& bus);
/// The bus settings of the config (participant "ugvsense/<vehicle>").
ipc::dds::BusConfig busConfig(const adapters::ServiceConfig& config);

} // namespace ugv::service
