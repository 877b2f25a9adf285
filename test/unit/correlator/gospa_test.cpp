// GOSPA (alpha = 2) against hand-computed cases and, for random sets, against a brute-force minimum over every
// partial assignment; the Hungarian assignment on square and rectangular cost matrices.

#include "ugv/correlator/gospa.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace ugv::correlator {
namespace {

using Eigen::Vector2d;
using Points = std::vector<Vector2d>;

constexpr double kTolerance = 1e-9;
constexpr GospaParams kC5P2{5.0, 2.0};

TEST(Gospa, EmptySetsGiveZero)
{
    const GospaResult sut = gospa({}, {}, kC5P2);

    EXPECT_EQ(sut.total, 0.0);
    EXPECT_EQ(sut.localisationPart + sut.missedPart + sut.falsePart, 0.0);
    EXPECT_EQ(sut.assigned + sut.missed + sut.falseCount, 0U);
    EXPECT_TRUE(sut.truthToEstimate.empty());
}

TEST(Gospa, AllMissedCostHalfTheCutoffEach)
{
    constexpr double kExpectedSquare = 25.0 / 2.0 * 3.0;
    const Points truth{{0, 0}, {10, 0}, {0, 10}};

    const GospaResult sut = gospa(truth, {}, kC5P2);

    EXPECT_NEAR(sut.total, std::sqrt(kExpectedSquare), kTolerance);
    EXPECT_NEAR(sut.missedPart, kExpectedSquare, kTolerance);
    EXPECT_EQ(sut.missed, 3U);
    EXPECT_EQ(sut.falseCount, 0U);
    EXPECT_EQ(sut.truthToEstimate, (std::vector<int>{-1, -1, -1}));
}

TEST(Gospa, AllFalseCostHalfTheCutoffEach)
{
    const Points estimates{{1, 1}, {2, 2}};

    const GospaResult sut = gospa({}, estimates, kC5P2);

    EXPECT_NEAR(sut.total, 5.0, kTolerance); // sqrt(2 x 25/2)
    EXPECT_NEAR(sut.falsePart, 25.0, kTolerance);
    EXPECT_EQ(sut.falseCount, 2U);
    EXPECT_EQ(sut.missed, 0U);
}

TEST(Gospa, PairWithinTheCutoffIsLocalisationError)
{
    const GospaResult sut = gospa({{0, 0}}, {{3, 0}}, kC5P2);

    EXPECT_NEAR(sut.total, 3.0, kTolerance);
    EXPECT_NEAR(sut.localisationPart, 9.0, kTolerance);
    EXPECT_EQ(sut.assigned, 1U);
    EXPECT_EQ(sut.truthToEstimate, (std::vector<int>{0}));
}

TEST(Gospa, PairBeyondTheCutoffIsOneMissedAndOneFalse)
{
    const GospaResult sut = gospa({{0, 0}}, {{6, 0}}, kC5P2);

    EXPECT_NEAR(sut.total, 5.0, kTolerance);
    EXPECT_EQ(sut.localisationPart, 0.0);
    EXPECT_NEAR(sut.missedPart, 12.5, kTolerance);
    EXPECT_NEAR(sut.falsePart, 12.5, kTolerance);
    EXPECT_EQ(sut.assigned, 0U);
    EXPECT_EQ(sut.missed, 1U);
    EXPECT_EQ(sut.falseCount, 1U);
    EXPECT_EQ(sut.truthToEstimate, (std::vector<int>{-1}));
}

TEST(Gospa, PairAtExactlyTheCutoffIsNotAssigned)
{
    const GospaResult sut = gospa({{0, 0}}, {{0, 5}}, kC5P2);

    EXPECT_NEAR(sut.total, 5.0, kTolerance);
    EXPECT_EQ(sut.assigned, 0U);
}

/// Greedy nearest-pair-first matching, to show the 3x3 case below is one where it is not optimal.
double greedySquareSum(const Points& truth, const Points& estimates)
{
    std::vector<bool> usedTruth(truth.size(), false);
    std::vector<bool> usedEstimate(estimates.size(), false);
    double sum = 0.0;
    for (std::size_t pairs = 0; pairs < std::min(truth.size(), estimates.size()); ++pairs) {
        double best = std::numeric_limits<double>::infinity();
        std::size_t bi = 0;
        std::size_t bj = 0;
        for (std::size_t i = 0; i < truth.size(); ++i) {
            for (std::size_t j = 0; j < estimates.size(); ++j) {
                const double d = (truth[i] - estimates[j]).norm();
                if (!usedTruth[i] && !usedEstimate[j] && d < best) {
                    best = d;
                    bi = i;
                    bj = j;
                }
            }
        }
        usedTruth[bi] = true;
        usedEstimate[bj] = true;
        sum += best * best;
    }
    return sum;
}

TEST(Gospa, ThreeByThreeWhereGreedyIsWrong)
{
    // Greedy takes T3-E3 (0.5), T2-E1 (0.9), then T1-E2 (3.0): 0.25 + 0.81 + 9 = 10.06.
    // Optimal: T1-E1 (1.0), T2-E2 (1.1), T3-E3 (0.5): 1 + 1.21 + 0.25 = 2.46.
    constexpr double kGreedySquare = 10.06;
    constexpr double kOptimalSquare = 2.46;
    const Points truth{{0, 0}, {1.9, 0}, {0, 10}};
    const Points estimates{{1, 0}, {3, 0}, {0, 10.5}};
    ASSERT_NEAR(greedySquareSum(truth, estimates), kGreedySquare, 1e-9);

    const GospaResult sut = gospa(truth, estimates, kC5P2);

    EXPECT_NEAR(sut.total * sut.total, kOptimalSquare, 1e-9);
    EXPECT_NEAR(sut.localisationPart, kOptimalSquare, 1e-9);
    EXPECT_EQ(sut.truthToEstimate, (std::vector<int>{0, 1, 2}));
    EXPECT_EQ(sut.assigned, 3U);
}

TEST(Gospa, MoreEstimatesThanTruth)
{
    constexpr double kExpectedSquare = 0.25 + 1.0 + 12.5;
    const Points truth{{0, 0}, {10, 0}};
    const Points estimates{{50, 50}, {10, 1}, {0.5, 0}};

    const GospaResult sut = gospa(truth, estimates, kC5P2);

    EXPECT_NEAR(sut.total, std::sqrt(kExpectedSquare), kTolerance);
    EXPECT_EQ(sut.truthToEstimate, (std::vector<int>{2, 1}));
    EXPECT_EQ(sut.falseCount, 1U);
}

TEST(Gospa, OrderOneAddsDistances)
{
    const GospaResult sut = gospa({{0, 0}, {100, 0}}, {{3, 0}}, GospaParams{5.0, 1.0});

    EXPECT_NEAR(sut.total, 3.0 + 2.5, kTolerance);
    EXPECT_NEAR(sut.localisationPart + sut.missedPart + sut.falsePart, sut.total, kTolerance);
}

/// GOSPA^p by its definition: the minimum over every partial assignment (recursive, small sets only).
double bruteForce(const Points& truth, const Points& estimates, std::size_t i, std::vector<bool>& used,
                  const GospaParams& params)
{
    const double half = std::pow(params.cutoffM, params.order) / 2.0;
    if (i == truth.size()) {
        return half * static_cast<double>(std::count(used.begin(), used.end(), false));
    }
    double best = half + bruteForce(truth, estimates, i + 1, used, params); // truth i missed
    for (std::size_t j = 0; j < estimates.size(); ++j) {
        if (used[j]) {
            continue;
        }
        used[j] = true;
        const double d = std::min((truth[i] - estimates[j]).norm(), params.cutoffM);
        best = std::min(best, std::pow(d, params.order) + bruteForce(truth, estimates, i + 1, used, params));
        used[j] = false;
    }
    return best;
}

TEST(Gospa, MatchesBruteForceOnRandomSets)
{
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> coordinate(0.0, 15.0);
    const auto randomPoints = [&](std::size_t n) {
        Points points;
        for (std::size_t k = 0; k < n; ++k) {
            points.emplace_back(coordinate(rng), coordinate(rng));
        }
        return points;
    };
    for (std::size_t n = 0; n <= 6; ++n) {
        for (std::size_t m = 0; m <= 6; ++m) {
            for (int trial = 0; trial < 5; ++trial) {
                const Points truth = randomPoints(n);
                const Points estimates = randomPoints(m);
                std::vector<bool> used(m, false);
                const double expected = bruteForce(truth, estimates, 0, used, kC5P2);

                const GospaResult sut = gospa(truth, estimates, kC5P2);

                ASSERT_NEAR(sut.total * sut.total, expected, 1e-9) << n << "x" << m << " trial " << trial;
                EXPECT_NEAR(sut.localisationPart + sut.missedPart + sut.falsePart, expected, 1e-9);
                EXPECT_EQ(sut.assigned + sut.missed, n);
                EXPECT_EQ(sut.assigned + sut.falseCount, m);
            }
        }
    }
}

TEST(SolveAssignment, MoreRowsThanColumnsLeavesRowsOver)
{
    // 3 rows x 2 columns: the best is row 0 -> col 1 (1) and row 2 -> col 0 (1); row 1 left over.
    const std::vector<double> cost{5, 1, //
                                   4, 4, //
                                   1, 5};

    const std::vector<int> sut = solveAssignment(cost, 3, 2);

    EXPECT_EQ(sut, (std::vector<int>{1, -1, 0}));
}

TEST(SolveAssignment, SquareMatrixMinimumCost)
{
    // The classic 3x3 example: optimum 5 = 1 (0->1) + 2 (1->0) + 2 (2->2).
    const std::vector<double> cost{4, 1, 3, //
                                   2, 0, 5, //
                                   3, 2, 2};

    const std::vector<int> sut = solveAssignment(cost, 3, 3);

    double total = 0.0;
    for (std::size_t row = 0; row < 3; ++row) {
        total += cost[row * 3 + static_cast<std::size_t>(sut[row])];
    }
    EXPECT_EQ(total, 5.0);
    EXPECT_EQ(sut, (std::vector<int>{1, 0, 2}));
}

TEST(SolveAssignment, EmptyMatrix)
{
    EXPECT_TRUE(solveAssignment({}, 0, 0).empty());
    EXPECT_EQ(solveAssignment({}, 2, 0), (std::vector<int>{-1, -1}));
    EXPECT_TRUE(solveAssignment({}, 0, 3).empty());
}

} // namespace
} // namespace ugv::correlator
