#include "ugv/hal/replay_camera.hpp"

#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace ugv::hal {
namespace {

using std::chrono::milliseconds;
using std::chrono::nanoseconds;

constexpr std::uint32_t kFrameWidth = 16;
constexpr std::uint32_t kFrameHeight = 4;

/// A clock that only moves when the camera sleeps (or the test advances it); it records every sleep.
struct FakeClock {
    std::int64_t nowNs = 5'000'000'000;
    std::vector<std::int64_t> sleeps;
    static std::int64_t now(void* c) { return static_cast<FakeClock*>(c)->nowNs; }
    static void sleepUntil(void* c, std::int64_t t)
    {
        auto* self = static_cast<FakeClock*>(c);
        self->sleeps.push_back(t);
        self->nowNs = std::max(self->nowNs, t);
    }
    ReplayClock seam() { return ReplayClock{now, sleepUntil, this}; }
};

class ReplayCameraTest : public ::testing::Test {
protected:
    void SetUp() override
    {
        dir_ =
            std::filesystem::temp_directory_path() / ("ugv-replay-test-" + std::to_string(::getpid()) + "-" +
                                                      ::testing::UnitTest::GetInstance()->current_test_info()->name());
        std::filesystem::create_directories(dir_);
        path_ = (dir_ / "r.ugvrec").string();
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    /// Frames with the given sequences and left stamps [ms]; right = left + 1 ms; pixel value = index.
    void record(const std::vector<std::uint64_t>& seqs, const std::vector<std::int64_t>& stampsMs)
    {
        auto writer = RecordingWriter::create(path_, kFrameWidth, kFrameHeight, "calib: 1\n");
        ASSERT_TRUE(writer.has_value());
        Image<std::uint8_t> image(kFrameWidth, kFrameHeight);
        for (std::size_t k = 0; k < seqs.size(); ++k) {
            for (int y = 0; y < static_cast<int>(kFrameHeight); ++y) {
                for (int x = 0; x < static_cast<int>(kFrameWidth); ++x) {
                    image.view().at(x, y) = static_cast<std::uint8_t>(k);
                }
            }
            const std::int64_t stamp = stampsMs[k] * 1'000'000;
            ASSERT_TRUE(
                writer->append(seqs[k], stamp, stamp + 1'000'000, greyViews(image.view(), image.view())).has_value());
        }
    }
    std::unique_ptr<ReplayCamera> open(const ReplayOptions& options)
    {
        auto camera = ReplayCamera::open(path_, options, clock_.seam());
        EXPECT_TRUE(camera.has_value()) << camera.error().message();
        return camera ? std::move(*camera) : nullptr;
    }

    std::filesystem::path dir_;
    std::string path_;
    FakeClock clock_;
};

TEST_F(ReplayCameraTest, RecordedPaceKeepsTheRecordedSpacingAndRestampsOnThisClock)
{
    record({0, 1, 2}, {100, 200, 350});
    auto camera = open({});
    ASSERT_NE(camera, nullptr);
    EXPECT_EQ(camera->width(), 16);
    EXPECT_EQ(camera->period(), nanoseconds(125'000'000)); // (350 - 100) / 2
    EXPECT_EQ(camera->calibrationText(), "calib: 1\n");

    CameraFrame f;
    const std::int64_t start = clock_.nowNs;
    ASSERT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
    EXPECT_EQ(f.leftStampNs, start);
    EXPECT_EQ(f.rightStampNs, start + 1'000'000);
    EXPECT_EQ(f.images.left.at(0, 0), 0);
    ASSERT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
    EXPECT_EQ(f.leftStampNs, start + 100'000'000);
    EXPECT_EQ(f.sequence, 1U);
    ASSERT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
    EXPECT_EQ(f.leftStampNs, start + 250'000'000);
    EXPECT_EQ(f.images.left.at(3, 3), 2);
    EXPECT_EQ(clock_.sleeps, (std::vector<std::int64_t>{start + 100'000'000, start + 250'000'000}));
    EXPECT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::End);
    EXPECT_EQ(camera->stats().frames, 3U);
}

TEST_F(ReplayCameraTest, TimeoutLeavesTheFramePendingUntilItIsDue)
{
    record({0, 1}, {0, 100});
    auto camera = open({});
    CameraFrame f;
    const std::int64_t start = clock_.nowNs;
    ASSERT_EQ(camera->grab(f, milliseconds(10)), GrabStatus::Frame);
    EXPECT_EQ(camera->grab(f, milliseconds(30)), GrabStatus::Timeout); // due in 100 ms
    EXPECT_EQ(clock_.nowNs, start + 30'000'000);
    ASSERT_EQ(camera->grab(f, milliseconds(100)), GrabStatus::Frame);
    EXPECT_EQ(f.sequence, 1U);
    EXPECT_EQ(f.leftStampNs, start + 100'000'000);
}

TEST_F(ReplayCameraTest, ForcedRateAndAsFastAsPossible)
{
    record({0, 1, 2}, {0, 500, 1000});
    ReplayOptions forced;
    forced.pace = ReplayPace::Forced;
    forced.forcedFps = 20.0;
    auto camera = open(forced);
    EXPECT_EQ(camera->period(), nanoseconds(50'000'000));
    CameraFrame f;
    const std::int64_t start = clock_.nowNs;
    for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
        EXPECT_EQ(f.leftStampNs, start + k * 50'000'000);
    }

