// ugvsense calibrate: stereo calibration from chessboard pairs in a folder; writes the calibration file and,
// on request, a JSON report.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ugv/adapters/calibration_file.hpp"
#include "ugv/adapters/camera_factory.hpp"
#include "ugv/adapters/config.hpp"
#include "ugv/platform/sectors_json.hpp" // jsonNumber, jsonString
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"
#include "ugv/tool/detection.hpp"
#include "ugv/tool/pair_files.hpp"
#include "ugv/vision/stereo_calibrator.hpp"

namespace ugv::tool {
namespace {

constexpr double kMinSquareM = 1e-4; // [m]
constexpr double kMaxSquareM = 10.0; // [m]

bool writeJson(const std::string& path, const vision::CalibrationReport& report)
{
    const vision::StereoCalibration& c = report.calibration;
    std::ofstream out(path);
    if (!out) {
        return false;
    }
    out << "{\n  \"rms_px\": " << jsonNumber(c.rmsPx) << ",\n  \"epipolar_px\": " << jsonNumber(c.epipolarPx)
        << ",\n  \"rectified_dy_px\": " << jsonNumber(c.rectifiedDyPx) << ",\n  \"pairs_used\": " << c.pairsUsed
        << ",\n  \"pairs_rejected\": " << report.rejected.size()
        << ",\n  \"rms_before_outliers_px\": " << jsonNumber(report.rmsBeforeOutliersPx)
        << ",\n  \"baseline_m\": " << jsonNumber(c.baselineM()) << ",\n  \"rejected\": [";
    for (std::size_t i = 0; i < report.rejected.size(); ++i) {
        out << (i == 0 ? "\n" : ",\n") << "    {\"pair\": " << jsonString(report.rejected[i].name)
            << ", \"reason\": " << jsonString(report.rejected[i].reason) << "}";
    }
    out << (report.rejected.empty() ? "],\n" : "\n  ],\n") << "  \"per_pair\": [";
    for (std::size_t i = 0; i < report.perPair.size(); ++i) {
        out << (i == 0 ? "\n" : ",\n") << "    {\"pair\": " << jsonString(report.perPair[i].name)
            << ", \"error_px\": " << jsonNumber(report.perPair[i].errorPx) << "}";
    }
    out << (report.perPair.empty() ? "]\n}\n" : "\n  ]\n}\n");
    out.flush();
    return static_cast<bool>(out);
}

bool parentIsFolder(const std::string& path)
{
    std::filesystem::path parent = std::filesystem::path(path).parent_path();
    if (parent.empty()) {
        parent = ".";
    }
    std::error_code ec;
    return std::filesystem::is_directory(parent, ec);
}

constexpr const char* kCalibrateCommand = "calibrate";

/// Where and how large the board appears in a kept pair.
struct BoardView {
    cv::Point2f centre;
    float span; ///< [px] the larger side of the corners' bounding box
};

/// The board's place in the left image, when the whole board is found in both images.
std::optional<BoardView> findBoard(const cv::Mat& left, const cv::Mat& right, cv::Size board)
{
    std::vector<cv::Point2f> cornersL;
    std::vector<cv::Point2f> cornersR;
    const int flags = cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK;
    if (!cv::findChessboardCorners(left, board, cornersL, flags) ||
        !cv::findChessboardCorners(right, board, cornersR, flags)) {
        return std::nullopt;
    }
    const cv::Rect box = cv::boundingRect(cornersL);
    return BoardView{cv::Point2f(static_cast<float>(box.x) + static_cast<float>(box.width) / 2.0F,
                                 static_cast<float>(box.y) + static_cast<float>(box.height) / 2.0F),
                     static_cast<float>(std::max(box.width, box.height))};
}

/// The camera of --config (the default configuration without it), or the recording --replay REC, read as fast as
/// possible.
Result<std::unique_ptr<hal::StereoCamera>, Error> openCaptureCamera(const Args& args)
{
    adapters::ServiceConfig config;
    if (args.has("config")) {
        auto loaded = adapters::loadConfig(args.get("config"));
        if (!loaded) {
            return Unexpected(loaded.error().front());
        }
        config = std::move(*loaded);
    }
    hal::ReplayOptions replay;
    replay.pace = hal::ReplayPace::AsFastAsPossible;
    return adapters::openCamera(config, args.get("replay"), replay);
}

} // namespace

/// Grabs pairs from the configured camera (or --replay REC) and keeps those where the board is found in both
/// images at a new place or size (centroid moved by 5 % of the width, or the corner span changed by 10 %), as
/// left_NN.png / right_NN.png in --images DIR. Returns the number kept.
Result<int, Error> capturePairs(const Args& args, cv::Size board)
{
    const auto pairs = args.number("pairs", 15, 4, 60);
    const auto seconds = args.number("seconds", 300, 1, 86400);
    for (const auto* value : {&pairs, &seconds}) {
        if (!*value) {
            return Unexpected(value->error());
        }
    }
    auto camera = openCaptureCamera(args);
    if (!camera) {
        return Unexpected(camera.error());
    }
    const std::filesystem::path dir = args.get("images");
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) {
        return Unexpected(Error{dir.string(), "cannot create the folder: " + ec.message(), "choose a writable place"});
    }
    std::printf("capturing from %s: hold the %dx%d board at different places, distances and tilts\n",
                (*camera)->description(), board.width, board.height);
    std::vector<BoardView> kept;
    const auto start = std::chrono::steady_clock::now();
    hal::CameraFrame frame;
    int grabbed = 0;
    while (static_cast<double>(kept.size()) < *pairs &&
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < *seconds) {
        const hal::GrabStatus status = (*camera)->grab(frame, std::chrono::milliseconds(500));
        if (status == hal::GrabStatus::End) {
            break;
        }
        if (status == hal::GrabStatus::Disconnected) {
            return Unexpected(Error{(*camera)->description(), "the camera went away during the capture",
                                    "plug it back in and capture again"});
        }
        if (status != hal::GrabStatus::Frame || frame.images.leftOnly()) {
            continue; // a left-only frame (the right camera lost, or a one-camera rig) calibrates no pair
        }
        ++grabbed;
        const cv::Mat left = matOver(frame.images, false);
        const cv::Mat right = matOver(frame.images, true);
        const std::optional<BoardView> seen = findBoard(left, right, board);
        const auto similar = [&](const BoardView& s) {
            return cv::norm(s.centre - seen->centre) < 0.05 * left.cols &&
                   std::abs(s.span - seen->span) < 0.1F * s.span;
        };
        if (!seen || std::any_of(kept.begin(), kept.end(), similar)) {
            continue;
        }
        char name[32];
        (void)std::snprintf(name, sizeof(name), "_%02zu.png", kept.size() + 1);
        if (!cv::imwrite((dir / (std::string("left") + name)).string(), left) ||
            !cv::imwrite((dir / (std::string("right") + name)).string(), right)) {
            return Unexpected(Error{dir.string(), "cannot write the captured images", "check the free space"});
        }
        kept.push_back(*seen);
        std::printf("  pair %zu kept (frame %llu, board at %.0f,%.0f px, %.0f px across)\n", kept.size(),
                    static_cast<unsigned long long>(frame.sequence), static_cast<double>(seen->centre.x),
                    static_cast<double>(seen->centre.y), static_cast<double>(seen->span));
    }
    if (kept.size() < 4) {
        return Unexpected(Error{(*camera)->description(),
                                "only " + std::to_string(kept.size()) + " distinct board view(s) in " +
                                    std::to_string(grabbed) + " frames",
                                "show the whole board to both cameras at more places and distances"});
    }
    return static_cast<int>(kept.size());
}

