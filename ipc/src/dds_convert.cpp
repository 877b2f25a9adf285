#include "ugv/ipc/dds_convert.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "ugv/ipc/sectors_message.hpp"
#include "ugv/platform/angles.hpp"
#include "ugv/platform/clock.hpp"

namespace ugv::ipc::dds {

namespace {

builtin_interfaces::msg::dds_::Time_ rosTime(std::int64_t realNs)
{
    builtin_interfaces::msg::dds_::Time_ t;
    t.sec(static_cast<std::int32_t>(realNs / 1'000'000'000));
    t.nanosec(static_cast<std::uint32_t>(realNs % 1'000'000'000));
    return t;
}

bool finite(double v) noexcept
{
    return std::isfinite(v);
}
bool latOk(double v) noexcept
{
    return finite(v) && v >= -90.0 && v <= 90.0;
}
bool lonOk(double v) noexcept
{
    return finite(v) && v >= -180.0 && v <= 180.0;
}
template <std::size_t N>
bool named(const eprosima::fastrtps::fixed_string<N>& s) noexcept
{
    static_assert(N == kMaxNameLength + 1, "names are bounded one above kMaxNameLength (ugvsense.idl)");
    return s.size() > 0 && s.size() <= kMaxNameLength;
}

float centreRad(const Sector& s) noexcept
{
    return static_cast<float>(0.5 * (static_cast<double>(s.bearingMinDeg) + s.bearingMaxDeg) * kDegToRad);
}

} // namespace

std::int64_t realtimeOffsetNs() noexcept
{
    return clockNs(CLOCK_REALTIME) - clockNs(CLOCK_MONOTONIC);
}
std::int64_t realtimeNowNs() noexcept
{
    return clockNs(CLOCK_REALTIME);
}

void toDds(const ObstacleSectors& sectors, const GroundSummary& ground, const std::string& vehicle,
           std::int64_t captureRealNs, std::int64_t publishRealNs, msg::ObstacleSectors& out)
{
    out.vehicle(vehicle);
    out.sequence_number(sectors.sequence);
    out.capture_stamp_ns(captureRealNs);
    out.publish_stamp_ns(publishRealNs);
    out.degraded(sectors.degraded);
    msg::GroundEstimate g;
    g.reliable(ground.reliable);
    g.pitch_deg(ground.pitchDeg);
    g.roll_deg(ground.rollDeg);
    g.camera_height_m(ground.cameraHeightM);
    out.ground(g);
    std::vector<msg::Sector>& v = out.sectors();
    v.resize(static_cast<std::size_t>(sectors.count));
    for (std::size_t i = 0; i < v.size(); ++i) {
        const Sector& s = sectors.sectors[i];
        msg::Sector& d = v[i];
        d.bearing_min_deg(s.bearingMinDeg);
        d.bearing_max_deg(s.bearingMaxDeg);
        d.range_m(s.rangeM);
        d.height_m(s.heightM);
        d.confidence(s.confidence);
        d.state(static_cast<std::uint8_t>(s.state));
        d.kind(static_cast<std::uint8_t>(s.kind));
        d.danger(static_cast<std::uint8_t>(s.danger));
    }
}

bool fromDds(const msg::ObstacleSectors& in, ObstacleSectors& out)
{
    if (check(in) != nullptr) {
        return false;
    }
    out = ObstacleSectors{};
    out.sequence = in.sequence_number();
    out.captureStampNs = in.capture_stamp_ns();
    out.degraded = in.degraded();
    out.count = static_cast<std::int32_t>(in.sectors().size());
    for (std::size_t i = 0; i < in.sectors().size(); ++i) {
        const msg::Sector& s = in.sectors()[i];
        Sector& d = out.sectors[i];
        d.bearingMinDeg = s.bearing_min_deg();
        d.bearingMaxDeg = s.bearing_max_deg();
        d.rangeM = s.range_m();
        d.heightM = s.height_m();
        d.confidence = s.confidence();
        d.state = static_cast<SectorState>(s.state());
        d.kind = static_cast<ObstacleKind>(s.kind());
        d.danger = static_cast<DangerClass>(s.danger());
    }
    return true;
}

void toLaserScan(const ObstacleSectors& sectors, std::int64_t captureRealNs, const std::string& frameId,
                 float rangeMinM, float rangeMaxM, float periodS, ros::LaserScan_& out)
{
    out.header().stamp(rosTime(captureRealNs));
    out.header().frame_id(frameId);
    const auto n = static_cast<std::size_t>(sectors.count);
    out.ranges().resize(n);
    out.intensities().clear();
    if (n == 0) {
        out.angle_min(0.0F);
        out.angle_max(0.0F);
        out.angle_increment(0.0F);
    } else {
        out.angle_min(centreRad(sectors.sectors[0]));
        out.angle_max(centreRad(sectors.sectors[n - 1]));
        out.angle_increment(n > 1 ? (out.angle_max() - out.angle_min()) / static_cast<float>(n - 1) : 0.0F);
    }
    out.time_increment(0.0F); // a global-shutter camera: every ray at the exposure
    out.scan_time(periodS);
    out.range_min(rangeMinM);
    out.range_max(rangeMaxM);
    for (std::size_t i = 0; i < n; ++i) {
        const Sector& s = sectors.sectors[i];
        switch (s.state) {
        case SectorState::Obstacle:
            // beyond range_max: nothing within it (+inf); a range that is no number stays NaN (unknown), never clear
            out.ranges()[i] = s.rangeM >= rangeMaxM ? std::numeric_limits<float>::infinity() : s.rangeM;
            break;
        case SectorState::Clear:
            out.ranges()[i] = std::numeric_limits<float>::infinity();
            break;
        case SectorState::Unknown:
            out.ranges()[i] = std::numeric_limits<float>::quiet_NaN();
            break;
        }
    }
}

void toNegativeCloud(const ObstacleSectors& sectors, std::int64_t captureRealNs, const std::string& frameId,
                     float minDepthM, ros::PointCloud2_& out)
{
    out.header().stamp(rosTime(captureRealNs));
    out.header().frame_id(frameId);
    if (out.fields().size() != 3) {
        out.fields().resize(3);
        const char* names[] = {"x", "y", "z"};
        for (std::size_t i = 0; i < 3; ++i) {
            out.fields()[i].name(names[i]);
            out.fields()[i].offset(static_cast<std::uint32_t>(4 * i));
            out.fields()[i].datatype(7); // sensor_msgs/PointField FLOAT32
            out.fields()[i].count(1);
        }
    }
    out.is_bigendian(false);
    out.point_step(12);
    out.is_dense(true);
    out.height(1);
    std::vector<std::uint8_t>& data = out.data();
    data.clear();
    for (int i = 0; i < sectors.count; ++i) {
        const Sector& s = sectors.sectors[static_cast<std::size_t>(i)];
        if (s.state != SectorState::Obstacle || s.kind != ObstacleKind::Negative || !std::isfinite(s.rangeM)) {
            continue;
        }
        const float b = centreRad(s);
        const float xyz[3] = {s.rangeM * std::cos(b), s.rangeM * std::sin(b),
                              -std::max(std::fabs(s.heightM), minDepthM)};
        const std::size_t at = data.size();
        data.resize(at + sizeof(xyz));
        std::memcpy(data.data() + at, xyz, sizeof(xyz)); // little-endian host (x86-64, aarch64)
    }
    out.width(static_cast<std::uint32_t>(data.size() / 12));
    out.row_step(static_cast<std::uint32_t>(data.size()));
}

const char* check(const msg::ObstacleSectors& s) noexcept
{
    if (!named(s.vehicle())) {
        return "no vehicle name";
    }
    if (s.sectors().empty() || s.sectors().size() > static_cast<std::size_t>(kMaxSectors)) {
        return "sector count out of range (1..180)";
    }
    for (const msg::Sector& x : s.sectors()) {
        if (!std::isfinite(x.bearing_min_deg()) || !std::isfinite(x.bearing_max_deg()) ||
            !(x.bearing_min_deg() < x.bearing_max_deg()) || x.state() > 2 || x.kind() > 2 || x.danger() > 3 ||
            !(x.confidence() >= 0.0F && x.confidence() <= 1.0F) || std::isnan(x.range_m()) ||
            std::isnan(x.height_m())) {
            return "a sector has invalid fields (bearing, enum, range, height or confidence)";
        }
        if (x.state() == 2 && !(std::isfinite(x.range_m()) && x.range_m() > 0.0F)) {
            return "an obstacle sector without a finite positive range";
        }
    }
    if (s.pose_valid() && check(s.pose()) != nullptr) {
        return check(s.pose());
    }
    return nullptr;
}

const char* check(const msg::ServiceHealth& s) noexcept
{
    if (!named(s.vehicle())) {
        return "no vehicle name";
    }
    if (!finite(s.latency_p50_ms()) || !finite(s.latency_p90_ms()) || !finite(s.latency_p99_ms()) ||
        !finite(s.latency_max_ms())) {
        return "a latency is not finite";
    }
    return s.camera_state() > static_cast<std::uint8_t>(CameraState::LeftOnly) ? "unknown camera state" : nullptr;
}

const char* check(const msg::VehiclePose& s) noexcept
{
    if (!named(s.vehicle())) {
        return "no vehicle name";
    }
    if (!latOk(s.latitude_deg()) || !lonOk(s.longitude_deg())) {
        return "latitude or longitude out of range or not finite";
    }
    if (!finite(s.altitude_m()) || !finite(s.east_m()) || !finite(s.north_m()) || !finite(s.up_m()) ||
        !finite(s.heading_deg())) {
        return "a position or the heading is not finite";
    }
    for (double c : s.covariance()) {
        if (!finite(c)) {
            return "the covariance is not finite";
        }
    }
    return s.stamp_ns() <= 0 ? "no timestamp" : nullptr;
}

const char* check(const msg::OoiObservation& s) noexcept
{
    if (!named(s.ugv()) || !named(s.track())) {
        return "no ugv or track name";
    }
    if (!finite(s.t()) || !latOk(s.ugv_lat_deg()) || !lonOk(s.ugv_lon_deg())) {
        return "time, latitude or longitude out of range or not finite";
    }
    if (!finite(s.ugv_heading_deg()) || !finite(s.bearing_deg()) || !finite(s.range_m()) || s.range_m() < 0.0) {
        return "heading, bearing or range not finite (or a negative range)";
    }
    return s.cls() > 3 ? "unknown class" : nullptr;
}

const char* check(const msg::UavObservation& s) noexcept
{
    if (!named(s.source())) {
        return "no source name";
    }
    if (!finite(s.t()) || !latOk(s.lat_deg()) || !lonOk(s.lon_deg())) {
        return "time, latitude or longitude out of range or not finite";
    }
    return s.cls() > 3 ? "unknown class" : nullptr;
}

const char* check(const msg::ConfirmationState& s) noexcept
{
    if (!named(s.source()) || !named(s.id())) {
        return "no source or object id";
    }
    if (!finite(s.t())) {
        return "time not finite";
    }
    return s.state() > 2 ? "unknown confirmation state" : nullptr;
}

const char* check(const msg::PoseCorrection& s) noexcept
{
    if (!named(s.source()) || !named(s.ugv())) {
        return "no source or ugv name";
    }
    if (!finite(s.t()) || !finite(s.since_t()) || !finite(s.until_t()) || !(s.since_t() <= s.until_t())) {
        return "times not finite or since_t after until_t";
    }
    if (!finite(s.d_east_m()) || !finite(s.d_north_m()) || !finite(s.d_heading_deg())) {
        return "a correction is not finite";
    }
    return nullptr;
}

const char* check(const msg::CorrelatedOoiList& s) noexcept
{
    if (!named(s.source()) || !finite(s.t())) {
        return "no source name or time not finite";
    }
    if (s.objects().size() > static_cast<std::size_t>(msg::MAX_OBJECTS) ||
        s.alerts().size() > static_cast<std::size_t>(msg::MAX_ALERTS)) {
        return "too many objects or alerts";
    }
    for (const msg::CorrelatedOoi& o : s.objects()) {
        if (!named(o.id()) || !latOk(o.lat_deg()) || !lonOk(o.lon_deg()) || o.cls() > 3 || o.state() > 2 ||
            !finite(o.sigma_major_m()) || !finite(o.sigma_minor_m()) || !finite(o.major_axis_deg()) ||
            o.ugvs().size() > 64) {
            return "an object has invalid fields";
        }
    }
    for (const msg::Alert& a : s.alerts()) {
        if (!named(a.non_combatant_id()) || !named(a.object_id()) || !finite(a.distance_m())) {
            return "an alert has invalid fields";
        }
    }
    return nullptr;
}

const char* check(const ros::LaserScan_& s) noexcept
{
    if (!finite(s.angle_min()) || !finite(s.angle_max()) || !finite(s.angle_increment())) {
        return "angles not finite";
    }
    if (s.ranges().size() > 100'000) {
        return "too many rays";
    }
    // ROS: intensities are empty or one per ray (a consumer indexes them by the ray).
    return !s.intensities().empty() && s.intensities().size() != s.ranges().size() ? "intensities do not match the rays"
                                                                                   : nullptr;
}

const char* check(const ros::PointCloud2_& s) noexcept
{
    // width x height x point_step can exceed 64 bits (3 x 32): a crafted sample must not wrap around to the size
    // of its (small) data; row_step must be width x point_step (a consumer steps rows by it).
    const std::uint64_t points = static_cast<std::uint64_t>(s.width()) * s.height(); // < 2^64
    if (s.point_step() == 0 || points > s.data().size() / s.point_step() ||
        points * s.point_step() != s.data().size()) {
        return "data size does not match width x height x point_step";
    }
    if (static_cast<std::uint64_t>(s.row_step()) != static_cast<std::uint64_t>(s.width()) * s.point_step()) {
        return "row_step is not width x point_step";
    }
    return nullptr;
}

const char* check(const graph::ParticipantEntitiesInfo_& s) noexcept
{
    for (const graph::NodeEntitiesInfo_& node : s.node_entities_info_seq()) {
        if (node.node_name().size() == 0) {
            return "a node without a name";
        }
    }
    return nullptr;
}

} // namespace ugv::ipc::dds
