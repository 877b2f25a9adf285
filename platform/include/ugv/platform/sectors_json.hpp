#pragma once

/// @file
/// The sectors as JSON text, written once for every file and report that holds them (`ugvsense detect --json`, the
/// simulator's `<stem>_sectors.json`): per sector `bearing_min_deg`, `bearing_max_deg`, `range_m`, `kind`, `state`,
/// `class`, `height_m`, `confidence`; a number that is not finite (an infinite range: nothing measured there) is
/// `null`; and the number and string helpers of the tools' JSON reports. Not for the frame path (it allocates).

#include <string>

#include "ugv/platform/obstacle_sectors.hpp"

namespace ugv {

/// "unknown", "clear", "obstacle".
const char* stateName(SectorState state) noexcept;
/// "none", "positive", "negative".
const char* kindName(ObstacleKind kind) noexcept;
/// "unknown", "green", "blue", "red".
const char* className(DangerClass danger) noexcept;

/// `value` with 6 significant digits (printf's %.6g), or null when it is not finite.
std::string jsonNumber(double value);

/// `text` as a JSON string: quoted, with quotes, backslashes and control characters escaped.
std::string jsonString(const std::string& text);

/// The sectors as a JSON array, one sector per line indented by `indent` spaces, the closing bracket by `indent - 2`.
std::string sectorsJsonArray(const ObstacleSectors& sectors, int indent);

} // namespace ugv
