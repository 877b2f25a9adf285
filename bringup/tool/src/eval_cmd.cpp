// ugvsense eval: (a) --sim: obstacle detection on simulator scenes against the exact ground-truth sectors
// (bringup/sim/README.md); (b) --middlebury: our matcher and OpenCV's default StereoSGBM against Middlebury ground
// truth (../shared/data, or $UGV_SHARED_DATA, or --data DIR); (c) --approach: how far ahead each obstacle type is
// seen as it comes nearer; (d) --hole-signal: how much of a far hole the images themselves show.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"
#include "ugv/tool/detection.hpp"
#include "ugv/tool/eval_suite.hpp"
#include "ugv/tool/pair_files.hpp"
#include "ugv/tool/real_eval.hpp"
#include "ugv/vision/colour_free_space.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/matcher_mode.hpp"
#include "ugv/vision/obstacle_detector.hpp"
#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/roi_matcher.hpp"
#include "ugv/vision/sector_builder.hpp"

namespace ugv::tool {
namespace {

constexpr int kExitSkipped = 77; ///< ctest SKIP_RETURN_CODE
constexpr double kTargetDetection = 0.95;
constexpr double kTargetFalseRate = 0.01;
constexpr double kTargetWithinTolerance = 0.95; ///< p95 of the range error within the tolerance
constexpr double kVerdictMaxRangeM = 10.0;      ///< [m] targets apply to 1-10 m

struct Band {
    double lo; ///< [m]
    double hi; ///< [m]
};
constexpr Band kBands[] = {{1.0, 3.0}, {3.0, 6.0}, {6.0, 10.0}, {10.0, 15.0}};
constexpr int kBandCount = 4;
constexpr int kTypeColumn = 12;       ///< [chars] type column of the obstacle tables
constexpr int kGroundTypeColumn = 23; ///< [chars] "ground/type" column of the new grounds' obstacle table

struct BandStats {
    int frames = 0;
    int gtFrames = 0; ///< frames whose GT has an obstacle sector
    int detected = 0;
    std::vector<double> errors; ///< [m] range errors of detected frames
    int withinTolerance = 0;
    int spill = 0;      ///< sectors reported Obstacle whose GT is not Obstacle (fattening, artefacts)
    int falseClear = 0; ///< sectors reported Clear whose GT has an obstacle within 10 m
    [[nodiscard]] double rate() const { return gtFrames > 0 ? static_cast<double>(detected) / gtFrames : 0.0; }
    [[nodiscard]] double withinRate() const
    {
        return detected > 0 ? static_cast<double>(withinTolerance) / detected : 0.0;
    }
};

struct SimOptions {
    std::vector<sim::GroundTexture> textures;
    std::vector<double> rangesPerBand; ///< fractions of each band's width
    std::vector<double> bearings;      ///< [deg]
    int seeds = 1;
    int emptySeeds = 10;
    std::vector<sim::GroundTexture> emptyTextures = {sim::GroundTexture::Asphalt, sim::GroundTexture::Grass,
                                                     sim::GroundTexture::Gravel, sim::GroundTexture::PaintedFloor};
    std::vector<double> doorwayRanges;                            ///< [m]
    std::vector<double> overhangRanges;                           ///< [m]
    std::vector<std::string> types;                               ///< obstacle types to run (empty: all)
    std::vector<std::string> groundKinds = sim::conditionNames(); ///< the new grounds (sim::applyCondition)
    int groundSeeds = 6;                                          ///< empty scenes per ground kind (variants cycle)
    std::vector<std::string> obstacleGrounds = {"camber", "paint", "shadow", "glossy"}; ///< obstacles run over these
    std::vector<double> groundRanges = {1.5, 2.5, 3.75, 5.25, 7.0, 9.0};                ///< [m] ... at these ranges
    vision::MatcherMode matcher = vision::MatcherMode::CensusSgm;
    bool groundPrior = false; ///< RoiMatcherConfig::groundPrior
    bool groundRange = false; ///< RoiMatcherConfig::groundRange
    bool colour = false;      ///< --detector colour: ColourFreeSpace on the left colour image, not stereo
    double halfResPx = vision::DetectorConfig{}.halfResolutionMinGroundPx; ///< --half-res
    double maxRangePx = vision::SectorBuilderConfig{}.maxRangeDisparityPx; ///< --max-range-px
};

const char* textureName(sim::GroundTexture t)
{
    switch (t) {
    case sim::GroundTexture::Grass:
        return "grass";
    case sim::GroundTexture::Gravel:
        return "gravel";
    case sim::GroundTexture::PaintedFloor:
        return "floor";
    case sim::GroundTexture::Asphalt:
        break;
    }
    return "asphalt";
}

/// One detector for the default rig (level, 0.59 m), fed with rendered frames; the ground prior is the rig mount.
/// The stereo detector on the grey pair, or (colour) the one-camera ColourFreeSpace on the left colour image, with
/// the same sector layout and the same mount.
class SimDetector {
public:
    static Result<SimDetector, Error> create(vision::MatcherMode matcher, bool groundPrior, bool groundRange,
                                             bool colour, double halfResPx, double maxRangePx)
    {
        const sim::Rig rig;
        vision::StereoCalibration calib = vision::makeRectifiedCalibration(
            cv::Size(rig.width, rig.height), rig.focalPx, rig.focalPx, rig.cx(), rig.cy(), rig.baselineM);
        calib.mount = vision::Mount{rig.heightM, rig.pitchDeg, rig.rollDeg};
        vision::DetectorConfig config = detectorConfig(DetectionOptions{});
        config.matcher.mode = matcher;
        config.matcher.groundPrior = groundPrior;
        config.matcher.groundRange = groundRange;
        config.halfResolutionMinGroundPx = halfResPx;
        config.sectors.maxRangeDisparityPx = static_cast<float>(maxRangePx);
        auto rectifier = vision::Rectifier::create(calib, vision::roiRectifierConfig(config));
        if (!rectifier) {
            return Unexpected(rectifier.error());
        }
        const vision::GroundPlane mountGround = vision::GroundPlane::fromMount(*calib.mount);
        auto detector = vision::ObstacleDetector::create(config, *rectifier, mountGround);
        if (!detector) {
            return Unexpected(detector.error());
        }
        const vision::DisparityPlane ground = mountGround.disparityPlane(rectifier->projection());
        std::optional<vision::ColourFreeSpace> colourFreeSpace;
        if (colour) {
            auto made =
                vision::ColourFreeSpace::create(vision::colourConfigFor(config.sectors),
                                                cv::Size(rig.width, rig.height), rectifier->projection(), mountGround);
            if (!made) {
                return Unexpected(made.error());
            }
            colourFreeSpace = std::move(made).value();
        }
        return SimDetector(std::move(rectifier).value(), std::move(detector).value(), ground,
                           std::move(colourFreeSpace));
    }

