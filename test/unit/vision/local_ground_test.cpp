// LocalGround: the per-sector ground profile follows a smooth surface (a camber's slope, a grade) and not a step
// (a kerb and its pavement), a face (a box's pixels spread over their heights) or a trench's far wall one bin deep.

#include "ugv/vision/local_ground.hpp"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace {

using ugv::vision::LocalGround;
using ugv::vision::LocalGroundConfig;

constexpr float kMaxRangeM = 20.0F;
constexpr int kSectors = 3;
constexpr float kTolM = 0.012F; ///< a mode is found to about a 1 cm height bin

/// Ground pixels of sector s between r0 and r1 at height z(r), `perMetre` of them per metre (rows thin out).
template <typename Height>
void addGround(LocalGround& sut, int s, float r0, float r1, int perMetre, Height z)
{
    const int n = static_cast<int>((r1 - r0) * static_cast<float>(perMetre));
    for (int i = 0; i < n; ++i) {
        const float r = r0 + (r1 - r0) * (static_cast<float>(i) + 0.5F) / static_cast<float>(n);
        sut.add(s, r, z(r));
    }
}

LocalGround makeSut(const LocalGroundConfig& config = {})
{
    LocalGround sut;
    sut.configure(config, kSectors, kMaxRangeM);
    sut.clear();
    return sut;
}

TEST(LocalGround, FollowsASlopeLikeACamberedRoadWithinASector)
{
    auto sut = makeSut();
    const auto camber = [](float r) { return -0.015F * r; }; // 1.5 % falling off with the range
    addGround(sut, 1, 2.0F, 15.0F, 60, camber);

    sut.fit();

    for (const float r : {3.0F, 6.0F, 10.0F, 13.0F}) {
        EXPECT_NEAR(sut.at(1, r), camber(r), 2.0F * kTolM) << r;
    }
    EXPECT_FLOAT_EQ(sut.at(0, 5.0F), 0.0F); // no pixels: the plane
}

TEST(LocalGround, DoesNotFollowAKerbUpToAPavement)
{
    auto sut = makeSut();
    addGround(sut, 1, 2.0F, 8.0F, 60, [](float) { return 0.0F; });
    addGround(sut, 1, 8.0F, 16.0F, 60, [](float) { return 0.12F; }); // the pavement, 12 cm up

    sut.fit();

    EXPECT_NEAR(sut.at(1, 5.0F), 0.0F, kTolM);
    EXPECT_NEAR(sut.at(1, 12.0F), 0.0F, kTolM); // the road's level holds: the pavement stays 12 cm above it
}

TEST(LocalGround, IgnoresAFaceAndATrenchWallOneBinDeep)
{
    auto sut = makeSut();
    addGround(sut, 1, 2.0F, 16.0F, 40, [](float) { return 0.0F; });
    // A box's face at 6 m: 200 pixels spread over 0..0.25 m (within the band).
    for (int i = 0; i < 200; ++i) {
        sut.add(1, 6.05F, 0.25F * static_cast<float>(i) / 200.0F);
    }
    // A far wall at 11 m: 60 pixels between 0 and 6 cm below the ground, in one bin.
    for (int i = 0; i < 60; ++i) {
        sut.add(1, 11.1F, -0.06F * static_cast<float>(i) / 60.0F);
    }

    sut.fit();

    for (const float r : {4.0F, 6.5F, 9.0F, 11.5F, 14.0F}) {
        EXPECT_NEAR(sut.at(1, r), 0.0F, kTolM) << r;
    }
}

TEST(LocalGround, StartsOnTheNearestConfirmedLevelNotOnANearCurbTop)
{
    auto sut = makeSut();
    addGround(sut, 0, 1.2F, 1.9F, 60, [](float) { return 0.12F; }); // a curb's top, one bin deep
    addGround(sut, 0, 2.0F, 15.0F, 60, [](float) { return 0.0F; });
    addGround(sut, 1, 1.5F, 15.0F, 60, [](float) { return -0.08F; }); // the road 8 cm below the plane throughout

    sut.fit();

    EXPECT_NEAR(sut.at(0, 1.5F), 0.0F, kTolM);
    EXPECT_NEAR(sut.at(0, 8.0F), 0.0F, kTolM);
    EXPECT_NEAR(sut.at(1, 2.0F), -0.08F, kTolM);
    EXPECT_NEAR(sut.at(1, 12.0F), -0.08F, kTolM);
}

TEST(LocalGround, StaysWithinItsOffsetBoundWhichWidensWithTheRangeFromThePlane)
{
    LocalGroundConfig config;
    config.maxOffsetM = 0.05F;
    auto sut = makeSut(config);
    // 6.5 % up from 4 m: each bin within the step tolerance of the extrapolation, so followed, but steeper than
    // maxSlope (4 %): the bound maxOffsetM + maxSlope r holds it (0.68 m up at 14.5 m, the bound 0.63 m).
    addGround(sut, 2, 2.0F, 16.0F, 60, [](float r) { return 0.065F * std::max(0.0F, r - 4.0F); });

    sut.fit();

    EXPECT_NEAR(sut.at(2, 3.5F), 0.0F, kTolM);
    EXPECT_NEAR(sut.at(2, 14.5F), config.maxOffsetM + config.maxSlope * 14.5F, kTolM);
}

TEST(LocalGround, FollowsAGradeBeyondTheNearBand)
{
    auto sut = makeSut();
    const auto grade = [](float r) { return 0.04F * std::max(0.0F, r - 8.0F); }; // 0.46 m up at 19.5 m
    addGround(sut, 1, 2.0F, 20.0F, 60, grade);

    sut.fit();

    for (const float r : {6.0F, 10.5F, 14.5F, 18.5F}) {
        EXPECT_NEAR(sut.at(1, r), grade(r), 3.0F * kTolM) << r;
    }
}

TEST(LocalGround, FollowsSparseFarGroundAcrossBinsWithoutAMode)
{
    auto sut = makeSut();
    const auto grade = [](float r) { return 0.03F * std::max(0.0F, r - 6.0F); };
    addGround(sut, 1, 2.0F, 10.0F, 60, grade);
    for (float r0 = 10.0F; r0 < 20.0F; r0 += 2.0F) { // every other bin seen: the far ground's rows thin out
        addGround(sut, 1, r0, r0 + 1.0F, 20, grade);
    }

    sut.fit();

    EXPECT_NEAR(sut.at(1, 18.5F), grade(18.5F), 3.0F * kTolM);
}

TEST(LocalGround, ABoundStartedOnAPavementDoesNotWidenWithTheRange)
{
    auto sut = makeSut();
    // The road out of view in this sector: the first ground is a pavement 10 cm up, rising 2 % away.
    const auto pavement = [](float r) { return 0.10F + 0.02F * (r - 5.0F); };
    addGround(sut, 0, 5.0F, 18.0F, 60, pavement);

    sut.fit();

    EXPECT_NEAR(sut.at(0, 7.5F), pavement(7.5F), 2.0F * kTolM);
    EXPECT_FLOAT_EQ(sut.at(0, 16.5F), LocalGroundConfig{}.maxOffsetM);
}

TEST(LocalGround, FitAllocatesNothing)
{
    auto sut = makeSut();
    addGround(sut, 1, 2.0F, 15.0F, 60, [](float r) { return 0.01F * r; });
    const ugv::test::ThreadAllocationScope scope;
    for (int k = 0; k < 100; ++k) {
        sut.clear();
        addGround(sut, 1, 2.0F, 15.0F, 60, [](float r) { return 0.01F * r; });
        sut.fit();
    }
    EXPECT_EQ(scope.count(), 0U);
}

} // namespace
