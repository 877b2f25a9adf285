#pragma once

/// @file
/// The ground plane in the rectified left camera frame and the disparity it produces.
///
/// Frames. Camera (OpenCV): X right, Y down, Z forward, origin at the left camera centre. Vehicle: x forward,
/// y left, z up, origin on the ground straight below the left camera. The mount (height h, pitch p positive
/// looking down, roll r positive right side down, as in ugvsense sim) gives the unit "down" vector in the camera
/// frame n = (sin r cos p, cos r cos p, sin p); ground points satisfy n . X = h.
///
/// Disparity. With X = Z ((x - cx)/f, (y - cy)/f, 1), a plane gives 1/Z linear in the pixel, so the ground's
/// disparity is a plane in image coordinates: d_g(x, y) = a x + b y + c with
/// a = B nx / h, b = B ny / h, c = B (f nz - nx cx - ny cy) / h (fx = fy = f after rectification).
/// For a level camera this is d_g = (B / h)(y - cy).
///
/// Thread-safety: value types and pure functions. RT-safe: yes.

#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::vision {

/// d(x, y) = a x + b y + c in full-frame rectified pixel coordinates [px].
struct DisparityPlane {
    double a = 0.0;
    double b = 0.0;
    double c = 0.0;
    [[nodiscard]] constexpr double at(double x, double y) const noexcept { return a * x + b * y + c; }
};

/// A point in the vehicle frame [m].
struct VehiclePoint {
    double x = 0.0; ///< forward
    double y = 0.0; ///< left
    double z = 0.0; ///< up, 0 on the ground plane
};

struct GroundPlane {
    double nx = 0.0; ///< unit "down" vector in the camera frame
    double ny = 1.0;
    double nz = 0.0;
    double heightM = 0.0; ///< [m] camera centre above the ground along n

    /// The plane of a mount (pitch and roll in degrees).
    [[nodiscard]] static GroundPlane fromMount(const Mount& mount) noexcept;

    /// The plane whose disparity model is `plane` (inverse of disparityPlane()); the normal is normalised.
    [[nodiscard]] static GroundPlane fromDisparityPlane(const DisparityPlane& plane,
                                                        const RectifiedProjection& p) noexcept;

    [[nodiscard]] DisparityPlane disparityPlane(const RectifiedProjection& p) const noexcept;

    /// Pitch [deg] (positive looking down) and roll [deg] (positive right side down) of this plane's normal.
    [[nodiscard]] double pitchDeg() const noexcept;
    [[nodiscard]] double rollDeg() const noexcept;

    /// Camera-frame point [m] to the vehicle frame (z = height above this ground plane).
    [[nodiscard]] VehiclePoint toVehicle(double xc, double yc, double zc) const noexcept;

    /// The 3D camera-frame point of pixel (x, y) at disparity d > 0 [px], then toVehicle().
    [[nodiscard]] VehiclePoint pixelToVehicle(double x, double y, double disparity,
                                              const RectifiedProjection& p) const noexcept;
};

} // namespace ugv::vision
