// ugvsensed: the real-time stereo obstacle service. See runner.hpp for one run and service.hpp for the threads.

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>

#include "ugv/platform/cpu_level.hpp"
#include "ugv/platform/log.hpp"
#include "ugv/service/runner.hpp"

namespace {

std::atomic<bool> gStop{false}; // NOLINT(cppcoreguidelines-avoid-non-const-global-variables): the signal handler's flag

void onSignal(int /*signal*/)
{
    gStop.store(true);
}

void usage(std::FILE* out)
{
    (void)std::fprintf(
        out, "usage: ugvsensed [--config FILE] [--replay REC] [options]\n"
             "  Runs the stereo obstacle service: capture -> iceoryx frame ring -> rectify + detect -> sectors on\n"
             "  iceoryx (ugvsense/obstacles/sectors) and on DDS (ugvsense/sectors, ROS 2 rt/<ns>/obstacle_scan and\n"
             "  rt/<ns>/negative_obstacles, ugvsense/health), and the OOI correlator when the config enables it\n"
             "  (vision.enabled: false runs only the correlator: a ground station). Stops at the end of the\n"
             "  recording, after --frames, or on SIGINT/SIGTERM, and prints the latency report.\n"
             "  $UGV_DDS_DOMAIN overrides dds.domain_id; without either, ROS 2's $ROS_DOMAIN_ID is the domain.\n\n"
             "options:\n"
             "  --config FILE      service config (default: built-in defaults; see ugvsense check-config)\n"
             "  --replay REC       replay a recording (ugvsense sim --course, recording import, record)\n"
             "  --calib FILE       calibration (default: the one stored in the recording)\n"
             "  --rate FPS         replay at this rate instead of the recorded pace\n"
             "  --fast             replay as fast as possible (the vision queue keeps the latest frame)\n"
             "  --loop             replay the recording over and over\n"
             "  --frames N         stop after N published frames\n"
             "  --print-every N    print a sector summary every N frames (default 10, 0 = none)\n"
             "  --embedded-roudi   run RouDi inside this process (no iox-roudi on this machine)\n"
             "  --wait-roudi S     wait up to S seconds for a RouDi that is still starting (systemd units)\n"
             "  --help             this text\n");
}

bool parseNumber(const char* text, double min, double max, double& out)
{
    char* end = nullptr;
    out = std::strtod(text, &end);
    return end != text && *end == '\0' && out >= min && out <= max;
}

// First, before the static initialisers of our own code (priority 101 runs before the default): a CPU without the
// instruction set this build is for (UGV_CPU) gets a clear error instead of SIGILL.
[[gnu::constructor(101)]] void checkCpuFirst()
{
    ugv::exitUnlessCpuRunsBuild("ugvsensed");
}

/// Reads the command line into `options`; the exit code when the process should end here (--help, a bad option).
std::optional<int> parseArgs(int argc, char** argv, ugv::service::RunOptions& options)
{
    constexpr std::array<std::string_view, 7> kTakesValue{"--config", "--replay",      "--calib",     "--rate",
                                                          "--frames", "--print-every", "--wait-roudi"};
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (i + 1 >= argc && std::find(kTakesValue.begin(), kTakesValue.end(), arg) != kTakesValue.end()) {
            (void)std::fprintf(stderr, "ugvsensed: error: %s needs a value (fix: see ugvsensed --help)\n", arg.c_str());
            return 2;
        }
        const auto value = [&]() -> const char* { return argv[++i]; }; // present: checked above
        double number = 0.0;
        if (arg == "--help" || arg == "-h") {
            usage(stdout);
            return 0;
        } else if (arg == "--config") {
            options.configPath = value();
        } else if (arg == "--replay") {
            options.replayPath = value();
        } else if (arg == "--calib") {
            options.calibrationPath = value();
        } else if (arg == "--rate") {
            if (!parseNumber(value(), 0.1, 1000.0, number)) {
                (void)std::fprintf(stderr, "ugvsensed: error: --rate: '%s' is not a rate in 0.1..1000 fps\n", argv[i]);
                return 2;
            }
            options.replay.pace = ugv::hal::ReplayPace::Forced;
            options.replay.forcedFps = number;
        } else if (arg == "--fast") {
            options.replay.pace = ugv::hal::ReplayPace::AsFastAsPossible;
        } else if (arg == "--loop") {
            options.replay.loop = true;
        } else if (arg == "--frames") {
            if (!parseNumber(value(), 1, 1e12, number)) {
                (void)std::fprintf(stderr, "ugvsensed: error: --frames: '%s' is not a positive count\n", argv[i]);
                return 2;
            }
            options.service.maxFrames = static_cast<std::uint64_t>(number);
        } else if (arg == "--print-every") {
            if (!parseNumber(value(), 0, 1e9, number)) {
                (void)std::fprintf(stderr, "ugvsensed: error: --print-every: '%s' is not a count\n", argv[i]);
                return 2;
            }
            options.printEvery = static_cast<int>(number);
        } else if (arg == "--wait-roudi") {
            if (!parseNumber(value(), 0, 600, number)) {
                (void)std::fprintf(stderr, "ugvsensed: error: --wait-roudi: '%s' is not a time in 0..600 s\n", argv[i]);
                return 2;
            }
            options.roudiWait = std::chrono::milliseconds(static_cast<std::int64_t>(number * 1000.0));
        } else if (arg == "--embedded-roudi") {
            options.roudi = ugv::service::RouDiMode::Embedded;
        } else {
            (void)std::fprintf(stderr, "ugvsensed: error: unknown option '%s' (fix: see ugvsensed --help)\n",
                               arg.c_str());
            return 2;
        }
    }
    return std::nullopt;
}

} // namespace

int main(int argc, char** argv)
{
    ugv::service::RunOptions options;
    options.printEvery = 10;
    if (const auto exit = parseArgs(argc, argv, options)) {
        return *exit;
    }
    struct sigaction action {};
    action.sa_handler = onSignal;
    ::sigaction(SIGINT, &action, nullptr);
    ::sigaction(SIGTERM, &action, nullptr);
    options.stop = &gStop;

    auto run = ugv::service::runService(options);
    if (!run) {
        // Under systemd "<3>" makes it an error-priority journal entry (platform/log.hpp).
        (void)std::fprintf(stderr, "%sugvsensed: error: %s\n", ugv::journalPrefix(ugv::LogLevel::Error),
                           run.error().message().c_str());
        return 1;
    }
    if (run->visionRan) {
        std::printf("%s", ugv::service::formatReport(run->report, run->extras).c_str());
    }
    std::printf("%s", ugv::service::formatBusReport(*run).c_str());
    if (run->roudiLost) {
        (void)std::fprintf(
            stderr,
            "%sugvsensed: error: iceoryx: RouDi went away during the run (nothing answers on /tmp/roudi); "
            "the service stopped (fix: restart RouDi, then the service; under systemd the units do "
            "both)\n",
            ugv::journalPrefix(ugv::LogLevel::Error));
        (void)std::fflush(nullptr);
        std::_Exit(1); // iceoryx's runtime would wait for the missing RouDi at exit
    }
    return 0;
}
