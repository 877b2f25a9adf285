#include "ugv/adapters/config.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iterator>
#include <map>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "ugv/adapters/yaml_guard.hpp"
#include "ugv/ipc/dds_bus.hpp"

namespace ugv::adapters {
namespace {

/// The config is about 100 lines and 3 levels deep; more is not a config (yaml-cpp itself stops at 500 levels).
constexpr YamlLimits kConfigLimits{256U * 1024U, 16, false};

enum class Kind { Int, Double, Text, Path, Choice };

/// One config key: its type, range, description, and how to read and write it in ServiceConfig.
struct KeySpec {
    std::string path;
    std::string description;
    Kind kind = Kind::Double;
    double min = 0.0;
    double max = 0.0;
    std::vector<std::string> choices;
    std::function<void(ServiceConfig&, double)> setNumber;
    std::function<double(const ServiceConfig&)> getNumber;
    std::function<void(ServiceConfig&, const std::string&)> setText;
    std::function<std::string(const ServiceConfig&)> getText;
};

template <class Ref>
KeySpec numberKey(std::string path, Kind kind, double min, double max, std::string description, Ref ref)
{
    KeySpec key{std::move(path), std::move(description), kind, min, max, {}, {}, {}, {}, {}};
    key.setNumber = [ref](ServiceConfig& c, double v) {
        ref(c) = static_cast<std::remove_reference_t<decltype(ref(c))>>(v);
    };
    key.getNumber = [ref](const ServiceConfig& c) { return static_cast<double>(ref(c)); };
    return key;
}

template <class Ref>
KeySpec textKey(std::string path, Kind kind, std::string description, Ref ref)
{
    KeySpec key{std::move(path), std::move(description), kind, 0, 0, {}, {}, {}, {}, {}};
    key.setText = [ref](ServiceConfig& c, const std::string& v) { ref(c) = v; };
    key.getText = [ref](const ServiceConfig& c) { return ref(c); };
    return key;
}

template <class E, class Ref>
KeySpec choiceKey(std::string path, std::string description, std::vector<std::pair<std::string, E>> names, Ref ref)
{
    KeySpec key{std::move(path), std::move(description), Kind::Choice, 0, 0, {}, {}, {}, {}, {}};
    for (const auto& [name, value] : names) {
        key.choices.push_back(name);
    }
    key.setText = [ref, names](ServiceConfig& c, const std::string& v) {
        for (const auto& [name, value] : names) {
            if (name == v) {
                ref(c) = value;
            }
        }
    };
    key.getText = [ref, names](const ServiceConfig& c) {
        for (const auto& [name, value] : names) {
            if (ref(c) == value) {
                return name;
            }
        }
        return std::string("?");
    };
    return key;
}

// The member `member` of a ServiceConfig, const or not (the getters read through the same accessor).
#define UGV_REF(member) ([](auto& c) -> auto& { return c.member; })

// The vehicle, its calibration and its cameras.
std::vector<KeySpec> cameraKeys()
{
    return {
        textKey("vehicle_id", Kind::Text, "name of this vehicle in published messages", UGV_REF(vehicleId)),
        textKey("calibration", Kind::Path,
                "stereo calibration file written by 'ugvsense calibrate' ($UGV_CALIBRATION overrides)",
                UGV_REF(calibrationPath)),
        choiceKey<CameraBackend>(
            "camera.backend", "where frames come from",
            {{"v4l2", CameraBackend::V4l2}, {"libcamera", CameraBackend::Libcamera}, {"replay", CameraBackend::Replay}},
            UGV_REF(camera.backend)),
        textKey("camera.left_device", Kind::Text, "V4L2 device of the left camera (or the side-by-side stereo device)",
                UGV_REF(camera.leftDevice)),
        textKey("camera.right_device", Kind::Text,
                "V4L2 device of the right camera; empty for a side-by-side device; none for one camera (the one-camera "
                "mode, obstacles.detector: colour)",
                UGV_REF(camera.rightDevice)),
        numberKey("camera.width", Kind::Int, 64, 4096, "image width per camera [px]", UGV_REF(camera.width)),
        numberKey("camera.height", Kind::Int, 48, 4096, "image height per camera [px]", UGV_REF(camera.height)),
        numberKey("camera.fps", Kind::Double, 1, 240, "camera frame rate [Hz]; the frame deadline is 1/fps",
                  UGV_REF(camera.fps)),
        numberKey("camera.max_pair_skew_ms", Kind::Double, 0, 100,
                  "left/right timestamps further apart are not paired [ms]", UGV_REF(camera.maxPairSkewMs)),
        choiceKey<PixelFormatChoice>("camera.format", "V4L2 pixel format: yuyv or grey",
                                     {{"yuyv", PixelFormatChoice::Yuyv}, {"grey", PixelFormatChoice::Grey}},
                                     UGV_REF(camera.format)),
        choiceKey<ColourChoice>(
            "camera.colour",
            "BGR frames for the one-camera detector and stereo's fallback to the left camera: auto = from a V4L2 "
            "yuyv camera; true = also from libcamera (its YUV420 converted); false = grey (the Y plane: saves a "
            "conversion)",
            {{"auto", ColourChoice::Auto}, {"true", ColourChoice::On}, {"false", ColourChoice::Off}},
            UGV_REF(camera.colour)),
        textKey("camera.replay_path", Kind::Path, "recording to replay (backend: replay)", UGV_REF(camera.replayPath)),
        choiceKey<ReplayPace>(
            "camera.replay_pace", "replay pace: as recorded, at replay_fps, or as fast as possible",
            {{"recorded", ReplayPace::Recorded}, {"fixed", ReplayPace::Fixed}, {"fastest", ReplayPace::Fastest}},
            UGV_REF(camera.replayPace)),
        numberKey("camera.replay_fps", Kind::Double, 0.1, 1000, "replay rate when replay_pace is fixed [Hz]",
                  UGV_REF(camera.replayFps)),
        choiceKey<bool>("camera.replay_loop", "replay the recording over and over (backend: replay)",
                        {{"true", true}, {"false", false}}, UGV_REF(camera.replayLoop)),
    };
}

// The region of interest, the matcher, the obstacle detector, overload and handover.
std::vector<KeySpec> visionKeys()
{
    return {
        numberKey("roi.top_fraction", Kind::Double, 0.0, 0.9,
                  "first row of the region of interest, as a fraction of the height", UGV_REF(roi.topFraction)),
        numberKey("roi.matcher_margin_rows", Kind::Int, 0, 64,
                  "rows above the region of interest that the matcher reads [px]", UGV_REF(roi.matcherMarginRows)),
        choiceKey<MatcherMode>("stereo.mode", "matcher: our census SGM, or an OpenCV StereoSGBM mode",
                               {vision::kMatcherModes.begin(), vision::kMatcherModes.end()}, UGV_REF(stereo.mode)),
        numberKey("stereo.num_disparities", Kind::Int, 16, 256, "disparity search range [px], a multiple of 16",
                  UGV_REF(stereo.numDisparities)),
        numberKey("stereo.block_size", Kind::Int, 1, 11, "matching block size [px], odd", UGV_REF(stereo.blockSize)),
        choiceKey<bool>("stereo.ground_range",
                        "census SGM: each row searches only the disparities from a little below the previous "
                        "frame's ground up (full range without a reliable ground estimate)",
                        {{"true", true}, {"false", false}}, UGV_REF(stereo.groundRange)),
        numberKey("stereo.ground_range_drop_m", Kind::Double, 0.05, 10,
                  "ground_range: drops down to this far below the ground are searched at their true depth [m]",
                  UGV_REF(stereo.groundRangeDropM)),
        numberKey("stereo.ground_range_margin_deg", Kind::Double, 0, 10,
                  "ground_range: pitch and roll change between two frames that the search floor absorbs [deg]",
                  UGV_REF(stereo.groundRangeMarginDeg)),
        numberKey("stereo.half_resolution_min_ground_px", Kind::Double, 0, 1000,
                  "census SGM: the ROI rows where the mount's ground disparity is at least this are matched at half "
                  "resolution (0: every row at full resolution) [px]",
                  UGV_REF(stereo.halfResolutionMinGroundPx)),
        choiceKey<DetectorMode>(
            "obstacles.detector", "stereo (two cameras), colour (one camera) or both",
            {{"stereo", DetectorMode::Stereo}, {"colour", DetectorMode::Colour}, {"both", DetectorMode::Both}},
            UGV_REF(obstacles.detector)),
        numberKey("obstacles.sector_count", Kind::Int, 4, 180, "bearing sectors across the horizontal field of view",
                  UGV_REF(obstacles.sectorCount)),
        numberKey("obstacles.danger_distance_m", Kind::Double, 0.1, 50, "obstacles closer than this are red [m]",
                  UGV_REF(obstacles.dangerDistanceM)),
        numberKey("obstacles.caution_distance_m", Kind::Double, 0.1, 100,
                  "obstacles closer than this are blue, beyond green [m]", UGV_REF(obstacles.cautionDistanceM)),
        numberKey("obstacles.min_height_m", Kind::Double, 0.02, 2, "positive obstacles taller than this count [m]",
                  UGV_REF(obstacles.minHeightM)),
        numberKey("obstacles.min_depth_m", Kind::Double, 0.02, 2, "negative obstacles deeper than this count [m]",
                  UGV_REF(obstacles.minDepthM)),
        numberKey("obstacles.max_range_disparity_px", Kind::Double, 2, 128,
                  "the detector looks as far as the disparity stays at or above this [px]: to f B / this",
                  UGV_REF(obstacles.maxRangeDisparityPx)),
        choiceKey<OverloadChoice>(
            "overload.policy",
            "when a frame would miss its deadline: degrade (ground-plane-only sectors, flagged) or drop (queue of one)",
            {{"degrade", OverloadChoice::Degrade}, {"drop", OverloadChoice::Drop}}, UGV_REF(overload.policy)),
        numberKey("overload.deadline_factor", Kind::Double, 0.1, 10,
                  "deadline = this many camera periods from exposure to published sectors",
                  UGV_REF(overload.deadlineFactor)),
        numberKey("handover.spin_us", Kind::Int, 0, 10000,
                  "the vision task polls the frame ring this long before and after each frame is due, instead of "
                  "sleeping (faster wake-up across cores, about this much CPU per frame) [us]; 0 = off",
                  UGV_REF(handover.spinUs)),
        choiceKey<bool>("vision.enabled", "false: no camera, no vision (a ground station running only the correlator)",
                        {{"true", true}, {"false", false}}, UGV_REF(visionEnabled)),
    };
}

// The DDS bus and its security.
std::vector<KeySpec> ddsKeys()
{
    return {
        choiceKey<bool>("dds.enabled", "join the DDS bus: sectors, ROS 2 scans, health out; poses in",
                        {{"true", true}, {"false", false}}, UGV_REF(dds.enabled)),
        numberKey("dds.domain_id", Kind::Int, 0, 232,
                  "DDS domain, the same on every vehicle and the ground station; not given: $ROS_DOMAIN_ID, else 0",
                  UGV_REF(dds.domainId)),
        textKey("dds.partition", Kind::Text, "DDS partition of our topics (a team); empty = the default partition",
                UGV_REF(dds.partition)),
        textKey("dds.ros_namespace", Kind::Text,
                "ROS 2 topics rt/<ns>/obstacle_scan...; empty = vehicle_id without its - (ugv-1: ugv1)",
                UGV_REF(dds.rosNamespace)),
        textKey("dds.frame_id", Kind::Text, "frame of the LaserScan and PointCloud2: on the ground below the camera",
                UGV_REF(dds.frameId)),
        textKey(
            "dds.discovery_server", Kind::Text,
            "empty = multicast discovery; IP:PORT[;IP:PORT] of Fast DDS discovery servers (meshes without multicast)",
            UGV_REF(dds.discoveryServer)),
        choiceKey<bool>("dds.ros_reliability",
                        "the ROS 2 scan and cloud: reliable (keep last 1: RViz's and ros2 topic echo's default "
                        "readers match, and best-effort ones too) or best_effort (only best-effort readers match)",
                        {{"reliable", true}, {"best_effort", false}}, UGV_REF(dds.rosReliable)),
        choiceKey<bool>("dds.shared_memory", "also Fast DDS shared memory between processes of this host",
                        {{"true", true}, {"false", false}}, UGV_REF(dds.sharedMemory)),
        numberKey("dds.pose_max_age_ms", Kind::Double, 1, 60000,
                  "a vehicle pose further than this from a frame's capture time is flagged stale [ms]",
                  UGV_REF(dds.poseMaxAgeMs)),
        choiceKey<bool>("dds.security.enabled",
                        "DDS Security: authenticated, access-controlled, encrypted bus (the files below; "
                        "bringup/deploy/security/make_security.sh makes them)",
                        {{"true", true}, {"false", false}}, UGV_REF(dds.security.enabled)),
        textKey("dds.security.identity_ca", Kind::Path, "identity CA certificate (PEM)",
                UGV_REF(dds.security.identityCa)),
        textKey("dds.security.certificate", Kind::Path, "this vehicle's certificate (PEM; its CN is vehicle_id)",
                UGV_REF(dds.security.certificate)),
        textKey("dds.security.private_key", Kind::Path, "this vehicle's private key (PEM)",
                UGV_REF(dds.security.privateKey)),
        textKey("dds.security.permissions_ca", Kind::Path, "permissions CA certificate (PEM)",
                UGV_REF(dds.security.permissionsCa)),
        textKey("dds.security.governance", Kind::Path, "signed governance document (S/MIME)",
                UGV_REF(dds.security.governance)),
        textKey("dds.security.permissions", Kind::Path, "this vehicle's signed permissions document (S/MIME)",
                UGV_REF(dds.security.permissions)),
    };
}

// The OOI correlator.
std::vector<KeySpec> correlatorKeys()
{
    return {
        choiceKey<bool>("correlator.enabled", "run the OOI correlator on the bus's observations (lowest priority)",
                        {{"true", true}, {"false", false}}, UGV_REF(correlator.enabled)),
        choiceKey<correlator::Mode>("correlator.mode",
                                    "pose-corrected (default) or original (the published algorithm); improved is "
                                    "an alias of pose-corrected",
                                    {{"pose-corrected", correlator::Mode::PoseCorrected},
                                     {"improved", correlator::Mode::PoseCorrected},
                                     {"original", correlator::Mode::Original}},
                                    UGV_REF(correlator.mode)),
        numberKey("correlator.period_s", Kind::Double, 0.01, 3600, "mission-time period of the correlated list [s]",
                  UGV_REF(correlator.periodS)),
        numberKey("correlator.reorder_ms", Kind::Double, 0, 60000,
                  "a received input waits this long to be put in time order with the others [ms]",
                  UGV_REF(correlator.reorderMs)),
        numberKey("correlator.late_window_s", Kind::Double, 0, 3600,
                  "an input up to this much older than the latest applied one is still put in its place (the state "
                  "is rolled back and replayed: a UGV back from a radio dropout); 0 = refused [s]",
                  UGV_REF(correlator.lateWindowS)),
        numberKey("correlator.startup_hold_ms", Kind::Double, 0, 600000,
                  "after the first input nothing is applied this long: a (re)started station gathers the team's "
                  "histories first [ms]",
                  UGV_REF(correlator.startupHoldMs)),
        textKey("correlator.log_dir", Kind::Path,
                "folder of inputs.jsonl (every accepted input) and snapshots.jsonl; empty = no log",
                UGV_REF(correlator.logDir)),
        numberKey("correlator.max_rate_per_source", Kind::Double, 1, 1e6,
                  "inputs per second one participant may send; beyond it they are refused and counted (a flood)",
                  UGV_REF(correlator.maxRatePerSource)),
        numberKey("correlator.max_clock_skew_ms", Kind::Double, 0, 3600000,
                  "inputs stamped further ahead of this host's clock are refused and counted (keep the hosts' clocks "
                  "synchronised) [ms]",
                  UGV_REF(correlator.maxClockSkewMs)),
    };
}

std::vector<KeySpec> baseKeys()
{
    std::vector<KeySpec> keys;
    for (auto part : {cameraKeys, visionKeys, ddsKeys, correlatorKeys}) {
        std::vector<KeySpec> section = part();
        keys.insert(keys.end(), std::make_move_iterator(section.begin()), std::make_move_iterator(section.end()));
    }
    return keys;
}

std::vector<KeySpec> taskKeys();

const std::vector<KeySpec>& schema()
{
    static const std::vector<KeySpec> keys = [] {
        std::vector<KeySpec> all = baseKeys();
        for (auto& key : taskKeys()) {
            all.push_back(std::move(key));
        }
        return all;
    }();
    return keys;
}

/// The `tasks.<name>.*` keys, one set per row of rt's default task table.
std::vector<KeySpec> taskKeys()
{
    std::vector<KeySpec> keys;
    for (std::size_t i = 0; i < rt::kDefaultTaskTable.size(); ++i) {
        const std::string prefix = "tasks." + std::string(rt::kDefaultTaskTable[i].name) + ".";
        keys.push_back(choiceKey<rt::SchedPolicy>(
            prefix + "policy", "scheduling policy of this thread",
            {{"fifo", rt::SchedPolicy::Fifo}, {"other", rt::SchedPolicy::Other}}, [i](auto& c) -> auto& {
                return c.tasks[i].policy;
            }));
        keys.push_back(numberKey(
            prefix + "priority", Kind::Int, 0, 99,
            "priority: 1..99 with fifo (higher first), 0 with other", [i](auto& c) -> auto& {
                return c.tasks[i].priority;
            }));
        keys.push_back(numberKey(
            prefix + "cpu", Kind::Int, -1, 1023,
            "CPU to pin the thread to, -1 for any", [i](auto& c) -> auto& { return c.tasks[i].cpu; }));
    }
    return keys;
}

#undef UGV_REF

const KeySpec* findKey(const std::string& path)
{
    for (const auto& key : schema()) {
        if (key.path == path) {
            return &key;
        }
    }
    return nullptr;
}

/// Edit distance, for "did you mean" hints on misspelt keys.
std::size_t editDistance(const std::string& a, const std::string& b)
{
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) {
        row[j] = j;
    }
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t above = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
            diagonal = above;
        }
    }
    return row[b.size()];
}

