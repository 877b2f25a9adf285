#include "ugv/platform/log.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "captured_log.hpp"

namespace {

using ugv::LogCategory;
using ugv::LogLevel;

using ugv::test::CapturedLog;

std::vector<std::string> lines(const std::string& text)
{
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
        out.push_back(line);
    }
    return out;
}

ugv::LogThresholds allAt(LogLevel level)
{
    ugv::LogThresholds thresholds{};
    thresholds.fill(level);
    return thresholds;
}

// ---- names and UGV_LOG_LEVELS parsing ----

TEST(LogNames, EveryCategoryAndLevelHasItsLowercaseName)
{
    EXPECT_STREQ(ugv::toString(LogCategory::Platform), "platform");
    EXPECT_STREQ(ugv::toString(LogCategory::Hal), "hal");
    EXPECT_STREQ(ugv::toString(LogCategory::Rt), "rt");
    EXPECT_STREQ(ugv::toString(LogCategory::Vision), "vision");
    EXPECT_STREQ(ugv::toString(LogCategory::Ipc), "ipc");
    EXPECT_STREQ(ugv::toString(LogCategory::Bringup), "bringup");
    EXPECT_STREQ(ugv::toString(LogCategory::Tool), "tool");
    EXPECT_STREQ(ugv::toString(LogLevel::Debug), "debug");
    EXPECT_STREQ(ugv::toString(LogLevel::Info), "info");
    EXPECT_STREQ(ugv::toString(LogLevel::Warn), "warn");
    EXPECT_STREQ(ugv::toString(LogLevel::Error), "error");
    EXPECT_STREQ(ugv::toString(LogLevel::Fatal), "fatal");
}

TEST(ParseLogLevels, EmptySpecGivesDefaultsAndNoErrors)
{
    const auto sut = ugv::parseLogLevels("");
    EXPECT_EQ(sut.thresholds, allAt(LogLevel::Info));
    EXPECT_TRUE(sut.errors.empty());
}

TEST(ParseLogLevels, NamedCategoriesGetTheirLevelOthersKeepInfo)
{
    const auto sut = ugv::parseLogLevels("hal:debug,vision:error");
    EXPECT_EQ(sut.thresholds[static_cast<int>(LogCategory::Hal)], LogLevel::Debug);
    EXPECT_EQ(sut.thresholds[static_cast<int>(LogCategory::Vision)], LogLevel::Error);
    EXPECT_EQ(sut.thresholds[static_cast<int>(LogCategory::Rt)], LogLevel::Info);
    EXPECT_TRUE(sut.errors.empty());
}

TEST(ParseLogLevels, StarSetsAllAndLaterItemsWin)
{
    const auto sut = ugv::parseLogLevels(" *:warn , ipc : fatal,,");
    EXPECT_EQ(sut.thresholds[static_cast<int>(LogCategory::Tool)], LogLevel::Warn);
    EXPECT_EQ(sut.thresholds[static_cast<int>(LogCategory::Ipc)], LogLevel::Fatal);
    EXPECT_TRUE(sut.errors.empty());
}

TEST(ParseLogLevels, BadItemsAreReportedAndIgnoredGoodOnesApply)
{
    const auto sut = ugv::parseLogLevels("nocolon,radar:debug,hal:loud,rt:debug");
    ASSERT_EQ(sut.errors.size(), 3U);
    EXPECT_NE(sut.errors[0].find("'nocolon' has no ':'"), std::string::npos) << sut.errors[0];
    EXPECT_NE(sut.errors[1].find("unknown category 'radar'"), std::string::npos) << sut.errors[1];
    EXPECT_NE(sut.errors[2].find("unknown level 'loud'"), std::string::npos) << sut.errors[2];
    EXPECT_EQ(sut.thresholds[static_cast<int>(LogCategory::Hal)], LogLevel::Info);
    EXPECT_EQ(sut.thresholds[static_cast<int>(LogCategory::Rt)], LogLevel::Debug);
}

