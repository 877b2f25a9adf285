// ugvsense correlate-sim: a simulated multi-UGV OOI scenario (correlator/scenario.hpp) written as the correlator's
// input messages (JSON lines of correlate_io, as `ugvsense correlate` reads them) and its ground truth, a JSON-lines
// file that `ugvsense correlate-eval` reads (format in kTruthFormat below, printed by --help).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <iostream>
#include <set>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "ugv/adapters/correlate_io.hpp"
#include "ugv/correlator/scenario.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"

namespace ugv::tool {
using adapters::toJsonLine;
namespace {

using correlator::ScenarioConfig;
using correlator::ScenarioSetting;
using correlator::ScenarioTruth;
using nlohmann::ordered_json;

constexpr const char* kCorrelateSimCommand = "correlate-sim";
constexpr double kMaxUgvs = 100.0;
constexpr double kMaxPeriodS = 3600.0;
constexpr std::string_view kJsonLinesExtension = ".jsonl";

constexpr const char* kTruthFormat =
    "truth file (JSON lines; default OBS.truth.jsonl beside OBS.jsonl):\n"
    "  {\"kind\":\"scenario\",\"setting\":\"clean|bias|drift\",\"seed\":N,\"ugvs\":N,\"duration_s\":S,\"period_s\":S,\n"
    "   \"origin_lat\":DEG,\"origin_lon\":DEG,\"max_heading_bias_deg\":DEG,\"max_offset_m\":M,\n"
    "   \"drift_sigma_m_per_sqrt_s\":SIGMA,\"pose_corrections\":BOOL}       first line, once\n"
    "  {\"kind\":\"ugv\",\"ugv\":\"ugv-1\",\"heading_bias_deg\":DEG,\"offset_east_m\":M,\"offset_north_m\":M}\n"
    "                                                one per UGV: its constant pose errors (drift not listed)\n"
    "  {\"kind\":\"static\",\"id\":\"static-01\",\"class\":\"static\",\"lat\":DEG,\"lon\":DEG}   one per static OOI\n"
    "  {\"kind\":\"moving\",\"id\":\"mobile-01\",\"class\":\"mobile|noncombatant\",\"t\":S,\"lat\":DEG,\"lon\":DEG}\n"
    "                                                every moving object at t = 0, period_s, ... <= duration_s";

/// OBS.jsonl -> OBS.truth.jsonl; any other name gets ".truth.jsonl" appended.
std::string defaultTruthPath(const std::string& out)
{
    if (out.size() > kJsonLinesExtension.size() && out.ends_with(kJsonLinesExtension)) {
        return out.substr(0, out.size() - kJsonLinesExtension.size()) + ".truth.jsonl";
    }
    return out + ".truth.jsonl";
}

/// A knob of the world or the sensor: option name, the config field it sets, and its bounds. The scenario's own
/// validation (validateScenarioConfig) checks what depends on other fields.
struct NumberKnob {
    const char* name;
    double ScenarioConfig::*field;
    double min;
    double max;
};

/// A knob that is a count (a whole number).
struct CountKnob {
    const char* name;
    int ScenarioConfig::*field;
    double max;
};

constexpr double kMaxKnobDistanceM = 100000.0;
constexpr double kMaxKnobCount = 10000.0;
constexpr double kMaxKnobRateHz = 100.0;
constexpr double kHalfTurnDeg = 180.0;

const std::vector<NumberKnob>& numberKnobs()
{
    static const std::vector<NumberKnob> knobs{
        {"area-m", &ScenarioConfig::areaSizeM, 1.0, kMaxKnobDistanceM},
        {"close-pair-min-m", &ScenarioConfig::closePairMinM, 0.0, kMaxKnobDistanceM},
        {"close-pair-max-m", &ScenarioConfig::closePairMaxM, 0.0, kMaxKnobDistanceM},
        {"bearing-sigma-deg", &ScenarioConfig::bearingSigmaDeg, 0.0, kHalfTurnDeg},
        {"range-sigma-m", &ScenarioConfig::rangeSigmaM, 0.0, kMaxKnobDistanceM},
        {"range-sigma-fraction", &ScenarioConfig::rangeSigmaFraction, 0.0, 1.0},
        {"fov-half-deg", &ScenarioConfig::fieldOfViewHalfDeg, 1.0, kHalfTurnDeg},
        {"min-range-m", &ScenarioConfig::minRangeM, 0.0, kMaxKnobDistanceM},
        {"max-range-m", &ScenarioConfig::maxRangeM, 0.0, kMaxKnobDistanceM},
        {"miss", &ScenarioConfig::missProbability, 0.0, 1.0},
        {"clutter-hz", &ScenarioConfig::clutterRateHz, 0.0, kMaxKnobRateHz},
        {"track-switch", &ScenarioConfig::trackSwitchProbability, 0.0, 1.0},
        {"heading-bias-deg", &ScenarioConfig::maxHeadingBiasDeg, 0.0, kHalfTurnDeg},
        {"offset-m", &ScenarioConfig::maxOffsetM, 0.0, kMaxKnobDistanceM},
        {"offset-sigma-m", &ScenarioConfig::offsetSigmaM, 0.0, kMaxKnobDistanceM},
        {"drift", &ScenarioConfig::driftSigmaMPerSqrtS, 0.0, kMaxKnobDistanceM},
    };
    return knobs;
}

const std::vector<CountKnob>& countKnobs()
{
    static const std::vector<CountKnob> knobs{
        {"statics", &ScenarioConfig::staticCount, kMaxKnobCount},
        {"close-pairs", &ScenarioConfig::closePairCount, kMaxKnobCount},
        {"mobiles", &ScenarioConfig::mobileCount, kMaxKnobCount},
        {"noncombatants", &ScenarioConfig::nonCombatantCount, kMaxKnobCount},
    };
    return knobs;
}

/// The world and sensor knobs on top of the setting's preset; an unset option keeps the preset's value.
Result<void, Error> applyKnobs(const Args& args, ScenarioConfig& config)
{
    for (const NumberKnob& knob : numberKnobs()) {
        const auto value = args.number(knob.name, config.*knob.field, knob.min, knob.max);
        if (!value) {
            return Unexpected(value.error());
        }
        config.*knob.field = *value;
    }
    for (const CountKnob& knob : countKnobs()) {
        const auto value = args.wholeNumber(knob.name, config.*knob.field, 0, knob.max);
        if (!value) {
            return Unexpected(value.error());
        }
        config.*knob.field = static_cast<int>(*value);
    }
    if (args.has("offset-model")) {
        const std::string name = args.get("offset-model");
        const auto model = correlator::parseOffsetModel(name);
        if (!model) {
            return Unexpected(Error{"ugvsense " + std::string(kCorrelateSimCommand) + " --offset-model",
                                    "unknown offset model '" + name + "'", "use disc, gaussian or student-t"});
        }
        config.offsetModel = *model;
    }
    if (args.has("statics-anywhere")) {
        config.staticPlacement = correlator::StaticPlacement::Anywhere;
    }
    // The UAV fixes the first mobiles: never more than there are.
    config.uavTrackedMobiles = std::min(config.uavTrackedMobiles, config.mobileCount);
    return {};
}

/// The scenario config from the command line; usage errors name the option.
Result<ScenarioConfig, Error> configFrom(const Args& args)
{
    const std::string settingName = args.get("setting", "clean");
    const auto setting = correlator::parseScenarioSetting(settingName);
    if (!setting) {
        return Unexpected(Error{"ugvsense " + std::string(kCorrelateSimCommand) + " --setting",
                                "unknown setting '" + settingName + "'", "use clean, bias or drift"});
    }
    ScenarioConfig config = correlator::scenarioPreset(*setting);
    const auto ugvs = args.wholeNumber("ugvs", config.ugvCount, 1, kMaxUgvs);
    const auto seed = args.wholeNumber("seed", static_cast<double>(config.seed), 0, kMaxScenarioSeed);
    const auto duration = args.number("duration", config.durationS, 1, kMaxScenarioDurationS);
    const auto period = args.number("period", config.truthPeriodS, 0.01, kMaxPeriodS);
    for (const auto* number : {&ugvs, &seed, &duration, &period}) {
        if (!*number) {
            return Unexpected(number->error());
        }
    }
    config.ugvCount = static_cast<int>(*ugvs);
    config.seed = static_cast<std::uint64_t>(*seed);
    config.durationS = *duration;
    config.truthPeriodS = *period;
    config.poseCorrections = args.has("pose-corrections");
    if (auto knobs = applyKnobs(args, config); !knobs) {
        return Unexpected(knobs.error());
    }
    if (auto valid = correlator::validateScenarioConfig(config); !valid) {
        return Unexpected(valid.error());
    }
    return config;
}

Result<void, Error> writeMessages(const std::string& path, const std::vector<correlator::Message>& messages)
{
    std::ofstream out(path);
    if (!out) {
        return Unexpected(
            Error{path, "cannot open the file for writing", "check that the folder exists and is writable"});
    }
    for (const auto& message : messages) {
        out << toJsonLine(message) << '\n';
    }
    out.flush();
    if (!out) {
        return Unexpected(Error{path, "cannot write the file", "check the free space"});
    }
    return {};
}

ordered_json headerLine(const ScenarioConfig& config, ScenarioSetting setting, const ScenarioTruth& truth)
{
    return ordered_json{{"kind", "scenario"},
                        {"setting", correlator::toString(setting)},
                        {"seed", config.seed},
                        {"ugvs", config.ugvCount},
                        {"duration_s", truth.durationS},
                        {"period_s", truth.periodS},
                        {"origin_lat", truth.originLat},
                        {"origin_lon", truth.originLon},
                        {"max_heading_bias_deg", config.maxHeadingBiasDeg},
                        {"max_offset_m", config.maxOffsetM},
                        {"drift_sigma_m_per_sqrt_s", config.driftSigmaMPerSqrtS},
                        {"pose_corrections", config.poseCorrections},
                        {"offset_model", correlator::toString(config.offsetModel)},
                        {"offset_sigma_m", config.offsetSigmaM},
                        {"area_m", config.areaSizeM},
                        {"bearing_sigma_deg", config.bearingSigmaDeg},
                        {"range_sigma_m", config.rangeSigmaM},
                        {"range_sigma_fraction", config.rangeSigmaFraction},
                        {"fov_half_deg", config.fieldOfViewHalfDeg},
                        {"miss", config.missProbability},
                        {"clutter_hz", config.clutterRateHz},
                        {"track_switch", config.trackSwitchProbability},
                        {"close_pairs", config.closePairCount},
                        {"close_pair_min_m", config.closePairMinM},
                        {"close_pair_max_m", config.closePairMaxM}};
}

/// The truth as JSON lines (kTruthFormat): header, UGVs, static objects, moving samples.
std::vector<ordered_json> truthLines(const ScenarioConfig& config, ScenarioSetting setting, const ScenarioTruth& truth)
{
    std::vector<ordered_json> lines{headerLine(config, setting, truth)};
    for (const auto& ugv : truth.ugvs) {
        lines.push_back({{"kind", "ugv"},
                         {"ugv", ugv.name},
                         {"heading_bias_deg", ugv.headingBiasDeg},
                         {"offset_east_m", ugv.offsetEastM},
                         {"offset_north_m", ugv.offsetNorthM}});
    }
    for (const auto& object : truth.statics) {
        lines.push_back(
            {{"kind", "static"}, {"id", object.id}, {"class", "static"}, {"lat", object.lat}, {"lon", object.lon}});
    }
    for (const auto& sample : truth.moving) {
        lines.push_back({{"kind", "moving"},
                         {"id", sample.id},
                         {"class", correlator::toString(sample.cls)},
                         {"t", sample.t},
                         {"lat", sample.lat},
                         {"lon", sample.lon}});
    }
    return lines;
}

Result<void, Error> writeTruth(const std::string& path, const std::vector<ordered_json>& lines)
{
    std::ofstream out(path);
    if (!out) {
        return Unexpected(
            Error{path, "cannot open the file for writing", "check that the folder exists and is writable"});
    }
    for (const auto& line : lines) {
        out << line.dump() << '\n';
    }
    out.flush();
    if (!out) {
        return Unexpected(Error{path, "cannot write the file", "check the free space"});
    }
    return {};
}

/// Messages per kind, in the order of the Message variant (observation, UAV fix, confirm, pose correction).
std::vector<std::size_t> countByKind(const std::vector<correlator::Message>& messages)
{
    std::vector<std::size_t> counts(std::variant_size_v<correlator::Message>, 0);
    for (const auto& message : messages) {
        ++counts[message.index()];
    }
    return counts;
}

/// Number of distinct moving objects of class `cls`.
std::size_t countClass(const ScenarioTruth& truth, correlator::OoiClass cls)
{
    std::set<std::string> ids;
    for (const auto& sample : truth.moving) {
        if (sample.cls == cls) {
            ids.insert(sample.id);
        }
    }
    return ids.size();
}

void printSummary(const ScenarioConfig& config, ScenarioSetting setting, const correlator::Scenario& scenario,
                  const std::string& out, const std::string& truthPath)
{
    const auto counts = countByKind(scenario.messages);
    const ScenarioTruth& truth = scenario.truth;
    std::cout << "wrote " << scenario.messages.size() << " messages (" << counts[0] << " observations, " << counts[1]
              << " UAV fixes, " << counts[3] << " pose corrections) of " << config.ugvCount << " UGVs over "
              << config.durationS << " s (setting " << correlator::toString(setting) << ", seed " << config.seed
              << ") to " << out << "\nwrote the truth (" << truth.statics.size() << " static, "
              << countClass(truth, correlator::OoiClass::Mobile) << " mobile, "
              << countClass(truth, correlator::OoiClass::NonCombatant) << " non-combatant objects; "
              << truth.moving.size() << " moving samples every " << truth.periodS << " s) to " << truthPath << '\n';
}

} // namespace

int runCorrelateSim(int argc, char** argv)
{
    Args args(kCorrelateSimCommand,
              "--out OBS.jsonl [--truth TRUTH.jsonl] [--setting clean|bias|drift] [--ugvs N] [--duration S] "
              "[--seed N] [--period S] [--pose-corrections] [world and sensor knobs, below]\n"
              "  Simulates UGVs patrolling loops and reporting objects of interest (static, mobile, non-combatant)\n"
              "  with range/bearing noise, misses, clutter and track UUID changes, a UAV fixing mobile objects, and\n"
              "  per-UGV pose errors by setting: clean (none), bias (heading bias up to 8 deg, offset up to 1 m),\n"
              "  drift (random walk 0.05 m per sqrt(s)). Writes the correlator's input messages (JSON lines, the\n"
              "  format of 'ugvsense correlate') and the ground truth for 'ugvsense correlate-eval'.\n\n" +
                  std::string(kTruthFormat),
              {{"out", "OBS.jsonl", "input messages to write (observation, uav, pose_correction lines)", true},
               {"truth", "TRUTH.jsonl", "truth file to write, default OBS.truth.jsonl", false},
               {"setting", "NAME", "pose errors: clean, bias or drift, default clean", false},
               {"ugvs", "N", "number of UGVs, default 5", false},
               {"duration", "S", "scenario length in seconds, default 600", false},
               {"seed", "N", "random seed, default 1 (the settings of one seed share layout and noise)", false},
               {"period", "S", "truth sampling of moving objects (the snapshot period), default 1", false},
               {"pose-corrections", "", "emit the map builder's exact pose corrections every 60 s per UGV", false},
               {"area-m", "M", "side of the square area, default 200", false},
               {"statics", "N", "static OOIs (close pairs included), default 20", false},
               {"close-pairs", "N", "pairs of statics closer than the others, default 3", false},
               {"close-pair-min-m", "M", "a close pair's least distance, default 3.5", false},
               {"close-pair-max-m", "M", "a close pair's greatest distance, default 5", false},
               {"statics-anywhere", "", "statics anywhere in the area, not only beside the routes", false},
               {"mobiles", "N", "mobile OOIs, default 4 (the UAV fixes the first 2)", false},
               {"noncombatants", "N", "non-combatants, default 3", false},
               {"bearing-sigma-deg", "DEG", "bearing noise sigma, default 1", false},
               {"range-sigma-m", "M", "range noise sigma at zero range, default 0.1", false},
               {"range-sigma-fraction", "F", "range noise growth per metre of range, default 0.01", false},
               {"fov-half-deg", "DEG", "half the field of view, default 60", false},
               {"min-range-m", "M", "least range seen, default 5", false},
               {"max-range-m", "M", "greatest range seen, default 25", false},
               {"miss", "P", "probability of a missed detection, default 0.2", false},
               {"clutter-hz", "HZ", "false observations per UGV per second, default 0.02", false},
               {"track-switch", "P", "probability of a new track UUID at any detection, default 0.002", false},
               {"heading-bias-deg", "DEG", "heading bias uniform in +-DEG per UGV (overrides the setting's)", false},
               {"offset-model", "NAME",
                "position offset: disc (uniform, radius --offset-m), gaussian or student-t "
                "(--offset-sigma-m per axis), default disc",
                false},
               {"offset-m", "M", "radius of the disc offset model (overrides the setting's)", false},
               {"offset-sigma-m", "M", "per-axis scale of the gaussian and student-t offset models", false},
               {"drift", "SIGMA", "random-walk drift [m/sqrt(s)] per axis (overrides the setting's)", false}});
    if (const auto exit = parseOrExit(args, argc, argv, kCorrelateSimCommand)) {
        return *exit;
    }
    const auto config = configFrom(args);
    if (!config) {
        return reportUsageError(kCorrelateSimCommand, config.error());
    }
    const ScenarioSetting setting = *correlator::parseScenarioSetting(args.get("setting", "clean"));
    auto scenario = correlator::generateScenario(*config);
    if (!scenario) {
        return reportUsageError(kCorrelateSimCommand, scenario.error());
    }
    const std::string out = args.get("out");
    const std::string truthPath = args.get("truth", defaultTruthPath(out));
    if (auto written = writeMessages(out, scenario->messages); !written) {
        return reportError(kCorrelateSimCommand, written.error());
    }
    if (auto written = writeTruth(truthPath, truthLines(*config, setting, scenario->truth)); !written) {
        return reportError(kCorrelateSimCommand, written.error());
    }
    printSummary(*config, setting, *scenario, out, truthPath);
    return 0;
}

} // namespace ugv::tool
