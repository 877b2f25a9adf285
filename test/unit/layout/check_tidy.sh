#!/usr/bin/env bash
# clang-tidy over one folder of the product code, with the checks of the root .clang-tidy (why each is on or off:
# README "Static analysis"). Every translation unit of FOLDER in the build's compile_commands.json is checked, and with
# it our headers (platform/ ... bringup/, include/ and src/; generated code and third-party headers are not ours).
# Usage: check_tidy.sh SOURCE_DIR BUILD_DIR FOLDER [K/N]   -> exit 0 when clean, 1 with every finding, 77 when it
# cannot run. K/N: only the K-th of N equal shares of FOLDER's translation units (a big folder as N tests in parallel).
set -u
src=${1:?usage: check_tidy.sh SOURCE_DIR BUILD_DIR FOLDER}
build=${2:?usage: check_tidy.sh SOURCE_DIR BUILD_DIR FOLDER}
folder=${3:?usage: check_tidy.sh SOURCE_DIR BUILD_DIR FOLDER}
share=${4:-1/1}

tidy=$(command -v clang-tidy-14 || command -v clang-tidy || true)
if [ -z "$tidy" ]; then
    echo "SKIP: clang-tidy is not installed (Debian 12: apt-get install clang-tidy; toolchain/host.sh deps does it)"
    exit 77
fi
db=$build/compile_commands.json
if [ ! -f "$db" ]; then
    echo "SKIP: $db is missing: configure with CMAKE_EXPORT_COMPILE_COMMANDS=ON (the presets do)"
    exit 77
fi

mapfile -t files < <(grep -oE "\"file\": *\"$src/$folder/[^\"]+\.cpp\"" "$db" | sed -E 's/.*"file": *"([^"]+)"/\1/' | sort -u)
if [ ${#files[@]} -eq 0 ]; then
    echo "FAIL: no translation unit of $folder/ in $db: is FOLDER a code folder of $src?"
    exit 1
fi
k=${share%/*} n=${share#*/}
mine=()
for i in "${!files[@]}"; do
    [ $((i % n + 1)) -eq "$k" ] && mine+=("${files[$i]}")
done
files=("${mine[@]}")

ours="^$src/(platform|hal|rt|vision|ipc|correlator|bringup)/([a-z_]+/)?(include|src)/"
status=0
for f in "${files[@]}"; do
    if ! out=$("$tidy" -p "$build" --quiet --header-filter="$ours" "$f" 2>&1); then
        status=1
    fi
    # Print the findings (clang-tidy also prints how many warnings it suppressed in other files: not ours).
    grep -vE '^[0-9]+ warnings? (and [0-9]+ errors? )?generated\.$|^Suppressed [0-9]+ warnings|^Use -header-filter|^Error while processing' <<<"$out" || true
done
echo "clang-tidy: ${#files[@]} translation units of $folder/ (share $share): $([ $status -eq 0 ] && echo clean || echo 'findings above')"
if [ $status -ne 0 ]; then
    echo "fix: change the code the finding names; a NOLINT(check) with its reason only where the rule does not fit (README \"Static analysis\")"
fi
exit $status
