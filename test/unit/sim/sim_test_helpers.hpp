#pragma once

/// @file
/// Helpers shared by the simulator's unit tests: small rigs, scenes, a checked render, sector look-ups.

#include <cstddef>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"

namespace ugv::sim {

/// The default rig scaled down by `factor` (same field of view, camera height and baseline).
inline Rig smallRig(int factor)
{
    Rig rig;
    rig.width /= factor;
    rig.height /= factor;
    rig.focalPx /= factor;
    return rig;
}

inline Scene sceneWith(const Rig& rig, std::vector<Obstacle> obstacles)
{
    Scene scene;
    scene.rig = rig;
    scene.obstacles = std::move(obstacles);
    return scene;
}

inline RenderResult renderOk(const Scene& scene, const RenderOptions& options = {})
{
    auto result = render(scene, Pose{}, options);
    EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().message());
    return result.has_value() ? std::move(result).value() : RenderResult{};
}

/// Index of the sector whose [min, max) bearing span contains `bearingDeg`, or -1.
inline int sectorAt(const ObstacleSectors& sectors, float bearingDeg)
{
    for (int i = 0; i < sectors.count; ++i) {
        const Sector& s = sectors.sectors[static_cast<std::size_t>(i)];
        if (bearingDeg >= s.bearingMinDeg && bearingDeg < s.bearingMaxDeg) {
            return i;
        }
    }
    return -1;
}

inline const Sector& sector(const ObstacleSectors& sectors, int i)
{
    return sectors.sectors.at(static_cast<std::size_t>(i));
}

inline int countState(const ObstacleSectors& sectors, SectorState state)
{
    int n = 0;
    for (int i = 0; i < sectors.count; ++i) {
        n += sector(sectors, i).state == state ? 1 : 0;
    }
    return n;
}

} // namespace ugv::sim
