#pragma once

/// @file
/// Obstacle sectors from the ROI disparity, an optional obstacle label image (ground-mismatch stage) and the
/// ground plane of the frame.
///
/// Every analysed ROI pixel with a valid disparity becomes a vehicle-frame point (GroundPlane::pixelToVehicle)
/// and is binned by the bearing of the point, atan2(y, x), into `sectorCount` equal bins over the horizontal
/// field of view 2 atan(width / (2 fx)) (as the simulator's ground truth, bringup/sim/README.md):
///  - positive vote: z > faceHeightFraction * minHeightM (the face below an obstacle's top: a 12 cm curb at 8 m
///    has a row or two above 10 cm but several below), counted as tall when z > minHeightM; a positive cluster
///    needs minTallVotes tall votes besides its support, so only what rises above minHeightM is an obstacle (a 6 cm
///    bump is not); negative vote: z < -minDepthM, or z < -minDropDepthM where the ray to the
///    point crosses the ground at least minDropGapM before it (the point is seen over a gap: a drop, not a dip;
///    beyond 4 m only the top centimetres of a trench's far wall are in view). With `useDenseCue` every such pixel
///    votes (weight 1); a pixel that the label image also marks (1 positive, 2 negative) votes with weight 1 +
///    labelWeight. Without the dense cue only labelled pixels vote (unlabelled ones still forbid Clear).
///  - ground support: every other point.
///  - far drops by the row profile: beyond ~6 m a trench's far wall is 3..5 rows at 0.2..1.8 px below the ground
///    disparity, as deep as the noise of single pixels (a 1 m trench at 9 m: 0..6 cm; empty ground gives as
///    many per-pixel drop votes). Its rows are told apart by their mean: per sector and row, the mean residual
///    d - d_g (= d z / h) over the sector and its neighbours; a rim is a row on the ground with two rows below
///    the ground above it, right above it or above up to two rows between that are halfway down or sparse but
///    not empty (the matcher blends the rim into the wall's bottom row and the verifier thins that row out)
///    (dropProfile*). Its range is where the rim row and the first wall row meet: the
///    mean of their rays' ground crossings.
/// The range of a positive vote is the point's horizontal range; that of a negative vote is where the ray to it
/// crosses the ground plane (the near rim of the drop, where the vehicle must stop), as the simulator's truth.
/// Per sector and kind, the votes go into a range histogram (rangeBinM bins up to maxRangeM). The nearest
/// cluster is the first window [r, r (1 + clusterFraction) + clusterWindowM] holding >= minSupport votes;
/// its range is the rangePercentile-quantile (dropRangePercentile for negative votes) of the votes inside the window
/// (robust to single outliers).
/// Afterwards, on the sectors as built: a Clear sector within dropEdgeSectors of a negative obstacle reports that
/// drop (widenDrops), and a run of Clear sectors between two obstacle sectors whose nearest points are less than
/// closeGapM apart reports the nearer of the two (closeGaps); both at half the neighbour's confidence.
/// Sector state: Obstacle (nearer kind wins) when a cluster exists; else Clear (range +inf) when the ground
/// support is >= clearGroundFraction of the sector's analysed pixels, at least minClearFarVotes of those ground
/// pixels lie at or beyond clearRangeM (the ground is seen to be free that far) and the stray votes (outside any
/// cluster) are below maxStrayVotes (positive: a mesh fence's few wire pixels) and maxStrayDropVotes (negative);
/// else Unknown (no texture, invalid disparity, too few measurements, obstacles beyond maxRangeM): never a
/// false Clear. danger = classify(state, range, dangerDistanceM, cautionDistanceM).
///
/// Real ground and real cameras (issue 20). build() makes two passes over the analysed pixels: the first computes
/// every pixel's sector, range and height above the plane and learns the frame's local ground (LocalGround, per
/// sector along the range) and its disparity noise on the ground (groundNoisePx()); the second votes with heights
/// above the local ground. A positive vote must also rise heightNoiseFactor times the height noise at its range
/// (h r e / (fx B)), a negative one must be dropNoiseFactor times the noise below the ground. A negative cluster
/// stands only with evidence a matcher's error on a road cannot give: its votes are at least minDropShare of its
/// votes and the ground votes at its ranges (the ground ends), ground is seen within rimWindowFraction in front of
/// it (the near rim), a neighbouring sector has one at a range that follows (keepContinuousDrops), and no positive
/// cluster of the sector or its neighbours lies where its pixels are (explainedByObstacle: the matcher spreads an
/// obstacle's disparity down over the ground in front of it), and its pixels are a wall (wallLike: a drop shows
/// its far wall, whose disparity stays put from row to row while the ground's it hides changes; a grade, a dip or
/// a matcher's error spread over the road is a surface whose disparity follows the ground's). The row profile
/// (plane residuals) needs a far rim above the wall, dropProfileMinLabels negative labels and a wall among the
/// votes between the rim and the far rim. A drop seen without this evidence makes its sector Unknown, never Clear
/// (Cluster::suspect). maxRangeM follows from the rig when 0.
///
/// Thread-safety: thread-bound (build() writes the internal buffers). RT-safe: build() yes (no allocation, no
/// exception); create() no.

