#!/usr/bin/env bash
# correlate-eval --sweep --quick: both modes over the quick grid (the two centres and issue 21's scenarios, 10 seeds,
# 600 s each): every point is printed with the median and the worst seed of both modes, the JSON summary holds every
# seed's figures, and the targets that hold today stay held (a regression fails here). Accuracy, not speed.
# Usage: correlate_sweep_test.sh UGVSENSE WORKDIR
set -u
tool=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }
"$tool" correlate-eval --sweep --quick --json "$work/sweep.json" >"$work/sweep.txt" || fail "the sweep exited $?"
cat "$work/sweep.txt"
for point in sim sim/bias-setting harsh harsh/drift=0.05; do
    grep -q "^$point " "$work/sweep.txt" || fail "no row for $point"
done
python3 - "$work/sweep.json" <<'PY' || fail "the JSON summary"
import json, sys
j = json.load(open(sys.argv[1]))
points = {p["name"]: p for p in j["points"]}
assert set(points) == {"sim", "sim/bias-setting", "harsh", "harsh/drift=0.05"}, points.keys()
assert j["seeds"] == 10 and j["duration_s"] == 600 and j["machine"], j
for p in j["points"]:
    for mode in ("original", "pose-corrected"):
        for figure in ("static_gospa_m", "mobile_gospa_m", "static_id_changes", "static_false"):
            s = p[mode][figure]
            assert len(s["seeds"]) == 10, (p["name"], mode, figure)
            assert s["worst"] == max(s["seeds"]) and min(s["seeds"]) <= s["median"] <= s["worst"]
    assert p["pose_errors"] == (p["name"] != "sim"), p["name"]
# Held today (see correlator/README.md, "Sweep"): the issue 5 bias setting meets every target.
assert points["sim/bias-setting"]["targets"]["all"], points["sim/bias-setting"]["targets"]
assert "summary" in j and j["summary"]["points"] == 4
PY
echo "OK"
