// ugvsense bus-send: a sender for the DDS bus (tests, demos, a replay of a mission's inputs), in two modes.
//   --input OBS.jsonl  replays the correlator's JSON lines (as `ugvsense correlate-sim` writes them) on their
//                      topics; sequence_number = the line number, so a restarted sender's repeats are duplicates.
//   --poses VEHICLE    publishes VehiclePose samples of a vehicle driving a 10 m circle.
// (Malformed samples and floods: the test tool test/tools/bus_hostile.cpp, not installed.)
// It waits for readers first (--wait-readers) and, for the reliable topics, for their acknowledgements at the end;
// --linger keeps the writers (and their transient-local history) alive for late or restarted readers.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <variant>
#include <vector>

#include "ugv/adapters/correlate_io.hpp"
#include "ugv/adapters/correlator_dds.hpp"
#include "ugv/correlator/geodesy.hpp"
#include "ugv/ipc/dds_bus.hpp"
#include "ugv/ipc/dds_convert.hpp"
#include "ugv/platform/angles.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/bus_options.hpp"
#include "ugv/tool/bus_writers.hpp"
#include "ugv/tool/commands.hpp"

namespace ugv::tool {
namespace {

namespace dds = ipc::dds;
namespace msg = ipc::dds::msg;
using Clock = bus::Clock;
using bus::InputWriters;
using bus::kRefusedWriteTimeout;
using bus::sleepUntil;
using bus::writeOne;

constexpr const char* kBusSendCommand = "bus-send";
constexpr double kMaxRateHz = 1e6;
constexpr double kMaxLingerS = 1e7;
constexpr double kMaxReaders = 1000;
// --poses: the vehicle drives a circle of kCircleRadiusM around a fixed point (Adelaide, the MAGIC 2010 site).
constexpr double kCircleCentreLat = bus::kSiteLat;
constexpr double kCircleCentreLon = bus::kSiteLon;
constexpr double kCircleAltitudeM = 50.0;
constexpr double kCircleRadiusM = 10.0;
constexpr double kCircleSpeedMps = 2.0;
constexpr double kPoseSigmaM = 0.2;   ///< position standard deviation of the covariance [m]
constexpr double kPoseSigmaDeg = 1.0; ///< heading standard deviation [deg]
constexpr double kDefaultPoseRateHz = 10.0;
constexpr double kDefaultPoseDurationS = 10.0;

/// A line of the input file and its message.
struct Line {
    std::uint64_t number = 0;
    correlator::Message message;
};

Result<std::vector<Line>, Error> readInput(const std::string& path, std::size_t& bad)
{
    std::ifstream in(path);
    if (!in) {
        return Unexpected(Error{path, "cannot open the input file", "check the path (correlate-sim --out writes one)"});
    }
    std::vector<Line> lines;
    std::string text;
    std::uint64_t number = 0;
    while (adapters::readBoundedLine(in, text, adapters::kMaxMessageLineBytes)) {
        ++number;
        if (text.find_first_not_of(" \t\r") == std::string::npos) {
            continue;
        }
        auto parsed = adapters::parseMessageLine(text);
        if (!parsed) {
            if (++bad <= kMaxReportedLines) {
                std::cerr << path << ':' << number << ": skipped: " << parsed.error().message() << '\n';
            }
            continue;
        }
        lines.push_back(Line{number, std::move(*parsed)});
    }
    if (in.bad()) {
        return Unexpected(Error{path, "cannot read the input file", "check the file and the disk"});
    }
    return lines;
}

/// --only-ugv: keeps the observations of `ugv` alone; an error naming the file's UGVs when it has none of them.
std::optional<Error> keepOnlyUgv(std::vector<Line>& lines, const std::string& path, const std::string& ugv)
{
    std::set<std::string> ugvs;
    std::erase_if(lines, [&](const Line& l) {
        const auto* o = std::get_if<correlator::Observation>(&l.message);
        if (o != nullptr) {
            ugvs.insert(o->ugv);
        }
        return o == nullptr || o->ugv != ugv;
    });
    if (!lines.empty()) {
        return std::nullopt;
    }
    std::string names;
    for (const std::string& u : ugvs) {
        names += (names.empty() ? "" : ", ") + u;
    }
    return Error{path, "no observation of ugv '" + ugv + "'",
                 ugvs.empty() ? std::string("the file has no observations") : "give one of the file's UGVs: " + names};
}

/// --input: every line on its topic, paced by --rate.
int sendInput(dds::Bus& bus, const Args& args, double rateHz, const bus::ReaderWait& wait, double lingerS)
{
    const std::string path = args.get("input");
    const std::string source = args.get("source", "bus-send");
    const std::string onlyUgv = args.get("only-ugv");
    std::size_t bad = 0;
    auto lines = readInput(path, bad);
    if (!lines) {
        return reportError(kBusSendCommand, lines.error());
    }
    if (!onlyUgv.empty()) {
        if (auto none = keepOnlyUgv(*lines, path, onlyUgv)) {
            return reportError(kBusSendCommand, *none);
        }
    }
    if (lines->empty()) {
        return reportError(kBusSendCommand, Error{path, "no message to send",
                                                  "give a file of correlator JSON lines (ugvsense correlate-sim)"});
    }
    auto writers = InputWriters::create(bus);
    if (!writers) {
        return reportError(kBusSendCommand, writers.error());
    }
    InputWriters& w = *writers;
    std::array<bool, 4> used{}; // the topics the input has lines for, in the writers' order (the variant's)
    for (const Line& line : *lines) {
        used[line.message.index()] = true;
    }
    w.waitForReaders(used, wait, bus.config(), kBusSendCommand);
    std::printf("sending %zu message(s) to %d reader(s)\n", lines->size(), w.observations.matched());
    (void)std::fflush(stdout);
    const auto start = Clock::now();
    msg::OoiObservation observation;
    msg::UavObservation uav;
    msg::ConfirmationState confirmation;
    msg::PoseCorrection correction;
    std::size_t i = 0;
    for (const Line& line : *lines) {
        if (rateHz > 0.0 && !sleepUntil(start + std::chrono::duration_cast<Clock::duration>(
                                                    std::chrono::duration<double>(static_cast<double>(i) / rateHz)))) {
            break;
        }
        ++i;
        bool written = false;
        std::size_t topic = line.message.index();
        if (const auto* o = std::get_if<correlator::Observation>(&line.message)) {
            adapters::toDds(*o, line.number, observation);
            written = writeOne(w.observations, observation);
        } else if (const auto* u = std::get_if<correlator::UavFix>(&line.message)) {
            adapters::toDds(*u, source, line.number, uav);
            written = writeOne(w.uav, uav);
        } else if (const auto* c = std::get_if<correlator::Confirm>(&line.message)) {
            adapters::toDds(*c, source, line.number, confirmation);
            written = writeOne(w.confirmations, confirmation);
        } else if (const auto* p = std::get_if<correlator::PoseCorrection>(&line.message)) {
            adapters::toDds(*p, source, line.number, correction);
            written = writeOne(w.corrections, correction);
        }
        if (!written) {
            if (gStop.load()) {
                break;
            }
            return reportError(kBusSendCommand,
                               Error{path + ":" + std::to_string(line.number),
                                     "the bus refused the message for " + std::to_string(kRefusedWriteTimeout.count()) +
                                         " s (a reader does not acknowledge and the writer's history is full)",
                                     "check the readers, or pace the sender with --rate"});
        }
        ++w.sent[topic];
    }
    if (gStop.load()) {
        std::printf("interrupted: sent %llu of %zu message(s)\n", static_cast<unsigned long long>(w.total()),
                    lines->size());
        return 1;
    }
    if (bad > 0) {
        std::cerr << path << ": " << bad << " bad line(s) skipped\n";
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    char what[512];
    (void)std::snprintf(what, sizeof(what), "from %s%s in %.2f s", path.c_str(),
                        onlyUgv.empty() ? "" : (" (only ugv " + onlyUgv + ")").c_str(), seconds);
    return bus::finish(w, kBusSendCommand, what, lingerS, bus.config());
}

/// --poses: a vehicle on a 10 m circle, heading along it, at --rate for --duration.
int sendPoses(dds::Bus& bus, const std::string& vehicle, double rateHz, double durationS, const bus::ReaderWait& wait,
              double lingerS)
{
    auto writer = bus.writer<msg::VehiclePose>();
    if (!writer) {
        return reportError(kBusSendCommand, writer.error());
    }
    bus::waitForReaders(*writer, wait, dds::topicName(dds::TopicId::Pose, bus.config()), kBusSendCommand);
    const correlator::LocalFrame frame(kCircleCentreLat, kCircleCentreLon);
    const auto count = static_cast<std::uint64_t>(std::floor(durationS * rateHz)) + 1;
    const double omega = kCircleSpeedMps / kCircleRadiusM; // [rad/s], counter-clockwise seen from above
    msg::VehiclePose pose;
    pose.vehicle(vehicle);
    pose.covariance({kPoseSigmaM * kPoseSigmaM, 0.0, 0.0, 0.0, kPoseSigmaM * kPoseSigmaM, 0.0, 0.0, 0.0,
                     kPoseSigmaDeg * kPoseSigmaDeg});
    const auto start = Clock::now();
    std::uint64_t sent = 0;
    std::uint64_t refused = 0;
    for (std::uint64_t i = 0; i < count; ++i) {
        const double ts = static_cast<double>(i) / rateHz;
        if (!sleepUntil(start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(ts)))) {
            break;
        }
        const double angle = omega * ts;
        const double east = kCircleRadiusM * std::cos(angle);
        const double north = kCircleRadiusM * std::sin(angle);
        double lat = 0.0;
        double lon = 0.0;
        frame.toLatLon({east, north}, lat, lon);
        // Velocity (-sin, cos) in (east, north): compass heading atan2(east, north) = -angle.
        const double heading = std::fmod(std::fmod(-angle * kRadToDeg, 360.0) + 360.0, 360.0);
        pose.stamp_ns(dds::realtimeNowNs());
        pose.latitude_deg(lat);
        pose.longitude_deg(lon);
        pose.altitude_m(kCircleAltitudeM);
        pose.east_m(east);
        pose.north_m(north);
        pose.up_m(0.0);
        pose.heading_deg(heading);
        if (writer->write(pose)) {
            ++sent;
        } else {
            ++refused;
        }
    }
    std::printf("sent %llu pose(s) of '%s' (%g m circle around %.6f, %.6f at %g m/s) at %g Hz on %s to %d "
                "reader(s)%s\n",
                static_cast<unsigned long long>(sent), vehicle.c_str(), kCircleRadiusM, kCircleCentreLat,
                kCircleCentreLon, kCircleSpeedMps, rateHz, bus::describe(bus.config()).c_str(), writer->matched(),
                gStop.load() ? " (stopped by a signal)" : "");
    if (refused > 0) {
        std::printf("%llu pose(s) refused by the writer\n", static_cast<unsigned long long>(refused));
    }
    (void)std::fflush(stdout);
    if (lingerS > 0.0 && !gStop.load()) {
        sleepUntil(Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(lingerS)));
    }
    return refused > 0 ? 1 : 0;
}

/// One mode (--input or --poses), options only where they apply, and names the bus can carry.
std::optional<Error> checkModeAndNames(const Args& args)
{
    const std::string where = std::string("ugvsense ") + kBusSendCommand;
    const int modes = (args.has("input") ? 1 : 0) + (args.has("poses") ? 1 : 0);
    if (modes != 1) {
        return Error{where, modes == 0 ? "nothing to send" : "both --input and --poses",
                     "give exactly one of --input OBS.jsonl, --poses VEHICLE"};
    }
    const auto only = [&](const char* option, const char* mode, bool inMode) -> std::optional<Error> {
        if (args.has(option) && !inMode) {
            return Error{where + " --" + option, std::string("only applies to ") + mode,
                         std::string("remove it or add ") + mode};
        }
        return std::nullopt;
    };
    for (const auto& e :
         {only("only-ugv", "--input", args.has("input")), only("duration", "--poses", args.has("poses"))}) {
        if (e) {
            return e;
        }
    }
    if (args.has("poses") && args.get("poses").empty()) {
        return Error{where + " --poses", "an empty vehicle name", "name the vehicle"};
    }
    if ((args.has("source") && args.get("source").empty()) || (args.has("only-ugv") && args.get("only-ugv").empty())) {
        return Error{where, "an empty --source or --only-ugv name", "give a name"};
    }
    if (args.get("source", "").size() > dds::kMaxNameLength || args.get("only-ugv", "").size() > dds::kMaxNameLength) {
        return Error{where,
                     "a --source or --only-ugv name longer than " + std::to_string(dds::kMaxNameLength) + " characters",
                     "shorten it (the bus's name bound)"};
    }
    return std::nullopt;
}

} // namespace

