#include "ugv/platform/spsc_ring.hpp"

#include <cstdint>
#include <thread>

#include <gtest/gtest.h>

namespace {

using ugv::SpscRing;

TEST(SpscRing, EmptyRingPopsNothing)
{
    SpscRing<int, 4> sut;
    int out = -1;
    EXPECT_FALSE(sut.tryPop(out));
    EXPECT_EQ(out, -1);
    EXPECT_EQ(sut.size(), 0U);
    EXPECT_EQ((SpscRing<int, 4>::capacity()), 4U);
}

TEST(SpscRing, OnePushOnePop)
{
    SpscRing<int, 4> sut;
    ASSERT_TRUE(sut.tryPush(42));
    EXPECT_EQ(sut.size(), 1U);
    int out = 0;
    ASSERT_TRUE(sut.tryPop(out));
    EXPECT_EQ(out, 42);
    EXPECT_EQ(sut.size(), 0U);
}

TEST(SpscRing, FullRingRefusesPushAndKeepsContents)
{
    SpscRing<int, 4> sut;
    for (int i = 0; i < 4; ++i) {
        ASSERT_TRUE(sut.tryPush(i));
    }
    EXPECT_FALSE(sut.tryPush(99));
    EXPECT_EQ(sut.size(), 4U);
    for (int i = 0; i < 4; ++i) {
        int out = -1;
        ASSERT_TRUE(sut.tryPop(out));
        EXPECT_EQ(out, i);
    }
}

TEST(SpscRing, WrapsAroundManyTimesInOrder)
{
    SpscRing<int, 2> sut;
    for (int i = 0; i < 1000; ++i) {
        ASSERT_TRUE(sut.tryPush(i));
        int out = -1;
        ASSERT_TRUE(sut.tryPop(out));
        ASSERT_EQ(out, i);
    }
}

TEST(SpscRing, ProducerAndConsumerThreadsDeliverEverythingInOrder)
{
    constexpr std::uint64_t kItems = 200'000;
    SpscRing<std::uint64_t, 64> sut;
    std::thread producer([&] {
        for (std::uint64_t i = 0; i < kItems;) {
            if (sut.tryPush(i)) {
                ++i;
            }
        }
    });
    std::uint64_t expected = 0;
    bool inOrder = true;
    while (expected < kItems) {
        std::uint64_t out = 0;
        if (sut.tryPop(out)) {
            inOrder = inOrder && out == expected;
            ++expected;
        }
    }
    producer.join();
    EXPECT_TRUE(inOrder);
    EXPECT_EQ(sut.size(), 0U);
}

} // namespace
