#pragma once

/// @file
/// Per-frame ground estimate from a measured disparity image over the ROI.
///
/// Each update(): (1) candidates = every valid disparity on a sparse grid of the ROI; (2) hypotheses for
/// d = a x + b y + c: the last reliable estimate, the configured plane and RANSAC planes through three candidates
/// (fixed iteration count and seed: same input, same output); a hypothesis counts only when its plane is a
/// plausible ground, inside the band around the configured mount (height within heightBandFraction, pitch and roll
/// within their bands), so that a car's back, a wall or a kerb's face can never win however many pixels it has;
/// the one with the most inliers wins; (3) least-squares refinement on the inliers (closed form, centred
/// coordinates), twice; (4) GroundPlane::fromDisparityPlane, checked against the band again; (5) exponential
/// smoothing of the plane coefficients. When there are too few candidates or inliers, the fit is degenerate or
/// leaves the band, the estimate falls back to the configured plane with reliable == false and the reason, and
/// the smoothing restarts from the configured plane.
///
/// No candidate is chosen by its distance to the configured plane, so a mount that is off by the band (the default
/// admits +-14 deg pitch, +-8 deg roll and +-45 % height: a mount off by 10 deg, 5 deg or 30 % plus the road's own
/// grade and camber) is still found, and a pitching vehicle is followed from
/// frame to frame (the last estimate is always a hypothesis).
///
/// Disparity input: CV_16S fixed point as cv::StereoSGBM outputs (value / 16 = disparity [px]), invalid < 0.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::vision {

struct GroundEstimatorConfig {
    RectifiedProjection projection; ///< full-frame rectified projection
    Mount mount;                    ///< configured mount: the prior, the band centre and the fallback
    int width = 640;                ///< ROI width [px]
    int height = 248;               ///< ROI height [px]
    int y0 = 232;                   ///< full-frame row of ROI row 0 [px]
    int sampleStep = 4;             ///< candidate grid step [px]
    double inlierTolerancePx = 1.0; ///< RANSAC / refinement inlier distance [px]
    int ransacIterations = 64;
    std::uint64_t seed = 0x9E3779B97F4A7C15ULL; ///< RANSAC sampling seed (re-applied every update)
    int minInliers = 300;                       ///< absolute minimum of inliers
    double minInlierFraction = 0.15;            ///< minimum inliers / candidates (candidates include obstacles)
    double heightBandFraction = 0.60;           ///< allowed |height - configured| / configured (30 % low: +43 %)
    double pitchBandDeg = 14.0;                 ///< [deg] allowed |pitch - configured|
    double rollBandDeg = 8.0;                   ///< [deg] allowed |roll - configured|
    double smoothing = 0.5;                     ///< weight of the new measurement, (0, 1]; 1 = no smoothing
};

enum class GroundFallbackReason : std::uint8_t {
    None = 0,         ///< reliable estimate
    WrongInput,       ///< disparity view is not width x height
    TooFewCandidates, ///< fewer than minInliers valid disparities
    TooFewInliers,    ///< best plane has too few inliers (absolute or fraction)
    DegenerateFit,    ///< no non-degenerate sample or singular refinement
    OutOfBand,        ///< fitted plane outside the band around the configured mount
};

struct GroundEstimate {
    GroundPlane plane;        ///< the plane to use (smoothed estimate, or the configured one on fallback)
    DisparityPlane disparity; ///< plane.disparityPlane(projection), full-frame [px]
    bool reliable = false;    ///< false: configured fallback
    GroundFallbackReason reason = GroundFallbackReason::None;
    int candidates = 0;      ///< candidates this frame
    int inliers = 0;         ///< inliers of the refined fit this frame
    DisparityPlane measured; ///< this frame's refined fit (valid when reason is None or OutOfBand)
};

/// Thread-safety: thread-bound (update() mutates state). RT-safe: update() yes (no allocation); create() no.
class GroundEstimator {
public:
    /// Validates the config and allocates the candidate buffer.
    static Result<GroundEstimator, Error> create(const GroundEstimatorConfig& config);

    /// Fits the ground to one frame's disparity and updates the smoothed estimate.
    /// @param[in] disparity  CV_16S ROI disparity (x16, invalid < 0), width x height
    /// @return the new estimate (also available through estimate()).
    const GroundEstimate& update(ImageView<const std::int16_t> disparity) noexcept;

    [[nodiscard]] const GroundEstimate& estimate() const noexcept { return estimate_; }
    /// The configured plane (the fallback).
    [[nodiscard]] const GroundPlane& configuredPlane() const noexcept { return configured_; }
    /// Forgets the smoothing history (restart from the configured plane).
    void reset() noexcept;

private:
    struct Candidate {
        float x; ///< full-frame column [px]
        float y; ///< full-frame row [px]
        float d; ///< disparity [px]
    };

    explicit GroundEstimator(const GroundEstimatorConfig& config);
    void fallback(GroundFallbackReason reason) noexcept;
    int collectCandidates(ImageView<const std::int16_t> disparity) noexcept;
    bool ransac(int count, DisparityPlane& best) noexcept;
    /// The plane is a plausible ground: finite and inside the band around the configured mount.
    [[nodiscard]] bool inBand(const DisparityPlane& plane) const noexcept;
    [[nodiscard]] int countInliers(int count, const DisparityPlane& plane) const noexcept;
    bool refine(int count, DisparityPlane& plane, int& inliers) const noexcept;
    /// Calls f(candidate) for each of the first `count` candidates within inlierTolerancePx of `plane`, in order.
    template <typename F>
    void forEachInlier(int count, const DisparityPlane& plane, F&& f) const noexcept
    {
        for (int i = 0; i < count; ++i) {
            const Candidate& c = candidates_[static_cast<std::size_t>(i)];
            if (std::abs(plane.at(c.x, c.y) - c.d) < config_.inlierTolerancePx) {
                f(c);
            }
        }
    }

    GroundEstimatorConfig config_;
    GroundPlane configured_;
    DisparityPlane configuredDisparity_;
    DisparityPlane state_;
    GroundEstimate estimate_;
    std::vector<Candidate> candidates_; ///< sized at create(), never resized
};

} // namespace ugv::vision
