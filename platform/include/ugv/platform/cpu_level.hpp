#pragma once

/// @file
/// The x86-64 instruction-set level this build was compiled for (UGV_CPU, toolchain/cpu-level.cmake) and whether
/// this CPU runs it. A program built for x86-64-v3 would die of SIGILL at its first AVX2 instruction on an older
/// CPU; the programs check first and say what to do instead.
///
/// Thread-safety: reentrant. RT-safe: no (init only).

#include <string_view>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv {

/// The level this build needs: "x86-64", "x86-64-v2" or "x86-64-v3"; "" on other processors (no check).
[[nodiscard]] std::string_view builtCpuLevel() noexcept;

/// Whether this CPU runs `level` (true for "" and for levels it does not know: they are not ours to refuse).
[[nodiscard]] bool cpuRuns(std::string_view level) noexcept;

/// The error a program gives when the CPU cannot run its build: names the level, the program and the fix.
/// @return success when `cpuRunsLevel`.
Result<void, Error> checkCpuLevel(std::string_view program, std::string_view level, bool cpuRunsLevel);

/// For the first thing a program does (before its own static initialisers: see ugvsensed_main.cpp): when this CPU
/// cannot run this build, prints the error of checkCpuLevel to stderr and exits with status 1.
void exitUnlessCpuRunsBuild(const char* program) noexcept;

} // namespace ugv
