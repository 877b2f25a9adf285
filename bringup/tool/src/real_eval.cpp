#include "ugv/tool/real_eval.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <random>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ugv/platform/angles.hpp"
#include "ugv/tool/detection.hpp"
#include "ugv/tool/pair_files.hpp"
#include "ugv/vision/roi_matcher.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::tool {
namespace {

constexpr double kKittiScale = 256.0;     ///< KITTI GT: disparity = value / 256
constexpr int kBaselineDisparities = 128; ///< the issue's plain pipeline: StereoSGBM, 128 disparities, block 5
constexpr int kBaselineBlock = 5;
constexpr int kBaselineMinPoints = 20;  ///< the dense baseline's robust nearest (mismatch blobs have a few pixels)
constexpr double kTargetCorrect = 0.90; ///< issue 20's targets
constexpr double kTargetWrong = 0.05;

/// Sector of a bearing [deg] in `layout`, or -1.
int sectorOf(const ObstacleSectors& layout, double bearingDeg)
{
    if (layout.count < 1) {
        return -1;
    }
    const double lo = layout.sectors[0].bearingMinDeg;
    const double width = layout.sectors[0].bearingMaxDeg - lo;
    const int s = static_cast<int>(std::floor((bearingDeg - lo) / width));
    return s >= 0 && s < layout.count ? s : -1;
}

double nthNearest(std::vector<double>& ranges, int n)
{
    if (static_cast<int>(ranges.size()) < n || n < 1) {
        return SectorTruth::kNoRange;
    }
    std::nth_element(ranges.begin(), ranges.begin() + (n - 1), ranges.end());
    return ranges[static_cast<std::size_t>(n - 1)];
}

double tolerance(double rangeM, const RealScoringRules& rules)
{
    return std::max(rules.toleranceM, rules.toleranceFraction * rangeM);
}

/// Overlay colour of a reported sector: positive obstacle red, negative blue, Clear green, Unknown grey.
cv::Scalar stateColour(const Sector& s)
{
    if (s.state == SectorState::Obstacle) {
        return s.kind == ObstacleKind::Negative ? cv::Scalar(255, 0, 0) : cv::Scalar(0, 0, 255);
    }
    return s.state == SectorState::Clear ? cv::Scalar(0, 190, 0) : cv::Scalar(128, 128, 128);
}

/// One CSV line with double-quoted fields.
std::vector<std::string> splitCsv(const std::string& line)
{
    std::vector<std::string> fields(1);
    bool quoted = false;
    for (const char c : line) {
        if (c == '"') {
            quoted = !quoted;
        } else if (c == ',' && !quoted) {
            fields.emplace_back();
        } else if (c != '\r') {
            fields.back() += c;
        }
    }
    return fields;
}

struct RealPair {
    std::string dataset; ///< index.csv's, up to its first " (" ("KITTI 2015", "Middlebury 2014"); "" without the column
    std::string name;
    std::filesystem::path left, right, gt;
    std::string format;
    int width = 0, height = 0;
    double fx = 0.0, cx = 0.0, cy = 0.0, baselineM = 0.0, doffs = 0.0;
};

Result<std::vector<RealPair>, Error> readIndex(const std::filesystem::path& dir)
{
    const std::filesystem::path path = dir / "index.csv";
    std::ifstream in(path);
    std::string line;
    if (!in || !std::getline(in, line)) {
        return Unexpected(Error{path.string(), "cannot read the index", "give the real-stereo folder with --real"});
    }
    const std::vector<std::string> header = splitCsv(line);
    std::map<std::string, std::size_t> column;
    for (std::size_t i = 0; i < header.size(); ++i) {
        column[header[i]] = i;
    }
    for (const char* need : {"pair", "left", "right", "gt", "gt_format", "width", "height", "fx_px", "cx_px", "cy_px",
                             "baseline_m", "doffs_px"}) {
        if (column.count(need) == 0) {
            return Unexpected(Error{path.string(), std::string("no column '") + need + "'",
                                    "use the index.csv of ../shared/data/real-stereo"});
        }
    }
    std::vector<RealPair> pairs;
    for (int lineNo = 2; std::getline(in, line); ++lineNo) {
        if (line.empty()) {
            continue;
        }
        const std::vector<std::string> f = splitCsv(line);
        if (f.size() != header.size()) {
            return Unexpected(
                Error{path.string() + ":" + std::to_string(lineNo),
                      std::to_string(f.size()) + " fields, the header has " + std::to_string(header.size()),
                      "repair the line"});
        }
        RealPair p;
        const auto at = [&](const char* key) -> const std::string& { return f[column[key]]; };
        if (column.count("dataset") != 0) { // optional: without it, one data set
            p.dataset = at("dataset").substr(0, at("dataset").find(" ("));
        }
        p.name = at("pair");
        p.left = dir / at("left");
        p.right = dir / at("right");
        p.gt = dir / at("gt");
        p.format = at("gt_format");
        try {
            p.width = std::stoi(at("width"));
            p.height = std::stoi(at("height"));
            p.fx = std::stod(at("fx_px"));
            p.cx = std::stod(at("cx_px"));
            p.cy = std::stod(at("cy_px"));
            p.baselineM = std::stod(at("baseline_m"));
            p.doffs = std::stod(at("doffs_px"));
        } catch (const std::exception&) {
            return Unexpected(
                Error{path.string() + ":" + std::to_string(lineNo), "a number does not parse", "repair the line"});
        }
        pairs.push_back(p);
    }
    return pairs;
}

/// Whether the pair's GT is a Middlebury float PFM (index.csv's gt_format).
bool isPfmPair(const RealPair& pair)
{
    return pair.format.rfind("float32 PFM", 0) == 0;
}

/// Sectors of a point set as a detector would report them: Obstacle at the robust nearest range, else Clear.
ObstacleSectors sectorsFromTruth(const std::vector<SectorTruth>& truth, const ObstacleSectors& layout)
{
    ObstacleSectors out = layout;
    for (int s = 0; s < out.count; ++s) {
        Sector& sector = out.sectors[static_cast<std::size_t>(s)];
        const SectorTruth& t = truth[static_cast<std::size_t>(s)];
        sector.state = t.seesObstacle() ? SectorState::Obstacle : SectorState::Clear;
        sector.kind = t.seesObstacle() ? ObstacleKind::Positive : ObstacleKind::None;
        sector.rangeM =
            t.seesObstacle() ? static_cast<float>(t.obstacleRangeM) : std::numeric_limits<float>::infinity();
    }
    return out;
}

std::string tallyJson(const RealTally& t)
{
    std::vector<double> e = t.rangeErrorsM;
    std::sort(e.begin(), e.end());
    const double median = e.empty() ? 0.0 : e[e.size() / 2];
    return "{\"scored\": " + std::to_string(t.scored) + ", \"gt_obstacle\": " + std::to_string(t.gtObstacle) +
           ", \"correct\": " + std::to_string(t.correct) + ", \"missed\": " + std::to_string(t.missed) +
           ", \"too_near\": " + std::to_string(t.tooNear) + ", \"false\": " + std::to_string(t.falseSectors) +
           ", \"negative_on_no_drop_pairs\": " + std::to_string(t.negativeNoDrop) +
           ", \"correct_rate\": " + jsonNumber(t.correctRate()) + ", \"wrong_rate\": " + jsonNumber(t.wrongRate()) +
           ", \"median_range_error_m\": " + jsonNumber(median) + "}";
}

void printTally(const char* who, const RealTally& t)
{
    std::vector<double> e = t.rangeErrorsM;
    std::sort(e.begin(), e.end());
    std::printf("%-8s %4d/%4d correct (%5.1f %%) %4d missed %4d too near %4d false (too near + false %4.1f %% of "
                "%d scored) negative on no-drop pairs %d, median range error %.2f m\n",
                who, t.correct, t.gtObstacle, 100.0 * t.correctRate(), t.missed, t.tooNear, t.falseSectors,
                100.0 * t.wrongRate(), t.scored, t.negativeNoDrop, e.empty() ? 0.0 : e[e.size() / 2]);
}

/// The plain pipeline of the comparison on the full frame: OpenCV StereoSGBM -> CV_32F disparity [px].
Result<cv::Mat, Error> baselineDisparity(const cv::Mat& left, const cv::Mat& right)
{
    cv::Mat d16;
    try {
        const int area = kBaselineBlock * kBaselineBlock;
        cv::Ptr<cv::StereoSGBM> sgbm =
            cv::StereoSGBM::create(0, kBaselineDisparities, kBaselineBlock, 8 * area, 32 * area);
        sgbm->compute(left, right, d16);
    } catch (const std::exception& e) {
        return Unexpected(Error{"OpenCV StereoSGBM", e.what(), ""});
    }
    cv::Mat out;
    d16.convertTo(out, CV_32F, 1.0 / vision::RoiMatcher::kScale);
    return out;
}

/// Road plane of a full-frame CV_32F disparity: RANSAC in metres on the points of the bottom third and the middle
/// third of the columns (the road ahead, not a verge beside it) within 30 m
/// (a plane whose normal is within 30 deg of the camera's down axis, the camera 0.2-5 m above it; inliers within
/// 8 cm), refined by least squares (the smallest eigenvector of the inliers' scatter). Metric rather than in
/// disparity (fitGround) so that the truth does not depend on a pixel tolerance, and with no inlier fraction: the
/// GT of a street with parked cars close by is mostly car.
Result<vision::GroundPlane, Error> roadPlane(const cv::Mat& disparity, const vision::RectifiedProjection& p)
{
    constexpr int kStep = 2;
    constexpr double kMaxZ = 30.0;        // [m]
    constexpr double kInlierM = 0.08;     // [m]
    constexpr double kMaxTiltCos = 0.866; // cos 30 deg
    constexpr int kIterations = 500;
    constexpr int kMinInliers = 100;
    std::vector<cv::Vec3d> points;
    for (int v = disparity.rows - disparity.rows / 3; v < disparity.rows; v += kStep) {
        const float* row = disparity.ptr<float>(v);
        for (int u = disparity.cols / 3; u < disparity.cols - disparity.cols / 3; u += kStep) {
            if (!(row[u] > 0.0F) || !std::isfinite(row[u])) {
                continue;
            }
            const double z = p.fx * p.baselineM / row[u];
            if (z <= kMaxZ) {
                points.emplace_back((u - p.cx) * z / p.fx, (v - p.cy) * z / p.fy, z);
            }
        }
    }
    if (static_cast<int>(points.size()) < kMinInliers) {
        return Unexpected(Error{"road plane", "only " + std::to_string(points.size()) + " points in the bottom third",
                                "check the disparity map"});
    }
    std::mt19937 random(1); // fixed seed: the same disparities give the same plane
    std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
    cv::Vec3d bestN;
    double bestH = 0.0;
    int bestCount = 0;
    for (int it = 0; it < kIterations; ++it) {
        const cv::Vec3d a = points[pick(random)];
        cv::Vec3d n = (points[pick(random)] - a).cross(points[pick(random)] - a);
        const double norm = cv::norm(n);
        if (norm < 1e-9) {
            continue;
        }
        n /= norm;
        if (n[1] < 0.0) {
            n = -n;
        }
        const double h = n.dot(a);
        if (n[1] < kMaxTiltCos || h < 0.2 || h > 5.0) {
            continue;
        }
        int count = 0;
        for (const cv::Vec3d& q : points) {
            count += std::abs(n.dot(q) - h) < kInlierM ? 1 : 0;
        }
        if (count > bestCount) {
            bestCount = count;
            bestN = n;
            bestH = h;
        }
    }
    if (bestCount < kMinInliers) {
        return Unexpected(Error{"road plane", "no plane holds " + std::to_string(kMinInliers) + " points",
                                "check the disparity map"});
    }
    cv::Vec3d mean(0, 0, 0);
    std::vector<cv::Vec3d> inliers;
    for (const cv::Vec3d& q : points) {
        if (std::abs(bestN.dot(q) - bestH) < kInlierM) {
            inliers.push_back(q);
            mean += q;
        }
    }
    mean /= static_cast<double>(inliers.size());
    cv::Matx33d scatter = cv::Matx33d::zeros();
    for (const cv::Vec3d& q : inliers) {
        const cv::Vec3d c = q - mean;
        scatter += c * c.t();
    }
    cv::Mat values, vectors;
    cv::eigen(cv::Mat(scatter), values, vectors); // descending: the last row is the normal
    cv::Vec3d n(vectors.at<double>(2, 0), vectors.at<double>(2, 1), vectors.at<double>(2, 2));
    if (n[1] < 0.0) {
        n = -n;
    }
    return vision::GroundPlane{n[0], n[1], n[2], n.dot(mean)};
}

/// "A,B,C": three numbers (spaces before each allowed), nothing else.
bool parseThreeNumbers(const std::string& text, double& a, double& b, double& c)
{
    const char* at = text.data();
    const char* const end = text.data() + text.size();
    std::array<double*, 3> out{&a, &b, &c};
    for (std::size_t i = 0; i < out.size(); ++i) {
        while (at != end && *at == ' ') {
            ++at;
        }
        const auto [stop, error] = std::from_chars(at, end, *out[i]);
        if (error != std::errc{} || (i + 1 < out.size() ? (stop == end || *stop != ',') : stop != end)) {
            return false;
        }
        at = stop + 1;
    }
    return true;
}

} // namespace

