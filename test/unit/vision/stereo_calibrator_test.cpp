#include "ugv/vision/stereo_calibrator.hpp"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "ugv/sim/chessboard_render.hpp"

namespace {

using ugv::vision::calibrateStereo;
using ugv::vision::CalibrationPair;
using ugv::vision::CalibratorConfig;

constexpr int kPairs = 12;
constexpr std::uint64_t kSeed = 7;
constexpr double kNoiseSigma = 1.0;

/// Rendered once for all tests (about 1.5 s).
const std::vector<CalibrationPair>& renderedPairs()
{
    static const std::vector<CalibrationPair> pairs = [] {
        const ugv::sim::ChessboardRenderer renderer(ugv::sim::SimRig{}, ugv::sim::SimBoard{});
        cv::RNG rng(kSeed);
        std::vector<CalibrationPair> result;
        for (const auto& pose : renderer.poses(kPairs, kSeed)) {
            CalibrationPair pair;
            pair.name = "pair" + std::to_string(result.size() + 1);
            renderer.render(pose, kNoiseSigma, rng, pair.left, pair.right);
            result.push_back(std::move(pair));
        }
        return result;
    }();
    return pairs;
}

/// The rejected pairs with their reasons and the per-pair errors of those used, for failure messages.
std::string describe(const ugv::vision::CalibrationReport& report)
{
    std::string out;
    for (const auto& r : report.rejected) {
        out += "rejected " + r.name + ": " + r.reason + "\n";
    }
    for (const auto& p : report.perPair) {
        out += "used " + p.name + ": " + std::to_string(p.errorPx) + " px\n";
    }
    return out;
}

bool rejectedWith(const ugv::vision::CalibrationReport& report, const std::string& name, const std::string& reason)
{
    return std::any_of(report.rejected.begin(), report.rejected.end(),
                       [&](const auto& r) { return r.name == name && r.reason.find(reason) != std::string::npos; });
}

TEST(StereoCalibrator, RecoversTheRenderedRig)
{
    const ugv::sim::SimRig truth;
    ASSERT_EQ(renderedPairs().size(), static_cast<std::size_t>(kPairs));

    const auto report = calibrateStereo(renderedPairs(), CalibratorConfig{});

    ASSERT_TRUE(report.has_value()) << report.error().message();
    const auto& c = report->calibration;
    EXPECT_EQ(c.pairsUsed, kPairs);
    EXPECT_TRUE(report->rejected.empty());
    EXPECT_NEAR(c.K1.at<double>(0, 0), truth.fx, 0.005 * truth.fx);
    EXPECT_NEAR(c.K2.at<double>(1, 1), truth.fy, 0.005 * truth.fy);
    EXPECT_NEAR(c.baselineM(), truth.baselineM, 0.01 * truth.baselineM);
    EXPECT_LT(c.D1.at<double>(0, 0), 0.0); // barrel distortion as rendered (k1..k3 trade off: sign only)
    EXPECT_LT(c.rmsPx, 0.2);
    EXPECT_LT(c.epipolarPx, 0.3);
    EXPECT_LT(c.rectifiedDyPx, 0.2);
    EXPECT_GT(c.rectifiedFocalPx(), 0.0);
    EXPECT_EQ(report->perPair.size(), static_cast<std::size_t>(kPairs));
}

TEST(StereoCalibrator, BlankImageIsRejectedAsBoardNotFound)
{
    std::vector<CalibrationPair> pairs = renderedPairs();
    pairs[2].left = cv::Mat(pairs[2].left.size(), CV_8UC1, cv::Scalar(128));

    const auto report = calibrateStereo(pairs, CalibratorConfig{});

    ASSERT_TRUE(report.has_value()) << report.error().message();
    EXPECT_TRUE(rejectedWith(*report, "pair3", "board not found in left image"));
    EXPECT_EQ(report->calibration.pairsUsed, kPairs - 1);
    EXPECT_EQ(report->calibration.pairsRejected, 1);
}

TEST(StereoCalibrator, SizeMismatchesAreRejected)
{
    std::vector<CalibrationPair> pairs = renderedPairs();
    cv::resize(pairs[1].right, pairs[1].right, cv::Size(320, 240)); // left and right differ
    cv::resize(pairs[4].left, pairs[4].left, cv::Size(320, 240));   // pair differs from the others
    cv::resize(pairs[4].right, pairs[4].right, cv::Size(320, 240));

    const auto report = calibrateStereo(pairs, CalibratorConfig{});

    ASSERT_TRUE(report.has_value()) << report.error().message();
    EXPECT_TRUE(rejectedWith(*report, "pair2", "size mismatch"));
    EXPECT_TRUE(rejectedWith(*report, "pair5", "size mismatch"));
    EXPECT_EQ(report->calibration.pairsUsed, kPairs - 2);
}

TEST(StereoCalibrator, ShiftedPairIsDroppedAsOutlierAndRmsImproves)
{
    std::vector<CalibrationPair> pairs = renderedPairs();
    const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, 0, 0, 1, 3); // right image 3 px down
    cv::Mat shifted;
    cv::warpAffine(pairs[5].right, shifted, shift, pairs[5].right.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    pairs[5].right = shifted;

    const auto report = calibrateStereo(pairs, CalibratorConfig{});

    ASSERT_TRUE(report.has_value()) << report.error().message();
    std::printf("[ MEASURED ] %s", describe(*report).c_str()); // compared across targets (toolchain/README.md)
    EXPECT_TRUE(rejectedWith(*report, "pair6", "outlier")) << describe(*report);
    EXPECT_EQ(report->calibration.pairsUsed, kPairs - 1) << describe(*report);
    EXPECT_GE(report->outlierRounds, 1);
    EXPECT_LT(report->calibration.rmsPx, report->rmsBeforeOutliersPx);
    EXPECT_LT(report->calibration.rmsPx, 0.2);
}

TEST(StereoCalibrator, TooFewUsablePairsIsAnError)
{
    std::vector<CalibrationPair> pairs(renderedPairs().begin(), renderedPairs().begin() + 3);
    pairs[0].right = cv::Mat(pairs[0].right.size(), CV_8UC1, cv::Scalar(0));

    const auto report = calibrateStereo(pairs, CalibratorConfig{});

    ASSERT_FALSE(report.has_value());
    EXPECT_NE(report.error().what.find("only 2 usable pair(s)"), std::string::npos) << report.error().message();
}

TEST(StereoCalibrator, EmptyAndColourImagesAreRejectedNotFatal)
{
    std::vector<CalibrationPair> pairs = renderedPairs();
    pairs[0].left = cv::Mat();
    cv::cvtColor(pairs[1].right, pairs[1].right, cv::COLOR_GRAY2BGR);

    const auto report = calibrateStereo(pairs, CalibratorConfig{});

    ASSERT_TRUE(report.has_value());
    EXPECT_TRUE(rejectedWith(*report, "pair1", "empty image"));
    EXPECT_TRUE(rejectedWith(*report, "pair2", "not an 8-bit grey image"));
}

TEST(StereoCalibrator, InvalidConfigIsAnError)
{
    CalibratorConfig config;
    config.squareM = 0.0;
    EXPECT_FALSE(calibrateStereo(renderedPairs(), config).has_value());
    config = CalibratorConfig{};
    config.innerCorners = cv::Size(1, 6);
    EXPECT_FALSE(calibrateStereo(renderedPairs(), config).has_value());
}

} // namespace
