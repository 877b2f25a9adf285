// The iceoryx rings with RouDi inside the test process (EmbeddedRouDi). Every test of this executable holds the
// ctest resource lock "iceoryx": one RouDi per machine at a time.

#include "ugv/ipc/iceoryx_rings.hpp"

#include <cstdint>
#include <future>
#include <limits>
#include <memory>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace ugv::ipc {
namespace {

using std::chrono::milliseconds;

constexpr int kWidth = 64;
constexpr int kHeight = 16;

class IceoryxRings : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        auto started = EmbeddedRouDi::start("ugv-ipc-test", packedFrameBytes(PixelFormat::Bgr8, kWidth, kHeight));
        ASSERT_TRUE(started.has_value()) << started.error().message();
        roudi_ = std::move(*started).release();
    }
    static void TearDownTestSuite()
    {
        delete roudi_;
        roudi_ = nullptr;
    }

    void fill(int k)
    {
        for (int y = 0; y < kHeight; ++y) {
            for (int x = 0; x < kWidth; ++x) {
                left_.view().at(x, y) = static_cast<std::uint8_t>(k + x);
                right_.view().at(x, y) = static_cast<std::uint8_t>(k + y);
            }
        }
    }

    static EmbeddedRouDi* roudi_;
    Image<std::uint8_t> left_{kWidth, kHeight};
    Image<std::uint8_t> right_{kWidth, kHeight};
};
EmbeddedRouDi* IceoryxRings::roudi_ = nullptr;

SectorsMessage validMessage(std::uint64_t sequence)
{
    SectorsMessage m;
    initSectors(m.sectors, 8, 60.0F);
    m.sectors.sequence = sequence;
    return m;
}

TEST_F(IceoryxRings, RouDiIsReachableAndASecondOneIsRefused)
{
    EXPECT_TRUE(roudiReachable());
    const auto second = EmbeddedRouDi::start("ugv-ipc-test-2", 1024);
    ASSERT_FALSE(second.has_value());
    EXPECT_NE(second.error().message().find("already runs"), std::string::npos) << second.error().message();
}

// A wait of an hour ends at wake() (the service's stop), whatever the wall clock does meanwhile: without the trigger
// this test waits an hour and ctest's timeout fails it. A wake before the wait ends the next wait; a frame that is
// queued is still taken.
TEST_F(IceoryxRings, WakeEndsAWaitOfAnHourAtOnce)
{
    auto publisher = FramePublisher::create(PixelFormat::Grey8, kWidth, kHeight).value();
    auto vision = FrameSubscriber::create(1).value();
    auto waiting = std::async(std::launch::async, [&] {
        TakenFrame frame;
        return vision->take(frame, std::chrono::hours(1));
    });
    // Until the waiter has surely begun, each wake may be consumed by a wait not yet started: repeat.
    while (waiting.wait_for(milliseconds(20)) != std::future_status::ready) {
        vision->wake();
    }
    EXPECT_EQ(waiting.get(), TakeStatus::Timeout);
    vision->wake(); // before the wait
    TakenFrame frame;
    EXPECT_EQ(vision->takeOldest(frame, std::chrono::hours(1)), TakeStatus::Timeout);
    fill(1);
    ASSERT_TRUE(publisher->publish(7, 10, 17, greyViews(left_.view(), right_.view())));
    vision->wake();
    ASSERT_EQ(vision->take(frame, std::chrono::hours(1)), TakeStatus::Frame);
    EXPECT_EQ(frame.header.sequence, 7U);
    vision->release(frame);
}

