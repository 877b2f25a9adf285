#include "ugv/rt/latency_histogram.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace ugv::rt {
namespace {

constexpr std::uint64_t kSubBuckets = std::uint64_t{1} << LatencyHistogram::kSubBucketBits;

} // namespace

std::size_t LatencyHistogram::bucketIndex(std::uint64_t valueNs) noexcept
{
    if (valueNs < kExactBuckets) {
        return static_cast<std::size_t>(valueNs);
    }
    // value in [2^msb, 2^(msb+1)), msb >= 6: drop `shift` low bits so that 32 <= (value >> shift) < 64.
    const auto msb = static_cast<unsigned>(std::bit_width(valueNs) - 1);
    const unsigned shift = msb - kSubBucketBits;
    return static_cast<std::size_t>(kExactBuckets + (shift - 1) * kSubBuckets + ((valueNs >> shift) - kSubBuckets));
}

std::uint64_t LatencyHistogram::bucketLowest(std::size_t index) noexcept
{
    if (index < kExactBuckets) {
        return index;
    }
    const std::uint64_t group = (index - kExactBuckets) / kSubBuckets; // shift - 1
    const std::uint64_t sub = (index - kExactBuckets) % kSubBuckets;
    return (kSubBuckets + sub) << (group + 1);
}

std::uint64_t LatencyHistogram::bucketHighest(std::size_t index) noexcept
{
    if (index < kExactBuckets) {
        return index;
    }
    const std::uint64_t group = (index - kExactBuckets) / kSubBuckets;
    return bucketLowest(index) + (std::uint64_t{1} << (group + 1)) - 1;
}

void LatencyHistogram::record(std::chrono::nanoseconds latency) noexcept
{
    const auto value = static_cast<std::uint64_t>(std::max<std::int64_t>(latency.count(), 0));
    ++count_;
    min_ = std::min(min_, value);
    max_ = std::max(max_, value);
    if (value > kMaxTrackableNs) {
        ++overflow_;
    } else {
        ++buckets_[bucketIndex(value)];
    }
}

std::chrono::nanoseconds LatencyHistogram::percentile(double p) const noexcept
{
    if (count_ == 0) {
        return std::chrono::nanoseconds(0);
    }
    constexpr double kHundred = 100.0;
    const double clamped = std::clamp(p, 0.0, kHundred);
    const auto rank = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::ceil(clamped / kHundred * static_cast<double>(count_))));
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < kBucketCount; ++i) {
        seen += buckets_[i];
        if (seen >= rank) {
            const std::uint64_t middle = bucketLowest(i) + (bucketHighest(i) - bucketLowest(i)) / 2;
            return std::chrono::nanoseconds(static_cast<std::int64_t>(std::clamp(middle, min_, max_)));
        }
    }
    return max(); // the rank lies in the overflow bucket
}

std::chrono::nanoseconds LatencyHistogram::min() const noexcept
{
    return std::chrono::nanoseconds(count_ == 0 ? 0 : static_cast<std::int64_t>(min_));
}

std::chrono::nanoseconds LatencyHistogram::max() const noexcept
{
    return std::chrono::nanoseconds(static_cast<std::int64_t>(max_));
}

void LatencyHistogram::merge(const LatencyHistogram& other) noexcept
{
    for (std::size_t i = 0; i < kBucketCount; ++i) {
        buckets_[i] += other.buckets_[i];
    }
    overflow_ += other.overflow_;
    count_ += other.count_;
    min_ = std::min(min_, other.min_);
    max_ = std::max(max_, other.max_);
}

} // namespace ugv::rt
