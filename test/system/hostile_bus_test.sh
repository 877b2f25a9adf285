#!/usr/bin/env bash
# Hostile input on the bus (issue 6): a ground station (ugvsensed, correlator only) gets a simulator scenario from
# one UGV process, then from an intruder every kind of malformed sample (NaN, latitude +-91, longitude 200, unknown
# class and state, empty names, since_t > until_t), a flood of 5000 valid observations as fast as it can send and
# 2000 more stamped one second apart from now on (a sender faking its clock to pass a guard that meters source time),
# then the whole scenario again from a new UGV process (its first half dropped as duplicates). Checked: the station keeps running and exits cleanly,
# every malformed sample is refused and counted, the flood is cut by the flood guard
# (correlator.max_rate_per_source 500) and counted, the faked stamps beyond correlator.max_clock_skew_ms (5 s,
# the default) refused and counted (all but the first few seconds' worth), every scenario message before and after the attack was applied,
# and the state stayed consistent: `ugvsense correlate` on the station's inputs.jsonl gives its snapshots.jsonl.
# (The intruder's own writer may not get every flood sample acknowledged in time: its exit code is not checked.)
# Usage: hostile_bus_test.sh UGVSENSE UGVSENSED BUS_HOSTILE WORKDIR DOMAIN
set -u
tool=$1 daemon=$2 hostile=$3 work=$4 domain=$5
rm -rf "$work" && mkdir -p "$work"
partition="hostile-test-$$"
gcs=""
cleanup() { [ -n "$gcs" ] && kill -9 "$gcs" 2>/dev/null; wait 2>/dev/null; true; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$work"/*.log; do echo "--- $f"; tail -n 20 "$f"; done; exit 1; }

"$tool" correlate-sim --setting drift --ugvs 3 --duration 60 --seed 2 --out "$work/scenario.jsonl" >/dev/null ||
    fail "correlate-sim"
total=$(wc -l <"$work/scenario.jsonl")
half=$((total / 2))
head -n "$half" "$work/scenario.jsonl" >"$work/first.jsonl"
cat >"$work/gcs.yaml" <<YAML
vehicle_id: gcs
vision:
  enabled: false
dds:
  domain_id: $domain
  partition: $partition
correlator:
  enabled: true
  reorder_ms: 1000
  startup_hold_ms: 0
  log_dir: $work/gcs
  max_rate_per_source: 500
YAML
"$daemon" --config "$work/gcs.yaml" >"$work/gcs.log" 2>&1 &
gcs=$!
bus=(--domain "$domain" --partition "$partition")
"$tool" bus-send --input "$work/first.jsonl" --source uav-1 "${bus[@]}" >"$work/first.log" 2>&1 ||
    fail "bus-send --input (first half)"
sleep 2 # applied before the attack (the reorder window is 1 s)
"$hostile" --source intruder --flood 5000 --ahead-flood 2000 "${bus[@]}" >"$work/hostile.log" 2>&1
# The whole scenario from a new process: the first half's lines are duplicates (same sender, same line numbers).
"$tool" bus-send --input "$work/scenario.jsonl" --source uav-1 "${bus[@]}" >"$work/second.log" 2>&1 ||
    fail "bus-send --input (second half, after the attack)"
malformed=$(grep -c ": 1$" "$work/hostile.log")
[ "$malformed" -ge 10 ] || fail "expected at least 10 kinds of malformed sample, the sender lists $malformed"
sleep 3 # the reorder window and the last poll
kill -0 "$gcs" || fail "the ground station died"
kill -TERM "$gcs"
wait "$gcs" || fail "the ground station exited with an error"
gcs=""
line=$(grep "^correlator:" "$work/gcs.log") || fail "no correlator report"
echo "$line"
refused=$(sed -E 's/.* ([0-9]+) refused as malformed.*/\1/' <<<"$line")
flooded=$(sed -E 's/.* ([0-9]+) refused by the flood guard.*/\1/' <<<"$line")
ahead=$(sed -E 's/.*\(([0-9]+) stamped ahead of this host.s clock\).*/\1/' <<<"$line")
[ "$refused" -eq "$malformed" ] || fail "$malformed malformed samples sent, $refused refused as malformed"
[ "$flooded" -gt 0 ] || fail "the flood guard refused nothing of a 5000-sample burst at 500/s"
sent_ahead=$(sed -nE 's/^ahead-flood: ([0-9]+) .*/\1/p' "$work/hostile.log")
[ "${sent_ahead:-0}" -eq 2000 ] || fail "the intruder sent ${sent_ahead:-no} faked-stamp samples, not 2000"
# Stamps 1 s apart pass only while they are within 5 s of the station's clock: the first 5 + (sending time) of them.
[ "$ahead" -ge 1950 ] || fail "only $ahead of 2000 samples stamped up to 2000 s ahead were refused"
# The once-per-run warnings are logged whatever number of per-input warnings came before them (those are capped).
grep -q "sends faster than correlator.max_rate_per_source" "$work/gcs.log" || fail "no flood warning in the log"
grep -q "stamps its samples .* ahead of this host's clock" "$work/gcs.log" || fail "no clock-skew warning in the log"
missing=$(comm -23 <(sort "$work/scenario.jsonl") <(sort "$work/gcs/inputs.jsonl") | wc -l)
[ "$missing" -eq 0 ] || fail "$missing of $total scenario messages were not given to the correlator"
# ... and it took them all (the intruder's valid observations put the second sending behind in time: the late
# window puts those in place).
grep -q " 0 refused by the correlator;" <<<"$line" || fail "the correlator refused inputs"
"$tool" correlate --input "$work/gcs/inputs.jsonl" --output "$work/offline.jsonl" >"$work/offline.log" 2>&1 ||
    fail "offline correlate"
cmp -s "$work/offline.jsonl" "$work/gcs/snapshots.jsonl" || fail "live snapshots differ from the offline tool's"
echo "OK: $malformed malformed refused, $flooded flood samples refused ($ahead of them stamped ahead), all $total" \
    "scenario messages applied"