std::string closestKey(const std::string& path)
{
    std::string best;
    std::size_t bestDistance = 3; // suggest only close spellings
    for (const auto& key : schema()) {
        if (const std::size_t d = editDistance(path, key.path); d < bestDistance) {
            best = key.path;
            bestDistance = d;
        }
    }
    return best;
}

bool isSection(const std::string& path)
{
    for (const auto& key : schema()) {
        if (key.path.rfind(path + ".", 0) == 0) {
            return true;
        }
    }
    return false;
}

std::string formatNumber(double value)
{
    std::ostringstream out;
    out << value;
    return out.str();
}

std::string rangeText(const KeySpec& key)
{
    switch (key.kind) {
    case Kind::Int:
        return "an integer in [" + formatNumber(key.min) + ", " + formatNumber(key.max) + "]";
    case Kind::Double:
        return "a number in [" + formatNumber(key.min) + ", " + formatNumber(key.max) + "]";
    case Kind::Choice: {
        std::string text = "one of";
        for (const auto& choice : key.choices) {
            text += " " + choice;
        }
        return text;
    }
    case Kind::Text:
    case Kind::Path:
        return "a string";
    }
    return {};
}

class Parser {
public:
    Parser(std::string source, std::string baseDir) : source_(std::move(source)), baseDir_(std::move(baseDir)) {}

