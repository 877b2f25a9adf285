#pragma once

/// @file
/// A pre-scan of YAML text before any YAML parser sees it (yaml-cpp for the config, OpenCV's FileStorage for the
/// calibration). OpenCV 4.6's FileStorage has no nesting limit: a file nested some 35,000 levels (`[[[[...` or
/// `x: x: x: ...`) overflows the stack (opencv#29939), and it wraps integers modulo 2^32 (`cy: 4294967536` reads as
/// 240). yaml-cpp stops at 500 levels with the message "bad file". The scan refuses, with the line:
/// - text longer than `maxBytes`, or holding a NUL byte (not a text file);
/// - nesting deeper than `maxDepth`: block indentation levels, `key: key:` and `- -` on one line, `[` and `{` all
///   count (a calibration is 3 deep, the config 3; an over-estimate never under-counts);
/// - with `refuseWideIntegers`, a plain integer outside int32 (what OpenCV would wrap).
///
/// Thread-safety: reentrant. RT-safe: no.

#include <cstddef>
#include <string>
#include <string_view>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::bringup {

struct YamlLimits {
    std::size_t maxBytes = 1U << 20; ///< [bytes]
    int maxDepth = 32;               ///< nesting levels
    bool refuseWideIntegers = false; ///< plain integers outside int32 are errors (for OpenCV's FileStorage)
};

/// @param[in] text   the YAML text
/// @param[in] where  the file (or recording) it came from, for messages ("where:LINE")
/// @return an error naming where, the line, what is wrong and the fix; nothing when the text is within the limits
Result<void, Error> checkYamlText(std::string_view text, const std::string& where, const YamlLimits& limits);

/// Reads a whole file of at most `maxBytes` (its size is checked before it is read).
/// @return the text, or an error naming the path (missing, not a regular file, too large, unreadable)
Result<std::string, Error> readTextFile(const std::string& path, std::size_t maxBytes, const std::string& fix);

} // namespace ugv::bringup
