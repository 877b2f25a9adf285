#include "ugv/platform/clock.hpp"

#include <chrono>
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

} // namespace
