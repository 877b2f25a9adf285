#include "ugv/vision/obstacle_detector.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "alloc_counter.hpp"
#include "test_rig.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::vision {
namespace {

using ugv::test::kRigProjection;
constexpr Rect kDetectorRoi{0, 232, 640, 248}; // Rectifier default ROI for 640x480 (top fraction 0.5, margin 8)
const GroundPlane kDetectorGround = GroundPlane::fromMount(Mount{0.59, 0.0, 0.0});

ObstacleDetector makeDetector()
{
    auto result = ObstacleDetector::create(DetectorConfig{}, kRigProjection, kDetectorRoi, kDetectorGround);
    EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().message());
    return std::move(result).value();
}

sim::RenderResult renderDetectorScene(const char* name, double rangeM, double bearingDeg, std::uint64_t seed = 11)
{
    auto scene = sim::makeScene(name, rangeM, bearingDeg, sim::GroundTexture::Asphalt, seed);
    EXPECT_TRUE(scene.has_value());
    auto result = sim::render(scene.value());
    EXPECT_TRUE(result.has_value());
    return std::move(result).value();
}

ConstImageViewU8 detectorRoiView(const cv::Mat& image)
{
    return {image.ptr<std::uint8_t>(kDetectorRoi.y), image.cols, kDetectorRoi.height,
            static_cast<std::ptrdiff_t>(image.step[0])};
}

void expectAllUnknown(const ObstacleSectors& s)
{
    ASSERT_EQ(s.count, 64);
    for (int i = 0; i < s.count; ++i) {
        EXPECT_EQ(s.sectors[static_cast<std::size_t>(i)].state, SectorState::Unknown) << i;
        EXPECT_EQ(s.sectors[static_cast<std::size_t>(i)].danger, DangerClass::Unknown) << i;
    }
}

TEST(ObstacleDetector, CreateRejectsInvalidSetup)
{
    DetectorConfig badMargin;
    badMargin.marginRows = kDetectorRoi.height;
    DetectorConfig badMatcher;
    badMatcher.matcher.numDisparities = 20;

    EXPECT_FALSE(ObstacleDetector::create(badMargin, kRigProjection, kDetectorRoi, kDetectorGround).has_value());
    EXPECT_FALSE(ObstacleDetector::create(badMatcher, kRigProjection, kDetectorRoi, kDetectorGround).has_value());
    EXPECT_FALSE(ObstacleDetector::create(DetectorConfig{}, kRigProjection, kDetectorRoi, GroundPlane{}).has_value());
}

TEST(ObstacleDetector, DetectsPolesInTheRightSectorWithinRangeTolerance)
{
    auto sut = makeDetector();
    for (const double rangeM : {2.0, 4.0, 6.0, 8.0}) {
        for (const double bearingDeg : {0.0, -12.0}) {
            const auto frame = renderDetectorScene("pole", rangeM, bearingDeg);

            const ObstacleSectors& out = sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 5U, 77);

            ASSERT_EQ(sut.status(), DetectorStatus::Ok);
            EXPECT_EQ(out.sequence, 5U);
            EXPECT_EQ(out.captureStampNs, 77);
            // The nearest obstacle among the sectors that the ground truth marks as obstacle.
            float nearest = std::numeric_limits<float>::infinity();
            int gtObstacles = 0;
            for (int i = 0; i < out.count; ++i) {
                if (frame.sectors.sectors[static_cast<std::size_t>(i)].state != SectorState::Obstacle) {
                    continue;
                }
                ++gtObstacles;
                const Sector& got = out.sectors[static_cast<std::size_t>(i)];
                if (got.state == SectorState::Obstacle && got.kind == ObstacleKind::Positive) {
                    nearest = std::min(nearest, got.rangeM);
                }
            }
            ASSERT_GT(gtObstacles, 0);
            const double tolerance = std::max(0.10, 0.03 * rangeM);
            std::printf("[ MEASURED ] pole %.0f m at %+.0f deg: range %.3f m, error %+.3f m (tolerance %.2f)\n", rangeM,
                        bearingDeg, nearest, nearest - rangeM, tolerance);
            EXPECT_NEAR(nearest, rangeM, tolerance) << rangeM << " m, " << bearingDeg << " deg";
        }
    }
}