    /// Renders `scene` and runs the detector on it; false when rendering or detection failed.
    bool run(const sim::Scene& scene, sim::RenderResult& rendered)
    {
        auto result = colour_ ? renderColour(scene) : sim::render(scene);
        if (!result) {
            std::cerr << "ugvsense eval: error: " << result.error().message() << '\n';
            return false;
        }
        rendered = std::move(result).value();
        if (colour_) {
            ++frames_;
            const bool ok =
                colour_->process(bgrViewOf(rendered.leftColour), colourSectors_) == vision::ColourFreeSpaceStatus::Ok;
            notGroundLike_ += colour_->reference().groundLike ? 0 : 1;
            return ok;
        }
        if (rectifier_.rectify(viewOf(rendered.left), viewOf(rendered.right)) != vision::RectifyStatus::Ok) {
            return false;
        }
        (void)detector_.process(rectifier_.rectifiedLeft(), rectifier_.rectifiedRight(), frames_++, 0);
        searchedSum_ += detector_.searchedFraction();
        return detector_.status() == vision::DetectorStatus::Ok;
    }
    [[nodiscard]] const ObstacleSectors& sectors() const { return colour_ ? colourSectors_ : detector_.sectors(); }
    /// Colour detector: frames so far whose reference band was not ground-like (all sectors Unknown).
    [[nodiscard]] int notGroundLikeFrames() const { return notGroundLike_; }
    /// The rig's ground (its mount) as a disparity model of the rectified left image.
    [[nodiscard]] const vision::DisparityPlane& ground() const { return ground_; }
    /// Frames run so far (each one rendered and detected).
    [[nodiscard]] std::uint64_t frames() const { return frames_; }
    /// The matcher's cost cells searched over those of the full range, mean over the frames run so far.
    [[nodiscard]] double meanSearchedFraction() const
    {
        return frames_ > 0 ? searchedSum_ / static_cast<double>(frames_) : 1.0;
    }
    /// [s] since the detector was made.
    [[nodiscard]] double seconds() const
    {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }

private:
    /// The scene with a lawn of its own per frame (Scene::colourSeed): the ground's texture is fixed in the world and
    /// the reference band sees the same piece of it in every scene, so without this all grass frames would judge one
    /// hue pattern.
    Result<sim::RenderResult, Error> renderColour(const sim::Scene& scene) const
    {
        sim::Scene lawn = scene;
        lawn.colourSeed = static_cast<std::uint32_t>(frames_);
        return sim::render(lawn);
    }
    SimDetector(vision::Rectifier rectifier, vision::ObstacleDetector detector, const vision::DisparityPlane& ground,
                std::optional<vision::ColourFreeSpace> colour)
        : rectifier_(std::move(rectifier)), detector_(std::move(detector)), ground_(ground), colour_(std::move(colour))
    {
    }
    vision::Rectifier rectifier_;
    vision::ObstacleDetector detector_;
    vision::DisparityPlane ground_;
    std::optional<vision::ColourFreeSpace> colour_;
    ObstacleSectors colourSectors_;
    int notGroundLike_ = 0;
    std::uint64_t frames_ = 0;
    double searchedSum_ = 0.0; ///< sum of ObstacleDetector::searchedFraction over the frames
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

bool honoursBearing(const std::string& type)
{
    return type != "curb" && type != "trench"; // they run across the whole view
}

/// The obstacle types to run: every scene but the empty ground and the overhang, or those of --types.
std::vector<std::string> obstacleTypes(const SimOptions& o)
{
    std::vector<std::string> types;
    for (const std::string& name : sim::sceneNames()) {
        if (name != "empty" && name != "overhang" &&
            (o.types.empty() || std::find(o.types.begin(), o.types.end(), name) != o.types.end())) {
            types.push_back(name);
        }
    }
    return types;
}

/// A fresh detector for a run (the ground estimate's smoothing starts anew); prints the error when it cannot be made.
std::optional<SimDetector> makeSimDetector(const SimOptions& o)
{
    auto detector = SimDetector::create(o.matcher, o.groundPrior, o.groundRange, o.colour, o.halfResPx, o.maxRangePx);
    if (!detector) {
        std::cerr << "ugvsense eval: error: " << detector.error().message() << '\n';
        return std::nullopt;
    }
    return std::move(detector).value();
}

/// One obstacle case of the suite: a catalogue scene, optionally over one of the new grounds.
struct ObstacleCase {
    std::string type;
    double rangeM;     ///< [m]
    double bearingDeg; ///< [deg] (ignored by the types that run across the view)
    sim::GroundTexture texture;
    std::string ground; ///< sim::applyCondition name; empty: none
    int variant;
    std::optional<sim::Chroma> chroma = std::nullopt; ///< the obstacle's colour; nullopt: its kind's default
};

/// The band of kBands holding `rangeM`, or -1.
int bandOf(double rangeM)
{
    for (int b = 0; b < kBandCount; ++b) {
        if (rangeM >= kBands[b].lo && rangeM < kBands[b].hi) {
            return b;
        }
    }
    return -1;
}

/// Renders and detects the case for every seed and adds its scores to its band in `stats` (kBandCount entries).
/// @return false on a render/detector failure (printed).
bool runObstacleCase(const SimOptions& o, SimDetector& det, const ObstacleCase& c, std::vector<BandStats>& stats)
{
    sim::RenderResult frame;
    for (int seed = 1; seed <= o.seeds; ++seed) {
        auto scene = sim::makeScene(c.type, c.rangeM, honoursBearing(c.type) ? c.bearingDeg : 0.0, c.texture,
                                    static_cast<std::uint64_t>(seed));
        const bool made = scene.has_value() && (c.ground.empty() || sim::applyCondition(*scene, c.ground, c.variant));
        if (made && c.chroma) {
            for (sim::Obstacle& obstacle : scene->obstacles) {
                obstacle.chroma = c.chroma;
            }
        }
        if (!made || !det.run(*scene, frame)) {
            std::cerr << "ugvsense eval: error: scene " << c.type << (c.ground.empty() ? "" : " over " + c.ground)
                      << " failed\n";
            return false;
        }
        const int band = bandOf(c.rangeM);
        if (band < 0) {
            continue;
        }
        const ObstacleFrameScore score = scoreObstacleFrame(det.sectors(), frame.sectors);
        BandStats& s = stats[static_cast<std::size_t>(band)];
        ++s.frames;
        s.spill += score.spillSectors;
        s.falseClear += score.falseClearSectors;
        s.gtFrames += score.gtHasObstacle ? 1 : 0;
        if (score.gtHasObstacle && score.detected) {
            ++s.detected;
            s.errors.push_back(score.rangeErrorM);
            s.withinTolerance += score.rangeErrorM <= rangeTolerance(score.gtRangeM) ? 1 : 0;
        }
    }
    return true;
}

/// Prints the band rows of one obstacle type (over `ground`, empty: the plain ground) and its 1-10 m verdict line,
/// and appends a JSON object per band (the keys of "obstacles"; "ground" added when there is one).
/// @return the sums over the bands within kVerdictMaxRangeM.
BandStats printTypeRows(const std::string& type, const std::string& ground, const std::vector<BandStats>& stats,
                        std::ostringstream& json, bool& firstRow)
{
    const std::string label = ground.empty() ? type : ground + "/" + type;
    const int width = ground.empty() ? kTypeColumn : kGroundTypeColumn;
    BandStats within10;
    for (int b = 0; b < kBandCount; ++b) {
        const BandStats& s = stats[static_cast<std::size_t>(b)];
        if (!ground.empty() && s.frames == 0) {
            continue; // the grounds run a few ranges only
        }
        char band[40];
        (void)std::snprintf(band, sizeof(band), "%g-%g m", kBands[b].lo, kBands[b].hi);
        const double p95 = quantile(s.errors, 0.95);
        char p95Text[24] = "-";
        if (!s.errors.empty()) {
            (void)std::snprintf(p95Text, sizeof(p95Text), "%.3f", p95);
        }
        std::printf("%-*s %-8s %6d %6d %8.1f %10s %9.1f %11.2f %11.2f\n", width, label.c_str(), band, s.frames,
                    s.gtFrames, 100.0 * s.rate(), p95Text, 100.0 * s.withinRate(),
                    s.frames > 0 ? static_cast<double>(s.spill) / s.frames : 0.0,
                    s.frames > 0 ? static_cast<double>(s.falseClear) / s.frames : 0.0);
        json << (firstRow ? "\n" : ",\n") << "      {"
             << (ground.empty() ? std::string() : "\"ground\": \"" + ground + "\", ") << "\"type\": \"" << type
             << "\", \"band\": \"" << band << "\", \"frames\": " << s.frames << ", \"gt_frames\": " << s.gtFrames
             << ", \"detected\": " << s.detected << ", \"detection_rate\": " << jsonNumber(s.rate())
             << ", \"range_error_p95_m\": " << jsonNumber(s.errors.empty() ? NAN : p95)
             << ", \"within_tolerance_rate\": " << jsonNumber(s.withinRate()) << ", \"spill_sectors\": " << s.spill
             << ", \"false_clear_sectors\": " << s.falseClear << "}";
        firstRow = false;
        if (kBands[b].hi <= kVerdictMaxRangeM) {
            within10.gtFrames += s.gtFrames;
            within10.detected += s.detected;
            within10.withinTolerance += s.withinTolerance;
        }
    }
    const bool detects = within10.gtFrames > 0 && within10.rate() >= kTargetDetection;
    const bool inRange = within10.detected > 0 && within10.withinRate() >= kTargetWithinTolerance;
    std::printf("%-*s 1-10 m   detection %5.1f%% %-4s range within tolerance %5.1f%% %s\n", width, label.c_str(),
                100.0 * within10.rate(), detects ? "PASS" : "FAIL", 100.0 * within10.withinRate(),
                inRange ? "PASS" : "FAIL");
    return within10;
}

/// What the detector reports wrongly on a new ground with no obstacle (the truth may still hold a kerb).
struct GroundEmptyStats {
    int frames = 0;
    int falseFrames = 0;   ///< frames with a false red/blue sector
    int falseRedBlue = 0;  ///< sectors reported red/blue whose truth is neither
    int falseObstacle = 0; ///< sectors reported Obstacle whose truth is not
    int gtObstacle = 0;    ///< sectors whose truth is Obstacle (the kerb)
    int missed = 0;        ///< of those, not reported Obstacle
};

void scoreGroundFrame(const ObstacleSectors& detected, const ObstacleSectors& gt, GroundEmptyStats& s)
{
    const auto redBlue = [](const Sector& x) { return x.danger == DangerClass::Red || x.danger == DangerClass::Blue; };
    int falseRedBlue = 0;
    for (int i = 0; i < std::min(detected.count, gt.count); ++i) {
        const Sector& d = detected.sectors[static_cast<std::size_t>(i)];
        const Sector& g = gt.sectors[static_cast<std::size_t>(i)];
        falseRedBlue += redBlue(d) && !redBlue(g) ? 1 : 0;
        s.falseObstacle += d.state == SectorState::Obstacle && g.state != SectorState::Obstacle ? 1 : 0;
        s.gtObstacle += g.state == SectorState::Obstacle ? 1 : 0;
        s.missed += g.state == SectorState::Obstacle && d.state != SectorState::Obstacle ? 1 : 0;
    }
    ++s.frames;
    s.falseRedBlue += falseRedBlue;
    s.falseFrames += falseRedBlue > 0 ? 1 : 0;
}

/// The new grounds (issue 20): (a) empty scenes over each kind, several seeds cycling its settings; (b) the obstacle
/// types over a selection of them, scored as the main table. Appends the "grounds" object to `json`.
/// @return 0 when everything ran, 1 on a render/detector failure.
int runGroundsSuite(const SimOptions& o, SimDetector& det, std::ostringstream& json)
{
    const std::uint64_t framesBefore = det.frames();
    const double secondsBefore = det.seconds();
    std::printf("\nnew grounds, empty scenes (%d seed(s) per kind, its settings cycling over the seeds): false = "
                "reported red/blue (or Obstacle) where the truth is not; target 0\n",
                o.groundSeeds);
    std::printf("%-12s %6s %9s %9s %9s %8s %8s\n", "ground", "frames", "false_frm", "false_rb", "false_obs", "gt_obs",
                "missed");
    json << ",\n    \"grounds\": {\n      \"empty\": [";
    sim::RenderResult frame;
    for (std::size_t k = 0; k < o.groundKinds.size(); ++k) {
        const std::string& kind = o.groundKinds[k];
        GroundEmptyStats s;
        for (int seed = 1; seed <= o.groundSeeds; ++seed) {
            auto scene =
                sim::makeScene("empty", 5.0, 0.0, sim::GroundTexture::Asphalt, static_cast<std::uint64_t>(seed));
            if (!scene || !sim::applyCondition(*scene, kind, seed - 1) || !det.run(*scene, frame)) {
                std::cerr << "ugvsense eval: error: empty scene over " << kind << " failed\n";
                return 1;
            }
            scoreGroundFrame(det.sectors(), frame.sectors, s);
        }
        std::printf("%-12s %6d %9d %9d %9d %8d %8d %s\n", kind.c_str(), s.frames, s.falseFrames, s.falseRedBlue,
                    s.falseObstacle, s.gtObstacle, s.missed,
                    s.falseRedBlue == 0 && s.falseObstacle == 0 ? "PASS" : "FAIL");
        json << (k == 0 ? "\n" : ",\n") << "        {\"ground\": \"" << kind << "\", \"frames\": " << s.frames
             << ", \"false_frames\": " << s.falseFrames << ", \"false_red_blue_sectors\": " << s.falseRedBlue
             << ", \"false_obstacle_sectors\": " << s.falseObstacle << ", \"gt_obstacle_sectors\": " << s.gtObstacle
             << ", \"missed_sectors\": " << s.missed << "}";
    }
    std::printf("\nobstacles over new grounds (ranges");
    for (const double r : o.groundRanges) {
        std::printf(" %g", r);
    }
    std::printf(" m, bearings taking turns, %d seed(s)):\n", o.seeds);
    std::printf("%-*s %-8s %6s %6s %8s %10s %9s %11s %11s\n", kGroundTypeColumn, "ground/type", "band", "frames", "gt",
                "det%", "p95err_m", "in_tol%", "spill/frame", "fclear/frm");
    json << "\n      ],\n      \"obstacles\": [";
    bool firstRow = true;
    for (const std::string& ground : o.obstacleGrounds) {
        for (const std::string& type : obstacleTypes(o)) {
            std::vector<BandStats> stats(kBandCount);
            for (std::size_t i = 0; i < o.groundRanges.size(); ++i) {
                const ObstacleCase c{
                    type,   o.groundRanges[i],  o.bearings[i % o.bearings.size()], sim::GroundTexture::Asphalt,
                    ground, static_cast<int>(i)};
                if (!runObstacleCase(o, det, c, stats)) {
                    return 1;
                }
            }
            (void)printTypeRows(type, ground, stats, json, firstRow);
        }
    }
    const auto frames = static_cast<int>(det.frames() - framesBefore);
    const double seconds = det.seconds() - secondsBefore;
    std::printf("new grounds: %d frames in %.1f s\n", frames, seconds);
    json << "\n      ],\n      \"frames\": " << frames << ",\n      \"seconds\": " << jsonNumber(seconds) << "\n    }";
    return 0;
}

/// Issue 23's targets for the one-camera mode: each positive obstacle type detected in >= 90 % of its frames at
/// 1-6 m on every ground; <= 2 % of the sectors of empty ground reported Obstacle.
constexpr double kColourTargetDetection = 0.90;
constexpr double kColourTargetFalseSectors = 0.02;
constexpr double kColourMaxRangeM = 6.0; ///< [m]
constexpr int kColourLabelColumn = 18;   ///< [chars]

bool isNegativeType(const std::string& type)
{
    return type == "trench" || type == "hole" || type == "hole_square";
}

/// One row of the one-camera table: an obstacle type, or the box painted the ground's own colour.
struct ColourRow {
    std::string label;
    std::string type;
    bool groundColoured; ///< the obstacle takes the ground's chroma (the hard case)
};

/// One row on one ground at 1-6 m, printed and into `json`. nullopt on a render/detector failure, else whether the
/// row meets the detection target (true for a negative type, which has none).
std::optional<bool> runColourRow(const SimOptions& o, SimDetector& det, sim::GroundTexture texture,
                                 const ColourRow& row, std::ostringstream& json, bool& firstRow)
{
    std::vector<BandStats> stats(kBandCount);
    const int refBefore = det.notGroundLikeFrames();
    std::size_t cases = 0;
    for (int b = 0; b < kBandCount && kBands[b].hi <= kColourMaxRangeM; ++b) {
        for (const double fraction : o.rangesPerBand) {
            const double range = kBands[b].lo + fraction * (kBands[b].hi - kBands[b].lo);
            const double bearing = o.bearings[cases++ % o.bearings.size()];
            const ObstacleCase c{row.type,
                                 range,
                                 bearing,
                                 texture,
                                 "",
                                 0,
                                 row.groundColoured ? std::optional(sim::groundChroma(texture)) : std::nullopt};
            if (!runObstacleCase(o, det, c, stats)) {
                return std::nullopt;
            }
        }
    }
    const int refBad = det.notGroundLikeFrames() - refBefore;
    BandStats all;
    for (int b = 0; b < kBandCount && kBands[b].hi <= kColourMaxRangeM; ++b) {
        const BandStats& s = stats[static_cast<std::size_t>(b)];
        all.frames += s.frames;
        all.gtFrames += s.gtFrames;
        all.detected += s.detected;
        all.spill += s.spill;
        all.falseClear += s.falseClear;
        all.errors.insert(all.errors.end(), s.errors.begin(), s.errors.end());
    }
    const bool target = !isNegativeType(row.type);
    const bool pass = all.gtFrames > 0 && all.rate() >= kColourTargetDetection;
    char p95Text[24] = "-";
    if (!all.errors.empty()) {
        (void)std::snprintf(p95Text, sizeof(p95Text), "%.3f", quantile(all.errors, 0.95));
    }
    std::printf("%-*s %-8s %6d %6d %7.1f %7.1f %7.1f %10s %7d %11.2f %11.2f %s\n", kColourLabelColumn,
                row.label.c_str(), textureName(texture), all.frames, all.gtFrames, 100.0 * stats[0].rate(),
                100.0 * stats[1].rate(), 100.0 * all.rate(), p95Text, refBad,
                all.frames > 0 ? static_cast<double>(all.spill) / all.frames : 0.0,
                all.frames > 0 ? static_cast<double>(all.falseClear) / all.frames : 0.0,
                target ? (pass ? "PASS" : "FAIL") : "(negative: no target)");
    json << (firstRow ? "\n" : ",\n") << "      {\"type\": \"" << row.label << "\", \"ground\": \""
         << textureName(texture) << "\", \"frames\": " << all.frames << ", \"gt_frames\": " << all.gtFrames
         << ", \"detected\": " << all.detected << ", \"detection_rate_1_3\": " << jsonNumber(stats[0].rate())
         << ", \"detection_rate_3_6\": " << jsonNumber(stats[1].rate())
         << ", \"detection_rate\": " << jsonNumber(all.rate())
         << ", \"range_error_p95_m\": " << jsonNumber(all.errors.empty() ? NAN : quantile(all.errors, 0.95))
         << ", \"reference_not_ground_like_frames\": " << refBad << ", \"spill_sectors\": " << all.spill
         << ", \"false_clear_sectors\": " << all.falseClear << ", \"target\": " << (target ? "true" : "false") << "}";
    firstRow = false;
    return !target || pass;
}

/// Empty `texture` ground: every sector reported Obstacle is false. Printed and into `json`; nullopt on a
/// render/detector failure, else whether the false sectors are within the target.
std::optional<bool> runColourEmpty(const SimOptions& o, SimDetector& det, sim::GroundTexture texture, bool first,
                                   std::ostringstream& json)
{
    sim::RenderResult frame;
    const int refBefore = det.notGroundLikeFrames();
    int frames = 0;
    int sectors = 0;
    int falseObstacle = 0;
    int unknown = 0;
    int clear = 0;
    for (int seed = 1; seed <= o.emptySeeds; ++seed) {
        auto scene = sim::makeScene("empty", 5.0, 0.0, texture, static_cast<std::uint64_t>(seed));
        if (!scene || !det.run(*scene, frame)) {
            return std::nullopt;
        }
        ++frames;
        for (int i = 0; i < det.sectors().count; ++i) {
            const SectorState state = det.sectors().sectors[static_cast<std::size_t>(i)].state;
            const bool gtObstacle = frame.sectors.sectors[static_cast<std::size_t>(i)].state == SectorState::Obstacle;
            ++sectors;
            falseObstacle += state == SectorState::Obstacle && !gtObstacle ? 1 : 0;
            unknown += state == SectorState::Unknown ? 1 : 0;
            clear += state == SectorState::Clear ? 1 : 0;
        }
    }
    const int refBad = det.notGroundLikeFrames() - refBefore;
    const double falseRate = sectors > 0 ? static_cast<double>(falseObstacle) / sectors : 0.0;
    const bool ok = falseRate <= kColourTargetFalseSectors;
    std::printf("%-8s %6d %8d %9d %8.2f %8.1f %8.1f %7d %s\n", textureName(texture), frames, sectors, falseObstacle,
                100.0 * falseRate, sectors > 0 ? 100.0 * unknown / sectors : 0.0,
                sectors > 0 ? 100.0 * clear / sectors : 0.0, refBad, ok ? "PASS" : "FAIL");
    json << (first ? "\n" : ",\n") << "      {\"ground\": \"" << textureName(texture) << "\", \"frames\": " << frames
         << ", \"sectors\": " << sectors << ", \"false_obstacle_sectors\": " << falseObstacle
         << ", \"false_obstacle_rate\": " << jsonNumber(falseRate) << ", \"unknown_sectors\": " << unknown
         << ", \"clear_sectors\": " << clear << ", \"reference_not_ground_like_frames\": " << refBad << "}";
    return ok;
}

/// The one-camera mode (`--detector colour`): ColourFreeSpace on the left colour image, scored by the stereo
/// suite's scorer (scoreObstacleFrame) per obstacle type and ground at 1-6 m, plus the hard case of a box painted
/// the ground's own colour, and the false Obstacle sectors of empty ground. Negative obstacles are listed for
/// information (the target names the positive ones). Appends the "colour" object to `json`.
/// @return 0 when everything ran, 1 on a render/detector failure.
int runColourSuite(const SimOptions& o, std::ostringstream& json)
{
    std::optional<SimDetector> detector = makeSimDetector(o);
    if (!detector) {
        return 1;
    }
    SimDetector& det = *detector;
    std::vector<ColourRow> rows;
    for (const std::string& type : obstacleTypes(o)) {
        rows.push_back({type, type, false});
    }
    rows.push_back({"box_ground_colour", "box", true});
    std::printf("\none-camera mode: ColourFreeSpace on the left colour image, default rig (640x480, level, 0.59 m), "
                "%zu range(s) per band at 1-6 m, %zu bearing(s) taking turns, %d seed(s); the stereo suite's scorer. "
                "ref_bad = frames whose reference band was not ground-like (all Unknown)\n",
                o.rangesPerBand.size(), o.bearings.size(), o.seeds);
    std::printf("%-*s %-8s %6s %6s %7s %7s %7s %10s %7s %11s %11s\n", kColourLabelColumn, "type", "ground", "frames",
                "gt", "det1-3", "det3-6", "det1-6", "p95err_m", "ref_bad", "spill/frame", "fclear/frm");
    json << "  \"colour\": {\n    \"obstacles\": [";
    bool firstRow = true;
    bool detectionOk = true;
    for (const sim::GroundTexture texture : o.textures) {
        for (const ColourRow& row : rows) {
            const auto ok = runColourRow(o, det, texture, row, json, firstRow);
            if (!ok) {
                return 1;
            }
            detectionOk = detectionOk && *ok;
        }
    }
    std::printf("empty ground (%d seed(s) per ground): false = sectors reported Obstacle, of all sectors\n",
                o.emptySeeds);
    std::printf("%-8s %6s %8s %9s %8s %8s %8s %7s\n", "ground", "frames", "sectors", "false_obs", "false%", "unknown%",
                "clear%", "ref_bad");
    json << "\n    ],\n    \"empty\": [";
    bool emptyOk = true;
    for (std::size_t t = 0; t < o.emptyTextures.size(); ++t) {
        const auto ok = runColourEmpty(o, det, o.emptyTextures[t], t == 0, json);
        if (!ok) {
            return 1;
        }
        emptyOk = emptyOk && *ok;
    }
    const int framesRun = static_cast<int>(det.frames());
    const double seconds = det.seconds();
    std::printf("one-camera mode: %d frames in %.1f s\n", framesRun, seconds);
    std::printf("verdicts (one-camera mode): every positive type >= 90%% at 1-6 m on every ground: %s; false obstacle "
                "sectors <= 2%% on empty ground: %s\n",
                detectionOk ? "PASS" : "FAIL", emptyOk ? "PASS" : "FAIL");
    json << "\n    ],\n    \"frames\": " << framesRun << ",\n    \"seconds\": " << jsonNumber(seconds)
         << ",\n    \"verdicts\": {\"detection\": " << (detectionOk ? "true" : "false")
         << ", \"empty_false_sectors\": " << (emptyOk ? "true" : "false") << "}\n  }";
    return 0;
}

/// Every obstacle type at every band's ranges, texture and bearing (taking turns) into `stats` per type and band.
bool runObstacleScenes(const SimOptions& o, SimDetector& det, const std::vector<std::string>& types,
                       std::map<std::string, std::vector<BandStats>>& stats)
{
    for (const std::string& type : types) {
        stats[type].resize(kBandCount);
        std::size_t cases = 0;
        for (int b = 0; b < kBandCount; ++b) {
            for (const double fraction : o.rangesPerBand) {
                const double range = kBands[b].lo + fraction * (kBands[b].hi - kBands[b].lo);
                for (const sim::GroundTexture texture : o.textures) {
                    // The bearings take turns over the cases (not a full product, to keep the run short): each
                    // type and band sees every bearing when cases per band >= bearings.
                    const double bearing = o.bearings[cases++ % o.bearings.size()];
                    if (!runObstacleCase(o, det, ObstacleCase{type, range, bearing, texture, "", 0}, stats[type])) {
                        return false;
                    }
                }
            }
        }
    }
    return true;
}

/// Empty ground: any Red/Blue sector is false.
struct EmptyScore {
    int frames = 0;
    int falseFrames = 0;
    int falseSectors = 0;
    int obstacleSectors = 0; ///< any range: a spurious far obstacle is not red/blue but still wrong
    [[nodiscard]] double falseRate() const { return frames > 0 ? static_cast<double>(falseFrames) / frames : 0.0; }
};

/// Every empty texture, the painted floor too (the weakest texture, where matching noise is worst), whichever
/// textures the obstacles ran on.
bool runEmptyScenes(const SimOptions& o, SimDetector& det, EmptyScore& score)
{
    sim::RenderResult frame;
    for (const sim::GroundTexture texture : o.emptyTextures) {
        for (int seed = 1; seed <= o.emptySeeds; ++seed) {
            auto scene = sim::makeScene("empty", 5.0, 0.0, texture, static_cast<std::uint64_t>(seed));
            if (!scene || !det.run(*scene, frame)) {
                return false;
            }
            ++score.frames;
            const int n = countRedBlue(det.sectors());
            score.falseSectors += n;
            for (int i = 0; i < det.sectors().count; ++i) {
                score.obstacleSectors +=
                    det.sectors().sectors[static_cast<std::size_t>(i)].state == SectorState::Obstacle ? 1 : 0;
            }
            score.falseFrames += n > 0 ? 1 : 0;
        }
    }
    return true;
}

/// Overhang (underside 1.5 m): never red or blue. The frames with a red or blue sector counted.
bool runOverhangScenes(const SimOptions& o, SimDetector& det, int& frames, int& falseFrames)
{
    sim::RenderResult frame;
    for (const sim::GroundTexture texture : o.textures) {
        for (const double range : o.overhangRanges) {
            auto scene = sim::makeScene("overhang", range, 0.0, texture, 1);
            if (!scene || !det.run(*scene, frame)) {
                return false;
            }
            ++frames;
            falseFrames += countRedBlue(det.sectors()) > 0 ? 1 : 0;
        }
    }
    return true;
}

/// Doorway: the GT-clear sectors of the gap must not be reported Obstacle.
struct DoorwayRow {
    double range;
    const char* texture;
    GapScore gap;
};

bool runDoorwayScenes(const SimOptions& o, SimDetector& det, std::vector<DoorwayRow>& doorway)
{
    sim::RenderResult frame;
    for (const sim::GroundTexture texture : o.textures) {
        for (const double range : o.doorwayRanges) {
            auto scene = sim::makeScene("wall_doorway", range, 0.0, texture, 1);
            if (!scene || !det.run(*scene, frame)) {
                return false;
            }
            doorway.push_back({range, textureName(texture), scoreGap(det.sectors(), frame.sectors)});
        }
    }
    return true;
}

/// The doorway rows printed and into `json`; true when every gap was visible.
bool reportDoorways(const std::vector<DoorwayRow>& doorway, std::ostringstream& json)
{
    bool doorwayOk = true;
    json << "\n    ],\n    \"doorway\": [";
    for (std::size_t i = 0; i < doorway.size(); ++i) {
        const DoorwayRow& d = doorway[i];
        std::printf("doorway 0.9 m at %.0f m (%s): %d GT-clear gap sectors: %d reported obstacle (%d inside the "
                    "edge sectors), %d clear -> %s\n",
                    d.range, d.texture, d.gap.gapSectors, d.gap.reportedObstacle, d.gap.innerObstacle,
                    d.gap.reportedClear, d.gap.visible() ? "gap visible" : "GAP NOT VISIBLE");
        doorwayOk = doorwayOk && d.gap.visible();
        json << (i == 0 ? "\n" : ",\n") << "      {\"range_m\": " << d.range << ", \"texture\": \"" << d.texture
             << "\", \"gap_sectors\": " << d.gap.gapSectors << ", \"reported_obstacle\": " << d.gap.reportedObstacle
             << ", \"inner_obstacle\": " << d.gap.innerObstacle << ", \"reported_clear\": " << d.gap.reportedClear
             << ", \"gap_visible\": " << (d.gap.visible() ? "true" : "false") << "}";
    }
    return doorwayOk;
}

/// Runs the simulator suite; prints the table and verdicts and appends the JSON object to `json`.
/// @return 0 when everything ran, 1 on a render/detector failure.
int runSimSuite(const SimOptions& o, std::ostringstream& json)
{
    std::optional<SimDetector> detector = makeSimDetector(o);
    if (!detector) {
        return 1;
    }
    SimDetector& det = *detector;
    const std::vector<std::string> types = obstacleTypes(o);
    std::map<std::string, std::vector<BandStats>> stats;
    EmptyScore empty;
    int overhangFrames = 0;
    int overhangFalseFrames = 0;
    std::vector<DoorwayRow> doorway;
    if (!runObstacleScenes(o, det, types, stats) || !runEmptyScenes(o, det, empty) ||
        !runOverhangScenes(o, det, overhangFrames, overhangFalseFrames) || !runDoorwayScenes(o, det, doorway)) {
        return 1;
    }
    const double seconds = det.seconds();
    const int framesRun = static_cast<int>(det.frames());

    // Table and verdicts.
    std::printf("\nsimulator suite: %d frames in %.1f s (default rig 640x480, level, 0.59 m; %zu texture(s), %zu "
                "range(s) per band, %zu bearing(s) taking turns, %d seed(s))\n",
                framesRun, seconds, o.textures.size(), o.rangesPerBand.size(), o.bearings.size(), o.seeds);
    std::printf("%-12s %-8s %6s %6s %8s %10s %9s %11s %11s\n", "type", "band", "frames", "gt", "det%", "p95err_m",
                "in_tol%", "spill/frame", "fclear/frm");
    bool detectionOk = true;
    bool rangeOk = true;
    json << "  \"sim\": {\n    \"frames\": " << framesRun << ",\n    \"seconds\": " << jsonNumber(seconds)
         << ",\n    \"obstacles\": [";
    bool firstRow = true;
    for (const std::string& type : types) {
        const BandStats within10 = printTypeRows(type, "", stats[type], json, firstRow);
        detectionOk = detectionOk && within10.gtFrames > 0 && within10.rate() >= kTargetDetection;
        rangeOk = rangeOk && within10.detected > 0 && within10.withinRate() >= kTargetWithinTolerance;
    }
    const bool emptyOk = empty.falseRate() < kTargetFalseRate;
    std::printf("empty ground: %d frames, %d with a false red/blue sector (%.2f%%), %.3f false red/blue sectors and "
                "%.3f obstacle sectors at any range per frame\n",
                empty.frames, empty.falseFrames, 100.0 * empty.falseRate(),
                empty.frames > 0 ? static_cast<double>(empty.falseSectors) / empty.frames : 0.0,
                empty.frames > 0 ? static_cast<double>(empty.obstacleSectors) / empty.frames : 0.0);
    std::printf("overhang (underside 1.5 m): %d frames, %d with a red/blue sector -> %s\n", overhangFrames,
                overhangFalseFrames, overhangFalseFrames == 0 ? "PASS" : "FAIL");
    const bool doorwayOk = reportDoorways(doorway, json);
    std::printf("verdicts: detection >= 95%% 1-10 m per type: %s; false red/blue on empty ground < 1%%: %s; range "
                "error within max(0.10 m, 3%%) at p95 within 10 m: %s; overhang: %s; doorway gap: %s\n",
                detectionOk ? "PASS" : "FAIL", emptyOk ? "PASS" : "FAIL", rangeOk ? "PASS" : "FAIL",
                overhangFalseFrames == 0 ? "PASS" : "FAIL", doorwayOk ? "PASS" : "FAIL");
    json << "\n    ],\n    \"empty\": {\"frames\": " << empty.frames << ", \"false_frames\": " << empty.falseFrames
         << ", \"false_sectors\": " << empty.falseSectors << ", \"obstacle_sectors\": " << empty.obstacleSectors
         << ", \"false_frame_rate\": " << jsonNumber(empty.falseRate())
         << "},\n    \"overhang\": {\"frames\": " << overhangFrames << ", \"false_frames\": " << overhangFalseFrames
         << "},\n    \"verdicts\": {\"detection\": " << (detectionOk ? "true" : "false")
         << ", \"empty_false_rate\": " << (emptyOk ? "true" : "false")
         << ", \"range_error\": " << (rangeOk ? "true" : "false")
         << ", \"overhang\": " << (overhangFalseFrames == 0 ? "true" : "false")
         << ", \"doorway\": " << (doorwayOk ? "true" : "false") << "}";
    const int rc = o.groundKinds.empty() && o.obstacleGrounds.empty() ? 0 : runGroundsSuite(o, det, json);
    std::printf("matcher cost cells searched (ground range %s, half resolution from %.0f px): %.1f %% of the full "
                "range, mean over %d frames\n",
                o.groundRange ? "on" : "off", o.halfResPx, 100.0 * det.meanSearchedFraction(),
                static_cast<int>(det.frames()));
    json << ",\n    \"searched_fraction\": " << jsonNumber(det.meanSearchedFraction()) << "\n  }";
    return rc;
}

/// The approach: each obstacle placed from kApproachFarM down to kApproachNearM, `stepM` nearer each frame (what
/// the vehicle sees driving at it, less the motion blur), once per texture with the bearings taking turns. Prints
/// per type how far ahead it is first seen and from where it is seen in every frame on.
/// @return 0 when everything ran, 1 on a render/detector failure.
int runApproach(const SimOptions& o, double stepM, std::ostringstream& json)
{
    constexpr double kApproachFarM = 12.0;
    constexpr double kApproachNearM = 1.0;
    std::optional<SimDetector> detector = makeSimDetector(o);
    if (!detector) {
        return 1;
    }
    SimDetector& det = *detector;
    sim::RenderResult frame;
    std::printf("\napproach: each obstacle from %.0f m to %.0f m in %.2f m steps (%zu texture(s), bearings %s)\n",
                kApproachFarM, kApproachNearM, stepM, o.textures.size(), o.bearings.size() > 1 ? "taking turns" : "0");
    std::printf("%-12s %-8s %8s %8s %10s %10s\n", "type", "texture", "bearing", "det%", "first_m", "held_m");
    json << "  \"approach\": {\n    \"step_m\": " << jsonNumber(stepM) << ",\n    \"runs\": [";
    bool firstRow = true;
    std::map<std::string, std::vector<double>> held;
    const std::vector<std::string> types = obstacleTypes(o);
    for (const std::string& type : types) {
        std::size_t cases = 0;
        for (const sim::GroundTexture texture : o.textures) {
            const double bearing = honoursBearing(type) ? o.bearings[cases++ % o.bearings.size()] : 0.0;
            std::vector<ApproachFrame> frames;
            const int steps = static_cast<int>(std::lround((kApproachFarM - kApproachNearM) / stepM));
            for (int i = 0; i <= steps; ++i) {
                const double range = kApproachFarM - i * stepM;
                auto scene = sim::makeScene(type, range, bearing, texture, 1);
                if (!scene || !det.run(*scene, frame)) {
                    std::cerr << "ugvsense eval: error: scene " << type << " failed\n";
                    return 1;
                }
                const ObstacleFrameScore score = scoreObstacleFrame(det.sectors(), frame.sectors);
                if (score.gtHasObstacle) {
                    frames.push_back({score.gtRangeM, score.detected});
                }
            }
            const ApproachScore a = scoreApproach(frames);
            held[type].push_back(a.heldRangeM);
            std::printf("%-12s %-8s %+8.0f %8.1f %10.2f %10.2f\n", type.c_str(), textureName(texture), bearing,
                        a.frames > 0 ? 100.0 * a.detected / a.frames : 0.0, a.firstRangeM, a.heldRangeM);
            json << (firstRow ? "\n" : ",\n") << "      {\"type\": \"" << type << "\", \"texture\": \""
                 << textureName(texture) << "\", \"bearing_deg\": " << jsonNumber(bearing)
                 << ", \"frames\": " << a.frames << ", \"detected\": " << a.detected
                 << ", \"first_range_m\": " << jsonNumber(a.firstRangeM)
                 << ", \"held_range_m\": " << jsonNumber(a.heldRangeM) << "}";
            firstRow = false;
        }
    }
    const double seconds = det.seconds();
    const int framesRun = static_cast<int>(det.frames());
    std::printf("approach summary (%d frames in %.1f s): held_m = seen in every frame from this GT range on\n",
                framesRun, seconds);
    for (const std::string& type : types) {
        const std::vector<double>& h = held[type];
        std::printf("%-12s held from %.2f m in every run (median of runs %.2f m)\n", type.c_str(),
                    *std::min_element(h.begin(), h.end()), quantile(h, 0.5));
    }
    json << "\n    ],\n    \"frames\": " << framesRun << ",\n    \"seconds\": " << jsonNumber(seconds) << "\n  }";
    return 0;
}

/// The hole signal: for 1 m holes from 6 to 10 m, the images' own evidence of the far wall (dropEvidence(), no
/// matcher) against plain ground in the same rows, beside our detector on the same frames. It tells a miss that
/// better matching could fix from one the images do not allow.
/// @return 0 when everything ran, 1 on a render/detector failure.
int runHoleSignal(const SimOptions& o, const std::vector<double>& ranges, std::ostringstream& json)
{
    constexpr int kHalfWidth = 7; ///< 15 x 1 px windows: the wall is 2 to 4 rows at 6 to 10 m
    constexpr int kStripWidth = 32;
    constexpr int kStripRows = 2;
    constexpr double kNearM = 5.0; ///< [m] the rows of ground from here ...
    constexpr double kFarM = 15.0; ///< [m] ... to here
    std::optional<SimDetector> detector = makeSimDetector(o);
    if (!detector) {
        return 1;
    }
    SimDetector& det = *detector;
    const vision::DisparityPlane& ground = det.ground();
    const sim::Rig rig;
    // The far band's rows at the image centre (ground disparity f b / Z).
    const auto rowAt = [&](double rangeM) {
        return static_cast<int>(
            std::lround((rig.focalPx * rig.baselineM / rangeM - ground.a * rig.cx() - ground.c) / ground.b));
    };
    const int rowFirst = rowAt(kFarM);
    const int rowLast = rowAt(kNearM);
    std::printf(
        "\nhole signal: the images' own evidence of a 1 m hole's far wall (no matcher: 15 x 1 px zero-mean SAD near "
        "the ground's disparity against the best 0.5-3 px below it, pooled over %d x %d px strips), the best wall "
        "strip against the best plain-ground strip of the same rows; beside our detector on the same frames\n",
        kStripWidth, kStripRows);
    std::printf("%-12s %8s %7s %8s %12s %12s %12s\n", "type", "range_m", "frames", "det%", "separable%", "wall_p50",
                "ground_p50");
    json << "  \"hole_signal\": [";
    bool firstRow = true;
    sim::RenderResult frame;
    for (const char* const type : {"hole", "hole_square"}) {
        for (const double range : ranges) {
            int frames = 0;
            int detected = 0;
            int separable = 0;
            std::vector<double> wall;
            std::vector<double> plain;
            for (const sim::GroundTexture texture : o.textures) {
                for (int seed = 1; seed <= o.seeds; ++seed) {
                    auto scene = sim::makeScene(type, range, 0.0, texture, static_cast<std::uint64_t>(seed));
                    if (!scene || !det.run(*scene, frame)) {
                        std::cerr << "ugvsense eval: error: scene " << type << " failed\n";
                        return 1;
                    }
                    const cv::Mat evidence =
                        dropEvidence(frame.left, frame.right, ground, rowFirst, rowLast, kHalfWidth);
                    const DropSignal signal = scoreDropSignal(evidence, frame.labels, frame.disparity, ground, rowFirst,
                                                              rowLast, kStripWidth, kStripRows);
                    if (!signal.hasWall) {
                        continue; // the hole lies beyond the rows, or its wall is too shallow to count
                    }
                    ++frames;
                    detected += scoreObstacleFrame(det.sectors(), frame.sectors).detected ? 1 : 0;
                    separable += signal.separable() ? 1 : 0;
                    wall.push_back(signal.wallBest);
                    plain.push_back(signal.groundBest);
                }
            }
            const double detRate = frames > 0 ? 100.0 * detected / frames : 0.0;
            const double sepRate = frames > 0 ? 100.0 * separable / frames : 0.0;
            std::printf("%-12s %8.1f %7d %8.1f %12.1f %12.3f %12.3f\n", type, range, frames, detRate, sepRate,
                        quantile(wall, 0.5), quantile(plain, 0.5));
            json << (firstRow ? "\n" : ",\n") << "    {\"type\": \"" << type << "\", \"range_m\": " << jsonNumber(range)
                 << ", \"frames\": " << frames << ", \"detected\": " << detected << ", \"separable\": " << separable
                 << ", \"wall_p50\": " << jsonNumber(quantile(wall, 0.5))
                 << ", \"ground_p50\": " << jsonNumber(quantile(plain, 0.5)) << "}";
            firstRow = false;
        }
    }
    json << "\n  ]";
    std::printf("separable%%: frames whose best wall strip beats every plain-ground strip of its rows, i.e. a detector "
                "told where the hole is and given the best threshold for the frame would see it\n");
    return 0;
}

struct StereoSet {
    const char* name;
    const char* folder; ///< relative to the data root
    const char* left;
    const char* right;
    const char* gt;
    double gtScale;
};
constexpr StereoSet kMiddlebury[] = {
    {"tsukuba", "middlebury/tsukuba", "im3.png", "im4.png", "disp3.pgm", 16.0},
    {"venus", "middlebury/venus", "im2.png", "im6.png", "disp2.pgm", 8.0},
    {"teddy", "middlebury/teddy", "im2.png", "im6.png", "disp2.png", 4.0},
    {"cones", "middlebury/cones", "im2.png", "im6.png", "disp2.png", 4.0},
};
constexpr StereoSet kAloe = {"aloe", "aloe", "aloeL.jpg", "aloeR.jpg", "aloeGT.png", 1.0};
constexpr int kDisparityMultiple = 16;

/// Scores both matchers on one pair; false (with a message) when files are missing or unreadable.
bool evalPair(const std::filesystem::path& root, const StereoSet& set, vision::MatcherMode mode, DisparityScore& ours,
              DisparityScore& opencv, int& numDisparities)
{
    const std::filesystem::path dir = root / set.folder;
    // Each header is checked before decoding (a PNG that declares a huge size is refused unread).
    std::string why; // of the first file that failed
    const auto read = [&](const char* file) {
        std::string reason;
        cv::Mat image = why.empty() ? readGrey(dir / file, &reason) : cv::Mat();
        if (image.empty() && why.empty()) {
            why = std::string(file) + ": " + reason;
        }
        return image;
    };
    const cv::Mat left = read(set.left);
    const cv::Mat right = read(set.right);
    const cv::Mat gt8 = read(set.gt);
    if (left.empty() || right.empty() || gt8.empty() || left.size() != right.size() || left.size() != gt8.size()) {
        std::cerr << "ugvsense eval: error: " << dir.string() << ": cannot read " << set.left << ", " << set.right
                  << " and " << set.gt << " of one size" << (why.empty() ? "" : ": " + why) << '\n';
        return false;
    }
    cv::Mat gt;
    gt8.convertTo(gt, CV_32F, 1.0 / set.gtScale);
    double gtMax = 0.0;
    cv::minMaxLoc(gt, nullptr, &gtMax);
    numDisparities = (static_cast<int>(std::floor(gtMax)) / kDisparityMultiple + 1) * kDisparityMultiple;

    vision::RoiMatcherConfig config; // our tuned defaults, only the search range adapted to the data set
    config.numDisparities = numDisparities;
    config.mode = mode;
    auto matcher = vision::RoiMatcher::create(config, left.size());
    if (!matcher || matcher->match(viewOf(left), viewOf(right)) != vision::MatchStatus::Ok) {
        std::cerr << "ugvsense eval: error: our matcher failed on " << set.name << '\n';
        return false;
    }
    cv::Mat oursF(left.size(), CV_32F);
    (void)matcher->toFloat(oursF);
    ours = scoreDisparity(oursF, gt);

    cv::Mat sgbm16;
    cv::Mat sgbmF;
    try {
        cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(0, numDisparities); // every other setting default
        sgbm->compute(left, right, sgbm16);
    } catch (const std::exception& e) {
        std::cerr << "ugvsense eval: error: OpenCV StereoSGBM failed on " << set.name << ": " << e.what() << '\n';
        return false;
    }
    sgbm16.convertTo(sgbmF, CV_32F, 1.0 / vision::RoiMatcher::kScale); // invalid (-16) becomes -1
    opencv = scoreDisparity(sgbmF, gt);
    return true;
}

int runMiddlebury(const std::filesystem::path& root, vision::MatcherMode matcher, std::ostringstream& json)
{
    std::vector<StereoSet> sets(std::begin(kMiddlebury), std::end(kMiddlebury));
    std::error_code ec;
    if (std::filesystem::is_directory(root / kAloe.folder, ec)) {
        sets.push_back(kAloe);
    }
    std::printf("\nMiddlebury (%s): bad-Npx = |d - gt| > N px over valid-GT pixels; 'all' counts missing predictions "
                "as bad, 'valid' uses predicted pixels only\n",
                root.string().c_str());
    std::printf("%-8s %4s | %-30s | %-30s\n", "set", "nd", "ours: bad1 bad2 (all) bad1 bad2 (valid) dens",
                "opencv default: same");
    bool noWorse = true;
    json << "  \"middlebury\": [";
    for (std::size_t i = 0; i < sets.size(); ++i) {
        DisparityScore ours;
        DisparityScore opencv;
        int nd = 0;
        if (!evalPair(root, sets[i], matcher, ours, opencv, nd)) {
            return 1;
        }
        const bool ok = ours.bad2All <= opencv.bad2All;
        noWorse = noWorse && ok;
        std::printf("%-8s %4d | %5.1f %5.1f  %5.1f %5.1f  %5.1f%% | %5.1f %5.1f  %5.1f %5.1f  %5.1f%% | bad-2px %s\n",
                    sets[i].name, nd, 100 * ours.bad1All, 100 * ours.bad2All, 100 * ours.bad1Valid,
                    100 * ours.bad2Valid, 100 * ours.density(), 100 * opencv.bad1All, 100 * opencv.bad2All,
                    100 * opencv.bad1Valid, 100 * opencv.bad2Valid, 100 * opencv.density(), ok ? "no worse" : "WORSE");
        const auto scoreJson = [](const DisparityScore& s) {
            return "{\"bad1_all\": " + jsonNumber(s.bad1All) + ", \"bad2_all\": " + jsonNumber(s.bad2All) +
                   ", \"bad1_valid\": " + jsonNumber(s.bad1Valid) + ", \"bad2_valid\": " + jsonNumber(s.bad2Valid) +
                   ", \"density\": " + jsonNumber(s.density()) + "}";
        };
        json << (i == 0 ? "\n" : ",\n") << "    {\"set\": \"" << sets[i].name << "\", \"num_disparities\": " << nd
             << ", \"ours\": " << scoreJson(ours) << ", \"opencv_default\": " << scoreJson(opencv) << "}";
    }
    json << "\n  ],\n  \"middlebury_bad2_no_worse_than_opencv_default\": " << (noWorse ? "true" : "false");
    std::printf("verdict: bad-2px (all valid-GT pixels) no worse than OpenCV default on every pair: %s\n",
                noWorse ? "PASS" : "FAIL");
    return 0;
}

/// eval's options.
Args evalArgs()
{
    return Args(
        "eval",
        "[--sim] [--approach] [--hole-signal] [--middlebury] [--real DIR [--mount [SET=]H,P,R] [--pairs LIST] "
        "[--perturb "
        "LIST] "
        "[--overlay-dir DIR] [--verbose]] [--quick] [--types LIST] [--grounds LIST] [--frames-per-case N] [--matcher "
        "MODE] "
        "[--ground-prior] [--ground-range on|off] [--half-res PX] [--max-range-px PX] [--detector stereo|colour] "
        "[--json OUT] [--data DIR] "
        "[--skip-missing]",
        {{"sim", "",
          "run the simulator suite (obstacle types x ranges x textures, empty, overhang, doorway, and the new grounds: "
          "camber, grade, kerb, photometry, paint, rails, shadows, mirrors)",
          false},
         {"approach", "",
          "simulator: each obstacle placed from 12 m to 1 m, 0.25 m nearer each frame: how far ahead it is seen",
          false},
         {"hole-signal", "",
          "simulator: 1 m holes at 6-10 m: the images' own evidence of the far wall (no matcher) against plain ground, "
          "beside our detector",
          false},
         {"middlebury", "", "score the matcher on Middlebury (and aloe) pairs against OpenCV's default SGBM", false},
         {"real", "DIR",
          "score the obstacle sectors on real pairs with LiDAR ground truth (DIR: ../shared/data/real-stereo, its "
          "index.csv), beside OpenCV StereoSGBM + RANSAC ground + a 0.25 m threshold",
          false},
         {"mount", "[SET=]H,P,R",
          "real: give every pair, or those of data set SET (index.csv's dataset starts with it), this mount (height "
          "m, pitch deg, roll deg); the others' ground is found",
          false},
         {"pairs", "LIST", "real: only these pairs, comma-separated (index.csv's pair column)", false},
         {"verbose", "", "real: a line per sector (truth, ours, outcome)", false},
         {"overlay-dir", "DIR", "real: write an overlay per pair (sector bar: ours; below it the truth)", false},
         {"perturb", "LIST",
          "real: run the pairs under these conditions, comma-separated, each scored in full beside the OpenCV "
          "pipeline on the same changed images: none, or parts joined by '+': noise:S (grey levels), gain:G (right "
          "camera), blur:S (px), exposure:F, jpeg:Q, half (another rig: half the resolution); sweep: a set of "
          "each at two strengths (JPEG at three)",
          false},
         {"quick", "",
          "simulator: a smoke version (1 texture, 1 range per band, bearing 0; new grounds: 2 seeds, obstacles at 4.5 "
          "m; "
          "the approach in 0.5 m steps)",
          false},
         {"types", "LIST", "simulator: only these obstacle types, comma-separated (ugvsense sim --list)", false},
         {"grounds", "LIST",
          "simulator suite: only these new grounds (ugvsense sim --list, conditions), for the empty scenes and the "
          "obstacles; none: skip them. Default: every kind empty, the obstacles over camber, paint, shadow, glossy",
          false},
         {"frames-per-case", "N", "simulator: noise seeds per case, 1..20, default 1", false},
         {"matcher", "MODE", "our matcher: census_sgm (default) or an OpenCV mode: sgbm_3way, sgbm, hh4", false},
         {"ground-prior", "",
          "simulator and real: census SGM's top path follows the ground (RoiMatcherConfig::groundPrior; on real pairs "
          "the configured ground: --mount's, else the plane found, or with --ground-range on the first run's estimate)",
          false},
         {"ground-range", "on|off",
          "simulator and real: census SGM's ground-guided disparity ranges (RoiMatcherConfig::groundRange; default: "
          "its default); real pairs are then run twice, the second frame searching from the first's ground",
          false},
         {"half-res", "PX",
          "simulator and real: match the near rows at half resolution, from the row where the configured ground's "
          "disparity reaches PX on (DetectorConfig::halfResolutionMinGroundPx; 0: off; default: its default)",
          false},
         {"max-range-px", "PX",
          "simulator and real: the detector looks as far as the disparity stays at or above PX "
          "(obstacles.max_range_disparity_px, SectorBuilderConfig::maxRangeDisparityPx; default 13.65)",
          false},
         {"detector", "NAME",
          "simulator suite: stereo (default) or colour: the one-camera mode (ColourFreeSpace on the left colour "
          "image) on asphalt, grass and floor at 1-6 m, scored by the same scorer, and its false sectors on empty "
          "ground; real: the one-camera mode scored beside the stereo detector on the same pairs",
          false},
         {"json", "OUT", "write all figures as JSON", false},
         {"data", "DIR", "shared data root, default $UGV_SHARED_DATA or ../shared/data", false},
         {"skip-missing", "", "exit 77 (skipped) when the Middlebury or real data are missing", false}});
}

/// What eval's options choose beside the suites.
struct EvalChoices {
    int seeds = 1;
    vision::MatcherMode matcher = vision::MatcherMode::CensusSgm;
    bool colourDetector = false;
    bool groundRange = vision::RoiMatcherConfig{}.groundRange;
    double halfResPx = vision::DetectorConfig{}.halfResolutionMinGroundPx;
    double maxRangePx = vision::SectorBuilderConfig{}.maxRangeDisparityPx;
    std::filesystem::path root = "../shared/data";
    std::vector<Perturbation> perturbations; ///< --perturb (real)
};

/// An exit code when the Middlebury or real data the options name are missing (77 with --skip-missing).
std::optional<int> missingData(const Args& args, const std::filesystem::path& root)
{
    std::error_code ec;
    if (args.has("middlebury") && !std::filesystem::is_directory(root / "middlebury", ec)) {
        std::cerr << "ugvsense eval: " << (args.has("skip-missing") ? "skipped" : "error") << ": Middlebury data "
                  << "not found at " << (root / "middlebury").string()
                  << " (fix: set UGV_SHARED_DATA or --data DIR to the shared data root)\n";
        return args.has("skip-missing") ? kExitSkipped : 1;
    }
    if (args.has("real") &&
        !std::filesystem::is_regular_file(std::filesystem::path(args.get("real")) / "index.csv", ec)) {
        std::cerr << "ugvsense eval: " << (args.has("skip-missing") ? "skipped" : "error")
                  << ": real stereo data not found: no " << args.get("real") << "/index.csv"
                  << " (fix: --real ../shared/data/real-stereo, or $UGV_SHARED_DATA/real-stereo)\n";
        return args.has("skip-missing") ? kExitSkipped : 1;
    }
    return std::nullopt;
}

/// The choices of `args`; an exit code when the options are wrong or the data they name is missing.
std::optional<int> readChoices(const Args& args, EvalChoices& c)
{
    if (!args.has("sim") && !args.has("approach") && !args.has("hole-signal") && !args.has("middlebury") &&
        !args.has("real")) {
        return reportUsageError("eval", Error{"ugvsense eval", "nothing to evaluate",
                                              "give --sim, --approach, --hole-signal, --middlebury and/or --real"});
    }
    const auto seeds = args.number("frames-per-case", 1, 1, 20);
    if (!seeds || *seeds != std::floor(*seeds)) {
        return reportUsageError("eval", seeds ? Error{"ugvsense eval --frames-per-case", "not a whole number", ""}
                                              : seeds.error());
    }
    c.seeds = static_cast<int>(*seeds);
    if (args.has("matcher")) {
        const std::string name = args.get("matcher");
        const auto mode = vision::parseMatcherMode(name);
        if (!mode) {
            return reportUsageError("eval", Error{"ugvsense eval --matcher", "unknown mode '" + name + "'",
                                                  "use " + std::string(vision::kMatcherModeNames)});
        }
        c.matcher = *mode;
    }
    const std::string detectorName = args.has("detector") ? args.get("detector") : "stereo";
    if (detectorName != "stereo" && detectorName != "colour") {
        return reportUsageError("eval", Error{"ugvsense eval --detector", "unknown detector '" + detectorName + "'",
                                              "use stereo or colour"});
    }
    c.colourDetector = detectorName == "colour";
    if (c.colourDetector && ((!args.has("sim") && !args.has("real")) || args.has("approach") ||
                             args.has("hole-signal") || args.has("middlebury"))) {
        return reportUsageError("eval", Error{"ugvsense eval --detector colour", "runs with --sim and --real only",
                                              "give --sim or --real (the approach, hole signal and Middlebury are "
                                              "stereo measures)"});
    }
    if (args.has("ground-range")) {
        const std::string value = args.get("ground-range");
        if (value != "on" && value != "off") {
            return reportUsageError("eval", Error{"ugvsense eval --ground-range", "'" + value + "' is not on or off",
                                                  "use --ground-range on or --ground-range off"});
        }
        c.groundRange = value == "on";
    }
    const auto halfRes = args.number("half-res", c.halfResPx, 0.0, 1000.0);
    if (!halfRes) {
        return reportUsageError("eval", halfRes.error());
    }
    c.halfResPx = *halfRes;
    const auto maxRange = args.number("max-range-px", c.maxRangePx, 2.0, 128.0);
    if (!maxRange) {
        return reportUsageError("eval", maxRange.error());
    }
    c.maxRangePx = *maxRange;
    if (args.has("data")) {
        c.root = args.get("data");
    } else if (const char* env = std::getenv("UGV_SHARED_DATA"); env != nullptr && *env != '\0') {
        c.root = env;
    }
    if (args.has("mount")) {
        if (auto mount = parseMount(args.get("mount")); !mount) {
            return reportUsageError("eval", mount.error());
        }
    }
    if (args.has("perturb")) {
        auto conditions = parsePerturbations(args.get("perturb"));
        if (!conditions) {
            return reportUsageError("eval", conditions.error());
        }
        if (c.colourDetector) {
            return reportUsageError("eval", Error{"ugvsense eval --perturb", "changes the stereo pair only",
                                                  "leave out --detector colour"});
        }
        c.perturbations = std::move(conditions).value();
    }
    return missingData(args, c.root);
}

/// A comma-separated list option of names, each one of `known` (or `extra`); an error naming the option otherwise.
Result<std::vector<std::string>, Error> nameList(const Args& args, const char* option,
                                                 const std::vector<std::string>& known, const std::string& what,
                                                 const std::string& fix)
{
    std::vector<std::string> names;
    std::stringstream list(args.get(option));
    for (std::string name; std::getline(list, name, ',');) {
        if (std::find(known.begin(), known.end(), name) == known.end()) {
            return Unexpected(
                Error{std::string("ugvsense eval --") + option, "unknown " + what + " '" + name + "'", fix});
        }
        names.push_back(name);
    }
    return names;
}

/// The simulator suites' cases: the full or the quick grid, narrowed by --types and --grounds.
Result<SimOptions, Error> simOptions(const Args& args, const EvalChoices& c)
{
    SimOptions o;
    if (args.has("quick")) {
        o.textures = {sim::GroundTexture::Asphalt};
        o.rangesPerBand = {0.5};
        o.bearings = {0.0};
        o.emptySeeds = 3;
        o.emptyTextures = o.textures;
        o.doorwayRanges = {3.0};
        o.overhangRanges = {3.0};
        o.groundSeeds = 2;
        o.groundRanges = {4.5};
    } else {
        o.textures = {sim::GroundTexture::Asphalt, sim::GroundTexture::Grass, sim::GroundTexture::Gravel};
        o.rangesPerBand = {0.25, 0.75};
        o.bearings = {0.0, -15.0, 15.0};
        o.emptySeeds = 10;
        o.doorwayRanges = {2.0, 3.0, 4.0, 5.0};
        o.overhangRanges = {2.0, 3.0, 4.0};
    }
    o.seeds = c.seeds;
    if (args.has("types")) {
        std::vector<std::string> types;
        for (const std::string& name : sim::sceneNames()) {
            if (name != "empty" && name != "overhang") {
                types.push_back(name);
            }
        }
        auto chosen = nameList(args, "types", types, "obstacle type", "see 'ugvsense sim --list'");
        if (!chosen) {
            return Unexpected(chosen.error());
        }
        o.types = *chosen;
    }
    if (args.has("grounds")) {
        std::vector<std::string> grounds = sim::conditionNames();
        grounds.emplace_back("none");
        auto chosen = nameList(args, "grounds", grounds, "ground", "see 'ugvsense sim --list' (conditions), or none");
        if (!chosen) {
            return Unexpected(chosen.error());
        }
        o.groundKinds.clear();
        std::copy_if(chosen->begin(), chosen->end(), std::back_inserter(o.groundKinds),
                     [](const std::string& name) { return name != "none"; });
        o.obstacleGrounds = o.groundKinds;
    }
    o.matcher = c.matcher;
    o.groundPrior = args.has("ground-prior");
    o.groundRange = c.groundRange;
    o.halfResPx = c.halfResPx;
    o.maxRangePx = c.maxRangePx;
    if (c.colourDetector) {
        // The grounds of issue 23's one-camera targets; the empty scenes on the same ones.
        o.colour = true;
        o.textures = {sim::GroundTexture::Asphalt, sim::GroundTexture::Grass, sim::GroundTexture::PaintedFloor};
        o.emptyTextures = o.textures;
        if (!args.has("quick")) {
            o.rangesPerBand = {0.125, 0.375, 0.625, 0.875};
        }
    }
    return o;
}

/// The simulator suites the options ask for (--sim, --approach, --hole-signal), their JSON into `json`.
int runSimulated(const Args& args, const SimOptions& o, std::ostringstream& json)
{
    if (o.colour) {
        if (const int rc = runColourSuite(o, json); rc != 0) {
            return rc;
        }
    } else if (args.has("sim")) {
        if (const int rc = runSimSuite(o, json); rc != 0) {
            return rc;
        }
    }
    if (args.has("approach")) {
        json << (args.has("sim") ? ",\n" : "");
        if (const int rc = runApproach(o, args.has("quick") ? 0.5 : 0.25, json); rc != 0) {
            return rc;
        }
    }
    if (args.has("hole-signal")) {
        json << (args.has("sim") || args.has("approach") ? ",\n" : "");
        const std::vector<double> ranges = args.has("quick")
                                               ? std::vector<double>{7.0, 9.0}
                                               : std::vector<double>{6.0, 6.5, 7.0, 7.5, 8.0, 8.5, 9.0, 9.5, 10.0};
        return runHoleSignal(o, ranges, json);
    }
    return 0;
}

/// --real: the options of the real-pair suite, run.
int runReal(const Args& args, const EvalChoices& choices, std::ostringstream& json)
{
    RealEvalOptions real;
    real.colour = choices.colourDetector;
    real.dir = args.get("real");
    real.overlayDir = args.get("overlay-dir");
    real.mount = args.get("mount");
    real.verbose = args.has("verbose");
    real.groundRange = choices.groundRange;
    real.groundPrior = args.has("ground-prior");
    real.halfResPx = choices.halfResPx;
    real.maxRangePx = choices.maxRangePx;
    std::stringstream list(args.get("pairs"));
    for (std::string name; std::getline(list, name, ',');) {
        real.pairs.push_back(name);
    }
    real.perturbations = choices.perturbations;
    return runRealEval(real, json);
}

/// --json OUT: every figure, written.
int writeJson(const std::string& path, const std::string& text)
{
    std::ofstream out(path);
    out << text;
    out.flush();
    if (!out) {
        std::cerr << "ugvsense eval: error: " << path << ": cannot write the JSON file\n";
        return 1;
    }
    std::printf("wrote %s\n", path.c_str());
    return 0;
}

} // namespace

int runEval(int argc, char** argv)
{
    Args args = evalArgs();
    if (const auto exit = parseOrExit(args, argc, argv, "eval")) {
        return *exit;
    }
    EvalChoices choices;
    if (const auto exit = readChoices(args, choices)) {
        return *exit;
    }
    std::ostringstream json;
    json << "{\n";
    const bool simulated = args.has("sim") || args.has("approach") || args.has("hole-signal");
    if (simulated) {
        const auto o = simOptions(args, choices);
        if (!o) {
            return reportUsageError("eval", o.error());
        }
        if (const int rc = runSimulated(args, *o, json); rc != 0) {
            return rc;
        }
    }
    if (args.has("middlebury")) {
        json << (simulated ? ",\n" : "");
        if (const int rc = runMiddlebury(choices.root, choices.matcher, json); rc != 0) {
            return rc;
        }
    }
    if (args.has("real")) {
        json << (simulated || args.has("middlebury") ? ",\n" : "");
        if (const int rc = runReal(args, choices, json); rc != 0) {
            return rc;
        }
    }
    json << "\n}\n";
    return args.has("json") ? writeJson(args.get("json"), json.str()) : 0;
}

} // namespace ugv::tool
