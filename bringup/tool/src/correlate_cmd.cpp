// ugvsense correlate: the OOI correlator offline. Reads time-ordered JSON lines of observations, UAV fixes,
// operator confirmations and pose corrections (bringup/tool/include/ugv/tool/correlate_io.hpp), writes one snapshot of
// the correlated objects per period, reports bad lines with their line number and goes on, and prints the correlator's
// processing rate. `--map` draws the last snapshot for the ground control station. `--from-dds` takes the inputs live
// from the bus instead (service::LiveCorrelator, the ground station's own code) and writes the last snapshot (and the
// map) when stopped.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <variant>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ugv/adapters/correlate_io.hpp"
#include "ugv/correlator/correlator_feed.hpp"
#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/mode.hpp"
#include "ugv/service/correlator_task.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/bus_options.hpp"
#include "ugv/tool/commands.hpp"
#include "ugv/tool/stop_signal.hpp"

namespace ugv::tool {
using adapters::parseMessageLine;
using adapters::toJsonLine;
namespace {

using correlator::Confirmation;
using correlator::LocalFrame;
using correlator::ObjectEstimate;
using correlator::OoiClass;
using correlator::project;
using correlator::Snapshot;

constexpr const char* kCorrelateCommand = "correlate";
constexpr int kMapSize = 900;

cv::Scalar stateColour(const ObjectEstimate& o)
{
    if (o.state == Confirmation::ConfirmedPositive) {
        return {40, 40, 220}; // red
    }
    if (o.state == Confirmation::ConfirmedNegative) {
        return {60, 170, 60}; // green
    }
    return o.cls == OoiClass::NonCombatant ? cv::Scalar(200, 120, 40) : cv::Scalar(30, 170, 230); // blue / amber
}

/// A length in map pixels that OpenCV's drawing takes: finite, within [min, 8 map sizes] (cv::ellipse asserts on an
/// axis that overflows int).
double drawable(double px, double min)
{
    return std::isfinite(px) ? std::clamp(px, min, 8.0 * kMapSize) : 8.0 * kMapSize;
}

/// Objects (2-sigma ellipses, ids, confirmation colours, activation zones) and UGVs (triangles) on a metric grid.
Result<void, Error> drawMap(const std::string& path, const Snapshot& s,
                            const std::map<std::string, correlator::UgvPose>& ugvs)
{
    if (s.objects.empty() && ugvs.empty()) {
        return Unexpected(Error{path, "nothing to draw: no objects and no UGVs", "check the input"});
    }
    for (const ObjectEstimate& o : s.objects) {
        if (!std::isfinite(o.lat) || !std::isfinite(o.lon)) {
            return Unexpected(Error{path, "object " + o.id + " has no finite position", "check the input"});
        }
    }
    double lat0 = 0.0;
    double lon0 = 0.0;
    const double n = static_cast<double>(s.objects.size() + ugvs.size());
    for (const ObjectEstimate& o : s.objects) {
        lat0 += o.lat / n;
        lon0 += o.lon / n;
    }
    for (const auto& [name, p] : ugvs) {
        lat0 += p.lat / n;
        lon0 += p.lon / n;
    }
    const LocalFrame frame(lat0, lon0);
    double extent = 10.0;
    for (const ObjectEstimate& o : s.objects) {
        extent = std::max(extent, frame.toLocal(o.lat, o.lon).cwiseAbs().maxCoeff() + o.zoneDiameterM);
    }
    for (const auto& [name, p] : ugvs) {
        extent = std::max(extent, frame.toLocal(p.lat, p.lon).cwiseAbs().maxCoeff() + 5.0);
    }
    const double scale = (kMapSize / 2.0 - 20.0) / extent; // px per metre
    const auto toPx = [&](const Eigen::Vector2d& en) {
        return cv::Point2d(kMapSize / 2.0 + en.x() * scale, kMapSize / 2.0 - en.y() * scale);
    };
    cv::Mat map(kMapSize, kMapSize, CV_8UC3, cv::Scalar(245, 245, 245));
    const double grid = extent > 100.0 ? 50.0 : 10.0;
    for (int gridLine = -static_cast<int>(std::floor(extent / grid)); gridLine * grid <= extent; ++gridLine) {
        const double g = gridLine * grid;
        cv::line(map, toPx({g, -extent}), toPx({g, extent}), cv::Scalar(225, 225, 225));
        cv::line(map, toPx({-extent, g}), toPx({extent, g}), cv::Scalar(225, 225, 225));
    }
    cv::putText(map,
                "grid " + std::to_string(static_cast<int>(grid)) + " m, north up, t " +
                    std::to_string(static_cast<int>(s.t)) + " s",
                {10, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(80, 80, 80));
    cv::putText(map,
                "red confirmed positive, green confirmed negative, amber unknown, blue non-combatant; "
                "ellipse 2 sigma, circle activation zone",
                {10, kMapSize - 10}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(80, 80, 80));
    for (const ObjectEstimate& o : s.objects) {
        const cv::Point2d c = toPx(frame.toLocal(o.lat, o.lon));
        const cv::Scalar colour = stateColour(o);
        cv::circle(map, c, static_cast<int>(drawable(o.zoneDiameterM / 2.0 * scale, 0.0)), colour, 1, cv::LINE_AA);
        // 2-sigma ellipse; major_axis_deg is a compass direction, image angles run clockwise from +x (east).
        const cv::Size2d axes(drawable(2.0 * o.sigmaMajorM * scale, 2.0), drawable(2.0 * o.sigmaMinorM * scale, 2.0));
        cv::ellipse(map, c, axes, std::isfinite(o.majorAxisDeg) ? o.majorAxisDeg - 90.0 : 0.0, 0, 360, colour, 2,
                    cv::LINE_AA);
        cv::putText(map, o.id, c + cv::Point2d(6, -6), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(30, 30, 30));
    }
    for (const auto& [name, p] : ugvs) {
        const Eigen::Vector2d at = frame.toLocal(p.lat, p.lon);
        const Eigen::Vector2d tip = project(at, p.headingDeg, 10.0 / scale);
        const Eigen::Vector2d left = project(at, p.headingDeg - 140.0, 6.0 / scale);
        const Eigen::Vector2d right = project(at, p.headingDeg + 140.0, 6.0 / scale);
        const std::vector<cv::Point> triangle{toPx(tip), toPx(left), toPx(right)};
        cv::fillConvexPoly(map, triangle, cv::Scalar(160, 60, 20), cv::LINE_AA);
        cv::putText(map, name, toPx(at) + cv::Point2d(8, 12), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(160, 60, 20));
    }
    if (!cv::imwrite(path, map)) {
        return Unexpected(Error{path, "cannot write the map image", "check the folder and the extension (.png)"});
    }
    return {};
}

} // namespace

namespace {

/// --from-dds: the live correlator on the bus as a viewer (it publishes nothing), until --duration or SIGINT.
int correlateFromDds(const Args& args, correlator::Mode mode, double period, double lateWindow, std::ofstream& out)
{
    const auto duration = args.number("duration", 0.0, 0.0, 1e7);
    const auto fallback = bus::environmentDomain();
    if (!fallback) {
        return reportUsageError(kCorrelateCommand, fallback.error());
    }
    const auto domain = args.number("domain", *fallback, 0, bus::kMaxDomainId);
    const auto reorder = args.number("reorder-ms", 2000.0, 0.0, 60000.0);
    if (!duration || !domain || !reorder) {
        return reportUsageError(kCorrelateCommand, !duration ? duration.error()
                                                   : !domain ? domain.error()
                                                             : reorder.error());
    }
    ipc::dds::BusConfig bc;
    bc.domainId = static_cast<int>(*domain);
    bc.participantName = "ugvsense/correlate";
    if (args.has("partition")) {
        bc.partitions.push_back(args.get("partition"));
    }
    bc.discoveryServers = args.get("discovery-server");
    bc.sharedMemory = !args.has("no-shm");
    bc.security = bus::securityFrom(args);
    auto bus = ipc::dds::Bus::create(bc);
    if (!bus) {
        return reportError(kCorrelateCommand, bus.error());
    }
    service::LiveCorrelatorOptions o;
    o.mode = mode;
    o.periodS = period;
    o.reorderMs = *reorder;
    o.lateWindowS = lateWindow;
    // The station's default hold: the histories of the team come first.
    o.publish = false;
    o.logDir = args.get("log-dir");
    auto live = service::LiveCorrelator::create(**bus, o);
    if (!live) {
        return reportError(kCorrelateCommand, live.error());
    }
    installStopHandler();
    std::printf("correlating live inputs on DDS domain %d%s (Ctrl-C to stop)\n", bc.domainId,
                *duration > 0.0 ? (", for " + std::to_string(static_cast<int>(*duration)) + " s").c_str() : "");
    (void)std::fflush(stdout);
    const auto start = std::chrono::steady_clock::now();
    while (!gStop.load() &&
           (*duration <= 0.0 ||
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < *duration)) {
        (*live)->waitForInput(std::chrono::milliseconds(50));
        bus::followNetworkChanges(**bus);
        (*live)->poll(
            std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
                .count());
        for (const std::string& w : (*live)->takeWarnings()) {
            std::cerr << w << '\n';
        }
    }
    const auto last = (*live)->finish();
    for (const std::string& w : (*live)->takeWarnings()) {
        std::cerr << w << '\n';
    }
    const service::LiveCorrelatorStats st = (*live)->stats();
    std::printf("received %llu input(s): %llu applied (%llu late, put in place), %llu malformed, %llu duplicate(s), "
                "%llu flood, %llu refused; %zu object(s) at t %.1f\n",
                static_cast<unsigned long long>(st.received), static_cast<unsigned long long>(st.applied),
                static_cast<unsigned long long>(st.resequenced), static_cast<unsigned long long>(st.rejected),
                static_cast<unsigned long long>(st.duplicates), static_cast<unsigned long long>(st.flooded),
                static_cast<unsigned long long>(st.refused), last ? last->objects.size() : std::size_t{0},
                last ? last->t : 0.0);
    if (last) {
        out << toJsonLine(*last) << '\n';
    }
    out.flush();
    if (args.has("map")) {
        if (!last) {
            return reportError(kCorrelateCommand,
                               Error{args.get("map"), "no input arrived: nothing to draw",
                                     "check the domain, the partition and that the vehicles publish"});
        }
        if (auto drawn = drawMap(args.get("map"), *last, (*live)->feed().ugvs()); !drawn) {
            return reportError(kCorrelateCommand, drawn.error());
        }
        std::printf("map of t %.1f written to %s\n", last->t, args.get("map").c_str());
    }
    return last ? 0 : 1;
}

} // namespace

namespace {

/// correlate's options.
Args correlateArgs()
{
    return Args(
        kCorrelateCommand,
        "(--input OBS.jsonl | --from-dds) --output SNAPSHOTS.jsonl [--period S] [--mode pose-corrected|original] "
        "[--map MAP.png]",
        {{"input", "OBS.jsonl", "time-ordered observations, UAV fixes, confirmations, pose corrections", false},
         {"from-dds", "", "take the inputs live from the DDS bus (ugvsense/ooi/*) instead of a file", false},
         {"output", "SNAPSHOTS.jsonl", "one snapshot of the correlated objects per period (--from-dds: the last)",
          true},
         {"period", "S", "snapshot period, default 1 s", false},
         {"mode", "MODE",
          "pose-corrected (default: pose errors estimated, statistical gates, Kalman mobiles) or original "
          "(the published algorithm); improved: an alias of pose-corrected",
          false},
         {"map", "MAP.png", "draw the last snapshot: error ellipses, ids, confirmation colours, UGVs", false},
         {"duration", "S", "--from-dds: stop after S seconds (default: at Ctrl-C)", false},
         {"domain", "N", "--from-dds: DDS domain (default $UGV_DDS_DOMAIN, else $ROS_DOMAIN_ID, else 0)", false},
         {"partition", "P", "--from-dds: DDS partition of the team", false},
         {"discovery-server", "LIST", "--from-dds: IP:PORT[;IP:PORT] of Fast DDS discovery servers", false},
         {"no-shm", "", "--from-dds: UDP only, no Fast DDS shared memory", false},
         {"security", "DIR", "--from-dds: a secured bus, with this participant's files (listen --help)", false},
         {"identity", "NAME", "--from-dds: the name in --security's certificate, default DIR's last folder", false},
         {"reorder-ms", "MS", "--from-dds: wait this long to put inputs in time order (default 2000)", false},
         {"late-window-s", "S",
          "an input up to S older than the latest is still put in its place (replayed; default 300, as "
          "correlator.late_window_s); 0: refused",
          false},
         {"log-dir", "DIR", "--from-dds: write inputs.jsonl and snapshots.jsonl there", false}});
}

/// What a run over a file gave beside the feed's own counts.
struct FileRun {
    std::size_t bad = 0; ///< lines skipped (malformed, or refused by the correlator)
    Snapshot last;
};

/// Every line of `in` into `feed`, each snapshot to `out`; a bad line is reported by number (the first
/// kMaxReportedLines of them) and skipped, a jump in time by the snapshots it skipped.
FileRun feedLines(const std::string& inputName, std::istream& in, correlator::CorrelatorFeed& feed, std::ostream& out)
{
    FileRun run;
    std::string line;
    std::size_t lineNumber = 0;
    const auto report = [&](const Error& e) {
        ++run.bad;
        if (run.bad <= kMaxReportedLines) {
            std::cerr << inputName << ':' << lineNumber << ": skipped: " << e.message() << '\n';
        }
    };
    const auto write = [&](const Snapshot& s) {
        run.last = s;
        out << toJsonLine(s) << '\n';
    };
    double lastT = NAN;
    while (adapters::readBoundedLine(in, line, adapters::kMaxMessageLineBytes)) {
        ++lineNumber;
        if (line.find_first_not_of(" \t\r") == std::string::npos) {
            continue;
        }
        auto message = parseMessageLine(line);
        if (!message) {
            report(message.error());
            continue;
        }
        const std::size_t skippedBefore = feed.skippedSnapshots();
        const double t = std::visit([](const auto& m) { return m.t; }, *message);
        if (auto applied = feed.add(*message, write); !applied) {
            report(applied.error());
        }
        if (feed.skippedSnapshots() > skippedBefore) {
            std::cerr << inputName << ':' << lineNumber << ": field 't' jumps from " << lastT << " to " << t
                      << " s: wrote " << correlator::CorrelatorFeed::kMaxSnapshotsPerGap
                      << " snapshots of the gap and skipped " << feed.skippedSnapshots() - skippedBefore << '\n';
        }
        lastT = std::isnan(lastT) ? t : std::max(lastT, t);
    }
    feed.finish(write);
    if (run.bad > kMaxReportedLines) {
        std::cerr << inputName << ": " << run.bad - kMaxReportedLines << " more bad line(s) not shown\n";
    }
    return run;
}

/// The run's counts and the correlator's time.
void printFileSummary(const correlator::CorrelatorFeed& feed, const FileRun& run, const std::string& outputName)
{
    const double seconds = feed.addSeconds();
    const double snapshotSeconds = feed.snapshotSeconds();
    const std::size_t messages = feed.applied();
    const std::size_t snapshots = feed.snapshots();
    if (feed.skippedSnapshots() > 0) {
        std::printf("%zu snapshot(s) skipped over jumps in time (at most %zu are written for one gap)\n",
                    feed.skippedSnapshots(), correlator::CorrelatorFeed::kMaxSnapshotsPerGap);
    }
    std::printf(
        "correlated %zu message(s) (%zu late, put in place by replaying %zu), %zu bad line(s) skipped, %zu "
        "snapshot(s) to %s; %zu object(s) at t %.1f\n"
        "correlator: %.3f s in add() (%.0f messages/s), %.3f s in snapshot() (%.1f us each); "
        "mode %s; %zu observation points held\n",
        messages, feed.resequenced(), feed.replayed(), run.bad, snapshots, outputName.c_str(), run.last.objects.size(),
        run.last.t, seconds, seconds > 0.0 ? static_cast<double>(messages) / seconds : 0.0, snapshotSeconds,
        snapshots > 0 ? snapshotSeconds * 1e6 / static_cast<double>(snapshots) : 0.0, feed.mode(), feed.storedPoints());
}

/// --input: the file's messages in order, a snapshot per period; exit 1 when every line was bad.
int correlateFile(const Args& args, correlator::Mode mode, double period, double lateWindow, std::istream& in,
                  std::ofstream& out)
{
    correlator::CorrelatorFeed feed(mode, period, lateWindow, [] {
        return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    });
    const FileRun run = feedLines(args.get("input"), in, feed, out);
    out.flush();
    if (!out) {
        return reportError(kCorrelateCommand, Error{args.get("output"), "write failed", "check the free space"});
    }
    printFileSummary(feed, run, args.get("output"));
    if (args.has("map")) {
        Result<void, Error> drawn;
        try {
            drawn = drawMap(args.get("map"), run.last, feed.ugvs());
        } catch (const cv::Exception& e) {
            drawn = Unexpected(Error{args.get("map"), std::string("cannot draw the map: ") + e.what(),
                                     "check the input's ranges and positions"});
        }
        if (!drawn) {
            return reportError(kCorrelateCommand, drawn.error());
        }
        std::printf("map of t %.1f written to %s\n", run.last.t, args.get("map").c_str());
    }
    return feed.applied() == 0 && run.bad > 0 ? 1 : 0;
}

} // namespace

int runCorrelate(int argc, char** argv)
{
    Args args = correlateArgs();
    if (const auto exit = parseOrExit(args, argc, argv, kCorrelateCommand)) {
        return *exit;
    }
    const auto period = args.number("period", 1.0, 0.01, 3600.0);
    const auto lateWindow = args.number("late-window-s", 300.0, 0.0, 3600.0);
    if (!period || !lateWindow) {
        return reportUsageError(kCorrelateCommand, !period ? period.error() : lateWindow.error());
    }
    const auto mode = correlator::parseMode(args.get("mode", "pose-corrected"));
    if (!mode) {
        return reportUsageError(kCorrelateCommand, Error{"--mode " + args.get("mode"), "unknown mode",
                                                         "use " + std::string(correlator::kModeNames)});
    }
    // Before the run, not after it: cv::imwrite throws on an extension it has no writer for.
    if (args.has("map") && !cv::haveImageWriter(args.get("map"))) {
        return reportUsageError(
            kCorrelateCommand,
            Error{"--map " + args.get("map"), "no image writer for this file name", "give a .png (or .jpg) file name"});
    }
    if (args.has("input") == args.has("from-dds")) {
        return reportUsageError(kCorrelateCommand,
                                Error{"--input / --from-dds", "give exactly one input",
                                      "a JSON-lines file with --input, or --from-dds for the live bus"});
    }
    std::ifstream in;
    if (args.has("input")) {
        in.open(args.get("input"));
        if (!in) {
            return reportError(kCorrelateCommand, Error{args.get("input"), "cannot open the input", "check the path"});
        }
    }
    std::ofstream out(args.get("output"));
    if (!out) {
        return reportError(kCorrelateCommand,
                           Error{args.get("output"), "cannot create the output", "check the folder"});
    }
    if (args.has("from-dds")) {
        return correlateFromDds(args, *mode, *period, *lateWindow, out);
    }
    return correlateFile(args, *mode, *period, *lateWindow, in, out);
}

} // namespace ugv::tool
