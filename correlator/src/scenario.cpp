#include "ugv/correlator/scenario.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "ugv/correlator/geodesy.hpp"
#include "ugv/platform/angles.hpp"

namespace ugv::correlator {
namespace {

using Eigen::Vector2d;

constexpr double kFullTurnDeg = 360.0;
constexpr double kHalfTurnDeg = 180.0;
constexpr double kQuarterTurnDeg = 90.0;
constexpr double kTimeSlackS = 1e-9; ///< [s] floating-point slack at the end of a time grid

// Layout.
constexpr int kPlacementTries = 50;
constexpr double kCornerJitter = 0.3;       ///< of the angular spacing of a loop's corners
constexpr double kMinCornerRadius = 0.35;   ///< of half the area size
constexpr double kMinLateralFraction = 0.1; ///< of the sensor's range band: distance of an object from its route
constexpr double kMaxLateralFraction = 0.5;
constexpr double kMinSpeedFactor = 0.8; ///< mobile objects: speed spread about mobileSpeedMps
constexpr double kMaxSpeedFactor = 1.2;
constexpr std::uint64_t kWorldStream = 0; ///< random stream of the layout and pose errors; UGV i uses i + 1

/// Clutter takes any class.
constexpr std::array kClutterClasses = {OoiClass::Static, OoiClass::Mobile, OoiClass::NonCombatant, OoiClass::Unknown};

// Validation bounds: generous, they only keep a config from asking for the impossible.
constexpr double kMaxDurationS = 7.0 * 24.0 * 3600.0;
constexpr double kMaxCount = 10000.0;
constexpr double kMaxDistanceM = 100000.0;
constexpr double kMaxSpeedMps = 100.0;
constexpr double kMaxRateHz = 100.0;
constexpr double kMaxPeriodS = 1e6;
constexpr double kMaxSamplingInstants = 1e8; ///< durationS x observationRateHz x ugvCount
constexpr double kMaxTruthSamples = 1e8;     ///< durationS / truthPeriodS x moving objects
constexpr double kMaxLatitudeDeg = 85.0;

// ---- small geometry ------------------------------------------------------------------------------------------

double wrap360(double deg)
{
    const double w = std::fmod(deg, kFullTurnDeg);
    return w < 0.0 ? w + kFullTurnDeg : w;
}

/// To (-180, 180].
double wrap180(double deg)
{
    const double w = wrap360(deg);
    return w > kHalfTurnDeg ? w - kFullTurnDeg : w;
}

/// Compass azimuth [deg] of an east-north vector.
double azimuthDeg(const Vector2d& v)
{
    return wrap360(std::atan2(v.x(), v.y()) * kRadToDeg);
}

/// East-north unit vector along a compass azimuth [deg].
Vector2d along(double azimuth)
{
    return {std::sin(azimuth * kDegToRad), std::cos(azimuth * kDegToRad)};
}

/// Number of points of the grid 0, step, 2 step, ... <= end.
std::size_t gridCount(double end, double step)
{
    return end < 0.0 ? 0 : static_cast<std::size_t>(std::floor(end / step + kTimeSlackS)) + 1;
}

std::string numberedId(const char* prefix, std::size_t number)
{
    char text[32];
    (void)std::snprintf(text, sizeof(text), "%s-%02zu", prefix, number);
    return text;
}

// ---- random streams ------------------------------------------------------------------------------------------

/// One seeded engine and the draws the scenario needs.
class Random {
public:
    Random(std::uint64_t seed, std::uint64_t stream)
    {
        std::seed_seq sequence{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32U),
                               static_cast<std::uint32_t>(stream), static_cast<std::uint32_t>(stream >> 32U)};
        engine_.seed(sequence);
    }

