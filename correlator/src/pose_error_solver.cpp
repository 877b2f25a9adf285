#include "ugv/correlator/pose_error_solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/Sparse>

#include "ugv/correlator/measurement_model.hpp"

namespace ugv::correlator {
namespace {

constexpr int kMinSamplesToSolve = 10;
/// A weak pull of every offset to zero (this x the offset prior) keeps the fleet's common offset (unobservable)
/// bounded.
constexpr double kCommonOffsetPull = 0.01;
constexpr double kWalkPriorFloor = 1e-4; ///< [m^2] keeps the random walk's prior finite without drift
// Learnt noise (learnNoise).
constexpr double kMaxNoiseScale = 5.0;            ///< the measured spread is trusted up to this x the configured one
constexpr int kMinNoiseSamples = 30;              ///< fewer residuals of a UGV: the configured model
constexpr int kMinNoiseObjectObservations = 6;    ///< objects seen this often give residuals
constexpr int kMinSpreadTracks = 8;               ///< fewer tracks of a UGV on shared objects: spread not measured
constexpr double kMedianToSigma2d = 1.0 / 1.1774; ///< per-axis sigma over the median distance of a 2-D Gaussian
constexpr double kMaxPoseSpreadM = 2.0;           ///< [m] the measured spread is trusted up to this
// The test that the evidence shows a pose error (keepOnlyShownErrors).
constexpr double kSqrt2 = 1.4142135623730951;
constexpr int kQuantileBisections = 60; ///< halvings of [0, kMaxNormalQuantile]: far below double precision
constexpr double kMaxNormalQuantile = 40.0;

using Triplets = std::vector<Eigen::Triplet<double>>;

/// Where each unknown sits: per UGV [heading bias, offsets of windows first..last], then per object [x, y]; -1:
/// not solved.
struct Layout {
    std::vector<int> ugvBase;
    std::vector<int> firstWindow;
    std::vector<int> lastWindow;
    std::vector<int> objectBase;
    int n = 0;
};

/// The weights of the stored samples: for the solve, each window's samples stand for every observation of it
/// (seen / stored) under the configured noise; for the test of keepOnlyShownErrors, what the estimate really rests
/// on: each stored sample once, under its UGV's learnt noise (the estimate is a weighted mean of the stored samples,
/// so its spread is theirs, not that of every observation).
enum class SampleWeights : std::uint8_t { Solve, Test };

/// The normal equations H delta = -g of one Gauss-Newton step.
struct NormalEquations {
    Triplets h;
    Eigen::VectorXd g;
};

template <class Block>
void addBlock(Triplets& h, int r, int c, const Block& m)
{
    for (int i = 0; i < m.rows(); ++i) {
        for (int k = 0; k < m.cols(); ++k) {
            h.emplace_back(r + i, c + k, m(i, k));
        }
    }
}

bool solvable(const StaticMap::StaticObject& so, const PoseCorrectedConfig& config)
{
    return so.alive && so.observations >= static_cast<std::uint64_t>(config.minStaticObservations);
}

Layout layoutOf(const StaticMap& map, const UgvPoseErrors& poses, const PoseCorrectedConfig& config)
{
    Layout l;
    l.ugvBase.assign(poses.size(), -1);
    l.firstWindow.assign(poses.size(), 0);
    l.lastWindow.assign(poses.size(), -1);
    std::vector<int> samplesOf(poses.size(), 0);
    for (const StaticMap::StaticObject& so : map.objects()) {
        if (!solvable(so, config)) {
            continue;
        }
        for (const int ti : so.tracks) {
            const StaticMap::Track& track = map.tracks()[static_cast<std::size_t>(ti)];
            for (const StaticMap::TrackWindow& tw : track.windows) {
                const auto u = static_cast<std::size_t>(track.ugv);
                l.firstWindow[u] = l.lastWindow[u] < 0 ? tw.window : std::min(l.firstWindow[u], tw.window);
                l.lastWindow[u] = std::max(l.lastWindow[u], tw.window);
                samplesOf[u] += static_cast<int>(tw.samples.size());
            }
        }
    }
    for (std::size_t u = 0; u < poses.size(); ++u) {
        if (samplesOf[u] >= kMinSamplesToSolve) {
            l.ugvBase[u] = l.n;
            l.n += 1 + 2 * (l.lastWindow[u] - l.firstWindow[u] + 1);
        }
    }
    l.objectBase.assign(map.objects().size(), -1);
    for (std::size_t j = 0; j < map.objects().size(); ++j) {
        if (solvable(map.objects()[j], config)) {
            l.objectBase[j] = l.n;
            l.n += 2;
        }
    }
    return l;
}

/// Windows up to the last one solved get an offset (a new one starts from the one before).
void extendOffsets(UgvPoseErrors& poses, const Layout& l)
{
    for (std::size_t u = 0; u < poses.size(); ++u) {
        auto& offsets = poses.ugv(u).offsets;
        if (l.ugvBase[u] >= 0 && static_cast<int>(offsets.size()) <= l.lastWindow[u]) {
            const Eigen::Vector2d last = offsets.empty() ? Eigen::Vector2d::Zero() : offsets.back();
            offsets.resize(static_cast<std::size_t>(l.lastWindow[u]) + 1, last);
        }
    }
}

/// The sums of one window's normal-equation terms: its samples share their unknowns.
struct WindowSums {
    Eigen::Matrix2d w = Eigen::Matrix2d::Zero();  // sum W
    Eigen::Vector2d wr = Eigen::Vector2d::Zero(); // sum W r
    Eigen::Vector2d wj = Eigen::Vector2d::Zero(); // sum W jh
    double jwj = 0.0;                             // sum jh' W jh
    double jwr = 0.0;                             // sum jh' W r

