// Colour free space: ours (ground colours learnt from the band, a running window sum: O(1) per pixel) against
//  - the original method, a per-window histogram recomputation and intersection with the reference histogram
//    (O(window area + bins) per pixel), on a 4x downscaled 160x120 frame where both run (ours measured there too,
//    for the ratio; the naive timing covers only the window scores from ours' bin image, which favours it), and
//  - cv::calcBackProject (per-pixel lookup, no window; with OpenCV's blur and HSV conversion) at 640x480 as a
//    reference of what OpenCV's own back-projection costs.
// Seeded synthetic input: green textured ground with a brown block. Quote ratios measured in the same run.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cstdint>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "ugv/vision/colour_free_space.hpp"
#include "ugv/vision/ground_plane.hpp"

namespace {

using ugv::vision::ColourFreeSpace;
using ugv::vision::ColourFreeSpaceConfig;

cv::Mat makeImage(int width, int height)
{
    cv::Mat hsv(height, width, CV_8UC3);
    cv::Mat value(height, width, CV_8UC1);
    cv::RNG rng(0);
    rng.fill(value, cv::RNG::UNIFORM, 60, 200);
    cv::GaussianBlur(value, value, cv::Size(5, 5), 1.2);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const int v = value.at<std::uint8_t>(y, x);
            const bool block = x > width / 3 && x < width / 2 && y > height * 6 / 10 && y < height * 7 / 10;
            hsv.at<cv::Vec3b>(y, x) =
                block ? cv::Vec3b(12, 120, static_cast<std::uint8_t>(v))
                      : cv::Vec3b(static_cast<std::uint8_t>(50 + (v - 128) / 16),
                                  static_cast<std::uint8_t>(140 + (v - 128) / 4), static_cast<std::uint8_t>(v));
        }
    }
    cv::Mat bgr;
    cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
    return bgr;
}

ugv::ConstBgrView view(const cv::Mat& m)
{
    return {reinterpret_cast<const ugv::BgrPixel*>(m.data), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}

ColourFreeSpaceConfig configFor(int width)
{
    ColourFreeSpaceConfig config;
    if (width < 640) { // the 4x downscaled case: band scaled, window kept (the original's cost driver)
        config.bandRows = 15;
        config.bandSlices = 4;
    }
    return config;
}

ColourFreeSpace makeSut(int width, int height)
{
    const double scale = width / 640.0;
    const ugv::vision::RectifiedProjection projection{546 * scale, 546 * scale, (width - 1) / 2.0, (height - 1) / 2.0,
                                                      0.3};
    auto sut = ColourFreeSpace::create(configFor(width), {width, height}, projection,
                                       ugv::vision::GroundPlane::fromMount({0.59, 0.0, 0.0}));
    return std::move(sut).value();
}

void BM_ColourOurs(benchmark::State& state)
{
    const int width = static_cast<int>(state.range(0));
    const int height = width * 3 / 4;
    const cv::Mat image = makeImage(width, height);
    auto sut = makeSut(width, height);
    ugv::ObstacleSectors out;
    for (auto _ : state) {
        benchmark::DoNotOptimize(sut.process(view(image), out));
        benchmark::ClobberMemory();
    }
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * image.total() * 3);
}

/// The original: for every ROI pixel, rebuild the window histogram from its pixels, then intersect it with the
/// reference histogram (here that of the band, scaled to the window area).
void BM_ColourNaiveWindows(benchmark::State& state)
{
    const int width = static_cast<int>(state.range(0));
    const int height = width * 3 / 4;
    const cv::Mat image = makeImage(width, height);
    auto sut = makeSut(width, height);
    ugv::ObstacleSectors out;
    (void)sut.process(view(image), out); // bins
    const auto bins = sut.bins();
    const ColourFreeSpaceConfig config = configFor(width);
    const int r = config.windowRadius;
    const int area = (2 * r + 1) * (2 * r + 1);
    std::array<int, ugv::vision::kColourBins> bandCounts{};
    for (int y = height - config.bandRows; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            ++bandCounts[bins.row(y - sut.binTop())[x]];
        }
    }
    std::array<std::int16_t, ugv::vision::kColourBins> ref{};
    for (std::size_t b = 0; b < ref.size(); ++b) {
        ref[b] = static_cast<std::int16_t>(bandCounts[b] * area / (width * config.bandRows));
    }
    cv::Mat scores(height - sut.roiTop(), width, CV_8UC1, cv::Scalar(0));
    for (auto _ : state) {
        for (int y = std::max(sut.roiTop(), sut.binTop() + r); y < height - r; ++y) {
            for (int x = r; x < width - r; ++x) {
                std::array<std::int16_t, ugv::vision::kColourBins> hist{};
                for (int v = y - r; v <= y + r; ++v) {
                    const std::uint8_t* row = bins.row(v - sut.binTop());
                    for (int u = x - r; u <= x + r; ++u) {
                        ++hist[row[u]];
                    }
                }
                int common = 0;
                for (std::size_t b = 0; b < hist.size(); ++b) {
                    common += std::min(hist[b], ref[b]);
                }
                scores.at<std::uint8_t>(y - sut.roiTop(), x) =
                    static_cast<std::uint8_t>(std::min((common * 255 + area / 2) / area, 255));
            }
        }
        benchmark::DoNotOptimize(scores.data);
        benchmark::ClobberMemory();
    }
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * image.total() * 3);
}

/// OpenCV reference: blur, HSV, the band's hue-saturation histogram, per-pixel back-projection of the ROI (no window
/// comparison).
void BM_ColourCalcBackProject(benchmark::State& state)
{
    const int width = static_cast<int>(state.range(0));
    const int height = width * 3 / 4;
    const cv::Mat image = makeImage(width, height);
    const ColourFreeSpaceConfig config = configFor(width);
    const cv::Rect roi(0, height / 2, width, height - height / 2);
    const cv::Rect patch(0, height - config.bandRows, width, config.bandRows);
    const int channels[] = {0, 1};
    const int histSize[] = {ugv::vision::kHueBins, ugv::vision::kSatBins};
    const float hueRange[] = {0, 180};
    const float satRange[] = {0, 256};
    const float* ranges[] = {hueRange, satRange};
    cv::Mat blurred;
    cv::Mat hsv;
    cv::Mat hist;
    cv::Mat backProject;
    for (auto _ : state) {
        cv::blur(image, blurred, cv::Size(3, 3));
        cv::cvtColor(blurred(roi), hsv, cv::COLOR_BGR2HSV);
        const cv::Mat patchHsv = hsv(cv::Rect(patch.x, patch.y - roi.y, patch.width, patch.height));
        cv::calcHist(&patchHsv, 1, channels, cv::Mat(), hist, 2, histSize, ranges);
        cv::normalize(hist, hist, 0, 255, cv::NORM_MINMAX);
        cv::calcBackProject(&hsv, 1, channels, hist, backProject, ranges);
        benchmark::DoNotOptimize(backProject.data);
        benchmark::ClobberMemory();
    }
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * image.total() * 3);
}

BENCHMARK(BM_ColourOurs)->Arg(160)->Arg(640)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ColourNaiveWindows)->Arg(160)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ColourCalcBackProject)->Arg(640)->Unit(benchmark::kMillisecond);

} // namespace

int main(int argc, char** argv)
{
    cv::setNumThreads(1); // as in the service: OpenCV threads off, so the reference runs single-threaded like ours
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) {
        return 1;
    }
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
