#include "ugv/vision/colour_free_space.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "ugv/platform/angles.hpp"

namespace ugv::vision {
namespace {

constexpr int kMaxWindowRadius = 15; // int16 column sums: 2 r + 1 <= 31 rows
constexpr int kMaxSlices = 32;
constexpr int kScoreMax = 255;
constexpr int kHueRange = 180; // OpenCV 8-bit hue 0..179
constexpr int kGreyShift = 4;  // 256 / kGreyBins
constexpr int kBlurTaps = 9;   // 3x3 box

Error colourConfigError(const std::string& what, const std::string& fix)
{
    return Error{"ColourFreeSpaceConfig", what, fix};
}

/// The colour bin of a blurred BGR pixel: grey by brightness below kGreyChroma, else OpenCV's 8-bit HSV hue
/// (0..179) and saturation (0..255) reduced to kHueBins x kSatBins.
inline std::uint8_t colourBin(int b, int g, int r, int& value) noexcept
{
    const int v = std::max({b, g, r});
    const int diff = v - std::min({b, g, r});
    value = v;
    if (diff < kGreyChroma) {
        return static_cast<std::uint8_t>(kChromaticBins + (v >> kGreyShift));
    }
    const int sat = (diff * kScoreMax + v / 2) / v; // v >= diff > 0
    int hue2 = 0;                                   // hue in [0, 360) degrees
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
    const int hue = std::min(hue2 / 2, kHueRange - 1);
    const int hueBin = hue * kHueBins / kHueRange;
    return static_cast<std::uint8_t>(hueBin * kSatBins + sat * kSatBins / (kScoreMax + 1));
}

/// Rows just above the horizon that aboveHorizonIsGround() reads: one window's height.
int aboveHorizonRows(const ColourFreeSpaceConfig& config)
{
    return 2 * config.windowRadius + 1;
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
        return Unexpected(colourConfigError("windowRadius " + std::to_string(r) + " is out of range",
                                            "use 1.." + std::to_string(kMaxWindowRadius)));
    }
    if (imageSize.width < win || imageSize.height < win) {
        return Unexpected(colourConfigError("image size " + std::to_string(imageSize.width) + "x" +
                                                std::to_string(imageSize.height) + " is smaller than the window",
                                            "give the camera's image size"));
    }
    if (!(config.roiTopFraction >= 0.0 && config.roiTopFraction < 1.0)) {
        return Unexpected(
            colourConfigError("roiTopFraction " + std::to_string(config.roiTopFraction) + " is outside [0, 1)",
                              "use e.g. 0.5 (bottom half)"));
    }
    const int roiTop = roiTopRow(config, imageSize);
    if (imageSize.height - roiTop < win) {
        return Unexpected(colourConfigError("the ROI has fewer rows than the window (" + std::to_string(win) + ")",
                                            "lower roiTopFraction or windowRadius"));
    }
    if (config.bandRows < win || config.bandRows > imageSize.height - roiTop) {
        return Unexpected(colourConfigError("bandRows " + std::to_string(config.bandRows) + " does not fit the ROI",
                                            "the reference band must be at least one window (" + std::to_string(win) +
                                                " rows) and lie inside the ROI rows, e.g. 40"));
    }
    if (config.bandSlices < 2 || config.bandSlices > kMaxSlices || imageSize.width / config.bandSlices < win) {
        return Unexpected(
            colourConfigError("bandSlices " + std::to_string(config.bandSlices) + " is out of range",
                              "use 2.." + std::to_string(kMaxSlices) + " slices at least one window wide"));
    }
    if (!(config.matchThreshold > 0.0 && config.matchThreshold <= 1.0) ||
        !(config.minColourShare > 0.0 && config.minColourShare <= 1.0) ||
        !(config.minSliceFraction > 0.0 && config.minSliceFraction <= 1.0) ||
        !(config.clearSliceFraction >= config.minSliceFraction && config.clearSliceFraction <= 1.0) ||
        !(config.minGroundCoverage >= 0.0 && config.minGroundCoverage <= 1.0)) {
        return Unexpected(
            colourConfigError("matchThreshold, minColourShare, minSliceFraction, clearSliceFraction and "
                              "minGroundCoverage must lie in (0, 1], (0, 1], (0, 1], [minSliceFraction, 1] "
                              "and [0, 1]",
                              "use e.g. 0.5, 0.02, 0.5, 0.75 and 0.7"));
    }
    if (config.minObstacleRows < 1 || config.minObstacleRows > imageSize.height - roiTop) {
        return Unexpected(
            colourConfigError("minObstacleRows " + std::to_string(config.minObstacleRows) + " is out of range",
                              "use 1..ROI rows, e.g. 3"));
    }
    if (config.sectorCount < 1 || config.sectorCount > kMaxSectors) {
        return Unexpected(colourConfigError("sectorCount " + std::to_string(config.sectorCount) + " is out of range",
                                            "use 1.." + std::to_string(kMaxSectors)));
    }
    if (!(config.maxRangeM > 0.0) || !(config.dangerDistanceM > 0.0F) ||
        !(config.cautionDistanceM >= config.dangerDistanceM)) {
        return Unexpected(colourConfigError("distances must be positive with dangerDistanceM <= cautionDistanceM",
                                            "use e.g. maxRangeM 50, danger 1.5, caution 5"));
    }
    return {};
}

} // namespace

