#include "frame_pipeline.hpp"

#include "ugv/platform/clock.hpp"

#include <ctime>
#include <utility>

#include "ugv/vision/ground_plane.hpp"

namespace ugv::service {

vision::DetectorConfig detectorConfigFrom(const bringup::ServiceConfig& config)
{
    vision::DetectorConfig d;
    d.matcher.mode = config.stereo.mode;
    d.matcher.numDisparities = config.stereo.numDisparities;
    d.matcher.blockSize = config.stereo.blockSize;
    d.matcher.groundRange = config.stereo.groundRange;
    d.matcher.groundRangeDropM = config.stereo.groundRangeDropM;
    d.matcher.groundRangeMarginDeg = config.stereo.groundRangeMarginDeg;
    d.sectors.sectorCount = config.obstacles.sectorCount;
    d.sectors.dangerDistanceM = static_cast<float>(config.obstacles.dangerDistanceM);
    d.sectors.cautionDistanceM = static_cast<float>(config.obstacles.cautionDistanceM);
    d.sectors.minHeightM = static_cast<float>(config.obstacles.minHeightM);
    d.sectors.minDepthM = static_cast<float>(config.obstacles.minDepthM);
    d.marginRows = config.roi.matcherMarginRows;
    return d;
}

FramePipeline::FramePipeline(vision::Rectifier rectifier, vision::ObstacleDetector detector, int width, int height)
    : rectifier_(std::move(rectifier)), detector_(std::move(detector)), width_(width), height_(height)
{
    detector_.setStageClock(&MonotonicClock::nowNs); // where the time goes, per stage (the service's report)
}

Result<std::unique_ptr<FramePipeline>, Error> FramePipeline::create(const vision::StereoCalibration& calibration,
                                                                    const bringup::ServiceConfig& config)
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
    vision::RectifierConfig rectifierConfig;
    rectifierConfig.roiTopFraction = config.roi.topFraction;
    rectifierConfig.roiMarginRows = detectorConfig.marginRows;
    auto rectifier = vision::Rectifier::create(calibration, rectifierConfig);
    if (!rectifier) {
        return Unexpected(rectifier.error());
    }
    auto detector = vision::ObstacleDetector::create(detectorConfig, rectifier->projection(), rectifier->roi(),
                                                     vision::GroundPlane::fromMount(*calibration.mount));
    if (!detector) {
        return Unexpected(detector.error());
    }
    return std::unique_ptr<FramePipeline>(
        new FramePipeline(std::move(*rectifier), std::move(*detector), width, height));
}

PipelineStatus FramePipeline::process(ConstImageViewU8 left, ConstImageViewU8 right, std::uint64_t sequence,
                                      std::int64_t stampNs, std::int64_t& rectifiedNs, bool groundOnly) noexcept
{
    if (left.width() != width_ || left.height() != height_ || right.width() != width_ || right.height() != height_) {
        rectifiedNs = MonotonicClock::nowNs();
        return PipelineStatus::WrongInputSize;
    }
    if (rectifier_.rectify(left, right) != vision::RectifyStatus::Ok) {
        rectifiedNs = MonotonicClock::nowNs();
        return PipelineStatus::RectifyFailed;
    }
    rectifiedNs = MonotonicClock::nowNs();
    if (groundOnly) {
        detector_.processGroundOnly(rectifier_.rectifiedLeft(), rectifier_.rectifiedRight(), sequence, stampNs);
    } else {
        detector_.process(rectifier_.rectifiedLeft(), rectifier_.rectifiedRight(), sequence, stampNs);
    }
    return detector_.status() == vision::DetectorStatus::Ok ? PipelineStatus::Ok : PipelineStatus::DetectorFailed;
}

} // namespace ugv::service
