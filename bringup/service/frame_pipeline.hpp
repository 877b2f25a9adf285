#pragma once

/// @file
/// The vision task's work on one stereo pair: ROI rectification, then the detector `obstacles.detector` names, built
/// once from the calibration and the service config. Shared by ugvsensed and `ugvsense bench`.
/// - stereo: vision::ObstacleDetector on the rectified pair.
/// - colour: the one-camera mode, vision::ColourFreeSpace on the rectified left ROI. The capture path is grey today
///   (V4L2's Y plane, grey recordings), so it tells the ground by grey level: the ground's grey levels learnt along
///   the bottom band. Its sectors are `degraded`; the ground is the mount's.
/// - both: stereo where it sees, and in the sectors stereo leaves Unknown the colour detector's obstacles (never its
///   Clear: a colour cue is blind to an obstacle of the ground's colour or grey level).
///
/// Thread-safety: thread-bound. RT-safe: process() allocates nothing with the default matcher (census SGM); with
/// stereo.mode an OpenCV mode, StereoSGBM::compute inside the detector allocates (vision/roi_matcher.hpp);
/// create() no.

#include <cstdint>
#include <memory>
#include <optional>

#include "ugv/bringup/config.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/obstacle_sectors.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/colour_free_space.hpp"
#include "ugv/vision/obstacle_detector.hpp"
#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::service {

/// Detector settings of the service config (sectors, danger distances, obstacle thresholds, matcher).
vision::DetectorConfig detectorConfigFrom(const bringup::ServiceConfig& config);

enum class PipelineStatus : std::uint8_t { Ok, WrongInputSize, RectifyFailed, DetectorFailed };

class FramePipeline {
public:
    /// Errors: a calibration without a mount section (the service needs the camera's height and tilt), a frame
    /// size that differs from the calibration's, and the stages' own config errors.
    static Result<std::unique_ptr<FramePipeline>, Error> create(const vision::StereoCalibration& calibration,
                                                                const bringup::ServiceConfig& config);

    /// Rectifies the pair and detects; `groundOnly` takes the overload path of the stereo detector
    /// (ObstacleDetector::processGroundOnly: no dense matching, degraded sectors; the colour detector is cheap and
    /// always runs in full). `rectifiedNs` receives the monotonic time after rectification.
    PipelineStatus process(ConstImageViewU8 left, ConstImageViewU8 right, std::uint64_t sequence, std::int64_t stampNs,
                           std::int64_t& rectifiedNs, bool groundOnly = false) noexcept;

    /// The last frame's sectors, of the configured detector.
    [[nodiscard]] const ObstacleSectors& sectors() const noexcept;
    [[nodiscard]] bringup::DetectorMode mode() const noexcept { return mode_; }
    [[nodiscard]] int width() const noexcept { return width_; }
    [[nodiscard]] int height() const noexcept { return height_; }
    [[nodiscard]] const vision::ObstacleDetector& detector() const noexcept { return detector_; }
    [[nodiscard]] const vision::Rectifier& rectifier() const noexcept { return rectifier_; }

private:
    FramePipeline(vision::Rectifier rectifier, vision::ObstacleDetector detector,
                  std::optional<vision::ColourFreeSpace> colour, bringup::DetectorMode mode, int width, int height);
    /// Both: the stereo sectors, with the colour detector's obstacles where stereo's are Unknown.
    void fuse() noexcept;

    vision::Rectifier rectifier_;
    vision::ObstacleDetector detector_;             ///< made in every mode: its ground estimate is the published one
    std::optional<vision::ColourFreeSpace> colour_; ///< colour and both
    bringup::DetectorMode mode_;
    ObstacleSectors colourSectors_;
    ObstacleSectors fused_;
    int width_;
    int height_;
};

} // namespace ugv::service
