#pragma once

/// @file
/// The per-frame stereo obstacle pipeline on the rectified ROI:
/// RoiMatcher (census SGM or StereoSGBM on the ROI) -> GroundEstimator (per-frame ground from that disparity, falling
/// back to the configured plane) -> warpGround + GroundMismatch (edge pixels where the left image warped through the
/// ground plane disagrees with the right one, with the sign of the residual disparity) -> ObstacleVerifier (every
/// off-ground disparity must explain the images better than the ground does, else it is invalidated) ->
/// SectorBuilder (dense disparity cue, confirmed and weighted by the mismatch labels) -> sectors.
///
/// The mismatch stage labels pixels of the right image; they are moved to the left image's grid (where the
/// disparity lives) through the warp's row map plus the residual disparity.
///
/// Bad input never crashes and never yields a false Clear: wrong-size frames give all sectors Unknown with
/// `degraded` set and status() == WrongInputSize; all-black, saturated and textureless frames give no valid
/// disparity and therefore Unknown sectors (SectorBuilder needs ground support for Clear).

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/obstacle_sectors.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/ground_estimator.hpp"
#include "ugv/vision/ground_mismatch.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/ground_warp.hpp"
#include "ugv/vision/obstacle_verifier.hpp"
#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/roi_matcher.hpp"
#include "ugv/vision/sector_builder.hpp"
#include "ugv/vision/stage_times.hpp"

namespace ugv::vision {

struct DetectorConfig {
    RoiMatcherConfig matcher;
    SectorBuilderConfig sectors;
    /// Projection, mount and ROI geometry are filled in by create(). No temporal smoothing by default: the
    /// sectors of a frame use the ground of that frame (a lagging ground turns a pitch step into obstacles).
    GroundEstimatorConfig ground = [] {
        GroundEstimatorConfig c;
        c.smoothing = 1.0;
        return c;
    }();
    GroundMismatchConfig mismatch;   ///< width and height are filled in by create()
    ObstacleVerifierConfig verifier; ///< width and height are filled in by create()
    /// Rows at the top of the ROI that only give the matcher's block context and are not analysed [px]
    /// (RectifierConfig::roiMarginRows).
    int marginRows = 8;
    /// Votes a cluster needs on the ground-only (overload) path, whose votes are edge pixels only (a box's
    /// uniform faces give none; the dense path's minSupport would miss it).
    int groundOnlyMinSupport = 12;
    /// The verifier re-matches below-ground pixels only where the ground is at least this far [m]: its
    /// refineMaxGroundPx is set from the rig, fx B / this (the default rig: 55 px).
    double refineMinRangeM = 3.0;
    /// The near rows matched at half resolution (RoiMatcherConfig::halfResolutionRows): create() sets them to the
    /// ROI rows from the first one on which the configured ground's disparity is at least this everywhere [px],
    /// an even count, none when fewer than 16 rows qualify. 0: every row at full resolution.
    double halfResolutionMinGroundPx = 0.0;
};

/// Outcome of the last ObstacleDetector::process(); no strings on the frame path.
enum class DetectorStatus : std::uint8_t {
    Ok,
    WrongInputSize, ///< a frame is empty or not the ROI size: all Unknown, degraded
    MatcherFailed,  ///< the matcher failed (OpenCV threw, or census SGM refused its buffers): all Unknown, degraded
    BuildFailed,    ///< the sector builder rejected its inputs (a bug): all Unknown, degraded
};

/// The rectifier configuration for a detector of `config`: the ROI from `roiTopFraction` of the image height down
/// (config roi.top_fraction), with the detector's margin rows above it (its matcher's block context).
[[nodiscard]] inline RectifierConfig
roiRectifierConfig(const DetectorConfig& config, double roiTopFraction = RectifierConfig{}.roiTopFraction) noexcept
{
    RectifierConfig rectifier;
    rectifier.roiTopFraction = roiTopFraction;
    rectifier.roiMarginRows = config.marginRows;
    return rectifier;
}

/// Thread-safety: thread-bound (process() writes the internal buffers). RT-safe: process() no allocation and no
/// exception with the census SGM; with an OpenCV matcher mode StereoSGBM::compute() allocates internally (see
/// roi_matcher.hpp); create() no.
class ObstacleDetector {
public:
    /// @param[in] projection       rectified projection (full-frame coordinates)
    /// @param[in] roi              full-frame rectangle of the rectified ROI images (Rectifier::roi())
    /// @param[in] configuredGround ground plane of the configured mount
    /// @return the detector, or an error from one of the stages' configs.
    static Result<ObstacleDetector, Error> create(const DetectorConfig& config, const RectifiedProjection& projection,
                                                  Rect roi, const GroundPlane& configuredGround);

    /// The detector over `rectifier`'s ROI and projection: made with roiRectifierConfig(config, ...), the two agree
    /// on the ROI and its margin rows.
    static Result<ObstacleDetector, Error> create(const DetectorConfig& config, const Rectifier& rectifier,
                                                  const GroundPlane& configuredGround)
    {
        return create(config, rectifier.projection(), rectifier.roi(), configuredGround);
    }

