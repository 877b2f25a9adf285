#pragma once

/// @file
/// `ugv::rt::PerfCounter`: per-task timing in the style of PX4's perf counters. begin()/end() around each step
/// give the elapsed time; successive begin() calls give the interval (period and its jitter). The first
/// `warmupSamples` samples of each are ignored (caches, page faults and start-up skew). Timestamps are passed
/// in (MonotonicClock::now() in the service, chosen values in tests).
///
/// Thread-safety: single writer (the task); readers on other threads see torn stats, so read them from the
/// task or after it stopped. RT-safe: yes (plain members, no allocation, no system call).

#include <algorithm>
#include <chrono>
#include <cstdint>

#include "ugv/platform/assert.hpp"

namespace ugv::rt {

/// count/last/min/max/mean of a series of durations. All zero while count == 0.
struct DurationStats {
    std::uint64_t count = 0;
    std::chrono::nanoseconds last{};
    std::chrono::nanoseconds min{};
    std::chrono::nanoseconds max{};
    std::chrono::nanoseconds mean{};
};

class PerfCounter {
public:
    /// @param[in] warmupSamples samples to skip, separately for elapsed and interval.
    explicit PerfCounter(std::uint32_t warmupSamples = 0) noexcept : warmup_(warmupSamples) {}

    /// @brief A step starts at `now`. Thread-safety: the task. RT-safe: yes.
    void begin(std::chrono::nanoseconds now) noexcept
    {
        if (haveBegin_) {
            interval_.add(now - lastBegin_, warmup_);
        }
        lastBegin_ = now;
        haveBegin_ = true;
        inStep_ = true;
    }

    /// @brief The step begun last ends at `now`; end() without begin() is a bug (checked).
    /// Thread-safety: the task. RT-safe: yes.
    void end(std::chrono::nanoseconds now) noexcept
    {
        UGV_EXPECTS(inStep_);
        inStep_ = false;
        elapsed_.add(now - lastBegin_, warmup_);
    }

    [[nodiscard]] DurationStats elapsed() const noexcept { return elapsed_.stats(); }
    [[nodiscard]] DurationStats interval() const noexcept { return interval_.stats(); }

    /// @brief Forget all samples; the warm-up starts again. Thread-safety: the task. RT-safe: yes.
    void reset() noexcept { *this = PerfCounter(warmup_); }

private:
    class Series {
    public:
        void add(std::chrono::nanoseconds sample, std::uint32_t warmup) noexcept
        {
            if (skipped_ < warmup) {
                ++skipped_;
                return;
            }
            ++count_;
            last_ = sample;
            min_ = std::min(min_, sample);
            max_ = std::max(max_, sample);
            sumNs_ += static_cast<double>(sample.count()); // double: no overflow over years of samples
        }
        [[nodiscard]] DurationStats stats() const noexcept
        {
            if (count_ == 0) {
                return {};
            }
            const auto mean = std::chrono::nanoseconds(static_cast<std::int64_t>(sumNs_ / static_cast<double>(count_)));
            return {count_, last_, min_, max_, mean};
        }

    private:
        std::uint32_t skipped_ = 0;
        std::uint64_t count_ = 0;
        std::chrono::nanoseconds last_{};
        std::chrono::nanoseconds min_ = std::chrono::nanoseconds::max();
        std::chrono::nanoseconds max_ = std::chrono::nanoseconds::min();
        double sumNs_ = 0.0;
    };

    std::uint32_t warmup_;
    Series elapsed_;
    Series interval_;
    std::chrono::nanoseconds lastBegin_{};
    bool haveBegin_ = false;
    bool inStep_ = false;
};

} // namespace ugv::rt
