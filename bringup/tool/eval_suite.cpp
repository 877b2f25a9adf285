#include "eval_suite.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace ugv::tool {
namespace {

constexpr double kMinToleranceM = 0.10; ///< [m]
constexpr double kRelativeTolerance = 0.03;

const Sector& at(const ObstacleSectors& s, int i)
{
    return s.sectors[static_cast<std::size_t>(i)];
}

} // namespace

double rangeTolerance(double rangeM)
{
    return std::max(kMinToleranceM, kRelativeTolerance * rangeM);
}

ObstacleFrameScore scoreObstacleFrame(const ObstacleSectors& detected, const ObstacleSectors& gt)
{
    ObstacleFrameScore score;
    for (int i = 0; i < gt.count; ++i) {
        if (at(gt, i).state == SectorState::Obstacle &&
            (score.gtSector < 0 || at(gt, i).rangeM < at(gt, score.gtSector).rangeM)) {
            score.gtSector = i;
        }
    }
    if (score.gtSector < 0) {
        return score;
    }
    score.gtHasObstacle = true;
    score.gtRangeM = at(gt, score.gtSector).rangeM;
    const int count = std::min(detected.count, gt.count);
    for (int i = std::max(0, score.gtSector - 1); i <= std::min(count - 1, score.gtSector + 1); ++i) {
        if (at(detected, i).state != SectorState::Obstacle) {
            continue;
        }
        const double error = std::abs(static_cast<double>(at(detected, i).rangeM) - score.gtRangeM);
        if (!score.detected || error < score.rangeErrorM) {
            score.rangeErrorM = error;
        }
        score.detected = true;
    }
    return score;
}

int countRedBlue(const ObstacleSectors& sectors)
{
    int n = 0;
    for (int i = 0; i < sectors.count; ++i) {
        n += at(sectors, i).danger == DangerClass::Red || at(sectors, i).danger == DangerClass::Blue ? 1 : 0;
    }
    return n;
}

GapScore scoreGap(const ObstacleSectors& detected, const ObstacleSectors& gt)
{
    int first = -1;
    int last = -1;
    for (int i = 0; i < gt.count; ++i) {
        if (at(gt, i).state == SectorState::Obstacle) {
            first = first < 0 ? i : first;
            last = i;
        }
    }
    GapScore score;
    for (int i = first + 1; first >= 0 && i < last && i < detected.count; ++i) {
        if (at(gt, i).state == SectorState::Clear) {
            ++score.gapSectors;
            score.reportedObstacle += at(detected, i).state == SectorState::Obstacle ? 1 : 0;
        }
    }
    return score;
}

DisparityScore scoreDisparity(const cv::Mat& predicted, const cv::Mat& gt)
{
    DisparityScore score;
    int bad1All = 0;
    int bad2All = 0;
    int bad1Valid = 0;
    int bad2Valid = 0;
    for (int y = 0; y < gt.rows; ++y) {
        const float* g = gt.ptr<float>(y);
        const float* d = predicted.ptr<float>(y);
        for (int x = 0; x < gt.cols; ++x) {
            if (!(g[x] > 0.0F)) {
                continue;
            }
            ++score.gtPixels;
            if (!(d[x] >= 0.0F)) {
                ++bad1All;
                ++bad2All;
                continue;
            }
            ++score.predictedValid;
            const float error = std::abs(d[x] - g[x]);
            bad1All += error > 1.0F ? 1 : 0;
            bad2All += error > 2.0F ? 1 : 0;
            bad1Valid += error > 1.0F ? 1 : 0;
            bad2Valid += error > 2.0F ? 1 : 0;
        }
    }
    if (score.gtPixels > 0) {
        score.bad1All = double(bad1All) / score.gtPixels;
        score.bad2All = double(bad2All) / score.gtPixels;
    }
    if (score.predictedValid > 0) {
        score.bad1Valid = double(bad1Valid) / score.predictedValid;
        score.bad2Valid = double(bad2Valid) / score.predictedValid;
    }
    return score;
}

double quantile(std::vector<double> values, double p)
{
    if (values.empty()) {
        return 0.0;
    }
    std::sort(values.begin(), values.end());
    const auto rank = static_cast<std::size_t>(std::ceil(p * static_cast<double>(values.size())));
    return values[std::min(values.size() - 1, rank == 0 ? 0 : rank - 1)];
}

} // namespace ugv::tool
