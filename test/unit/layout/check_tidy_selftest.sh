#!/usr/bin/env bash
# lint-tidy-selftest and lint-nolint-selftest: the checks catch what is planted in tidy_bad/ and let the NOLINTs with
# reasons pass, so a broken .clang-tidy (a check switched off by a typo, no config found) fails here.
# Usage: check_tidy_selftest.sh SOURCE_DIR tidy|nolint
set -u
src=${1:?usage: check_tidy_selftest.sh SOURCE_DIR tidy|nolint}
here=$src/test/unit/layout
tidy=$(command -v clang-tidy-14 || command -v clang-tidy || true)
if [ -z "$tidy" ]; then
    echo "SKIP: clang-tidy is not installed (Debian 12: apt-get install clang-tidy; toolchain/host.sh deps does it)"
    exit 77
fi
fail() { echo "FAIL: $1"; exit 1; }

case ${2:-} in
tidy)
    out=$("$tidy" --quiet --config-file="$src/.clang-tidy" "$here/tidy_bad/planted.cpp" -- -std=c++20 2>&1)
    rc=$?
    echo "$out"
    [ $rc -ne 0 ] || fail "clang-tidy passed the planted file (exit 0): are the checks on and errors?"
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
    echo "lint-tidy self-test OK: ${#lines[@]} planted findings reported, the NOLINTs with reasons respected"
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
*) echo "usage: check_tidy_selftest.sh SOURCE_DIR tidy|nolint"; exit 2 ;;
esac