#include <array>
#include <cstdint>
#include <vector>

#include "ugv/platform/error.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/obstacle_sectors.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/vision/block_grid.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/local_ground.hpp"
#include "ugv/vision/rectifier.hpp"

namespace ugv::vision {

struct SectorBuilderConfig {
    int sectorCount = 64;
    float minHeightM = 0.10F;           ///< [m] positive obstacle points are higher than this
    float faceHeightFraction = 0.5F;    ///< points above this fraction of minHeightM support a positive cluster ...
    int minTallVotes = 6;               ///< ... which needs this many votes above minHeightM to be an obstacle
    float minDepthM = 0.10F;            ///< [m] negative obstacle points are deeper than this
    float minDropDepthM = 0.03F;        ///< [m] ... or deeper than this when the ground they hide is long:
    float minDropGapM = 0.25F;          ///< [m] the ray to the point crosses the ground this far before it
                                        ///< (range (-z) / (h - z)): only the top of a trench's far wall is in
                                        ///< view beyond 4 m, a few centimetres below the ground, behind a gap
    float maxRangeM = 0.0F;             ///< [m] points farther away are ignored (disparity too coarse); 0: from the
                                        ///< rig, where the disparity falls to maxRangeDisparityPx (fx B / that)
    float maxRangeDisparityPx = 13.65F; ///< [px] (a 0.5 px error is 3.7 % of the range there; the default rig,
                                        ///< 546 px x 0.30 m: 12 m; KITTI's, 721 px x 0.53 m: 28 m)
    float rangeBinM = 0.02F;            ///< [m] histogram resolution
    float faceSupportRangeM = 5.0F;     ///< [m] a positive cluster farther than r needs minSupport (this / r) votes ...
    int minFaceSupport = 20;            ///< ... but at least this many ...
    int minFarTallVotes = 3;            ///< ... and minTallVotes (this / r) tall votes, at least this many
    /// Every count of pixels below (the supports, tall votes, stray votes, rim and far-ground votes, the row
    /// profile's pixels) is for a rig with this many image columns per sector and this focal length [px] (the
    /// default rig: 640 px, 64 sectors, fy 546 px); create() scales them by the pixels a face covers on the actual
    /// rig, (columns per sector / referenceColumnsPerSector) (fy / referenceFocalPx), at least 1: 2.6 on KITTI's
    /// 1242 px, fy 721 px (unscaled there, 20-vote far faces of the road's texture were 19 false obstacles)
    float referenceColumnsPerSector = 10.0F;
    float referenceFocalPx = 546.0F;
    int minSupport = 40;            ///< votes a cluster needs to make a sector Obstacle (20 let SGBM
                                    ///< mismatch blobs on empty ground through: 23..33 votes measured)
    float dropSupportRangeM = 5.0F; ///< [m] a negative cluster farther than r needs minSupport (this / r)^2
    int minDropSupport = 20;        ///< ... but at least this many votes
    int maxStrayVotes = 8;          ///< positive votes outside any cluster at or above which a sector cannot be Clear
                                    ///< (a mesh fence's wires: 42 -> 25..33 Clear sectors of 64; empty ground 52 -> 51)
    int maxStrayDropVotes = 20;     ///< the same for negative votes (far ground is noisier below the plane: 10 would
                                    ///< turn 52 -> 38 sectors of empty ground Unknown)
    /// Far drops by their row profile (see the file comment): a rim beyond dropProfileMinRangeM is a row whose
    /// mean residual disparity is above -dropProfileResidualPx / 2 with two rows above it (the far wall) below
    /// -dropProfileResidualPx (up to two blended or thinned rows between), over the sector and its two
    /// neighbours, each row with at least dropProfileMinPixels valid pixels.
    float dropProfileMinRangeM = 5.0F;   ///< [m] nearer drops are left to the per-pixel votes
    float dropProfileResidualPx = 1.0F;  ///< [px] (empty ground: row means within +-0.7 px at 9 m measured) ...
    float dropProfileNoiseFactor = 4.0F; ///< ... or this many times the frame's own spread of the row means, when
                                         ///< larger (learnt per frame and sector: a real road's rows wander)
    int dropProfileMinLabels = 2; ///< negative labels of the ground-mismatch stage the wall rows need (the second cue)
    int dropProfileMinPixels = 6;
    int dropEdgeSectors = 2;           ///< Clear sectors this near a negative obstacle report it (a hole's rim
                                       ///< thins out at its lateral ends); 0 disables
    float closeGapM = 0.5F;            ///< [m] Clear sectors between two obstacle sectors whose points are nearer
                                       ///< each other than this report the nearer one (a far curb's face gives
                                       ///< some sectors too few votes; no vehicle passes there); 0 disables
    float clusterWindowM = 0.15F;      ///< [m] cluster window, fixed part
    float clusterFraction = 0.05F;     ///< cluster window, part proportional to the range
    float rangePercentile = 0.20F;     ///< quantile of the cluster's votes reported as the range, [0, 1)
    float dropRangePercentile = 0.05F; ///< the same for negative votes: their rim ranges spread from the rim
                                       ///< to the far wall (only the nearest are the rim)
    float clearGroundFraction = 0.25F; ///< ground support (fraction of the sector's pixels) needed for Clear
    float clearRangeM = 5.0F;          ///< [m] Clear means free ground seen out to at least this range ...
    int minClearFarVotes = 20;         ///< ... by this many ground pixels at or beyond it (a textureless wall at
                                       ///< 3 m hides the ground behind it: Unknown, not Clear)
    int labelWeight = 1;               ///< extra votes of a pixel that the label image confirms
    bool useDenseCue = true;           ///< unlabelled pixels above/below the ground vote too
    float heightNoiseFactor = 3.0F;    ///< a positive vote must rise this many times the frame's height noise at
                                       ///< its range, h r e / (fx B) with e the ground noise [px], when that is
                                       ///< more than minHeightM (far rows: 0.10 m is in the noise at 20 m on KITTI)
    float dropNoiseFactor = 2.0F;      ///< a negative vote's residual disparity must exceed this many times the
                                       ///< frame's ground noise (learnt per frame, SectorBuilder::groundNoisePx())
    int minRimVotes = 10;              ///< ... and this many ground votes within rimWindowFraction of its range
    float rimWindowFraction = 0.10F;   ///< in front of it (the near rim: the ground is seen up to the drop)
    float explainWindowM = 0.5F;       ///< [m] a drop whose pixels lie within this (+ clusterFraction of the range)
                                       ///< of a positive obstacle of its sector or a neighbour is that obstacle's
                                       ///< disparity spread down by the matcher (SectorBuilder::explainedByObstacle)
    float minDropShare = 0.5F;         ///< a negative cluster's votes must be at least this share of its votes
                                       ///< and the ground votes at the same ranges: where a drop is, the ground
                                       ///< ends (on a real road a matcher's error below it leaves the road around)
    /// A drop's votes are a wall when the least-squares slope b of their disparity o on the ground's disparity g at
    /// the same pixels is within +-maxWallSlope, by wallSlopeSigmas standard errors: 0 on a wall, 1 on the road;
    /// halfway is the line (on KITTI roads the matcher's below-ground patches have slopes around 1 or undetermined,
    /// the simulator's trench and hole walls -0.4..0.3 with 0.01..0.1 standard error) ...
    float maxWallSlope = 0.5F;
    float wallSlopeSigmas = 2.0F;
    /// ... or a floor: a plane parallel to the ground, D below it, is o = g h / (h + D): a line through the origin
    /// (|b - mean o / mean g| within floorLineTolerance and the standard errors) whose slope b is at most
    /// h / (h + minDepthM) by wallSlopeSigmas standard errors, and whose ratio mean o / mean g (the depth measured
    /// over every vote) is at most h / (h + minDepthM) too (a step down, a ledge, a trench's floor). A patch of
    /// the matcher's errors on a road is o = g - e: slope 1, not through the origin; KITTI's come within 0.05 of
    /// the line only as floors 0.01-0.05 m deep. Without the ratio's own test a patch could pass on the slope's
    /// uncertainty in both directions: KITTI 000046_10 at half the exposure, slope 0.83 +- 0.10 (two standard
    /// errors) and ratio 0.958 (7 cm deep), made two false drop sectors.
    float floorLineTolerance = 0.05F;
    /// A pair coded in 8 x 8 blocks (JPEG, MJPEG) makes the matcher lock onto the blocks' edges: at the disparities
    /// that bring the two images' grids together (multiples of 8 px plus the grids' offset), constant down the rows,
    /// a wall to the drop test (KITTI 000013_10 at JPEG quality 20: 78 % of the votes of its 8 false drop sectors
    /// within half a pixel of a multiple of 8, against 12.5 % by chance). When both images show the grid
    /// (BlockGrid::contrast at least this, see block_grid.hpp; a camera's raw frames 1.00-1.08, JPEG quality 70
    /// 1.29 and more), a negative vote at such a disparity (within half a pixel) is no evidence of a drop: it only
    /// forbids Clear (SectorBuilder::setBlockGrid). 0: off.
    float blockGridContrast = 1.2F;
    bool useLocalGround = true; ///< heights from the per-sector ground profile (LocalGround), not the plane
    LocalGroundConfig localGround;
    float confidenceSupport = 200.0F; ///< votes that give confidence 1
    float dangerDistanceM = 1.5F;     ///< [m]
    float cautionDistanceM = 5.0F;    ///< [m]
};

enum class BuildStatus : std::uint8_t {
    Ok,
    WrongDisparitySize, ///< disparity is empty or not roi size: all sectors Unknown, degraded
    WrongLabelSize,     ///< labels are non-empty and not roi size: all sectors Unknown, degraded
};

/// Label values of the ground-mismatch stage's image.
inline constexpr std::uint8_t kLabelPositive = 1;
inline constexpr std::uint8_t kLabelNegative = 2;

class SectorBuilder {
public:
    /// @param[in] projection  rectified projection (full-frame coordinates)
    /// @param[in] roi         full-frame rectangle of the disparity/label images [px]
    /// @param[in] firstRow    first full-frame row analysed (rows above are the matcher's margin) [px]
    /// @return the builder, or an error for an invalid config or geometry.
    static Result<SectorBuilder, Error> create(const SectorBuilderConfig& config, const RectifiedProjection& projection,
                                               Rect roi, int firstRow);

