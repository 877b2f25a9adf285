#include "ugv/rt/latency_histogram.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace {

using namespace std::chrono_literals;
using ugv::rt::LatencyHistogram;

/// The sample of rank ceil(p/100 * n) (at least 1) of a sorted vector: the definition percentile() follows.
std::int64_t exactPercentile(const std::vector<std::int64_t>& sorted, double p)
{
    const auto rank =
        std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(sorted.size()))));
    return sorted[rank - 1];
}

std::vector<std::int64_t> randomLatencies(std::uint32_t seed, std::size_t n)
{
    std::mt19937_64 rng(seed);
    // log-uniform from 100 ns to 10 s: every octave of the range gets samples
    std::uniform_real_distribution<double> exponent(2.0, 10.0);
    std::vector<std::int64_t> out(n);
    for (auto& value : out) {
        value = static_cast<std::int64_t>(std::pow(10.0, exponent(rng)));
    }
    return out;
}

TEST(LatencyHistogram, EmptyReportsZero)
{
    const LatencyHistogram sut;
    EXPECT_EQ(sut.count(), 0U);
    EXPECT_EQ(sut.p50(), 0ns);
    EXPECT_EQ(sut.min(), 0ns);
    EXPECT_EQ(sut.max(), 0ns);
    EXPECT_EQ(sut.overflowCount(), 0U);
}

TEST(LatencyHistogram, OneSampleIsEveryPercentileExactly)
{
    LatencyHistogram sut;
    sut.record(12345ns);
    EXPECT_EQ(sut.count(), 1U);
    EXPECT_EQ(sut.percentile(0.0), 12345ns); // clamped to [min, max]
    EXPECT_EQ(sut.p999(), 12345ns);
    EXPECT_EQ(sut.min(), 12345ns);
    EXPECT_EQ(sut.max(), 12345ns);
}

TEST(LatencyHistogram, SmallValuesAreExactAndNegativeCountsAsZero)
{
    LatencyHistogram sut;
    sut.record(-5ns);
    for (int v = 1; v < 64; ++v) {
        sut.record(std::chrono::nanoseconds(v));
    }
    EXPECT_EQ(sut.min(), 0ns);
    EXPECT_EQ(sut.percentile(50.0), 31ns); // rank 32 of 0..63
    EXPECT_EQ(sut.max(), 63ns);
}

TEST(LatencyHistogram, BucketBoundaries)
{
    EXPECT_EQ(LatencyHistogram::kBucketCount, 1024U);
    EXPECT_EQ(LatencyHistogram::bucketIndex(63), 63U);
    EXPECT_EQ(LatencyHistogram::bucketIndex(64), 64U);
    EXPECT_EQ(LatencyHistogram::bucketIndex(65), 64U);
    EXPECT_EQ(LatencyHistogram::bucketIndex(127), 95U);
    EXPECT_EQ(LatencyHistogram::bucketIndex(128), 96U);
    EXPECT_EQ(LatencyHistogram::bucketIndex(LatencyHistogram::kMaxTrackableNs), LatencyHistogram::kBucketCount - 1);
    for (std::size_t i = 0; i < LatencyHistogram::kBucketCount; ++i) {
        ASSERT_EQ(LatencyHistogram::bucketIndex(LatencyHistogram::bucketLowest(i)), i);
        ASSERT_EQ(LatencyHistogram::bucketIndex(LatencyHistogram::bucketHighest(i)), i);
        if (i + 1 < LatencyHistogram::kBucketCount) {
            ASSERT_EQ(LatencyHistogram::bucketHighest(i) + 1, LatencyHistogram::bucketLowest(i + 1));
        }
        const double width =
            static_cast<double>(LatencyHistogram::bucketHighest(i) - LatencyHistogram::bucketLowest(i));
        ASSERT_LE(width / 2.0,
                  LatencyHistogram::kMaxRelativeError * static_cast<double>(LatencyHistogram::bucketLowest(i)) + 0.5);
    }
}

