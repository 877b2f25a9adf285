#include "ugv/tool/correlate_score.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>

namespace ugv::tool {
namespace {

using correlator::GospaResult;
using correlator::OoiClass;
using correlator::Snapshot;
using Eigen::Vector2d;

constexpr double kTimeSlackS = 1e-6;

/// The snapshot's objects of class `cls`: positions in the plane and their ids.
struct ClassObjects {
    std::vector<Vector2d> positions;
    std::vector<std::string> ids;
};

ClassObjects objectsOf(const Snapshot& snapshot, OoiClass cls, const correlator::LocalFrame& frame)
{
    ClassObjects objects;
    for (const auto& object : snapshot.objects) {
        if (object.cls == cls) {
            objects.positions.push_back(frame.toLocal(object.lat, object.lon));
            objects.ids.push_back(object.id);
        }
    }
    return objects;
}

/// Every moving object of `cls` with a sample within half a period of t, at that (nearest) sample.
std::vector<Vector2d> movingTruthAt(const Truth& truth, OoiClass cls, double t)
{
    std::vector<Vector2d> positions;
    for (const auto& [id, track] : truth.moving) {
        if (track.cls != cls || track.samples.empty()) {
            continue;
        }
        const auto& samples = track.samples;
        auto it = std::lower_bound(samples.begin(), samples.end(), t,
                                   [](const TimedPosition& s, double time) { return s.t < time; });
        if (it == samples.end() || (it != samples.begin() && t - std::prev(it)->t < it->t - t)) {
            it = std::prev(it);
        }
        if (std::abs(it->t - t) <= truth.periodS / 2.0 + kTimeSlackS) {
            positions.push_back(it->position);
        }
    }
    return positions;
}

/// Adds one snapshot's static ID changes to `changes`. `previous` holds, per static truth object, the id assigned
/// to it in the previous snapshot (empty: none); it is updated to this snapshot's.
void countIdChanges(const GospaResult& result, const ClassObjects& objects, std::vector<std::string>& previous,
                    std::size_t& changes)
{
    for (std::size_t i = 0; i < previous.size(); ++i) {
        const int j = result.truthToEstimate[i];
        const std::string current = j >= 0 ? objects.ids[static_cast<std::size_t>(j)] : std::string();
        if (!previous[i].empty() && !current.empty() && current != previous[i]) {
            ++changes;
        }
        previous[i] = current;
    }
}

} // namespace

Truth truthOf(const correlator::ScenarioTruth& truth)
{
    const correlator::LocalFrame frame(truth.originLat, truth.originLon);
    Truth out;
    out.originLat = truth.originLat;
    out.originLon = truth.originLon;
    out.durationS = truth.durationS;
    out.periodS = truth.periodS;
    for (const auto& object : truth.statics) {
        out.staticIds.push_back(object.id);
        out.statics.push_back(frame.toLocal(object.lat, object.lon));
    }
    for (const auto& sample : truth.moving) {
        MovingTrack& track = out.moving[sample.id];
        track.cls = sample.cls;
        track.samples.push_back({sample.t, frame.toLocal(sample.lat, sample.lon)});
    }
    return out; // the generator's samples are in time order
}

void GospaMean::add(const GospaResult& r)
{
    ++snapshots;
    total += r.total;
    localisationPart += r.localisationPart;
    missedPart += r.missedPart;
    falsePart += r.falsePart;
}

SnapshotScorer::SnapshotScorer(const Truth& truth)
    : truth_(truth), frame_(truth.originLat, truth.originLon), previousIds_(truth.statics.size())
{
}

void SnapshotScorer::add(const Snapshot& snapshot)
{
    if (figures_.snapshots == 0) {
        figures_.firstT = snapshot.t;
    }
    ++figures_.snapshots;
    figures_.lastT = snapshot.t;
    const ClassObjects statics = objectsOf(snapshot, OoiClass::Static, frame_);
    const GospaResult staticResult = correlator::gospa(truth_.statics, statics.positions, kScoreGospa);
    countIdChanges(staticResult, statics, previousIds_, figures_.staticIdChanges);
    figures_.staticLast = staticResult;
    figures_.staticEstimates = statics.positions.size();
    const bool covered =
        snapshot.t >= -truth_.periodS / 2.0 && snapshot.t <= truth_.durationS + truth_.periodS / 2.0 + kTimeSlackS;
    if (!covered) {
        return; // outside the truth's time span: the moving objects' positions are unknown
    }
    for (auto [cls, mean] :
         {std::pair{OoiClass::Mobile, &figures_.mobile}, std::pair{OoiClass::NonCombatant, &figures_.nonCombatant}}) {
        mean->add(correlator::gospa(movingTruthAt(truth_, cls, snapshot.t), objectsOf(snapshot, cls, frame_).positions,
                                    kScoreGospa));
    }
}

Figures score(const std::vector<Snapshot>& snapshots, const Truth& truth)
{
    SnapshotScorer scorer(truth);
    for (const Snapshot& snapshot : snapshots) {
        scorer.add(snapshot);
    }
    return scorer.figures();
}

} // namespace ugv::tool
