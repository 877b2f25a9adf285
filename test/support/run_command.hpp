#pragma once

/// @file
/// Runs a command line through the shell, as the tests of the `ugvsense` tools do with the built binary, and reads
/// and writes the text files they take and make.

#include <filesystem>
#include <string>

namespace ugv::test {

struct CommandRun {
    int exitCode = -1;  ///< -1: it did not exit normally (a signal), or the shell could not be started
    std::string output; ///< stdout and stderr together, in the order written
};

/// Runs `commandLine` with stderr merged into stdout and waits for it.
CommandRun runCommand(const std::string& commandLine);

/// The whole file as text; empty when it cannot be read.
std::string readText(const std::filesystem::path& path);

/// Writes `text` as the whole file (a test's fixture: a failure shows in what the test then reads).
void writeText(const std::filesystem::path& path, const std::string& text);

} // namespace ugv::test
