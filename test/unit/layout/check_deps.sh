#!/usr/bin/env bash
# Dependency direction (../shared/STYLE.md): platform includes nothing of ours; hal, rt, vision, ipc and correlator include
# only platform and themselves. In bringup/: adapters include the modules; the service includes the modules and the
# adapters; the simulator includes only platform (its truth does not come from the code it judges); the tool may
# include everything. What the service links (the modules, adapters, service) never includes OpenCV's
# imgcodecs/highgui (the service links only core, imgproc, calib3d), and vision/ includes no transport, camera or
# OS-device headers (it must build and test on any host).
# Usage: check_deps.sh ROOT   -> exit 0 when clean, 1 listing every violation.
set -u
root=${1:?usage: check_deps.sh ROOT}
status=0

violation() { echo "forbidden include: $1"; echo "  fix: $2"; status=1; }

# check_folder FOLDER ALLOWED [host]: FOLDER may include ugv/<m>/ only for m in ALLOWED; "host" allows the image-file
# and GUI headers of OpenCV (host tools).
check_folder() {
    local folder=$1 allowed=$2 host=${3:-}
    [ -d "$root/$folder" ] || return 0
    while IFS= read -r hit; do
        local file=${hit%%:*} rest=${hit#*:}
        local line=${rest%%:*} text=${rest#*:}
        local used
        used=$(sed -nE 's/.*#include *[<"]ugv\/([a-z_]+)\/.*/\1/p' <<<"$text")
        if [ -n "$used" ] && ! grep -qw -- "$used" <<<"$allowed"; then
            violation "$file:$line: $folder/ includes ugv/$used/" \
                "$folder/ may include only: $allowed. Move the shared type down (platform/, or adapters/ for bringup's), or do the wiring in the tool or the service."
        fi
    done < <(grep -rnE '#include *[<"]ugv/' "$root/$folder" --include='*.hpp' --include='*.cpp' --include='*.h' 2>/dev/null)

    [ "$host" = host ] && return 0
    while IFS= read -r hit; do
        violation "${hit%%:*}:$(cut -d: -f2 <<<"$hit"): $folder/ includes a host-tool or transport header" \
            "the service links only OpenCV core/imgproc/calib3d; vision/ stays free of I/O and transports"
    done < <(grep -rnE '#include *[<"](opencv2/(imgcodecs|highgui|videoio)|opencv2/opencv\.hpp)' "$root/$folder" \
                 --include='*.hpp' --include='*.cpp' --include='*.h' 2>/dev/null)
}

check_folder platform "platform"
check_folder hal "platform hal"
check_folder rt "platform rt"
check_folder vision "platform vision"
check_folder ipc "platform ipc"
check_folder correlator "platform correlator"
modules="platform hal rt vision ipc correlator"
check_folder bringup/adapters "$modules adapters"
check_folder bringup/service "$modules adapters service"
check_folder bringup/sim "platform sim" host
check_folder bringup/tool "$modules adapters service sim tool" host

if [ -d "$root/vision" ]; then
    while IFS= read -r hit; do
        violation "${hit%%:*}:$(cut -d: -f2 <<<"$hit"): vision/ includes an I/O or transport header" \
            "vision/ is pure computation; put device, shared-memory and DDS code in hal/ or ipc/"
    done < <(grep -rnE '#include *[<"](iceoryx|iox/|fastdds|fastrtps|libcamera|linux/videodev2|sys/ioctl|yaml-cpp)' "$root/vision" \
                 --include='*.hpp' --include='*.cpp' 2>/dev/null)
fi

if [ -d "$root/correlator" ]; then
    while IFS= read -r hit; do
        violation "${hit%%:*}:$(cut -d: -f2 <<<"$hit"): correlator/ includes an I/O, clock or thread header" \
            "the correlator is pure computation (time comes with the messages); do I/O in bringup/"
    done < <(grep -rnE '#include *<(fstream|iostream|chrono|thread|mutex)>|#include *[<"](iceoryx|iox/|fastdds|fastrtps|nlohmann|opencv2)' \
                 "$root/correlator" --include='*.hpp' --include='*.cpp' 2>/dev/null)
fi

[ $status -eq 0 ] && echo "dependency direction OK under $root"
exit $status
