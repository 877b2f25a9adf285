#!/usr/bin/env bash
# A network link that comes up after the bus started (a vehicle's radio associating after boot, a new DHCP
# address). Fast DDS 2.9 goes on with the addresses of the interfaces up when its participant started: a reader made
# before its link came up is announced at 127.0.0.1 only and receives nothing over the new link until its process
# restarts (README "On the DDS bus"). So the bus watches the interfaces (ipc::dds::Bus::networkInterfacesChanged, in
# the service's bus task, `ugvsense listen` and `ugvsense correlate --from-dds`) and says so, naming the fix:
#   - a listener starts in a network namespace whose only link is down;
#   - 3 s later that link comes up (an address, a multicast route), and a sender in a second namespace, linked to
#     it and up from the start, sends poses (UDP only: each process in its own namespace);
#   - passes when the listener warns of the changed interfaces within 5 s, and a listener started after the link
#     came up (the fix: a restart) receives 3 poses.
# Then the service itself, where a user meets it: a vehicle (ugvsensed replaying a course, its bus task) and a
# ground station (vision off, the correlator's main loop) start in a third namespace whose link is down; when it
# comes up, each warns within 5 s, and the vehicle's end report counts the change.
# Skipped with a message where network namespaces cannot be made.
# Usage: late_link_test.sh UGVSENSE UGVSENSED WORKDIR DOMAIN
set -u
tool=$1 daemon=$2 work=$3 domain=$4
rm -rf "$work" && mkdir -p "$work"
a="ugvlateA$$" b="ugvlateB$$" c="ugvlateC$$"
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null; done
    wait 2>/dev/null
    ip netns del "$a" 2>/dev/null
    ip netns del "$b" 2>/dev/null
    ip netns del "$c" 2>/dev/null
    true
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$work"/*.log; do echo "--- $f"; tail -n 15 "$f"; done; exit 1; }

if ! ip netns add "$a" 2>/dev/null; then
    echo "SKIPPED: cannot create network namespaces here (needs root and CAP_NET_ADMIN)"; exit 0
fi
ip netns add "$b" || fail "ip netns add $b"
ip -n "$a" link set lo up && ip -n "$b" link set lo up || fail "loopback up"
ip link add "la$$" type veth peer name "lb$$" || fail "a veth pair"
ip link set "la$$" netns "$a" && ip link set "lb$$" netns "$b" || fail "the veth ends into the namespaces"
ip -n "$b" addr add 10.78.0.2/24 dev "lb$$" && ip -n "$b" link set "lb$$" up &&
    ip -n "$b" route add 224.0.0.0/4 dev "lb$$" || fail "the sender's link"

partition="late-link-$$"
common=(--domain "$domain" --partition "$partition" --no-shm)
ip netns exec "$a" "$tool" listen pose --count 3 --timeout 12 "${common[@]}" >"$work/early.out" 2>"$work/early.log" &
early=$!
pids+=("$early")
sleep 3
ip -n "$a" addr add 10.78.0.1/24 dev "la$$" && ip -n "$a" link set "la$$" up &&
    ip -n "$a" route add 224.0.0.0/4 dev "la$$" || fail "the listener's link"
echo "the first listener's link is up 3 s after its start"
ip netns exec "$b" "$tool" bus-send --poses ugv-late --rate 10 --duration 40 "${common[@]}" >"$work/send.log" 2>&1 &
pids+=("$!")
for _ in $(seq 50); do
    grep -q "network interfaces changed" "$work/early.log" && break
    sleep 0.1
done
grep -q "network interfaces changed since the DDS bus started.*fix: restart" "$work/early.log" ||
    fail "the listener did not warn within 5 s that its interfaces changed"
echo "the first listener warned: $(grep -o 'network interfaces changed[^(]*' "$work/early.log" | head -1)"

# The fix it names: a process started with the link up.
ip netns exec "$a" "$tool" listen pose --count 3 --timeout 30 "${common[@]}" >"$work/late.out" 2>"$work/late.log"
rc=$?
poses=$(grep -c '"vehicle":"ugv-late"' "$work/late.out")
[ "$rc" -eq 0 ] && [ "$poses" -ge 3 ] || fail "a listener started after the link came up printed $poses pose(s) (exit $rc)"
wait "$early"
early_poses=$(grep -c '"vehicle":"ugv-late"' "$work/early.out")
echo "a listener started after the link came up got $poses poses (the one started before got $early_poses)"

# The service: a vehicle and a ground station, started while their namespace's link is down.
ip netns add "$c" && ip -n "$c" link set lo up || fail "the service's namespace"
ip -n "$c" link add "lc$$" type veth peer name "ld$$" || fail "the service's veth pair"
"$tool" sim --course default --frames 10 --out "$work/course.ugvrec" >/dev/null || fail "sim --course"
cat >"$work/station.yaml" <<YAML
vehicle_id: gcs-late
vision:
  enabled: false
dds:
  domain_id: $domain
  partition: $partition
  shared_memory: false
correlator:
  enabled: true
  log_dir: $work/station
YAML
ip netns exec "$c" env UGV_DDS_DOMAIN="$domain" "$daemon" --replay "$work/course.ugvrec" --embedded-roudi --rate 10 \
    --loop --print-every 0 >"$work/vehicle.log" 2>&1 &
vehicle=$!
pids+=("$vehicle")
ip netns exec "$c" "$daemon" --config "$work/station.yaml" >"$work/station.log" 2>&1 &
station=$!
pids+=("$station")
sleep 3
kill -0 "$vehicle" 2>/dev/null || fail "the vehicle service did not start"
kill -0 "$station" 2>/dev/null || fail "the ground station did not start"
grep -q "network interfaces changed" "$work/vehicle.log" "$work/station.log" && fail "a warning before the link came up"
ip -n "$c" addr add 10.79.0.1/24 dev "lc$$" && ip -n "$c" link set "lc$$" up && ip -n "$c" link set "ld$$" up ||
    fail "the service's link"
echo "the service's link is up 3 s after its start"
for _ in $(seq 50); do
    grep -q "network interfaces changed" "$work/vehicle.log" && grep -q "network interfaces changed" "$work/station.log" &&
        break
    sleep 0.1
done
for who in vehicle station; do
    grep -q "network interfaces changed since the DDS bus started.*fix: restart" "$work/$who.log" ||
        fail "the $who did not warn within 5 s that its interfaces changed"
done
kill -TERM "$vehicle" "$station"
wait "$vehicle" || fail "the vehicle service exited with an error"
wait "$station" || fail "the ground station exited with an error"
grep -Eq "^dds: .* 1 network interface change\(s\)" "$work/vehicle.log" ||
    fail "the vehicle's bus report does not count the change"
echo "PASS: warned of the new link; $poses poses to the listener started after it (the one started before got $early_poses); the vehicle service and the ground station warned too, the vehicle's report counts 1 change"
