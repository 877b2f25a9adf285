// bus-hostile: a test tool (not installed) that plays a broken or malicious participant on the DDS bus (issue 6,
// issue 22): samples on the correlator's input topics that each break one rule of ipc::dds::check() (NaN time,
// range or latitude, latitude +-91, longitude 200, class 9, state 7, empty or over-long names, since_t > until_t),
// then a flood of valid observations from this one participant, then (--ahead-flood) more stamped 1 s apart from
// now on (a faked clock). The receivers must refuse and count every hostile sample and keep up with the flood.
// Used by test/system/hostile_bus_test.sh and test/unit/bringup/bus_loopback_test.sh.

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "ugv/ipc/dds_bus.hpp"
#include "ugv/ipc/dds_convert.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/bus_options.hpp"
#include "ugv/tool/bus_writers.hpp"

namespace ugv::tool {
namespace {

namespace dds = ipc::dds;
namespace msg = ipc::dds::msg;
using Clock = bus::Clock;

constexpr const char* kCommand = "bus-hostile";
constexpr double kMaxLingerS = 1e7;
constexpr double kMaxFlood = 1e7;
constexpr double kMaxReaders = 1000;

/// What a broken or malicious participant could send, then a flood.
int sendHostile(dds::Bus& bus, const Args& args, int waitReaders, double lingerS, std::uint64_t flood,
                std::uint64_t aheadFlood)
{
    const std::string source = args.get("source", kCommand);
    auto writers = bus::InputWriters::create(bus);
    if (!writers) {
        return reportError(kCommand, writers.error());
    }
    bus::InputWriters& w = *writers;
    bus::waitForReaders(w.observations, bus::ReaderWait{waitReaders},
                        dds::topicName(dds::TopicId::Observation, bus.config()), kCommand);
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
        o.ugv_lat_deg(bus::kSiteLat);
        o.ugv_lon_deg(bus::kSiteLon);
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
        u.lat_deg(bus::kSiteLat);
        u.lon_deg(bus::kSiteLon);
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
        if (!bus::writeOne(writer, sample)) {
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
        return gStop.load() ? 1
                            : reportError(kCommand, Error{"ugvsense " + std::string(kCommand),
                                                          "the bus refused a sample for " +
                                                              std::to_string(bus::kRefusedWriteTimeout.count()) + " s",
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
        if (!bus::writeOne(w.observations, s)) {
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
        const auto until = Clock::now() + bus::kRefusedWriteTimeout;
        bool written = false;
        while (!(written = w.observations.writeStamped(s, stamp0 + static_cast<std::int64_t>(ahead) * 1'000'000'000)) &&
               !gStop.load() && Clock::now() < until) {
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
        return gStop.load() ? 1
                            : reportError(kCommand, Error{"ugvsense " + std::string(kCommand) + " --flood",
                                                          "the bus refused the flood after " + std::to_string(flooded) +
                                                              " sample(s) for " +
                                                              std::to_string(bus::kRefusedWriteTimeout.count()) + " s",
                                                          "check the readers"});
    }
    return bus::finish(w, kCommand, "(" + std::to_string(hostile) + " hostile, then the flood)", lingerS, bus.config());
}

int run(int argc, char** argv)
{
    std::vector<OptionSpec> specs{
        {"source", "NAME", "the ugv and source name of the samples, default bus-hostile", false},
        {"flood", "N", "valid observations sent as fast as possible after the hostile ones, default 5000", false},
        {"ahead-flood", "N", "then N valid observations stamped 1 s apart from now on (a faked clock), default 0",
         false},
        {"wait-readers", "N", "wait up to 20 s for N readers of the observation topic, default 1", false},
        {"linger", "S", "stay S more seconds after the acknowledgements", false}};
    for (auto& spec : bus::options()) {
        specs.push_back(std::move(spec));
    }
    Args args(
        kCommand,
        "[--source NAME] [--flood N] [--ahead-flood N] [--wait-readers N] [--linger S] [--domain N] "
        "[--partition P] [--discovery-server LIST] [--security DIR]\n"
        "  A test tool: sends samples that break the input checks of the correlator's topics, one per rule, then\n"
        "  floods valid observations. Ends when every matched reader acknowledged everything (60 s at most, else\n"
        "  exit 1).",
        specs);
    if (auto parsed = args.parse(argc, argv, 1); !parsed) {
        return reportUsageError(kCommand, parsed.error());
    }
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    const std::string where = std::string("ugvsense ") + kCommand;
    if (!args.positional().empty()) {
        return reportUsageError(kCommand, Error{where, "unexpected argument '" + args.positional().front() + "'",
                                                "see " + std::string(kCommand) + " --help"});
    }
    if (args.has("source") && (args.get("source").empty() || args.get("source").size() > dds::kMaxNameLength)) {
        return reportUsageError(kCommand, Error{where + " --source",
                                                "empty or longer than " + std::to_string(dds::kMaxNameLength),
                                                "give a name of the bus's bound"});
    }
    const auto linger = args.number("linger", 0.0, 0.0, kMaxLingerS);
    const auto readers = args.wholeNumber("wait-readers", 1, 0, kMaxReaders);
    const auto flood = args.wholeNumber("flood", 5000, 0, kMaxFlood);
    const auto aheadFlood = args.wholeNumber("ahead-flood", 0, 0, kMaxFlood);
    for (const auto* n : {&linger, &readers, &flood, &aheadFlood}) {
        if (!*n) {
            return reportUsageError(kCommand, n->error());
        }
    }
    auto config = bus::configFrom(args, kCommand, "ugvsense/bus-hostile");
    if (!config) {
        return reportUsageError(kCommand, config.error());
    }
    installStopHandler();
    auto created = dds::Bus::create(*config);
    if (!created) {
        return reportError(kCommand, created.error());
    }
    return sendHostile(**created, args, static_cast<int>(*readers), *linger, static_cast<std::uint64_t>(*flood),
                       static_cast<std::uint64_t>(*aheadFlood));
}

} // namespace
} // namespace ugv::tool

int main(int argc, char** argv)
{
    return ugv::tool::run(argc, argv);
}