    double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine_); }
    double gaussian() { return normal_(engine_); } ///< N(0, 1)
    bool chance(double probability) { return uniform(0.0, 1.0) < probability; }
    std::size_t index(std::size_t count) { return std::uniform_int_distribution<std::size_t>(0, count - 1)(engine_); }
    int poisson(double mean) { return mean > 0.0 ? std::poisson_distribution<int>(mean)(engine_) : 0; }
    /// Student's t with 3 degrees of freedom: N(0, 1) / sqrt(chi-square(3) / 3).
    double studentT3()
    {
        constexpr double kDegreesOfFreedom = 3.0;
        const double z = gaussian();
        double chi2 = 0.0;
        for (int i = 0; i < static_cast<int>(kDegreesOfFreedom); ++i) {
            const double g = gaussian();
            chi2 += g * g;
        }
        return z / std::sqrt(std::max(chi2, std::numeric_limits<double>::min()) / kDegreesOfFreedom);
    }

    /// A random (version 4, RFC 4122 variant) UUID, lower-case 8-4-4-4-12 hex.
    std::string uuid()
    {
        constexpr std::uint64_t kVersionMask = 0xF000U;
        constexpr std::uint64_t kVersion4 = 0x4000U;
        constexpr std::uint64_t kVariantMask = 0xC000000000000000ULL;
        constexpr std::uint64_t kVariantRfc = 0x8000000000000000ULL;
        const std::uint64_t hi = (engine_() & ~kVersionMask) | kVersion4;
        const std::uint64_t lo = (engine_() & ~kVariantMask) | kVariantRfc;
        char text[40];
        (void)std::snprintf(
            text, sizeof(text), "%08llx-%04llx-%04llx-%04llx-%012llx", static_cast<unsigned long long>(hi >> 32U),
            static_cast<unsigned long long>((hi >> 16U) & 0xFFFFU), static_cast<unsigned long long>(hi & 0xFFFFU),
            static_cast<unsigned long long>(lo >> 48U), static_cast<unsigned long long>(lo & 0xFFFFFFFFFFFFULL));
        return text;
    }

private:
    std::mt19937_64 engine_;
    std::normal_distribution<double> normal_{0.0, 1.0};
};

// ---- the world -----------------------------------------------------------------------------------------------

struct Pose {
    Vector2d position = Vector2d::Zero(); ///< [m] east, north
    double headingDeg = 0.0;
};

/// A closed polyline driven at constant speed: the pose at an arc length.
class Route {
public:
    explicit Route(std::vector<Vector2d> corners) : corners_(std::move(corners))
    {
        for (std::size_t i = 0; i < corners_.size(); ++i) {
            const Vector2d leg = corners_[(i + 1) % corners_.size()] - corners_[i];
            starts_.push_back(length_);
            headings_.push_back(azimuthDeg(leg));
            length_ += leg.norm();
        }
    }

    [[nodiscard]] double length() const { return length_; }

    /// The pose at arc length `s` [m] (any value: the loop repeats).
    [[nodiscard]] Pose at(double s) const
    {
        double u = std::fmod(s, length_);
        u = u < 0.0 ? u + length_ : u;
        const auto next = std::upper_bound(starts_.begin(), starts_.end(), u);
        const auto leg = static_cast<std::size_t>(next - starts_.begin()) - 1;
        return {corners_[leg] + (u - starts_[leg]) * along(headings_[leg]), headings_[leg]};
    }

private:
    std::vector<Vector2d> corners_;
    std::vector<double> starts_;   ///< [m] arc length at the start of each leg
    std::vector<double> headings_; ///< [deg] compass heading of each leg
    double length_ = 0.0;
};

struct UgvPlan {
    std::string name;
    Route route;
    double startS = 0.0;   ///< [m] arc length at t = 0
    double speedMps = 0.0; ///< [m/s]
    double headingBiasDeg = 0.0;
    Vector2d offset = Vector2d::Zero(); ///< [m]

    [[nodiscard]] Pose truePose(double t) const { return route.at(startS + speedMps * t); }
};

struct StaticObject {
    std::string id;
    Vector2d position = Vector2d::Zero();
};

/// Walks from `start` along `direction` for legM, back, and so on.
struct MovingObject {
    std::string id;
    OoiClass cls = OoiClass::Mobile;
    Vector2d start = Vector2d::Zero();
    Vector2d direction = Vector2d::UnitX();
    double legM = 0.0;
    double speedMps = 0.0;
    double phaseM = 0.0; ///< [m] distance walked at t = 0, in [0, 2 legM)

    [[nodiscard]] Vector2d at(double t) const
    {
        const double u = std::fmod(phaseM + speedMps * t, 2.0 * legM);
        return start + direction * (u <= legM ? u : 2.0 * legM - u);
    }
};

