// ugvsense correlate: the OOI correlator offline. Reads time-ordered JSON lines of observations, UAV fixes,
// operator confirmations and pose corrections (bringup/tool/correlate_io.hpp), writes one snapshot of the
// correlated objects per period, reports bad lines with their line number and goes on, and prints the
// correlator's processing rate. `--map` draws the last snapshot for the ground control station.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <variant>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "correlate_io.hpp"
#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/improved_correlator.hpp"
#include "ugv/correlator/original_correlator.hpp"

namespace ugv::tool {
namespace {

using namespace correlator;

constexpr const char* kCommand = "correlate";
constexpr int kMapSize = 900;
constexpr int kMaxReportedLines = 50; ///< bad lines printed one by one; the rest are counted

int fail(const Error& error)
{
    std::cerr << "ugvsense " << kCommand << ": error: " << error.message() << '\n';
    return 1;
}

struct UgvPose {
    double lat = 0.0;
    double lon = 0.0;
    double headingDeg = 0.0;
};

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

/// Objects (2-sigma ellipses, ids, confirmation colours, activation zones) and UGVs (triangles) on a metric grid.
Result<void, Error> drawMap(const std::string& path, const Snapshot& s, const std::map<std::string, UgvPose>& ugvs)
{
    if (s.objects.empty() && ugvs.empty()) {
        return Unexpected(Error{path, "nothing to draw: no objects and no UGVs", "check the input"});
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
    for (double g = -std::floor(extent / grid) * grid; g <= extent; g += grid) {
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
        cv::circle(map, c, static_cast<int>(o.zoneDiameterM / 2.0 * scale), colour, 1, cv::LINE_AA);
        // 2-sigma ellipse; major_axis_deg is a compass direction, image angles run clockwise from +x (east).
        const cv::Size2d axes(std::max(2.0 * o.sigmaMajorM * scale, 2.0), std::max(2.0 * o.sigmaMinorM * scale, 2.0));
        cv::ellipse(map, c, axes, o.majorAxisDeg - 90.0, 0, 360, colour, 2, cv::LINE_AA);
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

int runCorrelate(int argc, char** argv)
{
    Args args(kCommand,
              "--input OBS.jsonl --output SNAPSHOTS.jsonl [--period S] [--mode improved|original] [--map MAP.png]",
              {{"input", "OBS.jsonl", "time-ordered observations, UAV fixes, confirmations, pose corrections", true},
               {"output", "SNAPSHOTS.jsonl", "one snapshot of the correlated objects per period", true},
               {"period", "S", "snapshot period, default 1 s", false},
               {"mode", "MODE",
                "improved (default: pose errors estimated, statistical gates, Kalman mobiles) or original (the "
                "published algorithm)",
                false},
               {"map", "MAP.png", "draw the last snapshot: error ellipses, ids, confirmation colours, UGVs", false}});
    if (const auto exit = parseOrExit(args, argc, argv, kCommand)) {
        return *exit;
    }
    const auto period = args.number("period", 1.0, 0.01, 3600.0);
    if (!period) {
        return reportUsageError(kCommand, period.error());
    }
    const std::string mode = args.get("mode", "improved");
    if (mode != "original" && mode != "improved") {
        return reportUsageError(kCommand, Error{"--mode " + mode, "unknown mode", "use original or improved"});
    }
    std::ifstream in(args.get("input"));
    if (!in) {
        return fail(Error{args.get("input"), "cannot open the input", "check the path"});
    }
    std::ofstream out(args.get("output"));
    if (!out) {
        return fail(Error{args.get("output"), "cannot create the output", "check the folder"});
    }

    std::variant<OriginalCorrelator, ImprovedCorrelator> correlator;
    if (mode == "improved") {
        correlator.emplace<ImprovedCorrelator>();
    }
    std::map<std::string, UgvPose> ugvs;
    std::string line;
    std::size_t lineNumber = 0;
    std::size_t bad = 0;
    std::size_t messages = 0;
    std::size_t snapshots = 0;
    double lastT = -1e300;
    double nextSnapshotT = NAN;
    std::chrono::nanoseconds busy{0};         ///< in add()
    std::chrono::nanoseconds snapshotBusy{0}; ///< in snapshot()
    Snapshot last;
    const auto report = [&](const Error& e) {
        ++bad;
        if (bad <= kMaxReportedLines) {
            std::cerr << args.get("input") << ':' << lineNumber << ": skipped: " << e.message() << '\n';
        }
    };
    const auto emit = [&](double t) {
        const auto t0 = std::chrono::steady_clock::now();
        last = std::visit([t](auto& c) { return c.snapshot(t); }, correlator);
        snapshotBusy += std::chrono::steady_clock::now() - t0;
        out << toJsonLine(last) << '\n';
        ++snapshots;
    };
    while (std::getline(in, line)) {
        ++lineNumber;
        if (line.find_first_not_of(" \t\r") == std::string::npos) {
            continue;
        }
        auto message = parseMessageLine(line);
        if (!message) {
            report(message.error());
            continue;
        }
        const double t = std::visit([](const auto& m) { return m.t; }, *message);
        if (t < lastT) {
            report(Error{"", "time " + std::to_string(t) + " is before the previous line's " + std::to_string(lastT),
                         "sort the input by time"});
            continue;
        }
        lastT = t;
        if (std::isnan(nextSnapshotT)) {
            nextSnapshotT = (std::floor(t / *period) + 1.0) * *period;
        }
        while (t >= nextSnapshotT) {
            emit(nextSnapshotT);
            nextSnapshotT += *period;
        }
        const auto t0 = std::chrono::steady_clock::now();
        auto applied = std::visit([&message](auto& c) { return c.add(*message); }, correlator);
        busy += std::chrono::steady_clock::now() - t0;
        if (!applied) {
            report(applied.error());
            continue;
        }
        ++messages;
        if (const auto* o = std::get_if<Observation>(&*message)) {
            ugvs[o->ugv] = UgvPose{o->ugvLat, o->ugvLon, o->ugvHeadingDeg};
        }
    }
    if (messages > 0) {
        emit(lastT);
    }
    out.flush();
    if (!out) {
        return fail(Error{args.get("output"), "write failed", "check the free space"});
    }
    if (bad > kMaxReportedLines) {
        std::cerr << args.get("input") << ": " << bad - kMaxReportedLines << " more bad line(s) not shown\n";
    }
    const double seconds = std::chrono::duration<double>(busy).count();
    const double snapshotSeconds = std::chrono::duration<double>(snapshotBusy).count();
    std::printf("correlated %zu message(s), %zu bad line(s) skipped, %zu snapshot(s) to %s; %zu object(s) at t %.1f\n"
                "correlator: %.3f s in add() (%.0f messages/s), %.3f s in snapshot() (%.1f us each); "
                "mode %s; %zu observation points held\n",
                messages, bad, snapshots, args.get("output").c_str(), last.objects.size(), last.t, seconds,
                seconds > 0.0 ? static_cast<double>(messages) / seconds : 0.0, snapshotSeconds,
                snapshots > 0 ? snapshotSeconds * 1e6 / static_cast<double>(snapshots) : 0.0, mode.c_str(),
                std::visit([](const auto& c) { return c.storedPoints(); }, correlator));
    if (args.has("map")) {
        if (auto drawn = drawMap(args.get("map"), last, ugvs); !drawn) {
            return fail(drawn.error());
        }
        std::printf("map of t %.1f written to %s\n", last.t, args.get("map").c_str());
    }
    return messages == 0 && bad > 0 ? 1 : 0;
}

} // namespace ugv::tool
