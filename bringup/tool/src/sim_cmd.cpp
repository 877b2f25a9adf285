// ugvsense sim: synthetic stereo data.
// - Scene "chessboard": calibration pairs rendered by a known rig, with truth.yaml holding that rig, so that
//   `ugvsense calibrate` can be checked against it.
// - Any scene of the ray-cast simulator's catalogue (bringup/sim): one sample with its ground truth
//   (sim::writeSample) and calibration.yaml (sim::writeCalibration), optionally under real-world conditions (named
//   presets, --condition, and flags for the ground shape, photometry, markings, shadows and mirrors).
// - A course: a recording (--out REC.ugvrec) with its ground truth in REC.ugvrec.truth.csv, or numbered samples
//   frame_NNNN_*, calibration.yaml and poses.csv (frame, t, x, y, yaw) in a folder.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "ugv/hal/recording.hpp"
#include "ugv/sim/chessboard_render.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"
#include "ugv/sim/writer.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"
#include "ugv/tool/detection.hpp"

namespace ugv::tool {
namespace {

constexpr int kDefaultPairs = 12;
constexpr int kMaxPairs = 99;
constexpr double kDefaultNoise = 1.0; // [grey levels]
constexpr double kMaxNoise = 50.0;
constexpr double kDefaultRangeM = 5.0;
constexpr double kMaxRangeM = 200.0;
constexpr double kMaxBearingDeg = 180.0;
constexpr double kMaxTiltDeg = 45.0; // [deg] pitch and roll
constexpr double kMaxHeightM = 10.0;
constexpr double kDefaultFps = 10.0;
constexpr double kMaxFps = 100.0;
constexpr double kCourseSpeedMps = 1.5;
constexpr int kMaxFrames = 100000;
constexpr double kMaxSimSeed = 1e9;
constexpr const char* kChessboard = "chessboard";

/// Prints an error of the job (not of the command line) and returns exit code 1.
int reportFailure(const Error& error)
{
    std::cerr << "ugvsense sim: error: " << error.message() << '\n';
    return 1;
}

std::string knownScenes()
{
    std::string names = kChessboard;
    for (const auto& name : sim::sceneNames()) {
        names += ", " + name;
    }
    return names;
}

std::optional<sim::GroundTexture> parseTexture(const std::string& name)
{
    if (name == "asphalt") {
        return sim::GroundTexture::Asphalt;
    }
    if (name == "grass") {
        return sim::GroundTexture::Grass;
    }
    if (name == "gravel") {
        return sim::GroundTexture::Gravel;
    }
    if (name == "floor") {
        return sim::GroundTexture::PaintedFloor;
    }
    return std::nullopt;
}

/// A number flag of a catalogue scene's conditions and where it goes in the scene.
struct ConditionFlag {
    const char* name;
    double min;
    double max;
    void (*set)(sim::Scene&, double);
};

constexpr ConditionFlag kConditionFlags[] = {
    {"camber", 0.0, 0.3, [](sim::Scene& s, double v) { s.ground.camberSlope = v; }},
    {"crown-y", -kMaxRangeM, kMaxRangeM, [](sim::Scene& s, double v) { s.ground.crownY = v; }},
    {"grade", -0.3, 0.3, [](sim::Scene& s, double v) { s.ground.gradeChange = v; }},
    {"grade-at", -kMaxRangeM, kMaxRangeM, [](sim::Scene& s, double v) { s.ground.gradeAtX = v; }},
    {"kerb-y", -kMaxRangeM, kMaxRangeM, [](sim::Scene& s, double v) { s.ground.kerbY = v; }},
    {"kerb-height", 0.0, 1.0, [](sim::Scene& s, double v) { s.ground.kerbHeightM = v; }},
    {"right-gain", 0.1, 10.0, [](sim::Scene& s, double v) { s.lighting.rightGain = v; }},
    {"right-offset", -255.0, 255.0, [](sim::Scene& s, double v) { s.lighting.rightOffsetGrey = v; }},
    {"vignette-left", 0.0, 0.9, [](sim::Scene& s, double v) { s.lighting.vignetteLeft = v; }},
    {"vignette-right", 0.0, 0.9, [](sim::Scene& s, double v) { s.lighting.vignetteRight = v; }},
    {"noise", 0.0, kMaxNoise, [](sim::Scene& s, double v) { s.lighting.noiseSigmaGrey = v; }},
    {"jpeg", 1.0, 100.0, [](sim::Scene& s, double v) { s.lighting.jpegQuality = static_cast<int>(std::lround(v)); }},
    {"dash", 0.01, kMaxRangeM, [](sim::Scene& s, double v) { s.markings.dashM = v; }},
    {"gap", 0.0, kMaxRangeM, [](sim::Scene& s, double v) { s.markings.gapM = v; }},
    {"stop-line", 0.0, kMaxRangeM, [](sim::Scene& s, double v) { s.markings.stopLineX = v; }},
    {"glossy", 0.0, 1.0,
     [](sim::Scene& s, double v) {
         constexpr double kWholeFloorM = 1000.0;
         s.reflectors.push_back(sim::Reflector{0.0, 0.0, kWholeFloorM, kWholeFloorM, false, v});
     }},
};

/// Comma-separated finite numbers (none when the flag is absent); an Error naming the flag otherwise.
Result<std::vector<double>, Error> numberList(const Args& args, const std::string& name)
{
    std::vector<double> values;
    std::stringstream list(args.get(name));
    for (std::string item; std::getline(list, item, ',');) {
        char* end = nullptr;
        const double v = std::strtod(item.c_str(), &end);
        if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(v)) {
            return Unexpected(Error{"ugvsense sim --" + name, "bad number '" + item + "' in '" + args.get(name) + "'",
                                    "give comma-separated numbers, e.g. --" + name + " 1.75,-1.75"});
        }
        values.push_back(v);
    }
    return values;
}

/// The conditions of a catalogue scene: the presets of --condition (variant --variant), then the flags.
Result<void, Error> applyConditionOptions(const Args& args, sim::Scene& scene)
{
    const auto variant = args.number("variant", 0, 0, 1000);
    if (!variant) {
        return Unexpected(variant.error());
    }
    std::stringstream names(args.get("condition"));
    for (std::string name; std::getline(names, name, ',');) {
        if (auto applied = sim::applyCondition(scene, name, static_cast<int>(*variant)); !applied) {
            return Unexpected(Error{"ugvsense sim --condition", applied.error().what, applied.error().fix});
        }
    }
    for (const ConditionFlag& flag : kConditionFlags) {
        if (args.has(flag.name)) {
            const auto value = args.number(flag.name, 0.0, flag.min, flag.max);
            if (!value) {
                return Unexpected(value.error());
            }
            flag.set(scene, *value);
        }
    }
    const auto lanes = numberList(args, "lanes");
    const auto rails = numberList(args, "rails");
    const auto shadow = numberList(args, "shadow");
    const auto puddle = numberList(args, "puddle");
    for (const auto* list : {&lanes, &rails, &shadow, &puddle}) {
        if (!*list) {
            return Unexpected(list->error());
        }
    }
    if (args.has("lanes")) {
        scene.markings.laneLinesY = *lanes;
    }
    if (args.has("rails")) {
        scene.markings.tracksY = *rails;
    }
    if (args.has("shadow")) {
        if (shadow->size() < 6 || shadow->size() % 2 != 0) {
            return Unexpected(
                Error{"ugvsense sim --shadow", "a polygon needs 3 or more x,y corners", "e.g. 5,-9,5,9,9,0"});
        }
        sim::Shadow polygon;
        for (std::size_t i = 0; i + 1 < shadow->size(); i += 2) {
            polygon.polygon.emplace_back((*shadow)[i], (*shadow)[i + 1]);
        }
        scene.shadows.push_back(polygon);
    }
    if (args.has("puddle")) {
        const std::vector<double>& v = *puddle;
        if (v.size() != 5) {
            return Unexpected(Error{"ugvsense sim --puddle", "give 5 numbers X,Y,RX,RY,REFL", "e.g. 3,0,0.8,0.5,0.7"});
        }
        scene.reflectors.push_back(sim::Reflector{v[0], v[1], v[2], v[3], true, v[4]});
    }
    return sim::validate(scene);
}

/// Creates `out` if needed; an Error (exit 1) when it cannot be created or is not a folder.
Result<void, Error> prepareOutput(const std::filesystem::path& out)
{
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (!std::filesystem::is_directory(out, ec)) {
        return Unexpected(Error{out.string(), "cannot create the output folder",
                                "choose a writable --out folder (check the path and its permissions)"});
    }
    return {};
}

bool writeTruth(const std::string& path, const sim::SimRig& rig, const sim::SimBoard& board, int pairs)
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

int runChessboard(const Args& args)
{
    const auto pairs = args.number("pairs", kDefaultPairs, 1, kMaxPairs);
    const auto seed = args.number("seed", 1, 0, kMaxSimSeed);
    const auto noise = args.number("noise", kDefaultNoise, 0, kMaxNoise);
    for (const auto* number : {&pairs, &seed, &noise}) {
        if (!*number) {
            return reportUsageError("sim", number->error());
        }
    }
    const std::filesystem::path out = args.get("out");
    if (auto prepared = prepareOutput(out); !prepared) {
        return reportFailure(prepared.error());
    }

    const sim::SimRig rig;
    const sim::SimBoard board;
    const sim::ChessboardRenderer renderer(rig, board);
    const auto poses = renderer.poses(static_cast<int>(*pairs), static_cast<std::uint64_t>(*seed));
    cv::RNG rng(static_cast<std::uint64_t>(*seed) + 1);
    for (std::size_t i = 0; i < poses.size(); ++i) {
        cv::Mat left;
        cv::Mat right;
        renderer.render(poses[i], *noise, rng, left, right);
        char suffix[32];
        (void)std::snprintf(suffix, sizeof(suffix), "_%02zu.png", i + 1);
        const std::string leftPath = (out / ("left" + std::string(suffix))).string();
        const std::string rightPath = (out / ("right" + std::string(suffix))).string();
        bool written = false;
        try {
            written = cv::imwrite(leftPath, left) && cv::imwrite(rightPath, right);
        } catch (const cv::Exception&) {
            written = false;
        }
        if (!written) {
            return reportFailure(Error{leftPath, "cannot write the image", "check the folder"});
        }
    }
    const std::string truthPath = (out / "truth.yaml").string();
    if (!writeTruth(truthPath, rig, board, static_cast<int>(poses.size()))) {
        return reportFailure(Error{truthPath, "cannot write the file", "check the folder"});
    }
    std::cout << "wrote " << poses.size() << " chessboard pairs and truth.yaml to " << out.string() << " (fx " << rig.fx
              << " px, baseline " << rig.baselineM << " m)\n";
    return 0;
}

int runCatalogueScene(const Args& args)
{
    const std::string name = args.get("scene");
    const auto range = args.number("range", kDefaultRangeM, -kMaxRangeM, kMaxRangeM);
    const auto bearing = args.number("bearing", 0.0, -kMaxBearingDeg, kMaxBearingDeg);
    const auto seed = args.number("seed", 1, 0, kMaxSimSeed);
    const sim::Rig defaults;
    const auto pitch = args.number("pitch", defaults.pitchDeg, -kMaxTiltDeg, kMaxTiltDeg);
    const auto roll = args.number("roll", defaults.rollDeg, -kMaxTiltDeg, kMaxTiltDeg);
    const auto height = args.number("height", defaults.heightM, -kMaxHeightM, kMaxHeightM);
    for (const auto* number : {&range, &bearing, &seed, &pitch, &roll, &height}) {
        if (!*number) {
            return reportUsageError("sim", number->error());
        }
    }
    if (*range <= 0.0) {
        return reportFailure(Error{"ugvsense sim --range", "range " + args.get("range") + " m is not positive",
                                   "give the obstacle's distance in metres, e.g. --range 5"});
    }
    if (*height <= 0.0) {
        return reportFailure(Error{"ugvsense sim --height",
                                   "camera height " + args.get("height") + " m is not positive",
                                   "give the camera height above the ground in metres, e.g. --height 0.59"});
    }
    const std::string textureName = args.get("texture", "asphalt");
    const auto texture = parseTexture(textureName);
    if (!texture) {
        return reportFailure(Error{"ugvsense sim --texture", "unknown texture '" + textureName + "'",
                                   "use one of: asphalt, grass, gravel, floor"});
    }
    auto scene = sim::makeScene(name, *range, *bearing, *texture, static_cast<std::uint64_t>(*seed));
    if (!scene) {
        return reportFailure(Error{"ugvsense sim --scene", "unknown scene '" + name + "'",
                                   "use one of: " + knownScenes() + " (ugvsense sim --list)"});
    }
    scene->rig.pitchDeg = *pitch;
    scene->rig.rollDeg = *roll;
    scene->rig.heightM = *height;
    if (auto conditions = applyConditionOptions(args, *scene); !conditions) {
        return reportFailure(conditions.error());
    }

    const std::filesystem::path out = args.get("out");
    if (auto prepared = prepareOutput(out); !prepared) {
        return reportFailure(prepared.error());
    }
    if (auto written = sim::writeCalibration(scene->rig, out); !written) { // fails fast before the render
        return reportFailure(written.error());
    }
    auto frame = sim::render(*scene);
    if (!frame) {
        return reportFailure(frame.error());
    }
    if (auto written = sim::writeSample(*frame, scene->rig, out, name); !written) {
        return reportFailure(written.error());
    }
    std::cout << "wrote scene '" << name << "' (range " << *range << " m, bearing " << *bearing << " deg, "
              << textureName << ", pitch " << *pitch << " deg, roll " << *roll << " deg, height " << *height << " m"
              << (args.has("condition") ? ", conditions " + args.get("condition") : std::string()) << ") to "
              << out.string() << ": " << name << "_{left,left_colour,right,disparity,depth,labels,ids}.png, " << name
              << "_sectors.json, calibration.yaml\n";
    return 0;
}

/// A course as a recording (hal/recording.hpp) at `out` and its ground truth beside it in `<out>.truth.csv`:
/// one row per frame and sector (sequence, time, vehicle pose, sector bounds, state, kind, range, class).
/// The recording is written as `<out>.part` and renamed at the end, so `out` exists only when complete (the
/// default-recording unit makes it only when it is missing).
int writeCourseRecording(const sim::Course& course, std::size_t count, double fps, bool colour,
                         const std::filesystem::path& out)
{
    const sim::Rig& rig = course.scene.rig;
    hal::RecordingWriterOptions options;
    options.format = colour ? PixelFormat::Bgr8 : PixelFormat::Grey8;
    options.overwrite = true;
    options.syncEveryFrame = false; // generated data: one sync at close is enough
    const std::filesystem::path partPath = out.string() + ".part";
    auto writer =
        hal::RecordingWriter::create(partPath.string(), static_cast<std::uint32_t>(rig.width),
                                     static_cast<std::uint32_t>(rig.height), sim::calibrationText(rig), options);
    if (!writer) {
        return reportFailure(writer.error());
    }
    const std::filesystem::path truthPath = out.string() + ".truth.csv";
    std::ofstream truth(truthPath);
    truth << "sequence,t_s,x_m,y_m,yaw_deg,sector,bearing_min_deg,bearing_max_deg,state,kind,range_m,class\n";
    truth.precision(6);
    for (std::size_t k = 0; k < count; ++k) {
        sim::RenderOptions render;
        render.rightColour = colour;
        auto frame = sim::renderCourseFrame(course, k, render);
        if (!frame) {
            return reportFailure(frame.error());
        }
        // Stamps as a camera's monotonic clock would give them: 1 s after boot, then one frame period each.
        const auto stampNs = static_cast<std::int64_t>(std::llround((1.0 + static_cast<double>(k) / fps) * 1e9));
        const StereoViews images = colour ? bgrViews(bgrViewOf(frame->leftColour), bgrViewOf(frame->rightColour))
                                          : greyViews(viewOf(frame->left), viewOf(frame->right));
        if (auto appended = writer->append(k, stampNs, stampNs, images); !appended) {
            return reportFailure(Error{partPath.string(),
                                       std::string("cannot append frame: ") + appended.error().text(),
                                       "check the free space"});
        }
        const sim::Pose& pose = course.poses[k];
        const ObstacleSectors& sectors = frame->sectors;
        for (int i = 0; i < sectors.count; ++i) {
            const Sector& sector = sectors.sectors[static_cast<std::size_t>(i)];
            truth << k << ',' << static_cast<double>(k) / fps << ',' << pose.x << ',' << pose.y << ',' << pose.yawDeg
                  << ',' << i << ',' << sector.bearingMinDeg << ',' << sector.bearingMaxDeg << ','
                  << stateName(sector.state) << ',' << kindName(sector.kind) << ','
                  << (std::isfinite(sector.rangeM) ? std::to_string(sector.rangeM) : std::string("inf")) << ','
                  << className(sector.danger) << '\n';
        }
    }
    truth.flush();
    if (!truth) {
        return reportFailure(Error{truthPath.string(), "cannot write the file", "check the folder"});
    }
    if (auto closed = writer->close(); !closed) {
        return reportFailure(Error{partPath.string(), std::string("cannot close: ") + closed.error().text(), ""});
    }
    std::error_code renamed;
    std::filesystem::rename(partPath, out, renamed);
    if (renamed) {
        return reportFailure(Error{partPath.string(), "cannot rename it to " + out.string() + ": " + renamed.message(),
                                   "check the folder's permissions"});
    }
    std::cout << "wrote " << count << " of " << course.poses.size() << " frames of the course to the recording "
              << out.string() << " (" << rig.width << "x" << rig.height << ", " << fps << " fps) and its ground truth "
              << truthPath.string() << "\n";
    return 0;
}

int runCourse(const Args& args)
{
    const std::string name = args.get("course");
    const auto fps = args.number("fps", kDefaultFps, 0.0, kMaxFps);
    const auto frames = args.number("frames", 0, 0, kMaxFrames);
    for (const auto* number : {&fps, &frames}) {
        if (!*number) {
            return reportUsageError("sim", number->error());
        }
    }
    if (*fps <= 0.0) {
        return reportFailure(Error{"ugvsense sim --fps", "frame rate " + args.get("fps") + " is not positive",
                                   "give frames per second, e.g. --fps 10"});
    }
    auto course = sim::makeCourse(name, kCourseSpeedMps, *fps);
    if (!course) {
        return reportFailure(Error{"ugvsense sim --course", course.error().what, course.error().fix});
    }
    const std::size_t total = course->poses.size();
    const std::size_t count =
        args.has("frames") && *frames >= 1.0 ? std::min(total, static_cast<std::size_t>(*frames)) : total;
    const std::filesystem::path out = args.get("out");
    if (out.extension() == ".ugvrec") {
        return writeCourseRecording(*course, count, *fps, args.has("colour"), out);
    }
    if (auto prepared = prepareOutput(out); !prepared) {
        return reportFailure(prepared.error());
    }
    if (auto written = sim::writeCalibration(course->scene.rig, out); !written) {
        return reportFailure(written.error());
    }
    const auto posesPath = out / "poses.csv";
    std::ofstream poses(posesPath);
    poses << "frame,t,x,y,yaw\n";
    for (std::size_t k = 0; k < count; ++k) {
        auto frame = sim::renderCourseFrame(*course, k);
        if (!frame) {
            return reportFailure(frame.error());
        }
        char stem[32];
        (void)std::snprintf(stem, sizeof(stem), "frame_%04zu", k);
        if (auto written = sim::writeSample(*frame, course->scene.rig, out, stem); !written) {
            return reportFailure(written.error());
        }
        const sim::Pose& pose = course->poses[k];
        poses << k << ',' << static_cast<double>(k) / *fps << ',' << pose.x << ',' << pose.y << ',' << pose.yawDeg
              << '\n';
    }
    poses.flush();
    if (!poses) {
        return reportFailure(Error{posesPath.string(), "cannot write the file", "check the folder"});
    }
    std::cout << "wrote " << count << " of " << total << " frames of course '" << name << "' to " << out.string()
              << " (frame_NNNN_*.png, frame_NNNN_sectors.json, calibration.yaml, poses.csv)\n";
    return 0;
}

} // namespace

