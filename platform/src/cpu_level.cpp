// Compiled for the plain x86-64 level whatever UGV_CPU is (platform/CMakeLists.txt): this code runs on the CPUs
// the rest of the build may not.
#include "ugv/platform/cpu_level.hpp"

#include <cstdio>
#include <cstdlib>
#include <string>

#ifndef UGV_BUILT_CPU_LEVEL
#define UGV_BUILT_CPU_LEVEL ""
#endif

namespace ugv {

std::string_view builtCpuLevel() noexcept
{
    return UGV_BUILT_CPU_LEVEL;
}

bool cpuRuns(std::string_view level) noexcept
{
#if defined(__x86_64__)
    __builtin_cpu_init();
    if (level == "x86-64-v3") {
        return __builtin_cpu_supports("x86-64-v3") != 0;
    }
    if (level == "x86-64-v2") {
        return __builtin_cpu_supports("x86-64-v2") != 0;
    }
#endif
    (void)level;
    return true;
}

Result<void, Error> checkCpuLevel(std::string_view program, std::string_view level, bool cpuRunsLevel)
{
    if (cpuRunsLevel) {
        return {};
    }
    return Unexpected(Error{"instruction set",
                            "this build is for " + std::string(level) + " CPUs and this CPU is not one (" +
                                std::string(program) + " needs " +
                                (level == "x86-64-v3" ? "AVX2, FMA and BMI2" : "SSE4.2 and POPCNT") + ")",
                            "rebuild with 'cmake -DUGV_CPU=x86-64' (runs on any x86-64 CPU) or install a "
                            "package built that way"});
}

void exitUnlessCpuRunsBuild(const char* program) noexcept
{
    const std::string_view level = builtCpuLevel();
    if (auto ok = checkCpuLevel(program, level, cpuRuns(level)); !ok) {
        std::fprintf(stderr, "%s: error: %s\n", program, ok.error().message().c_str());
        std::_Exit(1);
    }
}

} // namespace ugv
