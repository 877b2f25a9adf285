#pragma once

/// @file
/// The GOSPA metric (generalized optimal sub-pattern assignment; A. S. Rahmathullah, A. F. Garcia-Fernandez,
/// L. Svensson, "Generalized optimal sub-pattern assignment metric", FUSION 2017) between a set of true and a set
/// of estimated 2-D positions, with alpha = 2, which splits into localisation, missed and false parts:
///
///     GOSPA^p = min over assignments  sum_(assigned pairs, d < c) d^p  +  c^p / 2 x (missed + false)
///
/// A pair farther apart than the cutoff c counts as one missed and one false object. The optimal assignment
/// minimises the sum of min(d, c)^p over min(|truth|, |estimates|) pairs (an optimal assignment of that capped
/// cost matrix is an optimal GOSPA assignment), found by the Hungarian algorithm (shortest augmenting paths with
/// potentials, Jonker-Volgenant style), O(n^2 m).
///
/// Thread-safety: pure functions, reentrant. RT-safe: no (allocates).

#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace ugv::correlator {

struct GospaParams {
    double cutoffM = 5.0; ///< [m] c > 0
    double order = 2.0;   ///< p >= 1
};

/// GOSPA and its parts. The parts are in [m^p]: localisationPart + missedPart + falsePart = total^p.
struct GospaResult {
    double total = 0.0;            ///< [m] the GOSPA distance
    double localisationPart = 0.0; ///< [m^p] sum of d^p over the assigned pairs (d < c)
    double missedPart = 0.0;       ///< [m^p] c^p / 2 per missed true object
    double falsePart = 0.0;        ///< [m^p] c^p / 2 per false estimate
    std::size_t assigned = 0;      ///< pairs closer than c
    std::size_t missed = 0;        ///< true objects without an estimate closer than c
    std::size_t falseCount = 0;    ///< estimates without a true object closer than c
    /// Per true object: the index of its assigned estimate (closer than c), or -1.
    std::vector<int> truthToEstimate;
};

/// GOSPA between `truth` and `estimates` (positions in one plane [m]).
/// @param[in] params c > 0 and p >= 1 (a violation is a bug: UGV_EXPECTS).
[[nodiscard]] GospaResult gospa(const std::vector<Eigen::Vector2d>& truth,
                                const std::vector<Eigen::Vector2d>& estimates, const GospaParams& params = {});

/// Minimum-cost assignment of a rows x cols cost matrix (row-major, finite entries, any shape): every row is
/// assigned a distinct column when rows <= cols, every column a distinct row otherwise.
/// @return per row, its column, or -1 for the rows left over when rows > cols.
[[nodiscard]] std::vector<int> solveAssignment(const std::vector<double>& cost, std::size_t rows, std::size_t cols);

} // namespace ugv::correlator
