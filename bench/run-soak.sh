#!/bin/bash
# run-soak.sh - the gateway's memory over a long run at full rate (docs/performance.md, "Soak"):
# teejet-gateway --can sim:32 with every telemetry message at 0.1 s (bench/full-poll.yaml,
# ~2,600 frames/s), an ECU reading every topic and moving valves at 20 commands/s, VmRSS
# sampled every 10 s. Runs inside tests/netns/isolated: DDS stays on this host.
#
#   bench/run-soak.sh [--build-dir DIR] [--minutes M] [--settle-s S]
#
# Prints the RESOURCES, RSS, RSS_SERIES (every sample), COMMANDS and SUBSCRIBER lines of gateway_latency resources.
# Exit status: 0 when RSS stayed within 1 MiB (lowest to highest) after settling; 1 otherwise.
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
build=$root/build minutes=10 settle_s=30 inside=0
while [ $# -gt 0 ]; do
  case $1 in
  --build-dir) build=$(cd "$2" && pwd) || exit 2; shift 2 ;;
  --minutes) minutes=$2; shift 2 ;;
  --settle-s) settle_s=$2; shift 2 ;;
  --inside) inside=1; shift ;; # internal: the half inside the namespace
  *) sed -n '7p' "${BASH_SOURCE[0]}" | sed 's/^# *//' >&2; exit 2 ;;
  esac
done
if [ "$inside" = 0 ]; then
  exec "$root/tests/netns/isolated" "${BASH_SOURCE[0]}" --inside --build-dir "$build" \
    --minutes "$minutes" --settle-s "$settle_s"
fi

unset FASTDDS_DEFAULT_PROFILES_FILE # every program gets the profile with --profile
profile=$root/config/fastdds-loopback.xml
log=$(mktemp "${TMPDIR:-/tmp}/soak-gateway.XXXXXX")
"$build/gateway/app/teejet-gateway" --can sim:32 -c "$here/full-poll.yaml" --domain 90 \
  --profile "$profile" --log-level warn >"$log" 2>&1 &
gateway=$!
trap 'kill -TERM $gateway 2>/dev/null; wait $gateway 2>/dev/null; rm -f "$log"' EXIT
window_s=$(awk -v m="$minutes" 'BEGIN { print m * 60 }')
out=$("$build/bench/gateway_latency" resources --label soak --pid "$gateway" --subscribe \
  --domain 90 --profile "$profile" --commands-per-second 20 --rss-every-s 10 \
  --settle-s "$settle_s" --window-s "$window_s") || { cat "$log" >&2; exit 1; }
echo "$out"
spread=$(echo "$out" | sed -n 's/^RSS .*spread_kib=\([0-9]*\).*/\1/p')
[ -n "$spread" ] && [ "$spread" -le 1024 ]
