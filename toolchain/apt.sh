# Sourced by host.sh, cross.sh and fuzz.sh: which Debian packages are missing, and installing them as root.
# Each caller sets `script` (its name, for messages) before sourcing.

as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"
    elif command -v sudo >/dev/null; then sudo "$@"
    else echo "$script: need root to install packages: run as root or install sudo" >&2; exit 1; fi
}

# Prints the packages among the arguments that are not installed, one per line.
missing_packages() {
    local p
    for p in "$@"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || echo "$p"
    done
}

# Installs the packages among the arguments that are not installed (apt-get, waiting up to 10 minutes for dpkg's
# lock when another install runs).
install_missing() {
    local missing
    mapfile -t missing < <(missing_packages "$@")
    if [ ${#missing[@]} -eq 0 ]; then
        echo "$script: all $# Debian packages present"
        return
    fi
    echo "$script: installing ${missing[*]}"
    as_root apt-get update -q
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
        -o DPkg::Lock::Timeout=600 "${missing[@]}"
}
