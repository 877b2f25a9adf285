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

TEST(FrameHeader, ViewsPointAtLeftThenRightRows)
{
    const auto frame = makeFrame(makeGreyHeader(kWidth, kHeight, 7, 100, 101));

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

    ASSERT_TRUE(packGreyFrame(frame.data(), kWidth, kHeight, 3, 100, 0, left, ConstImageViewU8()));
    const auto sut = viewFrame(frame.data(), frame.size());

    ASSERT_TRUE(sut.has_value());
    EXPECT_EQ(sut->left.at(4, 2), 77);
    EXPECT_TRUE(sut->right.empty());
    FrameHeader header;
    std::memcpy(&header, frame.data(), sizeof(header));
    EXPECT_EQ(header.flags, kFrameLeftOnly);
    EXPECT_EQ(frame.back(), std::byte{0}); // the right rows are zero, not stale bytes

    ASSERT_TRUE(packGreyFrame(frame.data(), kWidth, kHeight, 4, 100, 101, left, left));
    std::memcpy(&header, frame.data(), sizeof(header));
    EXPECT_EQ(header.flags, 0U);
    EXPECT_EQ(viewFrame(frame.data(), frame.size())->right.at(4, 2), 77);
    const ConstImageViewU8 small(leftPixels.data(), kWidth - 1, kHeight, kWidth);
    EXPECT_FALSE(packGreyFrame(frame.data(), kWidth, kHeight, 5, 0, 0, left, small));
    EXPECT_FALSE(packGreyFrame(frame.data(), kWidth, kHeight, 5, 0, 0, ConstImageViewU8(), left));
}

TEST(FrameHeader, PaddedStrideIsHonoured)
{
    auto header = makeGreyHeader(kWidth, kHeight, 0, 0, 0);
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
    const auto good = makeGreyHeader(kWidth, kHeight, 0, 0, 0);
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
    h.payloadBytes += 1;
    expectError(h, FrameError::PayloadMismatch);
    EXPECT_TRUE(validate(good, size).has_value());
}

TEST(FrameHeader, TruncatedFramesAreRejected)
{
    const auto frame = makeFrame(makeGreyHeader(kWidth, kHeight, 0, 0, 0));

    EXPECT_EQ(viewFrame(frame.data(), frame.size() - 1).error(), FrameError::Truncated);
    EXPECT_EQ(viewFrame(frame.data(), sizeof(FrameHeader) - 1).error(), FrameError::Truncated);
    EXPECT_EQ(viewFrame(nullptr, 0).error(), FrameError::Truncated);
}

TEST(FrameHeader, HugeGeometryCannotOverflowTheSizeCheck)
{
    auto header = makeGreyHeader(kMaxFrameSide, kMaxFrameSide, 0, 0, 0);

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
