#include "ugv/hal/sys_call.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cstring>
#include <utility>

#include <gtest/gtest.h>

namespace ugv::hal {
namespace {

int gCalls = 0;

int failWithEintrTwiceThenSucceed()
{
    if (++gCalls <= 2) {
        errno = EINTR;
        return -1;
    }
    return 42;
}

int alwaysEintr()
{
    ++gCalls;
    errno = EINTR;
    return -1;
}

TEST(SysCall, ReturnsTheValueOnSuccess)
{
    const auto sut = sysCall(::getpid);

    ASSERT_TRUE(sut.has_value());
    EXPECT_EQ(*sut, ::getpid());
}

TEST(SysCall, RetriesEintr)
{
    gCalls = 0;
    const auto sut = sysCall(failWithEintrTwiceThenSucceed);

    ASSERT_TRUE(sut.has_value());
    EXPECT_EQ(*sut, 42);
    EXPECT_EQ(gCalls, 3);
}

TEST(SysCall, GivesUpOnEndlessEintr)
{
    gCalls = 0;
    const auto sut = sysCall(alwaysEintr);

    ASSERT_FALSE(sut.has_value());
    EXPECT_EQ(sut.error().code, EINTR);
    EXPECT_EQ(gCalls, 101);
}

TEST(SysCall, ReportsErrnoWithNameAndText)
{
    const auto sut = sysCall(::open, "/nonexistent/ugv-device", O_RDONLY);

    ASSERT_FALSE(sut.has_value());
    EXPECT_EQ(sut.error().code, ENOENT);
    EXPECT_STREQ(sut.error().name(), "ENOENT");
    EXPECT_STREQ(sut.error().text(), "No such file or directory");
}

TEST(SysCall, UnknownErrnoHasFallbackStrings)
{
    constexpr SysError kOdd{99999};

    EXPECT_STREQ(kOdd.name(), "errno");
    EXPECT_STREQ(kOdd.text(), "unknown error");
}

bool isOpen(int fd)
{
    return ::fcntl(fd, F_GETFD) != -1;
}

TEST(UniqueFd, ClosesWhenDestroyedOrAssignedOverAndAMoveLeavesTheSourceEmpty)
{
    int ends[2] = {-1, -1};
    ASSERT_EQ(::pipe(ends), 0);
    {
        UniqueFd a(ends[0]);
        UniqueFd b(ends[1]);
        UniqueFd moved(std::move(a));
        EXPECT_FALSE(a.valid()); // the moved-from state
        EXPECT_EQ(moved.get(), ends[0]);
        moved = std::move(b); // closes ends[0]
        EXPECT_FALSE(isOpen(ends[0]));
        EXPECT_TRUE(isOpen(ends[1]));
        EXPECT_EQ(moved.get(), ends[1]);
    }
    EXPECT_FALSE(isOpen(ends[1])); // closed by the destructor

    ASSERT_EQ(::pipe(ends), 0);
    UniqueFd kept(ends[0]);
    const int released = kept.release();
    EXPECT_FALSE(kept.valid());
    EXPECT_TRUE(isOpen(released)); // release() gives it up unclosed
    EXPECT_EQ(::close(released), 0);
    EXPECT_EQ(::close(ends[1]), 0);
}

} // namespace
} // namespace ugv::hal