int runSim(int argc, char** argv)
{
    Args args(
        "sim",
        "(--scene NAME | --course NAME) --out DIR [options] | --list\n"
        "  --scene chessboard: calibration pairs and truth.yaml ([--pairs N] [--seed S] [--noise SIGMA])\n"
        "  --scene NAME (ugvsense sim --list): one simulator sample with ground truth and calibration.yaml\n"
        "  --course NAME --out REC.ugvrec [--colour]: a recording of the drive (grey, or BGR with --colour) and "
        "REC.ugvrec.truth.csv (truth per frame and sector);\n"
        "  --course NAME --out DIR: numbered samples frame_NNNN_*, calibration.yaml and poses.csv (frame, t, x, "
        "y, yaw)",
        {{"scene", "NAME", "scene to render: chessboard, or a simulator scene (see --list)", false},
         {"course", "NAME", "course to render as a sequence (see --list)", false},
         {"out", "DIR|REC", "output folder (created if missing), or a course's recording REC.ugvrec", false},
         {"list", "", "print the scene and course names", false},
         {"range", "M", "simulator scene: obstacle range in metres, default 5", false},
         {"bearing", "DEG", "simulator scene: obstacle bearing, positive left, default 0", false},
         {"texture", "NAME", "simulator scene: asphalt|grass|gravel|floor, default asphalt", false},
         {"pitch", "DEG", "simulator scene: camera pitch, positive down, default 0", false},
         {"roll", "DEG", "simulator scene: camera roll, positive right side down, default 0", false},
         {"height", "M", "simulator scene: camera height above the ground, default 0.59", false},
         {"frames", "N", "course: number of frames to write, default all", false},
         {"colour", "", "course recording: both cameras in colour (BGR), for the one-camera detector", false},
         {"fps", "F", "course: frame rate (poses 1.5 m/s apart in time), default 10", false},
         {"pairs", "N", "chessboard: number of pairs, default 12", false},
         {"seed", "S", "random seed (chessboard poses and noise; simulator noise), default 1", false},
         {"noise", "SIGMA", "Gaussian noise in grey levels, default 1 (chessboard) or 1.5 (simulator scene)", false},
         {"condition", "LIST",
          "simulator scene: real-world conditions, comma-separated presets (ugvsense sim --list); the flags "
          "below override them",
          false},
         {"variant", "K", "simulator scene: which setting of each --condition preset, default 0", false},
         {"camber", "SLOPE", "simulator scene: road crown, fall per metre to both sides (0.025 = 2.5 %)", false},
         {"crown-y", "M", "simulator scene: lateral position (world y) of the crown line, default 0", false},
         {"grade", "CHANGE", "simulator scene: change of the forward slope (0.04 = +4 %, uphill beyond)", false},
         {"grade-at", "M", "simulator scene: forward distance of the grade change, default 8", false},
         {"kerb-height", "M", "simulator scene: kerb height; a flat pavement beyond --kerb-y", false},
         {"kerb-y", "M", "simulator scene: lateral position of the kerb face, default -2 (right)", false},
         {"right-gain", "G", "simulator scene: right camera gain relative to the left, default 1.02", false},
         {"right-offset", "GREY", "simulator scene: right camera offset in grey levels, default 0", false},
         {"vignette-left", "K", "simulator scene: left vignetting 1 - K (r/r_corner)^2, 0..0.9", false},
         {"vignette-right", "K", "simulator scene: right vignetting, 0..0.9", false},
         {"jpeg", "Q", "simulator scene: JPEG-compress both images at quality Q (1..100)", false},
         {"lanes", "Y,...", "simulator scene: lane lines along x at these lateral positions [m]", false},
         {"dash", "M", "simulator scene: lane line dash length, default 3", false},
         {"gap", "M", "simulator scene: gap between dashes, default 6; 0 = solid lines", false},
         {"stop-line", "X", "simulator scene: a stop line across the view at this forward distance [m]", false},
         {"rails", "Y,...", "simulator scene: tram tracks (two rails each) centred at these lateral positions", false},
         {"shadow", "X,Y,X,Y,X,Y...", "simulator scene: a hard shadow (albedo x 0.3) inside this polygon [m]", false},
         {"puddle", "X,Y,RX,RY,REFL",
          "simulator scene: an elliptic mirror-like puddle (centre, semi-axes [m], "
          "reflectance 0..1)",
          false},
         {"glossy", "REFL", "simulator scene: the whole floor mirrors with this reflectance (0..1)", false}});
    if (const auto exit = parseOrExit(args, argc, argv, "sim")) {
        return *exit;
    }
    if (args.has("list")) {
        std::string conditions;
        for (const auto& name : sim::conditionNames()) {
            conditions += (conditions.empty() ? "" : ", ") + name;
        }
        std::cout << "scenes: " << knownScenes() << "\ncourses: default\nconditions: " << conditions << '\n';
        return 0;
    }
    if (args.has("scene") == args.has("course")) {
        return reportUsageError("sim", Error{"ugvsense sim", "give exactly one of --scene NAME and --course NAME",
                                             "see 'ugvsense sim --help' and 'ugvsense sim --list'"});
    }
    if (!args.has("out")) {
        return reportUsageError(
            "sim", Error{"ugvsense sim", "missing required option '--out DIR'", "see 'ugvsense sim --help'"});
    }
    if (args.has("course")) {
        return runCourse(args);
    }
    return args.get("scene") == kChessboard ? runChessboard(args) : runCatalogueScene(args);
}

} // namespace ugv::tool
