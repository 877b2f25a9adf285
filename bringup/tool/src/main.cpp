// ugvsense: the command-line tool (calibration, config checks, simulation; later detection, evaluation,
// recording, benchmarks, correlation). The service itself is ugvsensed.

#include <cstring>
#include <iostream>

#include "ugv/platform/cpu_level.hpp"
#include "ugv/tool/commands.hpp"

namespace {

struct Subcommand {
    const char* name;
    const char* summary;
    int (*run)(int argc, char** argv);
};

constexpr Subcommand kSubcommands[] = {
    {"calibrate", "calibrate a stereo rig from chessboard image pairs", ugv::tool::runCalibrate},
    {"check-config", "validate a service config file and print the effective config", ugv::tool::runCheckConfig},
    {"rectify", "rectify image pairs with a calibration and report the row alignment", ugv::tool::runRectify},
    {"sim", "generate synthetic stereo data (chessboard pairs for calibration)", ugv::tool::runSim},
    {"detect", "detect obstacles in one stereo pair (sectors, JSON, overlay)", ugv::tool::runDetect},
    {"eval", "evaluate detection on simulator scenes and matching on Middlebury data", ugv::tool::runEval},
    {"recording", "inspect, import (PNG pairs) and export recordings", ugv::tool::runRecording},
    {"record", "record the frames the running service publishes (low priority, crash-safe)", ugv::tool::runRecord},
    {"correlate", "fuse OOI observations of many UGVs into one object list (JSON lines in and out)",
     ugv::tool::runCorrelate},
    {"correlate-sim", "simulate UGVs reporting OOIs (correlator input) and write the ground truth",
     ugv::tool::runCorrelateSim},
    {"correlate-eval", "score correlator snapshots against correlate-sim truth (GOSPA, ID changes)",
     ugv::tool::runCorrelateEval},
    {"listen", "print the samples of one DDS topic live, one JSON line each (field debugging)", ugv::tool::runListen},
    {"bus-send", "publish correlator input files, hostile samples or test poses on the DDS bus", ugv::tool::runBusSend},
    {"bench", "latency budget: replay a recording through the real service and report p50..max", ugv::tool::runBench},
    {"soak", "the service for an hour (or M minutes) with the other core loaded: latency and RSS sampled",
     ugv::tool::runSoak},
};

void printHelp(std::ostream& out)
{
    out << "usage: ugvsense SUBCOMMAND [options]   (ugvsense SUBCOMMAND --help for its options)\n\nsubcommands:\n";
    for (const auto& sub : kSubcommands) {
        out << "  " << sub.name << std::string(16 - std::strlen(sub.name), ' ') << sub.summary << '\n';
    }
}

// First, before the static initialisers of our own code (priority 101 runs before the default): a CPU without the
// instruction set this build is for (UGV_CPU) gets a clear error instead of SIGILL.
[[gnu::constructor(101)]] void checkCpuFirst()
{
    ugv::exitUnlessCpuRunsBuild("ugvsense");
}

} // namespace

int main(int argc, char** argv)
{
    if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
        printHelp(argc < 2 ? std::cerr : std::cout);
        return argc < 2 ? 2 : 0;
    }
    for (const auto& sub : kSubcommands) {
        if (std::strcmp(argv[1], sub.name) == 0) {
            return sub.run(argc, argv);
        }
    }
    std::cerr << "ugvsense: error: unknown subcommand '" << argv[1] << "' (fix: run 'ugvsense --help' for the list)\n";
    return 2;
}