TEST(ObstacleDetector, EmptyGroundHasNoRedOrBlueSectors)
{
    auto sut = makeDetector();
    for (const sim::GroundTexture texture : {sim::GroundTexture::Asphalt, sim::GroundTexture::Grass}) {
        auto scene = sim::makeScene("empty", 5.0, 0.0, texture, 5);
        ASSERT_TRUE(scene.has_value());
        const auto frame = sim::render(scene.value()).value();

        const ObstacleSectors& out = sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 1U, 0);

        int clear = 0;
        for (int i = 0; i < out.count; ++i) {
            const Sector& s = out.sectors[static_cast<std::size_t>(i)];
            EXPECT_NE(s.danger, DangerClass::Red) << i;
            EXPECT_NE(s.danger, DangerClass::Blue)
                << i << " kind " << static_cast<int>(s.kind) << " range " << s.rangeM << " conf " << s.confidence;
            clear += s.state == SectorState::Clear ? 1 : 0;
        }
        std::printf("[ MEASURED ] empty ground (texture %d): %d of %d sectors clear\n", static_cast<int>(texture),
                    clear, out.count);
        EXPECT_GE(clear, out.count / 2);
    }
}

TEST(ObstacleDetector, MatcherFillInAtTheHorizonIsNotAnObstacle)
{
    // Before the obstacle verifier these empty scenes gave red/blue sectors at 1.4 to 1.8 m: StereoSGBM filled the
    // weakly textured rows at the horizon with a near disparity (a "0.59 m tall object").
    struct Case {
        sim::GroundTexture texture;
        std::uint64_t seed;
    };
    constexpr Case kCases[] = {{sim::GroundTexture::Asphalt, 8},
                               {sim::GroundTexture::Grass, 7},
                               {sim::GroundTexture::Gravel, 3},
                               {sim::GroundTexture::Gravel, 9}};
    auto sut = makeDetector();
    for (const Case& c : kCases) {
        auto scene = sim::makeScene("empty", 5.0, 0.0, c.texture, c.seed);
        ASSERT_TRUE(scene.has_value());
        const auto frame = sim::render(scene.value()).value();

        const ObstacleSectors& out = sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 1U, 0);

        for (int i = 0; i < out.count; ++i) {
            const Sector& s = out.sectors[static_cast<std::size_t>(i)];
            EXPECT_NE(s.state, SectorState::Obstacle) << "texture " << static_cast<int>(c.texture) << " seed " << c.seed
                                                      << " sector " << i << " range " << s.rangeM;
        }
        EXPECT_GT(sut.verifier().counts().rejected, 0);
    }
}

TEST(ObstacleDetector, SpeedBumpPitchIsTrackedFromTheFirstFrame)
{
    // The vehicle pitches 3 degrees down (front wheels over a bump) while the config says level: the ground
    // used for this frame's sectors must be this frame's ground, not a lagging average.
    // (False red/blue sectors on empty ground from SGBM mismatch blobs are measured by `ugvsense eval`; they are
    // the same with and without the pitch step and are not asserted here.)
    auto sut = makeDetector();
    auto scene = sim::makeScene("empty", 5.0, 0.0, sim::GroundTexture::Asphalt, 8);
    ASSERT_TRUE(scene.has_value());
    scene->rig.pitchDeg = 3.0;
    const auto frame = sim::render(scene.value()).value();

    const ObstacleSectors& out = sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 1U, 0);

    ASSERT_EQ(sut.status(), DetectorStatus::Ok);
    EXPECT_TRUE(sut.groundEstimate().reliable);
    EXPECT_NEAR(sut.ground().pitchDeg(), 3.0, 0.3);
    EXPECT_NEAR(sut.ground().heightM, 0.59, 0.02);
    int clear = 0;
    for (int k = 0; k < out.count; ++k) {
        clear += out.sectors[static_cast<std::size_t>(k)].state == SectorState::Clear ? 1 : 0;
    }
    EXPECT_GE(clear, out.count * 3 / 4); // with a lagging level ground nearly every sector turned blue
}

