#include "ugv/platform/frame_header.hpp"

#include <cstring>
#include <type_traits>

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

bool StereoViews::fits(int width, int height) const noexcept
{
    const auto fitsView = [&](const auto& image) { return image.width() == width && image.height() == height; };
    if (colour()) {
        return fitsView(leftBgr) && (rightBgr.empty() || fitsView(rightBgr)) && left.empty() && right.empty();
    }
    return fitsView(left) && (right.empty() || fitsView(right)) && leftBgr.empty() && rightBgr.empty();
}

FrameHeader makeFrameHeader(PixelFormat format, std::uint32_t width, std::uint32_t height, std::uint64_t sequence,
                            std::int64_t leftStampNs, std::int64_t rightStampNs) noexcept
{
    FrameHeader header;
    header.format = format;
    header.width = width;
    header.height = height;
    header.strideBytes = width * bytesPerPixel(format);
    header.sequence = sequence;
    header.leftStampNs = leftStampNs;
    header.rightStampNs = rightStampNs;
    header.payloadBytes = 2ULL * header.strideBytes * height;
    return header;
}

namespace {

/// Copies `rows` rows of `rowBytes` from `image` (zeros when it is null) to `out`; returns the byte after them.
template <class View>
std::byte* packRows(std::byte* out, const View& image, int rows, std::size_t rowBytes) noexcept
{
    for (int y = 0; y < rows; ++y, out += rowBytes) {
        if (image.empty()) {
            std::memset(out, 0, rowBytes);
        } else {
            std::memcpy(out, image.row(y), rowBytes);
        }
    }
    return out;
}

} // namespace

bool packFrame(std::byte* out, std::uint32_t width, std::uint32_t height, std::uint64_t sequence,
               std::int64_t leftStampNs, std::int64_t rightStampNs, const StereoViews& images) noexcept
{
    if (bytesPerPixel(images.format) == 0 || !images.fits(static_cast<int>(width), static_cast<int>(height))) {
        return false;
    }
    FrameHeader header = makeFrameHeader(images.format, width, height, sequence, leftStampNs, rightStampNs);
    header.flags = images.leftOnly() ? kFrameLeftOnly : 0U;
    std::memcpy(out, &header, sizeof(header));
    std::byte* pixels = out + sizeof(header);
    const auto rows = static_cast<int>(height);
    const std::size_t rowBytes = header.strideBytes;
    if (images.colour()) {
        pixels = packRows(pixels, images.leftBgr, rows, rowBytes);
        (void)packRows(pixels, images.rightBgr, rows, rowBytes);
    } else {
        pixels = packRows(pixels, images.left, rows, rowBytes);
        (void)packRows(pixels, images.right, rows, rowBytes);
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
    const std::uint32_t pixelBytes = bytesPerPixel(header.format);
    if (pixelBytes == 0 || (header.flags & ~kFrameKnownFlags) != 0) {
        return Unexpected(FrameError::BadFormat);
    }
    if (header.width == 0 || header.height == 0 || header.width > kMaxFrameSide || header.height > kMaxFrameSide ||
        header.strideBytes < header.width * pixelBytes || header.strideBytes > 4 * kMaxFrameSide) {
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
    const std::byte* left = frame + sizeof(FrameHeader);
    const auto width = static_cast<int>(header.width);
    const auto height = static_cast<int>(header.height);
    const auto stride = static_cast<std::ptrdiff_t>(header.strideBytes);
    const std::byte* right = (header.flags & kFrameLeftOnly) != 0 ? nullptr : left + stride * height;
    const auto view = [&](const std::byte* pixels, auto type) {
        using View = decltype(type);
        using Pixel = std::remove_pointer_t<decltype(View().data())>;
        return pixels == nullptr ? View() : View(reinterpret_cast<Pixel*>(pixels), width, height, stride);
    };
    if (header.format == PixelFormat::Bgr8) {
        return bgrViews(view(left, ConstBgrView()), view(right, ConstBgrView()));
    }
    return greyViews(view(left, ConstImageViewU8()), view(right, ConstImageViewU8()));
}

} // namespace ugv
