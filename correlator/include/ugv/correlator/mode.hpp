#pragma once

/// @file
/// The correlator's two modes and their names, parsed in one place for every caller (config file, `correlate
/// --mode`, the sweep, the live task).
///
/// Thread-safety: reentrant. RT-safe: yes.

#include <cstdint>
#include <optional>
#include <string_view>

namespace ugv::correlator {

enum class Mode : std::uint8_t {
    Original,      ///< the published MAGIC algorithm (OriginalCorrelator)
    PoseCorrected, ///< UGV pose errors estimated with the static map, statistical gates, Kalman mobiles
};

/// The names a mode is given by, for help texts and error messages.
inline constexpr std::string_view kModeNames = "pose-corrected (default) or original; improved is an alias of "
                                               "pose-corrected (its former name)";

/// @return the mode of a name: "original", "pose-corrected", or "improved" (the alias of "pose-corrected");
///         nullopt for any other.
[[nodiscard]] std::optional<Mode> parseMode(std::string_view name) noexcept;

/// The canonical name of a mode ("original", "pose-corrected"), as printed and written to JSON.
[[nodiscard]] const char* modeName(Mode mode) noexcept;

} // namespace ugv::correlator