TEST(ObstacleDetector, MismatchLabelsMarkThePoleOnTheLeftGrid)
{
    auto sut = makeDetector();
    const auto frame = renderDetectorScene("pole", 4.0, 0.0);

    (void)sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 1U, 0);

    const ConstImageViewU8 labels = sut.labels();
    ASSERT_EQ(labels.width(), kDetectorRoi.width);
    int positive = 0;
    int onPole = 0;
    for (int y = 0; y < labels.height(); ++y) {
        for (int x = 0; x < labels.width(); ++x) {
            if (labels.at(x, y) == static_cast<std::uint8_t>(GroundLabel::Positive)) {
                ++positive;
                const auto truth = static_cast<sim::Label>(frame.labels.at<std::uint8_t>(kDetectorRoi.y + y, x));
                onPole += truth == sim::Label::Positive ? 1 : 0;
            }
        }
    }
    std::printf("[ MEASURED ] pole at 4 m: %d positive labels on the left grid, %d on the pole\n", positive, onPole);
    EXPECT_GT(positive, 20);
    EXPECT_GT(onPole, positive * 6 / 10);
}

/// A clock that ticks once per read: each lap of a stage then adds exactly 1, so the counts tell which stage boundary
/// was passed how often.
std::int64_t ticks = 0;
std::int64_t tickingClock() noexcept
{
    return ++ticks;
}

TEST(ObstacleDetector, EveryStageIsTimedWithTheClockItIsGivenAndNoneWithout)
{
    auto sut = makeDetector();
    const auto frame = renderDetectorScene("pole", 4.0, 0.0);
    (void)sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 1U, 0);
    EXPECT_EQ(sut.stageTimes().totalNs(), 0); // no clock given: vision reads none

    sut.setStageClock(&tickingClock);
    (void)sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 2U, 0);

    const VisionStageTimes& t = sut.stageTimes();
    for (const VisionStage once :
         {VisionStage::MatchOther, VisionStage::Census, VisionStage::Speckle, VisionStage::Ground, VisionStage::Warp,
          VisionStage::Mismatch, VisionStage::Verify, VisionStage::Sectors}) {
        EXPECT_EQ(t[once], 1) << stageName(once);
    }
    for (const VisionStage perRow : {VisionStage::Cost, VisionStage::Aggregate, VisionStage::LeftRight}) {
        EXPECT_EQ(t[perRow], kDetectorRoi.height) << stageName(perRow); // the census matcher's row loop
    }

    (void)sut.processGroundOnly(detectorRoiView(frame.left), detectorRoiView(frame.right), 3U, 0); // the overload path
    EXPECT_EQ(sut.stageTimes()[VisionStage::Warp], 1);
    EXPECT_EQ(sut.stageTimes()[VisionStage::Mismatch], 1);
    EXPECT_EQ(sut.stageTimes()[VisionStage::Sectors], 1);
    EXPECT_EQ(sut.stageTimes().totalNs(), 3);
}

TEST(ObstacleDetector, BlackSaturatedAndTexturelessFramesAreUnknown)
{
    auto sut = makeDetector();
    for (const int grey : {0, 128, 255}) {
        const cv::Mat flat(480, 640, CV_8UC1, cv::Scalar(grey));

        const ObstacleSectors& out = sut.process(detectorRoiView(flat), detectorRoiView(flat), 3U, 0);

        EXPECT_EQ(sut.status(), DetectorStatus::Ok);
        expectAllUnknown(out);
    }
}