namespace {

/// --mount-height/pitch/roll: the mount to write, none without them; a usage error (exit code) when wrong.
std::optional<int> readMount(const Args& args, std::optional<vision::Mount>& mount)
{
    if (!args.has("mount-height") && !args.has("mount-pitch") && !args.has("mount-roll")) {
        return std::nullopt;
    }
    if (!args.has("mount-height")) {
        return reportUsageError("calibrate", Error{"ugvsense calibrate",
                                                   "--mount-pitch/--mount-roll without "
                                                   "--mount-height",
                                                   "give --mount-height M too"});
    }
    const auto height = args.number("mount-height", 0.0, 1e-3, adapters::kMaxMountHeightM);
    const auto pitch = args.number("mount-pitch", 0.0, -adapters::kMaxMountPitchDeg, adapters::kMaxMountPitchDeg);
    const auto roll = args.number("mount-roll", 0.0, -adapters::kMaxMountRollDeg, adapters::kMaxMountRollDeg);
    for (const auto* value : {&height, &pitch, &roll}) {
        if (!*value) {
            return reportUsageError("calibrate", value->error());
        }
    }
    mount = vision::Mount{*height, *pitch, *roll};
    return std::nullopt;
}

/// The listed pairs read in grey; a pair with a file that cannot be read goes to `unreadable` (printed).
std::vector<vision::CalibrationPair> readPairs(const PairListing& listing,
                                               std::vector<vision::RejectedPair>& unreadable)
{
    std::vector<vision::CalibrationPair> pairs;
    for (const auto& files : listing.pairs) {
        vision::CalibrationPair pair{files.name, readGrey(files.left), readGrey(files.right)};
        if (pair.left.empty() || pair.right.empty()) {
            unreadable.push_back({files.name, "unreadable image file " +
                                                  (pair.left.empty() ? files.left : files.right).filename().string()});
            continue;
        }
        pairs.push_back(std::move(pair));
    }
    for (const auto& rejected : unreadable) {
        std::cout << "rejected " << rejected.name << ": " << rejected.reason << '\n';
    }
    return pairs;
}

/// The per-pair errors, the pairs the calibrator rejected (the first `alreadyPrinted` were) and the quality figures.
void printReport(const vision::CalibrationReport& report, std::size_t alreadyPrinted)
{
    const vision::StereoCalibration& c = report.calibration;
    std::printf("per-pair reprojection error:\n");
    for (const auto& pair : report.perPair) {
        std::printf("  %-40s %.3f px\n", pair.name.c_str(), pair.errorPx);
    }
    for (std::size_t i = alreadyPrinted; i < report.rejected.size(); ++i) {
        std::printf("rejected %s: %s\n", report.rejected[i].name.c_str(), report.rejected[i].reason.c_str());
    }
    if (report.outlierRounds > 0) {
        std::printf("dropped outliers and recalibrated (%d round(s)): RMS %.3f -> %.3f px (%.1f %% better)\n",
                    report.outlierRounds, report.rmsBeforeOutliersPx, c.rmsPx,
                    100.0 * (report.rmsBeforeOutliersPx - c.rmsPx) / report.rmsBeforeOutliersPx);
    }
    std::printf("pairs used %d, rejected %d\n", c.pairsUsed, c.pairsRejected);
    std::printf("RMS reprojection error %.4f px\nmean epipolar error    %.4f px\nrectified mean |dy|    %.4f px\n",
                c.rmsPx, c.epipolarPx, c.rectifiedDyPx);
    std::printf("fx %.2f px, baseline %.4f m, rectified f %.2f px\n", c.K1.at<double>(0, 0), c.baselineM(),
                c.rectifiedFocalPx());
}

/// calibrate's options.
Args calibrateArgs()
{
    return Args(
        "calibrate", "--images DIR --board WxH --square M --out CALIB.yaml [--json REPORT.json] [--mount-*]",
        {{"images", "DIR", "folder with left*/right* chessboard images (left01.jpg pairs with right01.jpg)", true},
         {"board", "WxH", "inner corners per row x per column, e.g. 9x6", true},
         {"square", "M", "square side in metres, e.g. 0.025", true},
         {"out", "CALIB.yaml", "calibration file to write", true},
         {"json", "REPORT.json", "also write a JSON report", false},
         {"mount-height", "M", "camera height above ground, (0, 10] m (writes the mount section)", false},
         {"mount-pitch", "DEG", "camera pitch, [-45, 45] deg, default 0", false},
         {"mount-roll", "DEG", "camera roll, [-30, 30] deg, default 0", false},
         {"capture", "", "first grab chessboard pairs from the camera into --images DIR (when the board is seen)",
          false},
         {"config", "FILE", "capture: the service config naming the camera (default: built-in defaults)", false},
         {"replay", "REC", "capture: take the pairs from a recording instead of the camera", false},
         {"pairs", "N", "capture: pairs to keep, 4..60, default 15", false},
         {"seconds", "S", "capture: give up after S seconds, default 300", false}});
}

} // namespace

