#include "ugv/vision/stereo_calibrator.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace ugv::vision {
namespace {

constexpr int kMaxSubPixHalfWindow = 5; // 11x11 window, right for 640x480 boards of 20+ px squares
constexpr int kMinSubPixHalfWindow = 2;
constexpr double kSubPixWindowPerSquare = 0.4; // half window as a fraction of the smallest square side [px/px]
constexpr int kSubPixMaxIterations = 100;
constexpr double kSubPixEpsilon = 1e-4; // [px]
constexpr int kStereoMaxIterations = 200;
constexpr double kStereoEpsilon = 1e-7;

struct Detection {
    std::string name;
    std::vector<cv::Point2f> left;
    std::vector<cv::Point2f> right;
};

std::string formatPx(double value)
{
    char text[32];
    (void)std::snprintf(text, sizeof(text), "%.3f", value);
    return text;
}

double smallestSquareSidePx(const std::vector<cv::Point2f>& corners, cv::Size innerCorners)
{
    double side = 1e9;
    for (int row = 0; row < innerCorners.height; ++row) {
        for (int col = 0; col + 1 < innerCorners.width; ++col) {
            const int i = row * innerCorners.width + col;
            side = std::min(side, static_cast<double>(cv::norm(corners[i + 1] - corners[i])));
        }
    }
    return side;
}

struct StereoRun {
    StereoCalibration calib;
    std::vector<double> pairErrorsPx;
};

/// Per-camera calibration for a start, then the joint stereo refinement (best figures on the OpenCV sample
/// pairs: RMS 0.445, epipolar 0.262, |dy| 0.127 px against 0.448/0.290/0.141 with CALIB_FIX_INTRINSIC).
StereoRun runStereo(const std::vector<Detection>& detections, const std::vector<cv::Point3f>& board, cv::Size imageSize)
{
    std::vector<std::vector<cv::Point3f>> objectPoints(detections.size(), board);
    std::vector<std::vector<cv::Point2f>> left;
    std::vector<std::vector<cv::Point2f>> right;
    for (const auto& detection : detections) {
        left.push_back(detection.left);
        right.push_back(detection.right);
    }
    StereoRun run;
    StereoCalibration& c = run.calib;
    c.imageSize = imageSize;
    std::vector<cv::Mat> rvecs;
    std::vector<cv::Mat> tvecs;
    cv::calibrateCamera(objectPoints, left, imageSize, c.K1, c.D1, rvecs, tvecs);
    cv::calibrateCamera(objectPoints, right, imageSize, c.K2, c.D2, rvecs, tvecs);
    cv::Mat perViewErrors;
    c.rmsPx = cv::stereoCalibrate(
        objectPoints, left, right, c.K1, c.D1, c.K2, c.D2, imageSize, c.R, c.T, c.E, c.F, perViewErrors,
        cv::CALIB_USE_INTRINSIC_GUESS,
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, kStereoMaxIterations, kStereoEpsilon));
    for (int i = 0; i < perViewErrors.rows; ++i) {
        const double l = perViewErrors.at<double>(i, 0);
        const double r = perViewErrors.at<double>(i, 1);
        run.pairErrorsPx.push_back(std::sqrt((l * l + r * r) / 2.0));
    }
    cv::stereoRectify(c.K1, c.D1, c.K2, c.D2, imageSize, c.R, c.T, c.R1, c.R2, c.P1, c.P2, c.Q,
                      cv::CALIB_ZERO_DISPARITY, 0.0);

    // Epipolar error as in OpenCV's samples/cpp/stereo_calib.cpp: on undistorted points, distance of each
    // right corner to the epipolar line of its left corner plus the reverse, summed, averaged over corners.
    double epipolarSum = 0.0;
    std::size_t points = 0;
    for (std::size_t i = 0; i < left.size(); ++i) {
        std::vector<cv::Point2f> undistortedLeft;
        std::vector<cv::Point2f> undistortedRight;
        cv::undistortPoints(left[i], undistortedLeft, c.K1, c.D1, cv::noArray(), c.K1);
        cv::undistortPoints(right[i], undistortedRight, c.K2, c.D2, cv::noArray(), c.K2);
        std::vector<cv::Vec3f> linesInRight;
        std::vector<cv::Vec3f> linesInLeft;
        cv::computeCorrespondEpilines(undistortedLeft, 1, c.F, linesInRight);
        cv::computeCorrespondEpilines(undistortedRight, 2, c.F, linesInLeft);
        for (std::size_t j = 0; j < undistortedLeft.size(); ++j) {
            const cv::Point2f& pl = undistortedLeft[j];
            const cv::Point2f& pr = undistortedRight[j];
            epipolarSum += std::abs(pr.x * linesInRight[j][0] + pr.y * linesInRight[j][1] + linesInRight[j][2]) +
                           std::abs(pl.x * linesInLeft[j][0] + pl.y * linesInLeft[j][1] + linesInLeft[j][2]);
            ++points;
        }
    }
    c.epipolarPx = points == 0 ? 0.0 : epipolarSum / static_cast<double>(points);
    c.rectifiedDyPx = meanRectifiedDy(c, left, right);
    c.pairsUsed = static_cast<int>(detections.size());
    return run;
}