TEST(ObstacleDetector, WrongSizeGivesErrorStatusAndAllUnknown)
{
    auto sut = makeDetector();
    const auto frame = renderDetectorScene("empty", 5.0, 0.0);
    (void)sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 1U, 0);
    const cv::Mat small(100, 320, CV_8UC1, cv::Scalar(90));

    const ObstacleSectors& out =
        sut.process(ConstImageViewU8(small.data, small.cols, small.rows), detectorRoiView(frame.right), 2U, 9);

    EXPECT_EQ(sut.status(), DetectorStatus::WrongInputSize);
    EXPECT_TRUE(out.degraded);
    EXPECT_EQ(out.sequence, 2U);
    expectAllUnknown(out);
    (void)sut.process(detectorRoiView(frame.left), ConstImageViewU8{}, 3U, 9);
    EXPECT_EQ(sut.status(), DetectorStatus::WrongInputSize);
}

/// A detector made over a rectifier with roiRectifierConfig runs on that rectifier's ROI, whatever the top fraction
/// and margin: its pole is found, and an ROI of the default size no longer fits it.
TEST(ObstacleDetector, ADetectorOverARectifierRunsOnThatRectifiersRoi)
{
    DetectorConfig config;
    config.marginRows = 12;
    const StereoCalibration calib =
        makeRectifiedCalibration(cv::Size(640, 480), kRigProjection.fx, kRigProjection.fy, kRigProjection.cx,
                                 kRigProjection.cy, kRigProjection.baselineM);
    auto rectifier = Rectifier::create(calib, roiRectifierConfig(config, 0.6)).value();
    ASSERT_EQ(rectifier.roi().y, 288 - 12);
    ASSERT_EQ(rectifier.roi().height, 480 - 276);
    auto sut = ObstacleDetector::create(config, rectifier, kDetectorGround).value();
    const auto frame = renderDetectorScene("pole", 4.0, 0.0);
    const auto view = [](const cv::Mat& image) { return ConstImageViewU8(image.data, image.cols, image.rows); };

    ASSERT_EQ(rectifier.rectify(view(frame.left), view(frame.right)), RectifyStatus::Ok);
    const ObstacleSectors& out = sut.process(rectifier.rectifiedLeft(), rectifier.rectifiedRight(), 1U, 0);

    ASSERT_EQ(sut.status(), DetectorStatus::Ok);
    int found = 0;
    for (int i = 0; i < out.count; ++i) {
        const Sector& got = out.sectors[static_cast<std::size_t>(i)];
        found += frame.sectors.sectors[static_cast<std::size_t>(i)].state == SectorState::Obstacle &&
                 got.state == SectorState::Obstacle && std::abs(got.rangeM - 4.0F) < 0.5F;
    }
    EXPECT_GT(found, 0);
    (void)sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 2U, 0);
    EXPECT_EQ(sut.status(), DetectorStatus::WrongInputSize);
}

/// 300 frames through the default detector (census SGM): zero allocations. With an OpenCV mode, everything
/// but cv::StereoSGBM::compute() is allocation-free: the detector's count equals the bare StereoSGBM count on
/// the same frames (documented in roi_matcher.hpp).
TEST(ObstacleDetector, ThreeHundredFramesAllocateNothing)
{
    const auto a = renderDetectorScene("pole", 3.0, 5.0);
    const auto b = renderDetectorScene("box", 4.0, -8.0);
    // 300 frames of the default matcher; for an OpenCV mode 60 frames show the equality (a long sanitizer run
    // otherwise).
    int frames = 300;
    const auto countFrames = [&](auto&& step) {
        const test::AllocationScope scope;
        for (int i = 0; i < frames; ++i) {
            const auto& frame = i % 2 == 0 ? a : b;
            step(frame, i);
        }
        return scope.count();
    };
    for (const auto& [mode, ranged] :
         {std::pair{MatcherMode::CensusSgm, false}, std::pair{MatcherMode::CensusSgm, true},
          std::pair{MatcherMode::Sgbm3Way, false}}) {
        frames = mode == MatcherMode::CensusSgm ? 300 : 60;
        DetectorConfig config;
        config.matcher.mode = mode;
        config.matcher.groundRange = ranged;
        auto sut = ObstacleDetector::create(config, kRigProjection, kDetectorRoi, kDetectorGround).value();
        auto matcher = RoiMatcher::create(config.matcher, cv::Size(kDetectorRoi.width, kDetectorRoi.height)).value();
        (void)sut.process(detectorRoiView(a.left), detectorRoiView(a.right), 0U, 0);
        (void)matcher.match(detectorRoiView(a.left), detectorRoiView(a.right));

        const std::size_t detectorAllocations = countFrames([&](const sim::RenderResult& frame, int i) {
            (void)sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), static_cast<std::uint64_t>(i),
                              i);
        });
        const std::size_t matcherAllocations = countFrames([&](const sim::RenderResult& frame, int) {
            (void)matcher.match(detectorRoiView(frame.left), detectorRoiView(frame.right));
        });

        std::printf("[ MEASURED ] matcher mode %d%s, %d frames: detector %zu allocations (%.1f per frame), bare "
                    "matcher %zu\n",
                    static_cast<int>(mode), ranged ? " ranged" : "", frames, detectorAllocations,
                    static_cast<double>(detectorAllocations) / frames, matcherAllocations);
        EXPECT_EQ(sut.status(), DetectorStatus::Ok);
        EXPECT_EQ(detectorAllocations, matcherAllocations);
        if (mode == MatcherMode::CensusSgm) {
            EXPECT_EQ(detectorAllocations, 0U);
        }
    }
}

} // namespace
} // namespace ugv::vision

