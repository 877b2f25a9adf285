#!/usr/bin/env bash
# `ugvsense bus-send` and `ugvsense listen` over loopback DDS (two processes on this host):
#   1. a short correlate-sim scenario sent with bus-send --input: every line arrives on its topic (observations,
#      uav, pose_corrections) and each sample's sequence_number is its line number in the file;
#   2. --only-ugv sends that UGV's observations and nothing else;
#   3. bus-hostile (the test tool): listen refuses the 10 hostile observations (stderr "refused: ...", counted) and prints
#      the 5000 valid ones of the flood;
#   4. listen with nobody publishing: exit 1 after --timeout, saying what to check.
# A domain id and partition of its own (150 + pid % 80), so parallel runs and other DDS users do not cross-talk.
# Usage: bus_loopback_test.sh UGVSENSE BUS_HOSTILE WORKDIR
set -u
tool=$1 hostile=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
domain=$((150 + $$ % 80))
part="bus-test-$$"
bus=(--domain "$domain" --partition "$part")
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$work"/*.err; do echo "--- $f"; cat "$f"; done; exit 1; }

"$tool" correlate-sim --out "$work/obs.jsonl" --ugvs 3 --duration 40 --pose-corrections >/dev/null ||
    fail "correlate-sim"
n_obs=$(grep -c '"kind":"observation"' "$work/obs.jsonl")
n_uav=$(grep -c '"kind":"uav"' "$work/obs.jsonl")
n_cor=$(grep -c '"kind":"pose_correction"' "$work/obs.jsonl")
n_all=$(wc -l <"$work/obs.jsonl")
echo "scenario: $n_all lines: $n_obs observations, $n_uav UAV fixes, $n_cor pose corrections (domain $domain)"
[ "$n_obs" -gt 0 ] && [ "$n_uav" -gt 0 ] && [ "$n_cor" -gt 0 ] && [ $((n_obs + n_uav + n_cor)) -eq "$n_all" ] ||
    fail "unexpected scenario"

# 1. every line arrives
"$tool" listen observations --count "$n_obs" --timeout 30 "${bus[@]}" >"$work/obs.out" 2>"$work/obs.err" &
l1=$!; pids+=($l1)
"$tool" listen uav --count "$n_uav" --timeout 30 "${bus[@]}" >"$work/uav.out" 2>"$work/uav.err" &
l2=$!; pids+=($l2)
"$tool" listen pose_corrections --count "$n_cor" --timeout 30 "${bus[@]}" >"$work/cor.out" 2>"$work/cor.err" &
l3=$!; pids+=($l3)
# bus-send waits for a reader of each topic the file uses (a CI mirror under load once matched the pose_corrections
# listener only after bus-send had ended, when it waited for the observation reader alone); --linger keeps the
# transient-local history for a reader that still comes late.
out=$("$tool" bus-send --input "$work/obs.jsonl" --source gcs-test --linger 3 "${bus[@]}" 2>&1) || fail "bus-send: $out"
echo "$out"
grep -qE "sent $n_all message\(s\) \($n_obs observation\(s\), $n_uav UAV fix\(es\), 0 confirmation\(s\), $n_cor pose correction\(s\)\).*acknowledged by [1-9]" <<<"$out" ||
    fail "bus-send summary"
wait $l1 || fail "listen observations exited $?"
wait $l2 || fail "listen uav exited $?"
wait $l3 || fail "listen pose_corrections exited $?"
got=$(($(wc -l <"$work/obs.out") + $(wc -l <"$work/uav.out") + $(wc -l <"$work/cor.out")))
echo "received $got of $n_all lines"
[ "$got" -eq "$n_all" ] || fail "received $got of $n_all"
# sequence_number = line number in the file, per topic
for kind in observation:obs uav:uav pose_correction:cor; do
    want=$(grep -n "\"kind\":\"${kind%%:*}\"" "$work/obs.jsonl" | cut -d: -f1 | sort -n | tr '\n' ' ')
    have=$(grep -o '"sequence_number":[0-9]*' "$work/${kind##*:}.out" | cut -d: -f2 | sort -n | tr '\n' ' ')
    [ "$want" = "$have" ] || fail "${kind%%:*}: sequence numbers are not the line numbers"
