#include "ugv/sim/writer.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

#include "ugv/sim/renderer.hpp"

namespace ugv::sim {
namespace {

std::filesystem::path freshDir(const std::string& name)
{
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("ugv_sim_test_" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

TEST(SimWriter, WritesImagesSectorsAndRectifiedCalibration)
{
    Scene scene;
    scene.rig.width = 160;
    scene.rig.height = 120;
    scene.rig.focalPx = 136.5;
    scene.rig.pitchDeg = 2.0;
    scene.obstacles.push_back(pole(3.0, 0.0));
    auto sample = render(scene);
    ASSERT_TRUE(sample.has_value());
    const std::filesystem::path dir = freshDir("write");

    const auto sut = writeSample(*sample, scene.rig, dir, "f000");

    ASSERT_TRUE(sut.has_value()) << sut.error().message();
    const cv::Mat left = cv::imread((dir / "f000_left.png").string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(left.type(), CV_8U);
    EXPECT_EQ(cv::norm(left, sample->left, cv::NORM_L1), 0.0);
    const cv::Mat disparity = cv::imread((dir / "f000_disparity.png").string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(disparity.type(), CV_16U);
    const int y = scene.rig.height - 1;
    EXPECT_NEAR(disparity.at<std::uint16_t>(y, 0) / kDisparityScale, sample->disparity.at<float>(y, 0), 0.5 / 256);
    EXPECT_EQ(disparity.at<std::uint16_t>(0, 0), 0); // sky
    const cv::Mat depth = cv::imread((dir / "f000_depth.png").string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(depth.type(), CV_16U);
    EXPECT_NEAR(depth.at<std::uint16_t>(y, 0) / kDepthScale, sample->depth.at<float>(y, 0), 0.001);
    EXPECT_TRUE(std::filesystem::exists(dir / "f000_labels.png"));
    EXPECT_TRUE(std::filesystem::exists(dir / "f000_ids.png"));

    std::ifstream json(dir / "f000_sectors.json");
    std::stringstream text;
    text << json.rdbuf();
    EXPECT_NE(text.str().find("\"range_m\": null"), std::string::npos);
    EXPECT_NE(text.str().find("\"kind\": \"positive\""), std::string::npos);
    EXPECT_NE(text.str().find("\"class\": \"blue\""), std::string::npos);

    cv::FileStorage fs((dir / "calibration.yaml").string(), cv::FileStorage::READ);
    ASSERT_TRUE(fs.isOpened());
    EXPECT_EQ(static_cast<int>(fs["schema_version"]), 1);
    EXPECT_EQ(static_cast<int>(fs["rectified"]), 1);
    EXPECT_EQ(static_cast<int>(fs["image_width"]), 160);
    EXPECT_EQ(static_cast<int>(fs["image_height"]), 120);
    EXPECT_DOUBLE_EQ(static_cast<double>(fs["fx"]), 136.5);
    EXPECT_DOUBLE_EQ(static_cast<double>(fs["fy"]), 136.5);
    EXPECT_DOUBLE_EQ(static_cast<double>(fs["cx"]), 79.5);
    EXPECT_DOUBLE_EQ(static_cast<double>(fs["cy"]), 59.5);
    EXPECT_DOUBLE_EQ(static_cast<double>(fs["baseline_m"]), 0.30);
    EXPECT_DOUBLE_EQ(static_cast<double>(fs["mount"]["height_m"]), 0.59);
    EXPECT_DOUBLE_EQ(static_cast<double>(fs["mount"]["pitch_deg"]), 2.0);
    EXPECT_DOUBLE_EQ(static_cast<double>(fs["mount"]["roll_deg"]), 0.0);
    std::filesystem::remove_all(dir);
}

TEST(SimWriter, MissingDirectoryIsAnError)
{
    Scene scene;
    scene.rig.width = 32;
    scene.rig.height = 24;
    scene.rig.focalPx = 27.3;
    auto sample = render(scene);
    ASSERT_TRUE(sample.has_value());

    const auto sut = writeSample(*sample, scene.rig, "/nonexistent/ugv_sim", "x");

    ASSERT_FALSE(sut.has_value());
    EXPECT_NE(sut.error().where.find("nonexistent"), std::string::npos);
    EXPECT_FALSE(writeCalibration(scene.rig, "/nonexistent/ugv_sim").has_value());
}

} // namespace
} // namespace ugv::sim
