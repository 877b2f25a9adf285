#pragma once

/// @file
/// Mode `pose-corrected`'s static objects and their rules:
/// - every static observation is kept in its UGV's frame (a bounded reservoir per track and offset window), so
///   that pose corrections and estimated pose errors re-project it exactly (rebuild);
/// - two tracks one UGV reports at the same instant are two objects (seen apart): a new track never joins an object
///   with a track it was seen with; two objects never merge, nor a track moves between them, once seen apart at
///   kApartInstants instants (one shared instant is often a clutter report beside a real one);
/// - a new track joins the nearest object within the chi-square gate (Mahalanobis distance, the UGVs' pose
///   uncertainty included unless only its own UGV saw the object) and not seen apart from it, else starts one;
/// - a new track kept out of an object by one track of its UGV alone (seen with it; not the object's first track)
///   takes the object when it fits the object's other tracks clearly better than that track does, which moves to
///   another object or starts one (a close pair's post that joined its neighbour first under wide gates): the id
///   stays with the evidence that founded it;
/// - a track whose own estimate lies outside its object's gate and inside another's (not seen apart from it) moves
///   there at the next rebuild (hard-assignment EM over tracks: a first reading decided its object);
/// - split: an object whose tracks form two groups far apart (associated while the pose errors were unknown)
///   splits, the group with more observations keeps the id; merge: two objects within each other's gate and not
///   seen apart become one, the earliest id kept; hysteresis: a split that undoes a merge (the leaving group's
///   tracks came mostly from the absorbed object) revives that object and its id instead of making a new one; a
///   possible duplicate of an older object (within its gate once both objects' pose uncertainty is counted, not seen
///   apart) is not published until a merge folds it in, unless it was published before (markShown: hysteresis);
/// - tentative objects (fewer than minStaticObservations after tentativeTimeoutS) are dropped (clutter);
/// - samples older than the horizon fold into their object's prior.
///
/// Thread-safety: thread-bound. RT-safe: no (allocates).

#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/measurement_model.hpp"
#include "ugv/correlator/messages.hpp"
#include "ugv/correlator/object_ids.hpp"
#include "ugv/correlator/pose_corrected_config.hpp"
#include "ugv/correlator/rules.hpp"
#include "ugv/correlator/ugv_pose_errors.hpp"

namespace ugv::correlator {

class StaticMap {
public:
    struct TrackWindow {
        int window = 0;
        std::uint64_t seen = 0;
        std::vector<RangeBearing> samples; ///< a uniform reservoir of the `seen`
    };
    /// A track's own estimate from its stored samples: the mean, and its covariance (the samples' measurement noise
    /// averaged, plus their UGV's remaining pose uncertainty, which is common to them).
    struct TrackEstimate {
        bool valid = false; ///< false: no samples left
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        Eigen::Matrix2d cov = Eigen::Matrix2d::Identity();
        Eigen::Matrix2d measurementCov = Eigen::Matrix2d::Identity(); ///< the measurement noise averaged alone
    };
    struct Apart {
        int track = -1;
        int instants = 0;
    };
    /// Instants two tracks must share before their objects count as seen apart for a merge, a move or a publication
    /// (one is enough to keep a new track out of an object): one clutter report beside an object's reading at one
    /// instant is chance (measured: seed 24 of correlate-sim's defaults, an object published twice for good), a close
    /// pair in view is reported together at every instant both are seen.
    static constexpr int kApartInstants = 2;
    struct Track {
        int ugv = -1;
        int object = -1;
        OoiClass cls = OoiClass::Static;
        std::vector<TrackWindow> windows;
        std::string key; ///< in trackIndex_
        std::uint64_t seen = 0;
        double lastT = 0.0;
        /// Tracks of the same UGV observed at the same instant as this one, and at how many instants: other objects
        /// (seen apart; see kApartInstants).
        std::vector<Apart> apart;
        /// The object this track first joined: when a merge folded that object into another and the track's group
        /// splits off again, it gets that object's id back (the merge is undone, not a new object made).
        int origin = -1;
    };
    struct StaticObject : rules::Identity {
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        Eigen::Matrix2d info = Eigen::Matrix2d::Zero(); ///< sum of inverse covariances
        Eigen::Vector2d infoMean = Eigen::Vector2d::Zero();
        Eigen::Matrix2d measurementInfo = Eigen::Matrix2d::Zero(); ///< the same without the pose uncertainty
        std::uint64_t observations = 0;
        double firstT = 0.0;
        std::vector<int> tracks;
        Eigen::Matrix2d priorInfo = Eigen::Matrix2d::Zero(); ///< from samples dropped beyond the horizon
        Eigen::Vector2d priorMean = Eigen::Vector2d::Zero();
        /// Weighted sum of its observations' pose covariance (their UGVs' remaining pose uncertainty, common to all
        /// of a UGV's observations, so not reduced by their number) and the weights.
        Eigen::Matrix2d poseCovSum = Eigen::Matrix2d::Zero();
        double weightSum = 0.0;
        /// Once published, not held back again as a possible duplicate (hysteresis: its id stays shown until a
        /// merge folds it in).
        bool shown = false;
    };

