#pragma once

/// @file
/// The one place errno is read. Device backends (V4L2 ioctl/poll/mmap, file I/O of recordings) call the
/// OS through `sysCall`, which retries EINTR and turns a failure into a `SysError` holding errno, so that
/// errno never leaks out of hal/.
///
/// Thread-safety: reentrant. RT-safe: yes (no allocation; the call itself may block, which is the caller's
/// decision: only the frame wait may block on the frame path).

#include <cerrno>
#include <cstdint>
#include <utility>

#include <unistd.h>

#include "ugv/platform/result.hpp"

namespace ugv::hal {

/// errno of a failed system call.
struct SysError {
    int code = 0;
    /// strerror text, e.g. "No such device" (static storage, never allocates).
    [[nodiscard]] const char* text() const noexcept;
    /// The errno symbol, e.g. "ENODEV", or "errno" for codes we do not name.
    [[nodiscard]] const char* name() const noexcept;
    friend bool operator==(const SysError&, const SysError&) = default;
};

/// Calls `f(args...)`; retries while it fails with EINTR. Success is any return value other than
/// `failure` (-1 for most calls); the error carries errno. `maxRetries` bounds the retry loop.
template <class F, class... Args>
auto sysCall(F&& f, Args&&... args) noexcept -> Result<decltype(f(std::forward<Args>(args)...)), SysError>
{
    constexpr int kMaxEintrRetries = 100;
    for (int attempt = 0;; ++attempt) {
        const auto value = f(args...);
        if (value != -1) {
            return value;
        }
        const int code = errno;
        if (code != EINTR || attempt >= kMaxEintrRetries) {
            return Unexpected(SysError{code});
        }
    }
}

/// An owned file descriptor: closed when destroyed or assigned over, moved (the source left empty), not copied.
/// Close errors are not reported: a file whose data must be on disk is synced and closed by its owner first
/// (RecordingWriter::close).
class UniqueFd {
public:
    UniqueFd() noexcept = default;
    explicit UniqueFd(int fd) noexcept : fd_(fd) {}
    UniqueFd(UniqueFd&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
    UniqueFd& operator=(UniqueFd&& other) noexcept
    {
        if (this != &other) {
            reset();
            fd_ = std::exchange(other.fd_, -1);
        }
        return *this;
    }
    UniqueFd(const UniqueFd&) = delete;
    UniqueFd& operator=(const UniqueFd&) = delete;
    ~UniqueFd() { reset(); }

    [[nodiscard]] int get() const noexcept { return fd_; }
    [[nodiscard]] bool valid() const noexcept { return fd_ >= 0; }
    /// Gives the descriptor up without closing it.
    [[nodiscard]] int release() noexcept { return std::exchange(fd_, -1); }
    /// Closes the descriptor, if any.
    void reset() noexcept
    {
        if (fd_ >= 0) {
            ::close(std::exchange(fd_, -1)); // never retried: the descriptor is gone either way
        }
    }

private:
    int fd_ = -1;
};

} // namespace ugv::hal
