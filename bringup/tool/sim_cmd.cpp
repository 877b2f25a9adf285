// ugvsense sim: synthetic stereo data. Scene "chessboard": calibration pairs rendered by a known rig, with
// truth.yaml holding that rig, so that `ugvsense calibrate` can be checked against it.

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "args.hpp"
#include "chessboard_render.hpp"
#include "commands.hpp"

namespace ugv::tool {
namespace {

constexpr int kDefaultPairs = 12;
constexpr int kMaxPairs = 99;
constexpr double kDefaultNoise = 1.0; // [grey levels]
constexpr double kMaxNoise = 50.0;

bool writeTruth(const std::string& path, const SimRig& rig, const SimBoard& board, int pairs)
{
    try {
        cv::FileStorage fs(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
        if (!fs.isOpened()) {
            return false;
        }
        fs << "image_width" << rig.imageSize.width << "image_height" << rig.imageSize.height;
        fs << "board_width" << board.innerCorners.width << "board_height" << board.innerCorners.height;
        fs << "square_m" << board.squareM << "pairs" << pairs;
        fs << "K1" << rig.cameraMatrix() << "D1" << rig.distortion() << "K2" << rig.cameraMatrix() << "D2"
           << rig.distortion();
        fs << "R" << rig.rotation() << "T" << rig.translation() << "baseline_m" << rig.baselineM;
        fs.release();
        return true;
    } catch (const cv::Exception&) {
        return false;
    }
}

} // namespace

int runSim(int argc, char** argv)
{
    Args args("sim", "--scene chessboard --out DIR [--pairs N] [--seed S] [--noise SIGMA]",
              {{"scene", "NAME", "scene to render: chessboard (calibration pairs)", true},
               {"out", "DIR", "output folder (created if missing)", true},
               {"pairs", "N", "number of pairs, default 12", false},
               {"seed", "S", "random seed for poses and noise, default 1", false},
               {"noise", "SIGMA", "Gaussian noise in grey levels, default 1", false}});
    if (auto parsed = args.parse(argc, argv, 2); !parsed) {
        return reportUsageError("sim", parsed.error());
    }
    if (args.helpRequested()) {
        std::cout << args.usage();
        return 0;
    }
    if (args.get("scene") != "chessboard") {
        return reportUsageError("sim", Error{"ugvsense sim --scene", "unknown scene '" + args.get("scene") + "'",
                                             "the available scene is: chessboard"});
    }
    const auto pairs = args.number("pairs", kDefaultPairs, 1, kMaxPairs);
    const auto seed = args.number("seed", 1, 0, 1e9);
    const auto noise = args.number("noise", kDefaultNoise, 0, kMaxNoise);
    for (const auto* number : {&pairs, &seed, &noise}) {
        if (!*number) {
            return reportUsageError("sim", number->error());
        }
    }
    const std::filesystem::path out = args.get("out");
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (!std::filesystem::is_directory(out, ec)) {
        std::cerr << "ugvsense sim: error: " << out.string() << ": cannot create the output folder\n";
        return 1;
    }

    const SimRig rig;
    const SimBoard board;
    const ChessboardRenderer renderer(rig, board);
    const auto poses = renderer.poses(static_cast<int>(*pairs), static_cast<std::uint64_t>(*seed));
    cv::RNG rng(static_cast<std::uint64_t>(*seed) + 1);
    for (std::size_t i = 0; i < poses.size(); ++i) {
        cv::Mat left;
        cv::Mat right;
        renderer.render(poses[i], *noise, rng, left, right);
        char suffix[32];
        std::snprintf(suffix, sizeof(suffix), "_%02zu.png", i + 1);
        const std::string leftPath = (out / ("left" + std::string(suffix))).string();
        const std::string rightPath = (out / ("right" + std::string(suffix))).string();
        bool written = false;
        try {
            written = cv::imwrite(leftPath, left) && cv::imwrite(rightPath, right);
        } catch (const cv::Exception&) {
            written = false;
        }
        if (!written) {
            std::cerr << "ugvsense sim: error: " << leftPath << ": cannot write the image (fix: check the folder)\n";
            return 1;
        }
    }
    const std::string truthPath = (out / "truth.yaml").string();
    if (!writeTruth(truthPath, rig, board, static_cast<int>(poses.size()))) {
        std::cerr << "ugvsense sim: error: " << truthPath << ": cannot write the file (fix: check the folder)\n";
        return 1;
    }
    std::cout << "wrote " << poses.size() << " chessboard pairs and truth.yaml to " << out.string()
              << " (fx " << rig.fx << " px, baseline " << rig.baselineM << " m)\n";
    return 0;
}

} // namespace ugv::tool
