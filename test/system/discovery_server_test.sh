#!/usr/bin/env bash
# The discovery-server option (issue 6, meshes without multicast): a Fast DDS discovery server on this host, a
# sender and a listener that know only the server's address (dds.discovery_server / --discovery-server). Every
# sample arrives.
# Usage: discovery_server_test.sh UGVSENSE WORKDIR DOMAIN
set -u
tool=$1 work=$2 domain=$3
rm -rf "$work" && mkdir -p "$work"
command -v fastdds >/dev/null || { echo "SKIPPED: fastdds (package fastdds-tools) is not installed"; exit 0; }
port=$((20000 + $$ % 20000))
server=""
# `fastdds discovery` is a wrapper that starts fast-discovery-server as its child: the server runs in a session of
# its own and the whole group is stopped, else the child outlives the test.
cleanup() { [ -n "$server" ] && { kill -- -"$server" 2>/dev/null || kill "$server" 2>/dev/null; }; wait 2>/dev/null; true; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$work"/*.log; do echo "--- $f"; tail -n 20 "$f"; done; exit 1; }
setsid fastdds discovery -i 0 -l 127.0.0.1 -p "$port" >"$work/server.log" 2>&1 &
server=$!
sleep 1
kill -0 "$server" 2>/dev/null || fail "the discovery server did not start"
"$tool" correlate-sim --ugvs 2 --duration 30 --out "$work/scenario.jsonl" >/dev/null || fail "correlate-sim"
# The observations only: bus-send waits for a reader of each topic it sends, and the listener reads this one.
grep '"kind":"observation"' "$work/scenario.jsonl" >"$work/obs.jsonl"
n=$(wc -l <"$work/obs.jsonl")
opts=(--domain "$domain" --discovery-server "127.0.0.1:$port")
"$tool" listen observations "${opts[@]}" --count "$n" --timeout 60 >"$work/listen.out" 2>"$work/listen.log" &
listener=$!
"$tool" bus-send --input "$work/obs.jsonl" "${opts[@]}" >"$work/send.log" 2>&1 || fail "bus-send through the server"
wait "$listener" || fail "listen through the server"
got=$(wc -l <"$work/listen.out")
[ "$got" -eq "$n" ] || fail "$got of $n observations arrived through the discovery server"
echo "OK: $n observations through the discovery server at 127.0.0.1:$port"
