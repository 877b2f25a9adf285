#pragma once

/// @file
/// Degrees and radians: the one pair of conversion factors of the project (compass headings and bearings are
/// degrees at the interfaces, radians inside the maths).
///
/// Thread-safety: constants. RT-safe: yes.

#include <numbers>

namespace ugv {

inline constexpr double kDegToRad = std::numbers::pi / 180.0; ///< [rad/deg]
inline constexpr double kRadToDeg = 180.0 / std::numbers::pi; ///< [deg/rad]

} // namespace ugv
