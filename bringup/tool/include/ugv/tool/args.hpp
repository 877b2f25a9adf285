#pragma once

/// @file
/// A small command-line parser for the `ugvsense` subcommands: `--name value`, `--name=value`, `--flag`,
/// `--help`/`-h`. Unknown options, missing values and missing required options are errors that name the
/// option and point at `--help`. Init-time only (allocates).

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::tool {

struct OptionSpec {
    std::string name;      ///< without the leading "--"
    std::string valueName; ///< empty for a flag
    std::string help;
    bool required = false;
};

class Args {
public:
    Args(std::string command, std::string synopsis, std::vector<OptionSpec> options);

    /// Parses argv[first..argc). Positional arguments are collected in order.
    Result<void, Error> parse(int argc, char** argv, int first);

    [[nodiscard]] bool helpRequested() const { return help_; }
    [[nodiscard]] std::string usage() const;
    [[nodiscard]] bool has(const std::string& name) const;
    [[nodiscard]] std::string get(const std::string& name, const std::string& fallback = {}) const;
    [[nodiscard]] const std::vector<std::string>& positional() const { return positional_; }
    /// The option as a finite number within [min, max].
    Result<double, Error> number(const std::string& name, double fallback, double min, double max) const;
    /// As number(), and a whole number (a count, a seed).
    Result<double, Error> wholeNumber(const std::string& name, double fallback, double min, double max) const;

private:
    const OptionSpec* find(const std::string& name) const;

    std::string command_;
    std::string synopsis_;
    std::vector<OptionSpec> options_;
    std::map<std::string, std::string> values_;
    std::vector<std::string> positional_;
    bool help_ = false;
};

/// Prints `error.message()` prefixed with "ugvsense COMMAND: error: " to stderr; returns the exit code 2
/// for usage errors, which callers return from main.
int reportUsageError(const std::string& command, const Error& error);

/// Prints `error.message()` prefixed with "ugvsense COMMAND: error: " to stderr; returns the exit code 1 of a
/// subcommand that failed at run time (bad input, a device or file it could not use).
int reportError(const std::string& command, const Error& error);

/// Whether a subcommand takes positional arguments (a TOPIC, an action) besides its options.
enum class Positionals : bool { Refused, Allowed };

/// The opening of a subcommand: parses argv[2..], prints the usage for --help, rejects positional arguments unless
/// they are allowed.
/// @return the exit code to return now (0 after --help, 2 on a usage error), or nothing to go on.
std::optional<int> parseOrExit(Args& args, int argc, char** argv, const std::string& command,
                               Positionals positionals = Positionals::Refused);

} // namespace ugv::tool