    /// Builds the sectors of one frame.
    /// @param[in] disparity16  roi-size disparity, d * 16 (RoiMatcher::kScale), invalid <= 0
    /// @param[in] labels       roi-size label image (1 positive, 2 negative, else none), or empty
    /// @param[in] ground       ground plane of this frame
    /// @param[in] sequence, stampNs  carried into the output
    /// @return Ok or the input that was wrong (then all sectors Unknown and `degraded` set).
    BuildStatus build(ImageView<const std::int16_t> disparity16, ConstImageViewU8 labels, const GroundPlane& ground,
                      std::uint64_t sequence, std::int64_t stampNs) noexcept;

    /// The per-pixel reference of build() (GroundPlane::pixelToVehicle, atan2 and hypot per pixel; tests and
    /// benchmarks). build() computes the same points from per-row linear factors (the vehicle point is linear in
    /// 1/d for a fixed plane) and finds the sector by walking the sector boundaries; the results agree up to
    /// double rounding at a bin or sector boundary.
    BuildStatus buildReference(ImageView<const std::int16_t> disparity16, ConstImageViewU8 labels,
                               const GroundPlane& ground, std::uint64_t sequence, std::int64_t stampNs) noexcept;

    /// Marks all sectors Unknown and degraded (callers' failure paths).
    void setAllUnknown(std::uint64_t sequence, std::int64_t stampNs) noexcept;
    /// The next builds' block grids of the left and right images (measureBlockGrid; ObstacleDetector sets them every
    /// frame): when both reach blockGridContrast, negative votes at the disparities that match the grids to each
    /// other are left out (SectorBuilderConfig::blockGridContrast). Default: no grid.
    void setBlockGrid(const BlockGrid& left, const BlockGrid& right) noexcept;
    /// Flags the last build's sectors as produced by a fallback path (ObstacleDetector::processGroundOnly).
    void markDegraded() noexcept { sectors_.degraded = true; }

