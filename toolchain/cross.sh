#!/usr/bin/env bash
# Cross-build the whole project for aarch64 (Debian 12's aarch64-linux-gnu-g++ against an arm64 sysroot) and run
# the unit tests under qemu-user (see toolchain/README.md):
#   toolchain/cross.sh           everything below in order: deps, sysroot, build, test
#   toolchain/cross.sh deps      only install the missing host packages (cross compiler, qemu-user, mmdebstrap)
#   toolchain/cross.sh sysroot   only make the arm64 sysroot (reused when it is complete)
#   toolchain/cross.sh build     deps + sysroot + configure and build the preset aarch64 into build/aarch64
#   toolchain/cross.sh test      the emulated unit tests of the cross build (ctest through qemu-aarch64)
# Environment: UGV_SYSROOT (sysroot folder, default build/sysroot-arm64), UGV_CROSS_JOBS (build jobs, default 2),
# UGV_CROSS_TESTS (ctest -R regex of the test executables to run, default below), UGV_CROSS_EXCLUDE (ctest -E regex,
# default below), UGV_CROSS_TIMEOUT (seconds per test, default 900).
# The native builds (build/release, build/asan) are not touched.
set -euo pipefail
cd "$(dirname "$0")/.."

sysroot=${UGV_SYSROOT:-$PWD/build/sysroot-arm64}
jobs=${UGV_CROSS_JOBS:-2}
# The unit executables run under qemu: vision's kernels, rt, the correlator, platform, the simulator and the hal
# backends on fakes. The others need what qemu-user lacks or takes too long (see toolchain/README.md).
tests=${UGV_CROSS_TESTS:-'^unit-(vision|vision-ground|vision-detect|vision-colour|rt|platform|correlator|correlator-sim|sim|hal)\.'}
# Excluded: gtest death tests in the "threadsafe" style re-execute the test binary with execv(), which fails with
# "Exec format error" without binfmt_misc (qemu-user does not follow a foreign exec); the "fast" style (fork only)
# works and runs.
excludes=${UGV_CROSS_EXCLUDE:-'^unit-platform\.LogLevelsEnvDeathTest\.'}
timeout=${UGV_CROSS_TIMEOUT:-900}

# Host programs: the cross compiler, qemu-user (runs the arm64 tests), mmdebstrap (makes the sysroot), and what the
# native build needs anyway to run on the host during the cross build (cmake, ninja, pkg-config, fastddsgen).
host_packages=(
    g++-aarch64-linux-gnu qemu-user mmdebstrap
    cmake ninja-build pkg-config fastddsgen default-jre-headless
)

# arm64 packages of the sysroot (apt adds their dependencies): libc and libstdc++ headers and start files, and the
# -dev package of everything the project's CMake finds. OpenCV comes as its module packages (libopencv-dev would pull
# every module, gdal and vtk); the top-level CMakeLists.txt finds them without a CMake config when cross-compiling.
sysroot_packages=(
    libc6-dev libstdc++-12-dev linux-libc-dev
    libopencv-core-dev libopencv-imgproc-dev libopencv-calib3d-dev libopencv-imgcodecs-dev
    libyaml-cpp-dev libeigen3-dev nlohmann-json3-dev libgeographiclib-dev zlib1g-dev
    iceoryx libiceoryx-posh-dev libiceoryx-hoofs-dev libacl1-dev
    libsystemd-dev libcamera-dev libv4l-dev
    libfastrtps-dev libfastcdr-dev
    libgtest-dev libgmock-dev libbenchmark-dev
)

script=cross.sh
# shellcheck source=toolchain/apt.sh
source toolchain/apt.sh

phase_start=0
phase() { echo "== $*"; phase_start=$(date +%s); }
phase_done() { echo "== $1: $(( $(date +%s) - phase_start )) s wall"; }

deps() { install_missing "${host_packages[@]}"; }

