#include "ugv/tool/args.hpp"

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <sstream>

namespace ugv::tool {

Args::Args(std::string command, std::string synopsis, std::vector<OptionSpec> options)
    : command_(std::move(command)), synopsis_(std::move(synopsis)), options_(std::move(options))
{
}

const OptionSpec* Args::find(const std::string& name) const
{
    for (const auto& option : options_) {
        if (option.name == name) {
            return &option;
        }
    }
    return nullptr;
}

Result<void, Error> Args::parse(int argc, char** argv, int first)
{
    const std::string where = "ugvsense " + command_;
    for (int i = first; i < argc; ++i) {
        std::string arg = argv[i];
        if (arg == "--help" || arg == "-h") {
            help_ = true;
            return {};
        }
        if (arg.rfind("--", 0) != 0) {
            positional_.push_back(arg);
            continue;
        }
        std::string name = arg.substr(2);
        std::optional<std::string> inlineValue;
        if (const auto eq = name.find('='); eq != std::string::npos) {
            inlineValue = name.substr(eq + 1);
            name.resize(eq);
        }
        const OptionSpec* spec = find(name);
        if (spec == nullptr) {
            return Unexpected(
                Error{where, "unknown option '--" + name + "'", "see 'ugvsense " + command_ + " --help'"});
        }
        if (spec->valueName.empty()) {
            if (inlineValue) {
                return Unexpected(Error{where, "option '--" + name + "' takes no value", ""});
            }
            values_[name] = "1";
            continue;
        }
        if (inlineValue) {
            values_[name] = *inlineValue;
        } else if (i + 1 < argc) {
            values_[name] = argv[++i];
        } else {
            return Unexpected(Error{where, "option '--" + name + "' needs a value " + spec->valueName,
                                    "write '--" + name + " " + spec->valueName + "'"});
        }
    }
    for (const auto& option : options_) {
        if (option.required && values_.count(option.name) == 0) {
            return Unexpected(Error{where, "missing required option '--" + option.name + " " + option.valueName + "'",
                                    "see 'ugvsense " + command_ + " --help'"});
        }
    }
    return {};
}

std::string Args::usage() const
{
    std::ostringstream out;
    out << "usage: ugvsense " << command_ << ' ' << synopsis_ << "\n\noptions:\n";
    for (const auto& option : options_) {
        std::string left = "  --" + option.name + (option.valueName.empty() ? "" : " " + option.valueName);
        out << left << std::string(left.size() < 28 ? 28 - left.size() : 1, ' ') << option.help
            << (option.required ? " (required)" : "") << '\n';
    }
    out << "  --help, -h                show this help\n";
    return out.str();
}

bool Args::has(const std::string& name) const
{
    return values_.count(name) != 0;
}

std::string Args::get(const std::string& name, const std::string& fallback) const
{
    const auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
}

Result<double, Error> Args::number(const std::string& name, double fallback, double min, double max) const
{
    const auto it = values_.find(name);
    if (it == values_.end()) {
        return fallback;
    }
    const std::string& text = it->second;
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(value) || value < min || value > max) {
        std::ostringstream range;
        range << "give a number in [" << min << ", " << max << "]";
        return Unexpected(Error{"ugvsense " + command_ + " --" + name, "bad value '" + text + "'", range.str()});
    }
    return value;
}

Result<double, Error> Args::wholeNumber(const std::string& name, double fallback, double min, double max) const
{
    auto value = number(name, fallback, min, max);
    if (value && std::floor(*value) != *value) {
        return Unexpected(
            Error{"ugvsense " + command_ + " --" + name, "bad value '" + get(name) + "'", "give a whole number"});
    }
    return value;
}

int reportError(const std::string& command, const Error& error)
{
    std::cerr << "ugvsense " << command << ": error: " << error.message() << '\n';
    return 1;
}

int reportUsageError(const std::string& command, const Error& error)
{
    (void)reportError(command, error);
    return 2;
}

std::optional<int> parseOrExit(Args& args, int argc, char** argv, const std::string& command, Positionals positionals)
{
    if (auto parsed = args.parse(argc, argv, 2); !parsed) {
        return reportUsageError(command, parsed.error());
    }
    if (args.helpRequested()) {
        std::cout << args.usage();
        return 0;
    }
    if (positionals == Positionals::Refused && !args.positional().empty()) {
        return reportUsageError(command,
                                Error{"ugvsense " + command, "unexpected argument '" + args.positional().front() + "'",
                                      "see 'ugvsense " + command + " --help'"});
    }
    return std::nullopt;
}

} // namespace ugv::tool
