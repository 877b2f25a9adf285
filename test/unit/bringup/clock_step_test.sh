#!/usr/bin/env bash
# A wall-clock step under a running ugvsensed (chrony or GPS setting the clock at boot): the clock is stepped back an
# hour, put right (a step forward), then back an hour again. Frames go on being published through every step (the
# service's stamps and waits are CLOCK_MONOTONIC), and SIGTERM with the clock an hour behind stops it (its stop also
# ends iceoryx's frame wait, which runs on CLOCK_REALTIME and which a step during the wait would stretch:
# FrameSubscriber::wake, unit test IceoryxRings.WakeEndsAWaitOfAnHourAtOnce). Each time the clock is an hour behind,
# the test holds 3 s: iceoryx 2.0's runtime sends RouDi its keep-alive from a task that waits on CLOCK_REALTIME, so a
# step back stalls it for the hour; a RouDi that monitors its clients removes the service after 1.5 s and the service
# aborts at its next chunk (POPO__CHUNK_LOCKING_ERROR, seen once in CI and then every time with the hold). RouDi is
# started with the options of the ugvsense-roudi unit (read from it: `-m off`), so the test covers what is deployed.
# Steps beyond the true time are left out: files written then would carry future times and mislead make-like tools
# on the machine. Needs CAP_SYS_TIME (root): skipped with a message otherwise. Run alone (ctest RUN_SERIAL): it moves
# the machine's clock.
# Usage: clock_step_test.sh UGVSENSE UGVSENSED ROUDI_TOML WORKDIR RECORDING ROUDI_UNIT
set -u
tool=$1 service=$2 config=$3 work=$4 recording=$5 unit=$6
# The unit's RouDi options after its config file (e.g. "-m off -l warning").
options=$(sed -n 's|^ExecStart=/usr/bin/iox-roudi -c @UGV_CONFDIR@/roudi.toml ||p' "$unit")
[ -n "$options" ] || { echo "FAIL: no 'ExecStart=/usr/bin/iox-roudi -c @UGV_CONFDIR@/roudi.toml ...' in $unit"; exit 1; }
rm -rf "$work" && mkdir -p "$work"
# The offset of the wall clock from the monotonic one, kept in a file: whatever happens, the clock is put back.
python3 - "$work/offset" <<'PY' || { echo "SKIP: cannot set the clock here (needs root / CAP_SYS_TIME)"; exit 77; }
import sys, time
time.clock_settime(time.CLOCK_REALTIME, time.time())  # a no-op step: is it permitted?
open(sys.argv[1], "w").write(repr(time.time() - time.monotonic()))
PY
step() { python3 -c "import time; time.clock_settime(time.CLOCK_REALTIME, time.time() + $1)"; }
restore() { python3 -c "import time; time.clock_settime(time.CLOCK_REALTIME, time.monotonic() + float(open('$work/offset').read()))"; }
if pgrep -x iox-roudi >/dev/null; then echo "another iox-roudi runs: this test needs its own"; exit 1; fi
# shellcheck disable=SC2086 # the unit's options, split as systemd splits them
iox-roudi -c "$config" $options >"$work/roudi.log" 2>&1 &
roudi=$!
svc=""
trap 'restore; [ -n "$svc" ] && kill -9 $svc 2>/dev/null; kill $roudi 2>/dev/null; wait 2>/dev/null' EXIT
for _ in $(seq 100); do [ -S /tmp/roudi ] && break; sleep 0.1; done
sleep 0.3
"$service" --replay "$recording" --loop --print-every 1 >"$work/service.log" 2>&1 &
svc=$!
published() { grep -c "^frame " "$work/service.log"; }
wait_for_more() { # $1: what happened; fails when no new frame comes within 200 polls
    local before
    before=$(published)
    for _ in $(seq 200); do
        [ "$(published)" -gt $((before + 3)) ] && return 0
        kill -0 $svc 2>/dev/null || { echo "FAIL: the service ended $1"; cat "$work/service.log"; exit 1; }
        sleep 0.05
    done
    echo "FAIL: no frame published $1 ($before before)"; tail "$work/service.log"; exit 1
}
wait_for_more "at start"
step -3600
sleep 3 # past RouDi's 1.5 s keep-alive timeout
wait_for_more "after the clock was stepped back an hour"
restore
wait_for_more "after the clock was stepped forward an hour (put right)"
step -3600
sleep 3
wait_for_more "with the clock an hour behind again"
kill -TERM $svc
for _ in $(seq 200); do kill -0 $svc 2>/dev/null || break; sleep 0.05; done
kill -0 $svc 2>/dev/null && { echo "FAIL: SIGTERM did not stop the service with the clock an hour behind"; exit 1; }
wait $svc
rc=$?
svc=""
restore
[ $rc -eq 0 ] || { echo "FAIL: exit code $rc"; cat "$work/service.log"; exit 1; }
grep -q "frames: [0-9]* published" "$work/service.log" || { echo "FAIL: no report"; cat "$work/service.log"; exit 1; }
grep -q "not responding" "$work/roudi.log" && { echo "FAIL: RouDi removed a client"; cat "$work/roudi.log"; exit 1; }
echo "frames went on through clock steps of -1 h (3 s), +1 h, -1 h (3 s) ($(published) published); SIGTERM stopped it: OK"
