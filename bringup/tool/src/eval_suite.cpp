#include "ugv/tool/eval_suite.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include "ugv/sim/renderer.hpp"

namespace ugv::tool {

namespace {
constexpr double kFalseClearRangeM = 10.0; ///< [m] GT obstacles this near reported Clear count as false Clear
} // namespace
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
    // Detected: a GT obstacle sector, or one next to it (bearings on a boundary), is reported Obstacle. The range
    // error: the nearest range reported in the GT obstacle sectors against the nearest true one (the neighbours
    // only when none of those is reported). Scoring only the single nearest GT sector would miss a wide obstacle
    // whose nearest GT sector is a sliver at its lateral edge (a hole's rim seen at a grazing angle). Obstacle
    // reports in GT-clear sectors are counted apart (spill: the matcher's foreground fattening).
    const int count = std::min(detected.count, gt.count);
    const auto isGtObstacle = [&gt](int i) {
        return i >= 0 && i < gt.count && at(gt, i).state == SectorState::Obstacle;
    };
    double nearestInside = std::numeric_limits<double>::infinity();
    double nearestNext = std::numeric_limits<double>::infinity();
    for (int i = 0; i < count; ++i) {
        if (at(detected, i).state == SectorState::Clear && isGtObstacle(i) && at(gt, i).rangeM <= kFalseClearRangeM) {
            ++score.falseClearSectors; // the vehicle would be told it may drive where an obstacle stands
        }
        if (at(detected, i).state != SectorState::Obstacle) {
            continue;
        }
        const double range = at(detected, i).rangeM;
        if (isGtObstacle(i)) {
            nearestInside = std::min(nearestInside, range);
        } else if (isGtObstacle(i - 1) || isGtObstacle(i + 1)) {
            nearestNext = std::min(nearestNext, range);
            ++score.spillSectors;
        } else {
            ++score.spillSectors;
        }
    }
    score.detected = std::isfinite(nearestInside) || std::isfinite(nearestNext);
    if (score.detected) {
        score.detectedRangeM = std::isfinite(nearestInside) ? nearestInside : nearestNext;
        score.rangeErrorM = std::abs(score.detectedRangeM - score.gtRangeM);
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
    int gapFirst = -1;
    int gapLast = -1;
    for (int i = first + 1; first >= 0 && i < last && i < detected.count; ++i) {
        if (at(gt, i).state == SectorState::Clear) {
            gapFirst = gapFirst < 0 ? i : gapFirst;
            gapLast = i;
            ++score.gapSectors;
            score.reportedObstacle += at(detected, i).state == SectorState::Obstacle ? 1 : 0;
            score.reportedClear += at(detected, i).state == SectorState::Clear ? 1 : 0;
        }
    }
    for (int i = gapFirst + 1; gapFirst >= 0 && i < gapLast; ++i) {
        score.innerObstacle +=
            at(gt, i).state == SectorState::Clear && at(detected, i).state == SectorState::Obstacle ? 1 : 0;
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
        score.bad1All = static_cast<double>(bad1All) / score.gtPixels;
        score.bad2All = static_cast<double>(bad2All) / score.gtPixels;
    }
    if (score.predictedValid > 0) {
        score.bad1Valid = static_cast<double>(bad1Valid) / score.predictedValid;
        score.bad2Valid = static_cast<double>(bad2Valid) / score.predictedValid;
    }
    return score;
}

ApproachScore scoreApproach(std::vector<ApproachFrame> frames)
{
    std::sort(frames.begin(), frames.end(),
              [](const ApproachFrame& a, const ApproachFrame& b) { return a.gtRangeM < b.gtRangeM; });
    ApproachScore score;
    score.frames = static_cast<int>(frames.size());
    bool held = true; // every frame so far (from the nearest out) detected
    for (const ApproachFrame& f : frames) {
        held = held && f.detected;
        if (f.detected) {
            ++score.detected;
            score.firstRangeM = f.gtRangeM; // sorted: the last detected is the farthest
        }
        if (held) {
            score.heldRangeM = f.gtRangeM;
        }
    }
    return score;
}

namespace {

constexpr float kWallBelowGroundPx = 0.75F;
constexpr int kStripStepPx = 4;
constexpr int kGroundRowsAroundWall = 6;

/// Linear interpolation of row `r` at x; false outside the row.
bool sampleRow(const std::uint8_t* r, int cols, double x, float& value)
{
    const int x0 = static_cast<int>(std::floor(x));
    if (x0 < 0 || x0 + 1 >= cols) {
        return false;
    }
    const auto f = static_cast<float>(x - x0);
    value = (1.0F - f) * static_cast<float>(r[x0]) + f * static_cast<float>(r[x0 + 1]);
    return true;
}

} // namespace

cv::Mat dropEvidence(const cv::Mat& left, const cv::Mat& right, const vision::DisparityPlane& ground, int rowFirst,
                     int rowLast, int halfWidth)
{
    CV_Assert(left.type() == CV_8UC1 && right.type() == CV_8UC1 && left.size() == right.size() && halfWidth >= 1);
    constexpr double kNearestBelowPx = 0.5;
    constexpr double kFarthestBelowPx = 3.0;
    constexpr double kStepPx = 0.25;
    constexpr double kGroundSearchPx = 0.375;
    constexpr double kGroundStepPx = 0.125;
    constexpr int kGroundSteps = 7; // -kGroundSearchPx .. +kGroundSearchPx
    constexpr int kBelowSteps = 11; // kFarthestBelowPx .. kNearestBelowPx below the ground
    static_assert((2 * kGroundSearchPx) / kGroundStepPx + 1 == kGroundSteps);
    static_assert((kFarthestBelowPx - kNearestBelowPx) / kStepPx + 1 == kBelowSteps);
    cv::Mat evidence(left.size(), CV_32F, cv::Scalar(0));
    const int n = 2 * halfWidth + 1;
    std::vector<float> l(static_cast<std::size_t>(n));
    std::vector<float> r(static_cast<std::size_t>(n));
    // Zero-mean SAD per pixel of the window at disparity d(x) for each window pixel; false off the image.
    const auto cost = [&](int y, int x, const auto& disparityAt, float& c) {
        const std::uint8_t* lr = left.ptr<std::uint8_t>(y);
        const std::uint8_t* rr = right.ptr<std::uint8_t>(y);
        float ml = 0.0F;
        float mr = 0.0F;
        for (int i = 0; i < n; ++i) {
            const int xi = x - halfWidth + i;
            l[static_cast<std::size_t>(i)] = lr[xi];
            if (!sampleRow(rr, right.cols, xi - disparityAt(xi), r[static_cast<std::size_t>(i)])) {
                return false;
            }
            ml += l[static_cast<std::size_t>(i)];
            mr += r[static_cast<std::size_t>(i)];
        }
        ml /= static_cast<float>(n);
        mr /= static_cast<float>(n);
        c = 0.0F;
        for (std::size_t i = 0; i < l.size(); ++i) {
            c += std::abs((l[i] - ml) - (r[i] - mr));
        }
        c /= static_cast<float>(n);
        return true;
    };
    for (int y = std::max(0, rowFirst); y <= std::min(left.rows - 1, rowLast); ++y) {
        float* e = evidence.ptr<float>(y);
        for (int x = halfWidth; x < left.cols - halfWidth; ++x) {
            // The ground gets a search of its own (+-3/8 px): the least of the 11 farther costs would otherwise beat
            // a single ground cost by chance wherever the images disagree for another reason (the noise of a strong
            // edge: the simulator's jittered samples, a real rig's small vertical misalignment).
            float onGround = std::numeric_limits<float>::infinity();
            for (int step = 0; step < kGroundSteps; ++step) {
                const double shift = -kGroundSearchPx + step * kGroundStepPx;
                float c = 0.0F;
                if (cost(
                        y, x, [&](int xi) { return ground.at(xi, y) + shift; }, c)) {
                    onGround = std::min(onGround, c);
                }
            }
            if (!std::isfinite(onGround)) {
                continue;
            }
            float best = std::numeric_limits<float>::infinity();
            const double dg = ground.at(x, y);
            for (int step = 0; step < kBelowSteps; ++step) {
                const double d = dg - kFarthestBelowPx + step * kStepPx;
                float c = 0.0F;
                if (d > 0.0 && cost(
                                   y, x, [d](int) { return d; }, c)) {
                    best = std::min(best, c);
                }
            }
            e[x] = std::isfinite(best) ? (onGround - best) / (onGround + 1.0F) : 0.0F;
        }
    }
    return evidence;
}

DropSignal scoreDropSignal(const cv::Mat& evidence, const cv::Mat& labels, const cv::Mat& gtDisparity,
                           const vision::DisparityPlane& ground, int rowFirst, int rowLast, int stripWidth,
                           int stripRows)
{
    rowFirst = std::max(0, rowFirst);
    rowLast = std::min(evidence.rows - 1, rowLast);
    const auto isWall = [&](int y, int x) {
        return labels.at<std::uint8_t>(y, x) == static_cast<std::uint8_t>(sim::Label::Negative) &&
               ground.at(x, y) - gtDisparity.at<float>(y, x) >= kWallBelowGroundPx;
    };
    int wallFirst = rowLast + 1;
    int wallLast = rowFirst - 1;
    for (int y = rowFirst; y <= rowLast; ++y) {
        for (int x = 0; x < evidence.cols; ++x) {
            if (isWall(y, x)) {
                wallFirst = std::min(wallFirst, y);
                wallLast = std::max(wallLast, y);
            }
        }
    }
    DropSignal signal;
    if (wallFirst > wallLast) {
        return signal;
    }
    signal.wallBest = -std::numeric_limits<double>::infinity();
    signal.groundBest = -std::numeric_limits<double>::infinity();
    const int area = stripWidth * stripRows;
    for (int y = std::max(rowFirst, wallFirst - kGroundRowsAroundWall);
         y + stripRows - 1 <= std::min(rowLast, wallLast + kGroundRowsAroundWall); ++y) {
        for (int x0 = 0; x0 + stripWidth <= evidence.cols; x0 += kStripStepPx) {
            double sum = 0.0;
            int wall = 0;
            int plain = 0;
            for (int yy = y; yy < y + stripRows; ++yy) {
                for (int x = x0; x < x0 + stripWidth; ++x) {
                    sum += evidence.at<float>(yy, x);
                    wall += isWall(yy, x) ? 1 : 0;
                    plain += labels.at<std::uint8_t>(yy, x) == static_cast<std::uint8_t>(sim::Label::Ground) ? 1 : 0;
                }
            }
            const double mean = sum / area;
            if (2 * wall >= area) {
                signal.hasWall = true;
                signal.wallBest = std::max(signal.wallBest, mean);
            } else if (plain == area) {
                signal.groundBest = std::max(signal.groundBest, mean);
            }
        }
    }
    signal.wallBest = signal.hasWall ? signal.wallBest : 0.0;
    signal.groundBest = std::isfinite(signal.groundBest) ? signal.groundBest : 0.0;
    return signal;
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
