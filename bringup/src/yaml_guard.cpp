#include "ugv/bringup/yaml_guard.hpp"

#include <cctype>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

namespace ugv::bringup {
namespace {

constexpr const char* kDamagedFix = "check that this is the right file; if it is, it is damaged: write it again";

bool isBlank(char c)
{
    return c == ' ' || c == '\t' || c == '\r';
}

bool isDigit(char c)
{
    return std::isdigit(static_cast<unsigned char>(c)) != 0;
}

/// The index of the quote that closes the one at `open` (the line's end when there is none on this line).
std::size_t closingQuote(std::string_view line, std::size_t open)
{
    const char quote = line[open];
    for (std::size_t i = open + 1; i < line.size(); ++i) {
        if (quote == '"' && line[i] == '\\') {
            ++i;
        } else if (line[i] == quote) {
            return i;
        }
    }
    return line.size();
}

/// A plain integer token (optional sign, digits only) outside int32.
bool isWideInteger(std::string_view token)
{
    std::size_t i = token.front() == '-' || token.front() == '+' ? 1 : 0;
    if (i == token.size()) {
        return false;
    }
    for (std::size_t k = i; k < token.size(); ++k) {
        if (!isDigit(token[k])) {
            return false;
        }
    }
    while (i + 1 < token.size() && token[i] == '0') {
        ++i;
    }
    const std::string_view digits = token.substr(i);
    const std::string_view limit = token.front() == '-' ? "2147483648" : "2147483647";
    return digits.size() > limit.size() || (digits.size() == limit.size() && digits > limit);
}

class Scanner {
public:
    Scanner(std::string where, const YamlLimits& limits) : where_(std::move(where)), limits_(limits) {}

    Result<void, Error> line(std::string_view text, std::size_t number)
    {
        number_ = number;
        if (text.find('\0') != std::string_view::npos) {
            return fail("holds a NUL byte: not a YAML text file", kDamagedFix);
        }
        const std::size_t indent = text.find_first_not_of(" \t\r");
        if (indent == std::string_view::npos || text[indent] == '#') {
            return {};
        }
        if (flow_ == 0) { // a block line: its indentation is one level below every smaller one before it
            while (!indents_.empty() && indents_.back() >= indent) {
                indents_.pop_back();
            }
            indents_.push_back(indent);
        }
        int inlineLevels = 0;
        bool indicatorsOnly = true; // only "- " so far on this line
        for (std::size_t i = indent; i < text.size(); ++i) {
            const char c = text[i];
            const bool endsToken = i + 1 == text.size() || isBlank(text[i + 1]);
            const bool startsToken =
                i == indent || isBlank(text[i - 1]) || std::string_view("[{,").find(text[i - 1]) != npos;
            // A quote opens a quoted scalar only at a token's start ("x'y" is plain text: what follows still counts).
            if ((c == '"' || c == '\'') && startsToken) {
                i = closingQuote(text, i);
                indicatorsOnly = false;
                continue;
            }
            if (c == '#' && (i == 0 || isBlank(text[i - 1]))) {
                break;
            }
            if (c == '[' || c == '{') {
                ++flow_;
            } else if (c == ']' || c == '}') {
                flow_ = flow_ > 0 ? flow_ - 1 : 0;
            } else if (c == ':' && flow_ == 0 && endsToken) {
                ++inlineLevels;
            } else if (c == '-' && indicatorsOnly && endsToken) {
                ++inlineLevels;
                continue;
            } else if (limits_.refuseWideIntegers && (isDigit(c) || c == '-' || c == '+') &&
                       (startsToken || text[i - 1] == ':')) {
                std::size_t end = i + 1;
                while (end < text.size() && (std::isalnum(static_cast<unsigned char>(text[end])) != 0 ||
                                             std::string_view("._+-").find(text[end]) != npos)) {
                    ++end;
                }
                if (isWideInteger(text.substr(i, end - i))) {
                    return fail("integer " + std::string(text.substr(i, end - i)) +
                                    " does not fit in 32 bits (OpenCV would read it modulo 2^32)",
                                "write the value it should have; " + std::string(kDamagedFix));
                }
                i = end - 1;
            }
            if (!isBlank(c)) {
                indicatorsOnly = false;
            }
            if (static_cast<int>(indents_.size()) + inlineLevels + flow_ > limits_.maxDepth) {
                return fail("nested deeper than " + std::to_string(limits_.maxDepth) +
                                " levels (brackets, braces, 'key: key:' or indentation); a valid file is a few levels "
                                "deep",
                            kDamagedFix);
            }
        }
        return {};
    }

private:
    static constexpr std::size_t npos = std::string_view::npos;

    Unexpected<Error> fail(const std::string& what, const std::string& fix) const
    {
        return Unexpected(Error{where_ + ":" + std::to_string(number_), what, fix});
    }

    std::string where_;
    YamlLimits limits_;
    std::size_t number_ = 0;
    int flow_ = 0;                     ///< open [ and { (across lines)
    std::vector<std::size_t> indents_; ///< the indentation of the enclosing block lines
};

} // namespace

Result<void, Error> checkYamlText(std::string_view text, const std::string& where, const YamlLimits& limits)
{
    if (text.size() > limits.maxBytes) {
        return Unexpected(Error{where,
                                "the text is " + std::to_string(text.size()) + " bytes, more than the " +
                                    std::to_string(limits.maxBytes) + " a valid file can have",
                                kDamagedFix});
    }
    Scanner scanner(where, limits);
    std::size_t number = 1;
    for (std::size_t start = 0; start <= text.size(); ++number) {
        std::size_t end = text.find('\n', start);
        if (end == std::string_view::npos) {
            end = text.size();
        }
        if (auto ok = scanner.line(text.substr(start, end - start), number); !ok) {
            return ok;
        }
        start = end + 1;
    }
    return {};
}

Result<std::string, Error> readTextFile(const std::string& path, std::size_t maxBytes, const std::string& fix)
{
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        return Unexpected(Error{path, "file not found or not a regular file", fix});
    }
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec || size > maxBytes) {
        return Unexpected(Error{path,
                                "the file is " + std::to_string(size) + " bytes, more than the " +
                                    std::to_string(maxBytes) + " a valid file can have",
                                kDamagedFix});
    }
    std::ifstream in(path, std::ios::binary);
    std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (!in && !in.eof()) {
        return Unexpected(Error{path, "cannot read the file", "check its permissions"});
    }
    return text;
}

} // namespace ugv::bringup
