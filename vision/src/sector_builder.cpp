#include "ugv/vision/sector_builder.hpp"

#include "ugv/platform/angles.hpp"
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>

namespace ugv::vision {
namespace {

constexpr int kKinds = 2; // 0 positive, 1 negative
constexpr float kDisparityScale = 16.0F;
constexpr int kMaxProfileRows = 2048; ///< analysed rows the row profile's noise estimate looks at
constexpr float kWallBinM = 0.10F;    ///< [m] range resolution of the wall test's sums
constexpr auto kSubpixels = static_cast<int>(kDisparityScale); ///< disparity units per pixel

/// d16 (> 0) within half a pixel of offsetPx plus a multiple of the block size.
bool onBlockGrid(int d16, int offsetPx) noexcept
{
    constexpr int kPeriod = BlockGrid::kBlockPx * kSubpixels;
    const int phase = ((d16 - offsetPx * kSubpixels) % kPeriod + kPeriod) % kPeriod;
    return phase < kSubpixels / 2 || phase >= kPeriod - kSubpixels / 2;
}

/// Vehicle axes in camera coordinates, exactly as GroundPlane::toVehicle builds them: forward f and left l
/// (both of norm 1 / invNorm) and up u (unit).
struct GroundAxes {
    double f[3];
    double l[3];
    double u[3];
    double invNorm;
};

GroundAxes groundAxes(const GroundPlane& g) noexcept
{
    GroundAxes a{};
    a.f[0] = -g.nz * g.nx;
    a.f[1] = -g.nz * g.ny;
    a.f[2] = 1.0 - g.nz * g.nz;
    a.u[0] = -g.nx;
    a.u[1] = -g.ny;
    a.u[2] = -g.nz;
    a.l[0] = a.u[1] * a.f[2] - a.u[2] * a.f[1];
    a.l[1] = a.u[2] * a.f[0] - a.u[0] * a.f[2];
    a.l[2] = a.u[0] * a.f[1] - a.u[1] * a.f[0];
    a.invNorm = 1.0 / std::sqrt(a.f[0] * a.f[0] + a.f[1] * a.f[1] + a.f[2] * a.f[2]);
    return a;
}

Error sectorConfigError(const std::string& what)
{
    return Error{"SectorBuilderConfig", what, "see vision/include/ugv/vision/sector_builder.hpp"};
}

Result<void, Error> checkConfig(const SectorBuilderConfig& config)
{
    if (config.sectorCount < 1 || config.sectorCount > kMaxSectors) {
        return Unexpected(sectorConfigError("sectorCount " + std::to_string(config.sectorCount) + " is not in 1.." +
                                            std::to_string(kMaxSectors)));
    }
    if (!(config.minHeightM > 0.0F) || !(config.minDepthM > 0.0F) || !(config.rangeBinM > 0.0F) ||
        !(config.maxRangeM >= 0.0F) || !(config.maxRangeDisparityPx > 0.0F) || config.minSupport < 1 ||
        config.minDropSupport < 1 || config.maxStrayVotes < 1 || config.maxStrayDropVotes < 1 ||
        !(config.dropSupportRangeM > 0.0F) || config.clusterWindowM < 0.0F || config.clusterFraction < 0.0F ||
        !(config.rangePercentile >= 0.0F && config.rangePercentile < 1.0F) ||
        !(config.dropRangePercentile >= 0.0F && config.dropRangePercentile < 1.0F) ||
        !(config.clearGroundFraction > 0.0F && config.clearGroundFraction <= 1.0F) || config.labelWeight < 0 ||
        !(config.confidenceSupport > 0.0F) || !(config.minDropDepthM > 0.0F) || !(config.minDropGapM >= 0.0F) ||
        !(config.clearRangeM > 0.0F) || config.minClearFarVotes < 0 ||
        !(config.faceHeightFraction > 0.0F && config.faceHeightFraction <= 1.0F) || config.minTallVotes < 1 ||
        !(config.dangerDistanceM <= config.cautionDistanceM) || !(config.dropProfileMinRangeM > 0.0F) ||
        !(config.dropProfileResidualPx > 0.0F) || config.dropProfileMinPixels < 1 || config.dropEdgeSectors < 0 ||
        !(config.closeGapM >= 0.0F) || !(config.faceSupportRangeM > 0.0F) || config.minFaceSupport < 1 ||
        config.minFarTallVotes < 1 || !(config.referenceColumnsPerSector > 0.0F) || !(config.referenceFocalPx > 0.0F)) {
        return Unexpected(sectorConfigError(
            "a threshold is out of range (all must be positive, percentile in [0, 1), faceHeightFraction in (0, 1])"));
    }
    const LocalGroundConfig& lg = config.localGround;
    if (!(lg.bandM > 0.0F) || !(lg.binM > 0.0F) || lg.minPoints < 1 || !(lg.stepM >= 0.0F) || !(lg.maxSlope >= 0.0F) ||
        !(lg.maxOffsetM >= 0.0F) || !(config.minDropShare >= 0.0F && config.minDropShare <= 1.0F) ||
        config.minRimVotes < 0 || !(config.rimWindowFraction >= 0.0F) || !(config.explainWindowM >= 0.0F) ||
        !(config.heightNoiseFactor >= 0.0F) || !(config.dropNoiseFactor >= 0.0F) ||
        !(config.dropProfileNoiseFactor >= 0.0F) || config.dropProfileMinLabels < 0 || !(config.maxWallSlope > 0.0F) ||
        !(config.wallSlopeSigmas >= 0.0F) || !(config.floorLineTolerance >= 0.0F) ||
        !(config.blockGridContrast >= 0.0F)) {
        return Unexpected(sectorConfigError("a local-ground or drop-evidence setting is out of range (band, bin > 0, "
                                            "minPoints >= 1, share in [0, 1], maxWallSlope > 0, the others >= 0)"));
    }
    return {};
}

/// The config with its vote counts scaled to this rig's pixels and maxRangeM from the rig when it is 0.
SectorBuilderConfig rigConfig(const SectorBuilderConfig& config, const RectifiedProjection& projection)
{
    SectorBuilderConfig rig = config;
    // Vote counts are pixels: a face of a given size at a given range covers (columns per sector) x (fy x its
    // height / range) of them. The counts are set for the reference rig and scale with this rig's pixel density.
    const double columnsPerSector = (2.0 * projection.cx + 1.0) / config.sectorCount;
    const double pixelScale = columnsPerSector / static_cast<double>(config.referenceColumnsPerSector) * projection.fy /
                              static_cast<double>(config.referenceFocalPx);
    const auto scaled = [&](int count) { return std::max(1, static_cast<int>(std::lround(count * pixelScale))); };
    rig.minSupport = scaled(config.minSupport);
    rig.minFaceSupport = scaled(config.minFaceSupport);
    rig.minTallVotes = scaled(config.minTallVotes);
    rig.minFarTallVotes = scaled(config.minFarTallVotes);
    rig.minDropSupport = scaled(config.minDropSupport);
    rig.maxStrayVotes = scaled(config.maxStrayVotes);
    rig.maxStrayDropVotes = scaled(config.maxStrayDropVotes);
    rig.minRimVotes = config.minRimVotes == 0 ? 0 : scaled(config.minRimVotes);
    rig.minClearFarVotes = config.minClearFarVotes == 0 ? 0 : scaled(config.minClearFarVotes);
    rig.dropProfileMinPixels = scaled(config.dropProfileMinPixels);
    if (config.maxRangeM == 0.0F) {
        rig.maxRangeM =
            static_cast<float>(projection.fx * projection.baselineM / static_cast<double>(config.maxRangeDisparityPx));
    }
    return rig;
}

} // namespace

Result<SectorBuilder, Error> SectorBuilder::create(const SectorBuilderConfig& config,
                                                   const RectifiedProjection& projection, Rect roi, int firstRow)
{
    if (auto valid = checkConfig(config); !valid) {
        return Unexpected(valid.error());
    }
    if (!(projection.fx > 0.0) || !(projection.fy > 0.0) || !(projection.baselineM > 0.0)) {
        return Unexpected(Error{"SectorBuilder::create", "projection has no positive focal length and baseline", ""});
    }
    if (roi.empty() || firstRow < roi.y || firstRow >= roi.y + roi.height) {
        return Unexpected(
            Error{"SectorBuilder::create", "firstRow " + std::to_string(firstRow) + " is not inside the ROI rows", ""});
    }

    SectorBuilder sut;
    sut.config_ = rigConfig(config, projection);
    if (!(sut.config_.maxRangeM > config.rangeBinM)) {
        return Unexpected(
            sectorConfigError("maxRangeM " + std::to_string(sut.config_.maxRangeM) + " is not above rangeBinM"));
    }
    sut.projection_ = projection;
    sut.roi_ = roi;
    sut.firstRow_ = firstRow;
    sut.bins_ = static_cast<int>(std::ceil(sut.config_.maxRangeM / config.rangeBinM));
    // The full frame's width is 2 cx + 1 (pixel centres at integers, principal point at the centre).
    const double width = 2.0 * projection.cx + 1.0;
    sut.hfovDeg_ = static_cast<float>(2.0 * std::atan(width / (2.0 * projection.fx)) * kRadToDeg);
    initSectors(sut.sectors_, config.sectorCount, sut.hfovDeg_);
    sut.allocate();
    sut.initSectorGeometry();
    return sut;
}

void SectorBuilder::allocate()
{
    const auto n = static_cast<std::size_t>(config_.sectorCount);
    const auto bins = static_cast<std::size_t>(bins_);
    histograms_.assign(n * kKinds * bins, 0U);
    extremes_.assign(histograms_.size(), 0.0F);
    tallVotes_.assign(n * bins, 0U);
    groundByRange_.assign(tallVotes_.size(), 0U);
    dropDistance_.assign(tallVotes_.size(), 0.0F);
    wallBinRatio_ = std::max(1, static_cast<int>(std::lround(kWallBinM / config_.rangeBinM)));
    wallBins_ = bins_ / wallBinRatio_ + 1;
    wallSums_.assign(n * static_cast<std::size_t>(wallBins_), WallSums{});
    groundVotes_.assign(n, 0U);
    farGroundVotes_.assign(n, 0U);
    profileRows_ = roi_.y + roi_.height - firstRow_;
    rowCount_.assign(n * static_cast<std::size_t>(profileRows_), 0U);
    rowResidual_.assign(rowCount_.size(), 0.0F);
    rowCrossing_.assign(rowCount_.size(), 0.0F);
    rowDisparity_.assign(rowCount_.size(), 0.0F);
    rowDropLabels_.assign(rowCount_.size(), 0U);
    noiseHistogram_.assign(256, 0U);
    kindVotes_.assign(n * kKinds, 0U);
    points_.resize(static_cast<std::size_t>(roi_.width) * static_cast<std::size_t>(profileRows_));
    localGround_.configure(config_.localGround, config_.sectorCount, config_.maxRangeM);
    pixelsPerSector_.assign(n, 0U);
    boundaryCos_.assign(n + 1, 0.0);
    boundarySin_.assign(n + 1, 0.0);
    boundary0_.assign(n + 1, 0.0);
    boundary1_.assign(n + 1, 0.0);
}

void SectorBuilder::initSectorGeometry() noexcept
{
    const auto n = static_cast<std::size_t>(config_.sectorCount);
    const float binDeg = hfovDeg_ / static_cast<float>(config_.sectorCount);
    for (std::size_t k = 0; k <= n; ++k) {
        // The reference's sector is floor((bearing + hfov / 2) / binDeg) in float: boundary k at k binDeg - hfov / 2.
        const double b = (static_cast<double>(k) * binDeg - hfovDeg_ / 2.0) / kRadToDeg;
        boundaryCos_[k] = std::cos(b);
        boundarySin_[k] = std::sin(b);
    }
    const auto rows = static_cast<std::uint32_t>(roi_.y + roi_.height - firstRow_);
    for (int x = 0; x < roi_.width; ++x) {
        const double bearing = std::atan2(projection_.cx - (x + roi_.x), projection_.fx) * kRadToDeg;
        const int s = static_cast<int>(std::floor((static_cast<float>(bearing) + hfovDeg_ / 2.0F) / binDeg));
        if (s >= 0 && s < config_.sectorCount) {
            pixelsPerSector_[static_cast<std::size_t>(s)] += rows;
        }
    }
}

void SectorBuilder::setAllUnknown(std::uint64_t sequence, std::int64_t stampNs) noexcept
{
    initSectors(sectors_, config_.sectorCount, hfovDeg_);
    sectors_.sequence = sequence;
    sectors_.captureStampNs = stampNs;
    sectors_.degraded = true;
}

void SectorBuilder::setBlockGrid(const BlockGrid& left, const BlockGrid& right) noexcept
{
    const float threshold = config_.blockGridContrast;
    const bool coded = threshold > 0.0F && left.contrast >= threshold && right.contrast >= threshold;
    // A left column x on its grid's edge (x % 8 == left.offset) matches the right column x - d on the right grid's
    // edge: d % 8 == left.offset - right.offset.
    constexpr int kBlock = BlockGrid::kBlockPx;
    gridOffsetPx_ = coded ? ((left.offset - right.offset) % kBlock + kBlock) % kBlock : -1;
}

bool SectorBuilder::wallLike(int s, int firstBin, int endBin) const noexcept
{
    WallSums w;
    const int first = std::max(0, firstBin) / wallBinRatio_;
    const int end = std::min(wallBins_, (std::max(0, endBin) + wallBinRatio_ - 1) / wallBinRatio_);
    for (int b = first; b < end; ++b) {
        const WallSums& x =
            wallSums_[static_cast<std::size_t>(s) * static_cast<std::size_t>(wallBins_) + static_cast<std::size_t>(b)];
        w.n += x.n;
        w.g += x.g;
        w.o += x.o;
        w.gg += x.gg;
        w.go += x.go;
        w.oo += x.oo;
    }
    if (w.n < 3.0) {
        return false;
    }
    const double varG = w.gg / w.n - (w.g / w.n) * (w.g / w.n);
    const double cov = w.go / w.n - (w.g / w.n) * (w.o / w.n);
    const double varO = w.oo / w.n - (w.o / w.n) * (w.o / w.n);
    if (!(varG > 1e-6)) {
        return false; // all on one row: no slope to see
    }
    const double slope = cov / varG;
    const double margin = config_.wallSlopeSigmas * std::sqrt(std::max(0.0, varO - slope * cov) / (w.n * varG));
    // A wall: o stays put while g changes.
    const bool wall = std::abs(slope) + margin < config_.maxWallSlope;
    // A floor: o = g h / (h + D), a line through the origin whose slope gives a depth D of at least minDepthM. The
    // line's own ratio, mean o / mean g, must give that depth too: it is the floor's depth measured over every vote,
    // while the free slope is uncertain by its margin (a patch whose line through the origin is 7 cm deep must not
    // pass as deeper on the slope's uncertainty).
    const double h = groundHeight_;
    const double shallowestRatio = h / (h + static_cast<double>(config_.minDepthM));
    const double ratio = w.o / w.g;
    const bool floor = std::abs(slope - ratio) <= margin + config_.floorLineTolerance &&
                       slope + margin <= shallowestRatio && ratio <= shallowestRatio;
    return wall || floor;
}

SectorBuilder::Cluster SectorBuilder::nearestCluster(const std::uint32_t* histogram, const std::uint32_t* tall,
                                                     float percentile, int dropSector) const noexcept
{
    const bool drop = dropSector >= 0;
    for (int start = 0; start < bins_; ++start) {
        if (histogram[start] == 0U) {
            continue;
        }
        const float r0 = static_cast<float>(start) * config_.rangeBinM;
        const float r1 = r0 * (1.0F + config_.clusterFraction) + config_.clusterWindowM;
        const int end = std::min(bins_, static_cast<int>(r1 / config_.rangeBinM) + 1);
        std::uint32_t votes = 0;
        std::uint32_t tallVotes = 0;
        for (int b = start; b < end; ++b) {
            votes += histogram[b];
            tallVotes += tall != nullptr ? tall[b] : 0U;
        }
        // A face's pixels in a sector shrink with its range (its rows do; the sector's columns do not): beyond
        // faceSupportRangeM it needs proportionally fewer votes and tall votes, never fewer than minFaceSupport
        // and minFarTallVotes.
        std::uint32_t minSupport = static_cast<std::uint32_t>(config_.minSupport);
        std::uint32_t minTall = static_cast<std::uint32_t>(config_.minTallVotes);
        if (!drop && r0 > config_.faceSupportRangeM) {
            const float scale = config_.faceSupportRangeM / r0;
            minSupport = static_cast<std::uint32_t>(
                std::max(static_cast<float>(config_.minFaceSupport), static_cast<float>(config_.minSupport) * scale));
            minTall = static_cast<std::uint32_t>(std::max(static_cast<float>(config_.minFarTallVotes),
                                                          static_cast<float>(config_.minTallVotes) * scale));
        }
        if (!drop && tallVotes < minTall) {
            continue; // a face that never rises above minHeightM: a bump, not an obstacle
        }
        // Where the ground ends, the rays that would have met it within the window go down into the drop: the
        // negative votes must outnumber the ground seen at those ranges (a matcher's error on a road leaves the
        // road around it).
        if (drop && static_cast<float>(votes) < config_.minDropShare * static_cast<float>(votes + tallVotes)) {
            continue;
        }
        // ... and the ground must be seen up to it: a near rim, the last ground before the drop. Below-ground
        // disparities in the nearest rows with no ground in front of them are no evidence of a drop.
        if (drop) {
            const int rimBins = std::max(1, static_cast<int>(config_.rimWindowFraction * r0 / config_.rangeBinM));
            std::uint32_t rim = 0;
            for (int b = std::max(0, start - rimBins); b < start; ++b) {
                rim += tall[b];
            }
            if (rim < static_cast<std::uint32_t>(config_.minRimVotes)) {
                continue;
            }
        }
        // A drop's visible part shrinks with the square of its range (a strip of wall, not a face): beyond
        // dropSupportRangeM it needs proportionally fewer votes, never fewer than minDropSupport.
        if (drop && r0 > config_.dropSupportRangeM) {
            const float scale = config_.dropSupportRangeM / r0;
            minSupport = static_cast<std::uint32_t>(std::max(static_cast<float>(config_.minDropSupport),
                                                             static_cast<float>(config_.minSupport) * scale * scale));
        }
        if (votes < minSupport) {
            continue;
        }
        if (drop && !wallLike(dropSector, start, end)) {
            continue; // a surface below the ground, not a wall
        }
        // Quantile of the votes inside the window; the range is the centre of that bin.
        const auto target = static_cast<std::uint32_t>(percentile * static_cast<float>(votes));
        std::uint32_t cumulative = 0;
        int b = start;
        for (; b < end; ++b) {
            cumulative += histogram[b];
            if (cumulative > target) {
                break;
            }
        }
        return Cluster{static_cast<int>(votes), (static_cast<float>(b) + 0.5F) * config_.rangeBinM, start, end};
    }
    return Cluster{};
}

SectorBuilder::ProfileRow SectorBuilder::profileRow(int s, int v) const noexcept
{
    const int first = std::max(0, s - 1);
    const int last = std::min(config_.sectorCount - 1, s + 1);
    const auto rows = static_cast<std::size_t>(profileRows_);
    ProfileRow r;
    for (int k = first; k <= last; ++k) {
        const std::size_t i = static_cast<std::size_t>(k) * rows + static_cast<std::size_t>(v);
        r.count += rowCount_[i];
        r.labels += rowDropLabels_[i];
        r.residual += rowResidual_[i];
        r.crossing += rowCrossing_[i];
        r.disparity += rowDisparity_[i];
    }
    if (r.count > 0) {
        r.disparity /= static_cast<float>(r.count);
        r.residual /= static_cast<float>(r.count);
        r.crossing /= static_cast<float>(r.count);
    }
    return r;
}

float SectorBuilder::profileThreshold(int s) const noexcept
{
    // dropProfileResidualPx, or the spread of this frame's row means over the far rows (1.4826 x their median
    // absolute value: the far rows' residuals from the plane, centred on 0) times the noise factor, whichever is
    // larger.
    const auto minPixels = static_cast<std::uint32_t>(config_.dropProfileMinPixels);
    std::array<float, kMaxProfileRows> spread{};
    int spreadCount = 0;
    for (int v = 0; v < profileRows_ && spreadCount < kMaxProfileRows; ++v) {
        const ProfileRow r = profileRow(s, v);
        if (r.count >= minPixels && r.crossing >= config_.dropProfileMinRangeM && r.crossing < config_.maxRangeM) {
            spread[static_cast<std::size_t>(spreadCount++)] = std::abs(r.residual);
        }
    }
    float noise = 0.0F;
    if (spreadCount > 0) {
        auto* middle = spread.data() + spreadCount / 2;
        std::nth_element(spread.data(), middle, spread.data() + spreadCount);
        noise = 1.4826F * *middle;
    }
    return std::max(config_.dropProfileResidualPx, config_.dropProfileNoiseFactor * noise);
}

bool SectorBuilder::ownRowsBelow(int s, int w1, int w2, float tau) const noexcept
{
    const std::size_t own = static_cast<std::size_t>(s) * static_cast<std::size_t>(profileRows_);
    const std::uint32_t ownCount =
        rowCount_[own + static_cast<std::size_t>(w1)] + rowCount_[own + static_cast<std::size_t>(w2)];
    const float ownResidual =
        rowResidual_[own + static_cast<std::size_t>(w1)] + rowResidual_[own + static_cast<std::size_t>(w2)];
    return ownCount != 0 && ownResidual < -tau * static_cast<float>(ownCount) * 0.5F;
}

bool SectorBuilder::farRimAbove(int s, int w2, float tau) const noexcept
{
    constexpr int kMaxWallRows = 12; ///< rows above the wall that may show the far rim
    const auto minPixels = static_cast<std::uint32_t>(config_.dropProfileMinPixels);
    bool farRim = false;
    for (int w = w2 - 1; w >= std::max(0, w2 - kMaxWallRows) && !farRim; --w) {
        const ProfileRow r = profileRow(s, w);
        farRim = r.count >= minPixels && r.residual > -0.5F * tau;
    }
    return farRim;
}

bool SectorBuilder::profileWall(const ProfileRow& wall1, const ProfileRow& wall2) const noexcept
{
    const float groundStep = (wall1.disparity - wall1.residual) - (wall2.disparity - wall2.residual);
    const float slope = (wall1.disparity - wall2.disparity) / groundStep;
    const float slopeError =
        disparityNoisePx_ * std::sqrt(1.0F / static_cast<float>(wall1.count) + 1.0F / static_cast<float>(wall2.count)) /
        std::abs(groundStep);
    return std::abs(slope) + config_.wallSlopeSigmas * slopeError < config_.maxWallSlope;
}

SectorBuilder::Cluster SectorBuilder::profileDrop(int s) const noexcept
{
    constexpr int kMaxBlendRows = 2;
    const auto minPixels = static_cast<std::uint32_t>(config_.dropProfileMinPixels);
    const float tau = profileThreshold(s);
    bool suspect = false;
    // From the nearest row up: the first rim beyond dropProfileMinRangeM.
    for (int v = profileRows_ - 1; v >= 2; --v) {
        const ProfileRow rim = profileRow(s, v);
        if (rim.count < minPixels || rim.crossing < config_.dropProfileMinRangeM) {
            continue;
        }
        if (rim.crossing >= config_.maxRangeM) {
            break;
        }
        if (!(rim.residual > -0.5F * tau)) {
            continue;
        }
        // The wall: two rows below -tau, right above the rim or above up to kMaxBlendRows rows between them that
        // are halfway down or sparse but not empty (the matcher blends the rim into the wall's bottom row, and the
        // verifier removes much of that row: its windows straddle the rim).
        for (int gap = 0; gap <= kMaxBlendRows && v - gap - 2 >= 0; ++gap) {
            if (gap > 0) {
                const ProfileRow blend = profileRow(s, v - gap);
                // A row with no valid pixel is no evidence that the wall goes on down to the rim.
                if (blend.count == 0 || (blend.count >= minPixels && !(blend.residual < -0.5F * tau))) {
                    break;
                }
            }
            const int w1 = v - gap - 1;
            const int w2 = v - gap - 2;
            const ProfileRow wall1 = profileRow(s, w1);
            const ProfileRow wall2 = profileRow(s, w2);
            if (wall1.count < minPixels || wall2.count < minPixels || !(wall1.residual < -tau) ||
                !(wall2.residual < -tau)) {
                continue;
            }
            // The sector itself must see the wall, not only a neighbour.
            if (!ownRowsBelow(s, w1, w2, tau)) {
                continue;
            }
            // A wall seen by one cue only, or with no far rim, is not a drop; but the ground is not seen to be
            // free there either (Unknown, never Clear).
            if (!farRimAbove(s, w2, tau) ||
                wall1.labels + wall2.labels < static_cast<std::uint32_t>(config_.dropProfileMinLabels)) {
                suspect = true;
                continue;
            }
            // ... and the two wall rows are a wall.
            if (!profileWall(wall1, wall2)) {
                suspect = true;
                continue;
            }
            return Cluster{static_cast<int>(wall1.count + wall2.count), 0.5F * (rim.crossing + wall1.crossing)};
        }
    }
    Cluster none;
    none.suspect = suspect;
    return none;
}

BuildStatus SectorBuilder::build(ImageView<const std::int16_t> disparity16, ConstImageViewU8 labels,
                                 const GroundPlane& ground, std::uint64_t sequence, std::int64_t stampNs) noexcept
{
    const BuildStatus status = checkInputs(disparity16, labels, sequence, stampNs);
    if (status != BuildStatus::Ok) {
        return status;
    }
    resetAccumulators();
    finish(collectPerRow(disparity16, labels, ground), ground, sequence, stampNs);
    return BuildStatus::Ok;
}

BuildStatus SectorBuilder::buildReference(ImageView<const std::int16_t> disparity16, ConstImageViewU8 labels,
                                          const GroundPlane& ground, std::uint64_t sequence,
                                          std::int64_t stampNs) noexcept
{
    const BuildStatus status = checkInputs(disparity16, labels, sequence, stampNs);
    if (status != BuildStatus::Ok) {
        return status;
    }
    resetAccumulators();
    finish(collectPerPixel(disparity16, labels, ground), ground, sequence, stampNs);
    return BuildStatus::Ok;
}

BuildStatus SectorBuilder::checkInputs(ImageView<const std::int16_t> disparity16, ConstImageViewU8 labels,
                                       std::uint64_t sequence, std::int64_t stampNs) noexcept
{
    if (disparity16.data() == nullptr || disparity16.width() != roi_.width || disparity16.height() != roi_.height) {
        setAllUnknown(sequence, stampNs);
        return BuildStatus::WrongDisparitySize;
    }
    if (!labels.empty() && (labels.width() != roi_.width || labels.height() != roi_.height)) {
        setAllUnknown(sequence, stampNs);
        return BuildStatus::WrongLabelSize;
    }
    return BuildStatus::Ok;
}

void SectorBuilder::resetAccumulators() noexcept
{
    localGround_.clear();
    std::fill(histograms_.begin(), histograms_.end(), 0U);
    std::fill(extremes_.begin(), extremes_.end(), 0.0F);
    std::fill(tallVotes_.begin(), tallVotes_.end(), 0U);
    std::fill(groundByRange_.begin(), groundByRange_.end(), 0U);
    std::fill(dropDistance_.begin(), dropDistance_.end(), 0.0F);
    std::fill(wallSums_.begin(), wallSums_.end(), WallSums{});
    std::fill(groundVotes_.begin(), groundVotes_.end(), 0U);
    std::fill(farGroundVotes_.begin(), farGroundVotes_.end(), 0U);
    std::fill(kindVotes_.begin(), kindVotes_.end(), 0U);
    std::fill(rowCount_.begin(), rowCount_.end(), 0U);
    std::fill(rowResidual_.begin(), rowResidual_.end(), 0.0F);
    std::fill(rowCrossing_.begin(), rowCrossing_.end(), 0.0F);
    std::fill(rowDisparity_.begin(), rowDisparity_.end(), 0.0F);
    std::fill(rowDropLabels_.begin(), rowDropLabels_.end(), 0U);
}

int SectorBuilder::minDisparity16() const noexcept
{
    // Disparities below this are farther than maxRangeM even straight ahead: skipped early.
    return static_cast<int>(std::floor(projection_.fx * projection_.baselineM / config_.maxRangeM * kDisparityScale));
}

void SectorBuilder::addPoint(std::size_t& count, int s, int v, float range, float z, int d16, const std::uint8_t* label,
                             int u) noexcept
{
    points_[count++] = PixelPoint{range,
                                  z,
                                  0.0F,
                                  static_cast<std::int16_t>(s),
                                  static_cast<std::int16_t>(v),
                                  static_cast<std::int16_t>(d16),
                                  label != nullptr ? label[u] : static_cast<std::uint8_t>(0)};
    localGround_.add(s, range, z);
}

std::size_t SectorBuilder::collectPerPixel(ImageView<const std::int16_t> disparity16, ConstImageViewU8 labels,
                                           const GroundPlane& ground) noexcept
{
    const bool haveLabels = !labels.empty();
    const int minDisparity16 = this->minDisparity16();
    const float binDeg = hfovDeg_ / static_cast<float>(config_.sectorCount);
    std::size_t count = 0;
    for (int v = firstRow_ - roi_.y; v < roi_.height; ++v) {
        const std::int16_t* d16 = disparity16.row(v);
        const std::uint8_t* label = haveLabels ? labels.row(v) : nullptr;
        const double yFull = v + roi_.y;
        for (int u = 0; u < roi_.width; ++u) {
            if (d16[u] <= 0 || d16[u] < minDisparity16) {
                continue;
            }
            const double d = static_cast<double>(d16[u]) / kDisparityScale;
            const VehiclePoint p = ground.pixelToVehicle(u + roi_.x, yFull, d, projection_);
            const auto range = static_cast<float>(std::hypot(p.x, p.y));
            if (!(p.x > 0.0) || range >= config_.maxRangeM) {
                continue;
            }
            const auto bearing = static_cast<float>(std::atan2(p.y, p.x) * kRadToDeg);
            const int s = static_cast<int>(std::floor((bearing + hfovDeg_ / 2.0F) / binDeg));
            if (s < 0 || s >= config_.sectorCount) {
                continue;
            }
            addPoint(count, s, v - (firstRow_ - roi_.y), range, static_cast<float>(p.z), d16[u], label, u);
        }
    }
    return count;
}

std::size_t SectorBuilder::collectPerRow(ImageView<const std::int16_t> disparity16, ConstImageViewU8 labels,
                                         const GroundPlane& ground) noexcept
{
    const bool haveLabels = !labels.empty();
    const int minDisparity16 = this->minDisparity16();
    std::size_t count = 0;
    // For a fixed plane the vehicle point of pixel (u, v) at disparity d is linear in 1/d:
    // with the ray r = ((u - cx)/fx, (v - cy)/fy, 1) and depth Z = fx B / d, GroundPlane::toVehicle gives
    // x = Z (r . F) / |F|, y = Z (r . L) / |F|, z = h + Z (r . U) (F forward, L left, U up, unnormalised as
    // toVehicle). So the bearing atan2(y, x) = atan2(r . L, r . F) does not depend on d, the range is
    // Z |(r.F, r.L)| / |F| and the height h + Z (r . U). Per row, r . F, r . L and r . U are linear in u; the
    // sector of a pixel is found by walking the sector boundaries (bearing monotone along a row) instead of
    // an atan2 per pixel, and the range and height factors are computed once per pixel of the row.
    // Equal to the reference up to double rounding (the last bits of Z r . F vs the reference's order of
    // operations): the sectors are equal on the simulator scenes (sector_builder_test.cpp).
    const GroundAxes axes = groundAxes(ground);
    const double fb = projection_.fx * projection_.baselineM * kDisparityScale; // Z = fb / d16
    const int boundaries = config_.sectorCount + 1;
    for (int v = firstRow_ - roi_.y; v < roi_.height; ++v) {
        const std::int16_t* d16 = disparity16.row(v);
        const std::uint8_t* label = haveLabels ? labels.row(v) : nullptr;
        const double ry = (v + roi_.y - projection_.cy) / projection_.fy;
        const double du = 1.0 / projection_.fx; // d r.x / d u
        const double rx0 = (roi_.x - projection_.cx) / projection_.fx;
        // r . A = (A.x rx0 + A.y ry + A.z) + A.x du u
        const double f0 = axes.f[0] * rx0 + axes.f[1] * ry + axes.f[2];
        const double f1 = axes.f[0] * du;
        const double l0 = axes.l[0] * rx0 + axes.l[1] * ry + axes.l[2];
        const double l1 = axes.l[0] * du;
        const double up0 = axes.u[0] * rx0 + axes.u[1] * ry + axes.u[2];
        const double up1 = axes.u[0] * du;
        for (int k = 0; k < boundaries; ++k) {
            const auto ku = static_cast<std::size_t>(k);
            // Bearing >= boundary k  <=>  g_k(u) = (r.L) cos(b_k) - (r.F) sin(b_k) >= 0 (for r.F > 0).
            boundary0_[ku] = l0 * boundaryCos_[ku] - f0 * boundarySin_[ku];
            boundary1_[ku] = l1 * boundaryCos_[ku] - f1 * boundarySin_[ku];
        }
        int s = -1; // number of boundaries at or below the bearing, minus 1
        for (int u = 0; u < roi_.width; ++u) {
            const double uu = u;
            const double rf = f0 + f1 * uu;
            // The walk runs for every pixel so that s stays near the bearing; it is only used where r.F > 0.
            while (s + 1 < boundaries &&
                   boundary0_[static_cast<std::size_t>(s + 1)] + boundary1_[static_cast<std::size_t>(s + 1)] * uu >=
                       0.0) {
                ++s;
            }
            while (s >= 0 &&
                   boundary0_[static_cast<std::size_t>(s)] + boundary1_[static_cast<std::size_t>(s)] * uu < 0.0) {
                --s;
            }
            if (d16[u] <= 0 || d16[u] < minDisparity16 || !(rf > 0.0) || s < 0 || s >= config_.sectorCount) {
                continue;
            }
            const double z = fb / static_cast<double>(d16[u]);
            const double rl = l0 + l1 * uu;
            const auto range = static_cast<float>(z * std::sqrt(rf * rf + rl * rl) * axes.invNorm);
            if (range >= config_.maxRangeM) {
                continue;
            }
            addPoint(count, s, v - (firstRow_ - roi_.y), range,
                     static_cast<float>(ground.heightM + z * (up0 + up1 * uu)), d16[u], label, u);
        }
    }
    return count;
}

void SectorBuilder::vote(const PixelPoint& p, const VoteLimits& limits) noexcept
{
    const int s = p.sector;
    const int v = p.row;
    float range = p.rangeM;
    const float zPlane = p.z;
    const int d16 = p.d16;
    const std::uint8_t labelValue = p.label;
    const float groundHeight = limits.groundHeight;
    const float dropResidualPx = limits.dropResidualPx;
    const auto bins = static_cast<std::size_t>(bins_);
    // Row profile: residual d - d_g = d z / h (d / d_g = h / (h - z) along one ray) and the ray's ground
    // crossing, range h / (h - z) (a function of the pixel only; only rays that meet the ground ahead).
    if (zPlane < groundHeight) {
        const std::size_t row =
            static_cast<std::size_t>(s) * static_cast<std::size_t>(profileRows_) + static_cast<std::size_t>(v);
        ++rowCount_[row];
        rowDropLabels_[row] += labelValue == kLabelNegative ? 1U : 0U;
        rowResidual_[row] += static_cast<float>(d16) / kDisparityScale * zPlane / groundHeight;
        rowCrossing_[row] += range * groundHeight / (groundHeight - zPlane);
        rowDisparity_[row] += static_cast<float>(d16) / kDisparityScale;
    }
    const float z = p.zLocal;
    int kind = -1;
    // The height noise grows with the range (a disparity error e moves a ground point's height by
    // h r e / (fx B)): beyond where it reaches minHeightM / heightNoiseFactor, a positive vote must rise above
    // heightNoiseFactor times it.
    const float noiseHeight = limits.heightNoisePerM * range;
    if (z > std::max(limits.faceHeight, noiseHeight)) {
        kind = 0;
    } else if ((z < -config_.minDepthM ||
                (z < -config_.minDropDepthM && range * -z >= config_.minDropGapM * (groundHeight - z))) &&
               static_cast<float>(d16) / kDisparityScale * z / groundHeight < -dropResidualPx) {
        kind = 1;
    } else {
        ++groundVotes_[static_cast<std::size_t>(s)];
        ++groundByRange_[static_cast<std::size_t>(s) * bins + static_cast<std::size_t>(range / config_.rangeBinM)];
        farGroundVotes_[static_cast<std::size_t>(s)] += range >= config_.clearRangeM ? 1U : 0U;
        return;
    }
    const std::uint8_t wanted = kind == 0 ? kLabelPositive : kLabelNegative;
    const bool labelled = labelValue == wanted;
    const std::size_t slot = static_cast<std::size_t>(s) * kKinds + static_cast<std::size_t>(kind);
    // Face votes (below minHeightM) support a cluster but do not forbid Clear by themselves.
    const bool tall = kind == 1 || z > std::max(config_.minHeightM, noiseHeight);
    // A drop vote where the two images' block grids meet: the matcher's lock onto the blocks' edges, no evidence.
    const bool gridLock = kind == 1 && gridOffsetPx_ >= 0 && onBlockGrid(d16, gridOffsetPx_);
    if ((!labelled && !config_.useDenseCue) || gridLock) {
        kindVotes_[slot] += tall ? 1U : 0U; // unconfirmed: not an obstacle, but it forbids Clear
        return;
    }
    const std::uint32_t weight = 1U + (labelled ? static_cast<std::uint32_t>(config_.labelWeight) : 0U);
    // A drop's range is where the ground ends: the ray from the camera (height h) to the point below the
    // ground crosses the ground plane at h / (h - z) of the point's horizontal range (the near rim).
    const float ownRange = range;
    if (kind == 1) {
        range *= static_cast<float>(limits.groundHeightM / (limits.groundHeightM - static_cast<double>(z)));
    }
    const auto bin = static_cast<std::size_t>(range / config_.rangeBinM);
    if (kind == 1) {
        dropDistance_[static_cast<std::size_t>(s) * bins + bin] += ownRange * static_cast<float>(weight);
        const double own = static_cast<double>(d16) / kDisparityScale;
        const double groundD = own - own * static_cast<double>(z / groundHeight); // d - residual d z / h
        WallSums& w = wallSums_[static_cast<std::size_t>(s) * static_cast<std::size_t>(wallBins_) +
                                bin / static_cast<std::size_t>(wallBinRatio_)];
        w.n += 1.0;
        w.g += groundD;
        w.o += own;
        w.gg += groundD * groundD;
        w.go += groundD * own;
        w.oo += own * own;
    }
    histograms_[slot * bins + bin] += weight;
    float& extreme = extremes_[slot * bins + bin];
    extreme = std::max(extreme, std::fabs(z));
    if (tall) {
        kindVotes_[slot] += weight;
        if (kind == 0) {
            tallVotes_[static_cast<std::size_t>(s) * bins + bin] += weight;
        }
    }
}

void SectorBuilder::finish(std::size_t pointCount, const GroundPlane& ground, std::uint64_t sequence,
                           std::int64_t stampNs) noexcept
{
    // First pass (collectPer*): every analysed pixel's sector, range and height above the plane, and the local
    // ground's histograms; second pass: the votes, with heights above the local ground.
    if (config_.useLocalGround) {
        localGround_.fit();
    }
    for (std::size_t i = 0; i < pointCount; ++i) {
        PixelPoint& p = points_[i];
        p.zLocal = p.z - localGround_.at(p.sector, p.rangeM);
    }
    const auto groundHeight = static_cast<float>(ground.heightM);
    groundHeight_ = groundHeight;
    disparityNoisePx_ = groundNoise(pointCount);
    VoteLimits limits;
    limits.groundHeightM = ground.heightM;
    limits.groundHeight = groundHeight;
    limits.faceHeight = config_.faceHeightFraction * config_.minHeightM;
    limits.heightNoisePerM = config_.heightNoiseFactor * disparityNoisePx_ * groundHeight /
                             static_cast<float>(projection_.fx * projection_.baselineM);
    limits.dropResidualPx = config_.dropNoiseFactor * disparityNoisePx_;
    for (std::size_t i = 0; i < pointCount; ++i) {
        vote(points_[i], limits);
    }
    classifySectors(sequence, stampNs);
    widenDrops();
    closeGaps();
}

void SectorBuilder::classifySectors(std::uint64_t sequence, std::int64_t stampNs) noexcept
{
    const auto bins = static_cast<std::size_t>(bins_);
    initSectors(sectors_, config_.sectorCount, hfovDeg_);
    sectors_.sequence = sequence;
    sectors_.captureStampNs = stampNs;
    sectors_.degraded = false;
    const auto heightWindowBins = static_cast<int>(std::ceil(0.10F / config_.rangeBinM)); // as the GT: 0.10 m
    for (int s = 0; s < config_.sectorCount; ++s) {
        const std::size_t slot0 = static_cast<std::size_t>(s) * kKinds;
        positives_[static_cast<std::size_t>(s)] = nearestCluster(
            &histograms_[slot0 * bins], &tallVotes_[static_cast<std::size_t>(s) * bins], config_.rangePercentile, -1);
    }
    for (int s = 0; s < config_.sectorCount; ++s) {
        const std::size_t slot0 = static_cast<std::size_t>(s) * kKinds;
        Cluster negative =
            nearestCluster(&histograms_[(slot0 + 1) * bins], &groundByRange_[static_cast<std::size_t>(s) * bins],
                           config_.dropRangePercentile, s);
        if (negative.votes > 0 && explainedByObstacle(s, negative, positives_)) {
            negative = Cluster{};
        }
        if (const Cluster far = profileDrop(s);
            far.votes > 0 && (negative.votes == 0 || far.rangeM < negative.rangeM)) {
            negative = far;
        } else {
            negative.suspect = negative.suspect || far.suspect;
        }
        negatives_[static_cast<std::size_t>(s)] = negative;
    }
    keepContinuousDrops();
    for (int s = 0; s < config_.sectorCount; ++s) {
        Sector& out = sectors_.sectors[static_cast<std::size_t>(s)];
        const std::size_t slot0 = static_cast<std::size_t>(s) * kKinds;
        const Cluster& positive = positives_[static_cast<std::size_t>(s)];
        const Cluster& negative = negatives_[static_cast<std::size_t>(s)];
        const bool havePositive = positive.votes > 0;
        const bool haveNegative = negative.votes > 0;
        if (havePositive || haveNegative) {
            const bool pickPositive = havePositive && (!haveNegative || positive.rangeM <= negative.rangeM);
            const Cluster& c = pickPositive ? positive : negative;
            const std::size_t slot = slot0 + (pickPositive ? 0U : 1U);
            const int first = static_cast<int>(c.rangeM / config_.rangeBinM);
            float extreme = 0.0F;
            for (int b = std::max(0, first - 1); b < std::min(bins_, first + heightWindowBins + 1); ++b) {
                extreme = std::max(extreme, extremes_[slot * bins + static_cast<std::size_t>(b)]);
            }
            out.state = SectorState::Obstacle;
            out.kind = pickPositive ? ObstacleKind::Positive : ObstacleKind::Negative;
            out.rangeM = c.rangeM;
            out.heightM = extreme;
            out.confidence = std::min(1.0F, static_cast<float>(c.votes) / config_.confidenceSupport);
        } else {
            // Stray votes that make no cluster still forbid Clear: a far drop seen over too few pixels is
            // Unknown, never Clear.
            const bool stray = kindVotes_[slot0] >= static_cast<std::uint32_t>(config_.maxStrayVotes) ||
                               kindVotes_[slot0 + 1] >= static_cast<std::uint32_t>(config_.maxStrayDropVotes) ||
                               negative.suspect;
            const auto pixels = static_cast<float>(pixelsPerSector_[static_cast<std::size_t>(s)]);
            const float groundFraction =
                pixels > 0.0F ? static_cast<float>(groundVotes_[static_cast<std::size_t>(s)]) / pixels : 0.0F;
            if (!stray && groundFraction >= config_.clearGroundFraction &&
                farGroundVotes_[static_cast<std::size_t>(s)] >= static_cast<std::uint32_t>(config_.minClearFarVotes)) {
                out.state = SectorState::Clear;
                out.rangeM = std::numeric_limits<float>::infinity();
                out.confidence = std::min(1.0F, groundFraction);
            }
        }
        out.danger = classify(out.state, out.rangeM, config_.dangerDistanceM, config_.cautionDistanceM);
    }
}

void SectorBuilder::keepContinuousDrops() noexcept
{
    // A drop's rim is a line on the ground: a neighbouring sector sees it too, at a range that follows. A negative
    // cluster alone among its neighbours is a matcher's error on a weak or saturated patch.
    const int n = config_.sectorCount;
    std::array<bool, kMaxSectors> keep{};
    for (int s = 0; s < n; ++s) {
        const Cluster& c = negatives_[static_cast<std::size_t>(s)];
        if (c.votes == 0) {
            continue;
        }
        for (int k = std::max(0, s - 1); k <= std::min(n - 1, s + 1); ++k) {
            const Cluster& other = negatives_[static_cast<std::size_t>(k)];
            keep[static_cast<std::size_t>(s)] =
                keep[static_cast<std::size_t>(s)] ||
                (k != s && other.votes > 0 &&
                 std::abs(other.rangeM - c.rangeM) <= config_.clusterFraction * c.rangeM + config_.explainWindowM);
        }
    }
    for (int s = 0; s < n; ++s) {
        Cluster& c = negatives_[static_cast<std::size_t>(s)];
        if (c.votes > 0 && !keep[static_cast<std::size_t>(s)]) {
            c = Cluster{};
            c.suspect = true; // seen, not confirmed: Unknown, never Clear
        }
    }
}

bool SectorBuilder::explainedByObstacle(int s, const Cluster& drop,
                                        const std::array<Cluster, kMaxSectors>& positives) const noexcept
{
    const auto bins = static_cast<std::size_t>(bins_);
    const std::size_t slot = (static_cast<std::size_t>(s) * kKinds + 1U) * bins;
    float votes = 0.0F;
    float distance = 0.0F;
    for (int b = drop.firstBin; b < drop.endBin; ++b) {
        votes += static_cast<float>(histograms_[slot + static_cast<std::size_t>(b)]);
        distance += dropDistance_[static_cast<std::size_t>(s) * bins + static_cast<std::size_t>(b)];
    }
    if (!(votes > 0.0F)) {
        return false;
    }
    const float own = distance / votes; // [m] mean own range of the drop's pixels
    for (int k = std::max(0, s - 1); k <= std::min(config_.sectorCount - 1, s + 1); ++k) {
        const Cluster& p = positives[static_cast<std::size_t>(k)];
        if (p.votes > 0 && std::abs(p.rangeM - own) <= config_.clusterFraction * own + config_.explainWindowM) {
            return true;
        }
    }
    return false;
}

float SectorBuilder::groundNoise(std::size_t pointCount) noexcept
{
    // 1.4826 x the median |d - d_ground| [px] of the ground-like pixels (within the local ground's band): the
    // matcher's noise on this frame's ground, robust to the obstacles' pixels.
    constexpr float kBinsPerPx = 32.0F;
    std::fill(noiseHistogram_.begin(), noiseHistogram_.end(), 0U);
    std::uint32_t total = 0;
    for (std::size_t i = 0; i < pointCount; ++i) {
        const PixelPoint& p = points_[i];
        const float dz = p.zLocal;
        if (!(std::abs(dz) < config_.localGround.bandM)) {
            continue;
        }
        const float residual = std::abs(static_cast<float>(p.d16) / kDisparityScale * dz) / groundHeight_;
        const float scaled = residual * kBinsPerPx; // NaN or huge (a degenerate plane): the last bin
        const std::size_t last = noiseHistogram_.size() - 1;
        const std::size_t bin = scaled < static_cast<float>(last) ? static_cast<std::size_t>(scaled) : last;
        ++noiseHistogram_[bin];
        ++total;
    }
    std::uint32_t cumulative = 0;
    for (std::size_t b = 0; b < noiseHistogram_.size(); ++b) {
        cumulative += noiseHistogram_[b];
        if (2U * cumulative > total) {
            return 1.4826F * (static_cast<float>(b) + 0.5F) / kBinsPerPx;
        }
    }
    return 0.0F;
}

void SectorBuilder::reportNeighbour(Sector& out, const Sector& from) const noexcept
{
    out.state = SectorState::Obstacle;
    out.kind = from.kind;
    out.rangeM = from.rangeM;
    out.heightM = from.heightM;
    out.confidence = 0.5F * from.confidence; // inferred from the neighbour, not seen
    out.danger = classify(out.state, out.rangeM, config_.dangerDistanceM, config_.cautionDistanceM);
}

void SectorBuilder::widenDrops() noexcept
{
    // A hole's rim runs out at a grazing angle at its lateral ends: there its far wall shows only a sliver, too
    // few pixels to vote, so the detected drop is narrower than the true one. A Clear sector next to a negative
    // obstacle is therefore reported as that drop (the nearer neighbour's range), never as Clear. Decided on the
    // sectors as built, so a drop widens by dropEdgeSectors and no more.
    const int n = config_.sectorCount;
    std::array<bool, kMaxSectors> drop{};
    for (int s = 0; s < n; ++s) {
        const Sector& c = sectors_.sectors[static_cast<std::size_t>(s)];
        drop[static_cast<std::size_t>(s)] = c.state == SectorState::Obstacle && c.kind == ObstacleKind::Negative;
    }
    for (int s = 0; s < n; ++s) {
        Sector& out = sectors_.sectors[static_cast<std::size_t>(s)];
        if (out.state != SectorState::Clear) {
            continue;
        }
        const Sector* nearest = nullptr;
        for (int k = std::max(0, s - config_.dropEdgeSectors); k <= std::min(n - 1, s + config_.dropEdgeSectors); ++k) {
            const Sector& c = sectors_.sectors[static_cast<std::size_t>(k)];
            if (drop[static_cast<std::size_t>(k)] && (nearest == nullptr || c.rangeM < nearest->rangeM)) {
                nearest = &c;
            }
        }
        if (nearest != nullptr) {
            reportNeighbour(out, *nearest);
        }
    }
}

void SectorBuilder::closeGaps() noexcept
{
    // A far curb's face is a row or two per sector: some sectors get too few votes for a cluster and their ground
    // is seen free, so they would be Clear between sectors that see the curb. A gap narrower than closeGapM between
    // two obstacles is not a way through for any vehicle either: it reports the nearer side, at half confidence.
    // Only runs of Clear sectors: Unknown ones stay Unknown.
    const int n = config_.sectorCount;
    const double binRad = static_cast<double>(hfovDeg_) / n * (std::numbers::pi / 180.0);
    int left = -1; // the last obstacle sector seen
    for (int s = 0; s < n; ++s) {
        const Sector& c = sectors_.sectors[static_cast<std::size_t>(s)];
        if (c.state == SectorState::Unknown) {
            left = -1;
            continue;
        }
        if (c.state != SectorState::Obstacle) {
            continue;
        }
        if (left >= 0 && s - left > 1) {
            const Sector& a = sectors_.sectors[static_cast<std::size_t>(left)];
            // The two obstacles' points nearest each other: at the run's edges, the angle between is the run's.
            const double angle = (s - left - 1) * binRad;
            const double ra = a.rangeM;
            const double rb = c.rangeM;
            const double gap = std::sqrt(std::max(0.0, ra * ra + rb * rb - 2.0 * ra * rb * std::cos(angle)));
            if (gap < config_.closeGapM) {
                const Sector& nearer = ra <= rb ? a : c;
                for (int k = left + 1; k < s; ++k) {
                    reportNeighbour(sectors_.sectors[static_cast<std::size_t>(k)], nearer);
                }
            }
        }
        left = s;
    }
}

} // namespace ugv::vision
