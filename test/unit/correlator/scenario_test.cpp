// The scenario generator: determinism, time order, the sensor model (range band, field of view, noise, misses),
// pose errors of the presets and the pose corrections that undo them, track UUID changes, clutter, the UAV feed,
// the truth and config validation.

#include "ugv/correlator/scenario.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "ugv/correlator/geodesy.hpp"

namespace ugv::correlator {
namespace {

using Eigen::Vector2d;

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr double kExactM = 1e-6; ///< [m] lat/lon round trips through the tangent plane

Scenario generated(const ScenarioConfig& config)
{
    auto scenario = generateScenario(config);
    EXPECT_TRUE(scenario.has_value()) << (scenario ? "" : scenario.error().message());
    return scenario ? std::move(scenario).value() : Scenario{};
}

template <class T>
std::vector<T> messagesOf(const Scenario& scenario)
{
    std::vector<T> out;
    for (const auto& message : scenario.messages) {
        if (const auto* m = std::get_if<T>(&message)) {
            out.push_back(*m);
        }
    }
    return out;
}

/// A config whose sensor measures exactly: no noise, misses or clutter.
ScenarioConfig exactSensor(ScenarioConfig config)
{
    config.rangeSigmaM = 0.0;
    config.rangeSigmaFraction = 0.0;
    config.bearingSigmaDeg = 0.0;
    config.missProbability = 0.0;
    config.clutterRateHz = 0.0;
    return config;
}

struct Plane {
    LocalFrame frame;
    std::vector<Vector2d> statics;

    explicit Plane(const ScenarioTruth& truth) : frame(truth.originLat, truth.originLon)
    {
        for (const auto& object : truth.statics) {
            statics.push_back(frame.toLocal(object.lat, object.lon));
        }
    }

    [[nodiscard]] Vector2d ugvPosition(const Observation& o) const { return frame.toLocal(o.ugvLat, o.ugvLon); }

    /// The object's position from the reported pose, corrected by (dPosition, dHeading).
    [[nodiscard]] Vector2d project(const Observation& o, const Vector2d& dPosition = Vector2d::Zero(),
                                   double dHeadingDeg = 0.0) const
    {
        return correlator::project(ugvPosition(o) + dPosition, o.ugvHeadingDeg + dHeadingDeg + o.bearingDeg, o.rangeM);
    }

