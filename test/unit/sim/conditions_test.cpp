// The real-world conditions of the simulator (issue 20): ground shapes against analytic ray-surface intersections,
// kerb and pavement truth, mirrors, markings, shadows and photometry that change the images but not the truth, and
// the defaults that render exactly as before these conditions existed.

#include <cmath>
#include <cstdint>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "sim_test_helpers.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"

namespace ugv::sim {
namespace {

/// FNV-1a over the bytes of every row of `m`.
std::uint64_t hashMat(const cv::Mat& m, std::uint64_t h = 1469598103934665603ULL)
{
    for (int y = 0; y < m.rows; ++y) {
        const auto* row = m.ptr<std::uint8_t>(y);
        for (std::size_t i = 0; i < m.cols * m.elemSize(); ++i) {
            h = (h ^ row[i]) * 1099511628211ULL;
        }
    }
    return h;
}

std::uint64_t hashResult(const RenderResult& r)
{
    std::uint64_t h = hashMat(r.left);
    for (const cv::Mat* m : {&r.right, &r.disparity, &r.depth, &r.labels, &r.ids}) {
        h = hashMat(*m, h);
    }
    return h;
}

bool sameTruth(const RenderResult& a, const RenderResult& b)
{
    return cv::norm(a.disparity, b.disparity, cv::NORM_INF) == 0.0 &&
           cv::norm(a.labels, b.labels, cv::NORM_INF) == 0.0 && cv::norm(a.ids, b.ids, cv::NORM_INF) == 0.0 &&
           countState(a.sectors, SectorState::Obstacle) == countState(b.sectors, SectorState::Obstacle) &&
           countState(a.sectors, SectorState::Clear) == countState(b.sectors, SectorState::Clear);
}

/// The scene of the golden hash: a pole, a hole and a mesh fence on gravel, 160x120.
Scene goldenScene()
{
    Scene scene = sceneWith(smallRig(4), {pole(3.0, 10.0), hole(5.0, -8.0, 1.0, 0.5), meshFence(7.0, 0.0, 3.0)});
    scene.texture = GroundTexture::Gravel;
    scene.seed = 5;
    return scene;
}

/// Ray through left pixel (u, v) of a level rig: direction (1, -b, -a) in the vehicle frame.
struct PixelRay {
    double a; ///< (v - cy) / f
    double b; ///< (u - cx) / f
};
PixelRay pixelRay(const Rig& rig, int u, int v)
{
    return {(v - rig.cy()) / rig.focalPx, (u - rig.cx()) / rig.focalPx};
}

TEST(SimConditions, DefaultsRenderBitIdenticalToTheRendererBeforeTheConditions)
{
    // Golden hash of goldenScene() from the renderer of commit ae26e47, before the conditions existed (same flags).
    constexpr std::uint64_t kGolden = 0xa5b4137ffd4c7b8fULL;
    const RenderResult sut = renderOk(goldenScene());
    EXPECT_EQ(hashResult(sut), kGolden) << std::hex << hashResult(sut);
}

TEST(SimConditions, ConditionsSwitchedOffRenderBitIdenticalToDefaults)
{
    const RenderResult defaults = renderOk(goldenScene());
    Scene off = goldenScene();
    off.ground.kerbY = 3.0;        // no kerb height: no kerb
    off.ground.gradeAtX = 2.0;     // no grade change
    off.markings.stopLineX = -5.0; // none
    off.shadows.push_back(Shadow{{{1.0, -5.0}, {9.0, -5.0}, {9.0, 5.0}}, 1.0});
    off.reflectors.push_back(Reflector{4.0, 0.0, 2.0, 2.0, true, 0.0});
    const RenderResult sut = renderOk(off);
    EXPECT_EQ(hashResult(sut), hashResult(defaults));
}

TEST(SimConditions, CamberedGroundDisparityMatchesAnalyticValueAndIsClearGround)
{
    constexpr double kSlope = 0.03;
    Scene scene = sceneWith(smallRig(2), {});
    scene.ground.camberSlope = kSlope; // crown at y = 0: falls to both sides
    const RenderResult sut = renderOk(scene);
    const Rig& rig = scene.rig;
    for (const auto& [u, v] : {std::pair{20, 200}, std::pair{300, 200}, std::pair{160, 150}, std::pair{250, 130}}) {
        const PixelRay r = pixelRay(rig, u, v);
        // z = h - lambda a = -s |lambda b|  =>  lambda = h / (a - s |b|); disparity f B / lambda.
        const double lambda = rig.heightM / (r.a - kSlope * std::abs(r.b));
        const double expected = rig.focalPx * rig.baselineM / lambda;
        EXPECT_NEAR(sut.disparity.at<float>(v, u), expected, 1e-4 * expected) << u << "," << v;
        EXPECT_EQ(sut.labels.at<std::uint8_t>(v, u), static_cast<std::uint8_t>(Label::Ground));
        EXPECT_NEAR(sut.height.at<float>(v, u), 0.0F, 1e-5F);
    }
    // Flat ground would give f B a / h: at the image's edge the ground has fallen 5 cm, 2.3 px less disparity.
    const PixelRay edge = pixelRay(rig, 0, 200);
    EXPECT_LT(sut.disparity.at<float>(200, 0) - rig.focalPx * rig.baselineM * edge.a / rig.heightM, -2.0);
    EXPECT_EQ(countState(sut.sectors, SectorState::Obstacle), 0);
    EXPECT_EQ(countState(sut.sectors, SectorState::Clear), sut.sectors.count);
}

TEST(SimConditions, GradeChangeDisparityMatchesAnalyticValueBeyondTheGradeLine)
{
    constexpr double kGrade = 0.05;
    constexpr double kAtM = 4.0;
    Scene scene = sceneWith(smallRig(2), {});
    scene.ground.gradeChange = kGrade;
    scene.ground.gradeAtX = kAtM;
    const RenderResult sut = renderOk(scene);
    const Rig& rig = scene.rig;
    for (const int v : {125, 130, 140}) { // ground beyond 4 m at the centre column
        const PixelRay r = pixelRay(rig, 160, v);
        // h - lambda a = g (lambda - x0)  =>  lambda = (h + g x0) / (a + g)
        const double lambda = (rig.heightM + kGrade * kAtM) / (r.a + kGrade);
        ASSERT_GT(lambda, kAtM);
        const double expected = rig.focalPx * rig.baselineM / lambda;
        EXPECT_NEAR(sut.disparity.at<float>(v, 160), expected, 1e-4 * expected) << v;
        EXPECT_EQ(sut.labels.at<std::uint8_t>(v, 160), static_cast<std::uint8_t>(Label::Ground));
    }
    // Uphill beyond the grade line: ground where the flat world shows sky (the horizon rises).
    EXPECT_EQ(sut.labels.at<std::uint8_t>(118, 160), static_cast<std::uint8_t>(Label::Ground));
    EXPECT_EQ(countState(sut.sectors, SectorState::Obstacle), 0);
}

TEST(SimConditions, PavementBeyondKerbIsGroundAndKerbFaceIsPositiveObstacle)
{
    constexpr double kKerbY = -2.0;
    constexpr double kKerbM = 0.15;
    Scene scene = sceneWith(smallRig(2), {});
    scene.ground.kerbY = kKerbY;
    scene.ground.kerbHeightM = kKerbM;
    const RenderResult sut = renderOk(scene);
    const Rig& rig = scene.rig;
    int pavement = 0;
    int face = 0;
    for (int v = 125; v < rig.height; ++v) {
        for (int u = 161; u < rig.width; ++u) {
            const PixelRay r = pixelRay(rig, u, v);
            const double tPave = (rig.heightM - kKerbM) / r.a; // lambda where the ray meets z = 0.15
            const double tKerb = -kKerbY / r.b;                // lambda where it meets y = -2
            const double zKerb = rig.heightM - tKerb * r.a;
            const auto label = static_cast<Label>(sut.labels.at<std::uint8_t>(v, u));
            const double d = sut.disparity.at<float>(v, u);
            if (zKerb > 0.01 && zKerb < kKerbM - 0.01) { // the face, away from its edges
                ++face;
                EXPECT_EQ(label, Label::Positive) << u << "," << v;
                EXPECT_NEAR(d, rig.focalPx * rig.baselineM / tKerb, 1e-3) << u << "," << v;
                EXPECT_EQ(sut.ids.at<std::uint16_t>(v, u), 1); // no obstacles: the kerb is obstacle count + 1
            } else if (tPave * r.b > -kKerbY + 0.01) {         // beyond the kerb, on the pavement
                ++pavement;
                EXPECT_EQ(label, Label::Ground) << u << "," << v;
                EXPECT_NEAR(d, rig.focalPx * rig.baselineM / tPave, 1e-3) << u << "," << v;
                EXPECT_NEAR(sut.height.at<float>(v, u), 0.0F, 1e-5F);
            }
        }
    }
    EXPECT_GT(face, 100);
    EXPECT_GT(pavement, 1000);
    // Sectors: obstacle (the kerb's top, over 0.10 m) only on the right, ranges those of the kerb line y = -2.
    int obstacles = 0;
    for (int i = 0; i < sut.sectors.count; ++i) {
        const Sector& s = sector(sut.sectors, i);
        if (s.state == SectorState::Obstacle) {
            ++obstacles;
            EXPECT_LT(s.bearingMaxDeg, 0.0F);
            EXPECT_EQ(s.kind, ObstacleKind::Positive);
            // Nearer than 15 m (beyond, the top 5 cm of the face are under a pixel high): the kerb line's range.
            const double expected = -kKerbY / std::sin(-s.bearingMinDeg * 3.14159265 / 180.0);
            if (expected < 15.0) {
                EXPECT_NEAR(s.rangeM, expected, 0.03 * expected) << i;
            }
        }
    }
    EXPECT_GT(obstacles, 10);
    EXPECT_EQ(sector(sut.sectors, sectorAt(sut.sectors, 0.0F)).state, SectorState::Clear);
}

TEST(SimConditions, ObstacleOnAGradeStandsOnTheLocalSurface)
{
    Scene scene = sceneWith(smallRig(2), {pole(7.0, 0.0, 0.1, 1.5)});
    scene.ground.gradeChange = 0.05;
    scene.ground.gradeAtX = 4.0; // the ground at the pole: 0.05 * 3.1 = 0.155 m up
    const RenderResult sut = renderOk(scene);
    float lowest = 10.0F;
    float highest = -10.0F;
    for (int v = 0; v < sut.labels.rows; ++v) {
        for (int u = 150; u < 170; ++u) {
            if (sut.ids.at<std::uint16_t>(v, u) == 1) {
                lowest = std::min(lowest, sut.height.at<float>(v, u));
                highest = std::max(highest, sut.height.at<float>(v, u));
            }
        }
    }
    EXPECT_NEAR(lowest, 0.0F, 0.03F);  // it meets the ground ...
    EXPECT_NEAR(highest, 1.5F, 0.03F); // ... and is 1.5 m tall above it
    const Sector& s = sector(sut.sectors, sectorAt(sut.sectors, 0.0F));
    EXPECT_EQ(s.state, SectorState::Obstacle);
    EXPECT_NEAR(s.rangeM, 7.0F, 0.03F);
}

TEST(SimConditions, PuddleMirrorsThePoleButItsTruthIsTheFloor)
{
    Scene dry = sceneWith(smallRig(2), {pole(4.0, 0.0, 0.1, 1.5)});
    Scene wet = dry;
    wet.reflectors.push_back(Reflector{3.0, 0.0, 0.8, 0.6, true, 0.8});
    const RenderResult sut = renderOk(wet);
    const RenderResult reference = renderOk(dry);
    EXPECT_TRUE(sameTruth(sut, reference));
    const Rig& rig = wet.rig;
    // A puddle pixel below the pole, at ground 2.6 m: the floor's disparity f B a / h.
    const int row = static_cast<int>(std::lround(rig.cy() + rig.focalPx * rig.heightM / 2.6));
    const PixelRay r = pixelRay(rig, 160, row);
    EXPECT_NEAR(sut.disparity.at<float>(row, 160), rig.focalPx * rig.baselineM * r.a / rig.heightM, 1e-3);
    EXPECT_EQ(sut.labels.at<std::uint8_t>(row, 160), static_cast<std::uint8_t>(Label::Ground));
    // Its image: the mirrored (dark) pole in the pole's columns, the mirrored (bright) sky beside it.
    const auto mean = [&](const cv::Mat& img, int u) { return cv::mean(img(cv::Rect(u - 1, row - 2, 3, 5)))[0]; };
    EXPECT_LT(mean(sut.left, 160) + 60.0, mean(sut.left, 175));
    EXPECT_GT(mean(sut.left, 175), mean(reference.left, 175) + 60.0);
    EXPECT_GT(std::abs(mean(sut.left, 160) - mean(reference.left, 160)), 10.0);
}

TEST(SimConditions, GlossyFloorMirrorsTheBackgroundWallAndStaysGround)
{
    Scene scene = sceneWith(smallRig(2), {});
    scene.background.type = BackgroundType::Walls;
    ASSERT_TRUE(applyCondition(scene, "glossy", 2).has_value());
    const RenderResult sut = renderOk(scene);
    scene.reflectors.clear();
    const RenderResult matte = renderOk(scene);
    EXPECT_TRUE(sameTruth(sut, matte));
    EXPECT_GT(cv::norm(sut.left, matte.left, cv::NORM_L1) / static_cast<double>(sut.left.total()), 10.0);
    EXPECT_EQ(countState(sut.sectors, SectorState::Obstacle), 0);
}

TEST(SimConditions, PhotometryAndJpegChangeTheImagesButNotTheTruth)
{
    const Scene plain = sceneWith(smallRig(2), {box(4.0, 5.0)});
    const RenderResult reference = renderOk(plain);
    Scene scene = plain;
    scene.lighting.jpegQuality = 50;
    scene.lighting.rightGain = 0.85;
    scene.lighting.rightOffsetGrey = 5.0;
    scene.lighting.vignetteRight = 0.4;
    const RenderResult sut = renderOk(scene);
    EXPECT_TRUE(sameTruth(sut, reference));
    const double leftDiff = cv::norm(sut.left, reference.left, cv::NORM_L1) / static_cast<double>(sut.left.total());
    EXPECT_GT(leftDiff, 0.3); // JPEG only
    EXPECT_LT(leftDiff, 8.0);
    // The right image: darker overall, most at the corners (gain 0.85 and vignetting).
    const double centre =
        cv::mean(sut.right(cv::Rect(150, 110, 20, 20)))[0] - cv::mean(reference.right(cv::Rect(150, 110, 20, 20)))[0];
    const double corner =
        cv::mean(sut.right(cv::Rect(0, 0, 20, 20)))[0] - cv::mean(reference.right(cv::Rect(0, 0, 20, 20)))[0];
    EXPECT_LT(centre, -5.0);
    EXPECT_LT(corner, centre - 20.0);
}

TEST(SimConditions, PaintRailsAndShadowsChangeTheAlbedoOnly)
{
    const Scene plain = sceneWith(smallRig(2), {});
    const RenderResult reference = renderOk(plain);
    Scene scene = plain;
    scene.markings.stopLineX = 4.0; // 4.0 to 4.3 m
    scene.markings.tracksY = {0.0};
    scene.shadows.push_back(Shadow{{{6.0, -20.0}, {12.0, -20.0}, {12.0, 20.0}, {6.0, 20.0}}, 0.3});
    const RenderResult sut = renderOk(scene);
    EXPECT_TRUE(sameTruth(sut, reference));
    EXPECT_EQ(countState(sut.sectors, SectorState::Obstacle), 0);
    const Rig& rig = scene.rig;
    const auto rowAt = [&](double x) {
        return static_cast<int>(std::lround(rig.cy() + rig.focalPx * rig.heightM / x));
    };
    const auto mean = [](const cv::Mat& img, int u, int v) { return cv::mean(img(cv::Rect(u - 3, v, 7, 1)))[0]; };
    EXPECT_GT(mean(sut.left, 100, rowAt(4.15)), mean(reference.left, 100, rowAt(4.15)) + 60.0); // paint
    const double shaded = mean(sut.left, 100, rowAt(8.0)) / mean(reference.left, 100, rowAt(8.0));
    EXPECT_NEAR(shaded, 0.3, 0.08);
    // The rail head at y = -0.7175 (right of the centre) at 3 m: brighter than the plain ground.
    const int u = static_cast<int>(std::lround(rig.cx() + rig.focalPx * 0.7175 / 3.0));
    EXPECT_GT(sut.left.at<std::uint8_t>(rowAt(3.0), u), reference.left.at<std::uint8_t>(rowAt(3.0), u) + 40);
}

TEST(SimConditions, CastShadowOfAPoleReachesItsHeightOverTanOfTheSunElevation)
{
    const Obstacle caster = pole(5.0, 0.0, 0.1, 2.0);   // centre at (5.1, 0)
    const Shadow sut = castShadow(caster, 180.0, 45.0); // sun behind: the shadow points forward, 2 m long
    ASSERT_GE(sut.polygon.size(), 3U);
    double maxX = -1e9;
    double minX = 1e9;
    for (const auto& [x, y] : sut.polygon) {
        maxX = std::max(maxX, x);
        minX = std::min(minX, x);
    }
    EXPECT_NEAR(maxX, 5.1 + 0.1 + 2.0, 1e-9);
    EXPECT_NEAR(minX, 5.0, 1e-9);
    EXPECT_TRUE(castShadow(hole(3.0, 0.0, 1.0, 0.5), 180.0, 45.0).polygon.empty());
}

TEST(SimConditions, EveryConditionRendersAnEmptySceneWithNoObstacleInTheTruthButTheKerb)
{
    for (const std::string& name : conditionNames()) {
        for (int variant = 0; variant < 3; ++variant) {
            Scene scene = sceneWith(smallRig(4), {});
            ASSERT_TRUE(applyCondition(scene, name, variant).has_value()) << name;
            const RenderResult sut = renderOk(scene);
            const int obstacles = countState(sut.sectors, SectorState::Obstacle);
            if (name == "kerb") {
                EXPECT_GT(obstacles, 0) << name << " " << variant;
            } else {
                EXPECT_EQ(obstacles, 0) << name << " " << variant;
            }
        }
    }
    Scene scene;
    EXPECT_FALSE(applyCondition(scene, "fog").has_value());
}

TEST(SimConditions, InvalidConditionsAreErrors)
{
    const auto invalid = [](auto change) {
        Scene scene;
        change(scene);
        return !render(scene).has_value();
    };
    EXPECT_TRUE(invalid([](Scene& s) { s.ground.kerbHeightM = 0.1, s.ground.kerbY = 0.0; }));
    EXPECT_TRUE(invalid([](Scene& s) { s.ground.camberSlope = -0.01; }));
    EXPECT_TRUE(invalid([](Scene& s) { s.lighting.jpegQuality = 101; }));
    EXPECT_TRUE(invalid([](Scene& s) { s.lighting.vignetteLeft = 1.0; }));
    EXPECT_TRUE(invalid([](Scene& s) { s.reflectors.push_back(Reflector{4.0, 0.0, 1.0, 1.0, true, 1.5}); }));
    EXPECT_TRUE(invalid([](Scene& s) { s.shadows.push_back(Shadow{{{0.0, 0.0}, {1.0, 0.0}}, 0.3}); }));
    EXPECT_TRUE(invalid([](Scene& s) { s.markings.laneLinesY = {std::nan("")}; }));
    EXPECT_FALSE(invalid([](Scene& s) { s.markings.laneLinesY = {1.75}; }));
}

} // namespace
} // namespace ugv::sim
