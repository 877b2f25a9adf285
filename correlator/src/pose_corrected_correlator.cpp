#include "ugv/correlator/pose_corrected_correlator.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "rules.hpp"
#include <Eigen/Sparse>

#include "ugv/correlator/gaussian_mixture.hpp"
#include "ugv/correlator/gospa.hpp"

namespace ugv::correlator {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr double kSolvedHeadingSigmaDeg = 0.5; ///< remaining pose uncertainty once a UGV's errors are estimated
constexpr double kSolvedOffsetSigmaM = 0.3;
/// Added to a static object's covariance: its observations share their UGVs' remaining pose errors, so it is
/// never more certain than those (the information of independent observations would say centimetres).
constexpr double kFloorSigmaM = 0.3;
constexpr double kSplitDistanceM = 2.0; ///< track groups of one object at least this far apart may split
/// A mobile object predicted with a larger sigma is not shown: under GOSPA (c 5 m, p 2, alpha 2) an estimate that
/// far off costs about as much as a miss (12.5 m^2) and it would also crowd the planner's map with stale zones.
constexpr double kMaxPublishedMobileSigmaM = 2.5;
constexpr double kWalkerSpeedSigmaMps = 2.0; ///< prior of a new (or manoeuvring) mobile's velocity, per axis
// The line a mobile object walks (fitLine).
constexpr double kLineHistoryS = 180.0;    ///< history of filtered positions kept per mobile object
constexpr double kLineHistoryStepS = 1.0;  ///< at most one history sample per this
constexpr std::size_t kLineMinSamples = 8; ///< an object only the UAV fixes (every 10 s) has 18 in its history
constexpr std::size_t kLineMinSpeedPairs = 5;
constexpr double kLineMinSpanS = 40.0;
constexpr double kLineMaxWidthM = 1.5; ///< rms distance from the line
constexpr double kLineMinLengthM = 10.0;
constexpr double kLineMinStepM = 0.3;          ///< a step along the line shorter than this has no direction
constexpr double kLineMinBaselineS = 4.0;      ///< speed from history pairs at least this far apart (noise)...
constexpr double kLineMaxBaselineS = 15.0;     ///< ...and at most this far (the longer, the more straddle a turn)
constexpr double kLineMinSpeedSigmaMps = 0.03; ///< people do not walk at an exactly constant speed
// UAV fixes outside every gate (flushUav).
constexpr double kMaxWalkSpeedMps = 2.5; ///< farther than a person walks since the last estimate: another object
constexpr double kReachSigmas = 3.0;
constexpr double kReachMaxAgeS = 20.0; ///< an object unseen longer than this is only reached through its gate
constexpr int kMinSamplesToSolve = 10;
// Learnt noise (learnNoise).
constexpr double kMadToSigma = 1.4826;         ///< sigma of a Gaussian over its median absolute deviation
constexpr double kMaxNoiseScale = 5.0;         ///< the measured spread is trusted up to this x the configured one
constexpr int kMinNoiseSamples = 30;           ///< fewer residuals of a UGV: the configured model
constexpr int kMinNoiseObjectObservations = 6; ///< objects seen this often give residuals
constexpr double kMaxPriorObservations = 20.0; ///< a folded prior is worth at most this many observations

double mahalanobis2(const Eigen::Vector2d& d, const Eigen::Matrix2d& cov)
{
    return d.dot(cov.ldlt().solve(d));
}

} // namespace

PoseCorrectedCorrelator::PoseCorrectedCorrelator(const PoseCorrectedConfig& config) : config_(config) {}

std::string PoseCorrectedCorrelator::newId()
{
    return "ooi-" + std::to_string(nextId_++);
}

int PoseCorrectedCorrelator::ugvIndex(const std::string& name)
{
    auto [it, inserted] = ugvIndex_.try_emplace(name, static_cast<int>(ugvs_.size()));
    if (inserted) {
        ugvs_.push_back(Ugv{});
        ugvs_.back().name = name;
    }
    return it->second;
}

int PoseCorrectedCorrelator::window(double t) const
{
    return static_cast<int>(std::floor(t / config_.offsetWindowS));
}

Eigen::Vector2d PoseCorrectedCorrelator::offsetAt(int ugv, double t) const
{
    const auto& offsets = ugvs_[static_cast<std::size_t>(ugv)].offsets;
    if (offsets.empty()) {
        return Eigen::Vector2d::Zero();
    }
    const int w = std::clamp(window(t), 0, static_cast<int>(offsets.size()) - 1);
    return offsets[static_cast<std::size_t>(w)];
}

bool PoseCorrectedCorrelator::explicitCorrection(int ugv, double t, Eigen::Vector2d& dPos, double& dHeading) const
{
    dPos.setZero();
    dHeading = 0.0;
    bool covered = false;
    for (const PoseCorrection& c : ugvs_[static_cast<std::size_t>(ugv)].corrections) {
        if (t >= c.sinceT && t <= c.untilT) {
            dPos = Eigen::Vector2d(c.dEastM, c.dNorthM);
            dHeading = c.dHeadingDeg * kDegToRad;
            covered = true;
        }
    }
    return covered;
}

void PoseCorrectedCorrelator::projectSample(int ugv, const Sample& s, Eigen::Vector2d& p, Eigen::Matrix2d* cov,
                                            bool withPose) const
{
    const Ugv& u = ugvs_[static_cast<std::size_t>(ugv)];
    Eigen::Vector2d dPos;
    double dHeading = 0.0;
    // The map builder's correction is authoritative where it exists; the estimated errors cover the rest.
    const bool corrected = explicitCorrection(ugv, s.t, dPos, dHeading);
    const double az = s.headingRad + dHeading + (corrected ? 0.0 : u.headingBias) + s.bearingRad;
    const Eigen::Vector2d ray(std::sin(az), std::cos(az));
    p = s.ugvPos + dPos + (corrected ? Eigen::Vector2d::Zero() : offsetAt(ugv, s.t)) + s.rangeM * ray;
    if (cov == nullptr) {
        return;
    }
    const Eigen::Vector2d across(ray.y(), -ray.x());
    const double sr = u.rangeScale * (config_.rangeSigmaM + config_.rangeSigmaFraction * s.rangeM);
    const bool knownPose = u.solved || corrected;
    const double headingSigma =
        withPose ? (knownPose ? kSolvedHeadingSigmaDeg : config_.headingBiasSigmaDeg) * kDegToRad : 0.0;
    const double sc2 = std::pow(s.rangeM * u.bearingScale * config_.bearingSigmaDeg * kDegToRad, 2) +
                       std::pow(s.rangeM * headingSigma, 2);
    const double offset = withPose ? (knownPose ? kSolvedOffsetSigmaM : config_.offsetSigmaM) : 0.0;
    *cov = sr * sr * ray * ray.transpose() + sc2 * across * across.transpose() +
           offset * offset * Eigen::Matrix2d::Identity();
}