struct World {
    std::vector<UgvPlan> ugvs;
    std::vector<StaticObject> statics;
    std::vector<MovingObject> moving;
};

std::vector<Vector2d> loopCorners(const ScenarioConfig& config, Random& random)
{
    const double half = config.areaSizeM / 2.0;
    const double rotation = random.uniform(0.0, kFullTurnDeg);
    const double spacing = kFullTurnDeg / config.routeWaypoints;
    std::vector<Vector2d> corners;
    for (int w = 0; w < config.routeWaypoints; ++w) {
        const double azimuth = rotation + spacing * (w + random.uniform(-kCornerJitter, kCornerJitter));
        corners.push_back(half * random.uniform(kMinCornerRadius, 1.0) * along(azimuth));
    }
    if (random.chance(0.5)) {
        std::reverse(corners.begin(), corners.end());
    }
    return corners;
}

UgvPlan planUgv(const ScenarioConfig& config, std::size_t index, Random& random)
{
    Route route(loopCorners(config, random));
    const double startS = random.uniform(0.0, route.length());
    const double speed = random.uniform(config.ugvMinSpeedMps, config.ugvMaxSpeedMps);
    const double bias = random.uniform(-config.maxHeadingBiasDeg, config.maxHeadingBiasDeg);
    Vector2d offset = Vector2d::Zero();
    switch (config.offsetModel) {
    case OffsetModel::Disc: {
        const double offsetM = config.maxOffsetM * std::sqrt(random.uniform(0.0, 1.0)); // uniform over the disc
        offset = offsetM * along(random.uniform(0.0, kFullTurnDeg));
        break;
    }
    case OffsetModel::Gaussian:
        offset = config.offsetSigmaM * Vector2d(random.gaussian(), random.gaussian());
        break;
    case OffsetModel::StudentT:
        offset = config.offsetSigmaM * Vector2d(random.studentT3(), random.studentT3());
        break;
    }
    return UgvPlan{"ugv-" + std::to_string(index + 1), std::move(route), startS, speed, bias, offset};
}

/// A point beside a random point of a random route, inside the sensor's range band from it.
Vector2d besideARoute(const ScenarioConfig& config, const std::vector<UgvPlan>& ugvs, Random& random)
{
    const Route& route = ugvs[random.index(ugvs.size())].route;
    const Pose pose = route.at(random.uniform(0.0, route.length()));
    const double side = random.chance(0.5) ? 1.0 : -1.0;
    const double lateral = config.minRangeM + random.uniform(kMinLateralFraction, kMaxLateralFraction) *
                                                  (config.maxRangeM - config.minRangeM);
    return pose.position + lateral * along(pose.headingDeg + side * kQuarterTurnDeg);
}

bool separated(const Vector2d& candidate, const std::vector<StaticObject>& placed, double minDistanceM)
{
    return std::all_of(placed.begin(), placed.end(),
                       [&](const StaticObject& other) { return (other.position - candidate).norm() >= minDistanceM; });
}

/// A static's candidate place by config.staticPlacement.
Vector2d staticCandidate(const ScenarioConfig& config, const std::vector<UgvPlan>& ugvs, Random& random)
{
    if (config.staticPlacement == StaticPlacement::Anywhere) {
        const double half = config.areaSizeM / 2.0;
        return {random.uniform(-half, half), random.uniform(-half, half)};
    }
    return besideARoute(config, ugvs, random);
}

Vector2d placeSeparated(const ScenarioConfig& config, const World& world, Random& random)
{
    Vector2d candidate = staticCandidate(config, world.ugvs, random);
    for (int attempt = 1;
         attempt < kPlacementTries && !separated(candidate, world.statics, config.minStaticSeparationM); ++attempt) {
        candidate = staticCandidate(config, world.ugvs, random);
    }
    return candidate;
}

/// The partner of a close pair: closePairMinM..closePairMaxM from `first`, away from the other statics.
Vector2d placePartner(const ScenarioConfig& config, const World& world, const Vector2d& first, Random& random)
{
    Vector2d candidate = first;
    for (int attempt = 0; attempt < kPlacementTries; ++attempt) {
        const double distance = random.uniform(config.closePairMinM, config.closePairMaxM);
        candidate = first + distance * along(random.uniform(0.0, kFullTurnDeg));
        if (separated(candidate, world.statics, config.minStaticSeparationM)) {
            break;
        }
    }
    return candidate;
}

