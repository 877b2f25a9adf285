#include "ugv/vision/sector_builder.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string_view>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "alloc_counter.hpp"
#include "mat_view.hpp"
#include "test_rig.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"

namespace ugv::vision {
namespace {

using ugv::test::view;
using ugv::test::view16;

using ugv::test::kRigProjection;
constexpr double kHeightM = 0.59;
constexpr Rect kRoi{0, 232, 640, 248};
constexpr int kFirstAnalysedRow = 240;
constexpr double kFb = 546.0 * 0.30;

SectorBuilder makeBuilder(const SectorBuilderConfig& config = {})
{
    auto result = SectorBuilder::create(config, kRigProjection, kRoi, kFirstAnalysedRow);
    EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().message());
    return std::move(result).value();
}

const GroundPlane kGround = GroundPlane::fromMount(Mount{kHeightM, 0.0, 0.0});

/// Disparity x16 of flat ground (level camera) over the ROI; rows at or above the horizon invalid.
cv::Mat groundDisparity()
{
    cv::Mat d16(kRoi.height, kRoi.width, CV_16SC1, cv::Scalar(-16));
    const DisparityPlane plane = kGround.disparityPlane(kRigProjection);
    for (int v = 0; v < kRoi.height; ++v) {
        for (int u = 0; u < kRoi.width; ++u) {
            const double d = plane.at(u, v + kRoi.y);
            if (d > 0.0) {
                d16.at<std::int16_t>(v, u) = static_cast<std::int16_t>(std::lround(d * 16.0));
            }
        }
    }
    return d16;
}

/// Pixel column of a camera-frame lateral offset X [m] (right positive) at depth Z [m].
int column(double xM, double zM)
{
    return static_cast<int>(std::lround(kRigProjection.cx + kRigProjection.fx * xM / zM));
}
/// ROI row of a point at height z [m] above the ground at depth Z [m] (level camera).
int roiRow(double zUp, double zM)
{
    return static_cast<int>(std::lround(kRigProjection.cy + kRigProjection.fy * (kHeightM - zUp) / zM)) - kRoi.y;
}

/// A fronto-parallel box face at depth Z, lateral [x0, x1] (camera X, right positive), from the ground up to top.
void paintFace(cv::Mat& d16, double zM, double x0, double x1, double top)
{
    const auto value = static_cast<std::int16_t>(std::lround(kFb / zM * 16.0));
    for (int v = std::max(0, roiRow(top, zM)); v <= std::min(d16.rows - 1, roiRow(0.0, zM)); ++v) {
        for (int u = std::max(0, column(x0, zM)); u <= std::min(d16.cols - 1, column(x1, zM)); ++u) {
            d16.at<std::int16_t>(v, u) = value;
        }
    }
}

/// Ground `depthM` below the plane, seen at depths [z0, z1] over camera X in [-halfWidth, halfWidth] [m].
void paintSunkenGround(cv::Mat& d16, double depthM, double z0, double z1, double halfWidth)
{
    for (int v = 0; v < d16.rows; ++v) {
        const double dy = v + kRoi.y - kRigProjection.cy;
        const double z = dy > 0.0 ? kRigProjection.fy * (kHeightM + depthM) / dy : 1e9;
        if (z < z0 || z > z1) {
            continue;
        }
        for (int u = column(-halfWidth, z); u <= column(halfWidth, z); ++u) {
            d16.at<std::int16_t>(v, u) = static_cast<std::int16_t>(std::lround(kFb / z * 16.0));
        }
    }
}

int sectorOf(const ObstacleSectors& s, double bearingDeg)
{
    for (int i = 0; i < s.count; ++i) {
        const Sector& sector = s.sectors[static_cast<std::size_t>(i)];
        if (bearingDeg >= sector.bearingMinDeg && bearingDeg < sector.bearingMaxDeg) {
            return i;
        }
    }
    return -1;
}

TEST(SectorBuilder, CreateRejectsInvalidConfigAndGeometry)
{
    SectorBuilderConfig tooManySectors;
    tooManySectors.sectorCount = kMaxSectors + 1;
    SectorBuilderConfig badPercentile;
    badPercentile.rangePercentile = 1.0F;

    EXPECT_FALSE(SectorBuilder::create(tooManySectors, kRigProjection, kRoi, kFirstAnalysedRow).has_value());
    EXPECT_FALSE(SectorBuilder::create(badPercentile, kRigProjection, kRoi, kFirstAnalysedRow).has_value());
    EXPECT_FALSE(SectorBuilder::create({}, kRigProjection, kRoi, kRoi.y - 1).has_value());
    EXPECT_FALSE(SectorBuilder::create({}, RectifiedProjection{}, kRoi, kFirstAnalysedRow).has_value());
}

TEST(SectorBuilder, CreateRejectsInvalidClearRule)
{
    SectorBuilderConfig noClearRange;
    noClearRange.clearRangeM = 0.0F;
    SectorBuilderConfig negativeVotes;
    negativeVotes.minClearFarVotes = -1;

    EXPECT_FALSE(SectorBuilder::create(noClearRange, kRigProjection, kRoi, kFirstAnalysedRow).has_value());
    EXPECT_FALSE(SectorBuilder::create(negativeVotes, kRigProjection, kRoi, kFirstAnalysedRow).has_value());
}

TEST(SectorBuilder, CreateRejectsInvalidDropRule)
{
    const auto rejected = [](void (*set)(SectorBuilderConfig&)) {
        SectorBuilderConfig c;
        set(c);
        return !SectorBuilder::create(c, kRigProjection, kRoi, kFirstAnalysedRow).has_value();
    };
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.minDropDepthM = 0.0F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.minDropGapM = -0.1F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.dropRangePercentile = 1.0F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.minDropSupport = 0; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.dropSupportRangeM = 0.0F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.dropProfileMinRangeM = 0.0F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.dropProfileResidualPx = -1.0F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.dropProfileMinPixels = 0; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.dropEdgeSectors = -1; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.closeGapM = -0.1F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.closeGapM = NAN; }));
    // The local ground and the drop evidence.
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.localGround.binM = 0.0F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.localGround.minPoints = 0; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.minDropShare = 1.5F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.minRimVotes = -1; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.dropNoiseFactor = NAN; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.maxRangeDisparityPx = 0.0F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.maxWallSlope = 0.0F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.wallSlopeSigmas = NAN; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.floorLineTolerance = -0.1F; }));
    EXPECT_TRUE(rejected([](SectorBuilderConfig& c) { c.maxRangeM = 0.01F; })); // not above the range bin
}

TEST(SectorBuilder, FlatGroundIsClearEverywhere)
{
    auto sut = makeBuilder();
    const cv::Mat d16 = groundDisparity();

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 42U, 123456789), BuildStatus::Ok);

    const ObstacleSectors& s = sut.sectors();
    EXPECT_EQ(s.count, 64);
    EXPECT_EQ(s.sequence, 42U);
    EXPECT_EQ(s.captureStampNs, 123456789);
    EXPECT_FALSE(s.degraded);
    EXPECT_NEAR(sut.hfovDeg(), 60.7, 0.05);
    for (int i = 0; i < s.count; ++i) {
        EXPECT_EQ(s.sectors[static_cast<std::size_t>(i)].state, SectorState::Clear) << i;
        EXPECT_EQ(s.sectors[static_cast<std::size_t>(i)].danger, DangerClass::Green) << i;
    }
}

