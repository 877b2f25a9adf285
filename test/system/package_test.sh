#!/usr/bin/env bash
# The Debian package (issue 7), for real but in a scratch root: cpack builds the .deb from this build; it is
# installed with dpkg in an overlay of this machine's / (a private mount namespace: nothing on the host changes),
# which has the package's dependencies because host.sh installed them. Then:
#   - the package's control data: dependencies (libraries from dpkg-shlibdeps, iceoryx, adduser), conffiles;
#   - after dpkg -i: the FHS layout, the system user (in group video, no login shell), /var/lib/ugvsense owned by
#     it, nothing enabled, the installed units verified and rated by systemd-analyze, the shipped config valid;
#   - `systemctl start ugvsensed` as the units do it: systemd is not PID 1 here, so the units' ExecStart lines run
#     in their order (default recording, RouDi, ugvsensed) as their User= with their LimitRTPRIO/LimitMEMLOCK and
#     ambient capabilities; ugvsensed must publish frames from the embedded default recording and stop cleanly
#     on SIGTERM with its latency report;
#   - an upgrade (the same package again) keeps an edited conffile; dpkg -r keeps the conffiles, dpkg -P removes
#     them and the generated recording but keeps what an operator recorded.
# usage: package_test.sh BUILD_DIR WORK_DIR DDS_DOMAIN
set -euo pipefail
build=$1
work=$2
domain=$3
skip() { echo "SKIPPED: $*"; exit 0; }
fail() { echo "FAIL: $*" >&2; exit 1; }

[ "$(id -u)" -eq 0 ] || skip "needs root (dpkg -i into an overlay of / in a private mount namespace)"
for tool in cpack dpkg-deb dpkg-shlibdeps unshare setpriv prlimit systemd-analyze; do
    command -v "$tool" >/dev/null || skip "$tool not found (bash toolchain/host.sh deps installs it)"
done
rm -rf "$work" && mkdir -p "$work"

echo "== cpack"
cpack --config "$build/CPackConfig.cmake" -B "$work/pkg" >"$work/cpack.log" 2>&1 ||
    { cat "$work/cpack.log"; fail "cpack could not build the package"; }
deb=$(ls "$work"/pkg/ugvsense_*.deb)
echo "$(basename "$deb"): $(du -h "$deb" | cut -f1)"
dpkg-deb -f "$deb" Depends >"$work/depends.txt"
echo "Depends: $(cat "$work/depends.txt")"
for dep in 'libc6' 'libopencv-core406' 'libopencv-calib3d406' 'libfastrtps2.9' 'libyaml-cpp0.7' 'iceoryx' 'adduser'; do
    grep -q "$dep" "$work/depends.txt" || fail "Depends lacks $dep"
done
dpkg-deb -f "$deb" Recommends | grep -q openssl || fail "Recommends lacks openssl (ugvsense-make-security)"
dpkg-deb -e "$deb" "$work/control"
grep -qx /etc/ugvsense/config.yaml "$work/control/conffiles" || fail "config.yaml is not a conffile"
grep -qx /etc/ugvsense/roudi.toml "$work/control/conffiles" || fail "roudi.toml is not a conffile"
for script in postinst prerm postrm; do [ -x "$work/control/$script" ] || fail "no $script"; done

if ! unshare -m true 2>/dev/null; then skip "cannot make a mount namespace here (unshare -m)"; fi

# The scratch root: / as the lower layer, changes in $work/root/upper; its own /tmp, /run and /dev/shm, so that
# RouDi and DDS in it never meet the host's.
mkdir -p "$work/root/upper" "$work/root/work" "$work/root/merged"
cp "$deb" "$work/ugvsense.deb"
cat >"$work/inside.sh" <<'INSIDE'
set -euo pipefail
domain=$1
fail() { echo "FAIL: $*" >&2; exit 1; }
step() { echo "== $*"; }

step "dpkg -i (the package's dependencies are on this machine already)"
dpkg -i /ugvsense.deb >/dpkg-install.log 2>&1 || { cat /dpkg-install.log; fail "dpkg -i failed"; }
for f in /usr/bin/ugvsense /usr/sbin/ugvsensed /usr/bin/ugvsense-make-security; do [ -x "$f" ] || fail "$f missing"; done
ugvsense-make-security /tmp/team --partition team-a gcs ugv-1 >/make-security.log 2>&1 ||
    { cat /make-security.log; fail "ugvsense-make-security failed"; }