ColourFreeSpaceConfig colourConfigFor(const SectorBuilderConfig& sectors) noexcept
{
    ColourFreeSpaceConfig config;
    config.sectorCount = sectors.sectorCount;
    config.dangerDistanceM = sectors.dangerDistanceM;
    config.cautionDistanceM = sectors.cautionDistanceM;
    return config;
}

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
    // Each column's first row below the horizon (the ray meets the ground), and the rows binned: from a window's
    // height above the highest horizon (see aboveHorizonIsGround) or half a window above the ROI, whichever is higher
    // (on a rig pitched down the horizon is well above the ROI, and the rows between are binned too: more work, for
    // a check that must hold at every pitch).
    sut.horizonRow_.assign(static_cast<std::size_t>(imageSize.width), imageSize.height);
    int highestHorizon = imageSize.height;
    for (int x = 0; x < imageSize.width; ++x) {
        for (int y = 0; y < imageSize.height; ++y) {
            double range = 0.0;
            double bearing = 0.0;
            if (sut.groundPoint(x, y, range, bearing, std::numeric_limits<double>::infinity())) {
                sut.horizonRow_[static_cast<std::size_t>(x)] = y;
                highestHorizon = std::min(highestHorizon, y);
                break;
            }
        }
    }
    sut.binTop_ = std::max(0, std::min(roiTop - config.windowRadius, highestHorizon - aboveHorizonRows(config)));
    sut.thresholdScore_ = static_cast<int>(std::lround(config.matchThreshold * kScoreMax));
    sut.bins_ = Image<std::uint8_t>(imageSize.width, imageSize.height - sut.binTop_);
    sut.scores_ = Image<std::uint8_t>(imageSize.width, imageSize.height - roiTop);
    sut.colSum_.assign(static_cast<std::size_t>(imageSize.width), 0);
    sut.sliceCounts_.assign(static_cast<std::size_t>(config.bandSlices) * kColourBins, 0);
    const auto w = static_cast<std::size_t>(imageSize.width);
    sut.columnRange_.assign(w, 0.0F);
    sut.columnBearing_.assign(w, 0.0F);
    sut.columnHit_.assign(w, 0);
    sut.columnUnsure_.assign(w, 0);
    sut.tentativeCount_.assign(w, 0);
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
    return groundPoint(x, y, rangeM, bearingDeg, config_.maxRangeM);
}

bool ColourFreeSpace::groundPoint(double x, double y, double& rangeM, double& bearingDeg,
                                  double maxRangeM) const noexcept
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
    return rangeM <= maxRangeM;
}

