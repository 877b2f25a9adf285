// data-calibration: the full stereo calibration on OpenCV's 13 real chessboard pairs (../shared/data).

#include <iostream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "shared_data.hpp"
#include "ugv/vision/stereo_calibrator.hpp"

namespace {

constexpr double kMaxRmsPx = 0.45;
constexpr double kMaxEpipolarPx = 0.45;
constexpr double kMaxRectifiedDyPx = 0.20;
constexpr int kPairs[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14}; // there is no pair 10

TEST(CalibrationData, OpenCvSamplePairsMeetTheQualityFigures)
{
    UGV_REQUIRE_SHARED_DATA(dir, "opencv-stereo-calib");
    std::vector<ugv::vision::CalibrationPair> pairs;
    for (const int id : kPairs) {
        const std::string suffix = (id < 10 ? "0" : "") + std::to_string(id) + ".jpg";
        pairs.push_back({"left" + suffix, cv::imread((dir / ("left" + suffix)).string(), cv::IMREAD_GRAYSCALE),
                         cv::imread((dir / ("right" + suffix)).string(), cv::IMREAD_GRAYSCALE)});
        ASSERT_FALSE(pairs.back().left.empty() || pairs.back().right.empty()) << suffix;
    }

    const auto report = ugv::vision::calibrateStereo(pairs, ugv::vision::CalibratorConfig{});

    ASSERT_TRUE(report.has_value()) << report.error().message();
    const auto& c = report->calibration;
    RecordProperty("rms_px", std::to_string(c.rmsPx));
    RecordProperty("epipolar_px", std::to_string(c.epipolarPx));
    RecordProperty("rectified_dy_px", std::to_string(c.rectifiedDyPx));
    std::cout << "opencv-stereo-calib: pairs used " << c.pairsUsed << ", RMS " << c.rmsPx << " px, epipolar "
              << c.epipolarPx << " px, rectified |dy| " << c.rectifiedDyPx << " px, baseline " << c.baselineM()
              << " m\n";
    EXPECT_LE(c.rmsPx, kMaxRmsPx);
    EXPECT_LE(c.epipolarPx, kMaxEpipolarPx);
    EXPECT_LE(c.rectifiedDyPx, kMaxRectifiedDyPx);
    EXPECT_GE(c.pairsUsed, 12);
    // README reference: |T| = 3.345 squares = 8.4 cm with 25 mm squares.
    EXPECT_NEAR(c.baselineM(), 0.0836, 0.002);
}

} // namespace
