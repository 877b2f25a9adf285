#include "ugv/tool/correlate_sweep.hpp"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include <sys/utsname.h>

#include <nlohmann/json.hpp>

#include "ugv/correlator/correlator_feed.hpp"
#include "ugv/correlator/mode.hpp"
#include "ugv/correlator/scenario.hpp"
#include "ugv/tool/correlate_score.hpp"

namespace ugv::tool {
namespace {

using correlator::OffsetModel;
using correlator::ScenarioConfig;
using nlohmann::ordered_json;

constexpr double kSecondsPerHour = 3600.0;
constexpr double kSnapshotPeriodS = 1.0;
// Issue 21's targets.
constexpr double kStaticRatio = 0.5; ///< pose-corrected's median static GOSPA at most this x original's (pose errors)
constexpr double kMobileRatio = 0.7; ///< pose-corrected's median mobile GOSPA at most this x original's (pose errors)
constexpr double kCleanSlackM = 0.2; ///< [m] without pose errors: at most original's + this
constexpr double kIdChangesPerHour = 1.0; ///< median static ID changes per hour over the grid, at most
constexpr double kMinPoseBiasDeg = 2.0;   ///< a point has pose errors with a heading bias of at least this, ...
constexpr double kTolerance = 1e-9;       ///< comparisons of equal figures

struct SweepPoint {
    std::string name;
    ScenarioConfig config;
};

/// Pose errors in the sense of the targets: heading bias >= 2 deg, an offset, or drift.
bool hasPoseErrors(const ScenarioConfig& c)
{
    const bool offset = c.offsetModel == OffsetModel::Disc ? c.maxOffsetM > 0.0 : c.offsetSigmaM > 0.0;
    return c.maxHeadingBiasDeg >= kMinPoseBiasDeg || offset || c.driftSigmaMPerSqrtS > 0.0;
}

ScenarioConfig simCentre()
{
    return correlator::scenarioPreset(correlator::ScenarioSetting::Clean);
}

/// Issue 21's "bias" scenario as this generator can make it.
ScenarioConfig harshCentre()
{
    ScenarioConfig c = simCentre();
    c.areaSizeM = 250.0; // the figures, named by the fields
    c.staticCount = 30;
    c.closePairCount = 5;
    c.mobileCount = 3;
    c.bearingSigmaDeg = 2.0;
    c.rangeSigmaM = 0.2;
    c.rangeSigmaFraction = 0.04;
    c.fieldOfViewHalfDeg = 35.0;
    c.missProbability = 0.15;
    c.trackSwitchProbability = 0.02;
    c.clutterRateHz = 1.0 / 60.0;
    c.maxHeadingBiasDeg = 8.0;
    c.offsetModel = OffsetModel::Gaussian;
    c.offsetSigmaM = 1.0;
    return c;
}

/// One knob moved to one value: a name suffix and the change.
struct Variant {
    std::string name;
    std::function<void(ScenarioConfig&)> apply;
};

std::vector<Variant> variants()
{
    // The grid's values, named by the variant.
    return {
        {"bearing=0.5", [](ScenarioConfig& c) { c.bearingSigmaDeg = 0.5; }},
        {"bearing=3", [](ScenarioConfig& c) { c.bearingSigmaDeg = 3.0; }},
        {"range=1%+0.1", [](ScenarioConfig& c) { c.rangeSigmaFraction = 0.01, c.rangeSigmaM = 0.1; }},
        {"range=5%+0.3", [](ScenarioConfig& c) { c.rangeSigmaFraction = 0.05, c.rangeSigmaM = 0.3; }},
        {"fov=35", [](ScenarioConfig& c) { c.fieldOfViewHalfDeg = 35.0; }},
        {"fov=60", [](ScenarioConfig& c) { c.fieldOfViewHalfDeg = 60.0; }},
        {"switch=0.002", [](ScenarioConfig& c) { c.trackSwitchProbability = 0.002; }},
        {"switch=0.02", [](ScenarioConfig& c) { c.trackSwitchProbability = 0.02; }},
        {"switch=0.05", [](ScenarioConfig& c) { c.trackSwitchProbability = 0.05; }},
        {"offset=gauss1.5",
         [](ScenarioConfig& c) { c.offsetModel = OffsetModel::Gaussian, c.offsetSigmaM = 1.5, c.maxOffsetM = 0.0; }},
        {"offset=t3x1",
         [](ScenarioConfig& c) { c.offsetModel = OffsetModel::StudentT, c.offsetSigmaM = 1.0, c.maxOffsetM = 0.0; }},
        {"offset=none",
         [](ScenarioConfig& c) { c.offsetModel = OffsetModel::Disc, c.offsetSigmaM = 0.0, c.maxOffsetM = 0.0; }},
        {"miss=0.1", [](ScenarioConfig& c) { c.missProbability = 0.1; }},
        {"miss=0.3", [](ScenarioConfig& c) { c.missProbability = 0.3; }},
        {"clutter=0.01", [](ScenarioConfig& c) { c.clutterRateHz = 0.01; }},
        {"clutter=0.05", [](ScenarioConfig& c) { c.clutterRateHz = 0.05; }},
        {"pairs=3m", [](ScenarioConfig& c) { c.closePairMinM = 3.0, c.closePairMaxM = 3.0; }},
        {"pairs=5m", [](ScenarioConfig& c) { c.closePairMinM = 5.0, c.closePairMaxM = 5.0; }},
        {"bias=0", [](ScenarioConfig& c) { c.maxHeadingBiasDeg = 0.0; }},
        {"bias=2", [](ScenarioConfig& c) { c.maxHeadingBiasDeg = 2.0; }},
        {"bias=10", [](ScenarioConfig& c) { c.maxHeadingBiasDeg = 10.0; }},
        {"drift=0.02", [](ScenarioConfig& c) { c.driftSigmaMPerSqrtS = 0.02; }},
        {"drift=0.08", [](ScenarioConfig& c) { c.driftSigmaMPerSqrtS = 0.08; }},
    };
}

/// The knobs the variants move, to tell a variant that changes nothing from one that does.
bool sameKnobs(const ScenarioConfig& a, const ScenarioConfig& b)
{
    return a.bearingSigmaDeg == b.bearingSigmaDeg && a.rangeSigmaM == b.rangeSigmaM &&
           a.rangeSigmaFraction == b.rangeSigmaFraction && a.fieldOfViewHalfDeg == b.fieldOfViewHalfDeg &&
           a.trackSwitchProbability == b.trackSwitchProbability && a.offsetModel == b.offsetModel &&
           a.offsetSigmaM == b.offsetSigmaM && a.maxOffsetM == b.maxOffsetM && a.missProbability == b.missProbability &&
           a.clutterRateHz == b.clutterRateHz && a.closePairMinM == b.closePairMinM &&
           a.closePairMaxM == b.closePairMaxM && a.maxHeadingBiasDeg == b.maxHeadingBiasDeg &&
           a.driftSigmaMPerSqrtS == b.driftSigmaMPerSqrtS;
}

std::vector<SweepPoint> grid(const SweepOptions& options)
{
    const double duration = options.durationS;
    std::vector<SweepPoint> points;
    const auto add = [&](std::string name, ScenarioConfig config) {
        config.durationS = duration;
        if (options.only.empty() || name.find(options.only) != std::string::npos) {
            points.push_back({std::move(name), config});
        }
    };
    ScenarioConfig drift = harshCentre();
    drift.driftSigmaMPerSqrtS = 0.05; // issue 21's second scenario
    if (options.quick) {
        ScenarioConfig simBias = correlator::scenarioPreset(correlator::ScenarioSetting::Bias);
        add("sim", simCentre());
        add("sim/bias-setting", simBias);
        add("harsh", harshCentre());
        add("harsh/drift=0.05", drift);
        return points;
    }
    for (const auto& [centreName, centre] : {std::pair{"sim", simCentre()}, std::pair{"harsh", harshCentre()}}) {
        add(centreName, centre);
        for (const Variant& variant : variants()) {
            ScenarioConfig config = centre;
            variant.apply(config);
            if (!sameKnobs(config, centre)) {
                std::string name = centreName;
                name += '/';
                name += variant.name;
                add(std::move(name), config);
            }
        }
    }
    add("harsh/drift=0.05", drift);
    add("sim/bias-setting", correlator::scenarioPreset(correlator::ScenarioSetting::Bias));
    add("sim/drift-setting", correlator::scenarioPreset(correlator::ScenarioSetting::Drift));
    return points;
}

// ---- running and summarising ---------------------------------------------------------------------------------

/// One mode's figures on one seed.
struct Run {
    double staticGospa = 0.0; ///< [m] at the last snapshot
    double mobileGospa = 0.0; ///< [m] mean over the snapshots
    double staticIdChanges = 0.0;
    double staticFalse = 0.0; ///< false static objects at the last snapshot
    double staticMissed = 0.0;
    double seconds = 0.0; ///< [s] of computation (add and snapshot)
    double messages = 0.0;
};

Run runMode(correlator::Mode mode, const correlator::Scenario& scenario, const Truth& truth)
{
    correlator::CorrelatorFeed feed(mode, kSnapshotPeriodS);
    SnapshotScorer scorer(truth);
    const auto onSnapshot = [&scorer](const correlator::Snapshot& s) { scorer.add(s); };
    const auto t0 = std::chrono::steady_clock::now();
    for (const correlator::Message& message : scenario.messages) {
        (void)feed.add(message, onSnapshot); // a refused message is the generator's bug; the figures show it
    }
    (void)feed.finish(onSnapshot);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const Figures& f = scorer.figures();
    return Run{f.staticLast.total,
               f.mobile.mean(f.mobile.total),
               static_cast<double>(f.staticIdChanges),
               static_cast<double>(f.staticLast.falseCount),
               static_cast<double>(f.staticLast.missed),
               seconds,
               static_cast<double>(scenario.messages.size())};
}

double median(std::vector<double> v)
{
    if (v.empty()) {
        return 0.0;
    }
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 == 1 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2.0;
}

double worst(const std::vector<double>& v)
{
    return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
}

/// One figure of one mode over the seeds.
struct Series {
    std::vector<double> values;
    [[nodiscard]] double med() const { return median(values); }
    [[nodiscard]] double max() const { return worst(values); }
};

struct ModeSeries {
    Series staticGospa, mobileGospa, idChanges, staticFalse, staticMissed, seconds, messages;

