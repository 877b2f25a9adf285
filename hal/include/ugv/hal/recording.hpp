#pragma once

/// @file
/// Recordings: raw stereo frames with their timestamps, sequence numbers and the calibration, in one
/// append-only file that survives a crash or a power cut mid-write.
///
/// Format (version 1, little-endian, `*.ugvrec`):
///
///     FileHeader (64 bytes)                      magic "UGVREC01", version, frame geometry, calibration size,
///                                                CRC-32 of the header bytes before the CRC and the calibration
///     calibration text (calibrationBytes)        the calibration file as written by `ugvsense calibrate`
///     record 0, record 1, ...                    one per stereo frame, nothing else
///
///     record = RecordPrefix (16 bytes: magic "UGVr", frame bytes, CRC-32 of the frame bytes, reserved)
///              frame  = FrameHeader (56 bytes, platform/frame_header.hpp) + left rows + right rows (packed)
///
/// Every frame of a recording has the file header's pixel format: Grey8, or Bgr8 from a colour camera (three times
/// the bytes; what the one-camera detector needs to tell the ground by colour).
///
/// A writer appends whole records (one write per frame; with `syncEveryFrame` an fdatasync after each), so a
/// crash or power cut loses at most the frame being written. The reader returns every complete record whose CRC
/// matches; a record cut off at the end of the file is reported as `Truncated` (the recovered frame count is the
/// number read before it), a record whose CRC does not match is skipped and counted (`corruptFrames`), and a
/// damaged prefix is skipped by scanning for the next record magic.
///
/// Thread-safety: thread-compatible (one owner per object). RT-safe: RecordingReader::next() and rewind() do
/// not allocate (file reads into a buffer sized at open); they do block on file I/O, so the service reads a
/// recording on its capture thread, never on the vision thread. The writer is for low-priority threads.

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "ugv/hal/sys_call.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/frame_header.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::hal {

inline constexpr char kRecordingMagic[8] = {'U', 'G', 'V', 'R', 'E', 'C', '0', '1'};
inline constexpr std::uint16_t kRecordingVersion = 1;
inline constexpr std::uint32_t kRecordMagic = 0x72564755;       ///< "UGVr" little-endian
inline constexpr std::uint32_t kMaxCalibrationBytes = 1U << 20; ///< larger is a corrupt header
inline constexpr std::size_t kRecordingFileHeaderBytes = 64;

struct RecordingFileHeader {
    char magic[8] = {'U', 'G', 'V', 'R', 'E', 'C', '0', '1'};
    std::uint16_t version = kRecordingVersion;
    std::uint16_t format = static_cast<std::uint16_t>(PixelFormat::Grey8);
    std::uint32_t headerBytes = kRecordingFileHeaderBytes;
    std::uint32_t width = 0;  ///< [px] per camera
    std::uint32_t height = 0; ///< [px]
    std::uint32_t calibrationBytes = 0;
    std::uint32_t reserved0 = 0;
    std::int64_t createdRealtimeNs = 0; ///< [ns] CLOCK_REALTIME when the recording was started
    std::uint8_t reserved1[20] = {};
    std::uint32_t crc = 0; ///< CRC-32 of the 60 bytes before it and the calibration text
};
static_assert(sizeof(RecordingFileHeader) == kRecordingFileHeaderBytes, "wire format: size must not change");

struct RecordPrefix {
    std::uint32_t magic = kRecordMagic;
    std::uint32_t frameBytes = 0; ///< FrameHeader + payload
    std::uint32_t crc = 0;        ///< CRC-32 of the frame bytes
    std::uint32_t reserved = 0;
};
static_assert(sizeof(RecordPrefix) == 16, "wire format: size must not change");

/// CRC-32 (zlib's, polynomial 0xEDB88320) of `bytes`, continuing from `crc` (0 to start).
std::uint32_t crc32(std::uint32_t crc, const void* bytes, std::size_t size) noexcept;

struct RecordingWriterOptions {
    PixelFormat format = PixelFormat::Grey8; ///< of every frame (appending another format is EINVAL)
    bool syncEveryFrame = true; ///< fdatasync after each frame: a power cut loses at most the frame being written
    bool overwrite = false;     ///< replace an existing file (otherwise creating over one is an error)
};

class RecordingWriter {
public:
    /// Creates `path` and writes the file header and the calibration text (made durable before returning).
    /// @return the writer, or an error naming the file, the errno text and the fix.
    static Result<RecordingWriter, Error> create(const std::string& path, std::uint32_t width, std::uint32_t height,
                                                 const std::string& calibrationText,
                                                 const RecordingWriterOptions& options = {});
    RecordingWriter(RecordingWriter&& other) noexcept = default;
    /// Not assignable: assigning over a writer would close its file unsynced; close() it and create another.
    RecordingWriter& operator=(RecordingWriter&& other) = delete;
    RecordingWriter(const RecordingWriter&) = delete;
    RecordingWriter& operator=(const RecordingWriter&) = delete;
    ~RecordingWriter();

