#include "ugv/rt/memory.hpp"

#include <malloc.h>
#include <pthread.h>
#include <sys/mman.h>
#include <sys/resource.h>

#include <cerrno>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace {

int gLockFlags = 0;
int lockOk(int flags)
{
    gLockFlags = flags;
    return 0;
}
int lockRefused(int /*flags*/)
{
    return EPERM;
}
int malloptOk(int /*option*/, int /*value*/)
{
    return 0;
}
int malloptRefused(int /*option*/, int /*value*/)
{
    return EINVAL;
}

ugv::rt::SysOps ops(int (*lock)(int), int (*mallopt)(int, int))
{
    auto result = ugv::rt::realSysOps();
    result.lockAll = lock;
    result.mallocOption = mallopt;
    return result;
}

TEST(LockMemory, AllStepsAcceptedNoWarnings)
{
    const auto sut = ugv::rt::lockMemory(ops(&lockOk, &malloptOk));
    EXPECT_TRUE(sut.locked);
    EXPECT_TRUE(sut.mallocTuned);
    EXPECT_TRUE(sut.warnings.empty());
    EXPECT_EQ(gLockFlags, MCL_CURRENT | MCL_FUTURE);
    EXPECT_TRUE(sut.lockedBytes.has_value());
}

TEST(LockMemory, RefusedMlockallDegradesToOneWarningWithFix)
{
    const auto sut = ugv::rt::lockMemory(ops(&lockRefused, &malloptOk));
    EXPECT_FALSE(sut.locked);
    EXPECT_TRUE(sut.mallocTuned);
    ASSERT_EQ(sut.warnings.size(), 1U);
    EXPECT_NE(sut.warnings[0].find("mlockall): Operation not permitted (EPERM)"), std::string::npos) << sut.warnings[0];
    EXPECT_NE(sut.warnings[0].find("LimitMEMLOCK=infinity"), std::string::npos);
}

TEST(LockMemory, RefusedMalloptDegradesToOneWarning)
{
    const auto sut = ugv::rt::lockMemory(ops(&lockOk, &malloptRefused));
    EXPECT_TRUE(sut.locked);
    EXPECT_FALSE(sut.mallocTuned);
    ASSERT_EQ(sut.warnings.size(), 1U);
    EXPECT_NE(sut.warnings[0].find("mallopt"), std::string::npos);
}

TEST(LockMemory, RealCallsLockOrDegrade)
{
    if (!ugv::test::mallocFamilyCounted()) { // a sanitizer build: it owns malloc
        GTEST_SKIP() << "mlockall(MCL_CURRENT) would try to lock the sanitizer's terabytes of shadow memory";
    }
    const auto sut = ugv::rt::lockMemory();
    if (sut.locked) {
        ASSERT_TRUE(sut.lockedBytes.has_value());
        EXPECT_GT(*sut.lockedBytes, 0U);
    } else {
        ASSERT_FALSE(sut.warnings.empty());
    }
    ::munlockall();
    ::mallopt(M_MMAP_MAX, 65536); // glibc's default again, for the rest of this test process
}

TEST(LockedBytesFromStatus, ParsesVmLckInKilobytes)
{
    constexpr std::size_t kExpected = 1234UL * 1024UL;
    EXPECT_EQ(ugv::rt::lockedBytesFromStatus("Name:\tx\nVmLck:\t    1234 kB\nVmPin:\t0 kB\n"), kExpected);
    EXPECT_EQ(ugv::rt::lockedBytesFromStatus("VmLck:\t0 kB\n"), 0U);
}

TEST(LockedBytesFromStatus, MissingOrMalformedIsNullopt)
{
    EXPECT_FALSE(ugv::rt::lockedBytesFromStatus("").has_value());
    EXPECT_FALSE(ugv::rt::lockedBytesFromStatus("Name:\tx\n").has_value());
    EXPECT_FALSE(ugv::rt::lockedBytesFromStatus("VmLck:\tlots\n").has_value());
    EXPECT_FALSE(ugv::rt::lockedBytesFromStatus("VmLck:\t12 MB\n").has_value());
    EXPECT_FALSE(ugv::rt::lockedBytesFromStatus("XVmLck:\t12 kB\n").has_value()); // key must start a line
}

