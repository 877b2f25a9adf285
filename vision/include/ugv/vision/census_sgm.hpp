#pragma once

/// @file
/// Our own semi-global matcher: centre-symmetric census 9x7 (31 bits), Hamming cost plus a clipped intensity
/// difference, two, three or five
/// aggregation paths in one pass over the rows (left-to-right, right-to-left, optionally top, top-left and
/// top-right), winner-take-all with a uniqueness test, parabolic sub-pixel, OpenCV's left-right
/// check and speckle filter. Every buffer is allocated by create(); match() allocates nothing, which
/// cv::StereoSGBM cannot do (it allocates inside compute() on every call).
///
/// Output convention: CV_16S, d * 16, invalid = -16; columns x < numDisparities - 1 (whose search range
/// leaves the right image) are invalid, as in OpenCV.
///
/// Optionally each row searches only [floor(y), numDisparities) (setSearchFloor: ground-guided ranges); the
/// buffers keep the full range's layout, and the kernels run over the searched 16-disparity blocks only.
///
/// Vectorised with OpenCV universal intrinsics (census_sgm.simd.hpp); a scalar reference (config.simd = false)
/// gives bit-identical results (test unit-vision-detect CensusSgm.SimdMatchesScalar).

#include <cstddef>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/stage_times.hpp"

namespace ugv::vision {

struct CensusSgmConfig {
    int numDisparities = 128; ///< [px] multiple of 16
    /// Penalties tuned on `ugvsense eval --sim` (6/90 against 10/120 and 14/150: table-leg range and hole
    /// detection better, curbs alike; all three beat OpenCV's default SGBM on Middlebury).
    int p1 = 6;  ///< penalty of a 1 px disparity step, cost units (census 0..31 per pixel)
    int p2 = 90; ///< penalty of a larger step; p1 < p2 <= 254 - 31 - intensityClip (8-bit paths)
    /// Intensity term of the cost: min(|left/4 - right/4|, intensityClip), added to the census Hamming
    /// distance (0..31); 0 disables it. It gives the cost a slope between census steps: sub-pixel error on
    /// simulator ground and poles is smaller with it (measured, pixels within 0.25 px: ground 41 -> 46 %, a pole
    /// at 6 m 69 -> 76 %; OpenCV's SGBM_3WAY: 49 % and 99.7 %, its parabola fits its block costs better).
    int intensityClip = 15;
    int uniquenessRatio = 10;    ///< [%] second best (outside best +-1) must exceed best by this margin
    int disp12MaxDiff = 1;       ///< [px] left-right tolerance; < 0 disables the check
    int speckleWindowSize = 100; ///< [px] regions smaller than this are invalidated; 0 disables
    int speckleRange = 2;        ///< [px] disparity step inside a speckle region
    /// 2: left-to-right and right-to-left; 3: and top (the default); 5: and the two top diagonals (MODE_SGBM's
    /// directions). Every top-down path lags on ground whose disparity grows down the image: measured on
    /// simulator ground, mean error -0.25 px with 3 paths, -0.86 px with 5, +0.06 px with 2; but 2 paths
    /// streak across thin legs and doorways (eval --sim), so 3 is the default.
    int paths = 3;
    /// [px] With a ground prior (setGroundPrior), the top path follows the ground's disparity step from one row to
    /// the next at columns whose winner in the row above lies within this of the ground (see setGroundPrior).
    double groundPriorTolerancePx = 1.0;
    bool simd = true; ///< false: the scalar reference (tests)
};

/// Thread-safety: thread-bound. RT-safe: match() allocates nothing, takes no lock, throws nothing; create() no.
class CensusSgm {
public:
    static constexpr int kScale = 16;
    static constexpr std::int16_t kInvalid = -kScale;
    static constexpr int kCensusBits = 31;

    /// Validates the config and allocates every buffer for images of `size`.
    /// @return the matcher, or an error naming the invalid field and its valid range.
    static Result<CensusSgm, Error> create(const CensusSgmConfig& config, cv::Size size);

    /// Disparity of `left` (reference) against `right` into `disp16` (size, CV_16S, caller-owned).
    /// @param[out] times  when given, the time of each of its stages is added (Census .. Speckle)
    /// @return false (nothing written) when a view or disp16 has the wrong size or type.
    bool match(ConstImageViewU8 left, ConstImageViewU8 right, cv::Mat& disp16,
               VisionStageTimes* times = nullptr) noexcept;

    /// The ground's disparity in this matcher's image coordinates, d = a x + b y + c [px]. The top path lags on a
    /// surface whose disparity grows down the image: its smoothness penalty favours the row above's disparity, so
    /// on simulator ground the matcher reads 0.15 px low near and up to 0.5 px low at 8-16 m. With the prior, at a
    /// column whose winner in the row above lies on the ground (within groundPriorTolerancePx), the top path
    /// continues that row's disparity plus the ground's step (0 or 1 px, rounding b y); elsewhere (obstacle
    /// faces, constant disparity) it is unchanged. RT-safe (no allocation); takes effect from the next match().
    /// Non-finite values (or |b| > 4 px per row) turn the prior off: the plain top path.
    void setGroundPrior(double a, double b, double c) noexcept;

