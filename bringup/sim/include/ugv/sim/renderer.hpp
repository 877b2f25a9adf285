#pragma once

/// @file
/// The ray caster: renders a rectified stereo pair of a Scene seen from a vehicle Pose, with exact per-pixel
/// ground truth (disparity, depth, label, obstacle id, height) and ground-truth obstacle sectors.
/// The definition of the ground truth is in bringup/sim/README.md.
///
/// The image rays run on every core (RenderOptions::threads, rows dealt out in turn); each pixel is traced alone and
/// the noise is drawn in pixel order on one thread, so the images are the same bit for bit whatever the number of
/// threads.
///
/// Thread-safety: reentrant (no shared state). RT-safe: no (host tooling; allocates the output images).

#include <cstdint>

#include <opencv2/core/mat.hpp>

#include "ugv/platform/error.hpp"
#include "ugv/platform/obstacle_sectors.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/sim/scene.hpp"

namespace ugv::sim {

/// Per-pixel ground-truth label (values of RenderResult::labels).
enum class Label : std::uint8_t {
    Ground = 0,   ///< flat ground, and obstacle-free ground-level surfaces
    Positive = 1, ///< positive obstacle (anything standing on the ground below the clearance)
    Negative = 2, ///< wall or floor of a hole or trench
    Overhang = 3, ///< object whose underside is above the clearance
    Far = 4,      ///< sky or background wall
};

/// Rendering and ground-truth options. The ground-truth sector definition uses the last group.
struct RenderOptions {
    int samplesPerAxis = 2;        ///< jittered supersampling: samplesPerAxis^2 rays per pixel, 1..4
    double roiTopFraction = 0.5;   ///< ROI rows: [roiTopFraction * height, height)
    double minHeightM = 0.10;      ///< [m] positive-obstacle hit points must be higher than this
    double minDepthM = 0.10;       ///< [m] negative obstacles (holes, trenches) deeper than this count ...
    double minVisibleDropM = 0.02; ///< [m] ... where their hit points are this far below the ground
    double clearanceM = 1.0;       ///< [m] objects whose underside is above this are overhangs
    int sectorCount = 64;          ///< sectors across the horizontal field of view
    float dangerDistanceM = 1.5F;  ///< [m] classify(): Red below this range
    float cautionDistanceM = 5.0F; ///< [m] classify(): Blue below this range
    bool rightColour = false;      ///< also the right camera in colour (RenderResult::rightColour: colour recordings)
    int threads = 0; ///< threads tracing the image rays, 0..64; 0: one per core (the images do not depend on it)
};

/// One rendered stereo pair with its ground truth (all images rig.width x rig.height).
struct RenderResult {
    cv::Mat left; ///< CV_8UC1 grey
    /// CV_8UC3 BGR of the left camera: the same radiance with each surface's Chroma, so that its luminance
    /// (OpenCV BGR2GRAY) is `left` within rounding, where no channel clips at 0 or 255 (bringup/sim/README.md).
    cv::Mat leftColour;
    cv::Mat right;           ///< CV_8UC1 grey
    cv::Mat rightColour;     ///< CV_8UC3 BGR of the right camera, as leftColour; with RenderOptions::rightColour only
    cv::Mat disparity;       ///< CV_32F [px] of the left image, fx * baseline / Z; exactly 0 for sky (Z = infinity)
    cv::Mat depth;           ///< CV_32F [m] Z along the left optical axis; +inf for sky
    cv::Mat labels;          ///< CV_8U, values of Label
    cv::Mat ids;             ///< CV_16U, obstacle index + 1 (0: ground, sky, background)
    cv::Mat height;          ///< CV_32F [m] hit point height above the flat ground (negative in holes); NaN for sky
    ObstacleSectors sectors; ///< ground-truth sectors (see README.md)
};

/// Renders `scene` seen from the vehicle at `pose` (world frame). The ground truth is sampled by one ray
/// through each pixel centre of the left camera; the images average samplesPerAxis^2 jittered rays.
/// @return the images and ground truth, or an Error for invalid scene parameters or options.
[[nodiscard]] Result<RenderResult, Error> render(const Scene& scene, const Pose& pose = {},
                                                 const RenderOptions& options = {});

/// Renders frame `frame` of `course` (its scene seen from poses[frame]; the noise seed is scene.seed + frame).
/// @return as render(), or an Error when frame is out of range.
[[nodiscard]] Result<RenderResult, Error> renderCourseFrame(const Course& course, std::size_t frame,
                                                            const RenderOptions& options = {});

} // namespace ugv::sim
