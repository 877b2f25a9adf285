#include "detection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

namespace ugv::tool {
namespace {

constexpr int kFitStepPx = 4;        ///< [px] sample grid of the ground fit
constexpr double kFitInlierPx = 1.0; ///< [px]
constexpr int kFitIterations = 200;
constexpr int kFitMinInliers = 300;
constexpr double kFitMinInlierFraction = 0.3;
constexpr double kMinCameraHeightM = 0.05; ///< [m]
constexpr double kMaxCameraHeightM = 10.0; ///< [m]
constexpr double kMaxPitchDeg = 45.0;      ///< [deg]
constexpr double kMaxRollDeg = 30.0;       ///< [deg]

struct Sample {
    double x;
    double y;
    double d;
};

/// Least-squares plane through `points`; false when singular.
bool solvePlane(const std::vector<Sample>& points, vision::DisparityPlane& out)
{
    cv::Matx33d ata = cv::Matx33d::zeros();
    cv::Vec3d atb(0, 0, 0);
    for (const Sample& s : points) {
        const cv::Vec3d row(s.x, s.y, 1.0);
        ata += row * row.t();
        atb += row * s.d;
    }
    cv::Vec3d abc;
    if (!cv::solve(ata, atb, abc, cv::DECOMP_CHOLESKY)) {
        return false;
    }
    out = vision::DisparityPlane{abc[0], abc[1], abc[2]};
    return true;
}

} // namespace

vision::DetectorConfig detectorConfig(const DetectionOptions& options)
{
    vision::DetectorConfig config;
    config.sectors.sectorCount = options.sectorCount;
    config.sectors.dangerDistanceM = options.dangerM;
    config.sectors.cautionDistanceM = options.cautionM;
    return config;
}

ConstImageViewU8 viewOf(const cv::Mat& grey)
{
    return ConstImageViewU8(grey.ptr<std::uint8_t>(0), grey.cols, grey.rows, static_cast<std::ptrdiff_t>(grey.step));
}

Result<GroundFit, Error> fitGround(const cv::Mat& disparity16, Rect roi, const vision::RectifiedProjection& projection)
{
    const std::string where = "ground estimate";
    const int imageHeight = roi.y + roi.height;
    const int firstRow = std::max(roi.y, imageHeight - imageHeight / 3);
    std::vector<Sample> samples;
    for (int y = firstRow; y < imageHeight; y += kFitStepPx) {
        const auto* row = disparity16.ptr<std::int16_t>(y - roi.y);
        for (int x = 0; x < roi.width; x += kFitStepPx) {
            if (row[x] > 0) {
                samples.push_back({static_cast<double>(roi.x + x), static_cast<double>(y),
                                   row[x] / static_cast<double>(vision::RoiMatcher::kScale)});
            }
        }
    }
    GroundFit fit;
    fit.samples = static_cast<int>(samples.size());
    if (fit.samples < kFitMinInliers) {
        return Unexpected(Error{where,
                                "only " + std::to_string(fit.samples) +
                                    " valid disparities in the bottom third of the image (need " +
                                    std::to_string(kFitMinInliers) + ")",
                                "give the mount in the calibration file (mount: height_m, pitch_deg, roll_deg)"});
    }
    std::mt19937 random(1); // fixed seed: the same images give the same plane
    std::uniform_int_distribution<std::size_t> pick(0, samples.size() - 1);
    std::vector<Sample> best;
    std::vector<Sample> inliers;
    for (int i = 0; i < kFitIterations; ++i) {
        vision::DisparityPlane candidate;
        if (!solvePlane({samples[pick(random)], samples[pick(random)], samples[pick(random)]}, candidate)) {
            continue;
        }
        inliers.clear();
        for (const Sample& s : samples) {
            if (std::abs(candidate.at(s.x, s.y) - s.d) <= kFitInlierPx) {
                inliers.push_back(s);
            }
        }
        if (inliers.size() > best.size()) {
            best.swap(inliers);
        }
    }
    fit.inliers = static_cast<int>(best.size());
    if (fit.inliers < kFitMinInliers || fit.inliers < kFitMinInlierFraction * fit.samples ||
        !solvePlane(best, fit.plane)) {
        return Unexpected(Error{where,
                                "no dominant ground plane in the bottom third of the image (" +
                                    std::to_string(fit.inliers) + " of " + std::to_string(fit.samples) +
                                    " disparities fit one plane)",
                                "give the mount in the calibration file (mount: height_m, pitch_deg, roll_deg)"});
    }
    fit.ground = vision::GroundPlane::fromDisparityPlane(fit.plane, projection);
    const double pitch = fit.ground.pitchDeg();
    const double roll = fit.ground.rollDeg();
    if (!(fit.plane.b > 0.0) || !(fit.ground.heightM > kMinCameraHeightM && fit.ground.heightM <= kMaxCameraHeightM) ||
        std::abs(pitch) > kMaxPitchDeg || std::abs(roll) > kMaxRollDeg) {
        char text[160];
        std::snprintf(text, sizeof(text),
                      "the fitted plane is not a plausible ground (height %.3g m, pitch %.3g deg, "
                      "roll %.3g deg)",
                      fit.ground.heightM, pitch, roll);
        return Unexpected(
            Error{where, text, "give the mount in the calibration file (mount: height_m, pitch_deg, roll_deg)"});
    }
    return fit;
}

const char* stateName(SectorState state)
{
    switch (state) {
    case SectorState::Clear:
        return "clear";
    case SectorState::Obstacle:
        return "obstacle";
    case SectorState::Unknown:
        break;
    }
    return "unknown";
}

const char* kindName(ObstacleKind kind)
{
    switch (kind) {
    case ObstacleKind::Positive:
        return "positive";
    case ObstacleKind::Negative:
        return "negative";
    case ObstacleKind::None:
        break;
    }
    return "none";
}

const char* className(DangerClass danger)
{
    switch (danger) {
    case DangerClass::Green:
        return "green";
    case DangerClass::Blue:
        return "blue";
    case DangerClass::Red:
        return "red";
    case DangerClass::Unknown:
        break;
    }
    return "unknown";
}

std::string jsonNumber(double value)
{
    if (!std::isfinite(value)) {
        return "null";
    }
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g", value);
    return text;
}

std::string sectorsJsonArray(const ObstacleSectors& sectors, int indent)
{
    const std::string pad(static_cast<std::size_t>(indent), ' ');
    std::string out = "[";
    for (int i = 0; i < sectors.count; ++i) {
        const Sector& s = sectors.sectors[static_cast<std::size_t>(i)];
        out += (i == 0 ? "\n" : ",\n") + pad + "{\"bearing_min_deg\": " + jsonNumber(s.bearingMinDeg) +
               ", \"bearing_max_deg\": " + jsonNumber(s.bearingMaxDeg) + ", \"range_m\": " + jsonNumber(s.rangeM) +
               ", \"kind\": \"" + kindName(s.kind) + "\", \"state\": \"" + stateName(s.state) + "\", \"class\": \"" +
               className(s.danger) + "\", \"height_m\": " + jsonNumber(s.heightM) +
               ", \"confidence\": " + jsonNumber(s.confidence) + "}";
    }
    return out + (sectors.count > 0 ? "\n" + pad.substr(std::min<std::size_t>(pad.size(), 2)) + "]" : "]");
}

} // namespace ugv::tool
