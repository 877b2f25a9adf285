#include "ugv/adapters/calibration_file.hpp"

#include <cmath>
#include <exception>
#include <filesystem>
#include <set>
#include <sstream>
#include <utility>

#include <opencv2/core.hpp>

#include "ugv/adapters/yaml_guard.hpp"

namespace ugv::adapters {
namespace {

using vision::StereoCalibration;

constexpr const char* kRecalibrate = "re-run 'ugvsense calibrate' to write a new calibration file";
/// A calibration is about 3 KB and 3 levels deep (a key, an opencv-matrix, its data list). OpenCV 4.6's reader has no
/// nesting limit (a deep file overflows the stack) and wraps integers modulo 2^32: the text is checked first.
constexpr YamlLimits kCalibrationLimits{kMaxCalibrationBytes, 8, true, true};

std::string numberText(double value)
{
    std::ostringstream out;
    out << value;
    return out.str();
}

/// Reads the keys of one file; every error carries "path: key".
class Reader {
public:
    Reader(const cv::FileNode& root, std::string path) : root_(root), path_(std::move(path)) {}

    [[nodiscard]] Error error(const std::string& key, const std::string& what, const std::string& fix) const
    {
        return Error{path_ + ": " + key, what, fix};
    }

    Result<double, Error> number(const std::string& key, const cv::FileNode& parent) const
    {
        const cv::FileNode node = parent[key];
        if (node.empty() || node.isNone()) {
            return Unexpected(error(key, "missing key", "add '" + key + "' or " + kRecalibrate));
        }
        if (!node.isInt() && !node.isReal()) {
            return Unexpected(error(key, "not a number", "write a plain number for '" + key + "'"));
        }
        const double value = node.real();
        if (!std::isfinite(value)) {
            return Unexpected(error(key, "value " + numberText(value) + " is not finite", kRecalibrate));
        }
        return value;
    }
    Result<double, Error> number(const std::string& key) const { return number(key, root_); }

    /// A number within (min, max] (minOpen) or [min, max].
    Result<double, Error> numberIn(const std::string& key, double min, double max, bool minOpen,
                                   const cv::FileNode& parent, const std::string& fix) const
    {
        auto value = number(key, parent);
        if (!value) {
            return value;
        }
        const double v = *value;
        if ((minOpen ? v <= min : v < min) || v > max) {
            return Unexpected(error(key, "value " + numberText(v) + " out of range", fix));
        }
        return v;
    }

    Result<cv::Mat, Error> matrix(const std::string& key, int rows, int cols) const
    {
        const cv::FileNode node = root_[key];
        if (node.empty() || node.isNone()) {
            return Unexpected(error(key, "missing key", kRecalibrate));
        }
        cv::Mat m;
        if (node.isMap()) {
            try {
                node >> m;
            } catch (const cv::Exception&) {
                m.release();
            }
        }
        if (m.empty()) {
            return Unexpected(error(key, "not an opencv-matrix", kRecalibrate));
        }
        if (m.type() != CV_64F) {
            return Unexpected(error(key, "matrix type is not double (dt: d)", kRecalibrate));
        }
        if (rows > 0 && (m.rows != rows || m.cols != cols)) {
            return Unexpected(error(key,
                                    "matrix is " + std::to_string(m.rows) + "x" + std::to_string(m.cols) +
                                        ", expected " + std::to_string(rows) + "x" + std::to_string(cols),
                                    kRecalibrate));
        }
        if (!cv::checkRange(m)) {
            return Unexpected(error(key, "matrix holds NaN or inf", kRecalibrate));
        }
        return m;
    }

    Result<cv::Mat, Error> distortion(const std::string& key) const
    {
        auto m = matrix(key, 0, 0);
        if (!m) {
            return m;
        }
        const int n = static_cast<int>(m->total());
        const bool vector = m->rows == 1 || m->cols == 1;
        if (!vector || (n != 4 && n != 5 && n != 8 && n != 12 && n != 14)) {
            return Unexpected(error(key, "distortion is " + std::to_string(m->rows) + "x" + std::to_string(m->cols),
                                    "expected 1xN with N in 4, 5, 8, 12, 14; " + std::string(kRecalibrate)));
        }
        return m->reshape(1, 1);
    }

