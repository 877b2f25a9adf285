// Two processes over loopback: a child (this test binary again, in the writer role) writes every DDS type with
// every field set to a distinctive non-default value; the parent reads one sample of each topic and compares it
// with the expected one field by field (the generated operator==).
//
// The child repeats its samples every 50 ms until the parent, done, sends SIGTERM: the best-effort topics (sectors,
// pose, scan, negatives) may lose a sample written while discovery is still completing.

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <limits>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "ugv/ipc/dds_bus.hpp"
#include "ugv/ipc/dds_convert.hpp"

extern char** environ; // POSIX, for posix_spawn

namespace ugv::ipc::dds {
namespace {

constexpr const char* kRoleVar = "UGV_DDS_TEST_ROLE";
constexpr const char* kDomainVar = "UGV_DDS_TEST_DOMAIN";
constexpr const char* kPartitionVar = "UGV_DDS_TEST_PARTITION";
constexpr auto kReceiveTimeout = std::chrono::seconds(15);
constexpr auto kWriterLifetime = std::chrono::seconds(30); ///< the child ends by itself if the parent died
/// Overrides kWriterLifetime [s]: a caller that reads many topics one process at a time (listen_types_test.sh) needs
/// longer on a loaded sanitizer build; it stops the writer itself at the end.
constexpr const char* kLifetimeVar = "UGV_DDS_TEST_WRITER_S";

// ---- the samples: every field distinctive (no two fields of a struct alike, no default value) ----

msg::VehiclePose pose()
{
    msg::VehiclePose p;
    p.vehicle("ugv-roundtrip-7");
    p.stamp_ns(1'717'171'717'123'456'789);
    p.latitude_deg(-34.928512345);
    p.longitude_deg(138.600712345);
    p.altitude_m(51.25);
    p.east_m(-12.5);
    p.north_m(33.75);
    p.up_m(0.125);
    p.heading_deg(271.5);
    p.covariance({0.04, 0.001, 0.002, 0.003, 0.05, 0.004, 0.005, 0.006, 1.5});
    return p;
}

msg::ObstacleSectors sectors()
{
    msg::ObstacleSectors s;
    s.vehicle("ugv-roundtrip-7");
    s.sequence_number(987'654'321'012ULL);
    s.capture_stamp_ns(1'717'171'717'100'000'001);
    s.publish_stamp_ns(1'717'171'717'104'000'003);
    s.pose_valid(true);
    s.pose_stale(true);
    s.pose(pose());
    msg::GroundEstimate g;
    g.reliable(true);
    g.pitch_deg(-2.5F);
    g.roll_deg(1.25F);
    g.camera_height_m(1.125F);
    s.ground(g);
    s.degraded(true);
    for (int i = 0; i < 5; ++i) {
        msg::Sector x;
        x.bearing_min_deg(-30.0F + 12.0F * static_cast<float>(i));
        x.bearing_max_deg(-18.0F + 12.0F * static_cast<float>(i));
        x.range_m(i == 1 ? std::numeric_limits<float>::infinity() : 2.5F + static_cast<float>(i));
        x.height_m(0.25F * static_cast<float>(i + 1));
        x.confidence(0.15F * static_cast<float>(i + 1));
        x.state(static_cast<std::uint8_t>(i == 1 ? 1 : 2));
        x.kind(static_cast<std::uint8_t>(1 + i % 2));
        x.danger(static_cast<std::uint8_t>(1 + i % 3));
        s.sectors().push_back(x);
    }
    return s;
}

msg::ServiceHealth health()
{
    msg::ServiceHealth h;
    h.vehicle("ugv-roundtrip-7");
    h.stamp_ns(1'717'171'718'000'000'007);
    h.latency_p50_ms(3.25);
    h.latency_p90_ms(4.5);
    h.latency_p99_ms(7.75);
    h.latency_max_ms(12.125);
    h.frames_captured(100'001);
    h.frames_processed(100'002);
    h.frames_dropped(3);
    h.camera_gaps(4);
    h.deadline_misses(5);
    h.degraded_frames(6);
    h.camera_reconnects(7);
    h.camera_state(1);
    h.bus_drops(8);
    h.rejected_messages(9);
    return h;
}

msg::OoiObservation observation()
{
    msg::OoiObservation o;
    o.ugv("ugv-3");
    o.sequence_number(4242);
    o.t(123.456);
    o.track("track-uuid-9f8e");
    o.cls(2);
    o.ugv_lat_deg(-34.91);
    o.ugv_lon_deg(138.61);
    o.ugv_heading_deg(123.5);
    o.range_m(17.25);
    o.bearing_deg(-33.5);
    return o;
}

msg::UavObservation uav()
{
    msg::UavObservation u;
    u.source("uav-hawk");
    u.sequence_number(77);
    u.t(200.5);
    u.cls(1);
    u.lat_deg(-34.92);
    u.lon_deg(138.62);
    return u;
}

msg::ConfirmationState confirmation()
{
    msg::ConfirmationState c;
    c.source("gcs-console-2");
    c.sequence_number(88);
    c.t(300.25);
    c.id("ooi-17");
    c.state(2);
    return c;
}

msg::PoseCorrection correction()
{
    msg::PoseCorrection p;
    p.source("map-builder");
    p.sequence_number(99);
    p.t(400.75);
    p.ugv("ugv-4");
    p.since_t(310.5);
    p.until_t(390.25);
    p.d_east_m(1.5);
    p.d_north_m(-2.25);
    p.d_heading_deg(3.125);
    return p;
}

msg::CorrelatedOoiList correlated()
{
    msg::CorrelatedOoiList l;
    l.source("gcs-correlator");
    l.sequence_number(555);
    l.t(500.5);
    l.inputs_accepted(12'345);
    l.inputs_rejected(67);
    for (int i = 0; i < 3; ++i) {
        msg::CorrelatedOoi o;
        o.id("ooi-" + std::to_string(i + 1));
        o.cls(static_cast<std::uint8_t>(i));
        o.lat_deg(-34.93 - 0.001 * i);
        o.lon_deg(138.63 + 0.001 * i);
        o.sigma_major_m(1.5 + i);
        o.sigma_minor_m(0.5 + i);
        o.major_axis_deg(45.0 + 10.0 * i);
        o.state(static_cast<std::uint8_t>(2 - i));
        o.observations(10 + i);
        for (int u = 0; u <= i; ++u) {
            o.ugvs().emplace_back("ugv-" + std::to_string(u + 1));
        }
        o.zone_diameter_m(i == 1 ? 20.0 : 5.0);
        l.objects().push_back(o);
    }
    for (int i = 0; i < 2; ++i) {
        msg::Alert a;
        a.non_combatant_id("ooi-" + std::to_string(i + 3));
        a.object_id("ooi-" + std::to_string(i + 1));
        a.distance_m(4.5 + i);
        l.alerts().push_back(a);
    }
    return l;
}

ros::LaserScan_ scan()
{
    ros::LaserScan_ s;
    s.header().stamp().sec(1'717'171'719);
    s.header().stamp().nanosec(123'456'789);
    s.header().frame_id("ugv1/camera_ground");
    s.angle_min(-0.5F);
    s.angle_max(0.5F);
    s.angle_increment(0.25F);
    s.time_increment(0.001F);
    s.scan_time(0.1F);
    s.range_min(0.3F);
    s.range_max(40.0F);
    s.ranges({1.5F, std::numeric_limits<float>::infinity(), 3.5F, 4.25F, 5.125F});
    s.intensities({10.0F, 20.0F, 30.0F, 40.0F, 50.0F});
    return s;
}

ros::PointCloud2_ cloud()
{
    ros::PointCloud2_ c;
    c.header().stamp().sec(1'717'171'720);
    c.header().stamp().nanosec(987'654'321);
    c.header().frame_id("ugv1/camera_ground");
    c.height(1);
    c.width(2);
    const char* names[] = {"x", "y", "z"};
    for (std::uint32_t i = 0; i < 3; ++i) {
        ros::PointField_ f;
        f.name(names[i]);
        f.offset(4 * i);
        f.datatype(7);
        f.count(1);
        c.fields().push_back(f);
    }
    c.is_bigendian(true); // not what we publish, but distinct from the default
    c.point_step(12);
    c.row_step(24);
    for (int i = 0; i < 24; ++i) {
        c.data().push_back(static_cast<std::uint8_t>(0xA0 + i));
    }
    c.is_dense(true);
    return c;
}

graph::ParticipantEntitiesInfo_ graphInfo()
{
    graph::ParticipantEntitiesInfo_ info;
    for (std::size_t i = 0; i < info.gid().data().size(); ++i) {
        info.gid().data()[i] = static_cast<std::uint8_t>(0x10 + i);
    }
    graph::NodeEntitiesInfo_ node;
    node.node_namespace("/ugv_roundtrip");
    node.node_name("ugvsense_roundtrip");
    graph::Gid_ reader;
    reader.data().fill(0x5A);
    graph::Gid_ writer;
    writer.data().fill(0xA5);
    node.reader_gid_seq().push_back(reader);
    node.writer_gid_seq() = {writer, reader};
    info.node_entities_info_seq().push_back(node);
    return info;
}

/// The ROS 2 topics are in the default partition: a namespace of the test's own keeps them apart too.
BusConfig testConfig(int domain, const std::string& partition)
{
    BusConfig c;
    c.domainId = domain;
    c.participantName = "unit-dds-roundtrip";
    c.partitions = {partition};
    c.rosNamespace = partition;
    return c;
}

std::atomic<bool> g_writerStop{false};

struct AllWriters {
    Writer<msg::ObstacleSectors> sectors;
    Writer<msg::ServiceHealth> health;
    Writer<msg::VehiclePose> pose;
    Writer<msg::OoiObservation> observation;
    Writer<msg::UavObservation> uav;
    Writer<msg::ConfirmationState> confirmation;
    Writer<msg::PoseCorrection> correction;
    Writer<msg::CorrelatedOoiList> correlated;
    Writer<ros::LaserScan_> scan;
    Writer<ros::PointCloud2_> cloud;
    Writer<graph::ParticipantEntitiesInfo_> graph;
    Writer<ros::LaserScan_> clearScan;
};

template <class T>
bool make(Bus& bus, Writer<T>& out, TopicId id = TopicOf<T>::id)
{
    auto w = bus.writer<T>(id);
    if (!w) {
        return false;
    }
    out = *w;
    return true;
}

/// The child: writes every sample every 50 ms until SIGTERM. Exit code 0, or 3 when the bus failed.
int runWriter()
{
    struct sigaction action {};
    action.sa_handler = [](int /*signal*/) { g_writerStop.store(true); };
    ::sigaction(SIGTERM, &action, nullptr);
    const char* domain = std::getenv(kDomainVar);
    const char* partition = std::getenv(kPartitionVar);
    if (domain == nullptr || partition == nullptr) {
        return 3;
    }
    auto bus = Bus::create(testConfig(std::atoi(domain), partition));
    if (!bus) {
        return 3;
    }
    AllWriters w;
    Bus& b = **bus;
    if (!make(b, w.sectors) || !make(b, w.health) || !make(b, w.pose) || !make(b, w.observation) || !make(b, w.uav) ||
        !make(b, w.confirmation) || !make(b, w.correction) || !make(b, w.correlated) || !make(b, w.scan) ||
        !make(b, w.cloud) || !make(b, w.graph) || !make(b, w.clearScan, TopicId::RosClearScan)) {
        return 3;
    }
    const auto samples = std::make_tuple(sectors(), health(), pose(), observation(), uav(), confirmation(),
                                         correction(), correlated(), scan(), cloud(), graphInfo());
    auto lifetime = std::chrono::duration_cast<std::chrono::steady_clock::duration>(kWriterLifetime);
    if (const char* seconds = std::getenv(kLifetimeVar); seconds != nullptr && std::atoi(seconds) > 0) {
        lifetime = std::chrono::seconds(std::atoi(seconds));
    }
    const auto until = std::chrono::steady_clock::now() + lifetime;
    while (!g_writerStop.load() && std::chrono::steady_clock::now() < until) {
        w.sectors.write(std::get<0>(samples));
        w.health.write(std::get<1>(samples));
        w.pose.write(std::get<2>(samples));
        w.observation.write(std::get<3>(samples));
        w.uav.write(std::get<4>(samples));
        w.confirmation.write(std::get<5>(samples));
        w.correction.write(std::get<6>(samples));
        w.correlated.write(std::get<7>(samples));
        w.scan.write(std::get<8>(samples));
        w.cloud.write(std::get<9>(samples));
        w.graph.write(std::get<10>(samples));
        w.clearScan.write(std::get<8>(samples));
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return 0;
}

/// Takes the first sample of `reader` into `out` (once); true when it has one.
template <class T>
bool poll(Reader<T>& reader, T& out, bool& got)
{
    if (!got && reader.take(out)) {
        got = true;
    }
    return got;
}

TEST(DdsTwoProcess, EveryTypeRoundTripsWithAllFields)
{
    if (const char* role = std::getenv(kRoleVar); role != nullptr && std::string(role) == "writer") {
        std::_Exit(runWriter()); // the child: no gtest report, no static destructors racing Fast DDS threads
    }
    // Arrange: a domain and partition of our own (parallel tests, other DDS users of the machine).
    const int domain = 150 + static_cast<int>(::getpid() % 80);
    const std::string partition = "unit_dds_" + std::to_string(::getpid());
    auto bus = Bus::create(testConfig(domain, partition));
    ASSERT_TRUE(bus) << bus.error().message();
    Bus& b = **bus;
    auto rSectors = b.reader<msg::ObstacleSectors>();
    auto rHealth = b.reader<msg::ServiceHealth>();
    auto rPose = b.reader<msg::VehiclePose>();
    auto rObservation = b.reader<msg::OoiObservation>();
    auto rUav = b.reader<msg::UavObservation>();
    auto rConfirmation = b.reader<msg::ConfirmationState>();
    auto rCorrection = b.reader<msg::PoseCorrection>();
    auto rCorrelated = b.reader<msg::CorrelatedOoiList>();
    auto rScan = b.reader<ros::LaserScan_>();
    auto rCloud = b.reader<ros::PointCloud2_>();
    auto rGraph = b.reader<graph::ParticipantEntitiesInfo_>();
    auto rClearScan = b.reader<ros::LaserScan_>(TopicId::RosClearScan);
    ASSERT_TRUE(rSectors && rHealth && rPose && rObservation && rUav && rConfirmation && rCorrection && rCorrelated &&
                rScan && rCloud && rGraph && rClearScan);

    const std::string self = "/proc/self/exe";
    const std::string filter = "--gtest_filter=DdsTwoProcess.EveryTypeRoundTripsWithAllFields";
    std::vector<std::string> env{std::string(kRoleVar) + "=writer",
                                 std::string(kDomainVar) + "=" + std::to_string(domain),
                                 std::string(kPartitionVar) + "=" + partition};
    std::vector<char*> envp;
    for (std::string& e : env) {
        envp.push_back(e.data());
    }
    for (char** e = environ; *e != nullptr; ++e) {
        envp.push_back(*e);
    }
    envp.push_back(nullptr);
    std::string exe = self;
    std::string arg = filter;
    char* argv[] = {exe.data(), arg.data(), nullptr};
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0); // the child's gtest banner
    pid_t child = 0;
    const int spawned = ::posix_spawn(&child, self.c_str(), &actions, nullptr, argv, envp.data());
    posix_spawn_file_actions_destroy(&actions);
    ASSERT_EQ(spawned, 0) << "posix_spawn of the writer failed";

    // Act: one sample of every topic, or the timeout.
    msg::ObstacleSectors gotSectors;
    msg::ServiceHealth gotHealth;
    msg::VehiclePose gotPose;
    msg::OoiObservation gotObservation;
    msg::UavObservation gotUav;
    msg::ConfirmationState gotConfirmation;
    msg::PoseCorrection gotCorrection;
    msg::CorrelatedOoiList gotCorrelated;
    ros::LaserScan_ gotScan;
    ros::PointCloud2_ gotCloud;
    graph::ParticipantEntitiesInfo_ gotGraph;
    ros::LaserScan_ gotClearScan;
    bool got[kTopicCount] = {};
    const auto until = std::chrono::steady_clock::now() + kReceiveTimeout;
    bool all = false;
    while (!all && std::chrono::steady_clock::now() < until) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        // Every reader is polled in each round (a braced list is evaluated in order, without short-circuit).
        const bool polled[] = {poll(*rSectors, gotSectors, got[0]),
                               poll(*rHealth, gotHealth, got[1]),
                               poll(*rPose, gotPose, got[2]),
                               poll(*rObservation, gotObservation, got[3]),
                               poll(*rUav, gotUav, got[4]),
                               poll(*rConfirmation, gotConfirmation, got[5]),
                               poll(*rCorrection, gotCorrection, got[6]),
                               poll(*rCorrelated, gotCorrelated, got[7]),
                               poll(*rScan, gotScan, got[8]),
                               poll(*rCloud, gotCloud, got[9]),
                               poll(*rGraph, gotGraph, got[10]),
                               poll(*rClearScan, gotClearScan, got[11])};
        all = std::all_of(std::begin(polled), std::end(polled), [](bool p) { return p; });
    }
    ::kill(child, SIGTERM);
    int status = 0;
    ::waitpid(child, &status, 0);

    // Assert
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "the writer failed, status " << status;
    for (int i = 0; i < kTopicCount; ++i) {
        EXPECT_TRUE(got[i]) << "nothing arrived on " << topicName(static_cast<TopicId>(i), b.config());
    }
    EXPECT_TRUE(gotSectors == sectors());
    EXPECT_TRUE(gotHealth == health());
    EXPECT_TRUE(gotPose == pose());
    EXPECT_TRUE(gotObservation == observation());
    EXPECT_TRUE(gotUav == uav());
    EXPECT_TRUE(gotConfirmation == confirmation());
    EXPECT_TRUE(gotCorrection == correction());
    EXPECT_TRUE(gotCorrelated == correlated());
    EXPECT_TRUE(gotScan == scan());
    EXPECT_TRUE(gotCloud == cloud());
    EXPECT_TRUE(gotGraph == graphInfo());
    EXPECT_TRUE(gotClearScan == scan());
    // The distinctive values are valid ones: the checks of the receivers accept them.
    EXPECT_EQ(check(gotSectors), nullptr);
    EXPECT_EQ(check(gotHealth), nullptr);
    EXPECT_EQ(check(gotPose), nullptr);
    EXPECT_EQ(check(gotObservation), nullptr);
    EXPECT_EQ(check(gotUav), nullptr);
    EXPECT_EQ(check(gotConfirmation), nullptr);
    EXPECT_EQ(check(gotCorrection), nullptr);
    EXPECT_EQ(check(gotCorrelated), nullptr);
    EXPECT_EQ(check(gotScan), nullptr);
    EXPECT_EQ(check(gotCloud), nullptr);
}

TEST(DdsTwoProcess, SamplesAreDistinctFromDefaults)
{
    // The round trip proves nothing for a field left at its default: every field differs from it.
    EXPECT_FALSE(pose() == msg::VehiclePose{});
    const msg::VehiclePose p = pose();
    EXPECT_NE(p.stamp_ns(), 0);
    for (double c : p.covariance()) {
        EXPECT_NE(c, 0.0);
    }
    const msg::ObstacleSectors s = sectors();
    EXPECT_TRUE(s.pose_valid() && s.pose_stale() && s.degraded() && s.ground().reliable());
    EXPECT_GE(s.sectors().size(), 2U);
    const msg::CorrelatedOoiList l = correlated();
    EXPECT_FALSE(l.objects().empty());
    EXPECT_FALSE(l.alerts().empty());
    EXPECT_FALSE(l.objects().back().ugvs().empty());
    EXPECT_TRUE(cloud().is_bigendian() && cloud().is_dense());
}

} // namespace
} // namespace ugv::ipc::dds
