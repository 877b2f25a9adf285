// Mode `improved` rule by rule: joint estimation of a UGV's heading bias, pose corrections re-projecting stored
// observations, statistical association keeping close objects apart, Kalman prediction of mobile objects through
// gaps, clutter that never becomes an object, ids kept on merges, confirmation, UAV fixes.

#include "ugv/correlator/improved_correlator.hpp"
#include "ugv/correlator/original_correlator.hpp"

#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "scene.hpp"

namespace ugv::correlator {
namespace {

using test::Scene;

std::vector<ObjectEstimate> ofClass(const Snapshot& s, OoiClass cls)
{
    std::vector<ObjectEstimate> out;
    for (const ObjectEstimate& o : s.objects) {
        if (o.cls == cls) {
            out.push_back(o);
        }
    }
    return out;
}

TEST(ImprovedCorrelator, EstimatesAUgvsHeadingBiasFromSharedObjectsAndKeepsOneObjectEach)
{
    const Scene scene;
    ImprovedCorrelator sut;
    std::mt19937_64 rng(1);
    std::normal_distribution<double> bearingNoise(0.0, 0.3);
    std::vector<Eigen::Vector2d> posts;
    for (int i = 0; i < 8; ++i) {
        posts.emplace_back(-30.0 + 9.0 * i, 15.0 + 4.0 * (i % 3));
    }
    // ugv-1 reports its heading correctly, ugv-2 6 degrees off; both see every post from their own side.
    for (int step = 0; step < 600; ++step) {
        const double t = step * 0.5;
        for (std::size_t i = 0; i < posts.size(); ++i) {
            Observation a = scene.see(t, "ugv-1", "a" + std::to_string(i), OoiClass::Static, {-10, 0}, posts[i]);
            Observation b = scene.see(t, "ugv-2", "b" + std::to_string(i), OoiClass::Static, {10, 0}, posts[i], 6.0);
            a.bearingDeg += bearingNoise(rng);
            b.bearingDeg += bearingNoise(rng);
            ASSERT_TRUE(sut.add(a).has_value());
            ASSERT_TRUE(sut.add(b).has_value());
        }
    }
    const auto one = sut.poseError("ugv-1", 300).value();
    const auto two = sut.poseError("ugv-2", 300).value();
    // Only the difference is observable (the fleet's mean error is not): it must be the -6 deg correction.
    EXPECT_NEAR(two.headingBiasDeg - one.headingBiasDeg, -6.0, 0.5);
    const Snapshot s = sut.snapshot(300);
    EXPECT_EQ(ofClass(s, OoiClass::Static).size(), posts.size());
}

TEST(ImprovedCorrelator, PoseCorrectionReprojectsStoredObservationsExactly)
{
    const Scene scene;
    ImprovedCorrelator sut;
    const Eigen::Vector2d post(5, 20);
    // The UGV's reported position is 3 m east of the truth.
    for (int i = 0; i < 5; ++i) {
        ASSERT_TRUE(sut.add(scene.see(i, "ugv-1", "a", OoiClass::Static, {0, 0}, post, 0.0, {3, 0})).has_value());
    }
    const Snapshot before = sut.snapshot(5);
    ASSERT_EQ(before.objects.size(), 1U);
    EXPECT_NEAR(scene.local(before.objects[0]).x(), post.x() + 3.0, 1e-3);

    ASSERT_TRUE(sut.add(PoseCorrection{5, "ugv-1", 0, 5, -3.0, 0.0, 0.0}).has_value());

    const Snapshot s = sut.snapshot(6);
    ASSERT_EQ(s.objects.size(), 1U);
    EXPECT_LT((scene.local(s.objects[0]) - post).norm(), 1e-3);
}

TEST(ImprovedCorrelator, ObjectsTwoMetresApartStayApartWhereTheOriginalMergesThem)
{
    const Scene scene;
    ImprovedCorrelator improved;
    OriginalCorrelator original;
    std::mt19937_64 rng(2);
    std::normal_distribution<double> noise(0.0, 0.05);
    for (int i = 0; i < 20; ++i) {
        for (const auto& [track, at] :
             {std::pair{"a", Eigen::Vector2d(0, 12)}, std::pair{"b", Eigen::Vector2d(2.2, 12)}}) {
            Observation o = scene.see(i * 0.5, "ugv-1", track, OoiClass::Static, {1, 0}, at);
            o.rangeM += noise(rng);
            ASSERT_TRUE(improved.add(o).has_value());
            ASSERT_TRUE(original.add(o).has_value());
        }
    }
    EXPECT_EQ(improved.snapshot(10).objects.size(), 2U);
    EXPECT_EQ(original.snapshot(10).objects.size(), 1U); // its fixed 2.5 m gate
}

TEST(ImprovedCorrelator, MobileObjectIsPredictedThroughAGap)
{
    const Scene scene;
    ImprovedCorrelator sut;
    // Walks east at 1 m/s; seen for 10 s, then not for 2 s.
    for (int i = 0; i <= 20; ++i) {
        const double t = i * 0.5;
        ASSERT_TRUE(sut.add(scene.see(t, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {-5.0 + t, 15})).has_value());
    }
    const Snapshot s = sut.snapshot(12);

    const auto mobiles = ofClass(s, OoiClass::Mobile);
    ASSERT_EQ(mobiles.size(), 1U);
    EXPECT_LT((scene.local(mobiles[0]) - Eigen::Vector2d(-5.0 + 12.0, 15)).norm(), 0.3);
    EXPECT_GT(mobiles[0].sigmaMajorM, 0.0);
    // Four more seconds unseen: too uncertain to show (kept for when it is seen again).
    EXPECT_TRUE(ofClass(sut.snapshot(16), OoiClass::Mobile).empty());
    EXPECT_DOUBLE_EQ(mobiles[0].zoneDiameterM, kMobileZoneDiameterM);
}

TEST(ImprovedCorrelator, AMobileWalkingALineIsPredictedAlongItThroughALongGap)
{
    const Scene scene;
    ImprovedCorrelator sut;
    // Back and forth along 20 m of the east axis at 1 m/s (a 40 s round trip), seen for 120 s.
    const auto truth = [](double t) {
        const double phase = std::fmod(t, 40.0);
        return Eigen::Vector2d(-10.0 + (phase < 20.0 ? phase : 40.0 - phase), 15.0);
    };
    for (int i = 0; i <= 240; ++i) {
        const double t = i * 0.5;
        ASSERT_TRUE(sut.add(scene.see(t, "ugv-1", "m", OoiClass::Mobile, {0, 0}, truth(t))).has_value());
    }
    // 25 s unseen: far too long for the Kalman prediction, it turned at the end of the line meanwhile.
    const Snapshot s = sut.snapshot(145);

    const auto mobiles = ofClass(s, OoiClass::Mobile);
    ASSERT_EQ(mobiles.size(), 1U);
    EXPECT_LT((scene.local(mobiles[0]) - truth(145)).norm(), 2.0);
}

TEST(ImprovedCorrelator, ASingleMobileSightingIsNotPublishedAndTimesOut)
{
    const Scene scene;
    ImprovedCorrelator sut;
    ASSERT_TRUE(sut.add(scene.see(0, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {5, 15})).has_value());
    EXPECT_TRUE(sut.snapshot(1).objects.empty());
}

TEST(ImprovedCorrelator, ClutterNeverBecomesAnObject)
{
    const Scene scene;
    ImprovedCorrelator sut;
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> anywhere(-40, 40);
    // One false observation every 5 s in an 80 m square for an hour: each alone dies before it gathers 3.
    for (int i = 0; i < 720; ++i) {
        const Eigen::Vector2d at(anywhere(rng), 50 + anywhere(rng));
        ASSERT_TRUE(
            sut.add(scene.see(i * 5.0, "ugv-1", "c" + std::to_string(i), OoiClass::Static, {0, 0}, at)).has_value());
        if (i % 12 == 0) {
            EXPECT_TRUE(sut.snapshot(i * 5.0).objects.empty()) << "t " << i * 5.0;
        }
    }
    EXPECT_LT(sut.storedPoints(), 200U);
}

TEST(ImprovedCorrelator, ConfirmationsAndUavFixes)
{
    const Scene scene;
    ImprovedCorrelator sut;
    for (int i = 0; i < 4; ++i) {
        ASSERT_TRUE(sut.add(scene.see(i, "ugv-1", "s", OoiClass::Static, {0, 0}, {5, 15})).has_value());
        ASSERT_TRUE(sut.add(scene.see(i, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {-5, 15})).has_value());
    }
    Snapshot s = sut.snapshot(4);
    ASSERT_EQ(s.objects.size(), 2U);
    const std::string staticId = ofClass(s, OoiClass::Static).at(0).id;
    const std::string mobileId = ofClass(s, OoiClass::Mobile).at(0).id;
    ASSERT_TRUE(sut.add(Confirm{4.5, staticId, Confirmation::ConfirmedNegative}).has_value());
    EXPECT_FALSE(sut.add(Confirm{4.6, "ooi-77", Confirmation::ConfirmedPositive}).has_value());
    UavFix fix;
    fix.t = 5;
    scene.latLon({-4.5, 15.5}, fix.lat, fix.lon);
    ASSERT_TRUE(sut.add(fix).has_value());

    s = sut.snapshot(5);
    EXPECT_EQ(ofClass(s, OoiClass::Static).at(0).state, Confirmation::ConfirmedNegative);
    const auto mobiles = ofClass(s, OoiClass::Mobile);
    ASSERT_EQ(mobiles.size(), 1U); // the fix joined the tracked object, no new one
    EXPECT_EQ(mobiles[0].id, mobileId);
    EXPECT_EQ(mobiles[0].state, Confirmation::ConfirmedPositive);
    EXPECT_LT((scene.local(mobiles[0]) - Eigen::Vector2d(-4.5, 15.5)).norm(), 0.5);
}

TEST(ImprovedCorrelator, DuplicatesFromABiasedUgvMergeIntoTheEarliestId)
{
    const Scene scene;
    ImprovedCorrelator sut;
    // Before any estimate, ugv-2's 10 deg error puts the far post 4.4 m away from ugv-1's: two objects.
    const std::vector<Eigen::Vector2d> posts{{-20, 25}, {0, 25}, {20, 25}};
    std::string firstId;
    for (int step = 0; step < 600; ++step) {
        const double t = step * 0.5;
        for (std::size_t i = 0; i < posts.size(); ++i) {
            ASSERT_TRUE(sut.add(scene.see(t, "ugv-1", "a" + std::to_string(i), OoiClass::Static, {0, 0}, posts[i]))
                            .has_value());
            if (t >= 5.0) {
                ASSERT_TRUE(
                    sut.add(scene.see(t, "ugv-2", "b" + std::to_string(i), OoiClass::Static, {5, 0}, posts[i], 10.0))
                        .has_value());
            }
        }
        if (step == 4) {
            firstId = sut.snapshot(t).objects.at(0).id;
        }
    }
    const Snapshot s = sut.snapshot(300);
    ASSERT_EQ(s.objects.size(), posts.size());
    bool kept = false;
    for (const ObjectEstimate& o : s.objects) {
        kept = kept || o.id == firstId;
        EXPECT_EQ(o.ugvs, (std::vector<std::string>{"ugv-1", "ugv-2"}));
    }
    EXPECT_TRUE(kept);
}

} // namespace
} // namespace ugv::correlator
