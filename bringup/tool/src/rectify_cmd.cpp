// ugvsense rectify: rectifies image pairs with a calibration file through vision::Rectifier (the same ROI
// tables as the service) and measures the row alignment of a visible chessboard in the rectified images.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ugv/adapters/calibration_file.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"
#include "ugv/tool/pair_files.hpp"
#include "ugv/vision/mat_view.hpp"
#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/stereo_calibrator.hpp"

namespace ugv::tool {
namespace {

constexpr int kLineSpacingPx = 16; // horizontal guide lines in the written side-by-side images

constexpr const char* kRectifyCommand = "rectify";

/// The chessboard's mean |dy| between the rectified images, when the whole board is in both.
std::optional<double> boardDy(const cv::Mat& left, const cv::Mat& right, cv::Size board)
{
    std::vector<cv::Point2f> cornersLeft;
    std::vector<cv::Point2f> cornersRight;
    if (!vision::findBoardCorners(left, board, cornersLeft) || !vision::findBoardCorners(right, board, cornersRight)) {
        return std::nullopt;
    }
    double sum = 0.0;
    for (std::size_t i = 0; i < cornersLeft.size(); ++i) {
        sum += std::abs(cornersLeft[i].y - cornersRight[i].y);
    }
    return sum / static_cast<double>(cornersLeft.size());
}

/// --out: the rectified pair side by side with green row guide lines, as rectified_<left's name>.png.
Result<void, Error> writeSideBySide(const std::filesystem::path& outDir, const std::filesystem::path& leftFile,
                                    const cv::Mat& left, const cv::Mat& right)
{
    cv::Mat sideBySide;
    cv::hconcat(left, right, sideBySide);
    cv::cvtColor(sideBySide, sideBySide, cv::COLOR_GRAY2BGR);
    for (int y = kLineSpacingPx; y < sideBySide.rows; y += kLineSpacingPx) {
        cv::line(sideBySide, {0, y}, {sideBySide.cols - 1, y}, cv::Scalar(0, 255, 0), 1);
    }
    const std::filesystem::path path = outDir / ("rectified_" + leftFile.stem().string() + ".png");
    bool written = false;
    try {
        written = cv::imwrite(path.string(), sideBySide);
    } catch (const cv::Exception&) {
        written = false;
    }
    if (!written) {
        return Unexpected(Error{path.string(), "cannot write the image", "check the folder"});
    }
    return {};
}

/// What the pairs gave: rectify time and the board's row alignment.
struct RectifyTally {
    double totalMicros = 0.0;
    int rectified = 0;
    double dySum = 0.0;
    int dyPairs = 0;
};

/// One pair: read, rectified (timed), its board's |dy| and the side-by-side image. A pair that cannot be read or
/// is of another size is skipped with a line saying why; an image that cannot be written is an error.
Result<void, Error> rectifyPair(const PairFiles& files, vision::Rectifier& rectifier,
                                const vision::StereoCalibration& calib, cv::Size board, bool fullFrame,
                                const std::filesystem::path& outDir, RectifyTally& tally)
{
    std::string why;
    const cv::Mat left = readGrey(files.left, &why);
    const cv::Mat right = left.empty() ? cv::Mat() : readGrey(files.right, &why);
    if (left.empty() || right.empty()) {
        std::printf("%s: skipped, %s: %s\n", files.name.c_str(),
                    (left.empty() ? files.left : files.right).filename().c_str(), why.c_str());
        return {};
    }
    const ConstImageViewU8 leftView(left.data, left.cols, left.rows, static_cast<std::ptrdiff_t>(left.step));
    const ConstImageViewU8 rightView(right.data, right.cols, right.rows, static_cast<std::ptrdiff_t>(right.step));
    const auto start = std::chrono::steady_clock::now();
    const vision::RectifyStatus status = rectifier.rectify(leftView, rightView);
    const auto stop = std::chrono::steady_clock::now();
    if (status != vision::RectifyStatus::Ok) {
        // The left and right images may differ from each other: name the one that differs from the calibration.
        const bool leftFits = left.size() == calib.imageSize;
        const cv::Mat& wrong = leftFits ? right : left;
        std::printf("%s: skipped, %s is %dx%d but the calibration is for %dx%d\n", files.name.c_str(),
                    (leftFits ? files.right : files.left).filename().c_str(), wrong.cols, wrong.rows,
                    calib.imageSize.width, calib.imageSize.height);
        return {};
    }
    tally.totalMicros += std::chrono::duration<double, std::micro>(stop - start).count();
    ++tally.rectified;
    const cv::Mat outLeft = vision::matOver(rectifier.rectifiedLeft()).clone();
    const cv::Mat outRight = vision::matOver(rectifier.rectifiedRight()).clone();
    if (const auto dy = boardDy(outLeft, outRight, board)) {
        std::printf("%s: board mean |dy| %.3f px\n", files.name.c_str(), *dy);
        tally.dySum += *dy;
        ++tally.dyPairs;
    } else {
        std::printf("%s: board not (fully) visible in the rectified %s\n", files.name.c_str(),
                    fullFrame ? "frame" : "ROI");
    }
    return outDir.empty() ? Result<void, Error>{} : writeSideBySide(outDir, files.left, outLeft, outRight);
}

} // namespace

int runRectify(int argc, char** argv)
{
    Args args("rectify", "--calib CALIB.yaml --images DIR [--out OUTDIR] [--board WxH] [--full]",
              {{"calib", "CALIB.yaml", "calibration file (ugvsense calibrate)", true},
               {"images", "DIR", "folder with left*/right* image pairs", true},
               {"out", "OUTDIR", "write rectified side-by-side PNGs with row guide lines here", false},
               {"board", "WxH", "chessboard inner corners for the |dy| check, default 9x6", false},
               {"full", "", "rectify the whole frame instead of the obstacle ROI", false}});
    if (const auto exit = parseOrExit(args, argc, argv, "rectify")) {
        return *exit;
    }
    const auto board = parseBoard("rectify", args.get("board", "9x6"));
    if (!board) {
        return reportUsageError("rectify", board.error());
    }
    const auto calib = adapters::loadCalibration(args.get("calib"));
    if (!calib) {
        return reportError(kRectifyCommand, calib.error());
    }
    vision::RectifierConfig config;
    config.fullFrame = args.has("full");
    auto rectifier = vision::Rectifier::create(*calib, config);
    if (!rectifier) {
        return reportError(kRectifyCommand, rectifier.error());
    }
    const auto listing = listPairs(args.get("images"));
    if (!listing) {
        return reportError(kRectifyCommand, listing.error());
    }
    if (listing->pairs.empty()) {
        return reportError(kRectifyCommand, Error{args.get("images"), "no left*/right* image pairs found",
                                                  "name the images leftNN.ext and rightNN.ext"});
    }
    const std::filesystem::path outDir = args.get("out");
    if (!outDir.empty()) {
        std::error_code ec;
        std::filesystem::create_directories(outDir, ec);
        if (!std::filesystem::is_directory(outDir, ec)) {
            return reportError(kRectifyCommand,
                               Error{outDir.string(), "cannot create the output folder", "choose a writable path"});
        }
    }
    const Rect roi = rectifier->roi();
    std::printf("ROI rows [%d, %d) of %dx%d%s\n", roi.y, roi.y + roi.height, calib->imageSize.width,
                calib->imageSize.height, rectifier->identity() ? " (already rectified: row copy)" : "");
    RectifyTally tally;
    for (const auto& files : listing->pairs) {
        if (auto done = rectifyPair(files, *rectifier, *calib, *board, config.fullFrame, outDir, tally); !done) {
            return reportError(kRectifyCommand, done.error());
        }
    }
    if (tally.rectified == 0) {
        return reportError(kRectifyCommand, Error{args.get("images"), "no pair could be rectified",
                                                  "use images of the calibrated size"});
    }
    std::printf("rectified %d pair(s), mean rectify time %.1f us per pair\n", tally.rectified,
                tally.totalMicros / tally.rectified);
    if (tally.dyPairs > 0) {
        std::printf("chessboard mean |dy| in rectified images: %.3f px over %d pair(s)\n", tally.dySum / tally.dyPairs,
                    tally.dyPairs);
    } else {
        std::printf("no chessboard fully visible in the rectified images: |dy| not measured\n");
    }
    return 0;
}

} // namespace ugv::tool
