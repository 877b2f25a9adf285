#!/usr/bin/env bash
# ugvsensed --wait-roudi (the unit's way to meet a RouDi that is still starting): started before RouDi, the
# service waits and then runs; with no RouDi at all it gives up after the wait with the usual clear error.
# Usage: wait_roudi_test.sh UGVSENSE UGVSENSED ROUDI_TOML WORKDIR RECORDING
set -u
tool=$1 service=$2 config=$3 work=$4 recording=$5
rm -rf "$work" && mkdir -p "$work"
if pgrep -x iox-roudi >/dev/null; then echo "another iox-roudi runs: this test needs its own"; exit 1; fi
roudi=""
trap '[ -n "$roudi" ] && kill $roudi 2>/dev/null; wait 2>/dev/null' EXIT

start=$(date +%s%N)
"$service" --replay "$recording" --wait-roudi 1 --print-every 0 >"$work/none.log" 2>&1
rc=$?
waited_ms=$((($(date +%s%N) - start) / 1000000))
[ $rc -eq 1 ] || { cat "$work/none.log"; echo "FAIL: expected exit 1 without RouDi, got $rc"; exit 1; }
grep -q "no RouDi is running on this machine.*fix: start it first" "$work/none.log" ||
    { cat "$work/none.log"; echo "FAIL: no clear error"; exit 1; }
[ $waited_ms -ge 900 ] || { echo "FAIL: gave up after $waited_ms ms, not the 1 s asked"; exit 1; }
echo "no RouDi: gave up after $waited_ms ms with the clear error"

"$service" --replay "$recording" --loop --frames 4 --wait-roudi 20 --print-every 0 >"$work/late.log" 2>&1 &
svc=$!
sleep 2
kill -0 $svc 2>/dev/null || { cat "$work/late.log"; echo "FAIL: the service did not wait for RouDi"; exit 1; }
iox-roudi -c "$config" -m off -l warning >"$work/roudi.log" 2>&1 &
roudi=$!
wait $svc
rc=$?
[ $rc -eq 0 ] || { cat "$work/late.log"; echo "FAIL: exit $rc once RouDi came"; exit 1; }
grep -q "frames: [4-9] published" "$work/late.log" || { cat "$work/late.log"; echo "FAIL: no frames"; exit 1; }
echo "RouDi 2 s late: the service waited and ran"
