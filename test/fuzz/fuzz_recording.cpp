// Fuzz target: a recording file (`ugvsense record`, the replay camera): its header, the calibration text inside
// it (parsed as the service does at start) and every record, read to the end, peeked and rewound once.
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "ugv/adapters/calibration_file.hpp"
#include "ugv/hal/recording.hpp"

namespace {

void readAll(ugv::hal::RecordingReader& reader)
{
    constexpr int kMaxRecords = 10000;
    for (int k = 0; k < kMaxRecords && reader.peek() == ugv::hal::ReadStatus::Frame; ++k) {
        if (reader.next() != ugv::hal::ReadStatus::Frame) {
            break;
        }
        (void)reader.views();
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const int fd = ::memfd_create("fuzz-recording", MFD_CLOEXEC);
    if (fd < 0) {
        return 0;
    }
    std::size_t done = 0;
    while (done < size) {
        const ssize_t n = ::write(fd, data + done, size - done);
        if (n <= 0) {
            break;
        }
        done += static_cast<std::size_t>(n);
    }
    auto reader = ugv::hal::RecordingReader::open("/proc/self/fd/" + std::to_string(fd));
    if (reader) {
        (void)ugv::adapters::parseCalibration(reader->info().calibrationText, "fuzz.ugvrec");
        readAll(*reader);
        if (reader->rewind()) {
            readAll(*reader);
        }
    }
    ::close(fd);
    return 0;
}