    Result<void, Error> plausibleFocal(const std::string& key, const cv::Mat& m) const
    {
        const double fx = m.at<double>(0, 0);
        const double fy = m.at<double>(1, 1);
        const auto plausible = [](double f) { return f >= kMinFocalPx && f <= kMaxFocalPx; };
        if (!plausible(fx) || !plausible(fy)) {
            return Unexpected(error(key,
                                    "focal length fx " + numberText(fx) + ", fy " + numberText(fy) + " not in [" +
                                        numberText(kMinFocalPx) + ", " + numberText(kMaxFocalPx) + "] px",
                                    kRecalibrate));
        }
        return {};
    }

    /// A rotation: orthonormal with determinant +1 (to 1e-3).
    Result<void, Error> rotation(const std::string& key, const cv::Mat& m) const
    {
        if (cv::norm(m.t() * m, cv::Mat::eye(3, 3, CV_64F), cv::NORM_INF) > 1e-3 ||
            std::abs(cv::determinant(m) - 1.0) > 1e-3) {
            return Unexpected(error(key, "not a rotation matrix (R^T R != I or det != 1)", kRecalibrate));
        }
        return {};
    }

    /// An integer key (OpenCV writes them without a decimal point) within [min, max].
    Result<int, Error> integerIn(const std::string& key, int min, int max, const std::string& fix) const
    {
        auto value = number(key, root_);
        if (!value) {
            return Unexpected(value.error());
        }
        if (!root_[key].isInt() || *value < min || *value > max) {
            return Unexpected(error(key,
                                    "value " + numberText(*value) + " is not an integer in [" + std::to_string(min) +
                                        ", " + std::to_string(max) + "]",
                                    fix));
        }
        return static_cast<int>(*value);
    }

