#pragma once

/// @file
/// A MAGIC-like scenario for the OOI correlator: several UGVs patrol loops through an area and report the objects
/// of interest their sensor sees (range and bearing from their pose), a UAV reports some of the mobile ones, and
/// optionally the map builder sends pose corrections. The result is the correlator's input (time-ordered
/// messages) and the ground truth it is scored against (`ugvsense correlate-sim`, `ugvsense correlate-eval`).
///
/// The world, in a local east-north tangent plane around the origin (LocalFrame):
/// - each UGV drives a closed polyline (routeWaypoints corners around the origin, 0.35..1 x half the area size
///   from it) at a constant speed in [ugvMinSpeedMps, ugvMaxSpeedMps], from a random point of it, in a random
///   direction; its heading is the direction of the current leg;
/// - static OOIs stand 0.1..0.5 of the sensor's range band beside a random point of a random route (so every one
///   can be seen), closePairCount pairs of them 3.5..5 m apart; with staticPlacement Anywhere they stand anywhere
///   in the area instead (some may never be seen, as in a generator that does not know the routes); mobile OOIs and
///   non-combatants walk a straight line of mobileLegM centred beside a route, back and forth, at about mobileSpeedMps;
/// - every UGV looks at every object at observationRateHz (the UGVs' sampling instants are staggered within one
///   period). An object is seen when its true range is within [minRangeM, maxRangeM] and its bearing within
///   +-fieldOfViewHalfDeg, it is not missed (missProbability) and its measured range still falls in the range
///   band. Range noise sigma = rangeSigmaM + rangeSigmaFraction x range, bearing noise bearingSigmaDeg.
///   Clutter: false observations (Poisson, clutterRateHz per UGV) at uniform range and bearing in view, of a
///   random class, each with a track of its own;
/// - a UGV's track UUID for an object is new when it sees the object for the first time, after not seeing it for
///   more than trackLossS, and with trackSwitchProbability at any detection;
/// - pose errors per UGV: heading bias uniform in +-maxHeadingBiasDeg, a constant offset (offsetModel: uniform over
///   the disc of radius maxOffsetM; Gaussian with offsetSigmaM per axis; heavy-tailed: Student's t with 3 degrees
///   of freedom scaled by offsetSigmaM per axis), and a random walk of sigma driftSigmaMPerSqrtS per axis. The reported
///   pose (ugv_lat/lon/heading) is the true pose plus these errors; range and bearing are measured from the true pose.
/// - pose corrections (poseCorrections): every poseCorrectionPeriodS, per UGV, one PoseCorrection for its
///   sampling instants in [sinceT, untilT] (the first and last of the window; windows do not overlap), sent at
///   the end of the window: dHeadingDeg = -bias, (dEastM, dNorthM) = -(offset + mean drift over the window).
///   Applying it (true = reported + correction) recovers the true pose exactly without drift, and up to the
///   drift's deviation from its window mean with drift.
///
/// Determinism: the same config (seed included) gives the same scenario with the same standard library (the
/// std:: distributions are implementation-defined). Layout and pose errors come from one random stream, each
/// UGV's measurements from a stream of its own.
///
/// Cost: O(duration x observationRateHz x ugvCount x objects) plus sorting the messages; a 3.5 h, 5-UGV scenario
/// takes well under a second of computation.
///
/// Thread-safety: pure functions, reentrant. RT-safe: no (allocates).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ugv/correlator/messages.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::correlator {

/// The evaluation settings of issue 5.
enum class ScenarioSetting {
    Clean, ///< no pose errors (sensor noise, misses and clutter as configured)
    Bias,  ///< heading bias up to 8 deg and a position offset up to 1 m per UGV
    Drift, ///< random-walk position drift of 0.05 m per sqrt(s) per axis per UGV
};

/// How a UGV's constant position offset is drawn.
enum class OffsetModel {
    Disc,     ///< uniform over the disc of radius maxOffsetM
    Gaussian, ///< N(0, offsetSigmaM^2) per axis
    StudentT, ///< Student's t, 3 degrees of freedom, scaled by offsetSigmaM, per axis (heavy tails)
};

/// Where static OOIs stand.
enum class StaticPlacement {
    BesideRoutes, ///< within the sensor's range band beside a random point of a route (every one can be seen)
    Anywhere,     ///< uniform over the area
};

struct ScenarioConfig {
    std::uint64_t seed = 1;

    // Area and time.
    double originLat = -34.9;  ///< [deg] centre of the area (Adelaide, where MAGIC 2010 was held)
    double originLon = 138.6;  ///< [deg]
    double areaSizeM = 200.0;  ///< [m] side of the square the patrol loops stay in
    double durationS = 600.0;  ///< [s] messages and truth cover [0, durationS]
    double truthPeriodS = 1.0; ///< [s] sampling of the moving objects' truth (the correlator's snapshot period)

    // Vehicles.
    int ugvCount = 5;
    int routeWaypoints = 6;      ///< corners of each patrol loop (>= 3)
    double ugvMinSpeedMps = 1.0; ///< [m/s]
    double ugvMaxSpeedMps = 2.0; ///< [m/s]

