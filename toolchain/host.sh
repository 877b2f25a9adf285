#!/usr/bin/env bash
# One entry point for a fresh Debian 12 host (see README "Quick start"):
#   toolchain/host.sh run    install missing packages, build (release), run the main job on the embedded default
#   toolchain/host.sh test   install missing packages, build (release, asan, tsan, fuzz), run every test with a summary
#   toolchain/host.sh deps   only install the Debian packages
#   toolchain/host.sh build  only configure and build the release preset
#   toolchain/host.sh package  build the release preset and the Debian package (build/release/package/*.deb)
# Environment: UGV_SHARED_DATA (real test data, default ../shared/data), UGV_SKIP_ASAN=1, UGV_SKIP_TSAN=1,
# UGV_SKIP_FUZZ=1 (test: skip that preset).
set -euo pipefail
cd "$(dirname "$0")/.."

# Debian 12 packages: what each is for is in README.md "Dependencies".
packages=(
    g++ cmake ninja-build pkg-config ccache
    libopencv-dev          # core/imgproc/calib3d (service), imgcodecs (host tool), with CMake config
    libyaml-cpp-dev        # service config file
    libeigen3-dev          # small dense linear algebra (ground plane, correlator)
    zlib1g-dev             # CRC-32 of recording records (hal/recording)
    iceoryx libiceoryx-posh-dev libiceoryx-hoofs-dev libacl1-dev   # shared-memory frame and sector rings (RouDi + posh)
    libsystemd-dev         # sd_notify: READY and the watchdog of the service unit
    libcamera-dev          # the libcamera camera backend
    libgeographiclib-dev   # WGS84 <-> local tangent plane (correlator)
    nlohmann-json3-dev     # JSON lines of the correlator's offline tools
    libfastrtps-dev fastddsgen fastdds-tools default-jre-headless   # DDS: Fast DDS 2.9, IDL generator (Java), discovery server
    cyclonedds-dev cyclonedds-tools   # a second DDS (Cyclone 0.10, idlc): the interop test, test/interop
    iproute2 nftables      # the multi-host test: network namespaces and packet loss
    openssl                # DDS Security: bringup/deploy/security/make_security.sh (CA, certificates, signed XML)
    libgtest-dev libgmock-dev libbenchmark-dev   # tests and benchmarks
    clang-tidy             # static analysis: the lint-tidy.* tests (.clang-tidy, README "Static analysis")
    clang libclang-rt-14-dev   # the asan preset's compiler (half GCC's CPU time for that build) and the fuzz preset
    stress-ng              # the soak: a load on the other core (ugvsense soak --load-other-core)
    procps python3         # pgrep (run command, service tests), python3 (the fake systemd notify socket in a test)
    qemu-user              # an older x86-64 CPU for the CPU-level check's test (and aarch64 for cross.sh)
    systemd dpkg-dev file adduser util-linux   # systemd-analyze (unit tests), the .deb (CPack: dpkg-shlibdeps, file), its test
)

script=host.sh
# shellcheck source=toolchain/apt.sh
source toolchain/apt.sh

deps() { install_missing "${packages[@]}"; }

build() {
    local preset=$1
    local launcher=()
    command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
    cmake --preset "$preset" "${launcher[@]}" >/dev/null
    cmake --build --preset "$preset" -j "$(nproc)"
}

run_main_job() {
    local tool=build/release/bringup/ugvsense service=build/release/bringup/ugvsensed out=build/run
    local recording=build/default.ugvrec
    rm -rf "$out" && mkdir -p "$out"
    echo "== 1/5 calibrate: chessboard pairs seen by a known stereo rig (ugvsense sim), calibrated and rectified"
    "$tool" sim --scene chessboard --out "$out/pairs" --pairs 12
    "$tool" calibrate --images "$out/pairs" --board 9x6 --square 0.025 --out "$out/calibration.yaml" \
        --json "$out/calibration.json"
    "$tool" rectify --calib "$out/calibration.yaml" --images "$out/pairs"
    echo "== 2/5 the embedded default recording: the simulator drives the default course (made once, then reused)"
    if ! "$tool" recording info "$recording" >/dev/null 2>&1; then
        "$tool" sim --course default --out "$recording"
    fi
    "$tool" recording info "$recording"
    echo "== 3/5 RouDi (iceoryx): use a running one, else start iox-roudi with bringup/deploy/roudi.toml"
    roudi_pid=""
    if ! pgrep -x iox-roudi >/dev/null; then
        iox-roudi -c bringup/deploy/roudi.toml -m off -l warning >"$out/roudi.log" 2>&1 &
        roudi_pid=$!
        trap 'if [ -n "${roudi_pid:-}" ]; then kill "$roudi_pid" 2>/dev/null || true; fi' EXIT
        for _ in $(seq 50); do [ -S /tmp/roudi ] && break; sleep 0.1; done
    fi
    echo "== 4/5 ugvsensed replays the recording at its recorded pace (10 fps): sectors every 10th frame, then the latency report"
    "$service" --replay "$recording" --print-every 10
    echo "== 5/5 overlay of frame 60 (obstacles and the red/blue/green sector bar)"
    "$tool" recording export "$recording" --frame 60 --out "$out/frame60" >/dev/null
    "$tool" detect --calib "$out/frame60/calibration.yaml" --left "$out/frame60/frame_000060_left.png" \
        --right "$out/frame60/frame_000060_right.png" --overlay "$out/overlay.png" --json "$out/sectors.json" | tail -3
    if [ -n "$roudi_pid" ]; then kill "$roudi_pid" 2>/dev/null; wait "$roudi_pid" 2>/dev/null || true; roudi_pid=""; fi
    echo "== done: calibration in $out/calibration.yaml, sectors of frame 60 in $out/sectors.json, overlay $out/overlay.png"
}

