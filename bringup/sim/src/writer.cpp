#include "ugv/sim/writer.hpp"

#include <cmath>
#include <exception>
#include <fstream>
#include <sstream>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

#include "ugv/platform/sectors_json.hpp"

namespace ugv::sim {
namespace {

Error fileError(const std::filesystem::path& path, const std::string& what)
{
    return Error{path.string(), what, "check that the directory exists and is writable"};
}

/// Scales a float image to 16 bit: round(value * scale), non-finite values (sky) -> 0, clamped to 65535.
cv::Mat toU16(const cv::Mat& values, double scale)
{
    constexpr double kMaxU16 = 65535.0;
    cv::Mat out(values.size(), CV_16U);
    for (int y = 0; y < values.rows; ++y) {
        const auto* in = values.ptr<float>(y);
        auto* o = out.ptr<std::uint16_t>(y);
        for (int x = 0; x < values.cols; ++x) {
            const double v = static_cast<double>(in[x]) * scale;
            o[x] = std::isfinite(v) ? static_cast<std::uint16_t>(std::clamp(std::round(v), 0.0, kMaxU16)) : 0;
        }
    }
    return out;
}

Result<void, Error> writePng(const std::filesystem::path& path, const cv::Mat& image)
{
    try {
        if (image.empty() || !cv::imwrite(path.string(), image)) {
            return Unexpected(fileError(path, "cannot write PNG"));
        }
    } catch (const std::exception& e) { // cv::Exception from the encoder
        return Unexpected(fileError(path, std::string("cannot write PNG: ") + e.what()));
    }
    return {};
}

} // namespace

std::string calibrationText(const Rig& rig)
{
    cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
    fs << "schema_version" << 1;
    fs << "rectified" << 1;
    fs << "image_width" << rig.width;
    fs << "image_height" << rig.height;
    fs << "fx" << rig.focalPx;
    fs << "fy" << rig.focalPx;
    fs << "cx" << rig.cx();
    fs << "cy" << rig.cy();
    fs << "baseline_m" << rig.baselineM;
    fs << "mount"
       << "{";
    fs << "height_m" << rig.heightM;
    fs << "pitch_deg" << rig.pitchDeg;
    fs << "roll_deg" << rig.rollDeg;
    fs << "}";
    return fs.releaseAndGetString();
}

Result<void, Error> writeCalibration(const Rig& rig, const std::filesystem::path& dir)
{
    const std::filesystem::path path = dir / "calibration.yaml";
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec)) {
        return Unexpected(fileError(dir, "not a directory"));
    }
    std::ofstream out(path, std::ios::binary);
    out << calibrationText(rig);
    out.flush();
    if (!out) {
        return Unexpected(fileError(path, "cannot write"));
    }
    return {};
}

std::string sectorsJson(const ObstacleSectors& sectors)
{
    return "{\n  \"count\": " + std::to_string(sectors.count) + ",\n  \"sectors\": " + sectorsJsonArray(sectors, 4) +
           "\n}\n";
}

Result<void, Error> writeSample(const RenderResult& sample, const Rig& rig, const std::filesystem::path& dir,
                                const std::string& stem)
{
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec)) {
        return Unexpected(fileError(dir, "not a directory"));
    }
    struct Item {
        const char* suffix;
        cv::Mat image;
    };
    const std::vector<Item> items = {
        {"_left.png", sample.left},
        {"_left_colour.png", sample.leftColour},
        {"_right.png", sample.right},
        {"_disparity.png", toU16(sample.disparity, kDisparityScale)},
        {"_depth.png", toU16(sample.depth, kDepthScale)},
        {"_labels.png", sample.labels},
        {"_ids.png", sample.ids},
    };
    for (const Item& item : items) {
        if (auto written = writePng(dir / (stem + item.suffix), item.image); !written) {
            return written;
        }
    }
    const std::filesystem::path jsonPath = dir / (stem + "_sectors.json");
    std::ofstream json(jsonPath);
    json << sectorsJson(sample.sectors);
    json.close();
    if (!json) {
        return Unexpected(fileError(jsonPath, "cannot write JSON"));
    }
    return writeCalibration(rig, dir);
}

} // namespace ugv::sim
