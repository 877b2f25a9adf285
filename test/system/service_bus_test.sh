#!/usr/bin/env bash
# The vehicle service on the DDS bus (issue 6): ugvsensed replays a simulator course while `ugvsense bus-send
# --poses` plays the localisation (10 Hz); `ugvsense listen` checks what a consumer on another process sees:
# ugvsense/sectors with the pose interpolated at the capture time (valid, not stale), the ROS 2 LaserScan (one ray
# per sector: +inf clear, NaN unknown), the clearing LaserScan (range_max the clear range, 5 m: no finite ray at or
# beyond it) and PointCloud2, ROS 2's graph (the node /ugv1/ugvsense and its three writers
# on ros_discovery_info, what `ros2 node list` reads), and the health record (transient local: a late listener
# gets it). Then the poses stop: the sectors' poses turn stale. The service ends cleanly with its bus report.
# Usage: service_bus_test.sh UGVSENSE UGVSENSED WORKDIR DOMAIN
set -u
tool=$1 daemon=$2 work=$3 domain=$4
rm -rf "$work" && mkdir -p "$work"
export UGV_DDS_DOMAIN=$domain
svc=""
cleanup() { [ -n "$svc" ] && kill -9 "$svc" 2>/dev/null; wait 2>/dev/null; true; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$work"/*.log; do echo "--- $f"; tail -n 20 "$f"; done; exit 1; }
"$tool" sim --course default --frames 20 --out "$work/course.ugvrec" >/dev/null || fail "sim --course"
"$daemon" --replay "$work/course.ugvrec" --embedded-roudi --rate 10 --loop --print-every 0 >"$work/service.log" 2>&1 &
svc=$!
"$tool" bus-send --poses ugv-1 --rate 10 --duration 8 >"$work/poses.log" 2>&1 &
poser=$!
sleep 2
"$tool" listen sectors --count 20 --timeout 30 >"$work/sectors.out" 2>"$work/sectors.log" || fail "listen sectors"
fresh=$(grep -c '"pose_valid":true,"pose_stale":false' "$work/sectors.out")
[ "$fresh" -ge 10 ] || fail "only $fresh of 20 sectors samples carry a fresh pose"
grep -q '"sectors":\[{' "$work/sectors.out" || fail "sectors samples without sectors"
"$tool" listen scan --count 3 --timeout 30 >"$work/scan.out" 2>"$work/scan.log" ||
    fail "listen scan"
grep -q '"frame_id":"ugv1/ugvsense_ground"' "$work/scan.out" || fail "LaserScan frame id"
grep -q '"inf"' "$work/scan.out" || fail "no clear (+inf) ray in the LaserScan"
grep -Eq '"ranges":\[[^]]*[0-9]\.[0-9]' "$work/scan.out" || fail "no obstacle range in the LaserScan"
"$tool" listen clear_scan --count 3 --timeout 30 >"$work/clear.out" 2>"$work/clear.log" || fail "listen clear_scan"
grep -q '"frame_id":"ugv1/ugvsense_ground"' "$work/clear.out" || fail "clearing LaserScan frame id"
grep -Eq '"range_max":5(\.0)?[,}]' "$work/clear.out" || fail "the clearing LaserScan's range_max is not the clear range (5 m)"
grep -q '"inf"' "$work/clear.out" || fail "no clear (+inf) ray in the clearing LaserScan"
grep -o '"ranges":\[[^]]*\]' "$work/clear.out" | grep -Eq '[^0-9.]([5-9]|[1-9][0-9]+)\.[0-9]' &&
    fail "a finite ray at or beyond the clear range in the clearing LaserScan"
"$tool" listen negatives --count 1 --timeout 30 >"$work/cloud.out" 2>"$work/cloud.log" ||
    fail "listen negatives"
grep -q '"point_step":12' "$work/cloud.out" || fail "PointCloud2 layout"
"$tool" listen ros_discovery --count 1 --timeout 30 >"$work/graph.out" 2>"$work/graph.log" || fail "listen ros_discovery"
grep -Eq '"node_namespace":"/ugv1","node_name":"ugvsense","reader_gids":\[\],"writer_gids":\["[0-9a-f]{48}","[0-9a-f]{48}","[0-9a-f]{48}"\]' \
    "$work/graph.out" || fail "ros_discovery_info does not show the node /ugv1/ugvsense with its three ROS 2 writers"
"$tool" listen health --count 1 --timeout 30 >"$work/health.out" 2>"$work/health.log" || fail "listen health"
grep -Eq '"frames_processed":[1-9]' "$work/health.out" || fail "health without processed frames"
wait "$poser"
sleep 2 # pose_max_age_ms is 600
"$tool" listen sectors --count 5 --timeout 30 >"$work/stale.out" 2>"$work/stale.log" || fail "listen sectors (stale)"
stale=$(grep -c '"pose_stale":true' "$work/stale.out")
[ "$stale" -eq 5 ] || fail "after the poses stopped, only $stale of 5 samples are flagged stale"
kill -TERM "$svc"
wait "$svc" || fail "the service exited with an error"
svc=""
grep -E "^dds: [1-9][0-9]* frame\(s\) sent.*poses [1-9]" "$work/service.log" || fail "no bus report with poses used"
echo "OK: $fresh/20 sectors with a fresh pose, the two LaserScans, PointCloud2, the ROS 2 node and health seen; stale after the poses stopped"