TEST(StatusBytes, ReadsTheNamedFieldOnly)
{
    constexpr std::string_view kStatus = "Name:\tx\nVmRSSX:\t7 kB\nVmLck:\t1 kB\nVmRSS:\t  52100 kB\n";
    EXPECT_EQ(ugv::rt::statusBytes(kStatus, "VmRSS"), 52100UL * 1024UL); // not VmRSSX, whose name only starts so
    EXPECT_EQ(ugv::rt::statusBytes(kStatus, "VmLck"), 1024U);
    EXPECT_FALSE(ugv::rt::statusBytes(kStatus, "VmHWM").has_value());
    const auto rss = ugv::rt::readStatusBytes("VmRSS");
    ASSERT_TRUE(rss.has_value());
    EXPECT_GT(*rss, 0U);
}

TEST(ReadLockedBytes, ReadsThisProcess)
{
    EXPECT_TRUE(ugv::rt::readLockedBytes().has_value());
}

TEST(PrefaultStack, ZeroAndSomeBytes)
{
    EXPECT_EQ(ugv::rt::prefaultStack(0), 0U);
    constexpr std::size_t kBytes = 64UL * 1024UL;
    const ugv::test::AllocationScope scope;
    EXPECT_EQ(ugv::rt::prefaultStack(kBytes), kBytes);
    EXPECT_EQ(scope.count(), 0U);
}

/// Touches `bytes` of stack and returns the minor page faults that took (this thread).
[[gnu::noinline]] long faultsTouching(std::size_t bytes)
{
    rusage before{};
    ::getrusage(RUSAGE_THREAD, &before);
    ugv::rt::prefaultStack(bytes); // the touch itself
    rusage after{};
    ::getrusage(RUSAGE_THREAD, &after);
    return after.ru_minflt - before.ru_minflt;
}

struct FaultRun {
    bool prefault = false;
    long faults = -1;
};

void* faultThread(void* arg)
{
    auto& run = *static_cast<FaultRun*>(arg);
    constexpr std::size_t kTouch = 128UL * 1024UL;
    if (run.prefault) {
        ugv::rt::prefaultStack(2 * kTouch);
    }
    run.faults = faultsTouching(kTouch);
    return nullptr;
}

/// Runs faultThread on a fresh, never-touched mmap'd stack.
[[maybe_unused]] long faultsOnFreshStack(bool prefault)
{
    constexpr std::size_t kStackBytes = 1024UL * 1024UL;
    void* stack = ::mmap(nullptr, kStackBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (stack == MAP_FAILED) {
        return -1;
    }
    ::madvise(stack, kStackBytes, MADV_NOHUGEPAGE);
    pthread_attr_t attr;
    ::pthread_attr_init(&attr);
    ::pthread_attr_setstack(&attr, stack, kStackBytes);
    FaultRun run{prefault, -1};
    pthread_t thread{};
    if (::pthread_create(&thread, &attr, &faultThread, &run) == 0) {
        ::pthread_join(thread, nullptr);
    }
    ::pthread_attr_destroy(&attr);
    ::munmap(stack, kStackBytes);
    return run.faults;
}

TEST(PrefaultStack, TouchedStackTakesNoFaultsLater)
{
    if (!ugv::test::mallocFamilyCounted()) { // a sanitizer build: it owns malloc
        GTEST_SKIP() << "sanitizers move stack frames to their own fake stacks and shadow memory";
    }
    const long withoutPrefault = faultsOnFreshStack(false);
    const long withPrefault = faultsOnFreshStack(true);
    EXPECT_GT(withoutPrefault, 0);
    EXPECT_EQ(withPrefault, 0);
}

} // namespace
