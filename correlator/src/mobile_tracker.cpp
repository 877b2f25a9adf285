#include "ugv/correlator/mobile_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "ugv/correlator/gaussian_mixture.hpp"
#include "ugv/correlator/measurement_model.hpp"

namespace ugv::correlator {
namespace {

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

using History = std::vector<std::pair<double, Eigen::Vector2d>>;

double median(std::vector<double>& v)
{
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
}

/// The principal axis of the history's positions: its centre, unit direction and rms width across it.
/// @return false when the history is wider than kLineMaxWidthM (no line)
bool principalAxis(const History& h, Eigen::Vector2d& centre, Eigen::Vector2d& u, double& width)
{
    centre = Eigen::Vector2d::Zero();
    for (const auto& [ht, hp] : h) {
        centre += hp;
    }
    centre /= static_cast<double>(h.size());
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (const auto& [ht, hp] : h) {
        scatter += (hp - centre) * (hp - centre).transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter / static_cast<double>(h.size()));
    width = std::sqrt(std::max(eig.eigenvalues()(0), 0.0));
    if (width > kLineMaxWidthM) {
        return false;
    }
    u = eig.eigenvectors().col(1);
    return true;
}

/// Speeds along the line over pairs of samples kLineMinBaselineS..kLineMaxBaselineS apart. A pair that straddles
/// a turn reads low and noise either way, but turns are a minority of pairs; their spread gives the uncertainty.
std::vector<double> pairSpeeds(const History& h, const std::vector<double>& along)
{
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
    return speeds;
}

/// A turn: consecutive steps in opposite directions. The ends [lo, hi]: beyond the extreme samples, where a pair
/// of consecutive samples straddles a turn (both walked to the end and back at the line's speed).
/// @return true when the history turns
bool turnsBetweenEnds(const History& h, const std::vector<double>& along, double speed, double& lo, double& hi)
{
    bool reversed = false;
    double lastStep = 0.0;
    lo = *std::min_element(along.begin(), along.end());
    hi = *std::max_element(along.begin(), along.end());
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
    return reversed;
}

} // namespace

MobileTracker::MobileTracker(const PoseCorrectedConfig& config) : config_(config) {}

void MobileTracker::predict(Mobile& m, double t) const
{
    predictState(m.x, m.p, t - m.t);
    m.t = std::max(m.t, t);
}

/// Constant velocity with continuous white-noise acceleration of density q = mobileAccelDensity: the covariance
/// of a prediction over dt is the same whether it is made in one step or many (the discrete "one acceleration per
/// step" model grows the velocity variance with dt^2 per step, which made a 10 s gap between UAV fixes look like
/// 25 m of uncertainty and hid every object that only the UAV fixes).
void MobileTracker::predictState(Eigen::Vector4d& x, Eigen::Matrix4d& pm, double dt) const
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
void MobileTracker::updateMobile(Mobile& m, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t) const
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
void MobileTracker::fitLine(Mobile& m)
{
    Line& line = m.line;
    line.valid = false;
    const History& h = m.history;
    if (h.size() < kLineMinSamples || h.back().first - h.front().first < kLineMinSpanS) {
        return;
    }
    Eigen::Vector2d centre;
    Eigen::Vector2d u;
    double width = 0.0;
    if (!principalAxis(h, centre, u, width)) {
        return;
    }
    std::vector<double> along(h.size());
    for (std::size_t i = 0; i < h.size(); ++i) {
        along[i] = u.dot(h[i].second - centre);
    }
    std::vector<double> speeds = pairSpeeds(h, along);
    if (speeds.size() < kLineMinSpeedPairs) {
        return;
    }
    const double speed = median(speeds);
    std::vector<double> deviations;
    deviations.reserve(speeds.size());
    for (const double v : speeds) {
        deviations.push_back(std::abs(v - speed));
    }
    const double speedSigma = std::max(kLineMinSpeedSigmaMps, kMadToSigma * median(deviations) /
                                                                  std::sqrt(static_cast<double>(speeds.size())));
    double lo = 0.0;
    double hi = 0.0;
    if (!turnsBetweenEnds(h, along, speed, lo, hi) || hi - lo < kLineMinLengthM) {
        return;
    }
    line = Line{true, centre, u, lo, hi, speed, speedSigma, width};
}

bool MobileTracker::predictOnLine(const Mobile& m, double t, LinePrediction& out) const
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

void MobileTracker::predictPosition(const Mobile& m, double t, Eigen::Vector2d& p, Eigen::Matrix2d& cov) const
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

int MobileTracker::nearest(OoiClass cls, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t) const
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

int MobileTracker::create(OoiClass cls, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t, ObjectIds& ids)
{
    const int index = static_cast<int>(mobiles_.size());
    Mobile created;
    ObjectIds::Issued issued = ids.issue(false, index);
    rules::identify(created, std::move(issued.id), issued.order, cls);
    created.x << z, 0.0, 0.0;
    created.p.setZero();
    created.p.topLeftCorner<2, 2>() = r;
    created.p(2, 2) = created.p(3, 3) = kWalkerSpeedSigmaMps * kWalkerSpeedSigmaMps;
    created.t = t;
    created.observations = 1;
    created.history.emplace_back(t, z);
    mobiles_.push_back(std::move(created));
    return index;
}

void MobileTracker::update(int index, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t)
{
    updateMobile(mobiles_[static_cast<std::size_t>(index)], z, r, t);
}

void MobileTracker::add(const Observation& o, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov, ObjectIds& ids)
{
    const std::string key = rules::trackKey(o.ugv, o.track);
    int index = -1;
    if (const auto it = trackObject_.find(key);
        it != trackObject_.end() && mobiles_[static_cast<std::size_t>(it->second)].alive) {
        index = it->second;
    } else {
        index = nearest(o.cls, p, cov, o.t);
    }
    if (index < 0) {
        index = create(o.cls, p, cov, o.t, ids);
    } else {
        update(index, p, cov, o.t);
    }
    trackObject_[key] = index;
    Mobile& m = mobiles_[static_cast<std::size_t>(index)];
    if (std::find(m.ugvs.begin(), m.ugvs.end(), o.ugv) == m.ugvs.end()) {
        m.ugvs.push_back(o.ugv);
    }
}

void MobileTracker::markFixedByUav(int index)
{
    Mobile& m = mobiles_[static_cast<std::size_t>(index)];
    m.state = Confirmation::ConfirmedPositive;
    if (std::find(m.ugvs.begin(), m.ugvs.end(), "uav") == m.ugvs.end()) {
        m.ugvs.emplace_back("uav");
    }
}

void MobileTracker::timeOut(double t)
{
    for (Mobile& m : mobiles_) {
        if (m.alive && t - m.t > config_.mobileTimeoutS) {
            m.alive = false;
            m.history.clear(); // memory stays bounded by the objects alive
            m.history.shrink_to_fit();
        }
    }
}

void MobileTracker::publish(double t, const LocalFrame& frame, Snapshot& s, rules::Placed& civilians,
                            rules::Placed& threats) const
{
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
        ObjectEstimate e = rules::estimateOf(frame, position, el, live.id, live.cls, live.state);
        e.observations = live.observations;
        e.ugvs = live.ugvs;
        std::sort(e.ugvs.begin(), e.ugvs.end());
        (live.cls == OoiClass::NonCombatant ? civilians : threats).emplace_back(position, s.objects.size());
        s.objects.push_back(std::move(e));
    }
}

} // namespace ugv::correlator
