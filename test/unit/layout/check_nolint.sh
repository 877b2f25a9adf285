#!/usr/bin/env bash
# Every NOLINT must suppress something real: it names its checks, each check is on in the root .clang-tidy, it says
# why, and it sits in code that clang-tidy reads (the product folders; the tests are not tidied).
# Usage: check_nolint.sh ROOT [CONFIG_DIR]   -> exit 0 when clean, 1 listing every bad NOLINT, 77 when it cannot run.
# CONFIG_DIR (default ROOT) holds the .clang-tidy whose checks count as on.
set -u
root=${1:?usage: check_nolint.sh ROOT [CONFIG_DIR]}
config_dir=${2:-$root}
tidy=$(command -v clang-tidy-14 || command -v clang-tidy || true)
if [ -z "$tidy" ]; then
    echo "SKIP: clang-tidy is not installed (Debian 12: apt-get install clang-tidy; toolchain/host.sh deps does it)"
    exit 77
fi
mapfile -t enabled < <(cd "$config_dir" && "$tidy" --list-checks 2>/dev/null | sed -nE 's/^ +([a-z0-9.-]+)$/\1/p')
if [ ${#enabled[@]} -eq 0 ]; then
    echo "FAIL: no check is on in $config_dir/.clang-tidy (or clang-tidy could not read it)"
    exit 1
fi
status=0
bad() { echo "$1: $2"; echo "  fix: $3"; status=1; }

while IFS= read -r hit; do
    file=${hit%%:*} rest=${hit#*:}
    line=${rest%%:*} text=${rest#*:}
    where="${file#"$root"/}:$line"
    case "${file#"$root"/}" in
        platform/* | hal/* | rt/* | vision/* | ipc/* | correlator/* | bringup/*) ;;
        *)
            bad "$where" "a NOLINT outside the product folders suppresses nothing (clang-tidy reads platform/ ... bringup/)" \
                "delete it, keeping its reason as a plain comment if it explains the code"
            continue
            ;;
    esac
    [[ $text =~ NOLINTEND ]] && continue # checked at its NOLINTBEGIN
    if ! [[ $text =~ NOLINT(NEXTLINE|BEGIN)?\(([^\)]*)\)(.*)$ ]]; then
        bad "$where" "a NOLINT without the checks it suppresses switches every check off" \
            "name the check: NOLINT(check-name): reason (the finding's [check-name])"
        continue
    fi
    checks=${BASH_REMATCH[2]} after=${BASH_REMATCH[3]}
    IFS=', ' read -ra names <<<"$checks"
    for name in "${names[@]}"; do
        [ -z "$name" ] && continue
        if [[ $name == *'*'* ]]; then
            bad "$where" "NOLINT($name): a wildcard hides more than the one finding" "name the check"
        elif ! printf '%s\n' "${enabled[@]}" | grep -qxF -- "$name"; then
            bad "$where" "NOLINT($name): $name is not on in .clang-tidy, so this suppresses nothing" \
                "delete the NOLINT, or turn $name on in .clang-tidy (README \"Static analysis\")"
        fi
    done
    if ! [[ $after =~ [A-Za-z] ]]; then
        bad "$where" "NOLINT($checks) without a reason" "add it on the same line: NOLINT($checks): why the rule does not fit here"
    fi
done < <(grep -rnE 'NOLINT' "$root" --include='*.hpp' --include='*.cpp' --include='*.h' \
    --exclude-dir=build --exclude-dir=.git --exclude-dir=bad_tree --exclude-dir=tidy_bad 2>/dev/null)
[ $status -eq 0 ] && echo "NOLINT: every one names a check that is on and says why"
exit $status