Result<void, Error> PoseCorrectedCorrelator::add(const Message& message)
{
    // UAV fixes of one instant are assigned together (flushUav): the first message of a later instant ends them.
    if (!pendingUav_.empty() && std::visit([](const auto& m) { return m.t; }, message) > pendingUav_.front().t) {
        flushUav();
    }
    if (const auto* o = std::get_if<Observation>(&message)) {
        now_ = std::max(now_, o->t);
        if (!frame_) {
            frame_.emplace(o->ugvLat, o->ugvLon);
        }
        const int ugv = ugvIndex(o->ugv);
        if (rules::isMobileClass(o->cls)) {
            const Sample s{o->t, frame_->toLocal(o->ugvLat, o->ugvLon), o->ugvHeadingDeg * kDegToRad, o->rangeM,
                           o->bearingDeg * kDegToRad};
            Eigen::Vector2d p;
            Eigen::Matrix2d cov;
            projectSample(ugv, s, p, &cov);
            addMobile(*o, p, cov);
        } else {
            addStatic(*o, ugv);
        }
    } else if (const auto* u = std::get_if<UavFix>(&message)) {
        now_ = std::max(now_, u->t);
        if (!frame_) {
            frame_.emplace(u->lat, u->lon);
        }
        addUav(*u);
    } else if (const auto* c = std::get_if<Confirm>(&message)) {
        now_ = std::max(now_, c->t);
        return confirm(*c);
    } else if (const auto* pc = std::get_if<PoseCorrection>(&message)) {
        now_ = std::max(now_, pc->t);
        ugvs_[static_cast<std::size_t>(ugvIndex(pc->ugv))].corrections.push_back(*pc);
        rebuildObjects(); // stored observations re-project with the correction
    }
    if (now_ - lastSolveT_ >= config_.solvePeriodS) {
        lastSolveT_ = now_;
        solve();
    }
    return {};
}

// ------------------------------------------------------------------------------------------------------ static

void PoseCorrectedCorrelator::fuse(StaticObject& object, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov,
                                   const Eigen::Matrix2d& measurementCov, double weight) const
{
    const Eigen::Matrix2d info = weight * cov.inverse();
    object.info += info;
    object.infoMean += info * p;
    object.measurementInfo += weight * measurementCov.inverse();
    object.mean = object.info.ldlt().solve(object.infoMean);
}

/// Recomputes an object's estimate from its tracks' stored samples under the current pose model.
void PoseCorrectedCorrelator::refit(StaticObject& object) const
{
    object.info = object.priorInfo;
    object.infoMean = object.priorInfo * object.priorMean;
    object.measurementInfo = object.priorInfo;
    for (const int ti : object.tracks) {
        const Track& track = tracks_[static_cast<std::size_t>(ti)];
        for (const TrackWindow& tw : track.windows) {
            const double weight =
                tw.samples.empty() ? 0.0 : static_cast<double>(tw.seen) / static_cast<double>(tw.samples.size());
            for (const Sample& smp : tw.samples) {
                Eigen::Vector2d p;
                Eigen::Matrix2d cov;
                Eigen::Matrix2d measurementCov;
                projectSample(track.ugv, smp, p, &cov);
                projectSample(track.ugv, smp, p, &measurementCov, false);
                fuse(object, p, cov, measurementCov, weight);
            }
        }
    }
    if (object.info.determinant() > 0.0) {
        object.mean = object.info.ldlt().solve(object.infoMean);
    }
}

void PoseCorrectedCorrelator::addStatic(const Observation& o, int ugv)
{
    auto [it, inserted] = trackIndex_.try_emplace(rules::trackKey(o.ugv, o.track), static_cast<int>(tracks_.size()));
    if (inserted) {
        tracks_.push_back(Track{});
        tracks_.back().ugv = ugv;
        tracks_.back().cls = o.cls;
        tracks_.back().key = it->first;
    }
    const int ti = it->second;
    const Sample s{o.t, frame_->toLocal(o.ugvLat, o.ugvLon), o.ugvHeadingDeg * kDegToRad, o.rangeM,
                   o.bearingDeg * kDegToRad};
    {
        Track& track = tracks_[static_cast<std::size_t>(ti)];
        const int w = window(o.t);
        if (track.windows.empty() || track.windows.back().window != w) {
            track.windows.push_back(TrackWindow{w, 0, {}});
        }
        TrackWindow& tw = track.windows.back();
        ++tw.seen;
        if (tw.samples.size() < config_.samplesPerTrackWindow) {
            tw.samples.push_back(s);
        } else {
            std::uniform_int_distribution<std::uint64_t> pick(0, tw.seen - 1);
            if (const std::uint64_t slot = pick(rng_); slot < config_.samplesPerTrackWindow) {
                tw.samples[slot] = s;
            }
        }
        ++track.seen;
        track.lastT = o.t;
    }
    Eigen::Vector2d p;
    Eigen::Matrix2d cov;
    Eigen::Matrix2d measurementCov;
    projectSample(ugv, s, p, &cov);
    projectSample(ugv, s, p, &measurementCov, false);
    Track& track = tracks_[static_cast<std::size_t>(ti)];
    if (track.object < 0) {
        int best = -1;
        double bestD2 = config_.gateChi2;
        for (int i = 0; i < static_cast<int>(statics_.size()); ++i) {
            const StaticObject& so = statics_[static_cast<std::size_t>(i)];
            if (!so.alive) {
                continue;
            }
            // Against an object only this UGV has seen, its pose error is common to both: measurement noise only.
            const bool ownOnly = std::all_of(so.tracks.begin(), so.tracks.end(), [this, ugv](int other) {
                return tracks_[static_cast<std::size_t>(other)].ugv == ugv;
            });
            const Eigen::Matrix2d objectCov =
                ownOnly
                    ? Eigen::Matrix2d(so.measurementInfo.inverse())
                    : Eigen::Matrix2d(so.info.inverse() + kFloorSigmaM * kFloorSigmaM * Eigen::Matrix2d::Identity());
            const double d2 = mahalanobis2(p - so.mean, (ownOnly ? measurementCov : cov) + objectCov);
            if (d2 < bestD2) {
                best = i;
                bestD2 = d2;
            }
        }
        if (best < 0) {
            StaticObject created;
            created.id = newId();
            created.order = nextId_;
            created.cls = o.cls;
            created.state = rules::initialState(o.cls);
            created.firstT = o.t;
            best = static_cast<int>(statics_.size());
            idIndex_[created.id] = {true, best};
            statics_.push_back(std::move(created));
        }
        track.object = best;
        statics_[static_cast<std::size_t>(best)].tracks.push_back(ti);
    }
    StaticObject& object = statics_[static_cast<std::size_t>(track.object)];
    fuse(object, p, cov, measurementCov);
    ++object.observations;
}

