#include "ugv/correlator/static_map.hpp"

#include <algorithm>
#include <set>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "ugv/correlator/gaussian_mixture.hpp"

namespace ugv::correlator {
namespace {

/// Added to a static object's covariance: its observations share their UGVs' remaining pose errors, so it is
/// never more certain than those (the information of independent observations would say centimetres).
constexpr double kFloorSigmaM = 0.3;
/// A new track takes an object from the track that keeps it out only if it fits the object's other tracks better by
/// this much (chi-square: a likelihood ratio of e^0.5); a tie keeps the status quo (hysteresis).
constexpr double kContestMargin = 1.0;
constexpr double kSplitDistanceM = 2.0;        ///< track groups of one object at least this far apart may split
constexpr double kMaxPriorObservations = 20.0; ///< a folded prior is worth at most this many observations
constexpr int kTwoMeansIterations = 5;

Eigen::Matrix2d floorCovariance()
{
    return kFloorSigmaM * kFloorSigmaM * Eigen::Matrix2d::Identity();
}

/// Each stored sample of a window stands for seen / stored observations.
double sampleWeight(const StaticMap::TrackWindow& tw)
{
    return tw.samples.empty() ? 0.0 : static_cast<double>(tw.seen) / static_cast<double>(tw.samples.size());
}

/// Adds one observation's information to `object` (its mean is left for the caller to solve).
void accumulate(StaticMap::StaticObject& object, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov,
                const Eigen::Matrix2d& measurementCov, double weight)
{
    const Eigen::Matrix2d info = weight * cov.inverse();
    object.info += info;
    object.infoMean += info * p;
    object.measurementInfo += weight * measurementCov.inverse();
    object.poseCovSum += weight * (cov - measurementCov);
    object.weightSum += weight;
}

void fuse(StaticMap::StaticObject& object, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov,
          const Eigen::Matrix2d& measurementCov)
{
    accumulate(object, p, cov, measurementCov, 1.0);
    object.mean = object.info.ldlt().solve(object.infoMean);
}

/// Adds every stored sample of `track` to `object` and to `alone` (the track's own sums), each standing for seen /
/// stored observations; the means are left for the caller to solve.
void fuseTrack(StaticMap::StaticObject& object, StaticMap::StaticObject& alone, const StaticMap::Track& track,
               const UgvPoseErrors& poses)
{
    for (const StaticMap::TrackWindow& tw : track.windows) {
        const double weight = sampleWeight(tw);
        for (const RangeBearing& smp : tw.samples) {
            Eigen::Vector2d p;
            Eigen::Matrix2d cov;
            Eigen::Matrix2d measurementCov;
            poses.project(track.ugv, smp, p, &cov, &measurementCov);
            accumulate(object, p, cov, measurementCov, weight);
            accumulate(alone, p, cov, measurementCov, weight);
        }
    }
}

/// A track's own estimate from its samples summed alone (`part`): the samples' measurement noise averages out, their
/// UGV's pose error is common to all of them and does not.
StaticMap::TrackEstimate estimateOf(const StaticMap::StaticObject& part)
{
    StaticMap::TrackEstimate e;
    if (part.weightSum <= 0.0 || part.info.determinant() <= 0.0 || part.measurementInfo.determinant() <= 0.0) {
        return e;
    }
    e.valid = true;
    e.mean = part.info.ldlt().solve(part.infoMean);
    e.measurementCov = part.measurementInfo.inverse();
    e.cov = e.measurementCov + part.poseCovSum / part.weightSum;
    return e;
}

/// Two groups of an object's track means (two-means seeded by the farthest pair).
struct TwoGroups {
    Eigen::Vector2d ca = Eigen::Vector2d::Zero();
    Eigen::Vector2d cb = Eigen::Vector2d::Zero();
    std::vector<bool> inB;
    double spread = 0.0; ///< [m] the farthest mean from its group's centre
    double wa = 0.0;
    double wb = 0.0;
};

/// @return false when the farthest pair of means is closer than kSplitDistanceM (nothing to split).
bool twoGroups(const std::vector<Eigen::Vector2d>& means, const std::vector<double>& weights, TwoGroups& g)
{
    // The farthest pair, the first found in index order.
    std::size_t a = 0;
    std::size_t b = 0;
    double farthest = 0.0;
    for (std::size_t i = 0; i < means.size(); ++i) {
        for (std::size_t k = i + 1; k < means.size(); ++k) {
            const double d = (means[i] - means[k]).norm();
            if (d > farthest) {
                a = i;
                b = k;
                farthest = d;
            }
        }
    }
    if (farthest < kSplitDistanceM) {
        return false;
    }
    g.ca = means[a];
    g.cb = means[b];
    g.inB.assign(means.size(), false);
    for (int iteration = 0; iteration < kTwoMeansIterations; ++iteration) {
        Eigen::Vector2d sa = Eigen::Vector2d::Zero();
        Eigen::Vector2d sb = Eigen::Vector2d::Zero();
        double wa = 0.0;
        double wb = 0.0;
        for (std::size_t i = 0; i < means.size(); ++i) {
            g.inB[i] = (means[i] - g.cb).norm() < (means[i] - g.ca).norm();
            (g.inB[i] ? sb : sa) += weights[i] * means[i];
            (g.inB[i] ? wb : wa) += weights[i];
        }
        if (wa <= 0.0 || wb <= 0.0) {
            break;
        }
        g.ca = sa / wa;
        g.cb = sb / wb;
    }
    for (std::size_t i = 0; i < means.size(); ++i) {
        g.spread = std::max(g.spread, (means[i] - (g.inB[i] ? g.cb : g.ca)).norm());
        (g.inB[i] ? g.wb : g.wa) += weights[i];
    }
    return true;
}

} // namespace

StaticMap::StaticMap(const PoseCorrectedConfig& config) : config_(config) {}

void StaticMap::store(Track& track, const RangeBearing& sample, int window)
{
    if (track.windows.empty() || track.windows.back().window != window) {
        track.windows.push_back(TrackWindow{window, 0, {}});
    }
    TrackWindow& tw = track.windows.back();
    ++tw.seen;
    if (tw.samples.size() < config_.samplesPerTrackWindow) {
        tw.samples.push_back(sample);
    } else {
        std::uniform_int_distribution<std::uint64_t> pick(0, tw.seen - 1);
        if (const std::uint64_t slot = pick(rng_); slot < config_.samplesPerTrackWindow) {
            tw.samples[slot] = sample;
        }
    }
    ++track.seen;
    track.lastT = sample.t;
}

void StaticMap::noteInstant(int ugv, int ti, double t)
{
    if (instants_.size() <= static_cast<std::size_t>(ugv)) {
        instants_.resize(static_cast<std::size_t>(ugv) + 1);
    }
    Instant& instant = instants_[static_cast<std::size_t>(ugv)];
    if (instant.t != t) {
        instant.t = t;
        instant.tracks.clear();
    }
    const auto note = [this](int from, int to) {
        auto& apart = tracks_[static_cast<std::size_t>(from)].apart;
        const auto found = std::find_if(apart.begin(), apart.end(), [to](const Apart& a) { return a.track == to; });
        if (found == apart.end()) {
            apart.push_back(Apart{to, 1});
        } else {
            ++found->instants;
        }
    };
    for (const int other : instant.tracks) {
        if (other != ti) {
            note(ti, other);
            note(other, ti);
        }
    }
    instant.tracks.push_back(ti);
}

bool StaticMap::trackSeenApart(int ti, int object, int instants) const
{
    const auto& apart = tracks_[static_cast<std::size_t>(ti)].apart;
    return std::any_of(apart.begin(), apart.end(), [this, object, instants](const Apart& a) {
        return a.instants >= instants && tracks_[static_cast<std::size_t>(a.track)].object == object;
    });
}

bool StaticMap::seenApart(const StaticObject& x, int y) const
{
    return std::any_of(x.tracks.begin(), x.tracks.end(),
                       [this, y](int ti) { return trackSeenApart(ti, y, kApartInstants); });
}

bool StaticMap::onlySeenBy(const StaticObject& object, int ugv, int except) const
{
    return std::all_of(object.tracks.begin(), object.tracks.end(), [this, ugv, except](int ti) {
        return ti == except || tracks_[static_cast<std::size_t>(ti)].ugv == ugv;
    });
}

int StaticMap::associate(int ugv, int ti, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov,
                         const Eigen::Matrix2d& measurementCov) const
{
    int best = -1;
    double bestD2 = config_.gateChi2;
    for (int i = 0; i < static_cast<int>(objects_.size()); ++i) {
        const StaticObject& so = objects_[static_cast<std::size_t>(i)];
        if (!so.alive || trackSeenApart(ti, i, 1)) {
            continue;
        }
        // Against an object only this UGV has seen, its pose error is common to both: measurement noise only.
        const bool ownOnly = onlySeenBy(so, ugv);
        const Eigen::Matrix2d objectCov = ownOnly ? Eigen::Matrix2d(so.measurementInfo.inverse())
                                                  : Eigen::Matrix2d(so.info.inverse() + floorCovariance());
        const double d2 = mahalanobis2(p - so.mean, (ownOnly ? measurementCov : cov) + objectCov);
        if (d2 < bestD2) {
            best = i;
            bestD2 = d2;
        }
    }
    return best;
}

void StaticMap::add(const Observation& o, int ugv, const RangeBearing& sample, const UgvPoseErrors& poses,
                    ObjectIds& ids)
{
    auto [it, inserted] = trackIndex_.try_emplace(rules::trackKey(o.ugv, o.track), static_cast<int>(tracks_.size()));
    if (inserted) {
        tracks_.push_back(Track{});
        tracks_.back().ugv = ugv;
        tracks_.back().cls = o.cls;
        tracks_.back().key = it->first;
    }
    const int ti = it->second;
    noteInstant(ugv, ti, o.t);
    Track& track = tracks_[static_cast<std::size_t>(ti)]; // tracks_ does not grow below (create and rehome add objects)
    store(track, sample, poses.window(o.t));
    Eigen::Vector2d p;
    Eigen::Matrix2d cov;
    Eigen::Matrix2d measurementCov;
    poses.project(ugv, sample, p, &cov, &measurementCov);
    int displaced = -1;
    if (track.object < 0) {
        int best = associate(ugv, ti, p, cov, measurementCov);
        if (best < 0) {
            best = contest(ugv, ti, p, cov, measurementCov, poses, displaced);
        }
        join(ti, best >= 0 ? best : create(o.cls, o.t, ids));
    }
    StaticObject& object = objects_[static_cast<std::size_t>(track.object)];
    fuse(object, p, cov, measurementCov);
    ++object.observations;
    if (displaced >= 0) {
        rehome(displaced, o.t, poses, ids);
    }
}

int StaticMap::create(OoiClass cls, double t, ObjectIds& ids)
{
    const int index = static_cast<int>(objects_.size());
    StaticObject created;
    ObjectIds::Issued issued = ids.issue(true, index);
    rules::identify(created, std::move(issued.id), issued.order, cls);
    created.firstT = t;
    objects_.push_back(std::move(created));
    return index;
}

void StaticMap::join(int ti, int object)
{
    Track& track = tracks_[static_cast<std::size_t>(ti)];
    track.object = object;
    track.origin = object;
    objects_[static_cast<std::size_t>(object)].tracks.push_back(ti);
}

StaticMap::TrackEstimate StaticMap::estimateOfTracks(const std::vector<int>& tracks, int except,
                                                     const UgvPoseErrors& poses) const
{
    StaticObject all;
    StaticObject unused;
    for (const int ti : tracks) {
        if (ti != except) {
            fuseTrack(unused, all, tracks_[static_cast<std::size_t>(ti)], poses);
        }
    }
    return estimateOf(all);
}

/// A close pair's posts seen one after the other: under the wide gates of unknown pose errors the first reading of
/// the nearer post can join the object its neighbour founded; when one UGV then reports both at one instant, the
/// neighbour's new track is kept out of its own object. Here it contends: an object kept from new track `ti` by one
/// track `rival` alone (not the object's first track) goes to whichever of the two fits the object's other tracks
/// better (Mahalanobis distance of the new reading, and of the rival's own estimate, by kContestMargin); the rival is
/// displaced (rehome). The id stays with the evidence that founded it.
int StaticMap::contest(int ugv, int ti, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov,
                       const Eigen::Matrix2d& measurementCov, const UgvPoseErrors& poses, int& displaced) const
{
    int best = -1;
    double bestD2 = config_.gateChi2;
    const Track& track = tracks_[static_cast<std::size_t>(ti)];
    for (const Apart& apart : track.apart) {
        const int rival = apart.track;
        const int j = tracks_[static_cast<std::size_t>(rival)].object;
        if (j < 0) {
            continue;
        }
        const StaticObject& so = objects_[static_cast<std::size_t>(j)];
        const bool keptOutByRivalAlone = std::none_of(track.apart.begin(), track.apart.end(), [&](const Apart& a) {
            return a.track != rival && tracks_[static_cast<std::size_t>(a.track)].object == j;
        });
        if (!so.alive || so.cls != track.cls || so.tracks.size() < 2 || so.tracks.front() == rival ||
            !keptOutByRivalAlone) {
            continue;
        }
        const TrackEstimate rest = estimateOfTracks(so.tracks, rival, poses);
        const TrackEstimate theirs = estimateOfTracks({rival}, -1, poses);
        if (!rest.valid || !theirs.valid) {
            continue;
        }
        // Against tracks of this UGV alone, its pose error is common to both: measurement noise only.
        const bool ownOnly = onlySeenBy(so, ugv, rival);
        const Eigen::Matrix2d restCov = ownOnly ? rest.measurementCov : Eigen::Matrix2d(rest.cov + floorCovariance());
        const double mine = mahalanobis2(p - rest.mean, (ownOnly ? measurementCov : cov) + restCov);
        const double rivals =
            mahalanobis2(theirs.mean - rest.mean, (ownOnly ? theirs.measurementCov : theirs.cov) + restCov);
        if (mine < bestD2 && mine + kContestMargin < rivals) {
            best = j;
            bestD2 = mine;
            displaced = rival;
        }
    }
    if (best < 0) {
        displaced = -1;
    }
    return best;
}

void StaticMap::recount(StaticObject& object) const
{
    object.observations = 0;
    for (const int ti : object.tracks) {
        object.observations += tracks_[static_cast<std::size_t>(ti)].seen;
    }
}

void StaticMap::rehome(int ti, double t, const UgvPoseErrors& poses, ObjectIds& ids)
{
    Track& track = tracks_[static_cast<std::size_t>(ti)];
    std::vector<int>& left = objects_[static_cast<std::size_t>(track.object)].tracks;
    left.erase(std::find(left.begin(), left.end(), ti));
    recount(objects_[static_cast<std::size_t>(track.object)]);
    refit(objects_[static_cast<std::size_t>(track.object)], poses);
    const TrackEstimate own = estimateOfTracks({ti}, -1, poses);
    int to = own.valid ? associate(track.ugv, ti, own.mean, own.cov, own.measurementCov) : -1;
    if (to < 0) {
        to = create(track.cls, t, ids);
    }
    join(ti, to);
    StaticObject& joined = objects_[static_cast<std::size_t>(to)];
    recount(joined);
    refit(joined, poses);
}

void StaticMap::refit(StaticObject& object, const UgvPoseErrors& poses)
{
    object.info = object.priorInfo;
    object.infoMean = object.priorInfo * object.priorMean;
    object.measurementInfo = object.priorInfo;
    object.poseCovSum.setZero();
    object.weightSum = 0.0;
    if (trackEstimates_.size() < tracks_.size()) {
        trackEstimates_.resize(tracks_.size());
    }
    for (const int ti : object.tracks) {
        StaticObject alone;
        fuseTrack(object, alone, tracks_[static_cast<std::size_t>(ti)], poses);
        trackEstimates_[static_cast<std::size_t>(ti)] = estimateOf(alone);
    }
    if (object.info.determinant() > 0.0) {
        object.mean = object.info.ldlt().solve(object.infoMean);
    }
}

void StaticMap::rebuild(const UgvPoseErrors& poses, ObjectIds& ids)
{
    for (StaticObject& so : objects_) {
        if (so.alive) {
            refit(so, poses);
        }
    }
    reassignTracks(poses);
    splitAll(poses, ids);
    mergeAll(ids);
}

/// Hard-assignment EM over tracks: a track joins its object on its first reading, which under range noise can lie
/// nearer the neighbour of a close pair; then the object's other tracks that one UGV saw at the same instant as it
/// are kept out (seen apart) and the one post becomes two objects that never merge. Here each track's own estimate
/// is gated again against its object: outside the gate and inside the gate of another object of its class that no
/// track seen apart from it belongs to, it moves there. An object keeps at least one track (an object leaving whole
/// is a merge, mergeAll's decision); the track's origin stays (the id it first joined).
void StaticMap::reassignTracks(const UgvPoseErrors& poses)
{
    std::vector<int> changed;
    for (std::size_t j = 0; j < objects_.size(); ++j) {
        if (!objects_[j].alive || objects_[j].tracks.size() < 2) {
            continue;
        }
        for (std::size_t k = 0; k < objects_[j].tracks.size() && objects_[j].tracks.size() >= 2;) {
            const int ti = objects_[j].tracks[k];
            const int target = betterObject(ti, static_cast<int>(j));
            if (target < 0) {
                ++k;
                continue;
            }
            objects_[j].tracks.erase(objects_[j].tracks.begin() + static_cast<std::ptrdiff_t>(k));
            objects_[static_cast<std::size_t>(target)].tracks.push_back(ti);
            tracks_[static_cast<std::size_t>(ti)].object = target;
            changed.push_back(static_cast<int>(j));
            changed.push_back(target);
        }
    }
    std::sort(changed.begin(), changed.end());
    changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    for (const int j : changed) {
        StaticObject& so = objects_[static_cast<std::size_t>(j)];
        recount(so);
        refit(so, poses);
    }
}

int StaticMap::betterObject(int ti, int current) const
{
    const TrackEstimate& e = trackEstimates_[static_cast<std::size_t>(ti)];
    if (!e.valid) {
        return -1;
    }
    const auto d2 = [&](const StaticObject& so) {
        return mahalanobis2(e.mean - so.mean, e.cov + so.info.inverse() + floorCovariance());
    };
    const StaticObject& own = objects_[static_cast<std::size_t>(current)];
    if (own.info.determinant() <= 0.0 || d2(own) < config_.gateChi2) {
        return -1;
    }
    int best = -1;
    double bestD2 = config_.gateChi2;
    for (int i = 0; i < static_cast<int>(objects_.size()); ++i) {
        const StaticObject& so = objects_[static_cast<std::size_t>(i)];
        if (i == current || !so.alive || so.cls != tracks_[static_cast<std::size_t>(ti)].cls ||
            so.info.determinant() <= 0.0 || trackSeenApart(ti, i, kApartInstants)) {
            continue;
        }
        if (const double d = d2(so); d < bestD2) {
            best = i;
            bestD2 = d;
        }
    }
    return best;
}

Eigen::Vector2d StaticMap::trackMean(int trackIndex, const UgvPoseErrors& poses, double& weight) const
{
    const Track& track = tracks_[static_cast<std::size_t>(trackIndex)];
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    weight = 0.0;
    for (const TrackWindow& tw : track.windows) {
        const double w = sampleWeight(tw);
        for (const RangeBearing& s : tw.samples) {
            Eigen::Vector2d p;
            poses.project(track.ugv, s, p, nullptr);
            sum += w * p;
            weight += w;
        }
    }
    return weight > 0.0 ? Eigen::Vector2d(sum / weight) : Eigen::Vector2d::Zero();
}

/// The estimate of a group of tracks: their own means fused by their measurement information (the pose error is
/// common to one UGV's tracks; the merge test's floor stands for what is left of it).
StaticMap::TrackEstimate StaticMap::groupEstimate(const std::vector<int>& group) const
{
    Eigen::Matrix2d info = Eigen::Matrix2d::Zero();
    Eigen::Vector2d infoMean = Eigen::Vector2d::Zero();
    for (const int ti : group) {
        const TrackEstimate& e = trackEstimates_[static_cast<std::size_t>(ti)];
        if (e.valid && e.measurementCov.determinant() > 0.0) {
            const Eigen::Matrix2d i = e.measurementCov.inverse();
            info += i;
            infoMean += i * e.mean;
        }
    }
    TrackEstimate fused;
    if (info.determinant() > 0.0) {
        fused.valid = true;
        fused.cov = info.inverse();
        fused.mean = fused.cov * infoMean;
    }
    return fused;
}

/// Two groups of one object's tracks are two objects only if the merge test (sameObject's gate) tells them apart:
/// a split the gate cannot tell from noise is merged again at the next rebuild, and each split and merge moves
/// the object's id.
bool StaticMap::groupsApart(const std::vector<int>& a, const std::vector<int>& b) const
{
    const TrackEstimate ea = groupEstimate(a);
    const TrackEstimate eb = groupEstimate(b);
    return ea.valid && eb.valid &&
           mahalanobis2(ea.mean - eb.mean, ea.cov + eb.cov + 2.0 * floorCovariance()) >= config_.gateChi2;
}

void StaticMap::splitAll(const UgvPoseErrors& poses, ObjectIds& ids)
{
    const std::size_t count = objects_.size();
    for (std::size_t j = 0; j < count; ++j) {
        if (objects_[j].alive && objects_[j].tracks.size() >= 2) {
            split(j, poses, ids);
        }
    }
}

/// An object whose tracks form two groups far apart (two objects associated while the UGVs' pose errors were
/// still unknown), apart for the merge test too (groupsApart), splits: the group with more observations keeps the id,
/// the other becomes a new object, unless the split undoes a merge: then the absorbed object comes back with its id
/// (hysteresis). Tracks with no samples left (all folded into the prior) have no position and stay.
void StaticMap::split(std::size_t j, const UgvPoseErrors& poses, ObjectIds& ids)
{
    std::vector<int> tracks;
    std::vector<Eigen::Vector2d> means;
    std::vector<double> weights;
    for (const int ti : objects_[j].tracks) {
        double weight = 0.0;
        const Eigen::Vector2d mean = trackMean(ti, poses, weight);
        if (weight > 0.0) {
            tracks.push_back(ti);
            means.push_back(mean);
            weights.push_back(weight);
        }
    }
    TwoGroups g;
    if (tracks.size() < 2 || !twoGroups(means, weights, g)) {
        return;
    }
    if (g.wa <= 0.0 || g.wb <= 0.0 || (g.ca - g.cb).norm() < kSplitDistanceM || (g.ca - g.cb).norm() < 3.0 * g.spread) {
        return;
    }
    std::vector<int> groupA;
    std::vector<int> groupB;
    for (std::size_t i = 0; i < tracks.size(); ++i) {
        (g.inB[i] ? groupB : groupA).push_back(tracks[i]);
    }
    if (!groupsApart(groupA, groupB)) {
        return;
    }
    // The group that undoes a merge leaves (the other keeps this object's id); else the smaller one.
    const int originA = absorbedOrigin(groupA, j, ids);
    const int originB = absorbedOrigin(groupB, j, ids);
    const bool moveB = (originB >= 0) != (originA >= 0) ? originB >= 0 : g.wb <= g.wa;
    const std::vector<int>& leaving = moveB ? groupB : groupA;
    const int revived = moveB ? originB : originA;
    std::vector<int> stay = moveB ? groupA : groupB;
    for (const int ti : objects_[j].tracks) {
        if (std::find(tracks.begin(), tracks.end(), ti) == tracks.end()) {
            stay.push_back(ti); // no samples left: no position to split by
        }
    }
    int newIndex = revived;
    if (revived >= 0) {
        StaticObject& back = objects_[static_cast<std::size_t>(revived)];
        back.alive = true;
        back.state = objects_[j].state;
        back.priorInfo.setZero();
        back.tracks.clear();
        ids.unmerge(back.id);
    } else {
        newIndex = static_cast<int>(objects_.size());
        StaticObject created;
        ObjectIds::Issued issued = ids.issue(true, newIndex);
        rules::identify(created, std::move(issued.id), issued.order, objects_[j].cls, objects_[j].state);
        objects_.push_back(std::move(created));
    }
    StaticObject& moved = objects_[static_cast<std::size_t>(newIndex)];
    for (const int ti : leaving) {
        moved.tracks.push_back(ti);
        tracks_[static_cast<std::size_t>(ti)].object = newIndex;
    }
    recount(moved);
    StaticObject& kept = objects_[j];
    kept.tracks = std::move(stay);
    recount(kept);
    kept.priorInfo.setZero();
    refit(objects_[j], poses);
    refit(objects_[static_cast<std::size_t>(newIndex)], poses);
}

int StaticMap::absorbedOrigin(const std::vector<int>& tracks, std::size_t into, const ObjectIds& ids) const
{
    std::unordered_map<int, std::uint64_t> seenBy; // observations per origin
    std::uint64_t total = 0;
    for (const int ti : tracks) {
        const Track& track = tracks_[static_cast<std::size_t>(ti)];
        seenBy[track.origin] += track.seen;
        total += track.seen;
    }
    int best = -1;
    std::uint64_t bestSeen = 0;
    for (const auto& [origin, seen] : seenBy) {
        if (seen > bestSeen || (seen == bestSeen && origin < best)) {
            best = origin;
            bestSeen = seen;
        }
    }
    if (best < 0 || static_cast<std::size_t>(best) == into || 2 * bestSeen <= total ||
        objects_[static_cast<std::size_t>(best)].alive) {
        return -1;
    }
    const auto ref = ids.find(objects_[static_cast<std::size_t>(best)].id);
    return ref && ref->isStatic && ref->index == static_cast<int>(into) ? best : -1;
}

bool StaticMap::sameObject(const StaticObject& x, const StaticObject& y) const
{
    const Eigen::Matrix2d cov = x.info.inverse() + y.info.inverse() + 2.0 * floorCovariance();
    return mahalanobis2(x.mean - y.mean, cov) < config_.gateChi2;
}

bool StaticMap::maybeSameObject(const StaticObject& x, const StaticObject& y) const
{
    const auto poseCov = [](const StaticObject& so) {
        return so.weightSum > 0.0 ? Eigen::Matrix2d(so.poseCovSum / so.weightSum) : Eigen::Matrix2d::Zero();
    };
    const Eigen::Matrix2d cov = x.info.inverse() + y.info.inverse() + 2.0 * floorCovariance() + poseCov(x) + poseCov(y);
    return mahalanobis2(x.mean - y.mean, cov) < config_.gateChi2;
}

void StaticMap::mergeAll(ObjectIds& ids)
{
    for (std::size_t a = 0; a < objects_.size(); ++a) {
        for (std::size_t b = a + 1; b < objects_.size(); ++b) {
            StaticObject& x = objects_[a];
            StaticObject& y = objects_[b];
            if (!x.alive || !y.alive || x.info.determinant() <= 0.0 || y.info.determinant() <= 0.0) {
                continue;
            }
            if (!sameObject(x, y) || seenApart(x, static_cast<int>(b))) {
                continue;
            }
            StaticObject& kept = x.order <= y.order ? x : y;
            StaticObject& gone = x.order <= y.order ? y : x;
            const int keptIndex = static_cast<int>(&kept - objects_.data());
            for (const int ti : gone.tracks) {
                tracks_[static_cast<std::size_t>(ti)].object = keptIndex;
                kept.tracks.push_back(ti);
            }
            kept.info += gone.info;
            kept.infoMean += gone.infoMean;
            kept.measurementInfo += gone.measurementInfo;
            kept.poseCovSum += gone.poseCovSum;
            kept.weightSum += gone.weightSum;
            kept.priorInfo += gone.priorInfo;
            kept.priorMean = kept.mean;
            kept.mean = kept.info.ldlt().solve(kept.infoMean);
            kept.observations += gone.observations;
            kept.state = rules::inherit(kept.state, gone.state);
            gone.alive = false;
            gone.tracks.clear();
            ids.merge(gone.id, kept.id);
        }
    }
}

/// Clutter gathers into objects over a long mission unless objects that stay below minStaticObservations die.
void StaticMap::dropTentative(double t, ObjectIds& ids)
{
    for (StaticObject& so : objects_) {
        if (!so.alive || so.observations >= static_cast<std::uint64_t>(config_.minStaticObservations) ||
            t - so.firstT <= config_.tentativeTimeoutS) {
            continue;
        }
        so.alive = false;
        ids.erase(so.id);
        for (const int ti : so.tracks) {
            Track& track = tracks_[static_cast<std::size_t>(ti)];
            trackIndex_.erase(track.key);
            track.windows.clear();
            track.windows.shrink_to_fit();
            track.object = -1;
        }
        so.tracks.clear();
    }
}

void StaticMap::foldBeyondHorizon(int oldestWindow)
{
    for (StaticObject& so : objects_) {
        if (!so.alive) {
            continue;
        }
        std::size_t dropped = 0;
        for (const int ti : so.tracks) {
            auto& windows = tracks_[static_cast<std::size_t>(ti)].windows;
            const auto keep = std::find_if(windows.begin(), windows.end(),
                                           [oldestWindow](const TrackWindow& tw) { return tw.window >= oldestWindow; });
            for (auto it = windows.begin(); it != keep; ++it) {
                dropped += it->seen;
            }
            windows.erase(windows.begin(), keep);
        }
        if (dropped > 0) {
            const double share = std::min(1.0, kMaxPriorObservations / static_cast<double>(so.observations));
            so.priorInfo = share * so.info;
            so.priorMean = so.mean;
        }
    }
}

std::vector<const StaticMap::StaticObject*> StaticMap::published() const
{
    std::vector<const StaticObject*> published; // in creation order (objects_ is), so the older come first
    for (const StaticObject& so : objects_) {
        if (!so.alive || so.observations < static_cast<std::uint64_t>(config_.minStaticObservations) ||
            so.info.determinant() <= 0.0) {
            continue;
        }
        // A possible duplicate of an older object (a churned track UUID that missed the gate, or the UGVs' pose
        // errors putting one object in two places) is not shown while it waits for a merge: its id would steal the
        // object's for a while and then vanish. Unless one UGV saw both at one instant: then they are two. Once
        // shown it stays shown (hysteresis): hiding it again is the vanishing the rule is there to avoid.
        const int index = static_cast<int>(&so - objects_.data());
        if (!so.shown && std::any_of(published.begin(), published.end(), [&](const StaticObject* older) {
                return maybeSameObject(*older, so) && !seenApart(*older, index);
            })) {
            continue;
        }
        bool sustained = false; // a track that saw it twice: clutter falls on an object once per track
        std::set<int> ugvs;
        for (const int ti : so.tracks) {
            ugvs.insert(tracks_[static_cast<std::size_t>(ti)].ugv);
            sustained = sustained || tracks_[static_cast<std::size_t>(ti)].seen >= 2;
        }
        if (!sustained && ugvs.size() < 2) {
            continue;
        }
        published.push_back(&so);
    }
    return published;
}

void StaticMap::markShown()
{
    for (const StaticObject* so : published()) {
        objects_[static_cast<std::size_t>(so - objects_.data())].shown = true;
    }
}

void StaticMap::publish(const LocalFrame& frame, const UgvPoseErrors& poses, Snapshot& s, rules::Placed& threats) const
{
    for (const StaticObject* so : published()) {
        const Ellipse el = ellipseOf(so->info.inverse() + floorCovariance());
        ObjectEstimate e = rules::estimateOf(frame, so->mean, el, so->id, so->cls, so->state);
        e.observations = static_cast<int>(so->observations);
        std::set<std::string> names;
        for (const int ti : so->tracks) {
            names.insert(poses.ugv(static_cast<std::size_t>(tracks_[static_cast<std::size_t>(ti)].ugv)).name);
        }
        e.ugvs.assign(names.begin(), names.end());
        threats.emplace_back(so->mean, s.objects.size());
        s.objects.push_back(std::move(e));
    }
}

std::size_t StaticMap::storedPoints() const noexcept
{
    std::size_t n = 0;
    for (const Track& t : tracks_) {
        for (const TrackWindow& tw : t.windows) {
            n += tw.samples.size();
        }
    }
    return n;
}

} // namespace ugv::correlator