    // NOLINTNEXTLINE(misc-no-recursion): one level per nesting level, which the YAML guard bounds (maxDepth) first
    void walk(const YAML::Node& map, const std::string& prefix)
    {
        std::map<std::string, int> seen; // name -> line, for duplicates (yaml-cpp keeps both)
        for (const auto& item : map) {
            const std::string name = item.first.as<std::string>();
            const std::string path = prefix.empty() ? name : std::string(prefix).append(".").append(name);
            const YAML::Node& value = item.second;
            if (const auto [first, fresh] = seen.emplace(name, item.first.Mark().line + 1); !fresh) {
                error(item.first, path, "is given twice (first at line " + std::to_string(first->second) + ")",
                      "keep one of them");
                continue;
            }
            if (const KeySpec* key = findKey(path)) {
                setLeaf(*key, value);
            } else if (isSection(path)) {
                if (!value.IsMap()) {
                    error(value, path, "is a section and needs nested keys", "indent its keys below '" + name + ":'");
                } else {
                    walk(value, path);
                }
            } else {
                const std::string hint = closestKey(path);
                error(item.first, path, "unknown key",
                      (hint.empty() ? std::string("remove it") : "did you mean '" + hint + "'?") +
                          " ('ugvsense check-config --schema' lists every key)");
            }
        }
    }

