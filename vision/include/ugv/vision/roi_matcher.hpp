#pragma once

/// @file
/// Dense disparity of the rectified region of interest (the ROI rows, which include a margin of rows above
/// for the block), created once at configure: our census SGM (census_sgm.hpp, the default) or OpenCV's
/// StereoSGBM in one of its modes.
///
/// Allocation: the census SGM allocates nothing per frame. cv::StereoSGBM::compute() in OpenCV 4.6
/// allocates internally on every call (its cost/path buffers, and in SGBM_3WAY/HH4 per-stripe buffers)
/// although our output Mats are preallocated and reused; the count is measured by unit-vision-detect test
/// `RoiMatcher.AllocationsPerMatch` and printed. With an OpenCV mode, mitigation: one thread
/// (`cv::setNumThreads(1)`, called by create()); glibc keeps the freed blocks (the service sets
/// M_TRIM_THRESHOLD/M_MMAP_MAX at start), so after warm-up the calls reuse the same heap memory.

#include <cstdint>
#include <optional>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/census_sgm.hpp"
#include "ugv/vision/matcher_mode.hpp"
#include "ugv/vision/stage_times.hpp"

namespace ugv::vision {

struct RoiMatcherConfig {
    MatcherMode mode = MatcherMode::CensusSgm;
    int numDisparities = 128;    ///< [px] search range, multiple of 16
    int blockSize = 5;           ///< [px] OpenCV modes: odd, 1..11; P1 = 8 bs^2, P2 = 32 bs^2 (OpenCV's advice)
    int uniquenessRatio = 10;    ///< [%] best cost must beat the second best by this margin, else invalid
    int speckleWindowSize = 100; ///< [px] connected regions smaller than this are invalidated; 0 disables
    int speckleRange = 2;        ///< [px] maximum disparity step within a speckle region
    int disp12MaxDiff = 1;       ///< [px] left-right consistency tolerance; < 0 disables the check
    int preFilterCap = 63;       ///< clip of the x-derivative prefilter
    /// Pad both images on the left by numDisparities columns (zeros) so that the leftmost columns get a
    /// disparity wherever their match lies inside the right image (OpenCV leaves columns < numDisparities
    /// invalid, i.e. bearings above ~19 deg for the default rig). Off by default: measured on simulator ground,
    /// the padded columns are biased (mean error over the ROI -0.12 -> -0.5 px, bad-1px +1 %), which would
    /// show as false negative obstacles; it also costs (width + numDisparities) / width of the matching time.
    bool padLeft = false;
    /// Census SGM: the top path follows the ground given by setGroundPrior (ObstacleDetector passes the
    /// configured ground, then each frame's estimate). Off by default. Measured (`ugvsense eval --sim
    /// --frames-per-case 3 --ground-prior`): the matcher's error on simulator ground goes from -0.15 px near and
    /// -0.5 px at 8-16 m to within +-0.05 px (-0.17 px at the horizon band), and a 1 m hole at 6-10 m is detected
    /// in 50 % of frames instead of 22 %; but the far-range thresholds of the sector builder were tuned on the
    /// biased matcher, and with it curbs and trenches at 6-10 m fall out of the range tolerance (p95 in tolerance
    /// 94 -> 83 % and 88 -> 77 %). On once those thresholds are tuned again.
    bool groundPrior = false;
    /// Census SGM: ground-guided disparity ranges (CensusSgm::setSearchFloor). From the previous frame's reliable
    /// ground estimate, ObstacleDetector makes row y search only d >= s g(y) - m, rounded down to a multiple of 16,
    /// where g(y) is the ground's smallest disparity on that row, s = h / (h + groundRangeDropM) with h the
    /// estimate's camera height, and m = (B / h) (fx + width / 2) tan(groundRangeMarginDeg); the full range when
    /// the estimate is unreliable (the configured-ground fallback) or absent (the first frame). The upper end
    /// stays numDisparities - 1: an obstacle as tall as the camera can stand at any range short of the ground
    /// point, so nothing bounds it honestly.
    /// Geometry: on a row below the horizon the ray meets the ground at g; anything the row shows nearer than that
    /// point has d >= g (an obstacle standing on the ground in front, overhangs), so what d < g shows lies beyond
    /// the ground's intersection, visible only where the ground is not where the plane says: a drop or hole (a
    /// point D below the plane appears at g h / (h + D)), ground that falls away (a crest, a downhill), a
    /// reflection in a puddle, or a plane that is off (the vehicle pitched or rolled since the previous frame).
    /// A far object's top cannot appear in such a row over intact flat ground (the ray meets the ground first).
    /// What the cut loses: drops deeper than groundRangeDropM (their pixels read at the floor, i.e. at least that
    /// deep, or invalid, not at their true depth), ground beyond a crest or downhill that falls further than that,
    /// and, when the ground pitches or rolls by more than groundRangeMarginDeg between two frames, the rows where
    /// the ground itself falls below the floor (mismatched for one frame: the estimate of that frame then falls
    /// back, and the next frame searches the full range). The uniqueness test also sees only the searched
    /// disparities, so a repetitive texture whose second match lies below the floor is no longer rejected.
    /// Off by default: measured (vision/README.md, "Ground-guided disparity ranges"), it removes 15 % of the cost
    /// cells on the simulator rig and 8 % on the KITTI pairs, but only about 4 % of the matcher's instructions
    /// (whole 32-disparity blocks, per-column work), 3-7 % of the pipeline's time, while the simulator suite
    /// reports a little more Clear in front of a fence at 1-3 m; real pairs: one sector more correct.
    bool groundRange = false;
    /// Census SGM: the bottom rows of the ROI, where the ground is near and disparities are large, matched at half
    /// resolution (even; 0: none). The pair's rows [H - rows - kHalfOverlapRows, H) are averaged 2 x 2, matched with
    /// numDisparities / 2, and each disparity is written twice as large to the 2 x 2 pixels it covers of rows
    /// [H - rows, H); the rows above are matched at full resolution over [0, H - rows + kHalfOverlapRows) and
    /// their top H - rows kept (the overlaps give both parts their census and path context at the seam). A quarter
    /// of the pixels and half the disparities: about 1/8 of the matching work in those rows, where a disparity
    /// step of 1/16 half-resolution pixel is still under 0.5 % of the range. ObstacleDetector sets it from
    /// DetectorConfig::halfResolutionMinGroundPx. Needs numDisparities a multiple of 32 and no padLeft.
    int halfResolutionRows = 0;
    double groundRangeDropM = 0.3;     ///< [m] deepest drop below the ground plane seen at its true depth
    double groundRangeMarginDeg = 1.5; ///< [deg] pitch and roll change between two frames that the floor absorbs
    /// Census SGM settings (penalties, paths, intensity term); its numDisparities, uniquenessRatio,
    /// disp12MaxDiff and speckle fields are taken from the fields above.
    CensusSgmConfig census;
};

/// Outcome of RoiMatcher::match; no strings on the frame path.
enum class MatchStatus : std::uint8_t {
    Ok,
    WrongInputSize, ///< an input view is empty or not roiSize (disparity set to invalid)
    OpenCvFailed,   ///< StereoSGBM threw despite the checked preconditions (disparity set to invalid)
    MatcherFailed,  ///< the census SGM refused its buffers (not reachable after create; disparity invalid)
};

/// Semi-global matching of the ROI of a rectified pair into a preallocated CV_16S disparity (x16 fixed point,
/// kScale; invalid pixels < 0).
/// Thread-safety: thread-bound (match() writes the internal buffers). RT-safe: match() no allocation and no
/// exception with the census SGM; with an OpenCV mode, OpenCV allocates inside compute() (see the file
/// comment); create() no.
class RoiMatcher {
public:
    static constexpr int kScale = 16;          ///< fixed-point scale of disparity16()
    static constexpr int kHalfOverlapRows = 8; ///< [px] seam overlap of the two parts (halfResolutionRows)

