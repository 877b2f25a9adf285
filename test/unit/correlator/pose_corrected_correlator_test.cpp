// Mode `pose-corrected` rule by rule: joint estimation of a UGV's heading bias, pose corrections re-projecting stored
// observations, statistical association keeping close objects apart, Kalman prediction of mobile objects through
// gaps, clutter that never becomes an object, ids kept on merges and splits, confirmation, UAV fixes.

#include "ugv/correlator/original_correlator.hpp"
#include "ugv/correlator/pose_corrected_correlator.hpp"

#include <algorithm>
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

TEST(PoseCorrectedCorrelator, EstimatesAUgvsHeadingBiasFromSharedObjectsAndKeepsOneObjectEach)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
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
    const Snapshot s = snapshotAt(sut, 300);
    EXPECT_EQ(ofClass(s, OoiClass::Static).size(), posts.size());
}

/// Both UGVs report positions 2.5 m off in the same direction: the static objects alone cannot tell (everything moves
/// together), and zero-mean priors would leave every object 2.5 m off. The UAV fixes a walker that ugv-1 sees too:
/// those sightings are absolute anchors, and the fleet's common offset comes out.
TEST(PoseCorrectedCorrelator, UavFixesOfAnObjectAUgvSeesTooMakeTheFleetsCommonOffsetObservable)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    const Eigen::Vector2d offset(2.0, -1.5);
    const Eigen::Vector2d posOne(-10, 0);
    const Eigen::Vector2d posTwo(10, 0);
    std::vector<Eigen::Vector2d> posts;
    for (int i = 0; i < 6; ++i) {
        posts.emplace_back(-25.0 + 10.0 * i, 12.0 + 3.0 * (i % 2));
    }
    const auto walker = [](double t) { // back and forth along 40 m at 1 m/s
        const double phase = std::fmod(t, 80.0);
        return Eigen::Vector2d(-20.0 + (phase < 40.0 ? phase : 80.0 - phase), 30.0);
    };
    constexpr double kEndS = 300.0;
    for (int step = 0; 0.5 * step <= kEndS; ++step) {
        const double t = 0.5 * step;
        for (std::size_t i = 0; i < posts.size(); ++i) {
            const std::string n = std::to_string(i);
            ASSERT_TRUE(
                sut.add(scene.see(t, "ugv-1", "a" + n, OoiClass::Static, posOne, posts[i], 0.0, offset)).has_value());
            ASSERT_TRUE(
                sut.add(scene.see(t, "ugv-2", "b" + n, OoiClass::Static, posTwo, posts[i], 0.0, offset)).has_value());
        }
        ASSERT_TRUE(sut.add(scene.see(t, "ugv-1", "m", OoiClass::Mobile, posOne, walker(t), 0.0, offset)).has_value());
        if (step % 20 == 0) {
            UavFix fix;
            fix.t = t;
            scene.latLon(walker(t), fix.lat, fix.lon);
            ASSERT_TRUE(sut.add(fix).has_value());
        }
    }

    const auto statics = ofClass(snapshotAt(sut, kEndS), OoiClass::Static);
    ASSERT_EQ(statics.size(), posts.size());
    for (const ObjectEstimate& o : statics) {
        const Eigen::Vector2d at = scene.local(o);
        const auto nearest = std::min_element(posts.begin(), posts.end(), [&](const auto& x, const auto& y) {
            return (x - at).norm() < (y - at).norm();
        });
        EXPECT_LT((*nearest - at).norm(), 0.3) << o.id;
    }
    for (const char* ugv : {"ugv-1", "ugv-2"}) {
        EXPECT_LT((sut.poseError(ugv, kEndS).value().offset + offset).norm(), 0.3) << ugv;
    }
}

TEST(PoseCorrectedCorrelator, PoseCorrectionReprojectsStoredObservationsExactly)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    const Eigen::Vector2d post(5, 20);
    // The UGV's reported position is 3 m east of the truth.
    for (int i = 0; i < 5; ++i) {
        ASSERT_TRUE(sut.add(scene.see(i, "ugv-1", "a", OoiClass::Static, {0, 0}, post, 0.0, {3, 0})).has_value());
    }
    const Snapshot before = snapshotAt(sut, 5);
    ASSERT_EQ(before.objects.size(), 1U);
    EXPECT_NEAR(scene.local(before.objects[0]).x(), post.x() + 3.0, 1e-3);

    ASSERT_TRUE(sut.add(PoseCorrection{5, "ugv-1", 0, 5, -3.0, 0.0, 0.0}).has_value());

    const Snapshot s = snapshotAt(sut, 6);
    ASSERT_EQ(s.objects.size(), 1U);
    EXPECT_LT((scene.local(s.objects[0]) - post).norm(), 1e-3);
}

