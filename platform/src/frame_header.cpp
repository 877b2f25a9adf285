#include "ugv/platform/frame_header.hpp"

#include <cstring>

namespace ugv {

const char* toString(FrameError error) noexcept
{
    switch (error) {
    case FrameError::BadMagic:
        return "not a ugvsense frame (bad magic)";
    case FrameError::BadVersion:
        return "unsupported frame version";
    case FrameError::BadFormat:
        return "unsupported pixel format or flags";
    case FrameError::BadGeometry:
        return "impossible width, height or stride";
    case FrameError::PayloadMismatch:
        return "payload size does not match the geometry";
    case FrameError::Truncated:
        return "frame truncated";
    }
    return "unknown frame error";
}

FrameHeader makeGreyHeader(std::uint32_t width, std::uint32_t height, std::uint64_t sequence, std::int64_t leftStampNs,
                           std::int64_t rightStampNs) noexcept
{
    FrameHeader header;
    header.width = width;
    header.height = height;
    header.strideBytes = width;
    header.sequence = sequence;
    header.leftStampNs = leftStampNs;
    header.rightStampNs = rightStampNs;
    header.payloadBytes = 2ULL * width * height;
    return header;
}

bool packGreyFrame(std::byte* out, std::uint32_t width, std::uint32_t height, std::uint64_t sequence,
                   std::int64_t leftStampNs, std::int64_t rightStampNs, ConstImageViewU8 left,
                   ConstImageViewU8 right) noexcept
{
    const auto fits = [&](ConstImageViewU8 image) {
        return image.width() == static_cast<int>(width) && image.height() == static_cast<int>(height);
    };
    const bool leftOnly = right.empty();
    if (!fits(left) || (!leftOnly && !fits(right))) {
        return false;
    }
    FrameHeader header = makeGreyHeader(width, height, sequence, leftStampNs, rightStampNs);
    header.flags = leftOnly ? kFrameLeftOnly : 0U;
    std::memcpy(out, &header, sizeof(header));
    std::byte* pixels = out + sizeof(header);
    for (int y = 0; y < left.height(); ++y, pixels += width) {
        std::memcpy(pixels, left.row(y), width);
    }
    for (int y = 0; y < static_cast<int>(height); ++y, pixels += width) {
        if (leftOnly) {
            std::memset(pixels, 0, width);
        } else {
            std::memcpy(pixels, right.row(y), width);
        }
    }
    return true;
}

Result<void, FrameError> validate(const FrameHeader& header, std::size_t availableBytes) noexcept
{
    if (header.magic != kFrameMagic) {
        return Unexpected(FrameError::BadMagic);
    }
    if (header.version != kFrameVersion) {
        return Unexpected(FrameError::BadVersion);
    }
    if (header.format != PixelFormat::Grey8 || (header.flags & ~kFrameKnownFlags) != 0) {
        return Unexpected(FrameError::BadFormat);
    }
    if (header.width == 0 || header.height == 0 || header.width > kMaxFrameSide || header.height > kMaxFrameSide ||
        header.strideBytes < header.width || header.strideBytes > 4 * kMaxFrameSide) {
        return Unexpected(FrameError::BadGeometry);
    }
    if (header.payloadBytes != 2ULL * header.strideBytes * header.height) {
        return Unexpected(FrameError::PayloadMismatch);
    }
    if (availableBytes < sizeof(FrameHeader) || availableBytes - sizeof(FrameHeader) < header.payloadBytes) {
        return Unexpected(FrameError::Truncated);
    }
    return {};
}

Result<StereoViews, FrameError> viewFrame(const std::byte* frame, std::size_t availableBytes) noexcept
{
    if (frame == nullptr || availableBytes < sizeof(FrameHeader)) {
        return Unexpected(FrameError::Truncated);
    }
    FrameHeader header;
    std::memcpy(&header, frame, sizeof(header)); // the chunk may not be aligned for the header's fields
    if (auto valid = validate(header, availableBytes); !valid) {
        return Unexpected(valid.error());
    }
    const auto* pixels = reinterpret_cast<const std::uint8_t*>(frame + sizeof(FrameHeader)); // NOLINT: byte buffer
    const auto width = static_cast<int>(header.width);
    const auto height = static_cast<int>(header.height);
    const auto stride = static_cast<std::ptrdiff_t>(header.strideBytes);
    const ConstImageViewU8 left(pixels, width, height, stride);
    if ((header.flags & kFrameLeftOnly) != 0) {
        return StereoViews{left, ConstImageViewU8()};
    }
    return StereoViews{left, ConstImageViewU8(pixels + stride * height, width, height, stride)};
}

} // namespace ugv
