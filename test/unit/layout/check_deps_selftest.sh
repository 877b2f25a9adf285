#!/usr/bin/env bash
# The checker must exit 1 and name each of the three planted violations in bad_tree/.
set -u
here=$(cd "$(dirname "$0")" && pwd)
out=$(bash "$here/check_deps.sh" "$here/bad_tree")
rc=$?
echo "$out"
[ $rc -eq 1 ] || { echo "FAIL: expected exit 1, got $rc"; exit 1; }
for expected in "uses_hal.cpp:2: vision/ includes ugv/hal/" "uses_vision.hpp:2: platform/ includes ugv/vision/" \
                "uses_imgcodecs.cpp:2: hal/ includes a host-tool"; do
    grep -qF "$expected" <<<"$out" || { echo "FAIL: violation not reported: $expected"; exit 1; }
done
echo "lint-deps self-test OK"
