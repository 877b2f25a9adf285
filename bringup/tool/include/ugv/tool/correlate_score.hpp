#pragma once

/// @file
/// Scoring of correlator snapshots against a scenario's truth, shared by `ugvsense correlate-eval` (snapshots and
/// truth read from files) and its sweep (both in memory):
/// - GOSPA (c = 5 m, p = 2, alpha = 2) of the static objects at the last snapshot, split into localisation, missed
///   and false parts;
/// - the mean GOSPA over the snapshots of the mobile objects and of the non-combatants, each snapshot's objects of
///   that class against the truth sample nearest in time (within half the truth period) of every such object;
/// - the static ID changes: per static truth object, the id of the snapshot object GOSPA assigns to it; a change
///   counts between consecutive snapshots in which it is assigned both times.
/// Distances are in metres in the tangent plane at the truth's origin.
///
/// Thread-safety: reentrant (no shared state). RT-safe: no (host tooling).

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/gospa.hpp"
#include "ugv/correlator/messages.hpp"
#include "ugv/correlator/scenario.hpp"

namespace ugv::tool {

inline constexpr correlator::GospaParams kScoreGospa{5.0, 2.0}; ///< c = 5 m, p = 2 (alpha = 2 is built in)
inline constexpr int kScoreAlpha = 2;

struct TimedPosition {
    double t = 0.0;
    Eigen::Vector2d position = Eigen::Vector2d::Zero(); ///< [m] local east, north
};

struct MovingTrack {
    correlator::OoiClass cls = correlator::OoiClass::Mobile;
    std::vector<TimedPosition> samples; ///< by t
};

/// The truth in the tangent plane at its origin.
struct Truth {
    double originLat = 0.0;
    double originLon = 0.0;
    double durationS = 0.0;
    double periodS = 0.0;
    std::vector<std::string> staticIds;
    std::vector<Eigen::Vector2d> statics;      ///< [m] local east, north
    std::map<std::string, MovingTrack> moving; ///< by id
};

/// The generator's truth in the scorer's form (what correlate-eval reads back from the truth file).
[[nodiscard]] Truth truthOf(const correlator::ScenarioTruth& truth);

/// Sums of GOSPA figures over snapshots, for their means.
struct GospaMean {
    std::size_t snapshots = 0;
    double total = 0.0;
    double localisationPart = 0.0;
    double missedPart = 0.0;
    double falsePart = 0.0;

    void add(const correlator::GospaResult& r);
    [[nodiscard]] double mean(double sum) const { return snapshots > 0 ? sum / static_cast<double>(snapshots) : 0.0; }
};

struct Figures {
    std::size_t snapshots = 0;
    double firstT = 0.0;
    double lastT = 0.0;
    correlator::GospaResult staticLast;
    std::size_t staticEstimates = 0; ///< static objects in the last snapshot
    GospaMean mobile;
    GospaMean nonCombatant;
    std::size_t staticIdChanges = 0;
};

/// Scores snapshots one at a time, in time order (no snapshot is kept).
class SnapshotScorer {
public:
    explicit SnapshotScorer(const Truth& truth);
    void add(const correlator::Snapshot& snapshot);
    [[nodiscard]] const Figures& figures() const noexcept { return figures_; }

private:
    const Truth& truth_;
    correlator::LocalFrame frame_;
    Figures figures_;
    std::vector<std::string> previousIds_; ///< per static truth object: its id in the previous snapshot (empty: none)
};

/// The figures of snapshots in time order (at least one).
[[nodiscard]] Figures score(const std::vector<correlator::Snapshot>& snapshots, const Truth& truth);

} // namespace ugv::tool
