#pragma once

/// @file
/// WGS84 <-> a local east-north tangent plane, through GeographicLib's LocalCartesian (not hand-written
/// formulas). The correlator works in metres in this plane; the origin is the first position it sees.
///
/// Thread-safety: value type; const members reentrant. RT-safe: yes after construction.

#include <Eigen/Core>
#include <GeographicLib/LocalCartesian.hpp>

#include "ugv/correlator/measurement_model.hpp"

namespace ugv::correlator {

class LocalFrame {
public:
    LocalFrame(double originLat, double originLon) : cartesian_(originLat, originLon, 0.0) {}

    /// @return (east, north) [m] of a point on the ellipsoid surface.
    [[nodiscard]] Eigen::Vector2d toLocal(double lat, double lon) const
    {
        double x = 0.0;
        double y = 0.0;
        double z = 0.0;
        cartesian_.Forward(lat, lon, 0.0, x, y, z);
        return {x, y};
    }

    /// Inverse of toLocal() for a point in the tangent plane (z = 0).
    void toLatLon(const Eigen::Vector2d& en, double& lat, double& lon) const
    {
        double h = 0.0;
        cartesian_.Reverse(en.x(), en.y(), 0.0, lat, lon, h);
    }

private:
    GeographicLib::LocalCartesian cartesian_;
};

/// The point at `rangeM` along compass azimuth `azimuthDeg` from `from` (east-north plane).
[[nodiscard]] inline Eigen::Vector2d project(const Eigen::Vector2d& from, double azimuthDeg, double rangeM)
{
    return from + rangeM * rayAt(azimuthDeg * kRadPerDeg);
}

} // namespace ugv::correlator
