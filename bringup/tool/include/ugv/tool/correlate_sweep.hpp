#pragma once

/// @file
/// `ugvsense correlate-eval --sweep`: both correlator modes over a grid of simulated worlds (correlator/scenario.hpp),
/// several seeds per point, scored in memory (correlate_score.hpp); per point the median and the worst seed of
/// each mode, the issue 21 targets checked, and a JSON summary.
///
/// The grid is not a Cartesian product: two centres, each knob moved alone over its range around each of them
/// (one factor at a time), plus the two scenarios:
/// - centre `sim`: correlate-sim's defaults (bearing 1 deg, range 1 % + 0.1 m, field of view +-60 deg, UUID switch
///   0.002, misses 20 %, clutter 0.02 Hz, close pairs 3.5-5 m, 200 m area, 20 statics, no pose errors);
/// - centre `harsh`: issue 21's "bias" scenario (250 m area, 30 statics with 5 close pairs 3.5-5 m, 3 mobiles,
///   bearing 2 deg, range 4 % + 0.2 m, +-35 deg, misses 15 %, UUID switch 0.02, clutter 1/60 Hz, heading bias up
///   to 8 deg, Gaussian offsets of 1 m sigma);
/// - `harsh/drift`: the same plus a random-walk drift of 0.05 m/sqrt(s) (issue 21's second scenario).
/// The knobs and their values: bearing 0.5, 3 deg; range 1 % + 0.1 m, 5 % + 0.3 m; field of view 35, 60 deg; UUID
/// switch 0.002, 0.02, 0.05; offsets Gaussian 1.5 m, Student-t(3) 1 m, none; misses 10, 30 %; clutter 0.01,
/// 0.05 Hz; close pairs 3, 5 m; heading bias 0, 2, 10 deg; drift 0.02, 0.08 m/sqrt(s).
/// `--quick`: the two centres, the drift scenario and the sim centre with bias, 600 s each (a ctest test).
///
/// Thread-safety: thread-bound (one scenario at a time, on the calling thread). RT-safe: no (host tooling).

#include <cstdint>
#include <string>

namespace ugv::tool {

struct SweepOptions {
    bool quick = false;
    int seeds = 10;
    double durationS = 1800.0; ///< [s] of every scenario (--quick: 600 unless given)
    std::uint64_t firstSeed = 1;
    std::string only;            ///< run only the points whose name contains this (empty: all)
    std::string jsonPath;        ///< write the summary here (empty: none)
    bool requireTargets = false; ///< exit 3 when a target is not met
};

/// Runs the sweep, prints the table and the targets, writes the JSON summary.
/// @return the exit code: 0, 1 when the summary cannot be written, 3 when requireTargets and a target is missed
int runCorrelateSweep(const SweepOptions& options);

} // namespace ugv::tool
