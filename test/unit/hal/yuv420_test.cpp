// Yuv420ToBgr: a YUV420 buffer as a camera holds it (planes apart, strided rows with padding, a side-by-side pair
// in one buffer) converts to what OpenCV's I420 conversion gives on the packed image, crop by crop, allocating
// nothing; bad arguments are refused.

#include "ugv/hal/yuv420.hpp"

#include <cstdint>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"

namespace ugv::hal {
namespace {

constexpr int kCameraWidth = 64; // per camera
constexpr int kCameraHeight = 48;
constexpr std::size_t kPad = 24; // bytes of padding at each row's end, as drivers align strides

/// A colourful BGR image: gradients in each channel and blocks of saturated colour.
cv::Mat colourful(int width, int height, int seed)
{
    cv::Mat bgr(height, width, CV_8UC3);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const bool block = ((x / 8) + (y / 8) + seed) % 3 == 0;
            bgr.at<cv::Vec3b>(y, x) =
                block ? cv::Vec3b(static_cast<std::uint8_t>(40 + 50 * seed), 200, 30)
                      : cv::Vec3b(static_cast<std::uint8_t>(4 * x), static_cast<std::uint8_t>(5 * y),
                                  static_cast<std::uint8_t>(255 - 3 * x));
        }
    }
    return bgr;
}

/// A camera buffer: the packed I420 image `i420` (height * 3 / 2 rows of `width`) laid out with strided, padded rows
/// and the three planes in separate blocks (V before U in memory, to catch a swap).
struct Buffer {
    std::vector<std::uint8_t> y;
    std::vector<std::uint8_t> u;
    std::vector<std::uint8_t> v;
    std::size_t yStride = 0;
    std::size_t chromaStride = 0;
    [[nodiscard]] Yuv420View view() const { return {y.data(), u.data(), v.data(), yStride, chromaStride}; }
};

Buffer strided(const cv::Mat& i420, int width, int height)
{
    Buffer b;
    b.yStride = static_cast<std::size_t>(width) + kPad;
    b.chromaStride = b.yStride / 2;
    b.y.assign(b.yStride * static_cast<std::size_t>(height), 0xEE);
    b.u.assign(b.chromaStride * static_cast<std::size_t>(height / 2), 0xEE);
    b.v.assign(b.chromaStride * static_cast<std::size_t>(height / 2), 0xEE);
    const std::uint8_t* src = i420.data;
    for (int r = 0; r < height; ++r, src += width) {
        std::copy(src, src + width, b.y.data() + static_cast<std::size_t>(r) * b.yStride);
    }
    for (std::vector<std::uint8_t>* plane : {&b.u, &b.v}) {
        for (int r = 0; r < height / 2; ++r, src += width / 2) {
            std::copy(src, src + width / 2, plane->data() + static_cast<std::size_t>(r) * b.chromaStride);
        }
    }
    return b;
}

cv::Mat toI420(const cv::Mat& bgr)
{
    cv::Mat i420;
    cv::cvtColor(bgr, i420, cv::COLOR_BGR2YUV_I420);
    return i420;
}

cv::Mat fromI420(const cv::Mat& i420)
{
    cv::Mat bgr;
    cv::cvtColor(i420, bgr, cv::COLOR_YUV2BGR_I420);
    return bgr;
}

cv::Mat matOf(const Image<BgrPixel>& image)
{
    const ConstBgrView v = image.view();
    return {v.height(), v.width(), CV_8UC3, const_cast<BgrPixel*>(v.data()), static_cast<std::size_t>(v.strideBytes())};
}

TEST(Yuv420ToBgr, AStridedBufferConvertsAsOpenCvsPackedConversionAndLooksLikeTheOriginal)
{
    const cv::Mat original = colourful(kCameraWidth, kCameraHeight, 0);
    const cv::Mat i420 = toI420(original);
    const Buffer buffer = strided(i420, kCameraWidth, kCameraHeight);
    Yuv420ToBgr sut(kCameraWidth, kCameraHeight);
    Image<BgrPixel> out(kCameraWidth, kCameraHeight);

    ASSERT_TRUE(sut.convert(buffer.view(), 0, out.view()));

    EXPECT_EQ(cv::norm(matOf(out), fromI420(i420), cv::NORM_INF), 0.0);
    // And it is the original colours (chroma at half resolution: a small error on colour edges only).
    EXPECT_LT(cv::norm(matOf(out), original, cv::NORM_L1) / (kCameraWidth * kCameraHeight * 3.0), 6.0);
}

