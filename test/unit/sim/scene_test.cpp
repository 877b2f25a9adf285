#include "ugv/sim/scene.hpp"

#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "ugv/sim/renderer.hpp"

namespace ugv::sim {
namespace {

TEST(SimScene, DefaultRigMatchesOriginalSystem)
{
    const Rig sut;
    EXPECT_EQ(sut.width, 640);
    EXPECT_EQ(sut.height, 480);
    EXPECT_DOUBLE_EQ(sut.focalPx, 546.0);
    EXPECT_DOUBLE_EQ(sut.baselineM, 0.30);
    EXPECT_DOUBLE_EQ(sut.heightM, 0.59);
    EXPECT_DOUBLE_EQ(sut.cx(), 319.5);
    EXPECT_DOUBLE_EQ(sut.cy(), 239.5);
    EXPECT_NEAR(sut.hfovDeg(), 2.0 * std::atan(320.0 / 546.0) * 180.0 / 3.14159265358979, 1e-9);
}

TEST(SimScene, PlacementIsByNearestPoint)
{
    const auto [px, py] = obstacleCentre(pole(4.0, 90.0, 0.1));
    EXPECT_NEAR(px, 0.0, 1e-12);
    EXPECT_NEAR(py, 4.1, 1e-12);
    const auto [bx, by] = obstacleCentre(box(2.0, 0.0, 0.6));
    EXPECT_NEAR(bx, 2.3, 1e-12);
    EXPECT_NEAR(by, 0.0, 1e-12);
}

TEST(SimScene, CatalogueHasEveryTypeAndEachRendersWithAnObstacle)
{
    RenderOptions options;
    options.samplesPerAxis = 1;
    for (const std::string& name : sceneNames()) {
        auto scene = makeScene(name, 4.0, 0.0, GroundTexture::Gravel, 3);
        ASSERT_TRUE(scene.has_value()) << name;
        scene->rig.width = 160;
        scene->rig.height = 120;
        scene->rig.focalPx = 136.5;
        auto sut = render(*scene, Pose{}, options);
        ASSERT_TRUE(sut.has_value()) << name;
        int obstacles = 0;
        for (int i = 0; i < sut->sectors.count; ++i) {
            obstacles += sut->sectors.sectors.at(static_cast<std::size_t>(i)).state == SectorState::Obstacle;
        }
        if (name == "empty" || name == "overhang") {
            EXPECT_EQ(obstacles, 0) << name;
        } else {
            EXPECT_GT(obstacles, 0) << name;
        }
    }
}

TEST(SimScene, UnknownSceneOrCourseIsAnError)
{
    const auto sut = makeScene("dragon");
    ASSERT_FALSE(sut.has_value());
    EXPECT_NE(sut.error().fix.find("pole"), std::string::npos);
    EXPECT_FALSE(makeCourse("moon").has_value());
    EXPECT_FALSE(makeCourse("default", 0.0).has_value());
}

TEST(SimScene, DefaultCourseDrives30mAndFramesMove)
{
    auto sut = makeCourse("default", 1.5, 10.0);
    ASSERT_TRUE(sut.has_value());
    ASSERT_EQ(sut->poses.size(), 201U);
    EXPECT_NEAR(sut->poses.back().x, 30.0, 1e-9);
    EXPECT_GE(sut->scene.obstacles.size(), 10U);
    EXPECT_TRUE(validate(sut->scene).has_value());
    EXPECT_FALSE(renderCourseFrame(*sut, sut->poses.size()).has_value());
}

TEST(SimScene, PoseMovesTheWorld)
{
    // A pole 6 m ahead seen from x = 2 m is 4 m away; the world stays put when the vehicle moves or turns.
    Scene scene;
    scene.rig.width = 160;
    scene.rig.height = 120;
    scene.rig.focalPx = 136.5;
    scene.obstacles.push_back(pole(6.0, 0.0));
    RenderOptions options;
    options.samplesPerAxis = 1;
    auto ahead = render(scene, Pose{2.0, 0.0, 0.0}, options);
    ASSERT_TRUE(ahead.has_value());
    float nearest = 1e9F;
    for (int i = 0; i < ahead->sectors.count; ++i) {
        nearest = std::min(nearest, ahead->sectors.sectors.at(static_cast<std::size_t>(i)).rangeM);
    }
    EXPECT_NEAR(nearest, 4.0F, 0.03F);
    // Facing +y from 3 m to the right of the pole centre (6.06, 0): nearest point 2.94 m straight ahead.
    auto turned = render(scene, Pose{6.06, -3.0, 90.0}, options);
    ASSERT_TRUE(turned.has_value());
    const float ahead0 = turned->sectors.sectors.at(static_cast<std::size_t>(turned->sectors.count / 2)).rangeM;
    EXPECT_NEAR(ahead0, 2.94F, 0.03F);
    auto right = render(scene, Pose{2.0, 1.0, 0.0}, options); // pole at bearing atan2(-1, 4.06): right side
    ASSERT_TRUE(right.has_value());
    for (int y = 0; y < right->ids.rows; ++y) {
        for (int x = 0; x < right->ids.cols; ++x) {
            if (right->ids.at<std::uint16_t>(y, x) != 0) {
                EXPECT_GT(x, scene.rig.cx());
            }
        }
    }
    EXPECT_GT(cv::countNonZero(right->ids), 10);
}

} // namespace
} // namespace ugv::sim
