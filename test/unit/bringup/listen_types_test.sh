#!/usr/bin/env bash
# `ugvsense listen` on every topic: the writer role of unit-dds (every type, every field distinctive) publishes,
# and listen prints one sample of each topic as JSON with the expected fields (by short and by wire name).
# Usage: listen_types_test.sh UGVSENSE UNIT_DDS
set -u
tool=$1 unit=$2
domain=$((150 + $$ % 80))
part="listen_types_$$"
# 110 s: eleven listen processes one after another took more than the writer's default 30 s under ASan in a
# parallel ctest run (the last topic found no publisher); the trap stops it.
UGV_DDS_TEST_ROLE=writer UGV_DDS_TEST_DOMAIN=$domain UGV_DDS_TEST_PARTITION=$part UGV_DDS_TEST_WRITER_S=110 \
    "$unit" --gtest_filter=DdsTwoProcess.EveryTypeRoundTripsWithAllFields >/dev/null &
writer=$!
trap 'kill $writer 2>/dev/null; wait $writer 2>/dev/null' EXIT
check() { # topic regex
    local out
    out=$("$tool" listen "$1" --count 1 --timeout 10 --domain "$domain" --partition "$part" --ros-namespace "$part" 2>&1)
    local rc=$?
    echo "$out" | cut -c1-300
    [ $rc -eq 0 ] || { echo "FAIL: listen $1 exited $rc"; exit 1; }
    grep -qE -- "$2" <<<"$out" || { echo "FAIL: listen $1: no match for $2"; exit 1; }
}
check sectors '"sequence_number":987654321012,.*"pose":\{"vehicle":"ugv-roundtrip-7".*"ground":\{"reliable":true,"pitch_deg":-2.5.*"sectors":\[\{"bearing_min_deg":-30.0.*"range_m":"inf"'
check health '"camera_state":1,"bus_drops":8,"rejected_messages":9\}'
check pose '"heading_deg":271.5,"covariance":\[0.04,0.001,0.002,0.003,0.05,0.004,0.005,0.006,1.5\]'
check observations '"ugv":"ugv-3","sequence_number":4242,"t":123.456,"track":"track-uuid-9f8e","cls":2'
check ugvsense/ooi/uav '"source":"uav-hawk","sequence_number":77'
check confirmations '"id":"ooi-17","state":2'
check pose_corrections '"since_t":310.5,"until_t":390.25,"d_east_m":1.5'
check correlated '"ugvs":\["ugv-1","ugv-2"\].*"alerts":\[\{"non_combatant_id":"ooi-3","object_id":"ooi-1","distance_m":4.5\}'
check scan '"frame_id":"ugv1/camera_ground".*"ranges":\[1.5,"inf",3.5,4.25,5.125\],"intensities":\[10.0,'
check "rt/$part/negative_obstacles" '"row_step":24,"data":"a0a1a2.*b7","is_dense":true'
check ros_discovery '"gid":"101112131415161718191a1b1c1d1e1f2021222324252627","nodes":\[\{"node_namespace":"/ugv_roundtrip","node_name":"ugvsense_roundtrip","reader_gids":\["(5a){24}"\],"writer_gids":\["(a5){24}","(5a){24}"\]'
echo "OK"
