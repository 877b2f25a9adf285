#pragma once

/// @file
/// The range-bearing measurement model of mode `pose-corrected`, written once for association, the pose-error
/// solver and noise learning: an observation stored in its UGV's reported frame, the ray it points along, its
/// noise (range sigma a + b r along the ray, r x bearing sigma across it) and the statistical distance used by
/// every gate. Mode `original` projects along the same ray (geodesy.hpp's project()) and has no covariance model.
///
/// Thread-safety: value types and pure functions, reentrant. RT-safe: yes.

#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "ugv/platform/angles.hpp"

namespace ugv::correlator {

inline constexpr double kRadPerDeg = kDegToRad; ///< the correlator's name of ugv::kDegToRad

/// Sigma of a normal distribution over its median absolute deviation: the robust noise estimates (learnt noise,
/// a walker's speed spread) scale a median by it.
constexpr double kMadToSigma = 1.4826;

/// One observation as stored: the UGV's reported pose and what it measured.
struct RangeBearing {
    double t = 0.0;                                   ///< [s]
    Eigen::Vector2d ugvPos = Eigen::Vector2d::Zero(); ///< [m] reported, local frame
    double headingRad = 0.0;                          ///< [rad] reported, compass
    double rangeM = 0.0;                              ///< [m]
    double bearingRad = 0.0;                          ///< [rad] relative to the heading, clockwise
};

/// Range and bearing noise; each sigma may be scaled by a learnt factor (>= 1).
struct RangeBearingNoise {
    double rangeSigmaM = 0.1;         ///< [m] at zero range
    double rangeSigmaFraction = 0.01; ///< growth per metre of range
    double bearingSigmaDeg = 1.0;     ///< [deg]

    /// [m] sigma along the ray at `rangeM`
    [[nodiscard]] double alongSigma(double rangeM, double scale = 1.0) const noexcept
    {
        return scale * (rangeSigmaM + rangeSigmaFraction * rangeM);
    }
    /// [m] sigma across the ray at `rangeM`
    [[nodiscard]] double acrossSigma(double rangeM, double scale = 1.0) const noexcept
    {
        return rangeM * scale * bearingSigmaDeg * kRadPerDeg;
    }
};

/// The unit vector (east, north) of compass azimuth `azimuthRad`.
[[nodiscard]] inline Eigen::Vector2d rayAt(double azimuthRad) noexcept
{
    return {std::sin(azimuthRad), std::cos(azimuthRad)};
}

/// `ray` turned a quarter to the left: the direction a bearing error moves a point.
[[nodiscard]] inline Eigen::Vector2d acrossOf(const Eigen::Vector2d& ray) noexcept
{
    return {ray.y(), -ray.x()};
}

/// The inverse covariance of a point measured along `ray` with the given sigmas [m] along and across it.
[[nodiscard]] inline Eigen::Matrix2d rayInformation(const Eigen::Vector2d& ray, double alongSigma, double acrossSigma)
{
    const Eigen::Vector2d across = acrossOf(ray);
    return ray * ray.transpose() / (alongSigma * alongSigma) +
           across * across.transpose() / (acrossSigma * acrossSigma);
}

/// The squared Mahalanobis distance of `d` under covariance `cov` (every gate of mode pose-corrected).
[[nodiscard]] inline double mahalanobis2(const Eigen::Vector2d& d, const Eigen::Matrix2d& cov)
{
    return d.dot(cov.ldlt().solve(d));
}

} // namespace ugv::correlator
