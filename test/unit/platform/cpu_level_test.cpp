#include "ugv/platform/cpu_level.hpp"

#include <gtest/gtest.h>

namespace {

TEST(CpuLevel, TheBuildNamesALevelThisMachineRuns)
{
#if defined(__x86_64__)
    const std::string_view level = ugv::builtCpuLevel();
    EXPECT_TRUE(level == "x86-64" || level == "x86-64-v2" || level == "x86-64-v3") << level;
    EXPECT_TRUE(ugv::cpuRuns(level)) << "the tests run where they were built";
#else
    EXPECT_EQ(ugv::builtCpuLevel(), "");
#endif
    EXPECT_TRUE(ugv::cpuRuns("x86-64"));
    EXPECT_TRUE(ugv::cpuRuns(""));
}

TEST(CpuLevel, ACpuWithoutTheLevelGetsAnErrorNamingItAndTheFix)
{
    EXPECT_TRUE(ugv::checkCpuLevel("ugvsensed", "x86-64-v3", true));
    const auto sut = ugv::checkCpuLevel("ugvsensed", "x86-64-v3", false);
    ASSERT_FALSE(sut);
    const std::string text = sut.error().message();
    EXPECT_NE(text.find("this build is for x86-64-v3 CPUs and this CPU is not one (ugvsensed needs AVX2"),
              std::string::npos)
        << text;
    EXPECT_NE(text.find("-DUGV_CPU=x86-64"), std::string::npos) << text;
}

} // namespace
