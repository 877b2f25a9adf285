#pragma once

/// @file
/// Logging, in two halves.
///
/// Non-RT: `UGV_LOG(Vision, Warn) << "text " << value;` formats one line `[vision] warn: text 42` and writes it
/// with a single write(2) to the log output (stderr unless setLogOutputFd() chose another fd), so lines from
/// different threads never interleave. Per-category thresholds come from `UGV_LOG_LEVELS`
/// (`hal:debug,vision:info`, `*:warn`; later items win), read on first use; default Info. Bad items are reported
/// once on the log output and ignored. The stream operands are not evaluated when the level is filtered out.
///
/// RT: an RT thread owns one `RtLogChannel` (created at init) and calls `log(level, category, format, a0..a3)`,
/// which stores a fixed-size record (timestamp, literal format, four int64 arguments) in an SPSC ring: no
/// formatting, no allocation, no system call. A `LogDrain` on a low-priority thread formats and writes them.
/// Formats use `%lld` for an argument (up to four) and `%%` for a percent sign; nothing else is special.
///
/// Journal: under systemd, stderr is a stream to the journal and `$JOURNAL_STREAM` names its device and inode.
/// When the log output is that stream, every line starts with its syslog priority (`<7>` debug, `<6>` info,
/// `<4>` warn, `<3>` error, `<2>` fatal), which journald strips and stores as the entry's priority
/// (`journalctl -p warning -u ugvsensed`). Elsewhere lines are unchanged.
///
/// Fatal is a level like the others: logging it does not end the process (the caller does, with its action).

#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/platform/spsc_ring.hpp"

namespace ugv {

enum class LogCategory : std::uint8_t { Platform, Hal, Rt, Vision, Ipc, Bringup, Tool };
enum class LogLevel : std::uint8_t { Debug, Info, Warn, Error, Fatal };

inline constexpr std::size_t kLogCategoryCount = 7;
inline constexpr LogLevel kDefaultLogLevel = LogLevel::Info;
using LogThresholds = std::array<LogLevel, kLogCategoryCount>;

/// "vision", "warn", ... Thread-safety: reentrant. RT-safe: yes.
[[nodiscard]] const char* toString(LogCategory category) noexcept;
[[nodiscard]] const char* toString(LogLevel level) noexcept;

/// Outcome of parsing a `UGV_LOG_LEVELS` value: the thresholds (default Info where not named) and one message
/// per bad item (the bad items are ignored, the good ones still apply).
struct LogLevelsParse {
    LogThresholds thresholds{};
    std::vector<std::string> errors;
};

/// @brief Parse `cat:level[,cat:level...]`; `*` is every category. Empty items are ignored.
/// Thread-safety: reentrant. RT-safe: no (allocates).
[[nodiscard]] LogLevelsParse parseLogLevels(std::string_view spec);

/// @brief Read `UGV_LOG_LEVELS` once (later calls do nothing) and report its errors on the log output.
/// Called by the first UGV_LOG and by RtLogChannel's constructor; call it at init to fix the moment.
/// Thread-safety: thread-safe. RT-safe: no.
void initLogLevelsFromEnv();

/// @brief Replace all thresholds (tests, or bringup after reading its config). Reads the env first if that has
/// not happened yet, so a later first use cannot override these.
/// Thread-safety: thread-safe (each threshold is atomic). RT-safe: no (may read the env).
void setLogThresholds(const LogThresholds& thresholds);

/// @brief The current threshold of `category`, without reading the env.
/// Thread-safety: thread-safe. RT-safe: yes.
[[nodiscard]] LogLevel logThreshold(LogCategory category) noexcept;

/// @brief Whether a message of `level` in `category` is written (reads the env on the first call).
/// Thread-safety: thread-safe. RT-safe: no on the first call, yes after initLogLevelsFromEnv().
[[nodiscard]] bool logEnabled(LogCategory category, LogLevel level);

/// @brief Send log lines to `fd` instead of stderr (2); returns the previous fd. The caller keeps `fd` open.
/// Thread-safety: thread-safe. RT-safe: yes.
int setLogOutputFd(int fd) noexcept;

/// @brief Whether lines carry syslog priority prefixes for the journal (see the file comment). Decided with the
/// env on first use, from $JOURNAL_STREAM and the log output; setJournalPrefixes() overrides it (tests).
/// Thread-safety: thread-safe. RT-safe: no on the first call, yes after initLogLevelsFromEnv().
[[nodiscard]] bool journalPrefixes();
void setJournalPrefixes(bool on);

/// @brief "<4>" for Warn when journalPrefixes(), else "". Thread-safety: thread-safe. RT-safe: as journalPrefixes().
[[nodiscard]] const char* journalPrefix(LogLevel level);

/// @brief True when `fd` is the stream that `journalStream` (the value of $JOURNAL_STREAM, "DEV:INODE") names.
/// Thread-safety: reentrant. RT-safe: no (fstat).
[[nodiscard]] bool isJournalStream(int fd, const char* journalStream) noexcept;

/// @brief Write `line` (which ends in '\n') with one write(2) to the log output, retrying EINTR/short writes.
/// Thread-safety: thread-safe. RT-safe: no (system call).
void writeLogLine(std::string_view line) noexcept;

/// One UGV_LOG statement: collects the stream and writes the line in its destructor. Use through UGV_LOG.
/// Thread-safety: thread-bound (a temporary). RT-safe: no.
class LogLine {
public:
    LogLine(LogCategory category, LogLevel level);
    ~LogLine();
    LogLine(const LogLine&) = delete;
    LogLine& operator=(const LogLine&) = delete;
    LogLine(LogLine&&) = delete;
    LogLine& operator=(LogLine&&) = delete;

