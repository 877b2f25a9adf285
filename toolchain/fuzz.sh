#!/usr/bin/env bash
# Fuzzing (issue 22 item 2): the libFuzzer targets of test/fuzz, built with clang (the fuzz preset: ASan + UBSan).
#
#   toolchain/fuzz.sh [--runs N | --seconds S] [TARGET...]
#
# TARGET: config, calibration, recording, correlator_line, dds_sample (default: all). Default length: 60 s each.
# Each run starts from the kept corpus test/fuzz/corpus/TARGET (left as it is) and the inputs of earlier runs in
# build/fuzz/corpus/TARGET, where the new interesting inputs go; a crash, leak, timeout (10 s) or out-of-memory
# (2 GiB) input is written to build/fuzz/crashes/TARGET/ and the script exits 1. Keep a crash input in
# test/fuzz/corpus/TARGET once fixed: ctest's fuzz-replay.TARGET replays that folder on every test run (GCC, the
# release and asan presets). The last line per target: executions, coverage (cov: edges, ft: features) and
# corpus size, as libFuzzer printed them.
set -euo pipefail
cd "$(dirname "$0")/.."

all=(config calibration recording correlator_line dds_sample)
limit=(-max_total_time=60)
targets=()
while [ $# -gt 0 ]; do
    case "$1" in
        --runs) limit=(-runs="$2"); shift 2 ;;
        --seconds) limit=(-max_total_time="$2"); shift 2 ;;
        -h|--help) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        -*) echo "fuzz.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
        *) targets+=("$1"); shift ;;
    esac
done
[ ${#targets[@]} -gt 0 ] || targets=("${all[@]}")

script=fuzz.sh
# shellcheck source=toolchain/apt.sh
source toolchain/apt.sh
if [ -n "$(missing_packages clang libclang-rt-14-dev)" ]; then
    echo "fuzz.sh: clang or libclang-rt-14-dev is missing: apt-get install clang libclang-rt-14-dev (or run toolchain/host.sh deps)" >&2
    exit 1
fi
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake --preset fuzz "${launcher[@]}" >/dev/null
cmake --build --preset fuzz -j "$(nproc)"

status=0
for t in "${targets[@]}"; do
    bin=build/fuzz/test/fuzz/fuzz-$t
    if [ ! -x "$bin" ]; then
        echo "fuzz.sh: no fuzz target '$t' (targets: ${all[*]})" >&2
        exit 2
    fi
    mkdir -p "build/fuzz/corpus/$t" "build/fuzz/crashes/$t"
    log=build/fuzz/$t.log
    echo "fuzz.sh: $t (${limit[*]}), log $log"
    if ! "$bin" "${limit[@]}" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
        -artifact_prefix="build/fuzz/crashes/$t/" "build/fuzz/corpus/$t" "test/fuzz/corpus/$t" >"$log" 2>&1; then
        echo "fuzz.sh: $t FOUND A CRASH: see $log and build/fuzz/crashes/$t/" >&2
        status=1
    fi
    grep -E '^#[0-9]+' "$log" | tail -1 || true
    grep -E '^Done [0-9]+ runs' "$log" || true
done
exit $status
