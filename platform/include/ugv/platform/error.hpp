#pragma once

/// @file
/// `ugv::Error`: the error type of init-time (non-real-time) operations such as loading a config or a
/// calibration. Every such error says what is wrong, where (file, key, line, device) and how to fix it.
/// Real-time code uses small `enum class` error codes instead (no strings on the frame path).
///
/// Thread-safety: value type. RT-safe: no (owns strings).

#include <string>

namespace ugv {

struct Error {
    std::string where; ///< file (and key, line or item) the problem is in
    std::string what;  ///< what is wrong, with the offending value
    std::string fix;   ///< how to fix it (may be empty when obvious)

    /// "where: what (fix: ...)" on one line, for logs and command-line tools.
    [[nodiscard]] std::string message() const
    {
        std::string text = where.empty() ? what : where + ": " + what;
        if (!fix.empty()) {
            text += " (fix: " + fix + ")";
        }
        return text;
    }
};

} // namespace ugv