TEST(LatencyHistogram, PercentilesWithinStatedErrorOfExactOnes)
{
    const auto samples = randomLatencies(1, 50'000);
    LatencyHistogram sut;
    for (const auto v : samples) {
        sut.record(std::chrono::nanoseconds(v));
    }
    auto sorted = samples;
    std::sort(sorted.begin(), sorted.end());
    for (const double p : {0.0, 1.0, 10.0, 25.0, 50.0, 75.0, 90.0, 99.0, 99.9, 99.99, 100.0}) {
        const auto exact = static_cast<double>(exactPercentile(sorted, p));
        const auto estimate = static_cast<double>(sut.percentile(p).count());
        EXPECT_LE(std::abs(estimate - exact), LatencyHistogram::kMaxRelativeError * exact) << "p" << p;
    }
    EXPECT_EQ(sut.max().count(), sorted.back());
    EXPECT_EQ(sut.min().count(), sorted.front());
    EXPECT_EQ(sut.percentile(100.0).count(), sorted.back());
    EXPECT_EQ(sut.percentile(150.0), sut.max()); // clamped
    const auto p90 = static_cast<double>(exactPercentile(sorted, 90.0));
    const auto p99 = static_cast<double>(exactPercentile(sorted, 99.0));
    EXPECT_NEAR(static_cast<double>(sut.p90().count()), p90, p90 * LatencyHistogram::kMaxRelativeError);
    EXPECT_NEAR(static_cast<double>(sut.p99().count()), p99, p99 * LatencyHistogram::kMaxRelativeError);
}

TEST(LatencyHistogram, MergeEqualsRecordingBothSets)
{
    const auto a = randomLatencies(2, 5000);
    const auto b = randomLatencies(3, 7000);
    LatencyHistogram left;
    LatencyHistogram right;
    LatencyHistogram both;
    for (const auto v : a) {
        left.record(std::chrono::nanoseconds(v));
        both.record(std::chrono::nanoseconds(v));
    }
    for (const auto v : b) {
        right.record(std::chrono::nanoseconds(v));
        both.record(std::chrono::nanoseconds(v));
    }
    right.record(100s); // an overflow on one side
    both.record(100s);

    left.merge(right);

    EXPECT_EQ(left.count(), both.count());
    EXPECT_EQ(left.overflowCount(), 1U);
    EXPECT_EQ(left.min(), both.min());
    EXPECT_EQ(left.max(), both.max());
    for (double p = 0.0; p <= 100.0; p += 0.5) {
        ASSERT_EQ(left.percentile(p), both.percentile(p)) << "p" << p;
    }
    LatencyHistogram empty;
    empty.merge(LatencyHistogram{});
    EXPECT_EQ(empty.count(), 0U);
    EXPECT_EQ(empty.min(), 0ns);
}

TEST(LatencyHistogram, OverflowGoesToItsBucketAndPercentileReportsMax)
{
    LatencyHistogram sut;
    sut.record(1us);
    sut.record(std::chrono::nanoseconds(LatencyHistogram::kMaxTrackableNs)); // last tracked value
    sut.record(std::chrono::nanoseconds(LatencyHistogram::kMaxTrackableNs + 1));
    sut.record(200s);
    EXPECT_EQ(sut.overflowCount(), 2U);
    EXPECT_EQ(sut.count(), 4U);
    EXPECT_EQ(sut.max(), 200s);
    EXPECT_EQ(sut.percentile(100.0), 200s);
    EXPECT_EQ(sut.percentile(25.0), 1us);
    const auto lastTracked = static_cast<double>(LatencyHistogram::kMaxTrackableNs);
    EXPECT_NEAR(static_cast<double>(sut.p50().count()), lastTracked, lastTracked * LatencyHistogram::kMaxRelativeError);
}

TEST(LatencyHistogram, ResetForgetsEverything)
{
    LatencyHistogram sut;
    sut.record(5ms);
    sut.record(500s);
    sut.reset();
    EXPECT_EQ(sut.count(), 0U);
    EXPECT_EQ(sut.overflowCount(), 0U);
    EXPECT_EQ(sut.max(), 0ns);
    sut.record(7ns);
    EXPECT_EQ(sut.min(), 7ns);
}

TEST(LatencyHistogram, RecordAndPercentileAllocateNothing)
{
    const auto samples = randomLatencies(4, 100'000);
    auto sut = std::make_unique<LatencyHistogram>();
    const ugv::test::AllocationScope scope;
    for (const auto v : samples) {
        sut->record(std::chrono::nanoseconds(v));
    }
    const auto p99 = sut->p99();
    EXPECT_EQ(scope.count(), 0U);
    EXPECT_GT(p99, 0ns);
    EXPECT_EQ(sut->count(), 100'000U);
}

} // namespace