TEST(PoseCorrectedCorrelator, ObjectsTwoMetresApartStayApartWhereTheOriginalMergesThem)
{
    const Scene scene;
    PoseCorrectedCorrelator poseCorrected;
    OriginalCorrelator original;
    std::mt19937_64 rng(2);
    std::normal_distribution<double> noise(0.0, 0.05);
    for (int i = 0; i < 20; ++i) {
        for (const auto& [track, at] :
             {std::pair{"a", Eigen::Vector2d(0, 12)}, std::pair{"b", Eigen::Vector2d(2.2, 12)}}) {
            Observation o = scene.see(i * 0.5, "ugv-1", track, OoiClass::Static, {1, 0}, at);
            o.rangeM += noise(rng);
            ASSERT_TRUE(poseCorrected.add(o).has_value());
            ASSERT_TRUE(original.add(o).has_value());
        }
    }
    EXPECT_EQ(snapshotAt(poseCorrected, 10).objects.size(), 2U);
    EXPECT_EQ(snapshotAt(original, 10).objects.size(), 1U); // its fixed 2.5 m gate
}

TEST(PoseCorrectedCorrelator, MobileObjectIsPredictedThroughAGap)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    // Walks east at 1 m/s; seen for 10 s, then not for 2 s.
    for (int i = 0; i <= 20; ++i) {
        const double t = i * 0.5;
        ASSERT_TRUE(sut.add(scene.see(t, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {-5.0 + t, 15})).has_value());
    }
    const Snapshot s = snapshotAt(sut, 12);

    const auto mobiles = ofClass(s, OoiClass::Mobile);
    ASSERT_EQ(mobiles.size(), 1U);
    EXPECT_LT((scene.local(mobiles[0]) - Eigen::Vector2d(-5.0 + 12.0, 15)).norm(), 0.3);
    EXPECT_GT(mobiles[0].sigmaMajorM, 0.0);
    // Four more seconds unseen: too uncertain to show (kept for when it is seen again).
    EXPECT_TRUE(ofClass(snapshotAt(sut, 16), OoiClass::Mobile).empty());
    EXPECT_DOUBLE_EQ(mobiles[0].zoneDiameterM, kMobileZoneDiameterM);
}

TEST(PoseCorrectedCorrelator, AMobileWalkingALineIsPredictedAlongItThroughALongGap)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
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
    const Snapshot s = snapshotAt(sut, 145);

    const auto mobiles = ofClass(s, OoiClass::Mobile);
    ASSERT_EQ(mobiles.size(), 1U);
    EXPECT_LT((scene.local(mobiles[0]) - truth(145)).norm(), 2.0);
}

TEST(PoseCorrectedCorrelator, AMobileOnlyTheUavFixesIsPredictedAlongItsLineBetweenFixesAndKeepsItsId)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    // Back and forth along 40 m of the east axis at 1 m/s (an 80 s round trip); a UAV fix every 10 s, no UGV.
    const auto truth = [](double t) {
        const double phase = std::fmod(t, 80.0);
        return Eigen::Vector2d(-20.0 + (phase < 40.0 ? phase : 80.0 - phase), 30.0);
    };
    std::string id;
    for (int i = 0; i <= 20; ++i) {
        UavFix fix;
        fix.t = i * 10.0;
        scene.latLon(truth(fix.t), fix.lat, fix.lon);
        ASSERT_TRUE(sut.add(fix).has_value());
        const auto mobiles = ofClass(snapshotAt(sut, fix.t + 1.0), OoiClass::Mobile);
        ASSERT_EQ(mobiles.size(), 1U) << "t " << fix.t + 1.0;
        id = id.empty() ? mobiles[0].id : id;
        EXPECT_EQ(mobiles[0].id, id) << "t " << fix.t + 1.0;
    }
    // 7 s after the last fix, which found it at the east end: it turned there and walks back west.
    constexpr double kT = 207.0;
    const auto mobiles = ofClass(snapshotAt(sut, kT), OoiClass::Mobile);
    ASSERT_EQ(mobiles.size(), 1U);
    EXPECT_LT((scene.local(mobiles[0]) - truth(kT)).norm(), 1.5);
    EXPECT_EQ(mobiles[0].state, Confirmation::ConfirmedPositive);
}