    void crossCheck(const YAML::Node& root)
    {
        const auto at = [&root](const char* section) { return root[section] ? root[section] : root; };
        const auto atKey = [&at](const char* section, const char* key) {
            const YAML::Node s = at(section);
            return s.IsMap() && s[key] ? s[key] : s;
        };
        if (config_.obstacles.cautionDistanceM <= config_.obstacles.dangerDistanceM) {
            error(at("obstacles"), "obstacles.caution_distance_m",
                  "value " + formatNumber(config_.obstacles.cautionDistanceM) + " is not above danger_distance_m (" +
                      formatNumber(config_.obstacles.dangerDistanceM) + ")",
                  "make caution_distance_m larger than danger_distance_m");
        }
        if (config_.stereo.numDisparities % 16 != 0) {
            error(at("stereo"), "stereo.num_disparities",
                  "value " + std::to_string(config_.stereo.numDisparities) + " is not a multiple of 16",
                  "use 16, 32, 64, 128 or 256");
        }
        if (config_.obstacles.maxRangeDisparityPx >= config_.stereo.numDisparities) {
            error(at("obstacles"), "obstacles.max_range_disparity_px",
                  "value " + formatNumber(config_.obstacles.maxRangeDisparityPx) +
                      " is not below stereo.num_disparities (" + std::to_string(config_.stereo.numDisparities) +
                      "): the detector would look nowhere the matcher searches",
                  "lower max_range_disparity_px (default " + formatNumber(ObstacleConfig{}.maxRangeDisparityPx) +
                      ") or raise num_disparities");
        }
        if (config_.stereo.numDisparities >= config_.camera.width) {
            error(at("stereo"), "stereo.num_disparities",
                  "value " + std::to_string(config_.stereo.numDisparities) + " is not below the image width " +
                      std::to_string(config_.camera.width),
                  "lower num_disparities");
        }
        if (config_.stereo.groundRange && config_.stereo.mode != MatcherMode::CensusSgm) {
            error(at("stereo"), "stereo.ground_range",
                  std::string("is true but stereo.mode is ") +
                      std::string(vision::matcherModeName(config_.stereo.mode)),
                  "only census_sgm searches ground-guided ranges: set mode: census_sgm or ground_range: false");
        }
        if (config_.stereo.halfResolutionMinGroundPx > 0.0 &&
            (config_.stereo.mode != MatcherMode::CensusSgm || config_.stereo.numDisparities % 32 != 0)) {
            error(at("stereo"), "stereo.half_resolution_min_ground_px",
                  "is " + std::to_string(config_.stereo.halfResolutionMinGroundPx) + " with stereo.mode " +
                      std::string(vision::matcherModeName(config_.stereo.mode)) + " and num_disparities " +
                      std::to_string(config_.stereo.numDisparities),
                  "only census_sgm matches rows at half resolution, with num_disparities a multiple of 32: set "
                  "half_resolution_min_ground_px: 0 or mode: census_sgm");
        }
        if (config_.stereo.blockSize % 2 == 0) {
            error(at("stereo"), "stereo.block_size", "value " + std::to_string(config_.stereo.blockSize) + " is even",
                  "use an odd size such as 5");
        }
        if (config_.visionEnabled && config_.camera.backend == CameraBackend::Replay &&
            config_.camera.replayPath.empty()) {
            error(at("camera"), "camera.replay_path", "is empty but camera.backend is replay",
                  "set replay_path to a recording");
        }
        if (config_.camera.rightDevice == kNoRightCamera && config_.obstacles.detector != DetectorMode::Colour) {
            error(at("camera"), "camera.right_device",
                  "is none (one camera) but obstacles.detector needs a stereo pair",
                  "set obstacles.detector: colour for a one-camera rig, or name the right camera's device");
        }
        if (config_.camera.colour == ColourChoice::On && config_.camera.backend == CameraBackend::V4l2 &&
            config_.camera.format == PixelFormatChoice::Grey) {
            error(at("camera"), "camera.colour", "is true but camera.format is grey (a grey camera has no colour)",
                  "set camera.format: yuyv for colour, or camera.colour: auto");
        }
        if (config_.camera.backend == CameraBackend::V4l2 && config_.camera.leftDevice.empty()) {
            error(at("camera"), "camera.left_device", "is empty but camera.backend is v4l2",
                  "set it, e.g. /dev/video0");
        }
        const int cpus = rt::onlineCpuCount();
        for (const auto& task : config_.tasks) {
            if (auto valid = rt::validateTask(task, cpus); !valid) {
                const YAML::Node tasks = at("tasks");
                const std::string name(task.name);
                error(tasks[name] ? tasks[name] : tasks, "tasks." + name, valid.error().what,
                      "set tasks." + name + ".policy/priority/cpu within the range");
            }
        }
        if (!config_.visionEnabled && !config_.correlator.enabled) {
            error(at("vision"), "vision.enabled", "is false and correlator.enabled is false: nothing to run",
                  "enable one of them");
        }
        if (config_.correlator.enabled && !config_.dds.enabled) {
            error(at("dds"), "dds.enabled", "is false but the correlator needs the bus", "set dds.enabled: true");
        }
        checkNames(at, atKey);
        checkSecurity(root);
        if (config_.calibrationPath.empty()) {
            error(root, "calibration", "is empty", "set it to the file written by 'ugvsense calibrate'");
        }
    }

