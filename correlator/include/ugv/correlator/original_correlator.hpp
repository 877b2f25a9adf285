#pragma once

/// @file
/// The published MAGIC correlator, faithfully (mode `original`):
/// - Static objects (class static, and unknown: not seen to move): every observation is kept per UGV track UUID;
///   from 3 observations on, the track is fitted by EM with one or two Gaussian components (two when one track
///   covers two objects). A component joins an object when their error bounds (boundSigmas-sigma ellipses)
///   overlap or their centres are within mergeRadiusM; objects that come to overlap merge; the earliest id is
///   kept and later observations of either track go to it. Confirmation starts from the class (non-combatant:
///   confirmed negative, otherwise unknown), changes by confirm messages and is inherited by merges (a
///   confirmed state wins over unknown; between two confirmed states the kept object's stays).
/// - Mobile objects (combatant and non-combatant apart): the last two observations per track; the position is
///   the weighted average of those and the newest (0.5 newest, 0.3, 0.2); removed after mobileTimeoutS without
///   an observation; merged within mergeRadiusM. A UAV fix moves the nearest mobile object of its class within
///   uavGateM (or a new one) to the fix and confirms it positive.
/// - Pose corrections are not part of the original algorithm: they are counted and ignored.
/// Memory stays bounded: a track keeps at most maxPointsPerTrack points (a uniform reservoir of all it saw,
/// while its Gaussian uses every observation's moments); a static track idle for retireAfterS drops its points
/// and keeps its fit; tracks that never reached 3 observations and idle mobile tracks are forgotten.
///
/// Thread-safety: thread-bound. RT-safe: no (the correlator is the lowest-priority task).

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "ugv/correlator/gaussian_mixture.hpp"
#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/messages.hpp"
#include "ugv/correlator/rules.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::correlator {

struct OriginalConfig {
    double mergeRadiusM = 2.5;
    double boundSigmas = 2.0; ///< an error bound is this many standard deviations
    int minTrackObservations = 3;
    double mobileTimeoutS = 60.0;
    double uavGateM = 5.0;
    std::size_t maxPointsPerTrack = 256;
    double retireAfterS = 300.0;
    int refitEvery = 4; ///< a static track's two-component EM runs every this many observations (and at 3..16)
    MixtureConfig mixture;
    double mobileSigmaM = 1.0; ///< [m] reported sigma of a mobile object's position
};

class OriginalCorrelator {
public:
    explicit OriginalCorrelator(const OriginalConfig& config = {});

    /// Applies one message (time-ordered). Errors (the message is skipped): a confirm of an unknown id.
    Result<void, Error> add(const Message& message);

    /// What the passing of time alone changes, up to `t`: mobile objects and tracks past their timeout are removed,
    /// idle static tracks retired or forgotten. Call it before snapshot(t) (CorrelatorFeed does at every period
    /// boundary).
    void advance(double t);
    /// The objects and alerts at time `t`, as advance(t) left them; changes nothing.
    [[nodiscard]] Snapshot snapshot(double t) const;

    /// Observation points held in memory (bounded; tests watch it over long missions).
    [[nodiscard]] std::size_t storedPoints() const noexcept;
    [[nodiscard]] std::size_t ignoredPoseCorrections() const noexcept { return ignoredCorrections_; }

private:
    struct StaticTrack {
        std::string ugv;
        OoiClass cls = OoiClass::Unknown;
        std::vector<Eigen::Vector2d> points; ///< reservoir of at most maxPointsPerTrack
        std::uint64_t seen = 0;
        Eigen::Vector2d sum = Eigen::Vector2d::Zero();
        Eigen::Matrix2d sumSq = Eigen::Matrix2d::Zero();
        double lastT = 0.0;
        MixtureFit fit;
        std::array<int, 2> object{-1, -1}; ///< object index of each component
        bool retired = false;
    };
    struct StaticObject : rules::Identity {
        Gaussian2 estimate;
        std::vector<std::pair<int, int>> members; ///< (track index, component)
    };
    struct MobileTrack {
        std::array<Eigen::Vector2d, 2> last{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
        int count = 0;
        int object = -1;
        double lastT = 0.0;
    };
    struct MobileObject : rules::Identity {
        Eigen::Vector2d pos = Eigen::Vector2d::Zero();
        double lastT = 0.0;
        int observations = 0;
        std::vector<std::string> ugvs;
    };

    void ensureFrame(double lat, double lon);
    void addStatic(const Observation& o, const Eigen::Vector2d& p);
    void addMobile(const Observation& o, const Eigen::Vector2d& p);
    void addUav(const UavFix& u);
    Result<void, Error> confirm(const Confirm& c);
    void refit(StaticTrack& track, bool full);
    void assignComponents(int trackIndex);
    void refreshStatic(int object);
    void join(int trackIndex, int component, int object);
    void leave(int trackIndex, int object);
    int createStatic(OoiClass cls);
    int createMobile(OoiClass cls);
    void mergeStatic(int object);
    /// One merge of `object` with a static object close to it: the one kept, or nothing when none is close.
    std::optional<int> mergeStaticOnce(int object);
    void mergeMobile(int object);
    void expire(double t);
    [[nodiscard]] bool sameStatic(const Gaussian2& a, const Gaussian2& b) const;
    std::string newId();

    OriginalConfig config_;
    std::optional<LocalFrame> frame_;
    std::unordered_map<std::string, int> staticTrackIndex_;
    std::vector<StaticTrack> staticTracks_;
    std::vector<int> freeStaticTracks_; ///< slots of forgotten tracks, reused
    std::vector<StaticObject> staticObjects_;
    std::unordered_map<std::string, int> mobileTrackIndex_;
    std::vector<MobileTrack> mobileTracks_;
    std::vector<int> freeMobileTracks_;
    std::vector<MobileObject> mobileObjects_;
    std::vector<int> aliveMobiles_; ///< indices of the alive mobile objects, ascending
    std::vector<Gaussian2> parts_;  ///< refreshStatic()'s members' components, kept to reuse its memory
    std::unordered_map<std::string, std::string> mergedInto_;       ///< id -> the id that absorbed it
    std::unordered_map<std::string, std::pair<bool, int>> idIndex_; ///< id -> (static?, index)
    std::mt19937_64 rng_{7};
    std::uint64_t nextId_ = 1;
    std::size_t ignoredCorrections_ = 0;
    double now_ = 0.0;
};

} // namespace ugv::correlator
