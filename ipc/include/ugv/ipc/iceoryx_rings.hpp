#pragma once

/// @file
/// The service's shared-memory rings over iceoryx 2.0 (RouDi + posh), with no iceoryx type in this header.
///
/// Topics (iceoryx service / instance / event):
///  - `ugvsense/stereo/frames`: one chunk per stereo pair = FrameHeader + left rows + right rows (packed), as in
///    platform/frame_header.hpp. The capture task loans a chunk, copies the pair in and publishes it; the vision
///    task holds a queue of one (latest frame wins: an older pair is discarded, never queued); any other process
///    (the recorder, a viewer) subscribes with its own queue and reads the same chunks without copying.
///  - `ugvsense/obstacles/sectors`: one SectorsMessage (sectors_message.hpp) per frame for local consumers.
///
/// Publishers never block: a subscriber that is too slow loses its oldest chunks (ConsumerTooSlowPolicy::
/// DISCARD_OLDEST_DATA). A loan fails (counted) when the memory pool is exhausted, e.g. by a subscriber that holds
/// chunks; the chunk sizes and counts are RouDi's config (bringup/deploy/roudi.toml).
///
/// RouDi: startRuntime() first checks that a RouDi answers on its socket and fails with a clear error otherwise
/// (iceoryx itself would wait, then abort the process). EmbeddedRouDi runs RouDi inside this process (tests, and
/// `ugvsensed --embedded-roudi` on a machine without the iox-roudi service); other processes can still connect.
/// After a RouDi restart the shared memory of a running service is stale: iceoryx 2.0 cannot re-register, so the
/// service exits with an error and systemd restarts it (see bringup/README.md).
///
/// Thread-safety: each object is thread-bound (one publisher or subscriber per thread). RT-safe: loan/publish,
/// wait/take/release and the sectors publish/take allocate nothing after create() (iceoryx's lock-free mempools
/// and queues; the wait is a semaphore, not a lock); create() and the runtime start are not.

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "ugv/ipc/sectors_message.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/frame_header.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::ipc {

/// The default topics.
struct Topic {
    const char* service;
    const char* instance;
    const char* event;
};
inline constexpr Topic kFramesTopic{"ugvsense", "stereo", "frames"};
inline constexpr Topic kSectorsTopic{"ugvsense", "obstacles", "sectors"};

/// True when a RouDi listens on its IPC socket (/tmp/roudi).
[[nodiscard]] bool roudiReachable() noexcept;

/// Registers this process with RouDi under `appName` (once per process). Fails with a clear error, without
/// waiting, when no RouDi runs.
Result<void, Error> startRuntime(const std::string& appName);

