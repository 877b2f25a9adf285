// ugvsense bus-send: a test sender for the DDS bus, in three modes.
//   --input OBS.jsonl  replays the correlator's JSON lines (as `ugvsense correlate-sim` writes them) on their
//                      topics; sequence_number = the line number, so a restarted sender's repeats are duplicates.
//   --hostile          sends malformed samples on the correlator's input topics, then a flood of valid
//                      observations from this one participant (issue 6: rejected and counted, service keeps up).
//   --poses VEHICLE    publishes VehiclePose samples of a vehicle driving a 10 m circle.
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

#include "args.hpp"
#include "bus_options.hpp"
#include "commands.hpp"
#include "ugv/bringup/correlate_io.hpp"
#include "ugv/bringup/correlator_dds.hpp"
#include "ugv/correlator/geodesy.hpp"
#include "ugv/ipc/dds_bus.hpp"
#include "ugv/ipc/dds_convert.hpp"
#include "ugv/platform/angles.hpp"

namespace ugv::tool {
namespace {

namespace dds = ipc::dds;
namespace msg = ipc::dds::msg;
using Clock = std::chrono::steady_clock;

constexpr const char* kCommand = "bus-send";
constexpr auto kWaitReadersTimeout = std::chrono::seconds(20);
constexpr auto kAckTimeout = std::chrono::seconds(60);
constexpr auto kRefusedWriteTimeout = std::chrono::seconds(30); ///< a writer refusing every sample this long: fail
constexpr auto kSlice = std::chrono::milliseconds(100);
constexpr int kMaxReportedLines = 50;
constexpr double kMaxRateHz = 1e6;
constexpr double kMaxLingerS = 1e7;
constexpr double kMaxFlood = 1e7;
constexpr double kMaxReaders = 1000;
// --poses: the vehicle drives a circle of kCircleRadiusM around a fixed point (Adelaide, the MAGIC 2010 site).
constexpr double kCircleCentreLat = -34.9285;
constexpr double kCircleCentreLon = 138.6007;
constexpr double kCircleAltitudeM = 50.0;
constexpr double kCircleRadiusM = 10.0;
constexpr double kCircleSpeedMps = 2.0;
constexpr double kPoseSigmaM = 0.2;   ///< position standard deviation of the covariance [m]
constexpr double kPoseSigmaDeg = 1.0; ///< heading standard deviation [deg]
constexpr double kDefaultPoseRateHz = 10.0;
constexpr double kDefaultPoseDurationS = 10.0;

int fail(const Error& error)
{
    std::cerr << "ugvsense " << kCommand << ": error: " << error.message() << '\n';
    return 1;
}

/// Sleeps until `until` in short slices; false when a signal stopped it first.
bool sleepUntil(Clock::time_point until)
{
    while (!bus::g_stop.load()) {
        const auto now = Clock::now();
        if (now >= until) {
            return true;
        }
        std::this_thread::sleep_for(std::min<Clock::duration>(kSlice, until - now));
    }
    return false;
}

/// Waits up to kWaitReadersTimeout for `wanted` matched readers of `writer`.
template <class T>
void waitForReaders(const dds::Writer<T>& writer, int wanted, const std::string& topic)
{
    if (wanted <= 0) {
        return;
    }
    const auto until = Clock::now() + kWaitReadersTimeout;
    while (writer.matched() < wanted && Clock::now() < until && !bus::g_stop.load()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (writer.matched() < wanted && !bus::g_stop.load()) {
        std::cerr << "ugvsense " << kCommand << ": warning: " << writer.matched() << " of " << wanted
                  << " reader(s) of " << topic << " after " << kWaitReadersTimeout.count()
                  << " s; sending anyway (late reliable readers get the history while this process lives)\n";
    }
}

/// Writes one sample, retrying while Fast DDS refuses it (a full keep-all history: a reader is slow to
/// acknowledge). False after kRefusedWriteTimeout or a signal.
template <class T>
bool writeOne(dds::Writer<T>& writer, const T& sample)
{
    const auto until = Clock::now() + kRefusedWriteTimeout;
    while (!writer.write(sample)) {
        if (bus::g_stop.load() || Clock::now() >= until) {
            return false;
        }
    }
    return true;
}

/// The four writers of the correlator's inputs.
struct InputWriters {
    dds::Writer<msg::OoiObservation> observations;
    dds::Writer<msg::UavObservation> uav;
    dds::Writer<msg::ConfirmationState> confirmations;
    dds::Writer<msg::PoseCorrection> corrections;
    std::array<std::uint64_t, 4> sent{}; ///< per topic, in this order

    static Result<InputWriters, Error> create(dds::Bus& bus)
    {
        InputWriters w;
        auto o = bus.writer<msg::OoiObservation>();
        auto u = bus.writer<msg::UavObservation>();
        auto c = bus.writer<msg::ConfirmationState>();
        auto p = bus.writer<msg::PoseCorrection>();
        for (const Error* e :
             {o ? nullptr : &o.error(), u ? nullptr : &u.error(), c ? nullptr : &c.error(), p ? nullptr : &p.error()}) {
            if (e != nullptr) {
                return Unexpected(*e);
            }
        }
        w.observations = *o;
        w.uav = *u;
        w.confirmations = *c;
        w.corrections = *p;
        return w;
    }

    [[nodiscard]] std::uint64_t total() const { return sent[0] + sent[1] + sent[2] + sent[3]; }
    /// The most readers any used writer has.
    [[nodiscard]] int readers() const
    {
        int r = 0;
        r = std::max(r, sent[0] > 0 ? observations.matched() : 0);
        r = std::max(r, sent[1] > 0 ? uav.matched() : 0);
        r = std::max(r, sent[2] > 0 ? confirmations.matched() : 0);
        r = std::max(r, sent[3] > 0 ? corrections.matched() : 0);
        return r;
    }
    /// Every used writer's samples acknowledged by all its matched reliable readers, within kAckTimeout in all.
    bool waitForAcks()
    {
        const auto until = Clock::now() + kAckTimeout;
        const auto left = [&] {
            return std::max(std::chrono::milliseconds(0),
                            std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()));
        };
        bool ok = true;
        ok = (sent[0] == 0 || observations.waitForAcks(left())) && ok;
        ok = (sent[1] == 0 || uav.waitForAcks(left())) && ok;
        ok = (sent[2] == 0 || confirmations.waitForAcks(left())) && ok;
        ok = (sent[3] == 0 || corrections.waitForAcks(left())) && ok;
        return ok;
    }
};

/// The end of the reliable modes: acknowledgements, the summary line, --linger.
int finish(InputWriters& w, const std::string& what, double lingerS, const dds::BusConfig& config)
{
    const int matched = w.readers(); // before the wait: a reader that got everything may leave meanwhile
    const bool acked = w.waitForAcks();
    const int readers = std::max(matched, w.readers());
    std::printf("sent %llu message(s) (%llu observation(s), %llu UAV fix(es), %llu confirmation(s), %llu pose "
                "correction(s)) %s on %s, %s by %d reader(s)\n",
                static_cast<unsigned long long>(w.total()), static_cast<unsigned long long>(w.sent[0]),
                static_cast<unsigned long long>(w.sent[1]), static_cast<unsigned long long>(w.sent[2]),
                static_cast<unsigned long long>(w.sent[3]), what.c_str(), bus::describe(config).c_str(),
                acked ? "acknowledged" : "NOT all acknowledged", readers);
    std::fflush(stdout);
    if (!acked) {
        return fail(
            Error{"ugvsense " + std::string(kCommand),
                  "the readers did not acknowledge every message within " + std::to_string(kAckTimeout.count()) + " s",
                  "check the network between the hosts (loss, firewall) and that the readers keep up"});
    }
    if (lingerS > 0.0) {
        std::printf("lingering %g s (Ctrl-C to end)\n", lingerS);
        std::fflush(stdout);
        sleepUntil(Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(lingerS)));
    }
    return 0;
}

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
    while (bringup::readBoundedLine(in, text, bringup::kMaxMessageLineBytes)) {
        ++number;
        if (text.find_first_not_of(" \t\r") == std::string::npos) {
            continue;
        }
        auto parsed = bringup::parseMessageLine(text);
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

/// --input: every line on its topic, paced by --rate.
int sendInput(dds::Bus& bus, const Args& args, double rateHz, int waitReaders, double lingerS)
{
    const std::string path = args.get("input");
    const std::string source = args.get("source", "bus-send");
    const std::string onlyUgv = args.get("only-ugv");
    std::size_t bad = 0;
    auto lines = readInput(path, bad);
    if (!lines) {
        return fail(lines.error());
    }
    if (!onlyUgv.empty()) {
        std::set<std::string> ugvs;
        std::erase_if(*lines, [&](const Line& l) {
            const auto* o = std::get_if<correlator::Observation>(&l.message);
            if (o != nullptr) {
                ugvs.insert(o->ugv);
            }
            return o == nullptr || o->ugv != onlyUgv;
        });
        if (lines->empty()) {
            std::string names;
            for (const std::string& u : ugvs) {
                names += (names.empty() ? "" : ", ") + u;
            }
            return fail(Error{path, "no observation of ugv '" + onlyUgv + "'",
                              ugvs.empty() ? std::string("the file has no observations")
                                           : "give one of the file's UGVs: " + names});
        }
    }
    if (lines->empty()) {
        return fail(Error{path, "no message to send", "give a file of correlator JSON lines (ugvsense correlate-sim)"});
    }
    auto writers = InputWriters::create(bus);
    if (!writers) {
        return fail(writers.error());
    }
    InputWriters& w = *writers;
    waitForReaders(w.observations, waitReaders, dds::topicName(dds::TopicId::Observation, bus.config()));
    std::printf("sending %zu message(s) to %d reader(s)\n", lines->size(), w.observations.matched());
    std::fflush(stdout);
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
            bringup::toDds(*o, line.number, observation);
            written = writeOne(w.observations, observation);
        } else if (const auto* u = std::get_if<correlator::UavFix>(&line.message)) {
            bringup::toDds(*u, source, line.number, uav);
            written = writeOne(w.uav, uav);
        } else if (const auto* c = std::get_if<correlator::Confirm>(&line.message)) {
            bringup::toDds(*c, source, line.number, confirmation);
            written = writeOne(w.confirmations, confirmation);
        } else if (const auto* p = std::get_if<correlator::PoseCorrection>(&line.message)) {
            bringup::toDds(*p, source, line.number, correction);
            written = writeOne(w.corrections, correction);
        }
        if (!written) {
            if (bus::g_stop.load()) {
                break;
            }
            return fail(Error{path + ":" + std::to_string(line.number),
                              "the bus refused the message for " + std::to_string(kRefusedWriteTimeout.count()) +
                                  " s (a reader does not acknowledge and the writer's history is full)",
                              "check the readers, or pace the sender with --rate"});
        }
        ++w.sent[topic];
    }
    if (bus::g_stop.load()) {
        std::printf("interrupted: sent %llu of %zu message(s)\n", static_cast<unsigned long long>(w.total()),
                    lines->size());
        return 1;
    }
    if (bad > 0) {
        std::cerr << path << ": " << bad << " bad line(s) skipped\n";
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    char what[512];
    std::snprintf(what, sizeof(what), "from %s%s in %.2f s", path.c_str(),
                  onlyUgv.empty() ? "" : (" (only ugv " + onlyUgv + ")").c_str(), seconds);
    return finish(w, what, lingerS, bus.config());
}

/// --hostile: what a broken or malicious participant could send, then a flood.
int sendHostile(dds::Bus& bus, const Args& args, int waitReaders, double lingerS, std::uint64_t flood,
                std::uint64_t aheadFlood)
{
    const std::string source = args.get("source", "bus-send");
    auto writers = InputWriters::create(bus);
    if (!writers) {
        return fail(writers.error());
    }
    InputWriters& w = *writers;
    waitForReaders(w.observations, waitReaders, dds::topicName(dds::TopicId::Observation, bus.config()));
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    std::uint64_t sequence = 0;
    double t = 1.0;
    const auto observation = [&]() {
        msg::OoiObservation o;
        o.ugv(source);
        o.sequence_number(++sequence);
        o.t(t += 0.01);
        o.track("hostile-track");
        o.cls(0);
        o.ugv_lat_deg(kCircleCentreLat);
        o.ugv_lon_deg(kCircleCentreLon);
        o.ugv_heading_deg(90.0);
        o.range_m(10.0);
        o.bearing_deg(0.0);
        return o;
    };
    const auto uavFix = [&]() {
        msg::UavObservation u;
        u.source(source);
        u.sequence_number(++sequence);
        u.t(t += 0.01);
        u.cls(1);
        u.lat_deg(kCircleCentreLat);
        u.lon_deg(kCircleCentreLon);
        return u;
    };
    const auto confirm = [&]() {
        msg::ConfirmationState c;
        c.source(source);
        c.sequence_number(++sequence);
        c.t(t += 0.01);
        c.id("ooi-1");
        c.state(1);
        return c;
    };
    const auto correction = [&]() {
        msg::PoseCorrection p;
        p.source(source);
        p.sequence_number(++sequence);
        p.t(t += 0.01);
        p.ugv("ugv-1");
        p.since_t(0.0);
        p.until_t(1.0);
        p.d_east_m(0.5);
        p.d_north_m(-0.5);
        p.d_heading_deg(1.0);
        return p;
    };
    struct Kind {
        const char* topic;
        const char* what;
    };
    std::vector<Kind> kinds;
    const auto send = [&](auto& writer, const auto& sample, std::size_t topic, const char* what) {
        if (!writeOne(writer, sample)) {
            return false;
        }
        ++w.sent[topic];
        kinds.push_back({dds::shortName(static_cast<dds::TopicId>(static_cast<int>(dds::TopicId::Observation) +
                                                                  static_cast<int>(topic))),
                         what});
        return true;
    };
    // Each case breaks one rule of ipc::dds::check(); everything else in the sample is valid.
    bool ok = true;
    {
        auto s = observation();
        s.t(kNaN);
        ok = ok && send(w.observations, s, 0, "NaN time");
        s = observation();
        s.range_m(kNaN);
        ok = ok && send(w.observations, s, 0, "NaN range");
        s = observation();
        s.ugv_lat_deg(kNaN);
        ok = ok && send(w.observations, s, 0, "NaN latitude");
        s = observation();
        s.ugv_lat_deg(91.0);
        ok = ok && send(w.observations, s, 0, "latitude 91");
        s = observation();
        s.ugv_lat_deg(-91.0);
        ok = ok && send(w.observations, s, 0, "latitude -91");
        s = observation();
        s.ugv_lon_deg(200.0);
        ok = ok && send(w.observations, s, 0, "longitude 200");
        s = observation();
        s.cls(9);
        ok = ok && send(w.observations, s, 0, "unknown class 9");
        s = observation();
        s.ugv("");
        ok = ok && send(w.observations, s, 0, "empty ugv name");
        s = observation();
        s.track("");
        ok = ok && send(w.observations, s, 0, "empty track name");
        s = observation();
        s.track(std::string(dds::kMaxNameLength + 36, 't')); // arrives with kMaxNameLength + 1 characters
        ok = ok && send(w.observations, s, 0, "track name of 100 characters");
    }
    {
        auto s = uavFix();
        s.t(kNaN);
        ok = ok && send(w.uav, s, 1, "NaN time");
        s = uavFix();
        s.lat_deg(kNaN);
        ok = ok && send(w.uav, s, 1, "NaN latitude");
        s = uavFix();
        s.lat_deg(91.0);
        ok = ok && send(w.uav, s, 1, "latitude 91");
        s = uavFix();
        s.lat_deg(-91.0);
        ok = ok && send(w.uav, s, 1, "latitude -91");
        s = uavFix();
        s.lon_deg(200.0);
        ok = ok && send(w.uav, s, 1, "longitude 200");
        s = uavFix();
        s.cls(9);
        ok = ok && send(w.uav, s, 1, "unknown class 9");
        s = uavFix();
        s.source("");
        ok = ok && send(w.uav, s, 1, "empty source name");
    }
    {
        auto s = confirm();
        s.t(kNaN);
        ok = ok && send(w.confirmations, s, 2, "NaN time");
        s = confirm();
        s.state(7);
        ok = ok && send(w.confirmations, s, 2, "unknown confirmation state 7");
        s = confirm();
        s.id("");
        ok = ok && send(w.confirmations, s, 2, "empty object id");
        s = confirm();
        s.source("");
        ok = ok && send(w.confirmations, s, 2, "empty source name");
        s = confirm();
        s.id(std::string(dds::kMaxNameLength + 36, 'i'));
        ok = ok && send(w.confirmations, s, 2, "object id of 100 characters");
    }
    {
        auto s = correction();
        s.since_t(5.0);
        s.until_t(4.0);
        ok = ok && send(w.corrections, s, 3, "since_t > until_t");
        s = correction();
        s.d_east_m(kNaN);
        ok = ok && send(w.corrections, s, 3, "NaN east correction");
        s = correction();
        s.ugv("");
        ok = ok && send(w.corrections, s, 3, "empty ugv name");
        s = correction();
        s.source("");
        ok = ok && send(w.corrections, s, 3, "empty source name");
    }
    if (!ok) {
        return bus::g_stop.load()
                   ? 1
                   : fail(Error{"ugvsense " + std::string(kCommand) + " --hostile",
                                "the bus refused a sample for " + std::to_string(kRefusedWriteTimeout.count()) + " s",
                                "check the readers"});
    }
    std::printf("hostile samples sent (each breaks one check):\n");
    for (const Kind& k : kinds) {
        std::printf("  %-17s %s: 1\n", k.topic, k.what);
    }
    const std::uint64_t hostile = w.total();
    const auto start = Clock::now();
    std::uint64_t flooded = 0;
    for (; flooded < flood; ++flooded) {
        auto s = observation();
        s.track("flood");
        s.range_m(5.0 + static_cast<double>(flooded % 100) * 0.1);
        if (!writeOne(w.observations, s)) {
            break;
        }
        ++w.sent[0];
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    std::printf("flood: %llu valid observation(s) of ugv '%s' in %.2f s (%.0f per second)\n",
                static_cast<unsigned long long>(flooded), source.c_str(), seconds,
                seconds > 0.0 ? static_cast<double>(flooded) / seconds : 0.0);
    // A sender faking its clock: source stamps one second apart from now on, written as fast as possible. A guard
    // metering source time alone would see one sample per second.
    const std::int64_t stamp0 = dds::realtimeNowNs();
    std::uint64_t ahead = 0;
    for (; flooded == flood && ahead < aheadFlood; ++ahead) {
        auto s = observation();
        s.track("ahead");
        const auto until = Clock::now() + kRefusedWriteTimeout;
        bool written = false;
        while (!(written = w.observations.writeStamped(s, stamp0 + static_cast<std::int64_t>(ahead) * 1'000'000'000)) &&
               !bus::g_stop.load() && Clock::now() < until) {
        }
        if (!written) {
            break;
        }
        ++w.sent[0];
    }
    if (aheadFlood > 0) {
        std::printf("ahead-flood: %llu valid observation(s) stamped 1 s apart from now on\n",
                    static_cast<unsigned long long>(ahead));
    }
    std::fflush(stdout);
    if (flooded < flood || ahead < aheadFlood) {
        return bus::g_stop.load()
                   ? 1
                   : fail(Error{"ugvsense " + std::string(kCommand) + " --flood",
                                "the bus refused the flood after " + std::to_string(flooded) + " sample(s) for " +
                                    std::to_string(kRefusedWriteTimeout.count()) + " s",
                                "check the readers"});
    }
    return finish(w, "(" + std::to_string(hostile) + " hostile, then the flood)", lingerS, bus.config());
}

/// --poses: a vehicle on a 10 m circle, heading along it, at --rate for --duration.
int sendPoses(dds::Bus& bus, const std::string& vehicle, double rateHz, double durationS, int waitReaders,
              double lingerS)
{
    auto writer = bus.writer<msg::VehiclePose>();
    if (!writer) {
        return fail(writer.error());
    }
    waitForReaders(*writer, waitReaders, dds::topicName(dds::TopicId::Pose, bus.config()));
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
                bus::g_stop.load() ? " (stopped by a signal)" : "");
    if (refused > 0) {
        std::printf("%llu pose(s) refused by the writer\n", static_cast<unsigned long long>(refused));
    }
    std::fflush(stdout);
    if (lingerS > 0.0 && !bus::g_stop.load()) {
        sleepUntil(Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(lingerS)));
    }
    return refused > 0 ? 1 : 0;
}

Result<double, Error> wholeNumber(const Args& args, const std::string& name, double fallback, double min, double max)
{
    auto value = args.number(name, fallback, min, max);
    if (value && std::floor(*value) != *value) {
        return Unexpected(Error{"ugvsense " + std::string(kCommand) + " --" + name,
                                "bad value '" + args.get(name) + "'", "give a whole number"});
    }
    return value;
}

} // namespace

int runBusSend(int argc, char** argv)
{
    std::vector<OptionSpec> specs{
        {"input", "OBS.jsonl", "mode 1: publish the correlator's JSON lines (correlate-sim --out) on their topics",
         false},
        {"hostile", "", "mode 2: malformed samples on the input topics, then a flood of valid observations", false},
        {"poses", "VEHICLE", "mode 3: VehiclePose samples of VEHICLE driving a 10 m circle", false},
        {"source", "NAME", "sender of UAV fixes, confirmations, corrections (and --hostile's ugv), default bus-send",
         false},
        {"only-ugv", "NAME", "--input: send only the observations of this UGV (nothing else)", false},
        {"rate", "HZ", "--input: messages per second, default as fast as the writers accept; --poses: default 10",
         false},
        {"duration", "S", "--poses: how long, default 10", false},
        {"flood", "N", "--hostile: valid observations sent as fast as possible, default 5000", false},
        {"ahead-flood", "N",
         "--hostile: then N valid observations stamped 1 s apart from now on (a faked clock), default 0", false},
        {"wait-readers", "N", "wait up to 20 s for N readers of the observation (--poses: pose) topic, default 1",
         false},
        {"linger", "S", "stay S more seconds after the acknowledgements (late readers get the history)", false}};
    for (auto& spec : bus::options()) {
        specs.push_back(std::move(spec));
    }
    Args args(
        kCommand,
        "(--input OBS.jsonl [--source NAME] [--only-ugv NAME] [--rate HZ] | --hostile [--flood N] [--ahead-flood N] | "
        "--poses VEHICLE [--rate HZ] [--duration S]) [--wait-readers N] [--linger S] [--domain N] "
        "[--partition P] [--ros-namespace NS] [--discovery-server LIST]\n"
        "  A test sender for the DDS bus. --input publishes each line of a correlator input file on its topic\n"
        "  (observations, uav, confirmations, pose_corrections) with sequence_number = its line number, so a\n"
        "  restarted sender's repeats are duplicates. --hostile sends samples that break the input checks (NaN\n"
        "  time/range/latitude, latitude +-91, longitude 200, class 9, state 7, empty names, since_t > until_t)\n"
        "  and then floods valid observations (--ahead-flood: then more, stamped 1 s apart). --poses publishes\n"
        "  poses (stamp = CLOCK_REALTIME) of a vehicle on a 10 m circle. The reliable modes end when every\n"
        "  matched reader acknowledged everything (60 s at most, else exit 1).",
        specs);
    if (const auto exit = parseOrExit(args, argc, argv, kCommand)) {
        return *exit;
    }
    const std::string where = std::string("ugvsense ") + kCommand;
    const int modes = (args.has("input") ? 1 : 0) + (args.has("hostile") ? 1 : 0) + (args.has("poses") ? 1 : 0);
    if (modes != 1) {
        return reportUsageError(
            kCommand, Error{where, modes == 0 ? "nothing to send" : "more than one of --input, --hostile, --poses",
                            "give exactly one of --input OBS.jsonl, --hostile, --poses VEHICLE"});
    }
    const auto only = [&](const char* option, const char* mode, bool inMode) -> std::optional<Error> {
        if (args.has(option) && !inMode) {
            return Error{where + " --" + option, std::string("only applies to ") + mode,
                         std::string("remove it or add ") + mode};
        }
        return std::nullopt;
    };
    for (const auto& e :
         {only("only-ugv", "--input", args.has("input")), only("flood", "--hostile", args.has("hostile")),
          only("ahead-flood", "--hostile", args.has("hostile")), only("duration", "--poses", args.has("poses")),
          only("rate", "--input or --poses", !args.has("hostile"))}) {
        if (e) {
            return reportUsageError(kCommand, *e);
        }
    }
    if (args.has("poses") && args.get("poses").empty()) {
        return reportUsageError(kCommand, Error{where + " --poses", "an empty vehicle name", "name the vehicle"});
    }
    if ((args.has("source") && args.get("source").empty()) || (args.has("only-ugv") && args.get("only-ugv").empty())) {
        return reportUsageError(kCommand, Error{where, "an empty --source or --only-ugv name", "give a name"});
    }
    if (args.get("source", "").size() > dds::kMaxNameLength || args.get("only-ugv", "").size() > dds::kMaxNameLength) {
        return reportUsageError(kCommand, Error{where,
                                                "a --source or --only-ugv name longer than " +
                                                    std::to_string(dds::kMaxNameLength) + " characters",
                                                "shorten it (the bus's name bound)"});
    }
    const auto rate = args.number("rate", args.has("poses") ? kDefaultPoseRateHz : 0.0, 0.001, kMaxRateHz);
    const auto duration = args.number("duration", kDefaultPoseDurationS, 0.0, 1e7);
    const auto linger = args.number("linger", 0.0, 0.0, kMaxLingerS);
    const auto readers = wholeNumber(args, "wait-readers", 1, 0, kMaxReaders);
    const auto flood = wholeNumber(args, "flood", 5000, 0, kMaxFlood);
    const auto aheadFlood = wholeNumber(args, "ahead-flood", 0, 0, kMaxFlood);
    for (const auto* n : {&rate, &duration, &linger, &readers, &flood, &aheadFlood}) {
        if (!*n) {
            return reportUsageError(kCommand, n->error());
        }
    }
    auto config = bus::configFrom(args, kCommand, "ugvsense/bus-send");
    if (!config) {
        return reportUsageError(kCommand, config.error());
    }
    bus::installStopHandler();
    auto created = dds::Bus::create(*config);
    if (!created) {
        return fail(created.error());
    }
    dds::Bus& b = **created;
    const int waitReaders = static_cast<int>(*readers);
    if (args.has("input")) {
        return sendInput(b, args, args.has("rate") ? *rate : 0.0, waitReaders, *linger);
    }
    if (args.has("hostile")) {
        return sendHostile(b, args, waitReaders, *linger, static_cast<std::uint64_t>(*flood),
                           static_cast<std::uint64_t>(*aheadFlood));
    }
    return sendPoses(b, args.get("poses"), *rate, *duration, waitReaders, *linger);
}

} // namespace ugv::tool
