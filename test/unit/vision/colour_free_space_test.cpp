// Colour free space on simulator scenes tinted by their ground-truth labels: green textured ground, brown or grey
// obstacles, blue-ish sky (or the grey render itself, for grey ground). Ranges are checked against the simulator's
// ground-truth sectors.

#include "ugv/vision/colour_free_space.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"
#include "ugv/vision/ground_plane.hpp"

namespace {

using ugv::ObstacleSectors;
using ugv::SectorState;
using ugv::vision::ColourFreeSpace;
using ugv::vision::ColourFreeSpaceConfig;
using ugv::vision::ColourFreeSpaceStatus;

struct Tint {
    int obstacleHue = 12; // brown (OpenCV hue 0..179)
    int obstacleSat = 120;
    bool greyEverything = false; // the hard case: no colour at all
};

/// HSV per label: ground green with hue and saturation following the texture, obstacles `tint`, far blue-ish.
cv::Mat tintByLabels(const ugv::sim::RenderResult& frame, const Tint& tint)
{
    cv::Mat hsv(frame.left.size(), CV_8UC3);
    for (int y = 0; y < hsv.rows; ++y) {
        for (int x = 0; x < hsv.cols; ++x) {
            const int grey = frame.left.at<std::uint8_t>(y, x);
            const auto label = static_cast<ugv::sim::Label>(frame.labels.at<std::uint8_t>(y, x));
            int hue = 105;
            int sat = 50;
            if (label == ugv::sim::Label::Ground) {
                hue = 50 + (grey - 128) / 16;
                sat = std::clamp(140 + (grey - 128) / 4, 0, 255);
            } else if (label != ugv::sim::Label::Far) {
                hue = tint.obstacleHue;
                sat = std::clamp(tint.obstacleSat + (grey - 128) / 8, 0, 255);
            }
            if (tint.greyEverything) {
                sat = 0;
            }
            hsv.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<std::uint8_t>(hue), static_cast<std::uint8_t>(sat),
                                                static_cast<std::uint8_t>(std::max(grey, 40)));
        }
    }
    cv::Mat bgr;
    cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
    return bgr;
}

ugv::sim::RenderResult renderScene(const ugv::sim::Scene& scene)
{
    ugv::sim::RenderOptions options;
    options.samplesPerAxis = 1;
    auto frame = ugv::sim::render(scene, {}, options);
    EXPECT_TRUE(frame.has_value()) << frame.error().message();
    return std::move(frame).value();
}

ugv::sim::Scene catalogue(const char* name, double rangeM, double bearingDeg)
{
    auto scene = ugv::sim::makeScene(name, rangeM, bearingDeg, ugv::sim::GroundTexture::Grass, 7);
    EXPECT_TRUE(scene.has_value());
    return std::move(scene).value();
}

