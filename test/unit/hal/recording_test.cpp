#include "ugv/hal/recording.hpp"

#include <sys/mount.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace ugv::hal {
namespace {

constexpr std::uint32_t kWidth = 32;
constexpr std::uint32_t kHeight = 8;
const std::string kCalibration = "%YAML:1.0\n---\nschema_version: 1\nrectified: 1\n";
constexpr std::size_t kRecordBytes = sizeof(RecordPrefix) + sizeof(FrameHeader) + 2 * kWidth * kHeight;

/// A folder of its own per test (ctest runs tests in parallel processes).
class RecordingTest : public ::testing::Test {
protected:
    void SetUp() override
    {
        dir_ =
            std::filesystem::temp_directory_path() / ("ugv-recording-test-" + std::to_string(::getpid()) + "-" +
                                                      ::testing::UnitTest::GetInstance()->current_test_info()->name());
        std::filesystem::create_directories(dir_);
        path_ = (dir_ / "r.ugvrec").string();
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    /// Writes `frames` frames; frame k has sequence 10 + k, stamps 1000 k / 1000 k + 5 and pixels (k + x + y).
    void writeFrames(int frames)
    {
        auto writer = RecordingWriter::create(path_, kWidth, kHeight, kCalibration);
        ASSERT_TRUE(writer.has_value()) << writer.error().message();
        for (int k = 0; k < frames; ++k) {
            fill(k);
            ASSERT_TRUE(writer
                            ->append(static_cast<std::uint64_t>(10 + k), 1000 * k, 1000 * k + 5,
                                     greyViews(left_.view(), right_.view()))
                            .has_value());
        }
        EXPECT_EQ(writer->framesWritten(), static_cast<std::uint64_t>(frames));
        ASSERT_TRUE(writer->close().has_value());
    }
    void fill(int k)
    {
        for (int y = 0; y < static_cast<int>(kHeight); ++y) {
            for (int x = 0; x < static_cast<int>(kWidth); ++x) {
                left_.view().at(x, y) = static_cast<std::uint8_t>(k + x + y);
                right_.view().at(x, y) = static_cast<std::uint8_t>(200 - k - x);
            }
        }
    }
    void corruptByte(std::uint64_t offset)
    {
        std::fstream f(path_, std::ios::in | std::ios::out | std::ios::binary);
        f.seekg(static_cast<std::streamoff>(offset));
        char c = 0;
        f.read(&c, 1);
        c = static_cast<char>(c ^ 0x5A);
        f.seekp(static_cast<std::streamoff>(offset));
        f.write(&c, 1);
    }
    std::uint64_t recordOffset(int k) const
    {
        return kRecordingFileHeaderBytes + kCalibration.size() + static_cast<std::uint64_t>(k) * kRecordBytes;
    }
    /// Sequences of every frame the reader returns, and its final status.
    std::vector<std::uint64_t> readAll(ReadStatus& last)
    {
        std::vector<std::uint64_t> seqs;
        auto reader = RecordingReader::open(path_);
        EXPECT_TRUE(reader.has_value()) << reader.error().message();
        if (!reader) {
            return seqs;
        }
        while ((last = reader->next()) == ReadStatus::Frame) {
            seqs.push_back(reader->header().sequence);
        }
        return seqs;
    }

    std::filesystem::path dir_;
    std::string path_;
    Image<std::uint8_t> left_{kWidth, kHeight};
    Image<std::uint8_t> right_{kWidth, kHeight};
};

TEST_F(RecordingTest, FramesComeBackWithStampsSequencesPixelsAndCalibration)
{
    writeFrames(5);

    auto reader = RecordingReader::open(path_);
    ASSERT_TRUE(reader.has_value()) << reader.error().message();
    EXPECT_EQ(reader->info().width, kWidth);
    EXPECT_EQ(reader->info().height, kHeight);
    EXPECT_EQ(reader->info().calibrationText, kCalibration);
    EXPECT_GT(reader->info().createdRealtimeNs, 0);
    for (int k = 0; k < 5; ++k) {
        ASSERT_EQ(reader->next(), ReadStatus::Frame) << k;
        EXPECT_EQ(reader->header().sequence, static_cast<std::uint64_t>(10 + k));
        EXPECT_EQ(reader->header().leftStampNs, 1000 * k);
        EXPECT_EQ(reader->header().rightStampNs, 1000 * k + 5);
        const StereoViews v = reader->views();
        EXPECT_EQ(v.left.at(3, 2), static_cast<std::uint8_t>(k + 5));
        EXPECT_EQ(v.right.at(7, 4), static_cast<std::uint8_t>(200 - k - 7));
    }
    EXPECT_EQ(reader->next(), ReadStatus::End);
    EXPECT_EQ(reader->framesRead(), 5U);
    EXPECT_EQ(reader->corruptFrames(), 0U);
}

TEST_F(RecordingTest, ALeftOnlyFrameIsRecordedAndComesBackWithoutARightImage)
{
    fill(3);
    {
        auto writer = RecordingWriter::create(path_, kWidth, kHeight, kCalibration, {});
        ASSERT_TRUE(writer.has_value()) << writer.error().message();
        ASSERT_TRUE(writer->append(1, 10, 0, greyViews(left_.view(), ConstImageViewU8())).has_value());
        ASSERT_TRUE(writer->append(2, 20, 21, greyViews(left_.view(), right_.view())).has_value());
    }
    auto reader = RecordingReader::open(path_);
    ASSERT_TRUE(reader.has_value()) << reader.error().message();
    ASSERT_EQ(reader->next(), ReadStatus::Frame);
    EXPECT_EQ(reader->views().left.at(3, 2), left_.view().at(3, 2));
    EXPECT_TRUE(reader->views().right.empty());
    ASSERT_EQ(reader->next(), ReadStatus::Frame); // the pair after it is whole again
    EXPECT_EQ(reader->views().right.at(7, 4), right_.view().at(7, 4));
}

TEST_F(RecordingTest, AColourRecordingKeepsBgrFramesAndRefusesAGreyOne)
{
    Image<BgrPixel> left(kWidth, kHeight);
    Image<BgrPixel> right(kWidth, kHeight);
    left.view().at(3, 2) = BgrPixel{1, 2, 3};
    right.view().at(31, 7) = BgrPixel{200, 100, 50};
    RecordingWriterOptions options;
    options.format = PixelFormat::Bgr8;
    {
        auto writer = RecordingWriter::create(path_, kWidth, kHeight, kCalibration, options);
        ASSERT_TRUE(writer.has_value()) << writer.error().message();
        ASSERT_TRUE(writer->append(1, 10, 11, bgrViews(left.view(), right.view())).has_value());
        ASSERT_TRUE(writer->append(2, 20, 0, bgrViews(left.view())).has_value()); // left-only
        fill(0);
        const auto grey = writer->append(3, 30, 31, greyViews(left_.view(), right_.view()));
        ASSERT_FALSE(grey.has_value()); // one format per recording
        EXPECT_EQ(grey.error().code, EINVAL);
        EXPECT_EQ(writer->framesWritten(), 2U);
    }
    EXPECT_EQ(std::filesystem::file_size(path_),
              kRecordingFileHeaderBytes + kCalibration.size() +
                  2 * (sizeof(RecordPrefix) + sizeof(FrameHeader) + 6 * kWidth * kHeight));
    auto reader = RecordingReader::open(path_);
    ASSERT_TRUE(reader.has_value()) << reader.error().message();
    EXPECT_EQ(reader->info().format, PixelFormat::Bgr8);
    ASSERT_EQ(reader->next(), ReadStatus::Frame);
    const StereoViews pair = reader->views();
    ASSERT_EQ(pair.format, PixelFormat::Bgr8);
    EXPECT_EQ(pair.leftBgr.at(3, 2).r, 3);
    EXPECT_EQ(pair.rightBgr.at(31, 7).b, 200);
    ASSERT_EQ(reader->next(), ReadStatus::Frame);
    EXPECT_TRUE(reader->views().leftOnly());
    EXPECT_EQ(reader->views().leftBgr.at(3, 2).g, 2);
    EXPECT_EQ(reader->next(), ReadStatus::End);
}

TEST_F(RecordingTest, AFrameOfAnotherFormatThanTheFilesIsCountedCorrupt)
{
    // A grey recording whose second record (CRC and all) holds a colour frame: the reader sizes its buffer by the
    // file's format, so the record is no frame of this recording; it is skipped and counted, never viewed.
    writeFrames(1);
    std::vector<char> greyRecord(kRecordBytes);
    {
        std::ifstream in(path_, std::ios::binary);
        in.seekg(static_cast<std::streamoff>(recordOffset(0)));
        in.read(greyRecord.data(), static_cast<std::streamsize>(greyRecord.size()));
    }
    std::vector<std::byte> record(sizeof(RecordPrefix) + packedFrameBytes(PixelFormat::Bgr8, kWidth, kHeight));
    Image<BgrPixel> colour(kWidth, kHeight);
    ASSERT_TRUE(packFrame(record.data() + sizeof(RecordPrefix), kWidth, kHeight, 99, 0, 0,
                          bgrViews(colour.view(), colour.view())));
    RecordPrefix prefix;
    prefix.frameBytes = static_cast<std::uint32_t>(record.size() - sizeof(RecordPrefix));
    prefix.crc = crc32(0, record.data() + sizeof(RecordPrefix), prefix.frameBytes);
    std::memcpy(record.data(), &prefix, sizeof(prefix));
    {
        std::ofstream out(path_, std::ios::binary | std::ios::app);
        out.write(reinterpret_cast<const char*>(record.data()), static_cast<std::streamsize>(record.size()));
        out.write(greyRecord.data(), static_cast<std::streamsize>(greyRecord.size())); // a good frame after it
    }

    auto reader = RecordingReader::open(path_);
    ASSERT_TRUE(reader.has_value());
    int frames = 0;
    ReadStatus status = ReadStatus::Frame;
    while ((status = reader->next()) == ReadStatus::Frame) {
        EXPECT_EQ(reader->views().format, PixelFormat::Grey8);
        ++frames;
    }
    EXPECT_EQ(frames, 2); // the frames before and after it
    EXPECT_EQ(status, ReadStatus::End);
    EXPECT_GE(reader->corruptFrames(), 1U);
}

TEST_F(RecordingTest, CutOffLastFrameIsTruncatedAndEveryEarlierFrameIsRecovered)
{
    writeFrames(4);
    // A crash while frame 3 was being written: half of its record is on disk.
    std::filesystem::resize_file(path_, recordOffset(3) + kRecordBytes / 2);

    ReadStatus last = ReadStatus::Frame;
    EXPECT_EQ(readAll(last), (std::vector<std::uint64_t>{10, 11, 12}));
    EXPECT_EQ(last, ReadStatus::Truncated);

    const auto scan = scanRecording(path_);
    ASSERT_TRUE(scan.has_value());
    EXPECT_EQ(scan->frames, 3U);
    EXPECT_EQ(scan->trailingBytes, kRecordBytes / 2);
}

TEST_F(RecordingTest, CutInsideARecordPrefixIsTruncated)
{
    writeFrames(2);
    std::filesystem::resize_file(path_, recordOffset(1) + 7);

    ReadStatus last = ReadStatus::Frame;
    EXPECT_EQ(readAll(last), (std::vector<std::uint64_t>{10}));
    EXPECT_EQ(last, ReadStatus::Truncated);
}

TEST_F(RecordingTest, FrameWithABadCrcIsSkippedAndCounted)
{
    writeFrames(4);
    corruptByte(recordOffset(1) + sizeof(RecordPrefix) + sizeof(FrameHeader) + 17); // a pixel of frame 1

    auto reader = RecordingReader::open(path_);
    ASSERT_TRUE(reader.has_value());
    std::vector<std::uint64_t> seqs;
    while (reader->next() == ReadStatus::Frame) {
        seqs.push_back(reader->header().sequence);
    }
    EXPECT_EQ(seqs, (std::vector<std::uint64_t>{10, 12, 13}));
    EXPECT_EQ(reader->corruptFrames(), 1U);
}

TEST_F(RecordingTest, DamagedRecordPrefixIsSkippedByFindingTheNextRecord)
{
    writeFrames(4);
    corruptByte(recordOffset(2)); // the magic of record 2

    const auto scan = scanRecording(path_);
    ASSERT_TRUE(scan.has_value());
    EXPECT_EQ(scan->frames, 3U);
    EXPECT_EQ(scan->corruptFrames, 1U);
    EXPECT_EQ(scan->sequenceGaps, 1U); // sequence 12 is missing
    EXPECT_EQ(scan->lastSequence, 13U);
}

TEST_F(RecordingTest, PeekShowsTheNextHeaderWithoutConsumingIt)
{
    writeFrames(3);
    corruptByte(recordOffset(1)); // record 1's prefix: peek skips to record 2 as next() would
    std::filesystem::resize_file(path_, recordOffset(2) + kRecordBytes - 5);
    auto reader = RecordingReader::open(path_);
    ASSERT_TRUE(reader.has_value());

    ASSERT_EQ(reader->peek(), ReadStatus::Frame);
    EXPECT_EQ(reader->peekedHeader().sequence, 10U);
    EXPECT_EQ(reader->peekedHeader().leftStampNs, 0);
    ASSERT_EQ(reader->next(), ReadStatus::Frame);
    EXPECT_EQ(reader->header().sequence, 10U);
    // Record 1 is damaged, record 2 cut off: nothing complete is left.
    EXPECT_EQ(reader->peek(), ReadStatus::Truncated);
    EXPECT_EQ(reader->corruptFrames(), 1U);
    EXPECT_GT(reader->trailingBytes(), 0U);
    EXPECT_EQ(reader->next(), ReadStatus::End);
}

TEST_F(RecordingTest, CorruptHeadersGiveErrorsNamingTheFileAndWhat)
{
    struct Case {
        const char* what;
        std::uint64_t offset; ///< byte to damage; ~0 = truncate the file to 10 bytes
        const char* expected;
    };
    const Case cases[] = {
        {"magic", 0, "not a ugvsense recording"},
        {"version", offsetof(RecordingFileHeader, version), "version"},
        {"width", offsetof(RecordingFileHeader, width) + 3, "corrupt recording header"},
        {"created stamp (CRC)", offsetof(RecordingFileHeader, createdRealtimeNs), "CRC"},
        {"calibration text (CRC)", kRecordingFileHeaderBytes + 3, "CRC"},
        {"truncated header", ~0ULL, "shorter than a recording header"},
    };
    for (const Case& c : cases) {
        writeFrames(1);
        if (c.offset == ~0ULL) {
            std::filesystem::resize_file(path_, 10);
        } else {
            corruptByte(c.offset);
        }
        const auto reader = RecordingReader::open(path_);
        ASSERT_FALSE(reader.has_value()) << c.what;
        EXPECT_NE(reader.error().message().find(path_), std::string::npos) << reader.error().message();
        EXPECT_NE(reader.error().message().find(c.expected), std::string::npos) << reader.error().message();
        EXPECT_FALSE(reader.error().fix.empty()) << c.what;
        std::filesystem::remove(path_);
    }
}

TEST_F(RecordingTest, MissingFileAndExistingTargetAreErrors)
{
    const auto missing = RecordingReader::open((dir_ / "none.ugvrec").string());
    ASSERT_FALSE(missing.has_value());
    EXPECT_NE(missing.error().message().find("ENOENT"), std::string::npos) << missing.error().message();

    writeFrames(1);
    const auto again = RecordingWriter::create(path_, kWidth, kHeight, kCalibration);
    ASSERT_FALSE(again.has_value());
    EXPECT_NE(again.error().message().find("EEXIST"), std::string::npos) << again.error().message();
    RecordingWriterOptions overwrite;
    overwrite.overwrite = true;
    EXPECT_TRUE(RecordingWriter::create(path_, kWidth, kHeight, kCalibration, overwrite).has_value());
    EXPECT_FALSE(RecordingWriter::create((dir_ / "x.ugvrec").string(), 0, kHeight, kCalibration).has_value());
}

TEST_F(RecordingTest, AnUnknownPixelFormatIsRefusedByNameBeforeAFileIsMade)
{
    RecordingWriterOptions options;
    options.format = static_cast<PixelFormat>(7);
    const std::string path = (dir_ / "unknown.ugvrec").string();
    const auto writer = RecordingWriter::create(path, kWidth, kHeight, kCalibration, options);
    ASSERT_FALSE(writer.has_value());
    EXPECT_NE(writer.error().message().find("unknown pixel format 7"), std::string::npos) << writer.error().message();
    EXPECT_NE(writer.error().message().find("Grey8 or Bgr8"), std::string::npos) << writer.error().message();
    EXPECT_FALSE(std::filesystem::exists(path));
}

/// A disk that fills up while recording: a 256 KiB tmpfs mounted over a folder of the test's own (needs root, or
/// CAP_SYS_ADMIN: skipped with a message otherwise), frames of 64 x 64 (8.3 KiB a record).
TEST_F(RecordingTest, DiskFullKeepsEveryEarlierFrameAndAppendsGoOnOnceThereIsRoom)
{
    const std::filesystem::path mountPoint = dir_ / "small-disk";
    std::filesystem::create_directories(mountPoint);
    if (::mount("tmpfs", mountPoint.c_str(), "tmpfs", 0, "size=256k") != 0) {
        GTEST_SKIP() << "cannot mount a 256 KiB tmpfs on " << mountPoint << " (" << std::strerror(errno)
                     << "): the disk-full test needs root (CAP_SYS_ADMIN)";
    }
    struct Unmount {
        std::string path;
        ~Unmount() { (void)::umount2(path.c_str(), MNT_DETACH); }
    } unmount{mountPoint.string()};

    constexpr int kSide = 64;
    Image<std::uint8_t> left(kSide, kSide);
    Image<std::uint8_t> right(kSide, kSide);
    const std::string path = (mountPoint / "r.ugvrec").string();
    const std::string filler = (mountPoint / "filler").string();
    // Most of the disk taken by another file, so that a record can be cut off half-way.
    {
        std::ofstream f(filler, std::ios::binary);
        const std::vector<char> block(4096, 'x');
        for (int k = 0; k < 48; ++k) {
            f.write(block.data(), static_cast<std::streamsize>(block.size()));
        }
    }
    auto writer = RecordingWriter::create(path, kSide, kSide, kCalibration);
    ASSERT_TRUE(writer.has_value()) << writer.error().message();
    std::uint64_t written = 0;
    Result<void, SysError> appended;
    for (int k = 0; k < 100 && appended; ++k) {
        appended = writer->append(static_cast<std::uint64_t>(k), k, k, greyViews(left.view(), right.view()));
        written += appended ? 1U : 0U;
    }
    ASSERT_FALSE(appended) << "the 256 KiB disk never filled up";
    EXPECT_EQ(appended.error().code, ENOSPC);
    ASSERT_GT(written, 0U);
    EXPECT_EQ(writer->framesWritten(), written);

    // Every frame before the full disk is there, and the file ends cleanly after the last one (no torn record).
    const auto readBack = [&](std::uint64_t& frames) {
        auto reader = RecordingReader::open(path);
        ASSERT_TRUE(reader.has_value()) << reader.error().message();
        ReadStatus status = ReadStatus::Frame;
        while ((status = reader->next()) == ReadStatus::Frame) {
        }
        EXPECT_EQ(status, ReadStatus::End);
        EXPECT_EQ(reader->corruptFrames(), 0U);
        frames = reader->framesRead();
    };
    std::uint64_t frames = 0;
    readBack(frames);
    EXPECT_EQ(frames, written);

    // Room again (the other file removed): recording goes on where it stopped.
    std::filesystem::remove(filler);
    ASSERT_TRUE(writer->append(1000, 0, 0, greyViews(left.view(), right.view())).has_value());
    ASSERT_TRUE(writer->close().has_value());
    readBack(frames);
    EXPECT_EQ(frames, written + 1);
}

TEST_F(RecordingTest, WrongSizeFrameAndWriteAfterCloseAreRefused)
{
    auto writer = RecordingWriter::create(path_, kWidth, kHeight, kCalibration);
    ASSERT_TRUE(writer.has_value());
    Image<std::uint8_t> small(kWidth - 1, kHeight);
    const auto wrong = writer->append(1, 0, 0, greyViews(small.view(), right_.view()));
    ASSERT_FALSE(wrong.has_value());
    EXPECT_EQ(wrong.error().code, EINVAL);
    ASSERT_TRUE(writer->close().has_value());
    const auto closed = writer->append(1, 0, 0, greyViews(left_.view(), right_.view()));
    ASSERT_FALSE(closed.has_value());
    EXPECT_EQ(closed.error().code, EBADF);
}

TEST_F(RecordingTest, StridedViewsAreWrittenPacked)
{
    Image<std::uint8_t> wide(kWidth + 16, kHeight);
    for (int y = 0; y < static_cast<int>(kHeight); ++y) {
        for (int x = 0; x < static_cast<int>(kWidth + 16); ++x) {
            wide.view().at(x, y) = static_cast<std::uint8_t>(x * 3 + y);
        }
    }
    const auto roi = ConstImageViewU8(wide.view()).sub(Rect{4, 0, static_cast<int>(kWidth), static_cast<int>(kHeight)});
    {
        auto writer = RecordingWriter::create(path_, kWidth, kHeight, kCalibration);
        ASSERT_TRUE(writer.has_value());
        ASSERT_TRUE(writer->append(1, 0, 0, greyViews(roi, roi)).has_value());
    }
    auto reader = RecordingReader::open(path_);
    ASSERT_TRUE(reader.has_value());
    ASSERT_EQ(reader->next(), ReadStatus::Frame);
    EXPECT_EQ(reader->views().left.at(0, 1), static_cast<std::uint8_t>(4 * 3 + 1));
    EXPECT_EQ(reader->views().right.at(31, 7), static_cast<std::uint8_t>(35 * 3 + 7));
}

TEST_F(RecordingTest, ReadingAndRewindingAllocateNothingOverHundredsOfFrames)
{
    writeFrames(7);
    auto reader = RecordingReader::open(path_);
    ASSERT_TRUE(reader.has_value());

    int frames = 0;
    const ugv::test::ThreadAllocationScope scope;
    while (frames < 350) {
        const ReadStatus s = reader->next();
        if (s == ReadStatus::End) {
            ASSERT_TRUE(reader->rewind().has_value());
            continue;
        }
        ASSERT_EQ(s, ReadStatus::Frame);
        ++frames;
    }
    EXPECT_EQ(scope.count(), 0U);
    EXPECT_EQ(reader->framesRead(), 350U);
}

} // namespace
} // namespace ugv::hal
