#!/usr/bin/env bash
# `ugvsense record` against the running service, three processes as on the vehicle: iox-roudi (bringup/deploy/roudi.toml),
# ugvsensed replaying a 12-frame simulator course, and the recorder writing the first 8 pairs it sees; the written
# recording must hold 8 complete frames in sequence. Then the same from a colour camera (a BGR course: RouDi's 2 MiB
# pool, the service's grey conversion), recorded in colour. Usage: record_test.sh UGVSENSE UGVSENSED ROUDI_TOML WORKDIR RECORDING
set -u
tool=$1 service=$2 config=$3 work=$4 recording=$5
rm -rf "$work" && mkdir -p "$work"
command -v iox-roudi >/dev/null || { echo "iox-roudi not installed (package iceoryx)"; exit 1; }
if pgrep -x iox-roudi >/dev/null; then echo "another iox-roudi runs: this test needs its own"; exit 1; fi
iox-roudi -c "$config" -m off -l warning >"$work/roudi.log" 2>&1 &
roudi=$!
trap 'kill $roudi 2>/dev/null; wait $roudi 2>/dev/null' EXIT
for _ in $(seq 50); do [ -S /tmp/roudi ] && break; sleep 0.1; done
"$tool" recording export "$recording" --frame 0 --out "$work/f0" >/dev/null || exit 1
"$tool" record --out "$work/recorded.ugvrec" --calib "$work/f0/calibration.yaml" --frames 8 --seconds 60 \
    >"$work/record.log" 2>&1 &
recorder=$!
sleep 1.5 # the recorder subscribes before the service publishes its first pair
"$service" --replay "$recording" --print-every 0 >"$work/service.log" 2>&1 || { cat "$work/service.log"; exit 1; }
wait $recorder || { echo "record failed:"; cat "$work/record.log"; exit 1; }
cat "$work/record.log"
info=$("$tool" recording info "$work/recorded.ugvrec") || { echo "$info"; exit 1; }
echo "$info"
grep -q "frames: 8 complete (sequence 0..7, 0 missing" <<<"$info" || { echo "expected 8 frames in sequence"; exit 1; }
# A colour camera: BGR frames through RouDi's pools to the service and the recorder, which records them in colour.
"$tool" sim --course default --frames 6 --colour --out "$work/colour.ugvrec" >/dev/null || exit 1
"$tool" record --out "$work/recorded-colour.ugvrec" --calib "$work/f0/calibration.yaml" --frames 4 --seconds 60 \
    >"$work/record-colour.log" 2>&1 &
recorder=$!
sleep 1.5
"$service" --replay "$work/colour.ugvrec" --print-every 0 >"$work/service-colour.log" 2>&1 ||
    { cat "$work/service-colour.log"; exit 1; }
wait $recorder || { echo "record (colour) failed:"; cat "$work/record-colour.log"; exit 1; }
info=$("$tool" recording info "$work/recorded-colour.ugvrec") || { echo "$info"; exit 1; }
echo "$info"
grep -q "640x480 colour (BGR) stereo" <<<"$info" || { echo "expected a colour recording"; exit 1; }
grep -q "frames: 4 complete (sequence 0..3, 0 missing" <<<"$info" || { echo "expected 4 colour frames"; exit 1; }
# Every colour pair went into the ring (a slow build may drop some at the vision task: latest frame wins).
grep -q "of 6 captured.*; bad 0; loan failures 0;" "$work/service-colour.log" ||
    { echo "the service refused colour frames:"; cat "$work/service-colour.log"; exit 1; }
# No service publishing: the recorder gives up after --seconds, says why, exits 1 and leaves no file behind.
out=$("$tool" record --out "$work/empty.ugvrec" --calib "$work/f0/calibration.yaml" --seconds 1 2>&1)
rc=$?
echo "$out"
[ $rc -eq 1 ] || { echo "record without frames: exit $rc, expected 1"; exit 1; }
grep -q "no frame arrived; nothing written (is ugvsensed running?)" <<<"$out" || { echo "missing message"; exit 1; }
[ ! -e "$work/empty.ugvrec" ] || { echo "an empty recording was left behind"; exit 1; }