double median(std::vector<double> values)
{
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/// Why a pair cannot be calibrated from, before its board is looked for (an empty or non-grey image, sizes that
/// differ from each other or from the pairs taken so far, imageSize, empty before the first); empty when it can.
std::string imageProblem(const CalibrationPair& pair, cv::Size imageSize)
{
    if (pair.left.empty() || pair.right.empty()) {
        return std::string("empty image (") + (pair.left.empty() ? "left" : "right") + ")";
    }
    if (pair.left.type() != CV_8UC1 || pair.right.type() != CV_8UC1) {
        return "not an 8-bit grey image";
    }
    if (pair.left.size() != pair.right.size()) {
        return "size mismatch: left " + std::to_string(pair.left.cols) + "x" + std::to_string(pair.left.rows) +
               ", right " + std::to_string(pair.right.cols) + "x" + std::to_string(pair.right.rows);
    }
    if (!imageSize.empty() && pair.left.size() != imageSize) {
        return "size mismatch: " + std::to_string(pair.left.cols) + "x" + std::to_string(pair.left.rows) +
               ", other pairs " + std::to_string(imageSize.width) + "x" + std::to_string(imageSize.height);
    }
    return {};
}

/// The board corners of every usable pair, and their image size; each other pair goes to report.rejected with why.
std::vector<Detection> detectBoards(const std::vector<CalibrationPair>& pairs, const CalibratorConfig& config,
                                    CalibrationReport& report, cv::Size& imageSize)
{
    std::vector<Detection> detections;
    for (const auto& pair : pairs) {
        if (std::string problem = imageProblem(pair, imageSize); !problem.empty()) {
            report.rejected.push_back({pair.name, std::move(problem)});
            continue;
        }
        Detection detection{pair.name, {}, {}};
        const bool foundLeft = findBoardCorners(pair.left, config.innerCorners, detection.left);
        const bool foundRight = foundLeft && findBoardCorners(pair.right, config.innerCorners, detection.right);
        if (!foundLeft || !foundRight) {
            report.rejected.push_back(
                {pair.name, std::string("board not found in ") + (foundLeft ? "right" : "left") + " image"});
            continue;
        }
        imageSize = pair.left.size();
        detections.push_back(std::move(detection));
    }
    return detections;
}

std::vector<cv::Point3f> boardPoints(const CalibratorConfig& config)
{
    std::vector<cv::Point3f> board;
    for (int row = 0; row < config.innerCorners.height; ++row) {
        for (int col = 0; col < config.innerCorners.width; ++col) {
            board.emplace_back(static_cast<float>(col * config.squareM), static_cast<float>(row * config.squareM),
                               0.0F);
        }
    }
    return board;
}

/// Drops the worst pair and recalibrates without it, one pair a round, while its error is over the limit, at least
/// minPairs stay and the RMS improves; each dropped pair goes to report.rejected.
void dropOutliers(StereoRun& run, std::vector<Detection>& detections, const std::vector<cv::Point3f>& board,
                  cv::Size imageSize, const CalibratorConfig& config, CalibrationReport& report)
{
    for (int round = 0; round < config.maxOutlierRounds; ++round) {
        const double medianPx = median(run.pairErrorsPx);
        const double limitPx = std::max(config.outlierFactor * medianPx, config.outlierFloorPx);
        // Only the worst pair goes each round: a bad pair bends the calibration and inflates the others' errors,
        // which are judged again after recalibrating without it (on aarch64 a good pair crossed the limit beside
        // a shifted one when every pair above it went at once).
        const auto worst = static_cast<std::size_t>(std::max_element(run.pairErrorsPx.begin(), run.pairErrorsPx.end()) -
                                                    run.pairErrorsPx.begin());
        if (run.pairErrorsPx[worst] <= limitPx || detections.size() - 1 < static_cast<std::size_t>(config.minPairs)) {
            break;
        }
        RejectedPair dropped{detections[worst].name, "outlier: error " + formatPx(run.pairErrorsPx[worst]) + " px > " +
                                                         formatPx(config.outlierFactor) + " x median " +
                                                         formatPx(medianPx) + " px"};
        std::vector<Detection> kept = detections;
        kept.erase(kept.begin() + static_cast<std::ptrdiff_t>(worst));
        StereoRun candidate = runStereo(kept, board, imageSize);
        if (candidate.calib.rmsPx >= run.calib.rmsPx) {
            break; // dropping did not help: keep every pair
        }
        run = std::move(candidate);
        detections = std::move(kept);
        report.rejected.push_back(std::move(dropped));
        ++report.outlierRounds;
    }
}

Result<CalibrationReport, Error> calibrateChecked(const std::vector<CalibrationPair>& pairs,
                                                  const CalibratorConfig& config)
{
    CalibrationReport report;
    cv::Size imageSize;
    std::vector<Detection> detections = detectBoards(pairs, config, report, imageSize);
    if (detections.size() < static_cast<std::size_t>(config.minPairs)) {
        return Unexpected(Error{"calibration",
                                "only " + std::to_string(detections.size()) + " usable pair(s), need at least " +
                                    std::to_string(config.minPairs),
                                "take more pairs with the whole board visible in both cameras"});
    }
    const std::vector<cv::Point3f> board = boardPoints(config);
    StereoRun run = runStereo(detections, board, imageSize);
    report.rmsBeforeOutliersPx = run.calib.rmsPx;
    dropOutliers(run, detections, board, imageSize, config, report);
    for (std::size_t i = 0; i < detections.size(); ++i) {
        report.perPair.push_back({detections[i].name, run.pairErrorsPx[i]});
    }
    report.calibration = std::move(run.calib);
    report.calibration.pairsRejected = static_cast<int>(report.rejected.size());
    return report;
}

} // namespace