    [[nodiscard]] const ObstacleSectors& sectors() const noexcept { return sectors_; }
    [[nodiscard]] const SectorBuilderConfig& config() const noexcept { return config_; }
    [[nodiscard]] float hfovDeg() const noexcept { return hfovDeg_; }
    /// The last build's disparity noise on the ground [px]: 1.4826 x the median |d - d_ground| of the pixels near
    /// the local ground.
    [[nodiscard]] float groundNoisePx() const noexcept { return disparityNoisePx_; }

private:
    SectorBuilder() = default;
    /// create(): every buffer at its size for the config, the ROI and the range bins.
    void allocate();
    /// create(): the bearings of the sector boundaries and the analysed pixels whose column lies in each sector.
    void initSectorGeometry() noexcept;
    struct Cluster {
        int votes = 0;
        float rangeM = 0.0F;
        int firstBin = 0; ///< the window [firstBin, endBin) of range bins
        int endBin = 0;
        bool suspect = false; ///< no cluster, but a drop seen without enough evidence: the sector cannot be Clear
    };
    /// @param[in] tall  votes above minHeightM per bin (positive clusters), or the ground votes per bin (drops)
    /// @param[in] dropSector  the sector of a negative histogram, -1 for a positive one
    [[nodiscard]] Cluster nearestCluster(const std::uint32_t* histogram, const std::uint32_t* tall, float percentile,
                                         int dropSector) const noexcept;
    /// Sums over pixels of g, the ground's disparity there [px], and o, the pixel's own: enough for the slope of o
    /// on g and its standard error (double: the variance of g is a small difference of large sums).
    struct WallSums {
        double n = 0.0;
        double g = 0.0;
        double o = 0.0;
        double gg = 0.0;
        double go = 0.0;
        double oo = 0.0;
    };
    /// Whether the negative votes of sector s whose rays cross the ground in range bins [firstBin, endBin) are a
    /// wall (see maxWallSlope).
    [[nodiscard]] bool wallLike(int s, int firstBin, int endBin) const noexcept;
    /// Sets every sector Unknown (degraded) and returns the error when an input has the wrong size.
    BuildStatus checkInputs(ImageView<const std::int16_t> disparity16, ConstImageViewU8 labels, std::uint64_t sequence,
                            std::int64_t stampNs) noexcept;
    void resetAccumulators() noexcept;
    /// [px * kDisparityScale] disparities below this are farther than maxRangeM even straight ahead.
    [[nodiscard]] int minDisparity16() const noexcept;
    /// First pass: every analysed pixel's point (sector, range, height above the plane) into points_ and the local
    /// ground; per pixel with GroundPlane::pixelToVehicle and atan2 (the reference), or per row from linear factors
    /// (build(), see the .cpp). @return the number of points.
    std::size_t collectPerPixel(ImageView<const std::int16_t> disparity16, ConstImageViewU8 labels,
                                const GroundPlane& ground) noexcept;
    std::size_t collectPerRow(ImageView<const std::int16_t> disparity16, ConstImageViewU8 labels,
                              const GroundPlane& ground) noexcept;
    void addPoint(std::size_t& count, int s, int v, float range, float z, int d16, const std::uint8_t* label,
                  int u) noexcept;
    /// What a vote is measured against, fixed per frame between the passes (the frame's noise).
    struct VoteLimits {
        double groundHeightM = 0.0;   ///< [m] the plane's camera height
        float groundHeight = 0.0F;    ///< [m] the same
        float faceHeight = 0.0F;      ///< [m] faceHeightFraction * minHeightM
        float heightNoisePerM = 0.0F; ///< [m/m] heightNoiseFactor times the height noise per metre of range
        float dropResidualPx = 0.0F;  ///< [px] a negative vote's residual disparity must be below minus this
    };
    struct PixelPoint;
    /// Second pass for one point: a positive, negative or ground vote into the accumulators.
    void vote(const PixelPoint& p, const VoteLimits& limits) noexcept;
    /// The local ground, the frame's noise, the votes and the sectors from the first pass's points.
    void finish(std::size_t pointCount, const GroundPlane& ground, std::uint64_t sequence,
                std::int64_t stampNs) noexcept;
    /// Each sector's state from its clusters, ground support and stray votes.
    void classifySectors(std::uint64_t sequence, std::int64_t stampNs) noexcept;