ColourFreeSpaceStatus ColourFreeSpace::process(ConstBgrView image, ObstacleSectors& out) noexcept
{
    return processImage(image, out);
}

ColourFreeSpaceStatus ColourFreeSpace::process(ConstImageViewU8 grey, ObstacleSectors& out) noexcept
{
    return processImage(grey, out);
}

template <class Pixel>
ColourFreeSpaceStatus ColourFreeSpace::processImage(ImageView<const Pixel> image, ObstacleSectors& out) noexcept
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
    countTentative();
    computeScores();
    scanColumns();
    fillSectors(out);
    return ColourFreeSpaceStatus::Ok;
}

namespace {

/// The channels of a pixel: B, G, R of a colour image; the one grey level of a grey image (whose bin is then always a
/// grey one).
template <class Pixel>
struct Channels;

template <>
struct Channels<BgrPixel> {
    static constexpr int kCount = 3;
    static int at(const BgrPixel& p, int c) noexcept { return c == 0 ? p.b : (c == 1 ? p.g : p.r); }
};

template <>
struct Channels<std::uint8_t> {
    static constexpr int kCount = 1;
    static int at(std::uint8_t p, int /*c*/) noexcept { return p; }
};

} // namespace

template <class Pixel>
void ColourFreeSpace::computeBins(ImageView<const Pixel> image) noexcept
{
    constexpr int kChannels = Channels<Pixel>::kCount;
    const int width = size_.width;
    const int height = size_.height;
    const int bandTop = height - config_.bandRows;
    std::fill(sliceCounts_.begin(), sliceCounts_.end(), 0);
    bandValueSum_ = 0;
    std::uint16_t* sums = rowSum_.data();
    for (int y = binTop_; y < height; ++y) {
        // 3x3 box blur with replicated borders: vertical 3-row sums, then 3 horizontal taps.
        const Pixel* above = image.row(std::max(y - 1, 0));
        const Pixel* centre = image.row(y);
        const Pixel* below = image.row(std::min(y + 1, height - 1));
        for (int x = 0; x < width; ++x) {
            for (int c = 0; c < kChannels; ++c) {
                sums[kChannels * x + c] =
                    static_cast<std::uint16_t>(Channels<Pixel>::at(above[x], c) + Channels<Pixel>::at(centre[x], c) +
                                               Channels<Pixel>::at(below[x], c));
            }
        }
        std::uint8_t* binRow = bins_.view().row(y - binTop_);
        const bool inBand = y >= bandTop;
        for (int x = 0; x < width; ++x) {
            const int left = kChannels * std::max(x - 1, 0);
            const int mid = kChannels * x;
            const int right = kChannels * std::min(x + 1, width - 1);
            std::array<int, kChannels> blurred{};
            for (int c = 0; c < kChannels; ++c) {
                blurred[static_cast<std::size_t>(c)] =
                    (sums[left + c] + sums[mid + c] + sums[right + c] + kBlurTaps / 2) / kBlurTaps;
            }
            int value = 0;
            std::uint8_t bin = 0;
            if constexpr (kChannels == 3) {
                bin = colourBin(blurred[0], blurred[1], blurred[2], value);
            } else {
                value = blurred[0];
                bin = static_cast<std::uint8_t>(kChromaticBins + (value >> kGreyShift));
            }
            binRow[x] = bin;
            if (inBand) {
                const int slice = x * config_.bandSlices / width;
                ++sliceCounts_[static_cast<std::size_t>(slice) * kColourBins + bin];
                bandValueSum_ += value;
            }
        }
    }
}

