#pragma once

/// @file
/// A pre-scan of YAML text before any YAML parser sees it (yaml-cpp for the config, OpenCV's FileStorage for the
/// calibration). OpenCV 4.6's FileStorage has no nesting limit: a file nested some 35,000 levels (`[[[[...` or
/// `x: x: x: ...`) overflows the stack (opencv#29939), and it wraps integers modulo 2^32 (`cy: 4294967536` reads as
/// 240). yaml-cpp stops at 500 levels with the message "bad file". The scan refuses, with the line:
/// - text longer than `maxBytes`, or holding a NUL byte (not a text file);
/// - nesting deeper than `maxDepth`: block indentation levels, `key: key:` and `- -` on one line, `[` and `{` all
///   count (a calibration is 3 deep, the config 3; an over-estimate never under-counts);
/// - with `refuseWideIntegers`, a plain integer outside int32 (what OpenCV would wrap);
/// - with `openCvSubset`, what OpenCV 4.6's reader loops forever on (each found by the calibration fuzz target,
///   test/fuzz, and kept in its corpus): text after a `---` on its line (`---a: 1`, then a line `--x`), and a quoted
///   scalar that does not close on its line (`"a -.` then more lines); and what makes it allocate without bound:
///   a matrix's `rows:` or `cols:` above kMaxMatrixSide (a 51 GB matrix), or a byte that is not printable ASCII (a
///   `cols:` with bytes 0xFF before its 3 read as such a size). A calibration needs none of these.
///
/// Thread-safety: reentrant. RT-safe: no.

#include <cstddef>
#include <string>
#include <string_view>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::adapters {

/// The largest `rows:`/`cols:` of a matrix in the OpenCV subset (a calibration's are 4 at most, 14 for distortion).
inline constexpr int kMaxMatrixSide = 64;

struct YamlLimits {
    std::size_t maxBytes = 1U << 20; ///< [bytes]
    int maxDepth = 32;               ///< nesting levels
    bool refuseWideIntegers = false; ///< plain integers outside int32 are errors (for OpenCV's FileStorage)
    bool openCvSubset = false;       ///< refuse what OpenCV's FileStorage hangs on (see above)
};

/// @param[in] text   the YAML text
/// @param[in] where  the file (or recording) it came from, for messages ("where:LINE")
/// @return an error naming where, the line, what is wrong and the fix; nothing when the text is within the limits
Result<void, Error> checkYamlText(std::string_view text, const std::string& where, const YamlLimits& limits);

/// Reads a whole file of at most `maxBytes` (its size is checked before it is read).
/// @return the text, or an error naming the path (missing, not a regular file, too large, unreadable)
Result<std::string, Error> readTextFile(const std::string& path, std::size_t maxBytes, const std::string& fix);

} // namespace ugv::adapters
