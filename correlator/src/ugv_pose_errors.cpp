#include "ugv/correlator/ugv_pose_errors.hpp"

#include <algorithm>
#include <cmath>

namespace ugv::correlator {
namespace {

constexpr double kSolvedHeadingSigmaDeg = 0.5; ///< remaining pose uncertainty once a UGV's errors are estimated
constexpr double kSolvedOffsetSigmaM = 0.3;

} // namespace

UgvPoseErrors::UgvPoseErrors(const PoseCorrectedConfig& config) : config_(config) {}

int UgvPoseErrors::index(const std::string& name)
{
    auto [it, inserted] = index_.try_emplace(name, static_cast<int>(ugvs_.size()));
    if (inserted) {
        ugvs_.push_back(Ugv{});
        ugvs_.back().name = name;
    }
    return it->second;
}

std::optional<int> UgvPoseErrors::find(const std::string& name) const
{
    const auto it = index_.find(name);
    if (it == index_.end()) {
        return std::nullopt;
    }
    return it->second;
}

void UgvPoseErrors::addCorrection(const PoseCorrection& correction)
{
    ugvs_[static_cast<std::size_t>(index(correction.ugv))].corrections.push_back(correction);
}

int UgvPoseErrors::window(double t) const
{
    return static_cast<int>(std::floor(t / config_.offsetWindowS));
}

Eigen::Vector2d UgvPoseErrors::offsetAt(int ugv, double t) const
{
    const auto& offsets = ugvs_[static_cast<std::size_t>(ugv)].offsets;
    if (offsets.empty()) {
        return Eigen::Vector2d::Zero();
    }
    const int w = std::clamp(window(t), 0, static_cast<int>(offsets.size()) - 1);
    return offsets[static_cast<std::size_t>(w)];
}

bool UgvPoseErrors::explicitCorrection(int ugv, double t, Eigen::Vector2d& dPos, double& dHeading) const
{
    dPos.setZero();
    dHeading = 0.0;
    bool covered = false;
    for (const PoseCorrection& c : ugvs_[static_cast<std::size_t>(ugv)].corrections) {
        if (t >= c.sinceT && t <= c.untilT) {
            dPos = Eigen::Vector2d(c.dEastM, c.dNorthM);
            dHeading = c.dHeadingDeg * kRadPerDeg;
            covered = true;
        }
    }
    return covered;
}

double UgvPoseErrors::priorHeadingSigma() const
{
    return config_.headingBiasSigmaDeg * kRadPerDeg;
}

/// Once estimated (or corrected), the pose error left: what was measured (how far the last solve still moved the
/// estimate, the spread about other UGVs' objects), never below the model's floor nor above the prior.
UgvPoseErrors::PoseSigmas UgvPoseErrors::remainingSigmas(const Ugv& u, bool corrected) const
{
    if (corrected) {
        return {kSolvedHeadingSigmaDeg * kRadPerDeg, kSolvedOffsetSigmaM};
    }
    const double heading = std::clamp(u.headingStep, kSolvedHeadingSigmaDeg * kRadPerDeg, priorHeadingSigma());
    const double offset = std::clamp(std::max(u.poseSpreadM, u.offsetStepM), kSolvedOffsetSigmaM,
                                     std::max(kSolvedOffsetSigmaM, config_.offsetSigmaM));
    return {heading, offset};
}

Eigen::Matrix2d UgvPoseErrors::priorPoseCovariance(const RangeBearing& s, const Eigen::Vector2d& ray) const
{
    const Eigen::Vector2d across = acrossOf(ray);
    return std::pow(s.rangeM * priorHeadingSigma(), 2) * across * across.transpose() +
           config_.offsetSigmaM * config_.offsetSigmaM * Eigen::Matrix2d::Identity();
}

void UgvPoseErrors::project(int ugv, const RangeBearing& s, Eigen::Vector2d& p, Eigen::Matrix2d* cov,
                            Eigen::Matrix2d* measurementCov, Eigen::Vector2d* ray) const
{
    const Ugv& u = ugvs_[static_cast<std::size_t>(ugv)];
    Eigen::Vector2d dPos;
    double dHeading = 0.0;
    // The map builder's correction is authoritative where it exists; the estimated errors cover the rest.
    const bool corrected = explicitCorrection(ugv, s.t, dPos, dHeading);
    const double az = s.headingRad + dHeading + (corrected ? 0.0 : u.headingBias) + s.bearingRad;
    const Eigen::Vector2d along = rayAt(az);
    p = s.ugvPos + dPos + (corrected ? Eigen::Vector2d::Zero() : offsetAt(ugv, s.t)) + s.rangeM * along;
    if (ray != nullptr) {
        *ray = along;
    }
    if (cov == nullptr && measurementCov == nullptr) {
        return;
    }
    const Eigen::Vector2d across = acrossOf(along);
    const RangeBearingNoise noise = config_.noise();
    const double sr = noise.alongSigma(s.rangeM, u.rangeScale);
    // The measurement noise plus a pose uncertainty of headingSigma [rad] and offset [m] per axis.
    const auto covariance = [&](double headingSigma, double offset) {
        const double sc2 =
            std::pow(noise.acrossSigma(s.rangeM, u.bearingScale), 2) + std::pow(s.rangeM * headingSigma, 2);
        return Eigen::Matrix2d(sr * sr * along * along.transpose() + sc2 * across * across.transpose() +
                               offset * offset * Eigen::Matrix2d::Identity());
    };
    if (cov != nullptr) {
        const bool knownPose = u.solved || corrected;
        const PoseSigmas sigmas =
            knownPose ? remainingSigmas(u, corrected) : PoseSigmas{priorHeadingSigma(), config_.offsetSigmaM};
        *cov = covariance(sigmas.heading, sigmas.offsetM);
    }
    if (measurementCov != nullptr) {
        *measurementCov = covariance(0.0, 0.0);
    }
}

} // namespace ugv::correlator
