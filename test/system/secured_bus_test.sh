#!/usr/bin/env bash
# The secured team bus (issue 22 item 4, DDS Security): a ground station (ugvsensed, correlator only) with
# dds.security on, and the team's files made by bringup/deploy/security/make_security.sh (gcs, ugv-1 to ugv-4, a viewer and
# an operator console), plus ugv-2 from another CA (an attacker's). Every participant that runs at the same time as
# another has its own certificate, as on a real team, and the intruders join once the certified participants have
# matched: with one certificate in two live participants, or intruders (failing handshakes) joining at the same
# time, a certified sender sometimes matched 0 or 1 of its readers in 60 s on this machine (4 of 7 runs), and never
# in 8 runs (3 beside stress-ng --cpu 2) with this order. Even so, beside a full CPU load (or the background builds of
# the test command) Fast DDS 2.9.1 sometimes stalls one pair's handshake for good (2 of 7 runs beside stress-ng: one
# pair of 5 never authenticated in 150 s while every other pair did in 1 s); bus-send and listen, still waiting for
# what they expect after 10 s with a handshake unfinished, join the bus again (Bus::stalledHandshakes()). Checked:
#   1. certified ugv-1 sends its observations: every one is applied (the positive control);
#   2. a participant without a certificate, and one whose certificate another CA signed (named ugv-2), send UGV 2's
#      observations, the UAV fixes and the confirmations: 0 of them reach the station;
#   3. the same two listen to the OOI positions (observations, the correlated list) while the certified writers hold
#      their histories and the station publishes: 0 samples,
#      while certified ugv-2 gets the correlated list, and a certified viewer (correlate --from-dds --security)
#      applies ugv-1's observations;
#   4. one vehicle cannot write as another: certified ugv-3 sending UGV 2's observations has each one dropped by the
#      station (its writer's partition is ugv-3's: "in another sender's name") and refused by a certified listen,
#      ugv-4 asking to write in ugv-2's partition is refused by its own permissions, and ugv-1's certificate with
#      ugv-2's permissions document cannot join at all.
# Usage: secured_bus_test.sh UGVSENSE UGVSENSED MAKE_SECURITY WORKDIR DOMAIN
set -u
tool=$1 daemon=$2 make_security=$3 work=$4 domain=$5
rm -rf "$work" && mkdir -p "$work"
partition="secured-test-$$"
pids=()
cleanup() { for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null; done; wait 2>/dev/null; true; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$work"/*.log; do echo "--- $f"; tail -n 15 "$f"; done; exit 1; }
command -v openssl >/dev/null || { echo "SKIPPED: openssl is not installed"; exit 0; }

bash "$make_security" "$work/team" --partition "$partition" gcs ugv-1 ugv-2 ugv-3 ugv-4 viewer console \
    >"$work/make.log" 2>&1 ||
    fail "make_security.sh"
bash "$make_security" "$work/rogue" --partition "$partition" ugv-2 >>"$work/make.log" 2>&1 ||
    fail "make_security.sh (the other CA)"
mkdir -p "$work/mixed" # ugv-1's certificate and key with ugv-2's (validly signed) permissions
cp "$work/team/ugv-1/"* "$work/mixed/" && cp "$work/team/ugv-2/permissions.p7s" "$work/mixed/"

"$tool" correlate-sim --setting bias --ugvs 1 --duration 30 --seed 3 --out "$work/scenario.jsonl" >/dev/null ||
    fail "correlate-sim"
grep '"ugv":"ugv-1"' "$work/scenario.jsonl" | grep '"kind":"observation"' >"$work/ugv-1.jsonl"
sed 's/"ugv":"ugv-1"/"ugv":"ugv-2"/' "$work/ugv-1.jsonl" >"$work/ugv-2.jsonl" # the same, in UGV 2's name
# What an intruder would inject: UGV 2's observations, the UAV fixes and a confirmation of every object.
{ cat "$work/ugv-2.jsonl"; grep '"kind":"uav"' "$work/scenario.jsonl"
  for i in 1 2 3 4 5; do echo "{\"t\":1.$i,\"kind\":\"confirm\",\"id\":\"OOI-$i\",\"state\":\"confirmed_positive\"}"; done
} >"$work/others.jsonl"
own=$(wc -l <"$work/ugv-1.jsonl") others=$(wc -l <"$work/others.jsonl") foreign=$(wc -l <"$work/ugv-2.jsonl")
[ "$own" -gt 10 ] && [ "$foreign" -gt 10 ] || fail "scenario too short ($own, $foreign lines)"

# shellcheck source=test/support/security_yaml.sh
source "$(dirname "$0")/../support/security_yaml.sh"
sec=$work/team/gcs
cat >"$work/gcs.yaml" <<YAML
vehicle_id: gcs
vision:
  enabled: false
dds:
  domain_id: $domain
  partition: $partition
$(security_yaml "$sec")
correlator:
  enabled: true
  reorder_ms: 500
  startup_hold_ms: 0
  log_dir: $work/gcs
YAML
"$tool" check-config "$work/gcs.yaml" >"$work/check.log" 2>&1 || fail "check-config of the secured station"
bus=(--domain "$domain" --partition "$partition")
background() { # LOG CMD...: CMD in the background; its pid in $last
    local log=$1; shift
    "$@" >"$work/$log.log" 2>&1 &
    last=$!
    pids+=("$last")
}
# 4b. What a participant's own files refuse need no peer: run them before the others start, so that a participant
# that joins and leaves at once is not in the middle of the others' handshakes.
"$tool" bus-send --input "$work/ugv-2.jsonl" "${bus[@]}" --security "$work/team/ugv-4" --identity ugv-2 \
    --wait-readers 0 >"$work/other-partition.log" 2>&1 && fail "ugv-4 could write in ugv-2's partition"
grep -q "cannot create the writer" "$work/other-partition.log" || fail "ugv-4 in ugv-2's partition: no writer error"
"$tool" bus-send --input "$work/ugv-2.jsonl" "${bus[@]}" --security "$work/mixed" --identity ugv-2 \
    --wait-readers 0 >"$work/mixed.log" 2>&1 && fail "ugv-1's certificate joined with ugv-2's permissions"
grep -q "cannot create the DDS participant" "$work/mixed.log" || fail "ugv-1 with ugv-2's permissions: no error"

"$daemon" --config "$work/gcs.yaml" >"$work/gcs.log" 2>&1 &
pids+=($!)
gcs=$!
# 1 and 4a. The team's certified participants first: the station, a certified viewer (correlate --from-dds) and a
# certified listen of the observations (the console's files). Then two vehicles send: ugv-1 its own observations (the
# positive control) and ugv-3 UGV 2's (writing as another vehicle: the station drops each one, the viewer and the
# listen refuse each). Each sender waits for the three readers, so that none depends on a late joiner getting the
# writer's history (Fast DDS 2.9 sometimes gives a late-joining reader none of it: eProsima/Fast-DDS#3822), up to
# 60 s (a loaded CI machine once took more than 20 s to end the secured handshakes).
background viewer "$tool" correlate --from-dds --domain "$domain" --partition "$partition" \
    --security "$work/team/viewer" --duration 40 --output "$work/viewer.jsonl"
v1=$last
background listen-impersonated "$tool" listen observations "${bus[@]}" --security "$work/team/console" --timeout 120
l4=$last
"$tool" bus-send --input "$work/ugv-1.jsonl" "${bus[@]}" --security "$work/team/ugv-1" --source ugv-1 \
    --wait-readers 3 --wait-timeout 60 --linger 20 >"$work/ugv-1.log" 2>&1 &
pids+=($!)
"$tool" bus-send --input "$work/ugv-2.jsonl" "${bus[@]}" --security "$work/team/ugv-3" --source ugv-3 \
    --wait-readers 3 --wait-timeout 60 --linger 12 >"$work/impersonate.log" 2>&1 &
pids+=($!)
impersonate=$!
for log in ugv-1 impersonate; do
    for _ in $(seq 700); do grep -q "acknowledged" "$work/$log.log" && break; sleep 0.1; done
done
grep -q " acknowledged by 3 reader" "$work/ugv-1.log" ||
    fail "certified ugv-1's observations were not acknowledged by the station, the viewer and the listen"
grep -q " acknowledged by 3 reader" "$work/impersonate.log" ||
    fail "certified ugv-3's samples (naming ugv-2) were not acknowledged by the station, the viewer and the listen"
# 2 and 3. The intruders, while the certified writers still hold their histories: listeners without a valid
# certificate (those without one subscribe to every partition of the team, <partition>.*, where the secured
# participants write), and injection without one or with another CA's (their writers keep their histories while
# they linger).
background listen-open "$tool" listen observations --domain "$domain" --partition "$partition.*" --timeout 8
l1=$last
background listen-open-correlated "$tool" listen correlated --domain "$domain" --partition "$partition.*" --timeout 8
l2=$last
background listen-rogue "$tool" listen correlated "${bus[@]}" --security "$work/rogue/ugv-2" --timeout 8
l3=$last
background inject-open "$tool" bus-send --input "$work/others.jsonl" "${bus[@]}" --source ugv-2 --wait-readers 0 \
    --linger 4
i1=$last
background inject-rogue "$tool" bus-send --input "$work/others.jsonl" "${bus[@]}" --source ugv-2 --wait-readers 0 \
    --linger 4 --security "$work/rogue/ugv-2"
i2=$last
# 3. A certified reader gets the list.
"$tool" listen correlated "${bus[@]}" --security "$work/team/ugv-2" --count 1 --timeout 40 >"$work/listen-ok.log" \
    2>&1 || fail "certified ugv-2 got no correlated list"
for p in "$l1" "$l2" "$l3" "$i1" "$i2"; do wait "$p"; done
wait "$impersonate" || fail "certified ugv-3 could not send (its samples naming ugv-2)"
kill -INT "$l4" 2>/dev/null; wait "$l4"
wait "$v1" || fail "correlate --from-dds on the secured bus"
sleep 1 # the reorder window
kill -TERM "$gcs"
wait "$gcs" || fail "the ground station exited with an error"
line=$(grep "^correlator:" "$work/gcs.log") || fail "no correlator report"
echo "$line"

cmp -s <(sort "$work/gcs/inputs.jsonl") <(sort "$work/ugv-1.jsonl") ||
    fail "the station's inputs are not exactly certified ugv-1's $own observations"
echo "1. certified ugv-1's $own observations applied, nothing else"
echo "2. 0 of $others samples injected without a certificate or with another CA's"
for l in listen-open listen-open-correlated listen-rogue; do
    grep -q '^{' "$work/$l.log" && fail "$l printed a sample"
done
grep -qE "received [0-9]+ input\(s\): $own applied" "$work/viewer.log" || # ugv-3's in ugv-2's name: dropped
    fail "the certified viewer (correlate --from-dds --security) did not apply ugv-1's $own observations alone"
echo "3. 0 samples read without a certificate or with another CA's; certified ugv-2 got the correlated list," \
    "and correlate --from-dds --security applied ugv-1's $own observations"
impersonated=$(sed -E "s/.* ([0-9]+) in another sender's name.*/\1/" <<<"$line")
[ "$impersonated" -eq "$foreign" ] ||
    fail "$foreign observations naming ugv-2 sent by ugv-3, $impersonated dropped as in another sender's name"
listenRefused=$(grep -c "refused: a sample naming 'ugv-2' written by 'ugv-3'" "$work/listen-impersonated.log")
[ "$listenRefused" -eq "$foreign" ] ||
    fail "$foreign observations naming ugv-2 sent by ugv-3, $listenRefused refused by a certified listen"
grep -q '"ugv":"ugv-2"' "$work/listen-impersonated.log" && fail "a certified listen printed ugv-3's sample as ugv-2's"
grep -q "dds: refused participant" "$work/gcs.log" || fail "the station named no refused participant on its log"
echo "   the station named the participants it refused: $(grep -c "dds: refused participant" "$work/gcs.log")"
echo "4. ugv-3 as ugv-2: $impersonated of $foreign samples dropped by the station and $listenRefused refused by a" \
    "certified listen; ugv-4's own permissions refuse ugv-2's partition; ugv-1's certificate with ugv-2's" \
    "permissions cannot join"
echo "OK"
