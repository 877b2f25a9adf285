#pragma once

/// @file
/// Mode `pose-corrected`'s model of each UGV's pose errors: its estimated heading bias (constant) and position
/// offset (one per offsetWindowS window, a random walk between windows), the map builder's explicit pose corrections
/// (authoritative where they exist), and its learnt noise scales. It projects a stored observation to the object
/// position it implies under that model, with the covariance of the measurement and of the remaining pose error.
/// The estimates are written by PoseErrorSolver.
///
/// Thread-safety: thread-bound. RT-safe: no (allocates).

#include <cstddef>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "ugv/correlator/measurement_model.hpp"
#include "ugv/correlator/messages.hpp"
#include "ugv/correlator/pose_corrected_config.hpp"

namespace ugv::correlator {

class UgvPoseErrors {
public:
    struct Ugv {
        std::string name;
        double headingBias = 0.0;                ///< [rad] estimated
        std::vector<Eigen::Vector2d> offsets;    ///< [m] estimated, per window
        std::vector<PoseCorrection> corrections; ///< explicit, from the map builder
        bool solved = false;
        /// Learnt noise (learnNoise): the measured spread of this UGV's residuals over the configured one, per
        /// direction, never below 1 (the configured model is the floor: gates only widen with what is measured).
        double rangeScale = 1.0;
        double bearingScale = 1.0;
        /// [m] learnt (learnPoseSpread): the spread of this UGV's track means about the objects other UGVs saw
        /// too, once its errors are estimated: the pose error the estimate left (0: not measured yet).
        double poseSpreadM = 0.0;
        /// [rad], [m] how far the last solve moved the heading bias and the latest offset: the estimate is not
        /// known better than that (the first solve moves it from zero by the whole error).
        double headingStep = 0.0;
        double offsetStepM = 0.0;
    };

    explicit UgvPoseErrors(const PoseCorrectedConfig& config);

    /// The index of the UGV called `name`, added (no errors estimated yet) when new.
    int index(const std::string& name);
    [[nodiscard]] std::optional<int> find(const std::string& name) const;
    [[nodiscard]] std::size_t size() const noexcept { return ugvs_.size(); }
    [[nodiscard]] Ugv& ugv(std::size_t index) { return ugvs_[index]; }
    [[nodiscard]] const Ugv& ugv(std::size_t index) const { return ugvs_[index]; }

    void addCorrection(const PoseCorrection& correction);
    /// The offset window of time t.
    [[nodiscard]] int window(double t) const;
    /// [m] the estimated offset of `ugv` at time t (zero before any estimate; the last window's after it).
    [[nodiscard]] Eigen::Vector2d offsetAt(int ugv, double t) const;
    /// @return true when a pose correction covers time t (dPos [m], dHeading [rad] set from it).
    bool explicitCorrection(int ugv, double t, Eigen::Vector2d& dPos, double& dHeading) const;
    /// The object position `s` implies under the current pose model and, for each pointer that is not null: `cov`
    /// its covariance, the measurement noise and the UGV's remaining pose uncertainty (prior before its errors are
    /// estimated or corrected, smaller after); `measurementCov` the measurement noise alone; `ray` the unit vector
    /// from the UGV towards it under that model.
    void project(int ugv, const RangeBearing& s, Eigen::Vector2d& p, Eigen::Matrix2d* cov,
                 Eigen::Matrix2d* measurementCov = nullptr, Eigen::Vector2d* ray = nullptr) const;
    /// The covariance the prior pose errors (heading bias and offset, before any estimate) add to the position of
    /// `s` seen along `ray`: the absolute pose uncertainty, which the solves (they measure the UGVs' errors against
    /// each other) do not reduce without an absolute reference.
    [[nodiscard]] Eigen::Matrix2d priorPoseCovariance(const RangeBearing& s, const Eigen::Vector2d& ray) const;

private:
    struct PoseSigmas {
        double heading = 0.0; ///< [rad]
        double offsetM = 0.0; ///< [m] per axis
    };
    [[nodiscard]] double priorHeadingSigma() const;
    [[nodiscard]] PoseSigmas remainingSigmas(const Ugv& u, bool corrected) const;

    PoseCorrectedConfig config_;
    std::vector<Ugv> ugvs_;
    std::unordered_map<std::string, int> index_;
};

} // namespace ugv::correlator