    SectorBuilderConfig config_;
    RectifiedProjection projection_;
    Rect roi_;
    int firstRow_ = 0;
    int bins_ = 0;
    float hfovDeg_ = 0.0F;
    ObstacleSectors sectors_;
    std::vector<std::uint32_t> histograms_;    ///< [sector][kind 0 positive, 1 negative][bin] votes
    std::vector<std::uint32_t> tallVotes_;     ///< [sector][bin] positive votes above minHeightM
    std::vector<std::uint32_t> groundByRange_; ///< [sector][bin] ground votes
    std::vector<float> dropDistance_;          ///< [sector][bin] sum of the negative votes' own ranges [m]
    std::vector<WallSums> wallSums_;           ///< [sector][wall bin: wallBinRatio_ range bins] negative votes
    int wallBinRatio_ = 1;
    int wallBins_ = 0;
    std::array<Cluster, kMaxSectors> positives_{}; ///< the last build's positive clusters
    std::array<Cluster, kMaxSectors> negatives_{}; ///< ... and negative ones
    /// Drops only where a neighbouring sector sees one at a range that follows (a rim is a line).
    void keepContinuousDrops() noexcept;
    /// A negative cluster whose pixels lie (at their own range, not where their rays cross the ground) where the
    /// sector or a neighbour has a positive obstacle: the matcher spread that obstacle's disparity down over the
    /// ground in front of it (the shade under a car), not a drop.
    [[nodiscard]] bool explainedByObstacle(int s, const Cluster& drop,
                                           const std::array<Cluster, kMaxSectors>& positives) const noexcept;
    std::vector<float> extremes_;                ///< [sector][kind][bin] max height / depth [m]
    std::vector<std::uint32_t> groundVotes_;     ///< [sector]
    std::vector<std::uint32_t> farGroundVotes_;  ///< [sector] ground votes at or beyond clearRangeM
    std::vector<std::uint32_t> kindVotes_;       ///< [sector][kind] all votes
    std::vector<std::uint32_t> pixelsPerSector_; ///< analysed pixels whose column bearing is in the sector
    std::vector<double> boundaryCos_;            ///< [sectorCount + 1] cos / sin of the sector boundary bearings
    std::vector<double> boundarySin_;
    /// Nearest far drop of sector s by the row profile, or a Cluster with no votes.
    [[nodiscard]] Cluster profileDrop(int s) const noexcept;
    /// One analysed row of the row profile over a sector and its neighbours.
    struct ProfileRow {
        std::uint32_t count = 0;
        std::uint32_t labels = 0; ///< negative labels
        float residual = 0.0F;    ///< mean [px]
        float crossing = 0.0F;    ///< mean [m]
        float disparity = 0.0F;   ///< mean [px]
    };
    /// Row v of the profile of sector s and its two neighbours (sums, then means over their valid pixels). Inline
    /// (defined in the .cpp, its only user): called for every analysed row of every sector in each frame.
    [[nodiscard]] inline ProfileRow profileRow(int s, int v) const noexcept;
    /// [px] The residual below minus which a profile row is below the ground: dropProfileResidualPx, or the frame's
    /// row-mean spread over the far rows times dropProfileNoiseFactor, whichever is larger.
    [[nodiscard]] float profileThreshold(int s) const noexcept;
    /// Whether sector s's own rows w1 and w2 (not only its neighbours') lie below -tau on average.
    [[nodiscard]] bool ownRowsBelow(int s, int w1, int w2, float tau) const noexcept;
    /// The far rim: within a few rows above the wall's top row w2, the ground comes back to its plane. A road that
    /// bends down (a grade change) goes on below the plane and has none.
    [[nodiscard]] bool farRimAbove(int s, int w2, float tau) const noexcept;
    /// Whether two wall rows are a wall: their disparity stays put while the ground's changes from one to the other
    /// (the slope of the one on the other, by the frame's pixel noise; see maxWallSlope).
    [[nodiscard]] bool profileWall(const ProfileRow& wall1, const ProfileRow& wall2) const noexcept;
    /// `out` reports the obstacle of its neighbour `from`, at half its confidence (widenDrops, closeGaps).
    void reportNeighbour(Sector& out, const Sector& from) const noexcept;
    /// Clear sectors within dropEdgeSectors of a negative obstacle take it over (see the definition).
    void widenDrops() noexcept;
    /// Runs of Clear sectors between two obstacle sectors less than closeGapM apart take the nearer one over.
    void closeGaps() noexcept;

