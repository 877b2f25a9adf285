#pragma once

/// @file
/// The `ugvsense` subcommands. Each takes main's argc/argv unchanged (argv[1] is the subcommand name) and
/// returns the process exit code: 0 success, 1 failure of the job, 2 usage error.

namespace ugv::tool {

int runCalibrate(int argc, char** argv);
int runCheckConfig(int argc, char** argv);
int runRectify(int argc, char** argv);
int runSim(int argc, char** argv);
int runDetect(int argc, char** argv);
int runEval(int argc, char** argv);
int runRecording(int argc, char** argv);
int runBench(int argc, char** argv);
int runSoak(int argc, char** argv);
int runRecord(int argc, char** argv);
int runCorrelate(int argc, char** argv);
int runCorrelateSim(int argc, char** argv);
int runCorrelateEval(int argc, char** argv);
int runListen(int argc, char** argv);
int runBusSend(int argc, char** argv);

/// Bad lines of a JSON-lines input (bus-send, correlate) printed one by one; the rest are counted.
inline constexpr int kMaxReportedLines = 50;

/// The limits of the scenario options of correlate-sim and correlate-eval --sweep.
inline constexpr double kMaxScenarioDurationS = 7.0 * 24.0 * 3600.0;
inline constexpr double kMaxScenarioSeed = 1e15; ///< exact in a double (and in the truth file's JSON number)

} // namespace ugv::tool
