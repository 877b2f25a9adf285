#include "ugv/correlator/gaussian_mixture.hpp"

#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace ugv::correlator {
namespace {

/// `count` points drawn around `centre` with `sigma` per axis, from a fixed seed.
void addCluster(std::vector<Eigen::Vector2d>& points, Eigen::Vector2d centre, int count, double sigma, unsigned seed)
{
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, sigma);
    for (int i = 0; i < count; ++i) {
        points.emplace_back(centre.x() + noise(rng), centre.y() + noise(rng));
    }
}

TEST(GaussianMixture, OneClusterIsOneComponent)
{
    std::vector<Eigen::Vector2d> points;
    addCluster(points, {10, 10}, 60, 0.5, 1);
    const MixtureFit fit = fitMixture(points);
    EXPECT_EQ(fit.components, 1);
    EXPECT_NEAR(fit.g[0].mean.x(), 10.0, 0.2);
    EXPECT_NEAR(fit.g[0].mean.y(), 10.0, 0.2);
}

TEST(GaussianMixture, TwoSeparatedClustersAreTwoComponentsWithTheirMeansAndWeights)
{
    std::vector<Eigen::Vector2d> points;
    addCluster(points, {10, 10}, 40, 0.5, 2);
    addCluster(points, {10, 16}, 20, 0.5, 3);
    const MixtureFit fit = fitMixture(points);
    ASSERT_EQ(fit.components, 2);
    const int far = fit.g[0].mean.y() > fit.g[1].mean.y() ? 0 : 1;
    EXPECT_NEAR(fit.g[far].mean.y(), 16.0, 0.3);
    EXPECT_NEAR(fit.g[1 - far].mean.y(), 10.0, 0.3);
    EXPECT_NEAR(fit.g[far].weight, 20.0 / 60.0, 0.02);
    EXPECT_NEAR(fit.g[0].weight + fit.g[1].weight, 1.0, 1e-9);
}

// The rule "each component explains at least minComponentPoints points" counts whole points: a cluster of exactly
// that many far from the rest is a component on every compiler (its soft count is 3 give or take a rounding
// error), and one point fewer is not.
TEST(GaussianMixture, AComponentOfExactlyTheMinimumPointsIsKept)
{
    MixtureConfig config;
    ASSERT_EQ(config.minComponentPoints, 3);
    std::vector<Eigen::Vector2d> points;
    addCluster(points, {10, 10.5}, 60, 0.3, 4);
    addCluster(points, {10, 16}, 3, 0.3, 5);
    EXPECT_EQ(fitMixture(points, config).components, 2);

    points.pop_back();
    EXPECT_EQ(fitMixture(points, config).components, 1);
}

// A track of a noiseless source repeats its positions exactly. EM starts from a split at the median by rank; a split
// by value put all 60 equal points on one side, started with an empty component and never split.
TEST(GaussianMixture, RepeatedPositionsSplitLikeNoisyOnes)
{
    std::vector<Eigen::Vector2d> points(60, Eigen::Vector2d(10, 10.5));
    points.insert(points.end(), 3, Eigen::Vector2d(10, 16));
    const MixtureFit fit = fitMixture(points);
    ASSERT_EQ(fit.components, 2);
    const int far = fit.g[0].mean.y() > fit.g[1].mean.y() ? 0 : 1;
    EXPECT_NEAR(fit.g[far].mean.y(), 16.0, 1e-9);
    EXPECT_NEAR(fit.g[far].count, 3.0, 1e-6);

    const std::vector<Eigen::Vector2d> one(20, Eigen::Vector2d(4, 2)); // one place: one component
    EXPECT_EQ(fitMixture(one).components, 1);
}

TEST(GaussianMixture, TooFewPointsAreNeverSplit)
{
    std::vector<Eigen::Vector2d> points;
    addCluster(points, {0, 0}, 4, 0.1, 6);
    addCluster(points, {0, 20}, 3, 0.1, 7);
    EXPECT_EQ(fitMixture(points).components, 1); // 7 < minPointsToSplit
    EXPECT_EQ(fitMixture(std::vector<Eigen::Vector2d>{}).components, 0);
}

} // namespace
} // namespace ugv::correlator
