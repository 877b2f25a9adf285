#pragma once

/// @file
/// `ugvsense eval --real DIR`: obstacle sectors scored against real stereo pairs with ground truth
/// (../shared/data/real-stereo, its README and index.csv: KITTI's LiDAR truth as 16-bit PNG, Middlebury's structured
/// light as PFM with the pair's doffs; totals per data set too). The truth of a pair: its GT disparity in the rows
/// the detector analyses becomes 3-D points, a RANSAC road plane is fitted to the GT of the bottom third
/// (fitGround), and per sector the nearest range of the points 0.25-2.5 m above that plane within 25 m is the
/// obstacle (the 5th nearest point: robust to a few stray ones), the nearest of those 0.10 m or more above it the
/// kerb. A sector whose columns have GT on under 30 % of the analysed pixels is not scored.
/// Scoring per sector (scoreRealSector): a reported obstacle within max(1 m, 10 %) of the truth, or of the kerb,
/// is correct; nearer is too near; farther, Clear or Unknown is missed; an obstacle reported where the truth has
/// none (and no kerb at that range) is false.
/// With `colour`, the one-camera mode on the left colour image is scored by the same rules beside them.
/// The baseline in the same run: OpenCV StereoSGBM (128 disparities, block 5) on the full frame, its own RANSAC
/// ground (fitGround) and a 0.25 m height threshold, through the same per-sector rule as the truth.
/// Host tool only (allocates). Thread-safety: reentrant.

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "ugv/platform/error.hpp"
#include "ugv/platform/obstacle_sectors.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/tool/real_conditions.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/sector_builder.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::tool {

/// The scoring's constants (the definition; the same for every data set).
struct RealScoringRules {
    double obstacleMinHeightM = 0.25; ///< [m] GT obstacle points are this high above the road ...
    double obstacleMaxHeightM = 2.5;  ///< [m] ... and no higher (bridges, tree tops)
    double kerbMinHeightM = 0.10;     ///< [m] a report at the nearest point this high is a kerb, also correct
    double dropMinDepthM = 0.25;      ///< [m] GT points this far below the road are a drop in the truth
    double maxRangeM = 25.0;          ///< [m] horizontal range scored
    int minPoints = 5;                ///< the nearest range is that of the minPoints-th nearest point
    double minCoverage = 0.30;        ///< GT pixels / analysed pixels of a sector's columns, to be scored
    double toleranceM = 1.0;          ///< [m] a range is right within max(toleranceM, toleranceFraction r)
    double toleranceFraction = 0.10;
};

/// What a sector holds by a point set (GT or the baseline's), relative to a road plane.
struct SectorTruth {
    double coverage = 0.0;  ///< GT pixels / analysed pixels of the sector's columns
    bool scored = false;    ///< coverage >= minCoverage
    int obstaclePoints = 0; ///< points 0.25-2.5 m high within 27.5 m (see obstacleRangeM)
    /// [m] robust nearest of those, kNoRange when < minPoints; looked for out to the horizon plus its tolerance
    /// (27.5 m), so that a report at 26 m of a wall at 26 m is not false, but only a range within the horizon
    /// makes the sector an obstacle sector (hasObstacle)
    double obstacleRangeM = kNoRange;
    double kerbRangeM = kNoRange; ///< [m] the same for points >= 0.10 m high
    double horizonM = 25.0;       ///< [m] RealScoringRules::maxRangeM
    int dropPoints = 0;           ///< points >= 0.25 m below the road within 25 m
    [[nodiscard]] bool hasObstacle() const { return obstacleRangeM <= horizonM; }
    [[nodiscard]] bool seesObstacle() const { return obstacleRangeM < kNoRange; } ///< within the horizon's tolerance
    static constexpr double kNoRange = 1e9;
};

/// A disparity map's points in one sector layout.
/// @param[in] disparity   CV_32F [px], invalid <= 0, full frame
/// @param[in] firstRow    first analysed row (the detector's ROI rows below its margin)
/// @param[in] road        the road plane the heights are measured from
/// @param[in] layout      the sectors' bearings (the detector's)
std::vector<SectorTruth> sectorTruth(const cv::Mat& disparity, int firstRow, const vision::GroundPlane& road,
                                     const vision::RectifiedProjection& projection, const ObstacleSectors& layout,
                                     const RealScoringRules& rules);

