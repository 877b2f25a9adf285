#pragma once

/// @file
/// Expectation maximisation of a two-dimensional Gaussian mixture with one or two components, chosen by the
/// Bayesian information criterion: the static-object fit of the original correlator, where one track's points
/// may cover two objects and must then split into two groups.
///
/// Thread-safety: reentrant. RT-safe: no (the correlator is a low-priority task).

#include <array>
#include <span>

#include <Eigen/Core>

namespace ugv::correlator {

struct Gaussian2 {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    Eigen::Matrix2d cov = Eigen::Matrix2d::Identity();
    double weight = 1.0; ///< mixture weight (sums to 1 over the components)
    double count = 0.0;  ///< points it explains (sum of responsibilities)
};

struct MixtureFit {
    int components = 0; ///< 0 (no points), 1 or 2
    std::array<Gaussian2, 2> g{};
};

struct MixtureConfig {
    double minSigmaM = 0.3;   ///< [m] added in quadrature to every component's covariance (noise floor)
    int minPointsToSplit = 8; ///< fewer points: always one component
    int minComponentPoints = 3;
    double minSeparationSigmas = 3.0; ///< the two means at least this many (pooled) sigmas apart
    int maxIterations = 30;
};

/// Fits `points` with one component, and with two when there are enough points; keeps two only when the BIC
/// prefers them, each explains at least minComponentPoints points (points whose responsibility for it is at least
/// one half), and their means are well separated.
[[nodiscard]] MixtureFit fitMixture(std::span<const Eigen::Vector2d> points, const MixtureConfig& config = {});

/// One Gaussian by moments of the points (the covariance regularised by minSigmaM).
[[nodiscard]] Gaussian2 fitOne(std::span<const Eigen::Vector2d> points, double minSigmaM);

/// Standard deviations along the principal axes and the compass direction of the major one (0..180 deg).
struct Ellipse {
    double sigmaMajor = 0.0;
    double sigmaMinor = 0.0;
    double majorAxisDeg = 0.0;
};
[[nodiscard]] Ellipse ellipseOf(const Eigen::Matrix2d& cov);

/// The moment-matched single Gaussian of weighted components (weights = counts).
[[nodiscard]] Gaussian2 combine(std::span<const Gaussian2> parts);

} // namespace ugv::correlator
