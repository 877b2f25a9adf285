#include "alloc_counter.hpp"

#include <array>
#include <cstdlib>
#include <memory>
#include <numeric>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace {

using ugv::test::AllocationScope;
using ugv::test::ThreadAllocationScope;

// Keeps the compiler from removing a new/delete pair (allowed since C++14).
template <class T>
T* escape(T* ptr)
{
    asm volatile("" : : "g"(ptr) : "memory");
    return ptr;
}

TEST(AllocationScope, FreshScopeCountsZero)
{
    const AllocationScope sut;
    EXPECT_EQ(sut.count(), 0U);
}

TEST(AllocationScope, SeesOneNewInt)
{
    const AllocationScope sut;
    delete escape(new int(1));
    EXPECT_EQ(sut.count(), 1U);
}

TEST(AllocationScope, SeesArrayAlignedAndNothrowNew)
{
    struct alignas(64) Wide {
        std::array<char, 64> bytes;
    };
    const AllocationScope sut;
    delete[] escape(new int[3]);
    delete escape(new Wide{});
    delete escape(new (std::nothrow) int(2));
    delete[] escape(new (std::nothrow) Wide[2]);
    EXPECT_EQ(sut.count(), 4U);
}

TEST(AllocationScope, SeesVectorGrowth)
{
    const AllocationScope sut;
    std::vector<int> values;
    values.push_back(1);
    EXPECT_GE(sut.count(), 1U);
}

TEST(AllocationScope, SeesMallocFamilyWhenNotSanitized)
{
    if (!ugv::test::mallocFamilyCounted()) {
        GTEST_SKIP() << "built with ASan/TSan: only operator new is counted";
    }
    const AllocationScope sut;
    void* a = escape(std::malloc(16));
    void* b = escape(std::calloc(2, 8));
    a = escape(std::realloc(a, 64));
    void* c = escape(std::aligned_alloc(64, 64));
    void* d = nullptr;
    ASSERT_EQ(::posix_memalign(&d, 64, 64), 0);
    std::free(a);
    std::free(b);
    std::free(c);
    std::free(d);
    EXPECT_EQ(sut.count(), 5U);
}

TEST(AllocationScope, LoopOverStdArrayCountsNothing)
{
    std::array<int, 256> values{};
    const AllocationScope sut;
    std::iota(values.begin(), values.end(), 0);
    const long sum = std::accumulate(values.begin(), values.end(), 0L);
    EXPECT_EQ(sut.count(), 0U);
    EXPECT_EQ(sum, 255L * 256L / 2L);
}

TEST(AllocationScope, CountsOtherThreadsToo)
{
    const AllocationScope sut;
    std::thread other([] { delete escape(new int(3)); });
    other.join();
    EXPECT_GE(sut.count(), 1U); // the new int (std::thread's own state adds more)
}

TEST(AllocationScope, NestedScopesCountFromTheirOwnStart)
{
    const AllocationScope outer;
    delete escape(new int(1));
    const AllocationScope inner;
    delete escape(new int(2));
    EXPECT_EQ(inner.count(), 1U);
    EXPECT_EQ(outer.count(), 2U);
}

TEST(AllocationScope, NothingCountedAfterTheLastScopeEnds)
{
    std::size_t before = 0;
    {
        const AllocationScope first;
        before = first.count();
    }
    delete escape(new int(1)); // no scope alive: not counted
    const AllocationScope second;
    EXPECT_EQ(before, 0U);
    EXPECT_EQ(second.count(), 0U);
}

TEST(ThreadAllocationScope, CountsOnlyTheCallingThread)
{
    const ThreadAllocationScope sut;
    std::thread other([] {
        for (int i = 0; i < 10; ++i) {
            delete escape(new int(i));
        }
    });
    other.join();
    const std::size_t afterOther = sut.count(); // std::thread allocates its state on this thread
    delete escape(new int(4));
    EXPECT_EQ(sut.count(), afterOther + 1);
    EXPECT_LT(afterOther, 10U);
}

} // namespace