    [[nodiscard]] const cv::FileNode& root() const { return root_; }

private:
    cv::FileNode root_;
    std::string path_;
};

// NOLINTBEGIN(bugprone-macro-parentheses): `var` names a declared variable, which parentheses would not allow
#define UGV_TRY_ASSIGN(var, expr)                                                                                      \
    auto var##Result = (expr);                                                                                         \
    if (!var##Result) {                                                                                                \
        return Unexpected(var##Result.error());                                                                        \
    }                                                                                                                  \
    auto var = std::move(var##Result).value()
// NOLINTEND(bugprone-macro-parentheses)

std::string baselineFix()
{
    return "the baseline must be in [" + numberText(kMinBaselineM) + ", " + numberText(kMaxBaselineM) + "] metres";
}
std::string focalFix()
{
    return "a focal length must be in [" + numberText(kMinFocalPx) + ", " + numberText(kMaxFocalPx) + "] pixels";
}

Result<StereoCalibration, Error> readRectified(const Reader& in, cv::Size size)
{
    UGV_TRY_ASSIGN(fx, in.numberIn("fx", kMinFocalPx, kMaxFocalPx, false, in.root(), focalFix()));
    UGV_TRY_ASSIGN(fy, in.numberIn("fy", kMinFocalPx, kMaxFocalPx, false, in.root(), focalFix()));
    UGV_TRY_ASSIGN(cx, in.numberIn("cx", 0.0, size.width, false, in.root(), "cx must lie inside the image width"));
    UGV_TRY_ASSIGN(cy, in.numberIn("cy", 0.0, size.height, false, in.root(), "cy must lie inside the image height"));
    UGV_TRY_ASSIGN(baseline, in.numberIn("baseline_m", kMinBaselineM, kMaxBaselineM, false, in.root(), baselineFix()));
    double cxRight = cx;
    if (!in.root()["cx_right"].empty()) { // the right camera's, when the pair was rectified without zero disparity
        UGV_TRY_ASSIGN(right, in.numberIn("cx_right", 0.0, size.width, false, in.root(),
                                          "cx_right (the right camera's cx, e.g. cx + Middlebury's doffs) must lie "
                                          "inside the image width; leave it out when it equals cx"));
        cxRight = right;
    }
    return vision::makeRectifiedCalibration(size, fx, fy, cx, cy, baseline, cxRight);
}

Result<StereoCalibration, Error> readFull(const Reader& in, cv::Size size)
{
    StereoCalibration c;
    c.imageSize = size;
    UGV_TRY_ASSIGN(k1, in.matrix("K1", 3, 3));
    UGV_TRY_ASSIGN(d1, in.distortion("D1"));
    UGV_TRY_ASSIGN(k2, in.matrix("K2", 3, 3));
    UGV_TRY_ASSIGN(d2, in.distortion("D2"));
    UGV_TRY_ASSIGN(r, in.matrix("R", 3, 3));
    UGV_TRY_ASSIGN(t, in.matrix("T", 3, 1));
    UGV_TRY_ASSIGN(e, in.matrix("E", 3, 3));
    UGV_TRY_ASSIGN(f, in.matrix("F", 3, 3));
    UGV_TRY_ASSIGN(r1, in.matrix("R1", 3, 3));
    UGV_TRY_ASSIGN(r2, in.matrix("R2", 3, 3));
    UGV_TRY_ASSIGN(p1, in.matrix("P1", 3, 4));
    UGV_TRY_ASSIGN(p2, in.matrix("P2", 3, 4));
    UGV_TRY_ASSIGN(q, in.matrix("Q", 4, 4));
    for (const auto& [key, m] :
         {std::pair<const char*, const cv::Mat*>{"K1", &k1}, {"K2", &k2}, {"P1", &p1}, {"P2", &p2}}) {
        if (auto focal = in.plausibleFocal(key, *m); !focal) {
            return Unexpected(focal.error());
        }
    }
    for (const auto& [key, m] : {std::pair<const char*, const cv::Mat*>{"R", &r}, {"R1", &r1}, {"R2", &r2}}) {
        if (auto rotation = in.rotation(key, *m); !rotation) {
            return Unexpected(rotation.error());
        }
    }
    const double baseline = cv::norm(t);
    if (!(baseline >= kMinBaselineM) || baseline > kMaxBaselineM) {
        return Unexpected(in.error("T", "baseline |T| = " + numberText(baseline) + " m", baselineFix()));
    }
    // The rectified pair's baseline: P2(0,3) = -fx * baseline for the right camera of a horizontal pair (what the
    // detector reads). Zero or positive: the cameras are swapped or P2 is not this T's.
    const double rectifiedBaseline = -p2.at<double>(0, 3) / p2.at<double>(0, 0);
    if (!(rectifiedBaseline >= kMinBaselineM) || rectifiedBaseline > kMaxBaselineM) {
        return Unexpected(in.error("P2",
                                   "rectified baseline -P2(0,3)/P2(0,0) = " + numberText(rectifiedBaseline) +
                                       " m (zero or negative: left and right swapped, or P2 is not this rig's)",
                                   baselineFix() + "; " + kRecalibrate));
    }
    c.K1 = k1;
    c.D1 = d1;
    c.K2 = k2;
    c.D2 = d2;
    c.R = r;
    c.T = t;
    c.E = e;
    c.F = f;
    c.R1 = r1;
    c.R2 = r2;
    c.P1 = p1;
    c.P2 = p2;
    c.Q = q;
    const std::string figureFix = "must be a finite number >= 0; " + std::string(kRecalibrate);
    UGV_TRY_ASSIGN(rms, in.numberIn("rms_px", 0.0, 1e6, false, in.root(), figureFix));
    UGV_TRY_ASSIGN(epipolar, in.numberIn("epipolar_px", 0.0, 1e6, false, in.root(), figureFix));
    UGV_TRY_ASSIGN(dy, in.numberIn("rectified_dy_px", 0.0, 1e6, false, in.root(), figureFix));
    UGV_TRY_ASSIGN(used, in.numberIn("pairs_used", 0.0, 1e6, false, in.root(), figureFix));
    UGV_TRY_ASSIGN(rejected, in.numberIn("pairs_rejected", 0.0, 1e6, false, in.root(), figureFix));
    c.rmsPx = rms;
    c.epipolarPx = epipolar;
    c.rectifiedDyPx = dy;
    c.pairsUsed = static_cast<int>(used);
    c.pairsRejected = static_cast<int>(rejected);
    return c;
}

Result<StereoCalibration, Error> readFile(const Reader& in)
{
    UGV_TRY_ASSIGN(version, in.number("schema_version"));
    if (version != kCalibrationSchemaVersion) {
        return Unexpected(in.error("schema_version", "unsupported schema_version " + numberText(version),
                                   "this build reads schema_version 1; " + std::string(kRecalibrate)));
    }
    const std::string sizeFix = "image size must be an integer in [" + std::to_string(kMinImageSide) + ", " +
                                std::to_string(kMaxImageSide) + "] pixels";
    UGV_TRY_ASSIGN(width, in.integerIn("image_width", kMinImageSide, kMaxImageSide, sizeFix));
    UGV_TRY_ASSIGN(height, in.integerIn("image_height", kMinImageSide, kMaxImageSide, sizeFix));
    const cv::Size size(width, height);
    bool rectified = false;
    if (!in.root()["rectified"].empty()) {
        UGV_TRY_ASSIGN(flag, in.number("rectified"));
        if (flag != 0.0 && flag != 1.0) {
            return Unexpected(
                in.error("rectified", "value " + numberText(flag), "write 'rectified: 1' or leave it out"));
        }
        rectified = flag == 1.0;
    }
    UGV_TRY_ASSIGN(calib, rectified ? readRectified(in, size) : readFull(in, size));
    const cv::FileNode mountNode = in.root()["mount"];
    if (!mountNode.empty() && !mountNode.isNone()) {
        if (!mountNode.isMap()) {
            return Unexpected(
                in.error("mount", "not a map", "write mount: {height_m: .., pitch_deg: .., roll_deg: ..}"));
        }
        UGV_TRY_ASSIGN(h, in.numberIn("height_m", kMinMountHeightM, kMaxMountHeightM, false, mountNode,
                                      "mount.height_m must be in [" + numberText(kMinMountHeightM) + ", " +
                                          numberText(kMaxMountHeightM) + "] metres"));
        UGV_TRY_ASSIGN(p, in.numberIn("pitch_deg", -kMaxMountPitchDeg, kMaxMountPitchDeg, false, mountNode,
                                      "mount.pitch_deg must be in [-45, 45] degrees"));
        UGV_TRY_ASSIGN(r, in.numberIn("roll_deg", -kMaxMountRollDeg, kMaxMountRollDeg, false, mountNode,
                                      "mount.roll_deg must be in [-30, 30] degrees"));
        calib.mount = vision::Mount{h, p, r};
    }
    return calib;
}

#undef UGV_TRY_ASSIGN

bool hasMatrices(const StereoCalibration& c)
{
    for (const cv::Mat* m : {&c.K1, &c.D1, &c.K2, &c.D2, &c.R, &c.T, &c.E, &c.F, &c.R1, &c.R2, &c.P1, &c.P2, &c.Q}) {
        if (m->empty()) {
            return false;
        }
    }
    return true;
}

} // namespace

Result<void, Error> saveCalibration(const std::string& path, const vision::StereoCalibration& calib)
{
    if (!calib.rectified && !hasMatrices(calib)) {
        return Unexpected(Error{path, "calibration has empty matrices", "calibrate before saving"});
    }
    try {
        cv::FileStorage fs(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
        if (!fs.isOpened()) {
            return Unexpected(
                Error{path, "cannot open the file for writing", "check that the folder exists and is writable"});
        }
        fs << "schema_version" << kCalibrationSchemaVersion;
        fs << "image_width" << calib.imageSize.width << "image_height" << calib.imageSize.height;
        if (calib.rectified) {
            const cv::Mat& p1 = calib.P1;
            fs << "rectified" << 1;
            fs << "fx" << p1.at<double>(0, 0) << "fy" << p1.at<double>(1, 1) << "cx" << p1.at<double>(0, 2) << "cy"
               << p1.at<double>(1, 2) << "baseline_m" << calib.baselineM();
            if (const double cxRight = calib.P2.at<double>(0, 2); cxRight != p1.at<double>(0, 2)) {
                fs << "cx_right" << cxRight;
            }
        } else {
            fs << "K1" << calib.K1 << "D1" << calib.D1 << "K2" << calib.K2 << "D2" << calib.D2;
            fs << "R" << calib.R << "T" << calib.T << "E" << calib.E << "F" << calib.F;
            fs << "R1" << calib.R1 << "R2" << calib.R2 << "P1" << calib.P1 << "P2" << calib.P2 << "Q" << calib.Q;
            fs << "rms_px" << calib.rmsPx << "epipolar_px" << calib.epipolarPx << "rectified_dy_px"
               << calib.rectifiedDyPx << "pairs_used" << calib.pairsUsed << "pairs_rejected" << calib.pairsRejected;
        }
        if (calib.mount) {
            fs << "mount"
               << "{";
            fs << "height_m" << calib.mount->heightM << "pitch_deg" << calib.mount->pitchDeg << "roll_deg"
               << calib.mount->rollDeg;
            fs << "}";
        }
        fs.release();
    } catch (const cv::Exception& e) {
        return Unexpected(
            Error{path, std::string("writing failed: ") + e.what(), "check that the folder exists and is writable"});
    }
    return {};
}

namespace {

/// The first key given twice in `map` or the maps below it ("mount.height_m"), else empty. OpenCV keeps both.
// NOLINTNEXTLINE(misc-no-recursion): one level per nesting level, which the YAML guard bounds (maxDepth) before parsing
std::string duplicateKey(const cv::FileNode& map, const std::string& prefix)
{
    std::set<std::string> seen;
    for (auto it = map.begin(); it != map.end(); ++it) {
        const cv::FileNode node = *it;
        std::string name = prefix + node.name(); // not const: returned by move
        if (!seen.insert(name).second) {
            return name;
        }
        if (node.isMap()) {
            if (std::string inner = duplicateKey(node, name + "."); !inner.empty()) {
                return inner;
            }
        }
    }
    return {};
}

/// OpenCV 4.6 puts "(LINE): what" of a parse error in the function name and the function in the message.
Error parseError(const cv::Exception& e, const std::string& where, const std::string& fix)
{
    const std::string& detail = e.func;
    const auto close = detail.find("): ");
    if (e.code == cv::Error::StsParseError && !detail.empty() && detail.front() == '(' && close != std::string::npos) {
        return Error{where + ":" + detail.substr(1, close - 1), "not valid YAML: " + detail.substr(close + 3), fix};
    }
    return Error{where, std::string("cannot be read: ") + e.what(), fix};
}

Result<vision::StereoCalibration, Error> parseText(const std::string& text, const std::string& where,
                                                   const std::string& fix)
{
    if (auto bounded = checkYamlText(text, where, kCalibrationLimits); !bounded) {
        return Unexpected(bounded.error());
    }
    const std::size_t start = text.find_first_not_of(" \t\r\n");
    if (start == std::string::npos || text.compare(start, 5, "%YAML") != 0) {
        return Unexpected(
            Error{where, "does not start with '%YAML:1.0' (OpenCV reads only that YAML)",
                  "start the file with the lines '%YAML:1.0' and '---', or " + std::string(kRecalibrate)});
    }
    try {
        const cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
        if (!fs.isOpened() || !fs.root().isMap()) {
            return Unexpected(Error{where, "not a calibration (no map of keys)", fix});
        }
        if (const std::string twice = duplicateKey(fs.root(), ""); !twice.empty()) {
            return Unexpected(Error{where + ": " + twice, "the key is given twice", "keep one of them"});
        }
        const Reader reader(fs.root(), where);
        return readFile(reader);
    } catch (const cv::Exception& e) {
        return Unexpected(parseError(e, where, fix));
    } catch (const std::exception& e) {
        // OpenCV 4.6's YAML reader also lets std::length_error out of some broken tags (a node cut inside
        // "!!opencv-matrix"; found by the calibration fuzz target, test/fuzz/corpus/calibration/crash-*).
        return Unexpected(Error{where, std::string("not valid YAML: OpenCV's reader failed (") + e.what() + ")", fix});
    }
}

} // namespace

Result<CalibrationWithText, Error> loadCalibrationWithText(const std::string& path)
{
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        return Unexpected(
            Error{path, "calibration file not found", "give the path of a file written by 'ugvsense calibrate'"});
    }
    auto text = readTextFile(path, kCalibrationLimits.maxBytes, kRecalibrate);
    if (!text) {
        return Unexpected(text.error());
    }
    auto calibration = parseText(*text, path, "repair the file or " + std::string(kRecalibrate));
    if (!calibration) {
        return Unexpected(calibration.error());
    }
    return CalibrationWithText{std::move(*calibration), std::move(*text)};
}

Result<vision::StereoCalibration, Error> loadCalibration(const std::string& path)
{
    auto loaded = loadCalibrationWithText(path);
    if (!loaded) {
        return Unexpected(loaded.error());
    }
    return std::move(loaded->calibration);
}

Result<vision::StereoCalibration, Error> parseCalibration(const std::string& text, const std::string& where)
{
    return parseText(text, where, "repair the calibration or " + std::string(kRecalibrate));
}

} // namespace ugv::adapters
