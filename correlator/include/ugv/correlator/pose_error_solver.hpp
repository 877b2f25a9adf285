#pragma once

/// @file
/// Mode `pose-corrected`'s estimate of the UGVs' pose errors: every solvePeriodS, each UGV's heading bias
/// (constant) and position offset (per offsetWindowS window, a random walk between windows) are estimated jointly
/// with the static objects by sparse Gauss-Newton least squares (Eigen), each track window's pull bounded (Huber on
/// its mean, iteratively reweighted: a track on the wrong object moves nothing far); the UAV's anchors (UavAnchors) tie
/// the UGVs' poses to the absolute frame, and zero-mean priors fix what no anchor reaches (the fleet on average is
/// unbiased). If the evidence cannot show a pose error, nothing moves: the estimates of all UGVs, tested jointly
/// against their posterior covariance (the information of the samples stored, under the learnt noise), within the
/// chi-square quantile at the gates' significance are set to zero. Then each UGV's noise is learnt from its
/// residuals (learnNoise): the gates widen with what is measured, never below the configured model.
///
/// Thread-safety: reentrant (const; the state is in the StaticMap and UgvPoseErrors given). RT-safe: no.

#include "ugv/correlator/pose_corrected_config.hpp"
#include "ugv/correlator/static_map.hpp"
#include "ugv/correlator/uav_anchors.hpp"
#include "ugv/correlator/ugv_pose_errors.hpp"

namespace ugv::correlator {

class PoseErrorSolver {
public:
    explicit PoseErrorSolver(const PoseCorrectedConfig& config);

    /// solveIterations Gauss-Newton steps over the UGVs' errors (into `poses`) and the means of the static objects
    /// with at least minStaticObservations (into `map`), with the UAV's `anchors` as absolute references; then, when
    /// the estimates are not significantly different from zero (jointly, at the gates' significance), every UGV's
    /// errors are set to zero (the objects' means follow at the next StaticMap::rebuild).
    /// @return false when there was nothing to solve or the system was singular (the steps before it stay).
    bool estimate(StaticMap& map, UgvPoseErrors& poses, const UavAnchors& anchors) const;

    /// Each UGV's noise scales from the residuals of its stored static samples about their objects (robust
    /// spread: 1.4826 x the median absolute residual, in range and across the ray, over the configured sigma).
    void learnNoise(const StaticMap& map, UgvPoseErrors& poses) const;

    /// Each UGV's remaining pose error (UgvPoseErrors::Ugv::poseSpreadM): the robust spread of its tracks' mean
    /// positions about the objects that other UGVs saw too (the median distance over that of a 2-D Gaussian).
    void learnPoseSpread(const StaticMap& map, UgvPoseErrors& poses) const;

private:
    PoseCorrectedConfig config_;
};

} // namespace ugv::correlator
