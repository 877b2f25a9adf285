#include "ugv/adapters/yaml_guard.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace ugv::adapters {
namespace {

constexpr const char* kDamagedFix = "check that this is the right file; if it is, it is damaged: write it again";
constexpr const char* kCalibrationShape =
    "a calibration is 'key: value' lines, matrices as 'ugvsense calibrate' writes them, and one-line maps "
    "(README, \"Calibrating a stereo rig\"); write it again in that form";

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
        if (auto scanned = scanLine(text); !scanned) {
            return scanned;
        }
        return limits_.openCvSubset ? openCvLine(text.substr(0, text.find_last_not_of('\r') + 1))
                                    : Result<void, Error>{};
    }

private:
    static constexpr std::size_t kNpos = std::string_view::npos;

    /// Size, NUL, nesting depth and wide integers (every YAML), and quotes that stay open (openCvSubset).
    Result<void, Error> scanLine(std::string_view text)
    {
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
                i == indent || isBlank(text[i - 1]) || std::string_view("[{,").find(text[i - 1]) != kNpos;
            // A quote opens a quoted scalar only at a token's start ("x'y" is plain text: what follows still counts).
            if ((c == '"' || c == '\'') && startsToken) {
                const std::size_t open = i;
                i = closingQuote(text, i);
                if (limits_.openCvSubset && i == text.size()) {
                    return fail(std::string("the quoted text at column ") + std::to_string(open + 1) +
                                    " does not end on its line (OpenCV's reader can loop forever on it)",
                                "close the quote on the same line; " + std::string(kDamagedFix));
                }
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
                                             std::string_view("._+-").find(text[end]) != kNpos)) {
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

    /// The checks of YamlLimits::openCvSubset that look at a whole line: printable ASCII, the line shapes of a
    /// calibration, matrix sizes.
    Result<void, Error> openCvLine(std::string_view text)
    {
        for (std::size_t i = 0; i < text.size(); ++i) {
            const auto byte = static_cast<unsigned char>(text[i]);
            if ((byte < 0x20U && byte != '\t' && byte != '\r') || byte >= 0x7FU) {
                char hex[8];
                (void)std::snprintf(hex, sizeof(hex), "0x%02X", byte);
                return fail(std::string("byte ") + hex + " at column " + std::to_string(i + 1) +
                                " is not printable ASCII (a calibration is ASCII text)",
                            kDamagedFix);
            }
        }
        std::string_view line = withoutComment(text);
        while (!line.empty() && isBlank(line.back())) {
            line.remove_suffix(1);
        }
        const std::size_t start = line.find_first_not_of(" \t");
        if (start == kNpos) {
            return {};
        }
        line.remove_prefix(start);
        if (inFlowSequence_) { // the numbers of a matrix's data, over several lines
            return flowSequenceRest(line);
        }
        if (start == 0 && line.rfind("---", 0) == 0 && line != "---") {
            return fail("text after the document start '---' on its line (OpenCV's reader can loop forever on it)",
                        "put '---' on a line of its own; " + std::string(kDamagedFix));
        }
        if (start == 0 && (line == "---" || line.rfind("%YAML:", 0) == 0)) {
            return {};
        }
        std::size_t key = 0;
        while (key < line.size() && (std::isalnum(static_cast<unsigned char>(line[key])) != 0 || line[key] == '_')) {
            ++key;
        }
        if (key == 0 || key == line.size() || line[key] != ':' || (key + 1 < line.size() && line[key + 1] != ' ')) {
            return fail("'" + std::string(line) + "' is not a 'key: value' line of a calibration", kCalibrationShape);
        }
        const std::string_view name = line.substr(0, key);
        std::string_view value = line.substr(key + 1);
        value.remove_prefix(std::min(value.size(), value.find_first_not_of(' ')));
        if (value.empty() || value == "!!opencv-matrix" || isPlain(value) || isQuoted(value) || isFlowMap(value)) {
            if ((name == "rows" || name == "cols") && !isMatrixSide(value)) {
                return fail("matrix size '" + std::string(line) + "' is not a number up to " +
                                std::to_string(kMaxMatrixSide) + " (a calibration's matrices are 4 x 4 at most)",
                            kDamagedFix);
            }
            return {};
        }
        if (value.front() == '[') {
            inFlowSequence_ = true;
            return flowSequenceRest(value.substr(1));
        }
        return fail("the value of '" + std::string(name) +
                        "' is not a number, word, quoted text, matrix or "
                        "one-line { key: value } map",
                    kCalibrationShape);
    }

    /// The rest of a flow sequence of numbers: numbers and commas, up to its ']' (then nothing).
    Result<void, Error> flowSequenceRest(std::string_view rest)
    {
        for (std::size_t i = 0; i < rest.size(); ++i) {
            const char c = rest[i];
            if (c == ']') {
                inFlowSequence_ = false;
                if (rest.find_first_not_of(' ', i + 1) != kNpos) {
                    return fail("text after a matrix's closing ']'", kCalibrationShape);
                }
                return {};
            }
            if (!(isNumberChar(c) || c == ',' || isBlank(c))) {
                return fail(std::string("'") + c + "' in a matrix's data (numbers and commas only)", kCalibrationShape);
            }
        }
        return {};
    }

    static bool isNumberChar(char c)
    {
        return isDigit(c) || std::string_view("+-.eEinfatINFAT").find(c) != kNpos; // also .nan and .inf
    }
    static bool isPlain(std::string_view v)
    {
        return std::all_of(v.begin(), v.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) != 0 || std::string_view("_.+-").find(c) != kNpos;
        });
    }
    static bool isQuoted(std::string_view v)
    {
        return v.size() >= 2 && (v.front() == '"' || v.front() == '\'') && closingQuote(v, 0) == v.size() - 1;
    }
    /// `{ key: value, key: value }` on one line, plain keys and values.
    static bool isFlowMap(std::string_view v)
    {
        if (v.size() < 2 || v.front() != '{' || v.back() != '}') {
            return false;
        }
        std::string_view items = v.substr(1, v.size() - 2);
        while (!items.empty()) {
            const std::size_t comma = items.find(',');
            std::string_view item = items.substr(0, comma);
            const std::size_t colon = item.find(": ");
            const auto trim = [](std::string_view t) {
                const std::size_t b = t.find_first_not_of(' ');
                return b == kNpos ? std::string_view() : t.substr(b, t.find_last_not_of(' ') - b + 1);
            };
            if (colon == kNpos || trim(item.substr(0, colon)).empty() || !isPlain(trim(item.substr(0, colon))) ||
                trim(item.substr(colon + 2)).empty() || !isPlain(trim(item.substr(colon + 2)))) {
                return false;
            }
            items = comma == kNpos ? std::string_view() : items.substr(comma + 1);
        }
        return true;
    }
    static bool isMatrixSide(std::string_view v)
    {
        return !v.empty() && v.size() <= 2 && std::all_of(v.begin(), v.end(), isDigit) &&
               std::stoi(std::string(v)) <= kMaxMatrixSide;
    }
    /// The line without a trailing comment (a '#' after a blank, outside quotes).
    static std::string_view withoutComment(std::string_view text)
    {
        for (std::size_t i = 0; i < text.size(); ++i) {
            if ((text[i] == '"' || text[i] == '\'') && (i == 0 || isBlank(text[i - 1]))) {
                i = closingQuote(text, i);
            } else if (text[i] == '#' && (i == 0 || isBlank(text[i - 1]))) {
                return text.substr(0, i);
            }
        }
        return text;
    }

    Unexpected<Error> fail(const std::string& what, const std::string& fix) const
    {
        return Unexpected(Error{where_ + ":" + std::to_string(number_), what, fix});
    }

    std::string where_;
    YamlLimits limits_;
    std::size_t number_ = 0;
    int flow_ = 0;                     ///< open [ and { (across lines)
    bool inFlowSequence_ = false;      ///< openCvSubset: inside a matrix's data [ ... ] (across lines)
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

} // namespace ugv::adapters