    /// Names the bus carries (bounded at ipc::dds::kMaxNameLength there) and the discovery server list, as the
    /// service's ipc::dds::validate() reads them, but with the key and line.
    template <class At, class AtKey>
    void checkNames(const At& at, const AtKey& atKey)
    {
        const std::string& id = config_.vehicleId;
        // No control characters (UTF-8 letters are fine): the name goes into messages and logs.
        const bool printable = std::none_of(id.begin(), id.end(), [](char c) {
            const auto u = static_cast<unsigned char>(c);
            return u < 0x20 || u == 0x7F;
        });
        if (id.empty() || id.size() > ipc::dds::kMaxNameLength || !printable) {
            error(at("vehicle_id"), "vehicle_id",
                  "'" + (printable ? id : std::string("(unprintable)")) + "' (" + std::to_string(id.size()) +
                      " characters) is not a vehicle name",
                  "give 1 to " + std::to_string(ipc::dds::kMaxNameLength) +
                      " characters without control characters, e.g. ugv-1");
        }
        const std::string& ns = config_.dds.rosNamespace;
        const bool nameChars =
            ns.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_/") ==
            std::string::npos;
        if (!ns.empty() && (!nameChars || ns.front() == '/' || ns.back() == '/' || ns.find("//") != std::string::npos ||
                            ns.size() > ipc::dds::kMaxNameLength)) {
            error(atKey("dds", "ros_namespace"), "dds.ros_namespace", "'" + ns + "' is not a ROS 2 namespace",
                  "letters, digits, _ and inner single /, at most " + std::to_string(ipc::dds::kMaxNameLength) +
                      " characters, e.g. ugv1 or team/ugv1");
        }
        if (auto servers = ipc::dds::checkDiscoveryServers(config_.dds.discoveryServer, "dds.discovery_server");
            !servers) {
            error(atKey("dds", "discovery_server"), "dds.discovery_server", servers.error().what, servers.error().fix);
        }
    }