void ColourFreeSpace::computeReference() noexcept
{
    const int width = size_.width;
    const int slices = config_.bandSlices;
    const int needSlices = static_cast<int>(std::ceil(config_.minSliceFraction * slices - 1e-9));
    const int sureSlices = static_cast<int>(std::ceil(config_.clearSliceFraction * slices - 1e-9));
    std::array<std::int32_t, kMaxSlices> minCount{};
    for (int s = 0; s < slices; ++s) {
        const int x0 = (s * width + slices - 1) / slices; // first x with x * slices / width == s
        const int x1 = ((s + 1) * width + slices - 1) / slices;
        const double pixels = static_cast<double>(x1 - x0) * config_.bandRows;
        minCount[static_cast<std::size_t>(s)] =
            std::max(1, static_cast<std::int32_t>(std::ceil(config_.minColourShare * pixels)));
    }
    std::int64_t covered = 0;
    int colours = 0;
    for (int bin = 0; bin < kColourBins; ++bin) {
        int present = 0;
        std::int64_t count = 0;
        for (int s = 0; s < slices; ++s) {
            const std::int32_t c = sliceCounts_[static_cast<std::size_t>(s) * kColourBins + bin];
            present += c >= minCount[static_cast<std::size_t>(s)] ? 1 : 0;
            count += c;
        }
        const bool ground = present >= needSlices;
        learnt_[static_cast<std::size_t>(bin)] = present >= sureSlices ? 2 : (ground ? 1 : 0);
        covered += ground ? count : 0;
        colours += ground ? 1 : 0;
    }
    // A hue one bin from a learnt colour's (same saturation) is ground too: the bins' edges are arbitrary, and a
    // ground whose hue drifts across an edge (a lawn from lush to dry, the light's colour from sun to shade) must not
    // turn into an obstacle there. Brightness and saturation are not widened: they are what tells concrete from
    // asphalt, or a grey post from the road.
    // A bin is as sure as the surest of itself and its neighbours.
    for (int bin = 0; bin < kColourBins; ++bin) {
        std::uint8_t near = learnt_[static_cast<std::size_t>(bin)];
        if (bin < kChromaticBins) {
            const int hue = bin / kSatBins;
            const int sat = bin % kSatBins;
            for (const int h : {(hue + kHueBins - 1) % kHueBins, (hue + 1) % kHueBins}) { // hue is circular
                near = std::max(near, learnt_[static_cast<std::size_t>(h * kSatBins + sat)]);
            }
        }
        groundColour_[static_cast<std::size_t>(bin)] = near > 0 ? 1 : 0;
        tentative_[static_cast<std::size_t>(bin)] = near == 1 ? 1 : 0;
    }
    const double bandPixels = static_cast<double>(width) * config_.bandRows;
    reference_.meanValue = static_cast<double>(bandValueSum_) / bandPixels;
    reference_.coverage = static_cast<double>(covered) / bandPixels;
    reference_.groundColours = colours;
    reference_.groundLike =
        reference_.meanValue >= config_.minBandValue && reference_.coverage >= config_.minGroundCoverage;
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
    std::int16_t* colSum = colSum_.data();
    const std::uint8_t* ground = groundColour_.data();

    std::fill(colSum_.begin(), colSum_.end(), std::int16_t{0});
    for (int y = yFirst - r; y <= yFirst + r; ++y) {
        const std::uint8_t* row = bins.row(y - binTop_);
        for (int x = 0; x < width; ++x) {
            colSum[x] = static_cast<std::int16_t>(colSum[x] + ground[row[x]]);
        }
    }
    for (int y = yFirst; y <= yLast; ++y) {
        int window = 0;
        for (int x = 0; x < win; ++x) {
            window += colSum[x];
        }
        std::uint8_t* scoreRow = scores.row(y - roiTop_);
        for (int x = r; x <= width - 1 - r; ++x) {
            if (x > r) {
                window += colSum[x + r] - colSum[x - r - 1];
            }
            scoreRow[x] = static_cast<std::uint8_t>((window * kScoreMax + area / 2) / area);
        }
        std::fill(scoreRow, scoreRow + r, scoreRow[r]);
        std::fill(scoreRow + width - r, scoreRow + width, scoreRow[width - 1 - r]);
        if (y < yLast) {
            const std::uint8_t* leaveRow = bins.row(y - r - binTop_);
            const std::uint8_t* enterRow = bins.row(y + r + 1 - binTop_);
            for (int x = 0; x < width; ++x) {
                colSum[x] = static_cast<std::int16_t>(colSum[x] + ground[enterRow[x]] - ground[leaveRow[x]]);
            }
        }
    }
    for (int y = roiTop_; y < yFirst; ++y) {
        std::copy_n(scores.row(yFirst - roiTop_), width, scores.row(y - roiTop_));
    }
    for (int y = yLast + 1; y < height; ++y) {
        std::copy_n(scores.row(yLast - roiTop_), width, scores.row(y - roiTop_));
    }
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
        // Reached the top through mostly tentative colours, or the ground colours go on above the horizon.
        const bool tentative = 2 * tentativeCount_[column] > height - top;
        columnUnsure_[column] = boundary < 0 && (tentative || aboveHorizonIsGround(x)) ? 1 : 0;
    }
}

