#include "ugv/vision/roi_matcher.hpp"

#include <string>

#include <opencv2/core/utility.hpp>

#include "ugv/vision/mat_view.hpp"

namespace ugv::vision {
namespace {

constexpr int kMaxBlockSize = 11;
constexpr double kMaxGroundRangeDropM = 10.0;     ///< [m]
constexpr double kMaxGroundRangeMarginDeg = 10.0; ///< [deg]

Error configError(const std::string& what)
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
        return Unexpected(configError("numDisparities " + std::to_string(config.numDisparities) +
                                      " is not a positive multiple of 16"));
    }
    if (config.blockSize < 1 || config.blockSize > kMaxBlockSize || config.blockSize % 2 == 0) {
        return Unexpected(configError("blockSize " + std::to_string(config.blockSize) + " is not odd in 1..11"));
    }
    if (config.uniquenessRatio < 0 || config.speckleWindowSize < 0 || config.speckleRange < 0 ||
        config.preFilterCap < 1) {
        return Unexpected(configError("uniquenessRatio, speckle settings or preFilterCap out of range"));
    }
    if (!(config.groundRangeDropM > 0.0 && config.groundRangeDropM <= kMaxGroundRangeDropM) ||
        !(config.groundRangeMarginDeg >= 0.0 && config.groundRangeMarginDeg <= kMaxGroundRangeMarginDeg)) {
        return Unexpected(configError("groundRangeDropM " + std::to_string(config.groundRangeDropM) +
                                      " (need (0, 10] m) or groundRangeMarginDeg " +
                                      std::to_string(config.groundRangeMarginDeg) +
                                      " (need [0, 10] deg) out of range"));
    }
    if (roiSize.width <= config.numDisparities || roiSize.height < config.blockSize) {
        return Unexpected(configError("ROI " + std::to_string(roiSize.width) + "x" + std::to_string(roiSize.height) +
                                      " is too small for numDisparities " + std::to_string(config.numDisparities) +
                                      " and blockSize " + std::to_string(config.blockSize)));
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
            CensusSgmConfig census = config.census;
            census.numDisparities = config.numDisparities;
            census.uniquenessRatio = config.uniquenessRatio;
            census.disp12MaxDiff = config.disp12MaxDiff;
            census.speckleWindowSize = config.speckleWindowSize;
            census.speckleRange = config.speckleRange;
            auto matcher = CensusSgm::create(census, padded);
            if (!matcher) {
                return Unexpected(matcher.error());
            }
            sut.census_.emplace(std::move(matcher).value());
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

void RoiMatcher::setGroundPrior(double a, double b, double c) noexcept
{
    if (census_ && config_.groundPrior) {
        census_->setGroundPrior(a, b, c - a * pad_); // padded column x_p = x + pad_
    }
}

void RoiMatcher::setSearchFloor(double a, double b, double c) noexcept
{
    if (census_ && config_.groundRange) {
        census_->setSearchFloor(a, b, c - a * pad_); // padded column x_p = x + pad_
    }
}

void RoiMatcher::clearSearchFloor() noexcept
{
    if (census_) {
        census_->clearSearchFloor();
    }
}

double RoiMatcher::searchedFraction() const noexcept
{
    return census_ ? census_->searchedFraction() : 1.0;
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
            const auto view = [](const cv::Mat& m) {
                return ConstImageViewU8{m.ptr<std::uint8_t>(0), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step[0])};
            };
            if (!census_->match(view(padLeft_), view(padRight_), disp16Padded_, times)) {
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
    constexpr float kInvalid = -1.0F;
    constexpr float kInvScale = 1.0F / static_cast<float>(kScale);
    for (int y = 0; y < disp16_.rows; ++y) {
        const auto* src = disp16_.ptr<std::int16_t>(y);
        auto* dst = out.ptr<float>(y);
        for (int x = 0; x < disp16_.cols; ++x) {
            dst[x] = src[x] < 0 ? kInvalid : static_cast<float>(src[x]) * kInvScale;
        }
    }
    return true;
}

} // namespace ugv::vision
