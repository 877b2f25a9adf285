#include "ugv/hal/recording.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <ctime>
#include <utility>

#include "ugv/platform/clock.hpp"

namespace ugv::hal {

std::uint32_t crc32(std::uint32_t crc, const void* bytes, std::size_t size) noexcept
{
    // zlib takes uInt lengths: feed large buffers in pieces.
    const auto* p = static_cast<const Bytef*>(bytes);
    uLong c = crc;
    while (size > 0) {
        const std::size_t piece = std::min<std::size_t>(size, 1U << 30);
        c = ::crc32(c, p, static_cast<uInt>(piece));
        p += piece;
        size -= piece;
    }
    return static_cast<std::uint32_t>(c);
}

namespace {

constexpr std::size_t kCrcOffset = offsetof(RecordingFileHeader, crc);

std::uint32_t headerCrc(const RecordingFileHeader& header, const std::string& calibration) noexcept
{
    const std::uint32_t c = crc32(0, &header, kCrcOffset);
    return crc32(c, calibration.data(), calibration.size());
}

Error fileError(const std::string& path, const char* what, SysError e, const char* fix)
{
    return Error{path, std::string(what) + ": " + e.text() + " (" + e.name() + ")", fix};
}

/// Writes all of `size` bytes (write(2) may write less).
Result<void, SysError> writeAll(int fd, const std::byte* data, std::size_t size) noexcept
{
    while (size > 0) {
        auto n = sysCall(::write, fd, data, size);
        if (!n) {
            return Unexpected(n.error());
        }
        data += *n;
        size -= static_cast<std::size_t>(*n);
    }
    return {};
}

} // namespace

// ---------------------------------------------------------------------------------------------------- writer

RecordingWriter::RecordingWriter(int fd, std::string path, PixelFormat format, std::uint32_t width,
                                 std::uint32_t height, bool sync)
    : fd_(fd), path_(std::move(path)), format_(format), width_(width), height_(height), sync_(sync),
      record_(sizeof(RecordPrefix) + packedFrameBytes(format, width, height))
{
}

RecordingWriter::~RecordingWriter()
{
    (void)close();
}

Result<RecordingWriter, Error> RecordingWriter::create(const std::string& path, std::uint32_t width,
                                                       std::uint32_t height, const std::string& calibrationText,
                                                       const RecordingWriterOptions& options)
{
    if (width == 0 || height == 0 || width > kMaxFrameSide || height > kMaxFrameSide) {
        return Unexpected(Error{path,
                                "frame size " + std::to_string(width) + "x" + std::to_string(height) +
                                    " is not in 1.." + std::to_string(kMaxFrameSide),
                                "record frames of a real camera size"});
    }
    if (calibrationText.size() > kMaxCalibrationBytes) {
        return Unexpected(Error{path, "the calibration text is larger than 1 MiB", "give the calibration file"});
    }
    if (bytesPerPixel(options.format) == 0) {
        return Unexpected(Error{path, "unknown pixel format " + std::to_string(static_cast<int>(options.format)),
                                "record Grey8 or Bgr8 frames"});
    }
    const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (options.overwrite ? O_TRUNC : O_EXCL);
    auto fd = sysCall(::open, path.c_str(), flags, 0644);
    if (!fd) {
        return Unexpected(fileError(path, "cannot create the recording", fd.error(),
                                    fd.error().code == EEXIST ? "choose a new file name or remove the old recording"
                                                              : "check that the folder exists and is writable"));
    }
    RecordingWriter writer(*fd, path, options.format, width, height, options.syncEveryFrame);

    RecordingFileHeader header;
    header.format = static_cast<std::uint16_t>(options.format);
    header.width = width;
    header.height = height;
    header.calibrationBytes = static_cast<std::uint32_t>(calibrationText.size());
    header.createdRealtimeNs = clockNs(CLOCK_REALTIME);
    header.crc = headerCrc(header, calibrationText);
    auto written = writeAll(*fd, reinterpret_cast<const std::byte*>(&header), sizeof(header));
    if (written) {
        written = writeAll(*fd, reinterpret_cast<const std::byte*>(calibrationText.data()), calibrationText.size());
    }
    if (written) {
        auto synced = sysCall(::fdatasync, *fd);
        if (!synced) {
            written = Unexpected(synced.error());
        }
    }
    if (!written) {
        return Unexpected(fileError(path, "cannot write the recording header", written.error(),
                                    "check the free space and the device"));
    }
    writer.endBytes_ = sizeof(header) + calibrationText.size();
    return writer;
}

Result<void, SysError> RecordingWriter::append(std::uint64_t sequence, std::int64_t leftStampNs,
                                               std::int64_t rightStampNs, const StereoViews& images) noexcept
{
    if (!fd_.valid()) {
        return Unexpected(SysError{EBADF});
    }
    std::byte* out = record_.data() + sizeof(RecordPrefix);
    if (images.format != format_ || !packFrame(out, width_, height_, sequence, leftStampNs, rightStampNs, images)) {
        return Unexpected(SysError{EINVAL});
    }
    RecordPrefix prefix;
    prefix.frameBytes = static_cast<std::uint32_t>(record_.size() - sizeof(RecordPrefix));
    prefix.crc = crc32(0, out, prefix.frameBytes);
    std::memcpy(record_.data(), &prefix, sizeof(prefix));
    if (auto written = writeAll(fd_.get(), record_.data(), record_.size()); !written) {
        // Part of the record may be on disk (a full disk takes what fits): cut the file back to the last complete
        // record, so that it stays readable to its end and a later append starts on a record boundary.
        const auto end = static_cast<off_t>(endBytes_);
        (void)sysCall(::ftruncate, fd_.get(), end);
        (void)::lseek(fd_.get(), end, SEEK_SET);
        return written;
    }
    endBytes_ += record_.size(); // complete in the file (a failed sync below does not tear it)
    if (sync_) {
        if (auto synced = sysCall(::fdatasync, fd_.get()); !synced) {
            return Unexpected(synced.error());
        }
    }
    ++frames_;
    return {};
}

Result<void, SysError> RecordingWriter::close() noexcept
{
    if (!fd_.valid()) {
        return {};
    }
    const int fd = fd_.release();
    auto synced = sysCall(::fdatasync, fd);
    const int closed = ::close(fd); // never retried: the descriptor is gone either way
    if (!synced) {
        return Unexpected(synced.error());
    }
    if (closed != 0) {
        return Unexpected(SysError{errno});
    }
    return {};
}

// ---------------------------------------------------------------------------------------------------- reader

RecordingReader::RecordingReader(int fd, RecordingInfo info, std::uint64_t firstRecord, std::uint64_t fileBytes)
    : fd_(fd), info_(std::move(info)), firstRecord_(firstRecord), fileBytes_(fileBytes), offset_(firstRecord),
      frameBytes_(packedFrameBytes(info_.format, info_.width, info_.height)), frame_(frameBytes_)
{
}

Result<RecordingReader, Error> RecordingReader::open(const std::string& path)
{
    auto fd = sysCall(::open, path.c_str(), O_RDONLY | O_CLOEXEC);
    if (!fd) {
        return Unexpected(fileError(path, "cannot open the recording", fd.error(),
                                    "give the path of a recording made by `ugvsense record`, `sim --course` or "
                                    "`recording import`"));
    }
    const auto fail = [&](const std::string& what, const char* fix) {
        ::close(*fd);
        return Unexpected(Error{path, what, fix});
    };
    struct stat st {};
    if (::fstat(*fd, &st) != 0) {
        return fail("cannot stat the file", "check the file");
    }
    const auto fileBytes = static_cast<std::uint64_t>(st.st_size);
    RecordingFileHeader header;
    if (fileBytes < sizeof(header) ||
        ::pread(*fd, &header, sizeof(header), 0) != static_cast<ssize_t>(sizeof(header))) {
        return fail("shorter than a recording header (" + std::to_string(fileBytes) + " bytes)",
                    "the file is not a recording, or it was cut off before the first frame: record again");
    }
    if (std::memcmp(header.magic, kRecordingMagic, sizeof(kRecordingMagic)) != 0) {
        return fail("not a ugvsense recording (bad magic)", "give a .ugvrec file; convert PNG pairs with "
                                                            "`ugvsense recording import`");
    }
    if (header.version != kRecordingVersion) {
        return fail("recording format version " + std::to_string(header.version) +
                        " is not supported (this build "
                        "reads version 1)",
                    "replay it with the ugvsense version that recorded it");
    }
    const auto format = static_cast<PixelFormat>(header.format);
    if (header.headerBytes != sizeof(header) || bytesPerPixel(format) == 0 || header.width == 0 || header.height == 0 ||
        header.width > kMaxFrameSide || header.height > kMaxFrameSide ||
        header.calibrationBytes > kMaxCalibrationBytes || sizeof(header) + header.calibrationBytes > fileBytes) {
        return fail("corrupt recording header (geometry " + std::to_string(header.width) + "x" +
                        std::to_string(header.height) + ", calibration " + std::to_string(header.calibrationBytes) +
                        " bytes)",
                    "the header is damaged: the frames cannot be located; restore the file from a copy");
    }
    RecordingInfo info;
    info.format = format;
    info.width = header.width;
    info.height = header.height;
    info.createdRealtimeNs = header.createdRealtimeNs;
    info.calibrationText.resize(header.calibrationBytes);
    if (header.calibrationBytes > 0 && ::pread(*fd, info.calibrationText.data(), header.calibrationBytes,
                                               sizeof(header)) != static_cast<ssize_t>(header.calibrationBytes)) {
        return fail("cannot read the calibration text", "check the file");
    }
    if (headerCrc(header, info.calibrationText) != header.crc) {
        return fail("corrupt recording header (CRC mismatch over the header and calibration)",
                    "the header or calibration was damaged; restore the file from a copy");
    }
    return RecordingReader(*fd, std::move(info), sizeof(header) + header.calibrationBytes, fileBytes);
}

ssize_t RecordingReader::readFully(std::byte* out, std::size_t size) noexcept
{
    std::size_t got = 0;
    while (got < size) {
        auto n = sysCall(::pread, fd_.get(), out + got, size - got, static_cast<off_t>(offset_ + got));
        if (!n) {
            lastError_ = n.error();
            return -1;
        }
        if (*n == 0) {
            break;
        }
        got += static_cast<std::size_t>(*n);
    }
    return static_cast<ssize_t>(got);
}

ReadStatus RecordingReader::next() noexcept
{
    for (;;) {
        // peek() handles the end, a cut-off tail and damaged prefixes; here the whole record is read and checked.
        const ReadStatus status = peek();
        if (status != ReadStatus::Frame) {
            return status;
        }
        RecordPrefix prefix;
        if (readFully(reinterpret_cast<std::byte*>(&prefix), sizeof(prefix)) != static_cast<ssize_t>(sizeof(prefix))) {
            return ReadStatus::IoError;
        }
        offset_ += sizeof(prefix);
        if (readFully(frame_.data(), frameBytes_) != static_cast<ssize_t>(frameBytes_)) {
            offset_ -= sizeof(prefix);
            return ReadStatus::IoError; // peek() saw the whole record in the file
        }
        offset_ += frameBytes_;
        FrameHeader frameHeader;
        std::memcpy(&frameHeader, frame_.data(), sizeof(frameHeader));
        if (crc32(0, frame_.data(), frameBytes_) != prefix.crc || !validate(frameHeader, frameBytes_) ||
            frameHeader.width != info_.width || frameHeader.height != info_.height ||
            frameHeader.format != info_.format) {
            ++corrupt_;
            continue;
        }
        current_ = frameHeader;
        ++framesRead_;
        return ReadStatus::Frame;
    }
}

ReadStatus RecordingReader::peek() noexcept
{
    trailing_ = 0;
    for (;;) {
        if (offset_ >= fileBytes_) {
            return ReadStatus::End;
        }
        std::byte head[sizeof(RecordPrefix) + sizeof(FrameHeader)];
        const ssize_t got = readFully(head, sizeof(head));
        if (got < 0) {
            return ReadStatus::IoError;
        }
        RecordPrefix prefix;
        if (static_cast<std::size_t>(got) >= sizeof(prefix)) {
            std::memcpy(&prefix, head, sizeof(prefix));
            if (prefix.magic != kRecordMagic || prefix.frameBytes != frameBytes_) {
                ++corrupt_;
                if (!resync()) {
                    trailing_ = fileBytes_ - offset_;
                    offset_ = fileBytes_;
                    return ReadStatus::Truncated;
                }
                continue;
            }
        }
        if (static_cast<std::size_t>(got) < sizeof(head) || offset_ + sizeof(prefix) + frameBytes_ > fileBytes_) {
            trailing_ = fileBytes_ - offset_;
            offset_ = fileBytes_;
            return ReadStatus::Truncated;
        }
        std::memcpy(&peeked_, head + sizeof(prefix), sizeof(peeked_));
        return ReadStatus::Frame;
    }
}

bool RecordingReader::resync() noexcept
{
    // Scan forward in 4 KiB steps for the record magic (at most to the end of the file).
    constexpr std::size_t kStep = 4096;
    std::byte window[kStep + sizeof(std::uint32_t)];
    std::uint64_t at = offset_ + 1;
    while (at + sizeof(RecordPrefix) <= fileBytes_) {
        const std::uint64_t saved = offset_;
        offset_ = at;
        const ssize_t got = readFully(window, sizeof(window));
        offset_ = saved;
        if (got < static_cast<ssize_t>(sizeof(std::uint32_t))) {
            return false;
        }
        for (ssize_t i = 0; i + 4 <= got; ++i) {
            std::uint32_t magic = 0;
            std::memcpy(&magic, window + i, sizeof(magic));
            if (magic == kRecordMagic) {
                offset_ = at + static_cast<std::uint64_t>(i);
                return true;
            }
        }
        at += kStep;
    }
    return false;
}

Result<void, SysError> RecordingReader::rewind() noexcept
{
    offset_ = firstRecord_;
    trailing_ = 0;
    return {};
}

StereoViews RecordingReader::views() const noexcept
{
    auto views = viewFrame(frame_.data(), frame_.size());
    return views ? *views : StereoViews{};
}

Result<RecordingScan, Error> scanRecording(const std::string& path)
{
    auto reader = RecordingReader::open(path);
    if (!reader) {
        return Unexpected(reader.error());
    }
    RecordingScan scan;
    for (;;) {
        const ReadStatus status = reader->next();
        if (status == ReadStatus::IoError) {
            const SysError e = reader->lastError();
            return Unexpected(fileError(path, "read failed", e, "check the device"));
        }
        if (status != ReadStatus::Frame) {
            break;
        }
        const FrameHeader& h = reader->header();
        if (scan.frames == 0) {
            scan.firstSequence = h.sequence;
            scan.firstStampNs = h.leftStampNs;
        } else if (h.sequence > scan.lastSequence + 1) {
            scan.sequenceGaps += h.sequence - scan.lastSequence - 1;
        }
        scan.lastSequence = h.sequence;
        scan.lastStampNs = h.leftStampNs;
        ++scan.frames;
    }
    scan.corruptFrames = reader->corruptFrames();
    scan.trailingBytes = reader->trailingBytes();
    return scan;
}

} // namespace ugv::hal