    /// dds.security.*: every file as ipc::dds::checkSecurityFile() reads it (the service's Bus::create checks the
    /// same), each error at its key's line; vehicle_id names the write partition, so it must suit one.
    void checkSecurity(const YAML::Node& root)
    {
        const ipc::dds::SecurityConfig sec = securityOf(config_);
        if (!sec.enabled || !config_.dds.enabled) {
            return;
        }
        const YAML::Node dds = root["dds"];
        const YAML::Node section = dds.IsMap() && dds["security"] ? dds["security"] : dds;
        for (const ipc::dds::SecurityFile& f : ipc::dds::securityFiles(sec)) {
            const std::string key = std::string("dds.security.") + f.key;
            if (auto ok = ipc::dds::checkSecurityFile(f, key); !ok) {
                error(section.IsMap() && section[f.key] ? section[f.key] : section, key, ok.error().what,
                      ok.error().fix);
            }
        }
        if (auto ok = ipc::dds::checkIdentity(sec.identity, "vehicle_id"); !ok) {
            error(root["vehicle_id"] ? root["vehicle_id"] : root, "vehicle_id",
                  ok.error().what + " (with dds.security.enabled it is the certificate's name and the partition "
                                    "this vehicle writes in)",
                  ok.error().fix);
        }
    }

