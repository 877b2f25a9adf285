#pragma once

/// @file
/// Where a frame's detection time goes: the time of each stage of ObstacleDetector::process(), read at the stage
/// boundaries off a clock the caller passes in (vision reads no clock of its own: the service and the benchmarks give
/// MonotonicClock::nowNs, a vDSO read of about 20 ns; with the census matcher's per-row split about 750 reads, some
/// 20 us, per frame next to its 18 ms). `bench-detect` and the service's report (`ugvsense bench`) print them.
///
/// Thread-safety: a plain value. RT-safe: yes (no allocation), when the clock is.

#include <array>
#include <cstdint>

namespace ugv::vision {

/// The stages in the order of a frame's path. The census matcher splits its time into Census .. Speckle; an OpenCV
/// matcher mode counts all of it (and the copy into its padded buffers) as MatchOther.
enum class VisionStage : std::uint8_t {
    MatchOther, ///< the matcher's input copies; all of an OpenCV mode's compute()
    Census,     ///< census transform of both images
    Cost,       ///< per-pixel matching cost (Hamming + intensity) of every disparity
    Aggregate,  ///< the semi-global path sums and the winner per pixel
    LeftRight,  ///< the left-right consistency check
    Speckle,    ///< the speckle filter
    Ground,     ///< the ground estimate (RANSAC plane on the disparity)
    Warp,       ///< the left image warped onto the right through the ground's homography
    Mismatch,   ///< the ground-mismatch stage (edges that disagree with the warp)
    Verify,     ///< the obstacle verifier (a second look at every obstacle pixel)
    Sectors,    ///< the sector builder
};
inline constexpr int kVisionStageCount = 11;

/// "census", "cost", ... as in reports and JSON.
const char* stageName(VisionStage stage) noexcept;

/// A clock for the stage times: nanoseconds on a monotonic scale (MonotonicClock::nowNs).
using StageClock = std::int64_t (*)() noexcept;

struct VisionStageTimes {
    std::array<std::int64_t, kVisionStageCount> ns{};
    StageClock clock = nullptr; ///< none: nothing is timed (every stage stays 0)

    void clear() noexcept { ns.fill(0); }
    void add(VisionStage stage, std::int64_t durationNs) noexcept { ns[static_cast<std::size_t>(stage)] += durationNs; }
    [[nodiscard]] std::int64_t operator[](VisionStage stage) const noexcept
    {
        return ns[static_cast<std::size_t>(stage)];
    }
    [[nodiscard]] std::int64_t totalNs() const noexcept
    {
        std::int64_t sum = 0;
        for (const std::int64_t v : ns) {
            sum += v;
        }
        return sum;
    }
};

/// Adds the time since the last lap (or construction) to a stage: `lap.to(VisionStage::Census)` after the census.
/// Does nothing without times or without a clock.
class StageLap {
public:
    explicit StageLap(VisionStageTimes* times) noexcept
        : times_(times != nullptr && times->clock != nullptr ? times : nullptr),
          lastNs_(times_ != nullptr ? times_->clock() : 0)
    {
    }
    void to(VisionStage stage) noexcept
    {
        if (times_ == nullptr) {
            return;
        }
        const std::int64_t now = times_->clock();
        times_->add(stage, now - lastNs_);
        lastNs_ = now;
    }

private:
    VisionStageTimes* times_;
    std::int64_t lastNs_;
};

} // namespace ugv::vision