TEST_F(IceoryxRings, LatestFrameWinsForTheVisionQueueAndARecorderSeesEveryFrame)
{
    auto publisher = FramePublisher::create(PixelFormat::Grey8, kWidth, kHeight).value();
    auto vision = FrameSubscriber::create(1).value();
    auto recorder = FrameSubscriber::create(4).value();
    auto deep = FrameSubscriber::create(4).value(); // a deep queue read with take(): the newest, the rest dropped
    for (int k = 0; k < 3; ++k) {
        fill(k);
        ASSERT_TRUE(publisher->publish(static_cast<std::uint64_t>(100 + k), 1000 * k, 1000 * k + 7,
                                       greyViews(left_.view(), right_.view())));
    }
    EXPECT_TRUE(publisher->hasSubscribers());

    TakenFrame frame;
    ASSERT_EQ(vision->take(frame, milliseconds(500)), TakeStatus::Frame);
    EXPECT_EQ(frame.header.sequence, 102U); // the two older pairs were discarded, not queued
    EXPECT_EQ(frame.header.rightStampNs, 2007);
    EXPECT_EQ(frame.views.left.at(5, 0), 7);
    EXPECT_EQ(frame.views.right.at(0, 9), 11);
    vision->release(frame);
    EXPECT_EQ(vision->take(frame, milliseconds(10)), TakeStatus::Timeout);

    // A recorder's queue holds every pair: takeOldest() gives each in order, none lost, none twice.
    for (std::uint64_t expected = 100; expected <= 102; ++expected) {
        ASSERT_EQ(recorder->takeOldest(frame, milliseconds(500)), TakeStatus::Frame);
        EXPECT_EQ(frame.header.sequence, expected);
        EXPECT_EQ(frame.views.left.at(5, 0), static_cast<std::uint8_t>(expected - 100 + 5));
        recorder->release(frame);
    }
    EXPECT_EQ(recorder->takeOldest(frame, milliseconds(10)), TakeStatus::Timeout);

    // take() on the same deep queue returns the newest pair and drops the older ones.
    ASSERT_EQ(deep->take(frame, milliseconds(500)), TakeStatus::Frame);
    EXPECT_EQ(frame.header.sequence, 102U);
    deep->release(frame);
    EXPECT_EQ(deep->take(frame, milliseconds(10)), TakeStatus::Timeout);
}

TEST_F(IceoryxRings, ALeftOnlyFrameReachesTheSubscriberFlaggedAndWithoutARightView)
{
    auto publisher = FramePublisher::create(PixelFormat::Grey8, kWidth, kHeight).value();
    auto vision = FrameSubscriber::create(1).value();
    fill(4);
    ASSERT_TRUE(publisher->publish(7, 1000, 0, greyViews(left_.view(), ConstImageViewU8())));
    TakenFrame frame;
    ASSERT_EQ(vision->take(frame, milliseconds(500)), TakeStatus::Frame);
    EXPECT_EQ(frame.header.flags, kFrameLeftOnly);
    EXPECT_EQ(frame.views.left.at(5, 0), left_.view().at(5, 0));
    EXPECT_TRUE(frame.views.right.empty());
    vision->release(frame);
}

TEST_F(IceoryxRings, AColourPairReachesTheSubscriberInColourAndAGreyPairIsRefused)
{
    auto publisher = FramePublisher::create(PixelFormat::Bgr8, kWidth, kHeight).value();
    auto vision = FrameSubscriber::create(1).value();
    Image<BgrPixel> left(kWidth, kHeight);
    Image<BgrPixel> right(kWidth, kHeight);
    left.view().at(5, 1) = BgrPixel{9, 8, 7};
    right.view().at(kWidth - 1, kHeight - 1) = BgrPixel{250, 1, 2};

    ASSERT_TRUE(publisher->publish(3, 100, 101, bgrViews(left.view(), right.view())));
    fill(1);
    EXPECT_FALSE(publisher->publish(4, 200, 201, greyViews(left_.view(), right_.view()))); // not this ring's format
    EXPECT_EQ(publisher->loanFailures(), 1U);
    TakenFrame frame;
    ASSERT_EQ(vision->take(frame, milliseconds(500)), TakeStatus::Frame);
    EXPECT_EQ(frame.header.sequence, 3U);
    EXPECT_GE(frame.bytes, packedFrameBytes(PixelFormat::Bgr8, kWidth, kHeight));
    ASSERT_EQ(frame.views.format, PixelFormat::Bgr8);
    EXPECT_EQ(frame.views.leftBgr.at(5, 1).r, 7);
    EXPECT_EQ(frame.views.rightBgr.at(kWidth - 1, kHeight - 1).b, 250);
    vision->release(frame);
}