    /// Index of the static truth nearest to p, and the distance.
    [[nodiscard]] std::pair<std::size_t, double> nearestStatic(const Vector2d& p) const
    {
        std::pair<std::size_t, double> best{0, 1e300};
        for (std::size_t i = 0; i < statics.size(); ++i) {
            const double d = (statics[i] - p).norm();
            if (d < best.second) {
                best = {i, d};
            }
        }
        return best;
    }
};

bool sameMessage(const Message& a, const Message& b)
{
    if (a.index() != b.index()) {
        return false;
    }
    if (const auto* o = std::get_if<Observation>(&a)) {
        const auto& p = std::get<Observation>(b);
        return o->t == p.t && o->ugv == p.ugv && o->track == p.track && o->cls == p.cls && o->ugvLat == p.ugvLat &&
               o->ugvLon == p.ugvLon && o->ugvHeadingDeg == p.ugvHeadingDeg && o->rangeM == p.rangeM &&
               o->bearingDeg == p.bearingDeg;
    }
    if (const auto* u = std::get_if<UavFix>(&a)) {
        const auto& v = std::get<UavFix>(b);
        return u->t == v.t && u->cls == v.cls && u->lat == v.lat && u->lon == v.lon;
    }
    if (const auto* c = std::get_if<PoseCorrection>(&a)) {
        const auto& d = std::get<PoseCorrection>(b);
        return c->t == d.t && c->ugv == d.ugv && c->sinceT == d.sinceT && c->untilT == d.untilT &&
               c->dEastM == d.dEastM && c->dNorthM == d.dNorthM && c->dHeadingDeg == d.dHeadingDeg;
    }
    return false; // the generator sends no Confirm
}

double messageTime(const Message& m)
{
    return std::visit([](const auto& v) { return v.t; }, m);
}

ScenarioConfig shortConfig(ScenarioSetting setting = ScenarioSetting::Clean)
{
    ScenarioConfig config = scenarioPreset(setting);
    config.durationS = 300.0;
    return config;
}

TEST(Scenario, SameSeedGivesTheSameScenario)
{
    ScenarioConfig config = shortConfig(ScenarioSetting::Bias);
    config.poseCorrections = true;
    config.driftSigmaMPerSqrtS = 0.05;

    const Scenario a = generated(config);
    const Scenario b = generated(config);
    config.seed = 2;
    const Scenario other = generated(config);

    ASSERT_EQ(a.messages.size(), b.messages.size());
    ASSERT_GT(a.messages.size(), 1000U);
    for (std::size_t i = 0; i < a.messages.size(); ++i) {
        ASSERT_TRUE(sameMessage(a.messages[i], b.messages[i])) << "message " << i;
    }
    ASSERT_EQ(a.truth.statics.size(), other.truth.statics.size());
    EXPECT_NE(a.truth.statics[0].lat, other.truth.statics[0].lat);
    EXPECT_NE(messagesOf<Observation>(a).front().track, messagesOf<Observation>(other).front().track);
}

TEST(Scenario, MessagesAreInTheCorrelatorsOrderWithinTheDuration)
{
    ScenarioConfig config = shortConfig();
    config.poseCorrections = true;

    const Scenario sut = generated(config);

    ASSERT_FALSE(sut.messages.empty());
    EXPECT_TRUE(std::is_sorted(sut.messages.begin(), sut.messages.end(), appliedBefore));
    EXPECT_TRUE(std::is_sorted(sut.messages.begin(), sut.messages.end(),
                               [](const Message& a, const Message& b) { return messageTime(a) < messageTime(b); }));
    EXPECT_GE(messageTime(sut.messages.front()), 0.0);
    EXPECT_LE(messageTime(sut.messages.back()), config.durationS);
}

TEST(Messages, EqualTimesGoUgvByUgvCorrectionFirstThenUavFixesThenConfirmations)
{
    const auto obs = [](double t, const char* ugv) {
        Observation o;
        o.t = t;
        o.ugv = ugv;
        return Message{o};
    };
    const auto correction = [](double t, const char* ugv) {
        PoseCorrection c;
        c.t = t;
        c.ugv = ugv;
        return Message{c};
    };
    const std::vector<Message> want = {obs(4.0, "ugv-9"),
                                       correction(5.0, "ugv-1"),
                                       obs(5.0, "ugv-1"),
                                       correction(5.0, "ugv-2"),
                                       obs(5.0, "ugv-2"),
                                       Message{UavFix{.t = 5.0}},
                                       Message{Confirm{.t = 5.0, .id = "ooi-1"}},
                                       Message{Confirm{.t = 5.0, .id = "ooi-2"}},
                                       obs(5.5, "ugv-0")};
    for (std::size_t i = 0; i < want.size(); ++i) {
        for (std::size_t j = 0; j < want.size(); ++j) {
            EXPECT_EQ(appliedBefore(want[i], want[j]), i < j) << i << " before " << j;
        }
    }
}

TEST(Scenario, ObservationsAreInTheRangeBandAndTheFieldOfView)
{
    const ScenarioConfig config = shortConfig();
    constexpr double kBearingSlackDeg = 5.0; // 5 sigma of the bearing noise beyond the field of view

    const auto sut = messagesOf<Observation>(generated(config));

    ASSERT_GT(sut.size(), 1000U);
    for (const auto& o : sut) {
        ASSERT_GE(o.rangeM, config.minRangeM);
        ASSERT_LE(o.rangeM, config.maxRangeM);
        ASSERT_LE(std::abs(o.bearingDeg), config.fieldOfViewHalfDeg + kBearingSlackDeg);
        ASSERT_GE(o.ugvHeadingDeg, 0.0);
        ASSERT_LT(o.ugvHeadingDeg, 360.0);
    }
}

TEST(Scenario, CleanObservationsProjectWithinTheirNoiseOfTheTruth)
{
    ScenarioConfig config = shortConfig();
    config.clutterRateHz = 0.0;
    const Scenario scenario = generated(config);
    const Plane plane(scenario.truth);
    double radialSquares = 0.0;
    double tangentialSquares = 0.0;
    std::size_t count = 0;
    double worst = 0.0;

    for (const auto& o : messagesOf<Observation>(scenario)) {
        if (o.cls != OoiClass::Static) {
            continue;
        }
        const Vector2d projected = plane.project(o);
        const Vector2d truth = plane.statics[plane.nearestStatic(projected).first];
        const Vector2d error = projected - truth;
        const Vector2d direction = (projected - plane.ugvPosition(o)).normalized();
        const double trueRange = (truth - plane.ugvPosition(o)).norm();
        const double radial = error.dot(direction) / (config.rangeSigmaM + config.rangeSigmaFraction * trueRange);
        const double tangential =
            (error.x() * direction.y() - error.y() * direction.x()) / (trueRange * config.bearingSigmaDeg * kDegToRad);
        radialSquares += radial * radial;
        tangentialSquares += tangential * tangential;
        worst = std::max({worst, std::abs(radial), std::abs(tangential)});
        ++count;
    }

    ASSERT_GT(count, 1000U);
    EXPECT_LT(worst, 5.0); // in sigmas
    EXPECT_NEAR(std::sqrt(radialSquares / count), 1.0, 0.1);
    EXPECT_NEAR(std::sqrt(tangentialSquares / count), 1.0, 0.1);
}

TEST(Scenario, BiasSettingCorruptsThePoseWithinItsBounds)
{
    const ScenarioConfig config = exactSensor(shortConfig(ScenarioSetting::Bias));
    const Scenario scenario = generated(config);
    const Plane plane(scenario.truth);
    std::map<std::string, UgvTruth> ugvs;
    double largestBias = 0.0;
    for (const auto& ugv : scenario.truth.ugvs) {
        EXPECT_LE(std::abs(ugv.headingBiasDeg), 8.0);
        EXPECT_LE(std::hypot(ugv.offsetEastM, ugv.offsetNorthM), 1.0);
        largestBias = std::max(largestBias, std::abs(ugv.headingBiasDeg));
        ugvs[ugv.name] = ugv;
    }
    ASSERT_EQ(ugvs.size(), 5U);
    EXPECT_GT(largestBias, 2.0);
    double largestRawError = 0.0;

    for (const auto& o : messagesOf<Observation>(scenario)) {
        if (o.cls != OoiClass::Static) {
            continue;
        }
        const UgvTruth& ugv = ugvs.at(o.ugv);
        const Vector2d undone = plane.project(o, -Vector2d(ugv.offsetEastM, ugv.offsetNorthM), -ugv.headingBiasDeg);
        ASSERT_LT(plane.nearestStatic(undone).second, kExactM);
        largestRawError = std::max(largestRawError, plane.nearestStatic(plane.project(o)).second);
    }
    EXPECT_GT(largestRawError, 1.0);
}

/// The one correction of o's UGV whose window holds o.t (nullptr when none or several).
const PoseCorrection* correctionFor(const Observation& o, const std::vector<PoseCorrection>& corrections)
{
    const PoseCorrection* found = nullptr;
    for (const auto& c : corrections) {
        if (c.ugv == o.ugv && o.t >= c.sinceT && o.t <= c.untilT) {
            if (found != nullptr) {
                return nullptr;
            }
            found = &c;
        }
    }
    return found;
}

TEST(Scenario, PoseCorrectionsExactlyUndoBiasAndOffset)
{
    ScenarioConfig config = exactSensor(shortConfig(ScenarioSetting::Bias));
    config.poseCorrections = true;
    const Scenario scenario = generated(config);
    const Plane plane(scenario.truth);
    const auto corrections = messagesOf<PoseCorrection>(scenario);
    // 5 UGVs x 300 s / 60 s, and one more: ugv-1 samples at t = 300 s too (its phase is 0), in a sixth window.
    ASSERT_EQ(corrections.size(), 5U * 5U + 1U);
    for (const auto& c : corrections) {
        EXPECT_GE(c.t, c.untilT);
        EXPECT_LE(c.sinceT, c.untilT);
    }
    std::size_t checked = 0;

    for (const auto& o : messagesOf<Observation>(scenario)) {
        const PoseCorrection* c = correctionFor(o, corrections);
        ASSERT_NE(c, nullptr) << o.ugv << " at t = " << o.t;
        if (o.cls == OoiClass::Static) {
            const Vector2d corrected = plane.project(o, Vector2d(c->dEastM, c->dNorthM), c->dHeadingDeg);
            ASSERT_LT(plane.nearestStatic(corrected).second, kExactM);
            ++checked;
        }
    }
    EXPECT_GT(checked, 1000U);
}

TEST(Scenario, PoseCorrectionsOfDriftLeaveOnlyTheDeviationFromTheWindowMean)
{
    ScenarioConfig config = exactSensor(scenarioPreset(ScenarioSetting::Drift));
    config.poseCorrections = true;
    const Scenario scenario = generated(config);
    const Plane plane(scenario.truth);
    const auto corrections = messagesOf<PoseCorrection>(scenario);
    double rawSum = 0.0;
    double correctedSum = 0.0;
    std::size_t count = 0;

    for (const auto& o : messagesOf<Observation>(scenario)) {
        const PoseCorrection* c = correctionFor(o, corrections);
        ASSERT_NE(c, nullptr);
        if (o.cls == OoiClass::Static) {
            rawSum += plane.nearestStatic(plane.project(o)).second;
            correctedSum +=
                plane.nearestStatic(plane.project(o, Vector2d(c->dEastM, c->dNorthM), c->dHeadingDeg)).second;
            ++count;
        }
        EXPECT_EQ(c->dHeadingDeg, 0.0);
    }

    ASSERT_GT(count, 1000U);
    EXPECT_GT(rawSum / count, 0.3);                        // the walk is under way: 0.05 m/sqrt(s) over 600 s
    EXPECT_LT(correctedSum / count, rawSum / count / 2.0); // within a 60 s window it moves far less
}

/// Per (UGV, static object): the set of track UUIDs of its observations (exact sensor, static class only).
std::map<std::pair<std::string, std::size_t>, std::set<std::string>> tracksPerObject(const Scenario& scenario)
{
    const Plane plane(scenario.truth);
    std::map<std::pair<std::string, std::size_t>, std::set<std::string>> tracks;
    for (const auto& o : messagesOf<Observation>(scenario)) {
        if (o.cls == OoiClass::Static) {
            const auto [index, distance] = plane.nearestStatic(plane.project(o));
            EXPECT_LT(distance, kExactM);
            tracks[{o.ugv, index}].insert(o.track);
        }
    }
    return tracks;
}

std::size_t objectsWithSeveralTracks(const Scenario& scenario)
{
    const auto tracks = tracksPerObject(scenario);
    return static_cast<std::size_t>(
        std::count_if(tracks.begin(), tracks.end(), [](const auto& entry) { return entry.second.size() > 1; }));
}

TEST(Scenario, TrackUuidChangesOnReacquisition)
{
    ScenarioConfig config = exactSensor(shortConfig());
    config.trackSwitchProbability = 0.0;

    const Scenario sut = generated(config);

    EXPECT_GT(objectsWithSeveralTracks(sut), 3U);                // UGVs loop past objects and see them again
    std::map<std::string, std::set<std::string>> objectsOfTrack; // a track never spans two objects or UGVs
    for (const auto& [key, tracks] : tracksPerObject(sut)) {
        for (const auto& track : tracks) {
            objectsOfTrack[track].insert(key.first + "/" + std::to_string(key.second));
        }
    }
    for (const auto& [track, objects] : objectsOfTrack) {
        EXPECT_EQ(objects.size(), 1U) << track;
    }
}

TEST(Scenario, TrackUuidsKeptWithoutLossOrSwitches)
{
    ScenarioConfig config = exactSensor(shortConfig());
    config.trackSwitchProbability = 0.0;
    config.trackLossS = 1e9;

    EXPECT_EQ(objectsWithSeveralTracks(generated(config)), 0U);
}

TEST(Scenario, TrackUuidsSwitchAtRandom)
{
    ScenarioConfig config = exactSensor(shortConfig());
    config.trackSwitchProbability = 0.05;
    config.trackLossS = 1e9;

    EXPECT_GT(objectsWithSeveralTracks(generated(config)), 3U);
}

TEST(Scenario, TrackUuidsAreVersion4)
{
    for (const auto& o : messagesOf<Observation>(generated(shortConfig()))) {
        ASSERT_EQ(o.track.size(), 36U);
        EXPECT_EQ(o.track[8], '-');
        EXPECT_EQ(o.track[13], '-');
        EXPECT_EQ(o.track[14], '4');
        EXPECT_EQ(o.track[18], '-');
        EXPECT_NE(std::string("89ab").find(o.track[19]), std::string::npos);
        EXPECT_EQ(o.track[23], '-');
    }
}

ScenarioConfig emptyWorld()
{
    ScenarioConfig config = scenarioPreset(ScenarioSetting::Clean);
    config.staticCount = 0;
    config.closePairCount = 0;
    config.mobileCount = 0;
    config.nonCombatantCount = 0;
    config.uavTrackedMobiles = 0;
    return config;
}

TEST(Scenario, ClutterAppearsInViewAtItsRate)
{
    ScenarioConfig config = emptyWorld();
    config.clutterRateHz = 0.2;
    constexpr double kExpected = 0.2 * 600.0 * 5.0; // rate x duration x UGVs; Poisson sigma ~24

    const auto sut = messagesOf<Observation>(generated(config));

    EXPECT_NEAR(static_cast<double>(sut.size()), kExpected, 100.0);
    std::set<std::string> tracks;
    std::set<OoiClass> classes;
    for (const auto& o : sut) {
        EXPECT_GE(o.rangeM, config.minRangeM);
        EXPECT_LE(o.rangeM, config.maxRangeM);
        EXPECT_LE(std::abs(o.bearingDeg), config.fieldOfViewHalfDeg);
        tracks.insert(o.track);
        classes.insert(o.cls);
    }
    EXPECT_EQ(tracks.size(), sut.size()); // every false observation is a track of its own
    EXPECT_EQ(classes.size(), 4U);
}

TEST(Scenario, NoObjectsNoClutterNoObservations)
{
    ScenarioConfig config = emptyWorld();
    config.clutterRateHz = 0.0;

    EXPECT_TRUE(messagesOf<Observation>(generated(config)).empty());
}

TEST(Scenario, MissedDetectionsThinTheObservations)
{
    ScenarioConfig config = shortConfig();
    config.clutterRateHz = 0.0;
    config.missProbability = 0.0;
    const double all = static_cast<double>(messagesOf<Observation>(generated(config)).size());
    config.missProbability = 0.2;

    const double kept = static_cast<double>(messagesOf<Observation>(generated(config)).size());

    EXPECT_NEAR(kept / all, 0.8, 0.02);
}

TEST(Scenario, UavFixesTheFirstMobileObjectsEveryPeriod)
{
    const ScenarioConfig config = scenarioPreset(ScenarioSetting::Clean);
    const Scenario scenario = generated(config);
    const Plane plane(scenario.truth);

    const auto sut = messagesOf<UavFix>(scenario);

    ASSERT_EQ(sut.size(), 2U * 61U); // 2 tracked mobiles at t = 0, 10, ..., 600
    for (const auto& fix : sut) {
        EXPECT_EQ(fix.cls, OoiClass::Mobile);
        EXPECT_EQ(std::fmod(fix.t, 10.0), 0.0);
        const Vector2d p = plane.frame.toLocal(fix.lat, fix.lon);
        bool matched = false;
        for (const auto& sample : scenario.truth.moving) {
            const bool tracked = sample.id == "mobile-01" || sample.id == "mobile-02";
            matched = matched || (tracked && sample.t == fix.t &&
                                  (plane.frame.toLocal(sample.lat, sample.lon) - p).norm() < kExactM);
        }
        EXPECT_TRUE(matched) << "UAV fix at t = " << fix.t;
    }
}

TEST(Scenario, UavFeedCanBeOff)
{
    ScenarioConfig config = shortConfig();
    config.uavFeed = false;

    EXPECT_TRUE(messagesOf<UavFix>(generated(config)).empty());
}

TEST(Scenario, TruthHasTheObjectsAndCloseStaticPairs)
{
    const ScenarioConfig config = scenarioPreset(ScenarioSetting::Clean);
    const Scenario scenario = generated(config);
    const Plane plane(scenario.truth);

    const ScenarioTruth& sut = scenario.truth;

    ASSERT_EQ(sut.statics.size(), 20U);
    ASSERT_EQ(sut.moving.size(), 7U * 601U);
    EXPECT_EQ(sut.ugvs.size(), 5U);
    std::size_t closePairs = 0;
    for (std::size_t i = 0; i < plane.statics.size(); ++i) {
        for (std::size_t j = i + 1; j < plane.statics.size(); ++j) {
            const double d = (plane.statics[i] - plane.statics[j]).norm();
            closePairs += (d >= 3.5 && d <= 5.0) ? 1 : 0;
        }
    }
    EXPECT_GE(closePairs, 3U);
    std::map<std::string, Vector2d> last;
    for (const auto& sample : sut.moving) {
        const Vector2d p = plane.frame.toLocal(sample.lat, sample.lon);
        if (const auto it = last.find(sample.id); it != last.end()) {
            EXPECT_LE((p - it->second).norm(), 1.2 * config.mobileSpeedMps * sut.periodS + 1e-6) << sample.id;
        }
        last[sample.id] = p;
    }
    EXPECT_EQ(last.size(), 7U);
    EXPECT_EQ(last.count("noncombatant-03"), 1U);
}

TEST(Scenario, SettingsOfOneSeedShareLayoutAndSensing)
{
    const Scenario clean = generated(shortConfig(ScenarioSetting::Clean));
    const Scenario bias = generated(shortConfig(ScenarioSetting::Bias));

    ASSERT_EQ(clean.truth.statics.size(), bias.truth.statics.size());
    for (std::size_t i = 0; i < clean.truth.statics.size(); ++i) {
        EXPECT_EQ(clean.truth.statics[i].lat, bias.truth.statics[i].lat);
    }
    EXPECT_EQ(messagesOf<Observation>(clean).size(), messagesOf<Observation>(bias).size());
}

TEST(Scenario, PresetsAndSettingNames)
{
    EXPECT_EQ(scenarioPreset(ScenarioSetting::Bias).maxHeadingBiasDeg, 8.0);
    EXPECT_EQ(scenarioPreset(ScenarioSetting::Bias).maxOffsetM, 1.0);
    EXPECT_EQ(scenarioPreset(ScenarioSetting::Drift).driftSigmaMPerSqrtS, 0.05);
    const ScenarioConfig clean = scenarioPreset(ScenarioSetting::Clean);
    EXPECT_EQ(clean.maxHeadingBiasDeg + clean.maxOffsetM + clean.driftSigmaMPerSqrtS, 0.0);
    for (const auto setting : {ScenarioSetting::Clean, ScenarioSetting::Bias, ScenarioSetting::Drift}) {
        EXPECT_EQ(parseScenarioSetting(toString(setting)), setting);
    }
    EXPECT_FALSE(parseScenarioSetting("noisy").has_value());
}

TEST(Scenario, InvalidConfigsAreRefusedNamingTheField)
{
    const auto failsOn = [](ScenarioConfig config, const std::string& field) {
        const auto result = generateScenario(config);
        ASSERT_FALSE(result.has_value()) << field;
        EXPECT_NE(result.error().where.find(field), std::string::npos) << result.error().message();
        EXPECT_FALSE(result.error().fix.empty());
    };
    ScenarioConfig config;
    config.ugvCount = 0;
    failsOn(config, "ugvCount");
    config = {};
    config.maxRangeM = config.minRangeM;
    failsOn(config, "maxRangeM");
    config = {};
    config.closePairCount = 11;
    failsOn(config, "closePairCount");
    config = {};
    config.durationS = std::nan("");
    failsOn(config, "durationS");
    config = {};
    config.missProbability = 1.5;
    failsOn(config, "missProbability");
    config = {};
    config.uavTrackedMobiles = 5;
    failsOn(config, "uavTrackedMobiles");
    config = {};
    config.ugvCount = 1000;
    config.durationS = 7.0 * 24.0 * 3600.0;
    failsOn(config, "durationS"); // more sampling instants than the budget
}

} // namespace
} // namespace ugv::correlator

