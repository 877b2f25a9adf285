#include "ugv/tool/detection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "ugv/platform/angles.hpp"
#include "ugv/vision/mat_view.hpp"
#include "ugv/vision/roi_matcher.hpp"

namespace ugv::tool {
namespace {

constexpr int kFitStepPx = 4;        ///< [px] sample grid of the ground fit
constexpr double kFitInlierPx = 1.0; ///< [px]
constexpr int kFitIterations = 200;
constexpr int kFitMinInliers = 300;
/// The share of the samples a plane must hold: vision::GroundEstimatorConfig's (the samples include obstacles).
constexpr double kFitMinInlierFraction = 0.15;
constexpr double kMinCameraHeightM = 0.05; ///< [m]
constexpr double kMaxCameraHeightM = 10.0; ///< [m]
constexpr double kMaxPitchDeg = 45.0;      ///< [deg]
constexpr double kMaxRollDeg = 30.0;       ///< [deg]
constexpr int kBarHeightPx = 24;           ///< [px] sector bar below the overlay image
constexpr double kTintAlpha = 0.55;        ///< weight of the tint colour on obstacle pixels

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
    config.sectors.maxRangeDisparityPx = options.maxRangeDisparityPx;
    return config;
}

ConstImageViewU8 viewOf(const cv::Mat& grey)
{
    return ConstImageViewU8(grey.ptr<std::uint8_t>(0), grey.cols, grey.rows, static_cast<std::ptrdiff_t>(grey.step));
}

ConstBgrView bgrViewOf(const cv::Mat& bgr)
{
    CV_Assert(bgr.type() == CV_8UC3);
    return {bgr.ptr<BgrPixel>(0), bgr.cols, bgr.rows, static_cast<std::ptrdiff_t>(bgr.step)};
}

cv::Mat matOver(const StereoViews& images, bool right)
{
    if (images.colour()) {
        return vision::matOver(right ? images.rightBgr : images.leftBgr);
    }
    return vision::matOver(right ? images.right : images.left);
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
        (void)std::snprintf(text, sizeof(text),
                            "the fitted plane is not a plausible ground (height %.3g m, pitch %.3g deg, "
                            "roll %.3g deg)",
                            fit.ground.heightM, pitch, roll);
        return Unexpected(
            Error{where, text, "give the mount in the calibration file (mount: height_m, pitch_deg, roll_deg)"});
    }
    return fit;
}

Result<PairDetection, Error> detectPair(const vision::StereoCalibration& calib, const cv::Mat& left,
                                        const cv::Mat& right, const vision::DetectorConfig& config,
                                        const std::string& calibName)
{
    PairDetection out;
    auto rectifier = vision::Rectifier::create(calib, vision::roiRectifierConfig(config));
    if (!rectifier) {
        return Unexpected(std::move(rectifier).error());
    }
    out.rectifier.emplace(std::move(rectifier).value());
    vision::Rectifier& rect = *out.rectifier;
    if (rect.rectify(viewOf(left), viewOf(right)) != vision::RectifyStatus::Ok) {
        return Unexpected(Error{calibName, "rectification rejected the images", "check the image sizes"});
    }
    const Rect roi = rect.roi();
    const vision::RectifiedProjection& projection = rect.projection();
    vision::GroundPlane ground;
    if (calib.mount) {
        ground = vision::GroundPlane::fromMount(*calib.mount);
    } else {
        auto matcher = vision::RoiMatcher::create(config.matcher, cv::Size(roi.width, roi.height));
        if (!matcher) {
            return Unexpected(std::move(matcher).error());
        }
        if (matcher->match(rect.rectifiedLeft(), rect.rectifiedRight()) != vision::MatchStatus::Ok) {
            return Unexpected(Error{"ground estimate", "the stereo matcher failed on the ROI", ""});
        }
        auto fit = fitGround(matcher->disparity16(), roi, projection);
        if (!fit) {
            return Unexpected(Error{calibName + ": no mount, and the " + fit.error().where + " failed",
                                    fit.error().what, fit.error().fix});
        }
        ground = fit->ground;
        out.fit = *fit;
    }
    auto detector = vision::ObstacleDetector::create(config, rect, ground);
    if (!detector) {
        return Unexpected(std::move(detector).error());
    }
    out.detector.emplace(std::move(detector).value());
    // With ground-guided ranges the first frame searches the full range and sets the next frame's floor from its
    // ground: the pair's second frame is what the service sees in steady state (a still vehicle).
    const int frames = config.matcher.groundRange ? 2 : 1;
    for (int frame = 0; frame < frames; ++frame) {
        (void)out.detector->process(rect.rectifiedLeft(), rect.rectifiedRight(), static_cast<std::uint64_t>(frame), 0);
    }
    if (out.detector->status() != vision::DetectorStatus::Ok) {
        return Unexpected(Error{"detector",
                                "the pipeline failed (status " +
                                    std::to_string(static_cast<int>(out.detector->status())) + "), all sectors unknown",
                                ""});
    }
    return out;
}