namespace ugv::vision {
namespace {

/// The nearest range reported in the sectors the ground truth marks as obstacle (+inf when none).
float nearestInTruthSectors(const ObstacleSectors& got, const ObstacleSectors& truth)
{
    float nearest = std::numeric_limits<float>::infinity();
    for (int i = 0; i < got.count; ++i) {
        const auto k = static_cast<std::size_t>(i);
        if (truth.sectors[k].state == SectorState::Obstacle && got.sectors[k].state == SectorState::Obstacle) {
            nearest = std::min(nearest, got.sectors[k].rangeM);
        }
    }
    return nearest;
}

TEST(ObstacleDetector, GroundRangeFollowsThePreviousFramesReliableGround)
{
    DetectorConfig config;
    config.matcher.groundRange = true;
    auto sut = ObstacleDetector::create(config, kRigProjection, kDetectorRoi, kDetectorGround).value();
    const auto frame = renderDetectorScene("pole", 4.0, 0.0);

    const ObstacleSectors first = sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 1U, 0);
    const double firstSearched = sut.searchedFraction();
    const bool reliable = sut.groundEstimate().reliable;
    const ObstacleSectors second = sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 2U, 0);
    const double secondSearched = sut.searchedFraction();
    (void)sut.processGroundOnly(detectorRoiView(frame.left), detectorRoiView(frame.right), 3U, 0);
    (void)sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 4U, 0);
    const double afterGroundOnly = sut.searchedFraction();

    std::printf("[ MEASURED ] pole at 4 m, default rig: %.1f %% of the cost cells searched with the ground range; "
                "nearest %.3f m (full range %.3f m)\n",
                100.0 * secondSearched, nearestInTruthSectors(second, frame.sectors),
                nearestInTruthSectors(first, frame.sectors));
    EXPECT_EQ(firstSearched, 1.0); // no previous frame: the full range
    ASSERT_TRUE(reliable);
    EXPECT_LT(secondSearched, 0.9);
    EXPECT_GT(secondSearched, 0.5);
    EXPECT_EQ(afterGroundOnly, 1.0); // the ground-only frame has no estimate: the full range again
    EXPECT_NEAR(nearestInTruthSectors(second, frame.sectors), 4.0, 0.12);
}

