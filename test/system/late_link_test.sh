#!/usr/bin/env bash
# A network link that comes up after the bus started (a vehicle's radio associating after boot, a new DHCP
# address). Fast DDS 2.9 goes on with the addresses an endpoint was made with, so the bus follows the interfaces
# (ipc::dds::Bus::followNetworkChanges: the participant and every reader and writer are made again;
# README "On the DDS bus"). Checked where a user meets it, each process started while its only link is down:
#   - `ugvsense listen` in namespace A; 3 s later A's link comes up (an address, a multicast route) and a sender in
#     namespace B, linked to it and up from the start, sends poses: the listener says it followed and receives them;
#   - the vehicle service (ugvsensed replaying a course: its bus task) and a ground station (vision off: its main
#     loop) in namespace C; 3 s later C's link to namespace D comes up: both say they followed, a listener in D
#     receives the vehicle's sectors, and the vehicle's end report counts the change.
# UDP only (--no-shm, shared_memory: false): namespaces of one host would otherwise meet in /dev/shm.
# Skipped with a message where network namespaces cannot be made.
# Usage: late_link_test.sh UGVSENSE UGVSENSED WORKDIR DOMAIN
set -u
tool=$1 daemon=$2 work=$3 domain=$4
rm -rf "$work" && mkdir -p "$work"
a="ugvlateA$$" b="ugvlateB$$" c="ugvlateC$$" d="ugvlateD$$"
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null; done
    wait 2>/dev/null
    for n in "$a" "$b" "$c" "$d"; do ip netns del "$n" 2>/dev/null; done
    true
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$work"/*.log; do echo "--- $f"; tail -n 15 "$f"; done; exit 1; }
followed="the DDS bus made its participant, readers and writers again on the new addresses"

if ! ip netns add "$a" 2>/dev/null; then
    echo "SKIPPED: cannot create network namespaces here (needs root and CAP_NET_ADMIN)"; exit 0
fi
# A namespace (made) and a new one joined by a veth pair; the first end's address and link come later (link_up).
pair() { # NS1 NS2 END1 END2 NET
    ip netns add "$2" || fail "ip netns add $2"
    ip -n "$1" link set lo up && ip -n "$2" link set lo up || fail "loopback up"
    ip link add "$3" type veth peer name "$4" || fail "a veth pair"
    ip link set "$3" netns "$1" && ip link set "$4" netns "$2" || fail "the veth ends into the namespaces"
    ip -n "$2" addr add "$5.2/24" dev "$4" && ip -n "$2" link set "$4" up &&
        ip -n "$2" route add 224.0.0.0/4 dev "$4" || fail "the link of $2"
}
link_up() { # NS END NET: as a DHCP client does, the address last (the multicast route is there when it comes)
    ip -n "$1" link set "$2" up && ip -n "$1" route add 224.0.0.0/4 dev "$2" &&
        ip -n "$1" addr add "$3.1/24" dev "$2" || fail "the link of $1"
}
wait_for() { # PATTERN FILE...: up to 10 s
    for _ in $(seq 100); do
        grep -q "$1" "${@:2}" 2>/dev/null && return 0
        sleep 0.1
    done
    return 1
}

# 1. A listener.
pair "$a" "$b" "la$$" "lb$$" 10.78.0
partition="late-link-$$"
common=(--domain "$domain" --partition "$partition" --no-shm)
ip netns exec "$a" "$tool" listen pose --count 3 --timeout 20 "${common[@]}" >"$work/listen.out" 2>"$work/listen.log" &
listener=$!
pids+=("$listener")
sleep 3
link_up "$a" "la$$" 10.78.0
echo "the listener's link is up 3 s after its start"
ip netns exec "$b" "$tool" bus-send --poses ugv-late --rate 10 --duration 40 "${common[@]}" >"$work/send.log" 2>&1 &
pids+=("$!")
wait_for "$followed" "$work/listen.log" || fail "the listener did not follow the new link within 10 s"
wait "$listener"
rc=$?
poses=$(grep -c '"vehicle":"ugv-late"' "$work/listen.out")
[ "$rc" -eq 0 ] && [ "$poses" -ge 3 ] || fail "the listener followed the new link but printed $poses pose(s) (exit $rc)"
echo "the listener followed the new link and received $poses poses"

# 2. The vehicle service and a ground station.
ip netns add "$c" || fail "ip netns add $c"
pair "$c" "$d" "lc$$" "ld$$" 10.79.0
"$tool" sim --course default --frames 10 --out "$work/course.ugvrec" >/dev/null || fail "sim --course"
dds_yaml="dds:
  domain_id: $domain
  partition: $partition
  shared_memory: false"
printf 'vehicle_id: ugv-late\ncamera:\n  backend: replay\n  replay_path: %s\n%s\n' "$work/course.ugvrec" "$dds_yaml" \
    >"$work/vehicle.yaml"
printf 'vehicle_id: gcs-late\nvision:\n  enabled: false\n%s\ncorrelator:\n  enabled: true\n  log_dir: %s\n' \
    "$dds_yaml" "$work/station" >"$work/station.yaml"
ip netns exec "$c" "$daemon" --config "$work/vehicle.yaml" --replay "$work/course.ugvrec" --embedded-roudi --rate 10 \
    --loop --print-every 0 >"$work/vehicle.log" 2>&1 &
vehicle=$!
pids+=("$vehicle")
ip netns exec "$c" "$daemon" --config "$work/station.yaml" >"$work/station.log" 2>&1 &
station=$!
pids+=("$station")
sleep 3
kill -0 "$vehicle" 2>/dev/null || fail "the vehicle service did not start"
kill -0 "$station" 2>/dev/null || fail "the ground station did not start"
grep -q "network interfaces changed" "$work/vehicle.log" "$work/station.log" && fail "a change before the link came up"
link_up "$c" "lc$$" 10.79.0
echo "the service's link is up 3 s after its start"
for who in vehicle station; do
    wait_for "$followed" "$work/$who.log" || fail "the $who did not follow the new link within 10 s"
done
ip netns exec "$d" "$tool" listen sectors --count 3 --timeout 30 "${common[@]}" >"$work/sectors.out" \
    2>"$work/sectors.log" || fail "a listener beyond the new link received no sectors from the vehicle"
sectors=$(grep -c '"vehicle":"ugv-late"' "$work/sectors.out")
[ "$sectors" -ge 3 ] || fail "a listener beyond the new link printed $sectors sectors sample(s) of the vehicle"
kill -TERM "$vehicle" "$station"
wait "$vehicle" || fail "the vehicle service exited with an error"
wait "$station" || fail "the ground station exited with an error"
grep -Eq "^dds: .* 1 network interface change\(s\) followed" "$work/vehicle.log" ||
    fail "the vehicle's bus report does not count the change"
echo "PASS: each followed a link that came up after its start: the listener received $poses poses over it, a" \
    "listener beyond it $sectors sectors samples of the vehicle service, the ground station followed too"