TEST(PoseCorrectedCorrelator, SnapshotChangesNothingAndAdvanceAssignsThePendingUavFixes)
{
    static_assert(std::is_same_v<decltype(&PoseCorrectedCorrelator::snapshot),
                                 Snapshot (PoseCorrectedCorrelator::*)(double) const>);
    const Scene scene;
    PoseCorrectedCorrelator sut;
    UavFix fix;
    fix.t = 5.0;
    scene.latLon(Eigen::Vector2d(8, 20), fix.lat, fix.lon);
    ASSERT_TRUE(sut.add(fix).has_value());
    const PoseCorrectedCorrelator& view = sut;

    EXPECT_TRUE(view.snapshot(5.0).objects.empty()); // the fixes of an instant wait for the next one or advance()
    EXPECT_TRUE(view.snapshot(5.0).objects.empty());
    sut.advance(5.0);

    EXPECT_EQ(view.snapshot(5.0).objects.size(), 1U);
}

TEST(PoseCorrectedCorrelator, UavFixesOfOneInstantAreAssignedTogether)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    // Two objects only the UAV fixes; after 10 s, the first object's fix is nearer the second's last position.
    const Eigen::Vector2d a0(0, 20);
    const Eigen::Vector2d b0(12, 20);
    const Eigen::Vector2d a1(8, 20);
    const Eigen::Vector2d b1(12, 12);
    const auto fixAt = [&scene](double t, const Eigen::Vector2d& at) {
        UavFix fix;
        fix.t = t;
        scene.latLon(at, fix.lat, fix.lon);
        return fix;
    };
    ASSERT_TRUE(sut.add(fixAt(0, a0)).has_value());
    ASSERT_TRUE(sut.add(fixAt(0, b0)).has_value());
    const auto before = ofClass(snapshotAt(sut, 0.5), OoiClass::Mobile);
    ASSERT_EQ(before.size(), 2U);
    const bool firstIsA = (scene.local(before[0]) - a0).norm() < 0.5;
    const std::string idA = before[firstIsA ? 0 : 1].id;
    ASSERT_TRUE(sut.add(fixAt(10, a1)).has_value());
    ASSERT_TRUE(sut.add(fixAt(10, b1)).has_value());

    const auto after = ofClass(snapshotAt(sut, 10.5), OoiClass::Mobile);
    ASSERT_EQ(after.size(), 2U);
    for (const ObjectEstimate& o : after) {
        const bool isA = (scene.local(o) - a1).norm() < 1.0;
        EXPECT_EQ(o.id == idA, isA) << o.id;
    }
}

TEST(PoseCorrectedCorrelator, ASingleMobileSightingIsNotPublishedAndTimesOut)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    ASSERT_TRUE(sut.add(scene.see(0, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {5, 15})).has_value());
    EXPECT_TRUE(snapshotAt(sut, 1).objects.empty());
}

TEST(PoseCorrectedCorrelator, ClutterNeverBecomesAnObject)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> anywhere(-40, 40);
    // One false observation every 5 s in an 80 m square for an hour: each alone dies before it gathers 3.
    for (int i = 0; i < 720; ++i) {
        const Eigen::Vector2d at(anywhere(rng), 50 + anywhere(rng));
        ASSERT_TRUE(
            sut.add(scene.see(i * 5.0, "ugv-1", "c" + std::to_string(i), OoiClass::Static, {0, 0}, at)).has_value());
        if (i % 12 == 0) {
            EXPECT_TRUE(snapshotAt(sut, i * 5.0).objects.empty()) << "t " << i * 5.0;
        }
    }
    EXPECT_LT(sut.storedPoints(), 200U);
}

