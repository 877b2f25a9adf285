#include "ugv/correlator/original_correlator.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include <Eigen/LU>

#include "ugv/correlator/rules.hpp"

namespace ugv::correlator {
namespace {

constexpr std::uint64_t kAlwaysRefitUpTo = 16;
constexpr std::array<double, 3> kMobileWeights{0.5, 0.3, 0.2}; ///< newest, previous, the one before

/// Standard deviation of `g` along the unit direction `u`.
double sigmaAlong(const Gaussian2& g, const Eigen::Vector2d& u)
{
    return std::sqrt(std::max(u.dot(g.cov * u), 0.0));
}

/// The slot of `key` in `slots`: its own, a freed one reused, or a new one; `created` tells which.
template <class Slot>
int slotFor(std::unordered_map<std::string, int>& index, const std::string& key, std::vector<Slot>& slots,
            std::vector<int>& freed, bool& created)
{
    auto [it, inserted] = index.try_emplace(key, -1);
    created = inserted;
    if (inserted) {
        if (freed.empty()) {
            it->second = static_cast<int>(slots.size());
            slots.emplace_back();
        } else {
            it->second = freed.back();
            freed.pop_back();
        }
        slots[static_cast<std::size_t>(it->second)] = Slot{};
    }
    return it->second;
}

} // namespace

OriginalCorrelator::OriginalCorrelator(const OriginalConfig& config) : config_(config) {}

std::string OriginalCorrelator::newId()
{
    return "ooi-" + std::to_string(nextId_++);
}

void OriginalCorrelator::ensureFrame(double lat, double lon)
{
    if (!frame_) {
        frame_.emplace(lat, lon);
    }
}

Result<void, Error> OriginalCorrelator::add(const Message& message)
{
    if (const auto* o = std::get_if<Observation>(&message)) {
        now_ = std::max(now_, o->t);
        ensureFrame(o->ugvLat, o->ugvLon);
        const Eigen::Vector2d ugv = frame_->toLocal(o->ugvLat, o->ugvLon);
        const Eigen::Vector2d p = project(ugv, o->ugvHeadingDeg + o->bearingDeg, o->rangeM);
        if (rules::isMobileClass(o->cls)) {
            addMobile(*o, p);
        } else {
            addStatic(*o, p);
        }
        return {};
    }
    if (const auto* u = std::get_if<UavFix>(&message)) {
        now_ = std::max(now_, u->t);
        ensureFrame(u->lat, u->lon);
        addUav(*u);
        return {};
    }
    if (const auto* c = std::get_if<Confirm>(&message)) {
        now_ = std::max(now_, c->t);
        return confirm(*c);
    }
    ++ignoredCorrections_;
    return {};
}

// ------------------------------------------------------------------------------------------------------ static

void OriginalCorrelator::addStatic(const Observation& o, const Eigen::Vector2d& p)
{
    bool created = false;
    const int index =
        slotFor(staticTrackIndex_, rules::trackKey(o.ugv, o.track), staticTracks_, freeStaticTracks_, created);
    if (created) {
        staticTracks_[static_cast<std::size_t>(index)].ugv = o.ugv;
        staticTracks_[static_cast<std::size_t>(index)].cls = o.cls;
    }
    StaticTrack& track = staticTracks_[static_cast<std::size_t>(index)];
    ++track.seen;
    track.sum += p;
    track.sumSq += p * p.transpose();
    track.lastT = o.t;
    track.retired = false;
    if (track.points.size() < config_.maxPointsPerTrack) {
        track.points.push_back(p);
    } else {
        // Reservoir sampling: every observation so far is kept with the same probability.
        std::uniform_int_distribution<std::uint64_t> pick(0, track.seen - 1);
        const std::uint64_t slot = pick(rng_);
        if (slot < config_.maxPointsPerTrack) {
            track.points[slot] = p;
        }
    }
    if (track.seen < static_cast<std::uint64_t>(config_.minTrackObservations)) {
        return;
    }
    const bool full =
        track.seen <= kAlwaysRefitUpTo || track.seen % static_cast<std::uint64_t>(config_.refitEvery) == 0;
    refit(track, full);
    assignComponents(index);
}

void OriginalCorrelator::refit(StaticTrack& track, bool full)
{
    if (full) {
        track.fit = fitMixture(track.points, config_.mixture);
    }
    if (track.fit.components <= 1) {
        // One component: the moments of every observation, not only the reservoir's.
        const double n = static_cast<double>(track.seen);
        Gaussian2 g;
        g.mean = track.sum / n;
        g.cov = track.sumSq / n - g.mean * g.mean.transpose() +
                Eigen::Matrix2d::Identity() * config_.mixture.minSigmaM * config_.mixture.minSigmaM;
        g.count = n;
        track.fit.components = 1;
        track.fit.g[0] = g;
    } else {
        const double scale = static_cast<double>(track.seen) / static_cast<double>(track.points.size());
        track.fit.g[0].count = track.fit.g[0].weight * static_cast<double>(track.points.size()) * scale;
        track.fit.g[1].count = track.fit.g[1].weight * static_cast<double>(track.points.size()) * scale;
    }
}

bool OriginalCorrelator::sameStatic(const Gaussian2& a, const Gaussian2& b) const
{
    const Eigen::Vector2d d = b.mean - a.mean;
    const double distance = d.norm();
    if (distance <= config_.mergeRadiusM) {
        return true;
    }
    const Eigen::Vector2d u = d / distance;
    return distance <= config_.boundSigmas * (sigmaAlong(a, u) + sigmaAlong(b, u));
}

int OriginalCorrelator::createStatic(OoiClass cls)
{
    StaticObject created;
    rules::identify(created, newId(), nextId_, cls);
    const int index = static_cast<int>(staticObjects_.size());
    idIndex_[created.id] = {true, index};
    staticObjects_.push_back(std::move(created));
    return index;
}

void OriginalCorrelator::join(int trackIndex, int component, int object)
{
    staticTracks_[static_cast<std::size_t>(trackIndex)].object[static_cast<std::size_t>(component)] = object;
    staticObjects_[static_cast<std::size_t>(object)].members.emplace_back(trackIndex, component);
}

void OriginalCorrelator::leave(int trackIndex, int object)
{
    auto& members = staticObjects_[static_cast<std::size_t>(object)].members;
    members.erase(
        std::remove_if(members.begin(), members.end(), [trackIndex](const auto& m) { return m.first == trackIndex; }),
        members.end());
}

void OriginalCorrelator::assignComponents(int trackIndex)
{
    StaticTrack& track = staticTracks_[static_cast<std::size_t>(trackIndex)];
    const auto order = [this](int o) { return staticObjects_[static_cast<std::size_t>(o)].order; };
    const auto centre = [this](int o) { return staticObjects_[static_cast<std::size_t>(o)].estimate.mean; };
    std::vector<int> touched;
    if (track.fit.components == 1 && track.object[1] >= 0) {
        // Two groups became one: the track stays with the earlier object.
        const int a = track.object[0];
        const int b = track.object[1];
        const int kept = order(a) <= order(b) ? a : b;
        leave(trackIndex, a);
        leave(trackIndex, b);
        track.object = {-1, -1};
        join(trackIndex, 0, kept);
        touched = {a, b};
    } else if (track.fit.components == 2 && track.object[0] >= 0) {
        // EM may return the groups in either order: keep each object with the nearer group.
        const int a = track.object[0];
        const int b = track.object[1];
        const Eigen::Vector2d& m0 = track.fit.g[0].mean;
        const Eigen::Vector2d& m1 = track.fit.g[1].mean;
        const bool swap = b >= 0 ? (m0 - centre(b)).norm() + (m1 - centre(a)).norm() <
                                       (m0 - centre(a)).norm() + (m1 - centre(b)).norm()
                                 : (m1 - centre(a)).norm() < (m0 - centre(a)).norm();
        if (swap) {
            std::swap(track.fit.g[0], track.fit.g[1]);
        }
    }
    for (int c = 0; c < track.fit.components; ++c) {
        if (track.object[static_cast<std::size_t>(c)] >= 0) {
            touched.push_back(track.object[static_cast<std::size_t>(c)]);
            continue;
        }
        // Join the earliest object this group matches (not the track's other group's), else a new one.
        const int other = track.object[1 - static_cast<std::size_t>(c)];
        int best = -1;
        for (int i = 0; i < static_cast<int>(staticObjects_.size()); ++i) {
            const StaticObject& so = staticObjects_[static_cast<std::size_t>(i)];
            if (so.alive && i != other && sameStatic(so.estimate, track.fit.g[static_cast<std::size_t>(c)]) &&
                (best < 0 || so.order < order(best))) {
                best = i;
            }
        }
        if (best < 0) {
            best = createStatic(track.cls);
        }
        join(trackIndex, c, best);
        touched.push_back(best);
    }
    for (const int o : touched) {
        refreshStatic(o);
    }
    for (const int o : touched) {
        mergeStatic(o);
    }
}

void OriginalCorrelator::refreshStatic(int object)
{
    StaticObject& so = staticObjects_[static_cast<std::size_t>(object)];
    if (so.members.empty()) {
        so.alive = false;
        return;
    }
    parts_.clear();
    for (const auto& [t, c] : so.members) {
        parts_.push_back(staticTracks_[static_cast<std::size_t>(t)].fit.g[static_cast<std::size_t>(c)]);
    }
    so.estimate = combine(parts_);
}

void OriginalCorrelator::mergeStatic(int object)
{
    // A merge may bring the kept object close to another: merge again from it. A loop, not a recursion: one object
    // dies per round, so there are at most as many rounds as objects.
    for (std::optional<int> next = object; next.has_value();) {
        next = mergeStaticOnce(*next);
    }
}

std::optional<int> OriginalCorrelator::mergeStaticOnce(int object)
{
    if (!staticObjects_[static_cast<std::size_t>(object)].alive) {
        return std::nullopt;
    }
    for (int i = 0; i < static_cast<int>(staticObjects_.size()); ++i) {
        const StaticObject& other = staticObjects_[static_cast<std::size_t>(i)];
        const StaticObject& self = staticObjects_[static_cast<std::size_t>(object)];
        if (i == object || !other.alive || !sameStatic(self.estimate, other.estimate)) {
            continue;
        }
        const int keep = self.order <= other.order ? object : i;
        const int drop = keep == object ? i : object;
        StaticObject& kept = staticObjects_[static_cast<std::size_t>(keep)];
        StaticObject& gone = staticObjects_[static_cast<std::size_t>(drop)];
        kept.state = rules::inherit(kept.state, gone.state);
        gone.alive = false;
        mergedInto_[gone.id] = kept.id;
        for (const auto& [t, c] : gone.members) {
            StaticTrack& track = staticTracks_[static_cast<std::size_t>(t)];
            track.object[static_cast<std::size_t>(c)] = keep;
            if (track.object[0] == keep && track.object[1] == keep) {
                // Both groups of one track in one object: it is one group after all.
                leave(t, keep);
                track.object = {-1, -1};
                track.fit.g[0] = combine(std::span<const Gaussian2>(track.fit.g.data(), 2));
                track.fit.components = 1;
                join(t, 0, keep);
            } else {
                kept.members.emplace_back(t, c);
            }
        }
        gone.members.clear();
        refreshStatic(keep);
        return keep;
    }
    return std::nullopt;
}

// ------------------------------------------------------------------------------------------------------ mobile

void OriginalCorrelator::addMobile(const Observation& o, const Eigen::Vector2d& p)
{
    bool created = false;
    MobileTrack& track = mobileTracks_[static_cast<std::size_t>(
        slotFor(mobileTrackIndex_, rules::trackKey(o.ugv, o.track), mobileTracks_, freeMobileTracks_, created))];
    // The weighted average of the newest and the last two observations (renormalised while fewer exist).
    Eigen::Vector2d estimate = kMobileWeights[0] * p;
    double weight = kMobileWeights[0];
    for (int k = 0; k < track.count; ++k) {
        estimate += kMobileWeights[static_cast<std::size_t>(k) + 1] * track.last[static_cast<std::size_t>(k)];
        weight += kMobileWeights[static_cast<std::size_t>(k) + 1];
    }
    estimate /= weight;
    track.last[1] = track.last[0];
    track.last[0] = p;
    track.count = std::min(track.count + 1, 2);
    track.lastT = o.t;

    if (track.object >= 0 && !mobileObjects_[static_cast<std::size_t>(track.object)].alive) {
        track.object = -1;
    }
    if (track.object < 0) {
        int best = -1;
        double bestDistance = config_.mergeRadiusM;
        for (const int i : aliveMobiles_) {
            const MobileObject& mo = mobileObjects_[static_cast<std::size_t>(i)];
            const double d = (mo.pos - estimate).norm();
            if (mo.cls == o.cls && d <= bestDistance) {
                best = i;
                bestDistance = d;
            }
        }
        track.object = best >= 0 ? best : createMobile(o.cls);
    }
    MobileObject& mo = mobileObjects_[static_cast<std::size_t>(track.object)];
    mo.pos = estimate;
    mo.lastT = o.t;
    ++mo.observations;
    if (std::find(mo.ugvs.begin(), mo.ugvs.end(), o.ugv) == mo.ugvs.end()) {
        mo.ugvs.push_back(o.ugv);
    }
    mergeMobile(track.object);
}

int OriginalCorrelator::createMobile(OoiClass cls)
{
    MobileObject created;
    rules::identify(created, newId(), nextId_, cls);
    const int index = static_cast<int>(mobileObjects_.size());
    idIndex_[created.id] = {false, index};
    mobileObjects_.push_back(std::move(created));
    aliveMobiles_.push_back(index);
    return index;
}

void OriginalCorrelator::mergeMobile(int object)
{
    for (const int i : aliveMobiles_) {
        MobileObject& other = mobileObjects_[static_cast<std::size_t>(i)];
        MobileObject& self = mobileObjects_[static_cast<std::size_t>(object)];
        if (i == object || other.cls != self.cls || (other.pos - self.pos).norm() > config_.mergeRadiusM) {
            continue;
        }
        const int keep = self.order <= other.order ? object : i;
        const int drop = keep == object ? i : object;
        MobileObject& kept = mobileObjects_[static_cast<std::size_t>(keep)];
        MobileObject& gone = mobileObjects_[static_cast<std::size_t>(drop)];
        kept.state = rules::inherit(kept.state, gone.state);
        kept.observations += gone.observations;
        for (const std::string& u : gone.ugvs) {
            if (std::find(kept.ugvs.begin(), kept.ugvs.end(), u) == kept.ugvs.end()) {
                kept.ugvs.push_back(u);
            }
        }
        kept.lastT = std::max(kept.lastT, gone.lastT);
        gone.alive = false;
        mergedInto_[gone.id] = kept.id;
        for (MobileTrack& t : mobileTracks_) {
            if (t.object == drop) {
                t.object = keep;
            }
        }
        std::erase(aliveMobiles_, drop); // invalidates this loop's iterators: return at once
        return;
    }
}

void OriginalCorrelator::addUav(const UavFix& u)
{
    const Eigen::Vector2d p = frame_->toLocal(u.lat, u.lon);
    const OoiClass cls = u.cls == OoiClass::NonCombatant ? OoiClass::NonCombatant : OoiClass::Mobile;
    int best = -1;
    double bestDistance = config_.uavGateM;
    for (const int i : aliveMobiles_) {
        const MobileObject& mo = mobileObjects_[static_cast<std::size_t>(i)];
        const double d = (mo.pos - p).norm();
        if (mo.cls == cls && d <= bestDistance) {
            best = i;
            bestDistance = d;
        }
    }
    if (best < 0) {
        best = createMobile(cls);
    }
    MobileObject& mo = mobileObjects_[static_cast<std::size_t>(best)];
    mo.pos = p;
    mo.lastT = u.t;
    mo.state = Confirmation::ConfirmedPositive;
    ++mo.observations;
    if (std::find(mo.ugvs.begin(), mo.ugvs.end(), "uav") == mo.ugvs.end()) {
        mo.ugvs.emplace_back("uav");
    }
    mergeMobile(best);
}

Result<void, Error> OriginalCorrelator::confirm(const Confirm& c)
{
    std::string id = c.id;
    for (auto it = mergedInto_.find(id); it != mergedInto_.end(); it = mergedInto_.find(id)) {
        id = it->second; // confirm the object that absorbed it
    }
    const auto found = idIndex_.find(id);
    if (found == idIndex_.end()) {
        return Unexpected(Error{"confirm", "unknown object id '" + c.id + "'", "use an id from a snapshot"});
    }
    const auto [isStatic, index] = found->second;
    if (isStatic) {
        staticObjects_[static_cast<std::size_t>(index)].state = c.state;
    } else {
        MobileObject& mo = mobileObjects_[static_cast<std::size_t>(index)];
        if (!mo.alive) {
            return Unexpected(Error{"confirm", "object '" + c.id + "' timed out", "confirm a current object"});
        }
        mo.state = c.state;
    }
    return {};
}

// ------------------------------------------------------------------------------------------------------ output

void OriginalCorrelator::expire(double t)
{
    for (const int i : aliveMobiles_) {
        MobileObject& mo = mobileObjects_[static_cast<std::size_t>(i)];
        if (t - mo.lastT > config_.mobileTimeoutS) {
            mo.alive = false;
        }
    }
    std::erase_if(aliveMobiles_, [this](int i) { return !mobileObjects_[static_cast<std::size_t>(i)].alive; });
    // Forget idle mobile tracks, static tracks that never made an object, and retire idle static tracks.
    for (auto it = mobileTrackIndex_.begin(); it != mobileTrackIndex_.end();) {
        if (t - mobileTracks_[static_cast<std::size_t>(it->second)].lastT > config_.mobileTimeoutS) {
            mobileTracks_[static_cast<std::size_t>(it->second)] = MobileTrack{};
            freeMobileTracks_.push_back(it->second);
            it = mobileTrackIndex_.erase(it);
        } else {
            ++it;
        }
    }
    for (auto it = staticTrackIndex_.begin(); it != staticTrackIndex_.end();) {
        StaticTrack& track = staticTracks_[static_cast<std::size_t>(it->second)];
        const bool idle = t - track.lastT > config_.retireAfterS;
        if (idle && track.seen < static_cast<std::uint64_t>(config_.minTrackObservations)) {
            track = StaticTrack{};
            freeStaticTracks_.push_back(it->second);
            it = staticTrackIndex_.erase(it);
            continue;
        }
        if (idle && !track.retired) {
            track.retired = true;
            track.points.clear();
            track.points.shrink_to_fit();
        }
        ++it;
    }
}

void OriginalCorrelator::advance(double t)
{
    expire(t);
}

Snapshot OriginalCorrelator::snapshot(double t) const
{
    Snapshot s;
    s.t = t;
    if (!frame_) {
        return s;
    }
    rules::Placed threats; // (position, index in s.objects)
    for (const StaticObject& so : staticObjects_) {
        if (!so.alive) {
            continue;
        }
        ObjectEstimate e =
            rules::estimateOf(*frame_, so.estimate.mean, ellipseOf(so.estimate.cov), so.id, so.cls, so.state);
        e.observations = static_cast<int>(std::lround(so.estimate.count));
        std::set<std::string> ugvs;
        for (const auto& member : so.members) {
            ugvs.insert(staticTracks_[static_cast<std::size_t>(member.first)].ugv);
        }
        e.ugvs.assign(ugvs.begin(), ugvs.end());
        threats.emplace_back(so.estimate.mean, s.objects.size());
        s.objects.push_back(std::move(e));
    }
    rules::Placed civilians;
    for (const MobileObject& mo : mobileObjects_) {
        if (!mo.alive) {
            continue;
        }
        const Ellipse circle{config_.mobileSigmaM, config_.mobileSigmaM, 0.0};
        ObjectEstimate e = rules::estimateOf(*frame_, mo.pos, circle, mo.id, mo.cls, mo.state);
        e.observations = mo.observations;
        e.ugvs = mo.ugvs;
        std::sort(e.ugvs.begin(), e.ugvs.end());
        (mo.cls == OoiClass::NonCombatant ? civilians : threats).emplace_back(mo.pos, s.objects.size());
        s.objects.push_back(std::move(e));
    }
    rules::appendAlerts(s, civilians, threats);
    return s;
}

std::size_t OriginalCorrelator::storedPoints() const noexcept
{
    std::size_t n = 0;
    for (const StaticTrack& t : staticTracks_) {
        n += t.points.size();
    }
    return n + 2 * mobileTrackIndex_.size();
}

} // namespace ugv::correlator
