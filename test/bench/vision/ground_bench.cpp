// Ground stages at 640x480 with ROI = bottom 248 rows (seeded synthetic input): the ground warp (scalar
// reference, universal-intrinsics kernel, cv::remap with equivalent float maps as the baseline), the mismatch
// stage (on a synthetic pair where a band of the image is shifted off the ground model) and the estimator
// update. Quote results as ratios against the baseline measured in the same run.

#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "ugv/vision/ground_estimator.hpp"
#include "ugv/vision/ground_mismatch.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/ground_warp.hpp"

namespace {

constexpr int kWidth = 640;
constexpr int kRoiHeight = 248;
constexpr int kY0 = 480 - kRoiHeight;
const ugv::vision::RectifiedProjection kProj{546.0, 546.0, 319.5, 239.5, 0.30};

ugv::vision::DisparityPlane groundPlane()
{
    return ugv::vision::GroundPlane::fromMount({0.59, 1.0, 1.0}).disparityPlane(kProj);
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
void BM_GroundWarpScalar(benchmark::State& state) { BM_GroundWarp<false>(state); }
void BM_GroundWarpSimd(benchmark::State& state) { BM_GroundWarp<true>(state); }

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

void BM_GroundMismatch(benchmark::State& state)
{
    MismatchInput in;
    ugv::vision::GroundMismatchConfig config;
    config.width = kWidth;
    config.height = kRoiHeight;
    auto sut = ugv::vision::GroundMismatch::create(config);
    for (auto _ : state) {
        benchmark::DoNotOptimize(sut->run(view(in.left), view(in.right), view(in.warped), in.spans, in.plane, kY0));
    }
    state.counters["tested"] = sut->counts().tested;
    state.counters["notGround"] = sut->counts().positive + sut->counts().negative + sut->counts().unsure;
    state.SetBytesProcessed(state.iterations() * kWidth * kRoiHeight);
}

void BM_GroundEstimatorUpdate(benchmark::State& state)
{
    const ugv::vision::DisparityPlane plane = groundPlane();
    cv::Mat disparity(kRoiHeight, kWidth, CV_16SC1);
    cv::RNG rng(3);
    for (int r = 0; r < kRoiHeight; ++r) {
        for (int x = 0; x < kWidth; ++x) {
            const double d = rng.uniform(0.0, 1.0) < 0.1 ? rng.uniform(0.0, 100.0) : plane.at(x, kY0 + r) + rng.gaussian(0.3);
            disparity.at<std::int16_t>(r, x) = static_cast<std::int16_t>(cvRound(16.0 * std::max(d, -1.0)));
        }
    }
    ugv::vision::GroundEstimatorConfig config;
    config.projection = kProj;
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
BENCHMARK(BM_GroundMismatch)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GroundEstimatorUpdate)->Unit(benchmark::kMicrosecond);

} // namespace

BENCHMARK_MAIN();