TEST(LogLevelsEnvDeathTest, EnvIsAppliedAndBadItemsReportedOnce)
{
    GTEST_FLAG_SET(death_test_style, "threadsafe"); // fresh process: the env has not been read yet
    EXPECT_EXIT(
        {
            ::setenv("UGV_LOG_LEVELS", "hal:debug,bogus", 1); // single thread
            ugv::initLogLevelsFromEnv();
            ugv::initLogLevelsFromEnv(); // second call: nothing read or reported again
            const bool applied = ugv::logThreshold(LogCategory::Hal) == LogLevel::Debug &&
                                 ugv::logThreshold(LogCategory::Vision) == LogLevel::Info;
            std::exit(applied ? 0 : 1);
        },
        testing::ExitedWithCode(0), "\\[platform\\] warn: UGV_LOG_LEVELS item 'bogus' has no ':'");
}

// ---- thresholds and UGV_LOG ----

TEST(LogThresholds, SetThenQueryPerCategory)
{
    auto thresholds = allAt(LogLevel::Info);
    thresholds[static_cast<int>(LogCategory::Vision)] = LogLevel::Error;
    ugv::setLogThresholds(thresholds);
    EXPECT_EQ(ugv::logThreshold(LogCategory::Vision), LogLevel::Error);
    EXPECT_FALSE(ugv::logEnabled(LogCategory::Vision, LogLevel::Warn));
    EXPECT_TRUE(ugv::logEnabled(LogCategory::Vision, LogLevel::Error));
    EXPECT_TRUE(ugv::logEnabled(LogCategory::Hal, LogLevel::Info));
    EXPECT_FALSE(ugv::logEnabled(LogCategory::Hal, LogLevel::Debug));
    ugv::setLogThresholds(allAt(LogLevel::Info));
}

TEST(UgvLog, WritesOnePrefixedLine)
{
    ugv::setLogThresholds(allAt(LogLevel::Info));
    const CapturedLog log;
    constexpr int kValue = 42;
    UGV_LOG(Vision, Warn) << "text " << kValue;
    EXPECT_EQ(log.text(), "[vision] warn: text 42\n");
}

TEST(UgvLog, FilteredLevelWritesNothingAndSkipsOperands)
{
    ugv::setLogThresholds(allAt(LogLevel::Warn));
    const CapturedLog log;
    int evaluated = 0;
    UGV_LOG(Hal, Info) << ++evaluated;
    if (evaluated == 0)
        UGV_LOG(Hal, Debug) << "dangling-else check";
    else
        ++evaluated;
    EXPECT_EQ(evaluated, 0);
    EXPECT_EQ(log.text(), "");
    ugv::setLogThresholds(allAt(LogLevel::Info));
}

TEST(UgvLog, LinesFromManyThreadsNeverInterleave)
{
    ugv::setLogThresholds(allAt(LogLevel::Info));
    const CapturedLog log;
    constexpr int kThreads = 4;
    constexpr int kLinesPerThread = 500;
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t) {
        threads.emplace_back([t] {
            for (int i = 0; i < kLinesPerThread; ++i) {
                UGV_LOG(Tool, Info) << "thread " << t << " line " << i << " " << std::string(40, 'a' + t);
            }
        });
    }
    for (auto& thread : threads) {
        thread.join();
    }
    const auto all = lines(log.text());
    ASSERT_EQ(all.size(), static_cast<std::size_t>(kThreads * kLinesPerThread));
    for (const auto& line : all) {
        ASSERT_EQ(line.rfind("[tool] info: thread ", 0), 0U) << line;
        const char fill = line.back();
        ASSERT_EQ(line.substr(line.size() - 40), std::string(40, fill)) << line;
    }
}

TEST(WriteLogLine, WritesTheLineVerbatim)
{
    const CapturedLog log;
    ugv::writeLogLine("exact\n");
    EXPECT_EQ(log.text(), "exact\n");
}

TEST(WriteLogLine, ClosedOutputIsIgnoredWithoutHanging)
{
    const int previous = ugv::setLogOutputFd(-1); // write() fails with EBADF
    ugv::writeLogLine("lost\n");
    UGV_LOG(Tool, Error) << "lost too";
    EXPECT_EQ(ugv::setLogOutputFd(previous), -1);
}