    explicit StaticMap(const PoseCorrectedConfig& config);

    /// Stores observation `o` (of UGV index `ugv`, as `sample`) in its track and fuses it into the track's
    /// object, associating a new track first.
    void add(const Observation& o, int ugv, const RangeBearing& sample, const UgvPoseErrors& poses, ObjectIds& ids);
    /// Re-fits every object from its stored samples under the current pose model, then splits and merges.
    void rebuild(const UgvPoseErrors& poses, ObjectIds& ids);
    /// Drops the objects still tentative at time t (and their tracks' samples).
    void dropTentative(double t, ObjectIds& ids);
    /// Drops the samples of windows before `oldestWindow`, folding them into their object's prior.
    void foldBeyondHorizon(int oldestWindow);
    void setState(int object, Confirmation state) { objects_[static_cast<std::size_t>(object)].state = state; }
    /// Marks the objects published now as shown: a possible duplicate of an older object that was shown once stays
    /// shown (hiding it again would only make its id vanish and come back as the gate flips).
    void markShown();
    /// Appends the published static objects to `s` and their positions to `threats`.
    void publish(const LocalFrame& frame, const UgvPoseErrors& poses, Snapshot& s, rules::Placed& threats) const;
    [[nodiscard]] std::size_t storedPoints() const noexcept;
    /// The objects published now, in creation order.
    [[nodiscard]] std::vector<const StaticObject*> published() const;

