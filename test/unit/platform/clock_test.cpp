#include "ugv/platform/clock.hpp"

#include <semaphore.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <ctime>
#include <thread>

#include <gtest/gtest.h>

namespace {

using ugv::MonotonicClock;

TEST(MonotonicClock, NowNsAndNowAgreeAndNeverGoBack)
{
    const auto first = MonotonicClock::now();
    const std::int64_t second = MonotonicClock::nowNs();
    const auto third = MonotonicClock::now();
    EXPECT_GT(first.count(), 0);
    EXPECT_LE(first.count(), second);
    EXPECT_LE(second, third.count());
}

TEST(MonotonicClock, AdvancesOverASleep)
{
    constexpr auto kSleep = std::chrono::milliseconds(2);
    const auto before = MonotonicClock::now();
    std::this_thread::sleep_for(kSleep);
    EXPECT_GE(MonotonicClock::now() - before, kSleep);
}

std::int64_t nsOf(const timespec& ts)
{
    return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

TEST(MonotonicClock, ToTimespecSplitsSecondsAndNanoseconds)
{
    constexpr timespec kSplit = MonotonicClock::toTimespec(3'000'000'007);
    constexpr timespec kBelowOneSecond = MonotonicClock::toTimespec(999'999'999);
    EXPECT_EQ(kSplit.tv_sec, 3);
    EXPECT_EQ(kSplit.tv_nsec, 7);
    EXPECT_EQ(kBelowOneSecond.tv_sec, 0);
    EXPECT_EQ(kBelowOneSecond.tv_nsec, 999'999'999);
}

TEST(MonotonicClock, DeadlineAfterIsOnClockMonotonicNotTheWallClock)
{
    // A deadline taken from CLOCK_REALTIME would be decades later than this bracket (the epoch vs boot).
    constexpr auto kWait = std::chrono::milliseconds(250);
    timespec before{};
    timespec after{};
    ::clock_gettime(CLOCK_MONOTONIC, &before);
    const timespec sut = MonotonicClock::deadlineAfter(kWait);
    ::clock_gettime(CLOCK_MONOTONIC, &after);

    EXPECT_GE(nsOf(sut), nsOf(before) + std::chrono::nanoseconds(kWait).count());
    EXPECT_LE(nsOf(sut), nsOf(after) + std::chrono::nanoseconds(kWait).count());
    EXPECT_LT(sut.tv_nsec, 1'000'000'000);
}

TEST(MonotonicClock, SemClockwaitOnTheDeadlineTimesOutNoEarlierThanAsked)
{
    // The way semWait and the libcamera grab wait: a lower bound only (an upper one would flake on a busy machine).
    constexpr auto kWait = std::chrono::milliseconds(20);
    sem_t sem;
    ASSERT_EQ(::sem_init(&sem, 0, 0), 0);
    const auto start = MonotonicClock::now();
    const timespec deadline = MonotonicClock::deadlineAfter(kWait);
    int result = 0;
    while ((result = ::sem_clockwait(&sem, CLOCK_MONOTONIC, &deadline)) != 0 && errno == EINTR) {
    }
    const int error = errno;
    const auto waited = MonotonicClock::now() - start;
    ::sem_destroy(&sem);

    EXPECT_EQ(result, -1);
    EXPECT_EQ(error, ETIMEDOUT);
    EXPECT_GE(waited, kWait);
    EXPECT_LT(waited, std::chrono::seconds(30)); // sanity only: a wall-clock deadline would wait for decades
}

} // namespace