bool ColourFreeSpace::aboveHorizonIsGround(int x) const noexcept
{
    const int horizon = horizonRow_[static_cast<std::size_t>(x)];
    const int first = std::max(binTop_, horizon - aboveHorizonRows(config_));
    if (first >= horizon) {
        return false;
    }
    const ConstImageViewU8 bins = bins_.view();
    int count = 0;
    for (int y = first; y < horizon; ++y) {
        count += groundColour_[bins.row(y - binTop_)[x]];
    }
    return 2 * count > horizon - first;
}

void ColourFreeSpace::countTentative() noexcept
{
    std::fill(tentativeCount_.begin(), tentativeCount_.end(), std::int16_t{0});
    if (std::none_of(tentative_.begin(), tentative_.end(), [](std::uint8_t t) { return t != 0; })) {
        return; // the common case: every ground colour is sure
    }
    const int width = size_.width;
    const ConstImageViewU8 bins = bins_.view();
    const int first = *std::min_element(topRow_.begin(), topRow_.end());
    for (int y = first; y < size_.height; ++y) {
        const std::uint8_t* row = bins.row(y - binTop_);
        for (int x = 0; x < width; ++x) {
            const bool below = y >= topRow_[static_cast<std::size_t>(x)];
            tentativeCount_[static_cast<std::size_t>(x)] = static_cast<std::int16_t>(
                tentativeCount_[static_cast<std::size_t>(x)] + (below ? tentative_[row[x]] : 0));
        }
    }
}

void ColourFreeSpace::fillSectors(ObstacleSectors& out) noexcept
{
    initSectors(out, config_.sectorCount, hfovDeg_);
    out.degraded = true;
    std::array<float, kMaxSectors> minRange{};
    std::array<std::uint8_t, kMaxSectors> minHit{};
    std::array<std::uint8_t, kMaxSectors> seen{};
    std::array<std::uint8_t, kMaxSectors> unsure{};
    minRange.fill(std::numeric_limits<float>::infinity());
    const float binWidth = hfovDeg_ / static_cast<float>(out.count);
    for (std::size_t x = 0; x < columnRange_.size(); ++x) {
        const int index = std::clamp(static_cast<int>(std::floor((columnBearing_[x] + hfovDeg_ / 2.0F) / binWidth)), 0,
                                     out.count - 1);
        const auto i = static_cast<std::size_t>(index);
        seen[i] = 1;
        unsure[i] = static_cast<std::uint8_t>(unsure[i] | columnUnsure_[x]);
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
        } else if (unsure[i] == 0 && minRange[i] >= config_.cautionDistanceM) {
            s.state = SectorState::Clear;
        } else {
            // Not known to be free: a free run ends at the ROI top short of the caution distance, or one is not
            // evidence of ground (tentative colours, or ground colours above the horizon).
            continue;
        }
        s.confidence = static_cast<float>(reference_.coverage);
        s.danger = classify(s.state, s.rangeM, config_.dangerDistanceM, config_.cautionDistanceM);
    }
}

} // namespace ugv::vision