TEST(SetLogOutputFd, ReturnsThePreviousFd)
{
    const int previous = ugv::setLogOutputFd(2);
    EXPECT_EQ(ugv::setLogOutputFd(previous), 2);
}

// ---- RT records ----

TEST(FormatRtMessage, SubstitutesArgumentsInOrder)
{
    EXPECT_EQ(ugv::formatRtMessage("a=%lld b=%lld 100%%", {1, -2, 3, 4}), "a=1 b=-2 100%");
    EXPECT_EQ(ugv::formatRtMessage("no args", {1, 2, 3, 4}), "no args");
    EXPECT_EQ(ugv::formatRtMessage("%lld%lld%lld%lld", {1, 2, 3, 4}), "1234");
}

TEST(FormatRtMessage, FifthPlaceholderAndNullFormatAreVisible)
{
    EXPECT_EQ(ugv::formatRtMessage("%lld %lld %lld %lld %lld", {1, 2, 3, 4}), "1 2 3 4 <missing>");
    EXPECT_EQ(ugv::formatRtMessage(nullptr, {}), "<null format>");
    EXPECT_EQ(ugv::formatRtMessage("%d %", {}), "%d %");
}

TEST(RtLogChannel, RecordsComeOutInOrderFormatted)
{
    ugv::setLogThresholds(allAt(LogLevel::Info));
    const CapturedLog log;
    ugv::RtLogChannel channel("capture");
    ugv::LogDrain sut;
    ASSERT_TRUE(sut.addChannel(channel).has_value());
    channel.log(LogLevel::Info, LogCategory::Hal, "frame %lld took %lld us", 1, 250);
    channel.log(LogLevel::Error, LogCategory::Vision, "sector %lld", 7);
    channel.log(LogLevel::Warn, LogCategory::Rt, "no args");

    EXPECT_EQ(sut.drainOnce(), 3U);

    const auto all = lines(log.text());
    ASSERT_EQ(all.size(), 3U);
    EXPECT_EQ(all[0].rfind("[hal] info: frame 1 took 250 us [t=", 0), 0U) << all[0];
    EXPECT_EQ(all[1].rfind("[vision] error: sector 7 [t=", 0), 0U) << all[1];
    EXPECT_EQ(all[2].rfind("[rt] warn: no args [t=", 0), 0U) << all[2];
    EXPECT_EQ(sut.drainOnce(), 0U);
    EXPECT_EQ(channel.dropped(), 0U);
    EXPECT_STREQ(channel.name(), "capture");
}

TEST(RtLogChannel, FilteredRecordsAreNotStored)
{
    auto thresholds = allAt(LogLevel::Info);
    thresholds[static_cast<int>(LogCategory::Vision)] = LogLevel::Error;
    ugv::setLogThresholds(thresholds);
    ugv::RtLogChannel sut("vision");
    sut.log(LogLevel::Warn, LogCategory::Vision, "filtered");
    ugv::RtLogRecord record;
    EXPECT_FALSE(sut.tryPop(record));
    ugv::setLogThresholds(allAt(LogLevel::Info));
}

TEST(RtLogChannel, FullRingCountsDropsAndDrainReportsThemOnce)
{
    ugv::setLogThresholds(allAt(LogLevel::Info));
    const CapturedLog log;
    ugv::RtLogChannel channel("busy");
    constexpr std::size_t kExtra = 10;
    for (std::size_t i = 0; i < ugv::kRtLogChannelCapacity + kExtra; ++i) {
        channel.log(LogLevel::Info, LogCategory::Rt, "n=%lld", static_cast<std::int64_t>(i));
    }
    EXPECT_EQ(channel.dropped(), kExtra);
    ugv::LogDrain sut;
    ASSERT_TRUE(sut.addChannel(channel).has_value());

    EXPECT_EQ(sut.drainOnce(), ugv::kRtLogChannelCapacity);
    EXPECT_EQ(sut.drainOnce(), 0U);

    const auto all = lines(log.text());
    ASSERT_EQ(all.size(), ugv::kRtLogChannelCapacity + 1);
    EXPECT_EQ(all.back().rfind("[platform] warn: RT log channel 'busy' dropped 10 record(s) (total 10)", 0), 0U)
        << all.back();
    EXPECT_EQ(all[ugv::kRtLogChannelCapacity - 1].rfind("[rt] info: n=255 ", 0), 0U);
}

