#!/usr/bin/env bash
# `ugvsense correlate` on a small hand-written input: good lines make objects and snapshots; every kind of bad
# line (malformed JSON, missing field, wrong type, NaN, latitude out of range, unknown kind, unknown id, before the
# first line's time) is reported with its line number and skipped while the run goes on; a line out of time order
# within the late window is put in its place (with --late-window-s 0 it is refused); --map writes an image.
# Usage: correlate_test.sh UGVSENSE WORKDIR
set -u
tool=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
obs() { # t ugv track class range bearing
    printf '{"t": %s, "kind": "observation", "ugv": "%s", "track": "%s", "class": "%s", "ugv_lat": -34.9, "ugv_lon": 138.6, "ugv_heading_deg": 90, "range_m": %s, "bearing_deg": %s}\n' "$@"
}
{
    obs 0.0 ugv-1 a static 10 0          # line 1
    obs 0.5 ugv-1 a static 10 0
    obs 1.0 ugv-1 a static 10 0
    echo '{"t": 1.2, "kind": "observation", "ugv": "ugv-1"'                                    # 4: malformed
    echo '{"t": 1.3, "kind": "observation", "ugv": "ugv-1", "track": "a", "class": "static"}' # 5: missing fields
    obs 1.4 ugv-1 a static '"ten"' 0                                                          # 6: wrong type
    obs 1.5 ugv-1 a static NaN 0                                                              # 7: NaN
    echo '{"t": 1.6, "kind": "uav", "class": "mobile", "lat": 95.0, "lon": 138.6}'            # 8: latitude
    echo '{"t": 1.7, "kind": "teleport"}'                                                     # 9: unknown kind
    echo '{"t": 1.8, "kind": "confirm", "id": "ooi-42", "state": "confirmed_positive"}'       # 10: unknown id
    echo '{"t": 1.9, "kind": "confirm", "id": "ooi-1", "state": "confirmed_positive"}'        # 11: good
    obs 0.1 ugv-2 b static 10 0                                                               # 12: late, in place
    obs 2.5 ugv-2 m mobile 20 10                                                              # 13: good
    obs -1.0 ugv-2 b static 10 0                                                              # 14: before the first
} >"$work/obs.jsonl"
out=$("$tool" correlate --mode original --input "$work/obs.jsonl" --output "$work/snap.jsonl" --map "$work/map.png" 2>&1)
rc=$?
echo "$out"
[ $rc -eq 0 ] || { echo "exit $rc, expected 0"; exit 1; }
for want in "obs.jsonl:4: skipped: not valid JSON" "obs.jsonl:5: skipped: missing field 'ugv_lat'" \
    "obs.jsonl:6: skipped: field 'range_m' is not a number" "obs.jsonl:7: skipped: not valid JSON" \
    "obs.jsonl:8: skipped: uav latitude 95.000000 is outside -90..90" "obs.jsonl:9: skipped: unknown kind 'teleport'" \
    "obs.jsonl:10: skipped: confirm: unknown object id 'ooi-42'" \
    "obs.jsonl:14: skipped: time -1.000000 is before the earliest time held for a replay (0.000000" \
    "correlated 6 message(s) (1 late, put in place by replaying 5), 8 bad line(s) skipped"; do
    grep -qF -- "$want" <<<"$out" || { echo "missing: $want"; exit 1; }
done
last=$(tail -n 1 "$work/snap.jsonl")
echo "$last"
grep -q '"id":"ooi-1"' <<<"$last" && grep -q '"state":"confirmed_positive"' <<<"$last" &&
    grep -q '"class":"mobile"' <<<"$last" || { echo "last snapshot lacks the confirmed static or the mobile object"; exit 1; }
[ "$(wc -l <"$work/snap.jsonl")" -ge 3 ] || { echo "expected a snapshot per second"; exit 1; }
[ -s "$work/map.png" ] || { echo "no map written"; exit 1; }
# The default mode (pose-corrected) reads the same lines the same way.
out=$("$tool" correlate --input "$work/obs.jsonl" --output "$work/snap-pose-corrected.jsonl" 2>&1) || { echo "$out"; exit 1; }
echo "$out"
grep -qF "correlated 6 message(s) (1 late, put in place by replaying 5), 8 bad line(s) skipped" <<<"$out" &&
    grep -q "mode pose-corrected" <<<"$out" || { echo "pose-corrected mode: unexpected summary"; exit 1; }
# Without a late window the line out of time order is refused.
out=$("$tool" correlate --input "$work/obs.jsonl" --output "$work/snap-strict.jsonl" --late-window-s 0 2>&1)
echo "$out"
grep -qF "obs.jsonl:12: skipped: time 0.100000 is before the previous message's 1.900000 (fix: sort the input by time)" \
    <<<"$out" && grep -qF "correlated 5 message(s) (0 late" <<<"$out" || { echo "--late-window-s 0: unexpected"; exit 1; }
grep -q '"id":"ooi-1"' "$work/snap-pose-corrected.jsonl" || { echo "pose-corrected mode: no static object"; exit 1; }
# improved is an alias of pose-corrected (its former name): the same snapshots, byte for byte.
out=$("$tool" correlate --mode improved --input "$work/obs.jsonl" --output "$work/snap-improved.jsonl" 2>&1) ||
    { echo "$out"; exit 1; }
grep -q "mode pose-corrected" <<<"$out" || { echo "--mode improved: not mode pose-corrected"; exit 1; }
cmp "$work/snap-improved.jsonl" "$work/snap-pose-corrected.jsonl" || { echo "--mode improved: other snapshots"; exit 1; }
echo "OK"