for f in identity_ca.cert.pem cert.pem key.pem permissions_ca.cert.pem governance.p7s permissions.p7s; do
    [ -s "/tmp/team/ugv-1/$f" ] || fail "ugvsense-make-security made no ugv-1/$f"
done
echo "ugvsense-make-security made the files of a team (gcs, ugv-1)"
for f in /lib/systemd/system/ugvsensed.service /lib/systemd/system/ugvsense-roudi.service \
    /lib/systemd/system/ugvsense-default-recording.service /lib/systemd/system/ugvsense-record.service \
    /etc/ugvsense/config.yaml /etc/ugvsense/roudi.toml \
    /usr/share/doc/ugvsense/README.md /usr/share/doc/ugvsense/config.example.yaml; do
    [ -f "$f" ] || fail "$f missing"
done
IFS=: read -r _ _ uid _ _ home shell < <(getent passwd ugvsense) || fail "no user ugvsense"
[ "$uid" -lt 1000 ] || fail "ugvsense is not a system user (uid $uid)"
[ "$home" = /var/lib/ugvsense ] || fail "ugvsense's home is $home"
case "$shell" in */nologin | */false) ;; *) fail "ugvsense has a login shell ($shell)" ;; esac
id -nG ugvsense | grep -qw video || fail "ugvsense is not in group video (camera nodes)"
[ "$(stat -c '%U:%G %a' /var/lib/ugvsense)" = "ugvsense:ugvsense 750" ] ||
    fail "/var/lib/ugvsense is $(stat -c '%U:%G %a' /var/lib/ugvsense)"
if ls /etc/systemd/system/*.wants/ 2>/dev/null | grep -q ugvsense; then fail "the package enabled a unit"; fi
echo "user ugvsense (uid $uid, $shell, groups: $(id -nG ugvsense)); nothing enabled"

step "the installed units"
out=$(systemd-analyze verify --man=no /lib/systemd/system/ugvsense*.service 2>&1) || true
[ -z "$out" ] || fail "systemd-analyze verify: $out"
systemd-analyze security --offline=yes --threshold=20 /lib/systemd/system/ugvsensed.service >/security.txt 2>&1 ||
    { tail -3 /security.txt; fail "ugvsensed.service exposure above 2.0"; }
tail -1 /security.txt

# Runs one unit's ExecStart lines as its User= with its limits and capabilities (what systemd would do, less the
# sandboxing, which systemd-analyze rated above). Extra arguments go to the background switch: bg PIDFILE.
unit_exec() {
    local unit=/lib/systemd/system/$1 line caps="" rtprio=0 memlock=""
    caps=$(sed -n 's/^AmbientCapabilities=//p' "$unit" | tr 'A-Z ' 'a-z,' | sed 's/cap_/+/g')
    rtprio=$(sed -n 's/^LimitRTPRIO=//p' "$unit")
    memlock=$(sed -n 's/^LimitMEMLOCK=//p' "$unit")
    local -a wrap=(setpriv --reuid=ugvsense --regid=ugvsense --init-groups)
    [ -n "$caps" ] && wrap+=(--inh-caps="$caps" --ambient-caps="$caps")
    local -a limits=(prlimit)
    [ -n "$rtprio" ] && limits+=(--rtprio="$rtprio")
    [ -n "$memlock" ] && limits+=(--memlock="${memlock/infinity/unlimited}")
    if ! "${limits[@]}" true 2>/dev/null; then
        # Raising a hard limit needs CAP_SYS_RESOURCE, which some sandboxes (ours) lack; the ambient CAP_SYS_NICE
        # and CAP_IPC_LOCK alone allow SCHED_FIFO and mlockall, which the no-warning check below proves.
        echo "[$1] (cannot raise ${limits[*]:1} here: no CAP_SYS_RESOURCE; the capabilities suffice)"
        limits=(env)
    fi
    while read -r line; do
        read -ra cmd <<<"$line"
        echo "[$1] ${cmd[*]}"
        "${limits[@]}" "${wrap[@]}" "${cmd[@]}"
    done < <(sed -n 's/^ExecStart=//p' "$unit")
}

step "systemctl start ugvsensed, as its units do it"
start=$(date +%s)
unit_exec ugvsense-default-recording.service >/recording.log 2>&1 || { cat /recording.log; fail "default recording"; }
[ -f /var/lib/ugvsense/default.ugvrec ] || fail "the default recording was not made"
[ ! -e /var/lib/ugvsense/default.ugvrec.part ] || fail "a .part file was left behind"
echo "default recording made in $(($(date +%s) - start)) s: $(ugvsense recording info /var/lib/ugvsense/default.ugvrec | head -1)"
ugvsense check-config /etc/ugvsense/config.yaml >/check.log 2>&1 || { cat /check.log; fail "shipped config refused"; }
unit_exec ugvsense-roudi.service >/roudi.log 2>&1 &
roudi=$!
for _ in $(seq 100); do [ -S /tmp/roudi ] && break; sleep 0.1; done
[ -S /tmp/roudi ] || { cat /roudi.log; fail "RouDi did not start"; }
UGV_DDS_DOMAIN=$domain unit_exec ugvsensed.service >/service.log 2>&1 &
svc=$!
sleep 12
# Only the children of this test's unit_exec: the PID namespace is the host's, and a bare `pkill -x ugvsensed`
# stopped another test's service running beside this one (system.cyclone-interop, 2026-12-05).
pkill -TERM -x -P "$svc" ugvsensed || true
rc=0
wait "$svc" || rc=$?
pkill -TERM -x -P "$roudi" iox-roudi || true
wait || true
grep -q "^frames: " /service.log || { cat /service.log; fail "ugvsensed printed no report"; }
published=$(sed -n 's/^frames: \([0-9][0-9]*\) published.*/\1/p' /service.log | head -1)
[ "$rc" -eq 0 ] || { cat /service.log; fail "ugvsensed exited $rc on SIGTERM"; }
[ "${published:-0}" -ge 20 ] || { cat /service.log; fail "ugvsensed published ${published:-no} frames in 12 s"; }
grep -q "could not" /service.log && { cat /service.log; fail "ugvsensed warned about its real-time setup"; }
echo "ugvsensed as user ugvsense: $published frames published in 12 s, stopped cleanly"
grep -E "end.to.end|deadline" /service.log | head -3

