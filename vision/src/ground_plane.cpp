#include "ugv/vision/ground_plane.hpp"

#include "ugv/platform/angles.hpp"
#include <cmath>
#include <numbers>

namespace ugv::vision {
namespace {

} // namespace

GroundPlane GroundPlane::fromMount(const Mount& mount) noexcept
{
    const double p = mount.pitchDeg * kDegToRad;
    const double r = mount.rollDeg * kDegToRad;
    return GroundPlane{std::sin(r) * std::cos(p), std::cos(r) * std::cos(p), std::sin(p), mount.heightM};
}

DisparityPlane GroundPlane::disparityPlane(const RectifiedProjection& p) const noexcept
{
    const double k = p.baselineM / heightM;
    return DisparityPlane{k * nx, k * ny, k * (p.fx * nz - nx * p.cx - ny * p.cy)};
}

GroundPlane GroundPlane::fromDisparityPlane(const DisparityPlane& plane, const RectifiedProjection& p) noexcept
{
    // a = k nx, b = k ny, c = k (f nz - nx cx - ny cy) with k = B / h and |n| = 1.
    const double kx = plane.a;
    const double ky = plane.b;
    const double kz = (plane.c + kx * p.cx + ky * p.cy) / p.fx;
    const double k = std::sqrt(kx * kx + ky * ky + kz * kz);
    return GroundPlane{kx / k, ky / k, kz / k, p.baselineM / k};
}

double GroundPlane::pitchDeg() const noexcept
{
    return std::asin(nz) * kRadToDeg;
}

double GroundPlane::rollDeg() const noexcept
{
    return std::atan2(nx, ny) * kRadToDeg;
}

VehiclePoint GroundPlane::toVehicle(double xc, double yc, double zc) const noexcept
{
    // Vehicle axes in camera coordinates: up = -n; forward = the optical axis projected onto the ground plane;
    // left = up x forward.
    const double fx = -nz * nx;
    const double fy = -nz * ny;
    const double fz = 1.0 - nz * nz;
    const double fn = std::sqrt(fx * fx + fy * fy + fz * fz);
    const double ux = -nx;
    const double uy = -ny;
    const double uz = -nz;
    const double lx = uy * fz - uz * fy;
    const double ly = uz * fx - ux * fz;
    const double lz = ux * fy - uy * fx;
    return VehiclePoint{(xc * fx + yc * fy + zc * fz) / fn, (xc * lx + yc * ly + zc * lz) / fn,
                        heightM + xc * ux + yc * uy + zc * uz};
}

VehiclePoint GroundPlane::pixelToVehicle(double x, double y, double disparity,
                                         const RectifiedProjection& p) const noexcept
{
    const double z = p.fx * p.baselineM / disparity;
    return toVehicle((x - p.cx) * z / p.fx, (y - p.cy) * z / p.fy, z);
}

} // namespace ugv::vision
