#include "ugv/vision/ground_plane.hpp"

#include <cmath>

#include <gtest/gtest.h>

#include "test_rig.hpp"

namespace ugv::vision {
namespace {

using ugv::test::kRigProjection;
constexpr double kHeight = 0.59;

TEST(GroundPlane, LevelCameraGivesTheTextbookModel)
{
    const auto sut = GroundPlane::fromMount(Mount{kHeight, 0.0, 0.0}).disparityPlane(kRigProjection);

    EXPECT_NEAR(sut.a, 0.0, 1e-12);
    EXPECT_NEAR(sut.at(100.0, 400.0), kRigProjection.baselineM / kHeight * (400.0 - kRigProjection.cy), 1e-9);
    EXPECT_NEAR(sut.at(500.0, kRigProjection.cy), 0.0, 1e-9); // horizon through the principal point
}

TEST(GroundPlane, GroundPixelsMapToZeroHeightInTheVehicleFrame)
{
    for (const Mount mount :
         {Mount{kHeight, 0, 0}, Mount{0.8, 5.0, 0.0}, Mount{0.5, -2.0, 3.0}, Mount{1.2, 10.0, -4.0}}) {
        const auto ground = GroundPlane::fromMount(mount);
        const auto plane = ground.disparityPlane(kRigProjection);
        for (const double x : {20.0, 320.0, 600.0}) {
            for (const double y : {300.0, 400.0, 470.0}) {
                const double d = plane.at(x, y);
                ASSERT_GT(d, 0.0);
                const auto point = ground.pixelToVehicle(x, y, d, kRigProjection);
                EXPECT_NEAR(point.z, 0.0, 1e-9) << x << "," << y;
                EXPECT_GT(point.x, 0.0);
            }
        }
    }
}

TEST(GroundPlane, LevelCameraAxes)
{
    const auto sut = GroundPlane::fromMount(Mount{kHeight, 0.0, 0.0});

    const auto ahead = sut.toVehicle(0.0, 0.0, 4.0);
    const auto left = sut.toVehicle(-1.0, 0.0, 4.0); // camera X is right
    const auto up = sut.toVehicle(0.0, -0.2, 4.0);   // camera Y is down

    EXPECT_NEAR(ahead.x, 4.0, 1e-12);
    EXPECT_NEAR(ahead.z, kHeight, 1e-12);
    EXPECT_NEAR(left.y, 1.0, 1e-12);
    EXPECT_NEAR(up.z, kHeight + 0.2, 1e-12);
}

TEST(GroundPlane, PitchAndRollRoundTrip)
{
    const auto sut = GroundPlane::fromMount(Mount{0.7, 6.0, -2.5});

    EXPECT_NEAR(sut.pitchDeg(), 6.0, 1e-9);
    EXPECT_NEAR(sut.rollDeg(), -2.5, 1e-9);
    EXPECT_NEAR(sut.heightM, 0.7, 1e-12);
}

TEST(GroundPlane, DisparityPlaneRoundTrip)
{
    const auto original = GroundPlane::fromMount(Mount{0.65, 4.0, 1.5});

    const auto sut = GroundPlane::fromDisparityPlane(original.disparityPlane(kRigProjection), kRigProjection);

    EXPECT_NEAR(sut.nx, original.nx, 1e-12);
    EXPECT_NEAR(sut.ny, original.ny, 1e-12);
    EXPECT_NEAR(sut.nz, original.nz, 1e-12);
    EXPECT_NEAR(sut.heightM, original.heightM, 1e-12);
}

} // namespace
} // namespace ugv::vision
