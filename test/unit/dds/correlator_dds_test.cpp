// bringup/correlator_dds: correlator messages -> DDS samples -> messages, and the errors of hostile samples.

#include "ugv/adapters/correlator_dds.hpp"

#include <cstring>
#include <limits>
#include <string>
#include <variant>

#include <gtest/gtest.h>

namespace ugv::adapters {
namespace {

using namespace correlator;

TEST(CorrelatorDds, ObservationRoundTrips)
{
    Observation in;
    in.t = 12.5;
    in.ugv = "ugv-2";
    in.track = "trk-7";
    in.cls = OoiClass::NonCombatant;
    in.ugvLat = -34.91;
    in.ugvLon = 138.61;
    in.ugvHeadingDeg = 271.0;
    in.rangeM = 14.25;
    in.bearingDeg = -12.5;
    msg::OoiObservation sample;

    toDds(in, 42, sample);
    const auto sut = fromDds(sample);

    ASSERT_TRUE(sut) << sut.error().message();
    EXPECT_EQ(sample.sequence_number(), 42U);
    const auto* out = std::get_if<Observation>(&*sut);
    ASSERT_NE(out, nullptr);
    EXPECT_EQ(out->t, in.t);
    EXPECT_EQ(out->ugv, in.ugv);
    EXPECT_EQ(out->track, in.track);
    EXPECT_EQ(out->cls, in.cls);
    EXPECT_EQ(out->ugvLat, in.ugvLat);
    EXPECT_EQ(out->ugvLon, in.ugvLon);
    EXPECT_EQ(out->ugvHeadingDeg, in.ugvHeadingDeg);
    EXPECT_EQ(out->rangeM, in.rangeM);
    EXPECT_EQ(out->bearingDeg, in.bearingDeg);
}

TEST(CorrelatorDds, UavFixRoundTrips)
{
    const UavFix in{33.5, OoiClass::Mobile, -34.92, 138.62};
    msg::UavObservation sample;

    toDds(in, "uav-1", 7, sample);
    const auto sut = fromDds(sample);

    ASSERT_TRUE(sut) << sut.error().message();
    EXPECT_EQ(sample.source(), "uav-1");
    EXPECT_EQ(sample.sequence_number(), 7U);
    const auto* out = std::get_if<UavFix>(&*sut);
    ASSERT_NE(out, nullptr);
    EXPECT_EQ(out->t, in.t);
    EXPECT_EQ(out->cls, in.cls);
    EXPECT_EQ(out->lat, in.lat);
    EXPECT_EQ(out->lon, in.lon);
}

TEST(CorrelatorDds, ConfirmRoundTrips)
{
    const Confirm in{44.0, "ooi-3", Confirmation::ConfirmedNegative};
    msg::ConfirmationState sample;

    toDds(in, "gcs", 8, sample);
    const auto sut = fromDds(sample);

    ASSERT_TRUE(sut) << sut.error().message();
    EXPECT_EQ(sample.source(), "gcs");
    EXPECT_EQ(sample.sequence_number(), 8U);
    const auto* out = std::get_if<Confirm>(&*sut);
    ASSERT_NE(out, nullptr);
    EXPECT_EQ(out->t, in.t);
    EXPECT_EQ(out->id, in.id);
    EXPECT_EQ(out->state, in.state);
}

TEST(CorrelatorDds, PoseCorrectionRoundTrips)
{
    const correlator::PoseCorrection in{55.0, "ugv-4", 10.0, 50.0, 1.25, -0.75, 2.5};
    msg::PoseCorrection sample;

    toDds(in, "map", 9, sample);
    const auto sut = fromDds(sample);

    ASSERT_TRUE(sut) << sut.error().message();
    EXPECT_EQ(sample.source(), "map");
    EXPECT_EQ(sample.sequence_number(), 9U);
    const auto* out = std::get_if<correlator::PoseCorrection>(&*sut);
    ASSERT_NE(out, nullptr);
    EXPECT_EQ(out->t, in.t);
    EXPECT_EQ(out->ugv, in.ugv);
    EXPECT_EQ(out->sinceT, in.sinceT);
    EXPECT_EQ(out->untilT, in.untilT);
    EXPECT_EQ(out->dEastM, in.dEastM);
    EXPECT_EQ(out->dNorthM, in.dNorthM);
    EXPECT_EQ(out->dHeadingDeg, in.dHeadingDeg);
}

TEST(CorrelatorDds, SnapshotRoundTripsWithObjectsAndAlerts)
{
    Snapshot in;
    in.t = 99.0;
    ObjectEstimate a;
    a.id = "ooi-1";
    a.cls = OoiClass::Mobile;
    a.lat = -34.93;
    a.lon = 138.63;
    a.sigmaMajorM = 2.5;
    a.sigmaMinorM = 1.5;
    a.majorAxisDeg = 33.0;
    a.state = Confirmation::ConfirmedPositive;
    a.observations = 17;
    a.ugvs = {"ugv-1", "ugv-3"};
    a.zoneDiameterM = kMobileZoneDiameterM;
    ObjectEstimate b = a;
    b.id = "ooi-2";
    b.cls = OoiClass::NonCombatant;
    b.ugvs = {"ugv-2"};
    in.objects = {a, b};
    in.alerts = {Alert{"ooi-2", "ooi-1", 12.5}};
    msg::CorrelatedOoiList sample;

    toDds(in, "gcs", 3, 100, 4, sample);
    const auto sut = fromDds(sample);

    ASSERT_TRUE(sut) << sut.error().message();
    EXPECT_EQ(sample.inputs_accepted(), 100U);
    EXPECT_EQ(sample.inputs_rejected(), 4U);
    EXPECT_EQ(sut->t, in.t);
    ASSERT_EQ(sut->objects.size(), 2U);
    for (std::size_t i = 0; i < 2; ++i) {
        const ObjectEstimate& x = in.objects[i];
        const ObjectEstimate& y = sut->objects[i];
        EXPECT_EQ(y.id, x.id);
        EXPECT_EQ(y.cls, x.cls);
        EXPECT_EQ(y.lat, x.lat);
        EXPECT_EQ(y.lon, x.lon);
        EXPECT_EQ(y.sigmaMajorM, x.sigmaMajorM);
        EXPECT_EQ(y.sigmaMinorM, x.sigmaMinorM);
        EXPECT_EQ(y.majorAxisDeg, x.majorAxisDeg);
        EXPECT_EQ(y.state, x.state);
        EXPECT_EQ(y.observations, x.observations);
        EXPECT_EQ(y.ugvs, x.ugvs);
        EXPECT_EQ(y.zoneDiameterM, x.zoneDiameterM);
    }
    ASSERT_EQ(sut->alerts.size(), 1U);
    EXPECT_EQ(sut->alerts[0].nonCombatantId, "ooi-2");
    EXPECT_EQ(sut->alerts[0].objectId, "ooi-1");
    EXPECT_EQ(sut->alerts[0].distanceM, 12.5);
}

TEST(CorrelatorDds, ASampleDeclaringBillionsOfStringsIsRefusedWithoutAllocatingThem)
{
    // A correlated list whose object names one UGV, serialized as the bus sends it; then its UGV count (uint32 1,
    // followed by the string "ugv-1": length 6 with its NUL) is made 2^31 - 1. fastddsgen 2.x's deserialize()
    // resized to that count (68 GB: an out-of-memory crash of any reader, found by test/fuzz's dds_sample target);
    // ipc/idl/harden_generated.cmake bounds it, and the sample is refused as a short one is.
    Snapshot in;
    in.t = 1.0;
    ObjectEstimate a;
    a.id = "ooi-1";
    a.lat = -34.93;
    a.lon = 138.63;
    a.ugvs = {"ugv-1"};
    in.objects = {a};
    msg::CorrelatedOoiList sample;
    toDds(in, "gcs", 1, 1, 0, sample);
    msg::CorrelatedOoiListPubSubType type;
    eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&sample)());
    ASSERT_TRUE(type.serialize(&sample, &payload));
    const std::string bytes(reinterpret_cast<const char*>(payload.data), payload.length);
    const std::string countThenName("\x01\x00\x00\x00\x06\x00\x00\x00ugv-1", 13);
    const std::size_t at = bytes.find(countThenName);
    ASSERT_NE(at, std::string::npos) << "the serialized UGV list was not found";
    const unsigned char huge[4] = {0xFF, 0xFF, 0xFF, 0x7F}; // little-endian 2^31 - 1
    std::memcpy(payload.data + at, huge, sizeof(huge));

