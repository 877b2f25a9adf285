#include "ugv/platform/frame_header.hpp"

#include <cstring>
#include <vector>

#include <gtest/gtest.h>

namespace ugv {
namespace {

constexpr std::uint32_t kWidth = 5;
constexpr std::uint32_t kHeight = 3;

std::vector<std::byte> makeFrame(const FrameHeader& header)
{
    std::vector<std::byte> frame(sizeof(FrameHeader) + header.payloadBytes);
    std::memcpy(frame.data(), &header, sizeof(header));
    for (std::size_t i = 0; i < header.payloadBytes; ++i) {
        frame[sizeof(FrameHeader) + i] = static_cast<std::byte>(i);
    }
    return frame;
}

FrameHeader greyHeader(std::uint32_t width, std::uint32_t height, std::uint64_t sequence, std::int64_t leftNs,
                       std::int64_t rightNs)
{
    return makeFrameHeader(PixelFormat::Grey8, width, height, sequence, leftNs, rightNs);
}

TEST(FrameHeader, ViewsPointAtLeftThenRightRows)
{
    const auto frame = makeFrame(greyHeader(kWidth, kHeight, 7, 100, 101));

    const auto sut = viewFrame(frame.data(), frame.size());

    ASSERT_TRUE(sut.has_value());
    EXPECT_EQ(sut->left.width(), 5);
    EXPECT_EQ(sut->left.height(), 3);
    EXPECT_EQ(sut->left.at(0, 0), 0);
    EXPECT_EQ(sut->left.at(4, 2), 14);
    EXPECT_EQ(sut->right.at(0, 0), 15);
    EXPECT_EQ(sut->right.at(4, 2), 29);
}

TEST(FrameHeader, PackingALeftOnlyFrameFlagsItZeroesTheRightRowsAndGivesNoRightView)
{
    std::vector<std::uint8_t> leftPixels(kWidth * kHeight, 77);
    const ConstImageViewU8 left(leftPixels.data(), kWidth, kHeight, kWidth);
    std::vector<std::byte> frame(sizeof(FrameHeader) + 2 * kWidth * kHeight, std::byte{0xEE});

    ASSERT_TRUE(packFrame(frame.data(), kWidth, kHeight, 3, 100, 0, greyViews(left)));
    const auto sut = viewFrame(frame.data(), frame.size());

    ASSERT_TRUE(sut.has_value());
    EXPECT_EQ(sut->left.at(4, 2), 77);
    EXPECT_TRUE(sut->right.empty());
    FrameHeader header;
    std::memcpy(&header, frame.data(), sizeof(header));
    EXPECT_EQ(header.flags, kFrameLeftOnly);
    EXPECT_EQ(frame.back(), std::byte{0}); // the right rows are zero, not stale bytes

    ASSERT_TRUE(packFrame(frame.data(), kWidth, kHeight, 4, 100, 101, greyViews(left, left)));
    std::memcpy(&header, frame.data(), sizeof(header));
    EXPECT_EQ(header.flags, 0U);
    EXPECT_EQ(viewFrame(frame.data(), frame.size())->right.at(4, 2), 77);
    const ConstImageViewU8 small(leftPixels.data(), kWidth - 1, kHeight, kWidth);
    EXPECT_FALSE(packFrame(frame.data(), kWidth, kHeight, 5, 0, 0, greyViews(left, small)));
    EXPECT_FALSE(packFrame(frame.data(), kWidth, kHeight, 5, 0, 0, greyViews(ConstImageViewU8(), left)));
    EXPECT_FALSE(packFrame(frame.data(), kWidth, kHeight, 5, 0, 0, StereoViews{PixelFormat::Bgr8, left, left, {}, {}}));
}

TEST(FrameHeader, ABgrPairIsPackedThreeBytesAPixelAndViewedBackInColour)
{
    std::vector<BgrPixel> leftPixels(kWidth * kHeight, BgrPixel{10, 20, 30});
    std::vector<BgrPixel> rightPixels(kWidth * kHeight, BgrPixel{40, 50, 60});
    rightPixels.back() = BgrPixel{1, 2, 3};
    const ConstBgrView left(leftPixels.data(), kWidth, kHeight);
    const ConstBgrView right(rightPixels.data(), kWidth, kHeight);
    std::vector<std::byte> frame(packedFrameBytes(PixelFormat::Bgr8, kWidth, kHeight));
    EXPECT_EQ(frame.size(), sizeof(FrameHeader) + 6 * kWidth * kHeight);

    ASSERT_TRUE(packFrame(frame.data(), kWidth, kHeight, 9, 100, 101, bgrViews(left, right)));
    const auto sut = viewFrame(frame.data(), frame.size());

    ASSERT_TRUE(sut.has_value());
    EXPECT_EQ(sut->format, PixelFormat::Bgr8);
    EXPECT_TRUE(sut->left.empty()); // no grey views of a colour frame
    EXPECT_EQ(sut->width(), 5);
    EXPECT_EQ(sut->leftBgr.at(4, 2).r, 30);
    EXPECT_EQ(sut->rightBgr.at(0, 0).g, 50);
    EXPECT_EQ(sut->rightBgr.at(4, 2).b, 1);
    EXPECT_FALSE(sut->leftOnly());
    // A grey frame's worth of bytes is a truncated colour frame.
    EXPECT_EQ(viewFrame(frame.data(), packedFrameBytes(PixelFormat::Grey8, kWidth, kHeight)).error(),
              FrameError::Truncated);

    ASSERT_TRUE(packFrame(frame.data(), kWidth, kHeight, 10, 100, 0, bgrViews(left)));
    const auto leftOnly = viewFrame(frame.data(), frame.size());
    ASSERT_TRUE(leftOnly.has_value());
    EXPECT_TRUE(leftOnly->leftOnly());
    EXPECT_TRUE(leftOnly->rightBgr.empty());
    EXPECT_EQ(frame.back(), std::byte{0});
}

TEST(FrameHeader, PaddedStrideIsHonoured)
{
    auto header = greyHeader(kWidth, kHeight, 0, 0, 0);
    header.strideBytes = 8;
    header.payloadBytes = 2 * 8 * kHeight;
    const auto frame = makeFrame(header);

    const auto sut = viewFrame(frame.data(), frame.size());

    ASSERT_TRUE(sut.has_value());
    EXPECT_EQ(sut->left.at(0, 1), 8);
    EXPECT_EQ(sut->right.at(0, 0), 24);
}

TEST(FrameHeader, EveryMalformedFieldIsRejected)
{
    const auto good = greyHeader(kWidth, kHeight, 0, 0, 0);
    const std::size_t size = sizeof(FrameHeader) + good.payloadBytes;
    const auto expectError = [size](FrameHeader header, FrameError expected) {
        const auto result = validate(header, size);
        ASSERT_FALSE(result.has_value());
        EXPECT_EQ(result.error(), expected) << toString(result.error());
    };

    auto h = good;
    h.magic = 0;
    expectError(h, FrameError::BadMagic);
    h = good;
    h.version = 2;
    expectError(h, FrameError::BadVersion);
    h = good;
    h.format = static_cast<PixelFormat>(9);
    expectError(h, FrameError::BadFormat);
    h = good;
    h.flags = 2; // a flag this reader does not know
    expectError(h, FrameError::BadFormat);
    h = good;
    h.width = 0;
    expectError(h, FrameError::BadGeometry);
    h = good;
    h.height = kMaxFrameSide + 1;
    expectError(h, FrameError::BadGeometry);
    h = good;
    h.strideBytes = kWidth - 1;
    expectError(h, FrameError::BadGeometry);
    h = good;
    h.format = PixelFormat::Bgr8; // a stride of one byte a pixel is too short for three
    expectError(h, FrameError::BadGeometry);
    h = good;
    h.payloadBytes += 1;
    expectError(h, FrameError::PayloadMismatch);
    EXPECT_TRUE(validate(good, size).has_value());
}

TEST(FrameHeader, TruncatedFramesAreRejected)
{
    const auto frame = makeFrame(greyHeader(kWidth, kHeight, 0, 0, 0));

    EXPECT_EQ(viewFrame(frame.data(), frame.size() - 1).error(), FrameError::Truncated);
    EXPECT_EQ(viewFrame(frame.data(), sizeof(FrameHeader) - 1).error(), FrameError::Truncated);
    EXPECT_EQ(viewFrame(nullptr, 0).error(), FrameError::Truncated);
}

TEST(FrameHeader, HugeGeometryCannotOverflowTheSizeCheck)
{
    auto header = greyHeader(kMaxFrameSide, kMaxFrameSide, 0, 0, 0);

    const auto result = validate(header, sizeof(FrameHeader) + 100);

    ASSERT_FALSE(result.has_value());
    EXPECT_EQ(result.error(), FrameError::Truncated);
}

TEST(FrameHeader, EveryErrorHasText)
{
    for (auto e : {FrameError::BadMagic, FrameError::BadVersion, FrameError::BadFormat, FrameError::BadGeometry,
                   FrameError::PayloadMismatch, FrameError::Truncated}) {
        EXPECT_STRNE(toString(e), "unknown frame error");
    }
}

} // namespace
} // namespace ugv
