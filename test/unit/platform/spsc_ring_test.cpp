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

TEST(SpscRing, InPlaceClaimAndFrontShareTheRingWithPushAndPop)
{
    SpscRing<int, 2> sut;
    EXPECT_EQ(sut.front(), nullptr);
    int* slot = sut.claim();
    ASSERT_NE(slot, nullptr);
    *slot = 7;
    EXPECT_EQ(sut.front(), nullptr); // not visible before commit()
    sut.commit();
    ASSERT_TRUE(sut.tryPush(8));
    EXPECT_EQ(sut.claim(), nullptr); // full
    int* oldest = sut.front();
    ASSERT_NE(oldest, nullptr);
    EXPECT_EQ(*oldest, 7);
    EXPECT_EQ(sut.front(), oldest); // still there until release()
    sut.release();
    int out = 0;
    ASSERT_TRUE(sut.tryPop(out));
    EXPECT_EQ(out, 8);
    EXPECT_EQ(sut.front(), nullptr);
}

TEST(SpscRing, InPlaceProducerAndConsumerThreadsDeliverEverythingInOrder)
{
    struct Big {
        std::uint64_t first = 0;
        std::uint64_t pad[62] = {};
        std::uint64_t last = 0;
    };
    constexpr std::uint64_t kItems = 100'000;
    SpscRing<Big, 8> sut;
    std::thread producer([&] {
        for (std::uint64_t i = 0; i < kItems;) {
            if (Big* slot = sut.claim(); slot != nullptr) {
                slot->first = i;
                slot->last = i;
                sut.commit();
                ++i;
            }
        }
    });
    std::uint64_t expected = 0;
    bool whole = true;
    while (expected < kItems) {
        if (const Big* oldest = sut.front(); oldest != nullptr) {
            whole = whole && oldest->first == expected && oldest->last == expected; // never torn, in order
            sut.release();
            ++expected;
        }
    }
    producer.join();
    EXPECT_TRUE(whole);
    EXPECT_EQ(sut.size(), 0U);
}

} // namespace
