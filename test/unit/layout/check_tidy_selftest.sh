#!/usr/bin/env bash
# lint-tidy-selftest and lint-nolint-selftest: the checks catch what is planted in tidy_bad/ and let the NOLINTs with
# reasons pass, so a broken .clang-tidy (a check switched off by a typo, no config found) fails here.
# Usage: check_tidy_selftest.sh SOURCE_DIR tidy|unity|nolint
set -u
src=${1:?usage: check_tidy_selftest.sh SOURCE_DIR tidy|unity|nolint}
here=$src/test/unit/layout
tidy=$(command -v clang-tidy-14 || command -v clang-tidy || true)
if [ -z "$tidy" ]; then
    echo "SKIP: clang-tidy is not installed (Debian 12: apt-get install clang-tidy; toolchain/host.sh deps does it)"
    exit 77
fi
fail() { echo "FAIL: $1"; exit 1; }

# Every "// finding: CHECK" line of planted.cpp is reported in OUT, and no line a NOLINT allows.
expect_planted() {
    local out=$1 entry line check allowed
    mapfile -t lines < <(grep -n '// finding: ' "$here/tidy_bad/planted.cpp")
    for entry in "${lines[@]}"; do
        line=${entry%%:*} check=${entry##*finding: }
        grep -qE "planted\.cpp:$line:[0-9]+: error: .*\[$check(,|\])" <<<"$out" ||
            fail "line $line: $check not reported"
    done
    for allowed in $(grep -n 'allowed, with its reason' "$here/tidy_bad/planted.cpp" | cut -d: -f1); do
        if grep -q 'NOLINTNEXTLINE' <(sed -n "${allowed}p" "$here/tidy_bad/planted.cpp"); then allowed=$((allowed + 1)); fi
        if grep -qE "planted\.cpp:$allowed:[0-9]+: error" <<<"$out"; then fail "line $allowed: reported despite its NOLINT"; fi
    done
}

case ${2:-} in
tidy)
    out=$("$tidy" --quiet --config-file="$src/.clang-tidy" "$here/tidy_bad/planted.cpp" -- -std=c++20 2>&1)
    rc=$?
    echo "$out"
    [ $rc -ne 0 ] || fail "clang-tidy passed the planted file (exit 0): are the checks on and errors?"
    expect_planted "$out"
    echo "lint-tidy self-test OK: the planted findings reported, the NOLINTs with reasons respected"
    ;;
unity)
    # check_tidy.sh checks a target's files as one unity file: the planted file's findings must still be reported
    # at its own lines (and the .clang-tidy of the source tree used, not clang-tidy's defaults), beside a clean file
    # of the same target, and a source file included by another is reported as bugprone-suspicious-include would.
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    mkdir -p "$tmp/src/vision/src" "$tmp/build"
    cp "$src/.clang-tidy" "$tmp/src/"
    cp "$here/tidy_bad/planted.cpp" "$tmp/src/vision/src/planted.cpp"
    printf 'namespace {\nint helperValue() { return 1; }\n} // namespace\nint usesHelper() { return helperValue(); }\n' \
        >"$tmp/src/vision/src/clean.cpp"
    printf 'int partValue() { return 2; }\n' >"$tmp/src/vision/src/part.cc"
    printf '#include "part.cc"\n' >"$tmp/src/vision/src/includer.cpp"
    for f in clean planted includer; do
        printf '{"directory": "%s", "command": "clang++ -std=c++20 -o vision/CMakeFiles/t.dir/src/%s.o -c %s", "file": "%s"}\n' \
            "$tmp/build" "$f" "$tmp/src/vision/src/$f.cpp" "$tmp/src/vision/src/$f.cpp"
    done | paste -sd, | sed 's/^/[/; s/$/]/' >"$tmp/build/compile_commands.json"
    out=$(bash "$here/check_tidy.sh" "$tmp/src" "$tmp/build" vision 2>&1)
    rc=$?
    echo "$out"
    [ $rc -eq 1 ] || fail "check_tidy.sh exited $rc on a target with planted findings (expected 1)"
    expect_planted "$out"
    grep -qE "includer\.cpp:1:.*\[bugprone-suspicious-include\]" <<<"$out" || fail "the included part.cc not reported"
    grep -q "3 translation units of vision/ (share 1/1) in 1 unity file" <<<"$out" || fail "not one unity file of 3"
    if grep -qE "clean\.cpp:[0-9]+:" <<<"$out"; then fail "a finding reported in the clean file"; fi
    echo "lint-tidy unity self-test OK: one unity file of 3, each finding at its own file and line"
    ;;
nolint)
    out=$(bash "$here/check_nolint.sh" "$here/tidy_bad/nolint_tree" "$src")
    rc=$?
    echo "$out"
    [ $rc -eq 1 ] || fail "expected exit 1, got $rc"
    for expected in "bad.cpp:2: a NOLINT without the checks" "bad.cpp:3: NOLINT(readability-magic-numbers): readability-magic-numbers is not on" \
                    "bad.cpp:4: NOLINT(cppcoreguidelines-avoid-non-const-global-variables) without a reason" \
                    "bad.cpp:5: NOLINT(*-avoid-non-const-global-variables): a wildcard" \
                    "bad_test.cpp:2: a NOLINT outside the product folders"; do
        grep -qF "$expected" <<<"$out" || fail "not reported: $expected"
    done
    if grep -qF "bad.cpp:6:" <<<"$out"; then fail "a NOLINT with an enabled check and its reason was reported"; fi
    echo "lint-nolint self-test OK"
    ;;
*) echo "usage: check_tidy_selftest.sh SOURCE_DIR tidy|unity|nolint"; exit 2 ;;
esac