/// RouDi inside this process, with memory pools for `maxFrameBytes` frames (16 chunks) and small messages, and
/// this process registered as `appName` (PoshRuntimeSingleProcess). One per process; fails when another RouDi
/// already runs on this machine.
class EmbeddedRouDi {
public:
    static Result<std::unique_ptr<EmbeddedRouDi>, Error> start(const std::string& appName, std::size_t maxFrameBytes);
    ~EmbeddedRouDi();
    EmbeddedRouDi(const EmbeddedRouDi&) = delete;
    EmbeddedRouDi& operator=(const EmbeddedRouDi&) = delete;
    EmbeddedRouDi(EmbeddedRouDi&&) = delete;
    EmbeddedRouDi& operator=(EmbeddedRouDi&&) = delete;

private:
    struct Impl;
    explicit EmbeddedRouDi(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

class FramePublisher {
public:
    /// A publisher of `format` frames of width x height per image.
    static Result<std::unique_ptr<FramePublisher>, Error> create(PixelFormat format, int width, int height,
                                                                 Topic topic = kFramesTopic);
    ~FramePublisher();
    FramePublisher(const FramePublisher&) = delete;
    FramePublisher& operator=(const FramePublisher&) = delete;
    FramePublisher(FramePublisher&&) = delete;
    FramePublisher& operator=(FramePublisher&&) = delete;

    /// Loans a chunk, writes the header and copies both images in (packed), publishes it. An empty right image is a
    /// left-only frame (kFrameLeftOnly: one camera, or the pair's right camera lost). False (counted in
    /// loanFailures) when no chunk is free, or when the images are not width x height in the publisher's format.
    /// `publishStampNs`, when given, receives CLOCK_MONOTONIC right before the chunk is handed to iceoryx (the start
    /// of the hand-over).
    bool publish(std::uint64_t sequence, std::int64_t leftStampNs, std::int64_t rightStampNs, const StereoViews& images,
                 std::atomic<std::int64_t>* publishStampNs = nullptr) noexcept;
    [[nodiscard]] std::uint64_t published() const noexcept { return published_; }
    [[nodiscard]] std::uint64_t loanFailures() const noexcept { return loanFailures_; }
    /// True when at least one subscriber is connected.
    [[nodiscard]] bool hasSubscribers() const noexcept;

private:
    struct Impl;
    FramePublisher(std::unique_ptr<Impl> impl, PixelFormat format, int width, int height);
    std::unique_ptr<Impl> impl_;
    PixelFormat format_;
    int width_;
    int height_;
    std::uint64_t published_ = 0;
    std::uint64_t loanFailures_ = 0;
};

/// A frame taken from the ring: valid until release().
struct TakenFrame {
    const std::byte* chunk = nullptr; ///< FrameHeader + payload
    std::size_t bytes = 0;
    FrameHeader header{};
    StereoViews views{};
};

enum class TakeStatus : std::uint8_t { Frame, Timeout, Malformed };

class FrameSubscriber {
public:
    /// @param queueCapacity 1 for the vision task (latest frame wins); a recorder may ask for more (<= 16).
    static Result<std::unique_ptr<FrameSubscriber>, Error> create(int queueCapacity, Topic topic = kFramesTopic);
    ~FrameSubscriber();
    FrameSubscriber(const FrameSubscriber&) = delete;
    FrameSubscriber& operator=(const FrameSubscriber&) = delete;
    FrameSubscriber(FrameSubscriber&&) = delete;
    FrameSubscriber& operator=(FrameSubscriber&&) = delete;

    /// Waits up to `timeout` for a frame and takes the newest one queued. A malformed chunk (the header does
    /// not validate against its size) is released and reported as Malformed (counted).
    TakeStatus take(TakenFrame& out, std::chrono::nanoseconds timeout) noexcept;
    /// As take(), but the oldest queued frame (a recorder keeps every pair its queue holds).
    TakeStatus takeOldest(TakenFrame& out, std::chrono::nanoseconds timeout) noexcept;
    /// True when a frame is queued (no wait, no system call: a poll of the shared-memory queue).
    [[nodiscard]] bool hasData() const noexcept;
    /// Ends the current (or the next) wait of take()/takeOldest() at once: it returns Timeout unless a frame is
    /// queued. From any thread; the owner calls it when it stops, so that stopping never depends on iceoryx's
    /// timed wait, which runs on CLOCK_REALTIME (a clock step back while waiting would stretch it).
    void wake() noexcept;
    /// Gives the chunk back to the pool.
    void release(TakenFrame& frame) noexcept;
    [[nodiscard]] std::uint64_t malformed() const noexcept { return malformed_; }

private:
    struct Impl;
    explicit FrameSubscriber(std::unique_ptr<Impl> impl);
    TakeStatus takeFrame(TakenFrame& out, std::chrono::nanoseconds timeout, bool newest) noexcept;
    std::unique_ptr<Impl> impl_;
    std::uint64_t malformed_ = 0;
};

class SectorsPublisher {
public:
    static Result<std::unique_ptr<SectorsPublisher>, Error> create(Topic topic = kSectorsTopic);
    ~SectorsPublisher();
    SectorsPublisher(const SectorsPublisher&) = delete;
    SectorsPublisher& operator=(const SectorsPublisher&) = delete;
    SectorsPublisher(SectorsPublisher&&) = delete;
    SectorsPublisher& operator=(SectorsPublisher&&) = delete;

    /// Copies `message` into a loaned chunk and publishes it; false (counted) when no chunk is free.
    bool publish(const SectorsMessage& message) noexcept;
    [[nodiscard]] std::uint64_t loanFailures() const noexcept { return loanFailures_; }

private:
    struct Impl;
    explicit SectorsPublisher(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
    std::uint64_t loanFailures_ = 0;
};

class SectorsSubscriber {
public:
    static Result<std::unique_ptr<SectorsSubscriber>, Error> create(int queueCapacity, Topic topic = kSectorsTopic);
    ~SectorsSubscriber();
    SectorsSubscriber(const SectorsSubscriber&) = delete;
    SectorsSubscriber& operator=(const SectorsSubscriber&) = delete;
    SectorsSubscriber(SectorsSubscriber&&) = delete;
    SectorsSubscriber& operator=(SectorsSubscriber&&) = delete;

    /// Waits up to `timeout` for the next message, copies it to `out` and validates it (validate()). Timeout,
    /// Malformed (counted, `out` untouched) or Frame (a valid message).
    TakeStatus take(SectorsMessage& out, std::chrono::nanoseconds timeout) noexcept;
    [[nodiscard]] std::uint64_t malformed() const noexcept { return malformed_; }

private:
    struct Impl;
    explicit SectorsSubscriber(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
    std::uint64_t malformed_ = 0;
};

} // namespace ugv::ipc
