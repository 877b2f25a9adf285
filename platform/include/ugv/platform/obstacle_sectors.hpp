#pragma once

/// @file
/// The service's only output: obstacle sectors. N bearing bins across the horizontal field of view of the
/// rectified left camera, each with the horizontal range to the nearest obstacle, its kind and a danger
/// class. A fixed-size POD, so that it can be published, recorded and compared without allocation.
///
/// Conventions: bearings in degrees from the rectified left camera's optical axis, positive to the left
/// (counter-clockwise seen from above, as in robotics). Ranges are horizontal distances on the ground
/// plane from the point below the camera, in metres; +inf when the sector is clear.
///
/// "Unknown" (no texture, no valid disparity, out of view, degraded) is a state of its own and is never
/// reported as clear: a planner must treat it as not known to be free.
///
/// Thread-safety: plain data. RT-safe: yes.

#include <array>
#include <cstdint>
#include <limits>

namespace ugv {

inline constexpr int kMaxSectors = 180;

enum class SectorState : std::uint8_t { Unknown = 0, Clear = 1, Obstacle = 2 };
enum class ObstacleKind : std::uint8_t { None = 0, Positive = 1, Negative = 2 };
/// Red: obstacle closer than the danger distance; Blue: obstacle closer than the caution distance;
/// Green: clear (or obstacle beyond the caution distance); Unknown: not known to be free.
enum class DangerClass : std::uint8_t { Unknown = 0, Green = 1, Blue = 2, Red = 3 };

struct Sector {
    float bearingMinDeg = 0.0F;                            ///< [deg] right edge of the bin (smaller bearing)
    float bearingMaxDeg = 0.0F;                            ///< [deg] left edge
    float rangeM = std::numeric_limits<float>::infinity(); ///< [m] nearest obstacle, +inf when clear or unknown
    float heightM = 0.0F;    ///< [m] height above ground (positive kind) or depth below it (negative kind)
    float confidence = 0.0F; ///< [0, 1]
    SectorState state = SectorState::Unknown;
    ObstacleKind kind = ObstacleKind::None;
    DangerClass danger = DangerClass::Unknown;
};

struct ObstacleSectors {
    std::uint64_t sequence = 0;      ///< frame sequence number from capture
    std::int64_t captureStampNs = 0; ///< [ns] CLOCK_MONOTONIC exposure time of the left image
    std::int32_t count = 0;          ///< sectors in use, <= kMaxSectors
    bool degraded = false;           ///< produced by a fallback path (ground-plane only, configured ground, ...)
    std::array<Sector, kMaxSectors> sectors{};
};

/// The ground plane a frame's sectors were measured against, as the service publishes it with them (the iceoryx
/// SectorsMessage, the DDS sectors): the frame's own estimate when `reliable`, else the configured (mount) plane.
struct GroundSummary {
    bool reliable = false;      ///< estimated from this frame's pair (else the configured plane)
    float pitchDeg = 0.0F;      ///< [deg] camera pitch to the ground, positive looking down
    float rollDeg = 0.0F;       ///< [deg] camera roll to the ground, positive right side down
    float cameraHeightM = 0.0F; ///< [m] camera above the ground
};

/// The danger class of an obstacle at `rangeM` given the configured distances (clear => Green).
constexpr DangerClass classify(SectorState state, float rangeM, float dangerDistanceM, float cautionDistanceM) noexcept
{
    if (state == SectorState::Unknown) {
        return DangerClass::Unknown;
    }
    if (state == SectorState::Clear || rangeM >= cautionDistanceM) {
        return DangerClass::Green;
    }
    return rangeM < dangerDistanceM ? DangerClass::Red : DangerClass::Blue;
}

/// Fills `out` with `count` equal bins spanning [-hfovDeg/2, +hfovDeg/2], all Unknown.
constexpr void initSectors(ObstacleSectors& out, int count, float hfovDeg) noexcept
{
    out.count = count < 0 ? 0 : (count > kMaxSectors ? kMaxSectors : count);
    const float width = out.count > 0 ? hfovDeg / static_cast<float>(out.count) : 0.0F;
    for (int i = 0; i < out.count; ++i) {
        Sector& s = out.sectors[static_cast<std::size_t>(i)];
        s = Sector{};
        s.bearingMinDeg = -hfovDeg / 2.0F + width * static_cast<float>(i);
        s.bearingMaxDeg = s.bearingMinDeg + width;
    }
}

} // namespace ugv
