#include "ugv/correlator/gaussian_mixture.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace ugv::correlator {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kParamsOne = 5;  ///< mean 2 + covariance 3
constexpr int kParamsTwo = 11; ///< two of them + one weight

/// The log density of one component, with what does not depend on the point (inverse covariance, log
/// determinant) computed once.
class LogDensity {
public:
    explicit LogDensity(const Gaussian2& g)
        : mean_(g.mean), inverse_(g.cov.inverse()), logDet_(std::log(g.cov.determinant()))
    {
    }
    double operator()(const Eigen::Vector2d& x) const
    {
        const Eigen::Vector2d d = x - mean_;
        return -0.5 * d.dot(inverse_ * d) - std::log(2.0 * kPi) - 0.5 * logDet_;
    }

private:
    Eigen::Vector2d mean_;
    Eigen::Matrix2d inverse_;
    double logDet_;
};

/// log(exp(a) + exp(b)); the larger term's exp is exp(0) = 1.
double logSumExp(double a, double b)
{
    return std::max(a, b) + std::log(1.0 + std::exp(-std::abs(a - b)));
}

Eigen::Matrix2d floor(double minSigmaM)
{
    return Eigen::Matrix2d::Identity() * (minSigmaM * minSigmaM);
}

/// Weighted means and covariances of K components, in one pass over the points for all of them; `w[k]` are the
/// responsibilities of component k. A component without weight keeps the default mean and covariance (count 0).
template <std::size_t K>
std::array<Gaussian2, K> weightedFit(std::span<const Eigen::Vector2d> points,
                                     const std::array<std::span<const double>, K>& w, double minSigmaM)
{
    std::array<double, K> sum{};
    std::array<Eigen::Vector2d, K> mean;
    mean.fill(Eigen::Vector2d::Zero());
    for (std::size_t i = 0; i < points.size(); ++i) {
        for (std::size_t k = 0; k < K; ++k) {
            sum[k] += w[k][i];
            mean[k] += w[k][i] * points[i];
        }
    }
    for (std::size_t k = 0; k < K; ++k) {
        if (sum[k] > 0.0) {
            mean[k] /= sum[k];
        }
    }
    std::array<Eigen::Matrix2d, K> cov;
    cov.fill(Eigen::Matrix2d::Zero());
    for (std::size_t i = 0; i < points.size(); ++i) {
        for (std::size_t k = 0; k < K; ++k) {
            const Eigen::Vector2d d = points[i] - mean[k];
            cov[k].noalias() += w[k][i] * d * d.transpose(); // finite and unused when sum[k] is 0
        }
    }
    std::array<Gaussian2, K> g{};
    for (std::size_t k = 0; k < K; ++k) {
        g[k].count = sum[k];
        if (sum[k] > 0.0) {
            g[k].mean = mean[k];
            g[k].cov = cov[k] / sum[k] + floor(minSigmaM);
        }
    }
    return g;
}

/// The start of EM: the responsibilities of a split at the median along the major axis of `one`, by rank: the
/// first half of the points in that order (ties by index) against the rest. A split by value would put every point
/// equal to the median on one side, and a track whose fixes repeat one position would start with an empty
/// component and never split. `r0` and `r1` have one entry per point.
void splitAtMedian(std::span<const Eigen::Vector2d> points, const Gaussian2& one, std::vector<double>& r0,
                   std::vector<double>& r1)
{
    const std::size_t n = points.size();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(one.cov);
    const Eigen::Vector2d axis = eig.eigenvectors().col(1);
    std::vector<double> along(n);
    for (std::size_t i = 0; i < n; ++i) {
        along[i] = axis.dot(points[i] - one.mean);
    }
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t{0});
    const auto half = static_cast<std::ptrdiff_t>(n / 2);
    std::nth_element(order.begin(), order.begin() + half, order.end(), [&along](std::size_t a, std::size_t b) {
        return along[a] < along[b] || (along[a] == along[b] && a < b);
    });
    std::fill(r0.begin(), r0.end(), 0.0);
    std::fill(r1.begin(), r1.end(), 1.0);
    for (auto it = order.begin(); it != order.begin() + half; ++it) {
        r0[*it] = 1.0;
        r1[*it] = 0.0;
    }
}

} // namespace

Gaussian2 fitOne(std::span<const Eigen::Vector2d> points, double minSigmaM)
{
    const std::vector<double> w(points.size(), 1.0);
    Gaussian2 g = weightedFit<1>(points, {w}, minSigmaM)[0];
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
    std::vector<double> r0(n);
    std::vector<double> r1(n);
    splitAtMedian(points, fit.g[0], r0, r1);
    std::array<Gaussian2, 2> g = weightedFit<2>(points, {r0, r1}, config.minSigmaM);
    double logLikTwo = 0.0;
    for (int it = 0; it < config.maxIterations; ++it) {
        if (g[0].count <= 0.0 || g[1].count <= 0.0) {
            return fit;
        }
        g[0].weight = g[0].count / static_cast<double>(n);
        g[1].weight = g[1].count / static_cast<double>(n);
        const double logWeight0 = std::log(g[0].weight);
        const double logWeight1 = std::log(g[1].weight);
        const LogDensity logDensity0(g[0]);
        const LogDensity logDensity1(g[1]);
        double logLik = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            const double a = logWeight0 + logDensity0(points[i]);
            const double b = logWeight1 + logDensity1(points[i]);
            const double total = logSumExp(a, b);
            r0[i] = std::exp(a - total);
            r1[i] = 1.0 - r0[i];
            logLik += total;
        }
        const bool converged = it > 0 && std::abs(logLik - logLikTwo) < 1e-6 * std::abs(logLik);
        logLikTwo = logLik;
        g = weightedFit<2>(points, {r0, r1}, config.minSigmaM);
        if (converged) {
            break;
        }
    }
    const LogDensity logDensityOne(fit.g[0]);
    double logLikOne = 0.0;
    for (const Eigen::Vector2d& p : points) {
        logLikOne += logDensityOne(p);
    }
    const double logN = std::log(static_cast<double>(n));
    const double bicOne = -2.0 * logLikOne + kParamsOne * logN;
    const double bicTwo = -2.0 * logLikTwo + kParamsTwo * logN;
    const Eigen::Matrix2d pooled = 0.5 * (g[0].cov + g[1].cov);
    const Eigen::Vector2d d = g[1].mean - g[0].mean;
    const double separation = std::sqrt(d.dot(pooled.inverse() * d));
    // The points each component explains, counted whole (responsibility at least one half): a soft count of
    // exactly minComponentPoints points is that number give or take a rounding error, which would decide the
    // split differently on another compiler.
    const auto explainedByFirst =
        static_cast<int>(std::count_if(r0.begin(), r0.end(), [](double r) { return r >= 0.5; }));
    const int explainedBySecond = static_cast<int>(n) - explainedByFirst;
    if (bicTwo < bicOne && explainedByFirst >= config.minComponentPoints &&
        explainedBySecond >= config.minComponentPoints && separation >= config.minSeparationSigmas) {
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
