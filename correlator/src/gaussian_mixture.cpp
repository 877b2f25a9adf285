#include "ugv/correlator/gaussian_mixture.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace ugv::correlator {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kParamsOne = 5;  ///< mean 2 + covariance 3
constexpr int kParamsTwo = 11; ///< two of them + one weight

double logDensity(const Gaussian2& g, const Eigen::Vector2d& x)
{
    const Eigen::Vector2d d = x - g.mean;
    const double det = g.cov.determinant();
    return -0.5 * d.dot(g.cov.inverse() * d) - std::log(2.0 * kPi) - 0.5 * std::log(det);
}

double logSumExp(double a, double b)
{
    const double m = std::max(a, b);
    return m + std::log(std::exp(a - m) + std::exp(b - m));
}

Eigen::Matrix2d floor(double minSigmaM)
{
    return Eigen::Matrix2d::Identity() * (minSigmaM * minSigmaM);
}

/// Weighted mean and covariance; `w` are the responsibilities of one component.
Gaussian2 weightedFit(std::span<const Eigen::Vector2d> points, const std::vector<double>& w, double minSigmaM)
{
    Gaussian2 g;
    double sum = 0.0;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (std::size_t i = 0; i < points.size(); ++i) {
        sum += w[i];
        mean += w[i] * points[i];
    }
    g.count = sum;
    if (sum <= 0.0) {
        return g;
    }
    mean /= sum;
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector2d d = points[i] - mean;
        cov += w[i] * d * d.transpose();
    }
    g.mean = mean;
    g.cov = cov / sum + floor(minSigmaM);
    return g;
}

} // namespace

Gaussian2 fitOne(std::span<const Eigen::Vector2d> points, double minSigmaM)
{
    const std::vector<double> w(points.size(), 1.0);
    Gaussian2 g = weightedFit(points, w, minSigmaM);
    g.weight = 1.0;
    return g;
}

MixtureFit fitMixture(std::span<const Eigen::Vector2d> points, const MixtureConfig& config)
{
    MixtureFit fit;
    const auto n = points.size();
    if (n == 0) {
        return fit;
    }
    fit.components = 1;
    fit.g[0] = fitOne(points, config.minSigmaM);
    if (n < static_cast<std::size_t>(std::max(config.minPointsToSplit, 2 * config.minComponentPoints))) {
        return fit;
    }
    // Start: split at the median along the major axis.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(fit.g[0].cov);
    const Eigen::Vector2d axis = eig.eigenvectors().col(1);
    std::vector<double> along(n);
    for (std::size_t i = 0; i < n; ++i) {
        along[i] = axis.dot(points[i] - fit.g[0].mean);
    }
    std::vector<double> sorted = along;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(n / 2), sorted.end());
    const double median = sorted[n / 2];
    std::vector<double> r0(n);
    std::vector<double> r1(n);
    for (std::size_t i = 0; i < n; ++i) {
        r0[i] = along[i] < median ? 1.0 : 0.0;
        r1[i] = 1.0 - r0[i];
    }
    std::array<Gaussian2, 2> g{weightedFit(points, r0, config.minSigmaM), weightedFit(points, r1, config.minSigmaM)};
    double logLikTwo = 0.0;
    for (int it = 0; it < config.maxIterations; ++it) {
        if (g[0].count <= 0.0 || g[1].count <= 0.0) {
            return fit;
        }
        g[0].weight = g[0].count / static_cast<double>(n);
        g[1].weight = g[1].count / static_cast<double>(n);
        double logLik = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            const double a = std::log(g[0].weight) + logDensity(g[0], points[i]);
            const double b = std::log(g[1].weight) + logDensity(g[1], points[i]);
            const double total = logSumExp(a, b);
            r0[i] = std::exp(a - total);
            r1[i] = 1.0 - r0[i];
            logLik += total;
        }
        const bool converged = it > 0 && std::abs(logLik - logLikTwo) < 1e-6 * std::abs(logLik);
        logLikTwo = logLik;
        g = {weightedFit(points, r0, config.minSigmaM), weightedFit(points, r1, config.minSigmaM)};
        if (converged) {
            break;
        }
    }
    double logLikOne = 0.0;
    for (const Eigen::Vector2d& p : points) {
        logLikOne += logDensity(fit.g[0], p);
    }
    const double logN = std::log(static_cast<double>(n));
    const double bicOne = -2.0 * logLikOne + kParamsOne * logN;
    const double bicTwo = -2.0 * logLikTwo + kParamsTwo * logN;
    const Eigen::Matrix2d pooled = 0.5 * (g[0].cov + g[1].cov);
    const Eigen::Vector2d d = g[1].mean - g[0].mean;
    const double separation = std::sqrt(d.dot(pooled.inverse() * d));
    if (bicTwo < bicOne && g[0].count >= config.minComponentPoints && g[1].count >= config.minComponentPoints &&
        separation >= config.minSeparationSigmas) {
        fit.components = 2;
        g[0].weight = g[0].count / static_cast<double>(n);
        g[1].weight = g[1].count / static_cast<double>(n);
        fit.g = g;
    }
    return fit;
}

Ellipse ellipseOf(const Eigen::Matrix2d& cov)
{
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
    const Eigen::Vector2d major = eig.eigenvectors().col(1);     // (east, north)
    double deg = std::atan2(major.x(), major.y()) * 180.0 / kPi; // compass: from north towards east
    if (deg < 0.0) {
        deg += 180.0;
    }
    if (deg >= 180.0) {
        deg -= 180.0;
    }
    return Ellipse{std::sqrt(std::max(eig.eigenvalues()(1), 0.0)), std::sqrt(std::max(eig.eigenvalues()(0), 0.0)), deg};
}

Gaussian2 combine(std::span<const Gaussian2> parts)
{
    Gaussian2 out;
    double total = 0.0;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const Gaussian2& g : parts) {
        total += g.count;
        mean += g.count * g.mean;
    }
    if (total <= 0.0) {
        return parts.empty() ? out : parts.front();
    }
    mean /= total;
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const Gaussian2& g : parts) {
        const Eigen::Vector2d d = g.mean - mean;
        cov += g.count * (g.cov + d * d.transpose());
    }
    out.mean = mean;
    out.cov = cov / total;
    out.count = total;
    return out;
}

} // namespace ugv::correlator
