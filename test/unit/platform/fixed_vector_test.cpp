#include "ugv/platform/fixed_vector.hpp"

#include <numeric>
#include <string>

#include <gtest/gtest.h>

namespace {

using ugv::FixedVector;

TEST(FixedVector, StartsEmpty)
{
    const FixedVector<int, 3> sut;
    EXPECT_EQ(sut.size(), 0U);
    EXPECT_TRUE(sut.empty());
    EXPECT_FALSE(sut.full());
    EXPECT_EQ(sut.begin(), sut.end());
    EXPECT_TRUE(sut.span().empty());
    EXPECT_EQ((FixedVector<int, 3>::capacity()), 3U);
}

TEST(FixedVector, PushBackOneElement)
{
    FixedVector<int, 3> sut;
    ASSERT_TRUE(sut.push_back(7));
    ASSERT_EQ(sut.size(), 1U);
    EXPECT_EQ(sut[0], 7);
    EXPECT_FALSE(sut.empty());
}

TEST(FixedVector, FillsToCapacityThenRefuses)
{
    FixedVector<int, 3> sut;
    EXPECT_TRUE(sut.push_back(1));
    EXPECT_TRUE(sut.push_back(2));
    EXPECT_TRUE(sut.emplace_back(3));
    EXPECT_TRUE(sut.full());
    EXPECT_FALSE(sut.push_back(4));
    EXPECT_FALSE(sut.emplace_back(5));
    ASSERT_EQ(sut.size(), 3U);
    EXPECT_EQ(sut[2], 3);
}

TEST(FixedVector, EmplaceBackConstructsFromArguments)
{
    FixedVector<std::string, 2> sut;
    ASSERT_TRUE(sut.emplace_back(3U, 'x'));
    ASSERT_EQ(sut.size(), 1U);
    EXPECT_EQ(sut[0], "xxx");
}

TEST(FixedVector, IteratesAndSpansOnlyUsedElements)
{
    FixedVector<int, 8> sut;
    for (int i = 1; i <= 4; ++i) {
        ASSERT_TRUE(sut.push_back(i));
    }
    constexpr int kExpectedSum = 10;
    EXPECT_EQ(std::accumulate(sut.begin(), sut.end(), 0), kExpectedSum);
    const auto& constSut = sut;
    EXPECT_EQ(std::accumulate(constSut.begin(), constSut.end(), 0), kExpectedSum);
    EXPECT_EQ(constSut.span().size(), 4U);
    EXPECT_EQ(sut.span()[3], 4);
    EXPECT_EQ(constSut[1], 2);
}

TEST(FixedVector, ClearEmptiesAndAllowsReuse)
{
    FixedVector<int, 2> sut;
    ASSERT_TRUE(sut.push_back(1));
    ASSERT_TRUE(sut.push_back(2));
    sut.clear();
    EXPECT_TRUE(sut.empty());
    EXPECT_TRUE(sut.push_back(9));
    EXPECT_EQ(sut[0], 9);
}

TEST(FixedVectorDeathTest, IndexPastSizeIsABug)
{
    FixedVector<int, 4> sut;
    ASSERT_TRUE(sut.push_back(1));
    EXPECT_DEATH(static_cast<void>(sut[1]), "precondition failed");
}

} // namespace