    /// Ground-guided search ranges: row y searches only the disparities d >= floor(y), where floor(y) is the
    /// smallest value over the matched columns of f(x, y) = a x + b y + c [px], rounded down to a multiple of 16
    /// (the kernels' block) and at most numDisparities - 16; rows where f <= 0 search the full range. The caller
    /// derives f from the ground (ObstacleDetector: RoiMatcherConfig::groundRange). Path costs of the disparities
    /// a row does not search count as saturated (255) for the next row's top paths; the winner, uniqueness test,
    /// sub-pixel fit and left-right check see only the searched disparities, so a point whose disparity lies
    /// below the floor is reported at the floor or invalid. RT-safe; takes effect from the next match().
    /// Non-finite values clear the floor (the full range).
    void setSearchFloor(double a, double b, double c) noexcept;
    /// The full range in every row from the next match() on.
    void clearSearchFloor() noexcept { searchFloor_ = false; }
    /// Cost cells (columns x disparities) searched by the last match() over those of the full range: 1 without a
    /// floor.
    [[nodiscard]] double searchedFraction() const noexcept { return searchedFraction_; }

    [[nodiscard]] cv::Size size() const noexcept { return {width_, height_}; }
    [[nodiscard]] const CensusSgmConfig& config() const noexcept { return config_; }

private:
    CensusSgm() = default;

    void census(ConstImageViewU8 image, std::uint8_t* planes, bool reversed) noexcept;
    void searchRanges() noexcept;
    void costRow(int y) noexcept;
    void aggregateRow(std::int16_t* disp, const std::int16_t* above, int y) noexcept;
    struct RowRange;
    /// Left-to-right, top, top-left and top-right paths of the row; their sum into sum_.
    void forwardPaths(RowRange range, const std::int16_t* above, int y) noexcept;
    /// Right-to-left path: completes each column's sum, then the winner of that column.
    void backwardPaths(RowRange range, std::int16_t* disp) noexcept;
    void winner(int i, int lo, std::uint16_t minSum, std::int16_t* disp) noexcept;
    void leftRightCheck(std::int16_t* disp) const noexcept;
    [[nodiscard]] std::uint8_t* pathEntry(int half, int path, int entry) noexcept;
    /// Index of a path entry in pathMin_ (and, times stride_, in paths_).
    [[nodiscard]] std::size_t entryIndex(int half, int path, int entry) const noexcept;
    /// The left-to-right or right-to-left path's entry at column i (two entries, alternating).
    [[nodiscard]] std::uint8_t* horizontalEntry(int i) noexcept;

    CensusSgmConfig config_;
    int width_ = 0;
    int height_ = 0;
    int d_ = 0;      ///< numDisparities
    int x0_ = 0;     ///< first column with a full search range (d_ - 1)
    int cols_ = 0;   ///< width_ - x0_: columns matched
    int stride_ = 0; ///< bytes per path entry: d_ plus 16 pad bytes each side (pads hold 255)

    std::vector<std::uint8_t> padded_;      ///< (height + 6) x (width + 8) replicate-bordered input
    std::vector<std::uint8_t> censusRow_;   ///< 4 planes of one row before they are stored (maybe reversed)
    std::vector<std::uint8_t> leftCensus_;  ///< 5 byte planes per row (census 4, intensity 1): [y][plane][x]
    std::vector<std::uint8_t> rightCensus_; ///< same, columns reversed (x -> width - 1 - x)
    std::vector<std::uint8_t> cost_;        ///< cols x d: cost of the current row (cols x n when ranged)
    std::vector<std::uint8_t> paths_;       ///< prev/cur rows of the top, top-left, top-right paths
    std::vector<std::uint8_t> pathMin_;     ///< min over d of each entry in paths_
    std::vector<std::uint8_t> horizontal_;  ///< border + two entries: left-to-right and right-to-left path
    std::vector<std::uint8_t> zeros_;       ///< d zeros: the top path's term of the sum with 2 paths
    std::vector<std::uint16_t> sum_;        ///< cols x d: sum of the five paths (cols x n when ranged)
    std::vector<std::uint16_t> disp2Cost_;  ///< width: best cost seen for each right-image column
    std::vector<std::int16_t> disp2_;       ///< width: its disparity (left-right check)
    std::vector<int> rowLo_;                ///< height: first disparity searched in each row (setSearchFloor)
    cv::Mat speckleBuffer_;                 ///< cv::filterSpeckles work buffer, sized once
    int parity_ = 0;                        ///< which half of paths_ is the previous row
    bool groundPrior_ = false;              ///< setGroundPrior() was called
    double groundA_ = 0.0;                  ///< the prior: d = a x + b y + c [px]
    double groundB_ = 0.0;
    double groundC_ = 0.0;
    bool searchFloor_ = false; ///< setSearchFloor() was called with finite values
    double floorA_ = 0.0;      ///< the floor: d = a x + b y + c [px]
    double floorB_ = 0.0;
    double floorC_ = 0.0;
    double searchedFraction_ = 1.0;
};

} // namespace ugv::vision
