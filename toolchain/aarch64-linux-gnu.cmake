# Cross-compiling for aarch64 (Linux, glibc) with Debian 12's aarch64-linux-gnu-gcc/g++ against an arm64 sysroot
# made by toolchain/cross.sh (Debian bookworm arm64 packages unpacked into a folder). Tests run under qemu-user.
#
#   cmake --preset aarch64      (CMakePresets.json; or -DCMAKE_TOOLCHAIN_FILE=toolchain/aarch64-linux-gnu.cmake)
#
# Sysroot: the cache variable UGV_SYSROOT, else the environment variable UGV_SYSROOT, else build/sysroot-arm64 under
# the source tree.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

if(NOT UGV_SYSROOT)
    if(DEFINED ENV{UGV_SYSROOT} AND NOT "$ENV{UGV_SYSROOT}" STREQUAL "")
        set(UGV_SYSROOT "$ENV{UGV_SYSROOT}")
    else()
        get_filename_component(UGV_SYSROOT "${CMAKE_CURRENT_LIST_DIR}/../build/sysroot-arm64" ABSOLUTE)
    endif()
endif()
set(UGV_SYSROOT "${UGV_SYSROOT}" CACHE PATH "arm64 sysroot (toolchain/cross.sh sysroot makes it)")
if(NOT EXISTS "${UGV_SYSROOT}/usr/include/stdio.h")
    message(FATAL_ERROR "no arm64 sysroot at ${UGV_SYSROOT}: run toolchain/cross.sh sysroot (or set UGV_SYSROOT)")
endif()
# try_compile() projects read this file again: hand them the sysroot.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES UGV_SYSROOT)

set(CMAKE_SYSROOT "${UGV_SYSROOT}")
# The target baseline: ARMv8-A, whose Advanced SIMD (NEON) is what OpenCV's universal intrinsics use on aarch64.
# -ffp-contract=off: GCC fuses a * b + c into one FMA on aarch64 (in C++ even with -std=c++20; NEON's vmulq/vaddq
# are plain vector operators, so the universal-intrinsics kernels are fused too), which rounds differently from x86-64
# (no FMA at its baseline). The ground warp's float source coordinate is rounded to 1/32 px, so fused code changes
# its output bytes; without contraction it is bit-exact with the x86 build (test unit-vision Golden.*).
set(CMAKE_C_FLAGS_INIT "-march=armv8-a -ffp-contract=off")
set(CMAKE_CXX_FLAGS_INIT "-march=armv8-a -ffp-contract=off")

# Libraries, headers and CMake packages from the sysroot only; programs (fastddsgen, pkg-config) from the host.
set(CMAKE_FIND_ROOT_PATH "${UGV_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config (libcamera, libsystemd): the host's pkg-config reads only the sysroot's .pc files and prefixes their
# paths with the sysroot.
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${UGV_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
    "${UGV_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${UGV_SYSROOT}/usr/lib/pkgconfig:${UGV_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# ctest and gtest_discover_tests run the arm64 executables through qemu-user with the sysroot's loader and libraries
# (binfmt_misc is not needed).
find_program(UGV_QEMU_AARCH64 qemu-aarch64 REQUIRED NO_CMAKE_FIND_ROOT_PATH)
set(CMAKE_CROSSCOMPILING_EMULATOR "${UGV_QEMU_AARCH64};-L;${UGV_SYSROOT}")
