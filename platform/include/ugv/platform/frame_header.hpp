#pragma once

/// @file
/// The fixed-size header in front of every stereo frame that crosses a process boundary (shared-memory
/// frame ring chunks, recordings): geometry, pixel format, flags, sequence number and exposure timestamps,
/// followed by the left then the right image rows. A frame flagged kFrameLeftOnly comes from the left camera
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

enum class PixelFormat : std::uint16_t { Grey8 = 1 };

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

enum class FrameError : std::uint8_t { BadMagic, BadVersion, BadFormat, BadGeometry, PayloadMismatch, Truncated };

/// Human-readable text of the error (static string).
const char* toString(FrameError error) noexcept;

/// A header for a Grey8 pair of the given size with rows packed (stride = width).
FrameHeader makeGreyHeader(std::uint32_t width, std::uint32_t height, std::uint64_t sequence, std::int64_t leftStampNs,
                           std::int64_t rightStampNs) noexcept;

/// Writes a packed Grey8 frame to `out` (sizeof(FrameHeader) + 2 w h bytes): the header, the left rows, then the
/// right rows, or zero rows and kFrameLeftOnly when `right` is empty. False, nothing written, when `left` (or a
/// non-empty `right`) is not width x height. The one packer of frame rings and recordings.
bool packGreyFrame(std::byte* out, std::uint32_t width, std::uint32_t height, std::uint64_t sequence,
                   std::int64_t leftStampNs, std::int64_t rightStampNs, ConstImageViewU8 left,
                   ConstImageViewU8 right) noexcept;

/// Checks the header and that `availableBytes` (header + payload actually present) hold the whole frame.
Result<void, FrameError> validate(const FrameHeader& header, std::size_t availableBytes) noexcept;

struct StereoViews {
    ConstImageViewU8 left;
    ConstImageViewU8 right;
};

/// Views on the two images of a validated frame that starts at `frame` (the header) and spans
/// `availableBytes` (the right view empty for a kFrameLeftOnly frame); errors as validate().
Result<StereoViews, FrameError> viewFrame(const std::byte* frame, std::size_t availableBytes) noexcept;

} // namespace ugv
