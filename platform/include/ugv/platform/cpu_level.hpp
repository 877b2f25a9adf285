#pragma once

/// @file
/// The x86-64 instruction-set level this build was compiled for (UGV_CPU, toolchain/cpu-level.cmake) and whether
/// this CPU runs it. A program built for x86-64-v3 would die of SIGILL at its first AVX2 instruction on an older
/// CPU; the programs check first and say what to do instead.
///
/// Plain C strings and libc only: this code runs on CPUs the rest of the build may not, so it must not call an
/// inline C++ function whose kept copy could come from a file compiled for the higher level.
///
/// Thread-safety: reentrant. RT-safe: no (init only).

#include <cstddef>

namespace ugv {

/// The level this build needs: "x86-64", "x86-64-v2" or "x86-64-v3"; "" on other processors (no check).
[[nodiscard]] const char* builtCpuLevel() noexcept;

/// Whether this CPU runs `level` (true for "" and for levels it does not know: they are not ours to refuse).
[[nodiscard]] bool cpuRuns(const char* level) noexcept;

/// The one-line error of a program whose build this CPU cannot run (what, where and the fix), snprintf-style into
/// `out` of `size` bytes. @return the length of the whole line, as snprintf.
int formatCpuLevelError(char* out, std::size_t size, const char* program, const char* level) noexcept;

/// For the first thing a program does (before its own static initialisers: see ugvsensed_main.cpp): when this CPU
/// cannot run this build, prints the error of formatCpuLevelError to stderr and exits with status 1.
void exitUnlessCpuRunsBuild(const char* program) noexcept;

} // namespace ugv