void placeStatics(const ScenarioConfig& config, World& world, Random& random)
{
    for (int pair = 0; pair < config.closePairCount; ++pair) {
        const Vector2d first = placeSeparated(config, world, random);
        const Vector2d partner = placePartner(config, world, first, random);
        world.statics.push_back({numberedId("static", world.statics.size() + 1), first});
        world.statics.push_back({numberedId("static", world.statics.size() + 1), partner});
    }
    while (world.statics.size() < static_cast<std::size_t>(config.staticCount)) {
        const Vector2d position = placeSeparated(config, world, random);
        world.statics.push_back({numberedId("static", world.statics.size() + 1), position});
    }
}

MovingObject planMoving(const ScenarioConfig& config, const World& world, std::string id, OoiClass cls, Random& random)
{
    const Vector2d centre = besideARoute(config, world.ugvs, random);
    const Vector2d direction = along(random.uniform(0.0, kFullTurnDeg));
    const double speed = config.mobileSpeedMps * random.uniform(kMinSpeedFactor, kMaxSpeedFactor);
    const double phase = random.uniform(0.0, 2.0 * config.mobileLegM);
    return MovingObject{
        std::move(id), cls, centre - direction * (config.mobileLegM / 2.0), direction, config.mobileLegM, speed, phase};
}

World makeWorld(const ScenarioConfig& config)
{
    Random random(config.seed, kWorldStream);
    World world;
    for (std::size_t i = 0; i < static_cast<std::size_t>(config.ugvCount); ++i) {
        world.ugvs.push_back(planUgv(config, i, random));
    }
    placeStatics(config, world, random);
    for (int i = 0; i < config.mobileCount; ++i) {
        world.moving.push_back(planMoving(config, world, numberedId("mobile", i + 1), OoiClass::Mobile, random));
    }
    for (int i = 0; i < config.nonCombatantCount; ++i) {
        world.moving.push_back(
            planMoving(config, world, numberedId("noncombatant", i + 1), OoiClass::NonCombatant, random));
    }
    return world;
}

// ---- one UGV's sensor ----------------------------------------------------------------------------------------

struct ReportedPose {
    double lat = 0.0;
    double lon = 0.0;
    double headingDeg = 0.0;
};

struct Track {
    std::string uuid;
    double lastSeenT = -std::numeric_limits<double>::infinity();
};

/// The sampling instants of one UGV: its observations (objects and clutter), its drift and, when enabled, its
/// pose corrections, in time order.
class UgvSensor {
public:
    UgvSensor(const ScenarioConfig& config, const World& world, const LocalFrame& frame, std::size_t index)
        : config_(config), world_(world), frame_(frame), plan_(world.ugvs[index]), random_(config.seed, index + 1),
          tracks_(world.statics.size() + world.moving.size()), periodS_(1.0 / config.observationRateHz),
          phaseS_(periodS_ * static_cast<double>(index) / config.ugvCount), windowEndS_(config.poseCorrectionPeriodS)
    {
    }

    void run(std::vector<Message>& out)
    {
        const std::size_t steps = gridCount(config_.durationS - phaseS_, periodS_);
        for (std::size_t k = 0; k < steps; ++k) {
            step(k, out);
        }
        if (config_.poseCorrections) {
            flushCorrection(std::max(window_.untilT, std::min(windowEndS_, config_.durationS)), out);
        }
    }

private:
    /// The drift's sum over the sampling instants of the current correction window.
    struct Window {
        std::size_t count = 0;
        double sinceT = 0.0;
        double untilT = 0.0;
        Vector2d driftSum = Vector2d::Zero();
    };