step "upgrade keeps an edited conffile; remove; purge"
sed -i 's/^vehicle_id: ugv-1/vehicle_id: ugv-7/' /etc/ugvsense/config.yaml
dpkg -i --force-confold /ugvsense.deb >/dpkg-upgrade.log 2>&1 || { cat /dpkg-upgrade.log; fail "upgrade failed"; }
grep -q '^vehicle_id: ugv-7' /etc/ugvsense/config.yaml || fail "the upgrade replaced the edited config"
echo "operator data" >/var/lib/ugvsense/calibration.yaml
dpkg -r ugvsense >/dpkg-remove.log 2>&1 || { cat /dpkg-remove.log; fail "dpkg -r failed"; }
[ ! -e /usr/sbin/ugvsensed ] && [ ! -e /lib/systemd/system/ugvsensed.service ] || fail "dpkg -r left programs or units"
[ -f /etc/ugvsense/config.yaml ] || fail "dpkg -r removed a conffile"
dpkg -P ugvsense >/dpkg-purge.log 2>&1 || { cat /dpkg-purge.log; fail "dpkg -P failed"; }
[ ! -e /etc/ugvsense/config.yaml ] || fail "purge left the config"
[ ! -e /var/lib/ugvsense/default.ugvrec ] || fail "purge left the generated recording"
[ -f /var/lib/ugvsense/calibration.yaml ] || fail "purge removed the operator's calibration"
echo "removed and purged: conffiles and the generated recording gone, the operator's calibration kept"
INSIDE

echo "== into the scratch root"
unshare -m --propagation private bash -euo pipefail -c '
    work=$1 domain=$2
    root=$work/root/merged
    mount -t overlay overlay -o "lowerdir=/,upperdir=$work/root/upper,workdir=$work/root/work" "$root"
    mount --rbind /proc "$root/proc"
    mount --rbind /sys "$root/sys"
    mount --rbind /dev "$root/dev"
    mount -t tmpfs tmpfs "$root/dev/shm"
    mount -t tmpfs tmpfs "$root/tmp"
    mount -t tmpfs tmpfs "$root/run"
    cp "$work/ugvsense.deb" "$root/ugvsense.deb"
    chroot "$root" bash /dev/stdin "$domain" <"$work/inside.sh"
' _ "$work" "$domain"
echo "PASS"