    void add(const Run& r)
    {
        staticGospa.values.push_back(r.staticGospa);
        mobileGospa.values.push_back(r.mobileGospa);
        idChanges.values.push_back(r.staticIdChanges);
        staticFalse.values.push_back(r.staticFalse);
        staticMissed.values.push_back(r.staticMissed);
        seconds.values.push_back(r.seconds);
        messages.values.push_back(r.messages);
    }
};

struct Targets {
    bool poseErrors = false;
    bool staticMedian = true; ///< pose errors: <= 0.5x; else <= original + 0.2 m
    bool mobileMedian = true; ///< pose errors only: <= 0.7x
    bool idChanges = true;    ///< pose errors only: median <= original's
    bool worstSeed = true;    ///< pose errors only: static and mobile worst <= original's
    [[nodiscard]] bool all() const { return staticMedian && mobileMedian && idChanges && worstSeed; }
};

Targets check(const ScenarioConfig& config, const ModeSeries& o, const ModeSeries& i)
{
    Targets t;
    t.poseErrors = hasPoseErrors(config);
    if (!t.poseErrors) {
        t.staticMedian = i.staticGospa.med() <= o.staticGospa.med() + kCleanSlackM + kTolerance;
        return t;
    }
    t.staticMedian = i.staticGospa.med() <= kStaticRatio * o.staticGospa.med() + kTolerance;
    t.mobileMedian = i.mobileGospa.med() <= kMobileRatio * o.mobileGospa.med() + kTolerance;
    t.idChanges = i.idChanges.med() <= o.idChanges.med() + kTolerance;
    t.worstSeed = i.staticGospa.max() <= o.staticGospa.max() + kTolerance &&
                  i.mobileGospa.max() <= o.mobileGospa.max() + kTolerance;
    return t;
}

struct PointResult {
    SweepPoint point;
    ModeSeries original;
    ModeSeries poseCorrected;
    Targets targets;
};

ordered_json seriesJson(const Series& s)
{
    return ordered_json{{"median", s.med()}, {"worst", s.max()}, {"seeds", s.values}};
}

ordered_json modeJson(const ModeSeries& m)
{
    return ordered_json{{"static_gospa_m", seriesJson(m.staticGospa)},  {"mobile_gospa_m", seriesJson(m.mobileGospa)},
                        {"static_id_changes", seriesJson(m.idChanges)}, {"static_false", seriesJson(m.staticFalse)},
                        {"static_missed", seriesJson(m.staticMissed)},  {"seconds", seriesJson(m.seconds)}};
}

ordered_json configJson(const ScenarioConfig& c)
{
    return ordered_json{{"duration_s", c.durationS},
                        {"area_m", c.areaSizeM},
                        {"statics", c.staticCount},
                        {"close_pairs", c.closePairCount},
                        {"close_pair_m", {c.closePairMinM, c.closePairMaxM}},
                        {"mobiles", c.mobileCount},
                        {"bearing_sigma_deg", c.bearingSigmaDeg},
                        {"range_sigma_m", c.rangeSigmaM},
                        {"range_sigma_fraction", c.rangeSigmaFraction},
                        {"fov_half_deg", c.fieldOfViewHalfDeg},
                        {"miss", c.missProbability},
                        {"clutter_hz", c.clutterRateHz},
                        {"track_switch", c.trackSwitchProbability},
                        {"heading_bias_deg", c.maxHeadingBiasDeg},
                        {"offset_model", correlator::toString(c.offsetModel)},
                        {"offset_m", c.offsetModel == OffsetModel::Disc ? c.maxOffsetM : c.offsetSigmaM},
                        {"drift_m_per_sqrt_s", c.driftSigmaMPerSqrtS}};
}

std::string machineName()
{
    utsname u{};
    if (uname(&u) != 0) {
        return "unknown";
    }
    std::string cpu;
    std::ifstream cpuinfo("/proc/cpuinfo");
    for (std::string line; std::getline(cpuinfo, line);) {
        if (line.rfind("model name", 0) == 0) {
            cpu = line.substr(line.find(':') + 2);
            break;
        }
    }
    return std::string(u.nodename) + " (" + u.machine + ", " + cpu + ")";
}

void printHeader()
{
    std::printf("%-26s %4s | %-13s %-13s | %-13s %-13s | %-9s %-9s | %s\n", "point", "pose", "static orig",
                "static p-corr", "mobile orig", "mobile p-corr", "idch orig", "idch pcor", "targets");
    std::printf("%-26s %4s | %-13s %-13s | %-13s %-13s | %-9s %-9s |\n", "", "err", "med / worst", "med / worst",
                "med / worst", "med / worst", "med/worst", "med/worst");
}

void printRow(const PointResult& r)
{
    const auto pair = [](const Series& s) {
        char text[32];
        (void)std::snprintf(text, sizeof(text), "%5.2f / %5.2f", s.med(), s.max());
        return std::string(text);
    };
    const auto counts = [](const Series& s) {
        char text[32];
        (void)std::snprintf(text, sizeof(text), "%3.1f / %-3.0f", s.med(), s.max());
        return std::string(text);
    };
    const Targets& t = r.targets;
    char flags[8] = {};
    if (t.poseErrors) {
        (void)std::snprintf(flags, sizeof(flags), "%c%c%c%c", t.staticMedian ? 'S' : 's', t.mobileMedian ? 'M' : 'm',
                            t.idChanges ? 'I' : 'i', t.worstSeed ? 'W' : 'w');
    } else {
        (void)std::snprintf(flags, sizeof(flags), "%c", t.staticMedian ? 'C' : 'c');
    }
    std::printf("%-26s %4s | %-13s %-13s | %-13s %-13s | %-9s %-9s | %s\n", r.point.name.c_str(),
                t.poseErrors ? "yes" : "no", pair(r.original.staticGospa).c_str(),
                pair(r.poseCorrected.staticGospa).c_str(), pair(r.original.mobileGospa).c_str(),
                pair(r.poseCorrected.mobileGospa).c_str(), counts(r.original.idChanges).c_str(),
                counts(r.poseCorrected.idChanges).c_str(), flags);
    (void)std::fflush(stdout);
}

/// What the sweep adds up over every run of the grid.
struct SweepTotals {
    std::vector<double> idPerHour; ///< pose-corrected's static ID changes per hour of mission, every run
    std::vector<double> idPerHourOriginal;
    double messages[2] = {0.0, 0.0}; ///< original, pose-corrected
    double seconds[2] = {0.0, 0.0};

