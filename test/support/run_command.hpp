#pragma once

/// @file
/// Runs a command line through the shell, as the tests of the `ugvsense` tools do with the built binary.

#include <string>

namespace ugv::test {

struct CommandRun {
    int exitCode = -1;  ///< -1: it did not exit normally (a signal), or the shell could not be started
    std::string output; ///< stdout and stderr together, in the order written
};

/// Runs `commandLine` with stderr merged into stdout and waits for it.
CommandRun runCommand(const std::string& commandLine);

} // namespace ugv::test
