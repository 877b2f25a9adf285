// `ugvsense eval --real --perturb`: the conditions parsed (and refused with the part and the ranges named), and what
// each does to a pair: exposure, the right camera's gain, blur, noise drawn apart for each image and the same on
// every run, compression, and half resolution of the images and of the truth.

#include "ugv/tool/real_conditions.hpp"

#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

namespace {

using ugv::tool::halveDisparityTruth;
using ugv::tool::parsePerturbation;
using ugv::tool::parsePerturbations;
using ugv::tool::Perturbation;
using ugv::tool::perturbImages;
using ugv::tool::sweepConditions;

/// A textured 8-bit image (a ramp plus a checker), the same each call.
cv::Mat texture(int rows = 60, int cols = 80)
{
    cv::Mat image(rows, cols, CV_8U);
    for (int y = 0; y < rows; ++y) {
        for (int x = 0; x < cols; ++x) {
            image.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(60 + x + (((x / 4 + y / 4) % 2) != 0 ? 40 : 0));
        }
    }
    return image;
}

TEST(RealConditions, PartsJoinedByPlusSetEachField)
{
    const auto p = parsePerturbation("exposure:0.35+noise:3+gain:1.25+blur:1.5+jpeg:40+half");

    ASSERT_TRUE(p) << p.error().message();
    EXPECT_DOUBLE_EQ(p->exposure, 0.35);
    EXPECT_DOUBLE_EQ(p->noiseGrey, 3.0);
    EXPECT_DOUBLE_EQ(p->rightGain, 1.25);
    EXPECT_DOUBLE_EQ(p->blurSigmaPx, 1.5);
    EXPECT_EQ(p->jpegQuality, 40);
    EXPECT_TRUE(p->half);
    EXPECT_EQ(p->name, "exposure:0.35+noise:3+gain:1.25+blur:1.5+jpeg:40+half");
}

TEST(RealConditions, AnUnknownPartOrAValueOutOfRangeIsRefusedNamingIt)
{
    for (const char* bad : {"fog:3", "noise:-1", "noise:abc", "gain:0", "jpeg:101", "exposure:", "noise:3+", "",
                            "noise:nan", "blur:1e400"}) {
        const auto p = parsePerturbation(bad);

        ASSERT_FALSE(p) << bad;
        EXPECT_EQ(p.error().where, "--perturb") << bad;
        EXPECT_NE(p.error().fix.find("exposure:0.35+noise:3"), std::string::npos) << p.error().message();
    }
}

TEST(RealConditions, SweepStandsForItsConditionsAndNoneChangesNothing)
{
    const auto all = parsePerturbations("none,sweep");

    ASSERT_TRUE(all) << all.error().message();
    ASSERT_EQ(all->size(), 1 + sweepConditions().size());
    EXPECT_EQ((*all)[1].name, sweepConditions().front());
    const cv::Mat before = texture();
    cv::Mat left = before.clone();
    cv::Mat right = before.clone();
    perturbImages((*all)[0], 7, left, right);
    EXPECT_EQ(cv::norm(left, before, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(right, before, cv::NORM_INF), 0.0);
}

TEST(RealConditions, ExposureScalesBothImagesAndGainTheRightOneOnly)
{
    const cv::Mat before = texture();
    cv::Mat left = before.clone();
    cv::Mat right = before.clone();
    Perturbation p;
    p.exposure = 0.5;
    p.rightGain = 1.5;

    perturbImages(p, 1, left, right);

    EXPECT_NEAR(cv::mean(left)[0], 0.5 * cv::mean(before)[0], 0.6);
    EXPECT_NEAR(cv::mean(right)[0], 0.75 * cv::mean(before)[0], 0.6);
}

TEST(RealConditions, NoiseIsDrawnApartForEachImageAndTheSameOnEveryRun)
{
    const cv::Mat before(200, 200, CV_8U, cv::Scalar(128));
    Perturbation p;
    p.noiseGrey = 4.0;
    cv::Mat l1 = before.clone();
    cv::Mat r1 = before.clone();
    cv::Mat l2 = before.clone();
    cv::Mat r2 = before.clone();

    perturbImages(p, 42, l1, r1);
    perturbImages(p, 42, l2, r2);

    cv::Scalar mean;
    cv::Scalar sigma;
    cv::meanStdDev(l1, mean, sigma);
    EXPECT_NEAR(sigma[0], 4.0, 0.3);
    EXPECT_GT(cv::norm(l1, r1, cv::NORM_L1), 0.0) << "the two cameras' noise is not independent";
    EXPECT_EQ(cv::norm(l1, l2, cv::NORM_INF), 0.0) << "the same seed drew other noise";
    EXPECT_EQ(cv::norm(r1, r2, cv::NORM_INF), 0.0);
}

TEST(RealConditions, BlurAndCompressionChangeTheTextureButNotItsLevel)
{
    const cv::Mat before = texture();
    for (const char* name : {"blur:2", "jpeg:20"}) {
        cv::Mat left = before.clone();
        cv::Mat right = before.clone();
        perturbImages(*parsePerturbation(name), 1, left, right);

        EXPECT_GT(cv::norm(left, before, cv::NORM_L1) / static_cast<double>(before.total()), 0.5) << name;
        EXPECT_NEAR(cv::mean(left)[0], cv::mean(before)[0], 2.0) << name;
        EXPECT_EQ(left.size(), before.size()) << name;
    }
}

TEST(RealConditions, HalfResolutionHalvesTheImagesAndTheTruthsDisparitiesKeepingNoTruthAsNone)
{
    cv::Mat left = texture(60, 80);
    cv::Mat right = texture(60, 80);
    perturbImages(*parsePerturbation("half"), 1, left, right);
    cv::Mat truth(60, 80, CV_32F, cv::Scalar(20.0F));
    truth.at<float>(10, 10) = 0.0F; // no LiDAR return

    const cv::Mat half = halveDisparityTruth(truth);

    EXPECT_EQ(left.size(), cv::Size(40, 30));
    EXPECT_EQ(right.size(), cv::Size(40, 30));
    ASSERT_EQ(half.size(), cv::Size(40, 30));
    EXPECT_FLOAT_EQ(half.at<float>(5, 5), 0.0F);
    EXPECT_FLOAT_EQ(half.at<float>(6, 6), 10.0F);
}

} // namespace
