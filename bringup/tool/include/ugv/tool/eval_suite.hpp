#pragma once

/// @file
/// Scoring used by `ugvsense eval`: detected sectors against the simulator's ground-truth sectors
/// (bringup/sim/README.md), and a disparity map against Middlebury ground truth. Pure functions, host tool only.
/// Thread-safety: reentrant.

#include <vector>

#include <opencv2/core.hpp>

#include "ugv/platform/obstacle_sectors.hpp"
#include "ugv/vision/ground_plane.hpp"

namespace ugv::tool {

/// One frame of an obstacle scene.
struct ObstacleFrameScore {
    bool gtHasObstacle = false;  ///< the ground truth has at least one Obstacle sector
    int gtSector = -1;           ///< the GT sector holding the nearest GT obstacle
    double gtRangeM = 0.0;       ///< [m] its range
    bool detected = false;       ///< a GT obstacle sector, or a sector next to one, is reported Obstacle
    double detectedRangeM = 0.0; ///< [m] nearest range reported in the GT obstacle sectors (else next to them)
    double rangeErrorM = 0.0;    ///< [m] |detectedRangeM - gtRangeM|, when detected
    int spillSectors = 0;        ///< sectors reported Obstacle whose GT is not Obstacle
    int falseClearSectors = 0;   ///< sectors reported Clear whose GT holds an obstacle within 10 m (unsafe)
};

/// Scores `detected` against `gt` (same sector layout).
ObstacleFrameScore scoreObstacleFrame(const ObstacleSectors& detected, const ObstacleSectors& gt);

/// Sectors reported Red or Blue.
int countRedBlue(const ObstacleSectors& sectors);

/// Range tolerance of the evaluation: max(0.10 m, 3 % of the range) [m].
double rangeTolerance(double rangeM);

/// The doorway check: the GT-clear sectors lying between the first and the last GT-obstacle sector (the gap).
struct GapScore {
    int gapSectors = 0;       ///< GT-clear sectors inside the wall's extent
    int reportedObstacle = 0; ///< of those, reported Obstacle
    int innerObstacle = 0;    ///< of those, reported Obstacle, not counting the gap's first and last sector
    int reportedClear = 0;    ///< of those, reported Clear
    /// The gap exists in the GT and none of its sectors is reported Obstacle except, at most, the one sector at
    /// each edge of the gap (the same one-sector bearing tolerance as the detection score: the matcher's
    /// foreground fattening of 1 to 3 px can spill the wall's range into the next sector).
    [[nodiscard]] bool visible() const { return gapSectors > 2 && innerObstacle == 0; }
};
GapScore scoreGap(const ObstacleSectors& detected, const ObstacleSectors& gt);

/// One frame of an approach: the obstacle placed nearer frame by frame (`ugvsense eval --approach`).
struct ApproachFrame {
    double gtRangeM = 0.0; ///< [m] nearest GT obstacle range (frames whose GT has no obstacle are left out)
    bool detected = false; ///< as in ObstacleFrameScore
};

/// How far ahead an obstacle is seen on the way to it.
struct ApproachScore {
    int frames = 0;
    int detected = 0;
    double firstRangeM = 0.0; ///< [m] the farthest GT range at which it is detected; 0 when never
    /// [m] the farthest GT range from which it is detected in every frame on (at that range and every nearer
    /// one); 0 when the nearest frame is missed.
    double heldRangeM = 0.0;
};
/// @param frames in any order
ApproachScore scoreApproach(std::vector<ApproachFrame> frames);

/// Disparity errors against ground truth over the pixels with valid GT (GT > 0).
struct DisparityScore {
    int gtPixels = 0;       ///< pixels with valid GT
    int predictedValid = 0; ///< of those, with a valid prediction (>= 0)
    double bad1All = 0.0;   ///< fraction with |d - gt| > 1 or no prediction
    double bad2All = 0.0;   ///< fraction with |d - gt| > 2 or no prediction
    double bad1Valid = 0.0; ///< fraction with |d - gt| > 1 among predicted-valid pixels
    double bad2Valid = 0.0; ///< fraction with |d - gt| > 2 among predicted-valid pixels
    [[nodiscard]] double density() const { return gtPixels > 0 ? static_cast<double>(predictedValid) / gtPixels : 0.0; }
};

/// @param[in] predicted  CV_32F disparity [px], invalid < 0
/// @param[in] gt         CV_32F disparity [px], 0 = unknown (masked out); same size
DisparityScore scoreDisparity(const cv::Mat& predicted, const cv::Mat& gt);

/// The images' own evidence that pixels lie below the ground, with no matcher (`ugvsense eval --hole-signal`): over a
/// window of one row and 2 * halfWidth + 1 pixels, the zero-mean SAD per pixel of left against right near the
/// ground's disparity (c_g: the least within +-3/8 px of it, 1/8 px steps) and the least one at a constant disparity
/// 0.5 to 3 px below the ground's (c_b; 1/4 px steps), the right image interpolated linearly; evidence = (c_g - c_b) /
/// (c_g + 1) grey levels. Near 0 or below where the ground explains the window, up to 1 where a farther surface does
/// and the ground does not. The ground's own search keeps the least of many farther costs from winning by chance
/// where the images disagree for another reason (the noise of a strong edge).
/// @param[in] left, right  CV_8UC1 rectified pair of one size
/// @param[in] ground       the ground's disparity model
/// @param[in] rowFirst, rowLast  rows to compute (clamped to the image); the rest of the result is 0
/// @return CV_32F of the size of `left`
cv::Mat dropEvidence(const cv::Mat& left, const cv::Mat& right, const vision::DisparityPlane& ground, int rowFirst,
                     int rowLast, int halfWidth);

/// One frame's drop evidence pooled over strips of stripWidth x stripRows pixels (every 4 px, every row): the best
/// strip over a hole's far wall against the best plain-ground strip in the same rows.
struct DropSignal {
    bool hasWall = false;  ///< the truth has a wall strip: half its pixels or more are wall
    double wallBest = 0.0; ///< best mean evidence of a wall strip; 0 without one
    /// Best mean evidence of a strip all on plain ground, in the wall's rows +- 6; 0 without one.
    double groundBest = 0.0;
    /// Even a detector told where to look and given the best threshold for this frame would find the wall.
    [[nodiscard]] bool separable() const { return hasWall && wallBest > groundBest; }
};
/// @param[in] evidence     dropEvidence()
/// @param[in] labels       CV_8U truth per pixel, sim::Label (Ground, Negative: a hole's wall or floor)
/// @param[in] gtDisparity  CV_32F true disparity; a wall pixel is a label-2 pixel at least 0.75 px below the ground
DropSignal scoreDropSignal(const cv::Mat& evidence, const cv::Mat& labels, const cv::Mat& gtDisparity,
                           const vision::DisparityPlane& ground, int rowFirst, int rowLast, int stripWidth,
                           int stripRows);

/// The p-quantile (nearest rank) of `values` (copied and sorted); 0 when empty.
double quantile(std::vector<double> values, double p);

} // namespace ugv::tool