int runCalibrate(int argc, char** argv)
{
    Args args = calibrateArgs();
    if (const auto exit = parseOrExit(args, argc, argv, "calibrate")) {
        return *exit;
    }
    vision::CalibratorConfig config;
    const auto board = parseBoard("calibrate", args.get("board"));
    if (!board) {
        return reportUsageError("calibrate", board.error());
    }
    config.innerCorners = *board;
    const auto square = args.number("square", 0.0, kMinSquareM, kMaxSquareM);
    if (!square) {
        return reportUsageError("calibrate", square.error());
    }
    config.squareM = *square;
    std::optional<vision::Mount> mount;
    if (const auto exit = readMount(args, mount)) {
        return *exit;
    }
    const std::string outPath = args.get("out");
    const std::string jsonPath = args.get("json");
    for (const std::string& path : {outPath, jsonPath}) {
        if (!path.empty() && !parentIsFolder(path)) {
            return reportError(kCalibrateCommand, Error{path, "the folder of the output file does not exist",
                                                        "create it or choose another path"});
        }
    }
    if (args.has("capture")) {
        auto captured = capturePairs(args, config.innerCorners);
        if (!captured) {
            return reportError(kCalibrateCommand, captured.error());
        }
        std::printf("captured %d pair(s) into %s\n", *captured, args.get("images").c_str());
    }
    const auto listing = listPairs(args.get("images"));
    if (!listing) {
        return reportError(kCalibrateCommand, listing.error());
    }
    if (listing->pairs.empty()) {
        return reportError(kCalibrateCommand,
                           Error{args.get("images"), "no left*/right* image pairs found",
                                 "name the images leftNN.ext and rightNN.ext (e.g. left01.jpg, right01.jpg)"});
    }
    for (const auto& unpaired : listing->unpaired) {
        std::cout << "unpaired image: " << unpaired << '\n';
    }
    std::vector<vision::RejectedPair> unreadable;
    auto result = vision::calibrateStereo(readPairs(*listing, unreadable), config);
    if (!result) {
        Error error = result.error();
        error.where = args.get("images");
        if (!unreadable.empty()) {
            error.what += " (" + std::to_string(unreadable.size()) + " pair(s) unreadable)";
        }
        return reportError(kCalibrateCommand, error);
    }
    vision::CalibrationReport& report = *result;
    report.rejected.insert(report.rejected.begin(), unreadable.begin(), unreadable.end());
    report.calibration.pairsRejected = static_cast<int>(report.rejected.size());
    report.calibration.mount = mount;
    printReport(report, unreadable.size());
    if (auto saved = adapters::saveCalibration(outPath, report.calibration); !saved) {
        return reportError(kCalibrateCommand, saved.error());
    }
    std::printf("wrote %s\n", outPath.c_str());
    if (!jsonPath.empty()) {
        if (!writeJson(jsonPath, report)) {
            return reportError(kCalibrateCommand,
                               Error{jsonPath, "cannot write the JSON report", "check that the folder is writable"});
        }
        std::printf("wrote %s\n", jsonPath.c_str());
    }
    return 0;
}

} // namespace ugv::tool
