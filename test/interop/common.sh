# Sourced by the interop tests.

# nav2_from_readme README prints the README's Nav2 obstacle layer block
# ("obstacle_layer:" up to the blank line) as cyclone-interop's SOURCE.KEY=VALUE arguments, so that the documented
# settings are the tested ones: layer keys at 6 spaces, the observation sources' keys at 8 (ugvsense_scan -> scan,
# ugvsense_clear -> clear, ugvsense_negatives -> negatives).
nav2_from_readme() {
    awk '
    /^    obstacle_layer:/ { inside = 1; next }
    inside && /^[[:space:]]*$/ { exit }
    inside {
        line = $0; sub(/#.*/, "", line); match(line, /^ */); indent = RLENGTH; gsub(/^ +| +$/, "", line)
        if (line == "") next
        key = line; sub(/:.*/, "", key); value = line; sub(/^[^:]*:[ ]*/, "", value); gsub(/"/, "", value)
        if (indent == 6 && value == "") { source = key == "ugvsense_scan" ? "scan" : key == "ugvsense_clear" ? "clear" : key == "ugvsense_negatives" ? "negatives" : key; next }
        if (indent == 6) print "layer." key "=" value
        else if (indent == 8) print source "." key "=" value
    }' "$1"
}

# stop_service REPORT_REGEX WHY: SIGTERM to the service ($svc), its exit status checked, then its report in
# $work/service.log must hold a line matching REPORT_REGEX (else fail WHY; the caller defines fail).
stop_service() {
    kill -TERM "$svc"
    wait "$svc" || fail "the service exited with an error"
    svc=""
    grep -E "$1" "$work/service.log" || fail "$2"
}
