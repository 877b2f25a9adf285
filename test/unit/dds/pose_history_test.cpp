// service::PoseHistory: the vehicle pose at a frame's capture time.

#include "ugv/service/pose_history.hpp"

#include <cstdint>

#include <gtest/gtest.h>

namespace ugv::service {
namespace {

namespace msg = ipc::dds::msg;

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kT0 = 1'700'000'000'000'000'000; ///< [ns] UNIX epoch
constexpr std::int64_t kMaxAge = 200 * kMs;
constexpr double kTol = 1e-9;

msg::VehiclePose poseAt(std::int64_t stamp, double east, double north, double heading, double cov = 0.01)
{
    msg::VehiclePose p;
    p.vehicle("ugv-1");
    p.stamp_ns(stamp);
    p.latitude_deg(-34.9 + north * 1e-5);
    p.longitude_deg(138.6 + east * 1e-5);
    p.altitude_m(50.0 + north);
    p.east_m(east);
    p.north_m(north);
    p.up_m(north / 10.0);
    p.heading_deg(heading);
    p.covariance({cov, 0, 0, 0, cov, 0, 0, 0, cov});
    return p;
}

TEST(PoseHistory, InterpolatesPositionBetweenTwoPoses)
{
    PoseHistory sut;
    sut.add(poseAt(kT0, 0.0, 0.0, 10.0));
    sut.add(poseAt(kT0 + 500 * kMs, 10.0, -4.0, 20.0));
    msg::VehiclePose out;
    bool stale = true;

    ASSERT_TRUE(sut.at(kT0 + 100 * kMs, kMaxAge, out, stale)); // 20 % of the way

    EXPECT_FALSE(stale);
    EXPECT_EQ(out.stamp_ns(), kT0 + 100 * kMs);
    EXPECT_NEAR(out.east_m(), 2.0, kTol);
    EXPECT_NEAR(out.north_m(), -0.8, kTol);
    EXPECT_NEAR(out.up_m(), -0.08, kTol);
    EXPECT_NEAR(out.altitude_m(), 49.2, kTol);
    EXPECT_NEAR(out.latitude_deg(), -34.9 - 0.8e-5, 1e-12);
    EXPECT_NEAR(out.longitude_deg(), 138.6 + 2.0e-5, 1e-12);
    EXPECT_NEAR(out.heading_deg(), 12.0, kTol);
    EXPECT_EQ(out.vehicle(), "ugv-1");
}

TEST(PoseHistory, HeadingTurnsTheShortWayAcrossNorth)
{
    PoseHistory sut;
    sut.add(poseAt(kT0, 0.0, 0.0, 359.0));
    sut.add(poseAt(kT0 + 400 * kMs, 0.0, 0.0, 1.0));
    msg::VehiclePose out;
    bool stale = true;

    ASSERT_TRUE(sut.at(kT0 + 100 * kMs, kMaxAge, out, stale));
    EXPECT_NEAR(out.heading_deg(), 359.5, kTol); // not 269.5 (the long way round)
    ASSERT_TRUE(sut.at(kT0 + 300 * kMs, kMaxAge, out, stale));
    EXPECT_NEAR(out.heading_deg(), 0.5, kTol);
    ASSERT_TRUE(sut.at(kT0 + 200 * kMs, kMaxAge, out, stale));
    EXPECT_TRUE(out.heading_deg() < kTol || out.heading_deg() > 360.0 - kTol) << out.heading_deg();

    PoseHistory back; // and the other way: 1 -> 359 through 0
    back.add(poseAt(kT0, 0.0, 0.0, 1.0));
    back.add(poseAt(kT0 + 400 * kMs, 0.0, 0.0, 359.0));
    ASSERT_TRUE(back.at(kT0 + 100 * kMs, kMaxAge, out, stale));
    EXPECT_NEAR(out.heading_deg(), 0.5, kTol);
    ASSERT_TRUE(back.at(kT0 + 300 * kMs, kMaxAge, out, stale));
    EXPECT_NEAR(out.heading_deg(), 359.5, kTol);
}

TEST(PoseHistory, APoseArrivingLateIsInsertedInPlace)
{
    PoseHistory sut;
    sut.add(poseAt(kT0, 0.0, 0.0, 0.0));
    sut.add(poseAt(kT0 + 1000 * kMs, 10.0, 0.0, 0.0));
    sut.add(poseAt(kT0 + 500 * kMs, 0.0, 50.0, 0.0)); // late: between the two
    msg::VehiclePose out;
    bool stale = true;

    ASSERT_TRUE(sut.at(kT0 + 150 * kMs, kMaxAge, out, stale));

    EXPECT_EQ(sut.size(), 3U);
    EXPECT_NEAR(out.east_m(), 0.0, kTol); // between the first and the late one, not the first and the last
    EXPECT_NEAR(out.north_m(), 15.0, kTol);
    EXPECT_FALSE(stale);
}

TEST(PoseHistory, TheSameStampAgainReplacesThePose)
{
    PoseHistory sut;
    sut.add(poseAt(kT0, 0.0, 0.0, 0.0));
    sut.add(poseAt(kT0, 3.0, 0.0, 0.0));
    msg::VehiclePose out;
    bool stale = true;

    ASSERT_TRUE(sut.at(kT0, kMaxAge, out, stale));
    EXPECT_EQ(sut.size(), 1U);
    EXPECT_NEAR(out.east_m(), 3.0, kTol);
}

TEST(PoseHistory, NearestPoseAtTheEndsAndStaleBeyondMaxAge)
{
    PoseHistory sut;
    sut.add(poseAt(kT0, 1.0, 2.0, 30.0));
    sut.add(poseAt(kT0 + 500 * kMs, 5.0, 6.0, 40.0));
    msg::VehiclePose out;
    bool stale = true;

    ASSERT_TRUE(sut.at(kT0 - 100 * kMs, kMaxAge, out, stale)); // before the first, within max age
    EXPECT_NEAR(out.east_m(), 1.0, kTol);
    EXPECT_EQ(out.stamp_ns(), kT0); // the pose itself, with its own stamp
    EXPECT_FALSE(stale);

    ASSERT_TRUE(sut.at(kT0 + 500 * kMs + 150 * kMs, kMaxAge, out, stale)); // after the last, within max age
    EXPECT_NEAR(out.east_m(), 5.0, kTol);
    EXPECT_NEAR(out.heading_deg(), 40.0, kTol);
    EXPECT_FALSE(stale);

    ASSERT_TRUE(sut.at(kT0 + 500 * kMs + 201 * kMs, kMaxAge, out, stale)); // localisation stopped
    EXPECT_NEAR(out.east_m(), 5.0, kTol);
    EXPECT_TRUE(stale);

    ASSERT_TRUE(sut.at(kT0 - 300 * kMs, kMaxAge, out, stale)); // long before the first
    EXPECT_TRUE(stale);
}

TEST(PoseHistory, StaleBetweenPosesTooFarApart)
{
    PoseHistory sut;
    sut.add(poseAt(kT0, 0.0, 0.0, 0.0));
    sut.add(poseAt(kT0 + 2000 * kMs, 20.0, 0.0, 0.0)); // a 2 s gap
    msg::VehiclePose out;
    bool stale = false;

    ASSERT_TRUE(sut.at(kT0 + 1000 * kMs, kMaxAge, out, stale));
    EXPECT_TRUE(stale);
    EXPECT_NEAR(out.east_m(), 10.0, kTol); // still the best guess
    ASSERT_TRUE(sut.at(kT0 + 150 * kMs, kMaxAge, out, stale));
    EXPECT_FALSE(stale); // close to the first
}

TEST(PoseHistory, EmptyHasNoPose)
{
    const PoseHistory sut;
    msg::VehiclePose out;
    bool stale = false;

    EXPECT_FALSE(sut.at(kT0, kMaxAge, out, stale));
    EXPECT_EQ(sut.size(), 0U);
}

TEST(PoseHistory, KeepsTheNewestCapacityPoses)
{
    PoseHistory sut;
    constexpr std::size_t kExtra = 10;
    for (std::size_t i = 0; i < PoseHistory::kCapacity + kExtra; ++i) {
        sut.add(poseAt(kT0 + static_cast<std::int64_t>(i) * 100 * kMs, static_cast<double>(i), 0.0, 0.0));
    }
    msg::VehiclePose out;
    bool stale = false;

    EXPECT_EQ(sut.size(), PoseHistory::kCapacity);
    ASSERT_TRUE(sut.at(kT0, kMaxAge, out, stale)); // the first ones are gone: the oldest kept is number kExtra
    EXPECT_NEAR(out.east_m(), static_cast<double>(kExtra), kTol);
    EXPECT_TRUE(stale);
    ASSERT_TRUE(
        sut.at(kT0 + static_cast<std::int64_t>(PoseHistory::kCapacity + kExtra - 1) * 100 * kMs, kMaxAge, out, stale));
    EXPECT_NEAR(out.east_m(), static_cast<double>(PoseHistory::kCapacity + kExtra - 1), kTol);
    EXPECT_FALSE(stale);
}

} // namespace
} // namespace ugv::service
