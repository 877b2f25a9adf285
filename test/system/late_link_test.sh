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
# Skipped with a message where network namespaces cannot be made.
# Usage: late_link_test.sh UGVSENSE WORKDIR DOMAIN
set -u
tool=$1 work=$2 domain=$3
rm -rf "$work" && mkdir -p "$work"
a="ugvlateA$$" b="ugvlateB$$"
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null; done
    wait 2>/dev/null
    ip netns del "$a" 2>/dev/null
    ip netns del "$b" 2>/dev/null
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
echo "PASS: warned of the new link; $poses poses to the listener started after it (the one started before got $early_poses)"