TEST(SectorBuilder, PixelCountsFollowThePixelsAFaceCoversOnTheRig)
{
    // The default rig (640 px, 64 sectors, fy 546 px) is the reference: its counts are the configured ones.
    const SectorBuilderConfig config;
    EXPECT_EQ(makeBuilder(config).config().minSupport, config.minSupport);
    EXPECT_EQ(makeBuilder(config).config().maxStrayVotes, config.maxStrayVotes);

    // KITTI's rig: 1242 px (19.4 columns per sector) and fy 721.5 px, so a face covers 2.56 times the pixels.
    const RectifiedProjection kitti{721.5, 721.5, 620.5, 187.5, 0.54};
    auto result = SectorBuilder::create(config, kitti, Rect{0, 188, 1242, 187}, 200);
    ASSERT_TRUE(result.has_value()) << result.error().message();
    const double scale = 1242.0 / 64.0 / 10.0 * 721.5 / 546.0;
    const SectorBuilderConfig& scaled = result.value().config();
    EXPECT_EQ(scaled.minSupport, std::lround(config.minSupport * scale));
    EXPECT_EQ(scaled.minFaceSupport, std::lround(config.minFaceSupport * scale));
    EXPECT_EQ(scaled.minTallVotes, std::lround(config.minTallVotes * scale));
    EXPECT_EQ(scaled.minDropSupport, std::lround(config.minDropSupport * scale));
    EXPECT_EQ(scaled.minClearFarVotes, std::lround(config.minClearFarVotes * scale));

    // A coarse rig (320 px, fy 273 px) needs a quarter, never less than one.
    const RectifiedProjection coarse{273.0, 273.0, 159.5, 119.5, 0.30};
    auto small = SectorBuilder::create(config, coarse, Rect{0, 116, 320, 124}, 120);
    ASSERT_TRUE(small.has_value()) << small.error().message();
    EXPECT_EQ(small.value().config().minSupport, config.minSupport / 4);
    EXPECT_GE(small.value().config().minFarTallVotes, 1);
}

TEST(SectorBuilder, PositiveFaceGivesExactRangeKindHeightAndDanger)
{
    constexpr double kRangeM = 3.0;
    constexpr double kTopM = 0.5;
    auto sut = makeBuilder();
    cv::Mat d16 = groundDisparity();
    paintFace(d16, kRangeM, -0.2, 0.2, kTopM); // straight ahead, 0.4 m wide

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);

    const Sector& ahead = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    EXPECT_EQ(ahead.state, SectorState::Obstacle);
    EXPECT_EQ(ahead.kind, ObstacleKind::Positive);
    EXPECT_NEAR(ahead.rangeM, kRangeM, 0.03);
    EXPECT_NEAR(ahead.heightM, kTopM, 0.05);
    EXPECT_EQ(ahead.danger, DangerClass::Blue);
    EXPECT_GT(ahead.confidence, 0.5F);
    const Sector& side = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 20.0))];
    EXPECT_EQ(side.state, SectorState::Clear);
}

TEST(SectorBuilder, ACurbFarAwayIsAnObstacleThroughItsFaceBelowTheTop)
{
    // A 12 cm curb at 8 m: a row or two of its face are above minHeightM (0.10 m), too few votes for a cluster; the
    // face above half of minHeightM supports it.
    constexpr double kRangeM = 8.0;
    constexpr double kTopM = 0.12;
    cv::Mat d16 = groundDisparity();
    paintFace(d16, kRangeM, -2.0, 2.0, kTopM);
    auto sut = makeBuilder();
    SectorBuilderConfig topOnly;
    topOnly.faceHeightFraction = 1.0F; // only points above minHeightM vote (the rule before face votes)
    auto topOnlySut = makeBuilder(topOnly);

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);
    ASSERT_EQ(topOnlySut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);

    const auto ahead = static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0));
    const Sector& curb = sut.sectors().sectors[ahead];
    EXPECT_EQ(curb.state, SectorState::Obstacle);
    EXPECT_EQ(curb.kind, ObstacleKind::Positive);
    EXPECT_NEAR(curb.rangeM, kRangeM, 0.10);
    EXPECT_NEAR(curb.heightM, kTopM, 0.02);
    EXPECT_NE(topOnlySut.sectors().sectors[ahead].state, SectorState::Obstacle);
}

TEST(SectorBuilder, AFarFaceNeedsFewerVotesThanANearOne)
{
    // A face's rows in a sector shrink with its range: a 12 cm curb at 9 m gives about 40 votes a sector. With
    // minSupport raised to 60 it stands only because beyond faceSupportRangeM (5 m) the support needed falls as
    // 5 / r (to 33 at 9 m); with the scaling moved out of reach it is no obstacle.
    constexpr double kRangeM = 9.0;
    cv::Mat d16 = groundDisparity();
    paintFace(d16, kRangeM, -2.0, 2.0, 0.12);
    SectorBuilderConfig scaled;
    scaled.minSupport = 60;
    SectorBuilderConfig flat = scaled;
    flat.faceSupportRangeM = 100.0F;
    auto scaledSut = makeBuilder(scaled);
    auto flatSut = makeBuilder(flat);

    ASSERT_EQ(scaledSut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);
    ASSERT_EQ(flatSut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);

    const auto ahead = static_cast<std::size_t>(sectorOf(scaledSut.sectors(), 0.0));
    const Sector& curb = scaledSut.sectors().sectors[ahead];
    EXPECT_EQ(curb.state, SectorState::Obstacle);
    EXPECT_EQ(curb.kind, ObstacleKind::Positive);
    EXPECT_NEAR(curb.rangeM, kRangeM, 0.15);
    EXPECT_NE(flatSut.sectors().sectors[ahead].state, SectorState::Obstacle);
}

TEST(SectorBuilder, ABumpBelowMinHeightIsNoObstacleHoweverLarge)
{
    // An 8 cm bump at 4 m: a large face above half of minHeightM, but nothing above minHeightM.
    cv::Mat d16 = groundDisparity();
    paintFace(d16, 4.0, -2.0, 2.0, 0.08);
    auto sut = makeBuilder();

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);

    for (int i = 0; i < sut.sectors().count; ++i) {
        EXPECT_NE(sut.sectors().sectors[static_cast<std::size_t>(i)].state, SectorState::Obstacle) << i;
    }
}

