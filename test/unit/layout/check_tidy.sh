#!/usr/bin/env bash
# clang-tidy over one folder of the product code, with the checks of the root .clang-tidy (why each is on or off:
# README "Static analysis"). Every translation unit of FOLDER in the build's compile_commands.json is checked, and with
# it our headers (platform/ ... bringup/, include/ and src/; generated code and third-party headers are not ours).
# Usage: check_tidy.sh SOURCE_DIR BUILD_DIR FOLDER [K/N]   -> exit 0 when clean, 1 with every finding, 77 when it
# cannot run. K/N: only the K-th of N equal shares of FOLDER's translation units (a big folder as N tests in parallel).
#
# The files of one target (one compile command) are checked together, as one unity translation unit that includes
# them, the way the sanitizer presets build them (CMAKE_UNITY_BUILD): clang-tidy's matchers walk every header's AST
# (OpenCV, Fast DDS, the standard library) once per translation unit, so one pass over a target's files instead of
# one per file is most of the time saved. A finding names the file and line it is in, as before. The one check that
# a unity file would trip, bugprone-suspicious-include (it includes .cpp files), is checked here by grep instead.
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

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The unity files, one per target of this share, and their compile database: one line per unity file, "N PATH".
if ! units=$(python3 "$(dirname "$0")/tidy_units.py" "$db" "$src" "$folder" "$share" "$work"); then
    echo "FAIL: tidy_units.py could not make the unity files from $db (its error above): rebuild to refresh the database"
    exit 1
fi
if [ -z "$units" ]; then
    echo "FAIL: no translation unit of $folder/ in $db: is FOLDER a code folder of $src?"
    exit 1
fi

ours="^$src/(platform|hal|rt|vision|ipc|correlator|bringup)/([a-z_]+/)?(include|src)/"
status=0 files=0 targets=0
while read -r count unit; do
    files=$((files + count)) targets=$((targets + 1))
    mapfile -t sources < <(grep -oE '"/[^"]+"' "$unit" | tr -d '"')
    # Our headers, and this unity file's own sources wherever they sit (rt/alloc_counter/ is not under src/).
    filter="$ours|^($(printf '%s\n' "${sources[@]}" | sed 's/[.+]/\\&/g' | paste -sd'|'))\$"
    if ! out=$("$tidy" -p "$work" --quiet --config-file="$src/.clang-tidy" --checks=-bugprone-suspicious-include \
        --header-filter="$filter" "$unit" 2>&1); then
        status=1
    fi
    # Print the findings (clang-tidy also prints how many warnings it suppressed in other files: not ours).
    grep -vE '^[0-9]+ warnings? (and [0-9]+ errors? )?generated\.$|^Suppressed [0-9]+ warnings|^Use -header-filter|^Error while processing' <<<"$out" || true
    # bugprone-suspicious-include, as a grep: a .cpp (or .c, .cc, .cxx) file included by one of these sources.
    for f in "${sources[@]}"; do
        found=$(grep -nE '^\s*#\s*include\s*[<"][^>"]+\.(c|cc|cpp|cxx)[>"]' "$f") || continue
        sed "s|^|$f:|; s|\$|  error: suspicious #include of a source file [bugprone-suspicious-include]|" <<<"$found"
        status=1
    done
done <<<"$units"
echo "clang-tidy: $files translation units of $folder/ (share $share) in $targets unity file(s):" \
    "$([ $status -eq 0 ] && echo clean || echo 'findings above')"
if [ $status -ne 0 ]; then
    echo "fix: change the code the finding names; a NOLINT(check) with its reason only where the rule does not fit (README \"Static analysis\")"
fi
exit $status
