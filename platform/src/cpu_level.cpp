// Compiled for the plain x86-64 level whatever UGV_CPU is (platform/CMakeLists.txt): this code runs on the CPUs
// the rest of the build may not. Only libc and builtins here (see cpu_level.hpp).
#include "ugv/platform/cpu_level.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>

#ifndef UGV_BUILT_CPU_LEVEL
#define UGV_BUILT_CPU_LEVEL ""
#endif

namespace ugv {

const char* builtCpuLevel() noexcept
{
    return UGV_BUILT_CPU_LEVEL;
}

bool cpuRuns(const char* level) noexcept
{
#if defined(__x86_64__)
    __builtin_cpu_init();
#if defined(__clang__) // clang 14 knows the features, not the level names (the fuzz preset builds with it)
    const bool v2 = __builtin_cpu_supports("sse4.2") && __builtin_cpu_supports("popcnt");
    const bool v3 =
        v2 && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2");
#else
    const bool v2 = __builtin_cpu_supports("x86-64-v2") != 0;
    const bool v3 = __builtin_cpu_supports("x86-64-v3") != 0;
#endif
    if (std::strcmp(level, "x86-64-v3") == 0) {
        return v3;
    }
    if (std::strcmp(level, "x86-64-v2") == 0) {
        return v2;
    }
#endif
    (void)level;
    return true;
}

int formatCpuLevelError(char* out, std::size_t size, const char* program, const char* level) noexcept
{
    const bool v3 = std::strcmp(level, "x86-64-v3") == 0;
    return std::snprintf(out, size,
                         "%s: error: instruction set: this build is for %s CPUs and this CPU is not one (%s needs %s) "
                         "(fix: rebuild with 'cmake -DUGV_CPU=x86-64' (runs on any x86-64 CPU) or install a package "
                         "built that way)",
                         program, level, program, v3 ? "AVX2, FMA and BMI2" : "SSE4.2 and POPCNT");
}

void exitUnlessCpuRunsBuild(const char* program) noexcept
{
    const char* level = builtCpuLevel();
    if (!cpuRuns(level)) {
        char line[512];
        (void)formatCpuLevelError(line, sizeof(line), program, level);
        (void)std::fprintf(stderr, "%s\n", line);
        std::_Exit(1);
    }
}

} // namespace ugv