    // Objects.
    int staticCount = 20; ///< static OOIs, close pairs included
    StaticPlacement staticPlacement = StaticPlacement::BesideRoutes;
    int closePairCount = 3;             ///< pairs of static OOIs closePairMinM..closePairMaxM apart
    double closePairMinM = 3.5;         ///< [m]
    double closePairMaxM = 5.0;         ///< [m]
    double minStaticSeparationM = 10.0; ///< [m] between statics that are not a pair (best effort: 50 tries)
    int mobileCount = 4;                ///< mobile OOIs (combatants)
    int nonCombatantCount = 3;          ///< non-combatants, moving like the mobile OOIs
    double mobileSpeedMps = 1.0;        ///< [m/s] mean walking speed (each object 0.8..1.2 x this)
    double mobileLegM = 40.0;           ///< [m] length of the line walked back and forth

    // Sensor (per UGV).
    double observationRateHz = 2.0;        ///< [Hz] per visible object
    double minRangeM = 5.0;                ///< [m]
    double maxRangeM = 25.0;               ///< [m]
    double fieldOfViewHalfDeg = 60.0;      ///< [deg] about the heading
    double rangeSigmaM = 0.1;              ///< [m] range noise at zero range
    double rangeSigmaFraction = 0.01;      ///< range noise growth per metre of range
    double bearingSigmaDeg = 1.0;          ///< [deg]
    double missProbability = 0.2;          ///< per object and sampling instant
    double clutterRateHz = 0.02;           ///< [Hz] false observations per UGV
    double trackLossS = 3.0;               ///< [s] unseen longer than this: a new track UUID on re-acquisition
    double trackSwitchProbability = 0.002; ///< per detection: a new track UUID anyway

    // Pose errors (per UGV).
    double maxHeadingBiasDeg = 0.0; ///< [deg]
    double maxOffsetM = 0.0;        ///< [m] OffsetModel::Disc
    OffsetModel offsetModel = OffsetModel::Disc;
    double offsetSigmaM = 0.0;        ///< [m] per axis, OffsetModel::Gaussian and StudentT
    double driftSigmaMPerSqrtS = 0.0; ///< [m/sqrt(s)] per axis

    // UAV feed.
    bool uavFeed = true;
    double uavPeriodS = 10.0;  ///< [s]
    int uavTrackedMobiles = 2; ///< the first this many mobile OOIs are fixed by the UAV (<= mobileCount)

    // Map-builder pose corrections.
    bool poseCorrections = false;
    double poseCorrectionPeriodS = 60.0; ///< [s]
};

/// A static OOI's true position.
struct StaticTruth {
    std::string id; ///< "static-01", ...
    double lat = 0.0;
    double lon = 0.0;
};

/// A moving object's (mobile OOI or non-combatant) true position at time t.
struct MovingTruthSample {
    std::string id; ///< "mobile-01", ..., "noncombatant-01", ...
    OoiClass cls = OoiClass::Mobile;
    double t = 0.0; ///< [s]
    double lat = 0.0;
    double lon = 0.0;
};

/// A UGV's constant pose errors (its drift is a random walk on top of the offset, not recorded).
struct UgvTruth {
    std::string name; ///< "ugv-1", ...
    double headingBiasDeg = 0.0;
    double offsetEastM = 0.0;
    double offsetNorthM = 0.0;
};

struct ScenarioTruth {
    double originLat = 0.0;
    double originLon = 0.0;
    double durationS = 0.0;
    double periodS = 0.0; ///< [s] sampling period of `moving`
    std::vector<StaticTruth> statics;
    /// Every moving object at t = 0, periodS, 2 periodS, ... <= durationS, ordered by t, then object.
    std::vector<MovingTruthSample> moving;
    std::vector<UgvTruth> ugvs;
};

struct Scenario {
    std::vector<Message> messages; ///< ordered by t (ties: by UGV, UAV fixes last)
    ScenarioTruth truth;
};

/// The default config with the pose errors of `setting` (clean: none; bias: maxHeadingBiasDeg 8, maxOffsetM 1;
/// drift: driftSigmaMPerSqrtS 0.05).
[[nodiscard]] ScenarioConfig scenarioPreset(ScenarioSetting setting);

/// "clean", "bias" or "drift"; nullopt for anything else.
[[nodiscard]] std::optional<ScenarioSetting> parseScenarioSetting(std::string_view name);
[[nodiscard]] const char* toString(ScenarioSetting setting) noexcept;

/// "disc", "gaussian" or "student-t"; nullopt for anything else.
[[nodiscard]] std::optional<OffsetModel> parseOffsetModel(std::string_view name);
[[nodiscard]] const char* toString(OffsetModel model) noexcept;

/// @return an error naming the first field out of its valid range (and the range), or success.
Result<void, Error> validateScenarioConfig(const ScenarioConfig& config);

/// Generates the scenario of `config`.
/// @return the messages and the truth, or the validation error of the config.
Result<Scenario, Error> generateScenario(const ScenarioConfig& config);

} // namespace ugv::correlator
