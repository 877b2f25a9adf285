#include "ugv/rt/perf_counter.hpp"

#include <gtest/gtest.h>

namespace {

using namespace std::chrono_literals;
using ugv::rt::PerfCounter;

TEST(PerfCounter, EmptyCounterReportsZeros)
{
    const PerfCounter sut;
    EXPECT_EQ(sut.elapsed().count, 0U);
    EXPECT_EQ(sut.elapsed().max, 0ns);
    EXPECT_EQ(sut.interval().count, 0U);
    EXPECT_EQ(sut.interval().mean, 0ns);
}

TEST(PerfCounter, OneStepGivesElapsedButNoInterval)
{
    PerfCounter sut;
    sut.begin(1000ns);
    sut.end(1250ns);
    const auto elapsed = sut.elapsed();
    EXPECT_EQ(elapsed.count, 1U);
    EXPECT_EQ(elapsed.last, 250ns);
    EXPECT_EQ(elapsed.min, 250ns);
    EXPECT_EQ(elapsed.max, 250ns);
    EXPECT_EQ(elapsed.mean, 250ns);
    EXPECT_EQ(sut.interval().count, 0U);
}

TEST(PerfCounter, ManyStepsGiveMinMaxMeanLastAndIntervals)
{
    PerfCounter sut;
    // begins at 0, 100, 250; elapsed 10, 30, 20
    sut.begin(0ns);
    sut.end(10ns);
    sut.begin(100ns);
    sut.end(130ns);
    sut.begin(250ns);
    sut.end(270ns);
    const auto elapsed = sut.elapsed();
    EXPECT_EQ(elapsed.count, 3U);
    EXPECT_EQ(elapsed.min, 10ns);
    EXPECT_EQ(elapsed.max, 30ns);
    EXPECT_EQ(elapsed.mean, 20ns);
    EXPECT_EQ(elapsed.last, 20ns);
    const auto interval = sut.interval();
    EXPECT_EQ(interval.count, 2U);
    EXPECT_EQ(interval.min, 100ns);
    EXPECT_EQ(interval.max, 150ns);
    EXPECT_EQ(interval.mean, 125ns);
    EXPECT_EQ(interval.last, 150ns);
}

TEST(PerfCounter, WarmupSamplesAreSkipped)
{
    PerfCounter sut(2);
    sut.begin(0ns); // elapsed 1000 (skipped)
    sut.end(1000ns);
    sut.begin(2000ns); // interval 2000 (skipped); elapsed 900 (skipped)
    sut.end(2900ns);
    sut.begin(3000ns); // interval 1000 (skipped); elapsed 5 (counted)
    sut.end(3005ns);
    sut.begin(4000ns); // interval 1000 (counted)
    sut.end(4007ns);
    EXPECT_EQ(sut.elapsed().count, 2U);
    EXPECT_EQ(sut.elapsed().max, 7ns);
    EXPECT_EQ(sut.interval().count, 1U);
    EXPECT_EQ(sut.interval().max, 1000ns);
}

TEST(PerfCounter, ResetForgetsSamplesAndRestartsWarmup)
{
    PerfCounter sut(1);
    sut.begin(0ns);
    sut.end(5ns);
    sut.begin(10ns);
    sut.end(20ns);
    ASSERT_EQ(sut.elapsed().count, 1U);
    sut.reset();
    EXPECT_EQ(sut.elapsed().count, 0U);
    sut.begin(100ns);
    sut.end(101ns); // warm-up again: skipped
    EXPECT_EQ(sut.elapsed().count, 0U);
    EXPECT_EQ(sut.interval().count, 0U);
}

TEST(PerfCounterDeathTest, EndWithoutBeginIsABug)
{
    PerfCounter sut;
    EXPECT_DEATH(sut.end(1ns), "precondition failed");
}

} // namespace