    /// Validates the config, creates the StereoSGBM and allocates all buffers for images of `roiSize`.
    /// @return the matcher, or an error naming the invalid field.
    static Result<RoiMatcher, Error> create(const RoiMatcherConfig& config, cv::Size roiSize);

    /// Computes the disparity of `left` (reference) against `right`.
    /// @param[in] left, right  rectified ROI images, roiSize each, 8-bit grey
    /// @param[out] times        when given, the time of each stage is added (MatchOther, and Census .. Speckle of
    ///                          the census matcher)
    /// @return Ok, or why the disparity is all invalid.
    MatchStatus match(ConstImageViewU8 left, ConstImageViewU8 right, VisionStageTimes* times = nullptr) noexcept;

    /// Disparity of the last match, roiSize CV_16S, d * kScale with sub-pixel bits; invalid < 0. A header view
    /// into the internal (padded) buffer: valid until the next match().
    [[nodiscard]] const cv::Mat& disparity16() const noexcept { return disp16_; }
    [[nodiscard]] ImageView<const std::int16_t> disparityView() const noexcept;

    /// Float disparity [px] of the last match into a caller-preallocated roiSize CV_32F `out`; invalid = -1.
    /// @return false (out untouched) when out has the wrong size or type.
    bool toFloat(cv::Mat& out) const noexcept;

