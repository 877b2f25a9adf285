// Rectification of one stereo pair at 640x480: ours (fixed-point tables, ROI rows only, no allocation) against
// OpenCV's cv::remap on the same ROI and on the full frame (the baseline), with the same calibration.
// Quote results as ratios against the baseline measured in the same run.

#include <benchmark/benchmark.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace {

constexpr int kWidth = 640;
constexpr int kHeight = 480;

ugv::vision::StereoCalibration makeCalibration()
{
    ugv::vision::StereoCalibration c;
    c.imageSize = cv::Size(kWidth, kHeight);
    c.K1 = (cv::Mat_<double>(3, 3) << 546, 0, 321, 0, 546, 238, 0, 0, 1);
    c.K2 = (cv::Mat_<double>(3, 3) << 548, 0, 318, 0, 548, 241, 0, 0, 1);
    c.D1 = (cv::Mat_<double>(1, 5) << -0.05, 0.01, 0, 0, 0);
    c.D2 = (cv::Mat_<double>(1, 5) << -0.04, 0.01, 0, 0, 0);
    cv::Mat rvec = (cv::Mat_<double>(3, 1) << 0.004, -0.01, 0.003);
    cv::Rodrigues(rvec, c.R);
    c.T = (cv::Mat_<double>(3, 1) << -0.30, 0.001, 0.0);
    cv::stereoRectify(c.K1, c.D1, c.K2, c.D2, c.imageSize, c.R, c.T, c.R1, c.R2, c.P1, c.P2, c.Q,
                      cv::CALIB_ZERO_DISPARITY, 0.0);
    return c;
}

cv::Mat makeImage(int seed)
{
    cv::Mat image(kHeight, kWidth, CV_8UC1);
    cv::RNG rng(static_cast<std::uint64_t>(seed));
    rng.fill(image, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(image, image, cv::Size(3, 3), 0.8);
    return image;
}

ugv::ConstImageViewU8 view(const cv::Mat& m)
{
    return {m.ptr<std::uint8_t>(), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}

void BM_RectifyOursRoi(benchmark::State& state)
{
    auto sut = ugv::vision::Rectifier::create(makeCalibration(), ugv::vision::RectifierConfig{});
    if (!sut) {
        state.SkipWithError("rectifier create failed");
        return;
    }
    const cv::Mat left = makeImage(1);
    const cv::Mat right = makeImage(2);
    for (auto _ : state) {
        benchmark::DoNotOptimize(sut->rectify(view(left), view(right)));
    }
    state.SetBytesProcessed(state.iterations() * 2 * sut->roi().width * sut->roi().height);
}

/// cv::remap with fixed-point maps; `roiOnly` restricts the maps to the same rows as ours.
void remapBaseline(benchmark::State& state, bool roiOnly)
{
    cv::setNumThreads(1);
    const auto c = makeCalibration();
    const int top = roiOnly ? kHeight / 2 - ugv::vision::RectifierConfig{}.roiMarginRows : 0;
    cv::Mat maps[2][2];
    const cv::Mat* k[2] = {&c.K1, &c.K2};
    const cv::Mat* d[2] = {&c.D1, &c.D2};
    const cv::Mat* r[2] = {&c.R1, &c.R2};
    const cv::Mat* p[2] = {&c.P1, &c.P2};
    for (int i = 0; i < 2; ++i) {
        cv::Mat m1;
        cv::Mat m2;
        cv::initUndistortRectifyMap(*k[i], *d[i], *r[i], *p[i], c.imageSize, CV_16SC2, m1, m2);
        maps[i][0] = m1.rowRange(top, kHeight).clone();
        maps[i][1] = m2.rowRange(top, kHeight).clone();
    }
    const cv::Mat images[2] = {makeImage(1), makeImage(2)};
    cv::Mat out[2] = {cv::Mat(kHeight - top, kWidth, CV_8UC1), cv::Mat(kHeight - top, kWidth, CV_8UC1)};
    for (auto _ : state) {
        for (int i = 0; i < 2; ++i) {
            cv::remap(images[i], out[i], maps[i][0], maps[i][1], cv::INTER_LINEAR);
        }
        benchmark::DoNotOptimize(out[0].data);
    }
    state.SetBytesProcessed(state.iterations() * 2 * kWidth * (kHeight - top));
}

void BM_CvRemapRoi(benchmark::State& state)
{
    remapBaseline(state, true);
}
void BM_CvRemapFullFrameBaseline(benchmark::State& state)
{
    remapBaseline(state, false);
}

} // namespace

BENCHMARK(BM_CvRemapFullFrameBaseline)->Unit(benchmark::kMicrosecond)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_CvRemapRoi)->Unit(benchmark::kMicrosecond)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_RectifyOursRoi)->Unit(benchmark::kMicrosecond)->Repetitions(5)->ReportAggregatesOnly(true);

BENCHMARK_MAIN();