TEST(Yuv420ToBgr, EachHalfOfASideBySideBufferIsItsOwnCamerasImage)
{
    const cv::Mat left = colourful(kCameraWidth, kCameraHeight, 0);
    const cv::Mat right = colourful(kCameraWidth, kCameraHeight, 1);
    cv::Mat both;
    cv::hconcat(left, right, both);
    const Buffer buffer = strided(toI420(both), 2 * kCameraWidth, kCameraHeight);
    Yuv420ToBgr sut(kCameraWidth, kCameraHeight);
    Image<BgrPixel> out(kCameraWidth, kCameraHeight);

    ASSERT_TRUE(sut.convert(buffer.view(), kCameraWidth, out.view()));
    const cv::Mat rightHalf = fromI420(toI420(both))(cv::Rect(kCameraWidth, 0, kCameraWidth, kCameraHeight));
    EXPECT_EQ(cv::norm(matOf(out), rightHalf, cv::NORM_INF), 0.0);
    EXPECT_LT(cv::norm(matOf(out), right, cv::NORM_L1) / (kCameraWidth * kCameraHeight * 3.0), 6.0);

    ASSERT_TRUE(sut.convert(buffer.view(), 0, out.view()));
    EXPECT_LT(cv::norm(matOf(out), left, cv::NORM_L1) / (kCameraWidth * kCameraHeight * 3.0), 6.0);
}

TEST(Yuv420ToBgr, ConvertingFramesAllocatesNothing)
{
    const Buffer buffer = strided(toI420(colourful(kCameraWidth, kCameraHeight, 2)), kCameraWidth, kCameraHeight);
    Yuv420ToBgr sut(kCameraWidth, kCameraHeight);
    Image<BgrPixel> out(kCameraWidth, kCameraHeight);
    ASSERT_TRUE(sut.convert(buffer.view(), 0, out.view())); // OpenCV's first call may set itself up

    const ugv::test::AllocationScope scope; // every thread: OpenCV may convert on its workers
    for (int k = 0; k < 100; ++k) {
        ASSERT_TRUE(sut.convert(buffer.view(), 0, out.view()));
    }
    EXPECT_EQ(scope.count(), 0U);
}

TEST(Yuv420ToBgr, BadArgumentsAreRefusedAndNothingIsWritten)
{
    const Buffer buffer = strided(toI420(colourful(kCameraWidth, kCameraHeight, 0)), kCameraWidth, kCameraHeight);
    Yuv420ToBgr sut(kCameraWidth, kCameraHeight);
    Image<BgrPixel> out(kCameraWidth, kCameraHeight);
    Image<BgrPixel> small(kCameraWidth - 2, kCameraHeight);
    out.view().at(0, 0) = BgrPixel{1, 2, 3};

    EXPECT_FALSE(sut.convert(buffer.view(), 1, out.view()));  // an odd column splits a chroma sample
    EXPECT_FALSE(sut.convert(buffer.view(), -2, out.view())); // before the buffer
    EXPECT_FALSE(sut.convert(buffer.view(), 0, small.view()));
    Yuv420View noChroma = buffer.view();
    noChroma.u = nullptr;
    EXPECT_FALSE(sut.convert(noChroma, 0, out.view()));
    EXPECT_EQ(out.view().at(0, 0).b, 1);
    Yuv420ToBgr odd(kCameraWidth - 1, kCameraHeight);
    Image<BgrPixel> oddOut(kCameraWidth - 1, kCameraHeight);
    EXPECT_FALSE(odd.convert(buffer.view(), 0, oddOut.view()));
}

} // namespace
} // namespace ugv::hal
