// ugvsense detect: one-shot obstacle detection on one stereo pair with a calibration file; prints the sectors and
// optionally writes them (with the ground estimate) as JSON and an overlay PNG. With --mono, the one-camera mode:
// vision::ColourFreeSpace on the left image read in colour, the ground from the calibration's mount.

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ugv/adapters/calibration_file.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"
#include "ugv/tool/detection.hpp"
#include "ugv/tool/pair_files.hpp"
#include "ugv/vision/colour_free_space.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/obstacle_detector.hpp"
#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/roi_matcher.hpp"

namespace ugv::tool {
namespace {

constexpr double kMaxDistanceM = 100.0; ///< [m] upper bound of --danger / --caution

constexpr const char* kDetectCommand = "detect";

const char* fallbackName(vision::GroundFallbackReason reason)
{
    switch (reason) {
    case vision::GroundFallbackReason::None:
        return "none";
    case vision::GroundFallbackReason::WrongInput:
        return "wrong input";
    case vision::GroundFallbackReason::TooFewCandidates:
        return "too few valid disparities";
    case vision::GroundFallbackReason::TooFewInliers:
        return "too few inliers";
    case vision::GroundFallbackReason::DegenerateFit:
        return "degenerate fit";
    case vision::GroundFallbackReason::OutOfBand:
        return "outside the band around the mount";
    }
    return "unknown";
}

/// The ground as estimated (plane, reliability, from how many disparities, why it fell back, the noise it measured)
/// and the sectors.
bool writeJson(const std::string& path, const vision::ObstacleDetector& det, bool estimated)
{
    const vision::GroundPlane& g = det.ground();
    std::ofstream out(path);
    if (!out) {
        return false;
    }
    out << "{\n  \"ground\": {\"height_m\": " << jsonNumber(g.heightM)
        << ", \"pitch_deg\": " << jsonNumber(g.pitchDeg()) << ", \"roll_deg\": " << jsonNumber(g.rollDeg())
        << ", \"reliable\": " << (det.groundEstimate().reliable ? "true" : "false") << ", \"source\": \""
        << (estimated ? "estimated" : "configured mount") << "\", \"candidates\": " << det.groundEstimate().candidates
        << ", \"inliers\": " << det.groundEstimate().inliers << ", \"fallback_reason\": \""
        << fallbackName(det.groundEstimate().reason) << "\""
        << ", \"disparity_noise_px\": " << jsonNumber(det.groundNoisePx())
        << ", \"max_range_m\": " << jsonNumber(det.sectorConfig().maxRangeM)
        << "},\n  \"degraded\": " << (det.sectors().degraded ? "true" : "false")
        << ",\n  \"count\": " << det.sectors().count << ",\n  \"sectors\": " << sectorsJsonArray(det.sectors(), 4)
        << "\n}\n";
    out.flush();
    return static_cast<bool>(out);
}

void printSectors(const ObstacleSectors& sectors)
{
    int counts[4] = {0, 0, 0, 0}; // by DangerClass
    int obstacles = 0;
    int clear = 0;
    const Sector* nearest = nullptr;
    for (int i = 0; i < sectors.count; ++i) {
        const Sector& s = sectors.sectors[static_cast<std::size_t>(i)];
        ++counts[static_cast<int>(s.danger)];
        if (s.state == SectorState::Clear) {
            ++clear;
            continue;
        }
        if (s.state == SectorState::Obstacle) {
            ++obstacles;
            if (nearest == nullptr || s.rangeM < nearest->rangeM) {
                nearest = &s;
            }
        }
        std::printf("sector %3d [%6.1f, %6.1f] deg  %-8s %-8s %-7s", i, s.bearingMinDeg, s.bearingMaxDeg,
                    stateName(s.state), kindName(s.kind), className(s.danger));
        if (s.state == SectorState::Obstacle) {
            std::printf("  range %6.2f m  height %5.2f m  confidence %.2f", s.rangeM, s.heightM, s.confidence);
        }
        std::printf("\n");
    }
    std::printf("summary: %d sectors: %d obstacle (red %d, blue %d), %d clear, %d unknown (green %d)%s\n",
                sectors.count, obstacles, counts[static_cast<int>(DangerClass::Red)],
                counts[static_cast<int>(DangerClass::Blue)], clear, sectors.count - obstacles - clear,
                counts[static_cast<int>(DangerClass::Green)], sectors.degraded ? ", DEGRADED" : "");
    if (nearest != nullptr) {
        std::printf("nearest obstacle: %.2f m at bearing %.1f deg (%s, %s)\n", nearest->rangeM,
                    0.5 * (nearest->bearingMinDeg + nearest->bearingMaxDeg), kindName(nearest->kind),
                    className(nearest->danger));
    }
}

/// The one-camera mode's result: the ground it used (the mount), what its reference band taught, the sectors.
bool writeMonoJson(const std::string& path, const vision::GroundPlane& g, const vision::ColourFreeSpace& colour,
                   const ObstacleSectors& sectors)
{
    std::ofstream out(path);
    if (!out) {
        return false;
    }
    const vision::ColourReference& ref = colour.reference();
    out << "{\n  \"detector\": \"colour\",\n  \"ground\": {\"height_m\": " << jsonNumber(g.heightM)
        << ", \"pitch_deg\": " << jsonNumber(g.pitchDeg()) << ", \"roll_deg\": " << jsonNumber(g.rollDeg())
        << ", \"source\": \"configured mount\"},\n  \"reference\": {\"mean_value\": " << jsonNumber(ref.meanValue)
        << ", \"coverage\": " << jsonNumber(ref.coverage) << ", \"ground_colours\": " << ref.groundColours
        << ", \"ground_like\": " << (ref.groundLike ? "true" : "false")
        << "},\n  \"degraded\": " << (sectors.degraded ? "true" : "false") << ",\n  \"count\": " << sectors.count
        << ",\n  \"sectors\": " << sectorsJsonArray(sectors, 4) << "\n}\n";
    out.flush();
    return static_cast<bool>(out);
}

/// `detect --mono`: ColourFreeSpace on the left image (rectified with the calibration's left camera unless the
/// calibration is already in rectified form); the ground plane is the calibration's mount.
int runMono(const Args& args, const vision::StereoCalibration& calib, const DetectionOptions& options)
{
    if (!calib.mount) {
        return reportError(kDetectCommand, Error{args.get("calib"), "no mount: one camera cannot estimate the ground",
                                                 "add the mount (height_m, pitch_deg, roll_deg) to the calibration"});
    }
    std::string why;
    const cv::Mat image = readImage(args.get("left"), cv::IMREAD_COLOR, &why);
    if (image.empty()) {
        return reportError(kDetectCommand, Error{args.get("left"), why, "give an existing 8-bit image file"});
    }
    if (image.size() != calib.imageSize) {
        return reportError(kDetectCommand, Error{args.get("left"), "image size does not match the calibration",
                                                 "use the calibration of this camera at this resolution"});
    }
    vision::RectifierConfig rectConfig;
    rectConfig.fullFrame = true;
    auto rectifier = vision::Rectifier::create(calib, rectConfig);
    if (!rectifier) {
        return reportError(kDetectCommand, rectifier.error());
    }
    cv::Mat left = image;
    if (!calib.rectified) {
        try {
            cv::Mat mapX;
            cv::Mat mapY;
            cv::initUndistortRectifyMap(calib.K1, calib.D1, calib.R1, calib.P1, calib.imageSize, CV_32FC1, mapX, mapY);
            cv::remap(image, left, mapX, mapY, cv::INTER_LINEAR);
        } catch (const std::exception& e) {
            return reportError(kDetectCommand,
                               Error{args.get("calib"), std::string("cannot rectify the left image: ") + e.what(),
                                     "check the calibration file"});
        }
    }
    const vision::GroundPlane ground = vision::GroundPlane::fromMount(*calib.mount);
    auto colour = vision::ColourFreeSpace::create(vision::colourConfigFor(detectorConfig(options).sectors),
                                                  calib.imageSize, rectifier->projection(), ground);
    if (!colour) {
        return reportError(kDetectCommand, colour.error());
    }
    ObstacleSectors sectors;
    (void)colour->process(bgrViewOf(left), sectors); // the size was checked: always Ok
    const vision::ColourReference& ref = colour->reference();
    std::printf("one camera (ColourFreeSpace): ground from the mount: height %.3f m, pitch %.2f deg, roll %.2f deg; "
                "reference band: value %.1f, %d ground colours covering %.2f of it -> %s\n",
                ground.heightM, ground.pitchDeg(), ground.rollDeg(), ref.meanValue, ref.groundColours, ref.coverage,
                ref.groundLike ? "ground-like" : "NOT ground-like (all sectors Unknown)");
    printSectors(sectors);
    if (args.has("json")) {
        if (!writeMonoJson(args.get("json"), ground, *colour, sectors)) {
            return reportError(kDetectCommand,
                               Error{args.get("json"), "cannot write the JSON file", "check that the folder exists"});
        }
        std::printf("wrote %s\n", args.get("json").c_str());
    }
    return 0;
}

/// detect's options, parsed; an exit code when they are wrong.
std::optional<int> readDetectOptions(const Args& args, DetectionOptions& options)
{
    const auto sectorCount = args.number("sectors", 64, 1, kMaxSectors);
    const auto danger = args.number("danger", 1.5, 0.01, kMaxDistanceM);
    const auto caution = args.number("caution", 5.0, 0.01, kMaxDistanceM);
    const auto maxRangePx = args.number("max-range-px", DetectionOptions{}.maxRangeDisparityPx, 2.0, 128.0);
    for (const auto* value : {&sectorCount, &danger, &caution, &maxRangePx}) {
        if (!*value) {
            return reportUsageError("detect", value->error());
        }
    }
    const bool mono = args.has("mono");
    if (!mono && !args.has("right")) {
        return reportUsageError("detect", Error{"ugvsense detect", "missing required option '--right R.png'",
                                                "give --right, or --mono for one camera"});
    }
    if (mono && (args.has("right") || args.has("overlay"))) {
        return reportUsageError("detect", Error{"ugvsense detect --mono", "--right and --overlay are stereo options",
                                                "leave them out with --mono"});
    }
    if (*sectorCount != std::floor(*sectorCount) || *caution < *danger) {
        return reportUsageError("detect", Error{"ugvsense detect", "--sectors must be whole and --caution >= --danger",
                                                "see 'ugvsense detect --help'"});
    }
    options = DetectionOptions{static_cast<int>(*sectorCount), static_cast<float>(*danger),
                               static_cast<float>(*caution), static_cast<float>(*maxRangePx)};
    return std::nullopt;
}

/// The left and right images, grey, of one size and the calibration's; the error names the file and the fix.
Result<std::pair<cv::Mat, cv::Mat>, Error> readStereoPair(const Args& args, const vision::StereoCalibration& calib)
{
    if (isJpeg(args.get("left")) || isJpeg(args.get("right"))) {
        std::cerr << "ugvsense detect: warning: " << kJpegPairsWarning << '\n';
    }
    std::string why;
    cv::Mat left = readImage(args.get("left"), cv::IMREAD_GRAYSCALE, &why);
    if (left.empty()) {
        return Unexpected(Error{args.get("left"), why, "give an existing 8-bit image file"});
    }
    cv::Mat right = readImage(args.get("right"), cv::IMREAD_GRAYSCALE, &why);
    if (right.empty()) {
        return Unexpected(Error{args.get("right"), why, "give an existing 8-bit image file"});
    }
    const auto sizeText = [](cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); };
    if (left.size() != right.size()) {
        return Unexpected(
            Error{args.get("right"),
                  "size " + sizeText(right.size()) + " differs from the left image's " + sizeText(left.size()),
                  "give the two images of one stereo pair"});
    }
    if (left.size() != calib.imageSize) {
        return Unexpected(
            Error{args.get("left"),
                  "image size " + sizeText(left.size()) + " but the calibration is for " + sizeText(calib.imageSize),
                  "use the calibration of this camera at this resolution"});
    }
    return std::pair{std::move(left), std::move(right)};
}

/// The ground the pair was detected with, and its sectors, printed.
void printDetection(const PairDetection& run)
{
    const bool estimated = run.fit.has_value();
    if (estimated) {
        const vision::GroundPlane& g = run.fit->ground;
        std::printf("ground: estimated from the bottom rows (no mount in the calibration): height %.3f m, pitch "
                    "%.2f deg, roll %.2f deg (%d of %d disparities fit)\n",
                    g.heightM, g.pitchDeg(), g.rollDeg(), run.fit->inliers, run.fit->samples);
    }
    const vision::ObstacleDetector& detector = *run.detector;
    const vision::GroundPlane& used = detector.ground();
    std::printf("ground used: height %.3f m, pitch %.2f deg, roll %.2f deg (%s; per-frame estimate %s)\n", used.heightM,
                used.pitchDeg(), used.rollDeg(), estimated ? "estimated" : "configured mount",
                detector.groundEstimate().reliable ? "reliable" : "not reliable, prior used");
    printSectors(detector.sectors());
}

/// --overlay: the full rectified left image in colour with the obstacles and the sector bar.
Result<void, Error> writeOverlay(const Args& args, const vision::StereoCalibration& calib, const PairDetection& run,
                                 const vision::DetectorConfig& config)
{
    vision::RectifierConfig fullConfig;
    fullConfig.roiMarginRows = config.marginRows;
    fullConfig.fullFrame = true;
    auto fullRectifier = vision::Rectifier::create(calib, fullConfig);
    if (!fullRectifier) {
        return Unexpected(fullRectifier.error());
    }
    std::string why;
    const cv::Mat colour = readImage(args.get("left"), cv::IMREAD_COLOR, &why);
    bool written = false;
    if (!colour.empty()) {
        const cv::Mat overlay = makeOverlay(colour, *fullRectifier, *run.detector, config, run.rectifier->projection());
        try {
            written = cv::imwrite(args.get("overlay"), overlay);
        } catch (const std::exception&) {
            written = false;
        }
    }
    if (!written) {
        return Unexpected(Error{args.get("overlay"), "cannot write the overlay image",
                                "check that the folder exists and the name ends in .png"});
    }
    std::printf("wrote %s\n", args.get("overlay").c_str());
    return {};
}

} // namespace

