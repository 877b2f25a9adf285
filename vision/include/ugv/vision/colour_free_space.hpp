#pragma once

/// @file
/// Single-camera colour free space: "the ground looks like the ground just in front of the vehicle".
///
/// From one BGR image: 3x3 box blur, then one colour bin per pixel: a chromatic pixel (max - min of B, G, R at
/// least kGreyChroma) by hue and saturation (kHueBins x kSatBins, OpenCV's HSV scales), an achromatic one by its
/// brightness (kGreyBins), so that grey ground (asphalt, concrete) has colours too; hue is noise below that chroma
/// whatever the brightness. The ground's colours are learnt from the reference band, the bottom bandRows rows over
/// the whole width, cut into bandSlices column slices: a bin is a ground colour when it holds at least
/// minColourShare of the pixels of at least minSliceFraction of the slices. A colour seen along half the band is
/// ground; an obstacle standing in a smaller part of it (a post, a parked car at the side) is not, and neither are
/// the few pixels of noise in stray bins. A hue one bin from a ground colour's (same saturation) is ground too: bin
/// edges are arbitrary, and a ground whose hue drifts across one must not become an obstacle there. Every ROI pixel's
/// (2 radius + 1)^2 window scores the share of its pixels with ground colours (a running box sum: O(1) per pixel); the
/// window is free when that share reaches matchThreshold, i.e. when most of it looks like ground however the ground's
/// colours mix (a lawn drifting between lush and dry stays free as long as both were seen in the band). Then each
/// column is scanned upwards from the bottom to the first non-free run; that row's ground point (ray of the pixel meets
/// the ground plane) gives the free range and bearing, and each sector takes the minimum over its columns.
///
/// Sector states: Obstacle (kind Positive) when a column's free run ends inside the ROI; Clear when every column of
/// the sector reaches the ROI top (or the horizon, i.e. maxRangeM) beyond the caution distance and none of them does
/// so mostly through tentative colours (present in fewer than clearSliceFraction of the slices) or with ground colours
/// going on above the horizon, where no ground can be seen (an obstacle filling the view); Unknown when the
/// band is not ground-like (too dark for colour to mean anything, or less than minGroundCoverage of it in ground
/// colours: the band is mostly obstacle or clutter) or the free run reaches the ROI top short of the caution
/// distance. Output sectors are marked `degraded` (a single-camera mode) and carry heightM 0.
///
/// Limits, by design of a colour cue: an obstacle in the ground's own colours is not seen; one across most of the band
/// (nearer than the band's far edge, about 1.6 m on the default rig) becomes ground: not seen as an obstacle either,
/// but its sectors are Clear only if it is in three quarters of the band's slices and lower than the horizon.

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
#include "ugv/vision/sector_builder.hpp"

namespace ugv::vision {

inline constexpr int kHueBins = 16;                            ///< over OpenCV hue 0..179
inline constexpr int kSatBins = 7;                             ///< over saturation 0..255
inline constexpr int kGreyBins = 16;                           ///< over brightness 0..255
inline constexpr int kChromaticBins = kHueBins * kSatBins;     ///< bin = hueBin * kSatBins + satBin
inline constexpr int kColourBins = kChromaticBins + kGreyBins; ///< grey bins follow: kChromaticBins + value / 16
inline constexpr int kGreyChroma = 16; ///< max - min of B, G, R (after the blur) below which a pixel is grey

struct ColourFreeSpaceConfig {
    double roiTopFraction = 0.5;   ///< first analysed row = round(height * roiTopFraction)
    int bandRows = 40;             ///< [px] reference band: the bottom rows of the image, the whole width
    int bandSlices = 8;            ///< column slices of the band, 2..32
    double minColourShare = 0.02;  ///< a bin is present in a slice holding at least this share of its pixels
    double minSliceFraction = 0.5; ///< a ground colour is present in at least this fraction of the slices
    /// A ground colour present in fewer slices than this fraction is tentative: a column whose free run is mostly of
    /// tentative colours may end at an obstacle but never makes its sector Clear (Unknown instead). An obstacle a third
    /// of the image wide standing over the band (nearer than its far edge) is in half the slices; no ground is Clear
    /// on that evidence. In [minSliceFraction, 1].
    double clearSliceFraction = 0.75;
    double minGroundCoverage = 0.5; ///< share of the band in ground colours below which it is not ground-like
    double minBandValue = 30.0;     ///< mean brightness (0..255) of the band below which colour is noise
    int windowRadius = 7;           ///< [px] comparison window (2 r + 1)^2, r in [1, 15]
    double matchThreshold = 0.5;    ///< share of a window's pixels in ground colours >= this => free, in (0, 1]
    int minObstacleRows = 3;        ///< [px] consecutive non-free rows that end a column's free run
    double maxRangeM = 50.0;        ///< [m] rows farther than this count as the horizon (end of the scan)
    int sectorCount = 64;           ///< sectors over the horizontal field of view, 1..kMaxSectors
    float dangerDistanceM = 1.5F;   ///< [m] classify(): Red below
    float cautionDistanceM = 5.0F;  ///< [m] classify(): Blue below; a free run must reach this to be Clear
};

/// The default config with a stereo detector's sector count and danger distances, so that the two modes' sectors
/// line up (same bins over the same field of view) and are classified alike.
ColourFreeSpaceConfig colourConfigFor(const SectorBuilderConfig& sectors) noexcept;

/// Outcome of ColourFreeSpace::process; no strings on the frame path.
enum class ColourFreeSpaceStatus : std::uint8_t {
    Ok,             ///< sectors written (possibly all Unknown: see reference())
    WrongInputSize, ///< the image is not the configured size; sectors set to all Unknown
};

/// What the last frame's reference band taught.
struct ColourReference {
    double meanValue = 0.0;  ///< 0..255, the band's mean brightness after the blur
    double coverage = 0.0;   ///< share of the band's pixels in ground colours
    int groundColours = 0;   ///< bins found to be ground colours
    bool groundLike = false; ///< meanValue >= minBandValue and coverage >= minGroundCoverage
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
    /// The same on a grey image (a monochrome camera): every pixel is binned by its brightness, so the ground is
    /// told from obstacles by grey level alone. Bit-identical to process() on the image with B = G = R.
    ColourFreeSpaceStatus process(ConstImageViewU8 grey, ObstacleSectors& out) noexcept;