ugv::ConstBgrView bgrView(const cv::Mat& m)
{
    return {reinterpret_cast<const ugv::BgrPixel*>(m.data), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}

ColourFreeSpace makeSut(const ugv::sim::Rig& rig, const ColourFreeSpaceConfig& config = {})
{
    const ugv::vision::RectifiedProjection projection{rig.focalPx, rig.focalPx, rig.cx(), rig.cy(), rig.baselineM};
    const auto ground = ugv::vision::GroundPlane::fromMount({rig.heightM, rig.pitchDeg, rig.rollDeg});
    auto sut = ColourFreeSpace::create(config, {rig.width, rig.height}, projection, ground);
    EXPECT_TRUE(sut.has_value()) << sut.error().message();
    return std::move(sut).value();
}

std::size_t sectorAt(const ObstacleSectors& sectors, double bearingDeg)
{
    for (std::size_t i = 0; i < static_cast<std::size_t>(sectors.count); ++i) {
        if (bearingDeg >= sectors.sectors[i].bearingMinDeg && bearingDeg < sectors.sectors[i].bearingMaxDeg) {
            return i;
        }
    }
    return 0;
}

TEST(ColourFreeSpace, EmptyGrassIsClearEverywhere)
{
    const auto scene = catalogue("empty", 5.0, 0.0);
    const auto frame = renderScene(scene);
    auto sut = makeSut(scene.rig);
    ObstacleSectors out;

    const auto status = sut.process(bgrView(tintByLabels(frame, {})), out);

    ASSERT_EQ(status, ColourFreeSpaceStatus::Ok);
    EXPECT_TRUE(sut.reference().groundLike) << sut.reference().meanValue << " " << sut.reference().coverage;
    ASSERT_EQ(out.count, 64);
    for (int i = 0; i < out.count; ++i) {
        EXPECT_EQ(out.sectors[static_cast<std::size_t>(i)].state, SectorState::Clear) << "sector " << i;
        EXPECT_EQ(out.sectors[static_cast<std::size_t>(i)].danger, ugv::DangerClass::Green) << "sector " << i;
    }
    EXPECT_TRUE(out.degraded);
}

void expectObstacleAt(double rangeM, double bearingDeg, const Tint& tint)
{
    const auto scene = catalogue("box", rangeM, bearingDeg);
    const auto frame = renderScene(scene);
    auto sut = makeSut(scene.rig);
    ObstacleSectors out;

    ASSERT_EQ(sut.process(bgrView(tintByLabels(frame, tint)), out), ColourFreeSpaceStatus::Ok);

    ASSERT_TRUE(sut.reference().groundLike);
    const std::size_t hit = sectorAt(out, bearingDeg);
    const auto& truth = frame.sectors.sectors[hit];
    ASSERT_EQ(truth.state, SectorState::Obstacle);
    EXPECT_EQ(out.sectors[hit].state, SectorState::Obstacle);
    EXPECT_EQ(out.sectors[hit].kind, ugv::ObstacleKind::Positive);
    EXPECT_NEAR(out.sectors[hit].rangeM, truth.rangeM, 0.05 * truth.rangeM) << "truth " << truth.rangeM;
    std::printf("box at %.1f m, %.0f deg: free range %.3f m, truth %.3f m, band coverage %.2f\n", rangeM, bearingDeg,
                out.sectors[hit].rangeM, truth.rangeM, sut.reference().coverage);
    // Sectors well away from the box (10 deg beyond its bearing, on the far side of the axis) are clear.
    const std::size_t away = sectorAt(out, bearingDeg > 0.0 ? bearingDeg - 20.0 : bearingDeg + 20.0);
    EXPECT_EQ(out.sectors[away].state, SectorState::Clear);
}

TEST(ColourFreeSpace, BrownBoxAheadGivesItsRangeInItsSector)
{
    expectObstacleAt(5.0, 0.0, {});
}

TEST(ColourFreeSpace, GreyBoxToTheLeftGivesItsRangeInItsSector)
{
    expectObstacleAt(4.0, 12.0, Tint{0, 10, false});
}

TEST(ColourFreeSpace, BoxToTheRightAtThreeMetres)
{
    expectObstacleAt(3.0, -15.0, {});
}

TEST(ColourFreeSpace, GreyGroundHasColoursToo)
{
    // Asphalt-like: no hue anywhere. The grey ground's brightness is its colour, and a box twice as bright stands out.
    const auto scene = catalogue("box", 4.0, 0.0);
    const auto frame = renderScene(scene);
    cv::Mat bgr;
    cv::cvtColor(frame.left, bgr, cv::COLOR_GRAY2BGR);
    const cv::Mat box = frame.labels != static_cast<std::uint8_t>(ugv::sim::Label::Ground);
    bgr.setTo(cv::Scalar(200, 200, 200), box);
    auto sut = makeSut(scene.rig);
    ObstacleSectors out;

    ASSERT_EQ(sut.process(bgrView(bgr), out), ColourFreeSpaceStatus::Ok);

    EXPECT_TRUE(sut.reference().groundLike) << sut.reference().coverage;
    const std::size_t hit = sectorAt(out, 0.0);
    const auto& truth = frame.sectors.sectors[hit];
    ASSERT_EQ(truth.state, SectorState::Obstacle);
    EXPECT_EQ(out.sectors[hit].state, SectorState::Obstacle);
    EXPECT_NEAR(out.sectors[hit].rangeM, truth.rangeM, 0.05 * truth.rangeM);
    EXPECT_EQ(out.sectors[sectorAt(out, 20.0)].state, SectorState::Clear);
}

TEST(ColourFreeSpace, AGreyImageGivesWhatItsColourCopyGives)
{
    // A monochrome camera: the grey path bins by brightness exactly as the colour path bins a pixel with B = G = R.
    const auto scene = catalogue("box", 3.0, -10.0);
    const auto frame = renderScene(scene);
    cv::Mat bgr;
    cv::cvtColor(frame.left, bgr, cv::COLOR_GRAY2BGR);
    auto fromColour = makeSut(scene.rig);
    auto fromGrey = makeSut(scene.rig);
    ObstacleSectors colourOut;
    ObstacleSectors greyOut;
    const ugv::ConstImageViewU8 grey(frame.left.ptr<std::uint8_t>(), frame.left.cols, frame.left.rows,
                                     static_cast<std::ptrdiff_t>(frame.left.step));

    ASSERT_EQ(fromColour.process(bgrView(bgr), colourOut), ColourFreeSpaceStatus::Ok);
    ASSERT_EQ(fromGrey.process(grey, greyOut), ColourFreeSpaceStatus::Ok);

    EXPECT_TRUE(fromGrey.reference().groundLike);
    EXPECT_EQ(fromGrey.groundColours(), fromColour.groundColours());
    int differing = 0;
    for (int y = 0; y < fromGrey.scores().height(); ++y) {
        for (int x = 0; x < fromGrey.scores().width(); ++x) {
            differing += fromGrey.scores().at(x, y) == fromColour.scores().at(x, y) ? 0 : 1;
        }
    }
    EXPECT_EQ(differing, 0);
    for (int i = 0; i < greyOut.count; ++i) {
        const auto k = static_cast<std::size_t>(i);
        EXPECT_EQ(greyOut.sectors[k].state, colourOut.sectors[k].state) << "sector " << i;
        EXPECT_EQ(greyOut.sectors[k].rangeM, colourOut.sectors[k].rangeM) << "sector " << i;
    }
}

TEST(ColourFreeSpace, AnObstacleStandingInPartOfTheBandIsNotGround)
{
    // A brown post at 1.4 m stands in the reference band (its base is in the band's rows): its colour holds one slice
    // of the band, the grass all of them, so the post is an obstacle and the rest is clear.
    ugv::sim::Scene scene = catalogue("empty", 5.0, 0.0);
    constexpr double kBearingDeg = 12.0;
    scene.obstacles.push_back(ugv::sim::box(1.4, kBearingDeg, 0.15, 0.15, 0.8));
    const auto frame = renderScene(scene);
    auto sut = makeSut(scene.rig);
    ObstacleSectors out;

    ASSERT_EQ(sut.process(bgrView(tintByLabels(frame, {})), out), ColourFreeSpaceStatus::Ok);

    EXPECT_TRUE(sut.reference().groundLike);
    const std::size_t hit = sectorAt(out, kBearingDeg);
    EXPECT_EQ(out.sectors[hit].state, SectorState::Obstacle);
    EXPECT_LT(out.sectors[hit].rangeM, 1.6F);
    EXPECT_EQ(out.sectors[sectorAt(out, -20.0)].state, SectorState::Clear);
}

TEST(ColourFreeSpace, AnObstacleOverAThirdOfTheBandIsNeverClearBehindIt)
{
    // A brown box at 1.25 m covers a third of the image's width from the bottom up: its colour is in 4 of the band's
    // 8 slices, so it is learnt as a ground colour, but only tentatively (under 6 of 8). Its sectors are not known
    // to be free: Unknown, never Clear. Counted with the rule off (clearSliceFraction = minSliceFraction) too, which
    // calls them Clear.
    const auto scene = catalogue("box", 1.25, 0.0);
    const auto frame = renderScene(scene);
    const cv::Mat bgr = tintByLabels(frame, {});
    auto sut = makeSut(scene.rig);
    ColourFreeSpaceConfig off;
    off.clearSliceFraction = off.minSliceFraction;
    auto without = makeSut(scene.rig, off);
    ObstacleSectors out;
    ObstacleSectors outWithout;

    ASSERT_EQ(sut.process(bgrView(bgr), out), ColourFreeSpaceStatus::Ok);
    ASSERT_EQ(without.process(bgrView(bgr), outWithout), ColourFreeSpaceStatus::Ok);

    ASSERT_TRUE(sut.reference().groundLike);
    int truthObstacle = 0;
    int clear = 0;
    int clearWithout = 0;
    for (std::size_t i = 0; i < static_cast<std::size_t>(out.count); ++i) {
        if (frame.sectors.sectors[i].state == SectorState::Obstacle) {
            ++truthObstacle;
            clear += out.sectors[i].state == SectorState::Clear ? 1 : 0;
            clearWithout += outWithout.sectors[i].state == SectorState::Clear ? 1 : 0;
        }
    }
    EXPECT_GE(truthObstacle, 15);
    EXPECT_EQ(clear, 0) << "of " << truthObstacle << " sectors the box stands in";
    EXPECT_GE(clearWithout, truthObstacle / 2) << "the rule off: the box's colour is ground, its sectors Clear";
    EXPECT_EQ(out.sectors[sectorAt(out, -25.0)].state, SectorState::Clear);
    EXPECT_EQ(out.sectors[sectorAt(out, 25.0)].state, SectorState::Clear);
}

TEST(ColourFreeSpace, AnObstacleFillingTheViewIsUnknownNotClear)
{
    // A barrier across the whole view at 1.25 m, taller than the camera: the band sees only the barrier, whose colours
    // are therefore learnt as the ground's in every slice. But they go on above the horizon, where no ground can be
    // seen: every sector is Unknown, none Clear.
    const auto scene = catalogue("barrier", 1.25, 0.0);
    const auto frame = renderScene(scene);
    auto sut = makeSut(scene.rig);
    ObstacleSectors out;

    ASSERT_EQ(sut.process(bgrView(tintByLabels(frame, {})), out), ColourFreeSpaceStatus::Ok);

    for (int i = 0; i < out.count; ++i) {
        EXPECT_NE(out.sectors[static_cast<std::size_t>(i)].state, SectorState::Clear) << "sector " << i;
    }
    int aboveHorizon = 0;
    for (const std::uint8_t unsure : sut.columnUnsure()) {
        aboveHorizon += unsure;
    }
    EXPECT_EQ(aboveHorizon, scene.rig.width);
}

TEST(ColourFreeSpace, AGroundWhoseHueDriftsAcrossABinEdgeStaysClear)
{
    // The band's grass has hue 52 (bin 4 of 0..179 in 16 bins); beyond 3 m it dries to hue 44 (bin 3), a colour the
    // band never showed. Without the one-bin hue tolerance every sector would end at 3 m.
    const auto scene = catalogue("empty", 5.0, 0.0);
    const auto frame = renderScene(scene);
    cv::Mat bgr = tintByLabels(frame, {});
    cv::Mat hsv;
    cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
    const double rowAt3m = scene.rig.cy() + scene.rig.focalPx * scene.rig.heightM / 3.0;
    for (int y = 0; y < hsv.rows; ++y) {
        for (int x = 0; x < hsv.cols; ++x) {
            auto& p = hsv.at<cv::Vec3b>(y, x);
            if (frame.labels.at<std::uint8_t>(y, x) == static_cast<std::uint8_t>(ugv::sim::Label::Ground)) {
                p[0] = y < rowAt3m ? 44 : 52;
            }
        }
    }
    cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
    auto sut = makeSut(scene.rig);
    ObstacleSectors out;

    ASSERT_EQ(sut.process(bgrView(bgr), out), ColourFreeSpaceStatus::Ok);

    ASSERT_TRUE(sut.reference().groundLike);
    for (int i = 0; i < out.count; ++i) {
        EXPECT_EQ(out.sectors[static_cast<std::size_t>(i)].state, SectorState::Clear) << "sector " << i;
    }
}

TEST(ColourFreeSpace, ABandWithNoColourAlongHalfOfItIsUnknownNotClear)
{
    // Clutter: blocks of random colours, none of them along half the band. No colour is the ground's with any
    // certainty, so every sector is Unknown (never Clear).
    const ugv::sim::Rig rig;
    cv::Mat hsv(rig.height, rig.width, CV_8UC3);
    cv::RNG random(7);
    constexpr int kBlock = 40;
    for (int y = 0; y < rig.height; y += kBlock) {
        for (int x = 0; x < rig.width; x += kBlock) {
            const cv::Scalar colour(random.uniform(0, 180), random.uniform(80, 256), random.uniform(60, 256));
            hsv(cv::Rect(x, y, std::min(kBlock, rig.width - x), std::min(kBlock, rig.height - y))).setTo(colour);
        }
    }
    cv::Mat bgr;
    cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
    auto sut = makeSut(rig);
    ObstacleSectors out;

    ASSERT_EQ(sut.process(bgrView(bgr), out), ColourFreeSpaceStatus::Ok);

    EXPECT_FALSE(sut.reference().groundLike) << sut.reference().coverage;
    EXPECT_LT(sut.reference().coverage, ColourFreeSpaceConfig{}.minGroundCoverage);
    for (int i = 0; i < out.count; ++i) {
        EXPECT_EQ(out.sectors[static_cast<std::size_t>(i)].state, SectorState::Unknown) << "sector " << i;
        EXPECT_EQ(out.sectors[static_cast<std::size_t>(i)].confidence, 0.0F);
    }
}

TEST(ColourFreeSpace, ATooDarkBandIsUnknownNotClear)
{
    const auto scene = catalogue("empty", 5.0, 0.0);
    const cv::Mat night = tintByLabels(renderScene(scene), {}) * 0.15;
    auto sut = makeSut(scene.rig);
    ObstacleSectors out;

    ASSERT_EQ(sut.process(bgrView(night), out), ColourFreeSpaceStatus::Ok);

    EXPECT_LT(sut.reference().meanValue, ColourFreeSpaceConfig{}.minBandValue);
    EXPECT_FALSE(sut.reference().groundLike);
    for (int i = 0; i < out.count; ++i) {
        EXPECT_EQ(out.sectors[static_cast<std::size_t>(i)].state, SectorState::Unknown) << "sector " << i;
    }
}

TEST(ColourFreeSpace, IncrementalScoresEqualPerWindowRecomputation)
{
    const auto scene = catalogue("pole", 4.0, 5.0);
    const auto frame = renderScene(scene);
    ColourFreeSpaceConfig config;
    config.windowRadius = 4;
    auto sut = makeSut(scene.rig, config);
    ObstacleSectors out;
    ASSERT_EQ(sut.process(bgrView(tintByLabels(frame, {})), out), ColourFreeSpaceStatus::Ok);

    const int r = config.windowRadius;
    const int area = (2 * r + 1) * (2 * r + 1);
    const auto bins = sut.bins();
    const auto scores = sut.scores();
    const auto& ground = sut.groundColours();
    int mismatches = 0;
    int checked = 0;
    for (int y = sut.roiTop(); y < scene.rig.height - r; y += 3) {
        for (int x = r; x < scene.rig.width - r; x += 2) {
            int common = 0;
            for (int v = y - r; v <= y + r; ++v) {
                for (int u = x - r; u <= x + r; ++u) {
                    common += ground[bins.at(u, v - sut.binTop())];
                }
            }
            const int expected = (common * 255 + area / 2) / area;
            mismatches += scores.at(x, y - sut.roiTop()) == expected ? 0 : 1;
            ++checked;
        }
    }
    EXPECT_GT(checked, 10000);
    EXPECT_EQ(mismatches, 0);
}

TEST(ColourFreeSpace, ProcessAllocatesNothingOver300Frames)
{
    const auto scene = catalogue("box", 4.0, 0.0);
    const cv::Mat bgr = tintByLabels(renderScene(scene), {});
    auto sut = makeSut(scene.rig);
    ObstacleSectors out;
    ASSERT_EQ(sut.process(bgrView(bgr), out), ColourFreeSpaceStatus::Ok);
    constexpr int kFrames = 300;
    int ok = 0;

    const ugv::test::AllocationScope scope;
    for (int i = 0; i < kFrames; ++i) {
        ok += sut.process(bgrView(bgr), out) == ColourFreeSpaceStatus::Ok ? 1 : 0;
    }
    const std::size_t allocations = scope.count();

    EXPECT_EQ(allocations, 0U);
    EXPECT_EQ(ok, kFrames);
}

TEST(ColourFreeSpace, WrongImageSizeGivesAllUnknown)
{
    const ugv::sim::Rig rig;
    auto sut = makeSut(rig);
    const cv::Mat small(240, 320, CV_8UC3, cv::Scalar(40, 160, 40));
    ObstacleSectors out;

    EXPECT_EQ(sut.process(bgrView(small), out), ColourFreeSpaceStatus::WrongInputSize);

    ASSERT_EQ(out.count, 64);
    for (int i = 0; i < out.count; ++i) {
        EXPECT_EQ(out.sectors[static_cast<std::size_t>(i)].state, SectorState::Unknown);
    }
}

TEST(ColourFreeSpace, CreateRejectsBadConfigNamingIt)
{
    const ugv::vision::RectifiedProjection projection{546, 546, 319.5, 239.5, 0.3};
    const auto ground = ugv::vision::GroundPlane::fromMount({0.59, 0.0, 0.0});
    ColourFreeSpaceConfig window;
    window.windowRadius = 0;
    ColourFreeSpaceConfig band;
    band.bandRows = 300;
    ColourFreeSpaceConfig threshold;
    threshold.matchThreshold = 0.0;
    ColourFreeSpaceConfig sectors;
    sectors.sectorCount = ugv::kMaxSectors + 1;
    ColourFreeSpaceConfig clear;
    clear.clearSliceFraction = clear.minSliceFraction / 2.0; // Clear on less evidence than a ground colour needs

    const auto badWindow = ColourFreeSpace::create(window, {640, 480}, projection, ground);
    const auto badBand = ColourFreeSpace::create(band, {640, 480}, projection, ground);
    const auto badThreshold = ColourFreeSpace::create(threshold, {640, 480}, projection, ground);
    const auto badSectors = ColourFreeSpace::create(sectors, {640, 480}, projection, ground);
    const auto badClear = ColourFreeSpace::create(clear, {640, 480}, projection, ground);
    const auto badGround = ColourFreeSpace::create({}, {640, 480}, projection, ugv::vision::GroundPlane{});

    ASSERT_FALSE(badWindow.has_value());
    EXPECT_NE(badWindow.error().what.find("windowRadius"), std::string::npos);
    ASSERT_FALSE(badBand.has_value());
    EXPECT_NE(badBand.error().what.find("bandRows"), std::string::npos);
    ASSERT_FALSE(badThreshold.has_value());
    EXPECT_NE(badThreshold.error().what.find("matchThreshold"), std::string::npos);
    ASSERT_FALSE(badSectors.has_value());
    EXPECT_NE(badSectors.error().what.find("sectorCount"), std::string::npos);
    ASSERT_FALSE(badClear.has_value());
    EXPECT_NE(badClear.error().what.find("clearSliceFraction"), std::string::npos);
    ASSERT_FALSE(badGround.has_value());
    EXPECT_FALSE(badGround.error().fix.empty());
}

} // namespace
