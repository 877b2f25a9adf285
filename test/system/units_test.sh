#!/usr/bin/env bash
# The systemd units (bringup/deploy/systemd/*.service.in, configured with this build tree's programs):
#   - `systemd-analyze verify` passes with no output at all (it exits 0 even on unknown keys, so any line fails);
#   - `systemd-analyze security --offline=yes` rates ugvsensed.service at 2.0 or lower ("OK"), and the other units
#     lower still;
#   - both checks catch what they should: a unit with a misspelt key and an unhardened unit fail them.
# usage: units_test.sh UNIT_DIR WORK_DIR
set -euo pipefail
units=$1
work=$2
fail() { echo "FAIL: $*" >&2; exit 1; }
command -v systemd-analyze >/dev/null || fail "systemd-analyze not found (apt-get install systemd; host.sh deps does)"
rm -rf "$work" && mkdir -p "$work"

verify() { # prints what verify said; returns 0 only when it said nothing and exited 0
    local out rc=0
    out=$(systemd-analyze verify --man=no "$@" 2>&1) || rc=$?
    [ -n "$out" ] && echo "$out"
    [ "$rc" -eq 0 ] && [ -z "$out" ]
}

exposure() { # the overall exposure of unit $1, e.g. 1.9
    systemd-analyze security --offline=yes "$1" 2>&1 | sed -n 's/.*Overall exposure level for .*: \([0-9.]*\) .*/\1/p'
}

echo "== verify"
verify "$units"/ugvsensed.service "$units"/ugvsense-roudi.service "$units"/ugvsense-default-recording.service \
    "$units"/ugvsense-record.service ||
    fail "systemd-analyze verify complained about the units (above)"

echo "== security (exposure, lower is better; 2.0 or lower is OK)"
declare -A limit=([ugvsensed]=2.0 [ugvsense-roudi]=1.5 [ugvsense-default-recording]=1.5 [ugvsense-record]=1.5)
for unit in "${!limit[@]}"; do
    level=$(exposure "$units/$unit.service")
    [ -n "$level" ] || fail "$unit.service: systemd-analyze security gave no overall exposure level"
    echo "$unit.service: $level (limit ${limit[$unit]})"
    awk -v a="$level" -v b="${limit[$unit]}" 'BEGIN { exit !(a <= b) }' ||
        fail "$unit.service: exposure $level is above ${limit[$unit]} (systemd-analyze security --offline=yes lists what)"
    # The same limit as systemd-analyze's own threshold check (a x10 scale), which a deployment script can use.
    threshold=$(awk -v b="${limit[$unit]}" 'BEGIN { printf "%d", b * 10 }')
    systemd-analyze security --offline=yes --threshold="$threshold" "$units/$unit.service" >/dev/null 2>&1 ||
        fail "$unit.service: systemd-analyze security --threshold=$threshold failed"
done

echo "== the checks catch what they should"
sed 's/^Restart=on-failure$/Restart=on-failure\nRestartSecs=2s/' "$units/ugvsensed.service" >"$work/ugvsensed.service"
grep -q '^RestartSecs=' "$work/ugvsensed.service" || fail "could not make the misspelt unit"
cp "$units/ugvsense-roudi.service" "$work/"
if verify "$work/ugvsensed.service" >/dev/null; then
    fail "verify passed a unit with a misspelt key (RestartSecs=)"
fi
printf '[Unit]\nDescription=unhardened\n\n[Service]\nExecStart=/bin/true\n' >"$work/plain.service"
level=$(exposure "$work/plain.service")
awk -v a="$level" 'BEGIN { exit !(a > 2.0) }' || fail "an unhardened unit rated $level, not above 2.0"
echo "misspelt key: refused; unhardened unit: $level (refused)"
echo "PASS"
