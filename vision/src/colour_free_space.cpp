#include "ugv/vision/colour_free_space.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "ugv/platform/angles.hpp"
#include <opencv2/core/hal/intrin.hpp>

namespace ugv::vision {
namespace {

constexpr int kMaxWindowRadius = 15; // int16 window counts: (2 r + 1)^2 <= 961, far below 32767
constexpr int kScoreMax = 255;
constexpr int kHueRange = 180; // OpenCV 8-bit hue 0..179
constexpr int kSatShift = 5;   // 256 / kSatBins
constexpr int kBlurTaps = 9;   // 3x3 box

Error configError(const std::string& what, const std::string& fix)
{
    return Error{"ColourFreeSpaceConfig", what, fix};
}

/// OpenCV's 8-bit BGR -> HSV (hue 0..179, saturation and value 0..255), reduced to the bin index.
inline std::uint8_t colourBin(int b, int g, int r, int& sat, int& value) noexcept
{
    const int v = std::max({b, g, r});
    const int diff = v - std::min({b, g, r});
    value = v;
    sat = v == 0 ? 0 : (diff * kScoreMax + v / 2) / v;
    int hue2 = 0; // hue in [0, 360) degrees
    if (diff > 0) {
        if (v == r) {
            hue2 = 60 * (g - b) / diff;
        } else if (v == g) {
            hue2 = 120 + 60 * (b - r) / diff;
        } else {
            hue2 = 240 + 60 * (r - g) / diff;
        }
        if (hue2 < 0) {
            hue2 += 360;
        }
    }
    const int hue = std::min(hue2 / 2, kHueRange - 1);
    const int hueBin = hue * kHueBins / kHueRange;
    return static_cast<std::uint8_t>(hueBin * kSatBins + (sat >> kSatShift));
}

/// Intersection sum_b min(window_b, ref_b); at most the window area (<= 961), so int16 lanes cannot overflow.
inline int intersect(const std::int16_t* window, const std::int16_t* ref) noexcept
{
    int common = 0;
    for (int b = 0; b < kColourBins; ++b) {
        common += std::min(window[b], ref[b]);
    }
    return common;
}

/// window += enter - leave (one column in, one out), then intersect(window, ref). Counts stay within
/// [0, window area], so the saturating 16-bit lane arithmetic of the vector path equals the scalar one.
inline int slideAndIntersect(std::int16_t* window, const std::int16_t* enter, const std::int16_t* leave,
                             const std::int16_t* ref) noexcept
{
    int b = 0;
    int common = 0;
#if CV_SIMD128
    constexpr int kLanes = cv::v_int16x8::nlanes;
    cv::v_int16x8 sum = cv::v_setzero_s16();
    for (; b + kLanes <= kColourBins; b += kLanes) {
        const cv::v_int16x8 w = cv::v_load(window + b) + cv::v_load(enter + b) - cv::v_load(leave + b);
        cv::v_store(window + b, w);
        sum += cv::v_min(w, cv::v_load(ref + b));
    }
    common = cv::v_reduce_sum(sum);
#endif
    for (; b < kColourBins; ++b) {
        window[b] = static_cast<std::int16_t>(window[b] + enter[b] - leave[b]);
        common += std::min(window[b], ref[b]);
    }
    return common;
}

/// First ROI row [px]: roiTopFraction of the image height, rounded.
int roiTopRow(const ColourFreeSpaceConfig& config, cv::Size imageSize)
{
    return static_cast<int>(std::lround(imageSize.height * config.roiTopFraction));
}

/// The config's sizes, fractions and thresholds against each other and the image size.
Result<void, Error> checkConfig(const ColourFreeSpaceConfig& config, cv::Size imageSize)
{
    const int r = config.windowRadius;
    const int win = 2 * r + 1;
    if (r < 1 || r > kMaxWindowRadius) {
        return Unexpected(configError("windowRadius " + std::to_string(r) + " is out of range",
                                      "use 1.." + std::to_string(kMaxWindowRadius)));
    }
    if (imageSize.width < win || imageSize.height < win) {
        return Unexpected(configError("image size " + std::to_string(imageSize.width) + "x" +
                                          std::to_string(imageSize.height) + " is smaller than the window",
                                      "give the camera's image size"));
    }
    if (!(config.roiTopFraction >= 0.0 && config.roiTopFraction < 1.0)) {
        return Unexpected(configError("roiTopFraction " + std::to_string(config.roiTopFraction) + " is outside [0, 1)",
                                      "use e.g. 0.5 (bottom half)"));
    }
    const int roiTop = roiTopRow(config, imageSize);
    if (imageSize.height - roiTop < win) {
        return Unexpected(configError("the ROI has fewer rows than the window (" + std::to_string(win) + ")",
                                      "lower roiTopFraction or windowRadius"));
    }
    if (config.patchWidth < win || config.patchHeight < win || config.patchWidth > imageSize.width ||
        config.patchHeight > imageSize.height - roiTop) {
        return Unexpected(configError("reference patch " + std::to_string(config.patchWidth) + "x" +
                                          std::to_string(config.patchHeight) + " does not fit the ROI",
                                      "the patch must be at least one window and lie inside the ROI rows"));
    }
    if (!(config.matchThreshold > 0.0 && config.matchThreshold <= 1.0) ||
        !(config.patchSelfMatch > 0.0 && config.patchSelfMatch <= 1.0) ||
        !(config.minPatchConsistency >= 0.0 && config.minPatchConsistency <= 1.0)) {
        return Unexpected(configError("matchThreshold, patchSelfMatch and minPatchConsistency must lie in (0, 1], "
                                      "(0, 1] and [0, 1]",
                                      "use e.g. 0.5, 0.65 and 0.7"));
    }
    if (config.minObstacleRows < 1 || config.minObstacleRows > imageSize.height - roiTop) {
        return Unexpected(configError("minObstacleRows " + std::to_string(config.minObstacleRows) + " is out of range",
                                      "use 1..ROI rows, e.g. 3"));
    }
    if (config.sectorCount < 1 || config.sectorCount > kMaxSectors) {
        return Unexpected(configError("sectorCount " + std::to_string(config.sectorCount) + " is out of range",
                                      "use 1.." + std::to_string(kMaxSectors)));
    }
    if (!(config.maxRangeM > 0.0) || !(config.dangerDistanceM > 0.0F) ||
        !(config.cautionDistanceM >= config.dangerDistanceM)) {
        return Unexpected(configError("distances must be positive with dangerDistanceM <= cautionDistanceM",
                                      "use e.g. maxRangeM 50, danger 1.5, caution 5"));
    }
    return {};
}

} // namespace

Result<ColourFreeSpace, Error> ColourFreeSpace::create(const ColourFreeSpaceConfig& config, cv::Size imageSize,
                                                       const RectifiedProjection& projection, const GroundPlane& ground)
{
    if (auto valid = checkConfig(config, imageSize); !valid) {
        return Unexpected(valid.error());
    }
    if (!(projection.fx > 0.0) || !(projection.fy > 0.0)) {
        return Unexpected(Error{"RectifiedProjection", "focal length must be positive", "pass the calibration's"});
    }
    if (!(ground.heightM > 0.0)) {
        return Unexpected(Error{"GroundPlane", "camera height must be positive", "set the mount height"});
    }

    ColourFreeSpace sut;
    sut.config_ = config;
    sut.size_ = imageSize;
    sut.projection_ = projection;
    sut.ground_ = ground;
    sut.hfovDeg_ = static_cast<float>(2.0 * std::atan(imageSize.width / (2.0 * projection.fx)) * kRadToDeg);
    const int roiTop = roiTopRow(config, imageSize);
    sut.roiTop_ = roiTop;
    sut.binTop_ = std::max(0, roiTop - config.windowRadius);
    sut.thresholdScore_ = static_cast<int>(std::lround(config.matchThreshold * kScoreMax));
    sut.selfScore_ = static_cast<int>(std::lround(config.patchSelfMatch * kScoreMax));
    sut.bins_ = Image<std::uint8_t>(imageSize.width, imageSize.height - sut.binTop_);
    sut.scores_ = Image<std::uint8_t>(imageSize.width, imageSize.height - roiTop);
    sut.colHist_.assign(static_cast<std::size_t>(imageSize.width) * kColourBins, 0);
    const auto w = static_cast<std::size_t>(imageSize.width);
    sut.columnRange_.assign(w, 0.0F);
    sut.columnBearing_.assign(w, 0.0F);
    sut.columnHit_.assign(w, 0);
    sut.rowSum_.assign(3 * w, 0);
    sut.topRow_.assign(w, imageSize.height);
    for (int x = 0; x < imageSize.width; ++x) {
        for (int y = roiTop; y < imageSize.height; ++y) {
            double range = 0.0;
            double bearing = 0.0;
            if (sut.groundPoint(x, y, range, bearing)) {
                sut.topRow_[static_cast<std::size_t>(x)] = y;
                break;
            }
        }
    }
    return sut;
}

bool ColourFreeSpace::groundPoint(double x, double y, double& rangeM, double& bearingDeg) const noexcept
{
    const double dx = (x - projection_.cx) / projection_.fx;
    const double dy = (y - projection_.cy) / projection_.fy;
    const double along = ground_.nx * dx + ground_.ny * dy + ground_.nz;
    if (!(along > 0.0)) {
        return false; // at or above the horizon
    }
    const double t = ground_.heightM / along;
    const VehiclePoint p = ground_.toVehicle(t * dx, t * dy, t);
    rangeM = std::hypot(p.x, p.y);
    bearingDeg = std::atan2(p.y, p.x) * kRadToDeg;
    return rangeM <= config_.maxRangeM;
}

ColourFreeSpaceStatus ColourFreeSpace::process(ConstBgrView image, ObstacleSectors& out) noexcept
{
    if (image.empty() || image.width() != size_.width || image.height() != size_.height) {
        initSectors(out, config_.sectorCount, hfovDeg_);
        out.degraded = true;
        for (int i = 0; i < out.count; ++i) {
            out.sectors[static_cast<std::size_t>(i)].danger = DangerClass::Unknown;
        }
        return ColourFreeSpaceStatus::WrongInputSize;
    }
    computeBins(image);
    computeReference();
    computeScores();
    scanColumns();
    fillSectors(out);
    return ColourFreeSpaceStatus::Ok;
}

void ColourFreeSpace::computeBins(ConstBgrView image) noexcept
{
    const int width = size_.width;
    const int height = size_.height;
    const int patchX0 = (width - config_.patchWidth) / 2;
    const int patchX1 = patchX0 + config_.patchWidth;
    const int patchY0 = height - config_.patchHeight;
    patchCounts_.fill(0);
    std::int64_t satSum = 0;
    std::int64_t valueSum = 0;
    std::uint16_t* sums = rowSum_.data();
    for (int y = binTop_; y < height; ++y) {
        // 3x3 box blur with replicated borders: vertical 3-row sums, then 3 horizontal taps.
        const BgrPixel* above = image.row(std::max(y - 1, 0));
        const BgrPixel* centre = image.row(y);
        const BgrPixel* below = image.row(std::min(y + 1, height - 1));
        for (int x = 0; x < width; ++x) {
            sums[3 * x] = static_cast<std::uint16_t>(above[x].b + centre[x].b + below[x].b);
            sums[3 * x + 1] = static_cast<std::uint16_t>(above[x].g + centre[x].g + below[x].g);
            sums[3 * x + 2] = static_cast<std::uint16_t>(above[x].r + centre[x].r + below[x].r);
        }
        std::uint8_t* binRow = bins_.view().row(y - binTop_);
        const bool inPatchRows = y >= patchY0;
        for (int x = 0; x < width; ++x) {
            const int left = 3 * std::max(x - 1, 0);
            const int mid = 3 * x;
            const int right = 3 * std::min(x + 1, width - 1);
            const int b = (sums[left] + sums[mid] + sums[right] + kBlurTaps / 2) / kBlurTaps;
            const int g = (sums[left + 1] + sums[mid + 1] + sums[right + 1] + kBlurTaps / 2) / kBlurTaps;
            const int r = (sums[left + 2] + sums[mid + 2] + sums[right + 2] + kBlurTaps / 2) / kBlurTaps;
            int sat = 0;
            int value = 0;
            const std::uint8_t bin = colourBin(b, g, r, sat, value);
            binRow[x] = bin;
            if (inPatchRows && x >= patchX0 && x < patchX1) {
                ++patchCounts_[bin];
                satSum += sat;
                valueSum += value;
            }
        }
    }
    const double patchArea = static_cast<double>(config_.patchWidth) * config_.patchHeight;
    reference_.meanSaturation = static_cast<double>(satSum) / patchArea;
    reference_.meanValue = static_cast<double>(valueSum) / patchArea;
}

void ColourFreeSpace::computeReference() noexcept
{
    const int win = 2 * config_.windowRadius + 1;
    const std::int64_t area = static_cast<std::int64_t>(win) * win;
    const std::int64_t patchArea = static_cast<std::int64_t>(config_.patchWidth) * config_.patchHeight;
    for (int b = 0; b < kColourBins; ++b) {
        ref_[static_cast<std::size_t>(b)] =
            static_cast<std::int16_t>((patchCounts_[static_cast<std::size_t>(b)] * area + patchArea / 2) / patchArea);
    }
}

void ColourFreeSpace::computeScores() noexcept
{
    const int width = size_.width;
    const int height = size_.height;
    const int r = config_.windowRadius;
    const int win = 2 * r + 1;
    const int area = win * win;
    const int yFirst = std::max(roiTop_, binTop_ + r);
    const int yLast = height - 1 - r;
    const ConstImageViewU8 bins = bins_.view();
    const ImageViewU8 scores = scores_.view();
    std::int16_t* colHist = colHist_.data();
    const std::int16_t* ref = ref_.data();

    std::fill(colHist_.begin(), colHist_.end(), std::int16_t{0});
    for (int y = yFirst - r; y <= yFirst + r; ++y) {
        const std::uint8_t* row = bins.row(y - binTop_);
        for (int x = 0; x < width; ++x) {
            ++colHist[x * kColourBins + row[x]];
        }
    }
    std::array<std::int16_t, kColourBins> window{};
    for (int y = yFirst; y <= yLast; ++y) {
        window.fill(0);
        for (int x = 0; x < win; ++x) {
            const std::int16_t* column = colHist + x * kColourBins;
            for (int b = 0; b < kColourBins; ++b) {
                window[static_cast<std::size_t>(b)] =
                    static_cast<std::int16_t>(window[static_cast<std::size_t>(b)] + column[b]);
            }
        }
        std::uint8_t* scoreRow = scores.row(y - roiTop_);
        for (int x = r; x <= width - 1 - r; ++x) {
            const int common = x > r ? slideAndIntersect(window.data(), colHist + (x + r) * kColourBins,
                                                         colHist + (x - r - 1) * kColourBins, ref)
                                     : intersect(window.data(), ref);
            scoreRow[x] = static_cast<std::uint8_t>(std::min((common * kScoreMax + area / 2) / area, kScoreMax));
        }
        std::fill(scoreRow, scoreRow + r, scoreRow[r]);
        std::fill(scoreRow + width - r, scoreRow + width, scoreRow[width - 1 - r]);
        if (y < yLast) {
            const std::uint8_t* leaveRow = bins.row(y - r - binTop_);
            const std::uint8_t* enterRow = bins.row(y + r + 1 - binTop_);
            for (int x = 0; x < width; ++x) {
                --colHist[x * kColourBins + leaveRow[x]];
                ++colHist[x * kColourBins + enterRow[x]];
            }
        }
    }
    for (int y = roiTop_; y < yFirst; ++y) {
        std::copy_n(scores.row(yFirst - roiTop_), width, scores.row(y - roiTop_));
    }
    for (int y = yLast + 1; y < height; ++y) {
        std::copy_n(scores.row(yLast - roiTop_), width, scores.row(y - roiTop_));
    }

    // The patch must match itself: a patch that is partly occluded or mixed does not (a window of one part
    // shares only that part's share with the whole-patch histogram).
    const int patchX0 = (width - config_.patchWidth) / 2;
    const int patchY0 = height - config_.patchHeight;
    int matching = 0;
    for (int y = patchY0; y < height; ++y) {
        const std::uint8_t* scoreRow = scores.row(y - roiTop_);
        for (int x = patchX0; x < patchX0 + config_.patchWidth; ++x) {
            matching += scoreRow[x] >= selfScore_ ? 1 : 0;
        }
    }
    reference_.consistency =
        static_cast<double>(matching) / (static_cast<double>(config_.patchWidth) * config_.patchHeight);
    reference_.groundLike = reference_.meanSaturation >= config_.minPatchSaturation &&
                            reference_.meanValue >= config_.minPatchValue &&
                            reference_.consistency >= config_.minPatchConsistency;
}

void ColourFreeSpace::scanColumns() noexcept
{
    const int height = size_.height;
    const ConstImageViewU8 scores = scores_.view();
    for (int x = 0; x < size_.width; ++x) {
        const auto column = static_cast<std::size_t>(x);
        const int top = topRow_[column];
        int run = 0;
        int boundary = -1;
        for (int y = height - 1; y >= top; --y) {
            if (scores.row(y - roiTop_)[x] < thresholdScore_) {
                if (++run >= config_.minObstacleRows) {
                    boundary = y + config_.minObstacleRows - 1; // lowest row of the non-free run
                    break;
                }
            } else {
                run = 0;
            }
        }
        double range = 0.0;
        double bearing = 0.0;
        const int row = boundary >= 0 ? boundary : top;
        const bool seen = row < height && groundPoint(x, row, range, bearing);
        columnRange_[column] = seen ? static_cast<float>(range) : 0.0F;
        columnBearing_[column] = seen ? static_cast<float>(bearing)
                                      : static_cast<float>(std::atan2(projection_.cx - x, projection_.fx) * kRadToDeg);
        columnHit_[column] = boundary >= 0 ? 1 : 0;
    }
}

void ColourFreeSpace::fillSectors(ObstacleSectors& out) noexcept
{
    initSectors(out, config_.sectorCount, hfovDeg_);
    out.degraded = true;
    std::array<float, kMaxSectors> minRange{};
    std::array<std::uint8_t, kMaxSectors> minHit{};
    std::array<std::uint8_t, kMaxSectors> seen{};
    minRange.fill(std::numeric_limits<float>::infinity());
    const float binWidth = hfovDeg_ / static_cast<float>(out.count);
    for (std::size_t x = 0; x < columnRange_.size(); ++x) {
        const int index = std::clamp(static_cast<int>(std::floor((columnBearing_[x] + hfovDeg_ / 2.0F) / binWidth)), 0,
                                     out.count - 1);
        const auto i = static_cast<std::size_t>(index);
        seen[i] = 1;
        if (columnRange_[x] < minRange[i] || (columnRange_[x] == minRange[i] && columnHit_[x] != 0)) {
            minRange[i] = columnRange_[x];
            minHit[i] = columnHit_[x];
        }
    }
    for (std::size_t i = 0; i < static_cast<std::size_t>(out.count); ++i) {
        Sector& s = out.sectors[i];
        if (!reference_.groundLike || seen[i] == 0) {
            continue; // Unknown, as initialised
        }
        if (minHit[i] != 0) {
            s.state = SectorState::Obstacle;
            s.kind = ObstacleKind::Positive;
            s.rangeM = minRange[i];
        } else if (minRange[i] >= config_.cautionDistanceM) {
            s.state = SectorState::Clear;
        } else {
            continue; // the free run ends at the ROI top short of the caution distance: not known to be free
        }
        s.confidence = static_cast<float>(reference_.consistency);
        s.danger = classify(s.state, s.rangeM, config_.dangerDistanceM, config_.cautionDistanceM);
    }
}

} // namespace ugv::vision
