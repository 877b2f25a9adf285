// Ground stages at 640x480 with ROI = bottom 248 rows (seeded synthetic input): the ground warp (scalar
// reference, universal-intrinsics kernel, cv::remap with equivalent float maps as the baseline), the mismatch
// stage (on a synthetic pair where a band of the image is shifted off the ground model) and the estimator
// update. Quote results as ratios against the baseline measured in the same run. The mismatch stage runs on the
// synthetic worst case and on ugvsense sim frames (pole at 4 m, box at 3 m, on asphalt; model from the rig
// mount), each with the scalar reference (the baseline of the 16-residual kernel) in the same run.

#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "test_rig.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"
#include "ugv/vision/ground_estimator.hpp"
#include "ugv/vision/ground_mismatch.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/ground_warp.hpp"
#include "ugv/vision/sector_builder.hpp"

namespace {

constexpr int kWidth = 640;
constexpr int kRoiHeight = 248;
constexpr int kY0 = 480 - kRoiHeight;
using ugv::test::kRigProjection;

ugv::vision::DisparityPlane groundPlane()
{
    return ugv::vision::GroundPlane::fromMount({0.59, 1.0, 1.0}).disparityPlane(kRigProjection);
}

cv::Mat texture(std::uint64_t seed)
{
    cv::Mat image(kRoiHeight, kWidth, CV_8UC1);
    cv::RNG rng(seed);
    rng.fill(image, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(image, image, cv::Size(5, 5), 1.2);
    return image;
}

ugv::ConstImageViewU8 view(const cv::Mat& m)
{
    return {m.ptr<std::uint8_t>(), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}
ugv::ImageViewU8 view(cv::Mat& m)
{
    return {m.ptr<std::uint8_t>(), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}

template <bool kSimd>
void BM_GroundWarp(benchmark::State& state)
{
    const cv::Mat left = texture(1);
    cv::Mat warped(kRoiHeight, kWidth, CV_8UC1);
    std::vector<ugv::vision::WarpSpan> spans(kRoiHeight);
    const ugv::vision::DisparityPlane plane = groundPlane();
    for (auto _ : state) {
        const auto status = kSimd ? ugv::vision::warpGround(view(left), plane, kY0, view(warped), spans)
                                  : ugv::vision::warpGroundReference(view(left), plane, kY0, view(warped), spans);
        benchmark::DoNotOptimize(status);
        benchmark::DoNotOptimize(warped.data);
    }
    state.SetBytesProcessed(state.iterations() * kWidth * kRoiHeight);
}
void BM_GroundWarpScalar(benchmark::State& state)
{
    BM_GroundWarp<false>(state);
}
void BM_GroundWarpSimd(benchmark::State& state)
{
    BM_GroundWarp<true>(state);
}

void BM_GroundWarpCvRemapBaseline(benchmark::State& state)
{
    const cv::Mat left = texture(1);
    cv::Mat warped(kRoiHeight, kWidth, CV_8UC1);
    cv::Mat mapX(kRoiHeight, kWidth, CV_32FC1);
    cv::Mat mapY(kRoiHeight, kWidth, CV_32FC1);
    const ugv::vision::DisparityPlane plane = groundPlane();
    for (int r = 0; r < kRoiHeight; ++r) {
        const ugv::vision::WarpRowMap m = ugv::vision::warpRowMap(plane, kY0 + r);
        for (int x = 0; x < kWidth; ++x) {
            mapX.at<float>(r, x) = static_cast<float>(x) * m.scale + m.offset;
            mapY.at<float>(r, x) = static_cast<float>(r);
        }
    }
    for (auto _ : state) {
        cv::remap(left, warped, mapX, mapY, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
        benchmark::DoNotOptimize(warped.data);
    }
    state.SetBytesProcessed(state.iterations() * kWidth * kRoiHeight);
}

/// A synthetic pair: the right image is the left seen through the ground model, except a 120 x 80 block that
/// is shifted by 20 px more (an obstacle), so the mismatch stage does its residual search there.
struct MismatchInput {
    cv::Mat left = texture(2);
    cv::Mat right = cv::Mat(kRoiHeight, kWidth, CV_8UC1, cv::Scalar(0));
    cv::Mat warped = cv::Mat(kRoiHeight, kWidth, CV_8UC1);
    std::vector<ugv::vision::WarpSpan> spans = std::vector<ugv::vision::WarpSpan>(kRoiHeight);
    ugv::vision::DisparityPlane plane = groundPlane();
    MismatchInput()
    {
        for (int r = 0; r < kRoiHeight; ++r) {
            for (int x = 0; x < kWidth; ++x) {
                const bool obstacle = x >= 260 && x < 380 && r >= 20 && r < 100;
                const int xs = cvRound(plane.at(x, kY0 + r)) + x + (obstacle ? 20 : 0);
                right.at<std::uint8_t>(r, x) = xs >= 0 && xs < kWidth ? left.at<std::uint8_t>(r, xs) : 0;
            }
        }
        (void)ugv::vision::warpGround(view(left), plane, kY0, view(warped), spans);
    }
};

template <bool kSimd>
void runMismatch(benchmark::State& state, const MismatchInput& in)
{
    ugv::vision::GroundMismatchConfig config;
    config.width = kWidth;
    config.height = kRoiHeight;
    auto sut = ugv::vision::GroundMismatch::create(config);
    for (auto _ : state) {
        const auto status =
            kSimd ? sut->run(view(in.left), view(in.right), view(in.warped), in.spans, in.plane, kY0)
                  : sut->runReference(view(in.left), view(in.right), view(in.warped), in.spans, in.plane, kY0);
        benchmark::DoNotOptimize(status);
    }
    state.counters["tested"] = sut->counts().tested;
    state.counters["notGround"] = sut->counts().positive + sut->counts().negative + sut->counts().unsure;
    state.SetBytesProcessed(state.iterations() * kWidth * kRoiHeight);
}

/// A ugvsense sim frame (seed 0), ROI = bottom 248 rows, the ground model from the rig mount.
MismatchInput simInput(const char* name, double rangeM)
{
    MismatchInput in;
    auto scene = ugv::sim::makeScene(name, rangeM, 0.0, ugv::sim::GroundTexture::Asphalt, 0).value();
    const auto frame = ugv::sim::render(scene).value();
    const ugv::sim::Rig& rig = scene.rig;
    const ugv::vision::RectifiedProjection proj{rig.focalPx, rig.focalPx, rig.cx(), rig.cy(), rig.baselineM};
    in.plane = ugv::vision::GroundPlane::fromMount({rig.heightM, rig.pitchDeg, rig.rollDeg}).disparityPlane(proj);
    in.left = frame.left.rowRange(kY0, kY0 + kRoiHeight).clone();
    in.right = frame.right.rowRange(kY0, kY0 + kRoiHeight).clone();
    (void)ugv::vision::warpGround(view(in.left), in.plane, kY0, view(in.warped), in.spans);
    return in;
}

template <bool kSimd>
void BM_GroundMismatch(benchmark::State& state)
{
    static const MismatchInput in;
    runMismatch<kSimd>(state, in);
}
template <bool kSimd>
void BM_GroundMismatchSimPole(benchmark::State& state)
{
    static const MismatchInput in = simInput("pole", 4.0);
    runMismatch<kSimd>(state, in);
}
template <bool kSimd>
void BM_GroundMismatchSimBox(benchmark::State& state)
{
    static const MismatchInput in = simInput("box", 3.0);
    runMismatch<kSimd>(state, in);
}

/// Sector builder: build() (per-row linear factors) vs buildReference() (pixelToVehicle + atan2 + hypot per
/// pixel, the baseline) on the sim ground-truth disparity of a pole at 4 m (x16, +-0.5 px noise).
template <bool kFast>
void BM_SectorBuild(benchmark::State& state)
{
    static const cv::Mat d16 = [] {
        auto scene = ugv::sim::makeScene("pole", 4.0, 0.0, ugv::sim::GroundTexture::Asphalt, 0).value();
        const auto frame = ugv::sim::render(scene).value();
        cv::Mat out(kRoiHeight, kWidth, CV_16SC1);
        cv::RNG rng(5);
        for (int r = 0; r < kRoiHeight; ++r) {
            for (int x = 0; x < kWidth; ++x) {
                const float d = frame.disparity.at<float>(r + kY0, x) + static_cast<float>(rng.uniform(-0.5, 0.5));
                out.at<std::int16_t>(r, x) = d > 0.0F ? static_cast<std::int16_t>(cvRound(d * 16.0F)) : -16;
            }
        }
        return out;
    }();
    auto sut =
        ugv::vision::SectorBuilder::create({}, kRigProjection, ugv::Rect{0, kY0, kWidth, kRoiHeight}, kY0 + 8).value();
    const ugv::vision::GroundPlane ground = ugv::vision::GroundPlane::fromMount({0.59, 0.0, 0.0});
    const ugv::ImageView<const std::int16_t> in{d16.ptr<std::int16_t>(), kWidth, kRoiHeight,
                                                static_cast<std::ptrdiff_t>(d16.step)};
    for (auto _ : state) {
        benchmark::DoNotOptimize(kFast ? sut.build(in, {}, ground, 1U, 0) : sut.buildReference(in, {}, ground, 1U, 0));
    }
}

void BM_GroundEstimatorUpdate(benchmark::State& state)
{
    const ugv::vision::DisparityPlane plane = groundPlane();
    cv::Mat disparity(kRoiHeight, kWidth, CV_16SC1);
    cv::RNG rng(3);
    for (int r = 0; r < kRoiHeight; ++r) {
        for (int x = 0; x < kWidth; ++x) {
            const double d =
                rng.uniform(0.0, 1.0) < 0.1 ? rng.uniform(0.0, 100.0) : plane.at(x, kY0 + r) + rng.gaussian(0.3);
            disparity.at<std::int16_t>(r, x) = static_cast<std::int16_t>(cvRound(16.0 * std::max(d, -1.0)));
        }
    }
    ugv::vision::GroundEstimatorConfig config;
    config.projection = kRigProjection;
    config.mount = {0.59, 0.0, 0.0};
    config.width = kWidth;
    config.height = kRoiHeight;
    config.y0 = kY0;
    auto sut = ugv::vision::GroundEstimator::create(config);
    const ugv::ImageView<const std::int16_t> in{disparity.ptr<std::int16_t>(), kWidth, kRoiHeight,
                                                static_cast<std::ptrdiff_t>(disparity.step)};
    for (auto _ : state) {
        benchmark::DoNotOptimize(sut->update(in).reliable);
    }
    state.counters["reliable"] = sut->estimate().reliable ? 1 : 0;
}

BENCHMARK(BM_GroundWarpCvRemapBaseline)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GroundWarpScalar)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GroundWarpSimd)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GroundMismatch<false>)->Name("BM_GroundMismatchReference")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GroundMismatch<true>)->Name("BM_GroundMismatch")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GroundMismatchSimPole<false>)->Name("BM_GroundMismatchSimPoleReference")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GroundMismatchSimPole<true>)->Name("BM_GroundMismatchSimPole")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GroundMismatchSimBox<false>)->Name("BM_GroundMismatchSimBoxReference")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GroundMismatchSimBox<true>)->Name("BM_GroundMismatchSimBox")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SectorBuild<false>)->Name("BM_SectorBuildReference")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SectorBuild<true>)->Name("BM_SectorBuild")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GroundEstimatorUpdate)->Unit(benchmark::kMicrosecond);

} // namespace

BENCHMARK_MAIN();