    /// For the pose-error solver, which estimates the objects' means jointly with the UGVs' errors.
    [[nodiscard]] const std::vector<Track>& tracks() const noexcept { return tracks_; }
    [[nodiscard]] const std::vector<StaticObject>& objects() const noexcept { return objects_; }
    [[nodiscard]] std::vector<StaticObject>& objects() noexcept { return objects_; }
    /// The weighted mean position of a track's stored samples (and the weight).
    [[nodiscard]] Eigen::Vector2d trackMean(int trackIndex, const UgvPoseErrors& poses, double& weight) const;

private:
    /// Adds `sample` to the reservoir of its track's current window.
    void store(Track& track, const RangeBearing& sample, int window);
    /// Records that track `ti` of UGV index `ugv` was observed at time t with the UGV's other tracks of that instant.
    void noteInstant(int ugv, int ti, double t);
    /// A new static object of class `cls` first seen at t; its index.
    int create(OoiClass cls, double t, ObjectIds& ids);
    /// Track `ti` joins the object at index `object` (its first object: its origin).
    void join(int ti, int object);
    /// The estimate of `tracks` but `except` fused from their stored samples under `poses`.
    [[nodiscard]] TrackEstimate estimateOfTracks(const std::vector<int>& tracks, int except,
                                                 const UgvPoseErrors& poses) const;
    /// The object new track `ti` (reading `p`) takes from the one track of its UGV seen with it that keeps it out,
    /// which goes to `displaced` (see the .cpp), or -1.
    [[nodiscard]] int contest(int ugv, int ti, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov,
                              const Eigen::Matrix2d& measurementCov, const UgvPoseErrors& poses, int& displaced) const;
    /// An object's observation count from its tracks' (after tracks moved).
    void recount(StaticObject& object) const;
    /// Track `ti`, displaced from its object at time t, joins the nearest object within its gate not seen apart
    /// from it, else starts one; both objects are re-fitted.
    void rehome(int ti, double t, const UgvPoseErrors& poses, ObjectIds& ids);
    /// Every track of `object` but `except` is one of UGV index `ugv`'s: against it that UGV's pose error is common,
    /// and only measurement noise separates its readings.
    [[nodiscard]] bool onlySeenBy(const StaticObject& object, int ugv, int except = -1) const;
    /// The alive object within the gate of `p` nearest to it and not seen apart from track `ti`, or -1.
    [[nodiscard]] int associate(int ugv, int ti, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov,
                                const Eigen::Matrix2d& measurementCov) const;
    /// Track `ti` and a track of the object at index `object` were observed at `instants` or more instants by one UGV.
    [[nodiscard]] bool trackSeenApart(int ti, int object, int instants) const;
    /// A track of `x` and one of the object at index `y` were observed at kApartInstants instants by one UGV: two
    /// objects.
    [[nodiscard]] bool seenApart(const StaticObject& x, int y) const;
    /// Moves every track outside its object's gate to the object of its class whose gate it is in (see the .cpp);
    /// the tracks' own estimates are those of the refit just before.
    void reassignTracks(const UgvPoseErrors& poses);
    /// The object track `ti` belongs to rather than `current`: -1 while it is within `current`'s gate, else the
    /// nearest alive object of its class within the gate and not seen apart from it, or -1.
    [[nodiscard]] int betterObject(int ti, int current) const;
    /// Recomputes an object's estimate from its tracks' stored samples under the current pose model, and each of
    /// its tracks' own estimate (trackEstimates_).
    void refit(StaticObject& object, const UgvPoseErrors& poses);
    /// A group of tracks' own estimates fused, and whether two groups are apart for the merge test (a split must be).
    [[nodiscard]] TrackEstimate groupEstimate(const std::vector<int>& group) const;
    [[nodiscard]] bool groupsApart(const std::vector<int>& a, const std::vector<int>& b) const;
    void splitAll(const UgvPoseErrors& poses, ObjectIds& ids);
    void split(std::size_t j, const UgvPoseErrors& poses, ObjectIds& ids);
    /// The object most of `tracks`' observations first joined, if a merge folded it into the object at `into`
    /// (its id can come back); else -1.
    [[nodiscard]] int absorbedOrigin(const std::vector<int>& tracks, std::size_t into, const ObjectIds& ids) const;
    /// Two static objects within the merge gate of each other (their estimates' covariances and the floor).
    [[nodiscard]] bool sameObject(const StaticObject& x, const StaticObject& y) const;
    /// Two static objects within the gate of each other once their UGVs' remaining pose uncertainty is added: they
    /// may be one object that the pose errors put in two places.
    [[nodiscard]] bool maybeSameObject(const StaticObject& x, const StaticObject& y) const;
    void mergeAll(ObjectIds& ids);

    PoseCorrectedConfig config_;
    std::vector<Track> tracks_;
    std::vector<TrackEstimate> trackEstimates_; ///< per track, from the last refit of its object
    std::unordered_map<std::string, int> trackIndex_;
    std::vector<StaticObject> objects_;
    /// Per UGV index: the time of its latest observation and the tracks observed then.
    struct Instant {
        double t = -1.0;
        std::vector<int> tracks;
    };
    std::vector<Instant> instants_;
    std::mt19937_64 rng_{11};
};

} // namespace ugv::correlator