TEST(PoseCorrectedCorrelator, ConfirmationsAndUavFixes)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    for (int i = 0; i < 4; ++i) {
        ASSERT_TRUE(sut.add(scene.see(i, "ugv-1", "s", OoiClass::Static, {0, 0}, {5, 15})).has_value());
        ASSERT_TRUE(sut.add(scene.see(i, "ugv-1", "m", OoiClass::Mobile, {0, 0}, {-5, 15})).has_value());
    }
    Snapshot s = snapshotAt(sut, 4);
    ASSERT_EQ(s.objects.size(), 2U);
    const std::string staticId = ofClass(s, OoiClass::Static).at(0).id;
    const std::string mobileId = ofClass(s, OoiClass::Mobile).at(0).id;
    ASSERT_TRUE(sut.add(Confirm{4.5, staticId, Confirmation::ConfirmedNegative}).has_value());
    EXPECT_FALSE(sut.add(Confirm{4.6, "ooi-77", Confirmation::ConfirmedPositive}).has_value());
    UavFix fix;
    fix.t = 5;
    scene.latLon({-4.5, 15.5}, fix.lat, fix.lon);
    ASSERT_TRUE(sut.add(fix).has_value());

    s = snapshotAt(sut, 5);
    EXPECT_EQ(ofClass(s, OoiClass::Static).at(0).state, Confirmation::ConfirmedNegative);
    const auto mobiles = ofClass(s, OoiClass::Mobile);
    ASSERT_EQ(mobiles.size(), 1U); // the fix joined the tracked object, no new one
    EXPECT_EQ(mobiles[0].id, mobileId);
    EXPECT_EQ(mobiles[0].state, Confirmation::ConfirmedPositive);
    EXPECT_LT((scene.local(mobiles[0]) - Eigen::Vector2d(-4.5, 15.5)).norm(), 0.5);
}

TEST(PoseCorrectedCorrelator, DuplicatesFromABiasedUgvMergeIntoTheEarliestId)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
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
            firstId = snapshotAt(sut, t).objects.at(0).id;
        }
    }
    const Snapshot s = snapshotAt(sut, 300);
    ASSERT_EQ(s.objects.size(), posts.size());
    bool kept = false;
    for (const ObjectEstimate& o : s.objects) {
        kept = kept || o.id == firstId;
        EXPECT_EQ(o.ugvs, (std::vector<std::string>{"ugv-1", "ugv-2"}));
    }
    EXPECT_TRUE(kept);
}

/// A close pair that the UGVs' unknown heading errors first put in one place. ugv-1 reads its heading 4 deg to the
/// right, ugv-2 4 deg to the left (the fleet's mean error is zero, so the estimated errors are the true ones).
/// Post B, 4 m east of post A, is hidden from ugv-1: ugv-2's B lands 1.3 m from ugv-1's A, well inside the gate of
/// an object whose pose errors are unknown, and ugv-2 sees A and B at alternate instants (never both at one, which
/// would tell them apart), so one object is published for both. Posts both UGVs see elsewhere
/// let the solve (every 120 s) estimate the errors; then ugv-2's B track lies 4 m from the A tracks and the object
/// splits. bFirst: ugv-2 sees B from the start and A only later, so B founds the object and still loses the id
/// (A has two tracks, more observations). The first solve, made with the pair still associated, is skewed (the
/// objects land up to 3 m off and converge over the following solves), so positions are checked at the end.
const Eigen::Vector2d kPostA(0, 20);
const Eigen::Vector2d kPostB(4, 20);

struct SplitTrace {
    std::string published;    ///< the id of the one object near the pair before the first solve
    std::string firstSplitId; ///< of the part at B, from the first snapshot with two objects
    double splitT = -1.0;     ///< the first snapshot with two objects near the pair
    std::vector<std::string> problems;
    std::vector<ObjectEstimate> last; ///< near the pair, at the end
};