    /// Huber on the window's mean: a window whose mean is off its object by more than the gate (the chi-square of
    /// the mean of its stored samples, each `weight` in the sums, under the configured noise: a track on the wrong
    /// object of a close pair, a reading of the other post, clutter) pulls with a bounded force instead of one that
    /// grows with its distance; recomputed at every Gauss-Newton step (iteratively reweighted). The configured noise
    /// is the floor of the learnt one, so in a noisier world more windows are bounded: the estimate tends to the
    /// median-like L1 fit, which is what a misassociated window must not move.
    void bound(double weight, double gateChi2)
    {
        if (w.determinant() <= 0.0 || weight <= 0.0) {
            return;
        }
        const double m2 = wr.dot(w.inverse() * wr) / weight;
        if (m2 <= gateChi2) {
            return;
        }
        const double k = std::sqrt(gateChi2 / m2);
        w *= k;
        wr *= k;
        wj *= k;
        jwj *= k;
        jwr *= k;
    }
};

/// The terms of one window of one track of the object at `xo`.
void addWindowTerms(const StaticMap::Track& track, const StaticMap::TrackWindow& tw, const Eigen::Vector2d& objectMean,
                    int xo, const UgvPoseErrors& poses, const Layout& l, const PoseCorrectedConfig& config,
                    SampleWeights weights, NormalEquations& eq)
{
    const auto u = static_cast<std::size_t>(track.ugv);
    WindowSums sums;
    Eigen::Matrix2d fixedW = Eigen::Matrix2d::Zero(); // samples under a pose correction
    Eigen::Vector2d fixedWr = Eigen::Vector2d::Zero();
    const bool test = weights == SampleWeights::Test;
    const double weight = test ? 1.0 : static_cast<double>(tw.seen) / static_cast<double>(tw.samples.size());
    const RangeBearingNoise noise = config.noise();
    const UgvPoseErrors::Ugv& ugv = poses.ugv(static_cast<std::size_t>(track.ugv));
    const double rangeScale = test ? ugv.rangeScale : 1.0;
    const double bearingScale = test ? ugv.bearingScale : 1.0;
    for (const RangeBearing& smp : tw.samples) {
        Eigen::Vector2d p;
        Eigen::Vector2d ray;
        poses.project(track.ugv, smp, p, nullptr, nullptr, &ray);
        // Measurement noise only: the pose errors are unknowns here.
        const double sr = noise.alongSigma(smp.rangeM, rangeScale);
        const double sc = noise.acrossSigma(smp.rangeM, bearingScale);
        Eigen::Vector2d dPos;
        double dHeading = 0.0;
        if (poses.explicitCorrection(track.ugv, smp.t, dPos, dHeading)) {
            // Corrected by the map builder: a fixed constraint on the object only.
            const Eigen::Vector2d fixedRay = rayAt(smp.headingRad + dHeading + smp.bearingRad);
            const Eigen::Matrix2d w = weight * rayInformation(fixedRay, sr, sc);
            fixedW += w;
            fixedWr += w * (p - objectMean);
            continue;
        }
        // `ray` is along the azimuth with the estimated heading bias.
        const Eigen::Matrix2d w = weight * rayInformation(ray, sr, sc);
        const Eigen::Vector2d r = p - objectMean;
        const Eigen::Vector2d jh = smp.rangeM * acrossOf(ray); // d p / d heading
        sums.w += w;
        sums.wr += w * r;
        sums.wj += w * jh;
        sums.jwj += jh.dot(w * jh);
        sums.jwr += jh.dot(w * r);
    }
    sums.bound(weight, config.gateChi2);
    addBlock(eq.h, xo, xo, (sums.w + fixedW).eval());
    eq.g.segment<2>(xo) -= sums.wr + fixedWr;
    if (l.ugvBase[u] < 0 || sums.w.determinant() <= 0.0) {
        return;
    }
    const int th = l.ugvBase[u];
    const int ow = th + 1 + 2 * (tw.window - l.firstWindow[u]);
    const Eigen::Matrix<double, 1, 1> jj(sums.jwj);
    addBlock(eq.h, th, th, jj);
    addBlock(eq.h, th, ow, sums.wj.transpose());
    addBlock(eq.h, ow, th, sums.wj);
    addBlock(eq.h, ow, ow, sums.w);
    addBlock(eq.h, th, xo, (-sums.wj).transpose());
    addBlock(eq.h, xo, th, (-sums.wj).eval());
    addBlock(eq.h, ow, xo, (-sums.w).eval());
    addBlock(eq.h, xo, ow, (-sums.w).eval());
    eq.g(th) += sums.jwr;
    eq.g.segment<2>(ow) += sums.wr;
}

void addObservationTerms(const StaticMap& map, const UgvPoseErrors& poses, const Layout& l,
                         const PoseCorrectedConfig& config, SampleWeights weights, NormalEquations& eq)
{
    for (std::size_t j = 0; j < map.objects().size(); ++j) {
        const StaticMap::StaticObject& so = map.objects()[j];
        if (l.objectBase[j] < 0) {
            continue;
        }
        const int xo = l.objectBase[j];
        if (so.priorInfo.determinant() > 0.0) {
            addBlock(eq.h, xo, xo, so.priorInfo);
            eq.g.segment<2>(xo) += so.priorInfo * (so.mean - so.priorMean);
        }
        for (const int ti : so.tracks) {
            const StaticMap::Track& track = map.tracks()[static_cast<std::size_t>(ti)];
            for (const StaticMap::TrackWindow& tw : track.windows) {
                addWindowTerms(track, tw, so.mean, xo, poses, l, config, weights, eq);
            }
        }
    }
}

/// The priors of the UGVs' errors: heading bias zero-mean; the first window's offset about the one carried in
/// from before (zero at the start), each later one a random walk from the one before.
void addPoseTerms(const UgvPoseErrors& poses, const Layout& l, const PoseCorrectedConfig& config, NormalEquations& eq)
{
    const double headingPrior = 1.0 / std::pow(config.headingBiasSigmaDeg * kRadPerDeg, 2);
    const double offsetPrior = 1.0 / (config.offsetSigmaM * config.offsetSigmaM);
    const double walkPrior =
        1.0 / (config.driftSigmaMPerSqrtS * config.driftSigmaMPerSqrtS * config.offsetWindowS + kWalkPriorFloor);
    for (std::size_t u = 0; u < poses.size(); ++u) {
        if (l.ugvBase[u] < 0) {
            continue;
        }
        const auto& offsets = poses.ugv(u).offsets;
        const int th = l.ugvBase[u];
        eq.h.emplace_back(th, th, headingPrior);
        eq.g(th) += headingPrior * poses.ugv(u).headingBias;
        for (int w = l.firstWindow[u]; w <= l.lastWindow[u]; ++w) {
            const int ow = th + 1 + 2 * (w - l.firstWindow[u]);
            const Eigen::Vector2d o = offsets[static_cast<std::size_t>(w)];
            if (w == l.firstWindow[u]) {
                const Eigen::Vector2d before =
                    w > 0 ? offsets[static_cast<std::size_t>(w) - 1] : Eigen::Vector2d::Zero();
                const double prior = w > 0 ? walkPrior : offsetPrior;
                addBlock(eq.h, ow, ow, prior * Eigen::Matrix2d::Identity());
                eq.g.segment<2>(ow) += prior * (o - before);
            } else {
                const Eigen::Vector2d prev = offsets[static_cast<std::size_t>(w) - 1];
                const int op = ow - 2;
                addBlock(eq.h, ow, ow, walkPrior * Eigen::Matrix2d::Identity());
                addBlock(eq.h, op, op, walkPrior * Eigen::Matrix2d::Identity());
                addBlock(eq.h, ow, op, -walkPrior * Eigen::Matrix2d::Identity());
                addBlock(eq.h, op, ow, -walkPrior * Eigen::Matrix2d::Identity());
                eq.g.segment<2>(ow) += walkPrior * (o - prev);
                eq.g.segment<2>(op) -= walkPrior * (o - prev);
            }
            addBlock(eq.h, ow, ow, kCommonOffsetPull * offsetPrior * Eigen::Matrix2d::Identity());
            eq.g.segment<2>(ow) += kCommonOffsetPull * offsetPrior * o;
        }
    }
}

/// The UAV's anchors: each says where its UGV's pose puts an absolutely known point, so each is a term on that UGV's
/// heading bias and its window's offset alone (no object unknown). Its noise: the measurement's, and the anchor's
/// error scaled by the anchors that share it (they count once together). An anchor outside its gate under the
/// estimate of the moment (the gate of UavAnchors::resolve) is left out: it was made while its UGV's pose was
/// known worse, and it is not the object it then seemed.
void addAnchorTerms(const UavAnchors& anchors, const UgvPoseErrors& poses, const Layout& l,
                    const PoseCorrectedConfig& config, NormalEquations& eq)
{
    for (const UavAnchors::Anchor& a : anchors.anchors()) {
        const auto u = static_cast<std::size_t>(a.ugv);
        const int w = poses.window(a.sample.t);
        Eigen::Vector2d dPos;
        double dHeading = 0.0;
        if (l.ugvBase[u] < 0 || w < l.firstWindow[u] || w > l.lastWindow[u] ||
            poses.explicitCorrection(a.ugv, a.sample.t, dPos, dHeading)) {
            continue; // its offset is not solved here, or the map builder's correction fixes the pose
        }
        Eigen::Vector2d p;
        Eigen::Matrix2d measurementCov;
        Eigen::Vector2d ray;
        poses.project(a.ugv, a.sample, p, nullptr, &measurementCov, &ray);
        const Eigen::Vector2d r = p - a.position;
        const Eigen::Matrix2d own = a.sharedVariance * Eigen::Matrix2d::Identity();
        if (mahalanobis2(r, measurementCov + poses.priorPoseCovariance(a.sample, ray) + own) >= config.gateChi2) {
            continue;
        }
        const Eigen::Matrix2d weight = (measurementCov + a.shares * own).inverse();
        const Eigen::Vector2d jh = a.sample.rangeM * acrossOf(ray); // d p / d heading
        const int th = l.ugvBase[u];
        const int ow = th + 1 + 2 * (w - l.firstWindow[u]);
        const Eigen::Vector2d wj = weight * jh;
        const Eigen::Matrix<double, 1, 1> jj(jh.dot(wj));
        addBlock(eq.h, th, th, jj);
        addBlock(eq.h, th, ow, wj.transpose());
        addBlock(eq.h, ow, th, wj);
        addBlock(eq.h, ow, ow, weight);
        eq.g(th) += wj.dot(r);
        eq.g.segment<2>(ow) += weight * r;
    }
}

void applyStep(const Eigen::VectorXd& delta, const Layout& l, StaticMap& map, UgvPoseErrors& poses)
{
    for (std::size_t u = 0; u < poses.size(); ++u) {
        if (l.ugvBase[u] < 0) {
            continue;
        }
        UgvPoseErrors::Ugv& ugv = poses.ugv(u);
        ugv.headingBias += delta(l.ugvBase[u]);
        for (int w = l.firstWindow[u]; w <= l.lastWindow[u]; ++w) {
            ugv.offsets[static_cast<std::size_t>(w)] += delta.segment<2>(l.ugvBase[u] + 1 + 2 * (w - l.firstWindow[u]));
        }
        ugv.solved = true;
    }
    for (std::size_t j = 0; j < map.objects().size(); ++j) {
        if (l.objectBase[j] >= 0) {
            map.objects()[j].mean += delta.segment<2>(l.objectBase[j]);
        }
    }
}

/// How far this solve moved each solved UGV's heading bias and latest offset (UgvPoseErrors::Ugv::headingStep).
void recordSteps(const std::vector<UgvPoseErrors::Ugv>& before, const Layout& l, UgvPoseErrors& poses)
{
    for (std::size_t u = 0; u < poses.size(); ++u) {
        if (l.ugvBase[u] < 0) {
            continue;
        }
        UgvPoseErrors::Ugv& ugv = poses.ugv(u);
        const auto last = static_cast<std::size_t>(l.lastWindow[u]);
        const std::vector<Eigen::Vector2d>& old = before[u].offsets;
        const Eigen::Vector2d was = old.empty() ? Eigen::Vector2d::Zero() : old[std::min(last, old.size() - 1)];
        ugv.headingStep = std::abs(ugv.headingBias - before[u].headingBias);
        ugv.offsetStepM = (ugv.offsets[last] - was).norm();
    }
}

/// 1.4826 x the median of `v` (absolute residuals over their sigma), within [1, kMaxNoiseScale]; 1 with too few.
double robustScale(std::vector<double>& v)
{
    if (v.size() < static_cast<std::size_t>(kMinNoiseSamples)) {
        return 1.0;
    }
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return std::clamp(kMadToSigma * *mid, 1.0, kMaxNoiseScale);
}

/// The UGVs (indices) whose tracks make up `so`.
std::vector<int> ugvsOf(const StaticMap& map, const StaticMap::StaticObject& so)
{
    std::vector<int> ugvs;
    for (const int ti : so.tracks) {
        const int u = map.tracks()[static_cast<std::size_t>(ti)].ugv;
        if (std::find(ugvs.begin(), ugvs.end(), u) == ugvs.end()) {
            ugvs.push_back(u);
        }
    }
    return ugvs;
}

/// The standard normal quantile with upper tail `alpha` (bisection on erfc).
double normalQuantileUpper(double alpha)
{
    double lo = 0.0;
    double hi = kMaxNormalQuantile;
    for (int i = 0; i < kQuantileBisections; ++i) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(mid / kSqrt2) > alpha ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

/// The chi-square quantile of `dof` degrees of freedom with upper tail `alpha` (Wilson-Hilferty).
double chiSquareQuantileUpper(double alpha, int dof)
{
    const double k = dof;
    const double a = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - a + normalQuantileUpper(alpha) * std::sqrt(a), 3);
}

/// If the evidence cannot show a pose error, nothing moves: after a solve, the fleet's estimated pose errors theta
/// (every solved UGV's heading bias and the offsets of its windows solved, measured from zero: no error) are tested
/// jointly against their posterior covariance, the objects marginalised out. Its inverse is the Schur complement
/// of the objects' blocks in the normal matrix (the terms `h`, with SampleWeights::Test), and the objects' blocks
/// are 2 x 2 and uncoupled, so the statistical distance is theta' (H_pp - sum_j H_pj H_jj^-1 H_jp) theta: no
/// inverse and no factorisation. Jointly, because only part of the errors is observable without the UAV's anchors (the
/// UGVs' errors relative to each other): one UGV's estimate alone may be within its prior's reach of zero while the
/// difference to another's is certain. Where the distance stays below the chi-square quantile of as many degrees
/// of freedom at the gates' significance (gateChi2 of 2 degrees: exp(-gateChi2 / 2)), zero explains the data as
/// well as the estimate does: every estimate is set to zero and the observations project as reported, as in mode
/// original (without this, noise and the UAV's anchors moved the objects of UGVs with no pose error by up to 0.3 m,
/// and every object by a common 0.2 m).
void keepOnlyShownErrors(const Triplets& h, const Layout& l, const PoseCorrectedConfig& config, UgvPoseErrors& poses)
{
    Eigen::VectorXd theta = Eigen::VectorXd::Zero(l.n); // zero at the objects
    int count = 0;                                      // the UGVs' unknowns come first: [0, count)
    for (std::size_t u = 0; u < poses.size(); ++u) {
        if (l.ugvBase[u] < 0) {
            continue;
        }
        const UgvPoseErrors::Ugv& ugv = poses.ugv(u);
        theta(l.ugvBase[u]) = ugv.headingBias;
        for (int w = l.firstWindow[u]; w <= l.lastWindow[u]; ++w) {
            theta.segment<2>(l.ugvBase[u] + 1 + 2 * (w - l.firstWindow[u])) = ugv.offsets[static_cast<std::size_t>(w)];
        }
        count += 1 + 2 * (l.lastWindow[u] - l.firstWindow[u] + 1); // heading bias, offsets
    }
    if (count == 0) {
        return;
    }
    // Straight from the terms (duplicates sum): H theta (at the objects' rows: H_jp theta) and the objects' blocks.
    Eigen::VectorXd ht = Eigen::VectorXd::Zero(l.n);
    std::vector<Eigen::Matrix2d> hjj(static_cast<std::size_t>((l.n - count) / 2), Eigen::Matrix2d::Zero());
    for (const Eigen::Triplet<double>& t : h) {
        ht(t.row()) += t.value() * theta(t.col());
        if (t.row() >= count && t.col() >= count && (t.row() - count) / 2 == (t.col() - count) / 2) {
            hjj[static_cast<std::size_t>((t.row() - count) / 2)]((t.row() - count) % 2, (t.col() - count) % 2) +=
                t.value();
        }
    }
    double distance = theta.dot(ht); // theta' H_pp theta
    for (std::size_t j = 0; j < hjj.size(); ++j) {
        if (hjj[j].determinant() <= 0.0) {
            return; // an object the data does not place: no test, the estimates stay as solved
        }
        const Eigen::Vector2d v = ht.segment<2>(count + 2 * static_cast<int>(j));
        distance -= v.dot(hjj[j].inverse() * v);
    }
    const double alpha = std::exp(-config.gateChi2 / 2.0);
    if (distance >= chiSquareQuantileUpper(alpha, count)) {
        return;
    }
    for (std::size_t u = 0; u < poses.size(); ++u) {
        if (l.ugvBase[u] < 0) {
            continue;
        }
        UgvPoseErrors::Ugv& ugv = poses.ugv(u);
        ugv.headingBias = 0.0;
        for (int w = l.firstWindow[u]; w <= l.lastWindow[u]; ++w) {
            ugv.offsets[static_cast<std::size_t>(w)].setZero();
        }
    }
}

/// Two compressed sparse matrices of one size with the same non-zero pattern.
bool samePattern(const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b)
{
    return a.rows() == b.rows() && a.cols() == b.cols() && a.nonZeros() == b.nonZeros() &&
           std::equal(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1, b.outerIndexPtr()) &&
           std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), b.innerIndexPtr());
}

} // namespace

