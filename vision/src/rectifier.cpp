#include "ugv/vision/rectifier.hpp"

#include <cmath>
#include <cstring>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "ugv/vision/mat_view.hpp"

namespace ugv::vision {
namespace {

bool hasSize(const cv::Mat& m, int rows, int cols)
{
    return m.type() == CV_64F && m.rows == rows && m.cols == cols;
}

bool sameSize(ConstImageViewU8 view, int width, int height)
{
    return view.data() != nullptr && view.width() == width && view.height() == height;
}

/// Fixed-point tables for rows [roi.y, roi.y + roi.height) of one camera.
void buildMaps(const cv::Mat& K, const cv::Mat& D, const cv::Mat& R, const cv::Mat& P, cv::Size imageSize,
               const Rect& roi, cv::Mat& mapXY, cv::Mat& mapFrac)
{
    cv::Mat mapX;
    cv::Mat mapY;
    cv::initUndistortRectifyMap(K, D, R, P, imageSize, CV_32FC1, mapX, mapY);
    const cv::Range rows(roi.y, roi.y + roi.height);
    cv::convertMaps(mapX.rowRange(rows), mapY.rowRange(rows), mapXY, mapFrac, CV_16SC2);
}

/// Bilinear remap on OpenCV's fixed-point tables (CV_16SC2 integer source position, CV_16UC1 fraction index
/// fy * 32 + fx), pixels outside the source read as 0 (BORDER_CONSTANT). Our own loop because cv::remap in
/// OpenCV 4.6 allocates two scratch Mats per call (RemapInvoker), which the frame path must not do.
/// Weights are products of 5-bit fractions (sum 1024), rounded: within 1 grey level of cv::remap on float maps.
void remapBilinear(ConstImageViewU8 src, const cv::Mat& mapXY, const cv::Mat& mapFrac, ImageViewU8 dst) noexcept
{
    constexpr int kTabBits = 5; // cv::INTER_BITS
    constexpr int kTabMask = (1 << kTabBits) - 1;
    constexpr int kOne = 1 << kTabBits;
    constexpr int kShift = 2 * kTabBits;
    constexpr int kRound = 1 << (kShift - 1);
    const int width = src.width();
    const int height = src.height();
    const std::uint8_t* base = src.data();
    const std::ptrdiff_t stride = src.strideBytes();
    // Raw pointer arithmetic in the loop: ImageView::row() checks its precondition per call.
    const auto at = [&](int px, int py) {
        return px >= 0 && py >= 0 && px < width && py < height ? int{base[py * stride + px]} : 0;
    };
    for (int y = 0; y < dst.height(); ++y) {
        const auto* xy = mapXY.ptr<std::int16_t>(y);
        const auto* frac = mapFrac.ptr<std::uint16_t>(y);
        std::uint8_t* out = dst.row(y);
        for (int x = 0; x < dst.width(); ++x) {
            const int sx = xy[2 * x];
            const int sy = xy[2 * x + 1];
            const int fx = frac[x] & kTabMask;
            const int fy = (frac[x] >> kTabBits) & kTabMask;
            int p00 = 0;
            int p01 = 0;
            int p10 = 0;
            int p11 = 0;
            if (static_cast<unsigned>(sx) < static_cast<unsigned>(width - 1) &&
                static_cast<unsigned>(sy) < static_cast<unsigned>(height - 1)) {
                const std::uint8_t* r0 = base + sy * stride + sx;
                const std::uint8_t* r1 = r0 + stride;
                p00 = r0[0];
                p01 = r0[1];
                p10 = r1[0];
                p11 = r1[1];
            } else {
                p00 = at(sx, sy);
                p01 = at(sx + 1, sy);
                p10 = at(sx, sy + 1);
                p11 = at(sx + 1, sy + 1);
            }
            const int top = (kOne - fx) * p00 + fx * p01;
            const int bottom = (kOne - fx) * p10 + fx * p11;
            const int sum = (kOne - fy) * top + fy * bottom;
            out[x] = static_cast<std::uint8_t>((sum + kRound) >> kShift);
        }
    }
}

} // namespace

Result<Rectifier, Error> Rectifier::create(const StereoCalibration& calib, const RectifierConfig& config)
{
    const cv::Size size = calib.imageSize;
    if (size.width <= 0 || size.height <= 0) {
        return Unexpected(
            Error{"rectifier",
                  "image size " + std::to_string(size.width) + "x" + std::to_string(size.height) + " is not positive",
                  "load a valid calibration"});
    }
    if (!hasSize(calib.K1, 3, 3) || !hasSize(calib.K2, 3, 3) || !hasSize(calib.R1, 3, 3) || !hasSize(calib.R2, 3, 3) ||
        !hasSize(calib.P1, 3, 4) || !hasSize(calib.P2, 3, 4) || calib.D1.empty() || calib.D2.empty()) {
        return Unexpected(Error{"rectifier", "calibration matrices missing or of the wrong size/type",
                                "load the calibration with loadCalibration() or calibrate again"});
    }
    if (!(config.roiTopFraction >= 0.0 && config.roiTopFraction < 1.0)) {
        return Unexpected(Error{"rectifier",
                                "roiTopFraction " + std::to_string(config.roiTopFraction) + " outside [0, 1)",
                                "use 0.5 for the bottom half"});
    }
    const int roiTop = static_cast<int>(std::lround(size.height * config.roiTopFraction));
    if (config.roiMarginRows < 0 || config.roiMarginRows > roiTop) {
        return Unexpected(Error{"rectifier",
                                "roiMarginRows " + std::to_string(config.roiMarginRows) +
                                    " outside [0, first ROI row " + std::to_string(roiTop) + "]",
                                "use a small margin such as 8 rows"});
    }
    Rectifier sut;
    sut.imageSize_ = size;
    const int top = config.fullFrame ? 0 : roiTop - config.roiMarginRows;
    sut.roi_ = Rect{0, top, size.width, size.height - top};
    const double fx = calib.P1.at<double>(0, 0);
    sut.projection_ = RectifiedProjection{fx, calib.P1.at<double>(1, 1), calib.P1.at<double>(0, 2),
                                          calib.P1.at<double>(1, 2), fx != 0.0 ? -calib.P2.at<double>(0, 3) / fx : 0.0};
    // The disparity is fx B / Z only when both images have the principal point in the same place. A rectification
    // that leaves the right camera's elsewhere (cv::stereoRectify without CALIB_ZERO_DISPARITY, a pair with
    // Middlebury's doffs) would add its offset to every disparity: the right image is rectified into the left's
    // principal point instead (P2 with P1's cx, cy; its baseline term kept).
    const bool samePrincipalPoint = calib.P2.at<double>(0, 2) == calib.P1.at<double>(0, 2) &&
                                    calib.P2.at<double>(1, 2) == calib.P1.at<double>(1, 2);
    cv::Mat p2 = calib.P2.clone();
    p2.at<double>(0, 2) = calib.P1.at<double>(0, 2);
    p2.at<double>(1, 2) = calib.P1.at<double>(1, 2);
    sut.identity_ = calib.rectified && samePrincipalPoint;
    try {
        if (!sut.identity_) {
            buildMaps(calib.K1, calib.D1, calib.R1, calib.P1, size, sut.roi_, sut.mapLeftXY_, sut.mapLeftFrac_);
            buildMaps(calib.K2, calib.D2, calib.R2, p2, size, sut.roi_, sut.mapRightXY_, sut.mapRightFrac_);
        }
    } catch (const cv::Exception& e) {
        return Unexpected(
            Error{"rectifier", std::string("building the remap tables failed: ") + e.what(), "calibrate again"});
    }
    sut.outLeft_ = Image<std::uint8_t>(sut.roi_.width, sut.roi_.height);
    sut.outRight_ = Image<std::uint8_t>(sut.roi_.width, sut.roi_.height);
    return sut;
}

RectifyStatus Rectifier::rectify(ConstImageViewU8 left, ConstImageViewU8 right, ImageViewU8 outLeft,
                                 ImageViewU8 outRight) noexcept
{
    if (!sameSize(left, imageSize_.width, imageSize_.height) || !sameSize(right, imageSize_.width, imageSize_.height)) {
        return RectifyStatus::WrongInputSize;
    }
    if (!sameSize(outLeft, roi_.width, roi_.height) || !sameSize(outRight, roi_.width, roi_.height)) {
        return RectifyStatus::WrongOutputSize;
    }
    if (identity_) {
        for (int r = 0; r < roi_.height; ++r) {
            std::memcpy(outLeft.row(r), left.row(roi_.y + r), static_cast<std::size_t>(roi_.width));
            std::memcpy(outRight.row(r), right.row(roi_.y + r), static_cast<std::size_t>(roi_.width));
        }
        return RectifyStatus::Ok;
    }
    remapBilinear(left, mapLeftXY_, mapLeftFrac_, outLeft);
    remapBilinear(right, mapRightXY_, mapRightFrac_, outRight);
    return RectifyStatus::Ok;
}

RectifyStatus Rectifier::rectify(ConstImageViewU8 left, ConstImageViewU8 right) noexcept
{
    return rectify(left, right, outLeft_.view(), outRight_.view());
}

RectifyStatus Rectifier::rectifyLeft(ConstImageViewU8 left) noexcept
{
    if (!sameSize(left, imageSize_.width, imageSize_.height)) {
        return RectifyStatus::WrongInputSize;
    }
    const ImageViewU8 out = outLeft_.view();
    if (identity_) {
        for (int r = 0; r < roi_.height; ++r) {
            std::memcpy(out.row(r), left.row(roi_.y + r), static_cast<std::size_t>(roi_.width));
        }
        return RectifyStatus::Ok;
    }
    remapBilinear(left, mapLeftXY_, mapLeftFrac_, out);
    return RectifyStatus::Ok;
}

RectifyStatus Rectifier::rectifyLeft(ConstBgrView left, BgrView out) noexcept
{
    if (left.data() == nullptr || left.width() != imageSize_.width || left.height() != imageSize_.height) {
        return RectifyStatus::WrongInputSize;
    }
    if (out.data() == nullptr || out.width() != roi_.width || out.height() != roi_.height) {
        return RectifyStatus::WrongOutputSize;
    }
    const auto rowBytes = static_cast<std::size_t>(roi_.width) * sizeof(BgrPixel);
    if (identity_) {
        for (int r = 0; r < roi_.height; ++r) {
            std::memcpy(out.row(r), left.row(roi_.y + r), rowBytes);
        }
        return RectifyStatus::Ok;
    }
    // Sizes checked above and the tables' type fixed at create(): remap writes into `out` without allocating.
    cv::Mat dst = matOver(out);
    cv::remap(matOver(left), dst, mapLeftXY_, mapLeftFrac_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    return RectifyStatus::Ok;
}

} // namespace ugv::vision