TEST(ObstacleDetector, NearRowsAtHalfResolutionFromTheConfiguredGroundsDisparity)
{
    // The default rig's ground reaches 48 px of disparity at image row 334 (3.4 m): ROI rows 102..247, 146 rows,
    // are matched at half resolution, so (248 - 146 + 8 + (146 + 8) / 8) / 248 of the cost cells are searched.
    DetectorConfig config;
    config.halfResolutionMinGroundPx = 48.0;
    auto sut = ObstacleDetector::create(config, kRigProjection, kDetectorRoi, kDetectorGround).value();
    for (const double rangeM : {2.0, 4.0}) {
        const auto frame = renderDetectorScene("pole", rangeM, 0.0);
        const ObstacleSectors& out = sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 1U, 0);
        ASSERT_EQ(sut.status(), DetectorStatus::Ok);
        const double nearest = nearestInTruthSectors(out, frame.sectors);
        std::printf("[ MEASURED ] pole %.0f m, near rows at half resolution: range %.3f m\n", rangeM, nearest);
        EXPECT_NEAR(nearest, rangeM, std::max(0.10, 0.03 * rangeM));
    }
    EXPECT_NEAR(sut.searchedFraction(), (248.0 - 146.0 + 8.0 + (146.0 + 8.0) / 8.0) / 248.0, 1e-9);

    const auto frame = renderDetectorScene("pole", 3.0, 0.0);
    const test::AllocationScope scope;
    for (int i = 0; i < 20; ++i) {
        (void)sut.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 2U + static_cast<std::uint64_t>(i),
                          0);
    }
    EXPECT_EQ(scope.count(), 0U);

    DetectorConfig negative;
    negative.halfResolutionMinGroundPx = -1.0;
    EXPECT_FALSE(ObstacleDetector::create(negative, kRigProjection, kDetectorRoi, kDetectorGround).has_value());
    DetectorConfig none; // a threshold no row reaches: every row at full resolution
    none.halfResolutionMinGroundPx = 500.0;
    auto full = ObstacleDetector::create(none, kRigProjection, kDetectorRoi, kDetectorGround).value();
    (void)full.process(detectorRoiView(frame.left), detectorRoiView(frame.right), 1U, 0);
    EXPECT_EQ(full.searchedFraction(), 1.0);
}

TEST(ObstacleDetector, GroundOnlyPathFindsObstaclesIsNeverClearAndIsFlaggedDegraded)
{
    auto sut = makeDetector();
    for (const char* name : {"box", "pole", "barrier"}) {
        for (const double rangeM : {2.0, 4.0}) {
            const auto frame = renderDetectorScene(name, rangeM, 5.0);

            const ObstacleSectors& out =
                sut.processGroundOnly(detectorRoiView(frame.left), detectorRoiView(frame.right), 9U, 3);

            ASSERT_EQ(sut.status(), DetectorStatus::Ok);
            EXPECT_TRUE(out.degraded);
            EXPECT_EQ(out.sequence, 9U);
            const float nearest = nearestInTruthSectors(out, frame.sectors);
            EXPECT_NEAR(nearest, rangeM, 0.10 * rangeM) << name << " at " << rangeM << " m";
            for (int i = 0; i < out.count; ++i) {
                EXPECT_NE(out.sectors[static_cast<std::size_t>(i)].state, SectorState::Clear) << name << " " << i;
            }
        }
    }
    // Empty ground: nothing red or blue.
    const auto empty = renderDetectorScene("empty", 5.0, 0.0);
    const ObstacleSectors& out =
        sut.processGroundOnly(detectorRoiView(empty.left), detectorRoiView(empty.right), 1U, 0);
    for (int i = 0; i < out.count; ++i) {
        const DangerClass d = out.sectors[static_cast<std::size_t>(i)].danger;
        EXPECT_TRUE(d != DangerClass::Red && d != DangerClass::Blue) << "sector " << i;
    }
}

TEST(ObstacleDetector, GroundOnlyPathAllocatesNothingOverHundredsOfFrames)
{
    auto sut = makeDetector();
    const auto frame = renderDetectorScene("box", 3.0, 0.0);
    (void)sut.processGroundOnly(detectorRoiView(frame.left), detectorRoiView(frame.right), 0U, 0);

    const ugv::test::ThreadAllocationScope scope;
    for (int k = 1; k <= 300; ++k) {
        (void)sut.processGroundOnly(detectorRoiView(frame.left), detectorRoiView(frame.right),
                                    static_cast<std::uint64_t>(k), k);
    }
    EXPECT_EQ(scope.count(), 0U);
}

} // namespace
} // namespace ugv::vision