    /// Runs the pipeline on one rectified ROI pair.
    /// @param[in] rectLeftRoi, rectRightRoi  roi.width x roi.height each
    /// @param[in] sequence, stampNs          carried into the sectors
    /// @return the sectors of this frame (valid until the next call); see status().
    const ObstacleSectors& process(ConstImageViewU8 rectLeftRoi, ConstImageViewU8 rectRightRoi, std::uint64_t sequence,
                                   std::int64_t stampNs) noexcept;

    /// The overload path (no dense matching, about a tenth of process()'s time): on the configured ground, the
    /// ground-mismatch stage's positive and negative edge pixels, at the ground disparity plus their residual,
    /// become a sparse disparity map for the sector builder. No pixel gives ground support, so no sector can be
    /// Clear: each is Obstacle or Unknown, and the sectors are flagged degraded.
    const ObstacleSectors& processGroundOnly(ConstImageViewU8 rectLeftRoi, ConstImageViewU8 rectRightRoi,
                                             std::uint64_t sequence, std::int64_t stampNs) noexcept;

    [[nodiscard]] DetectorStatus status() const noexcept { return status_; }
    /// The sectors of the last process() or processGroundOnly().
    [[nodiscard]] const ObstacleSectors& sectors() const noexcept
    {
        return lastGroundOnly_ ? groundOnlyBuilder_->sectors() : builder_.sectors();
    }
    /// Intermediate buffers of the last frame, read-only (tools, overlays).
    [[nodiscard]] const cv::Mat& disparity16() const noexcept { return matcher_.disparity16(); }
    /// Cost cells the last frame's matcher searched over those of the full range (RoiMatcherConfig::groundRange).
    [[nodiscard]] double searchedFraction() const noexcept { return matcher_.searchedFraction(); }
    /// The disparity the sectors were built from: the matcher's, less the pixels the verifier rejected.
    [[nodiscard]] const ObstacleVerifier& verifier() const noexcept { return verifier_; }
    /// Obstacle labels (GroundLabel values) of the ground-mismatch stage on the left image's ROI grid.
    [[nodiscard]] ConstImageViewU8 labels() const noexcept { return leftLabels_.view(); }
    /// The ground-mismatch stage's own labels, on the right image's grid.
    [[nodiscard]] const GroundMismatch& mismatch() const noexcept { return mismatch_; }
    /// The last ground estimate (reliable, or the configured plane with the reason).
    [[nodiscard]] const GroundEstimate& groundEstimate() const noexcept { return estimator_.estimate(); }
    /// The ground plane the last frame's sectors used.
    [[nodiscard]] const GroundPlane& ground() const noexcept { return ground_; }
    [[nodiscard]] Rect roi() const noexcept { return roi_; }
    /// The last frame's disparity noise on the ground [px] (SectorBuilder::groundNoisePx()).
    [[nodiscard]] float groundNoisePx() const noexcept { return builder_.groundNoisePx(); }
    /// The sector builder's config as used (maxRangeM resolved from the rig).
    [[nodiscard]] const SectorBuilderConfig& sectorConfig() const noexcept { return builder_.config(); }
    /// Times each stage of process() and processGroundOnly() with `clock` (MonotonicClock::nowNs); nullptr (the
    /// default) times nothing. Vision reads no clock of its own.
    void setStageClock(StageClock clock) noexcept { times_.clock = clock; }
    /// The time of each stage of the last frame (all 0 without a clock; the ground-only path: warp, mismatch,
    /// sectors).
    [[nodiscard]] const VisionStageTimes& stageTimes() const noexcept { return times_; }

private:
    ObstacleDetector(RoiMatcher matcher, SectorBuilder builder, GroundEstimator estimator, GroundMismatch mismatch,
                     ObstacleVerifier verifier, Rect roi) noexcept
        : matcher_(std::move(matcher)), builder_(std::move(builder)), estimator_(std::move(estimator)),
          mismatch_(std::move(mismatch)), verifier_(std::move(verifier)), warped_(roi.width, roi.height),
          spans_(static_cast<std::size_t>(roi.height)), leftLabels_(roi.width, roi.height),
          sparse_(roi.width, roi.height)
    {
    }
    /// Moves the mismatch labels from the right grid to the left grid (leftLabels_); with `withDisparity` also
    /// their disparity d_g + residual into sparse_ (the ground-only path).
    void labelsToLeftGrid(const DisparityPlane& plane, bool withDisparity) noexcept;

    RoiMatcher matcher_;
    SectorBuilder builder_;
    std::optional<SectorBuilder> groundOnlyBuilder_; ///< processGroundOnly(): minSupport = groundOnlyMinSupport
    bool lastGroundOnly_ = false;
    VisionStageTimes times_;
    GroundEstimator estimator_;
    GroundMismatch mismatch_;
    ObstacleVerifier verifier_;
    Image<std::uint8_t> warped_;
    std::vector<WarpSpan> spans_;
    Image<std::uint8_t> leftLabels_;
    Image<std::int16_t> sparse_; ///< processGroundOnly(): labelled edge pixels' disparity (x16), else invalid
    RectifiedProjection projection_;
    GroundPlane configuredGround_;
    GroundPlane ground_;
    Rect roi_;
    DetectorStatus status_ = DetectorStatus::Ok;
};

} // namespace ugv::vision