TEST(SectorBuilder, CreateRejectsInvalidFaceRule)
{
    SectorBuilderConfig noFace;
    noFace.faceHeightFraction = 0.0F;
    SectorBuilderConfig faceAboveTop;
    faceAboveTop.faceHeightFraction = 1.5F;
    SectorBuilderConfig noTallVotes;
    noTallVotes.minTallVotes = 0;

    EXPECT_FALSE(SectorBuilder::create(noFace, kRigProjection, kRoi, kFirstAnalysedRow).has_value());
    EXPECT_FALSE(SectorBuilder::create(faceAboveTop, kRigProjection, kRoi, kFirstAnalysedRow).has_value());
    EXPECT_FALSE(SectorBuilder::create(noTallVotes, kRigProjection, kRoi, kFirstAnalysedRow).has_value());
    for (const auto set : {+[](SectorBuilderConfig& c) { c.faceSupportRangeM = 0.0F; },
                           +[](SectorBuilderConfig& c) { c.minFaceSupport = 0; },
                           +[](SectorBuilderConfig& c) { c.minFarTallVotes = 0; }}) {
        SectorBuilderConfig c;
        set(c);
        EXPECT_FALSE(SectorBuilder::create(c, kRigProjection, kRoi, kFirstAnalysedRow).has_value());
    }
}

TEST(SectorBuilder, NegativeFloorGivesNegativeKind)
{
    // The floor of a trench 0.3 m deep, seen from 4 m to 5 m straight ahead.
    constexpr double kDepthM = 0.3;
    auto sut = makeBuilder();
    cv::Mat d16 = groundDisparity();
    paintSunkenGround(d16, kDepthM, 4.0, 5.0, 0.5);

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);

    const Sector& ahead = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    EXPECT_EQ(ahead.state, SectorState::Obstacle);
    EXPECT_EQ(ahead.kind, ObstacleKind::Negative);
    // The range of a drop is its near rim: the ray that sees the floor at 4 m crosses the ground at 4 h / (h + depth).
    EXPECT_NEAR(ahead.rangeM, 4.0 * kHeightM / (kHeightM + kDepthM), 0.12);
    EXPECT_NEAR(ahead.heightM, kDepthM, 0.03);
}

TEST(SectorBuilder, ClearSectorsBesideADropReportItAndNoFurther)
{
    // A hole's floor 0.3 m deep seen over 4..5 m, 0.3 m either side of the axis: the sectors it covers are
    // negative; the dropEdgeSectors on each side take over the nearer neighbour's drop; farther ones stay Clear.
    cv::Mat d16 = groundDisparity();
    paintSunkenGround(d16, 0.3, 4.0, 5.0, 0.3);
    const auto build = [&d16](int edge) {
        SectorBuilderConfig config;
        config.dropEdgeSectors = edge;
        auto sut = makeBuilder(config);
        EXPECT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);
        return sut.sectors();
    };
    const ObstacleSectors seen = build(0);
    const ObstacleSectors widened = build(2);
    int first = -1;
    int last = -1;
    for (int i = 0; i < seen.count; ++i) {
        const Sector& s = seen.sectors[static_cast<std::size_t>(i)];
        if (s.state == SectorState::Obstacle && s.kind == ObstacleKind::Negative) {
            first = first < 0 ? i : first;
            last = i;
        }
    }
    ASSERT_GE(first, 2);
    ASSERT_LE(last, seen.count - 3);
    for (int i = first; i <= last; ++i) {
        EXPECT_EQ(widened.sectors[static_cast<std::size_t>(i)].rangeM,
                  seen.sectors[static_cast<std::size_t>(i)].rangeM);
    }
    // Only Clear sectors change (the one beside the drop may be Unknown from the rim's stray votes).
    int widenedCount = 0;
    for (const int i : {first - 2, first - 1, last + 1, last + 2}) {
        const Sector& before = seen.sectors[static_cast<std::size_t>(i)];
        const Sector& after = widened.sectors[static_cast<std::size_t>(i)];
        const Sector& edge = seen.sectors[static_cast<std::size_t>(i < first ? first : last)];
        if (before.state != SectorState::Clear) {
            EXPECT_EQ(after.state, before.state) << i;
            continue;
        }
        ++widenedCount;
        EXPECT_EQ(after.state, SectorState::Obstacle) << i;
        EXPECT_EQ(after.kind, ObstacleKind::Negative) << i;
        EXPECT_EQ(after.rangeM, edge.rangeM) << i;
        EXPECT_EQ(after.danger, edge.danger) << i;
        EXPECT_LT(after.confidence, edge.confidence) << i;
    }
    EXPECT_GE(widenedCount, 2);
    for (const int i : {first - 3, last + 3}) {
        EXPECT_EQ(widened.sectors[static_cast<std::size_t>(i)].state, SectorState::Clear) << i;
    }
}

/// Rows where a trench whose near rim is at `rimM` shows its far wall at `wallM`: from the ground (z = 0) down to
/// where the rim ray meets the wall; painted over [-2, 2] m laterally (camera X).
TEST(SectorBuilder, AGapNarrowerThanCloseGapBetweenObstaclesIsClosedAWiderOneStaysClear)
{
    // Two posts 0.4 m wide at 3 m with a gap of `gap` m between them, straight ahead; and two at 2 m and 6 m
    // whose sectors are as close but whose points are 4 m apart.
    const auto build = [](double gap, float closeGapM, double nearZ, double farZ) {
        cv::Mat d16 = groundDisparity();
        paintFace(d16, nearZ, -gap / 2.0 - 0.4, -gap / 2.0, 0.5);
        paintFace(d16, farZ, gap / 2.0 * farZ / nearZ, gap / 2.0 * farZ / nearZ + 0.4 * farZ / nearZ, 0.5);
        SectorBuilderConfig config;
        config.closeGapM = closeGapM;
        auto sut = makeBuilder(config);
        EXPECT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);
        return sut.sectors();
    };
    const auto gapStates = [](const ObstacleSectors& s) {
        // The sectors strictly between the two obstacles' runs around bearing 0.
        int left = sectorOf(s, 0.0);
        int right = left;
        while (left < s.count && s.sectors[static_cast<std::size_t>(left)].state != SectorState::Obstacle) {
            ++left;
        }
        while (right >= 0 && s.sectors[static_cast<std::size_t>(right)].state != SectorState::Obstacle) {
            --right;
        }
        std::vector<Sector> out;
        for (int i = right + 1; i < left; ++i) {
            out.push_back(s.sectors[static_cast<std::size_t>(i)]);
        }
        return out;
    };
    const std::vector<Sector> open = gapStates(build(0.2, 0.0F, 3.0, 3.0));
    ASSERT_GE(open.size(), 2U); // seen as a gap without the rule
    for (const Sector& s : open) {
        EXPECT_EQ(s.state, SectorState::Clear);
    }
    const ObstacleSectors closedAll = build(0.2, 0.5F, 3.0, 3.0);
    const Sector& post = closedAll.sectors[static_cast<std::size_t>(sectorOf(closedAll, 5.0))];
    ASSERT_EQ(post.state, SectorState::Obstacle);
    const Sector& ahead = closedAll.sectors[static_cast<std::size_t>(sectorOf(closedAll, 0.0))];
    EXPECT_EQ(ahead.state, SectorState::Obstacle);
    EXPECT_EQ(ahead.kind, ObstacleKind::Positive);
    EXPECT_NEAR(ahead.rangeM, 3.0, 0.1);
    EXPECT_LT(ahead.confidence, post.confidence);
    for (const Sector& s : gapStates(build(0.8, 0.5F, 3.0, 3.0))) { // wider than closeGapM: stays Clear
        EXPECT_EQ(s.state, SectorState::Clear);
    }
    const std::vector<Sector> apart = gapStates(build(0.2, 0.5F, 2.0, 6.0)); // as close in bearing, 4 m apart
    ASSERT_GE(apart.size(), 2U);
    for (const Sector& s : apart) {
        EXPECT_EQ(s.state, SectorState::Clear);
    }
}

