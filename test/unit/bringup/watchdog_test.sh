#!/usr/bin/env bash
# ugvsensed speaks systemd's notification protocol: READY=1 after start, WATCHDOG=1 while frames flow (the unit's
# WatchdogSec restarts a stalled service), STOPPING=1 at the end. A python3 datagram socket plays systemd.
# Usage: watchdog_test.sh UGVSENSE UGVSENSED WORKDIR RECORDING
set -u
tool=$1 service=$2 work=$3 recording=$4
rm -rf "$work" && mkdir -p "$work"
python3 - "$work/notify.sock" "$work/messages.txt" <<'PY' &
import socket, sys
s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
s.bind(sys.argv[1])
s.settimeout(30)
with open(sys.argv[2], "w") as out:
    while True:
        try:
            m = s.recv(4096).decode()
        except socket.timeout:
            break
        out.write(m + "\n"); out.flush()
        if "STOPPING=1" in m:
            break
PY
listener=$!
for _ in $(seq 50); do [ -S "$work/notify.sock" ] && break; sleep 0.1; done
NOTIFY_SOCKET="$work/notify.sock" WATCHDOG_USEC=400000 "$service" --replay "$recording" --embedded-roudi \
    --print-every 0 >"$work/service.log" 2>&1 || { cat "$work/service.log"; exit 1; }
wait $listener
cat "$work/messages.txt"
grep -q "READY=1" "$work/messages.txt" || { echo "no READY=1"; exit 1; }
pings=$(grep -c "WATCHDOG=1" "$work/messages.txt")
[ "$pings" -ge 3 ] || { echo "expected >= 3 watchdog pings over the 1.5 s replay, got $pings"; exit 1; }
grep -q "STOPPING=1" "$work/messages.txt" || { echo "no STOPPING=1"; exit 1; }
echo "READY, $pings watchdog pings, STOPPING: OK"