Result<RealMount, Error> parseMount(const std::string& text)
{
    RealMount out;
    const std::size_t equals = text.find('=');
    const std::string numbers = equals == std::string::npos ? text : text.substr(equals + 1);
    out.dataset = equals == std::string::npos ? std::string() : text.substr(0, equals);
    vision::Mount& m = out.mount;
    if ((equals != std::string::npos && out.dataset.empty()) ||
        !parseThreeNumbers(numbers, m.heightM, m.pitchDeg, m.rollDeg) || !(m.heightM > 0.0 && m.heightM < 10.0) ||
        !(std::abs(m.pitchDeg) < 45.0) || !(std::abs(m.rollDeg) < 45.0)) {
        return Unexpected(Error{"ugvsense eval --mount", "'" + text + "' is not [DATASET=]HEIGHT_M,PITCH_DEG,ROLL_DEG",
                                "for example --mount 1.65,0,0 or --mount KITTI=1.65,0,0 (height 0-10 m, pitch and "
                                "roll within 45 deg)"});
    }
    return out;
}

std::vector<SectorTruth> sectorTruth(const cv::Mat& disparity, int firstRow, const vision::GroundPlane& road,
                                     const vision::RectifiedProjection& projection, const ObstacleSectors& layout,
                                     const RealScoringRules& rules)
{
    const auto n = static_cast<std::size_t>(layout.count);
    std::vector<SectorTruth> out(n);
    std::vector<std::vector<double>> obstacle(n);
    std::vector<std::vector<double>> kerb(n);
    std::vector<int> analysed(n, 0);
    std::vector<int> withGt(n, 0);
    const double horizon = rules.maxRangeM + tolerance(rules.maxRangeM, rules);
    for (int v = std::max(0, firstRow); v < disparity.rows; ++v) {
        const float* row = disparity.ptr<float>(v);
        for (int u = 0; u < disparity.cols; ++u) {
            const int column = sectorOf(layout, std::atan2(projection.cx - u, projection.fx) * kRadToDeg);
            const bool valid = row[u] > 0.0F && std::isfinite(row[u]);
            if (column >= 0) {
                ++analysed[static_cast<std::size_t>(column)];
                withGt[static_cast<std::size_t>(column)] += valid ? 1 : 0;
            }
            if (!valid) {
                continue;
            }
            const vision::VehiclePoint p = road.pixelToVehicle(u, v, row[u], projection);
            const double range = std::hypot(p.x, p.y);
            const int s = sectorOf(layout, std::atan2(p.y, p.x) * kRadToDeg);
            if (s < 0 || range > horizon || !(p.x > 0.0)) {
                continue;
            }
            const auto k = static_cast<std::size_t>(s);
            if (p.z >= rules.kerbMinHeightM && p.z <= rules.obstacleMaxHeightM) {
                kerb[k].push_back(range);
                if (p.z >= rules.obstacleMinHeightM) {
                    obstacle[k].push_back(range);
                }
            } else if (p.z <= -rules.dropMinDepthM && range <= rules.maxRangeM) {
                ++out[k].dropPoints;
            }
        }
    }
    for (std::size_t k = 0; k < n; ++k) {
        SectorTruth& t = out[k];
        t.coverage = analysed[k] > 0 ? static_cast<double>(withGt[k]) / analysed[k] : 0.0;
        t.scored = t.coverage >= rules.minCoverage;
        t.obstaclePoints = static_cast<int>(obstacle[k].size());
        t.obstacleRangeM = nthNearest(obstacle[k], rules.minPoints);
        t.kerbRangeM = nthNearest(kerb[k], rules.minPoints);
        t.horizonM = rules.maxRangeM;
    }
    return out;
}

