#!/usr/bin/env bash
# The checker must exit 1, name each of the six planted violations in bad_tree/, and pass the tool's allowed includes.
set -u
here=$(cd "$(dirname "$0")" && pwd)
out=$(bash "$here/check_deps.sh" "$here/bad_tree")
rc=$?
echo "$out"
[ $rc -eq 1 ] || { echo "FAIL: expected exit 1, got $rc"; exit 1; }
for expected in "uses_hal.cpp:2: vision/ includes ugv/hal/" "uses_vision.hpp:2: platform/ includes ugv/vision/" \
                "uses_imgcodecs.cpp:2: hal/ includes a host-tool" \
                "uses_tool.cpp:2: bringup/service/ includes ugv/tool/" \
                "uses_vision.cpp:2: bringup/sim/ includes ugv/vision/" \
                "uses_imgcodecs.cpp:2: bringup/adapters/ includes a host-tool"; do
    grep -qF "$expected" <<<"$out" || { echo "FAIL: violation not reported: $expected"; exit 1; }
done
if grep -qF "allowed.cpp" <<<"$out"; then
    echo "FAIL: an include the tool may make was reported"; exit 1
fi
echo "lint-deps self-test OK"
