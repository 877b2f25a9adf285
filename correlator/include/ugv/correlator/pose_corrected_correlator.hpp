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
///   squares with Eigen (zero-mean priors fix the gauge: the fleet on average is unbiased);
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
/// Thread-safety: thread-bound. RT-safe: no (the lowest-priority task).

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/messages.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::correlator {

struct PoseCorrectedConfig {
    // Observation error model.
    double rangeSigmaM = 0.1;
    double rangeSigmaFraction = 0.01;
    double bearingSigmaDeg = 1.0;
    // Pose error priors and the drift model.
    double headingBiasSigmaDeg = 5.0;
    double offsetSigmaM = 1.0;
    double driftSigmaMPerSqrtS = 0.05;
    double offsetWindowS = 60.0;
    double solvePeriodS = 120.0;
    int solveIterations = 2;
    // Association.
    double gateChi2 = 11.8; ///< 2 degrees of freedom, 99.7 %
    int minStaticObservations = 3;
    double tentativeTimeoutS = 60.0;       ///< an object with fewer observations this long after its first is dropped
    std::size_t samplesPerTrackWindow = 4; ///< reservoir per track and offset window
    double horizonS = 1800.0;              ///< windows older than this are frozen and their samples dropped
    // Mobile objects.
    /// [m^2/s^3] density of the continuous white acceleration of a mobile object: people walk at a steady
    /// velocity for tens of seconds; turns are handled as manoeuvres (the velocity is re-learnt, see
    /// updateMobile), not by a process noise large enough to cover them.
    double mobileAccelDensity = 0.05;
    double mobileTimeoutS = 60.0;
    int minMobileObservations = 3;
    double uavSigmaM = 0.5;
};

class PoseCorrectedCorrelator {
public:
    explicit PoseCorrectedCorrelator(const PoseCorrectedConfig& config = {});

    /// Applies one message (time-ordered). Errors (the message is skipped): a confirm of an unknown id.
    Result<void, Error> add(const Message& message);
    /// What the passing of time alone changes, up to `t`: the UAV fixes still pending are assigned, static objects
    /// still tentative tentativeTimeoutS after their first observation are dropped, mobile objects unseen for
    /// mobileTimeoutS are dropped. Call it before snapshot(t) (CorrelatorFeed does at every period boundary).
    void advance(double t);
    /// The objects and alerts at time `t`, as advance(t) left them; changes nothing.
    [[nodiscard]] Snapshot snapshot(double t) const;
    [[nodiscard]] std::size_t storedPoints() const noexcept;

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
    struct Sample {
        double t = 0.0;
        Eigen::Vector2d ugvPos = Eigen::Vector2d::Zero(); ///< reported, local frame
        double headingRad = 0.0;                          ///< reported
        double rangeM = 0.0;
        double bearingRad = 0.0;
    };
    struct TrackWindow {
        int window = 0;
        std::uint64_t seen = 0;
        std::vector<Sample> samples;
    };
    struct Track {
        int ugv = -1;
        int object = -1;
        OoiClass cls = OoiClass::Static;
        std::vector<TrackWindow> windows;
        std::string key; ///< in trackIndex_
        std::uint64_t seen = 0;
        double lastT = 0.0;
    };
    struct StaticObject {
        std::string id;
        std::uint64_t order = 0;
        OoiClass cls = OoiClass::Static;
        Confirmation state = Confirmation::Unknown;
        bool alive = true;
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        Eigen::Matrix2d info = Eigen::Matrix2d::Zero(); ///< sum of inverse covariances
        Eigen::Vector2d infoMean = Eigen::Vector2d::Zero();
        Eigen::Matrix2d measurementInfo = Eigen::Matrix2d::Zero(); ///< the same without the pose uncertainty
        std::uint64_t observations = 0;
        double firstT = 0.0;
        std::vector<int> tracks;
        Eigen::Matrix2d priorInfo = Eigen::Matrix2d::Zero(); ///< from samples dropped beyond the horizon
        Eigen::Vector2d priorMean = Eigen::Vector2d::Zero();
    };
    struct Ugv {
        std::string name;
        double headingBias = 0.0;                ///< [rad] estimated
        std::vector<Eigen::Vector2d> offsets;    ///< estimated, per window
        std::vector<PoseCorrection> corrections; ///< explicit, from the map builder
        bool solved = false;
        /// Learnt noise (learnNoise): the measured spread of this UGV's residuals over the configured one, per
        /// direction, never below 1 (the configured model is the floor: gates only widen with what is measured).
        double rangeScale = 1.0;
        double bearingScale = 1.0;
    };
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
    struct LinePrediction {
        Eigen::Vector2d position = Eigen::Vector2d::Zero();
        Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
        double sigma = 0.0; ///< [m]
    };
    struct Mobile {
        std::string id;
        std::uint64_t order = 0;
        OoiClass cls = OoiClass::Mobile;
        Confirmation state = Confirmation::Unknown;
        bool alive = true;
        Eigen::Vector4d x = Eigen::Vector4d::Zero(); ///< east, north, v_east, v_north
        Eigen::Matrix4d p = Eigen::Matrix4d::Identity();
        double t = 0.0;
        int observations = 0;
        std::vector<std::string> ugvs;
        std::vector<std::pair<double, Eigen::Vector2d>> history; ///< filtered positions, 1 per s, last 180 s
        Line line;                                               ///< fitted to history
    };

    int ugvIndex(const std::string& name);
    [[nodiscard]] int window(double t) const;
    /// The object position an observation implies under the current pose model, and its covariance.
    void projectSample(int ugv, const Sample& s, Eigen::Vector2d& p, Eigen::Matrix2d* cov, bool withPose = true) const;
    [[nodiscard]] Eigen::Vector2d offsetAt(int ugv, double t) const;
    /// @return true when a pose correction covers time t (dPos, dHeading set from it).
    bool explicitCorrection(int ugv, double t, Eigen::Vector2d& dPos, double& dHeading) const;
    void addStatic(const Observation& o, int ugv);
    void addMobile(const Observation& o, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov);
    void addUav(const UavFix& u);
    void flushUav();
    [[nodiscard]] int nearestMobile(OoiClass cls, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t) const;
    int createMobile(OoiClass cls, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t);
    Result<void, Error> confirm(const Confirm& c);
    void fuse(StaticObject& object, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov,
              const Eigen::Matrix2d& measurementCov, double weight = 1.0) const;
    void refit(StaticObject& object) const;
    void solve();
    /// Each UGV's noise scales from the residuals of its stored static samples about their objects (robust
    /// spread: 1.4826 x the median absolute residual, in range and across the ray, over the configured sigma).
    void learnNoise();
    void rebuildObjects();
    /// Two static objects within the merge gate of each other (their estimates' covariances and the floor).
    [[nodiscard]] bool sameObject(const StaticObject& x, const StaticObject& y) const;
    void mergeStatics();
    void dropTentative(double t);
    void timeOutMobiles(double t);
    void splitStatics();
    [[nodiscard]] Eigen::Vector2d trackMean(int trackIndex, double& weight) const;
    void predict(Mobile& m, double t) const;
    void predictState(Eigen::Vector4d& x, Eigen::Matrix4d& p, double dt) const;
    /// Mobile OOIs walk fixed lines back and forth (the original's observation): once the history shows one,
    /// the position at time t along it, turning at its ends. @return false when the history shows no line.
    [[nodiscard]] bool predictOnLine(const Mobile& m, double t, LinePrediction& out) const;
    static void fitLine(Mobile& m);
    /// Where m is at t, and the covariance: along its line if it walks one, else by its Kalman filter.
    void predictPosition(const Mobile& m, double t, Eigen::Vector2d& p, Eigen::Matrix2d& cov) const;
    void updateMobile(Mobile& m, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t) const;
    std::string newId();

    PoseCorrectedConfig config_;
    std::optional<LocalFrame> frame_;
    std::vector<Ugv> ugvs_;
    std::unordered_map<std::string, int> ugvIndex_;
    std::vector<Track> tracks_;
    std::unordered_map<std::string, int> trackIndex_;
    std::vector<StaticObject> statics_;
    std::vector<Mobile> mobiles_;
    std::unordered_map<std::string, int> mobileTrackObject_; ///< (ugv, track) -> mobile index
    std::vector<UavFix> pendingUav_;                         ///< the fixes of the latest instant, not yet assigned
    std::unordered_map<std::string, std::string> mergedInto_;
    std::unordered_map<std::string, std::pair<bool, int>> idIndex_; ///< id -> (static?, index)
    std::mt19937_64 rng_{11};
    std::uint64_t nextId_ = 1;
    double now_ = 0.0;
    double lastSolveT_ = 0.0;
};

} // namespace ugv::correlator
