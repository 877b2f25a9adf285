#pragma once

/// @file
/// Mode `pose-corrected`'s mobile objects (mobile OOIs and non-combatants, classes apart): a constant-velocity
/// Kalman filter each (continuous white acceleration), predicted through gaps, published after
/// minMobileObservations (or a UAV fix) while the prediction's sigma stays below 2.5 m; once an object's history
/// shows a line walked back and forth, it is predicted along that line (turning at its ends, the sigma growing
/// with the speed's uncertainty), and a measurement far from the prediction re-learns the velocity (a manoeuvre).
/// A UGV track stays with its object; a new track joins the nearest object within the gate, else starts one.
/// Objects unseen for mobileTimeoutS are dropped.
///
/// Thread-safety: thread-bound. RT-safe: no (allocates).

#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/messages.hpp"
#include "ugv/correlator/object_ids.hpp"
#include "ugv/correlator/pose_corrected_config.hpp"
#include "ugv/correlator/rules.hpp"

namespace ugv::correlator {

class MobileTracker {
public:
    /// The line a mobile object walks back and forth: centre + a u, a in [lo, hi], at `speed`.
    struct Line {
        bool valid = false;
        Eigen::Vector2d centre = Eigen::Vector2d::Zero();
        Eigen::Vector2d u = Eigen::Vector2d::UnitX(); ///< unit direction
        double lo = 0.0;                              ///< [m] along u from centre
        double hi = 0.0;                              ///< [m]
        double speed = 0.0;                           ///< [m/s]
        double speedSigma = 0.0;                      ///< [m/s]
        double width = 0.0;                           ///< [m] rms distance of the history from the line
    };
    struct Mobile : rules::Identity {
        Eigen::Vector4d x = Eigen::Vector4d::Zero(); ///< east, north, v_east, v_north
        Eigen::Matrix4d p = Eigen::Matrix4d::Identity();
        double t = 0.0;
        int observations = 0;
        std::vector<std::string> ugvs;
        std::vector<std::pair<double, Eigen::Vector2d>> history; ///< filtered positions, 1 per s, last 180 s
        Line line;                                               ///< fitted to history
    };

    explicit MobileTracker(const PoseCorrectedConfig& config);

    /// A UGV's observation `o` of a mobile object at `p` (covariance `cov`).
    void add(const Observation& o, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov, ObjectIds& ids);
    /// A new object at `z` (covariance `r`) at time t. @return its index
    int create(OoiClass cls, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t, ObjectIds& ids);
    /// The measurement `z` (covariance `r`) at time t of the object at `index`.
    void update(int index, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t);
    /// The object at `index` was fixed by the UAV: confirmed positive, "uav" among its sources.
    void markFixedByUav(int index);
    void setState(int index, Confirmation state) { mobiles_[static_cast<std::size_t>(index)].state = state; }
    /// Drops the objects unseen for mobileTimeoutS at time t.
    void timeOut(double t);
    /// Where m is at t, and the covariance: along its line if it walks one, else by its Kalman filter.
    void predictPosition(const Mobile& m, double t, Eigen::Vector2d& p, Eigen::Matrix2d& cov) const;
    /// Appends the published objects at time t to `s`, their positions to `civilians` or `threats`.
    void publish(double t, const LocalFrame& frame, Snapshot& s, rules::Placed& civilians,
                 rules::Placed& threats) const;
    [[nodiscard]] const std::vector<Mobile>& mobiles() const noexcept { return mobiles_; }

private:
    struct LinePrediction {
        Eigen::Vector2d position = Eigen::Vector2d::Zero();
        Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
        double sigma = 0.0; ///< [m]
    };

    /// The alive object of class `cls` nearest to `z` within the gate at time t, or -1.
    [[nodiscard]] int nearest(OoiClass cls, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t) const;
    void predict(Mobile& m, double t) const;
    void updateMobile(Mobile& m, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t) const;
    void predictState(Eigen::Vector4d& x, Eigen::Matrix4d& p, double dt) const;
    /// Mobile OOIs walk fixed lines back and forth (the original's observation): once the history shows one,
    /// the position at time t along it, turning at its ends. @return false when the history shows no line.
    [[nodiscard]] bool predictOnLine(const Mobile& m, double t, LinePrediction& out) const;
    static void fitLine(Mobile& m);

    PoseCorrectedConfig config_;
    std::vector<Mobile> mobiles_;
    std::unordered_map<std::string, int> trackObject_; ///< (ugv, track) -> mobile index
};

} // namespace ugv::correlator
