# The x86-64 instruction-set level of our own code (UGV_CPU); included by the top-level CMakeLists.txt.
#
# OpenCV's universal intrinsics in code outside OpenCV compile to SSE2 only unless told otherwise: OpenCV's own
# kernels (StereoSGBM, remap) choose AVX2 at run time, ours cannot without this. At x86-64-v3 the same kernels
# run 256-bit AVX2 with hardware min/max and popcount (the census SGM 1.7x faster, measured with bench-detect).
# Results are bit-identical at every level (the SIMD kernels equal their scalar references; -ffp-contract=off
# keeps FMA out of floating-point code), so the golden tests hold everywhere.
#
#   auto       the best level this build machine runs (the default: host.sh builds on the machine that runs it)
#   x86-64     any x86-64 CPU (SSE2)
#   x86-64-v2  SSE4.2, SSSE3, POPCNT (Intel Nehalem 2008, AMD Bulldozer 2011, Atom Silvermont 2013 and later)
#   x86-64-v3  AVX2, FMA, BMI2 (Intel Haswell 2013, AMD Excavator 2015, Zen and later)
#
# The whole project uses one level (no mixing, so no inline function compiled for AVX2 can be picked for SSE2
# code). ugvsensed and ugvsense check at start that the CPU runs the level they were built for and exit with a
# clear error otherwise (platform/cpu_level.hpp). A package for older PCs: configure with -DUGV_CPU=x86-64.
# Other processors (aarch64: NEON is its baseline) ignore UGV_CPU.
set(UGV_CPU "auto" CACHE STRING "x86-64 level of our code: auto, x86-64, x86-64-v2 or x86-64-v3")
set_property(CACHE UGV_CPU PROPERTY STRINGS auto x86-64 x86-64-v2 x86-64-v3)

set(UGV_CPU_LEVEL "")
if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64)$")
    set(UGV_CPU_LEVEL "${UGV_CPU}")
    if(UGV_CPU_LEVEL STREQUAL "auto")
        if(CMAKE_CROSSCOMPILING)
            set(UGV_CPU_LEVEL "x86-64")
        else()
            set(probe "${CMAKE_BINARY_DIR}/cpu_level_probe.cpp")
            file(WRITE "${probe}" [=[
#include <cstdio>
int main()
{
    __builtin_cpu_init();
    std::puts(__builtin_cpu_supports("x86-64-v3") ? "x86-64-v3" : __builtin_cpu_supports("x86-64-v2") ? "x86-64-v2" : "x86-64");
}
]=])
            try_run(probe_ran probe_compiled SOURCES "${probe}" RUN_OUTPUT_VARIABLE probe_output)
            string(STRIP "${probe_output}" probe_output)
            if(probe_compiled AND probe_ran EQUAL 0 AND probe_output MATCHES "^x86-64(-v[23])?$")
                set(UGV_CPU_LEVEL "${probe_output}")
            else()
                set(UGV_CPU_LEVEL "x86-64")
            endif()
        endif()
    elseif(NOT UGV_CPU_LEVEL MATCHES "^x86-64(-v[23])?$")
        message(FATAL_ERROR "UGV_CPU='${UGV_CPU}' is not a level: use auto, x86-64, x86-64-v2 or x86-64-v3")
    endif()
    message(STATUS "x86-64 level of our code: ${UGV_CPU_LEVEL} (UGV_CPU=${UGV_CPU})")

    # OpenCV's headers, outside OpenCV's own build, assume SSE2: name what the level adds so that its universal
    # intrinsics use it (256-bit with CV_AVX2).
    set(opencv_simd "")
    if(UGV_CPU_LEVEL MATCHES "v[23]$")
        list(APPEND opencv_simd CV_SSE3=1 CV_SSSE3=1 CV_SSE4_1=1 CV_SSE4_2=1 CV_POPCNT=1)
    endif()
    if(UGV_CPU_LEVEL STREQUAL "x86-64-v3")
        list(APPEND opencv_simd CV_AVX=1 CV_AVX2=1 CV_FMA3=1 CV_FP16=1)
    endif()
    if(NOT UGV_CPU_LEVEL STREQUAL "x86-64")
        add_compile_options(-march=${UGV_CPU_LEVEL} -ffp-contract=off "SHELL:-include immintrin.h")
        add_compile_definitions(${opencv_simd})
    endif()
endif()
