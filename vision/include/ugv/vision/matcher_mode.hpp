#pragma once

/// @file
/// The stereo matcher's modes and their names, parsed in one place for every caller (config `stereo.mode`,
/// `ugvsense eval --matcher`). No OpenCV here, so that the config can hold a mode without the matcher's headers.
///
/// Thread-safety: reentrant. RT-safe: yes.

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <utility>

namespace ugv::vision {

/// The matcher (config stereo.mode): ours, or an OpenCV StereoSGBM mode.
enum class MatcherMode : std::uint8_t {
    CensusSgm, ///< census 9x7 + 5-path SGM (census_sgm.hpp): no allocation per frame
    Sgbm,      ///< MODE_SGBM: 5 paths, single pass
    Sgbm3Way,  ///< MODE_SGBM_3WAY: 3 paths, faster (measured 28 vs 37 ms on 640x242)
    Hh4,       ///< MODE_HH4: 8 paths with 4-way full-image passes, slowest
};

/// Every mode with its name, in the order of the enum (the order `check-config` lists them in).
inline constexpr std::array<std::pair<std::string_view, MatcherMode>, 4> kMatcherModes{{
    {"census_sgm", MatcherMode::CensusSgm},
    {"sgbm", MatcherMode::Sgbm},
    {"sgbm_3way", MatcherMode::Sgbm3Way},
    {"hh4", MatcherMode::Hh4},
}};

/// The names a mode is given by, for help texts and error messages (default first, then fastest first).
inline constexpr std::string_view kMatcherModeNames = "census_sgm, sgbm_3way, sgbm or hh4";

/// @return the mode of a name in kMatcherModes; nullopt for any other.
[[nodiscard]] constexpr std::optional<MatcherMode> parseMatcherMode(std::string_view name) noexcept
{
    for (const auto& [modeName, mode] : kMatcherModes) {
        if (modeName == name) {
            return mode;
        }
    }
    return std::nullopt;
}

/// The name of a mode ("census_sgm", "sgbm", "sgbm_3way", "hh4"), as parsed and printed.
[[nodiscard]] constexpr std::string_view matcherModeName(MatcherMode mode) noexcept
{
    for (const auto& [modeName, value] : kMatcherModes) {
        if (value == mode) {
            return modeName;
        }
    }
    return "?";
}

} // namespace ugv::vision