int runBusSend(int argc, char** argv)
{
    std::vector<OptionSpec> specs{
        {"input", "OBS.jsonl", "mode 1: publish the correlator's JSON lines (correlate-sim --out) on their topics",
         false},
        {"poses", "VEHICLE", "mode 2: VehiclePose samples of VEHICLE driving a 10 m circle", false},
        {"source", "NAME", "sender of UAV fixes, confirmations, corrections, default bus-send", false},
        {"only-ugv", "NAME", "--input: send only the observations of this UGV (nothing else)", false},
        {"rate", "HZ", "--input: messages per second, default as fast as the writers accept; --poses: default 10",
         false},
        {"duration", "S", "--poses: how long, default 10", false},
        {"wait-readers", "N",
         "wait for N readers of each topic the input uses (--poses: the pose topic) before sending, default 1", false},
        {"wait-timeout", "S", "wait at most S seconds for them (then send anyway, with a warning), default 20", false},
        {"linger", "S", "stay S more seconds after the acknowledgements (late readers get the history)", false}};
    for (auto& spec : bus::options()) {
        specs.push_back(std::move(spec));
    }
    Args args(kBusSendCommand,
              "(--input OBS.jsonl [--source NAME] [--only-ugv NAME] [--rate HZ] | --poses VEHICLE [--rate HZ] "
              "[--duration S]) [--wait-readers N] [--wait-timeout S] [--linger S] [--domain N] "
              "[--partition P] [--ros-namespace NS] [--discovery-server LIST]\n"
              "  A test sender for the DDS bus. --input publishes each line of a correlator input file on its topic\n"
              "  (observations, uav, confirmations, pose_corrections) with sequence_number = its line number, so a\n"
              "  restarted sender's repeats are duplicates. --poses publishes poses (stamp = CLOCK_REALTIME) of a\n"
              "  vehicle on a 10 m circle. --input ends when every matched reader acknowledged everything (60 s at\n"
              "  most, else exit 1).",
              specs);
    if (const auto exit = parseOrExit(args, argc, argv, kBusSendCommand)) {
        return *exit;
    }
    if (auto bad = checkModeAndNames(args)) {
        return reportUsageError(kBusSendCommand, *bad);
    }
    const auto rate = args.number("rate", args.has("poses") ? kDefaultPoseRateHz : 0.0, 0.001, kMaxRateHz);
    const auto duration = args.number("duration", kDefaultPoseDurationS, 0.0, 1e7);
    const auto linger = args.number("linger", 0.0, 0.0, kMaxLingerS);
    const auto readers = args.wholeNumber("wait-readers", 1, 0, kMaxReaders);
    const auto waitTimeout = args.number("wait-timeout", bus::kDefaultWaitReadersS, 0.0, kMaxLingerS);
    for (const auto* n : {&rate, &duration, &linger, &readers, &waitTimeout}) {
        if (!*n) {
            return reportUsageError(kBusSendCommand, n->error());
        }
    }
    auto config = bus::configFrom(args, kBusSendCommand, "ugvsense/bus-send");
    if (!config) {
        return reportUsageError(kBusSendCommand, config.error());
    }
    installStopHandler();
    auto created = dds::Bus::create(*config);
    if (!created) {
        return reportError(kBusSendCommand, created.error());
    }
    dds::Bus& b = **created;
    const bus::ReaderWait wait{static_cast<int>(*readers), *waitTimeout, &b};
    if (args.has("input")) {
        return sendInput(b, args, args.has("rate") ? *rate : 0.0, wait, *linger);
    }
    return sendPoses(b, args.get("poses"), *rate, *duration, wait, *linger);
}

} // namespace ugv::tool