enum class RealOutcome {
    NotScored, ///< too little GT in the sector
    Correct,   ///< obstacle reported at the truth's range (or at the kerb's)
    TooNear,   ///< obstacle reported nearer than the truth's range (or where there is none, nearer than 25 m)
    Missed,    ///< truth has an obstacle; Clear, Unknown or reported too far
    False,     ///< obstacle reported where the truth has none
    FreeOk,    ///< truth has none and none is reported (or the report is a kerb)
};

/// @param reported  the sector as reported (Obstacle with its range, or Clear / Unknown)
RealOutcome scoreRealSector(const SectorTruth& truth, const Sector& reported, const RealScoringRules& rules);

/// Totals of one detector over pairs.
struct RealTally {
    int scored = 0;                   ///< scored sectors
    int gtObstacle = 0;               ///< scored sectors whose truth has an obstacle
    int correct = 0;                  ///< of those
    int missed = 0;                   ///< of those
    int tooNear = 0;                  ///< of those
    int falseSectors = 0;             ///< scored sectors without GT obstacle, reported Obstacle
    int negativeNoDrop = 0;           ///< Negative sectors (any, scored or not) on pairs whose truth has no drop
    std::vector<double> rangeErrorsM; ///< |reported - truth| of the correct sectors
    void add(RealOutcome outcome, const SectorTruth& truth, const Sector& reported);
    void merge(const RealTally& other);
    [[nodiscard]] double correctRate() const
    {
        return gtObstacle > 0 ? static_cast<double>(correct) / gtObstacle : 0.0;
    }
    [[nodiscard]] double wrongRate() const
    {
        return scored > 0 ? static_cast<double>(tooNear + falseSectors) / scored : 0.0;
    }
};

struct RealEvalOptions {
    std::filesystem::path dir;        ///< the real-stereo folder (index.csv)
    std::filesystem::path overlayDir; ///< per-pair overlays when not empty
    std::string mount;                ///< "" (found), "H,PITCH,ROLL" for every pair, or "SET=H,PITCH,ROLL"
    std::vector<std::string> pairs;   ///< only these pairs (empty: all)
    bool verbose = false;             ///< a line per sector: truth, ours, outcome
    bool groundRange = false;         ///< RoiMatcherConfig::groundRange (detectPair then runs each pair twice)
    bool groundPrior = false;         ///< RoiMatcherConfig::groundPrior (the configured ground; with groundRange
                                      ///< the second run's prior is the first run's estimate)
    double halfResPx = 0.0;           ///< DetectorConfig::halfResolutionMinGroundPx (eval --half-res)
    double maxRangePx = vision::SectorBuilderConfig{}.maxRangeDisparityPx; ///< eval --max-range-px
    /// --detector colour: also the one-camera mode (vision::ColourFreeSpace on the left colour image, the ground of
    /// --mount, else of the stereo detector's estimate as a calibrated mount would give it), scored the same way
    bool colour = false;
    /// --perturb: the conditions to run the pairs under, each scored in full (empty: the pairs as they are); with
    /// more than one, only each condition's totals are printed, then a table of them
    std::vector<Perturbation> perturbations;
};

/// eval --real --mount: a rig's mount, for every pair or for one data set's.
struct RealMount {
    std::string dataset; ///< "" for every pair, else the pairs whose index.csv dataset starts with it
    vision::Mount mount;

    /// Whether a pair of `pairDataset` (index.csv's, "" without the column) is of this mount's rig.
    [[nodiscard]] bool appliesTo(const std::string& pairDataset) const noexcept
    {
        return pairDataset.rfind(dataset, 0) == 0;
    }
};

/// "[DATASET=]HEIGHT_M,PITCH_DEG,ROLL_DEG" (eval --real --mount), or a usage error naming the option.
Result<RealMount, Error> parseMount(const std::string& text);

/// A Middlebury PFM disparity map ("Pf": one float32 channel, rows stored bottom-up, a negative scale for little
/// endian) as CV_32F, top row first, the values as stored (inf where there is no GT). OpenCV 4.6's reader is not
/// used: it multiplies the values by 1 / |scale|, and Middlebury writes the scale -1/255 while its disparities are in
/// pixels as stored. Empty, with `why` set, when the file is not such a PFM of `size` (a different size, another
/// header, big endian, truncated data).
cv::Mat readPfmDisparity(const std::filesystem::path& path, cv::Size size, std::string& why);

/// Runs the evaluation; prints a table per pair and the totals, appends `"real": {...}` to `json`.
/// @return 0, 1 on unreadable data.
int runRealEval(const RealEvalOptions& options, std::ostringstream& json);

} // namespace ugv::tool