    msg::CorrelatedOoiList out;
    EXPECT_FALSE(type.deserialize(&payload, &out));

    // The unmodified sample still reads.
    std::memcpy(payload.data + at, countThenName.data(), 4);
    ASSERT_TRUE(type.deserialize(&payload, &out));
    ASSERT_EQ(out.objects().size(), 1U);
    EXPECT_EQ(out.objects()[0].ugvs().size(), 1U);
}

TEST(CorrelatorDds, ASampleWithABadEncapsulationIsRefusedNotThrown)
{
    // The dds_sample fuzz target's second find: an unknown CDR encapsulation (the payload's first two bytes) made
    // fastcdr throw BadParamException, which the generated deserialize() let out of the reader (std::terminate).
    PoseCorrection in;
    in.t = 3.0;
    in.ugv = "ugv-1";
    msg::PoseCorrection sample;
    toDds(in, "gcs", 1, sample);
    msg::PoseCorrectionPubSubType type;
    eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&sample)());
    ASSERT_TRUE(type.serialize(&sample, &payload));
    payload.data[1] = 0x7F; // representation identifier 0x007F: no CDR kind

    msg::PoseCorrection out;
    bool accepted = true;
    EXPECT_NO_THROW(accepted = type.deserialize(&payload, &out));
    EXPECT_FALSE(accepted);
}