TEST_F(IceoryxRings, WrongSizeImagesAreRefusedAndCounted)
{
    auto publisher = FramePublisher::create(PixelFormat::Grey8, kWidth, kHeight).value();
    Image<std::uint8_t> small(kWidth - 1, kHeight);
    EXPECT_FALSE(publisher->publish(1, 0, 0, greyViews(small.view(), right_.view())));
    EXPECT_EQ(publisher->loanFailures(), 1U);
    EXPECT_FALSE(FramePublisher::create(PixelFormat::Grey8, 0, kHeight).has_value());
    EXPECT_FALSE(FrameSubscriber::create(0).has_value());
}

TEST_F(IceoryxRings, AnUnknownPixelFormatIsRefusedByName)
{
    const auto publisher = FramePublisher::create(static_cast<PixelFormat>(0), kWidth, kHeight);
    ASSERT_FALSE(publisher.has_value());
    EXPECT_NE(publisher.error().message().find("unknown pixel format 0"), std::string::npos)
        << publisher.error().message();
    EXPECT_NE(publisher.error().message().find("Grey8 or Bgr8"), std::string::npos) << publisher.error().message();
}

TEST_F(IceoryxRings, SectorsArriveValidatedAndMalformedOnesAreCounted)
{
    auto publisher = SectorsPublisher::create().value();
    auto subscriber = SectorsSubscriber::create(8).value();
    ASSERT_TRUE(publisher->publish(validMessage(5)));
    SectorsMessage bad = validMessage(6);
    bad.sectors.sectors[0].rangeM = std::numeric_limits<float>::quiet_NaN();
    ASSERT_TRUE(publisher->publish(bad));

    SectorsMessage got;
    ASSERT_EQ(subscriber->take(got, milliseconds(500)), TakeStatus::Frame);
    EXPECT_EQ(got.sectors.sequence, 5U);
    EXPECT_EQ(subscriber->take(got, milliseconds(500)), TakeStatus::Malformed);
    EXPECT_EQ(got.sectors.sequence, 5U); // untouched
    EXPECT_EQ(subscriber->malformed(), 1U);
    EXPECT_EQ(subscriber->take(got, milliseconds(10)), TakeStatus::Timeout);
}

TEST_F(IceoryxRings, SteadyStateHandOverAllocatesNothing)
{
    auto publisher = FramePublisher::create(PixelFormat::Grey8, kWidth, kHeight).value();
    auto vision = FrameSubscriber::create(1).value();
    auto sectorsOut = SectorsPublisher::create().value();
    auto sectorsIn = SectorsSubscriber::create(4).value();
    fill(1);
    TakenFrame frame;
    SectorsMessage message = validMessage(0);
    ASSERT_TRUE(publisher->publish(0, 0, 0, greyViews(left_.view(), right_.view())));
    ASSERT_EQ(vision->take(frame, milliseconds(500)), TakeStatus::Frame);
    vision->release(frame);

    const ugv::test::ThreadAllocationScope scope; // this thread: RouDi's own threads are not the frame path
    int frames = 0;
    for (int k = 1; k <= 300; ++k) {
        publisher->publish(static_cast<std::uint64_t>(k), k, k, greyViews(left_.view(), right_.view()));
        if (vision->take(frame, milliseconds(500)) == TakeStatus::Frame) {
            ++frames;
            message.sectors.sequence = frame.header.sequence;
            vision->release(frame);
        }
        sectorsOut->publish(message);
        (void)sectorsIn->take(message, milliseconds(500));
    }
    EXPECT_EQ(scope.count(), 0U);
    EXPECT_EQ(frames, 300);
}

} // namespace
} // namespace ugv::ipc
