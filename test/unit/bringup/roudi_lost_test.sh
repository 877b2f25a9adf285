#!/usr/bin/env bash
# RouDi crashing under a running ugvsensed: the service stops with a clear error and exit code 1 (systemd restarts
# it), and once RouDi runs again a new service works. Then the service crashing (-9) under a running RouDi: started
# again at once (systemd's restart), it registers under its name again (RouDi removes the dead one's ports; RouDi runs
# with -m off as its unit does, so this is the only clean-up) and publishes. Usage: roudi_lost_test.sh UGVSENSE UGVSENSED ROUDI_TOML WORKDIR RECORDING
set -u
tool=$1 service=$2 config=$3 work=$4 recording=$5
rm -rf "$work" && mkdir -p "$work"
if pgrep -x iox-roudi >/dev/null; then echo "another iox-roudi runs: this test needs its own"; exit 1; fi
start_roudi() {
    # A RouDi killed with -9 leaves its socket file: wait for the new RouDi's own (another inode), not the stale one.
    local stale
    stale=$(stat -c %i /tmp/roudi 2>/dev/null || echo none)
    iox-roudi -c "$config" -m off -l warning >>"$work/roudi.log" 2>&1 &
    roudi=$!
    for _ in $(seq 100); do
        [ -S /tmp/roudi ] && [ "$(stat -c %i /tmp/roudi 2>/dev/null)" != "$stale" ] && sleep 0.3 && return
        sleep 0.1
    done
}
trap 'kill $roudi 2>/dev/null; wait $roudi 2>/dev/null' EXIT # TERM: RouDi cleans its shared memory up
start_roudi
"$service" --replay "$recording" --loop --print-every 0 >"$work/service.log" 2>&1 &
svc=$!
sleep 3
kill -9 $roudi # a crash: RouDi cannot tell the service
wait $roudi 2>/dev/null
wait $svc
rc=$?
cat "$work/service.log" | grep -v "^  \|^capture\|^vision\|^publish"
[ $rc -eq 1 ] || { echo "expected exit code 1, got $rc"; exit 1; }
grep -q "RouDi went away during the run.*fix: restart RouDi" "$work/service.log" || { echo "no clear error"; exit 1; }
start_roudi
# --loop: a slow (sanitizer) build drops frames by latest-frame-wins and needs more than one pass for 4. On a loaded
# machine the new RouDi may not listen yet (its socket path can even reuse the killed one's inode): try again then.
for attempt in $(seq 20); do
    "$service" --replay "$recording" --loop --frames 4 --print-every 0 >"$work/again.log" 2>&1 && break
    grep -q "no RouDi is running" "$work/again.log" || { cat "$work/again.log"; exit 1; }
    [ "$attempt" -lt 20 ] || { cat "$work/again.log"; exit 1; }
    sleep 0.5
done
grep -q "frames: [4-9] published" "$work/again.log" || { cat "$work/again.log"; exit 1; }
"$service" --replay "$recording" --loop --print-every 0 >"$work/crashed.log" 2>&1 &
svc=$!
sleep 2 # registered and publishing
kill -0 $svc 2>/dev/null || { echo "FAIL: the service ended early"; cat "$work/crashed.log"; exit 1; }
kill -9 $svc
wait $svc 2>/dev/null
"$service" --replay "$recording" --loop --frames 4 --print-every 0 >"$work/restarted.log" 2>&1 ||
    { echo "FAIL: the service did not start again after its crash"; cat "$work/restarted.log"; exit 1; }
grep -q "frames: [4-9] published" "$work/restarted.log" || { cat "$work/restarted.log"; exit 1; }
echo "service stopped with a clear error when RouDi crashed, and ran again after RouDi restarted; started again after"
echo "its own crash, it registered again and published: OK"
