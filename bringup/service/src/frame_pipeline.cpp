#include "ugv/service/frame_pipeline.hpp"

#include "ugv/platform/clock.hpp"

#include <ctime>
#include <utility>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/mat_view.hpp"

namespace ugv::service {

vision::DetectorConfig detectorConfigFrom(const adapters::ServiceConfig& config)
{
    vision::DetectorConfig d;
    d.matcher.mode = config.stereo.mode;
    d.matcher.numDisparities = config.stereo.numDisparities;
    d.matcher.blockSize = config.stereo.blockSize;
    d.matcher.groundRange = config.stereo.groundRange;
    d.matcher.groundRangeDropM = config.stereo.groundRangeDropM;
    d.matcher.groundRangeMarginDeg = config.stereo.groundRangeMarginDeg;
    d.halfResolutionMinGroundPx = config.stereo.halfResolutionMinGroundPx;
    d.sectors.sectorCount = config.obstacles.sectorCount;
    d.sectors.dangerDistanceM = static_cast<float>(config.obstacles.dangerDistanceM);
    d.sectors.cautionDistanceM = static_cast<float>(config.obstacles.cautionDistanceM);
    d.sectors.minHeightM = static_cast<float>(config.obstacles.minHeightM);
    d.sectors.minDepthM = static_cast<float>(config.obstacles.minDepthM);
    d.sectors.maxRangeDisparityPx = static_cast<float>(config.obstacles.maxRangeDisparityPx);
    d.marginRows = config.roi.matcherMarginRows;
    return d;
}

namespace {

/// The one-camera detector on the rectifier's left ROI image: its rows are the image it sees (the projection's
/// principal point moved up by the ROI's top), and the rows above the analysed ones are the matcher's margin.
Result<vision::ColourFreeSpace, Error> makeColour(const vision::Rectifier& rectifier,
                                                  const vision::DetectorConfig& detectorConfig,
                                                  const vision::GroundPlane& ground)
{
    const Rect roi = rectifier.roi();
    vision::RectifiedProjection projection = rectifier.projection();
    projection.cy -= roi.y;
    vision::ColourFreeSpaceConfig config = vision::colourConfigFor(detectorConfig.sectors);
    config.roiTopFraction = static_cast<double>(detectorConfig.marginRows) / roi.height;
    return vision::ColourFreeSpace::create(config, cv::Size(roi.width, roi.height), projection, ground);
}

} // namespace

FramePipeline::FramePipeline(vision::Rectifier rectifier, vision::ObstacleDetector detector,
                             vision::ColourFreeSpace colour, adapters::DetectorMode mode,
                             vision::GroundPlane mountGround, int width, int height)
    : rectifier_(std::move(rectifier)), detector_(std::move(detector)), colour_(std::move(colour)), mode_(mode),
      mountGround_(mountGround), greyLeft_(width, height), greyRight_(width, height),
      colourRoi_(rectifier_.roi().width, rectifier_.roi().height), width_(width), height_(height)
{
    detector_.setStageClock(&MonotonicClock::nowNs); // where the time goes, per stage (the service's report)
}

Result<std::unique_ptr<FramePipeline>, Error> FramePipeline::create(const vision::StereoCalibration& calibration,
                                                                    const adapters::ServiceConfig& config)
{
    if (!calibration.mount) {
        return Unexpected(Error{"calibration", "has no mount section (camera height, pitch and roll above the ground)",
                                "measure the mount and add `mount: { height_m: ..., pitch_deg: ..., roll_deg: ... }` "
                                "to the calibration file"});
    }
    const int width = calibration.imageSize.width;
    const int height = calibration.imageSize.height;
    if (width != config.camera.width || height != config.camera.height) {
        return Unexpected(Error{"calibration",
                                "is for " + std::to_string(width) + "x" + std::to_string(height) +
                                    " but the camera delivers " + std::to_string(config.camera.width) + "x" +
                                    std::to_string(config.camera.height),
                                "calibrate at the camera's resolution, or set camera.width/height"});
    }
    const vision::DetectorConfig detectorConfig = detectorConfigFrom(config);
    auto rectifier =
        vision::Rectifier::create(calibration, vision::roiRectifierConfig(detectorConfig, config.roi.topFraction));
    if (!rectifier) {
        return Unexpected(rectifier.error());
    }
    const vision::GroundPlane ground = vision::GroundPlane::fromMount(*calibration.mount);
    auto detector = vision::ObstacleDetector::create(detectorConfig, *rectifier, ground);
    if (!detector) {
        return Unexpected(detector.error());
    }
    // Made in every mode: a left-only frame (the pair's right camera lost) falls back to it.
    auto colour = makeColour(*rectifier, detectorConfig, ground);
    if (!colour) {
        return Unexpected(colour.error());
    }
    return std::unique_ptr<FramePipeline>(new FramePipeline(std::move(*rectifier), std::move(*detector),
                                                            std::move(*colour), config.obstacles.detector, ground,
                                                            width, height));
}

GroundSummary FramePipeline::ground() const noexcept
{
    const bool stereoRan = !leftOnly_ && mode_ != adapters::DetectorMode::Colour;
    const vision::GroundEstimate& estimate = detector_.groundEstimate();
    const vision::GroundPlane& plane = stereoRan ? estimate.plane : mountGround_;
    return GroundSummary{stereoRan && estimate.reliable, static_cast<float>(plane.pitchDeg()),
                         static_cast<float>(plane.rollDeg()), static_cast<float>(plane.heightM)};
}

const ObstacleSectors& FramePipeline::sectors() const noexcept
{
    if (leftOnly_) {
        return colourSectors_;
    }
    switch (mode_) {
    case adapters::DetectorMode::Colour:
        return colourSectors_;
    case adapters::DetectorMode::Both:
        return fused_;
    case adapters::DetectorMode::Stereo:
        break;
    }
    return detector_.sectors();
}

void FramePipeline::fuse() noexcept
{
    fused_ = detector_.sectors();
    if (colourSectors_.count != fused_.count) {
        return; // never: both are made with the same sector count over the same image width
    }
    for (int i = 0; i < fused_.count; ++i) {
        // The one-camera cue adds obstacles where stereo cannot tell, never Clear: it cannot see an obstacle of the
        // ground's colour (or grey level), so its Clear is no evidence against stereo's Unknown.
        Sector& s = fused_.sectors[static_cast<std::size_t>(i)];
        const Sector& c = colourSectors_.sectors[static_cast<std::size_t>(i)];
        if (s.state == SectorState::Unknown && c.state == SectorState::Obstacle) {
            s = c;
        }
    }
}

vision::RectifyStatus FramePipeline::rectify(const StereoViews& images, bool colourOnly) noexcept
{
    if (!images.colour()) {
        return colourOnly ? rectifier_.rectifyLeft(images.left) : rectifier_.rectify(images.left, images.right);
    }
    if (colourOnly) {
        return rectifier_.rectifyLeft(images.leftBgr, colourRoi_.view());
    }
    // The sizes were checked by process(): cvtColor writes into the buffers of create() without allocating.
    cv::Mat greyLeft = vision::matOver(greyLeft_.view());
    cv::Mat greyRight = vision::matOver(greyRight_.view());
    cv::cvtColor(vision::matOver(images.leftBgr), greyLeft, cv::COLOR_BGR2GRAY);
    cv::cvtColor(vision::matOver(images.rightBgr), greyRight, cv::COLOR_BGR2GRAY);
    const vision::RectifyStatus pair = rectifier_.rectify(greyLeft_.view(), greyRight_.view());
    if (pair != vision::RectifyStatus::Ok || mode_ != adapters::DetectorMode::Both) {
        return pair;
    }
    return rectifier_.rectifyLeft(images.leftBgr, colourRoi_.view());
}

void FramePipeline::detectColour(bool bgrFrame, std::uint64_t sequence, std::int64_t stampNs) noexcept
{
    // The ROI's size is the one colour_ was made for: always Ok.
    if (bgrFrame) {
        (void)colour_.process(ConstBgrView(colourRoi_.view()), colourSectors_);
    } else {
        (void)colour_.process(rectifier_.rectifiedLeft(), colourSectors_);
    }
    colourSectors_.sequence = sequence;
    colourSectors_.captureStampNs = stampNs;
}

PipelineStatus FramePipeline::process(const StereoViews& images, std::uint64_t sequence, std::int64_t stampNs,
                                      std::int64_t& rectifiedNs, bool groundOnly) noexcept
{
    leftOnly_ = images.leftOnly();
    if (!images.fits(width_, height_)) {
        rectifiedNs = MonotonicClock::nowNs();
        return PipelineStatus::WrongInputSize;
    }
    // The one-camera mode needs the left image only; so does every mode on a left-only frame.
    const bool colourOnly = leftOnly_ || mode_ == adapters::DetectorMode::Colour;
    const vision::RectifyStatus rectified = rectify(images, colourOnly);
    rectifiedNs = MonotonicClock::nowNs();
    if (rectified != vision::RectifyStatus::Ok) {
        return PipelineStatus::RectifyFailed;
    }
    if (colourOnly || mode_ == adapters::DetectorMode::Both) {
        detectColour(images.colour(), sequence, stampNs);
        if (colourOnly) {
            leftOnlyFrames_ += leftOnly_ ? 1U : 0U;
            return PipelineStatus::Ok;
        }
    }
    if (groundOnly) {
        detector_.processGroundOnly(rectifier_.rectifiedLeft(), rectifier_.rectifiedRight(), sequence, stampNs);
    } else {
        detector_.process(rectifier_.rectifiedLeft(), rectifier_.rectifiedRight(), sequence, stampNs);
    }
    if (detector_.status() != vision::DetectorStatus::Ok) {
        return PipelineStatus::DetectorFailed;
    }
    if (mode_ == adapters::DetectorMode::Both) {
        fuse();
    }
    return PipelineStatus::Ok;
}

} // namespace ugv::service