void PoseCorrectedCorrelator::rebuildObjects()
{
    for (StaticObject& so : statics_) {
        if (so.alive) {
            refit(so);
        }
    }
    splitStatics();
    mergeStatics();
}

Eigen::Vector2d PoseCorrectedCorrelator::trackMean(int trackIndex, double& weight) const
{
    const Track& track = tracks_[static_cast<std::size_t>(trackIndex)];
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    weight = 0.0;
    for (const TrackWindow& tw : track.windows) {
        const double w =
            tw.samples.empty() ? 0.0 : static_cast<double>(tw.seen) / static_cast<double>(tw.samples.size());
        for (const Sample& s : tw.samples) {
            Eigen::Vector2d p;
            projectSample(track.ugv, s, p, nullptr);
            sum += w * p;
            weight += w;
        }
    }
    return weight > 0.0 ? Eigen::Vector2d(sum / weight) : Eigen::Vector2d::Zero();
}

/// An object whose tracks form two groups far apart (two objects associated while the UGVs' pose errors were
/// still unknown) splits: the group with more observations keeps the id, the other becomes a new object.
void PoseCorrectedCorrelator::splitStatics()
{
    const std::size_t count = statics_.size();
    for (std::size_t j = 0; j < count; ++j) {
        if (!statics_[j].alive || statics_[j].tracks.size() < 2) {
            continue;
        }
        const std::vector<int> tracks = statics_[j].tracks;
        std::vector<Eigen::Vector2d> means(tracks.size());
        std::vector<double> weights(tracks.size());
        for (std::size_t i = 0; i < tracks.size(); ++i) {
            means[i] = trackMean(tracks[i], weights[i]);
        }
        // Two-means from the farthest pair.
        std::size_t a = 0;
        std::size_t b = 0;
        for (std::size_t i = 0; i < means.size(); ++i) {
            for (std::size_t k = i + 1; k < means.size(); ++k) {
                if ((means[i] - means[k]).norm() > (means[a] - means[b]).norm()) {
                    a = i;
                    b = k;
                }
            }
        }
        if ((means[a] - means[b]).norm() < kSplitDistanceM) {
            continue;
        }
        Eigen::Vector2d ca = means[a];
        Eigen::Vector2d cb = means[b];
        std::vector<bool> inB(means.size(), false);
        for (int iteration = 0; iteration < 5; ++iteration) {
            Eigen::Vector2d sa = Eigen::Vector2d::Zero();
            Eigen::Vector2d sb = Eigen::Vector2d::Zero();
            double wa = 0.0;
            double wb = 0.0;
            for (std::size_t i = 0; i < means.size(); ++i) {
                inB[i] = (means[i] - cb).norm() < (means[i] - ca).norm();
                (inB[i] ? sb : sa) += weights[i] * means[i];
                (inB[i] ? wb : wa) += weights[i];
            }
            if (wa <= 0.0 || wb <= 0.0) {
                break;
            }
            ca = sa / wa;
            cb = sb / wb;
        }
        double spread = 0.0;
        double wa = 0.0;
        double wb = 0.0;
        for (std::size_t i = 0; i < means.size(); ++i) {
            spread = std::max(spread, (means[i] - (inB[i] ? cb : ca)).norm());
            (inB[i] ? wb : wa) += weights[i];
        }
        if (wa <= 0.0 || wb <= 0.0 || (ca - cb).norm() < kSplitDistanceM || (ca - cb).norm() < 3.0 * spread) {
            continue;
        }
        // The smaller group leaves with a new id.
        const bool moveB = wb <= wa;
        StaticObject created;
        created.id = newId();
        created.order = nextId_;
        created.cls = statics_[j].cls;
        created.state = statics_[j].state;
        const int newIndex = static_cast<int>(statics_.size());
        idIndex_[created.id] = {true, newIndex};
        std::vector<int> stay;
        for (std::size_t i = 0; i < tracks.size(); ++i) {
            if (inB[i] == moveB) {
                created.tracks.push_back(tracks[i]);
                tracks_[static_cast<std::size_t>(tracks[i])].object = newIndex;
                created.observations += tracks_[static_cast<std::size_t>(tracks[i])].seen;
            } else {
                stay.push_back(tracks[i]);
            }
        }
        statics_.push_back(std::move(created));
        StaticObject& kept = statics_[j];
        kept.tracks = stay;
        kept.observations = 0;
        for (const int ti : stay) {
            kept.observations += tracks_[static_cast<std::size_t>(ti)].seen;
        }
        kept.priorInfo.setZero();
        refit(statics_[j]);
        refit(statics_[static_cast<std::size_t>(newIndex)]);
    }
}

bool PoseCorrectedCorrelator::sameObject(const StaticObject& x, const StaticObject& y) const
{
    const Eigen::Matrix2d cov =
        x.info.inverse() + y.info.inverse() + 2.0 * kFloorSigmaM * kFloorSigmaM * Eigen::Matrix2d::Identity();
    return mahalanobis2(x.mean - y.mean, cov) < config_.gateChi2;
}

void PoseCorrectedCorrelator::mergeStatics()
{
    for (std::size_t a = 0; a < statics_.size(); ++a) {
        for (std::size_t b = a + 1; b < statics_.size(); ++b) {
            StaticObject& x = statics_[a];
            StaticObject& y = statics_[b];
            if (!x.alive || !y.alive || x.info.determinant() <= 0.0 || y.info.determinant() <= 0.0) {
                continue;
            }
            if (!sameObject(x, y)) {
                continue;
            }
            StaticObject& kept = x.order <= y.order ? x : y;
            StaticObject& gone = x.order <= y.order ? y : x;
            const int keptIndex = static_cast<int>(&kept - statics_.data());
            for (const int ti : gone.tracks) {
                tracks_[static_cast<std::size_t>(ti)].object = keptIndex;
                kept.tracks.push_back(ti);
            }
            kept.info += gone.info;
            kept.infoMean += gone.infoMean;
            kept.measurementInfo += gone.measurementInfo;
            kept.priorInfo += gone.priorInfo;
            kept.priorMean = kept.mean;
            kept.mean = kept.info.ldlt().solve(kept.infoMean);
            kept.observations += gone.observations;
            kept.state = rules::inherit(kept.state, gone.state);
            gone.alive = false;
            gone.tracks.clear();
            mergedInto_[gone.id] = kept.id;
        }
    }
}

