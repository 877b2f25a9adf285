// ugvsense correlate-eval: scores the correlator's snapshots (JSON lines of correlate_io, as `ugvsense correlate`
// writes them) against the ground truth of `ugvsense correlate-sim` (format in correlate_sim_cmd.cpp); the
// figures are those of correlate_score.hpp. `--sweep` runs both modes over a grid of simulated worlds instead
// (correlate_sweep.hpp).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <iterator>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ugv/adapters/correlate_io.hpp"
#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/gospa.hpp"
#include "ugv/correlator/messages.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"
#include "ugv/tool/correlate_score.hpp"
#include "ugv/tool/correlate_sweep.hpp"

namespace ugv::tool {
using adapters::parseSnapshotLine;
namespace {

using correlator::GospaResult;
using correlator::OoiClass;
using correlator::Snapshot;
using Eigen::Vector2d;
using nlohmann::json;
using nlohmann::ordered_json;

constexpr const char* kCorrelateEvalCommand = "correlate-eval";
constexpr const correlator::GospaParams& kGospa = kScoreGospa;
constexpr int kAlpha = kScoreAlpha;

// ---- truth ---------------------------------------------------------------------------------------------------

/// The number `key` within [min, max] (a truth file of correlate-sim is within them).
Result<double, Error> number(const json& j, const char* key, double min, double max)
{
    const auto it = j.find(key);
    if (it == j.end() || !it->is_number() || !std::isfinite(it->get<double>())) {
        return Unexpected(Error{"", std::string("missing or non-numeric field '") + key + "'", ""});
    }
    const double v = it->get<double>();
    if (v < min || v > max) {
        std::ostringstream what;
        what << "field '" << key << "' value " << v << " is outside [" << min << ", " << max << "]";
        return Unexpected(Error{"", what.str(), "give the truth file correlate-sim wrote"});
    }
    return v;
}

constexpr double kMaxTruthTimeS = adapters::kMaxMessageTimeS;

Result<std::string, Error> text(const json& j, const char* key)
{
    const auto it = j.find(key);
    if (it == j.end() || !it->is_string()) {
        return Unexpected(Error{"", std::string("missing or non-string field '") + key + "'", ""});
    }
    return it->get<std::string>();
}

Result<void, Error> parseHeader(const json& j, Truth& truth)
{
    const auto lat = number(j, "origin_lat", -90.0, 90.0);
    const auto lon = number(j, "origin_lon", -180.0, 180.0);
    const auto duration = number(j, "duration_s", 0.0, kMaxTruthTimeS);
    const auto period = number(j, "period_s", 0.01, 3600.0);
    for (const auto* field : {&lat, &lon, &duration, &period}) {
        if (!*field) {
            return Unexpected(field->error());
        }
    }
    truth.originLat = *lat;
    truth.originLon = *lon;
    truth.durationS = *duration;
    truth.periodS = *period;
    return {};
}

Result<void, Error> parseStatic(const json& j, const correlator::LocalFrame& frame, Truth& truth)
{
    const auto id = text(j, "id");
    const auto lat = number(j, "lat", -90.0, 90.0);
    const auto lon = number(j, "lon", -180.0, 180.0);
    if (!id) {
        return Unexpected(id.error());
    }
    for (const auto* field : {&lat, &lon}) {
        if (!*field) {
            return Unexpected(field->error());
        }
    }
    truth.staticIds.push_back(*id);
    truth.statics.push_back(frame.toLocal(*lat, *lon));
    return {};
}

Result<void, Error> parseMoving(const json& j, const correlator::LocalFrame& frame, Truth& truth)
{
    const auto id = text(j, "id");
    const auto cls = text(j, "class");
    const auto t = number(j, "t", -kMaxTruthTimeS, kMaxTruthTimeS);
    const auto lat = number(j, "lat", -90.0, 90.0);
    const auto lon = number(j, "lon", -180.0, 180.0);
    for (const auto* field : {&id, &cls}) {
        if (!*field) {
            return Unexpected(field->error());
        }
    }
    for (const auto* field : {&t, &lat, &lon}) {
        if (!*field) {
            return Unexpected(field->error());
        }
    }
    if (*cls != "mobile" && *cls != "noncombatant") {
        return Unexpected(Error{"", "class '" + *cls + "' of a moving object", "use mobile or noncombatant"});
    }
    MovingTrack& track = truth.moving[*id];
    track.cls = *cls == "mobile" ? OoiClass::Mobile : OoiClass::NonCombatant;
    track.samples.push_back({*t, frame.toLocal(*lat, *lon)});
    return {};
}

/// One truth line; the header (kind "scenario") must come first because it holds the plane's origin.
Result<void, Error> parseTruthLine(const std::string& line, Truth& truth, std::optional<correlator::LocalFrame>& frame)
{
    if (line.size() > adapters::kMaxMessageLineBytes) {
        return Unexpected(Error{"", "line over " + std::to_string(adapters::kMaxMessageLineBytes) + " bytes",
                                "give the truth file correlate-sim wrote"});
    }
    const json j = json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.is_object()) {
        return Unexpected(Error{"", "not a JSON object", ""});
    }
    const auto kind = text(j, "kind");
    if (!kind) {
        return Unexpected(kind.error());
    }
    if (*kind == "scenario") {
        if (frame) {
            return Unexpected(Error{"", "a second scenario line", "give one truth file of correlate-sim"});
        }
        if (auto header = parseHeader(j, truth); !header) {
            return header;
        }
        frame.emplace(truth.originLat, truth.originLon);
        return {};
    }
    if (!frame) {
        return Unexpected(Error{"", "the first line is not the scenario line", "give a truth file of correlate-sim"});
    }
    if (*kind == "static") {
        return parseStatic(j, *frame, truth);
    }
    if (*kind == "moving") {
        return parseMoving(j, *frame, truth);
    }
    if (*kind == "ugv") {
        return {}; // the UGVs' pose errors: not scored
    }
    return Unexpected(Error{"", "unknown kind '" + *kind + "'", "use scenario, ugv, static or moving"});
}

Result<Truth, Error> readTruth(const std::string& path)
{
    std::ifstream in(path);
    if (!in) {
        return Unexpected(Error{path, "cannot open the truth file", "give the file correlate-sim wrote (--truth)"});
    }
    Truth truth;
    std::optional<correlator::LocalFrame> frame;
    std::string line;
    for (std::size_t number = 1; adapters::readBoundedLine(in, line, adapters::kMaxMessageLineBytes); ++number) {
        if (line.empty()) {
            continue;
        }
        if (auto parsed = parseTruthLine(line, truth, frame); !parsed) {
            Error error = parsed.error();
            error.where = path + ":" + std::to_string(number);
            return Unexpected(error);
        }
    }
    if (!frame) {
        return Unexpected(Error{path, "no scenario line", "give the truth file correlate-sim wrote"});
    }
    for (auto& [id, track] : truth.moving) {
        std::sort(track.samples.begin(), track.samples.end(),
                  [](const TimedPosition& a, const TimedPosition& b) { return a.t < b.t; });
    }
    return truth;
}

Result<std::vector<Snapshot>, Error> readSnapshots(const std::string& path)
{
    std::ifstream in(path);
    if (!in) {
        return Unexpected(Error{path, "cannot open the snapshot file", "give the --output of 'ugvsense correlate'"});
    }
    std::vector<Snapshot> snapshots;
    std::string line;
    for (std::size_t number = 1; adapters::readBoundedLine(in, line, adapters::kMaxSnapshotLineBytes); ++number) {
        if (line.empty()) {
            continue;
        }
        auto snapshot = parseSnapshotLine(line);
        const std::string where = path + ":" + std::to_string(number);
        if (!snapshot) {
            return Unexpected(Error{where, snapshot.error().message(), ""});
        }
        if (!snapshots.empty() && snapshot->t < snapshots.back().t) {
            return Unexpected(
                Error{where, "snapshot at t = " + std::to_string(snapshot->t) + " s is older than the one before",
                      "give the snapshots in time order"});
        }
        snapshots.push_back(std::move(snapshot).value());
    }
    if (snapshots.empty()) {
        return Unexpected(Error{path, "no snapshots", "run 'ugvsense correlate' on the scenario first"});
    }
    return snapshots;
}

// ---- output --------------------------------------------------------------------------------------------------

std::size_t movingCount(const Truth& truth, OoiClass cls)
{
    return static_cast<std::size_t>(std::count_if(truth.moving.begin(), truth.moving.end(),
                                                  [cls](const auto& entry) { return entry.second.cls == cls; }));
}

void printRow(const char* name, double total, double localisation, double missed, double falsePart)
{
    std::cout << std::left << std::setw(30) << name << std::right << std::fixed << std::setprecision(3) << std::setw(10)
              << total << std::setw(14) << localisation << std::setw(12) << missed << std::setw(12) << falsePart;
}

void printTable(const Figures& f, const Truth& truth)
{
    std::cout << "snapshots: " << f.snapshots << " (t " << std::fixed << std::setprecision(1) << f.firstT << " .. "
              << f.lastT << " s); truth: " << truth.statics.size() << " static, "
              << movingCount(truth, OoiClass::Mobile) << " mobile, " << movingCount(truth, OoiClass::NonCombatant)
              << " non-combatant objects\n";
    std::cout << std::defaultfloat << "GOSPA c = " << kGospa.cutoffM << " m, p = " << kGospa.order
              << ", alpha = " << kAlpha << " (parts in m^2: localisation + missed + false = GOSPA^2)\n";
    std::cout << std::left << std::setw(30) << "" << std::right << std::setw(10) << "GOSPA [m]" << std::setw(14)
              << "localisation" << std::setw(12) << "missed" << std::setw(12) << "false"
              << "   counts\n";
    const GospaResult& s = f.staticLast;
    char staticName[64];
    (void)std::snprintf(staticName, sizeof(staticName), "static at t = %.1f s", f.lastT);
    printRow(staticName, s.total, s.localisationPart, s.missedPart, s.falsePart);
    std::cout << "   " << s.assigned << " assigned, " << s.missed << " missed, " << s.falseCount << " false (of "
              << f.staticEstimates << ")\n";
    for (const auto& [name, m] :
         {std::pair{"mobile, mean", &f.mobile}, std::pair{"non-combatant, mean", &f.nonCombatant}}) {
        printRow(name, m->mean(m->total), m->mean(m->localisationPart), m->mean(m->missedPart), m->mean(m->falsePart));
        std::cout << "   over " << m->snapshots << " snapshots\n";
    }
    std::cout << "static ID changes: " << f.staticIdChanges << '\n';
}

ordered_json meanJson(const GospaMean& m)
{
    return ordered_json{{"snapshots", m.snapshots},
                        {"mean_gospa_m", m.mean(m.total)},
                        {"mean_localisation_m2", m.mean(m.localisationPart)},
                        {"mean_missed_m2", m.mean(m.missedPart)},
                        {"mean_false_m2", m.mean(m.falsePart)}};
}

ordered_json figuresJson(const Figures& f, const Truth& truth)
{
    const GospaResult& s = f.staticLast;
    return ordered_json{{"snapshots", f.snapshots},
                        {"first_t", f.firstT},
                        {"last_t", f.lastT},
                        {"cutoff_m", kGospa.cutoffM},
                        {"order", kGospa.order},
                        {"alpha", kAlpha},
                        {"static",
                         {{"t", f.lastT},
                          {"truth", truth.statics.size()},
                          {"estimates", f.staticEstimates},
                          {"gospa_m", s.total},
                          {"localisation_m2", s.localisationPart},
                          {"missed_m2", s.missedPart},
                          {"false_m2", s.falsePart},
                          {"assigned", s.assigned},
                          {"missed", s.missed},
                          {"false", s.falseCount}}},
                        {"mobile", meanJson(f.mobile)},
                        {"noncombatant", meanJson(f.nonCombatant)},
                        {"static_id_changes", f.staticIdChanges}};
}

Result<void, Error> writeJson(const std::string& path, const ordered_json& figures)
{
    std::ofstream out(path);
    out << figures.dump(2) << '\n';
    out.flush();
    if (!out) {
        return Unexpected(Error{path, "cannot write the file", "check that the folder exists and is writable"});
    }
    return {};
}

/// --sweep: the options of the grid run (correlate_sweep.hpp).
int runSweep(const Args& args)
{
    constexpr double kMaxSeeds = 1000.0;
    SweepOptions options;
    options.quick = args.has("quick");
    const auto seeds = args.number("seeds", options.seeds, 1, kMaxSeeds);
    const auto firstSeed = args.number("first-seed", static_cast<double>(options.firstSeed), 0, kMaxScenarioSeed);
    const auto duration = args.number("duration", options.quick ? 600.0 : options.durationS, 1, kMaxScenarioDurationS);
    for (const auto* number : {&seeds, &firstSeed, &duration}) {
        if (!*number) {
            return reportUsageError(kCorrelateEvalCommand, number->error());
        }
    }
    options.seeds = static_cast<int>(*seeds);
    options.firstSeed = static_cast<std::uint64_t>(*firstSeed);
    options.durationS = *duration;
    options.only = args.get("only");
    options.jsonPath = args.get("json");
    options.requireTargets = args.has("require-targets");
    return runCorrelateSweep(options);
}

} // namespace

