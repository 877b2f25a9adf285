#include "ugv/vision/roi_matcher.hpp"

#include <algorithm>
#include <optional>
#include <string>
#include <utility>

#include <opencv2/core/utility.hpp>

#include "ugv/vision/mat_view.hpp"

namespace ugv::vision {
namespace {

constexpr int kMaxBlockSize = 11;
constexpr double kMaxGroundRangeDropM = 10.0;     ///< [m]
constexpr double kMaxGroundRangeMarginDeg = 10.0; ///< [deg]

Error matcherConfigError(const std::string& what)
{
    return Error{"RoiMatcherConfig", what, "see vision/include/ugv/vision/roi_matcher.hpp for the valid ranges"};
}

int toOpenCvMode(MatcherMode mode) noexcept
{
    switch (mode) {
    case MatcherMode::CensusSgm:
    case MatcherMode::Sgbm:
        return cv::StereoSGBM::MODE_SGBM;
    case MatcherMode::Sgbm3Way:
        return cv::StereoSGBM::MODE_SGBM_3WAY;
    case MatcherMode::Hh4:
        return cv::StereoSGBM::MODE_HH4;
    }
    return cv::StereoSGBM::MODE_SGBM;
}

} // namespace

Result<RoiMatcher, Error> RoiMatcher::create(const RoiMatcherConfig& config, cv::Size roiSize)
{
    if (config.numDisparities < 16 || config.numDisparities % 16 != 0) {
        return Unexpected(matcherConfigError("numDisparities " + std::to_string(config.numDisparities) +
                                             " is not a positive multiple of 16"));
    }
    if (config.blockSize < 1 || config.blockSize > kMaxBlockSize || config.blockSize % 2 == 0) {
        return Unexpected(matcherConfigError("blockSize " + std::to_string(config.blockSize) + " is not odd in 1..11"));
    }
    if (config.uniquenessRatio < 0 || config.speckleWindowSize < 0 || config.speckleRange < 0 ||
        config.preFilterCap < 1) {
        return Unexpected(matcherConfigError("uniquenessRatio, speckle settings or preFilterCap out of range"));
    }
    if (!(config.groundRangeDropM > 0.0 && config.groundRangeDropM <= kMaxGroundRangeDropM) ||
        !(config.groundRangeMarginDeg >= 0.0 && config.groundRangeMarginDeg <= kMaxGroundRangeMarginDeg)) {
        return Unexpected(matcherConfigError("groundRangeDropM " + std::to_string(config.groundRangeDropM) +
                                             " (need (0, 10] m) or groundRangeMarginDeg " +
                                             std::to_string(config.groundRangeMarginDeg) +
                                             " (need [0, 10] deg) out of range"));
    }
    const int halfRows = config.halfResolutionRows;
    if (halfRows != 0 && (config.mode != MatcherMode::CensusSgm || config.padLeft || config.numDisparities % 32 != 0 ||
                          halfRows < 0 || halfRows % 2 != 0 || halfRows + 2 * kHalfOverlapRows > roiSize.height)) {
        return Unexpected(
            matcherConfigError("halfResolutionRows " + std::to_string(halfRows) +
                               " needs the census matcher without padLeft, numDisparities a multiple of 32 "
                               "and an even count of at most the ROI height " +
                               std::to_string(roiSize.height) + " - " + std::to_string(2 * kHalfOverlapRows)));
    }
    if (roiSize.width <= config.numDisparities || roiSize.height < config.blockSize) {
        return Unexpected(matcherConfigError("ROI " + std::to_string(roiSize.width) + "x" +
                                             std::to_string(roiSize.height) + " is too small for numDisparities " +
                                             std::to_string(config.numDisparities) + " and blockSize " +
                                             std::to_string(config.blockSize)));
    }

    cv::setNumThreads(1);
    RoiMatcher sut;
    sut.config_ = config;
    sut.roiSize_ = roiSize;
    sut.pad_ = config.padLeft ? config.numDisparities : 0;
    const int area = config.blockSize * config.blockSize;
    try {
        const cv::Size padded(roiSize.width + sut.pad_, roiSize.height);
        sut.padLeft_ = cv::Mat::zeros(padded, CV_8UC1);
        sut.padRight_ = cv::Mat::zeros(padded, CV_8UC1);
        sut.disp16Padded_ = cv::Mat(padded, CV_16SC1, cv::Scalar(-kScale));
        sut.disp16_ = sut.disp16Padded_(cv::Rect(sut.pad_, 0, roiSize.width, roiSize.height));
        if (config.mode == MatcherMode::CensusSgm) {
            if (auto error = sut.createCensus(padded)) {
                return Unexpected(std::move(*error));
            }
            return sut;
        }
        sut.sgbm_ = cv::StereoSGBM::create(0, config.numDisparities, config.blockSize, 8 * area, 32 * area,
                                           config.disp12MaxDiff, config.preFilterCap, config.uniquenessRatio,
                                           config.speckleWindowSize, config.speckleRange, toOpenCvMode(config.mode));
        // Warm-up: the first compute() sizes OpenCV's internal buffers.
        sut.sgbm_->compute(sut.padLeft_, sut.padRight_, sut.disp16Padded_);
    } catch (const cv::Exception& e) {
        return Unexpected(Error{"RoiMatcher::create", std::string("OpenCV: ") + e.what(), ""});
    }
    return sut;
}

std::optional<Error> RoiMatcher::createCensus(cv::Size padded)
{
    CensusSgmConfig census = config_.census;
    census.numDisparities = config_.numDisparities;
    census.uniquenessRatio = config_.uniquenessRatio;
    census.disp12MaxDiff = config_.disp12MaxDiff;
    census.speckleWindowSize = config_.speckleWindowSize;
    census.speckleRange = config_.speckleRange;
    const int halfRows = config_.halfResolutionRows;
    fullRows_ = halfRows > 0 ? roiSize_.height - halfRows + kHalfOverlapRows : roiSize_.height;
    auto matcher = CensusSgm::create(census, cv::Size(padded.width, fullRows_));
    if (!matcher) {
        return matcher.error();
    }
    census_.emplace(std::move(matcher).value());
    if (halfRows == 0) {
        return std::nullopt;
    }
    CensusSgmConfig half = census;
    half.numDisparities = census.numDisparities / 2;
    half.speckleWindowSize = census.speckleWindowSize / 4; // the same area in the scene
    const cv::Size halfSize(roiSize_.width / 2, (halfRows + kHalfOverlapRows) / 2);
    auto halfMatcher = CensusSgm::create(half, halfSize);
    if (!halfMatcher) {
        return halfMatcher.error();
    }
    halfCensus_.emplace(std::move(halfMatcher).value());
    halfLeft_ = cv::Mat::zeros(halfSize, CV_8UC1);
    halfRight_ = cv::Mat::zeros(halfSize, CV_8UC1);
    halfDisp16_ = cv::Mat(halfSize, CV_16SC1, cv::Scalar(-kScale));
    halfTop_ = roiSize_.height - halfRows - kHalfOverlapRows;
    return std::nullopt;
}

namespace {

/// The first `rows` rows of an 8-bit matrix as a view (no copy).
ConstImageViewU8 rowsOf(const cv::Mat& m, int rows) noexcept
{
    return {m.ptr<std::uint8_t>(0), m.cols, rows, static_cast<std::ptrdiff_t>(m.step[0])};
}

/// A ROI plane d = a x + b y + c [px] in the half-resolution images whose first row is ROI row `top`: half pixel
/// (hx, hy) covers ROI pixels 2 hx .. 2 hx + 1 of rows top + 2 hy .. top + 2 hy + 1, and its disparity is half.
struct HalfPlane {
    double a, b, c;
};
HalfPlane toHalf(double a, double b, double c, int top) noexcept
{
    return {a, b, (0.5 * a + b * (top + 0.5) + c) / 2.0};
}

} // namespace

void RoiMatcher::givePlane(PlaneSetter set, double a, double b, double c) noexcept
{
    ((*census_).*set)(a, b, c - a * pad_); // padded column x_p = x + pad_
    if (halfCensus_) {
        const HalfPlane h = toHalf(a, b, c, halfTop_);
        ((*halfCensus_).*set)(h.a, h.b, h.c);
    }
}

void RoiMatcher::setGroundPrior(double a, double b, double c) noexcept
{
    if (census_ && config_.groundPrior) {
        givePlane(&CensusSgm::setGroundPrior, a, b, c);
    }
}

void RoiMatcher::setSearchFloor(double a, double b, double c) noexcept
{
    if (census_ && config_.groundRange) {
        givePlane(&CensusSgm::setSearchFloor, a, b, c);
    }
}

void RoiMatcher::clearSearchFloor() noexcept
{
    if (census_) {
        census_->clearSearchFloor();
    }
    if (halfCensus_) {
        halfCensus_->clearSearchFloor();
    }
}

double RoiMatcher::searchedFraction() const noexcept
{
    if (!census_) {
        return 1.0;
    }
    if (!halfCensus_) {
        return census_->searchedFraction();
    }
    // Cells over those of the whole ROI at full resolution and range: a half-resolution cell is 1/8 of one.
    const double d = config_.numDisparities;
    const double full = static_cast<double>(roiSize_.width + pad_) * fullRows_ * d;
    const double half = static_cast<double>(halfLeft_.cols) * halfLeft_.rows * (d / 2.0);
    const double whole = static_cast<double>(roiSize_.width + pad_) * roiSize_.height * d;
    return (census_->searchedFraction() * full + halfCensus_->searchedFraction() * half) / whole;
}

bool RoiMatcher::matchHalf(ConstImageViewU8 left, ConstImageViewU8 right, VisionStageTimes* times) noexcept
{
    StageLap lap(times);
    const int halfWidth = halfLeft_.cols;
    const auto average = [this, halfWidth](ConstImageViewU8 src, cv::Mat& dst) {
        for (int r = 0; r < dst.rows; ++r) {
            const std::uint8_t* a = src.row(halfTop_ + 2 * r);
            const std::uint8_t* b = src.row(halfTop_ + 2 * r + 1);
            auto* out = dst.ptr<std::uint8_t>(r);
            for (int c = 0; c < halfWidth; ++c) {
                out[c] = static_cast<std::uint8_t>((a[2 * c] + a[2 * c + 1] + b[2 * c] + b[2 * c + 1] + 2) >> 2);
            }
        }
    };
    average(left, halfLeft_);
    average(right, halfRight_);
    lap.to(VisionStage::MatchOther);
    if (!halfCensus_->match(rowsOf(halfLeft_, halfLeft_.rows), rowsOf(halfRight_, halfRight_.rows), halfDisp16_,
                            times)) {
        return false;
    }
    StageLap back(times);
    upsampleHalf();
    back.to(VisionStage::MatchOther);
    return true;
}

void RoiMatcher::upsampleHalf() noexcept
{
    // Full pixel (x, y) lies at half-resolution coordinates ((x - 0.5) / 2, (y - halfTop_ - 0.5) / 2): between four
    // half pixels, with weights of 1/4 and 3/4 along each axis. Bilinear where the four are valid and within one
    // half-resolution pixel of each other (a surface: the ground's slope is kept, not stepped every two rows);
    // otherwise the half pixel that covers it (an edge stays an edge). Disparities double.
    const int halfWidth = halfDisp16_.cols;
    const int halfHeight = halfDisp16_.rows;
    for (int y = roiSize_.height - config_.halfResolutionRows; y < roiSize_.height; ++y) {
        const int v = y - halfTop_;
        const int cover = v / 2;
        const int y0 = (v & 1) != 0 ? cover : std::max(cover - 1, 0); // the half row above the point
        const int y1 = std::min(y0 + 1, halfHeight - 1);
        const int wy1 = (v & 1) != 0 ? 1 : 3; // [1/4] weight of y1
        const auto* r0 = halfDisp16_.ptr<std::int16_t>(y0);
        const auto* r1 = halfDisp16_.ptr<std::int16_t>(y1);
        const auto* rc = halfDisp16_.ptr<std::int16_t>(cover);
        auto* dst = disp16_.ptr<std::int16_t>(y);
        for (int x = 0; x < roiSize_.width; ++x) {
            const int hx = std::min(x / 2, halfWidth - 1);
            const int x0 = (x & 1) != 0 ? hx : std::max(hx - 1, 0);
            const int x1 = std::min(x0 + 1, halfWidth - 1);
            const int wx1 = (x & 1) != 0 ? 1 : 3;
            const int d00 = r0[x0];
            const int d01 = r0[x1];
            const int d10 = r1[x0];
            const int d11 = r1[x1];
            const int lo = std::min(std::min(d00, d01), std::min(d10, d11));
            const int hi = std::max(std::max(d00, d01), std::max(d10, d11));
            if (lo >= 0 && hi - lo <= kScale) {
                const int sum = (4 - wy1) * ((4 - wx1) * d00 + wx1 * d01) + wy1 * ((4 - wx1) * d10 + wx1 * d11);
                dst[x] = static_cast<std::int16_t>((sum + 4) >> 3); // 2 sum / 16
                continue;
            }
            const int d = rc[hx];
            dst[x] = static_cast<std::int16_t>(d < 0 ? -kScale : 2 * d);
        }
    }
}

MatchStatus RoiMatcher::match(ConstImageViewU8 left, ConstImageViewU8 right, VisionStageTimes* times) noexcept
{
    StageLap lap(times);
    const auto sizeOk = [this](ConstImageViewU8 v) {
        return v.data() != nullptr && v.width() == roiSize_.width && v.height() == roiSize_.height;
    };
    if (!sizeOk(left) || !sizeOk(right)) {
        disp16Padded_.setTo(-kScale);
        return MatchStatus::WrongInputSize;
    }
    try {
        // Same size and type: copyTo() into the views does not reallocate. The pad columns stay 0.
        const cv::Rect image(pad_, 0, roiSize_.width, roiSize_.height);
        cv::Mat leftDst = padLeft_(image);
        cv::Mat rightDst = padRight_(image);
        matOver(left).copyTo(leftDst);
        matOver(right).copyTo(rightDst);
        lap.to(VisionStage::MatchOther);
        if (census_) {
            // The full-resolution rows (all of them without halfResolutionRows); a row range is a header, no copy.
            cv::Mat fullDisp = disp16Padded_.rowRange(0, fullRows_);
            if (!census_->match(rowsOf(padLeft_, fullRows_), rowsOf(padRight_, fullRows_), fullDisp, times) ||
                (halfCensus_ && !matchHalf(left, right, times))) {
                disp16Padded_.setTo(-kScale);
                return MatchStatus::MatcherFailed;
            }
            return MatchStatus::Ok;
        }
        sgbm_->compute(padLeft_, padRight_, disp16Padded_);
        lap.to(VisionStage::MatchOther);
    } catch (...) {
        disp16Padded_.setTo(-kScale);
        return MatchStatus::OpenCvFailed;
    }
    return MatchStatus::Ok;
}

ImageView<const std::int16_t> RoiMatcher::disparityView() const noexcept
{
    return {disp16_.ptr<std::int16_t>(0), disp16_.cols, disp16_.rows, static_cast<std::ptrdiff_t>(disp16_.step[0])};
}

bool RoiMatcher::toFloat(cv::Mat& out) const noexcept
{
    if (out.type() != CV_32FC1 || out.rows != roiSize_.height || out.cols != roiSize_.width) {
        return false;
    }
    constexpr float kNoDisparity = -1.0F;
    constexpr float kInvScale = 1.0F / static_cast<float>(kScale);
    for (int y = 0; y < disp16_.rows; ++y) {
        const auto* src = disp16_.ptr<std::int16_t>(y);
        auto* dst = out.ptr<float>(y);
        for (int x = 0; x < disp16_.cols; ++x) {
            dst[x] = src[x] < 0 ? kNoDisparity : static_cast<float>(src[x]) * kInvScale;
        }
    }
    return true;
}

} // namespace ugv::vision