    ServiceConfig& config() { return config_; }
    ConfigErrors& errors() { return errors_; }

    void error(const YAML::Node& node, const std::string& key, const std::string& what, const std::string& fix)
    {
        std::string where = source_;
        if (node.IsDefined() && node.Mark().line >= 0) {
            where += ":" + std::to_string(node.Mark().line + 1);
        }
        errors_.push_back(Error{where + " (" + key + ")", what, fix});
    }

private:
    void setLeaf(const KeySpec& key, const YAML::Node& value)
    {
        if (!value.IsScalar()) {
            error(value, key.path, value.IsNull() ? "has no value" : "must be a single value, not a list or map",
                  "give " + rangeText(key) + ": " + key.description);
            return;
        }
        const std::string& text = value.Scalar();
        if (key.kind == Kind::Text || key.kind == Kind::Path) {
            std::string resolved = text;
            if (key.kind == Kind::Path && !text.empty() && std::filesystem::path(text).is_relative()) {
                resolved = (std::filesystem::path(baseDir_) / text).lexically_normal().string();
            }
            key.setText(config_, resolved);
            return;
        }
        if (key.kind == Kind::Choice) {
            for (const auto& choice : key.choices) {
                if (choice == text) {
                    key.setText(config_, text);
                    return;
                }
            }
            error(value, key.path, "value '" + text + "' is not allowed", "give " + rangeText(key));
            return;
        }
        char* end = nullptr;
        const double number = std::strtod(text.c_str(), &end);
        const bool parsed = !text.empty() && end == text.c_str() + text.size();
        if (!parsed || !std::isfinite(number) || number < key.min || number > key.max ||
            (key.kind == Kind::Int && number != std::floor(number))) {
            error(value, key.path,
                  "value '" + text + "' is " +
                      (parsed && std::isfinite(number) ? "out of range" : "not a valid number"),
                  "give " + rangeText(key) + ": " + key.description);
            return;
        }
        key.setNumber(config_, number);
    }

    std::string source_;
    std::string baseDir_;
    ServiceConfig config_;
    ConfigErrors errors_;
};

/// ROS 2's $ROS_DOMAIN_ID when the file gives no dds.domain_id: a vehicle already set up for ROS 2 joins its domain.
void applyRosDomainId(const YAML::Node& root, ServiceConfig& config, ConfigErrors& errors)
{
    if (const YAML::Node dds = root["dds"]; dds.IsDefined() && dds.IsMap() && dds["domain_id"].IsDefined()) {
        return;
    }
    const auto domain = ipc::dds::domainFromEnvironment("ROS_DOMAIN_ID");
    if (!domain) {
        Error e = domain.error();
        e.fix += " (or set dds.domain_id, which wins over it)";
        errors.push_back(std::move(e));
        return;
    }
    if (domain->has_value()) {
        config.dds.domainId = **domain;
    }
}

} // namespace