    /// The ground's disparity d = a x + b y + c [px] in ROI coordinates, for the census SGM's top path (see
    /// CensusSgm::setGroundPrior) when config.groundPrior is set; ignored otherwise and by the OpenCV modes.
    /// RT-safe; takes effect from the next match().
    void setGroundPrior(double a, double b, double c) noexcept;

    /// The census SGM's search floor d >= a x + b y + c [px] in ROI coordinates (CensusSgm::setSearchFloor) when
    /// config.groundRange is set; ignored otherwise and by the OpenCV modes. RT-safe; takes effect from the next
    /// match().
    void setSearchFloor(double a, double b, double c) noexcept;
    /// The full range from the next match() on. RT-safe.
    void clearSearchFloor() noexcept;
    /// Cost cells searched by the last match() over those of the full range (1 with an OpenCV mode).
    [[nodiscard]] double searchedFraction() const noexcept;

    [[nodiscard]] cv::Size roiSize() const noexcept { return roiSize_; }
    [[nodiscard]] const RoiMatcherConfig& config() const noexcept { return config_; }

private:
    RoiMatcher() = default;
    using PlaneSetter = void (CensusSgm::*)(double, double, double) noexcept;
    /// Calls `set` of the census matchers with the plane a x + b y + c of ROI coordinates in each one's own: padded
    /// columns at full resolution, the half-resolution rows' pixels. Needs census_.
    void givePlane(PlaneSetter set, double a, double b, double c) noexcept;

    RoiMatcherConfig config_;
    cv::Size roiSize_;
    int pad_ = 0;                     ///< [px] left padding columns
    cv::Ptr<cv::StereoSGBM> sgbm_;    ///< OpenCV modes
    std::optional<CensusSgm> census_; ///< MatcherMode::CensusSgm (the full-resolution rows)
    /// halfResolutionRows: the near rows' matcher, their 2 x 2 averaged images and disparity.
    std::optional<CensusSgm> halfCensus_;
    cv::Mat halfLeft_, halfRight_, halfDisp16_;
    int fullRows_ = 0; ///< [px] rows matched at full resolution (with the seam overlap)
    int halfTop_ = 0;  ///< [px] the first ROI row of the half-resolution images
    /// The census matchers of the full- and (halfResolutionRows) the half-resolution rows with their buffers.
    std::optional<Error> createCensus(cv::Size padded);
    /// The half-resolution rows: average, match and write back; false when the matcher refused its buffers.
    bool matchHalf(ConstImageViewU8 left, ConstImageViewU8 right, VisionStageTimes* times) noexcept;
    /// The half-resolution disparity into the bottom halfResolutionRows rows of the output.
    void upsampleHalf() noexcept;
    cv::Mat padLeft_, padRight_; ///< CV_8U (width + pad) x height; pad columns stay 0
    cv::Mat disp16Padded_;       ///< CV_16S (width + pad) x height, compute() output
    cv::Mat disp16_;             ///< header view of the unpadded columns
};

} // namespace ugv::vision
