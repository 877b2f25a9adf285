#pragma once

/// @file
/// Single-camera colour free space: "the ground looks like the patch in front of the vehicle".
///
/// From one BGR image: 3x3 box blur, hue-saturation bins (kHueBins x kSatBins, OpenCV's HSV scales: hue
/// 0..179, saturation 0..255), the histogram of a reference patch at the bottom centre of the image, and a
/// sliding-window comparison of every ROI pixel's (2 radius + 1)^2 window histogram against the reference by
/// histogram intersection (sum_b min(window_b, reference_b) / window area, in [0, 1]). The window histograms are
/// updated incrementally (per-column vertical histograms rolled down the rows, and a horizontal running window
/// histogram), so the cost per pixel is O(bins) whatever the window size. Then each column is scanned upwards from
/// the bottom to the first non-free pixel; that row's ground point (ray of the pixel meets the ground plane)
/// gives the free range and bearing, and each sector takes the minimum over its columns.
///
/// Sector states: Obstacle (kind Positive) when a column's free run ends inside the ROI; Clear when every column of
/// the sector reaches the ROI top (or the horizon, i.e. maxRangeM) beyond the caution distance; Unknown when the
/// reference patch is not ground-like (too little saturation or brightness for hue to mean anything, or the patch
/// does not match itself, i.e. it is occluded or mixed) or the free run reaches the ROI top short of the caution
/// distance. Output sectors are marked `degraded` (a single-camera fallback) and carry heightM 0.
///
/// This is the method of the original system, whose per-window recomputation was too slow; here it is linear.

#include <array>
#include <cstdint>
#include <vector>

#include <opencv2/core/types.hpp>

#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/obstacle_sectors.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/rectifier.hpp"

namespace ugv::vision {

/// One pixel of an 8-bit BGR image (cv::Mat CV_8UC3 layout: a row of such pixels is the Mat row).
struct BgrPixel {
    std::uint8_t b = 0;
    std::uint8_t g = 0;
    std::uint8_t r = 0;
};
static_assert(sizeof(BgrPixel) == 3, "BgrPixel must match CV_8UC3");

/// A view of a BGR image; width in pixels, stride in bytes (as cv::Mat::step).
using ConstBgrView = ImageView<const BgrPixel>;

inline constexpr int kHueBins = 16;                     ///< over OpenCV hue 0..179
inline constexpr int kSatBins = 8;                      ///< over saturation 0..255
inline constexpr int kColourBins = kHueBins * kSatBins; ///< bin index = hueBin * kSatBins + satBin

struct ColourFreeSpaceConfig {
    double roiTopFraction = 0.5;      ///< first analysed row = round(height * roiTopFraction)
    int patchWidth = 160;             ///< [px] reference patch, centred horizontally
    int patchHeight = 120;            ///< [px] reference patch, ending at the bottom row
    int windowRadius = 7;             ///< [px] comparison window (2 r + 1)^2, r in [1, 15]
    double matchThreshold = 0.5;      ///< intersection >= this => free, in (0, 1]
    int minObstacleRows = 3;          ///< [px] consecutive non-free rows that end a column's free run
    double minPatchSaturation = 40.0; ///< mean saturation (0..255) of the patch below which it is not ground-like
    double minPatchValue = 30.0;      ///< mean brightness (0..255) below which hue is noise
    double patchSelfMatch = 0.65;     ///< a window of the patch matches the patch when its intersection >= this
    double minPatchConsistency = 0.7; ///< fraction of the patch's own windows that must match the patch
    double maxRangeM = 50.0;          ///< [m] rows farther than this count as the horizon (end of the scan)
    int sectorCount = 64;             ///< sectors over the horizontal field of view, 1..kMaxSectors
    float dangerDistanceM = 1.5F;     ///< [m] classify(): Red below
    float cautionDistanceM = 5.0F;    ///< [m] classify(): Blue below; a free run must reach this to be Clear
};

/// Outcome of ColourFreeSpace::process; no strings on the frame path.
enum class ColourFreeSpaceStatus : std::uint8_t {
    Ok,             ///< sectors written (possibly all Unknown: see reference())
    WrongInputSize, ///< the image is not the configured size; sectors set to all Unknown
};

/// Statistics of the last frame's reference patch.
struct ColourReference {
    double meanSaturation = 0.0; ///< 0..255, after the blur
    double meanValue = 0.0;      ///< 0..255
    double consistency = 0.0;    ///< fraction of patch windows whose intersection >= patchSelfMatch
    bool groundLike = false;     ///< all three above their thresholds
};

/// Colour-histogram free space for one camera. All buffers are allocated in create().
/// Thread-safety: thread-bound (process() writes the internal buffers). RT-safe: process() yes (no allocation, no
/// exception, no OpenCV call); create() no.
class ColourFreeSpace {
public:
    /// Validates the configuration against the image size and geometry and allocates all buffers.
    /// @param[in] config      thresholds and sizes
    /// @param[in] imageSize   [px] size of the images given to process()
    /// @param[in] projection  rectified pinhole projection of the camera (fx, fy, cx, cy; baseline unused)
    /// @param[in] ground      ground plane in the camera frame (GroundPlane::fromMount)
    /// @return the detector, or an Error naming the offending parameter.
    static Result<ColourFreeSpace, Error> create(const ColourFreeSpaceConfig& config, cv::Size imageSize,
                                                 const RectifiedProjection& projection, const GroundPlane& ground);