    ReplayOptions fast;
    fast.pace = ReplayPace::AsFastAsPossible;
    auto quick = open(fast);
    clock_.sleeps.clear();
    for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(quick->grab(f, milliseconds(500)), GrabStatus::Frame);
    }
    EXPECT_TRUE(clock_.sleeps.empty());
}

TEST_F(ReplayCameraTest, LateFrameIsDeliveredAtOnceWithoutABurstAfterIt)
{
    record({0, 1, 2}, {0, 100, 200});
    auto camera = open({});
    CameraFrame f;
    ASSERT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
    clock_.nowNs += 250'000'000; // the consumer was busy for 250 ms
    const std::int64_t late = clock_.nowNs;
    ASSERT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
    EXPECT_EQ(f.leftStampNs, late);
    ASSERT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
    EXPECT_EQ(f.leftStampNs, late + 100'000'000); // the spacing, not an immediate catch-up
}

TEST_F(ReplayCameraTest, LoopContinuesSequencesAndGapsAreCounted)
{
    record({10, 11, 13}, {0, 100, 200}); // frame 12 was lost by the camera
    ReplayOptions loop;
    loop.loop = true;
    loop.pace = ReplayPace::AsFastAsPossible;
    auto camera = open(loop);
    std::vector<std::uint64_t> seqs;
    CameraFrame f;
    for (int k = 0; k < 6; ++k) {
        ASSERT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
        seqs.push_back(f.sequence);
    }
    EXPECT_EQ(seqs, (std::vector<std::uint64_t>{10, 11, 13, 14, 15, 17}));
    EXPECT_EQ(camera->loops(), 1U);
    EXPECT_EQ(camera->stats().sequenceGaps, 2U);
}

TEST_F(ReplayCameraTest, CutOffRecordingReplaysEveryCompleteFrame)
{
    record({0, 1, 2}, {0, 100, 200});
    std::filesystem::resize_file(path_, std::filesystem::file_size(path_) - 10);
    auto camera = open({});
    EXPECT_EQ(camera->recordedFrames(), 2U);
    EXPECT_TRUE(camera->truncated());
    CameraFrame f;
    EXPECT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
    EXPECT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
    EXPECT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::End);
}

TEST_F(ReplayCameraTest, BadInputIsAClearError)
{
    record({}, {});
    auto empty = ReplayCamera::open(path_, {}, clock_.seam());
    ASSERT_FALSE(empty.has_value());
    EXPECT_NE(empty.error().message().find("no complete frame"), std::string::npos) << empty.error().message();

    std::filesystem::remove(path_);
    record({0}, {0});
    ReplayOptions bad;
    bad.pace = ReplayPace::Forced;
    bad.forcedFps = 0.0;
    auto badRate = ReplayCamera::open(path_, bad, clock_.seam());
    ASSERT_FALSE(badRate.has_value());
    EXPECT_NE(badRate.error().message().find("forced rate"), std::string::npos);

    auto missing = ReplayCamera::open((dir_ / "none.ugvrec").string(), {}, clock_.seam());
    ASSERT_FALSE(missing.has_value());
    EXPECT_NE(missing.error().message().find("ENOENT"), std::string::npos);
}

TEST_F(ReplayCameraTest, GrabAllocatesNothingOverHundredsOfLoopedFrames)
{
    record({0, 1, 2, 3}, {0, 33, 66, 100});
    ReplayOptions loop;
    loop.loop = true;
    auto camera = open(loop);
    CameraFrame f;
    ASSERT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
    clock_.sleeps.reserve(1000);

    const ugv::test::ThreadAllocationScope scope;
    for (int k = 0; k < 300; ++k) {
        ASSERT_EQ(camera->grab(f, milliseconds(500)), GrabStatus::Frame);
    }
    EXPECT_EQ(scope.count(), 0U);
}

} // namespace
} // namespace ugv::hal