void paintFarWall(cv::Mat& d16, double rimM, double wallM)
{
    const double bottom = kHeightM - wallM * kHeightM / rimM; // z where the rim ray meets the wall (< 0)
    const auto value = static_cast<std::int16_t>(std::lround(kFb / wallM * 16.0));
    for (int v = roiRow(0.0, wallM); v <= roiRow(bottom, wallM); ++v) {
        for (int u = column(-2.0, wallM); u <= column(2.0, wallM); ++u) {
            d16.at<std::int16_t>(v, u) = value;
        }
    }
    // The ground between the rim and the wall is hidden: rows of ranges in (rim, wall) carry the wall (above).
}

TEST(SectorBuilder, FarWallOfADropSeenOverAGapIsNegativeAtTheRim)
{
    // A 1 m trench at 7 m: only the top 8 cm of its far wall are in view, never deeper than minDepthM (0.10 m),
    // but the rays to it cross the ground up to 1 m before it (a gap in the seen ground): a drop.
    auto sut = makeBuilder();
    cv::Mat d16 = groundDisparity();
    paintFarWall(d16, 7.0, 8.0);

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);

    const Sector& ahead = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    EXPECT_EQ(ahead.state, SectorState::Obstacle);
    EXPECT_EQ(ahead.kind, ObstacleKind::Negative);
    EXPECT_NEAR(ahead.rangeM, 7.0, 0.03 * 7.0);
}

TEST(SectorBuilder, DropVotesWhereTheTwoImagesBlockGridsMeetAreNoEvidence)
{
    // A far wall at a disparity of 24 px behind a rim 1 m before it: a trench as the matcher shows it, and as it
    // shows the edges of JPEG blocks matched to each other (at multiples of 8 px when the two images' grids line up:
    // KITTI at JPEG quality 20 and 70). With both images showing the grid, at offsets that meet at 0 px, its votes
    // are no evidence: no drop, never Clear. Grids that meet at 4 px, a grid in one image only, or none: a drop.
    constexpr double kWallPx = 24.0;
    cv::Mat d16 = groundDisparity();
    paintFarWall(d16, kFb / kWallPx - 1.0, kFb / kWallPx);
    const auto ahead = [&d16](BlockGrid left, BlockGrid right) {
        auto sut = makeBuilder();
        sut.setBlockGrid(left, right);
        EXPECT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);
        return sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    };
    const BlockGrid coded{1.6F, 7};

    const Sector locked = ahead(coded, coded);
    EXPECT_NE(locked.state, SectorState::Obstacle);
    EXPECT_NE(locked.state, SectorState::Clear);

    for (const auto& [left, right] : {std::pair{coded, BlockGrid{1.6F, 3}}, std::pair{coded, BlockGrid{1.05F, 7}},
                                      std::pair{BlockGrid{}, BlockGrid{}}}) {
        const Sector drop = ahead(left, right);
        EXPECT_EQ(drop.state, SectorState::Obstacle) << right.contrast << " " << right.offset;
        EXPECT_EQ(drop.kind, ObstacleKind::Negative) << right.contrast << " " << right.offset;
    }
}

/// The default config with the per-pixel drop votes switched off (depth thresholds of 1 m): only the row profile
/// can report a drop.
SectorBuilderConfig profileOnly()
{
    SectorBuilderConfig config;
    config.minDepthM = 1.0F;
    config.minDropDepthM = 1.0F;
    return config;
}

/// The ground-mismatch stage's view of a disparity map: every pixel more than 0.3 px below the ground labelled
/// negative (the second cue a row-profile drop needs).
cv::Mat labelsBelowGround(const cv::Mat& d16)
{
    const ugv::vision::DisparityPlane plane = kGround.disparityPlane(kRigProjection);
    cv::Mat labels(d16.size(), CV_8UC1, cv::Scalar(0));
    for (int v = 0; v < d16.rows; ++v) {
        for (int u = 0; u < d16.cols; ++u) {
            const int d = d16.at<std::int16_t>(v, u);
            if (d > 0 && d / 16.0 < plane.at(u + kRoi.x, v + kRoi.y) - 0.3) {
                labels.at<std::uint8_t>(v, u) = ugv::vision::kLabelNegative;
            }
        }
    }
    return labels;
}

void expectNoObstacle(const ObstacleSectors& sectors)
{
    for (int i = 0; i < sectors.count; ++i) {
        EXPECT_NE(sectors.sectors[static_cast<std::size_t>(i)].state, SectorState::Obstacle) << "sector " << i;
    }
}

TEST(SectorBuilder, FarWallTooShallowForPixelVotesIsFoundByTheRowProfile)
{
    // A 1 m trench at 9 m: its far wall is 4 rows at 1.1..1.7 px below the ground disparity. With the per-pixel
    // drop votes switched off (thresholds of 1 m), only the row profile can find it: at the rim, within 3 %.
    SectorBuilderConfig config = profileOnly();
    auto sut = makeBuilder(config);
    cv::Mat d16 = groundDisparity();
    paintFarWall(d16, 9.0, 10.0);
    const cv::Mat labels = labelsBelowGround(d16);

    ASSERT_EQ(sut.build(view16(d16), view(labels), kGround, 1U, 0), BuildStatus::Ok);
    const Sector& ahead = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    EXPECT_EQ(ahead.state, SectorState::Obstacle);
    EXPECT_EQ(ahead.kind, ObstacleKind::Negative);
    EXPECT_NEAR(ahead.rangeM, 9.0, 0.03 * 9.0);

    // The same scene with the profile limited to rims beyond 10 m: nothing else could have found it.
    config.dropProfileMinRangeM = 10.0F;
    auto without = makeBuilder(config);
    ASSERT_EQ(without.build(view16(d16), view(labels), kGround, 1U, 0), BuildStatus::Ok);
    EXPECT_NE(without.sectors().sectors[static_cast<std::size_t>(sectorOf(without.sectors(), 0.0))].state,
              SectorState::Obstacle);
}

TEST(SectorBuilder, ARowProfileDropNeedsTheSecondCueAndIsNeverClearWithoutIt)
{
    // The far wall of the test above with no label of the ground-mismatch stage: one cue only, no drop; its rows
    // below the ground still keep the sector from Clear.
    auto sut = makeBuilder(profileOnly());
    cv::Mat d16 = groundDisparity();
    paintFarWall(d16, 9.0, 10.0);

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);

    const Sector& ahead = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    EXPECT_NE(ahead.kind, ObstacleKind::Negative);
    EXPECT_NE(ahead.state, SectorState::Clear);
}

