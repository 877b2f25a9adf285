#!/usr/bin/env bash
# `ugvsense correlate-sim` and `ugvsense correlate-eval` as binaries: a 60 s, 2-UGV scenario writes the input
# messages and the truth (default name OBS.truth.jsonl); the bias setting with --pose-corrections writes
# pose_correction lines; correlate-eval scores hand-made snapshots equal to a hand-made truth as GOSPA 0 (static
# and mobile) with the one ID change they contain, in the table and in --json; a missing file is exit 1.
# Usage: correlate_sim_eval_test.sh UGVSENSE FIXTURES WORKDIR
set -u
tool=$1 fixtures=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }

out=$("$tool" correlate-sim --out "$work/obs.jsonl" --duration 60 --ugvs 2 --seed 3 2>&1) || fail "correlate-sim: $out"
echo "$out"
[ -s "$work/obs.jsonl" ] && [ -s "$work/obs.truth.jsonl" ] || fail "missing output files"
[ "$(wc -l <"$work/obs.jsonl")" -gt 0 ] && [ "$(wc -l <"$work/obs.truth.jsonl")" -gt 0 ] || fail "empty output"
grep -q '"kind":"observation"' "$work/obs.jsonl" || fail "no observation lines"
grep -q '"kind":"uav"' "$work/obs.jsonl" || fail "no uav lines"
head -1 "$work/obs.truth.jsonl" | grep -q '"kind":"scenario"' || fail "the truth does not start with the scenario line"
[ "$(grep -c '"kind":"static"' "$work/obs.truth.jsonl")" -eq 20 ] || fail "expected 20 static truth lines"
grep -q '"kind":"moving"' "$work/obs.truth.jsonl" || fail "no moving truth lines"

out=$("$tool" correlate-sim --out "$work/bias.jsonl" --truth "$work/bias-truth.jsonl" --setting bias --duration 130 \
      --ugvs 2 --pose-corrections 2>&1) || fail "correlate-sim --setting bias: $out"
[ "$(grep -c '"kind":"pose_correction"' "$work/bias.jsonl")" -eq 6 ] || fail "expected 2 UGVs x 3 pose corrections"
grep -q '"setting":"bias"' "$work/bias-truth.jsonl" || fail "the truth does not name the setting"

out=$("$tool" correlate-eval --snapshots "$fixtures/correlate_eval_snapshots.jsonl" \
      --truth "$fixtures/correlate_eval_truth.jsonl" --json "$work/eval.json" 2>&1) || fail "correlate-eval: $out"
echo "$out"
grep -Eq 'static at t = 2\.0 s +0\.000 +0\.000 +0\.000 +0\.000 +2 assigned, 0 missed, 0 false' <<<"$out" ||
    fail "static GOSPA is not 0"
grep -Eq 'mobile, mean +0\.000 +0\.000 +0\.000 +0\.000 +over 3 snapshots' <<<"$out" || fail "mobile GOSPA is not 0"
grep -q 'static ID changes: 1' <<<"$out" || fail "expected one static ID change"
grep -q '"gospa_m": 0.0' "$work/eval.json" || fail "--json lacks static gospa_m 0"
grep -q '"static_id_changes": 1' "$work/eval.json" || fail "--json lacks static_id_changes"

out=$("$tool" correlate-eval --snapshots /nonexistent.jsonl --truth "$fixtures/correlate_eval_truth.jsonl" 2>&1)
rc=$?
[ $rc -eq 1 ] && grep -q '/nonexistent.jsonl: cannot open the snapshot file' <<<"$out" || fail "missing file: exit $rc: $out"
echo "OK"