bool captureInColour(const ServiceConfig& config)
{
    switch (config.camera.colour) {
    case ColourChoice::On:
        return true;
    case ColourChoice::Off:
        return false;
    case ColourChoice::Auto:
        break;
    }
    return config.camera.backend == CameraBackend::V4l2 && config.camera.format == PixelFormatChoice::Yuyv;
}

ipc::dds::SecurityConfig securityOf(const ServiceConfig& config)
{
    const DdsSecurityConfig& s = config.dds.security;
    return ipc::dds::SecurityConfig{s.enabled,       s.identityCa, s.certificate, s.privateKey,
                                    s.permissionsCa, s.governance, s.permissions, config.vehicleId};
}

Result<ServiceConfig, ConfigErrors> parseConfig(const std::string& yamlText, const std::string& sourceName,
                                                const std::string& baseDir)
{
    if (auto bounded = checkYamlText(yamlText, sourceName, kConfigLimits); !bounded) {
        return Unexpected(ConfigErrors{bounded.error()});
    }
    YAML::Node root;
    try {
        root = YAML::Load(yamlText);
    } catch (const YAML::Exception& e) {
        return Unexpected(ConfigErrors{
            Error{sourceName + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1),
                  "not valid YAML: " + e.msg, "fix the syntax at that line (is the file truncated?)"}});
    }
    if (root.IsNull()) {
        return Unexpected(
            ConfigErrors{Error{sourceName, "the file is empty", "start from bringup/deploy/config.example.yaml"}});
    }
    if (!root.IsMap()) {
        return Unexpected(ConfigErrors{
            Error{sourceName, "the top level is not a map of keys", "start from bringup/deploy/config.example.yaml"}});
    }
    Parser parser(sourceName, baseDir);
    try {
        parser.walk(root, "");
    } catch (const YAML::Exception& e) {
        parser.errors().push_back(Error{sourceName + ":" + std::to_string(e.mark.line + 1), "unexpected YAML: " + e.msg,
                                        "keys must be plain strings"});
    }
    if (const char* env = std::getenv("UGV_CALIBRATION"); env != nullptr && *env != '\0') {
        parser.config().calibrationPath = env;
    }
    applyRosDomainId(root, parser.config(), parser.errors());
    parser.crossCheck(root);
    if (!parser.errors().empty()) {
        return Unexpected(std::move(parser.errors()));
    }
    parser.config().sourceFile = sourceName;
    return std::move(parser.config());
}

Result<ServiceConfig, ConfigErrors> loadConfig(const std::string& path)
{
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        return Unexpected(ConfigErrors{
            Error{path, "config file not found or not a regular file",
                  "pass an existing file, e.g. 'ugvsense check-config bringup/deploy/config.example.yaml'"}});
    }
    auto text = readTextFile(path, kConfigLimits.maxBytes, "pass an existing config file");
    if (!text) {
        return Unexpected(ConfigErrors{text.error()});
    }
    const std::string baseDir = std::filesystem::absolute(path, ec).parent_path().string();
    return parseConfig(*text, path, baseDir);
}

std::string formatConfig(const ServiceConfig& config)
{
    std::ostringstream out;
    out << "# effective ugvsense config (from " << (config.sourceFile.empty() ? "defaults" : config.sourceFile)
        << ")\n";
    std::vector<std::string> open; // the sections the previous key was in
    for (const auto& key : schema()) {
        std::vector<std::string> parts;
        for (std::size_t start = 0;;) {
            const auto dot = key.path.find('.', start);
            parts.push_back(key.path.substr(start, dot - start));
            if (dot == std::string::npos) {
                break;
            }
            start = dot + 1;
        }
        std::size_t common = 0;
        while (common < open.size() && common + 1 < parts.size() && open[common] == parts[common]) {
            ++common;
        }
        open.resize(common);
        for (std::size_t level = common; level + 1 < parts.size(); ++level) {
            out << std::string(2 * level, ' ') << parts[level] << ":\n";
            open.push_back(parts[level]);
        }
        const std::string value = key.getText ? "\"" + key.getText(config) + "\"" : formatNumber(key.getNumber(config));
        std::string line = std::string(2 * open.size(), ' ') + parts.back() + ": " + value;
        if (line.size() < 44) {
            line.resize(44, ' ');
        }
        out << line << " # " << key.description << "; " << rangeText(key) << '\n';
    }
    return out.str();
}

std::string configPath(const char* fromArgs)
{
    if (fromArgs != nullptr && *fromArgs != '\0') {
        return fromArgs;
    }
    if (const char* env = std::getenv("UGV_CONFIG"); env != nullptr && *env != '\0') {
        return env;
    }
    return "/etc/ugvsense/config.yaml";
}

} // namespace ugv::adapters
