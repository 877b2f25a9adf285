#!/usr/bin/env bash
# expect_exit.sh CODE REGEX COMMAND...: runs COMMAND, passes when it exits with CODE (a crash never passes)
# and its combined output matches the extended REGEX (across lines). For testing command-line error paths.
set -u
want=$1 regex=$2
shift 2
out=$("$@" 2>&1)
got=$?
printf '%s\n' "$out"
[ "$got" -eq "$want" ] || { echo "FAIL: exit code $got, expected $want"; exit 1; }
grep -qzE -- "$regex" <<<"$out" || { echo "FAIL: output does not match: $regex"; exit 1; }
echo "OK: exit $got and output matches"