/// Gauss-Newton over the UGVs' heading biases, their offsets per window (a random walk) and the static objects.
void PoseCorrectedCorrelator::solve()
{
    // Drop samples beyond the horizon, folding them into their object's prior.
    const int oldest = window(now_ - config_.horizonS);
    for (StaticObject& so : statics_) {
        if (!so.alive) {
            continue;
        }
        std::size_t dropped = 0;
        for (const int ti : so.tracks) {
            auto& windows = tracks_[static_cast<std::size_t>(ti)].windows;
            const auto keep = std::find_if(windows.begin(), windows.end(),
                                           [oldest](const TrackWindow& tw) { return tw.window >= oldest; });
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
    // Unknowns: per UGV [heading bias, offsets of windows first..last], then per object [x, y].
    std::vector<int> ugvBase(ugvs_.size(), -1);
    std::vector<int> firstWindow(ugvs_.size(), 0);
    std::vector<int> lastWindow(ugvs_.size(), -1);
    std::vector<int> samplesOf(ugvs_.size(), 0);
    for (const StaticObject& so : statics_) {
        if (!so.alive || so.observations < static_cast<std::uint64_t>(config_.minStaticObservations)) {
            continue;
        }
        for (const int ti : so.tracks) {
            const Track& track = tracks_[static_cast<std::size_t>(ti)];
            for (const TrackWindow& tw : track.windows) {
                const auto u = static_cast<std::size_t>(track.ugv);
                firstWindow[u] = lastWindow[u] < 0 ? tw.window : std::min(firstWindow[u], tw.window);
                lastWindow[u] = std::max(lastWindow[u], tw.window);
                samplesOf[u] += static_cast<int>(tw.samples.size());
            }
        }
    }
    int n = 0;
    for (std::size_t u = 0; u < ugvs_.size(); ++u) {
        if (samplesOf[u] >= kMinSamplesToSolve) {
            ugvBase[u] = n;
            n += 1 + 2 * (lastWindow[u] - firstWindow[u] + 1);
        }
    }
    std::vector<int> objectBase(statics_.size(), -1);
    for (std::size_t j = 0; j < statics_.size(); ++j) {
        if (statics_[j].alive &&
            statics_[j].observations >= static_cast<std::uint64_t>(config_.minStaticObservations)) {
            objectBase[j] = n;
            n += 2;
        }
    }
    if (n == 0) {
        return;
    }
    for (std::size_t u = 0; u < ugvs_.size(); ++u) {
        auto& offsets = ugvs_[u].offsets;
        if (ugvBase[u] >= 0 && static_cast<int>(offsets.size()) <= lastWindow[u]) {
            const Eigen::Vector2d last = offsets.empty() ? Eigen::Vector2d::Zero() : offsets.back();
            offsets.resize(static_cast<std::size_t>(lastWindow[u]) + 1, last);
        }
    }
    const double headingPrior = 1.0 / std::pow(config_.headingBiasSigmaDeg * kDegToRad, 2);
    const double offsetPrior = 1.0 / (config_.offsetSigmaM * config_.offsetSigmaM);
    const double walkPrior =
        1.0 / (config_.driftSigmaMPerSqrtS * config_.driftSigmaMPerSqrtS * config_.offsetWindowS + 1e-4);
    for (int iteration = 0; iteration < config_.solveIterations; ++iteration) {
        std::vector<Eigen::Triplet<double>> h;
        Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
        const auto addBlock = [&h](int r, int c, const auto& m) {
            for (int i = 0; i < m.rows(); ++i) {
                for (int k = 0; k < m.cols(); ++k) {
                    h.emplace_back(r + i, c + k, m(i, k));
                }
            }
        };
        for (std::size_t j = 0; j < statics_.size(); ++j) {
            const StaticObject& so = statics_[j];
            if (objectBase[j] < 0) {
                continue;
            }
            const int xo = objectBase[j];
            if (so.priorInfo.determinant() > 0.0) {
                addBlock(xo, xo, so.priorInfo);
                g.segment<2>(xo) += so.priorInfo * (so.mean - so.priorMean);
            }
            for (const int ti : so.tracks) {
                const Track& track = tracks_[static_cast<std::size_t>(ti)];
                const auto u = static_cast<std::size_t>(track.ugv);
                for (const TrackWindow& tw : track.windows) {
                    // One window of one track shares its unknowns: sum its samples' normal-equation terms.
                    Eigen::Matrix2d sumW = Eigen::Matrix2d::Zero();   // sum W
                    Eigen::Vector2d sumWr = Eigen::Vector2d::Zero();  // sum W r
                    Eigen::Vector2d sumWj = Eigen::Vector2d::Zero();  // sum W jh
                    double sumJWj = 0.0;                              // sum jh' W jh
                    double sumJWr = 0.0;                              // sum jh' W r
                    Eigen::Matrix2d fixedW = Eigen::Matrix2d::Zero(); // samples under a pose correction
                    Eigen::Vector2d fixedWr = Eigen::Vector2d::Zero();
                    const double weight = static_cast<double>(tw.seen) / static_cast<double>(tw.samples.size());
                    for (const Sample& smp : tw.samples) {
                        Eigen::Vector2d p;
                        projectSample(track.ugv, smp, p, nullptr);
                        // Measurement noise only: the pose errors are unknowns here.
                        const double sr = config_.rangeSigmaM + config_.rangeSigmaFraction * smp.rangeM;
                        const double sc = smp.rangeM * config_.bearingSigmaDeg * kDegToRad;
                        Eigen::Vector2d dPos;
                        double dHeading = 0.0;
                        if (explicitCorrection(track.ugv, smp.t, dPos, dHeading)) {
                            // Corrected by the map builder: a fixed constraint on the object only.
                            const double az = smp.headingRad + dHeading + smp.bearingRad;
                            const Eigen::Vector2d ray(std::sin(az), std::cos(az));
                            const Eigen::Vector2d across(ray.y(), -ray.x());
                            const Eigen::Matrix2d w =
                                weight * (ray * ray.transpose() / (sr * sr) + across * across.transpose() / (sc * sc));
                            fixedW += w;
                            fixedWr += w * (p - so.mean);
                            continue;
                        }
                        const double az = smp.headingRad + dHeading + ugvs_[u].headingBias + smp.bearingRad;
                        const Eigen::Vector2d ray(std::sin(az), std::cos(az));
                        const Eigen::Vector2d across(ray.y(), -ray.x());
                        const Eigen::Matrix2d w =
                            weight * (ray * ray.transpose() / (sr * sr) + across * across.transpose() / (sc * sc));
                        const Eigen::Vector2d r = p - so.mean;
                        const Eigen::Vector2d jh = smp.rangeM * across; // d p / d heading
                        sumW += w;
                        sumWr += w * r;
                        sumWj += w * jh;
                        sumJWj += jh.dot(w * jh);
                        sumJWr += jh.dot(w * r);
                    }
                    addBlock(xo, xo, (sumW + fixedW).eval());
                    g.segment<2>(xo) -= sumWr + fixedWr;
                    if (ugvBase[u] < 0 || sumW.determinant() <= 0.0) {
                        continue;
                    }
                    const int th = ugvBase[u];
                    const int ow = th + 1 + 2 * (tw.window - firstWindow[u]);
                    const Eigen::Matrix<double, 1, 1> jj(sumJWj);
                    addBlock(th, th, jj);
                    addBlock(th, ow, sumWj.transpose());
                    addBlock(ow, th, sumWj);
                    addBlock(ow, ow, sumW);
                    addBlock(th, xo, (-sumWj).transpose());
                    addBlock(xo, th, (-sumWj).eval());
                    addBlock(ow, xo, (-sumW).eval());
                    addBlock(xo, ow, (-sumW).eval());
                    g(th) += sumJWr;
                    g.segment<2>(ow) += sumWr;
                }
            }
        }
        for (std::size_t u = 0; u < ugvs_.size(); ++u) {
            if (ugvBase[u] < 0) {
                continue;
            }
            const int th = ugvBase[u];
            h.emplace_back(th, th, headingPrior);
            g(th) += headingPrior * ugvs_[u].headingBias;
            for (int w = firstWindow[u]; w <= lastWindow[u]; ++w) {
                const int ow = th + 1 + 2 * (w - firstWindow[u]);
                const Eigen::Vector2d o = ugvs_[u].offsets[static_cast<std::size_t>(w)];
                if (w == firstWindow[u]) {
                    // The first window's offset relative to the one carried in from before (zero at the start).
                    const Eigen::Vector2d before =
                        w > 0 ? ugvs_[u].offsets[static_cast<std::size_t>(w) - 1] : Eigen::Vector2d::Zero();
                    const double prior = w > 0 ? walkPrior : offsetPrior;
                    addBlock(ow, ow, prior * Eigen::Matrix2d::Identity());
                    g.segment<2>(ow) += prior * (o - before);
                } else {
                    const Eigen::Vector2d prev = ugvs_[u].offsets[static_cast<std::size_t>(w) - 1];
                    const int op = ow - 2;
                    addBlock(ow, ow, walkPrior * Eigen::Matrix2d::Identity());
                    addBlock(op, op, walkPrior * Eigen::Matrix2d::Identity());
                    addBlock(ow, op, -walkPrior * Eigen::Matrix2d::Identity());
                    addBlock(op, ow, -walkPrior * Eigen::Matrix2d::Identity());
                    g.segment<2>(ow) += walkPrior * (o - prev);
                    g.segment<2>(op) -= walkPrior * (o - prev);
                }
                // A weak pull to zero keeps the fleet's common offset (unobservable) bounded.
                addBlock(ow, ow, 0.01 * offsetPrior * Eigen::Matrix2d::Identity());
                g.segment<2>(ow) += 0.01 * offsetPrior * o;
            }
        }
        Eigen::SparseMatrix<double> hm(n, n);
        hm.setFromTriplets(h.begin(), h.end());
        const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(hm);
        if (ldlt.info() != Eigen::Success) {
            return;
        }
        const Eigen::VectorXd delta = ldlt.solve(-g);
        for (std::size_t u = 0; u < ugvs_.size(); ++u) {
            if (ugvBase[u] < 0) {
                continue;
            }
            ugvs_[u].headingBias += delta(ugvBase[u]);
            for (int w = firstWindow[u]; w <= lastWindow[u]; ++w) {
                ugvs_[u].offsets[static_cast<std::size_t>(w)] +=
                    delta.segment<2>(ugvBase[u] + 1 + 2 * (w - firstWindow[u]));
            }
            ugvs_[u].solved = true;
        }
        for (std::size_t j = 0; j < statics_.size(); ++j) {
            if (objectBase[j] >= 0) {
                statics_[j].mean += delta.segment<2>(objectBase[j]);
            }
        }
    }
    // Windows after the last solved one start from its offset.
    rebuildObjects();
    learnNoise();
    rebuildObjects();
}

void PoseCorrectedCorrelator::learnNoise()
{
    std::vector<std::vector<double>> rangeResiduals(ugvs_.size());
    std::vector<std::vector<double>> crossResiduals(ugvs_.size());
    for (const StaticObject& so : statics_) {
        if (!so.alive || so.observations < static_cast<std::uint64_t>(kMinNoiseObjectObservations)) {
            continue;
        }
        for (const int ti : so.tracks) {
            const Track& track = tracks_[static_cast<std::size_t>(ti)];
            const auto u = static_cast<std::size_t>(track.ugv);
            for (const TrackWindow& tw : track.windows) {
                for (const Sample& smp : tw.samples) {
                    Eigen::Vector2d p;
                    projectSample(track.ugv, smp, p, nullptr);
                    const Eigen::Vector2d d = p - so.mean;
                    const Eigen::Vector2d ray = (p - smp.ugvPos).normalized();
                    const Eigen::Vector2d across(ray.y(), -ray.x());
                    const double sr = config_.rangeSigmaM + config_.rangeSigmaFraction * smp.rangeM;
                    const double sc = smp.rangeM * config_.bearingSigmaDeg * kDegToRad;
                    rangeResiduals[u].push_back(std::abs(d.dot(ray)) / sr);
                    crossResiduals[u].push_back(std::abs(d.dot(across)) / sc);
                }
            }
        }
    }
    const auto robustScale = [](std::vector<double>& v) {
        if (v.size() < static_cast<std::size_t>(kMinNoiseSamples)) {
            return 1.0;
        }
        const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
        std::nth_element(v.begin(), mid, v.end());
        return std::clamp(kMadToSigma * *mid, 1.0, kMaxNoiseScale);
    };
    for (std::size_t u = 0; u < ugvs_.size(); ++u) {
        ugvs_[u].rangeScale = robustScale(rangeResiduals[u]);
        ugvs_[u].bearingScale = robustScale(crossResiduals[u]);
    }
}

// ------------------------------------------------------------------------------------------------------ mobile

void PoseCorrectedCorrelator::predict(Mobile& m, double t) const
{
    predictState(m.x, m.p, t - m.t);
    m.t = std::max(m.t, t);
}

/// Constant velocity with continuous white-noise acceleration of density q = mobileAccelDensity: the covariance
/// of a prediction over dt is the same whether it is made in one step or many (the discrete "one acceleration per
/// step" model grows the velocity variance with dt^2 per step, which made a 10 s gap between UAV fixes look like
/// 25 m of uncertainty and hid every object that only the UAV fixes).
void PoseCorrectedCorrelator::predictState(Eigen::Vector4d& x, Eigen::Matrix4d& pm, double dt) const
{
    if (dt <= 0.0) {
        return;
    }
    Eigen::Matrix4d f = Eigen::Matrix4d::Identity();
    f(0, 2) = dt;
    f(1, 3) = dt;
    const double q = config_.mobileAccelDensity;
    Eigen::Matrix4d qm = Eigen::Matrix4d::Zero();
    for (int i = 0; i < 2; ++i) {
        qm(i, i) = q * dt * dt * dt / 3.0;
        qm(i, i + 2) = qm(i + 2, i) = q * dt * dt / 2.0;
        qm(i + 2, i + 2) = q * dt;
    }
    x = f * x;
    pm = f * pm * f.transpose() + qm;
}

/// The prior of a measurement at t is the line's prediction where the object walks a known line (so it turns at
/// the ends instead of overshooting them), else the constant-velocity one. A measurement far outside the prior
/// is a manoeuvre (a turn before any line is known, a change of course, a UAV fix after a turn between fixes):
/// the velocity is forgotten and re-learnt from the next measurements, instead of dragging the old one along.
void PoseCorrectedCorrelator::updateMobile(Mobile& m, const Eigen::Vector2d& z, const Eigen::Matrix2d& r,
                                           double t) const
{
    LinePrediction onLine;
    const bool lined = predictOnLine(m, t, onLine);
    predict(m, t);
    if (lined) {
        m.x.head<2>() = onLine.position;
        m.x.tail<2>() = onLine.velocity;
    }
    const Eigen::Vector2d innovation = z - m.x.head<2>();
    if (mahalanobis2(innovation, m.p.topLeftCorner<2, 2>() + r) > config_.gateChi2) {
        m.p.topRightCorner<2, 2>().setZero();
        m.p.bottomLeftCorner<2, 2>().setZero();
        m.p.bottomRightCorner<2, 2>() = kWalkerSpeedSigmaMps * kWalkerSpeedSigmaMps * Eigen::Matrix2d::Identity();
        m.p.topLeftCorner<2, 2>() += innovation * innovation.transpose();
    }
    const Eigen::Matrix2d s = m.p.topLeftCorner<2, 2>() + r;
    const Eigen::Matrix<double, 4, 2> k = m.p.leftCols<2>() * s.inverse();
    m.x += k * innovation;
    m.p = (Eigen::Matrix4d::Identity() - k * Eigen::Matrix<double, 2, 4>::Identity()) * m.p;
    m.t = t;
    ++m.observations;
    if (m.history.empty() || t - m.history.back().first >= kLineHistoryStepS) {
        m.history.emplace_back(t, m.x.head<2>());
        const auto old = std::find_if(m.history.begin(), m.history.end(),
                                      [t](const auto& h) { return t - h.first <= kLineHistoryS; });
        m.history.erase(m.history.begin(), old);
        fitLine(m);
    }
}

/// Fits the line an object walks back and forth (the original's observation of the mobile OOIs) to its history
/// of filtered positions: the principal axis, the speed along it and the two ends. Invalid (the object is
/// predicted by its Kalman filter alone) until the history is long, narrow and shows a turn.
void PoseCorrectedCorrelator::fitLine(Mobile& m)
{
    Line& line = m.line;
    line.valid = false;
    const auto& h = m.history;
    if (h.size() < kLineMinSamples || h.back().first - h.front().first < kLineMinSpanS) {
        return;
    }
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (const auto& [ht, hp] : h) {
        centre += hp;
    }
    centre /= static_cast<double>(h.size());
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (const auto& [ht, hp] : h) {
        scatter += (hp - centre) * (hp - centre).transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter / static_cast<double>(h.size()));
    const double width = std::sqrt(std::max(eig.eigenvalues()(0), 0.0));
    if (width > kLineMaxWidthM) {
        return;
    }
    const Eigen::Vector2d u = eig.eigenvectors().col(1);
    std::vector<double> along(h.size());
    for (std::size_t i = 0; i < h.size(); ++i) {
        along[i] = u.dot(h[i].second - centre);
    }
    // Speed: the median over pairs of samples kLineMinBaselineS..kLineMaxBaselineS apart. A pair that straddles
    // a turn reads low and noise either way, but turns are a minority of pairs; the spread gives its uncertainty.
    std::vector<double> speeds;
    for (std::size_t i = 0, j = 0; i < h.size(); ++i) {
        j = std::max(j, i + 1);
        while (j < h.size() && h[j].first - h[i].first < kLineMinBaselineS) {
            ++j;
        }
        if (j < h.size() && h[j].first - h[i].first <= kLineMaxBaselineS) {
            speeds.push_back(std::abs(along[j] - along[i]) / (h[j].first - h[i].first));
        }
    }
    if (speeds.size() < kLineMinSpeedPairs) {
        return;
    }
    const auto median = [](std::vector<double>& v) {
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
        return v[v.size() / 2];
    };
    const double speed = median(speeds);
    std::vector<double> deviations;
    deviations.reserve(speeds.size());
    for (const double v : speeds) {
        deviations.push_back(std::abs(v - speed));
    }
    constexpr double kMadToSigma = 1.4826; // of a normal distribution
    const double speedSigma = std::max(kLineMinSpeedSigmaMps, kMadToSigma * median(deviations) /
                                                                  std::sqrt(static_cast<double>(speeds.size())));
    // A turn: consecutive steps in opposite directions. The ends: beyond the extreme samples, where a pair of
    // consecutive samples straddles a turn (both walked to the end and back at the line's speed).
    bool reversed = false;
    double lastStep = 0.0;
    double lo = *std::min_element(along.begin(), along.end());
    double hi = *std::max_element(along.begin(), along.end());
    for (std::size_t i = 1; i < h.size(); ++i) {
        const double step = along[i] - along[i - 1];
        reversed = reversed || (step * lastStep < 0.0 && std::abs(step) > kLineMinStepM);
        lastStep = std::abs(step) > kLineMinStepM ? step : lastStep;
        const double dt = h[i].first - h[i - 1].first;
        if (dt <= kLineMaxBaselineS) {
            hi = std::max(hi, (along[i] + along[i - 1] + speed * dt) / 2.0);
            lo = std::min(lo, (along[i] + along[i - 1] - speed * dt) / 2.0);
        }
    }
    if (!reversed || hi - lo < kLineMinLengthM) {
        return;
    }
    line = Line{true, centre, u, lo, hi, speed, speedSigma, width};
}

bool PoseCorrectedCorrelator::predictOnLine(const Mobile& m, double t, LinePrediction& out) const
{
    const Line& line = m.line;
    if (!line.valid) {
        return false;
    }
    double along = std::clamp(line.u.dot(m.x.head<2>() - line.centre), line.lo, line.hi);
    double direction = line.u.dot(m.x.tail<2>()) >= 0.0 ? 1.0 : -1.0;
    const double dt = std::max(0.0, t - m.t);
    // Walk, turning at the ends; whole round trips change nothing.
    const double length = line.hi - line.lo;
    double remaining = std::fmod(line.speed * dt, 2.0 * length);
    while (remaining > 0.0) {
        const double room = direction > 0.0 ? line.hi - along : along - line.lo;
        if (remaining <= room) {
            along += direction * remaining;
            break;
        }
        along += direction * room;
        remaining -= room;
        direction = -direction;
    }
    out.position = line.centre + along * line.u;
    out.velocity = direction * line.speed * line.u;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> last(m.p.topLeftCorner<2, 2>());
    out.sigma =
        std::sqrt(std::max(last.eigenvalues()(1), 0.0) + std::pow(line.speedSigma * dt, 2) + line.width * line.width);
    return true;
}

void PoseCorrectedCorrelator::predictPosition(const Mobile& m, double t, Eigen::Vector2d& p, Eigen::Matrix2d& cov) const
{
    LinePrediction onLine;
    if (predictOnLine(m, t, onLine)) {
        p = onLine.position;
        cov = onLine.sigma * onLine.sigma * Eigen::Matrix2d::Identity();
        return;
    }
    Eigen::Vector4d x = m.x;
    Eigen::Matrix4d pm = m.p;
    predictState(x, pm, t - m.t);
    p = x.head<2>();
    cov = pm.topLeftCorner<2, 2>();
}

int PoseCorrectedCorrelator::nearestMobile(OoiClass cls, const Eigen::Vector2d& z, const Eigen::Matrix2d& r,
                                           double t) const
{
    int index = -1;
    double bestD2 = config_.gateChi2;
    for (int i = 0; i < static_cast<int>(mobiles_.size()); ++i) {
        const Mobile& m = mobiles_[static_cast<std::size_t>(i)];
        if (!m.alive || m.cls != cls) {
            continue;
        }
        Eigen::Vector2d p;
        Eigen::Matrix2d cov;
        predictPosition(m, t, p, cov);
        const double d2 = mahalanobis2(z - p, cov + r);
        if (d2 < bestD2) {
            index = i;
            bestD2 = d2;
        }
    }
    return index;
}

int PoseCorrectedCorrelator::createMobile(OoiClass cls, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t)
{
    Mobile created;
    created.id = newId();
    created.order = nextId_;
    created.cls = cls;
    created.state = rules::initialState(cls);
    created.x << z, 0.0, 0.0;
    created.p.setZero();
    created.p.topLeftCorner<2, 2>() = r;
    created.p(2, 2) = created.p(3, 3) = kWalkerSpeedSigmaMps * kWalkerSpeedSigmaMps;
    created.t = t;
    created.observations = 1;
    created.history.emplace_back(t, z);
    const int index = static_cast<int>(mobiles_.size());
    idIndex_[created.id] = {false, index};
    mobiles_.push_back(std::move(created));
    return index;
}

void PoseCorrectedCorrelator::addMobile(const Observation& o, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov)
{
    const std::string key = rules::trackKey(o.ugv, o.track);
    int index = -1;
    if (const auto it = mobileTrackObject_.find(key);
        it != mobileTrackObject_.end() && mobiles_[static_cast<std::size_t>(it->second)].alive) {
        index = it->second;
    } else {
        index = nearestMobile(o.cls, p, cov, o.t);
    }
    if (index < 0) {
        index = createMobile(o.cls, p, cov, o.t);
    } else {
        updateMobile(mobiles_[static_cast<std::size_t>(index)], p, cov, o.t);
    }
    mobileTrackObject_[key] = index;
    Mobile& m = mobiles_[static_cast<std::size_t>(index)];
    if (std::find(m.ugvs.begin(), m.ugvs.end(), o.ugv) == m.ugvs.end()) {
        m.ugvs.push_back(o.ugv);
    }
}

void PoseCorrectedCorrelator::addUav(const UavFix& u)
{
    if (!pendingUav_.empty() && pendingUav_.front().t != u.t) {
        flushUav();
    }
    pendingUav_.push_back(u);
}

/// The UAV fixes of one instant, assigned jointly (an optimal assignment of their statistical distances), so
/// that one object's fix cannot take the track of another it passes close to (one at a time, the first fix took
/// whichever track was nearest and left the other fix the wrong one). A fix outside every gate may still go to an
/// object it could have walked to since its last estimate (a turn between two fixes of an object that only the
/// UAV sees), at a cost above every gated pair; a fix cheapest alone is a new object.
void PoseCorrectedCorrelator::flushUav()
{
    if (pendingUav_.empty()) {
        return;
    }
    const Eigen::Matrix2d r = config_.uavSigmaM * config_.uavSigmaM * Eigen::Matrix2d::Identity();
    const double newObjectCost = config_.gateChi2 + 1.0; // above every pair: gated < gate, reached < gate + 1
    const double forbidden = 1e6 * newObjectCost;
    const std::size_t fixCount = pendingUav_.size();
    std::vector<Eigen::Vector2d> fixes;
    std::vector<int> candidates; // mobile indices of the columns after the fixes' own "new object" columns
    for (int i = 0; i < static_cast<int>(mobiles_.size()); ++i) {
        if (mobiles_[static_cast<std::size_t>(i)].alive) {
            candidates.push_back(i);
        }
    }
    const std::size_t cols = fixCount + candidates.size();
    std::vector<double> cost(fixCount * cols, forbidden);
    for (std::size_t k = 0; k < fixCount; ++k) {
        const UavFix& u = pendingUav_[k];
        const Eigen::Vector2d z = frame_->toLocal(u.lat, u.lon);
        fixes.push_back(z);
        const OoiClass cls = u.cls == OoiClass::NonCombatant ? OoiClass::NonCombatant : OoiClass::Mobile;
        cost[k * cols + k] = newObjectCost;
        for (std::size_t c = 0; c < candidates.size(); ++c) {
            const Mobile& m = mobiles_[static_cast<std::size_t>(candidates[c])];
            if (m.cls != cls) {
                continue;
            }
            Eigen::Vector2d p;
            Eigen::Matrix2d cov;
            predictPosition(m, u.t, p, cov);
            const double d2 = mahalanobis2(z - p, cov + r);
            const double age = u.t - m.t;
            const double reach = kMaxWalkSpeedMps * age + kReachSigmas * std::sqrt(m.p.topLeftCorner<2, 2>().trace());
            const double d = (z - m.x.head<2>()).norm();
            if (d2 < config_.gateChi2) {
                cost[k * cols + fixCount + c] = d2;
            } else if (age <= kReachMaxAgeS && d <= reach) {
                cost[k * cols + fixCount + c] = config_.gateChi2 + d / reach;
            }
        }
    }
    const std::vector<int> column = solveAssignment(cost, fixCount, cols);
    std::vector<int> assigned(fixCount, -1);
    for (std::size_t k = 0; k < fixCount; ++k) {
        const int c = column[k];
        if (c >= static_cast<int>(fixCount) && cost[k * cols + static_cast<std::size_t>(c)] < forbidden) {
            assigned[k] = candidates[static_cast<std::size_t>(c) - fixCount];
        }
    }
    for (std::size_t k = 0; k < pendingUav_.size(); ++k) {
        const UavFix& u = pendingUav_[k];
        int index = assigned[k];
        if (index < 0) {
            const OoiClass cls = u.cls == OoiClass::NonCombatant ? OoiClass::NonCombatant : OoiClass::Mobile;
            index = createMobile(cls, fixes[k], r, u.t);
        } else {
            updateMobile(mobiles_[static_cast<std::size_t>(index)], fixes[k], r, u.t);
        }
        Mobile& m = mobiles_[static_cast<std::size_t>(index)];
        m.state = Confirmation::ConfirmedPositive;
        if (std::find(m.ugvs.begin(), m.ugvs.end(), "uav") == m.ugvs.end()) {
            m.ugvs.emplace_back("uav");
        }
    }
    pendingUav_.clear();
}

Result<void, Error> PoseCorrectedCorrelator::confirm(const Confirm& c)
{
    std::string id = c.id;
    for (auto it = mergedInto_.find(id); it != mergedInto_.end(); it = mergedInto_.find(id)) {
        id = it->second;
    }
    const auto found = idIndex_.find(id);
    if (found == idIndex_.end()) {
        return Unexpected(Error{"confirm", "unknown object id '" + c.id + "'", "use an id from a snapshot"});
    }
    const auto [isStatic, index] = found->second;
    if (isStatic) {
        statics_[static_cast<std::size_t>(index)].state = c.state;
    } else {
        mobiles_[static_cast<std::size_t>(index)].state = c.state;
    }
    return {};
}

// ------------------------------------------------------------------------------------------------------ output

/// Clutter gathers into objects over a long mission unless objects that stay below minStaticObservations die.
void PoseCorrectedCorrelator::dropTentative(double t)
{
    for (StaticObject& so : statics_) {
        if (!so.alive || so.observations >= static_cast<std::uint64_t>(config_.minStaticObservations) ||
            t - so.firstT <= config_.tentativeTimeoutS) {
            continue;
        }
        so.alive = false;
        idIndex_.erase(so.id);
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

void PoseCorrectedCorrelator::advance(double t)
{
    flushUav();
    dropTentative(t);
    timeOutMobiles(t);
}

void PoseCorrectedCorrelator::timeOutMobiles(double t)
{
    for (Mobile& m : mobiles_) {
        if (m.alive && t - m.t > config_.mobileTimeoutS) {
            m.alive = false;
            m.history.clear(); // memory stays bounded by the objects alive
            m.history.shrink_to_fit();
        }
    }
}

Snapshot PoseCorrectedCorrelator::snapshot(double t) const
{
    Snapshot s;
    s.t = t;
    if (!frame_) {
        return s;
    }
    rules::Placed threats;
    std::vector<const StaticObject*> published; // in creation order (statics_ is), so the older come first
    for (const StaticObject& so : statics_) {
        if (!so.alive || so.observations < static_cast<std::uint64_t>(config_.minStaticObservations) ||
            so.info.determinant() <= 0.0) {
            continue;
        }
        // A duplicate of an older object (a churned track UUID that missed the gate at first) is not shown while
        // it waits for the next merge: its id would steal the object's for a while and then vanish.
        if (std::any_of(published.begin(), published.end(),
                        [&](const StaticObject* older) { return sameObject(*older, so); })) {
            continue;
        }
        ObjectEstimate e;
        e.id = so.id;
        e.cls = so.cls;
        frame_->toLatLon(so.mean, e.lat, e.lon);
        const Ellipse el = ellipseOf(so.info.inverse() + kFloorSigmaM * kFloorSigmaM * Eigen::Matrix2d::Identity());
        e.sigmaMajorM = el.sigmaMajor;
        e.sigmaMinorM = el.sigmaMinor;
        e.majorAxisDeg = el.majorAxisDeg;
        e.state = so.state;
        e.observations = static_cast<int>(so.observations);
        std::set<std::string> names;
        bool sustained = false; // a track that saw it twice: clutter falls on an object once per track
        for (const int ti : so.tracks) {
            names.insert(ugvs_[static_cast<std::size_t>(tracks_[static_cast<std::size_t>(ti)].ugv)].name);
            sustained = sustained || tracks_[static_cast<std::size_t>(ti)].seen >= 2;
        }
        if (!sustained && names.size() < 2) {
            continue;
        }
        e.ugvs.assign(names.begin(), names.end());
        e.zoneDiameterM = kStaticZoneDiameterM;
        published.push_back(&so);
        threats.emplace_back(so.mean, s.objects.size());
        s.objects.push_back(std::move(e));
    }
    rules::Placed civilians;
    for (const Mobile& live : mobiles_) {
        if (!live.alive ||
            (live.observations < config_.minMobileObservations && live.state != Confirmation::ConfirmedPositive)) {
            continue;
        }
        // Through the gap since its last measurement, along its line if it walks one.
        Eigen::Vector2d position;
        Eigen::Matrix2d cov;
        predictPosition(live, t, position, cov);
        const Ellipse el = ellipseOf(cov);
        if (el.sigmaMajor > kMaxPublishedMobileSigmaM) {
            continue; // predicted too long to be useful; kept (with its id) for when it is seen again
        }
        ObjectEstimate e;
        e.id = live.id;
        e.cls = live.cls;
        frame_->toLatLon(position, e.lat, e.lon);
        e.sigmaMajorM = el.sigmaMajor;
        e.sigmaMinorM = el.sigmaMinor;
        e.majorAxisDeg = el.majorAxisDeg;
        e.state = live.state;
        e.observations = live.observations;
        e.ugvs = live.ugvs;
        std::sort(e.ugvs.begin(), e.ugvs.end());
        e.zoneDiameterM = kMobileZoneDiameterM;
        (live.cls == OoiClass::NonCombatant ? civilians : threats).emplace_back(position, s.objects.size());
        s.objects.push_back(std::move(e));
    }
    rules::appendAlerts(s, civilians, threats);
    return s;
}

std::size_t PoseCorrectedCorrelator::storedPoints() const noexcept
{
    std::size_t n = 0;
    for (const Track& t : tracks_) {
        for (const TrackWindow& tw : t.windows) {
            n += tw.samples.size();
        }
    }
    return n;
}

std::optional<PoseCorrectedCorrelator::PoseError> PoseCorrectedCorrelator::poseError(const std::string& ugv,
                                                                                     double t) const
{
    const auto it = ugvIndex_.find(ugv);
    if (it == ugvIndex_.end()) {
        return std::nullopt;
    }
    return PoseError{ugvs_[static_cast<std::size_t>(it->second)].headingBias / kDegToRad, offsetAt(it->second, t)};
}

std::optional<PoseCorrectedCorrelator::NoiseScale> PoseCorrectedCorrelator::noiseScale(const std::string& ugv) const
{
    const auto it = ugvIndex_.find(ugv);
    if (it == ugvIndex_.end()) {
        return std::nullopt;
    }
    const Ugv& u = ugvs_[static_cast<std::size_t>(it->second)];
    return NoiseScale{u.rangeScale, u.bearingScale};
}

} // namespace ugv::correlator