    void step(std::size_t k, std::vector<Message>& out)
    {
        const double t = phaseS_ + static_cast<double>(k) * periodS_;
        const Vector2d walk(random_.gaussian(), random_.gaussian());
        if (k > 0) {
            drift_ += config_.driftSigmaMPerSqrtS * std::sqrt(periodS_) * walk;
        }
        if (config_.poseCorrections) {
            accumulateCorrection(t, out);
        }
        const Pose truth = plan_.truePose(t);
        ReportedPose reported;
        frame_.toLatLon(truth.position + plan_.offset + drift_, reported.lat, reported.lon);
        reported.headingDeg = wrap360(truth.headingDeg + plan_.headingBiasDeg);
        for (std::size_t i = 0; i < world_.statics.size(); ++i) {
            observe(t, i, world_.statics[i].position, OoiClass::Static, truth, reported, out);
        }
        for (std::size_t i = 0; i < world_.moving.size(); ++i) {
            const MovingObject& object = world_.moving[i];
            observe(t, world_.statics.size() + i, object.at(t), object.cls, truth, reported, out);
        }
        addClutter(t, reported, out);
    }

    /// One object at one instant: seen (in range and view, not missed, measured range in the band) or not.
    void observe(double t, std::size_t target, const Vector2d& position, OoiClass cls, const Pose& truth,
                 const ReportedPose& reported, std::vector<Message>& out)
    {
        const Vector2d relative = position - truth.position;
        const double range = relative.norm();
        const double bearing = wrap180(azimuthDeg(relative) - truth.headingDeg);
        if (range < config_.minRangeM || range > config_.maxRangeM || std::abs(bearing) > config_.fieldOfViewHalfDeg ||
            random_.chance(config_.missProbability)) {
            return;
        }
        const double rangeSigma = config_.rangeSigmaM + config_.rangeSigmaFraction * range;
        const double measuredRange = range + rangeSigma * random_.gaussian();
        const double measuredBearing = wrap180(bearing + config_.bearingSigmaDeg * random_.gaussian());
        if (measuredRange < config_.minRangeM || measuredRange > config_.maxRangeM) {
            return;
        }
        emit(t, cls, trackFor(target, t), reported, measuredRange, measuredBearing, out);
    }

    /// The UGV's track UUID for `target`: new after a loss longer than trackLossS, or by a random switch.
    const std::string& trackFor(std::size_t target, double t)
    {
        Track& track = tracks_[target];
        const bool lost = t - track.lastSeenT > config_.trackLossS;
        const bool switched = random_.chance(config_.trackSwitchProbability);
        if (lost || switched) {
            track.uuid = random_.uuid();
        }
        track.lastSeenT = t;
        return track.uuid;
    }

    void addClutter(double t, const ReportedPose& reported, std::vector<Message>& out)
    {
        const int count = random_.poisson(config_.clutterRateHz * periodS_);
        for (int i = 0; i < count; ++i) {
            const double range = random_.uniform(config_.minRangeM, config_.maxRangeM);
            const double bearing = random_.uniform(-config_.fieldOfViewHalfDeg, config_.fieldOfViewHalfDeg);
            const OoiClass cls = kClutterClasses[random_.index(kClutterClasses.size())];
            emit(t, cls, random_.uuid(), reported, range, bearing, out);
        }
    }

    void emit(double t, OoiClass cls, const std::string& track, const ReportedPose& reported, double rangeM,
              double bearingDeg, std::vector<Message>& out) const
    {
        out.emplace_back(Observation{.t = t,
                                     .ugv = plan_.name,
                                     .track = track,
                                     .cls = cls,
                                     .ugvLat = reported.lat,
                                     .ugvLon = reported.lon,
                                     .ugvHeadingDeg = reported.headingDeg,
                                     .rangeM = rangeM,
                                     .bearingDeg = bearingDeg});
    }

    /// Closes the windows that end at or before t, then counts t in the current one.
    void accumulateCorrection(double t, std::vector<Message>& out)
    {
        while (t >= windowEndS_) {
            flushCorrection(windowEndS_, out);
            windowEndS_ += config_.poseCorrectionPeriodS;
        }
        if (window_.count == 0) {
            window_.sinceT = t;
        }
        window_.untilT = t;
        window_.driftSum += drift_;
        ++window_.count;
    }

    /// Sends the exact correction of the current window (if it holds any instant) at `sendT`.
    void flushCorrection(double sendT, std::vector<Message>& out)
    {
        if (window_.count == 0) {
            return;
        }
        const Vector2d error = plan_.offset + window_.driftSum / static_cast<double>(window_.count);
        out.emplace_back(PoseCorrection{.t = sendT,
                                        .ugv = plan_.name,
                                        .sinceT = window_.sinceT,
                                        .untilT = window_.untilT,
                                        .dEastM = -error.x(),
                                        .dNorthM = -error.y(),
                                        .dHeadingDeg = -plan_.headingBiasDeg});
        window_ = Window{};
    }

