#include "ugv/platform/cpu_level.hpp"

#include <string>
#include <string_view>

#include <gtest/gtest.h>

namespace {

TEST(CpuLevel, TheBuildNamesALevelThisMachineRuns)
{
#if defined(__x86_64__)
    const std::string_view level = ugv::builtCpuLevel();
    EXPECT_TRUE(level == "x86-64" || level == "x86-64-v2" || level == "x86-64-v3") << level;
    EXPECT_TRUE(ugv::cpuRuns(ugv::builtCpuLevel())) << "the tests run where they were built";
#else
    EXPECT_STREQ(ugv::builtCpuLevel(), "");
#endif
    EXPECT_TRUE(ugv::cpuRuns("x86-64"));
    EXPECT_TRUE(ugv::cpuRuns(""));
}

TEST(CpuLevel, TheErrorNamesTheProgramTheLevelAndTheFix)
{
    char line[512];
    const int length = ugv::formatCpuLevelError(line, sizeof(line), "ugvsensed", "x86-64-v3");
    const std::string text(line);
    EXPECT_EQ(length, static_cast<int>(text.size()));
    EXPECT_NE(text.find("ugvsensed: error: instruction set: this build is for x86-64-v3 CPUs and this CPU is not "
                        "one (ugvsensed needs AVX2, FMA and BMI2)"),
              std::string::npos)
        << text;
    EXPECT_NE(text.find("(fix: rebuild with 'cmake -DUGV_CPU=x86-64'"), std::string::npos) << text;

    ugv::formatCpuLevelError(line, sizeof(line), "ugvsense", "x86-64-v2");
    EXPECT_NE(std::string(line).find("(ugvsense needs SSE4.2 and POPCNT)"), std::string::npos) << line;
}

} // namespace