    /// Appends one frame (the images must be width x height in the recording's format, else EINVAL; the header's
    /// geometry is rewritten to the packed layout). An empty right image is recorded as a left-only frame
    /// (kFrameLeftOnly; the reader gives it back so). No allocation: the record is assembled in a buffer sized at
    /// create().
    /// @return nothing, or the errno of the failed write (ENOSPC: the disk is full). The file keeps every earlier
    /// frame and ends after the last one: a record that was written in part is cut off again, so appends may go on
    /// once there is room (a reader never sees a torn record from a full disk).
    Result<void, SysError> append(std::uint64_t sequence, std::int64_t leftStampNs, std::int64_t rightStampNs,
                                  const StereoViews& images) noexcept;
    /// Flushes and closes; further appends fail with EBADF. Also done by the destructor.
    Result<void, SysError> close() noexcept;

    [[nodiscard]] std::uint64_t framesWritten() const noexcept { return frames_; }
    [[nodiscard]] const std::string& path() const noexcept { return path_; }

private:
    RecordingWriter(int fd, std::string path, PixelFormat format, std::uint32_t width, std::uint32_t height, bool sync);

    UniqueFd fd_;
    std::string path_;
    PixelFormat format_ = PixelFormat::Grey8;
    std::uint32_t width_ = 0;
    std::uint32_t height_ = 0;
    bool sync_ = true;
    std::uint64_t frames_ = 0;
    std::uint64_t endBytes_ = 0;    ///< file size after the last complete record
    std::vector<std::byte> record_; ///< prefix + frame header + payload
};

enum class ReadStatus : std::uint8_t {
    Frame,     ///< a complete frame is in frame()/header()
    End,       ///< clean end of the file after the last complete record
    Truncated, ///< the last record is cut off (a crash while it was written): every earlier frame was returned
    IoError,   ///< read(2) failed (see lastError())
};

struct RecordingInfo {
    PixelFormat format = PixelFormat::Grey8;
    std::uint32_t width = 0;
    std::uint32_t height = 0;
    std::int64_t createdRealtimeNs = 0;
    std::string calibrationText;
};

class RecordingReader {
public:
    /// Opens `path` and validates the file header and calibration CRC.
    /// @return the reader, or an error naming the file, what is wrong (not a recording, unknown version, corrupt
    /// header, truncated header) and the fix.
    static Result<RecordingReader, Error> open(const std::string& path);
    RecordingReader(RecordingReader&& other) noexcept = default;
    RecordingReader& operator=(RecordingReader&& other) noexcept = default;
    RecordingReader(const RecordingReader&) = delete;
    RecordingReader& operator=(const RecordingReader&) = delete;
    ~RecordingReader() = default;

    [[nodiscard]] const RecordingInfo& info() const noexcept { return info_; }

    /// Reads the next complete, CRC-valid frame (skipping and counting corrupt ones). No allocation.
    ReadStatus next() noexcept;
    /// Reads only the next record's prefix and frame header (72 bytes) without consuming it, so that a replay can
    /// wait for the frame's due time before it reads the payload: Frame (peekedHeader() is valid; next() then
    /// reads that record), End, Truncated or IoError. A damaged prefix is skipped (counted) as in next().
    ReadStatus peek() noexcept;
    [[nodiscard]] const FrameHeader& peekedHeader() const noexcept { return peeked_; }
    /// Goes back to the first frame (loops of a replay). Counters are kept.
    Result<void, SysError> rewind() noexcept;

    /// The last frame returned by next() (valid until the next call).
    [[nodiscard]] const FrameHeader& header() const noexcept { return current_; }
    [[nodiscard]] StereoViews views() const noexcept;

    [[nodiscard]] std::uint64_t framesRead() const noexcept { return framesRead_; }
    [[nodiscard]] std::uint64_t corruptFrames() const noexcept { return corrupt_; }
    /// Bytes of the record cut off at the end of the file (Truncated), else 0.
    [[nodiscard]] std::uint64_t trailingBytes() const noexcept { return trailing_; }
    [[nodiscard]] SysError lastError() const noexcept { return lastError_; }

private:
    RecordingReader(int fd, RecordingInfo info, std::uint64_t firstRecord, std::uint64_t fileBytes);
    /// Reads exactly `size` bytes at the current offset; returns the bytes read (short at end of file) or -1.
    ssize_t readFully(std::byte* out, std::size_t size) noexcept;
    /// After a damaged prefix at offset_: moves offset_ to the next record magic; false at the end of the file.
    bool resync() noexcept;

    UniqueFd fd_;
    RecordingInfo info_;
    std::uint64_t firstRecord_ = 0;
    std::uint64_t fileBytes_ = 0;
    std::uint64_t offset_ = 0;
    std::size_t frameBytes_ = 0;
    std::vector<std::byte> frame_; ///< frame header + payload of the last frame
    FrameHeader current_{};
    FrameHeader peeked_{};
    std::uint64_t framesRead_ = 0;
    std::uint64_t corrupt_ = 0;
    std::uint64_t trailing_ = 0;
    SysError lastError_{};
};

/// Scans a whole recording without keeping frames: complete frames, corrupt ones, trailing bytes.
struct RecordingScan {
    std::uint64_t frames = 0;
    std::uint64_t corruptFrames = 0;
    std::uint64_t trailingBytes = 0;
    std::uint64_t firstSequence = 0;
    std::uint64_t lastSequence = 0;
    std::uint64_t sequenceGaps = 0; ///< frames missing between consecutive sequence numbers
    std::int64_t firstStampNs = 0;
    std::int64_t lastStampNs = 0;
};
Result<RecordingScan, Error> scanRecording(const std::string& path);

} // namespace ugv::hal