    const ScenarioConfig& config_;
    const World& world_;
    const LocalFrame& frame_;
    const UgvPlan& plan_;
    Random random_;
    std::vector<Track> tracks_; ///< per object: statics, then moving
    double periodS_;            ///< [s] between sampling instants
    double phaseS_;             ///< [s] first sampling instant (UGVs staggered within one period)
    double windowEndS_;         ///< [s] end (exclusive) of the current correction window
    Vector2d drift_ = Vector2d::Zero();
    Window window_;
};

// ---- UAV feed and truth --------------------------------------------------------------------------------------

void addUavFixes(const ScenarioConfig& config, const World& world, const LocalFrame& frame, std::vector<Message>& out)
{
    if (!config.uavFeed) {
        return;
    }
    const std::size_t instants = gridCount(config.durationS, config.uavPeriodS);
    for (std::size_t k = 0; k < instants; ++k) {
        const double t = static_cast<double>(k) * config.uavPeriodS;
        for (int i = 0; i < config.uavTrackedMobiles; ++i) {
            UavFix fix{.t = t, .cls = OoiClass::Mobile, .lat = 0.0, .lon = 0.0};
            frame.toLatLon(world.moving[static_cast<std::size_t>(i)].at(t), fix.lat, fix.lon);
            out.emplace_back(fix);
        }
    }
}

ScenarioTruth makeTruth(const ScenarioConfig& config, const World& world, const LocalFrame& frame)
{
    ScenarioTruth truth;
    truth.originLat = config.originLat;
    truth.originLon = config.originLon;
    truth.durationS = config.durationS;
    truth.periodS = config.truthPeriodS;
    for (const StaticObject& object : world.statics) {
        StaticTruth entry{object.id, 0.0, 0.0};
        frame.toLatLon(object.position, entry.lat, entry.lon);
        truth.statics.push_back(std::move(entry));
    }
    const std::size_t instants = gridCount(config.durationS, config.truthPeriodS);
    truth.moving.reserve(instants * world.moving.size());
    for (std::size_t k = 0; k < instants; ++k) {
        const double t = static_cast<double>(k) * config.truthPeriodS;
        for (const MovingObject& object : world.moving) {
            MovingTruthSample sample{object.id, object.cls, t, 0.0, 0.0};
            frame.toLatLon(object.at(t), sample.lat, sample.lon);
            truth.moving.push_back(std::move(sample));
        }
    }
    for (const UgvPlan& plan : world.ugvs) {
        truth.ugvs.push_back({plan.name, plan.headingBiasDeg, plan.offset.x(), plan.offset.y()});
    }
    return truth;
}

// ---- validation ----------------------------------------------------------------------------------------------

struct Check {
    bool ok;
    const char* field;
    double value;
    const char* requirement;
};

bool within(double value, double lo, double hi)
{
    return value >= lo && value <= hi; // false for NaN
}

bool positive(double value, double hi)
{
    return value > 0.0 && value <= hi;
}

