#include "ugv/vision/obstacle_detector.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "ugv/platform/angles.hpp"

namespace ugv::vision {

namespace {

/// The matcher's ground prior (RoiMatcher::setGroundPrior) from a full-frame disparity plane.
void setGroundPrior(RoiMatcher& matcher, const DisparityPlane& p, Rect roi) noexcept
{
    matcher.setGroundPrior(p.a, p.b, p.c + p.a * roi.x + p.b * roi.y);
}

/// The matcher's search floor for the next frame from this frame's ground estimate (RoiMatcherConfig::groundRange
/// explains the geometry): s g - m with s = h / (h + drop) and m the disparity change of a pitch and roll of
/// margin degrees; the full range when the estimate is not reliable.
void setSearchFloor(RoiMatcher& matcher, const GroundEstimate& estimate, const RectifiedProjection& projection,
                    Rect roi) noexcept
{
    const RoiMatcherConfig& config = matcher.config();
    const double h = estimate.plane.heightM; // [m]
    if (!config.groundRange || !estimate.reliable || !(h > 0.0)) {
        matcher.clearSearchFloor();
        return;
    }
    const double scale = h / (h + config.groundRangeDropM);
    // d = (B / h) (v cos(pitch) + f sin(pitch)) + roll term: a pitch change moves a row's ground by about
    // (B / h) f per radian, a roll change by (B / h) |x - cx| with |x - cx| up to half the width.
    const double marginPx = projection.baselineM / h * (projection.fx + 0.5 * roi.width) *
                            std::tan(config.groundRangeMarginDeg * kDegToRad);
    const DisparityPlane& g = estimate.disparity;
    matcher.setSearchFloor(scale * g.a, scale * g.b, scale * (g.c + g.a * roi.x + g.b * roi.y) - marginPx);
}

/// The ROI rows to match at half resolution (DetectorConfig::halfResolutionMinGroundPx): from the first row on which
/// the ground's disparity is at least minGroundPx at both ends of the row down to the ROI's bottom, an even count
/// that leaves the full-resolution part its seam overlap; 0 when fewer than 16 rows qualify or the threshold is 0.
int halfResolutionRows(const DisparityPlane& ground, Rect roi, double minGroundPx) noexcept
{
    if (!(minGroundPx > 0.0)) {
        return 0;
    }
    int first = roi.height;
    while (first > 0) {
        const int y = roi.y + first - 1;
        if (std::min(ground.at(roi.x, y), ground.at(roi.x + roi.width - 1, y)) < minGroundPx) {
            break;
        }
        --first;
    }
    int rows = std::min(roi.height - first, roi.height - 2 * RoiMatcher::kHalfOverlapRows);
    rows -= rows % 2;
    constexpr int kMinRows = 16;
    return rows >= kMinRows ? rows : 0;
}

/// The ROI matcher of `config`, its half-resolution rows from the configured ground.
Result<RoiMatcher, Error> makeMatcher(const DetectorConfig& config, const DisparityPlane& ground, Rect roi)
{
    if (!(config.halfResolutionMinGroundPx >= 0.0)) {
        return Unexpected(
            Error{"ObstacleDetector::create",
                  "halfResolutionMinGroundPx " + std::to_string(config.halfResolutionMinGroundPx) + " is not >= 0",
                  "set stereo.half_resolution_min_ground_px to 0 (off) or a disparity in pixels"});
    }
    RoiMatcherConfig matcherConfig = config.matcher;
    if (config.halfResolutionMinGroundPx > 0.0) {
        matcherConfig.halfResolutionRows = halfResolutionRows(ground, roi, config.halfResolutionMinGroundPx);
    }
    return RoiMatcher::create(matcherConfig, cv::Size(roi.width, roi.height));
}

} // namespace

Result<ObstacleDetector, Error> ObstacleDetector::create(const DetectorConfig& config,
                                                         const RectifiedProjection& projection, Rect roi,
                                                         const GroundPlane& configuredGround)
{
    if (roi.empty() || config.marginRows < 0 || config.marginRows >= roi.height) {
        return Unexpected(
            Error{"ObstacleDetector::create",
                  "ROI is empty or marginRows " + std::to_string(config.marginRows) + " is not below its height",
                  "check roi.matcher_margin_rows"});
    }
    if (!(configuredGround.heightM > 0.0)) {
        return Unexpected(
            Error{"ObstacleDetector::create", "configured ground has no positive camera height", "set mount.height_m"});
    }
    auto matcherResult = makeMatcher(config, configuredGround.disparityPlane(projection), roi);
    if (!matcherResult) {
        return Unexpected(std::move(matcherResult).error());
    }
    auto builderResult = SectorBuilder::create(config.sectors, projection, roi, roi.y + config.marginRows);
    if (!builderResult) {
        return Unexpected(std::move(builderResult).error());
    }
    GroundEstimatorConfig groundConfig = config.ground;
    groundConfig.projection = projection;
    groundConfig.mount = Mount{configuredGround.heightM, configuredGround.pitchDeg(), configuredGround.rollDeg()};
    groundConfig.width = roi.width;
    groundConfig.height = roi.height;
    groundConfig.y0 = roi.y;
    auto estimatorResult = GroundEstimator::create(groundConfig);
    if (!estimatorResult) {
        return Unexpected(std::move(estimatorResult).error());
    }
    GroundMismatchConfig mismatchConfig = config.mismatch;
    mismatchConfig.width = roi.width;
    mismatchConfig.height = roi.height;
    auto mismatchResult = GroundMismatch::create(mismatchConfig);
    if (!mismatchResult) {
        return Unexpected(std::move(mismatchResult).error());
    }
    ObstacleVerifierConfig verifierConfig = config.verifier;
    verifierConfig.width = roi.width;
    verifierConfig.height = roi.height;
    if (config.refineMinRangeM > 0.0) {
        verifierConfig.refineMaxGroundPx =
            static_cast<float>(projection.fx * projection.baselineM / config.refineMinRangeM);
    }
    auto verifierResult = ObstacleVerifier::create(verifierConfig);
    if (!verifierResult) {
        return Unexpected(std::move(verifierResult).error());
    }
    ObstacleDetector sut(std::move(matcherResult).value(), std::move(builderResult).value(),
                         std::move(estimatorResult).value(), std::move(mismatchResult).value(),
                         std::move(verifierResult).value(), roi);
    SectorBuilderConfig groundOnlyConfig = config.sectors;
    groundOnlyConfig.minSupport = config.groundOnlyMinSupport;
    // Its sparse map holds only labelled edge pixels, no ground: nothing to learn the local ground or the noise from.
    groundOnlyConfig.useLocalGround = false;
    groundOnlyConfig.heightNoiseFactor = 0.0F;
    groundOnlyConfig.dropNoiseFactor = 0.0F;
    auto groundOnly = SectorBuilder::create(groundOnlyConfig, projection, roi, roi.y + config.marginRows);
    if (!groundOnly) {
        return Unexpected(std::move(groundOnly).error());
    }
    sut.groundOnlyBuilder_.emplace(std::move(groundOnly).value());
    sut.configuredGround_ = configuredGround;
    sut.projection_ = projection;
    sut.ground_ = configuredGround;
    sut.roi_ = roi;
    setGroundPrior(sut.matcher_, configuredGround.disparityPlane(projection), roi);
    return sut;
}

const ObstacleSectors& ObstacleDetector::process(ConstImageViewU8 rectLeftRoi, ConstImageViewU8 rectRightRoi,
                                                 std::uint64_t sequence, std::int64_t stampNs) noexcept
{
    lastGroundOnly_ = false;
    const auto sizeOk = [this](ConstImageViewU8 v) {
        return v.data() != nullptr && v.width() == roi_.width && v.height() == roi_.height;
    };
    if (!sizeOk(rectLeftRoi) || !sizeOk(rectRightRoi)) {
        status_ = DetectorStatus::WrongInputSize;
        builder_.setAllUnknown(sequence, stampNs);
        return builder_.sectors();
    }
    times_.clear();
    if (matcher_.match(rectLeftRoi, rectRightRoi, &times_) != MatchStatus::Ok) {
        status_ = DetectorStatus::MatcherFailed;
        builder_.setAllUnknown(sequence, stampNs);
        return builder_.sectors();
    }
    StageLap lap(&times_);
    const GroundEstimate& estimate = estimator_.update(matcher_.disparityView());
    ground_ = estimate.plane;
    setGroundPrior(matcher_, estimate.disparity, roi_);    // for the next frame's top path
    setSearchFloor(matcher_, estimate, projection_, roi_); // for the next frame's search ranges
    lap.to(VisionStage::Ground);
    ConstImageViewU8 labels;
    const bool warped =
        warpGround(rectLeftRoi, estimate.disparity, roi_.y, warped_.view(), spans_) == GroundWarpStatus::Ok;
    lap.to(VisionStage::Warp);
    if (warped && mismatch_.run(rectLeftRoi, rectRightRoi, warped_.view(), spans_, estimate.disparity, roi_.y) ==
                      GroundMismatchStatus::Ok) {
        labelsToLeftGrid(estimate.disparity, false);
        labels = leftLabels_.view();
    }
    lap.to(VisionStage::Mismatch);
    ImageView<const std::int16_t> disparity = matcher_.disparityView();
    if (verifier_.run(rectLeftRoi, rectRightRoi, disparity, estimate.disparity, roi_.y) == VerifyStatus::Ok) {
        disparity = verifier_.disparity();
    }
    lap.to(VisionStage::Verify);
    builder_.setBlockGrid(measureBlockGrid(rectLeftRoi), measureBlockGrid(rectRightRoi));
    const BuildStatus built = builder_.build(disparity, labels, ground_, sequence, stampNs);
    lap.to(VisionStage::Sectors);
    status_ = built == BuildStatus::Ok ? DetectorStatus::Ok : DetectorStatus::BuildFailed;
    return builder_.sectors();
}

const ObstacleSectors& ObstacleDetector::processGroundOnly(ConstImageViewU8 rectLeftRoi, ConstImageViewU8 rectRightRoi,
                                                           std::uint64_t sequence, std::int64_t stampNs) noexcept
{
    lastGroundOnly_ = true;
    const auto sizeOk = [this](ConstImageViewU8 v) {
        return v.data() != nullptr && v.width() == roi_.width && v.height() == roi_.height;
    };
    if (!sizeOk(rectLeftRoi) || !sizeOk(rectRightRoi)) {
        status_ = DetectorStatus::WrongInputSize;
        groundOnlyBuilder_->setAllUnknown(sequence, stampNs);
        return groundOnlyBuilder_->sectors();
    }
    times_.clear();
    StageLap lap(&times_);
    matcher_.clearSearchFloor(); // no estimate this frame: the next dense frame searches the full range
    ground_ = configuredGround_;
    const DisparityPlane plane = ground_.disparityPlane(projection_);
    const bool warped = warpGround(rectLeftRoi, plane, roi_.y, warped_.view(), spans_) == GroundWarpStatus::Ok;
    lap.to(VisionStage::Warp);
    if (!warped ||
        mismatch_.run(rectLeftRoi, rectRightRoi, warped_.view(), spans_, plane, roi_.y) != GroundMismatchStatus::Ok) {
        status_ = DetectorStatus::BuildFailed;
        groundOnlyBuilder_->setAllUnknown(sequence, stampNs);
        return groundOnlyBuilder_->sectors();
    }
    labelsToLeftGrid(plane, true);
    lap.to(VisionStage::Mismatch);
    const BuildStatus built = groundOnlyBuilder_->build(sparse_.view(), leftLabels_.view(), ground_, sequence, stampNs);
    lap.to(VisionStage::Sectors);
    groundOnlyBuilder_->markDegraded();
    status_ = built == BuildStatus::Ok ? DetectorStatus::Ok : DetectorStatus::BuildFailed;
    return groundOnlyBuilder_->sectors();
}

void ObstacleDetector::labelsToLeftGrid(const DisparityPlane& plane, bool withDisparity) noexcept
{
    const ConstImageViewU8 rightLabels = mismatch_.labels();
    const ImageView<const std::int8_t> residuals = mismatch_.residuals();
    const ImageViewU8 out = leftLabels_.view();
    const ImageView<std::int16_t> sparse = sparse_.view();
    for (int y = 0; y < out.height(); ++y) {
        std::uint8_t* dst = out.row(y);
        std::fill(dst, dst + out.width(), static_cast<std::uint8_t>(GroundLabel::NotTested));
        std::int16_t* disparity = sparse.row(y);
        if (withDisparity) {
            std::fill(disparity, disparity + sparse.width(), static_cast<std::int16_t>(-16));
        }
        const std::uint8_t* labels = rightLabels.row(y);
        const std::int8_t* residual = residuals.row(y);
        const WarpRowMap map = warpRowMap(plane, roi_.y + y);
        for (int xr = 0; xr < out.width(); ++xr) {
            const auto label = static_cast<GroundLabel>(labels[xr]);
            if (label != GroundLabel::Positive && label != GroundLabel::Negative) {
                continue;
            }
            // The right pixel sees the point the left image shows at the ground-model source plus the residual.
            const int xl =
                static_cast<int>(std::lround(map.scale * static_cast<float>(xr) + map.offset)) + residual[xr];
            if (xl < 0 || xl >= out.width()) {
                continue;
            }
            dst[xl] = labels[xr];
            const double d = plane.at(xl + roi_.x, y + roi_.y) + residual[xr];
            if (withDisparity && d > 0.0) {
                disparity[xl] = static_cast<std::int16_t>(std::lround(d * 16.0));
            }
        }
    }
}

} // namespace ugv::vision
