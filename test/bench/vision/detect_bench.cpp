// bench-detect: the per-frame obstacle pipeline (ObstacleDetector::process, with our census SGM and with OpenCV's
// SGBM_3WAY) against OpenCV StereoSGBM on the full 640x480 frame (the baselines, same settings, MODE_SGBM and
// MODE_SGBM_3WAY, measured in the same run), our census SGM on the full frame (SIMD and its scalar reference), the
// ROI matcher alone (each mode), the sector builder alone and the obstacle verifier alone (SIMD and scalar). Input: one
// ugvsense sim pair (pole at 4 m, asphalt, seed 0), 128 disparities, block 5. Report ratios against
// BM_FullFrameSgbmBaseline (shared, noisy machines).
#include <algorithm>
#include <array>
#include <chrono>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "test_rig.hpp"
#include "ugv/platform/clock.hpp"
#include "ugv/rt/latency_histogram.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"
#include "ugv/vision/census_sgm.hpp"
#include "ugv/vision/obstacle_detector.hpp"
#include "ugv/vision/obstacle_verifier.hpp"
#include "ugv/vision/roi_matcher.hpp"
#include "ugv/vision/sector_builder.hpp"

namespace {

using namespace ugv;
using namespace ugv::vision;

using ugv::test::kRigProjection;
constexpr Rect kRoi{0, 232, 640, 248};

const sim::RenderResult& frame()
{
    static const sim::RenderResult result = [] {
        auto scene = sim::makeScene("pole", 4.0, 0.0, sim::GroundTexture::Asphalt, 0).value();
        return sim::render(scene).value();
    }();
    return result;
}

/// Per-frame latency percentiles of a benchmark loop (rt::LatencyHistogram), as counters p50_ms and p99_ms.
class FrameTimes {
public:
    void start() { t0_ = std::chrono::steady_clock::now(); }
    void stop() { histogram_.record(std::chrono::steady_clock::now() - t0_); }
    void report(benchmark::State& state) const
    {
        state.counters["p50_ms"] = std::chrono::duration<double, std::milli>(histogram_.p50()).count();
        state.counters["p99_ms"] = std::chrono::duration<double, std::milli>(histogram_.p99()).count();
    }

private:
    std::chrono::steady_clock::time_point t0_;
    rt::LatencyHistogram histogram_;
};

ConstImageViewU8 roiView(const cv::Mat& image)
{
    return {image.ptr<std::uint8_t>(kRoi.y), image.cols, kRoi.height, static_cast<std::ptrdiff_t>(image.step[0])};
}

/// OpenCV StereoSGBM on the full frame with our settings; state.range(0) is the OpenCV mode: MODE_SGBM (0, the
/// default mode, the issue's ~70 ms figure) and MODE_SGBM_3WAY (2, the faster mode our matcher uses).
void BM_FullFrameSgbmBaseline(benchmark::State& state)
{
    cv::setNumThreads(1);
    const RoiMatcherConfig c;
    constexpr int kArea = 25;
    auto sgbm = cv::StereoSGBM::create(0, c.numDisparities, c.blockSize, 8 * kArea, 32 * kArea, c.disp12MaxDiff,
                                       c.preFilterCap, c.uniquenessRatio, c.speckleWindowSize, c.speckleRange,
                                       static_cast<int>(state.range(0)));
    cv::Mat disparity(480, 640, CV_16SC1);
    FrameTimes times;
    for (auto _ : state) {
        times.start();
        sgbm->compute(frame().left, frame().right, disparity);
        benchmark::DoNotOptimize(disparity.data);
        times.stop();
    }
    times.report(state);
    state.SetBytesProcessed(state.iterations() * 2 * 640 * 480);
}

/// Our census SGM on the full frame: the matcher-for-matcher comparison with BM_FullFrameSgbmBaseline.
/// state.range(0): 1 the universal-intrinsics kernels, 0 the scalar reference (the same output).
void BM_FullFrameCensusSgm(benchmark::State& state)
{
    CensusSgmConfig config;
    config.simd = state.range(0) != 0;
    auto sut = CensusSgm::create(config, cv::Size(640, 480)).value();
    cv::Mat disparity(480, 640, CV_16SC1);
    const auto view = [](const cv::Mat& m) {
        return ConstImageViewU8{m.ptr<std::uint8_t>(0), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step[0])};
    };
    FrameTimes times;
    for (auto _ : state) {
        times.start();
        benchmark::DoNotOptimize(sut.match(view(frame().left), view(frame().right), disparity));
        times.stop();
    }
    times.report(state);
    state.SetBytesProcessed(state.iterations() * 2 * 640 * 480);
}