    [[nodiscard]] std::ostream& stream() noexcept { return stream_; }

private:
    std::ostringstream stream_;
};

/// Format an RT record's `format` with its arguments (`%lld` -> next argument, `%%` -> '%'; a fifth `%lld`
/// prints `<missing>`). Thread-safety: reentrant. RT-safe: no (allocates).
[[nodiscard]] std::string formatRtMessage(const char* format, const std::array<std::int64_t, 4>& args);

/// A fixed-size RT log record. `format` must be a string literal (it is read later, by the drain).
struct RtLogRecord {
    std::int64_t timestampNs = 0; ///< MonotonicClock [ns]
    const char* format = nullptr;
    std::array<std::int64_t, 4> args{};
    LogCategory category = LogCategory::Platform;
    LogLevel level = LogLevel::Info;
};

inline constexpr std::size_t kRtLogChannelCapacity = 256; ///< records per channel (power of two)

/// The log of one RT thread: a preallocated SPSC ring of RtLogRecord plus a drop counter.
/// Thread-safety: log() from exactly one producer thread; tryPop() from exactly one consumer (the drain);
/// dropped() from any thread. RT-safe: log() yes; the constructor reads the env (init time).
class RtLogChannel {
public:
    /// @param[in] name string literal naming the producer thread, used in drop reports.
    explicit RtLogChannel(const char* name);

    /// @brief Record a message; filtered by the category threshold; counts a drop when the ring is full.
    /// Thread-safety: the one producer thread. RT-safe: yes (no formatting, allocation or system call).
    void log(LogLevel level, LogCategory category, const char* format, std::int64_t a0 = 0, std::int64_t a1 = 0,
             std::int64_t a2 = 0, std::int64_t a3 = 0) noexcept;

    /// @brief Take the oldest record. Thread-safety: the one consumer thread. RT-safe: yes.
    [[nodiscard]] bool tryPop(RtLogRecord& out) noexcept { return ring_.tryPop(out); }

    /// @brief Records lost because the ring was full, since construction.
    [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }
    [[nodiscard]] const char* name() const noexcept { return name_; }

private:
    const char* name_;
    std::atomic<std::uint64_t> dropped_{0};
    SpscRing<RtLogRecord, kRtLogChannelCapacity> ring_;
};

inline constexpr std::size_t kMaxRtLogChannels = 16;

/// Formats and writes the records of registered channels. Channels are registered at init; the drain is the
/// single consumer of each. Either call drainOnce() yourself or start() its thread, not both. The thread survives
/// a throw out of a drain (bad_alloc while a line is formatted): the record being written is lost, the failure is
/// counted (failures()) and reported on the log output by a fixed line, and the next period drains on.
/// Thread-safety: thread-compatible (one owner thread), except the drain thread it runs. RT-safe: no.
class LogDrain {
public:
    LogDrain() = default;
    ~LogDrain(); ///< stops the thread (draining what is left)
    LogDrain(const LogDrain&) = delete;
    LogDrain& operator=(const LogDrain&) = delete;
    LogDrain(LogDrain&&) = delete;
    LogDrain& operator=(LogDrain&&) = delete;

    /// @brief Register `channel` (which must outlive the drain).
    /// @return an error when kMaxRtLogChannels are registered or the drain thread runs.
    [[nodiscard]] Result<void, Error> addChannel(RtLogChannel& channel);

    /// @brief Write all pending records, one line each, channel by channel (order kept within a channel), then
    /// one warning per channel whose drop count grew since the last report.
    /// @return the number of records written.
    std::size_t drainOnce();

    /// @brief Start a SCHED_OTHER thread calling drainOnce() every `period`.
    /// @return an error when already running or the thread cannot be created.
    [[nodiscard]] Result<void, Error> start(std::chrono::milliseconds period = std::chrono::milliseconds(5));

    /// @brief Stop and join the thread, then drain the rest. Does nothing when not running.
    void stop();

    [[nodiscard]] bool running() const noexcept { return thread_.joinable(); }
    /// Drains of the thread that ended in an exception (the thread went on).
    [[nodiscard]] std::uint64_t failures() const noexcept { return failures_.load(std::memory_order_relaxed); }

    /// Where lines go: writeLogLine by default. A seam for tests (a writer that throws); set before start().
    using LineWriter = void (*)(std::string_view line);
    void setWriterForTest(LineWriter writer) noexcept { writer_ = writer; }

private:
    void run(std::chrono::milliseconds period);

    std::array<RtLogChannel*, kMaxRtLogChannels> channels_{};
    std::array<std::uint64_t, kMaxRtLogChannels> reportedDrops_{};
    std::size_t channelCount_ = 0;
    std::atomic<bool> stopRequested_{false};
    std::atomic<std::uint64_t> failures_{0};
    LineWriter writer_ = nullptr; ///< nullptr: writeLogLine
    std::thread thread_;
};

} // namespace ugv

/// `UGV_LOG(Vision, Warn) << ...;` — the operands are evaluated only when the level passes the threshold.
/// The empty if-branch keeps an outer `if/else` around the macro binding as written.
#define UGV_LOG(category, level)                                                                                       \
    if (!::ugv::logEnabled(::ugv::LogCategory::category, ::ugv::LogLevel::level)) {                                    \
    } else                                                                                                             \
        ::ugv::LogLine(::ugv::LogCategory::category, ::ugv::LogLevel::level).stream()
