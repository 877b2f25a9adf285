#include "ugv/vision/rectifier.hpp"

#include <cstdint>
#include <cstring>

#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "mat_view.hpp"
#include "test_rig.hpp"

namespace {

using ugv::test::distortedCalibration;
using ugv::test::view;

using ugv::ConstImageViewU8;
using ugv::ImageViewU8;
using ugv::vision::Rectifier;
using ugv::vision::RectifierConfig;
using ugv::vision::RectifyStatus;
using ugv::vision::StereoCalibration;

constexpr int kWidth = 640;
constexpr int kHeight = 480;

cv::Mat makeTexture(int seed)
{
    cv::Mat noise(kHeight, kWidth, CV_8UC1);
    cv::RNG rng(static_cast<std::uint64_t>(seed));
    rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
    cv::Mat smooth;
    cv::GaussianBlur(noise, smooth, cv::Size(0, 0), 2.0); // bilinear-friendly texture
    cv::normalize(smooth, smooth, 0, 255, cv::NORM_MINMAX);
    return smooth;
}

ImageViewU8 mutableView(cv::Mat& m)
{
    return {m.ptr<std::uint8_t>(), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}

TEST(Rectifier, DefaultRoiIsBottomHalfPlusMargin)
{
    const auto sut = Rectifier::create(distortedCalibration(), RectifierConfig{});
    ASSERT_TRUE(sut.has_value()) << sut.error().message();
    constexpr ugv::Rect kExpected{0, kHeight / 2 - 8, kWidth, kHeight / 2 + 8};
    EXPECT_EQ(sut->roi(), kExpected);
    EXPECT_EQ(sut->rectifiedSize(), cv::Size(kWidth, kHeight / 2 + 8));
    EXPECT_FALSE(sut->identity());
}

TEST(Rectifier, TheLeftCameraAloneGivesTheSameRowsAsThePair)
{
    auto pair = Rectifier::create(distortedCalibration(), RectifierConfig{});
    auto single = Rectifier::create(distortedCalibration(), RectifierConfig{});
    ASSERT_TRUE(pair.has_value() && single.has_value());
    const cv::Mat left = makeTexture(1);
    const cv::Mat right = makeTexture(2);

    ASSERT_EQ(pair->rectify(view(left), view(right)), RectifyStatus::Ok);
    ASSERT_EQ(single->rectifyLeft(view(left)), RectifyStatus::Ok);
    EXPECT_EQ(single->rectifyLeft(view(right.rowRange(0, 10))), RectifyStatus::WrongInputSize);

    const ConstImageViewU8 a = pair->rectifiedLeft();
    const ConstImageViewU8 b = single->rectifiedLeft();
    int differing = 0;
    for (int y = 0; y < a.height(); ++y) {
        for (int x = 0; x < a.width(); ++x) {
            differing += a.at(x, y) == b.at(x, y) ? 0 : 1;
        }
    }
    EXPECT_EQ(differing, 0);
}

TEST(Rectifier, AColourLeftImageGivesInEachChannelWhatTheGreyPathGivesThatChannel)
{
    // Three different textures as the B, G and R planes: each rectified channel must be the grey path's result on
    // that plane (the same rows and tables; OpenCV's remap and ours agree to the bit, as the reference test shows
    // within one grey level).
    auto sut = Rectifier::create(distortedCalibration(), RectifierConfig{});
    ASSERT_TRUE(sut.has_value());
    const std::vector<cv::Mat> planes = {makeTexture(1), makeTexture(2), makeTexture(3)};
    cv::Mat bgr;
    cv::merge(planes, bgr);
    const ugv::ConstBgrView in(bgr.ptr<ugv::BgrPixel>(), bgr.cols, bgr.rows, static_cast<std::ptrdiff_t>(bgr.step));
    ugv::Image<ugv::BgrPixel> out(sut->roi().width, sut->roi().height);

    ASSERT_EQ(sut->rectifyLeft(in, out.view()), RectifyStatus::Ok);
    ugv::Image<ugv::BgrPixel> small(8, 8);
    EXPECT_EQ(sut->rectifyLeft(in, small.view()), RectifyStatus::WrongOutputSize);
    EXPECT_EQ(sut->rectifyLeft(ugv::ConstBgrView(), out.view()), RectifyStatus::WrongInputSize);

    int worst = 0;
    for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(sut->rectifyLeft(view(planes[static_cast<std::size_t>(c)])), RectifyStatus::Ok);
        const ConstImageViewU8 grey = sut->rectifiedLeft();
        for (int y = 0; y < grey.height(); ++y) {
            for (int x = 0; x < grey.width(); ++x) {
                const ugv::BgrPixel p = out.view().at(x, y);
                const int channel = c == 0 ? p.b : c == 1 ? p.g : p.r;
                worst = std::max(worst, std::abs(channel - int{grey.at(x, y)}));
            }
        }
    }
    EXPECT_EQ(worst, 0);
}

TEST(Rectifier, MatchesReferenceRemapOnFloatMapsInRoiRows)
{
    const StereoCalibration calib = distortedCalibration();
    auto sut = Rectifier::create(calib, RectifierConfig{});
    ASSERT_TRUE(sut.has_value()) << sut.error().message();
    const cv::Mat left = makeTexture(1);
    const cv::Mat right = makeTexture(2);

    ASSERT_EQ(sut->rectify(view(left), view(right)), RectifyStatus::Ok);

    const ugv::Rect roi = sut->roi();
    const cv::Mat* inputs[] = {&left, &right};
    const ConstImageViewU8 outputs[] = {sut->rectifiedLeft(), sut->rectifiedRight()};
    for (int camera = 0; camera < 2; ++camera) {
        cv::Mat mapX;
        cv::Mat mapY;
        cv::initUndistortRectifyMap(camera == 0 ? calib.K1 : calib.K2, camera == 0 ? calib.D1 : calib.D2,
                                    camera == 0 ? calib.R1 : calib.R2, camera == 0 ? calib.P1 : calib.P2,
                                    calib.imageSize, CV_32FC1, mapX, mapY);
        cv::Mat reference;
        cv::remap(*inputs[camera], reference, mapX, mapY, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
        const ConstImageViewU8 out = outputs[camera];
        const cv::Mat outMat(out.height(), out.width(), CV_8UC1, const_cast<std::uint8_t*>(out.data()),
                             static_cast<std::size_t>(out.strideBytes()));
        double maxDiff = 0.0;
        cv::minMaxLoc(cv::abs(outMat - reference.rowRange(roi.y, roi.y + roi.height)), nullptr, &maxDiff);
        EXPECT_LE(maxDiff, 1.0) << "camera " << camera;
        // The rows above the ROI differ from the output's first rows: the output really starts at roi.y.
        EXPECT_GT(cv::norm(outMat.rowRange(0, 8), reference.rowRange(0, 8), cv::NORM_INF), 1.0);
    }
}

TEST(Rectifier, FullFrameOptionCoversTheImage)
{
    RectifierConfig config;
    config.fullFrame = true;
    const auto sut = Rectifier::create(distortedCalibration(), config);
    ASSERT_TRUE(sut.has_value());
    EXPECT_EQ(sut->roi(), (ugv::Rect{0, 0, kWidth, kHeight}));
}

TEST(Rectifier, WrongInputSizeReturnsErrorAndLeavesOutputs)
{
    auto sut = Rectifier::create(distortedCalibration(), RectifierConfig{});
    ASSERT_TRUE(sut.has_value());
    const cv::Mat small(kHeight - 2, kWidth, CV_8UC1, cv::Scalar(7));
    const cv::Mat good = makeTexture(3);
    cv::Mat outLeft(sut->rectifiedSize(), CV_8UC1, cv::Scalar(42));
    cv::Mat outRight(sut->rectifiedSize(), CV_8UC1, cv::Scalar(42));

    EXPECT_EQ(sut->rectify(view(small), view(good), mutableView(outLeft), mutableView(outRight)),
              RectifyStatus::WrongInputSize);
    EXPECT_EQ(sut->rectify(view(good), view(small), mutableView(outLeft), mutableView(outRight)),
              RectifyStatus::WrongInputSize);
    EXPECT_EQ(sut->rectify(view(good), ConstImageViewU8{}, mutableView(outLeft), mutableView(outRight)),
              RectifyStatus::WrongInputSize);
    cv::Mat shortOut(sut->rectifiedSize().height - 1, kWidth, CV_8UC1);
    EXPECT_EQ(sut->rectify(view(good), view(good), mutableView(shortOut), mutableView(outRight)),
              RectifyStatus::WrongOutputSize);
    EXPECT_EQ(cv::countNonZero(outLeft != 42), 0);
    EXPECT_EQ(cv::countNonZero(outRight != 42), 0);
}

TEST(Rectifier, IdentityPathCopiesRoiRowsBitExact)
{
    const StereoCalibration calib =
        ugv::vision::makeRectifiedCalibration(cv::Size(kWidth, kHeight), 500.0, 500.0, 320.0, 240.0, 0.12);
    auto sut = Rectifier::create(calib, RectifierConfig{});
    ASSERT_TRUE(sut.has_value());
    ASSERT_TRUE(sut->identity());
    // Inputs with a row stride larger than the width (sub-views of a wider buffer).
    const cv::Mat wideLeft = cv::repeat(makeTexture(4), 1, 2);
    const cv::Mat wideRight = cv::repeat(makeTexture(5), 1, 2);
    const cv::Mat left = wideLeft.colRange(3, 3 + kWidth);
    const cv::Mat right = wideRight.colRange(5, 5 + kWidth);

    ASSERT_EQ(sut->rectify(view(left), view(right)), RectifyStatus::Ok);

    const ugv::Rect roi = sut->roi();
    const ConstImageViewU8 out = sut->rectifiedLeft();
    const cv::Mat outLeft(out.height(), out.width(), CV_8UC1, const_cast<std::uint8_t*>(out.data()));
    const ConstImageViewU8 outR = sut->rectifiedRight();
    const cv::Mat outRight(outR.height(), outR.width(), CV_8UC1, const_cast<std::uint8_t*>(outR.data()));
    EXPECT_EQ(cv::norm(outLeft, left.rowRange(roi.y, roi.y + roi.height), cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(outRight, right.rowRange(roi.y, roi.y + roi.height), cv::NORM_INF), 0.0);
    EXPECT_DOUBLE_EQ(sut->projection().baselineM, 0.12);
    EXPECT_DOUBLE_EQ(sut->projection().fx, 500.0);
}

TEST(Rectifier, ARightPrincipalPointElsewhereIsMovedIntoTheLeftsSoDisparitiesCarryNoOffset)
{
    // The already-rectified form with Middlebury-style doffs of 12 px: the right image moves 12 px left.
    constexpr int kDoffs = 12;
    const StereoCalibration calib = ugv::vision::makeRectifiedCalibration(cv::Size(kWidth, kHeight), 500.0, 500.0,
                                                                          320.0, 240.0, 0.12, 320.0 + kDoffs);
    auto sut = Rectifier::create(calib, RectifierConfig{});
    ASSERT_TRUE(sut.has_value()) << sut.error().message();
    EXPECT_FALSE(sut->identity());
    const cv::Mat left = makeTexture(6);
    const cv::Mat right = makeTexture(7);
    ASSERT_EQ(sut->rectify(view(left), view(right)), RectifyStatus::Ok);
    const ugv::Rect roi = sut->roi();
    const ConstImageViewU8 outL = sut->rectifiedLeft();
    const ConstImageViewU8 outR = sut->rectifiedRight();
    for (int r = 0; r < roi.height; r += 37) {
        for (int x = 0; x + kDoffs < kWidth - 1; ++x) {
            ASSERT_EQ(outL.row(r)[x], left.at<std::uint8_t>(roi.y + r, x)) << r << "," << x;
            ASSERT_EQ(outR.row(r)[x], right.at<std::uint8_t>(roi.y + r, x + kDoffs)) << r << "," << x;
        }
    }
    EXPECT_DOUBLE_EQ(sut->projection().cx, 320.0);
    EXPECT_DOUBLE_EQ(sut->projection().baselineM, 0.12);

    // The full form rectified without zero disparity (P2's cx elsewhere) gives the images of the one with it.
    const StereoCalibration zero = distortedCalibration();
    StereoCalibration apart = zero;
    apart.P2 = zero.P2.clone();
    apart.P2.at<double>(0, 2) += 7.25;
    auto a = Rectifier::create(zero, RectifierConfig{});
    auto b = Rectifier::create(apart, RectifierConfig{});
    ASSERT_TRUE(a.has_value() && b.has_value());
    ASSERT_EQ(a->rectify(view(left), view(right)), RectifyStatus::Ok);
    ASSERT_EQ(b->rectify(view(left), view(right)), RectifyStatus::Ok);
    for (int r = 0; r < a->roi().height; ++r) {
        ASSERT_EQ(std::memcmp(a->rectifiedRight().row(r), b->rectifiedRight().row(r), a->roi().width), 0) << r;
    }
}

TEST(Rectifier, ProjectionComesFromP1P2)
{
    const StereoCalibration calib = distortedCalibration();
    const auto sut = Rectifier::create(calib, RectifierConfig{});
    ASSERT_TRUE(sut.has_value());
    EXPECT_DOUBLE_EQ(sut->projection().fx, calib.P1.at<double>(0, 0));
    EXPECT_DOUBLE_EQ(sut->projection().cy, calib.P1.at<double>(1, 2));
    EXPECT_NEAR(sut->projection().baselineM, cv::norm(calib.T), 1e-9);
}

TEST(Rectifier, CreateRejectsBadCalibrationAndMargin)
{
    StereoCalibration empty;
    empty.imageSize = cv::Size(kWidth, kHeight);
    EXPECT_FALSE(Rectifier::create(empty, RectifierConfig{}).has_value());
    RectifierConfig badMargin;
    badMargin.roiMarginRows = -1;
    EXPECT_FALSE(Rectifier::create(distortedCalibration(), badMargin).has_value());
    StereoCalibration noSize = distortedCalibration();
    noSize.imageSize = cv::Size(0, kHeight);
    EXPECT_FALSE(Rectifier::create(noSize, RectifierConfig{}).has_value());
}

TEST(Rectifier, RoiTopFractionMovesTheRoi)
{
    RectifierConfig config;
    config.roiTopFraction = 0.4;
    config.roiMarginRows = 4;

    const auto sut = Rectifier::create(distortedCalibration(), config);

    ASSERT_TRUE(sut.has_value());
    EXPECT_EQ(sut->roi().y, static_cast<int>(std::lround(kHeight * 0.4)) - 4);
    EXPECT_EQ(sut->roi().height, kHeight - sut->roi().y);
}

TEST(Rectifier, CreateRejectsBadRoiFraction)
{
    for (const double fraction : {-0.1, 1.0, std::nan("")}) {
        RectifierConfig config;
        config.roiTopFraction = fraction;
        const auto result = Rectifier::create(distortedCalibration(), config);
        ASSERT_FALSE(result.has_value()) << fraction;
        EXPECT_NE(result.error().what.find("roiTopFraction"), std::string::npos);
    }
}

TEST(Rectifier, RectifyAllocatesNothingOver300Frames)
{
    constexpr int kFrames = 300;
    auto sut = Rectifier::create(distortedCalibration(), RectifierConfig{});
    ASSERT_TRUE(sut.has_value());
    const cv::Mat left = makeTexture(6);
    const cv::Mat right = makeTexture(7);
    cv::Mat outLeft(sut->rectifiedSize(), CV_8UC1);
    cv::Mat outRight(sut->rectifiedSize(), CV_8UC1);
    const ConstImageViewU8 leftView = view(left);
    const ConstImageViewU8 rightView = view(right);
    const ImageViewU8 outLeftView = mutableView(outLeft);
    const ImageViewU8 outRightView = mutableView(outRight);
    // As in the service (STYLE.md: OpenCV threads off): with worker threads, parallel_for_ allocates per call.
    const int threadsBefore = cv::getNumThreads();
    cv::setNumThreads(1);
    ASSERT_EQ(sut->rectify(leftView, rightView), RectifyStatus::Ok); // warm-up (OpenCV's lazy init)
    int failures = 0;

    const ugv::test::AllocationScope scope;
    for (int i = 0; i < kFrames; ++i) {
        failures += sut->rectify(leftView, rightView) != RectifyStatus::Ok ? 1 : 0;
        failures += sut->rectify(leftView, rightView, outLeftView, outRightView) != RectifyStatus::Ok ? 1 : 0;
    }
    const std::size_t allocations = scope.count();
    cv::setNumThreads(threadsBefore);

    EXPECT_EQ(failures, 0);
    EXPECT_EQ(allocations, 0U) << "malloc family counted: " << ugv::test::mallocFamilyCounted();
}

} // namespace
