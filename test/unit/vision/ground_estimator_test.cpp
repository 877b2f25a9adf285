// Ground estimator: synthetic disparity planes (noise, outliers, obstacle blobs), a 3-degree pitch step, the
// simulator's exact disparity for pitched rigs, fallbacks on garbage, config errors, allocation-free update().

#include "ugv/vision/ground_estimator.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "alloc_counter.hpp"
#include "mat_view.hpp"
#include "test_rig.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"
#include "ugv/vision/ground_plane.hpp"

namespace {

using ugv::test::view16;

using ugv::vision::GroundEstimator;
using ugv::vision::GroundEstimatorConfig;
using ugv::vision::GroundFallbackReason;
using ugv::vision::GroundPlane;
using ugv::vision::Mount;

constexpr int kWidth = 640;
constexpr int kHeight = 248;
constexpr int kRoiY0 = 232;
constexpr double kPitchTolDeg = 0.3;
constexpr double kHeightTolM = 0.02;
using ugv::test::kRigProjection;

GroundEstimatorConfig makeConfig(double smoothing = 0.5)
{
    GroundEstimatorConfig c;
    c.projection = kRigProjection;
    c.mount = Mount{0.59, 0.0, 0.0};
    c.width = kWidth;
    c.height = kHeight;
    c.y0 = kRoiY0;
    c.smoothing = smoothing;
    return c;
}

/// SGBM-like CV_16S disparity of the ground of `mount`, + Gaussian noise, a fraction of random outliers, and a
/// box-shaped obstacle blob of constant disparity (a wall-like object 3 m ahead).
cv::Mat syntheticDisparity(const Mount& mount, double noisePx, double outlierFraction, bool obstacle,
                           std::uint64_t seed)
{
    const ugv::vision::DisparityPlane plane = GroundPlane::fromMount(mount).disparityPlane(kRigProjection);
    cv::RNG rng(seed);
    cv::Mat disparity(kHeight, kWidth, CV_16SC1);
    for (int r = 0; r < kHeight; ++r) {
        for (int x = 0; x < kWidth; ++x) {
            double d = plane.at(x, kRoiY0 + r) + rng.gaussian(noisePx);
            if (obstacle && x >= 200 && x < 360 && r < 120) {
                d = 546.0 * 0.30 / 3.0; // fronto-parallel object at 3 m
            }
            if (rng.uniform(0.0, 1.0) < outlierFraction) {
                d = rng.uniform(-1.0, 120.0);
            }
            disparity.at<std::int16_t>(r, x) =
                d < 0.0 ? std::int16_t{-16} : static_cast<std::int16_t>(cvRound(d * 16.0));
        }
    }
    return disparity;
}

TEST(GroundEstimator, RecoversPitchedPlaneFromNoisyDisparityWithOutliersAndObstacle)
{
    constexpr Mount kTruth{0.62, 2.5, 1.5};
    const cv::Mat disparity = syntheticDisparity(kTruth, 0.3, 0.15, true, 1);
    auto sut = GroundEstimator::create(makeConfig(1.0));
    ASSERT_TRUE(sut.has_value());

    const ugv::vision::GroundEstimate& e = sut->update(view16(disparity));

    ASSERT_TRUE(e.reliable);
    EXPECT_EQ(e.reason, GroundFallbackReason::None);
    EXPECT_NEAR(e.plane.pitchDeg(), kTruth.pitchDeg, kPitchTolDeg);
    EXPECT_NEAR(e.plane.rollDeg(), kTruth.rollDeg, kPitchTolDeg);
    EXPECT_NEAR(e.plane.heightM, kTruth.heightM, kHeightTolM);
    EXPECT_GT(e.inliers, 1000);
}

TEST(GroundEstimator, TracksAThreeDegreePitchStepWithinAFewFrames)
{
    auto sut = GroundEstimator::create(makeConfig(0.5));
    ASSERT_TRUE(sut.has_value());
    const cv::Mat level = syntheticDisparity({0.59, 0.0, 0.0}, 0.3, 0.05, true, 2);
    const cv::Mat bump = syntheticDisparity({0.59, 3.0, 0.0}, 0.3, 0.05, true, 3);
    for (int i = 0; i < 5; ++i) {
        ASSERT_TRUE(sut->update(view16(level)).reliable);
    }
    EXPECT_NEAR(sut->estimate().plane.pitchDeg(), 0.0, kPitchTolDeg);

    int framesToTrack = -1;
    for (int i = 1; i <= 10; ++i) {
        const ugv::vision::GroundEstimate& e = sut->update(view16(bump));
        ASSERT_TRUE(e.reliable) << "frame " << i;
        if (framesToTrack < 0 && std::abs(e.plane.pitchDeg() - 3.0) < kPitchTolDeg) {
            framesToTrack = i;
        }
    }
    std::printf("[ MEASURE  ] 3 deg pitch step tracked within 0.3 deg after %d frames (smoothing 0.5)\n",
                framesToTrack);
    ASSERT_GT(framesToTrack, 0);
    EXPECT_LE(framesToTrack, 5);
    EXPECT_NEAR(sut->estimate().plane.heightM, 0.59, kHeightTolM);
}

TEST(GroundEstimator, RecoversPitchedRigsFromSimulatorDisparity)
{
    for (const Mount& mount : {Mount{0.59, 3.0, 0.0}, Mount{0.59, -2.0, 2.0}, Mount{0.70, 4.0, -1.0}}) {
        auto scene = ugv::sim::makeScene("box", 3.0, 10.0, ugv::sim::GroundTexture::Asphalt, 5);
        ASSERT_TRUE(scene.has_value());
        scene->rig.heightM = mount.heightM;
        scene->rig.pitchDeg = mount.pitchDeg;
        scene->rig.rollDeg = mount.rollDeg;
        ugv::sim::RenderOptions options;
        options.samplesPerAxis = 1;
        auto frame = ugv::sim::render(*scene, {}, options);
        ASSERT_TRUE(frame.has_value());
        cv::Mat disparity(kHeight, kWidth, CV_16SC1);
        for (int r = 0; r < kHeight; ++r) {
            for (int x = 0; x < kWidth; ++x) {
                const float d = frame->disparity.at<float>(kRoiY0 + r, x);
                disparity.at<std::int16_t>(r, x) = d > 0.0F ? static_cast<std::int16_t>(cvRound(d * 16.0F)) : -16;
            }
        }
        GroundEstimatorConfig config = makeConfig(1.0);
        config.mount = Mount{0.59, 0.0, 0.0};
        config.heightBandFraction = 0.25;
        auto sut = GroundEstimator::create(config);
        ASSERT_TRUE(sut.has_value());

        const ugv::vision::GroundEstimate& e = sut->update(view16(disparity));

        ASSERT_TRUE(e.reliable) << "pitch " << mount.pitchDeg << " reason " << static_cast<int>(e.reason);
        EXPECT_NEAR(e.plane.pitchDeg(), mount.pitchDeg, kPitchTolDeg);
        EXPECT_NEAR(e.plane.rollDeg(), mount.rollDeg, kPitchTolDeg);
        EXPECT_NEAR(e.plane.heightM, mount.heightM, kHeightTolM);
    }
}

TEST(GroundEstimator, LocksOnWhenTheConfiguredMountIsOffByTenDegreesFiveDegreesOrThirtyPercent)
{
    // The truth is the default rig's mount; the configured mount is off by the amounts issue 20 names, one at a
    // time and all together. Noise, outliers and an obstacle blob as in the first test.
    constexpr Mount kTruth{0.59, 0.0, 0.0};
    const cv::Mat disparity = syntheticDisparity(kTruth, 0.3, 0.15, true, 7);
    for (const Mount& configured :
         {Mount{0.59, 10.0, 0.0}, Mount{0.59, -10.0, 0.0}, Mount{0.59, 0.0, 5.0}, Mount{0.59, 0.0, -5.0},
          Mount{0.59 * 1.3, 0.0, 0.0}, Mount{0.59 * 0.7, 0.0, 0.0}, Mount{0.59 * 1.3, -10.0, 5.0}}) {
        GroundEstimatorConfig config = makeConfig(1.0);
        config.mount = configured;
        auto sut = GroundEstimator::create(config);
        ASSERT_TRUE(sut.has_value());

        const ugv::vision::GroundEstimate& e = sut->update(view16(disparity));

        ASSERT_TRUE(e.reliable) << "configured " << configured.heightM << " m, pitch " << configured.pitchDeg
                                << ", roll " << configured.rollDeg << ": reason " << static_cast<int>(e.reason);
        EXPECT_NEAR(e.plane.pitchDeg(), kTruth.pitchDeg, kPitchTolDeg);
        EXPECT_NEAR(e.plane.rollDeg(), kTruth.rollDeg, kPitchTolDeg);
        EXPECT_NEAR(e.plane.heightM, kTruth.heightM, kHeightTolM);
    }
}

TEST(GroundEstimator, FallsBackToConfiguredPlaneFlagged)
{
    auto sut = GroundEstimator::create(makeConfig(0.5));
    ASSERT_TRUE(sut.has_value());
    const GroundPlane configured = sut->configuredPlane();
    const auto expectFallback = [&](const ugv::vision::GroundEstimate& e, GroundFallbackReason reason) {
        EXPECT_FALSE(e.reliable);
        EXPECT_EQ(e.reason, reason);
        EXPECT_DOUBLE_EQ(e.plane.heightM, configured.heightM);
        EXPECT_DOUBLE_EQ(e.plane.nz, configured.nz);
        EXPECT_TRUE(std::isfinite(e.disparity.c));
    };

    const cv::Mat invalid(kHeight, kWidth, CV_16SC1, cv::Scalar(-16));
    expectFallback(sut->update(view16(invalid)), GroundFallbackReason::TooFewCandidates);

    cv::Mat garbage(kHeight, kWidth, CV_16SC1);
    cv::RNG rng(9);
    rng.fill(garbage, cv::RNG::UNIFORM, -16, 16 * 128);
    expectFallback(sut->update(view16(garbage)), GroundFallbackReason::TooFewInliers);

    // Roll 10 deg: a clean plane, but outside the 8 deg band.
    const cv::Mat rolled = syntheticDisparity({0.59, 0.0, 10.0}, 0.2, 0.0, false, 4);
    expectFallback(sut->update(view16(rolled)), GroundFallbackReason::OutOfBand);

    const cv::Mat small(kHeight - 1, kWidth, CV_16SC1, cv::Scalar(0));
    expectFallback(sut->update(view16(small)), GroundFallbackReason::WrongInput);

    // Recovery after a fallback.
    const cv::Mat good = syntheticDisparity({0.59, 1.0, 0.0}, 0.2, 0.0, false, 5);
    EXPECT_TRUE(sut->update(view16(good)).reliable);
}

TEST(GroundEstimator, RejectsInvalidConfigs)
{
    GroundEstimatorConfig c = makeConfig();
    c.smoothing = 0.0;
    EXPECT_FALSE(GroundEstimator::create(c).has_value());
    c = makeConfig();
    c.mount.heightM = 0.0;
    EXPECT_FALSE(GroundEstimator::create(c).has_value());
    c = makeConfig();
    c.projection.baselineM = 0.0;
    EXPECT_FALSE(GroundEstimator::create(c).has_value());
    c = makeConfig();
    c.sampleStep = 0;
    EXPECT_FALSE(GroundEstimator::create(c).has_value());
}

TEST(GroundEstimator, UpdateAllocatesNothingOver300Frames)
{
    auto sut = GroundEstimator::create(makeConfig());
    ASSERT_TRUE(sut.has_value());
    const cv::Mat a = syntheticDisparity({0.59, 1.0, 0.5}, 0.3, 0.1, true, 6);
    const cv::Mat invalid(kHeight, kWidth, CV_16SC1, cv::Scalar(-16));
    int reliable = 0;

    const ugv::test::AllocationScope scope;
    for (int i = 0; i < 300; ++i) {
        reliable += sut->update(view16(i % 10 == 9 ? invalid : a)).reliable ? 1 : 0;
    }
    EXPECT_EQ(scope.count(), 0U);
    EXPECT_EQ(reliable, 270);
}

} // namespace
