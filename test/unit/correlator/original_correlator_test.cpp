// Mode `original` rule by rule: static tracks (3 observations, EM split, merge by distance and by error bounds,
// earliest id), confirmation states (initial, confirm, inheritance, merged ids), mobile objects (weighted
// average, timeout, merge, classes apart), UAV fixes, alerts, bounded memory.

#include "ugv/correlator/original_correlator.hpp"

#include <cmath>
#include <random>
#include <string>
#include <type_traits>

#include <gtest/gtest.h>

#include "scene.hpp"

namespace ugv::correlator {
namespace {

using test::Scene;
using test::snapshotAt;

const ObjectEstimate* findId(const Snapshot& s, const std::string& id)
{
    for (const ObjectEstimate& o : s.objects) {
        if (o.id == id) {
            return &o;
        }
    }
    return nullptr;
}

/// The first observation defines the correlator's local frame: start every scene with the UGV at the origin.
void feed(OriginalCorrelator& sut, const Observation& o)
{
    ASSERT_TRUE(sut.add(o).has_value());
}

TEST(OriginalCorrelator, SnapshotChangesNothingAndAdvanceTimesOutMobileObjects)
{
    static_assert(
        std::is_same_v<decltype(&OriginalCorrelator::snapshot), Snapshot (OriginalCorrelator::*)(double) const>);
    const Scene scene;
    OriginalCorrelator sut;
    feed(sut, scene.see(0.0, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {8, 12}));
    const OriginalCorrelator& view = sut;
    const double late = OriginalConfig{}.mobileTimeoutS + 1.0;

    EXPECT_EQ(view.snapshot(late).objects.size(), 1U); // still there: only advance() times it out
    sut.advance(late);

    EXPECT_TRUE(view.snapshot(late).objects.empty());
}

TEST(OriginalCorrelator, StaticTrackBecomesAnObjectAtItsThirdObservation)
{
    const Scene scene;
    OriginalCorrelator sut;
    const Eigen::Vector2d ugv(0, 0);
    const Eigen::Vector2d post(8, 12);
    feed(sut, scene.see(0.0, "ugv-1", "a", OoiClass::Static, ugv, post));
    feed(sut, scene.see(0.5, "ugv-1", "a", OoiClass::Static, ugv, post));
    EXPECT_TRUE(snapshotAt(sut, 1.0).objects.empty());

    feed(sut, scene.see(1.0, "ugv-1", "a", OoiClass::Static, ugv, post));
    const Snapshot s = snapshotAt(sut, 1.5);

    ASSERT_EQ(s.objects.size(), 1U);
    EXPECT_LT((scene.local(s.objects[0]) - post).norm(), 0.05);
    EXPECT_EQ(s.objects[0].cls, OoiClass::Static);
    EXPECT_EQ(s.objects[0].state, Confirmation::Unknown);
    EXPECT_EQ(s.objects[0].observations, 3);
    EXPECT_DOUBLE_EQ(s.objects[0].zoneDiameterM, kStaticZoneDiameterM);
    EXPECT_EQ(s.objects[0].ugvs, std::vector<std::string>{"ugv-1"});
}

TEST(OriginalCorrelator, TracksWithin2_5mMergeKeepingTheEarliestId)
{
    const Scene scene;
    OriginalCorrelator sut;
    for (int i = 0; i < 3; ++i) {
        feed(sut, scene.see(i, "ugv-1", "a", OoiClass::Static, {0, 0}, {10, 10}));
    }
    const std::string first = snapshotAt(sut, 3).objects.at(0).id;
    // ugv-2's heading error puts the same object 2 m away.
    for (int i = 0; i < 3; ++i) {
        feed(sut, scene.see(3 + i, "ugv-2", "b", OoiClass::Static, {20, 0}, {12, 10}));
    }
    const Snapshot s = snapshotAt(sut, 7);

    ASSERT_EQ(s.objects.size(), 1U);
    EXPECT_EQ(s.objects[0].id, first);
    EXPECT_EQ(s.objects[0].ugvs, (std::vector<std::string>{"ugv-1", "ugv-2"}));
    EXPECT_EQ(s.objects[0].observations, 6);
    EXPECT_LT((scene.local(s.objects[0]) - Eigen::Vector2d(11, 10)).norm(), 0.1);
}

TEST(OriginalCorrelator, DistantTracksStaySeparate)
{
    const Scene scene;
    OriginalCorrelator sut;
    for (int i = 0; i < 3; ++i) {
        feed(sut, scene.see(i, "ugv-1", "a", OoiClass::Static, {0, 0}, {10, 10}));
        feed(sut, scene.see(i, "ugv-1", "b", OoiClass::Static, {0, 0}, {10, 14}));
    }
    EXPECT_EQ(snapshotAt(sut, 3).objects.size(), 2U);
}

TEST(OriginalCorrelator, OverlappingErrorBoundsMergeBeyondTheRadius)
{
    const Scene scene;
    std::mt19937_64 rng(3);
    for (const double spread : {0.05, 1.2}) {
        std::normal_distribution<double> noise(0.0, spread);
        OriginalCorrelator sut;
        feed(sut, scene.see(0, "ugv-1", "a", OoiClass::Static, {0, 0}, {10, 10}));
        for (int i = 1; i < 30; ++i) {
            feed(sut, scene.see(i, "ugv-1", "a", OoiClass::Static, {0, 0}, {10 + noise(rng), 10 + noise(rng)}));
            feed(sut, scene.see(i, "ugv-2", "b", OoiClass::Static, {0, 0}, {13.5 + noise(rng), 10 + noise(rng)}));
        }
        // 3.5 m apart: beyond the 2.5 m radius; with 1.2 m spread their 2-sigma bounds overlap, with 5 cm not.
        EXPECT_EQ(snapshotAt(sut, 31).objects.size(), spread > 1.0 ? 1U : 2U) << "spread " << spread;
    }
}

TEST(OriginalCorrelator, OneTrackOverTwoObjectsSplitsIntoTwo)
{
    const Scene scene;
    std::mt19937_64 rng(5);
    std::normal_distribution<double> noise(0.0, 0.15);
    OriginalCorrelator sut;
    for (int i = 0; i < 40; ++i) {
        const Eigen::Vector2d object = i % 2 == 0 ? Eigen::Vector2d(10, 10) : Eigen::Vector2d(16, 10);
        feed(sut, scene.see(i * 0.5, "ugv-1", "a", OoiClass::Static, {0, 0},
                            object + Eigen::Vector2d(noise(rng), noise(rng))));
    }
    const Snapshot s = snapshotAt(sut, 21);

    ASSERT_EQ(s.objects.size(), 2U);
    const double x0 = scene.local(s.objects[0]).x();
    const double x1 = scene.local(s.objects[1]).x();
    EXPECT_NEAR(std::min(x0, x1), 10.0, 0.2);
    EXPECT_NEAR(std::max(x0, x1), 16.0, 0.2);
}

TEST(OriginalCorrelator, ConfirmationStartsFromTheClassAndFollowsConfirms)
{
    const Scene scene;
    OriginalCorrelator sut;
    for (int i = 0; i < 3; ++i) {
        feed(sut, scene.see(i, "ugv-1", "a", OoiClass::Static, {0, 0}, {10, 10}));
        feed(sut, scene.see(i, "ugv-1", "p", OoiClass::NonCombatant, {0, 0}, {-10, 10}));
    }
    Snapshot s = snapshotAt(sut, 3);
    ASSERT_EQ(s.objects.size(), 2U);
    const ObjectEstimate civilian = s.objects[0].cls == OoiClass::NonCombatant ? s.objects[0] : s.objects[1];
    const ObjectEstimate post = s.objects[0].cls == OoiClass::Static ? s.objects[0] : s.objects[1];
    EXPECT_EQ(civilian.state, Confirmation::ConfirmedNegative);
    EXPECT_EQ(post.state, Confirmation::Unknown);

    ASSERT_TRUE(sut.add(Confirm{4, post.id, Confirmation::ConfirmedPositive}).has_value());

    s = snapshotAt(sut, 5);
    ASSERT_NE(findId(s, post.id), nullptr);
    EXPECT_EQ(findId(s, post.id)->state, Confirmation::ConfirmedPositive);
    const auto unknown = sut.add(Confirm{5, "ooi-999", Confirmation::ConfirmedPositive});
    ASSERT_FALSE(unknown.has_value());
    EXPECT_NE(unknown.error().what.find("ooi-999"), std::string::npos);
}

TEST(OriginalCorrelator, MergedObjectsInheritTheConfirmationAndMergedIdsStillConfirm)
{
    const Scene scene;
    // ugv-2's three early fixes must stay below the size of a track's second component, or its track would keep
    // them apart as a component of their own (GaussianMixture.AComponentOfExactlyTheMinimumPointsIsKept).
    OriginalConfig config;
    config.mixture.minComponentPoints = 4;
    OriginalCorrelator sut(config);
    for (int i = 0; i < 3; ++i) {
        feed(sut, scene.see(i, "ugv-1", "a", OoiClass::Static, {0, 0}, {10, 10}));
        feed(sut, scene.see(i, "ugv-2", "b", OoiClass::Static, {0, 0}, {10, 16}));
    }
    Snapshot s = snapshotAt(sut, 3);
    ASSERT_EQ(s.objects.size(), 2U);
    const std::string earlier = s.objects[0].id;
    const std::string later = s.objects[1].id;
    ASSERT_TRUE(sut.add(Confirm{3.5, later, Confirmation::ConfirmedPositive}).has_value());

    // ugv-2's track moves onto the first object (its earlier fixes were off): the two objects merge.
    for (int i = 0; i < 60; ++i) {
        feed(sut, scene.see(4 + i, "ugv-2", "b", OoiClass::Static, {0, 0}, {10, 10.5}));
    }
    s = snapshotAt(sut, 70);

    ASSERT_EQ(s.objects.size(), 1U);
    EXPECT_EQ(s.objects[0].id, earlier);
    EXPECT_EQ(s.objects[0].state, Confirmation::ConfirmedPositive); // inherited from the absorbed object
    ASSERT_TRUE(sut.add(Confirm{71, later, Confirmation::ConfirmedNegative}).has_value()); // the merged id
    EXPECT_EQ(snapshotAt(sut, 72).objects[0].state, Confirmation::ConfirmedNegative);
}

TEST(OriginalCorrelator, MobilePositionIsTheWeightedAverageOfTheLastThree)
{
    const Scene scene;
    OriginalCorrelator sut;
    feed(sut, scene.see(0, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {10, 10}));
    feed(sut, scene.see(1, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {11, 10}));
    feed(sut, scene.see(2, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {12, 10}));
    feed(sut, scene.see(3, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {13, 10}));
    const Snapshot s = snapshotAt(sut, 3.5);

    ASSERT_EQ(s.objects.size(), 1U);
    EXPECT_NEAR(scene.local(s.objects[0]).x(), 0.5 * 13 + 0.3 * 12 + 0.2 * 11, 1e-3);
    EXPECT_DOUBLE_EQ(s.objects[0].zoneDiameterM, kMobileZoneDiameterM);
    EXPECT_EQ(s.objects[0].observations, 4);
}

TEST(OriginalCorrelator, MobileObjectsTimeOutAfter60s)
{
    const Scene scene;
    OriginalCorrelator sut;
    feed(sut, scene.see(0, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {10, 10}));
    EXPECT_EQ(snapshotAt(sut, 59.0).objects.size(), 1U);
    EXPECT_TRUE(snapshotAt(sut, 61.0).objects.empty());
}

TEST(OriginalCorrelator, MobileTracksMergeWithin2_5mAndClassesStayApart)
{
    const Scene scene;
    OriginalCorrelator sut;
    feed(sut, scene.see(0, "ugv-1", "m1", OoiClass::Mobile, {0, 0}, {10, 10}));
    feed(sut, scene.see(0, "ugv-2", "m2", OoiClass::Mobile, {0, 0}, {11.5, 10}));
    feed(sut, scene.see(0, "ugv-2", "c1", OoiClass::NonCombatant, {0, 0}, {10.5, 10}));
    const Snapshot s = snapshotAt(sut, 0.5);

    ASSERT_EQ(s.objects.size(), 2U);
    int mobiles = 0;
    for (const ObjectEstimate& o : s.objects) {
        mobiles += o.cls == OoiClass::Mobile ? 1 : 0;
        if (o.cls == OoiClass::Mobile) {
            EXPECT_EQ(o.id, "ooi-1");
            EXPECT_EQ(o.ugvs, (std::vector<std::string>{"ugv-1", "ugv-2"}));
        }
    }
    EXPECT_EQ(mobiles, 1);
}

TEST(OriginalCorrelator, UavFixMovesTheNearestMobileObjectAndConfirmsIt)
{
    const Scene scene;
    OriginalCorrelator sut;
    feed(sut, scene.see(0, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {10, 10}));
    UavFix fix;
    fix.t = 1;
    scene.latLon({12, 11}, fix.lat, fix.lon);
    ASSERT_TRUE(sut.add(fix).has_value());
    UavFix far = fix;
    scene.latLon({60, 60}, far.lat, far.lon);
    ASSERT_TRUE(sut.add(far).has_value());
    const Snapshot s = snapshotAt(sut, 2);

    ASSERT_EQ(s.objects.size(), 2U);
    const ObjectEstimate* merged = findId(s, "ooi-1");
    ASSERT_NE(merged, nullptr);
    EXPECT_LT((scene.local(*merged) - Eigen::Vector2d(12, 11)).norm(), 1e-3);
    EXPECT_EQ(merged->state, Confirmation::ConfirmedPositive);
    for (const ObjectEstimate& o : s.objects) {
        EXPECT_EQ(o.state, Confirmation::ConfirmedPositive);
    }
}

TEST(OriginalCorrelator, NonCombatantsNearThreatsRaiseAlerts)
{
    const Scene scene;
    OriginalCorrelator sut;
    for (int i = 0; i < 3; ++i) {
        feed(sut, scene.see(i, "ugv-1", "s", OoiClass::Static, {0, 0}, {10, 10}));
    }
    feed(sut, scene.see(3, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {40, 10}));
    feed(sut, scene.see(3, "ugv-1", "c1", OoiClass::NonCombatant, {0, 0}, {13, 10}));  // 3 m from the static
    feed(sut, scene.see(3, "ugv-1", "c2", OoiClass::NonCombatant, {0, 0}, {25, 10}));  // 15 m from the mobile
    feed(sut, scene.see(3, "ugv-1", "c3", OoiClass::NonCombatant, {0, 0}, {-30, 10})); // far from both
    const Snapshot s = snapshotAt(sut, 4);

    ASSERT_EQ(s.alerts.size(), 2U);
    for (const Alert& a : s.alerts) {
        EXPECT_LE(a.distanceM, 20.0);
    }
}

TEST(OriginalCorrelator, StoredPointsStayBoundedOverALongMission)
{
    const Scene scene;
    OriginalConfig config;
    OriginalCorrelator sut(config);
    std::mt19937_64 rng(9);
    std::normal_distribution<double> noise(0.0, 0.3);
    std::uniform_real_distribution<double> anywhere(-200, 200);
    for (int i = 0; i < 20000; ++i) {
        const double t = i * 0.5;
        // One object seen for the whole mission, clutter tracks that never reach 3 observations.
        feed(sut, scene.see(t, "ugv-1", "a", OoiClass::Static, {0, 0}, {10 + noise(rng), 10 + noise(rng)}));
        feed(sut, scene.see(t, "ugv-1", "clutter-" + std::to_string(i), OoiClass::Static, {0, 0},
                            {anywhere(rng), anywhere(rng)}));
        if (i % 100 == 0) {
            (void)snapshotAt(sut, t);
        }
    }
    EXPECT_LE(sut.storedPoints(), config.maxPointsPerTrack + 2 * 700); // reservoir + clutter of the last 300 s
    const Snapshot s = snapshotAt(sut, 10000);
    ASSERT_EQ(s.objects.size(), 1U);
    EXPECT_EQ(s.objects[0].observations, 20000); // every observation counts in the fit, not only the stored ones
    EXPECT_LT((scene.local(s.objects[0]) - Eigen::Vector2d(10, 10)).norm(), 0.05);

    (void)snapshotAt(sut, 10000 + config.retireAfterS + 1); // idle: the track drops its points, keeps its fit
    EXPECT_EQ(sut.storedPoints(), 0U);
    EXPECT_EQ(snapshotAt(sut, 10400).objects.size(), 1U);
}

TEST(OriginalCorrelator, PoseCorrectionsAreCountedAndIgnored)
{
    OriginalCorrelator sut;
    ASSERT_TRUE(sut.add(PoseCorrection{1, "ugv-1", 0, 1, 1.0, 0.0, 2.0}).has_value());
    EXPECT_EQ(sut.ignoredPoseCorrections(), 1U);
}

} // namespace
} // namespace ugv::correlator