/// The ground seen offsetPx too far at depths [z0, z1] over camera X in [-halfWidth, halfWidth]: what a matcher's
/// error spread over a patch of road gives (its disparity follows the ground's, d = d_g - offset).
void paintOffsetPatch(cv::Mat& d16, double z0, double z1, double halfWidth, double offsetPx)
{
    const DisparityPlane plane = kGround.disparityPlane(kRigProjection);
    for (int v = roiRow(0.0, z1); v <= roiRow(0.0, z0); ++v) {
        const double z = kRigProjection.fy * kHeightM / (v + kRoi.y - kRigProjection.cy);
        for (int u = column(-halfWidth, z); u <= column(halfWidth, z); ++u) {
            const double d = plane.at(u + kRoi.x, v + kRoi.y) - offsetPx;
            d16.at<std::int16_t>(v, u) = static_cast<std::int16_t>(std::lround(d * 16.0));
        }
    }
}

TEST(SectorBuilder, ABelowGroundPatchThatFollowsTheGroundIsNoDropAndNeverClear)
{
    // 6-8 m ahead seen 5 px too far: every pixel 12-16 cm below the ground votes a drop (deeper than the local
    // ground follows), but the patch's disparity follows the ground's (slope 1, not through the origin): neither a
    // wall nor a floor. Unknown, not Clear. A far wall at the same ranges is a drop.
    auto sut = makeBuilder();
    cv::Mat d16 = groundDisparity();
    paintOffsetPatch(d16, 6.0, 8.0, 1.0, 5.0);

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);
    const Sector& ahead = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    EXPECT_NE(ahead.state, SectorState::Obstacle);
    EXPECT_NE(ahead.state, SectorState::Clear);

    // The wall test is what tells: accepting any slope, the patch is a drop.
    SectorBuilderConfig anySlope;
    anySlope.maxWallSlope = 100.0F;
    auto lax = makeBuilder(anySlope);
    ASSERT_EQ(lax.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);
    EXPECT_EQ(lax.sectors().sectors[static_cast<std::size_t>(sectorOf(lax.sectors(), 0.0))].kind,
              ObstacleKind::Negative);

    cv::Mat wall = groundDisparity();
    paintFarWall(wall, 6.0, 7.0);
    ASSERT_EQ(sut.build(view16(wall), {}, kGround, 2U, 0), BuildStatus::Ok);
    EXPECT_EQ(sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))].kind,
              ObstacleKind::Negative);
}

/// Below-ground pixels at depths [z0, z1] over camera X in [-halfWidth, halfWidth] [m] whose disparity is
/// slope * g + interceptPx +- spreadPx (g the plane's there) in two columns of every three; the third keeps the ground.
void paintLinePatch(cv::Mat& d16, double z0, double z1, double halfWidth, double slope, double interceptPx,
                    double spreadPx)
{
    const DisparityPlane plane = kGround.disparityPlane(kRigProjection);
    for (int v = roiRow(0.0, z1); v <= roiRow(0.0, z0); ++v) {
        const double z = kRigProjection.fy * kHeightM / (v + kRoi.y - kRigProjection.cy);
        for (int u = column(-halfWidth, z); u <= column(halfWidth, z); ++u) {
            if (u % 3 == 0) {
                continue;
            }
            const double d =
                slope * plane.at(u + kRoi.x, v + kRoi.y) + interceptPx + (u % 3 == 1 ? spreadPx : -spreadPx);
            d16.at<std::int16_t>(v, u) = static_cast<std::int16_t>(std::lround(d * 16.0));
        }
    }
}

TEST(SectorBuilder, AFloorMustBeDeepOverAllItsVotesNotOnlyByItsSlopesUncertainty)
{
    // Two thirds of the pixels at 6-8 m are a patch with the slope of a floor 18 cm deep, 0.77 of the ground's
    // disparity, that lies 8-9 cm below the ground (mean o / mean g 0.87-0.89): far enough that its pixels vote as
    // drops (minDropDepthM), with the ground seen between them. The patch's slope passes as a floor's within its
    // standard errors, but its own line through the origin is shallower than minDepthM (KITTI 000046_10 at half the
    // exposure: slope 0.83 +- 0.10, 7 cm deep by its line): no drop, and never Clear. The same slope through the
    // origin is a floor 18 cm deep: a drop.
    constexpr double kSlope = 0.77;
    const auto ahead = [](double interceptPx) {
        cv::Mat d16 = groundDisparity();
        paintLinePatch(d16, 6.0, 8.0, 1.0, kSlope, interceptPx, 0.1);
        auto sut = makeBuilder();
        EXPECT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);
        return sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    };

    const Sector shallow = ahead((0.88 - kSlope) * kFb / 7.0);
    EXPECT_NE(shallow.state, SectorState::Obstacle);
    EXPECT_NE(shallow.state, SectorState::Clear);

    const Sector floor = ahead(0.0);
    EXPECT_EQ(floor.state, SectorState::Obstacle);
    EXPECT_EQ(floor.kind, ObstacleKind::Negative);
}

TEST(SectorBuilder, ARowProfileDropMustBeAWallNotRowsThatFollowTheGround)
{
    // Rows at 9-10 m seen 1.5 px too far, with both cues (labels) and the ground back above them: the row profile's
    // rim, wall rows and far rim are all there, but the wall rows' disparity follows the ground's. No drop,
    // never Clear; the far wall of a trench at the same range is one.
    auto sut = makeBuilder(profileOnly());
    cv::Mat d16 = groundDisparity();
    paintOffsetPatch(d16, 9.0, 10.0, 2.0, 1.5);
    const cv::Mat labels = labelsBelowGround(d16);

    ASSERT_EQ(sut.build(view16(d16), view(labels), kGround, 1U, 0), BuildStatus::Ok);
    const Sector& ahead = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    EXPECT_NE(ahead.state, SectorState::Obstacle);
    EXPECT_NE(ahead.state, SectorState::Clear);

    SectorBuilderConfig anySlope = profileOnly();
    anySlope.maxWallSlope = 100.0F;
    auto lax = makeBuilder(anySlope);
    ASSERT_EQ(lax.build(view16(d16), view(labels), kGround, 1U, 0), BuildStatus::Ok);
    EXPECT_EQ(lax.sectors().sectors[static_cast<std::size_t>(sectorOf(lax.sectors(), 0.0))].kind,
              ObstacleKind::Negative);
}

