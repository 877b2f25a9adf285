#!/usr/bin/env bash
# A ROS 2 node on the secured bus (issue 22 item 4: "ROS 2 topics keep working for a ROS 2 node given the same
# security files"). There is no ROS 2 in Debian 12, so the node is cyclone-interop joining as rmw_cyclonedds_cpp
# does under SROS2: Cyclone DDS's own three security plugins, set up property by property from an enclave folder.
# The service (Fast DDS, dds.security on) replays the default course as ugv-1; bringup/deploy/security/make_security.sh
# makes the team (ugv-1) and a ROS 2 enclave (--ros nav2) from one CA, and another CA's nav2. Checked:
#   1. with the team's nav2 enclave, Cyclone reads the two LaserScans and the PointCloud2, every field checks out
#      and the README's Nav2 block marks every published drop point and clears nothing beyond Clear's 5 m, as on
#      the open bus (system.cyclone-interop);
#   2. a Cyclone participant without a certificate and one with another CA's enclave discover nothing of the
#      service and receive 0 samples in 10 s (the first also writes ugvsense/pose in ugv-1's name: the service
#      uses none of them).
# The intruders start after the certified node is done: failing handshakes beside a starting one slow it down on a
# 2-core machine (see test/system/secured_bus_test.sh).
# Usage: cyclone_secured_test.sh UGVSENSE UGVSENSED CYCLONE_INTEROP MAKE_SECURITY README WORKDIR DOMAIN
set -u
tool=$1 daemon=$2 interop=$3 make_security=$4 readme=$5 work=$6 domain=$7
rm -rf "$work" && mkdir -p "$work"
unset CYCLONEDDS_URI
svc=""
cleanup() { [ -n "$svc" ] && kill -9 "$svc" 2>/dev/null; wait 2>/dev/null; true; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$work"/*.log "$work"/*.out; do echo "--- $f"; tail -n 20 "$f"; done; exit 1; }
command -v openssl >/dev/null || { echo "SKIPPED: openssl is not installed"; exit 0; }
# shellcheck source=test/interop/common.sh
source "$(dirname "$0")/common.sh"
mapfile -t nav2 < <(nav2_from_readme "$readme")
[ "${#nav2[@]}" -ge 10 ] || fail "no Nav2 obstacle layer block in $readme (found ${#nav2[*]} keys)"

partition="interop-$$"
bash "$make_security" "$work/team" --partition "$partition" --ros nav2 ugv-1 >"$work/make.log" 2>&1 ||
    fail "make_security.sh"
bash "$make_security" "$work/rogue" --partition "$partition" --ros nav2 >>"$work/make.log" 2>&1 ||
    fail "make_security.sh (the other CA)"
# The default course as in system.cyclone-interop: 21 frames 1.5 m apart, past its hole and trench.
"$tool" sim --course default --fps 1 --frames 21 --out "$work/course.ugvrec" >/dev/null || fail "sim --course"
# shellcheck source=test/support/security_yaml.sh
source "$(dirname "$0")/../support/security_yaml.sh"
sec=$work/team/ugv-1
cat >"$work/ugv-1.yaml" <<YAML
vehicle_id: ugv-1
camera:
  backend: replay
  replay_path: $work/course.ugvrec
dds:
  domain_id: $domain
  partition: $partition
$(security_yaml "$sec")
YAML
"$tool" check-config "$work/ugv-1.yaml" >"$work/check.log" 2>&1 || fail "check-config of the secured vehicle"

"$daemon" --config "$work/ugv-1.yaml" --replay "$work/course.ugvrec" --embedded-roudi --rate 10 --loop \
    --print-every 0 >"$work/service.log" 2>&1 &
svc=$!
common=(--domain "$domain" --ns ugv1 --frame ugv1/ugvsense_ground --vehicle ugv-1 --clear-range 5.0 --min-depth 0.10)
# The drops are not placed on the course's truth here: that needs ugvsense/sectors' frame numbers, which a ROS 2
# node may not read.
"$interop" "${common[@]}" --enclave "$work/team/nav2" --participant ugvsense/ugv-1 --duration 40 --min-duration 2 \
    --frames 30 "${nav2[@]}" >"$work/certified.out" 2>"$work/certified.log"
rc=$?
cat "$work/certified.out"
[ "$rc" -eq 0 ] || fail "the certified ROS 2 node (cyclone-interop --enclave) exited with $rc"

"$interop" "${common[@]}" --expect-denied --duration 10 >"$work/open.out" 2>"$work/open.log" &
open=$!
"$interop" "${common[@]}" --expect-denied --enclave "$work/rogue/nav2" --duration 10 >"$work/rogue.out" \
    2>"$work/rogue.log" &
rogue=$!
wait "$open"
rc_open=$?
wait "$rogue"
rc_rogue=$?
cat "$work/open.out" "$work/rogue.out"
[ "$rc_open" -eq 0 ] || fail "a Cyclone participant without a certificate saw the secured service (rc $rc_open)"
[ "$rc_rogue" -eq 0 ] || fail "a Cyclone participant with another CA's enclave saw the secured service (rc $rc_rogue)"

stop_service "^dds: [1-9][0-9]* frame\(s\) sent.*poses 0 used" \
    "no bus report, or the service used a pose from the uncertified participant"
echo "OK: a ROS 2 node's SROS2 enclave (Cyclone DDS's security plugins) reads the secured service's ROS 2 topics;" \
    "without a certificate or with another CA's: nothing discovered, 0 samples, 0 poses injected"