TEST(RtLogChannel, LogAllocatesNothing)
{
    ugv::setLogThresholds(allAt(LogLevel::Info));
    ugv::RtLogChannel sut("rt");
    constexpr int kCalls = 1000; // more than the ring holds: the drop path too
    const ugv::test::AllocationScope scope;
    for (int i = 0; i < kCalls; ++i) {
        sut.log(LogLevel::Info, LogCategory::Rt, "i=%lld %lld %lld %lld", i, 1, 2, 3);
    }
    EXPECT_EQ(scope.count(), 0U);
    EXPECT_GT(sut.dropped(), 0U);
}

// ---- LogDrain ----

TEST(LogDrain, RefusesMoreThanMaxChannels)
{
    std::vector<std::unique_ptr<ugv::RtLogChannel>> channels;
    ugv::LogDrain sut;
    for (std::size_t i = 0; i < ugv::kMaxRtLogChannels; ++i) {
        channels.push_back(std::make_unique<ugv::RtLogChannel>("c"));
        ASSERT_TRUE(sut.addChannel(*channels.back()).has_value());
    }
    ugv::RtLogChannel extra("extra");
    const auto result = sut.addChannel(extra);
    ASSERT_FALSE(result.has_value());
    EXPECT_NE(result.error().what.find("'extra'"), std::string::npos) << result.error().message();
}

TEST(LogDrain, RefusesChannelsAndSecondStartWhileRunning)
{
    ugv::LogDrain sut;
    ASSERT_TRUE(sut.start().has_value());
    EXPECT_TRUE(sut.running());
    ugv::RtLogChannel late("late");
    const auto added = sut.addChannel(late);
    ASSERT_FALSE(added.has_value());
    EXPECT_NE(added.error().what.find("while the drain thread runs"), std::string::npos);
    EXPECT_FALSE(sut.start().has_value());
    sut.stop();
    EXPECT_FALSE(sut.running());
    sut.stop(); // idempotent
    EXPECT_TRUE(sut.addChannel(late).has_value());
}

TEST(LogDrain, ThreadDrainsAProducerThreadInOrderAndAccountsForEveryRecord)
{
    ugv::setLogThresholds(allAt(LogLevel::Info));
    const CapturedLog log;
    ugv::RtLogChannel channel("producer");
    ugv::LogDrain sut;
    ASSERT_TRUE(sut.addChannel(channel).has_value());
    ASSERT_TRUE(sut.start(std::chrono::milliseconds(1)).has_value());

    constexpr std::int64_t kRecords = 20'000;
    std::thread producer([&] {
        for (std::int64_t i = 0; i < kRecords; ++i) {
            channel.log(LogLevel::Info, LogCategory::Rt, "seq %lld", i);
            if (i % 128 == 0) {
                std::this_thread::sleep_for(std::chrono::microseconds(200)); // let the drain keep up mostly
            }
        }
    });
    producer.join();
    sut.stop(); // drains the rest

    std::int64_t written = 0;
    std::int64_t last = -1;
    bool inOrder = true;
    for (const auto& line : lines(log.text())) {
        if (line.rfind("[rt] info: seq ", 0) == 0) {
            const std::int64_t seq = std::stoll(line.substr(15));
            inOrder = inOrder && seq > last;
            last = seq;
            ++written;
        }
    }
    EXPECT_TRUE(inOrder);
    EXPECT_GT(written, 0);
    EXPECT_EQ(written + static_cast<std::int64_t>(channel.dropped()), kRecords);
}

std::atomic<int> gThrowingWrites{0};

/// A log writer that throws for its first gThrowingWrites calls, then writes as the drain does by default.
void throwingThenRealWriter(std::string_view line)
{
    if (gThrowingWrites.fetch_sub(1) > 0) {
        throw std::bad_alloc();
    }
    ugv::writeLogLine(line);
}

