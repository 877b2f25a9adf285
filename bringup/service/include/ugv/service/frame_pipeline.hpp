#pragma once

/// @file
/// The vision task's work on one stereo pair: ROI rectification, then the detector `obstacles.detector` names, built
/// once from the calibration and the service config. Shared by ugvsensed and `ugvsense bench`.
/// - stereo: vision::ObstacleDetector on the rectified pair.
/// - colour: the one-camera mode, vision::ColourFreeSpace on the rectified left ROI: by colour when the camera
///   delivers BGR frames (V4L2 with camera.colour, a colour recording), else by grey level (the ground's grey levels
///   learnt along the bottom band: much weaker). Its sectors are `degraded`; the ground is the mount's.
/// - both: stereo where it sees, and in the sectors stereo leaves Unknown the colour detector's obstacles (never its
///   Clear: a colour cue is blind to an obstacle of the ground's colour or grey level).
/// A left-only frame (an empty right image: a one-camera rig, or the pair's right camera lost) takes the colour path
/// in every mode: the service keeps publishing sectors, degraded, until the pair is whole again. A BGR pair is made
/// grey (OpenCV's BT.601 luma) for the stereo detector, in buffers allocated by create().
///
/// Thread-safety: thread-bound. RT-safe: process() allocates nothing with the default matcher (census SGM); with
/// stereo.mode an OpenCV mode, StereoSGBM::compute inside the detector allocates (vision/roi_matcher.hpp);
/// create() no.

#include <cstdint>
#include <memory>

#include "ugv/adapters/config.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/frame_header.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/obstacle_sectors.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/colour_free_space.hpp"
#include "ugv/vision/obstacle_detector.hpp"
#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::service {

/// Detector settings of the service config (sectors, danger distances, obstacle thresholds, matcher).
vision::DetectorConfig detectorConfigFrom(const adapters::ServiceConfig& config);

enum class PipelineStatus : std::uint8_t { Ok, WrongInputSize, RectifyFailed, DetectorFailed };

class FramePipeline {
public:
    /// Errors: a calibration without a mount section (the service needs the camera's height and tilt), a frame
    /// size that differs from the calibration's, and the stages' own config errors.
    static Result<std::unique_ptr<FramePipeline>, Error> create(const vision::StereoCalibration& calibration,
                                                                const adapters::ServiceConfig& config);

    /// Rectifies the pair, grey or BGR (the left image alone when the frame is left-only) and detects; `groundOnly`
    /// takes the overload path of the stereo detector (ObstacleDetector::processGroundOnly: no dense matching,
    /// degraded sectors; the colour detector is cheap and always runs in full). `rectifiedNs` receives the monotonic
    /// time after rectification.
    PipelineStatus process(const StereoViews& images, std::uint64_t sequence, std::int64_t stampNs,
                           std::int64_t& rectifiedNs, bool groundOnly = false) noexcept;

    /// The last frame's sectors, of the configured detector (the colour detector's for a left-only frame).
    [[nodiscard]] const ObstacleSectors& sectors() const noexcept;
    /// The ground the last frame's sectors were measured against: the stereo detector's estimate when it ran
    /// (reliable as it says), else the mount's plane (not reliable: the one-camera detector does not estimate it).
    [[nodiscard]] GroundSummary ground() const noexcept;
    /// True when the last frame was left-only (the colour path ran whatever the mode).
    [[nodiscard]] bool lastFrameLeftOnly() const noexcept { return leftOnly_; }
    /// Left-only frames processed since create().
    [[nodiscard]] std::uint64_t leftOnlyFrames() const noexcept { return leftOnlyFrames_; }
    [[nodiscard]] adapters::DetectorMode mode() const noexcept { return mode_; }
    [[nodiscard]] int width() const noexcept { return width_; }
    [[nodiscard]] int height() const noexcept { return height_; }
    [[nodiscard]] const vision::ObstacleDetector& detector() const noexcept { return detector_; }
    [[nodiscard]] const vision::Rectifier& rectifier() const noexcept { return rectifier_; }

private:
    FramePipeline(vision::Rectifier rectifier, vision::ObstacleDetector detector, vision::ColourFreeSpace colour,
                  adapters::DetectorMode mode, vision::GroundPlane mountGround, int width, int height);
    /// Both: the stereo sectors, with the colour detector's obstacles where stereo's are Unknown.
    void fuse() noexcept;
    /// Rectifies what the frame's detectors need: the left image alone (`colourOnly`), else the pair (a BGR pair
    /// made grey first); a BGR left image also in colour, for the colour detector.
    vision::RectifyStatus rectify(const StereoViews& images, bool colourOnly) noexcept;
    /// The colour detector on the rectified left ROI: in colour after a BGR frame, else grey.
    void detectColour(bool bgrFrame, std::uint64_t sequence, std::int64_t stampNs) noexcept;

    vision::Rectifier rectifier_;
    vision::ObstacleDetector detector_; ///< made in every mode: its ground estimate is the published one
    vision::ColourFreeSpace colour_;    ///< colour, both, and every left-only frame
    adapters::DetectorMode mode_;
    vision::GroundPlane mountGround_; ///< the calibration's mount: the one-camera detector's ground
    Image<std::uint8_t> greyLeft_;    ///< a BGR pair made grey for the stereo detector (full frame)
    Image<std::uint8_t> greyRight_;
    Image<BgrPixel> colourRoi_; ///< the rectified left ROI of a BGR frame
    ObstacleSectors colourSectors_;
    ObstacleSectors fused_;
    bool leftOnly_ = false;
    std::uint64_t leftOnlyFrames_ = 0;
    int width_;
    int height_;
};

} // namespace ugv::service
