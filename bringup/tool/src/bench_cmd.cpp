// ugvsense bench: latency budgets. Replays a recording through the real service (iceoryx rings, the three
// fixed-priority threads where permitted) and reports per stage and end to end: p50, p90, p99, p99.9, max,
// deadline misses, drops, CPU per task, allocations after warm-up (this tool links rt's allocation counter), the
// threads and the locked memory. --sweep finds the highest rate without deadline misses.

#include <unistd.h>

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "ugv/rt/alloc_counter.hpp"
#include "ugv/service/runner.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"

namespace ugv::tool {
namespace {

constexpr const char* kBenchCommand = "bench";

/// Counts each task thread's allocations from its steady state to its end (ServiceOptions::probe).
class AllocationProbe {
public:
    AllocationProbe()
    {
        for (const char* task : {"capture", "vision", "publish"}) {
            scopes_[task] = nullptr; // no map insertion while a scope counts
            counts_[task] = 0;
        }
    }
    static void call(void* self, const char* task, service::ProbeEvent event)
    {
        auto* p = static_cast<AllocationProbe*>(self);
        if (event == service::ProbeEvent::SteadyState) {
            auto scope = std::make_unique<rt::ThreadAllocationScope>();
            const std::lock_guard<std::mutex> lock(p->mutex_);
            p->scopes_[task] = std::move(scope);
            return;
        }
        const std::lock_guard<std::mutex> lock(p->mutex_);
        auto& scope = p->scopes_[task];
        if (scope) {
            p->counts_[task] = scope->count();
            scope.reset();
        }
    }
    std::uint64_t total()
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        std::uint64_t sum = 0;
        for (const auto& [task, count] : counts_) {
            sum += count;
        }
        return sum;
    }
    std::string byTask()
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        std::string text;
        for (const auto& [task, count] : counts_) {
            text += (text.empty() ? "" : ", ") + task + " " + std::to_string(count);
        }
        return text;
    }

private:
    std::mutex mutex_;
    std::map<std::string, std::unique_ptr<rt::ThreadAllocationScope>> scopes_;
    std::map<std::string, std::size_t> counts_;
};

struct BenchRun {
    service::RunResult result;
    std::string allocationsByTask;
};

Result<BenchRun, Error> benchOnce(const std::string& recording, const std::string& config, double rate,
                                  std::uint64_t frames, bool oneCore)
{
    service::RunOptions options;
    options.appName = "ugvsense-bench";
    options.replayPath = recording;
    options.configPath = config;
    options.roudi = service::RouDiMode::Auto;
    options.replay.loop = true;
    if (rate > 0.0) {
        options.replay.pace = hal::ReplayPace::Forced;
        options.replay.forcedFps = rate;
    }
    options.service.maxFrames = frames;
    options.service.warmupFrames = 10;
    AllocationProbe probe;
    options.service.probe = &AllocationProbe::call;
    options.service.probeContext = &probe;
    options.pinAllTasksTo = oneCore ? 0 : -1;
    auto run = service::runService(options);
    if (!run) {
        return Unexpected(run.error());
    }
    BenchRun out{std::move(*run), probe.byTask()};
    out.result.extras.allocationsAfterWarmup = probe.total();
    return out;
}

/// A number after `"key": ` in a JSON text (the bench's own), or -1.
double jsonValue(const std::string& json, const std::string& key, std::size_t from = 0)
{
    const std::size_t at = json.find("\"" + key + "\": ", from);
    double value = -1.0;
    if (at != std::string::npos) {
        const char* first = json.data() + at + key.size() + 4;
        (void)std::from_chars(first, json.data() + json.size(), value); // stays -1 when no number follows
    }
    return value;
}