SplitTrace runClosePair(bool bFirst)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    std::mt19937_64 rng(4);
    std::normal_distribution<double> bearingNoise(0.0, 0.3);
    const Eigen::Vector2d& a = kPostA;
    const Eigen::Vector2d& b = kPostB;
    const Eigen::Vector2d one(-10, 0);
    const Eigen::Vector2d two(10, 0);
    const std::vector<Eigen::Vector2d> shared{{-30, 15}, {-20, 32}, {-8, 38}, {14, 36}, {26, 30}, {34, 14}};
    const auto add = [&](Observation o) {
        o.bearingDeg += bearingNoise(rng);
        return sut.add(o).has_value();
    };
    const auto near = [&scene](const Snapshot& s, const Eigen::Vector2d& at, double radius) {
        std::vector<ObjectEstimate> out;
        for (const ObjectEstimate& o : ofClass(s, OoiClass::Static)) {
            if ((scene.local(o) - at).norm() < radius) {
                out.push_back(o);
            }
        }
        return out;
    };
    SplitTrace trace;
    const auto problem = [&trace](double t, const std::string& what) {
        trace.problems.push_back("t " + std::to_string(t) + ": " + what);
    };
    const Eigen::Vector2d middle = (a + b) / 2.0;
    for (int step = 0; step < 1800; ++step) {
        const double t = step * 0.5;
        const bool bInstant = step % 2 == 1;
        if (bInstant && bFirst && !add(scene.see(t, "ugv-2", "b", OoiClass::Static, two, b, -4.0))) {
            problem(t, "add");
        }
        if (!add(scene.see(t, "ugv-1", "a", OoiClass::Static, one, a, 4.0)) ||
            (!bInstant && (!bFirst || t >= 10.0) && !add(scene.see(t, "ugv-2", "a", OoiClass::Static, two, a, -4.0))) ||
            (bInstant && !bFirst && !add(scene.see(t, "ugv-2", "b", OoiClass::Static, two, b, -4.0)))) {
            problem(t, "add");
        }
        for (std::size_t i = 0; i < shared.size(); ++i) {
            if (!add(scene.see(t, "ugv-1", "s" + std::to_string(i), OoiClass::Static, one, shared[i], 4.0)) ||
                !add(scene.see(t, "ugv-2", "s" + std::to_string(i), OoiClass::Static, two, shared[i], -4.0))) {
                problem(t, "add");
            }
        }
        if (step % 10 != 9) {
            continue;
        }
        const Snapshot s = snapshotAt(sut, t);
        const auto pair = near(s, middle, 6.0);
        if (t < 120.0) { // before the first solve: one object for both posts
            if (pair.size() != 1) {
                problem(t, std::to_string(pair.size()) + " objects before the first solve");
            } else if (trace.published.empty()) {
                trace.published = pair[0].id;
            } else if (pair[0].id != trace.published) {
                problem(t, "id " + pair[0].id + " instead of " + trace.published);
            }
            continue;
        }
        if (pair.size() == 2) {
            // Which is which: the assignment of the two objects to the two posts with the smaller total distance.
            const auto d = [&scene, &pair](std::size_t i, const Eigen::Vector2d& at) {
                return (scene.local(pair[i]) - at).norm();
            };
            const std::size_t atA = d(0, a) + d(1, b) <= d(1, a) + d(0, b) ? 0 : 1;
            const std::string& idA = pair[atA].id;
            const std::string& idB = pair[1 - atA].id;
            if (trace.splitT < 0.0) {
                trace.splitT = t;
                trace.firstSplitId = idB;
            }
            if (idA != trace.published) {
                problem(t, "the object at A is " + idA + ", published as " + trace.published);
            }
            if (idB != trace.firstSplitId) {
                problem(t, "the object at B is " + idB + ", was " + trace.firstSplitId);
            }
        } else if (trace.splitT >= 0.0) {
            problem(t, std::to_string(pair.size()) + " objects after the split");
        } else if (pair.size() != 1 || pair[0].id != trace.published) {
            problem(t, std::to_string(pair.size()) + " objects (" + (pair.empty() ? "" : pair[0].id) + ") where " +
                           trace.published + " was published");
        }
        trace.last = pair;
    }
    return trace;
}

void expectSplitKeepingTheIdAtA(const SplitTrace& trace)
{
    const Scene scene;
    for (std::size_t i = 0; i < std::min<std::size_t>(trace.problems.size(), 5); ++i) {
        ADD_FAILURE() << trace.problems[i];
    }
    EXPECT_TRUE(trace.problems.empty()) << trace.problems.size() << " problems";
    ASSERT_FALSE(trace.published.empty());
    EXPECT_GE(trace.splitT, 120.0);
    // By the third solve: while the solves still move the heading estimates, the part at B may be a duplicate the
    // pose errors made (nothing tells them apart), so it is not shown before they settle.
    EXPECT_LE(trace.splitT, 370.0);
    ASSERT_EQ(trace.last.size(), 2U);
    const bool firstIsA = (scene.local(trace.last[0]) - kPostA).norm() < (scene.local(trace.last[1]) - kPostA).norm();
    const ObjectEstimate& atA = trace.last[firstIsA ? 0 : 1];
    const ObjectEstimate& atB = trace.last[firstIsA ? 1 : 0];
    EXPECT_LT((scene.local(atA) - kPostA).norm(), 0.5);
    EXPECT_LT((scene.local(atB) - kPostB).norm(), 0.5);
    EXPECT_EQ(atA.id, trace.published); // the larger part (two tracks) keeps the id
    EXPECT_NE(atB.id, trace.published);
    EXPECT_EQ(atB.id, trace.firstSplitId);
    EXPECT_GT(atA.observations, atB.observations);
    EXPECT_EQ(atA.ugvs, (std::vector<std::string>{"ugv-1", "ugv-2"}));
    EXPECT_EQ(atB.ugvs, (std::vector<std::string>{"ugv-2"}));
}

