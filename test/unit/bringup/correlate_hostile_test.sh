#!/usr/bin/env bash
# `ugvsense correlate` on hostile input (issue 22): absurd finite numbers (range_m 1e19, 1e308, a duplicate key with
# 1e300, t 1e17) and a 1 MB line are refused naming the line and the field; a jump in time from 1 to 1e9 s writes a bounded number of
# snapshots and says so; an object at the largest range accepted still draws a map (cv::ellipse aborted before).
# Usage: correlate_hostile_test.sh UGVSENSE WORKDIR
set -u
tool=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
obs() { # t track range bearing
    printf '{"t": %s, "kind": "observation", "ugv": "ugv-1", "track": "%s", "class": "static", "ugv_lat": -34.9, "ugv_lon": 138.6, "ugv_heading_deg": 90, "range_m": %s, "bearing_deg": %s}\n' "$@"
}
{
    obs 0.0 a 10 0    # line 1
    obs 0.5 b 1e19 0  # 2: absurd range
    echo '{"t": 0.6, "kind": "observation", "ugv": "ugv-1", "track": "c", "class": "static", "ugv_lat": -34.9, "ugv_lon": 138.6, "ugv_heading_deg": 90, "range_m": 10, "range_m": 1e300, "bearing_deg": 0}' # 3
    obs 0.7 d 1e308 0 # 4: NaN positions before
    obs 1e17 a 10 0   # 5: snapshots forever before
    obs 1.0 a 10 0
    obs 1.0 e 99999 45 # 7: the largest range accepted
    obs 1e9 a 10 0    # 8: a jump of 1e9 s
    obs 1e9 e 99999 45
    printf '{"t": 1e9, "kind": "observation", "x": "%s"}\n' "$(head -c 1000000 /dev/zero | tr '\0' x)" # 10: 1 MB
} >"$work/obs.jsonl"
out=$(timeout 60 "$tool" correlate --mode original --input "$work/obs.jsonl" --output "$work/snap.jsonl" \
    --map "$work/map.png" 2>&1)
rc=$?
echo "$out"
[ $rc -eq 0 ] || { echo "exit $rc, expected 0"; exit 1; }
for want in "obs.jsonl:2: skipped: field 'range_m' value 1e+19 is outside [0, 100000] m" \
    "obs.jsonl:3: skipped: field 'range_m' is given twice" \
    "obs.jsonl:4: skipped: field 'range_m' value 1e+308 is outside" \
    "obs.jsonl:5: skipped: field 't' value 1e+17 is outside [-1e+10, 1e+10] s" \
    "obs.jsonl:8: field 't' jumps from 1 to 1e+09 s: wrote 1000 snapshots of the gap and skipped 999998999" \
    "999998999 snapshot(s) skipped over jumps in time (at most 1000 are written for one gap)" \
    "obs.jsonl:10: skipped: line over 65536 bytes" "5 bad line(s) skipped" "map of t 1000000000.0 written"; do
    grep -qF -- "$want" <<<"$out" || { echo "missing: $want"; exit 1; }
done
lines=$(wc -l <"$work/snap.jsonl")
[ "$lines" -le 1002 ] || { echo "$lines snapshots, expected at most 1002"; exit 1; }
! grep -q null "$work/snap.jsonl" || { echo "a snapshot holds null"; exit 1; }
[ -s "$work/map.png" ] || { echo "no map written"; exit 1; }
# An object at the largest range accepted, seen long enough to be shown (its 2-sigma ellipse is kilometres long).
for t in 0 1 2 3 4 5 6; do obs $t e 99999 45; obs $t a 10 0; done >"$work/far.jsonl"
out=$(timeout 60 "$tool" correlate --input "$work/far.jsonl" --output "$work/far.jsonl.out" --map "$work/far.png" 2>&1)
rc=$?
echo "$out"
[ $rc -eq 0 ] && grep -qF "2 object(s) at t 6.0" <<<"$out" && [ -s "$work/far.png" ] ||
    { echo "far object: exit $rc, expected 2 objects and a map"; exit 1; }
echo "OK"