RealOutcome scoreRealSector(const SectorTruth& truth, const Sector& reported, const RealScoringRules& rules)
{
    if (!truth.scored) {
        return RealOutcome::NotScored;
    }
    const double r = reported.rangeM;
    const bool report = reported.state == SectorState::Obstacle && std::isfinite(r) &&
                        r <= rules.maxRangeM + tolerance(rules.maxRangeM, rules);
    const bool atKerb = report && truth.kerbRangeM < SectorTruth::kNoRange &&
                        std::abs(r - truth.kerbRangeM) <= tolerance(truth.kerbRangeM, rules);
    if (truth.hasObstacle()) {
        if (!report) {
            return RealOutcome::Missed;
        }
        if (std::abs(r - truth.obstacleRangeM) <= tolerance(truth.obstacleRangeM, rules) || atKerb) {
            return RealOutcome::Correct;
        }
        return r < truth.obstacleRangeM ? RealOutcome::TooNear : RealOutcome::Missed;
    }
    // Nothing within the horizon: a report is false unless it is a kerb or an obstacle just beyond the horizon.
    const bool beyond =
        report && truth.seesObstacle() && std::abs(r - truth.obstacleRangeM) <= tolerance(truth.obstacleRangeM, rules);
    return report && !atKerb && !beyond ? RealOutcome::False : RealOutcome::FreeOk;
}

