#include "ugv/tool/other_core_load.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>

#include <gtest/gtest.h>

namespace ugv::tool {
namespace {

/// True while `pid` names a live process or an unreaped child (kill's existence check).
bool exists(pid_t pid)
{
    return ::kill(pid, 0) == 0 || errno != ESRCH;
}

bool haveStressNg()
{
    return std::system("command -v stress-ng > /dev/null 2>&1") == 0;
}

TEST(OtherCoreLoad, RunsUntilDestroyedAndIsReapedThen)
{
    if (!haveStressNg()) {
        GTEST_SKIP() << "stress-ng is not installed (apt-get install stress-ng; toolchain/host.sh deps does)";
    }
    pid_t pid = 0;
    {
        OtherCoreLoad load;
        ASSERT_TRUE(load.start(0, 1.0).has_value());
        pid = load.pid();
        ASSERT_GT(pid, 0);
        EXPECT_TRUE(load.running());
        EXPECT_TRUE(exists(pid));
    }
    EXPECT_FALSE(exists(pid)); // ended and reaped by the destructor: no zombie left
}

// A load that ends early (killed by someone else) is reported ended, reaped once, and its pid never signalled again
// (by then it may name another process).
TEST(OtherCoreLoad, ALoadThatEndsEarlyIsReportedEndedAndNotSignalledAgain)
{
    if (!haveStressNg()) {
        GTEST_SKIP() << "stress-ng is not installed (apt-get install stress-ng; toolchain/host.sh deps does)";
    }
    OtherCoreLoad load;
    ASSERT_TRUE(load.start(0, 1.0).has_value());
    const pid_t pid = load.pid();
    ASSERT_EQ(::kill(pid, SIGKILL), 0);
    for (int i = 0; i < 200 && load.running(); ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    EXPECT_FALSE(load.running());
    EXPECT_EQ(load.pid(), 0);
    EXPECT_FALSE(exists(pid));
}

TEST(OtherCoreLoad, AMissingProgramIsAnErrorWithTheFix)
{
    const char* path = std::getenv("PATH");
    const std::string saved = path != nullptr ? path : "";
    ASSERT_EQ(::setenv("PATH", "/nonexistent", 1), 0);
    OtherCoreLoad load;
    const auto started = load.start(0, 1.0);
    ASSERT_EQ(::setenv("PATH", saved.c_str(), 1), 0);
    ASSERT_FALSE(started.has_value());
    EXPECT_NE(started.error().message().find("stress-ng"), std::string::npos);
    EXPECT_NE(started.error().message().find("apt-get install stress-ng"), std::string::npos);
    EXPECT_FALSE(load.running());
}

} // namespace
} // namespace ugv::tool