std::vector<Check> checks(const ScenarioConfig& c)
{
    const double moving = static_cast<double>(c.mobileCount) + c.nonCombatantCount;
    const double instants = c.durationS * c.observationRateHz * c.ugvCount;
    const double truthSamples = c.durationS / c.truthPeriodS * moving;
    const int maxClosePairs = c.staticCount / 2; // whole pairs
    return {
        {within(c.originLat, -kMaxLatitudeDeg, kMaxLatitudeDeg), "originLat", c.originLat, "in [-85, 85] deg"},
        {within(c.originLon, -kHalfTurnDeg, kHalfTurnDeg), "originLon", c.originLon, "in [-180, 180] deg"},
        {positive(c.areaSizeM, kMaxDistanceM), "areaSizeM", c.areaSizeM, "in (0, 100000] m"},
        {positive(c.durationS, kMaxDurationS), "durationS", c.durationS, "in (0, 604800] s"},
        {positive(c.truthPeriodS, kMaxPeriodS), "truthPeriodS", c.truthPeriodS, "in (0, 1e6] s"},
        {within(c.ugvCount, 1, kMaxCount), "ugvCount", static_cast<double>(c.ugvCount), "in [1, 10000]"},
        {within(c.routeWaypoints, 3, kMaxCount), "routeWaypoints", static_cast<double>(c.routeWaypoints),
         "in [3, 10000]"},
        {positive(c.ugvMinSpeedMps, kMaxSpeedMps), "ugvMinSpeedMps", c.ugvMinSpeedMps, "in (0, 100] m/s"},
        {within(c.ugvMaxSpeedMps, c.ugvMinSpeedMps, kMaxSpeedMps), "ugvMaxSpeedMps", c.ugvMaxSpeedMps,
         "in [ugvMinSpeedMps, 100] m/s"},
        {within(c.staticCount, 0, kMaxCount), "staticCount", static_cast<double>(c.staticCount), "in [0, 10000]"},
        {within(c.closePairCount, 0, maxClosePairs), "closePairCount", static_cast<double>(c.closePairCount),
         "in [0, staticCount/2]"},
        {within(c.closePairMinM, 0, kMaxDistanceM), "closePairMinM", c.closePairMinM, "in [0, 100000] m"},
        {within(c.closePairMaxM, c.closePairMinM, kMaxDistanceM), "closePairMaxM", c.closePairMaxM,
         "in [closePairMinM, 100000] m"},
        {within(c.minStaticSeparationM, 0, kMaxDistanceM), "minStaticSeparationM", c.minStaticSeparationM,
         "in [0, 100000] m"},
        {within(c.mobileCount, 0, kMaxCount), "mobileCount", static_cast<double>(c.mobileCount), "in [0, 10000]"},
        {within(c.nonCombatantCount, 0, kMaxCount), "nonCombatantCount", static_cast<double>(c.nonCombatantCount),
         "in [0, 10000]"},
        {within(c.mobileSpeedMps, 0, kMaxSpeedMps), "mobileSpeedMps", c.mobileSpeedMps, "in [0, 100] m/s"},
        {positive(c.mobileLegM, kMaxDistanceM), "mobileLegM", c.mobileLegM, "in (0, 100000] m"},
        {positive(c.observationRateHz, kMaxRateHz), "observationRateHz", c.observationRateHz, "in (0, 100] Hz"},
        {within(c.minRangeM, 0, kMaxDistanceM), "minRangeM", c.minRangeM, "in [0, 100000] m"},
        {within(c.maxRangeM, c.minRangeM, kMaxDistanceM) && c.maxRangeM > c.minRangeM, "maxRangeM", c.maxRangeM,
         "in (minRangeM, 100000] m"},
        {positive(c.fieldOfViewHalfDeg, kHalfTurnDeg), "fieldOfViewHalfDeg", c.fieldOfViewHalfDeg, "in (0, 180] deg"},
        {within(c.rangeSigmaM, 0, kMaxDistanceM), "rangeSigmaM", c.rangeSigmaM, "in [0, 100000] m"},
        {within(c.rangeSigmaFraction, 0, 1), "rangeSigmaFraction", c.rangeSigmaFraction, "in [0, 1]"},
        {within(c.bearingSigmaDeg, 0, kHalfTurnDeg), "bearingSigmaDeg", c.bearingSigmaDeg, "in [0, 180] deg"},
        {within(c.missProbability, 0, 1), "missProbability", c.missProbability, "in [0, 1]"},
        {within(c.clutterRateHz, 0, kMaxRateHz), "clutterRateHz", c.clutterRateHz, "in [0, 100] Hz"},
        {within(c.trackLossS, 0, std::numeric_limits<double>::max()), "trackLossS", c.trackLossS, "finite, >= 0 s"},
        {within(c.trackSwitchProbability, 0, 1), "trackSwitchProbability", c.trackSwitchProbability, "in [0, 1]"},
        {within(c.maxHeadingBiasDeg, 0, kHalfTurnDeg), "maxHeadingBiasDeg", c.maxHeadingBiasDeg, "in [0, 180] deg"},
        {within(c.maxOffsetM, 0, kMaxDistanceM), "maxOffsetM", c.maxOffsetM, "in [0, 100000] m"},
        {within(c.offsetSigmaM, 0, kMaxDistanceM), "offsetSigmaM", c.offsetSigmaM, "in [0, 100000] m"},
        {within(c.driftSigmaMPerSqrtS, 0, kMaxDistanceM), "driftSigmaMPerSqrtS", c.driftSigmaMPerSqrtS,
         "in [0, 100000] m/sqrt(s)"},
        {positive(c.uavPeriodS, kMaxPeriodS), "uavPeriodS", c.uavPeriodS, "in (0, 1e6] s"},
        {within(c.uavTrackedMobiles, 0, c.mobileCount), "uavTrackedMobiles", static_cast<double>(c.uavTrackedMobiles),
         "in [0, mobileCount]"},
        {positive(c.poseCorrectionPeriodS, kMaxPeriodS), "poseCorrectionPeriodS", c.poseCorrectionPeriodS,
         "in (0, 1e6] s"},
        {instants <= kMaxSamplingInstants, "durationS", c.durationS,
         "such that durationS x observationRateHz x ugvCount <= 1e8 sampling instants"},
        {truthSamples <= kMaxTruthSamples, "truthPeriodS", c.truthPeriodS,
         "such that durationS / truthPeriodS x (mobileCount + nonCombatantCount) <= 1e8 truth samples"},
    };
}

} // namespace