TEST(SectorBuilder, AFarWallIsFoundAboveABlendedOrThinnedBottomRow)
{
    // A 1 m drop at 7 m: its far wall at 8 m is 6 rows, 0.4..2.9 px below the ground. The matcher blends the rim
    // into the wall's bottom row (here: 0.6 px below the ground), or the verifier removes most of that row (here:
    // all but every 8th pixel); both hide the rim right below the wall, and the wall is still found above them.
    const auto ahead = [](const cv::Mat& d16) {
        auto sut = makeBuilder(profileOnly());
        const cv::Mat labels = labelsBelowGround(d16);
        EXPECT_EQ(sut.build(view16(d16), view(labels), kGround, 1U, 0), BuildStatus::Ok);
        return sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    };
    cv::Mat wall = groundDisparity();
    paintFarWall(wall, 7.0, 8.0);
    const int bottom = roiRow(kHeightM - 8.0 * kHeightM / 7.0, 8.0);
    const DisparityPlane plane = kGround.disparityPlane(kRigProjection);

    cv::Mat blended = wall.clone();
    cv::Mat thinned = wall.clone();
    for (int u = 0; u < wall.cols; ++u) {
        blended.at<std::int16_t>(bottom, u) =
            static_cast<std::int16_t>(std::lround((plane.at(u, bottom + kRoi.y) - 0.6) * 16.0));
        if (u % 8 != 0) {
            thinned.at<std::int16_t>(bottom, u) = -16;
        }
    }
    for (const cv::Mat* d16 : {&wall, &blended, &thinned}) {
        const Sector s = ahead(*d16);
        EXPECT_EQ(s.state, SectorState::Obstacle);
        EXPECT_EQ(s.kind, ObstacleKind::Negative);
        EXPECT_NEAR(s.rangeM, 7.0, 0.05 * 7.0);
    }
}

TEST(SectorBuilder, OneLowRowIsNoFarDrop)
{
    // A matcher streak: a single row 2 px below the ground at 9 m (a wall needs two rows below the ground above a
    // rim row on it), and two low rows without a ground row below them (the rows below are invalid).
    auto sut = makeBuilder(profileOnly());
    cv::Mat d16 = groundDisparity();
    const int row = roiRow(0.0, 9.0);
    for (int u = 0; u < d16.cols; ++u) {
        d16.at<std::int16_t>(row, u) = static_cast<std::int16_t>(d16.at<std::int16_t>(row, u) - 32);
    }
    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);
    expectNoObstacle(sut.sectors());

    cv::Mat gap = groundDisparity();
    for (int v = row; v < row + 2; ++v) {
        for (int u = 0; u < gap.cols; ++u) {
            gap.at<std::int16_t>(v, u) = static_cast<std::int16_t>(gap.at<std::int16_t>(v, u) - 32);
            gap.at<std::int16_t>(v + 2, u) = -16;
        }
    }
    ASSERT_EQ(sut.build(view16(gap), {}, kGround, 1U, 0), BuildStatus::Ok);
    expectNoObstacle(sut.sectors());
}

TEST(SectorBuilder, ShallowDipWithoutAGapIsGround)
{
    // The ground 4 cm lower from 2 m to 3 m (a dip seen from above, no hidden ground): the rays cross the ground
    // plane at most 3 * 0.04 / 0.63 = 0.19 m before the points, less than minDropGapM: ground, and Clear.
    auto sut = makeBuilder();
    cv::Mat d16 = groundDisparity();
    constexpr double kDipM = 0.04;
    paintSunkenGround(d16, kDipM, 2.0, 3.0, 1.0);

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);

    const Sector& ahead = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    EXPECT_EQ(ahead.state, SectorState::Clear);
}

TEST(SectorBuilder, GroundSeenOnlyNearIsUnknownNotClear)
{
    // A textureless wall at 3 m straight ahead: the matcher leaves it invalid, so the sector sees plenty of ground
    // in front of the wall but none beyond clearRangeM (5 m). That is not "clear": the sector must be Unknown.
    auto sut = makeBuilder();
    cv::Mat d16 = groundDisparity();
    const int wallFoot = roiRow(0.0, 3.0);
    for (int v = 0; v <= wallFoot; ++v) {
        for (int u = column(-0.5, 3.0); u <= column(0.5, 3.0); ++u) {
            d16.at<std::int16_t>(v, u) = -16;
        }
    }

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);

    const Sector& ahead = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];
    EXPECT_EQ(ahead.state, SectorState::Unknown);
    EXPECT_EQ(ahead.danger, DangerClass::Unknown);
    const Sector& side = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 20.0))];
    EXPECT_EQ(side.state, SectorState::Clear);
}

TEST(SectorBuilder, IsolatedOutliersNeitherCreateNorMoveObstacles)
{
    auto sut = makeBuilder();
    cv::Mat d16 = groundDisparity();
    paintFace(d16, 4.0, -0.2, 0.2, 0.5);
    const auto nearValue = static_cast<std::int16_t>(std::lround(kFb / 1.0 * 16.0)); // points at 1 m, high up
    for (int k = 0; k < 8; ++k) {
        d16.at<std::int16_t>(20 + 10 * k, 320) = nearValue; // in the obstacle's sector
    }
    for (int k = 0; k < 4; ++k) {
        d16.at<std::int16_t>(20 + 10 * k, 100) = nearValue; // a few in a clear sector
    }
    for (int k = 0; k < 8; ++k) {
        d16.at<std::int16_t>(20 + 10 * k, 560) = nearValue; // maxStrayVotes in another one
    }

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);

    const ObstacleSectors& s = sut.sectors();
    EXPECT_NEAR(s.sectors[static_cast<std::size_t>(sectorOf(s, 0.0))].rangeM, 4.0, 0.04);
    const auto bearingOf = [](double u) { return std::atan2(kRigProjection.cx - u, kRigProjection.fx) * 180.0 / M_PI; };
    EXPECT_EQ(s.sectors[static_cast<std::size_t>(sectorOf(s, bearingOf(100.0)))].state, SectorState::Clear);
    // As many stray votes as a mesh fence's wires give: not an obstacle, but no longer Clear either.
    EXPECT_EQ(s.sectors[static_cast<std::size_t>(sectorOf(s, bearingOf(560.0)))].state, SectorState::Unknown);
}

TEST(SectorBuilder, NoValidDisparityIsUnknownNeverClear)
{
    auto sut = makeBuilder();
    const cv::Mat invalid(kRoi.height, kRoi.width, CV_16SC1, cv::Scalar(-16));

    ASSERT_EQ(sut.build(view16(invalid), {}, kGround, 1U, 0), BuildStatus::Ok);

    for (int i = 0; i < sut.sectors().count; ++i) {
        EXPECT_EQ(sut.sectors().sectors[static_cast<std::size_t>(i)].state, SectorState::Unknown) << i;
        EXPECT_EQ(sut.sectors().sectors[static_cast<std::size_t>(i)].danger, DangerClass::Unknown) << i;
    }
}

TEST(SectorBuilder, LabelsOnlyModeNeedsLabelsAndUnlabelledVotesForbidClear)
{
    SectorBuilderConfig config;
    config.useDenseCue = false;
    auto sut = makeBuilder(config);
    cv::Mat d16 = groundDisparity();
    paintFace(d16, 3.0, -0.2, 0.2, 0.5);
    cv::Mat labels(kRoi.height, kRoi.width, CV_8UC1, cv::Scalar(0));

    ASSERT_EQ(sut.build(view16(d16), view(labels), kGround, 1U, 0), BuildStatus::Ok);
    const SectorState unlabelled = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))].state;
    labels.setTo(kLabelPositive);
    ASSERT_EQ(sut.build(view16(d16), view(labels), kGround, 2U, 0), BuildStatus::Ok);
    const Sector labelled = sut.sectors().sectors[static_cast<std::size_t>(sectorOf(sut.sectors(), 0.0))];

    EXPECT_EQ(unlabelled, SectorState::Unknown);
    EXPECT_EQ(labelled.state, SectorState::Obstacle);
    EXPECT_NEAR(labelled.rangeM, 3.0, 0.03);
}

