#pragma once

/// @file
/// The service configuration: one YAML file (default /etc/ugvsense/config.yaml; path from argv or
/// $UGV_CONFIG), parsed once at start into immutable typed structs. Every key has a type, a default, an
/// allowed range and a description (the schema in config.cpp, which `ugvsense check-config` prints).
/// Unknown keys, wrong types and out-of-range values are errors; all errors are collected, each naming
/// the file, line, key, bad value and allowed range. A config with any error refuses to start.
///
/// Environment overrides (paths and log levels only): $UGV_CALIBRATION replaces `calibration`.
///
/// Thread-safety: load/parse are reentrant; the result is immutable. RT-safe: no (init only).

#include <array>
#include <string>
#include <vector>

#include "ugv/correlator/mode.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/rt/task.hpp"
#include "ugv/vision/matcher_mode.hpp"

namespace ugv::ipc::dds {
struct SecurityConfig; // ugv/ipc/dds_bus.hpp
} // namespace ugv::ipc::dds

namespace ugv::adapters {

enum class CameraBackend { V4l2, Libcamera, Replay };
enum class ReplayPace { Recorded, Fixed, Fastest };
enum class PixelFormatChoice { Yuyv, Grey };
enum class ColourChoice { Auto, On, Off };
enum class OverloadChoice { Degrade, Drop };
enum class DetectorMode { Stereo, Colour, Both };
using MatcherMode = vision::MatcherMode; ///< names and parsing in ugv/vision/matcher_mode.hpp

/// camera.right_device of a one-camera rig (the one-camera mode: obstacles.detector colour).
inline constexpr const char* kNoRightCamera = "none";

struct CameraConfig {
    CameraBackend backend = CameraBackend::Replay;
    std::string leftDevice = "/dev/video0"; ///< V4L2 left device (or the side-by-side device)
    std::string rightDevice =
        "/dev/video1";          ///< right device; empty = side-by-side on leftDevice; kNoRightCamera = one camera
    int width = 640;            ///< [px] per camera
    int height = 480;           ///< [px]
    double fps = 30.0;          ///< [Hz] frame rate; the frame deadline is 1/fps
    double maxPairSkewMs = 5.0; ///< [ms] left/right timestamps further apart are not paired
    PixelFormatChoice format = PixelFormatChoice::Yuyv; ///< V4L2 pixel format
    ColourChoice colour = ColourChoice::Auto;           ///< BGR frames (V4L2 yuyv): see captureInColour()
    std::string replayPath;                             ///< recording for the replay backend
    ReplayPace replayPace = ReplayPace::Recorded;
    double replayFps = 30.0; ///< [Hz] rate when replayPace is Fixed
    bool replayLoop = false; ///< replay the recording over and over (a demo that runs until stopped)
};

struct RoiConfig {
    double topFraction = 0.5;  ///< first image row of the region of interest, as a fraction of the height
    int matcherMarginRows = 8; ///< [px] extra rows above the ROI that the block matcher reads
};

struct StereoConfig {
    MatcherMode mode = MatcherMode::CensusSgm; ///< the detector's default (vision/roi_matcher.hpp)
    int numDisparities = 128;                  ///< [px] multiple of 16
    int blockSize = 5;                         ///< [px] odd
    /// Ground-guided disparity ranges of the census SGM: vision::RoiMatcherConfig::groundRange and its two
    /// parameters, with the same defaults (test unit-bringup-config: DefaultsMatchTheDetectors).
    bool groundRange = false;
    double groundRangeDropM = 0.3;     ///< [m]
    double groundRangeMarginDeg = 1.5; ///< [deg]
    /// vision::DetectorConfig::halfResolutionMinGroundPx, the same default [px]; 0: every row at full resolution.
    double halfResolutionMinGroundPx = 0.0;
};

struct ObstacleConfig {
    DetectorMode detector = DetectorMode::Stereo;
    int sectorCount = 64;               ///< bearing bins across the horizontal field of view
    double dangerDistanceM = 1.5;       ///< [m] closer than this: red
    double cautionDistanceM = 5.0;      ///< [m] closer than this: blue; beyond: green
    double minHeightM = 0.10;           ///< [m] positive obstacles taller than this count
    double minDepthM = 0.10;            ///< [m] negative obstacles deeper than this count
    double maxRangeDisparityPx = 13.65; ///< [px] the detector looks as far as the disparity stays at or above this
};

struct OverloadConfig {
    OverloadChoice policy = OverloadChoice::Degrade; ///< degrade (ground-plane-only sectors) or drop only
    double deadlineFactor = 1.0; ///< deadline = this many camera periods from exposure to published sectors
};

struct HandoverConfig {
    /// [us] the vision task polls the frame ring around each frame's due time instead of sleeping in the
    /// kernel (ServiceOptions::spinBeforeFrame); 0 = off. 2000 us covers the capture jitter measured here
    /// (p99 1.3 ms) and costs at most 4 ms of CPU per frame (6 % of a core at 15 fps).
    int spinUs = 2000;
};

/// DDS Security of the bus (ipc::dds::SecurityConfig; README "Secured bus"): the files made by
/// bringup/deploy/security/make_security.sh for this vehicle (its name, vehicle_id, is its certificate's CN).
struct DdsSecurityConfig {
    bool enabled = false;
    std::string identityCa;    ///< identity CA certificate (PEM)
    std::string certificate;   ///< this vehicle's certificate (PEM)
    std::string privateKey;    ///< its private key (PEM)
    std::string permissionsCa; ///< permissions CA certificate (PEM)
    std::string governance;    ///< signed governance document (S/MIME)
    std::string permissions;   ///< this vehicle's signed permissions document (S/MIME)
};

/// The DDS bus (ipc/dds_bus.hpp): how this process joins the vehicle's and the team's data bus.
struct DdsConfig {
    bool enabled = true;      ///< publish sectors, scans and health, read poses (and run the correlator's bus)
    int domainId = 0;         ///< the same on every vehicle and the ground station (ROS 2's default is 0)
    std::string partition;    ///< our topics only; empty = the default partition
    std::string rosNamespace; ///< ROS 2 topics rt/<ns>/...; empty = vehicle_id's letters, digits and _ (ugv-1: ugv1)
    std::string frameId =
        "ugvsense_ground";       ///< frame of the LaserScan and PointCloud2 (on the ground below the camera)
    std::string discoveryServer; ///< "" = multicast discovery; "IP:PORT[;IP:PORT]" = Fast DDS discovery servers
    bool sharedMemory = true;    ///< Fast DDS shared memory between processes of this host (besides UDP)
    bool rosReliable = true;     ///< ROS 2 topics written reliable (every reader matches) or best effort
    double poseMaxAgeMs = 600.0; ///< [ms] a pose further than this from the capture time is flagged stale
    DdsSecurityConfig security;
};

/// The OOI correlator task (issue 5's algorithm, live on the bus).
struct CorrelatorTaskConfig {
    bool enabled = false;
    correlator::Mode mode = correlator::Mode::PoseCorrected; ///< pose-corrected (default; alias improved) or original
    double periodS = 1.0;                                    ///< [s] mission-time period of the correlated list
    double reorderMs = 2000.0;      ///< [ms] how long a received input waits to be put in time order with the others
    double lateWindowS = 300.0;     ///< [s] older inputs than the latest applied one are re-sequenced within this
    double startupHoldMs = 10000.0; ///< [ms] after the first input nothing is applied this long (the team's histories)
    std::string logDir;             ///< inputs.jsonl (every accepted input, in processing order) and snapshots.jsonl
    double maxRatePerSource = 2000.0; ///< [1/s] inputs from one participant beyond this rate are refused (a flood)
    double maxClockSkewMs = 5000.0;   ///< [ms] inputs stamped further ahead of this host's clock are refused
};

struct ServiceConfig {
    std::string sourceFile; ///< the file this came from (for messages)
    std::string vehicleId = "ugv-1";
    std::string calibrationPath = "/var/lib/ugvsense/calibration.yaml"; ///< absolute after loading
    CameraConfig camera;
    RoiConfig roi;
    StereoConfig stereo;
    ObstacleConfig obstacles;
    OverloadConfig overload;
    HandoverConfig handover;
    bool visionEnabled = true; ///< false: no camera and no vision (a ground station running only the correlator)
    DdsConfig dds;
    CorrelatorTaskConfig correlator;
    /// The service's threads: rt's default table with the `tasks.<name>.{policy,priority,cpu}` overrides.
    std::array<rt::TaskSpec, rt::kDefaultTaskTable.size()> tasks = rt::kDefaultTaskTable;
};

using ConfigErrors = std::vector<Error>;

/// Reads and validates the file; relative paths in it resolve against the file's folder.
Result<ServiceConfig, ConfigErrors> loadConfig(const std::string& path);

/// Validates YAML text; `sourceName` is used in messages and `baseDir` resolves relative paths.
Result<ServiceConfig, ConfigErrors> parseConfig(const std::string& yamlText, const std::string& sourceName,
                                                const std::string& baseDir);

/// The effective config as YAML, every key with its description and range as a comment.
std::string formatConfig(const ServiceConfig& config);

/// True when the camera is asked for BGR frames: camera.colour true, or auto with a V4L2 camera in yuyv (it has the
/// colour anyway). The one-camera detector needs them, and so does the stereo detector's fallback to the left camera
/// when the right one stops; the stereo detector itself uses their luma. A colour pair costs a conversion and three
/// times the frame ring's bytes (false saves them).
bool captureInColour(const ServiceConfig& config);

/// The bus's security settings of `config` (its identity is vehicle_id; include ugv/ipc/dds_bus.hpp to call it).
ipc::dds::SecurityConfig securityOf(const ServiceConfig& config);

/// The config file path: argv's value if given, else $UGV_CONFIG, else /etc/ugvsense/config.yaml.
std::string configPath(const char* fromArgs);

} // namespace ugv::adapters
