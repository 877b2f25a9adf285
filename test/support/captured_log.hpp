#pragma once

/// @file
/// CapturedLog: the log output (platform/log.hpp) in a memory file while the object lives, for tests that check
/// what was logged (UGV_LOG lines and the RT channels' records written by a LogDrain).
/// Thread-safety: construct and destroy on one thread; writers on any thread (one write(2) per line, O_APPEND).

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <array>
#include <cstddef>
#include <string>

#include "ugv/platform/log.hpp"

namespace ugv::test {

class CapturedLog {
public:
    CapturedLog() : fd_(::memfd_create("ugv-captured-log", 0))
    {
        // O_APPEND: concurrent writers each append whole lines, as on a pipe or the journal's stream.
        ::fcntl(fd_, F_SETFL, O_APPEND);
        previous_ = setLogOutputFd(fd_);
    }
    ~CapturedLog()
    {
        setLogOutputFd(previous_);
        ::close(fd_);
    }
    CapturedLog(const CapturedLog&) = delete;
    CapturedLog& operator=(const CapturedLog&) = delete;
    CapturedLog(CapturedLog&&) = delete;
    CapturedLog& operator=(CapturedLog&&) = delete;

    /// Everything written since construction.
    [[nodiscard]] std::string text() const
    {
        std::string out;
        std::array<char, 4096> buffer{};
        ssize_t got = 0;
        off_t offset = 0;
        while ((got = ::pread(fd_, buffer.data(), buffer.size(), offset)) > 0) {
            out.append(buffer.data(), static_cast<std::size_t>(got));
            offset += got;
        }
        return out;
    }

private:
    int fd_;
    int previous_ = 2;
};

} // namespace ugv::test
