// Parts of mode pose-corrected on their own: the measurement model (rays, noise, information), ObjectIds (ids
// in creation order, merges followed, erased ids gone), UgvPoseErrors' remaining pose uncertainty and StaticMap's
// split/merge hysteresis. The other rules they carry out are tested through PoseCorrectedCorrelator in
// pose_corrected_correlator_test.cpp.

#include "ugv/correlator/measurement_model.hpp"
#include "ugv/correlator/object_ids.hpp"
#include "ugv/correlator/static_map.hpp"
#include "ugv/correlator/ugv_pose_errors.hpp"

#include <cmath>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "ugv/correlator/geodesy.hpp"

namespace ugv::correlator {
namespace {

constexpr double kTolerance = 1e-12;

TEST(MeasurementModel, RaysAreCompassDirectionsAndAcrossIsAQuarterTurnLeft)
{
    const Eigen::Vector2d north = rayAt(0.0);
    const Eigen::Vector2d east = rayAt(90.0 * kRadPerDeg);

    EXPECT_NEAR(north.x(), 0.0, kTolerance);
    EXPECT_NEAR(north.y(), 1.0, kTolerance);
    EXPECT_NEAR(east.x(), 1.0, kTolerance);
    EXPECT_NEAR(east.y(), 0.0, kTolerance);
    EXPECT_NEAR((acrossOf(north) - Eigen::Vector2d(1.0, 0.0)).norm(), 0.0, kTolerance);
}

TEST(MeasurementModel, OriginalProjectsAlongTheSameRay)
{
    const Eigen::Vector2d from(3.0, -2.0);
    constexpr double kAzimuthDeg = 37.0;
    constexpr double kRangeM = 12.5;

    const Eigen::Vector2d p = project(from, kAzimuthDeg, kRangeM);

    EXPECT_EQ(p, Eigen::Vector2d(from + kRangeM * rayAt(kAzimuthDeg * kRadPerDeg)));
}

TEST(MeasurementModel, NoiseGrowsWithRangeAndScales)
{
    const RangeBearingNoise sut{0.1, 0.01, 2.0};
    constexpr double kRangeM = 20.0;

    EXPECT_NEAR(sut.alongSigma(kRangeM), 0.3, kTolerance);
    EXPECT_NEAR(sut.alongSigma(kRangeM, 2.0), 0.6, kTolerance);
    EXPECT_NEAR(sut.acrossSigma(kRangeM), kRangeM * 2.0 * kRadPerDeg, kTolerance);
}

TEST(MeasurementModel, RayInformationIsTheInverseOfTheRayCovariance)
{
    const Eigen::Vector2d ray = rayAt(25.0 * kRadPerDeg);
    const Eigen::Vector2d across = acrossOf(ray);
    constexpr double kAlong = 0.3;
    constexpr double kAcross = 0.7;
    const Eigen::Matrix2d cov =
        kAlong * kAlong * ray * ray.transpose() + kAcross * kAcross * across * across.transpose();

    const Eigen::Matrix2d product = rayInformation(ray, kAlong, kAcross) * cov;

    EXPECT_NEAR((product - Eigen::Matrix2d::Identity()).norm(), 0.0, 1e-9);
    EXPECT_NEAR(mahalanobis2(kAcross * across, cov), 1.0, 1e-9);
}

TEST(ObjectIds, IssuedInCreationOrderAndFound)
{
    ObjectIds sut;

    const ObjectIds::Issued first = sut.issue(true, 0);
    const ObjectIds::Issued second = sut.issue(false, 4);

    EXPECT_EQ(first.id, "ooi-1");
    EXPECT_EQ(second.id, "ooi-2");
    EXPECT_LT(first.order, second.order);
    const auto found = sut.find("ooi-2");
    ASSERT_TRUE(found.has_value());
    EXPECT_FALSE(found->isStatic);
    EXPECT_EQ(found->index, 4);
}

TEST(ObjectIds, AMergedIdLeadsToTheObjectThatAbsorbedItThroughAChain)
{
    ObjectIds sut;
    const std::string a = sut.issue(true, 0).id;
    const std::string b = sut.issue(true, 1).id;
    const std::string c = sut.issue(true, 2).id;

    sut.merge(c, b);
    sut.merge(b, a);

    const auto found = sut.find(c);
    ASSERT_TRUE(found.has_value());
    EXPECT_EQ(found->index, 0);
}

TEST(ObjectIds, ErasedAndUnknownIdsAreNotFound)
{
    ObjectIds sut;
    const std::string a = sut.issue(true, 0).id;

    sut.erase(a);

    EXPECT_FALSE(sut.find(a).has_value());
    EXPECT_FALSE(sut.find("ooi-42").has_value());
    EXPECT_FALSE(sut.find("").has_value());
}

/// The across-ray variance of an observation 20 m straight ahead of a UGV at the origin.
double acrossVariance(const UgvPoseErrors& poses, int ugv)
{
    const RangeBearing s{0.0, Eigen::Vector2d::Zero(), 0.0, 20.0, 0.0};
    Eigen::Vector2d p;
    Eigen::Matrix2d cov;
    poses.project(ugv, s, p, &cov);
    return cov(0, 0); // the ray points north: across is east
}

TEST(UgvPoseErrors, AfterASolveThePoseUncertaintyLeftIsAtLeastHowFarTheSolveStillMovedTheEstimate)
{
    const PoseCorrectedConfig config;
    UgvPoseErrors sut(config);
    const int settled = sut.index("ugv-1");
    const int moving = sut.index("ugv-2");
    const int unsolved = sut.index("ugv-3");
    for (const int u : {settled, moving}) {
        sut.ugv(static_cast<std::size_t>(u)).solved = true;
    }
    sut.ugv(static_cast<std::size_t>(settled)).headingStep = 0.001 * kRadPerDeg;
    sut.ugv(static_cast<std::size_t>(moving)).headingStep = 3.0 * kRadPerDeg; // the last solve still moved it 3 deg
    sut.ugv(static_cast<std::size_t>(unsolved)).headingStep = 30.0 * kRadPerDeg;

    const double settledVar = acrossVariance(sut, settled);
    const double movingVar = acrossVariance(sut, moving);
    const double priorVar = acrossVariance(sut, unsolved);

    constexpr double kRange = 20.0;
    const double movingHeading = kRange * 3.0 * kRadPerDeg;
    EXPECT_GT(movingVar, settledVar + 0.9 * movingHeading * movingHeading);
    EXPECT_LT(movingVar, priorVar); // never above the prior: a solved UGV is never less certain than an unsolved one
    EXPECT_GT(priorVar, std::pow(kRange * config.headingBiasSigmaDeg * kRadPerDeg, 2));
}

/// Two posts 3.9 m apart, A seen by ugv-1 and B by ugv-2 (both UGVs' errors known: two objects, ooi-1 and ooi-2).
/// A wrong heading estimate for ugv-2 (-10 deg, which turns B onto A) merges them into ooi-1; the estimate put
/// right splits them again. The split undoes the merge: B's object comes back as ooi-2, not as a new ooi-3.
TEST(StaticMap, ASplitThatUndoesAMergeGivesTheAbsorbedObjectItsIdBack)
{
    const PoseCorrectedConfig config;
    UgvPoseErrors poses(config);
    ObjectIds ids;
    StaticMap sut(config);
    const int one = poses.index("ugv-1");
    const int two = poses.index("ugv-2");
    poses.ugv(static_cast<std::size_t>(one)).solved = true;
    poses.ugv(static_cast<std::size_t>(two)).solved = true;
    const Eigen::Vector2d posOne(-10, 0);
    const Eigen::Vector2d posTwo(10, 0);
    const Eigen::Vector2d a(0, 20);
    const double turn = 10.0 * kRadPerDeg;
    const Eigen::Vector2d fromTwo = a - posTwo;
    const Eigen::Vector2d b = posTwo + Eigen::Vector2d(std::cos(turn) * fromTwo.x() + std::sin(turn) * fromTwo.y(),
                                                       -std::sin(turn) * fromTwo.x() + std::cos(turn) * fromTwo.y());
    ASSERT_NEAR((a - b).norm(), 3.9, 0.05);
    const auto see = [&](double t, int ugv, const char* name, const char* track, const Eigen::Vector2d& from,
                         const Eigen::Vector2d& post) {
        Observation o;
        o.t = t;
        o.ugv = name;
        o.track = track;
        o.cls = OoiClass::Static;
        const Eigen::Vector2d d = post - from;
        sut.add(o, ugv, RangeBearing{t, from, 0.0, d.norm(), std::atan2(d.x(), d.y())}, poses, ids);
    };
    for (int i = 0; i < 40; ++i) {
        see(0.5 * i, one, "ugv-1", "a", posOne, a);
        see(0.5 * i, two, "ugv-2", "b", posTwo, b);
    }
    ASSERT_EQ(sut.objects().size(), 2U);
    const std::string idA = sut.objects()[0].id;
    const std::string idB = sut.objects()[1].id;

    poses.ugv(static_cast<std::size_t>(two)).headingBias = -turn; // wrong: B lands on A
    sut.rebuild(poses, ids);
    ASSERT_FALSE(sut.objects()[1].alive) << "the wrong estimate should have merged B into A";
    ASSERT_EQ(ids.find(idB)->index, 0);
    poses.ugv(static_cast<std::size_t>(two)).headingBias = 0.0; // put right
    sut.rebuild(poses, ids);

    ASSERT_EQ(sut.objects().size(), 2U) << "a new object was made instead of B's coming back";
    EXPECT_TRUE(sut.objects()[0].alive);
    EXPECT_TRUE(sut.objects()[1].alive);
    EXPECT_EQ(sut.objects()[0].id, idA);
    EXPECT_EQ(sut.objects()[1].id, idB);
    EXPECT_EQ(ids.find(idB)->index, 1);
    EXPECT_EQ(ids.find(idA)->index, 0);
    EXPECT_LT((sut.objects()[0].mean - a).norm(), 0.1);
    EXPECT_LT((sut.objects()[1].mean - b).norm(), 0.1);
}

} // namespace
} // namespace ugv::correlator