# Absolute symlinks inside the sysroot (libfoo.so -> /lib/aarch64-linux-gnu/libfoo.so.1) would point at the host's
# files: make them relative, inside the sysroot.
fix_symlinks() {
    local link target
    while IFS= read -r -d '' link; do
        target=$(readlink "$link")
        [[ $target == /* ]] || continue
        ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$sysroot$target")" "$link"
    done < <(find "$sysroot" -type l -print0)
}

# Debian's Fast DDS and Fast-CDR CMake configs name their files with an absolute /usr prefix (the others derive it
# from the config's own location): point them into the sysroot the toolchain file sets as CMAKE_SYSROOT.
fix_cmake_configs() {
    local dir=$sysroot/usr/lib/aarch64-linux-gnu/cmake
    sed -i -E 's|"/usr([/"])|"${CMAKE_SYSROOT}/usr\1|g' "$dir"/fastcdr/*.cmake "$dir"/fastrtps/*.cmake
}

# Debian selects the BLAS and LAPACK that OpenCV core loads through update-alternatives in a maintainer script, which
# an extract-only sysroot never runs: link the reference implementations the packages brought.
fix_alternatives() {
    local lib dir=$sysroot/usr/lib/aarch64-linux-gnu
    for lib in blas lapack; do
        if [ ! -e "$dir/lib$lib.so.3" ] && [ -e "$dir/$lib/lib$lib.so.3" ]; then
            ln -sfn "$lib/lib$lib.so.3" "$dir/lib$lib.so.3"
        fi
    done
}

make_sysroot() {
    local stamp=$sysroot/.ugv-sysroot
    local want
    want=$(printf '%s\n' "${sysroot_packages[@]}" | sha256sum | cut -c1-16)
    if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
        echo "cross.sh: reusing the sysroot $sysroot ($(du -sh "$sysroot" | cut -f1))"
        return
    fi
    rm -rf "$sysroot"
    mkdir -p "$(dirname "$sysroot")"
    # The host's Debian sources (bookworm, updates, security) as the mirror list; extract = unpack the packages and
    # their dependencies without running any arm64 maintainer script (nothing is executed for arm64).
    as_root mmdebstrap --variant=extract --architectures=arm64 --include="$(IFS=,; echo "${sysroot_packages[*]}")" \
        bookworm "$sysroot" /etc/apt/sources.list.d/debian.sources
    fix_symlinks
    fix_cmake_configs
    fix_alternatives
    echo "$want" >"$stamp"
    echo "cross.sh: sysroot $sysroot: $(du -sh "$sysroot" | cut -f1)"
}

build() {
    UGV_SYSROOT=$sysroot cmake --preset aarch64 >/dev/null
    cmake --build --preset aarch64 -j "$jobs"
}

run_tests() {
    # UGV_UNDER_QEMU: the tests turn OpenCV's thread pool off (it spins forever under qemu-user 7.2).
    UGV_UNDER_QEMU=1 ctest --preset aarch64 -R "$tests" -E "$excludes" --timeout "$timeout" -j "$jobs"
}

case "${1:-all}" in
    deps) deps ;;
    sysroot)
        deps
        phase "sysroot (arm64 packages into $sysroot)"; make_sysroot; phase_done sysroot ;;
    build)
        deps
        phase "sysroot"; make_sysroot; phase_done sysroot
        phase "cross build (preset aarch64, -j $jobs)"; build; phase_done "cross build" ;;
    test)
        phase "emulated tests (qemu-aarch64, ctest -R '$tests')"; status=0; run_tests || status=$?
        phase_done "emulated tests"; exit $status ;;
    all)
        deps
        phase "sysroot"; make_sysroot; phase_done sysroot
        phase "cross build (preset aarch64, -j $jobs)"; build; phase_done "cross build"
        phase "emulated tests (qemu-aarch64, ctest -R '$tests')"; status=0; run_tests || status=$?
        phase_done "emulated tests"; exit $status ;;
    *) echo "usage: toolchain/cross.sh [deps|sysroot|build|test]" >&2; exit 2 ;;
esac