TEST(LogDrain, AThrowOutOfADrainIsCountedAndTheThreadGoesOn)
{
    ugv::setLogThresholds(allAt(LogLevel::Info));
    const CapturedLog log;
    ugv::RtLogChannel channel("producer");
    ugv::LogDrain sut;
    ASSERT_TRUE(sut.addChannel(channel).has_value());
    gThrowingWrites = 3;
    sut.setWriterForTest(&throwingThenRealWriter);
    ASSERT_TRUE(sut.start(std::chrono::milliseconds(1)).has_value());

    for (std::int64_t i = 0; i < 10; ++i) {
        channel.log(LogLevel::Info, LogCategory::Rt, "record %lld", i);
        std::this_thread::sleep_for(std::chrono::milliseconds(5)); // one record per drain, about
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (log.text().find("record 9") == std::string::npos && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    ASSERT_TRUE(sut.running());
    sut.stop();

    EXPECT_EQ(sut.failures(), 3U);
    EXPECT_NE(log.text().find("the log drain failed to format or write a record (lost); it goes on"), std::string::npos)
        << log.text();
    EXPECT_NE(log.text().find("[rt] info: record 9"), std::string::npos) << log.text(); // drained after the throws
}

} // namespace

// ---- journal priorities ----

TEST(Journal, StreamIsRecognisedByDeviceAndInode)
{
    const int fd = ::memfd_create("ugv-journal-test", 0);
    ASSERT_GE(fd, 0);
    struct stat st {};
    ASSERT_EQ(::fstat(fd, &st), 0);
    const std::string mine = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
    const std::string other = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino + 1);

    EXPECT_TRUE(ugv::isJournalStream(fd, mine.c_str()));
    EXPECT_FALSE(ugv::isJournalStream(fd, other.c_str()));
    EXPECT_FALSE(ugv::isJournalStream(fd, nullptr));
    EXPECT_FALSE(ugv::isJournalStream(fd, "not a stream"));
    EXPECT_FALSE(ugv::isJournalStream(fd, (mine + "x").c_str()));                      // trailing text
    EXPECT_FALSE(ugv::isJournalStream(fd, std::to_string(st.st_dev).c_str()));         // no inode
    EXPECT_FALSE(ugv::isJournalStream(fd, (std::to_string(st.st_dev) + ":").c_str())); // empty inode
    EXPECT_FALSE(ugv::isJournalStream(fd, ("-" + mine).c_str()));                      // a sign
    EXPECT_FALSE(ugv::isJournalStream(-1, mine.c_str()));
    ::close(fd);
}

TEST(Journal, LinesCarryTheirSyslogPriorityWhenWritingToTheJournal)
{
    ugv::setLogThresholds(allAt(LogLevel::Debug));
    const CapturedLog log;
    ugv::RtLogChannel channel("vision");
    ugv::LogDrain drain;
    ASSERT_TRUE(drain.addChannel(channel).has_value());
    ugv::setJournalPrefixes(true);

    UGV_LOG(Bringup, Debug) << "d";
    UGV_LOG(Bringup, Info) << "i";
    UGV_LOG(Hal, Warn) << "w";
    UGV_LOG(Hal, Error) << "e";
    UGV_LOG(Hal, Fatal) << "f";
    channel.log(LogLevel::Warn, LogCategory::Rt, "frame %lld missed its deadline", 12);
    drain.drainOnce();
    ugv::setJournalPrefixes(false);
    UGV_LOG(Hal, Warn) << "plain";

    const auto all = lines(log.text());
    ASSERT_EQ(all.size(), 7U);
    EXPECT_EQ(all[0], "<7>[bringup] debug: d");
    EXPECT_EQ(all[1], "<6>[bringup] info: i");
    EXPECT_EQ(all[2], "<4>[hal] warn: w");
    EXPECT_EQ(all[3], "<3>[hal] error: e");
    EXPECT_EQ(all[4], "<2>[hal] fatal: f");
    EXPECT_EQ(all[5].rfind("<4>[rt] warn: frame 12 missed its deadline [t=", 0), 0U) << all[5];
    EXPECT_EQ(all[6], "[hal] warn: plain");
    ugv::setLogThresholds(allAt(LogLevel::Info));
}
