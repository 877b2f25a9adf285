#include "ugv/sim/renderer.hpp"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "sim_test_helpers.hpp"
#include "ugv/sim/scene.hpp"

namespace ugv::sim {
namespace {

TEST(SimRenderer, FlatGroundDisparityMatchesAnalyticGroundPlane)
{
    const Scene scene = sceneWith(smallRig(4), {});
    const RenderResult sut = renderOk(scene);
    ASSERT_EQ(sut.disparity.rows, scene.rig.height);
    ASSERT_EQ(sut.disparity.type(), CV_32F);
    const double slope = scene.rig.baselineM / scene.rig.heightM; // [px/px]
    double worst = 0.0;
    for (int y = 0; y < scene.rig.height; ++y) {
        for (int x = 0; x < scene.rig.width; ++x) {
            const float d = sut.disparity.at<float>(y, x);
            if (y > scene.rig.cy()) {
                worst = std::max(worst, std::abs(d - slope * (y - scene.rig.cy())));
                EXPECT_EQ(sut.labels.at<std::uint8_t>(y, x), static_cast<std::uint8_t>(Label::Ground));
                EXPECT_NEAR(sut.height.at<float>(y, x), 0.0F, 1e-5F);
            } else {
                EXPECT_EQ(d, 0.0F);
                EXPECT_EQ(sut.labels.at<std::uint8_t>(y, x), static_cast<std::uint8_t>(Label::Far));
                EXPECT_TRUE(std::isinf(sut.depth.at<float>(y, x)));
            }
        }
    }
    EXPECT_LT(worst, 1e-3);
    EXPECT_EQ(sut.sectors.count, 64);
    EXPECT_EQ(countState(sut.sectors, SectorState::Clear), 64);
    EXPECT_EQ(sector(sut.sectors, 0).danger, DangerClass::Green);
}

// The image rays are traced on several threads; each pixel alone, the noise drawn in pixel order on one thread:
// the images are the same bit for bit with 1 thread and with 3 (rows dealt out unevenly), in grey and in colour.
TEST(SimRenderer, ImagesAreTheSameWhateverTheNumberOfThreads)
{
    const Scene scene = sceneWith(smallRig(4), {pole(4.0, 0.0), pole(6.0, 15.0)});
    RenderOptions one;
    one.threads = 1;
    one.rightColour = true;
    RenderOptions three = one;
    three.threads = 3;
    const RenderResult a = renderOk(scene, one);
    const RenderResult b = renderOk(scene, three);
    for (const auto& [x, y] : {std::pair{&a.left, &b.left}, std::pair{&a.right, &b.right},
                               std::pair{&a.leftColour, &b.leftColour}, std::pair{&a.rightColour, &b.rightColour}}) {
        ASSERT_FALSE(x->empty());
        ASSERT_EQ(x->size(), y->size());
        EXPECT_EQ(cv::norm(*x, *y, cv::NORM_INF), 0.0);
    }
    RenderOptions negative;
    negative.threads = -1;
    EXPECT_FALSE(render(scene, Pose{}, negative));
}

TEST(SimRenderer, PoleAhead4mGivesPositiveSectorAt4m)
{
    constexpr double kRangeM = 4.0;
    const Scene scene = sceneWith(smallRig(2), {pole(kRangeM, 0.0)});
    const RenderResult sut = renderOk(scene);
    const int centre = sectorAt(sut.sectors, 0.0F);
    ASSERT_GE(centre, 0);
    const Sector& s = sector(sut.sectors, centre);
    EXPECT_EQ(s.state, SectorState::Obstacle);
    EXPECT_EQ(s.kind, ObstacleKind::Positive);
    EXPECT_NEAR(s.rangeM, kRangeM, 0.02); // placed by its nearest point
    EXPECT_EQ(s.danger, DangerClass::Blue);
    EXPECT_GT(s.heightM, 0.1F);
    EXPECT_EQ(sector(sut.sectors, centre - 4).state, SectorState::Clear);
    EXPECT_EQ(sector(sut.sectors, centre + 4).state, SectorState::Clear);
    EXPECT_EQ(countState(sut.sectors, SectorState::Obstacle), 2); // the pole spans bearing 0: two sectors
}

TEST(SimRenderer, PoleAtPlus20DegIsOnTheLeft)
{
    const Scene scene = sceneWith(smallRig(2), {pole(4.0, 20.0)});
    const RenderResult sut = renderOk(scene);
    const int s = sectorAt(sut.sectors, 20.0F);
    ASSERT_GE(s, 0);
    EXPECT_GT(sector(sut.sectors, s).bearingMinDeg, 0.0F);
    EXPECT_EQ(sector(sut.sectors, s).state, SectorState::Obstacle);
    EXPECT_EQ(sector(sut.sectors, sectorAt(sut.sectors, -20.0F)).state, SectorState::Clear);
    int polePixels = 0;
    for (int y = 0; y < sut.ids.rows; ++y) {
        for (int x = 0; x < sut.ids.cols; ++x) {
            if (sut.ids.at<std::uint16_t>(y, x) == 1) {
                ++polePixels;
                EXPECT_LT(x, scene.rig.cx());
            }
        }
    }
    EXPECT_GT(polePixels, 100);
}

TEST(SimRenderer, HoleIsNegativeWithDepth)
{
    constexpr double kDepthM = 0.4;
    const Scene scene = sceneWith(smallRig(2), {hole(3.0, 0.0, 1.0, kDepthM)});
    const RenderResult sut = renderOk(scene);
    const Sector& s = sector(sut.sectors, sectorAt(sut.sectors, 0.0F));
    EXPECT_EQ(s.state, SectorState::Obstacle);
    EXPECT_EQ(s.kind, ObstacleKind::Negative);
    EXPECT_GT(s.heightM, 0.1F);
    EXPECT_LE(s.heightM, kDepthM + 1e-4);
    EXPECT_GE(s.rangeM, 3.0F); // beyond the near rim: the near wall is not visible from above
    EXPECT_LT(s.rangeM, 4.0F);
    // The floor is hidden: the deepest visible point is on the far wall, where the ray grazing the near rim
    // (3 m) has dropped 0.59 m * 1 m / 3 m.
    double minHeight = 0.0;
    cv::minMaxLoc(sut.height, &minHeight, nullptr, nullptr, nullptr, sut.labels == 2);
    EXPECT_NEAR(minHeight, -0.59 / 3.0, 0.01);
    EXPECT_NEAR(s.heightM, 0.59 / 3.0, 0.01);
}

TEST(SimRenderer, ShallowHoleShowsItsFloor)
{
    constexpr double kDepthM = 0.15;
    const RenderResult sut = renderOk(sceneWith(smallRig(2), {hole(3.0, 0.0, 1.0, kDepthM, false)}));
    double minHeight = 0.0;
    cv::minMaxLoc(sut.height, &minHeight, nullptr, nullptr, nullptr, sut.labels == 2);
    EXPECT_NEAR(minHeight, -kDepthM, 1e-5);
    EXPECT_NEAR(sector(sut.sectors, sectorAt(sut.sectors, 0.0F)).heightM, kDepthM, 1e-5);
}

TEST(SimRenderer, RollRightSideDownSeesGroundRightOfCentreRow)
{
    Scene scene = sceneWith(smallRig(4), {});
    scene.rig.rollDeg = 5.0;
    const RenderResult sut = renderOk(scene);
    const int y = scene.rig.height / 2;
    EXPECT_GT(sut.disparity.at<float>(y, scene.rig.width - 1), 0.5F);
    EXPECT_EQ(sut.disparity.at<float>(y, 0), 0.0F);
}

TEST(SimRenderer, SquareHoleAndTrenchAreNegative)
{
    for (const Obstacle& o : {hole(3.0, 0.0, 1.0, 0.4, false), trench(3.0, 1.0, 0.5)}) {
        const RenderResult sut = renderOk(sceneWith(smallRig(4), {o}));
        const Sector& s = sector(sut.sectors, sectorAt(sut.sectors, 0.0F));
        EXPECT_EQ(s.kind, ObstacleKind::Negative);
    }
}

TEST(SimRenderer, OverhangAboveClearanceIsNoObstacle)
{
    const RenderResult high = renderOk(sceneWith(smallRig(2), {overhang(3.0, 0.0, 1.5)}));
    EXPECT_EQ(countState(high.sectors, SectorState::Obstacle), 0);
    EXPECT_GT(cv::countNonZero(high.labels == static_cast<int>(Label::Overhang)), 0);

    const RenderResult low = renderOk(sceneWith(smallRig(2), {overhang(3.0, 0.0, 0.5)}));
    EXPECT_GT(countState(low.sectors, SectorState::Obstacle), 0);
    EXPECT_EQ(cv::countNonZero(low.labels == static_cast<int>(Label::Overhang)), 0);
}

TEST(SimRenderer, LeftMatchesRightAtGroundTruthDisparity)
{
    Scene scene = sceneWith(smallRig(2), {box(3.0, 0.0, 0.5, 0.6, 0.5)});
    for (const GroundTexture texture : {GroundTexture::Asphalt, GroundTexture::Grass, GroundTexture::Gravel}) {
        scene.texture = texture;
        const RenderResult sut = renderOk(scene);
        double matched = 0.0;
        double shifted = 0.0;
        int n = 0;
        const auto rightAt = [&](int y, double x) {
            const int x0 = static_cast<int>(std::floor(x));
            const double f = x - x0;
            return (1.0 - f) * sut.right.at<std::uint8_t>(y, x0) + f * sut.right.at<std::uint8_t>(y, x0 + 1);
        };
        for (int y = sut.left.rows * 3 / 4; y < sut.left.rows; ++y) {
            for (int x = 0; x < sut.left.cols; ++x) {
                const double xr = x - sut.disparity.at<float>(y, x);
                if (xr < 4.0) {
                    continue;
                }
                const double l = sut.left.at<std::uint8_t>(y, x);
                matched += std::abs(l - rightAt(y, xr));
                shifted += std::abs(l - rightAt(y, xr + 3.0));
                ++n;
            }
        }
        ASSERT_GT(n, 1000);
        matched /= n;
        shifted /= n;
        EXPECT_LT(matched, 6.0) << static_cast<int>(texture);
        EXPECT_LT(matched * 2.5, shifted) << static_cast<int>(texture);
        std::cout << "[ sim      ] texture " << static_cast<int>(texture) << ": |L - R| " << matched
                  << " at the true disparity, " << shifted << " 3 px off\n";
    }
}

TEST(SimRenderer, SameSeedIsIdenticalOtherSeedChangesNoiseOnly)
{
    Scene scene = sceneWith(smallRig(4), {pole(3.0, 5.0)});
    const RenderResult a = renderOk(scene);
    const RenderResult b = renderOk(scene);
    scene.seed = 2;
    const RenderResult c = renderOk(scene);
    EXPECT_EQ(cv::norm(a.left, b.left, cv::NORM_L1), 0.0);
    EXPECT_EQ(cv::norm(a.right, b.right, cv::NORM_L1), 0.0);
    const double meanDiff = cv::norm(a.left, c.left, cv::NORM_L1) / static_cast<double>(a.left.total());
    EXPECT_GT(meanDiff, 0.5);
    EXPECT_LT(meanDiff, 5.0); // only noise and jitter differ
    EXPECT_EQ(cv::norm(a.disparity, c.disparity, cv::NORM_L1), 0.0);
}

TEST(SimRenderer, DoorwaySeenFrom3mIsClearInsideWallElsewhere)
{
    constexpr double kRangeM = 3.0;
    const RenderResult sut = renderOk(sceneWith(smallRig(2), {wallWithDoorway(kRangeM, 0.0, 0.9)}));
    // Through the doorway: |bearing| < atan(0.45 / 3.15) = 8.1 deg.
    for (float b = -7.0F; b <= 7.0F; b += 0.5F) {
        EXPECT_EQ(sector(sut.sectors, sectorAt(sut.sectors, b)).state, SectorState::Clear) << b;
    }
    for (const float b : {-25.0F, -12.0F, 12.0F, 25.0F}) {
        const Sector& s = sector(sut.sectors, sectorAt(sut.sectors, b));
        EXPECT_EQ(s.state, SectorState::Obstacle) << b;
        EXPECT_NEAR(s.rangeM, kRangeM / std::cos(s.bearingMaxDeg * 3.14159265 / 180.0), 0.1) << b;
    }
}

TEST(SimRenderer, MeshFenceIsAnObstacleAndSeeThrough)
{
    const Scene scene = sceneWith(smallRig(2), {meshFence(4.0, 0.0)});
    const RenderResult sut = renderOk(scene);
    const Sector& s = sector(sut.sectors, sectorAt(sut.sectors, 0.0F));
    EXPECT_EQ(s.state, SectorState::Obstacle);
    EXPECT_NEAR(s.rangeM, 4.0, 0.02);
    // Sub-pixel wires: the image behind the fence stays close to the ground brightness (coverage < 20 %).
    const Scene empty = sceneWith(smallRig(2), {});
    const RenderResult bare = renderOk(empty);
    // Ground behind the wires (the fence spans rows 57..160 at 4 m), right of the centre post.
    const cv::Rect below(scene.rig.width / 2 + 10, 130, 40, 20);
    const double withFence = cv::mean(sut.left(below))[0];
    const double without = cv::mean(bare.left(below))[0];
    EXPECT_GT(std::abs(withFence - without), 1.0);
    EXPECT_LT(std::abs(withFence - without), 0.25 * without);
}

TEST(SimRenderer, PitchedDownRigSeesGroundAboveCentreRow)
{
    // Ray f + a * down with a = (v - cy) / f meets the ground at Z = h / (sin p + a cos p).
    Scene scene = sceneWith(smallRig(4), {});
    constexpr double kPitchDeg = 5.0;
    scene.rig.pitchDeg = kPitchDeg;
    const RenderResult sut = renderOk(scene);
    const double p = kPitchDeg * 3.14159265358979 / 180.0;
    const Rig& rig = scene.rig;
    for (const int y : {rig.height / 2 - 5, rig.height / 2, rig.height - 1}) {
        const double a = (y - rig.cy()) / rig.focalPx;
        const double expected = rig.focalPx * rig.baselineM * (std::sin(p) + a * std::cos(p)) / rig.heightM;
        EXPECT_NEAR(sut.disparity.at<float>(y, 3), expected, 1e-3) << y;
    }
}

TEST(SimRenderer, InvalidInputIsAnError)
{
    Scene scene;
    scene.rig.focalPx = 0.0;
    EXPECT_FALSE(render(scene).has_value());
    scene = Scene{};
    scene.obstacles.push_back(pole(3.0, 0.0, -0.1));
    EXPECT_FALSE(render(scene).has_value());
    RenderOptions options;
    options.samplesPerAxis = 0;
    EXPECT_FALSE(render(Scene{}, Pose{}, options).has_value());
}

TEST(SimRenderer, ReportsRenderTimeOfDefaultCourseFrame)
{
    using Ms = std::chrono::milliseconds;
    auto course = makeCourse("default");
    ASSERT_TRUE(course.has_value());
    const auto start = std::chrono::steady_clock::now();
    const auto frame = renderCourseFrame(*course, 0);
    const auto mid = std::chrono::steady_clock::now();
    const auto empty = render(Scene{});
    const auto end = std::chrono::steady_clock::now();
    ASSERT_TRUE(frame.has_value());
    ASSERT_TRUE(empty.has_value());
    EXPECT_EQ(frame->left.cols, 640);
    EXPECT_GT(countState(frame->sectors, SectorState::Obstacle), 0);
    std::cout << "[ sim      ] 640x480 stereo pair + ground truth, 2x2 supersampling: default course frame ("
              << course->scene.obstacles.size() << " obstacles) " << std::chrono::duration_cast<Ms>(mid - start).count()
              << " ms, empty scene " << std::chrono::duration_cast<Ms>(end - mid).count() << " ms\n";
}

} // namespace
} // namespace ugv::sim
