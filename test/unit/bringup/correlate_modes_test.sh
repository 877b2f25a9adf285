#!/usr/bin/env bash
# Both correlator modes on simulator scenarios of issue 5's settings (5 UGVs, 600 s, seed 1): with heading bias
# (up to 8 deg) and position offsets (up to 1 m), and with a random-walk drift (0.05 m/sqrt(s)), mode pose-corrected
# must reach at most half of mode original's static GOSPA (c 5 m, p 2) at the last snapshot and at most half of its
# mean mobile GOSPA over the snapshots, and keep every static id when the errors are a bias. Accuracy, not speed:
# nothing here is timed.
# Usage: correlate_modes_test.sh UGVSENSE WORKDIR
set -u
tool=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }
static_gospa() { sed -n 's/^static at t = [0-9.]* s *\([0-9.]*\) .*/\1/p' "$1"; }
mobile_gospa() { sed -n 's/^mobile, mean *\([0-9.]*\) .*/\1/p' "$1"; }
at_most_half() { awk -v o="$1" -v i="$2" 'BEGIN { exit !(o > 0 && i <= o / 2) }'; }
for setting in bias drift; do
    "$tool" correlate-sim --setting "$setting" --out "$work/$setting.jsonl" --duration 600 --seed 1 >/dev/null ||
        fail "correlate-sim --setting $setting"
    for mode in original pose-corrected; do
        "$tool" correlate --mode "$mode" --input "$work/$setting.jsonl" --output "$work/$setting.$mode.jsonl" \
            >"$work/$setting.$mode.log" || fail "correlate --mode $mode"
        "$tool" correlate-eval --snapshots "$work/$setting.$mode.jsonl" --truth "$work/$setting.truth.jsonl" \
            >"$work/$setting.$mode.eval" || fail "correlate-eval ($setting, $mode)"
    done
    original=$(static_gospa "$work/$setting.original.eval")
    corrected=$(static_gospa "$work/$setting.pose-corrected.eval")
    echo "$setting: static GOSPA original $original m, pose-corrected $corrected m"
    at_most_half "$original" "$corrected" ||
        fail "$setting: static GOSPA of pose-corrected $corrected is not at most half of original $original"
    original=$(mobile_gospa "$work/$setting.original.eval")
    corrected=$(mobile_gospa "$work/$setting.pose-corrected.eval")
    echo "$setting: mobile GOSPA (mean) original $original m, pose-corrected $corrected m"
    at_most_half "$original" "$corrected" ||
        fail "$setting: mobile GOSPA of pose-corrected $corrected is not at most half of original $original"
done
grep -q "static ID changes: 0" "$work/bias.pose-corrected.eval" || fail "bias: pose-corrected changed a static id"
# improved is an alias of pose-corrected (its former name): the same snapshots, byte for byte.
"$tool" correlate --mode improved --input "$work/bias.jsonl" --output "$work/bias.improved.jsonl" >/dev/null ||
    fail "correlate --mode improved"
cmp "$work/bias.improved.jsonl" "$work/bias.pose-corrected.jsonl" || fail "--mode improved: other snapshots"
echo "OK"
