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

} // namespace ugv::tool