PoseErrorSolver::PoseErrorSolver(const PoseCorrectedConfig& config) : config_(config) {}

bool PoseErrorSolver::estimate(StaticMap& map, UgvPoseErrors& poses, const UavAnchors& anchors) const
{
    const Layout l = layoutOf(map, poses, config_);
    if (l.n == 0) {
        return false;
    }
    extendOffsets(poses, l);
    std::vector<UgvPoseErrors::Ugv> before;
    for (std::size_t u = 0; u < poses.size(); ++u) {
        before.push_back(poses.ugv(u));
    }
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
    Eigen::SparseMatrix<double> analysed; // the pattern of ldlt's ordering
    // The terms of the normal equations at the estimate of the moment.
    const auto normalEquations = [&](SampleWeights weights) {
        NormalEquations eq{{}, Eigen::VectorXd::Zero(l.n)};
        addObservationTerms(map, poses, l, config_, weights, eq);
        addPoseTerms(poses, l, config_, eq);
        addAnchorTerms(anchors, poses, l, config_, eq);
        return eq;
    };
    for (int iteration = 0; iteration < config_.solveIterations; ++iteration) {
        const NormalEquations eq = normalEquations(SampleWeights::Solve);
        Eigen::SparseMatrix<double> hm(l.n, l.n);
        hm.setFromTriplets(eq.h.begin(), eq.h.end());
        hm.makeCompressed();
        // The fill-reducing ordering depends on the pattern alone: computed again only when that changes.
        if (!samePattern(hm, analysed)) {
            ldlt.analyzePattern(hm);
            analysed = hm;
        }
        ldlt.factorize(hm);
        if (ldlt.info() != Eigen::Success) {
            return false;
        }
        applyStep(ldlt.solve(-eq.g), l, map, poses);
    }
    keepOnlyShownErrors(normalEquations(SampleWeights::Test).h, l, config_, poses);
    recordSteps(before, l, poses);
    return true;
}