bool findBoardCorners(const cv::Mat& grey, cv::Size innerCorners, std::vector<cv::Point2f>& corners)
{
    corners.clear();
    if (cv::findChessboardCorners(grey, innerCorners, corners,
                                  cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
        const double sidePx = smallestSquareSidePx(corners, innerCorners);
        const int half =
            std::clamp(static_cast<int>(kSubPixWindowPerSquare * sidePx), kMinSubPixHalfWindow, kMaxSubPixHalfWindow);
        cv::cornerSubPix(
            grey, corners, cv::Size(half, half), cv::Size(-1, -1),
            cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, kSubPixMaxIterations, kSubPixEpsilon));
        return true;
    }
    // The sector-based detector finds boards the classic one misses (blur, strong perspective); its corners
    // are already sub-pixel accurate.
    corners.clear();
    return cv::findChessboardCornersSB(grey, innerCorners, corners, cv::CALIB_CB_NORMALIZE_IMAGE) &&
           corners.size() == static_cast<std::size_t>(innerCorners.area());
}

double meanRectifiedDy(const StereoCalibration& calib, const std::vector<std::vector<cv::Point2f>>& left,
                       const std::vector<std::vector<cv::Point2f>>& right)
{
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < left.size() && i < right.size(); ++i) {
        std::vector<cv::Point2f> rectifiedLeft;
        std::vector<cv::Point2f> rectifiedRight;
        cv::undistortPoints(left[i], rectifiedLeft, calib.K1, calib.D1, calib.R1, calib.P1);
        cv::undistortPoints(right[i], rectifiedRight, calib.K2, calib.D2, calib.R2, calib.P2);
        for (std::size_t j = 0; j < rectifiedLeft.size() && j < rectifiedRight.size(); ++j) {
            sum += std::abs(rectifiedLeft[j].y - rectifiedRight[j].y);
            ++count;
        }
    }
    return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

Result<CalibrationReport, Error> calibrateStereo(const std::vector<CalibrationPair>& pairs,
                                                 const CalibratorConfig& config)
{
    if (config.innerCorners.width < 2 || config.innerCorners.height < 2 || !std::isfinite(config.squareM) ||
        config.squareM <= 0.0 || config.minPairs < 3 || !(config.outlierFactor > 1.0) ||
        !(config.outlierFloorPx >= 0.0) || config.maxOutlierRounds < 0) {
        return Unexpected(Error{"calibration config", "invalid board or outlier settings",
                                "board needs >= 2x2 inner corners, square > 0 m, minPairs >= 3, factor > 1"});
    }
    try {
        return calibrateChecked(pairs, config);
    } catch (const cv::Exception& e) {
        return Unexpected(Error{"calibration", std::string("OpenCV failed: ") + e.what(),
                                "check that the pairs show the same board in varied poses"});
    }
}

} // namespace ugv::vision
