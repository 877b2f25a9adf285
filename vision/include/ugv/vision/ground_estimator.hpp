#pragma once

/// @file
/// Per-frame ground estimate from a measured disparity image over the ROI.
///
/// Each update(): (1) candidates = valid disparities on a sparse grid within candidateTolerancePx of the
/// CONFIGURED model d_g (so that obstacles and garbage far from any plausible ground never seed the fit);
/// (2) RANSAC for d = a x + b y + c with a fixed iteration count and a fixed seed (same input, same output);
/// (3) least-squares refinement on the inliers (closed form, centred coordinates), twice;
/// (4) GroundPlane::fromDisparityPlane, checked against a band around the configured mount (height, pitch,
/// roll); (5) exponential smoothing of the plane coefficients. When there are too few candidates or inliers,
/// the fit is degenerate or leaves the band, the estimate falls back to the configured plane with
/// reliable == false and the reason, and the smoothing restarts from the configured plane.
///
/// The candidate tolerance bounds the pitch step that can be tracked: a pitch change of dp moves the ground's
/// disparity by about (B/h) f dp (4.9 px/deg for the default rig), so the default 20 px admits ~4 deg.
///
/// Disparity input: CV_16S fixed point as cv::StereoSGBM outputs (value / 16 = disparity [px]), invalid < 0.

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
    RectifiedProjection projection;     ///< full-frame rectified projection
    Mount mount;                        ///< configured mount: the prior, the band centre and the fallback
    int width = 640;                    ///< ROI width [px]
    int height = 248;                   ///< ROI height [px]
    int y0 = 232;                       ///< full-frame row of ROI row 0 [px]
    int sampleStep = 4;                 ///< candidate grid step [px]
    double candidateTolerancePx = 20.0; ///< |d - d_g(config)| below this makes a candidate [px]
    double inlierTolerancePx = 1.0;     ///< RANSAC / refinement inlier distance [px]
    int ransacIterations = 64;
    std::uint64_t seed = 0x9E3779B97F4A7C15ULL; ///< RANSAC sampling seed (re-applied every update)
    int minInliers = 300;                       ///< absolute minimum of inliers
    double minInlierFraction = 0.3;             ///< minimum inliers / candidates
    double heightBandM = 0.15;                  ///< [m] allowed |height - configured|
    double pitchBandDeg = 5.0;                  ///< [deg] allowed |pitch - configured|
    double rollBandDeg = 5.0;                   ///< [deg] allowed |roll - configured|
    double smoothing = 0.5;                     ///< weight of the new measurement, (0, 1]; 1 = no smoothing
};

enum class GroundFallbackReason : std::uint8_t {
    None = 0,         ///< reliable estimate
    WrongInput,       ///< disparity view is not width x height
    TooFewCandidates, ///< fewer than minInliers candidates near the configured ground
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
    bool refine(int count, DisparityPlane& plane, int& inliers) const noexcept;

    GroundEstimatorConfig config_;
    GroundPlane configured_;
    DisparityPlane configuredDisparity_;
    DisparityPlane state_;
    GroundEstimate estimate_;
    std::vector<Candidate> candidates_; ///< sized at create(), never resized
};

} // namespace ugv::vision
