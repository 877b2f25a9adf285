#pragma once

/// @file
/// Mode `pose-corrected`'s absolute anchors from the UAV feed. The UAV fixes mobile objects where they are, free of
/// the UGVs' pose errors; a UGV's observation of a fixed object between two of its fixes says where that UGV's
/// reported pose puts a point known in the absolute frame. The static objects alone cannot give the fleet's common
/// offset (moving every UGV and every object by one vector changes no residual): these anchors make it observable
/// to PoseErrorSolver.
/// - A UGV's observation of a mobile object waits until the fixes of the UAV's objects bracket its time (resolve(),
///   after each instant of fixes); one that no pair of fixes brackets within mobileTimeoutS is dropped.
/// - Its anchor is the object's position interpolated between the two fixes. The anchor's variance is measured, not
///   tuned: the UAV's noise (uavSigmaM) at both fixes, plus the worst a walker can stray from the chord between
///   them (half of what it could walk beyond the chord at the fastest speed its recent fixes show: a turn between
///   the fixes). That error is common to every anchor of one pair of fixes: the UAV part of each is scaled by their
///   number, so the pair counts once however many observations fall between its fixes.
/// - An observation becomes an anchor only when exactly one fixed object of its class is within its gate: its
///   measurement noise, the anchor's variance and the prior pose uncertainty (the absolute one: the solves measure
///   the UGVs' errors against each other, which leaves the common part as uncertain as the prior says). The solver
///   applies the same gate under the estimate of the moment, so an anchor made while its UGV's pose was known worse
///   drops out once the estimate shows it far from the object it seemed to be.
///
/// Thread-safety: thread-bound. RT-safe: no (allocates).

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "ugv/correlator/measurement_model.hpp"
#include "ugv/correlator/messages.hpp"
#include "ugv/correlator/pose_corrected_config.hpp"
#include "ugv/correlator/ugv_pose_errors.hpp"

namespace ugv::correlator {

class UavAnchors {
public:
    struct Anchor {
        int ugv = -1;
        RangeBearing sample;                                ///< the UGV's observation, in its reported frame
        Eigen::Vector2d position = Eigen::Vector2d::Zero(); ///< [m] where the UAV's fixes put the object at sample.t
        double sharedVariance = 0.0; ///< [m^2] per axis: the error of `position` (fixes and interpolation)
        double shares = 1.0;         ///< anchors made from the same pair of fixes (that error is common to them)
    };

    explicit UavAnchors(const PoseCorrectedConfig& config);

    /// A UGV's (index `ugv`) observation `sample` of a mobile object of class `cls`, held until fixes bracket it.
    void observe(int ugv, OoiClass cls, const RangeBearing& sample);
    /// The UAV fixed the mobile object `object` (the tracker's index) of class `cls` at `position` [m] at time t.
    void fix(int object, OoiClass cls, double t, const Eigen::Vector2d& position);
    /// The held observations that fixes now bracket become anchors (or are dropped); see the file comment.
    void resolve(const UgvPoseErrors& poses);
    /// Drops the anchors of offset windows before `oldestWindow` (the solver's horizon).
    void dropBefore(int oldestWindow, const UgvPoseErrors& poses);
    [[nodiscard]] const std::vector<Anchor>& anchors() const noexcept { return anchors_; }
    [[nodiscard]] std::size_t held() const noexcept { return pending_.size(); }
    /// The observations stored: anchors and held ones.
    [[nodiscard]] std::size_t storedPoints() const noexcept { return anchors_.size() + pending_.size(); }

private:
    struct Held {
        int ugv = -1;
        OoiClass cls = OoiClass::Mobile;
        RangeBearing sample;
    };
    struct Fix {
        double t = 0.0;
        Eigen::Vector2d position = Eigen::Vector2d::Zero();
    };
    struct Fixed {
        int object = -1;
        OoiClass cls = OoiClass::Mobile;
        std::vector<Fix> fixes; ///< the latest, by t
    };
    /// Where `f`'s fixes put its object at time t and the variance of that [m^2]. @return false: no bracket
    [[nodiscard]] bool interpolate(const Fixed& f, double t, Eigen::Vector2d& position, double& variance,
                                   int& bracket) const;

    PoseCorrectedConfig config_;
    std::vector<Held> pending_;
    std::vector<Fixed> fixed_;
    std::vector<Anchor> anchors_;
};

} // namespace ugv::correlator