# The sanitizer presets the test command builds and runs (UGV_SKIP_ASAN=1 / UGV_SKIP_TSAN=1 leave one out).
sanitizer_presets() {
    if [ "${UGV_SKIP_ASAN:-0}" != 1 ]; then echo asan; fi
    if [ "${UGV_SKIP_TSAN:-0}" != 1 ]; then echo tsan; fi
    if [ "${UGV_SKIP_FUZZ:-0}" != 1 ]; then echo fuzz; fi
}

run_tests() {
    build release
    # The sanitizer builds run in the background at the lowest CPU priority while the release tests run: they take
    # the cycles the tests leave idle (DDS discovery waits, paced replays, the package test's dpkg) and give them
    # back at once to any test that wants them (nice 19 weighs 15 against a test's 1024).
    local presets background_log=build/sanitizer-builds.log background_pid=""
    mapfile -t presets < <(sanitizer_presets)
    if [ ${#presets[@]} -gt 0 ]; then
        echo "== ${presets[*]}: building in the background at nice 19 (log: $background_log)"
        ( renice -n 19 -p "$BASHPID" >/dev/null; for p in "${presets[@]}"; do build "$p"; done ) \
            >"$background_log" 2>&1 &
        background_pid=$!
    fi
    echo "== release: unit and data tests"
    local status=0
    if ! ctest --preset release -j "$(nproc)"; then
        # One more try for the multi-process DDS tests alone (system.team-bus.*): Fast DDS's discovery of a process
        # restarted after SIGKILL, or of a secured participant's handshakes, sometimes misses its 60 s
        # (eProsima/Fast-DDS#3822; a rerun on the same machine passes). Any other failure stands.
        local failed=build/release/Testing/Temporary/LastTestsFailed.log
        if [ -s "$failed" ] && ! grep -qv ':system[.]team-bus[.]' "$failed"; then
            echo "== release: the team-bus tests that failed, once more: $(cut -d: -f2 "$failed" | tr '\n' ' ')"
            ctest --preset release --rerun-failed || status=1
        else
            status=1
        fi
    fi
    if [ -n "$background_pid" ]; then
        echo "== ${presets[*]}: waiting for the background builds"
        if ! wait "$background_pid"; then
            cat "$background_log"
            echo "host.sh: the ${presets[*]} build failed (its output above)" >&2
            return 1
        fi
        grep -E '^\[[0-9]+/[0-9]+\] Linking' "$background_log" | tail -n 2 || true
    fi
    if [ "${UGV_SKIP_ASAN:-0}" != 1 ]; then
        echo "== asan (address + undefined sanitizers): unit tests"
        # new_delete_type_mismatch=0: Fast DDS 2.9.1 itself deletes its StatisticsReaderImpl through RTPSReader with
        # the smaller size (a Debian libfastrtps bug, not ours); every other ASan check stays on.
        ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:new_delete_type_mismatch=0 \
            UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
            ctest --preset asan -j "$(nproc)" || status=1
    fi
    if [ "${UGV_SKIP_TSAN:-0}" != 1 ]; then
        echo "== tsan (thread sanitizer): the unit tests that start threads (platform, rt, the service)"
        ctest --preset tsan -j "$(nproc)" || status=1
    fi
    if [ "${UGV_SKIP_FUZZ:-0}" != 1 ]; then
        echo "== fuzz (libFuzzer, coverage-guided, ASan + UBSan): 5 s of each target from its kept corpus"
        bash toolchain/fuzz.sh --seconds 5 || status=1
    fi
    return $status
}

case "${1:-}" in
    deps) deps ;;
    build) deps; build release ;;
    package) deps; build release; cpack --config build/release/CPackConfig.cmake -B build/release/package ;;
    run) deps; build release; run_main_job ;;
    test) deps; run_tests ;;
    *) echo "usage: toolchain/host.sh run|test|deps|build|package" >&2; exit 2 ;;
esac