cv::Scalar dangerColour(DangerClass danger)
{
    switch (danger) {
    case DangerClass::Red:
        return {0, 0, 255};
    case DangerClass::Blue:
        return {255, 0, 0};
    case DangerClass::Green:
        return {0, 190, 0};
    case DangerClass::Unknown:
        break;
    }
    return {128, 128, 128};
}

/// The rectified left image in colour (identity for the rectified form; each channel remapped otherwise) with
/// the obstacle pixels of the dense cue tinted (above the ground: red, below: blue) and a bar of the sectors'
/// danger classes below it, each sector over the columns of its bearings.
cv::Mat makeOverlay(const cv::Mat& colourLeft, vision::Rectifier& fullRectifier, const vision::ObstacleDetector& det,
                    const vision::DetectorConfig& config, const vision::RectifiedProjection& p)
{
    cv::Mat rectified;
    if (fullRectifier.identity()) {
        rectified = colourLeft.clone();
    } else {
        std::vector<cv::Mat> channels;
        cv::split(colourLeft, channels);
        for (cv::Mat& channel : channels) {
            cv::Mat out(channel.size(), CV_8UC1);
            (void)fullRectifier.rectify(viewOf(channel), viewOf(channel), ImageViewU8(out.data, out.cols, out.rows),
                                        ImageViewU8(out.data, out.cols, out.rows));
            channel = out;
        }
        cv::merge(channels, rectified);
    }
    const Rect roi = det.roi();
    const cv::Mat& disparity = det.disparity16();
    const vision::GroundPlane& ground = det.ground();
    for (int y = config.marginRows; y < roi.height; ++y) {
        const auto* d = disparity.ptr<std::int16_t>(y);
        auto* pixel = rectified.ptr<cv::Vec3b>(roi.y + y);
        for (int x = 0; x < roi.width; ++x) {
            if (d[x] <= 0) {
                continue;
            }
            const vision::VehiclePoint point =
                ground.pixelToVehicle(roi.x + x, roi.y + y, d[x] / static_cast<double>(vision::RoiMatcher::kScale), p);
            if (std::hypot(point.x, point.y) > det.sectorConfig().maxRangeM) {
                continue;
            }
            cv::Vec3b tint;
            if (point.z > det.sectorConfig().minHeightM) {
                tint = {0, 0, 255};
            } else if (point.z < -det.sectorConfig().minDepthM) {
                tint = {255, 0, 0};
            } else {
                continue;
            }
            cv::Vec3b& px = pixel[roi.x + x];
            for (int c = 0; c < 3; ++c) {
                px[c] = cv::saturate_cast<std::uint8_t>((1.0 - kTintAlpha) * px[c] + kTintAlpha * tint[c]);
            }
        }
    }
    const ObstacleSectors& sectors = det.sectors();
    std::vector<cv::Scalar> colours;
    colours.reserve(static_cast<std::size_t>(std::max(sectors.count, 0)));
    for (int i = 0; i < sectors.count; ++i) {
        colours.push_back(dangerColour(sectors.sectors[static_cast<std::size_t>(i)].danger));
    }
    return appendSectorBar(rectified, sectors, colours, p);
}

cv::Mat appendSectorBar(const cv::Mat& image, const ObstacleSectors& layout, const std::vector<cv::Scalar>& colours,
                        const vision::RectifiedProjection& p)
{
    cv::Mat canvas(image.rows + kBarHeightPx, image.cols, CV_8UC3, cv::Scalar(0, 0, 0));
    image.copyTo(canvas(cv::Rect(0, 0, image.cols, image.rows)));
    for (int i = 0; i < layout.count && i < static_cast<int>(colours.size()); ++i) {
        const Sector& s = layout.sectors[static_cast<std::size_t>(i)];
        // Positive bearings are to the left: the larger bearing gives the smaller column.
        const int x0 = static_cast<int>(std::lround(p.cx - p.fx * std::tan(s.bearingMaxDeg * kDegToRad)));
        const int x1 = static_cast<int>(std::lround(p.cx - p.fx * std::tan(s.bearingMinDeg * kDegToRad)));
        cv::rectangle(canvas, cv::Point(std::max(0, x0), image.rows + 2),
                      cv::Point(std::min(canvas.cols - 1, x1 - 1), canvas.rows - 3),
                      colours[static_cast<std::size_t>(i)], cv::FILLED);
    }
    return canvas;
}

} // namespace ugv::tool
