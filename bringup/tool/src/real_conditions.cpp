#include "ugv/tool/real_conditions.hpp"

#include <charconv>
#include <cmath>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace ugv::tool {
namespace {

const char* const kPerturbFix = "use none, or parts joined by '+': noise:S (0..50), gain:G (0.2..5), blur:S (0..10), "
                                "exposure:F (0.05..4), jpeg:Q (1..100), half; e.g. exposure:0.35+noise:3, or sweep";

/// The number after "key:" in `part`, within [lo, hi].
Result<double, Error> valueOf(const std::string& part, std::size_t colon, double lo, double hi)
{
    const std::string text = part.substr(colon + 1);
    double value = 0.0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value) || value < lo || value > hi) {
        std::ostringstream range;
        range << lo << ".." << hi;
        return Unexpected(
            Error{"--perturb", "'" + part + "': the value must be a number in " + range.str(), kPerturbFix});
    }
    return value;
}

/// One "key:value" (or "half") into `p`.
Result<void, Error> applyPart(const std::string& part, Perturbation& p)
{
    if (part == "half") {
        p.half = true;
        return {};
    }
    const std::size_t colon = part.find(':');
    const std::string key = part.substr(0, colon);
    struct Field {
        const char* key;
        double lo;
        double hi;
    };
    static constexpr Field kFields[] = {
        {"noise", 0, 50}, {"gain", 0.2, 5}, {"blur", 0, 10}, {"exposure", 0.05, 4}, {"jpeg", 1, 100}};
    for (const Field& f : kFields) {
        if (colon == std::string::npos || key != f.key) {
            continue;
        }
        auto value = valueOf(part, colon, f.lo, f.hi);
        if (!value) {
            return Unexpected(value.error());
        }
        if (key == "noise") {
            p.noiseGrey = *value;
        } else if (key == "gain") {
            p.rightGain = *value;
        } else if (key == "blur") {
            p.blurSigmaPx = *value;
        } else if (key == "exposure") {
            p.exposure = *value;
        } else {
            p.jpegQuality = static_cast<int>(std::lround(*value));
        }
        return {};
    }
    return Unexpected(Error{"--perturb", "unknown condition '" + part + "'", kPerturbFix});
}

/// Exposure, gain, blur and noise on one image, saturated to 8 bits, then compression.
void perturbOne(const Perturbation& p, double gain, cv::RNG& rng, cv::Mat& image)
{
    cv::Mat f;
    image.convertTo(f, CV_32F, p.exposure * gain);
    if (p.blurSigmaPx > 0.0) {
        cv::GaussianBlur(f, f, cv::Size(), p.blurSigmaPx);
    }
    if (p.noiseGrey > 0.0) {
        cv::Mat noise(f.size(), CV_32F);
        rng.fill(noise, cv::RNG::NORMAL, 0.0, p.noiseGrey);
        f += noise;
    }
    f.convertTo(image, CV_8U); // rounds and saturates
    if (p.jpegQuality > 0) {
        std::vector<uchar> bytes;
        cv::imencode(".jpg", image, bytes, {cv::IMWRITE_JPEG_QUALITY, p.jpegQuality});
        image = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
    }
}

} // namespace

Result<Perturbation, Error> parsePerturbation(const std::string& text)
{
    Perturbation p;
    p.name = text;
    if (text == "none") {
        return p;
    }
    std::size_t start = 0;
    while (start <= text.size()) {
        const std::size_t plus = text.find('+', start);
        const std::string part = text.substr(start, plus == std::string::npos ? std::string::npos : plus - start);
        if (auto ok = applyPart(part, p); !ok) {
            return Unexpected(ok.error());
        }
        if (plus == std::string::npos) {
            break;
        }
        start = plus + 1;
    }
    return p;
}

const std::vector<std::string>& sweepConditions()
{
    static const std::vector<std::string> kSweep = {"none",         "noise:3",      "noise:6",
                                                    "gain:0.8",     "gain:1.25",    "blur:1",
                                                    "blur:2",       "exposure:0.5", "exposure:0.25+noise:2",
                                                    "exposure:1.6", "jpeg:70",      "jpeg:50",
                                                    "jpeg:20",      "half"};
    return kSweep;
}

Result<std::vector<Perturbation>, Error> parsePerturbations(const std::string& list)
{
    std::vector<std::string> names;
    std::stringstream in(list);
    for (std::string name; std::getline(in, name, ',');) {
        if (name == "sweep") {
            names.insert(names.end(), sweepConditions().begin(), sweepConditions().end());
        } else {
            names.push_back(name);
        }
    }
    if (names.empty()) {
        return Unexpected(Error{"--perturb", "no condition given", kPerturbFix});
    }
    std::vector<Perturbation> out;
    for (const std::string& name : names) {
        auto p = parsePerturbation(name);
        if (!p) {
            return Unexpected(p.error());
        }
        out.push_back(*p);
    }
    return out;
}

void perturbImages(const Perturbation& p, std::uint64_t seed, cv::Mat& left, cv::Mat& right)
{
    if (p.half) {
        cv::resize(left, left, cv::Size(left.cols / 2, left.rows / 2), 0, 0, cv::INTER_AREA);
        cv::resize(right, right, cv::Size(right.cols / 2, right.rows / 2), 0, 0, cv::INTER_AREA);
    }
    cv::RNG rng(seed);
    perturbOne(p, 1.0, rng, left);
    perturbOne(p, p.rightGain, rng, right);
}

cv::Mat halveDisparityTruth(const cv::Mat& disparity)
{
    cv::Mat half(disparity.rows / 2, disparity.cols / 2, CV_32F);
    for (int y = 0; y < half.rows; ++y) {
        for (int x = 0; x < half.cols; ++x) {
            half.at<float>(y, x) = 0.5F * disparity.at<float>(2 * y, 2 * x);
        }
    }
    return half;
}

} // namespace ugv::tool