/// --sweep: one child process per rate (iceoryx's runtime is one per process), each writing its JSON report.
int sweep(const Args& args, std::uint64_t frames, bool oneCore)
{
    double best = 0.0;
    std::printf("rate_fps  frames  misses  drops  degraded  e2e_p50_ms  e2e_p99_ms  e2e_max_ms\n");
    const std::string json =
        std::filesystem::temp_directory_path() / ("ugvsense-sweep-" + std::to_string(::getpid()) + ".json");
    std::error_code ec;
    const std::string self = std::filesystem::read_symlink("/proc/self/exe", ec).string(); // this ugvsense binary
    if (ec) {
        return reportError(kBenchCommand, Error{"/proc/self/exe", "cannot find this program: " + ec.message(),
                                                "run it from its path"});
    }
    for (const int r : {10, 15, 20, 25, 30}) {
        std::string command = "'" + self + "' bench --recording '" + args.get("recording") + "' --rate " +
                              std::to_string(r) + " --frames " + std::to_string(frames) + " --json '" + json + "'";
        if (oneCore) {
            command += " --one-core";
        }
        if (args.has("config")) {
            command += " --config '" + args.get("config") + "'";
        }
        const std::string log = json + ".log";
        command += " >'" + log + "' 2>&1";
        if (std::system(command.c_str()) != 0) { // NOLINT(cert-env33-c): our own binary, quoted arguments
            std::ifstream failed(log);
            const std::string output{std::istreambuf_iterator<char>(failed), std::istreambuf_iterator<char>()};
            (void)std::fprintf(stderr, "%s", output.substr(output.size() > 4000 ? output.size() - 4000 : 0).c_str());
            return reportError(kBenchCommand,
                               Error{"ugvsense bench --sweep",
                                     "the run at " + std::to_string(r) + " fps failed (its output above)",
                                     "run it alone: ugvsense bench --recording REC --rate " + std::to_string(r)});
        }
        std::filesystem::remove(log);
        std::ifstream in(json);
        const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
        const std::size_t e2e = text.find("\"end_to_end\"");
        const double misses = jsonValue(text, "deadline_misses");
        const double drops = jsonValue(text, "drops");
        std::printf("%8d  %6.0f  %6.0f  %5.0f  %8.0f  %10.1f  %10.1f  %10.1f\n", r, jsonValue(text, "frames"), misses,
                    drops, jsonValue(text, "degraded"), jsonValue(text, "p50_us", e2e) / 1000.0,
                    jsonValue(text, "p99_us", e2e) / 1000.0, jsonValue(text, "max_us", e2e) / 1000.0);
        if (misses == 0.0 && drops == 0.0) {
            best = r;
        }
    }
    std::filesystem::remove(json);
    std::printf("highest rate without a deadline miss or a drop: %s\n",
                best > 0.0 ? (std::to_string(static_cast<int>(best)) + " fps").c_str() : "none of the rates");
    return 0;
}

} // namespace

int runBench(int argc, char** argv)
{
    Args args(
        kBenchCommand,
        "--recording REC [--rate FPS] [--frames N] [--json OUT] [--one-core] [--sweep] [--config FILE]\n"
        "  Replays REC (looping) through the real service: iceoryx rings (a running RouDi, else one inside this\n"
        "  process), capture/vision/publish threads at their configured priorities where permitted. Reports\n"
        "  per stage and end to end (exposure stamp to sectors published) p50/p90/p99/p99.9/max, deadline\n"
        "  misses (deadline = 1/rate), drops, CPU per task, allocations after warm-up, threads, locked memory.\n"
        "  --sweep: rates 10, 15, 20, 25, 30 fps, N frames each; prints the highest rate without a miss.",
        {{"recording", "REC", "the recording to replay (ugvsense sim --course default --out REC)", true},
         {"rate", "FPS", "replay rate, default: the recorded pace", false},
         {"frames", "N", "frames to publish, default 300", false},
         {"json", "OUT", "write the report as JSON (frames, deadline_misses, drops, end_to_end, stages, ...)", false},
         {"one-core", "", "pin the three tasks to CPU 0 (the one-core budget)", false},
         {"sweep", "", "find the highest rate without deadline misses", false},
         {"config", "FILE", "service config (default: built-in defaults)", false}});
    if (const auto exit = parseOrExit(args, argc, argv, kBenchCommand)) {
        return *exit;
    }
    const auto rate = args.number("rate", 0.0, 0.0, 1000.0);
    const auto frames = args.number("frames", 300, 20, 1e9);
    for (const auto* value : {&rate, &frames}) {
        if (!*value) {
            return reportUsageError(kBenchCommand, value->error());
        }
    }
    const bool oneCore = args.has("one-core");
    if (args.has("sweep")) {
        return sweep(args, static_cast<std::uint64_t>(*frames), oneCore);
    }
    auto run =
        benchOnce(args.get("recording"), args.get("config"), *rate, static_cast<std::uint64_t>(*frames), oneCore);
    if (!run) {
        return reportError(kBenchCommand, run.error());
    }
    std::printf("%s%s", service::formatReport(run->result.report, run->result.extras).c_str(),
                service::formatBusReport(run->result).c_str());
    std::printf("allocations after warm-up by task: %s (0 expected; with stereo.mode an OpenCV mode, vision "
                "counts StereoSGBM::compute's own, see vision/roi_matcher.hpp)\n",
                run->allocationsByTask.c_str());
    if (args.has("json")) {
        std::ofstream out(args.get("json"));
        out << service::reportJson(run->result.report, run->result.extras);
        if (!out) {
            return reportError(kBenchCommand, Error{args.get("json"), "cannot write the file", "check the folder"});
        }
        std::printf("wrote %s\n", args.get("json").c_str());
    }
    return 0;
}

} // namespace ugv::tool