/// A builder keeps nothing of the frames before (its histograms, local ground and row profile are per frame): after a
/// frame whose ground lies 0.15 m below the plane, with a trench, the next frame's sectors are those a new builder
/// gives, by both projections (per row and the per-pixel reference).
TEST(SectorBuilder, TheSectorsOfAFrameDoNotDependOnTheFramesBefore)
{
    cv::Mat before = groundDisparity();
    const DisparityPlane lower =
        GroundPlane::fromMount(Mount{kHeightM + 0.15, 0.0, 0.0}).disparityPlane(kRigProjection);
    for (int v = 0; v < kRoi.height; ++v) {
        for (int u = 0; u < kRoi.width; ++u) {
            const double d = lower.at(u, v + kRoi.y);
            before.at<std::int16_t>(v, u) = d > 0.0 ? static_cast<std::int16_t>(std::lround(d * 16.0)) : -16;
        }
    }
    paintSunkenGround(before, 0.3, 4.0, 5.0, 0.5);
    cv::Mat frame = groundDisparity();
    paintFace(frame, 3.0, -0.2, 0.2, 0.5);

    for (const bool reference : {false, true}) {
        const auto build = [reference](SectorBuilder& b, const cv::Mat& d16) {
            return reference ? b.buildReference(view16(d16), {}, kGround, 2U, 0)
                             : b.build(view16(d16), {}, kGround, 2U, 0);
        };
        auto fresh = makeBuilder();
        auto reused = makeBuilder();
        ASSERT_EQ(build(reused, before), BuildStatus::Ok);
        ASSERT_EQ(build(reused, frame), BuildStatus::Ok);
        ASSERT_EQ(build(fresh, frame), BuildStatus::Ok);
        EXPECT_EQ(reused.groundNoisePx(), fresh.groundNoisePx());
        for (int i = 0; i < fresh.sectors().count; ++i) {
            const Sector& a = fresh.sectors().sectors[static_cast<std::size_t>(i)];
            const Sector& b = reused.sectors().sectors[static_cast<std::size_t>(i)];
            EXPECT_EQ(a.state, b.state) << "sector " << i << (reference ? " (reference)" : "");
            EXPECT_EQ(a.kind, b.kind) << "sector " << i;
            EXPECT_EQ(a.rangeM, b.rangeM) << "sector " << i;
            EXPECT_EQ(a.heightM, b.heightM) << "sector " << i;
            EXPECT_EQ(a.confidence, b.confidence) << "sector " << i;
        }
    }
}

TEST(SectorBuilder, WrongInputSizesGiveAllUnknownDegraded)
{
    auto sut = makeBuilder();
    const cv::Mat d16 = groundDisparity();
    const cv::Mat small16(10, 10, CV_16SC1, cv::Scalar(0));
    const cv::Mat smallLabels(10, 10, CV_8UC1, cv::Scalar(0));

    ASSERT_EQ(sut.build(view16(d16), {}, kGround, 1U, 0), BuildStatus::Ok);
    EXPECT_EQ(sut.build(view16(small16), {}, kGround, 2U, 5), BuildStatus::WrongDisparitySize);
    EXPECT_TRUE(sut.sectors().degraded);
    EXPECT_EQ(sut.sectors().sequence, 2U);
    EXPECT_EQ(sut.build(view16(d16), view(smallLabels), kGround, 3U, 5), BuildStatus::WrongLabelSize);

    EXPECT_TRUE(sut.sectors().degraded);
    for (int i = 0; i < sut.sectors().count; ++i) {
        EXPECT_EQ(sut.sectors().sectors[static_cast<std::size_t>(i)].state, SectorState::Unknown);
    }
}

/// Perfect inputs (simulator ground-truth disparity and labels) reproduce the simulator's ground-truth sectors.
void expectMatchesGroundTruth(const char* name, double rangeM, double bearingDeg)
{
    auto scene = sim::makeScene(name, rangeM, bearingDeg, sim::GroundTexture::Asphalt, 3);
    ASSERT_TRUE(scene.has_value());
    auto rendered = sim::render(scene.value(), {}, sim::RenderOptions{1});
    ASSERT_TRUE(rendered.has_value());
    const auto& frame = rendered.value();
    cv::Mat d16(kRoi.height, kRoi.width, CV_16SC1);
    cv::Mat labels(kRoi.height, kRoi.width, CV_8UC1);
    for (int v = 0; v < kRoi.height; ++v) {
        for (int u = 0; u < kRoi.width; ++u) {
            const float d = frame.disparity.at<float>(v + kRoi.y, u);
            d16.at<std::int16_t>(v, u) = d > 0.0F ? static_cast<std::int16_t>(std::lround(d * 16.0F)) : -16;
            const std::uint8_t l = frame.labels.at<std::uint8_t>(v + kRoi.y, u);
            labels.at<std::uint8_t>(v, u) = l == 1 || l == 2 ? l : 0;
        }
    }
    // Qualifying ground-truth hits per sector (bearing of the hit point, level rig: x = depth).
    std::array<int, kMaxSectors> support{};
    const float binDeg = 60.7F / 64.0F;
    for (int y = kFirstAnalysedRow; y < frame.labels.rows; ++y) {
        for (int u = 0; u < frame.labels.cols; ++u) {
            const std::uint8_t l = frame.labels.at<std::uint8_t>(y, u);
            const float h = frame.height.at<float>(y, u);
            if ((l == 1 && h > 0.10F) || (l == 2 && h < -0.02F)) { // the simulator's qualifying hits
                const double z = frame.depth.at<float>(y, u);
                const double bearing = std::atan2(-(u - kRigProjection.cx) * z / kRigProjection.fx, z) * 180.0 / M_PI;
                const int s = static_cast<int>(std::floor((bearing + 60.7 / 2.0) / binDeg));
                if (s >= 0 && s < 64) {
                    ++support[static_cast<std::size_t>(s)];
                }
            }
        }
    }
    SectorBuilderConfig config;
    config.dropEdgeSectors = 0; // perfect inputs show a hole's rim to its ends: no widening beyond the truth
    config.closeGapM = 0.0F;    // ... and every gap as it is
    auto sut = makeBuilder(config);

    ASSERT_EQ(sut.build(view16(d16), view(labels), kGround, 9U, 0), BuildStatus::Ok);

    const ObstacleSectors& gt = frame.sectors;
    ASSERT_EQ(sut.sectors().count, gt.count);
    int obstacles = 0;
    for (int i = 0; i < gt.count; ++i) {
        const Sector& want = gt.sectors[static_cast<std::size_t>(i)];
        const Sector& got = sut.sectors().sectors[static_cast<std::size_t>(i)];
        EXPECT_NEAR(got.bearingMinDeg, want.bearingMinDeg, 1e-3F);
        if (want.state == SectorState::Obstacle && support[static_cast<std::size_t>(i)] < config.minSupport) {
            // By design (outlier rejection) fewer than minSupport hits do not make an obstacle: only the edge
            // sector of an object, seen by a sliver of pixels.
            std::printf("[ MEASURED ] %s sector %d: %d GT hits < minSupport, got state %d\n", name, i,
                        support[static_cast<std::size_t>(i)], static_cast<int>(got.state));
            continue;
        }
        EXPECT_EQ(got.state, want.state) << name << " sector " << i;
        EXPECT_EQ(got.kind, want.kind) << name << " sector " << i;
        EXPECT_EQ(got.danger, want.danger) << name << " sector " << i;
        if (want.state == SectorState::Obstacle && got.state == SectorState::Obstacle) {
            ++obstacles;
            EXPECT_NEAR(got.rangeM, want.rangeM, std::max(0.10F, 0.03F * want.rangeM)) << name << " sector " << i;
            std::printf("[ MEASURED ] %s sector %d: range %.3f m (GT %.3f m)\n", name, i, got.rangeM, want.rangeM);
        }
    }
    if (std::string_view(name) != "empty") {
        EXPECT_GT(obstacles, 0) << name;
    }
}