    /// Last frame's reference band statistics.
    [[nodiscard]] const ColourReference& reference() const noexcept { return reference_; }
    /// Colour bin of every pixel of rows [binTop(), height) (after the blur).
    [[nodiscard]] ConstImageViewU8 bins() const noexcept { return bins_.view(); }
    [[nodiscard]] int binTop() const noexcept { return binTop_; }
    /// Window score 0..255 (= round(255 * share of ground-coloured pixels)) of rows [roiTop(), height); border rows
    /// and columns where the window does not fit copy the nearest computed score.
    [[nodiscard]] ConstImageViewU8 scores() const noexcept { return scores_.view(); }
    [[nodiscard]] int roiTop() const noexcept { return roiTop_; }
    /// Last frame's ground colours: 1 for a bin learnt as ground, 0 otherwise.
    [[nodiscard]] const std::array<std::uint8_t, kColourBins>& groundColours() const noexcept { return groundColour_; }
    /// Last frame's free range [m] of each column: to the end of its free run, or to the top of the scan (ROI top or
    /// horizon) when columnHit() is 0; 0 when the column sees no ground.
    [[nodiscard]] const std::vector<float>& columnRangeM() const noexcept { return columnRange_; }
    [[nodiscard]] const std::vector<std::uint8_t>& columnHit() const noexcept { return columnHit_; }
    /// 1 for a column whose free run reached the top on evidence that does not make its sector Clear: mostly through
    /// tentative ground colours, or with ground colours going on above the horizon (no ground is seen there: the
    /// "ground" is a surface standing in front of the camera).
    [[nodiscard]] const std::vector<std::uint8_t>& columnUnsure() const noexcept { return columnUnsure_; }

private:
    ColourFreeSpace() = default;
    template <class Pixel>
    ColourFreeSpaceStatus processImage(ImageView<const Pixel> image, ObstacleSectors& out) noexcept;
    template <class Pixel>
    void computeBins(ImageView<const Pixel> image) noexcept;
    void computeReference() noexcept;
    void computeScores() noexcept;
    void scanColumns() noexcept;
    void fillSectors(ObstacleSectors& out) noexcept;
    /// Per column, the pixels with tentative ground colours from its top row down (row by row; nothing to count, and
    /// all 0, when every ground colour is sure).
    void countTentative() noexcept;
    /// More than half of the window's height of rows just above column x's horizon have ground colours.
    [[nodiscard]] bool aboveHorizonIsGround(int x) const noexcept;
    /// Ground point of pixel (x, y): false when the ray does not meet the ground within maxRangeM.
    bool groundPoint(double x, double y, double& rangeM, double& bearingDeg) const noexcept;
    /// The same within maxRangeM (infinity: wherever the ray meets the ground).
    bool groundPoint(double x, double y, double& rangeM, double& bearingDeg, double maxRangeM) const noexcept;

    ColourFreeSpaceConfig config_;
    cv::Size size_;
    RectifiedProjection projection_;
    GroundPlane ground_;
    float hfovDeg_ = 0.0F;
    int roiTop_ = 0;
    int binTop_ = 0;
    int thresholdScore_ = 0; ///< matchThreshold on the 0..255 scale
    Image<std::uint8_t> bins_;
    Image<std::uint8_t> scores_;
    std::vector<std::int16_t> colSum_;                     ///< per column: ground pixels of the window's rows
    std::vector<std::int32_t> sliceCounts_;                ///< bandSlices x kColourBins, the band's histograms
    std::array<std::uint8_t, kColourBins> learnt_{};       ///< 2: a sure colour of the band, 1: tentative, 0: none
    std::array<std::uint8_t, kColourBins> groundColour_{}; ///< 1: a ground colour (learnt, or next to one)
    std::array<std::uint8_t, kColourBins> tentative_{};    ///< 1: a ground colour only tentatively
    std::vector<float> columnRange_;                       ///< [m]
    std::vector<float> columnBearing_;                     ///< [deg]
    std::vector<std::uint8_t> columnHit_;                  ///< 1: run ended at an obstacle; 0: reached the top
    std::vector<std::uint8_t> columnUnsure_;               ///< 1: reached the top, but not on evidence of Clear
    std::vector<std::int16_t> tentativeCount_;             ///< per column: see countTentative()
    std::vector<int> horizonRow_;                          ///< per column: first row whose ray meets the ground
    std::vector<int> topRow_;           ///< per column: first ROI row whose ground point is within maxRangeM
    std::vector<std::uint16_t> rowSum_; ///< 3 x width vertical 3-row sums of B, G, R (or 1 x width: grey) (blur)
    std::int64_t bandValueSum_ = 0;
    ColourReference reference_;
};

} // namespace ugv::vision