int runDetect(int argc, char** argv)
{
    Args args("detect", "--calib FILE --left L.png (--right R.png | --mono) [--json OUT] [--overlay OUT.png] [options]",
              {{"calib", "FILE", "calibration file (full or already-rectified form; mount optional)", true},
               {"left", "L.png", "left image", true},
               {"right", "R.png", "right image (required unless --mono)", false},
               {"mono", "",
                "one camera: ColourFreeSpace on the left image read in colour (no --right); the ground is the "
                "calibration's mount (required)",
                false},
               {"json", "OUT", "write the ground estimate and the sectors as JSON", false},
               {"overlay", "OUT.png", "write the rectified left image with obstacles and the sector bar", false},
               {"sectors", "N", "number of sectors, 1..180, default 64", false},
               {"danger", "M", "red below this range, default 1.5 m", false},
               {"caution", "M", "blue below this range, default 5 m (>= --danger)", false},
               {"max-range-px", "PX",
                "look as far as the disparity stays at or above PX (obstacles.max_range_disparity_px), 2..128, "
                "default 13.65",
                false}});
    if (const auto exit = parseOrExit(args, argc, argv, "detect")) {
        return *exit;
    }
    DetectionOptions options;
    if (const auto exit = readDetectOptions(args, options)) {
        return *exit;
    }
    auto calib = adapters::loadCalibration(args.get("calib"));
    if (!calib) {
        return reportError(kDetectCommand, calib.error());
    }
    if (args.has("mono")) {
        return runMono(args, *calib, options);
    }
    auto pair = readStereoPair(args, *calib);
    if (!pair) {
        return reportError(kDetectCommand, pair.error());
    }
    const vision::DetectorConfig config = detectorConfig(options);
    auto run = detectPair(*calib, pair->first, pair->second, config, args.get("calib"));
    if (!run) {
        return reportError(kDetectCommand, run.error());
    }
    printDetection(*run);
    if (args.has("json")) {
        if (!writeJson(args.get("json"), *run->detector, run->fit.has_value())) {
            return reportError(kDetectCommand,
                               Error{args.get("json"), "cannot write the JSON file", "check that the folder exists"});
        }
        std::printf("wrote %s\n", args.get("json").c_str());
    }
    if (args.has("overlay")) {
        if (auto written = writeOverlay(args, *calib, *run, config); !written) {
            return reportError(kDetectCommand, written.error());
        }
    }
    return 0;
}

} // namespace ugv::tool
