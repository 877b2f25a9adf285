#include "ugv/platform/log.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <system_error>

#include "ugv/platform/clock.hpp"

namespace ugv {
namespace {

constexpr std::array<const char*, kLogCategoryCount> kCategoryNames{"platform", "hal",     "rt",  "vision",
                                                                    "ipc",      "bringup", "tool"};
constexpr std::array<const char*, 5> kLevelNames{"debug", "info", "warn", "error", "fatal"};
constexpr const char* kEnvName = "UGV_LOG_LEVELS";
constexpr int kStderrFd = 2;

// NOLINTBEGIN(cppcoreguidelines-avoid-non-const-global-variables): the logger's process-wide state, atomics any thread
// reads
std::array<std::atomic<LogLevel>, kLogCategoryCount> gThresholds{kDefaultLogLevel, kDefaultLogLevel, kDefaultLogLevel,
                                                                 kDefaultLogLevel, kDefaultLogLevel, kDefaultLogLevel,
                                                                 kDefaultLogLevel};
std::atomic<bool> gEnvRead{false};
std::once_flag gEnvOnce;
std::atomic<int> gOutputFd{kStderrFd};
std::atomic<bool> gJournal{false};
// NOLINTEND(cppcoreguidelines-avoid-non-const-global-variables)
constexpr std::array<const char*, 5> kJournalPrefixes{"<7>", "<6>", "<4>", "<3>", "<2>"}; // syslog priorities

std::string_view trim(std::string_view text)
{
    const auto first = text.find_first_not_of(" \t");
    if (first == std::string_view::npos) {
        return {};
    }
    const auto last = text.find_last_not_of(" \t");
    return text.substr(first, last - first + 1);
}

void readEnvOnce()
{
    const char* spec = std::getenv(kEnvName);
    gJournal.store(isJournalStream(gOutputFd.load(), std::getenv("JOURNAL_STREAM")), std::memory_order_relaxed);
    if (spec != nullptr) {
        const LogLevelsParse parsed = parseLogLevels(spec);
        for (std::size_t i = 0; i < kLogCategoryCount; ++i) {
            gThresholds[i].store(parsed.thresholds[i], std::memory_order_relaxed);
        }
        for (const std::string& error : parsed.errors) {
            // journalPrefix() would wait for this call_once: the prefix straight from gJournal.
            const char* prefix = gJournal.load(std::memory_order_relaxed)
                                     ? kJournalPrefixes[static_cast<std::size_t>(LogLevel::Warn)]
                                     : "";
            writeLogLine(prefix + std::string("[platform] warn: ") + error + " (item ignored)\n");
        }
    }
    gEnvRead.store(true, std::memory_order_release);
}

} // namespace

const char* toString(LogCategory category) noexcept
{
    return kCategoryNames[static_cast<std::size_t>(category)];
}
const char* toString(LogLevel level) noexcept
{
    return kLevelNames[static_cast<std::size_t>(level)];
}

LogLevelsParse parseLogLevels(std::string_view spec)
{
    LogLevelsParse result;
    result.thresholds.fill(kDefaultLogLevel);
    while (!spec.empty()) {
        const auto comma = spec.find(',');
        const std::string_view item = trim(spec.substr(0, comma));
        spec = comma == std::string_view::npos ? std::string_view{} : spec.substr(comma + 1);
        if (item.empty()) {
            continue;
        }
        const std::string quoted = std::string(kEnvName) + " item '" + std::string(item) + "'";
        const auto colon = item.find(':');
        if (colon == std::string_view::npos) {
            result.errors.push_back(quoted + " has no ':'; expected category:level, e.g. vision:debug");
            continue;
        }
        const std::string_view category = trim(item.substr(0, colon));
        const std::string_view levelName = trim(item.substr(colon + 1));

        std::size_t level = kLevelNames.size();
        for (std::size_t i = 0; i < kLevelNames.size(); ++i) {
            if (levelName == kLevelNames[i]) {
                level = i;
            }
        }
        if (level == kLevelNames.size()) {
            result.errors.push_back(quoted + ": unknown level '" + std::string(levelName) +
                                    "'; known: debug, info, warn, error, fatal");
            continue;
        }
        bool known = category == "*";
        for (std::size_t i = 0; i < kLogCategoryCount; ++i) {
            if (category == "*" || category == kCategoryNames[i]) {
                result.thresholds[i] = static_cast<LogLevel>(level);
                known = true;
            }
        }
        if (!known) {
            result.errors.push_back(quoted + ": unknown category '" + std::string(category) +
                                    "'; known: platform, hal, rt, vision, ipc, bringup, tool, *");
        }
    }
    return result;
}

void initLogLevelsFromEnv()
{
    std::call_once(gEnvOnce, readEnvOnce);
}

void setLogThresholds(const LogThresholds& thresholds)
{
    initLogLevelsFromEnv();
    for (std::size_t i = 0; i < kLogCategoryCount; ++i) {
        gThresholds[i].store(thresholds[i], std::memory_order_relaxed);
    }
}

LogLevel logThreshold(LogCategory category) noexcept
{
    return gThresholds[static_cast<std::size_t>(category)].load(std::memory_order_relaxed);
}

bool logEnabled(LogCategory category, LogLevel level)
{
    if (!gEnvRead.load(std::memory_order_acquire)) {
        initLogLevelsFromEnv();
    }
    return level >= logThreshold(category);
}

bool isJournalStream(int fd, const char* journalStream) noexcept
{
    if (journalStream == nullptr) {
        return false;
    }
    // JOURNAL_STREAM is "<device>:<inode>" in decimal (systemd.exec(5)).
    const std::string_view text(journalStream);
    const char* const end = text.data() + text.size();
    std::uintmax_t device = 0;
    std::uintmax_t inode = 0;
    const auto [afterDevice, deviceError] = std::from_chars(text.data(), end, device);
    if (deviceError != std::errc{} || afterDevice == end || *afterDevice != ':') {
        return false;
    }
    const auto [afterInode, inodeError] = std::from_chars(afterDevice + 1, end, inode);
    struct stat st {};
    if (inodeError != std::errc{} || afterInode != end || ::fstat(fd, &st) != 0) {
        return false;
    }
    return static_cast<std::uintmax_t>(st.st_dev) == device && static_cast<std::uintmax_t>(st.st_ino) == inode;
}

bool journalPrefixes()
{
    if (!gEnvRead.load(std::memory_order_acquire)) {
        initLogLevelsFromEnv();
    }
    return gJournal.load(std::memory_order_relaxed);
}

void setJournalPrefixes(bool on)
{
    initLogLevelsFromEnv();
    gJournal.store(on, std::memory_order_relaxed);
}

const char* journalPrefix(LogLevel level)
{
    return journalPrefixes() ? kJournalPrefixes[static_cast<std::size_t>(level)] : "";
}

int setLogOutputFd(int fd) noexcept
{
    return gOutputFd.exchange(fd);
}

void writeLogLine(std::string_view line) noexcept
{
    const int fd = gOutputFd.load();
    while (!line.empty()) {
        const ssize_t written = ::write(fd, line.data(), line.size());
        if (written < 0 && errno == EINTR) {
            continue;
        }
        if (written <= 0) {
            return; // nowhere left to report a failing log output
        }
        line.remove_prefix(static_cast<std::size_t>(written));
    }
}

LogLine::LogLine(LogCategory category, LogLevel level)
{
    stream_ << journalPrefix(level) << '[' << toString(category) << "] " << toString(level) << ": ";
}

LogLine::~LogLine()
{
    stream_ << '\n';
    writeLogLine(stream_.view());
}

std::string formatRtMessage(const char* format, const std::array<std::int64_t, 4>& args)
{
    constexpr std::string_view kPlaceholder = "%lld";
    std::string out;
    std::size_t next = 0;
    std::string_view rest = format == nullptr ? std::string_view("<null format>") : std::string_view(format);
    while (!rest.empty()) {
        if (rest.starts_with(kPlaceholder)) {
            out += next < args.size() ? std::to_string(args[next]) : std::string("<missing>");
            ++next;
            rest.remove_prefix(kPlaceholder.size());
        } else if (rest.starts_with("%%")) {
            out += '%';
            rest.remove_prefix(2);
        } else {
            out += rest.front();
            rest.remove_prefix(1);
        }
    }
    return out;
}

RtLogChannel::RtLogChannel(const char* name) : name_(name)
{
    initLogLevelsFromEnv();
}

void RtLogChannel::log(LogLevel level, LogCategory category, const char* format, std::int64_t a0, std::int64_t a1,
                       std::int64_t a2, std::int64_t a3) noexcept
{
    if (level < logThreshold(category)) {
        return;
    }
    const RtLogRecord record{MonotonicClock::nowNs(), format, {a0, a1, a2, a3}, category, level};
    if (!ring_.tryPush(record)) {
        dropped_.fetch_add(1, std::memory_order_relaxed);
    }
}

LogDrain::~LogDrain()
{
    stop();
}

Result<void, Error> LogDrain::addChannel(RtLogChannel& channel)
{
    if (running()) {
        return Unexpected(Error{"LogDrain",
                                std::string("cannot add channel '") + channel.name() + "' while the drain thread runs",
                                "register all channels at init, before start()"});
    }
    if (channelCount_ == kMaxRtLogChannels) {
        return Unexpected(Error{"LogDrain",
                                std::string("cannot add channel '") + channel.name() + "': all " +
                                    std::to_string(kMaxRtLogChannels) + " channel slots are in use",
                                "raise kMaxRtLogChannels in platform/log.hpp"});
    }
    channels_[channelCount_++] = &channel;
    return {};
}

std::size_t LogDrain::drainOnce()
{
    constexpr std::int64_t kNsPerSecond = 1'000'000'000;
    constexpr int kFractionDigits = 9;
    std::size_t written = 0;
    const auto write = [this](const std::string& line) { writer_ != nullptr ? writer_(line) : writeLogLine(line); };
    for (std::size_t i = 0; i < channelCount_; ++i) {
        RtLogChannel& channel = *channels_[i];
        RtLogRecord record;
        while (channel.tryPop(record)) {
            std::string fraction = std::to_string(record.timestampNs % kNsPerSecond);
            fraction.insert(0, static_cast<std::size_t>(kFractionDigits) - fraction.size(), '0');
            write(std::string(journalPrefix(record.level)) + "[" + toString(record.category) + "] " +
                  toString(record.level) + ": " + formatRtMessage(record.format, record.args) +
                  " [t=" + std::to_string(record.timestampNs / kNsPerSecond) + "." + fraction + "]\n");
            ++written;
        }
        const std::uint64_t dropped = channel.dropped();
        if (dropped != reportedDrops_[i]) {
            write(std::string(journalPrefix(LogLevel::Warn)) + "[platform] warn: RT log channel '" + channel.name() +
                  "' dropped " + std::to_string(dropped - reportedDrops_[i]) + " record(s) (total " +
                  std::to_string(dropped) + "); its ring holds " + std::to_string(kRtLogChannelCapacity) +
                  ": log less often or drain more often\n");
            reportedDrops_[i] = dropped;
        }
    }
    return written;
}

Result<void, Error> LogDrain::start(std::chrono::milliseconds period)
{
    if (running()) {
        return Unexpected(Error{"LogDrain", "start() called while the drain thread runs", "call stop() first"});
    }
    stopRequested_.store(false);
    try {
        thread_ = std::thread([this, period] { run(period); });
    } catch (const std::system_error& e) { // the only place std::thread reports failure
        return Unexpected(Error{"LogDrain", std::string("cannot create the drain thread: ") + e.what(),
                                "check the thread limits (ulimit -u, systemd TasksMax=)"});
    }
    return {};
}

void LogDrain::stop()
{
    if (!running()) {
        return;
    }
    stopRequested_.store(true);
    thread_.join();
    drainOnce();
}

void LogDrain::run(std::chrono::milliseconds period)
{
    // A thread inherits its creator's policy; the drain must never compete with RT tasks.
    const sched_param normal{};
    static_cast<void>(::pthread_setschedparam(::pthread_self(), SCHED_OTHER, &normal)); // lowering cannot be refused
    while (!stopRequested_.load()) {
        try {
            drainOnce();
        } catch (const std::exception&) {
            // Formatting allocates; a failure here must not end the service (the thread would call terminate).
            // A fixed line, written without allocating, says so; the record being written is lost.
            failures_.fetch_add(1, std::memory_order_relaxed);
            writeLogLine("[platform] error: the log drain failed to format or write a record (lost); it goes on\n");
        }
        std::this_thread::sleep_for(period);
    }
}

} // namespace ugv
