#pragma once

/// @file
/// Platform values -> DDS samples (the sectors as ugvsense/sectors, a ROS 2 LaserScan and a PointCloud2 of the
/// negative obstacles), and the checks every received sample passes before anything trusts a field (NaN,
/// out-of-range latitude, unknown enum values, empty or oversized strings and sequences).
///
/// Stamps: capture stamps on the frame path are CLOCK_MONOTONIC; on the bus they are UNIX-epoch nanoseconds:
/// monoToRealtimeNs() converts with the offset between the two clocks read now (both clocks tick at the same rate;
/// NTP slews move the offset by microseconds).
///
/// Thread-safety: pure functions. RT-safe: no (the samples own strings and vectors).

#include <cstdint>
#include <string>

#include "ugv/ipc/dds_bus.hpp"
#include "ugv/platform/obstacle_sectors.hpp"

namespace ugv::ipc::dds {

/// CLOCK_REALTIME - CLOCK_MONOTONIC now [ns].
std::int64_t realtimeOffsetNs() noexcept;
/// Nanoseconds since the UNIX epoch now.
std::int64_t realtimeNowNs() noexcept;

/// The ground the sectors were measured against (platform vocabulary, also in the iceoryx SectorsMessage).
using GroundSummary = ugv::GroundSummary;

/// The sectors as ugvsense/sectors (pose fields untouched: the caller attaches the pose).
void toDds(const ObstacleSectors& sectors, const GroundSummary& ground, const std::string& vehicle,
           std::int64_t captureRealNs, std::int64_t publishRealNs, msg::ObstacleSectors& out);
/// Back (ugvsense listen, tests): false when the sample fails validate().
bool fromDds(const msg::ObstacleSectors& in, ObstacleSectors& out);

/// The sectors as a sensor_msgs/LaserScan in frame `frameId` (x forward, y left, on the ground below the camera):
/// one ray per sector at its centre bearing (ROS angles: counter-clockwise, like ours). Obstacle -> its range,
/// Clear -> +inf (REP 117: nothing within range_max; costmaps clear along the ray), Unknown -> NaN (no
/// measurement; nothing cleared). Negative obstacles are in it too: a hole is as impassable as a post. An obstacle
/// at or beyond `rangeMaxM` is +inf as well (nothing within range_max): so with `rangeMaxM` = the clear range
/// (SectorBuilderConfig::clearRangeM) every ray says how far the ground is known free, and no farther (the
/// clear_scan topic).
void toLaserScan(const ObstacleSectors& sectors, std::int64_t captureRealNs, const std::string& frameId,
                 float rangeMinM, float rangeMaxM, float periodS, ros::LaserScan_& out);
/// The negative obstacles as a sensor_msgs/PointCloud2 (x, y, z float32) in `frameId`: one point per Negative
/// sector at its range and centre bearing, z = -depth, never shallower than `minDepthM` (the least depth that counts
/// as a drop: a drop whose bottom was not seen has depth 0, and a point on the ground plane would flicker in and out
/// of a costmap's height band with any TF offset). Empty cloud when there is none.
void toNegativeCloud(const ObstacleSectors& sectors, std::int64_t captureRealNs, const std::string& frameId,
                     float minDepthM, ros::PointCloud2_& out);

/// Why a received sample was refused (static strings), or nullptr when it is fine.
const char* check(const msg::ObstacleSectors& s) noexcept;
const char* check(const msg::ServiceHealth& s) noexcept;
const char* check(const msg::VehiclePose& s) noexcept;
const char* check(const msg::OoiObservation& s) noexcept;
const char* check(const msg::UavObservation& s) noexcept;
const char* check(const msg::ConfirmationState& s) noexcept;
const char* check(const msg::PoseCorrection& s) noexcept;
const char* check(const msg::CorrelatedOoiList& s) noexcept;
const char* check(const ros::LaserScan_& s) noexcept;
const char* check(const ros::PointCloud2_& s) noexcept;
/// A graph sample whose every node has a name (rmw sends none without one; the IDL bounds the rest).
const char* check(const graph::ParticipantEntitiesInfo_& s) noexcept;

/// The participant a sample names as its sender (vehicle, UGV or source): on a secured bus it must be the writer's
/// identity (Bus::writerIdentity), or the sample is sent in another's name. ROS 2 samples name none (empty).
inline std::string sender(const msg::ObstacleSectors& s)
{
    return s.vehicle().to_string();
}
inline std::string sender(const msg::ServiceHealth& s)
{
    return s.vehicle().to_string();
}
inline std::string sender(const msg::VehiclePose& s)
{
    return s.vehicle().to_string();
}
inline std::string sender(const msg::OoiObservation& s)
{
    return s.ugv().to_string();
}
inline std::string sender(const msg::UavObservation& s)
{
    return s.source().to_string();
}
inline std::string sender(const msg::ConfirmationState& s)
{
    return s.source().to_string();
}
inline std::string sender(const msg::PoseCorrection& s)
{
    return s.source().to_string();
}
inline std::string sender(const msg::CorrelatedOoiList& s)
{
    return s.source().to_string();
}
inline std::string sender(const ros::LaserScan_& /*s*/)
{
    return {};
}
inline std::string sender(const ros::PointCloud2_& /*s*/)
{
    return {};
}
inline std::string sender(const graph::ParticipantEntitiesInfo_& /*s*/)
{
    return {};
}

} // namespace ugv::ipc::dds