    /// Computes the free space of one BGR frame into `out` (count = config.sectorCount over the camera's
    /// horizontal field of view; sequence and stamp are left to the caller).
    /// @param[in] image  imageSize BGR pixels
    /// @param[out] out   sectors
    /// @return Ok, or WrongInputSize (then all sectors Unknown).
    ColourFreeSpaceStatus process(ConstBgrView image, ObstacleSectors& out) noexcept;

    /// Last frame's reference patch statistics.
    [[nodiscard]] const ColourReference& reference() const noexcept { return reference_; }
    /// Hue-saturation bin of every pixel of rows [binTop(), height) (after the blur).
    [[nodiscard]] ConstImageViewU8 bins() const noexcept { return bins_.view(); }
    [[nodiscard]] int binTop() const noexcept { return binTop_; }
    /// Window intersection score 0..255 (= round(255 * intersection)) of rows [roiTop(), height); border rows and
    /// columns where the window does not fit copy the nearest computed score.
    [[nodiscard]] ConstImageViewU8 scores() const noexcept { return scores_.view(); }
    [[nodiscard]] int roiTop() const noexcept { return roiTop_; }
    /// Reference histogram scaled to the window area (what each window is intersected with).
    [[nodiscard]] const std::array<std::int16_t, kColourBins>& referenceHistogram() const noexcept { return ref_; }
    /// Last frame's free range [m] of each column: to the end of its free run, or to the top of the scan (ROI top or
    /// horizon) when columnHit() is 0; 0 when the column sees no ground.
    [[nodiscard]] const std::vector<float>& columnRangeM() const noexcept { return columnRange_; }
    [[nodiscard]] const std::vector<std::uint8_t>& columnHit() const noexcept { return columnHit_; }

private:
    ColourFreeSpace() = default;
    void computeBins(ConstBgrView image) noexcept;
    void computeReference() noexcept;
    void computeScores() noexcept;
    void scanColumns() noexcept;
    void fillSectors(ObstacleSectors& out) noexcept;
    /// Ground point of pixel (x, y): false when the ray does not meet the ground within maxRangeM.
    bool groundPoint(double x, double y, double& rangeM, double& bearingDeg) const noexcept;

    ColourFreeSpaceConfig config_;
    cv::Size size_;
    RectifiedProjection projection_;
    GroundPlane ground_;
    float hfovDeg_ = 0.0F;
    int roiTop_ = 0;
    int binTop_ = 0;
    int thresholdScore_ = 0; ///< matchThreshold on the 0..255 scale
    int selfScore_ = 0;      ///< patchSelfMatch on the 0..255 scale
    Image<std::uint8_t> bins_;
    Image<std::uint8_t> scores_;
    std::vector<std::int16_t> colHist_; ///< width x kColourBins, vertical window histograms of the current row
    std::array<std::int16_t, kColourBins> ref_{};
    std::vector<float> columnRange_;      ///< [m]
    std::vector<float> columnBearing_;    ///< [deg]
    std::vector<std::uint8_t> columnHit_; ///< 1: run ended at an obstacle; 0: reached the top
    std::vector<int> topRow_;             ///< per column: first ROI row whose ground point is within maxRangeM
    std::vector<std::uint16_t> rowSum_;   ///< 3 x width vertical 3-row sums of B, G, R (blur)
    std::array<std::int32_t, kColourBins> patchCounts_{};
    ColourReference reference_;
};

} // namespace ugv::vision