TEST(CorrelatorDds, HostileSamplesGiveAnErrorNamingTopicAndSender)
{
    msg::OoiObservation o;
    toDds(Observation{1.0, "ugv-evil", "t", OoiClass::Static, 91.0, 138.6, 0.0, 5.0, 0.0}, 1, o);
    const auto observation = fromDds(o);
    ASSERT_FALSE(observation);
    EXPECT_NE(observation.error().where.find("ugvsense/ooi/observations"), std::string::npos);
    EXPECT_NE(observation.error().where.find("ugv-evil"), std::string::npos);
    EXPECT_NE(observation.error().what.find("latitude"), std::string::npos);

    msg::UavObservation u;
    toDds(UavFix{1.0, OoiClass::Mobile, -34.9, 200.0}, "uav-evil", 1, u);
    const auto uav = fromDds(u);
    ASSERT_FALSE(uav);
    EXPECT_NE(uav.error().where.find("ugvsense/ooi/uav"), std::string::npos);
    EXPECT_NE(uav.error().where.find("uav-evil"), std::string::npos);

    msg::ConfirmationState c;
    toDds(Confirm{1.0, "ooi-1", Confirmation::Unknown}, "console-evil", 1, c);
    c.state(7);
    const auto confirm = fromDds(c);
    ASSERT_FALSE(confirm);
    EXPECT_NE(confirm.error().where.find("ugvsense/ooi/confirmations"), std::string::npos);
    EXPECT_NE(confirm.error().where.find("console-evil"), std::string::npos);
    EXPECT_NE(confirm.error().what.find("state"), std::string::npos);

    msg::PoseCorrection p;
    toDds(correlator::PoseCorrection{1.0, "ugv-1", 5.0, 4.0, 0, 0, 0}, "map-evil", 1, p);
    const auto correction = fromDds(p);
    ASSERT_FALSE(correction);
    EXPECT_NE(correction.error().where.find("ugvsense/ooi/pose_corrections"), std::string::npos);
    EXPECT_NE(correction.error().where.find("map-evil"), std::string::npos);
    EXPECT_NE(correction.error().what.find("since_t"), std::string::npos);

    msg::CorrelatedOoiList l;
    toDds(Snapshot{std::numeric_limits<double>::quiet_NaN(), {}, {}}, "gcs-evil", 1, 0, 0, l);
    const auto list = fromDds(l);
    ASSERT_FALSE(list);
    EXPECT_NE(list.error().where.find("ugvsense/ooi/correlated"), std::string::npos);
    EXPECT_NE(list.error().where.find("gcs-evil"), std::string::npos);
    EXPECT_FALSE(list.error().fix.empty());
}

TEST(CorrelatorDds, AbsurdFiniteNumbersAreRefusedAsFromAJsonLine)
{
    msg::OoiObservation o;
    toDds(Observation{1.0, "ugv-far", "t", OoiClass::Static, -34.9, 138.6, 0.0, 1e19, 0.0}, 1, o);
    const auto observation = fromDds(o);
    ASSERT_FALSE(observation);
    EXPECT_NE(observation.error().where.find("ugv-far"), std::string::npos);
    EXPECT_NE(observation.error().what.find("field 'range_m' value 1e+19"), std::string::npos)
        << observation.error().message();

    msg::ConfirmationState c;
    toDds(Confirm{1e17, "ooi-1", Confirmation::Unknown}, "console-late", 1, c);
    const auto confirm = fromDds(c);
    ASSERT_FALSE(confirm);
    EXPECT_NE(confirm.error().what.find("field 't' value 1e+17"), std::string::npos) << confirm.error().message();
}

} // namespace
} // namespace ugv::adapters
