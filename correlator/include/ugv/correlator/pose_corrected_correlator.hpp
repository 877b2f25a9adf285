#pragma once

/// @file
/// Mode `pose-corrected` (alias `improved`, its former name): the original's weakness is disagreement between the UGVs'
/// poses (a few degrees of heading error puts one object in two places; a drifting UGV doubles every shared object) and
/// a fixed 2.5 m gate that merges distinct objects standing close together. This mode:
/// - keeps every static observation in the UGV's frame (reported pose, range, bearing; a bounded reservoir per
///   track and offset window) so that pose corrections and estimated pose errors re-project it exactly;
/// - models each observation's error: range sigma a + b r, bearing sigma, plus the UGV's remaining pose
///   uncertainty; associates by Mahalanobis distance (chi-square gate) instead of a fixed radius; the noise is
///   learnt per UGV from its residuals after every solve (learnNoise): the gates widen with what is measured,
///   never below the configured model;
/// - estimates, every solvePeriodS, each UGV's heading bias (constant) and position offset (per offsetWindowS
///   window, a random walk between windows) jointly with the static objects, by sparse Gauss-Newton least
///   squares with Eigen; the UAV's fixes of mobile objects that UGVs observe too are absolute anchors (UavAnchors)
///   that make the fleet's common offset observable, and zero-mean priors fix what no anchor reaches;
/// - tracks mobile objects with a constant-velocity Kalman filter (continuous white acceleration), predicted
///   through gaps, published after minMobileObservations while the prediction's sigma stays below 2.5 m; once
///   the object's history shows a line walked back and forth, it is predicted along that line (turning at its
///   ends, the sigma growing with the speed's uncertainty), and a measurement far from the prediction re-learns
///   the velocity (a manoeuvre); UAV fixes are precise measurements that confirm, the fixes of one instant
///   assigned together (an optimal assignment), one beyond every gate to an object it could have walked to;
/// - never changes a published id: merges keep the earliest; a track stays with its object, unless the object's
///   tracks form two groups far apart (associated while the pose errors were unknown): then it splits, and the
///   group with more observations keeps the id; a duplicate of an older object (a churned track UUID whose first
///   reading missed the gate) is not shown until the next merge folds it in (the older id stays).
///
/// The parts, each in its own file: UgvPoseErrors (the pose model and the projection of an observation),
/// StaticMap (static objects, association, split/merge, tentative drop), PoseErrorSolver (Gauss-Newton and
/// noise learning), MobileTracker (Kalman and line-walking mobiles), UavAssignment (the fixes of an instant),
/// UavAnchors (UGV observations of UAV-fixed objects) and ObjectIds; this class composes them and orders their steps.
///
/// Thread-safety: thread-bound. RT-safe: no (the lowest-priority task).

#include <cstddef>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/messages.hpp"
#include "ugv/correlator/mobile_tracker.hpp"
#include "ugv/correlator/object_ids.hpp"
#include "ugv/correlator/pose_corrected_config.hpp"
#include "ugv/correlator/pose_error_solver.hpp"
#include "ugv/correlator/static_map.hpp"
#include "ugv/correlator/uav_anchors.hpp"
#include "ugv/correlator/uav_assignment.hpp"
#include "ugv/correlator/ugv_pose_errors.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::correlator {

class PoseCorrectedCorrelator {
public:
    explicit PoseCorrectedCorrelator(const PoseCorrectedConfig& config = {});

    /// Applies one message (time-ordered). Errors (the message is skipped): a confirm of an unknown id.
    Result<void, Error> add(const Message& message);
    /// What the passing of time alone changes, up to `t`: the UAV fixes still pending are assigned (and the UGV
    /// sightings they bracket become anchors), static objects still tentative tentativeTimeoutS after their first
    /// observation are dropped, mobile objects unseen for mobileTimeoutS are dropped. Call it before snapshot(t)
    /// (CorrelatorFeed does at every period boundary).
    void advance(double t);
    /// The objects and alerts at time `t`, as advance(t) left them; changes nothing.
    [[nodiscard]] Snapshot snapshot(double t) const;
    [[nodiscard]] std::size_t storedPoints() const noexcept
    {
        return statics_.storedPoints() + anchors_.storedPoints();
    }

    /// The current estimate of a UGV's heading bias [deg] and offset at time t [m] (tests, diagnostics).
    struct PoseError {
        double headingBiasDeg = 0.0;
        Eigen::Vector2d offset = Eigen::Vector2d::Zero();
    };
    [[nodiscard]] std::optional<PoseError> poseError(const std::string& ugv, double t) const;

    /// A UGV's learnt noise: the measured spread of its range and cross-range residuals over the configured
    /// model's, each at least 1 (tests, diagnostics).
    struct NoiseScale {
        double range = 1.0;
        double bearing = 1.0;
    };
    [[nodiscard]] std::optional<NoiseScale> noiseScale(const std::string& ugv) const;

private:
    void addObservation(const Observation& o);
    Result<void, Error> confirm(const Confirm& c);
    /// Re-projects every stored static observation under the current pose model (after a correction or a solve).
    void rebuildStatics();
    /// Every solvePeriodS of mission time: the pose errors and the static map estimated jointly, the noise learnt.
    void solve();
    /// Assigns the UAV fixes held; the observations they now bracket become anchors.
    void flushUav();

    PoseCorrectedConfig config_;
    std::optional<LocalFrame> frame_;
    UgvPoseErrors poses_;
    ObjectIds ids_;
    StaticMap statics_;
    MobileTracker mobiles_;
    UavAssignment uav_;
    UavAnchors anchors_;
    PoseErrorSolver solver_;
    double now_ = 0.0;
    double lastSolveT_ = 0.0;
};

} // namespace ugv::correlator