void RealTally::add(RealOutcome outcome, const SectorTruth& truth, const Sector& reported)
{
    if (outcome == RealOutcome::NotScored) {
        return;
    }
    ++scored;
    gtObstacle += truth.hasObstacle() ? 1 : 0;
    switch (outcome) {
    case RealOutcome::Correct:
        ++correct;
        rangeErrorsM.push_back(std::abs(reported.rangeM - (std::abs(reported.rangeM - truth.obstacleRangeM) <=
                                                                   std::abs(reported.rangeM - truth.kerbRangeM)
                                                               ? truth.obstacleRangeM
                                                               : truth.kerbRangeM)));
        break;
    case RealOutcome::Missed:
        ++missed;
        break;
    case RealOutcome::TooNear:
        ++tooNear;
        break;
    case RealOutcome::False:
        ++falseSectors;
        break;
    case RealOutcome::NotScored:
    case RealOutcome::FreeOk:
        break;
    }
}

void RealTally::merge(const RealTally& o)
{
    scored += o.scored;
    gtObstacle += o.gtObstacle;
    correct += o.correct;
    missed += o.missed;
    tooNear += o.tooNear;
    falseSectors += o.falseSectors;
    negativeNoDrop += o.negativeNoDrop;
    rangeErrorsM.insert(rangeErrorsM.end(), o.rangeErrorsM.begin(), o.rangeErrorsM.end());
}