namespace ugv::correlator {
namespace {

/// Per-axis offsets of many UGVs drawn with `model` at scale 1 m (one short scenario, no objects).
std::vector<double> offsetsOf(OffsetModel model)
{
    ScenarioConfig config = scenarioPreset(ScenarioSetting::Clean);
    config.durationS = 1.0;
    config.ugvCount = 400;
    config.staticCount = 0;
    config.closePairCount = 0;
    config.mobileCount = 0;
    config.nonCombatantCount = 0;
    config.uavTrackedMobiles = 0;
    config.offsetModel = model;
    config.offsetSigmaM = 1.0;
    config.maxOffsetM = 1.0;
    const Scenario scenario = generated(config);
    std::vector<double> axes;
    for (const auto& ugv : scenario.truth.ugvs) {
        axes.push_back(ugv.offsetEastM);
        axes.push_back(ugv.offsetNorthM);
    }
    return axes;
}

double fractionBeyond(const std::vector<double>& values, double limit)
{
    const auto n = std::count_if(values.begin(), values.end(), [limit](double v) { return std::abs(v) > limit; });
    return static_cast<double>(n) / static_cast<double>(values.size());
}

TEST(Scenario, OffsetModelsDrawDiscGaussianAndHeavyTails)
{
    const std::vector<double> disc = offsetsOf(OffsetModel::Disc);
    const std::vector<double> gaussian = offsetsOf(OffsetModel::Gaussian);
    const std::vector<double> studentT = offsetsOf(OffsetModel::StudentT);

    EXPECT_EQ(fractionBeyond(disc, 1.0), 0.0);
    // N(0, 1): 4.6 % beyond 2 sigma, none to speak of beyond 4; t(3): 14 % beyond 2, 2.8 % beyond 4.
    EXPECT_GT(fractionBeyond(gaussian, 1.0), 0.2);
    EXPECT_LT(fractionBeyond(gaussian, 2.0), 0.09);
    EXPECT_LT(fractionBeyond(gaussian, 4.0), 0.003);
    EXPECT_GT(fractionBeyond(studentT, 4.0), 0.01);
}

TEST(Scenario, OffsetModelNames)
{
    for (const auto model : {OffsetModel::Disc, OffsetModel::Gaussian, OffsetModel::StudentT}) {
        EXPECT_EQ(parseOffsetModel(toString(model)), model);
    }
    EXPECT_FALSE(parseOffsetModel("cauchy").has_value());
}

TEST(Scenario, StaticsAnywhereFillTheAreaNotOnlyTheRouteBands)
{
    // Route corners are at most half the area size (100 m) from the centre and statics beside a route at most
    // 5 + 0.5 x 20 = 15 m from it: none beyond 115 m. Anywhere in the 200 m square, about 5 % are beyond 120 m.
    constexpr double kBeyondRoutesM = 120.0;
    ScenarioConfig config = scenarioPreset(ScenarioSetting::Clean);
    config.durationS = 1.0;
    config.staticCount = 200;
    config.closePairCount = 0;
    config.minStaticSeparationM = 0.0;
    const auto countBeyond = [&](StaticPlacement placement) {
        config.staticPlacement = placement;
        const Scenario scenario = generated(config);
        std::size_t beyond = 0;
        for (const Vector2d& p : Plane(scenario.truth).statics) {
            EXPECT_LE(p.cwiseAbs().maxCoeff(), config.areaSizeM / 2.0 + kExactM);
            beyond += p.norm() > kBeyondRoutesM ? 1U : 0U;
        }
        return beyond;
    };

    EXPECT_EQ(countBeyond(StaticPlacement::BesideRoutes), 0U);
    EXPECT_GT(countBeyond(StaticPlacement::Anywhere), 2U);
}

} // namespace
} // namespace ugv::correlator