done
grep -q '"source":"gcs-test"' "$work/uav.out" || fail "--source not used for UAV fixes"
grep -q '"ugv":"ugv-1"' "$work/obs.out" && grep -q '"ugv":"ugv-3"' "$work/obs.out" || fail "observations of every UGV"

# 2. --only-ugv
n_u2=$(grep '"kind":"observation"' "$work/obs.jsonl" | grep -c '"ugv":"ugv-2"')
"$tool" listen observations --count "$n_u2" --timeout 30 "${bus[@]}" >"$work/u2.out" 2>"$work/u2.err" &
l4=$!; pids+=($l4)
out=$("$tool" bus-send --input "$work/obs.jsonl" --only-ugv ugv-2 "${bus[@]}" 2>&1) || fail "bus-send --only-ugv: $out"
echo "$out"
grep -qF "sent $n_u2 message(s) ($n_u2 observation(s), 0 UAV fix(es), 0 confirmation(s), 0 pose correction(s))" <<<"$out" ||
    fail "--only-ugv summary"
wait $l4 || fail "listen (only-ugv) exited $?"
[ "$(wc -l <"$work/u2.out")" -eq "$n_u2" ] && [ "$(grep -c '"ugv":"ugv-2"' "$work/u2.out")" -eq "$n_u2" ] ||
    fail "--only-ugv: not exactly ugv-2's $n_u2 observations"
out=$("$tool" bus-send --input "$work/obs.jsonl" --only-ugv ugv-9 --wait-readers 0 "${bus[@]}" 2>&1)
rc=$?
echo "$out"
[ $rc -eq 1 ] && grep -qF "no observation of ugv 'ugv-9' (fix: give one of the file's UGVs: ugv-1, ugv-2, ugv-3)" <<<"$out" ||
    fail "--only-ugv of an unknown UGV: exit $rc"

# 3. hostile samples and a flood
"$tool" listen observations --count 5000 --timeout 30 "${bus[@]}" >"$work/hostile.out" 2>"$work/hostile.err" &
l5=$!; pids+=($l5)
out=$("$hostile" --flood 5000 "${bus[@]}" 2>&1) || fail "bus-hostile: $out"
echo "$out"
for want in "observations      NaN time: 1" "observations      latitude 91: 1" "observations      latitude -91: 1" \
    "observations      longitude 200: 1" "observations      unknown class 9: 1" "observations      empty ugv name: 1" \
    "observations      track name of 100 characters: 1" "uav               empty source name: 1" "confirmations     unknown confirmation state 7: 1" \
    "pose_corrections  since_t > until_t: 1" "flood: 5000 valid observation(s)"; do
    grep -qF -- "$want" <<<"$out" || fail "bus-hostile: missing '$want'"
done
wait $l5 || fail "listen (hostile) exited $?"
cat "$work/hostile.err"
[ "$(grep -c '^refused: ' "$work/hostile.err")" -eq 10 ] || fail "expected 10 refused observations"
grep -qF "5000 sample(s) printed, 10 refused" "$work/hostile.err" || fail "listen's refused count"
[ "$(wc -l <"$work/hostile.out")" -eq 5000 ] || fail "expected the 5000 valid observations of the flood"
grep -q '"t":"nan"\|"ugv_lat_deg":91' "$work/hostile.out" && fail "a hostile sample was printed"

# 4. nobody publishes
out=$("$tool" listen confirmations --timeout 0.5 --domain "$domain" --partition "nobody-$$" 2>&1)
rc=$?
echo "$out"
[ $rc -eq 1 ] && grep -qF "nothing arrived in 0.5 s (0 publisher(s) matched" <<<"$out" &&
    grep -qF "check that the publisher runs, on the same domain" <<<"$out" || fail "listen timeout: exit $rc"
echo "OK"
