// bench-detect: the per-frame obstacle pipeline (ObstacleDetector::process) against OpenCV StereoSGBM on the full
// 640x480 frame (the baseline, same settings, measured in the same run), the ROI matcher alone and the sector
// builder alone. Input: one ugvsense sim pair (pole at 4 m, asphalt, seed 0), 128 disparities, block 5.
// Report ratios against BM_FullFrameSgbmBaseline (shared, noisy machines).
#include <algorithm>
#include <vector>

#include <benchmark/benchmark.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "sim/renderer.hpp"
#include "sim/scene.hpp"
#include "ugv/vision/obstacle_detector.hpp"
#include "ugv/vision/roi_matcher.hpp"
#include "ugv/vision/sector_builder.hpp"

namespace {

using namespace ugv;
using namespace ugv::vision;

constexpr RectifiedProjection kProjection{546.0, 546.0, 319.5, 239.5, 0.30};
constexpr Rect kRoi{0, 232, 640, 248};

const sim::RenderResult& frame()
{
    static const sim::RenderResult result = [] {
        auto scene = sim::makeScene("pole", 4.0, 0.0, sim::GroundTexture::Asphalt, 0).value();
        return sim::render(scene).value();
    }();
    return result;
}

ConstImageViewU8 roiView(const cv::Mat& image)
{
    return {image.ptr<std::uint8_t>(kRoi.y), image.cols, kRoi.height, static_cast<std::ptrdiff_t>(image.step[0])};
}

void BM_FullFrameSgbmBaseline(benchmark::State& state)
{
    cv::setNumThreads(1);
    const RoiMatcherConfig c;
    constexpr int kArea = 25;
    auto sgbm =
        cv::StereoSGBM::create(0, c.numDisparities, c.blockSize, 8 * kArea, 32 * kArea, c.disp12MaxDiff, c.preFilterCap,
                               c.uniquenessRatio, c.speckleWindowSize, c.speckleRange, cv::StereoSGBM::MODE_SGBM_3WAY);
    cv::Mat disparity(480, 640, CV_16SC1);
    for (auto _ : state) {
        sgbm->compute(frame().left, frame().right, disparity);
        benchmark::DoNotOptimize(disparity.data);
    }
    state.SetBytesProcessed(state.iterations() * 2 * 640 * 480);
}

void BM_DetectorPipeline(benchmark::State& state)
{
    auto sut =
        ObstacleDetector::create(DetectorConfig{}, kProjection, kRoi, GroundPlane::fromMount(Mount{0.59, 0.0, 0.0}))
            .value();
    std::uint64_t sequence = 0;
    for (auto _ : state) {
        const auto& out = sut.process(roiView(frame().left), roiView(frame().right), ++sequence, 0);
        benchmark::DoNotOptimize(&out);
    }
    state.SetBytesProcessed(state.iterations() * 2 * kRoi.width * kRoi.height);
}

void BM_RoiMatcher(benchmark::State& state)
{
    auto sut = RoiMatcher::create(RoiMatcherConfig{}, cv::Size(kRoi.width, kRoi.height)).value();
    for (auto _ : state) {
        benchmark::DoNotOptimize(sut.match(roiView(frame().left), roiView(frame().right)));
    }
    state.SetBytesProcessed(state.iterations() * 2 * kRoi.width * kRoi.height);
}

void BM_SectorBuilder(benchmark::State& state)
{
    auto matcher = RoiMatcher::create(RoiMatcherConfig{}, cv::Size(kRoi.width, kRoi.height)).value();
    (void)matcher.match(roiView(frame().left), roiView(frame().right));
    auto sut = SectorBuilder::create(SectorBuilderConfig{}, kProjection, kRoi, kRoi.y + 8).value();
    const GroundPlane ground = GroundPlane::fromMount(Mount{0.59, 0.0, 0.0});
    for (auto _ : state) {
        benchmark::DoNotOptimize(sut.build(matcher.disparityView(), {}, ground, 1U, 0));
    }
}

BENCHMARK(BM_FullFrameSgbmBaseline)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3)
    ->ComputeStatistics("max", [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); });
BENCHMARK(BM_DetectorPipeline)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3)
    ->ComputeStatistics("max", [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); });
BENCHMARK(BM_RoiMatcher)->Unit(benchmark::kMillisecond)->Repetitions(3);
BENCHMARK(BM_SectorBuilder)->Unit(benchmark::kMillisecond)->Repetitions(3);

} // namespace

BENCHMARK_MAIN();