namespace {

/// A pair's images, its ground truth in pixels of disparity, and its calibration.
struct RealImages {
    cv::Mat left;
    cv::Mat right;
    cv::Mat gt; ///< [px] disparity, 0 where the LiDAR saw nothing
    vision::StereoCalibration calib;
};

/// Reads a pair. Each header is checked before decoding (a PNG that declares a huge size is refused unread); the
/// error names the pair, its files and the first that failed.
Result<RealImages, Error> readRealPair(const RealPair& pair, const std::optional<vision::Mount>& mount)
{
    std::string why; // of the first file that failed
    const auto read = [&](const std::filesystem::path& file, int flags) {
        std::string reason;
        cv::Mat image = why.empty() ? readImage(file, flags, &reason) : cv::Mat();
        if (image.empty() && why.empty()) {
            why = file.filename().string() + ": " + reason;
        }
        return image;
    };
    RealImages images;
    images.left = read(pair.left, cv::IMREAD_GRAYSCALE);
    images.right = read(pair.right, cv::IMREAD_GRAYSCALE);
    const cv::Size size(pair.width, pair.height);
    const bool pfm = isPfmPair(pair);
    cv::Mat gtRaw;
    if (pfm && why.empty()) {
        std::string reason;
        gtRaw = readPfmDisparity(pair.gt, size, reason);
        why = gtRaw.empty() ? pair.gt.filename().string() + ": " + reason : why;
    } else if (!pfm) {
        gtRaw = read(pair.gt, cv::IMREAD_UNCHANGED);
    }
    if (images.left.empty() || images.right.empty() || gtRaw.type() != (pfm ? CV_32FC1 : CV_16UC1) ||
        images.left.size() != size || images.right.size() != size || gtRaw.size() != size) {
        return Unexpected(Error{"",
                                "cannot read " + pair.left.string() + ", " + pair.right.string() + " and the GT " +
                                    pair.gt.string() + " of size " + std::to_string(pair.width) + "x" +
                                    std::to_string(pair.height) + (why.empty() ? "" : ": " + why),
                                "give index.csv's images and disparity ground truth (KITTI's 16-bit PNG or "
                                "Middlebury's PFM) of the size it names"});
    }
    if (pfm) {
        images.gt = cv::Mat(size, CV_32F, cv::Scalar(0.0)); // no GT (inf in a PFM) is 0, as in KITTI's files
        gtRaw.copyTo(images.gt, (gtRaw > 0.0F) & (gtRaw < std::numeric_limits<float>::max()));
    } else {
        gtRaw.convertTo(images.gt, CV_32F, 1.0 / kKittiScale);
    }
    if (pair.doffs != 0.0) {
        // One principal point for both images (the right camera's is doffs right of the left's, Z = f B / (d +
        // doffs)): the right image moved left by doffs (bilinear) and doffs added to the truth, so that every
        // disparity is f B / Z. Done here, not by our Rectifier (a calibration's cx_right), because OpenCV's
        // baseline matches these images directly.
        cv::add(images.gt, cv::Scalar(pair.doffs), images.gt, images.gt > 0.0F);
        const cv::Matx23d shift(1.0, 0.0, -pair.doffs, 0.0, 1.0, 0.0);
        cv::Mat moved;
        cv::warpAffine(images.right, moved, shift, size, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
        images.right = moved;
    }
    images.calib = vision::makeRectifiedCalibration(size, pair.fx, pair.fx, pair.cx, pair.cy, pair.baselineM);
    images.calib.mount = mount;
    return images;
}

/// The plain OpenCV pipeline's sectors: its disparity's RANSAC road and the same height rules with the dense
/// matcher's point count; nothing known (ours' layout, every sector blank) when it finds no road.
ObstacleSectors baselineSectors(const cv::Mat& disparity, int firstRow, const vision::RectifiedProjection& projection,
                                const ObstacleSectors& ours, const RealScoringRules& rules)
{
    if (auto baseRoad = roadPlane(disparity, projection)) {
        RealScoringRules denseRules = rules;
        denseRules.minPoints = kBaselineMinPoints;
        return sectorsFromTruth(sectorTruth(disparity, firstRow, *baseRoad, projection, ours, denseRules), ours);
    }
    ObstacleSectors baseline = ours;
    for (int k = 0; k < baseline.count; ++k) {
        Sector& sector = baseline.sectors[static_cast<std::size_t>(k)];
        const Sector blank;
        sector.state = blank.state;
        sector.kind = blank.kind;
        sector.rangeM = blank.rangeM;
    }
    return baseline;
}

/// --overlay-dir: the left image with our obstacles and two bars under it, ours by state and kind, then the truth
/// (grey: not scored). False when it could not be written.
bool writeRealOverlay(const std::filesystem::path& out, const RealPair& pair, const RealImages& images,
                      const PairDetection& run, const vision::DetectorConfig& config,
                      const std::vector<SectorTruth>& truth, bool changed)
{
    const ObstacleSectors& ours = run.detector->sectors();
    const vision::RectifiedProjection& projection = run.rectifier->projection();
    cv::Mat colour; // the left image in colour, or as matched when a condition changed it (eval --perturb)
    if (changed) {
        cv::cvtColor(images.left, colour, cv::COLOR_GRAY2BGR);
    } else {
        colour = readImage(pair.left, cv::IMREAD_COLOR);
    }
    vision::RectifierConfig fullConfig;
    fullConfig.fullFrame = true;
    auto full = vision::Rectifier::create(images.calib, fullConfig);
    std::vector<cv::Scalar> oursColours;
    std::vector<cv::Scalar> truthColours;
    for (int s = 0; s < ours.count; ++s) {
        const SectorTruth& t = truth[static_cast<std::size_t>(s)];
        oursColours.push_back(stateColour(ours.sectors[static_cast<std::size_t>(s)]));
        truthColours.push_back(!t.scored         ? cv::Scalar(128, 128, 128)
                               : t.hasObstacle() ? cv::Scalar(0, 0, 255)
                                                 : cv::Scalar(0, 190, 0));
    }
    if (colour.empty() || !full) {
        return false;
    }
    const cv::Mat image = makeOverlay(colour, *full, *run.detector, config, projection);
    const cv::Mat plain = image(cv::Rect(0, 0, image.cols, images.left.rows)); // without the danger bar
    return cv::imwrite(out.string(), appendSectorBar(appendSectorBar(plain, ours, oursColours, projection), ours,
                                                     truthColours, projection));
}

/// --verbose: a line per sector (truth, ours, outcome).
void printSectorLines(const ObstacleSectors& ours, const std::vector<SectorTruth>& truth, const RealScoringRules& rules)
{
    static constexpr const char* kOutcome[] = {"not scored", "correct", "too near", "missed", "FALSE", "ok"};
    for (int s = 0; s < ours.count; ++s) {
        const auto k = static_cast<std::size_t>(s);
        const Sector& r = ours.sectors[k];
        std::printf("    sector %2d truth %6.2f m (kerb %6.2f, %4d pts, cov %3.0f %%) ours %-8s %-8s %6.2f m  %s\n", s,
                    truth[k].hasObstacle() ? truth[k].obstacleRangeM : -1.0,
                    truth[k].kerbRangeM < SectorTruth::kNoRange ? truth[k].kerbRangeM : -1.0, truth[k].obstaclePoints,
                    100.0 * truth[k].coverage, stateName(r.state), kindName(r.kind), r.rangeM,
                    kOutcome[static_cast<int>(scoreRealSector(truth[k], r, rules))]);
    }
}

/// `p` applied to a pair as read (its images, and at half resolution its truth and calibration too).
void applyCondition(const Perturbation& p, const RealPair& pair, RealImages& images)
{
    if (p.half) {
        images.gt = halveDisparityTruth(images.gt);
        const std::optional<vision::Mount> mount = images.calib.mount;
        // Pixel centres: x_half = (x + 0.5) / 2 - 0.5.
        images.calib =
            vision::makeRectifiedCalibration(images.gt.size(), pair.fx / 2.0, pair.fx / 2.0,
                                             (pair.cx + 0.5) / 2.0 - 0.5, (pair.cy + 0.5) / 2.0 - 0.5, pair.baselineM);
        images.calib.mount = mount;
    }
    std::uint64_t seed = 1469598103934665603ULL; // FNV-1a of the pair's name: the same noise every run
    for (const char c : pair.name) {
        seed = (seed ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
    }
    perturbImages(p, seed, images.left, images.right);
}

/// What the suite keeps across the pairs.
struct RealRun {
    const RealEvalOptions& options;
    std::optional<RealMount> mount;
    vision::DetectorConfig config;
    RealScoringRules rules;
    Perturbation condition; ///< applied to every pair
    bool quiet = false;     ///< no line per pair (one of several conditions)
    RealTally ours;
    RealTally baseline;
    RealTally colour; ///< the one-camera mode (options.colour)
    /// ours and the baseline per data set (each its own rig and scenes), in the order first seen
    std::vector<std::pair<std::string, std::array<RealTally, 2>>> byDataset;
    double searchedSum = 0.0; ///< CensusSgm::searchedFraction over the pairs
    int searchedPairs = 0;
    bool firstJson = true;
};

/// The one-camera mode on a pair: its sectors (the layout equals the stereo detector's: same sector count and field
/// of view) and what its reference band taught.
struct ColourRun {
    ObstacleSectors sectors;
    vision::ColourReference reference;
};

/// --detector colour: ColourFreeSpace on the pair's left colour image, the ground of the mount (or the stereo
/// detector's estimate: what a calibrated mount would give).
Result<ColourRun, Error> colourSectors(const RealPair& pair, const RealImages& images, const RealRun& r,
                                       const PairDetection& run)
{
    std::string why;
    const cv::Mat bgr = readImage(pair.left, cv::IMREAD_COLOR, &why);
    if (bgr.empty() || bgr.cols != pair.width || bgr.rows != pair.height) {
        return Unexpected(
            Error{pair.left.string(),
                  "cannot read it in colour at the index's size" + (why.empty() ? std::string() : ": " + why),
                  "give index.csv's left image"});
    }
    const vision::GroundPlane ground =
        images.calib.mount ? vision::GroundPlane::fromMount(*images.calib.mount) : run.detector->ground();
    auto colour = vision::ColourFreeSpace::create(vision::colourConfigFor(r.config.sectors), bgr.size(),
                                                  run.rectifier->projection(), ground);
    if (!colour) {
        return Unexpected(colour.error());
    }
    ColourRun out;
    (void)colour->process(bgrViewOf(bgr), out.sectors); // the size was checked: always Ok
    out.reference = colour->reference();
    return out;
}

/// Whether the truth of a pair holds a drop (in any sector).
bool hasDrop(const std::vector<SectorTruth>& truth, const RealScoringRules& rules)
{
    return std::any_of(truth.begin(), truth.end(),
                       [&](const SectorTruth& t) { return t.dropPoints >= rules.minPoints; });
}

/// The one-camera mode's tally of a pair, its line printed (below the pair's).
RealTally scoreColour(const ColourRun& mono, const std::vector<SectorTruth>& truth, const RealRun& r)
{
    RealTally c;
    int unknown = 0;
    for (int s = 0; s < mono.sectors.count; ++s) {
        const auto k = static_cast<std::size_t>(s);
        c.add(scoreRealSector(truth[k], mono.sectors.sectors[k], r.rules), truth[k], mono.sectors.sectors[k]);
        unknown += mono.sectors.sectors[k].state == SectorState::Unknown ? 1 : 0;
    }
    std::printf("%-12s colour: %4d correct %4d missed %4d too near %4d false, %d of %d sectors Unknown; band: value "
                "%.0f, %d ground colours covering %.2f\n",
                "", c.correct, c.missed, c.tooNear, c.falseSectors, unknown, mono.sectors.count,
                mono.reference.meanValue, mono.reference.groundColours, mono.reference.coverage);
    return c;
}

/// One pair: ours and the baseline scored against the truth, the pair's line and JSON, the overlay.
/// @return 0, or 1 on a pair that cannot be read or run, or an overlay that cannot be written.
int runRealPair(const RealPair& pair, RealRun& r, std::ostringstream& json)
{
    // A mount belongs to one rig: given for a data set, the other data sets' pairs have their ground found.
    const bool mounted = r.mount && r.mount->appliesTo(pair.dataset);
    auto images = readRealPair(pair, mounted ? std::optional<vision::Mount>(r.mount->mount) : std::nullopt);
    if (images) {
        applyCondition(r.condition, pair, *images);
    }
    auto run = images ? detectPair(images->calib, images->left, images->right, r.config, pair.name)
                      : Result<PairDetection, Error>(Unexpected(images.error()));
    if (!run) {
        std::cerr << "ugvsense eval: error: " << pair.name << ": " << run.error().message() << '\n';
        return 1;
    }
    const vision::RectifiedProjection& projection = run->rectifier->projection();
    const int firstRow = run->rectifier->roi().y + r.config.marginRows;
    const ObstacleSectors& ours = run->detector->sectors();
    auto road = roadPlane(images->gt, projection);
    auto baseDisparity = baselineDisparity(images->left, images->right);
    if (!road || !baseDisparity) {
        std::cerr << "ugvsense eval: error: " << pair.name << ": "
                  << (!road ? road.error().message() : baseDisparity.error().message()) << '\n';
        return 1;
    }
    const std::vector<SectorTruth> truth = sectorTruth(images->gt, firstRow, *road, projection, ours, r.rules);
    const ObstacleSectors baseline = baselineSectors(*baseDisparity, firstRow, projection, ours, r.rules);
    const bool truthHasDrop = hasDrop(truth, r.rules);
    std::optional<ColourRun> mono;
    if (r.options.colour) {
        auto made = colourSectors(pair, *images, r, *run);
        if (!made) {
            std::cerr << "ugvsense eval: error: " << pair.name << ": " << made.error().message() << '\n';
            return 1;
        }
        mono = std::move(made).value();
    }
    RealTally o;
    RealTally b;
    for (int s = 0; s < ours.count; ++s) {
        const auto k = static_cast<std::size_t>(s);
        o.add(scoreRealSector(truth[k], ours.sectors[k], r.rules), truth[k], ours.sectors[k]);
        b.add(scoreRealSector(truth[k], baseline.sectors[k], r.rules), truth[k], baseline.sectors[k]);
        if (!truthHasDrop && ours.sectors[k].state == SectorState::Obstacle &&
            ours.sectors[k].kind == ObstacleKind::Negative) {
            ++o.negativeNoDrop;
        }
    }
    const vision::GroundPlane& g = run->detector->ground();
    if (!r.quiet) {
        std::printf("%-12s %5d | %4d %4d %4d %4d %4d  h %4.2f p %5.1f%s | %4d %4d %4d %4d  (GT road h %4.2f p %5.1f)\n",
                    pair.name.c_str(), o.gtObstacle, o.correct, o.missed, o.tooNear, o.falseSectors, o.negativeNoDrop,
                    g.heightM, g.pitchDeg(), run->detector->groundEstimate().reliable ? " " : "!", b.correct, b.missed,
                    b.tooNear, b.falseSectors, road->heightM, road->pitchDeg());
    }
    const RealTally c = mono ? scoreColour(*mono, truth, r) : RealTally{};
    if (r.options.verbose) {
        printSectorLines(ours, truth, r.rules);
        if (mono) {
            std::printf("    one camera (colour):\n");
            printSectorLines(mono->sectors, truth, r.rules);
        }
    }
    json << (r.firstJson ? "\n" : ",\n") << "    {\"pair\": " << jsonString(pair.name)
         << ", \"dataset\": " << jsonString(pair.dataset)
         << ", \"truth_has_drop\": " << (truthHasDrop ? "true" : "false")
         << ", \"ground\": {\"height_m\": " << jsonNumber(g.heightM) << ", \"pitch_deg\": " << jsonNumber(g.pitchDeg())
         << ", \"roll_deg\": " << jsonNumber(g.rollDeg()) << ", \"gt_height_m\": " << jsonNumber(road->heightM)
         << ", \"gt_pitch_deg\": " << jsonNumber(road->pitchDeg())
         << "}, \"ground_noise_px\": " << jsonNumber(run->detector->groundNoisePx())
         << ", \"image_noise_grey\": " << jsonNumber(run->detector->verifier().noiseSigma())
         << ", \"verifier_contrast_grey\": " << jsonNumber(run->detector->verifier().requiredContrast())
         << ", \"searched_fraction\": " << jsonNumber(run->detector->searchedFraction())
         << ", \"ours\": " << tallyJson(o) << ", \"opencv\": " << tallyJson(b)
         << (mono ? ", \"colour\": " + tallyJson(c) : std::string()) << "}";
    r.firstJson = false;
    r.searchedSum += run->detector->searchedFraction();
    ++r.searchedPairs;
    if (!r.options.overlayDir.empty()) {
        const std::filesystem::path out = r.options.overlayDir / (pair.name + ".png");
        if (!writeRealOverlay(out, pair, *images, *run, r.config, truth, r.condition.name != "none")) {
            std::cerr << "ugvsense eval: error: cannot write the overlay " << out.string() << '\n';
            return 1;
        }
    }
    r.ours.merge(o);
    r.baseline.merge(b);
    auto set =
        std::find_if(r.byDataset.begin(), r.byDataset.end(), [&](const auto& d) { return d.first == pair.dataset; });
    if (set == r.byDataset.end()) {
        set = r.byDataset.insert(r.byDataset.end(), {pair.dataset, {}});
    }
    set->second[0].merge(o);
    set->second[1].merge(b);
    r.colour.merge(c);
    return 0;
}

/// The totals and the targets' verdicts, printed and closing `json`'s "real" object.
void reportRealTotals(const RealRun& r, std::ostringstream& json)
{
    std::printf("total:\n");
    const double searched = r.searchedPairs > 0 ? r.searchedSum / r.searchedPairs : 1.0;
    std::printf("matcher cost cells searched (ground range %s): %.1f %% of the full range, mean over the pairs\n",
                r.config.matcher.groundRange ? "on" : "off", 100.0 * searched);
    printTally("ours", r.ours);
    printTally("opencv", r.baseline);
    if (r.options.colour) {
        printTally("colour", r.colour);
    }
    if (r.byDataset.size() > 1) {
        for (const auto& [name, tallies] : r.byDataset) {
            std::printf("  %s:\n", name.c_str());
            printTally("  ours", tallies[0]);
            printTally("  opencv", tallies[1]);
        }
    }
    const auto verdict = [](bool ok) { return ok ? "PASS" : "FAIL"; };
    const bool noWorse = r.ours.correctRate() >= r.baseline.correctRate() &&
                         r.ours.tooNear + r.ours.falseSectors <= r.baseline.tooNear + r.baseline.falseSectors;
    std::printf("targets (issue 20): correct >= 90 %%: %s; too near + false <= 5 %% of scored: %s; no negative sector "
                "on pairs without a drop: %s\n",
                verdict(r.ours.correctRate() >= kTargetCorrect), verdict(r.ours.wrongRate() <= kTargetWrong),
                verdict(r.ours.negativeNoDrop == 0));
    std::printf("against the plain OpenCV pipeline: correct no lower and too near + false no more: %s\n",
                verdict(noWorse));
    json << "\n  ], \"ours\": " << tallyJson(r.ours) << ", \"opencv\": " << tallyJson(r.baseline)
         << (r.options.colour ? ", \"colour\": " + tallyJson(r.colour) : std::string()) << ", \"by_dataset\": [";
    for (std::size_t i = 0; i < r.byDataset.size(); ++i) {
        const auto& [name, tallies] = r.byDataset[i];
        json << (i == 0 ? "" : ", ") << "{\"dataset\": " << jsonString(name) << ", \"ours\": " << tallyJson(tallies[0])
             << ", \"opencv\": " << tallyJson(tallies[1]) << "}";
    }
    json << "]}";
}

/// Every pair of `index` whose truth can be read (each once, on its first GT row) into `r`.
/// @return 0, or runRealPair's error code.
int runRealPairs(const std::vector<RealPair>& index, RealRun& r, std::ostringstream& json)
{
    std::vector<std::string> done; // index.csv has a row per GT file: a pair is scored once, on its first (noc)
    for (const RealPair& pair : index) {
        if (std::find(done.begin(), done.end(), pair.name) != done.end()) {
            continue;
        }
        done.push_back(pair.name);
        if (!r.options.pairs.empty() &&
            std::find(r.options.pairs.begin(), r.options.pairs.end(), pair.name) == r.options.pairs.end()) {
            continue;
        }
        if (pair.format.rfind("uint16 PNG", 0) != 0 && !isPfmPair(pair)) {
            if (!r.quiet) {
                std::printf("%-12s skipped: its GT is neither KITTI's 16-bit PNG nor Middlebury's PFM\n",
                            pair.name.c_str());
            }
            continue;
        }
        if (const int rc = runRealPair(pair, r, json); rc != 0) {
            return rc;
        }
    }
    return 0;
}

/// A condition's totals, for the table of several.
struct ConditionTotals {
    std::string name;
    RealTally ours;
    RealTally baseline;
    bool failed = false; ///< a pair could not be run under it (its error printed above)
};

/// The table of several conditions' totals; closes `json`'s "real" object with them.
void reportConditions(const std::vector<ConditionTotals>& all, std::ostringstream& json)
{
    std::printf("\nUnder each condition (ours against OpenCV StereoSGBM + RANSAC ground + 0.25 m, the same changed "
                "images, the same truth; drops: negative sectors on pairs without a drop):\n%-24s | %-31s | %-31s | "
                "%s\n",
                "condition", "ours: correct near+false drops", "opencv: correct near+false drops", "ours no worse");
    json << "\n  ], \"conditions\": [";
    bool first = true;
    for (const ConditionTotals& c : all) {
        if (c.failed) {
            std::printf("%-24s | %-31s | %-31s | NO\n", c.name.c_str(), "failed (the error above)", "");
            json << (first ? "\n" : ",\n") << "    {\"condition\": \"" << c.name << "\", \"failed\": true}";
            first = false;
            continue;
        }
        const bool noWorse = c.ours.correctRate() >= c.baseline.correctRate() &&
                             c.ours.tooNear + c.ours.falseSectors <= c.baseline.tooNear + c.baseline.falseSectors &&
                             c.ours.negativeNoDrop <= c.baseline.negativeNoDrop;
        std::printf("%-24s |    %5.1f %%   %5.1f %%  %5d |      %5.1f %%   %5.1f %%  %5d | %s\n", c.name.c_str(),
                    100.0 * c.ours.correctRate(), 100.0 * c.ours.wrongRate(), c.ours.negativeNoDrop,
                    100.0 * c.baseline.correctRate(), 100.0 * c.baseline.wrongRate(), c.baseline.negativeNoDrop,
                    noWorse ? "yes" : "NO");
        json << (first ? "\n" : ",\n") << "    {\"condition\": \"" << c.name << "\", \"ours\": " << tallyJson(c.ours)
             << ", \"opencv\": " << tallyJson(c.baseline) << ", \"ours_no_worse\": " << (noWorse ? "true" : "false")
             << "}";
        first = false;
    }
    json << "\n  ]}";
}

} // namespace

cv::Mat readPfmDisparity(const std::filesystem::path& path, cv::Size size, std::string& why)
{
    std::ifstream in(path, std::ios::binary);
    std::string magic;
    int width = 0;
    int height = 0;
    double scale = 0.0;
    if (!(in >> magic >> width >> height >> scale) || magic != "Pf" || in.get() != '\n') {
        why = "not a one-channel PFM (\"Pf\", width, height, scale, then the data)";
        return {};
    }
    if (width != size.width || height != size.height) {
        why = "a PFM of " + std::to_string(width) + "x" + std::to_string(height) + ", the index says " +
              std::to_string(size.width) + "x" + std::to_string(size.height);
        return {};
    }
    if (!(scale < 0.0)) {
        why = "a big-endian PFM (positive scale): only little-endian ones are read";
        return {};
    }
    cv::Mat raw(height, width, CV_32F);
    const auto bytes = static_cast<std::streamsize>(raw.total() * raw.elemSize());
    if (!in.read(reinterpret_cast<char*>(raw.data), bytes)) {
        why = "the PFM is truncated: " + std::to_string(in.gcount()) + " of " + std::to_string(bytes) + " data bytes";
        return {};
    }
    static_assert(std::endian::native == std::endian::little, "the PFM reader assumes a little-endian host");
    cv::Mat out;
    cv::flip(raw, out, 0); // bottom-up rows
    return out;
}

int runRealEval(const RealEvalOptions& options, std::ostringstream& json)
{
    auto index = readIndex(options.dir);
    if (!index) {
        std::cerr << "ugvsense eval: error: " << index.error().message() << '\n';
        return 1;
    }
    std::optional<RealMount> mount;
    if (!options.mount.empty()) {
        auto parsed = parseMount(options.mount);
        if (!parsed) {
            std::cerr << "ugvsense eval: error: " << parsed.error().message() << '\n';
            return 2;
        }
        mount = *parsed;
        const bool anyMounted = std::any_of(index->begin(), index->end(),
                                            [&](const RealPair& pair) { return mount->appliesTo(pair.dataset); });
        if (!anyMounted) {
            std::cerr << "ugvsense eval: warning: --mount " << options.mount << ": no pair of " << options.dir.string()
                      << "/index.csv is of a data set named '" << mount->dataset
                      << "...' (its dataset column), so every ground is found\n";
        }
    }
    const std::vector<Perturbation> conditions =
        options.perturbations.empty() ? std::vector<Perturbation>{Perturbation{}} : options.perturbations;
    const bool several = conditions.size() > 1;
    std::printf("\nReal pairs (%s), ground %s: obstacle sectors (GT 0.25-2.5 m above the GT road within 25 m) right "
                "within max(1 m, 10 %%); ours against OpenCV StereoSGBM + RANSAC ground + 0.25 m threshold\n",
                options.dir.string().c_str(),
                mount ? ("of the mount " + options.mount).c_str() : "found (no mount given)");
    json << "  \"real\": {\"mount\": \"" << (mount ? options.mount : "found") << "\", \"pairs\": [";
    std::vector<ConditionTotals> totals;
    for (const Perturbation& condition : conditions) {
        RealRun r{options, mount, detectorConfig(DetectionOptions{}), RealScoringRules{}, condition, several, {}, {},
                  {},      {}};
        r.config.matcher.groundRange = options.groundRange;
        r.config.matcher.groundPrior = options.groundPrior;
        r.config.halfResolutionMinGroundPx = options.halfResPx;
        r.config.sectors.maxRangeDisparityPx = static_cast<float>(options.maxRangePx);
        if (several || condition.name != "none") {
            std::printf("condition %s\n", condition.name.c_str());
        }
        if (!several) {
            std::printf("%-12s %5s | %-46s | %-19s\n", "pair", "gt", "ours: correct missed near false neg, ground",
                        "opencv: same");
        }
        std::ostringstream pairs; // several: each condition's pairs are left out of the JSON (its totals go in)
        const int rc = runRealPairs(*index, r, several ? pairs : json);
        if (!several) {
            if (rc == 0) {
                reportRealTotals(r, json);
            }
            return rc;
        }
        if (rc != 0) { // the others still run: one condition that breaks a pair is a finding, not the end
            totals.push_back({condition.name, {}, {}, true});
            continue;
        }
        printTally("  ours", r.ours);
        printTally("  opencv", r.baseline);
        totals.push_back({condition.name, r.ours, r.baseline, false});
    }
    reportConditions(totals, json);
    const bool anyFailed = std::any_of(totals.begin(), totals.end(), [](const ConditionTotals& c) { return c.failed; });
    return anyFailed ? 1 : 0;
}

} // namespace ugv::tool