/// state.range(0): the MatcherMode (0 census SGM, the default; 2 OpenCV SGBM_3WAY); state.range(1): 1 turns the
/// census SGM's ground-guided ranges on (RoiMatcherConfig::groundRange; every frame after the first searches from
/// the previous frame's ground, here the same pair's), 0 off; state.range(2), when given: the near rows at half
/// resolution from this ground disparity on [px] (DetectorConfig::halfResolutionMinGroundPx).
void BM_DetectorPipeline(benchmark::State& state)
{
    DetectorConfig config;
    config.matcher.mode = static_cast<MatcherMode>(state.range(0));
    config.matcher.groundRange = state.range(1) != 0;
    config.halfResolutionMinGroundPx = static_cast<double>(state.range(2));
    auto sut =
        ObstacleDetector::create(config, kRigProjection, kRoi, GroundPlane::fromMount(Mount{0.59, 0.0, 0.0})).value();
    sut.setStageClock(&ugv::MonotonicClock::nowNs);
    std::uint64_t sequence = 0;
    FrameTimes times;
    std::array<double, ugv::vision::kVisionStageCount> stageMs{};
    for (auto _ : state) {
        times.start();
        const auto& out = sut.process(roiView(frame().left), roiView(frame().right), ++sequence, 0);
        benchmark::DoNotOptimize(&out);
        times.stop();
        for (int i = 0; i < ugv::vision::kVisionStageCount; ++i) {
            stageMs[static_cast<std::size_t>(i)] +=
                static_cast<double>(sut.stageTimes().ns[static_cast<std::size_t>(i)]) / 1e6;
        }
    }
    times.report(state);
    state.counters["searched_pct"] = 100.0 * sut.searchedFraction(); // cost cells searched / the full range's
    // Where the time goes: the mean of each stage per frame [ms] (issue 25 item 1).
    for (int i = 0; i < ugv::vision::kVisionStageCount; ++i) {
        state.counters[std::string("ms_") + stageName(static_cast<ugv::vision::VisionStage>(i))] =
            stageMs[static_cast<std::size_t>(i)] / static_cast<double>(std::max<std::int64_t>(state.iterations(), 1));
    }
    state.SetBytesProcessed(state.iterations() * 2 * kRoi.width * kRoi.height);
}

/// state.range(0): the MatcherMode.
void BM_RoiMatcher(benchmark::State& state)
{
    RoiMatcherConfig config;
    config.mode = static_cast<MatcherMode>(state.range(0));
    auto sut = RoiMatcher::create(config, cv::Size(kRoi.width, kRoi.height)).value();
    for (auto _ : state) {
        benchmark::DoNotOptimize(sut.match(roiView(frame().left), roiView(frame().right)));
    }
    state.SetBytesProcessed(state.iterations() * 2 * kRoi.width * kRoi.height);
}

void BM_SectorBuilder(benchmark::State& state)
{
    auto matcher = RoiMatcher::create(RoiMatcherConfig{}, cv::Size(kRoi.width, kRoi.height)).value();
    (void)matcher.match(roiView(frame().left), roiView(frame().right));
    auto sut = SectorBuilder::create(SectorBuilderConfig{}, kRigProjection, kRoi, kRoi.y + 8).value();
    const GroundPlane ground = GroundPlane::fromMount(Mount{0.59, 0.0, 0.0});
    for (auto _ : state) {
        benchmark::DoNotOptimize(sut.build(matcher.disparityView(), {}, ground, 1U, 0));
    }
}

/// state.range(0): 1 the universal-intrinsics window costs, 0 the scalar reference (the same output).
void BM_ObstacleVerifier(benchmark::State& state)
{
    auto matcher = RoiMatcher::create(RoiMatcherConfig{}, cv::Size(kRoi.width, kRoi.height)).value();
    (void)matcher.match(roiView(frame().left), roiView(frame().right));
    ObstacleVerifierConfig config;
    config.width = kRoi.width;
    config.height = kRoi.height;
    config.simd = state.range(0) != 0;
    auto sut = ObstacleVerifier::create(config).value();
    const DisparityPlane ground = GroundPlane::fromMount(Mount{0.59, 0.0, 0.0}).disparityPlane(kRigProjection);
    for (auto _ : state) {
        benchmark::DoNotOptimize(
            sut.run(roiView(frame().left), roiView(frame().right), matcher.disparityView(), ground, kRoi.y));
    }
}

BENCHMARK(BM_FullFrameSgbmBaseline)
    ->Arg(cv::StereoSGBM::MODE_SGBM)
    ->Arg(cv::StereoSGBM::MODE_SGBM_3WAY)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3)
    ->ComputeStatistics("max", [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); });
BENCHMARK(BM_FullFrameCensusSgm)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->Repetitions(3);
BENCHMARK(BM_DetectorPipeline)
    ->Args({static_cast<int>(MatcherMode::CensusSgm), 0, 0})
    ->Args({static_cast<int>(MatcherMode::CensusSgm), 1, 0})
    ->Args({static_cast<int>(MatcherMode::CensusSgm), 0, 48})
    ->Args({static_cast<int>(MatcherMode::Sgbm3Way), 0, 0})
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3)
    ->ComputeStatistics("max", [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); });
BENCHMARK(BM_RoiMatcher)
    ->Arg(static_cast<int>(MatcherMode::CensusSgm))
    ->Arg(static_cast<int>(MatcherMode::Sgbm))
    ->Arg(static_cast<int>(MatcherMode::Sgbm3Way))
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3);
BENCHMARK(BM_SectorBuilder)->Unit(benchmark::kMillisecond)->Repetitions(3);
BENCHMARK(BM_ObstacleVerifier)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->Repetitions(3);

} // namespace

BENCHMARK_MAIN();
