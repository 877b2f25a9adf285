#pragma once

/// @file
/// The fixed-size header in front of every stereo frame that crosses a process boundary (shared-memory
/// frame ring chunks, recordings): geometry, pixel format, flags, sequence number and exposure timestamps,
/// followed by the left then the right image rows. Both images have the frame's pixel format: Grey8 (one byte a
/// pixel: a grey camera, or a colour camera's luma) or Bgr8 (three bytes, OpenCV's CV_8UC3 order: what the one-camera
/// detector needs to tell the ground by its colour). A frame flagged kFrameLeftOnly comes from the left camera
/// alone (a one-camera rig, or the pair's right camera lost): its right rows are zero and viewFrame() gives an
/// empty right view, so nothing matches a black image. A receiver validates the header against the bytes it
/// actually holds before it builds image views on the payload, so a malformed or truncated frame is an
/// error code, never an out-of-bounds read.
///
/// Thread-safety: plain data and pure functions. RT-safe: yes.

#include <cstddef>
#include <cstdint>

#include "ugv/platform/image_view.hpp"
#include "ugv/platform/result.hpp"

namespace ugv {

enum class PixelFormat : std::uint16_t { Grey8 = 1, Bgr8 = 2 };

/// Bytes of one pixel: 1 (Grey8), 3 (Bgr8), 0 for a value that is no PixelFormat.
[[nodiscard]] constexpr std::uint32_t bytesPerPixel(PixelFormat format) noexcept
{
    switch (format) {
    case PixelFormat::Grey8:
        return 1;
    case PixelFormat::Bgr8:
        return 3;
    }
    return 0;
}

inline constexpr std::uint32_t kFrameMagic = 0x46564755; ///< "UGVF" in little-endian byte order
inline constexpr std::uint16_t kFrameVersion = 1;
inline constexpr std::uint32_t kMaxFrameSide = 8192; ///< [px] larger sizes are rejected as corrupt

/// FrameHeader::flags bits; any other bit set is an unknown format (BadFormat).
inline constexpr std::uint32_t kFrameLeftOnly = 1U; ///< the right camera delivered nothing: right rows are zero
inline constexpr std::uint32_t kFrameKnownFlags = kFrameLeftOnly;

struct FrameHeader {
    std::uint32_t magic = kFrameMagic;
    std::uint16_t version = kFrameVersion;
    PixelFormat format = PixelFormat::Grey8;
    std::uint32_t width = 0;        ///< [px] per camera
    std::uint32_t height = 0;       ///< [px]
    std::uint32_t strideBytes = 0;  ///< bytes between rows of one image
    std::uint32_t flags = 0;        ///< kFrame* bits (0 in files written before flags existed)
    std::uint64_t sequence = 0;     ///< capture sequence number, +1 per pair; gaps mean dropped frames
    std::int64_t leftStampNs = 0;   ///< [ns] CLOCK_MONOTONIC exposure time of the left image
    std::int64_t rightStampNs = 0;  ///< [ns] of the right image
    std::uint64_t payloadBytes = 0; ///< bytes after the header: 2 * strideBytes * height
};
static_assert(sizeof(FrameHeader) == 56, "FrameHeader is a wire format: its size must not change");

/// Bytes of a packed frame (header + both images, rows packed) of `width` x `height` in `format`.
[[nodiscard]] constexpr std::size_t packedFrameBytes(PixelFormat format, std::uint32_t width,
                                                     std::uint32_t height) noexcept
{
    return sizeof(FrameHeader) + 2U * static_cast<std::size_t>(bytesPerPixel(format)) * width * height;
}

/// The two images of a pair in the frame's pixel format: `left`/`right` for Grey8, `leftBgr`/`rightBgr` for Bgr8
/// (the other two empty). The right image is empty for a left-only frame (kFrameLeftOnly).
struct StereoViews {
    PixelFormat format = PixelFormat::Grey8;
    ConstImageViewU8 left;
    ConstImageViewU8 right;
    ConstBgrView leftBgr;
    ConstBgrView rightBgr;

    [[nodiscard]] bool colour() const noexcept { return format == PixelFormat::Bgr8; }
    [[nodiscard]] bool leftOnly() const noexcept { return colour() ? rightBgr.empty() : right.empty(); }
    [[nodiscard]] int width() const noexcept { return colour() ? leftBgr.width() : left.width(); }    ///< [px]
    [[nodiscard]] int height() const noexcept { return colour() ? leftBgr.height() : left.height(); } ///< [px]
    /// True when the left image (and the right one unless the frame is left-only) is `width` x `height`.
    [[nodiscard]] bool fits(int width, int height) const noexcept;
};

/// Grey views of a pair (right empty: left-only).
[[nodiscard]] inline StereoViews greyViews(ConstImageViewU8 left, ConstImageViewU8 right = {}) noexcept
{
    return StereoViews{PixelFormat::Grey8, left, right, {}, {}};
}
/// BGR views of a pair (right empty: left-only).
[[nodiscard]] inline StereoViews bgrViews(ConstBgrView left, ConstBgrView right = {}) noexcept
{
    return StereoViews{PixelFormat::Bgr8, {}, {}, left, right};
}

/// A header for a pair of the given size and format with rows packed (stride = width x bytes per pixel).
FrameHeader makeFrameHeader(PixelFormat format, std::uint32_t width, std::uint32_t height, std::uint64_t sequence,
                            std::int64_t leftStampNs, std::int64_t rightStampNs) noexcept;

/// Writes a packed frame of `images` to `out` (packedFrameBytes(images.format, width, height) bytes): the header, the
/// left rows, then the right rows, or zero rows and kFrameLeftOnly when the right image is empty. False, nothing
/// written, when the images do not fit width x height. The one packer of frame rings and recordings.
bool packFrame(std::byte* out, std::uint32_t width, std::uint32_t height, std::uint64_t sequence,
               std::int64_t leftStampNs, std::int64_t rightStampNs, const StereoViews& images) noexcept;

enum class FrameError : std::uint8_t { BadMagic, BadVersion, BadFormat, BadGeometry, PayloadMismatch, Truncated };

/// Human-readable text of the error (static string).
const char* toString(FrameError error) noexcept;

/// Checks the header and that `availableBytes` (header + payload actually present) hold the whole frame.
Result<void, FrameError> validate(const FrameHeader& header, std::size_t availableBytes) noexcept;

/// Views on the two images of a validated frame that starts at `frame` (the header) and spans
/// `availableBytes`, in its pixel format (the right view empty for a kFrameLeftOnly frame); errors as validate().
Result<StereoViews, FrameError> viewFrame(const std::byte* frame, std::size_t availableBytes) noexcept;

} // namespace ugv
