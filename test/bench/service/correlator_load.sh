#!/usr/bin/env bash
# bench: does the correlator task delay frames? The service's own latency report (`ugvsense bench`, 15 fps, the
# default course) twice in one run: without the correlator, and with it enabled (the lowest-priority task) while
# `ugvsense bus-send` feeds it 10,000 observations per second over DDS. Prints both end-to-end distributions and
# their ratio; it asserts nothing about time (a benchmark, label bench).
# Usage: correlator_load.sh UGVSENSE WORKDIR [FRAMES]
set -u
tool=$1 work=$2 frames=${3:-300}
rm -rf "$work" && mkdir -p "$work"
domain=$((180 + $$ % 40))
export UGV_DDS_DOMAIN=$domain
"$tool" sim --course default --frames 60 --out "$work/course.ugvrec" >/dev/null || exit 1
# 10 UGVs for 3.5 h of mission: more observations than the load needs.
"$tool" correlate-sim --setting bias --ugvs 10 --duration 12600 --out "$work/obs.jsonl" >/dev/null || exit 1
grep '"kind":"observation"' "$work/obs.jsonl" >"$work/observations.jsonl"
cat >"$work/plain.yaml" <<YAML
camera:
  replay_path: $work/course.ugvrec
dds:
  partition: load-$$
YAML
cat "$work/plain.yaml" - >"$work/loaded.yaml" <<YAML
correlator:
  enabled: true
  max_rate_per_source: 1000000
YAML
e2e() { grep -E "^ *end_to_end" "$1"; }
"$tool" bench --recording "$work/course.ugvrec" --rate 15 --frames "$frames" --config "$work/plain.yaml" \
    --json "$work/plain.json" >"$work/plain.log" 2>&1 || { cat "$work/plain.log"; exit 1; }
"$tool" bus-send --input "$work/observations.jsonl" --rate 10000 --partition "load-$$" --wait-readers 1 \
    >"$work/send.log" 2>&1 &
sender=$!
"$tool" bench --recording "$work/course.ugvrec" --rate 15 --frames "$frames" --config "$work/loaded.yaml" \
    --json "$work/loaded.json" >"$work/loaded.log" 2>&1 || { cat "$work/loaded.log"; kill $sender; exit 1; }
kill $sender 2>/dev/null
wait $sender 2>/dev/null
echo "without the correlator:"; e2e "$work/plain.log"; grep -E "^frames:|^cpu" "$work/plain.log"
echo "with the correlator fed 10,000 observations/s:"; e2e "$work/loaded.log"
grep -E "^frames:|^cpu|^correlator:" "$work/loaded.log"
python3 - "$work/plain.json" "$work/loaded.json" <<'PY'
import json, sys
a, b = (json.load(open(p))["end_to_end"] for p in sys.argv[1:3])
for k in ("p50_us", "p99_us", "max_us"):
    print(f"end to end {k}: {a[k] / 1000:.1f} ms without, {b[k] / 1000:.1f} ms with (ratio {b[k] / a[k]:.2f})")
PY
