#!/usr/bin/env bash
# A second DDS implementation on the service's bus (issue 23 item 1, and its Nav2-consumer target): ugvsensed
# replays the default simulator course (Fast DDS) while cyclone-interop (Cyclone DDS, its own IDL) discovers it,
# reads the ROS 2 LaserScans (marking and clearing) and PointCloud2 with a reliable reader and checks every field, checks the rays against
# ugvsense/sectors, writes the vehicle's pose, and applies the README's Nav2 obstacle layer block (read from
# README.md here, so the documented settings are the tested ones). Then `ugvsense listen sectors` (Fast DDS)
# confirms that the service used the Cyclone pose, and the service's bus report counts it.
# Usage: cyclone_interop_test.sh UGVSENSE UGVSENSED CYCLONE_INTEROP README WORKDIR DOMAIN
set -u
tool=$1 daemon=$2 interop=$3 readme=$4 work=$5 domain=$6
rm -rf "$work" && mkdir -p "$work"
export UGV_DDS_DOMAIN=$domain
unset CYCLONEDDS_URI # Cyclone's defaults, as a fresh ROS 2 install has them
svc=""
cleanup() { [ -n "$svc" ] && kill -9 "$svc" 2>/dev/null; wait 2>/dev/null; true; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$work"/*.log; do echo "--- $f"; tail -n 20 "$f"; done; exit 1; }

# The Nav2 block of the README, as SOURCE.KEY=VALUE arguments.
# shellcheck source=test/interop/common.sh
source "$(dirname "$0")/common.sh"
mapfile -t nav2 < <(nav2_from_readme "$readme")
[ "${#nav2[@]}" -ge 10 ] || fail "no Nav2 obstacle layer block in $readme (found ${#nav2[*]} keys)"
printf 'Nav2 (README): %s\n' "${nav2[*]}"

# The default course at 1 fps: its 21 frames are 1.5 m apart and cover the whole 30 m drive, past both of its
# negative obstacles (bringup/sim/src/scene.cpp makeCourse: a hole of 0.8 m diameter centred at (14.5, -0.4) and a
# trench 1 m wide across the drive at 36.5), in 10 s of rendering; replayed at 10 Hz.
"$tool" sim --course default --fps 1 --frames 21 --out "$work/course.ugvrec" >/dev/null || fail "sim --course"
"$daemon" --replay "$work/course.ugvrec" --embedded-roudi --rate 10 --loop --print-every 0 >"$work/service.log" 2>&1 &
svc=$!
# The defaults of the service that the checks depend on: vehicle ugv-1 -> ROS namespace ugv1, frame
# <ns>/ugvsense_ground, Clear = free ground to 5 m (SectorBuilderConfig::clearRangeM), drops at least
# obstacles.min_depth_m (0.10 m) deep.
"$interop" --domain "$domain" --ns ugv1 --frame ugv1/ugvsense_ground --vehicle ugv-1 --participant ugvsense/ugv-1 --duration 15 --min-duration 6 --frames 30 \
    --clear-range 5.0 --min-depth 0.10 --truth "$work/course.ugvrec.truth.csv" --drop hole:14.5,-0.4,0.4,0.4 \
    --drop trench:36.5,0,0.5,20 "${nav2[@]}" >"$work/interop.out" 2>"$work/interop.log" &
reader=$!
sleep 2
"$tool" listen sectors --count 10 --timeout 10 >"$work/sectors.out" 2>"$work/sectors.log" || fail "listen sectors"
ours=$(grep -c '"pose_valid":true,"pose_stale":false.*"east_m":123.25' "$work/sectors.out")
wait "$reader"
rc=$?
cat "$work/interop.out"
[ "$rc" -eq 0 ] || fail "cyclone-interop exited with $rc"
[ "$ours" -ge 8 ] || fail "only $ours of 10 sectors samples (Fast DDS listener) carry the Cyclone pose"
stop_service "^dds: [1-9][0-9]* frame\(s\) sent.*poses [1-9][0-9]* used, 0 of other vehicles, 0 refused" \
    "no bus report with the Cyclone poses used and none refused"
echo "OK: Cyclone DDS <-> Fast DDS: scan, cloud and sectors read and checked, $ours/10 sectors samples with the Cyclone pose"
