// ugvsense soak: the service over a long replay, with the other core loaded. Replays a recording (looping) at a
// fixed rate through the real service, its three tasks on CPU 0 and, with --load-other-core, `stress-ng --cpu 1`
// pinned to CPU 1; every --sample-s seconds it prints one line: frames, deadline misses, degraded frames, end to end
// p50/p99/max of that window and the process's resident memory (VmRSS). At the end: the service's report and the
// RSS growth after warm-up (the first window is the warm-up: the baseline is the RSS at its end), with
// --max-rss-growth-kb as a check (exit 3 when exceeded).

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "ugv/platform/clock.hpp"
#include "ugv/rt/memory.hpp"
#include "ugv/service/runner.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"
#include "ugv/tool/other_core_load.hpp"

namespace ugv::tool {
namespace {

constexpr const char* kSoakCommand = "soak";
constexpr int kExitTargetMissed = 3;
constexpr int kServiceCpu = 0;
constexpr int kLoadCpu = 1;

struct Window {
    double endS = 0.0;
    std::uint64_t frames = 0;
    std::uint64_t misses = 0;
    std::uint64_t degraded = 0;
    double p50Ms = 0.0;
    double p99Ms = 0.0;
    double maxMs = 0.0;
    std::size_t rssBytes = 0;
};

/// Per window of `windowS` seconds: the end-to-end times of the frames the monitor saw, and VmRSS at its end.
class Sampler {
public:
    Sampler(double windowS, double rate)
        : windowNs_(static_cast<std::int64_t>(windowS * 1e9)), startNs_(MonotonicClock::nowNs()),
          endNs_(startNs_ + windowNs_)
    {
        endToEndMs_.reserve(static_cast<std::size_t>(windowS * rate * 2.0) + 16);
        std::printf("  time_s  frames  misses  degraded  e2e_p50_ms  e2e_p99_ms  e2e_max_ms  rss_kb\n");
    }

    void onFrame(const service::PublishedFrame& frame)
    {
        const std::int64_t now = MonotonicClock::nowNs();
        if (now >= endNs_) {
            close(now);
        }
        endToEndMs_.push_back(static_cast<double>(frame.stageNs[static_cast<std::size_t>(service::Stage::EndToEnd)]) /
                              1e6);
        current_.misses += frame.deadlineMissed ? 1 : 0;
        current_.degraded += frame.message.sectors.degraded ? 1 : 0;
    }

    /// Closes the last (partial) window. The service has stopped by now and let its memory go: the window keeps the
    /// RSS read last while it ran.
    void finish()
    {
        if (!endToEndMs_.empty()) {
            close(MonotonicClock::nowNs(), false);
        }
    }

    [[nodiscard]] const std::vector<Window>& windows() const { return windows_; }

private:
    void close(std::int64_t now, bool running = true)
    {
        current_.endS = static_cast<double>(now - startNs_) / 1e9;
        current_.frames = endToEndMs_.size();
        if (!endToEndMs_.empty()) {
            std::sort(endToEndMs_.begin(), endToEndMs_.end());
            const auto at = [&](double q) {
                return endToEndMs_[static_cast<std::size_t>(q * static_cast<double>(endToEndMs_.size() - 1))];
            };
            current_.p50Ms = at(0.50);
            current_.p99Ms = at(0.99);
            current_.maxMs = endToEndMs_.back();
        }
        current_.rssBytes =
            running || windows_.empty() ? rt::readStatusBytes("VmRSS").value_or(0) : windows_.back().rssBytes;
        std::printf("%8.0f  %6llu  %6llu  %8llu  %10.2f  %10.2f  %10.2f  %6zu\n", current_.endS,
                    static_cast<unsigned long long>(current_.frames), static_cast<unsigned long long>(current_.misses),
                    static_cast<unsigned long long>(current_.degraded), current_.p50Ms, current_.p99Ms, current_.maxMs,
                    current_.rssBytes / 1024);
        (void)std::fflush(stdout);
        windows_.push_back(current_);
        current_ = Window{};
        endToEndMs_.clear();
        while (endNs_ <= now) {
            endNs_ += windowNs_;
        }
    }