TEST(PoseCorrectedCorrelator, AClosePairAssociatedWhileTheHeadingErrorsWereUnknownSplitsAndTheLargerPartKeepsTheId)
{
    expectSplitKeepingTheIdAtA(runClosePair(false));
}

TEST(PoseCorrectedCorrelator, ASplitKeepsTheIdForTheLargerPartEvenWhenTheSmallerFoundedTheObject)
{
    expectSplitKeepingTheIdAtA(runClosePair(true));
}

/// The close pair of runClosePair, but ugv-2 sees B and A at the same instants (B first): its two tracks are two
/// objects, so its A never joins the object its B joined, however close the unknown heading errors put them.
TEST(PoseCorrectedCorrelator, AClosePairOneUgvSeesAtOneInstantIsNeverOneObject)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    const Eigen::Vector2d one(-10, 0);
    const Eigen::Vector2d two(10, 0);
    const Eigen::Vector2d middle = (kPostA + kPostB) / 2.0;
    std::size_t fewest = 99;
    for (int step = 0; step < 480; ++step) {
        const double t = step * 0.5;
        ASSERT_TRUE(sut.add(scene.see(t, "ugv-2", "b", OoiClass::Static, two, kPostB, -4.0)).has_value());
        ASSERT_TRUE(sut.add(scene.see(t, "ugv-1", "a", OoiClass::Static, one, kPostA, 4.0)).has_value());
        ASSERT_TRUE(sut.add(scene.see(t, "ugv-2", "a", OoiClass::Static, two, kPostA, -4.0)).has_value());
        if (step < 10 || step % 10 != 9) {
            continue;
        }
        std::size_t near = 0;
        for (const ObjectEstimate& o : snapshotAt(sut, t).objects) {
            near += (scene.local(o) - middle).norm() < 6.0 ? 1U : 0U;
        }
        fewest = std::min(fewest, near);
    }
    EXPECT_EQ(fewest, 2U);
}

} // namespace
} // namespace ugv::correlator

#include "ugv/correlator/scenario.hpp"

namespace ugv::correlator {
namespace {

/// Mode pose-corrected over a generated clean scenario of `config`'s sensor (600 s, seed 1).
PoseCorrectedCorrelator runOn(const ScenarioConfig& config)
{
    auto scenario = generateScenario(config);
    EXPECT_TRUE(scenario.has_value());
    PoseCorrectedCorrelator sut;
    for (const Message& m : scenario.value().messages) {
        (void)sut.add(m);
    }
    return sut;
}

TEST(PoseCorrectedCorrelator, LearnsEachUgvsNoiseFromItsResidualsAndWidensOnlyWithWhatIsMeasured)
{
    ScenarioConfig noisy = scenarioPreset(ScenarioSetting::Clean);
    noisy.bearingSigmaDeg = 3.0; // 3x the configured 1 deg
    noisy.rangeSigmaM = 0.3;     // 3x the configured 0.1 m + 1 %
    noisy.rangeSigmaFraction = 0.03;
    const ScenarioConfig asConfigured = scenarioPreset(ScenarioSetting::Clean);

    const PoseCorrectedCorrelator wide = runOn(noisy);
    const PoseCorrectedCorrelator tight = runOn(asConfigured);

    for (const char* ugv : {"ugv-1", "ugv-3", "ugv-5"}) {
        const auto measured = wide.noiseScale(ugv);
        ASSERT_TRUE(measured.has_value());
        EXPECT_GT(measured->bearing, 2.0) << ugv;
        EXPECT_LT(measured->bearing, 4.0) << ugv;
        EXPECT_GT(measured->range, 2.0) << ugv;
        EXPECT_LT(measured->range, 4.0) << ugv;
        const auto configured = tight.noiseScale(ugv);
        ASSERT_TRUE(configured.has_value());
        EXPECT_LT(configured->bearing, 1.5) << ugv;
        EXPECT_LT(configured->range, 1.5) << ugv;
        EXPECT_GE(configured->bearing, 1.0) << ugv; // never below the configured model
        EXPECT_GE(configured->range, 1.0) << ugv;
    }
    EXPECT_FALSE(wide.noiseScale("ugv-9").has_value());
}

} // namespace
} // namespace ugv::correlator