ScenarioConfig scenarioPreset(ScenarioSetting setting)
{
    constexpr double kBiasMaxHeadingDeg = 8.0;
    constexpr double kBiasMaxOffsetM = 1.0;
    constexpr double kDriftSigma = 0.05; // [m/sqrt(s)]
    ScenarioConfig config;
    switch (setting) {
    case ScenarioSetting::Bias:
        config.maxHeadingBiasDeg = kBiasMaxHeadingDeg;
        config.maxOffsetM = kBiasMaxOffsetM;
        break;
    case ScenarioSetting::Drift:
        config.driftSigmaMPerSqrtS = kDriftSigma;
        break;
    case ScenarioSetting::Clean:
        break;
    }
    return config;
}

std::optional<ScenarioSetting> parseScenarioSetting(std::string_view name)
{
    for (const auto setting : {ScenarioSetting::Clean, ScenarioSetting::Bias, ScenarioSetting::Drift}) {
        if (name == toString(setting)) {
            return setting;
        }
    }
    return std::nullopt;
}

const char* toString(ScenarioSetting setting) noexcept
{
    switch (setting) {
    case ScenarioSetting::Bias:
        return "bias";
    case ScenarioSetting::Drift:
        return "drift";
    case ScenarioSetting::Clean:
        break;
    }
    return "clean";
}

std::optional<OffsetModel> parseOffsetModel(std::string_view name)
{
    for (const auto model : {OffsetModel::Disc, OffsetModel::Gaussian, OffsetModel::StudentT}) {
        if (name == toString(model)) {
            return model;
        }
    }
    return std::nullopt;
}

const char* toString(OffsetModel model) noexcept
{
    switch (model) {
    case OffsetModel::Gaussian:
        return "gaussian";
    case OffsetModel::StudentT:
        return "student-t";
    case OffsetModel::Disc:
        break;
    }
    return "disc";
}

Result<void, Error> validateScenarioConfig(const ScenarioConfig& config)
{
    for (const Check& check : checks(config)) {
        if (!check.ok) {
            char value[32];
            (void)std::snprintf(value, sizeof(value), "%g", check.value);
            return Unexpected(Error{std::string("scenario config ") + check.field,
                                    std::string("value ") + value + " is out of range",
                                    std::string("give a value ") + check.requirement});
        }
    }
    return {};
}

Result<Scenario, Error> generateScenario(const ScenarioConfig& config)
{
    if (auto valid = validateScenarioConfig(config); !valid) {
        return Unexpected(valid.error());
    }
    const LocalFrame frame(config.originLat, config.originLon);
    const World world = makeWorld(config);
    Scenario scenario;
    for (std::size_t i = 0; i < world.ugvs.size(); ++i) {
        UgvSensor(config, world, frame, i).run(scenario.messages);
    }
    addUavFixes(config, world, frame, scenario.messages);
    std::stable_sort(scenario.messages.begin(), scenario.messages.end(), appliedBefore);
    scenario.truth = makeTruth(config, world, frame);
    return scenario;
}

} // namespace ugv::correlator
