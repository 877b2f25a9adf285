#!/usr/bin/env bash
# The team's DDS bus end to end (issue 6): a ground station (ugvsensed with vision off, the correlator on) and
# three UGV processes, each replaying its own observations of one simulator scenario (bias setting, 3 UGVs), plus
# a fourth sending the UAV fixes, all over the bus. Checked, with nothing timed:
#   1. every message arrives exactly once: the station's inputs.jsonl holds exactly the scenario's lines, although
#      UGV 2's process is killed (SIGKILL) mid-way and restarted (it replays its file from the start: the repeats
#      are dropped as duplicates);
#   2. the station's snapshots.jsonl equals `ugvsense correlate` on inputs.jsonl, byte for byte, and its last list
#      equals the offline tool's on the scenario in time order: UGV 2's restarted process sends its new messages
#      seconds after the others' later ones were applied (the reorder window is 1 s), so they are put in place by
#      replays (CorrelatorFeed's late window), and the list does not depend on the order of arrival;
#   3. the station is killed and restarted while the UGV processes linger: the new one gets every message again
#      from their transient-local histories (inputs.jsonl again holds the scenario), and the first run's logs are
#      kept (inputs.1.jsonl);
#   4. a `ugvsense listen correlated` late joiner gets the published list;
#   5. (netns) a network partition: UGV 3's namespace is cut off (every packet in and out dropped) for 3 s while it
#      sends, then healed: check 1 holds, nothing it wrote meanwhile is lost (reliable writers resend).
# Modes: loopback (every process on this host, Fast DDS shared memory and UDP), netns (each process in its own
# network namespace on a bridge, UDP only, 20 % of received UDP packets dropped by nftables in every namespace;
# skipped with a message when namespaces cannot be made).
# Usage: team_bus_test.sh UGVSENSE UGVSENSED WORKDIR DOMAIN loopback|netns
set -u
tool=$1 daemon=$2 work=$3 domain=$4 mode=$5
rm -rf "$work" && mkdir -p "$work"
partition="team-test-$$"
pids=()
namespaces=()
cleanup() {
    for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null; done
    wait 2>/dev/null
    for ns in "${namespaces[@]}"; do ip netns del "$ns" 2>/dev/null; done
    [ "$mode" = netns ] && ip link del "ugvbr$$" 2>/dev/null
    true
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$work"/*.log; do echo "--- $f"; tail -n 15 "$f"; done; exit 1; }

# ---- where each role runs ----
shm=true
declare -A ns_of
roles=(gcs ugv-1 ugv-2 ugv-3 uav late)
if [ "$mode" = netns ]; then
    shm=false # processes of one host would use shared memory and bypass the network
    if ! ip netns add "ugvprobe$$" 2>/dev/null; then
        echo "SKIPPED: cannot create network namespaces here (needs root and CAP_NET_ADMIN)"; exit 0
    fi
    ip netns del "ugvprobe$$"
    command -v nft >/dev/null || { echo "SKIPPED: nft (package nftables) is not installed"; exit 0; }
    ip link add "ugvbr$$" type bridge && ip link set "ugvbr$$" up || { echo "SKIPPED: cannot create a bridge"; exit 0; }
    i=0
    for r in "${roles[@]}"; do
        i=$((i + 1))
        ns="ugv$$-$i"
        ip netns add "$ns" || fail "ip netns add $ns"
        namespaces+=("$ns")
        ip link add "v$$-$i" type veth peer name eth0 netns "$ns" || fail "veth for $ns"
        ip link set "v$$-$i" master "ugvbr$$" up
        ip -n "$ns" addr add "10.77.0.$i/24" dev eth0
        ip -n "$ns" link set eth0 up
        ip -n "$ns" link set lo up
        ip -n "$ns" route add 224.0.0.0/4 dev eth0
        # 20 % of the UDP packets this namespace receives are lost.
        ip netns exec "$ns" nft -f - <<NFT || { echo "SKIPPED: nftables cannot filter in a namespace here"; exit 0; }
table inet loss {
    chain in { type filter hook input priority 0; meta l4proto udp numgen random mod 100 < 20 drop; }
}
NFT
        ns_of[$r]=$ns
    done
fi
run_as() { # ROLE CMD...: run CMD where ROLE lives, in place of this shell (so that $! of `run_as ... &` is CMD)
    local r=$1; shift
    if [ "$mode" = netns ]; then exec ip netns exec "${ns_of[$r]}" "$@"; else exec "$@"; fi
}

# ---- the scenario, split by sender ----
"$tool" correlate-sim --setting bias --ugvs 3 --duration 240 --seed 3 --out "$work/scenario.jsonl" >/dev/null ||
    fail "correlate-sim"
for u in ugv-1 ugv-2 ugv-3; do
    grep "\"kind\":\"observation\"" "$work/scenario.jsonl" | grep "\"ugv\":\"$u\"" >"$work/$u.jsonl"
done
grep -v "\"kind\":\"observation\"" "$work/scenario.jsonl" >"$work/uav.jsonl"
total=$(wc -l <"$work/scenario.jsonl")
[ "$total" -gt 100 ] || fail "scenario too short ($total lines)"

cat >"$work/gcs.yaml" <<YAML
vehicle_id: gcs
vision:
  enabled: false
dds:
  domain_id: $domain
  partition: $partition
  shared_memory: $shm
correlator:
  enabled: true
  period_s: 1
  # Below the worst delay of this scenario: UGV 2's restarted process first replays ~120 duplicates at 40/s (3 s)
  # before its new messages, which arrive after the others' later ones were applied: the late window puts them
  # in place.
  reorder_ms: 1000
  late_window_s: 300
  log_dir: $work/gcs
YAML

start_gcs() {
    run_as gcs "$daemon" --config "$work/gcs.yaml" >"$work/gcs.$1.log" 2>&1 &
    gcs_pid=$!
    pids+=("$gcs_pid")
}
stop_gcs() {
    kill -TERM "$gcs_pid"
    wait "$gcs_pid" || fail "the ground station exited with an error"
}
send_opts=(--domain "$domain" --partition "$partition")
[ "$shm" = false ] && send_opts+=(--no-shm)
start_sender() { # ROLE FILE LOG [BUS-SEND OPTION...]
    local role=$1 file=$2 log=$3
    shift 3
    run_as "$role" "$tool" bus-send --input "$file" "${send_opts[@]}" --rate 40 --linger 600 --source uav-1 "$@" \
        >"$work/$log.log" 2>&1 &
    sender_pid[$role]=$!
    pids+=("${sender_pid[$role]}")
}
wait_acked() { # LOG...: every sender says its messages were acknowledged by a reader at least (bounded: 180 s)
    for log in "$@"; do
        for _ in $(seq 1800); do
            grep -q "acknowledged" "$work/$log.log" && break
            sleep 0.1
        done
        grep -q "acknowledged" "$work/$log.log" || fail "$log: not acknowledged"
        grep -q "acknowledged by 0 reader" "$work/$log.log" &&
            fail "$log: sent to no reader (the station was not matched)"
    done
}
partition() { # ROLE SECONDS: cut ROLE's namespace off the network (every packet in and out dropped), then heal it
    local ns=${ns_of[$1]}
    ip netns exec "$ns" nft -f - <<NFT || fail "cannot cut $1 off the network"
table inet cut {
    chain in { type filter hook input priority -10; policy drop; }
    chain out { type filter hook output priority -10; policy drop; }
}
NFT
    sleep "$2"
    ip netns exec "$ns" nft delete table inet cut || fail "cannot heal the partition of $1"
}
same_lines() { # A B: the same lines, in any order
    cmp -s <(sort "$1") <(sort "$2")
}

declare -A sender_pid
start_gcs first
sleep 1
start_sender ugv-1 "$work/ugv-1.jsonl" ugv-1
start_sender ugv-2 "$work/ugv-2.jsonl" ugv-2 --rate 20 # slower: 12.5 s for its 250, so the kill below lands mid-way
start_sender ugv-3 "$work/ugv-3.jsonl" ugv-3
start_sender uav "$work/uav.jsonl" uav
# Kill UGV 2's process once it is under way, and start it again: it replays its file from the first line.
for _ in $(seq 600); do grep -q "^sending" "$work/ugv-2.log" && break; sleep 0.1; done # discovered the station
# About 120 of its 250 observations sent at 20/s. At 40/s a kill 2 s, and once (a clean-clone CI mirror) 4 s, after
# "sending" found nothing delivered yet (no repeats); at 20/s it has 6.5 s more before its last message.
sleep 6
kill -9 "${sender_pid[ugv-2]}"
wait "${sender_pid[ugv-2]}" 2>/dev/null
# Up to 60 s for the station: a clean-clone CI mirror once saw the restarted process match no reader in 20 s, send
# to nobody and count as acknowledged (87 messages missing at the station).
start_sender ugv-2 "$work/ugv-2.jsonl" ugv-2.restarted --wait-timeout 60
[ "$mode" = netns ] && partition ugv-3 3 # UGV 3 is still sending (about 250 observations at 40/s)
wait_acked ugv-1 ugv-2.restarted ugv-3 uav
sleep 3 # the reorder window (1 s) and the last poll
stop_gcs

[ -s "$work/gcs/inputs.jsonl" ] || fail "the ground station logged no inputs"
got=$(wc -l <"$work/gcs/inputs.jsonl")
same_lines "$work/gcs/inputs.jsonl" "$work/scenario.jsonl" ||
    fail "the station's inputs ($got lines) are not the scenario's $total lines, each once"
echo "1. every message arrived once: $got of $total (UGV 2's process killed and restarted)"
"$tool" correlate --input "$work/gcs/inputs.jsonl" --output "$work/offline.jsonl" >"$work/offline.log" 2>&1 ||
    fail "offline correlate"
cmp -s "$work/offline.jsonl" "$work/gcs/snapshots.jsonl" || fail "live snapshots differ from the offline tool's"
echo "2. the live snapshots equal the offline tool's on the same inputs ($(wc -l <"$work/offline.jsonl") snapshots)"
line=$(grep -E "^correlator:" "$work/gcs.first.log")
echo "$line"
"$tool" correlate --input "$work/scenario.jsonl" --output "$work/sorted.jsonl" >/dev/null 2>&1 || fail "correlate sorted"
cmp -s <(tail -n 1 "$work/offline.jsonl") <(tail -n 1 "$work/sorted.jsonl") ||
    fail "the station's last list differs from the offline tool's on the scenario in time order"
late=$(sed -E 's/.*\(([0-9]+) late, put in place\).*/\1/' <<<"$line")
echo "   its last list equals the offline tool's on the scenario in time order ($late input(s) arrived late)"
duplicates=$(sed -E 's/.* ([0-9]+) duplicate\(s\).*/\1/' <<<"$line")
[ "$duplicates" -gt 0 ] || fail "UGV 2's restarted process repeated nothing: the kill came too early to test it"

# The station again, while the UGV processes linger with their histories.
restarted_station_gets_all() { # LOG KEPT: start it (the last run's log is set aside as inputs.KEPT.jsonl), wait
    start_gcs "$1" # for every message (60 s), stop it; true when the new log holds the whole scenario
    for _ in $(seq 300); do [ -f "$work/gcs/inputs.$2.jsonl" ] && break; sleep 0.1; done
    for _ in $(seq 600); do
        [ -f "$work/gcs/inputs.jsonl" ] && [ "$(wc -l <"$work/gcs/inputs.jsonl")" -ge "$total" ] && break
        sleep 0.1
    done
    sleep 1
    stop_gcs
    same_lines "$work/gcs/inputs.jsonl" "$work/scenario.jsonl"
}
# Fast DDS 2.9 now and then sends a keep-all, transient-local writer's history to none of a late-joining reader
# (eProsima/Fast-DDS#3822, open upstream): seen once here (a CI run, 2026-12-02), when one UGV's whole history
# stayed away from the restarted station. A second restart gets it (README, operator guide); two misses in a row
# fail the test.
if ! restarted_station_gets_all second 1; then
    echo "   the restarted station got $(wc -l <"$work/gcs/inputs.jsonl") of $total messages (Fast DDS 2.9's" \
        "late-joiner miss, eProsima/Fast-DDS#3822): restarting it once more"
    restarted_station_gets_all second-retry 2 ||
        fail "the restarted station got $(wc -l <"$work/gcs/inputs.jsonl") of $total messages, twice in a row"
fi
[ -s "$work/gcs/inputs.1.jsonl" ] || fail "the first run's log was not kept as inputs.1.jsonl"
"$tool" correlate --input "$work/gcs/inputs.jsonl" --output "$work/offline2.jsonl" >/dev/null 2>&1
cmp -s "$work/offline2.jsonl" "$work/gcs/snapshots.jsonl" || fail "restarted: live snapshots differ from offline"
cmp -s <(tail -n 1 "$work/offline.jsonl") <(tail -n 1 "$work/offline2.jsonl") ||
    fail "the restarted station's last list differs from the first one's"
echo "3. the restarted station got all $total messages again from the UGVs' histories; same last list"
(run_as late "$tool" correlate --from-dds "${send_opts[@]}" --duration 25 --output "$work/viewer.jsonl" \
    --map "$work/viewer.png") >"$work/viewer.log" 2>&1 || fail "correlate --from-dds"
[ -s "$work/viewer.png" ] || fail "correlate --from-dds drew no map"
cmp -s "$work/viewer.jsonl" <(tail -n 1 "$work/offline.jsonl") || fail "the viewer's last list differs from the station's"
echo "   correlate --from-dds drew the GCS map from the lingering histories; its list equals the station's"

# A late joiner on the correlated list (transient local, keep last 1): the restarted station published it last.
start_gcs third
(run_as late "$tool" listen correlated "${send_opts[@]}" --count 1 --timeout 60) >"$work/late.log" 2>&1 ||
    fail "listen correlated got nothing"
grep -q '"objects"' "$work/late.log" || fail "listen correlated printed no objects"
stop_gcs
echo "4. a late listener got the correlated list"
echo "OK ($mode)"