namespace ugv::correlator {
namespace {

/// ugv-1 sees a post from t = 0 with track "a". At t = 30 s its track UUID churns: the new track "a2" starts with
/// an outlier (range 4 m long), outside the gate of the post's object, so a second object is made; its later
/// (exact) readings pull it onto the post. Until the next merge (the solve at 120 s) it is a duplicate: not shown,
/// the post keeps its first id. A second post 4 m away, seen apart, is shown as its own object all along.
TEST(PoseCorrectedCorrelator, ADuplicateUnderAChurnedTrackIsNotShownBeforeItMergesAndTheOlderIdStays)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    const Eigen::Vector2d post(0, 20);
    const Eigen::Vector2d neighbour(4, 20);
    std::string firstId;
    std::size_t mostShown = 0;
    for (int step = 0; step < 220; ++step) {
        const double t = step * 0.5;
        ASSERT_TRUE(sut.add(scene.see(t, "ugv-1", "n", OoiClass::Static, {0, 0}, neighbour)).has_value());
        Observation o = scene.see(t, "ugv-1", t < 30.0 ? "a" : "a2", OoiClass::Static, {0, 0}, post);
        if (t == 30.0) {
            o.rangeM += 4.0;
        }
        ASSERT_TRUE(sut.add(o).has_value());
        const Snapshot s = snapshotAt(sut, t);
        mostShown = std::max(mostShown, s.objects.size());
        for (const ObjectEstimate& e : s.objects) {
            if ((scene.local(e) - post).norm() < 1.5) {
                if (firstId.empty()) {
                    firstId = e.id;
                }
                EXPECT_EQ(e.id, firstId) << "t " << t;
            }
        }
    }
    EXPECT_FALSE(firstId.empty());
    EXPECT_EQ(mostShown, 2U);
    EXPECT_EQ(snapshotAt(sut, 110).objects.size(), 2U);
}

/// Before any solve ugv-2's unknown 10 deg heading error puts the post 3.5 m from ugv-1's reading, and its first
/// reading is an outlier (range 15 m long), outside the gate: ugv-2's track makes a second object. Its estimate
/// is certain enough for the merge gate to keep them apart, but not once the UGVs' unknown pose errors are
/// counted: it may be the same post, so it is not shown and the post keeps one id.
TEST(PoseCorrectedCorrelator, AnObjectThePoseErrorsMayHaveDoubledIsNotShownBesideTheOlderOne)
{
    const Scene scene;
    PoseCorrectedCorrelator sut;
    const Eigen::Vector2d post(0, 20);
    std::string firstId;
    std::size_t mostNear = 0;
    for (int step = 0; step < 200; ++step) {
        const double t = step * 0.5;
        ASSERT_TRUE(sut.add(scene.see(t, "ugv-1", "a", OoiClass::Static, {0, 0}, post)).has_value());
        if (t >= 5.0) {
            Observation o = scene.see(t, "ugv-2", "b", OoiClass::Static, {0, 0}, post, 10.0);
            o.rangeM += t == 5.0 ? 15.0 : 0.0;
            ASSERT_TRUE(sut.add(o).has_value());
        }
        std::size_t near = 0;
        for (const ObjectEstimate& e : snapshotAt(sut, t).objects) {
            if ((scene.local(e) - post).norm() < 6.0) {
                firstId = firstId.empty() ? e.id : firstId;
                EXPECT_EQ(e.id, firstId) << "t " << t;
                ++near;
            }
        }
        mostNear = std::max(mostNear, near);
    }
    EXPECT_EQ(mostNear, 1U);
}

} // namespace
} // namespace ugv::correlator
