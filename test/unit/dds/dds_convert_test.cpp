// ipc/dds_convert: the sectors as ugvsense/sectors, LaserScan and PointCloud2 (ROS 2 conventions), and the
// checks every received sample passes.

#include "ugv/ipc/dds_convert.hpp"

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <gtest/gtest.h>

namespace ugv::ipc::dds {
namespace {

constexpr float kPi = 3.14159265358979F;
constexpr float kDegToRad = kPi / 180.0F;
constexpr float kAngleTolerance = 1e-6F;

/// Four 15-degree sectors over [-30, 30] deg: obstacle at 3.5 m, clear, unknown, negative obstacle at 4 m, 0.3 m deep.
ObstacleSectors fourSectors()
{
    ObstacleSectors s;
    initSectors(s, 4, 60.0F);
    s.sequence = 41;
    s.captureStampNs = 1'000;
    s.degraded = true;
    s.sectors[0].state = SectorState::Obstacle;
    s.sectors[0].kind = ObstacleKind::Positive;
    s.sectors[0].rangeM = 3.5F;
    s.sectors[0].heightM = 0.8F;
    s.sectors[0].confidence = 0.9F;
    s.sectors[0].danger = DangerClass::Red;
    s.sectors[1].state = SectorState::Clear;
    s.sectors[1].danger = DangerClass::Green;
    s.sectors[1].confidence = 0.7F;
    s.sectors[2].state = SectorState::Unknown;
    s.sectors[3].state = SectorState::Obstacle;
    s.sectors[3].kind = ObstacleKind::Negative;
    s.sectors[3].rangeM = 4.0F;
    s.sectors[3].heightM = 0.3F;
    s.sectors[3].confidence = 0.6F;
    s.sectors[3].danger = DangerClass::Blue;
    return s;
}

TEST(DdsConvert, LaserScanHasOneRayPerSectorAtItsCentreBearing)
{
    const ObstacleSectors s = fourSectors();
    ros::LaserScan_ sut;
    constexpr std::int64_t kStampNs = 1'717'000'000'123'456'789;

    toLaserScan(s, kStampNs, "ugv1/base", 0.3F, 40.0F, 0.1F, sut);

    ASSERT_EQ(sut.ranges().size(), 4U);
    EXPECT_NEAR(sut.angle_min(), -22.5F * kDegToRad, kAngleTolerance);
    EXPECT_NEAR(sut.angle_max(), 22.5F * kDegToRad, kAngleTolerance);
    EXPECT_NEAR(sut.angle_increment(), 15.0F * kDegToRad, kAngleTolerance);
    EXPECT_FLOAT_EQ(sut.ranges()[0], 3.5F);                             // obstacle: its range
    EXPECT_EQ(sut.ranges()[1], std::numeric_limits<float>::infinity()); // clear: +inf (REP 117)
    EXPECT_TRUE(std::isnan(sut.ranges()[2]));                           // unknown: NaN, clears nothing
    EXPECT_FLOAT_EQ(sut.ranges()[3], 4.0F);                             // a hole is an obstacle too
    EXPECT_EQ(sut.header().stamp().sec(), 1'717'000'000);
    EXPECT_EQ(sut.header().stamp().nanosec(), 123'456'789U);
    EXPECT_EQ(sut.header().frame_id(), "ugv1/base");
    EXPECT_FLOAT_EQ(sut.range_min(), 0.3F);
    EXPECT_FLOAT_EQ(sut.range_max(), 40.0F);
    EXPECT_FLOAT_EQ(sut.scan_time(), 0.1F);
    EXPECT_EQ(sut.time_increment(), 0.0F);
    EXPECT_TRUE(sut.intensities().empty());
    EXPECT_EQ(check(sut), nullptr);
}

TEST(DdsConvert, TheClearingScanSaysFreeToItsRangeMaxAndNoFarther)
{
    // range_max = the clear range (4 m): the obstacle at 3.5 m and the hole at 4 m; Clear and every obstacle at or
    // beyond range_max are +inf (nothing within range_max), so a consumer clears no farther than 4 m; an obstacle
    // whose range is no number stays unknown, never clear.
    ObstacleSectors s = fourSectors();
    ros::LaserScan_ sut;

    toLaserScan(s, 0, "f", 0.0F, 4.0F, 0.1F, sut);
    EXPECT_FLOAT_EQ(sut.ranges()[0], 3.5F);
    EXPECT_EQ(sut.ranges()[1], std::numeric_limits<float>::infinity());
    EXPECT_TRUE(std::isnan(sut.ranges()[2]));
    EXPECT_EQ(sut.ranges()[3], std::numeric_limits<float>::infinity());
    EXPECT_EQ(check(sut), nullptr);

    s.sectors[0].rangeM = std::numeric_limits<float>::quiet_NaN();
    toLaserScan(s, 0, "f", 0.0F, 4.0F, 0.1F, sut);
    EXPECT_TRUE(std::isnan(sut.ranges()[0]));
}

TEST(DdsConvert, LaserScanOfOneSectorOrNone)
{
    ObstacleSectors one;
    initSectors(one, 1, 10.0F);
    ros::LaserScan_ sut;

    toLaserScan(one, 0, "f", 0.1F, 10.0F, 0.1F, sut);
    EXPECT_EQ(sut.ranges().size(), 1U);
    EXPECT_EQ(sut.angle_min(), sut.angle_max());
    EXPECT_EQ(sut.angle_increment(), 0.0F);

    ObstacleSectors none;
    toLaserScan(none, 0, "f", 0.1F, 10.0F, 0.1F, sut);
    EXPECT_TRUE(sut.ranges().empty());
    EXPECT_EQ(sut.angle_min(), 0.0F);
}

TEST(DdsConvert, NegativeCloudHasOnePointBelowTheGroundPerNegativeSector)
{
    const ObstacleSectors s = fourSectors();
    ros::PointCloud2_ sut;

    toNegativeCloud(s, 2'000'000'001, "ugv1/base", 0.1F, sut);

    ASSERT_EQ(sut.fields().size(), 3U);
    const char* names[] = {"x", "y", "z"};
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(sut.fields()[i].name(), names[i]);
        EXPECT_EQ(sut.fields()[i].offset(), 4 * i);
        EXPECT_EQ(sut.fields()[i].datatype(), 7); // FLOAT32
        EXPECT_EQ(sut.fields()[i].count(), 1U);
    }
    EXPECT_EQ(sut.height(), 1U);
    EXPECT_EQ(sut.width(), 1U); // the positive obstacle, the clear and the unknown sector are not in it
    EXPECT_EQ(sut.point_step(), 12U);
    EXPECT_EQ(sut.row_step(), 12U);
    EXPECT_FALSE(sut.is_bigendian());
    EXPECT_TRUE(sut.is_dense());
    EXPECT_EQ(sut.header().stamp().sec(), 2);
    EXPECT_EQ(sut.header().stamp().nanosec(), 1U);
    ASSERT_EQ(sut.data().size(), 12U);
    float xyz[3];
    std::memcpy(xyz, sut.data().data(), sizeof(xyz));
    EXPECT_NEAR(xyz[0], 4.0F * std::cos(22.5F * kDegToRad), 1e-5F);
    EXPECT_NEAR(xyz[1], 4.0F * std::sin(22.5F * kDegToRad), 1e-5F); // left of the axis: positive y
    EXPECT_FLOAT_EQ(xyz[2], -0.3F);                                 // below the ground
    EXPECT_EQ(check(sut), nullptr);
}

TEST(DdsConvert, ADropOfUnmeasuredDepthIsPublishedBelowTheGroundNeverOnIt)
{
    ObstacleSectors s = fourSectors();
    s.sectors[3].heightM = 0.0F; // the bottom was not seen
    ros::PointCloud2_ sut;

    toNegativeCloud(s, 0, "f", 0.12F, sut);

    ASSERT_EQ(sut.data().size(), 12U);
    float xyz[3];
    std::memcpy(xyz, sut.data().data(), sizeof(xyz));
    EXPECT_FLOAT_EQ(xyz[2], -0.12F); // the least depth that counts as a drop, not -0
}

TEST(DdsConvert, NegativeCloudIsEmptyWithoutNegativeObstacles)
{
    ObstacleSectors s = fourSectors();
    s.sectors[3].kind = ObstacleKind::Positive;
    ros::PointCloud2_ sut;

    toNegativeCloud(s, 0, "f", 0.1F, sut);

    EXPECT_EQ(sut.width(), 0U);
    EXPECT_EQ(sut.row_step(), 0U);
    EXPECT_TRUE(sut.data().empty());
    EXPECT_EQ(check(sut), nullptr);
}

TEST(DdsConvert, SectorsRoundTripThroughTheSample)
{
    const ObstacleSectors in = fourSectors();
    const GroundSummary ground{true, -1.5F, 0.5F, 1.2F};
    msg::ObstacleSectors sample;
    ObstacleSectors sut;

    toDds(in, ground, "ugv-9", 1'700'000'000'000'000'001, 1'700'000'000'004'000'000, sample);
    ASSERT_TRUE(fromDds(sample, sut)) << check(sample);

    EXPECT_EQ(sample.vehicle(), "ugv-9");
    EXPECT_EQ(sample.capture_stamp_ns(), 1'700'000'000'000'000'001);
    EXPECT_EQ(sample.publish_stamp_ns(), 1'700'000'000'004'000'000);
    EXPECT_TRUE(sample.ground().reliable());
    EXPECT_FLOAT_EQ(sample.ground().pitch_deg(), -1.5F);
    EXPECT_FLOAT_EQ(sample.ground().roll_deg(), 0.5F);
    EXPECT_FLOAT_EQ(sample.ground().camera_height_m(), 1.2F);
    EXPECT_EQ(sut.sequence, in.sequence);
    EXPECT_EQ(sut.captureStampNs, 1'700'000'000'000'000'001); // the bus's UNIX-epoch stamp
    EXPECT_EQ(sut.degraded, in.degraded);
    ASSERT_EQ(sut.count, in.count);
    for (int i = 0; i < in.count; ++i) {
        const Sector& a = in.sectors[static_cast<std::size_t>(i)];
        const Sector& b = sut.sectors[static_cast<std::size_t>(i)];
        EXPECT_EQ(a.bearingMinDeg, b.bearingMinDeg) << i;
        EXPECT_EQ(a.bearingMaxDeg, b.bearingMaxDeg) << i;
        EXPECT_EQ(a.rangeM, b.rangeM) << i;
        EXPECT_EQ(a.heightM, b.heightM) << i;
        EXPECT_EQ(a.confidence, b.confidence) << i;
        EXPECT_EQ(a.state, b.state) << i;
        EXPECT_EQ(a.kind, b.kind) << i;
        EXPECT_EQ(a.danger, b.danger) << i;
    }
}

TEST(DdsConvert, FromDdsRefusesAnInvalidSample)
{
    msg::ObstacleSectors sample;
    toDds(fourSectors(), GroundSummary{}, "", 1, 2, sample); // no vehicle name
    ObstacleSectors sut;
    sut.sequence = 7;

    EXPECT_FALSE(fromDds(sample, sut));
    EXPECT_EQ(sut.sequence, 7U); // untouched
}

// ---- check(): one broken rule per case, the rest valid ----

msg::OoiObservation goodObservation()
{
    msg::OoiObservation o;
    o.ugv("ugv-1");
    o.sequence_number(1);
    o.t(1.0);
    o.track("t1");
    o.cls(0);
    o.ugv_lat_deg(-34.9);
    o.ugv_lon_deg(138.6);
    o.ugv_heading_deg(90.0);
    o.range_m(10.0);
    o.bearing_deg(5.0);
    return o;
}

template <class T>
void expectRefused(const T& good, const char* what, const std::function<void(T&)>& breakIt)
{
    ASSERT_EQ(check(good), nullptr) << "the good sample is refused: " << check(good);
    T bad = good;
    breakIt(bad);
    EXPECT_NE(check(bad), nullptr) << what << " was accepted";
}

TEST(DdsCheck, ObservationRefusesEachBrokenField)
{
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    using O = msg::OoiObservation;
    const O good = goodObservation();
    expectRefused<O>(good, "NaN time", [&](O& o) { o.t(kNaN); });
    expectRefused<O>(good, "NaN range", [&](O& o) { o.range_m(kNaN); });
    expectRefused<O>(good, "negative range", [](O& o) { o.range_m(-1.0); });
    expectRefused<O>(good, "NaN latitude", [&](O& o) { o.ugv_lat_deg(kNaN); });
    expectRefused<O>(good, "latitude 91", [](O& o) { o.ugv_lat_deg(91.0); });
    expectRefused<O>(good, "latitude -91", [](O& o) { o.ugv_lat_deg(-91.0); });
    expectRefused<O>(good, "longitude 200", [](O& o) { o.ugv_lon_deg(200.0); });
    expectRefused<O>(good, "NaN bearing", [&](O& o) { o.bearing_deg(kNaN); });
    expectRefused<O>(good, "unknown class 9", [](O& o) { o.cls(9); });
    expectRefused<O>(good, "empty ugv", [](O& o) { o.ugv(""); });
    expectRefused<O>(good, "empty track", [](O& o) { o.track(""); });
    expectRefused<O>(good, "ugv name of 65 characters", [](O& o) { o.ugv(std::string(65, 'u')); });
    expectRefused<O>(good, "track name of 100 characters", [](O& o) { o.track(std::string(100, 't')); });
    O edge = good; // the edges of the ranges are valid
    edge.ugv(std::string(64, 'u'));
    edge.ugv_lat_deg(90.0);
    edge.ugv_lon_deg(-180.0);
    edge.cls(3);
    EXPECT_EQ(check(edge), nullptr);
}

TEST(DdsCheck, ANameLongerThanTheBoundIsTruncatedOnReceiptAndRefused)
{
    // The wire as another participant's IDL could write it: the observation with a 99-character ugv name. The
    // generated code reads it whole and truncates it to the bound (kMaxNameLength + 1); check() refuses it.
    const msg::OoiObservation good = goodObservation(); // "ugv-1": 4 + 6 bytes, padded to 16 before the uint64
    std::vector<char> original(msg::OoiObservation::getCdrSerializedSize(good));
    eprosima::fastcdr::FastBuffer originalBuffer(original.data(), original.size());
    eprosima::fastcdr::Cdr writer(originalBuffer);
    good.serialize(writer);
    ASSERT_EQ(writer.getSerializedDataLength() % 8, 0U);

    std::vector<char> wire(original.size() + 128);
    eprosima::fastcdr::FastBuffer wireBuffer(wire.data(), wire.size());
    eprosima::fastcdr::Cdr longName(wireBuffer);
    longName << std::string(99, 'u'); // 4 + 100 bytes: the next field is 8-aligned again
    ASSERT_EQ(longName.getSerializedDataLength(), 104U);
    std::memcpy(wire.data() + 104, original.data() + 16, writer.getSerializedDataLength() - 16);

    eprosima::fastcdr::FastBuffer readBuffer(wire.data(), 104 + writer.getSerializedDataLength() - 16);
    eprosima::fastcdr::Cdr reader(readBuffer);
    msg::OoiObservation received;
    received.deserialize(reader);
    EXPECT_EQ(received.ugv().size(), kMaxNameLength + 1);
    EXPECT_EQ(received.track(), good.track()); // the rest of the sample is intact
    EXPECT_NE(check(received), nullptr);
}

TEST(DdsCheck, UavConfirmationAndCorrectionRefuseBrokenFields)
{
    msg::UavObservation u;
    u.source("uav");
    u.t(1.0);
    u.cls(1);
    u.lat_deg(-34.9);
    u.lon_deg(138.6);
    using U = msg::UavObservation;
    expectRefused<U>(u, "uav latitude 91", [](U& s) { s.lat_deg(91.0); });
    expectRefused<U>(u, "uav longitude 200", [](U& s) { s.lon_deg(200.0); });
    expectRefused<U>(u, "uav class 9", [](U& s) { s.cls(9); });
    expectRefused<U>(u, "uav empty source", [](U& s) { s.source(""); });
    expectRefused<U>(u, "uav infinite time", [](U& s) { s.t(std::numeric_limits<double>::infinity()); });

    msg::ConfirmationState c;
    c.source("gcs");
    c.t(2.0);
    c.id("ooi-1");
    c.state(1);
    using C = msg::ConfirmationState;
    expectRefused<C>(c, "confirmation state 7", [](C& s) { s.state(7); });
    expectRefused<C>(c, "empty object id", [](C& s) { s.id(""); });
    expectRefused<C>(c, "empty source", [](C& s) { s.source(""); });
    expectRefused<C>(c, "NaN time", [](C& s) { s.t(std::numeric_limits<double>::quiet_NaN()); });

    msg::PoseCorrection p;
    p.source("map");
    p.t(3.0);
    p.ugv("ugv-1");
    p.since_t(1.0);
    p.until_t(2.0);
    using P = msg::PoseCorrection;
    expectRefused<P>(p, "since_t > until_t", [](P& s) {
        s.since_t(5.0);
        s.until_t(4.0);
    });
    expectRefused<P>(p, "empty ugv", [](P& s) { s.ugv(""); });
    expectRefused<P>(p, "NaN correction", [](P& s) { s.d_east_m(std::numeric_limits<double>::quiet_NaN()); });
    P instant = p; // since_t == until_t: one instant, valid
    instant.until_t(instant.since_t());
    EXPECT_EQ(check(instant), nullptr);
}

TEST(DdsCheck, SectorsRefuse181SectorsNoneAndBrokenOnes)
{
    msg::ObstacleSectors good;
    toDds(fourSectors(), GroundSummary{}, "ugv-1", 1, 2, good);
    using S = msg::ObstacleSectors;
    expectRefused<S>(good, "181 sectors", [](S& s) { s.sectors().resize(181, s.sectors()[1]); });
    expectRefused<S>(good, "no sector", [](S& s) { s.sectors().clear(); });
    expectRefused<S>(good, "empty vehicle", [](S& s) { s.vehicle(""); });
    expectRefused<S>(good, "unknown sector state", [](S& s) { s.sectors()[0].state(3); });
    expectRefused<S>(good, "unknown kind", [](S& s) { s.sectors()[0].kind(3); });
    expectRefused<S>(good, "unknown danger", [](S& s) { s.sectors()[0].danger(4); });
    expectRefused<S>(good, "confidence 1.5", [](S& s) { s.sectors()[0].confidence(1.5F); });
    expectRefused<S>(good, "NaN range", [](S& s) { s.sectors()[0].range_m(std::numeric_limits<float>::quiet_NaN()); });
    expectRefused<S>(good, "an obstacle at +inf",
                     [](S& s) { s.sectors()[0].range_m(std::numeric_limits<float>::infinity()); });
    expectRefused<S>(good, "an empty bearing interval",
                     [](S& s) { s.sectors()[0].bearing_min_deg(s.sectors()[0].bearing_max_deg()); });
    expectRefused<S>(good, "a valid-flagged pose at latitude 91", [](S& s) {
        s.pose_valid(true);
        s.pose().vehicle("ugv-1");
        s.pose().stamp_ns(1);
        s.pose().latitude_deg(91.0);
    });
    S full = good; // 180 sectors is the bound, valid
    full.sectors().resize(180, full.sectors()[1]);
    EXPECT_EQ(check(full), nullptr);
}

TEST(DdsCheck, PoseHealthListScanAndCloudRefuseBrokenFields)
{
    msg::VehiclePose pose;
    pose.vehicle("ugv-1");
    pose.stamp_ns(5);
    pose.latitude_deg(-34.9);
    pose.longitude_deg(138.6);
    using V = msg::VehiclePose;
    expectRefused<V>(pose, "pose latitude 91", [](V& p) { p.latitude_deg(91.0); });
    expectRefused<V>(pose, "pose longitude 200", [](V& p) { p.longitude_deg(200.0); });
    expectRefused<V>(pose, "NaN heading", [](V& p) { p.heading_deg(std::numeric_limits<double>::quiet_NaN()); });
    expectRefused<V>(pose, "infinite covariance",
                     [](V& p) { p.covariance()[4] = std::numeric_limits<double>::infinity(); });
    expectRefused<V>(pose, "no stamp", [](V& p) { p.stamp_ns(0); });
    expectRefused<V>(pose, "empty vehicle", [](V& p) { p.vehicle(""); });

    msg::ServiceHealth health;
    health.vehicle("ugv-1");
    using H = msg::ServiceHealth;
    expectRefused<H>(health, "unknown camera state", [](H& h) { h.camera_state(4); });
    expectRefused<H>(health, "NaN p99", [](H& h) { h.latency_p99_ms(std::numeric_limits<double>::quiet_NaN()); });

    msg::CorrelatedOoiList list;
    list.source("gcs");
    msg::CorrelatedOoi object;
    object.id("ooi-1");
    object.lat_deg(-34.9);
    object.lon_deg(138.6);
    list.objects().push_back(object);
    msg::Alert alert;
    alert.non_combatant_id("ooi-2");
    alert.object_id("ooi-1");
    list.alerts().push_back(alert);
    using L = msg::CorrelatedOoiList;
    expectRefused<L>(list, "object latitude 91", [](L& l) { l.objects()[0].lat_deg(91.0); });
    expectRefused<L>(list, "object class 9", [](L& l) { l.objects()[0].cls(9); });
    expectRefused<L>(list, "object without id", [](L& l) { l.objects()[0].id(""); });
    expectRefused<L>(list, "alert without object", [](L& l) { l.alerts()[0].object_id(""); });
    expectRefused<L>(list, "list without source", [](L& l) { l.source(""); });

    ros::LaserScan_ scan;
    using R = ros::LaserScan_;
    expectRefused<R>(scan, "NaN angle", [](R& s) { s.angle_min(std::numeric_limits<float>::quiet_NaN()); });
    expectRefused<R>(scan, "too many rays", [](R& s) { s.ranges().resize(100'001); });
    scan.ranges() = {1.0F, 2.0F};
    expectRefused<R>(scan, "one intensity for two rays", [](R& s) { s.intensities() = {1.0F}; });
    scan.intensities() = {5.0F, 6.0F};
    EXPECT_EQ(check(scan), nullptr);

    ros::PointCloud2_ cloud;
    toNegativeCloud(fourSectors(), 0, "f", 0.1F, cloud);
    using P = ros::PointCloud2_;
    expectRefused<P>(cloud, "width beyond the data", [](P& c) { c.width(2); });
    expectRefused<P>(cloud, "point_step 0", [](P& c) { c.point_step(0); });
    expectRefused<P>(cloud, "row_step not width x point_step", [](P& c) { c.row_step(13); });
    // 2^22 x 2^22 x 2^20 = 2^64 wraps to 0 in 64 bits: an empty data must not pass for such a cloud.
    expectRefused<P>(cloud, "a size product wrapping around 64 bits", [](P& c) {
        c.width(1U << 22);
        c.height(1U << 22);
        c.point_step(1U << 20);
        c.row_step(0);
        c.data().clear();
    });
}

} // namespace
} // namespace ugv::ipc::dds