    int profileRows_ = 0;                 ///< analysed rows (firstRow .. roi bottom)
    std::vector<std::uint32_t> rowCount_; ///< [sector][row] valid pixels
    std::vector<float> rowResidual_;      ///< [sector][row] sum of d - d_g [px]
    std::vector<float> rowCrossing_;      ///< [sector][row] sum of the ranges where the pixels' rays meet the ground
    std::vector<float> rowDisparity_;     ///< [sector][row] sum of d [px]
    std::vector<std::uint32_t> rowDropLabels_; ///< [sector][row] pixels the mismatch stage labels negative
    std::vector<double> boundary0_;            ///< [sectorCount + 1] per-row boundary functions g_k(u) = b0 + b1 u
    std::vector<double> boundary1_;
    /// A pixel's geometry, kept from the first pass (points and the local ground) for the second (votes).
    struct PixelPoint {
        float rangeM;
        float z;      ///< [m] above the plane
        float zLocal; ///< [m] above the local ground (set once the local ground is fitted)
        std::int16_t sector;
        std::int16_t row; ///< analysed row index
        std::int16_t d16;
        std::uint8_t label;
    };
    std::vector<PixelPoint> points_; ///< capacity: every analysed pixel
    [[nodiscard]] float groundNoise(std::size_t pointCount) noexcept;
    std::vector<std::uint32_t> noiseHistogram_; ///< |d - d_ground| in 1/32 px bins
    float disparityNoisePx_ = 0.0F;
    int gridOffsetPx_ = -1;     ///< setBlockGrid(): the grids' disparity offset, -1 without a grid
    float groundHeight_ = 0.0F; ///< [m] the last build's plane
    LocalGround localGround_;
};

} // namespace ugv::vision