void PoseErrorSolver::learnNoise(const StaticMap& map, UgvPoseErrors& poses) const
{
    const RangeBearingNoise noise = config_.noise();
    std::vector<std::vector<double>> rangeResiduals(poses.size());
    std::vector<std::vector<double>> crossResiduals(poses.size());
    for (const StaticMap::StaticObject& so : map.objects()) {
        if (!so.alive || so.observations < static_cast<std::uint64_t>(kMinNoiseObjectObservations)) {
            continue;
        }
        for (const int ti : so.tracks) {
            const StaticMap::Track& track = map.tracks()[static_cast<std::size_t>(ti)];
            const auto u = static_cast<std::size_t>(track.ugv);
            for (const StaticMap::TrackWindow& tw : track.windows) {
                for (const RangeBearing& smp : tw.samples) {
                    Eigen::Vector2d p;
                    poses.project(track.ugv, smp, p, nullptr);
                    const Eigen::Vector2d d = p - so.mean;
                    const Eigen::Vector2d ray = (p - smp.ugvPos).normalized();
                    rangeResiduals[u].push_back(std::abs(d.dot(ray)) / noise.alongSigma(smp.rangeM));
                    crossResiduals[u].push_back(std::abs(d.dot(acrossOf(ray))) / noise.acrossSigma(smp.rangeM));
                }
            }
        }
    }
    for (std::size_t u = 0; u < poses.size(); ++u) {
        poses.ugv(u).rangeScale = robustScale(rangeResiduals[u]);
        poses.ugv(u).bearingScale = robustScale(crossResiduals[u]);
    }
}

void PoseErrorSolver::learnPoseSpread(const StaticMap& map, UgvPoseErrors& poses) const
{
    std::vector<std::vector<double>> distances(poses.size());
    for (const StaticMap::StaticObject& so : map.objects()) {
        if (!so.alive || so.observations < static_cast<std::uint64_t>(kMinNoiseObjectObservations) ||
            ugvsOf(map, so).size() < 2) {
            continue;
        }
        for (const int ti : so.tracks) {
            double weight = 0.0;
            const Eigen::Vector2d mean = map.trackMean(ti, poses, weight);
            if (weight > 0.0) {
                distances[static_cast<std::size_t>(map.tracks()[static_cast<std::size_t>(ti)].ugv)].push_back(
                    (mean - so.mean).norm());
            }
        }
    }
    for (std::size_t u = 0; u < poses.size(); ++u) {
        std::vector<double>& d = distances[u];
        if (d.size() < static_cast<std::size_t>(kMinSpreadTracks) || !poses.ugv(u).solved) {
            continue;
        }
        const auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
        std::nth_element(d.begin(), mid, d.end());
        poses.ugv(u).poseSpreadM = std::min(kMaxPoseSpreadM, kMedianToSigma2d * *mid);
    }
}

} // namespace ugv::correlator