    double rate(int mode) const { return seconds[mode] > 0 ? messages[mode] / seconds[mode] : 0.0; }
};

/// Writes the sweep's JSON summary to options.jsonPath; false (with a message) when it cannot be written.
bool writeSummary(const SweepOptions& options, const std::vector<PointResult>& results, const SweepTotals& totals,
                  std::size_t met, bool idTarget)
{
    ordered_json j{{"machine", machineName()},        {"seeds", options.seeds}, {"first_seed", options.firstSeed},
                   {"duration_s", options.durationS}, {"quick", options.quick}, {"points", ordered_json::array()}};
    for (const PointResult& r : results) {
        j["points"].push_back(ordered_json{{"name", r.point.name},
                                           {"pose_errors", r.targets.poseErrors},
                                           {"config", configJson(r.point.config)},
                                           {"original", modeJson(r.original)},
                                           {"pose-corrected", modeJson(r.poseCorrected)},
                                           {"targets",
                                            {{"static_median", r.targets.staticMedian},
                                             {"mobile_median", r.targets.mobileMedian},
                                             {"id_changes", r.targets.idChanges},
                                             {"worst_seed", r.targets.worstSeed},
                                             {"all", r.targets.all()}}}});
    }
    j["summary"] =
        ordered_json{{"points", results.size()},
                     {"points_meeting_every_target", met},
                     {"id_changes_per_hour_median",
                      {{"original", median(totals.idPerHourOriginal)}, {"pose-corrected", median(totals.idPerHour)}}},
                     {"id_changes_per_hour_target_met", idTarget},
                     {"messages_per_s", {{"original", totals.rate(0)}, {"pose-corrected", totals.rate(1)}}}};
    std::ofstream out(options.jsonPath);
    out << j.dump(2) << '\n';
    out.flush();
    if (!out) {
        std::cerr << "ugvsense correlate-eval --sweep: error: " << options.jsonPath
                  << ": cannot write the summary; fix: check that the folder exists and is writable\n";
        return false;
    }
    std::printf("wrote the summary to %s\n", options.jsonPath.c_str());
    return true;
}

} // namespace

int runCorrelateSweep(const SweepOptions& options)
{
    const std::vector<SweepPoint> points = grid(options);
    std::printf(
        "correlate-eval --sweep: %zu points x %d seeds (from %llu), %.0f s each, modes original and pose-corrected\n",
        points.size(), options.seeds, static_cast<unsigned long long>(options.firstSeed), options.durationS);
    std::printf("GOSPA c 5 m, p 2: static at the last snapshot, mobile mean over snapshots; idch: static ID changes\n");
    std::printf("targets: with pose errors S static median <= 0.5x, M mobile median <= 0.7x, I ID changes median <= "
                "original's, W worst seed (static, mobile) <= original's; without: C static median <= original's + "
                "0.2 m; lower case: missed\n");
    printHeader();
    std::vector<PointResult> results;
    SweepTotals totals;
    for (const SweepPoint& point : points) {
        PointResult result{point, {}, {}, {}};
        for (int k = 0; k < options.seeds; ++k) {
            ScenarioConfig config = point.config;
            config.seed = options.firstSeed + static_cast<std::uint64_t>(k);
            auto scenario = correlator::generateScenario(config);
            if (!scenario) {
                std::cerr << "ugvsense correlate-eval --sweep: " << point.name << ": " << scenario.error().message()
                          << '\n';
                return 1;
            }
            const Truth truth = truthOf(scenario->truth);
            const Run o = runMode(correlator::Mode::Original, *scenario, truth);
            const Run i = runMode(correlator::Mode::PoseCorrected, *scenario, truth);
            result.original.add(o);
            result.poseCorrected.add(i);
            const double hours = config.durationS / kSecondsPerHour;
            totals.idPerHour.push_back(i.staticIdChanges / hours);
            totals.idPerHourOriginal.push_back(o.staticIdChanges / hours);
            totals.messages[0] += o.messages;
            totals.messages[1] += i.messages;
            totals.seconds[0] += o.seconds;
            totals.seconds[1] += i.seconds;
        }
        result.targets = check(point.config, result.original, result.poseCorrected);
        printRow(result);
        results.push_back(std::move(result));
    }
    std::size_t met = 0;
    for (const PointResult& r : results) {
        met += r.targets.all() ? 1U : 0U;
    }
    const double idMedian = median(totals.idPerHour);
    const bool idTarget = idMedian <= kIdChangesPerHour + kTolerance;
    std::printf("points meeting every target: %zu of %zu\n", met, results.size());
    std::printf("static ID changes per hour over the grid (median of every run): original %.2f, pose-corrected %.2f "
                "(target <= %.0f: %s)\n",
                median(totals.idPerHourOriginal), idMedian, kIdChangesPerHour, idTarget ? "met" : "missed");
    std::printf("throughput over the sweep: original %.0f, pose-corrected %.0f messages/s (add and snapshot)\n",
                totals.rate(0), totals.rate(1));
    if (!options.jsonPath.empty() && !writeSummary(options, results, totals, met, idTarget)) {
        return 1;
    }
    constexpr int kTargetsMissedExit = 3;
    return options.requireTargets && (met < results.size() || !idTarget) ? kTargetsMissedExit : 0;
}

} // namespace ugv::tool
