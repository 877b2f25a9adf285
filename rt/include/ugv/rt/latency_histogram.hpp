#pragma once

/// @file
/// `ugv::rt::LatencyHistogram`: a log-linear latency histogram in the style of HdrHistogram, fixed storage.
///
/// Values are nanoseconds. 0..63 ns are counted exactly; above that each power-of-two range [2^k, 2^(k+1)) is
/// split into 32 equal sub-buckets, up to kMaxTrackableNs (2^36 - 1 ns, about 68.7 s). Larger values go to an
/// overflow bucket. min and max are exact. percentile() returns the middle of the bucket holding the sample of
/// that rank, clamped to [min, max], so its relative error against the exact sample is at most 1/64 (1.6 %)
/// (a bucket is at most 1/32 of its lower bound wide); a percentile in the overflow bucket returns max().
///
/// Thread-safety: thread-compatible (one writer; merge or read from the writer or after it stopped).
/// RT-safe: record, count, min, max, percentile, merge and reset yes (O(1) or O(buckets), no allocation).

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace ugv::rt {

class LatencyHistogram {
public:
    static constexpr unsigned kSubBucketBits = 5; ///< 32 sub-buckets per octave
    static constexpr unsigned kMaxValueBits = 36; ///< values below 2^36 ns
    static constexpr std::uint64_t kMaxTrackableNs = (std::uint64_t{1} << kMaxValueBits) - 1;
    static constexpr std::size_t kExactBuckets = std::size_t{2} << kSubBucketBits; ///< 0..63 exact
    static constexpr std::size_t kBucketCount =
        kExactBuckets + (kMaxValueBits - kSubBucketBits - 1) * (std::size_t{1} << kSubBucketBits);
    static constexpr double kMaxRelativeError = 1.0 / 64.0;

    /// @brief Count one sample; negative durations count as 0. O(1).
    /// Thread-safety: the writer. RT-safe: yes.
    void record(std::chrono::nanoseconds latency) noexcept;

    /// @brief The value at percentile `p` (0..100, clamped): the sample of rank ceil(p/100 * count) (at least
    /// rank 1) within kMaxRelativeError. 0 when empty. Thread-safety: reader. RT-safe: yes.
    [[nodiscard]] std::chrono::nanoseconds percentile(double p) const noexcept;
    [[nodiscard]] std::chrono::nanoseconds p50() const noexcept { return percentile(50.0); }
    [[nodiscard]] std::chrono::nanoseconds p90() const noexcept { return percentile(90.0); }
    [[nodiscard]] std::chrono::nanoseconds p99() const noexcept { return percentile(99.0); }
    [[nodiscard]] std::chrono::nanoseconds p999() const noexcept { return percentile(99.9); }

    /// Exact smallest/largest sample; 0 when empty.
    [[nodiscard]] std::chrono::nanoseconds min() const noexcept;
    [[nodiscard]] std::chrono::nanoseconds max() const noexcept;
    [[nodiscard]] std::uint64_t count() const noexcept { return count_; }
    /// Samples above kMaxTrackableNs.
    [[nodiscard]] std::uint64_t overflowCount() const noexcept { return overflow_; }

    /// @brief Add `other`'s samples; the result equals recording both sets into one histogram.
    void merge(const LatencyHistogram& other) noexcept;

    /// @brief Forget every sample.
    void reset() noexcept { *this = LatencyHistogram(); }

    /// The bucket of a value (<= kMaxTrackableNs) and the bucket's [lowest, highest] values. Exposed for tests.
    [[nodiscard]] static std::size_t bucketIndex(std::uint64_t valueNs) noexcept;
    [[nodiscard]] static std::uint64_t bucketLowest(std::size_t index) noexcept;
    [[nodiscard]] static std::uint64_t bucketHighest(std::size_t index) noexcept;

private:
    std::array<std::uint64_t, kBucketCount> buckets_{};
    std::uint64_t overflow_ = 0;
    std::uint64_t count_ = 0;
    std::uint64_t min_ = std::numeric_limits<std::uint64_t>::max();
    std::uint64_t max_ = 0;
};

} // namespace ugv::rt