TEST(SectorBuilder, GroundTruthInputsReproduceGroundTruthSectors)
{
    expectMatchesGroundTruth("empty", 5.0, 0.0);
    expectMatchesGroundTruth("pole", 3.0, 5.0);
    expectMatchesGroundTruth("box", 4.0, -10.0);
    expectMatchesGroundTruth("person", 2.5, 15.0);
    expectMatchesGroundTruth("hole", 3.0, 0.0);
}

TEST(SectorBuilder, SteadyStateBuildDoesNotAllocate)
{
    auto sut = makeBuilder();
    cv::Mat d16 = groundDisparity();
    paintFace(d16, 3.0, -0.2, 0.2, 0.5);
    const cv::Mat labels(kRoi.height, kRoi.width, CV_8UC1, cv::Scalar(kLabelPositive));
    constexpr int kFrames = 300;

    std::size_t allocations = 0;
    {
        const test::AllocationScope scope;
        for (int i = 0; i < kFrames; ++i) {
            (void)sut.build(view16(d16), view(labels), kGround, static_cast<std::uint64_t>(i), i);
        }
        allocations = scope.count();
    }

    EXPECT_EQ(allocations, 0U);
    EXPECT_EQ(sut.sectors().sequence, static_cast<std::uint64_t>(kFrames - 1));
}

} // namespace
} // namespace ugv::vision

namespace ugv::vision {
namespace {

/// build() (per-row linear factors, boundary walk) against buildReference() (pixelToVehicle, atan2, hypot per
/// pixel) on simulator ground-truth disparity with noise-free and noisy (+-0.5 px) values, for level, pitched and
/// rolled ground planes, with and without labels: the sectors must be equal field by field.
TEST(SectorBuilder, FastBuildEqualsPerPixelReferenceOnSimulatorInputs)
{
    struct Case {
        const char* name;
        double rangeM;
        double bearingDeg;
        double pitchDeg;
        double rollDeg;
    };
    constexpr std::array<Case, 6> kCases{{{"empty", 5.0, 0.0, 0.0, 0.0},
                                          {"pole", 3.0, 5.0, 0.0, 0.0},
                                          {"box", 4.0, -10.0, 2.0, 0.0},
                                          {"person", 2.5, 15.0, 0.0, 1.5},
                                          {"hole", 3.0, 0.0, 3.0, -1.0},
                                          {"trench", 3.0, 0.0, 0.0, 0.0}}};
    int compared = 0;
    for (const Case& c : kCases) {
        auto scene = sim::makeScene(c.name, c.rangeM, c.bearingDeg, sim::GroundTexture::Asphalt, 3);
        ASSERT_TRUE(scene.has_value());
        auto rendered = sim::render(scene.value(), {}, sim::RenderOptions{1});
        ASSERT_TRUE(rendered.has_value());
        const auto& frame = rendered.value();
        cv::Mat d16(kRoi.height, kRoi.width, CV_16SC1);
        cv::Mat labels(kRoi.height, kRoi.width, CV_8UC1);
        cv::RNG rng(7);
        for (int v = 0; v < kRoi.height; ++v) {
            for (int u = 0; u < kRoi.width; ++u) {
                const float d = frame.disparity.at<float>(v + kRoi.y, u) + static_cast<float>(rng.uniform(-0.5, 0.5));
                d16.at<std::int16_t>(v, u) = d > 0.0F ? static_cast<std::int16_t>(std::lround(d * 16.0F)) : -16;
                const std::uint8_t l = frame.labels.at<std::uint8_t>(v + kRoi.y, u);
                labels.at<std::uint8_t>(v, u) = l == 1 || l == 2 ? l : 0;
            }
        }
        // The plane of a (slightly) different mount than the render: points off the plane vote everywhere.
        const GroundPlane ground = GroundPlane::fromMount(Mount{kHeightM, c.pitchDeg, c.rollDeg});
        for (const bool dense : {true, false}) {
            SectorBuilderConfig config;
            config.useDenseCue = dense;
            auto fast = makeBuilder(config);
            auto reference = makeBuilder(config);

            ASSERT_EQ(fast.build(view16(d16), view(labels), ground, 5U, 7), BuildStatus::Ok);
            ASSERT_EQ(reference.buildReference(view16(d16), view(labels), ground, 5U, 7), BuildStatus::Ok);

            const ObstacleSectors& got = fast.sectors();
            const ObstacleSectors& want = reference.sectors();
            ASSERT_EQ(got.count, want.count);
            EXPECT_EQ(got.sequence, want.sequence);
            EXPECT_EQ(got.degraded, want.degraded);
            for (int i = 0; i < got.count; ++i) {
                const Sector& g = got.sectors[static_cast<std::size_t>(i)];
                const Sector& w = want.sectors[static_cast<std::size_t>(i)];
                EXPECT_EQ(g.state, w.state) << c.name << " sector " << i;
                EXPECT_EQ(g.kind, w.kind) << c.name << " sector " << i;
                EXPECT_EQ(g.danger, w.danger) << c.name << " sector " << i;
                EXPECT_EQ(g.rangeM, w.rangeM) << c.name << " sector " << i;
                EXPECT_EQ(g.heightM, w.heightM) << c.name << " sector " << i;
                EXPECT_EQ(g.confidence, w.confidence) << c.name << " sector " << i;
                compared += w.state == SectorState::Obstacle ? 1 : 0;
            }
        }
    }
    EXPECT_GT(compared, 0);
}

TEST(SectorBuilder, ReferenceBuildAlsoRejectsWrongSizes)
{
    auto sut = makeBuilder();
    const cv::Mat small16(10, 10, CV_16SC1, cv::Scalar(0));

    EXPECT_EQ(sut.buildReference(view16(small16), {}, kGround, 2U, 5), BuildStatus::WrongDisparitySize);
    EXPECT_TRUE(sut.sectors().degraded);
}

} // namespace
} // namespace ugv::vision