int runCorrelateEval(int argc, char** argv)
{
    Args args(kCorrelateEvalCommand,
              "--snapshots SNAPSHOTS.jsonl --truth TRUTH.jsonl [--json OUT]\n"
              "       ugvsense correlate-eval --sweep [--quick] [--seeds N] [--first-seed N] [--duration S] "
              "[--only TEXT] [--json OUT] [--require-targets]\n"
              "  Scores correlator snapshots (the output of 'ugvsense correlate') against the truth of\n"
              "  'ugvsense correlate-sim' with GOSPA (c = 5 m, p = 2, alpha = 2; parts in m^2):\n"
              "  static objects at the last snapshot; mobile objects and non-combatants: the mean over the\n"
              "  snapshots, against the truth sample nearest in time (within half its period); static ID changes:\n"
              "  per true static object, changes of the id assigned to it between consecutive snapshots in which\n"
              "  it is assigned.\n"
              "  --sweep runs both modes over a grid of simulated worlds (two centres, the correlate-sim defaults\n"
              "  and issue 21's harsh bias scenario, each knob moved alone around them, plus the drift scenario),\n"
              "  10 seeds per point, and prints per point the median and the worst seed of each mode and the\n"
              "  issue 21 targets; --json writes the summary.",
              {{"snapshots", "SNAPSHOTS.jsonl", "snapshot lines of 'ugvsense correlate'", false},
               {"truth", "TRUTH.jsonl", "truth file of 'ugvsense correlate-sim'", false},
               {"json", "OUT", "also write the figures (with --sweep: the summary) as JSON to OUT", false},
               {"sweep", "", "run both modes over the grid of simulated worlds", false},
               {"quick", "", "with --sweep: four points (the centres and the issue's scenarios), 600 s", false},
               {"seeds", "N", "with --sweep: seeds per point, default 10", false},
               {"first-seed", "N", "with --sweep: the first seed, default 1", false},
               {"duration", "S", "with --sweep: scenario length, default 1800 (--quick: 600)", false},
               {"only", "TEXT", "with --sweep: only the points whose name contains TEXT", false},
               {"require-targets", "", "with --sweep: exit 3 when a point misses a target", false}});
    if (const auto exit = parseOrExit(args, argc, argv, kCorrelateEvalCommand)) {
        return *exit;
    }
    if (args.has("sweep")) {
        return runSweep(args);
    }
    for (const auto& [name, value] : {std::pair{"snapshots", "SNAPSHOTS.jsonl"}, std::pair{"truth", "TRUTH.jsonl"}}) {
        if (!args.has(name)) {
            return reportUsageError(kCorrelateEvalCommand,
                                    Error{"ugvsense " + std::string(kCorrelateEvalCommand),
                                          std::string("missing required option '--") + name + " " + value + "'",
                                          "see 'ugvsense " + std::string(kCorrelateEvalCommand) + " --help'"});
        }
    }
    const auto truth = readTruth(args.get("truth"));
    if (!truth) {
        return reportError(kCorrelateEvalCommand, truth.error());
    }
    const auto snapshots = readSnapshots(args.get("snapshots"));
    if (!snapshots) {
        return reportError(kCorrelateEvalCommand, snapshots.error());
    }
    const Figures figures = score(*snapshots, *truth);
    printTable(figures, *truth);
    if (args.has("json")) {
        if (auto written = writeJson(args.get("json"), figuresJson(figures, *truth)); !written) {
            return reportError(kCorrelateEvalCommand, written.error());
        }
    }
    return 0;
}

} // namespace ugv::tool