    std::int64_t windowNs_;
    std::int64_t startNs_;
    std::int64_t endNs_;
    Window current_;
    std::vector<double> endToEndMs_;
    std::vector<Window> windows_;
};

struct SoakFigures {
    std::size_t baselineRss = 0; ///< at the end of the first (warm-up) window
    std::size_t peakRss = 0;     ///< the largest of the later windows
    std::size_t finalRss = 0;
    std::int64_t growthKb = 0; ///< peak - baseline
};

SoakFigures memoryFigures(const std::vector<Window>& windows)
{
    SoakFigures f;
    if (windows.size() < 2) {
        return f;
    }
    f.baselineRss = windows.front().rssBytes;
    for (std::size_t i = 1; i < windows.size(); ++i) {
        f.peakRss = std::max(f.peakRss, windows[i].rssBytes);
    }
    f.finalRss = windows.back().rssBytes;
    f.growthKb = (static_cast<std::int64_t>(f.peakRss) - static_cast<std::int64_t>(f.baselineRss)) / 1024;
    return f;
}

std::string soakJson(const service::RunResult& run, const std::vector<Window>& windows, const SoakFigures& memory,
                     bool loaded)
{
    std::string json = "{\n  \"other_core_loaded\": " + std::string(loaded ? "true" : "false") +
                       ",\n  \"rss_baseline_kb\": " + std::to_string(memory.baselineRss / 1024) +
                       ",\n  \"rss_peak_kb\": " + std::to_string(memory.peakRss / 1024) +
                       ",\n  \"rss_growth_kb\": " + std::to_string(memory.growthKb) + ",\n  \"windows\": [";
    char line[256];
    for (std::size_t i = 0; i < windows.size(); ++i) {
        const Window& w = windows[i];
        (void)std::snprintf(line, sizeof(line),
                            "%s\n    {\"end_s\": %.1f, \"frames\": %llu, \"misses\": %llu, \"degraded\": %llu, "
                            "\"e2e_p50_ms\": %.3f, \"e2e_p99_ms\": %.3f, \"e2e_max_ms\": %.3f, \"rss_kb\": %zu}",
                            i == 0 ? "" : ",", w.endS, static_cast<unsigned long long>(w.frames),
                            static_cast<unsigned long long>(w.misses), static_cast<unsigned long long>(w.degraded),
                            w.p50Ms, w.p99Ms, w.maxMs, w.rssBytes / 1024);
        json += line;
    }
    return json + "\n  ],\n  \"service\": " + service::reportJson(run.report, run.extras) + "\n}\n";
}

struct SoakPlan {
    double minutes = 0.0;
    double rate = 0.0;
    double sampleS = 0.0;
    bool load = false;
    double maxRssGrowthKb = -1.0; ///< < 0: not checked
};

Result<SoakPlan, Error> readPlan(const Args& args)
{
    const auto minutes = args.number("minutes", 60.0, 0.5, 7 * 24 * 60.0);
    const auto rate = args.number("rate", 15.0, 1.0, 120.0);
    const auto sample = args.number("sample-s", 60.0, 1.0, 3600.0);
    const auto growth = args.number("max-rss-growth-kb", -1.0, 0.0, 1e9);
    for (const auto* value : {&minutes, &rate, &sample, &growth}) {
        if (!*value) {
            return Unexpected(value->error());
        }
    }
    const SoakPlan plan{*minutes, *rate, *sample, args.has("load-other-core"), *growth};
    if (plan.load && ::sysconf(_SC_NPROCESSORS_ONLN) < 2) {
        return Unexpected(Error{"--load-other-core", "this machine has one CPU: there is no other core to load",
                                "leave out --load-other-core"});
    }
    return plan;
}

Result<service::RunResult, Error> soakOnce(const Args& args, const SoakPlan& plan, Sampler& sampler)
{
    service::RunOptions options;
    options.appName = "ugvsense-soak";
    options.replayPath = args.get("recording");
    options.configPath = args.get("config");
    options.roudi = service::RouDiMode::Auto;
    options.replay.loop = true;
    options.replay.pace = hal::ReplayPace::Forced;
    options.replay.forcedFps = plan.rate;
    options.service.maxFrames = static_cast<std::uint64_t>(plan.minutes * 60.0 * plan.rate);
    options.service.warmupFrames = 10;
    options.pinAllTasksTo = kServiceCpu;
    options.onPublished = [&sampler](const service::PublishedFrame& frame) { sampler.onFrame(frame); };
    return service::runService(options);
}

int report(const Args& args, const SoakPlan& plan, const service::RunResult& run, const std::vector<Window>& windows)
{
    std::printf("%s%s", service::formatReport(run.report, run.extras).c_str(), service::formatBusReport(run).c_str());
    const SoakFigures memory = memoryFigures(windows);
    std::printf("soak: %.1f min at %.0f fps, tasks on CPU %d, other core %s: RSS %zu kB after warm-up (end of the "
                "first window), peak later %zu kB, at the end %zu kB: growth %" PRId64 " kB\n",
                plan.minutes, plan.rate, kServiceCpu, plan.load ? "loaded (stress-ng --cpu 1)" : "not loaded",
                memory.baselineRss / 1024, memory.peakRss / 1024, memory.finalRss / 1024, memory.growthKb);
    if (args.has("json")) {
        std::ofstream out(args.get("json"));
        out << soakJson(run, windows, memory, plan.load);
        if (!out) {
            return reportError(kSoakCommand, Error{args.get("json"), "cannot write the file", "check the folder"});
        }
    }
    if (windows.size() < 2) {
        (void)std::fprintf(stderr,
                           "ugvsense soak: only %zu window(s): no RSS growth can be measured (make --minutes "
                           "longer than two --sample-s)\n",
                           windows.size());
        return kExitTargetMissed;
    }
    if (plan.maxRssGrowthKb >= 0.0 && static_cast<double>(memory.growthKb) > plan.maxRssGrowthKb) {
        (void)std::fprintf(stderr,
                           "ugvsense soak: RSS grew %" PRId64 " kB after warm-up, above --max-rss-growth-kb %.0f\n",
                           memory.growthKb, plan.maxRssGrowthKb);
        return kExitTargetMissed;
    }
    return 0;
}

} // namespace

int runSoak(int argc, char** argv)
{
    Args args(kSoakCommand,
              "--recording REC [--minutes M] [--rate FPS] [--sample-s S] [--load-other-core] [--json OUT]\n"
              "  [--max-rss-growth-kb KB] [--config FILE]\n"
              "  Replays REC (looping) at FPS through the real service, its tasks on CPU 0, for M minutes; every S\n"
              "  seconds prints frames, deadline misses, degraded frames, end to end p50/p99/max and VmRSS. The\n"
              "  first window is the warm-up; RSS growth = the largest later RSS - the RSS at its end.\n"
              "  --load-other-core runs `stress-ng --cpu 1` on CPU 1 meanwhile. Exit 3: RSS grew more than\n"
              "  --max-rss-growth-kb, or fewer than two windows.",
              {{"recording", "REC", "the recording to replay (ugvsense sim --course default --out REC)", true},
               {"minutes", "M", "length of the soak, default 60", false},
               {"rate", "FPS", "replay rate, default 15", false},
               {"sample-s", "S", "window length, default 60 s", false},
               {"load-other-core", "", "run stress-ng --cpu 1 on CPU 1 for the whole soak", false},
               {"json", "OUT", "write the windows and the service's report as JSON", false},
               {"max-rss-growth-kb", "KB", "exit 3 when the RSS grew more than this after warm-up", false},
               {"config", "FILE", "service config (default: built-in defaults)", false}});
    if (const auto exit = parseOrExit(args, argc, argv, kSoakCommand)) {
        return *exit;
    }
    const auto plan = readPlan(args);
    if (!plan) {
        return reportUsageError(kSoakCommand, plan.error());
    }
    OtherCoreLoad load;
    if (plan->load) {
        if (auto started = load.start(kLoadCpu, plan->minutes * 60.0); !started) {
            return reportError(kSoakCommand, started.error());
        }
    }
    Sampler sampler(plan->sampleS, plan->rate);
    auto run = soakOnce(args, *plan, sampler);
    if (!run) {
        return reportError(kSoakCommand, run.error());
    }
    sampler.finish();
    if (plan->load && !load.running()) {
        return reportError(kSoakCommand, Error{"stress-ng", "the load on the other core ended before the soak did",
                                               "run `stress-ng --cpu 1 --taskset 1 --timeout 10s` alone to see why"});
    }
    return report(args, *plan, *run, sampler.windows());
}

} // namespace ugv::tool
