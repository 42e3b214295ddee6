#!/bin/bash
# run-web-bench.sh - the dashboard at a full bus (docs/performance.md, "Dashboard"):
# teejet-gateway --can sim:32 with every telemetry message at 0.1 s (bench/full-poll.yaml), an
# ECU moving the valves in turn at --commands-per-second (gateway_latency resources, which also
# reads every topic), teejet-web (read-only) and the page in headless Chromium. Prints what
# reaches the browser (bench/web_browser_rate.py: WEB_BROWSER) and the CPU and memory of
# teejet-web and the gateway over the same window (RESOURCES lines).
# Runs inside tests/netns/isolated: DDS and HTTP stay on this host.
#
#   bench/run-web-bench.sh [--build-dir DIR] [--seconds S] [--commands-per-second R]
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
build=$root/build seconds=30 rate=20 inside=0
while [ $# -gt 0 ]; do
  case $1 in
  --build-dir) build=$(cd "$2" && pwd) || exit 2; shift 2 ;;
  --seconds) seconds=$2; shift 2 ;;
  --commands-per-second) rate=$2; shift 2 ;;
  --inside) inside=1; shift ;; # internal: the half inside the namespace
  *) sed -n '10p' "${BASH_SOURCE[0]}" | sed 's/^# *//' >&2; exit 2 ;;
  esac
done
if [ "$inside" = 0 ]; then
  exec "$root/tests/netns/isolated" "${BASH_SOURCE[0]}" --inside --build-dir "$build" \
    --seconds "$seconds" --commands-per-second "$rate"
fi

work=$(mktemp -d /tmp/teejet-web-bench.XXXXXX)
pids=()
trap 'kill "${pids[@]}" 2>/dev/null; wait 2>/dev/null; rm -rf "$work"' EXIT
port=18090
settle=10

"$build/gateway/app/teejet-gateway" --can sim:32 -c "$here/full-poll.yaml" --log-level warn &
gateway=$!
pids+=("$gateway")
"$build/tools/valvectl/valvectl" list --wait-for 32 --timeout 20 > /dev/null || {
  echo "the gateway did not list 32 valves" >&2
  exit 1
}
"$build/tools/teejet-web/teejet-web" --listen "127.0.0.1:$port" 2> "$work/web.log" &
web=$!
pids+=("$web")

# The ECU moves valves only in its window, which starts after --settle-s; the browser's window
# starts after Chromium is up (2-3 s) and its own settling time, so inside the ECU's window: while
# no valve moves, nothing changes and the dashboard sends only the once-a-second gateway status.
"$build/bench/gateway_latency" resources --label web --pid "$web" --pid "$gateway" --subscribe \
  --commands-per-second "$rate" --settle-s "$settle" --window-s "$((seconds + settle))" \
  > "$work/resources.txt" &
resources=$!
pids+=("$resources")
/usr/bin/python3 "$here/web_browser_rate.py" --url "http://127.0.0.1:$port/" --valves 32 \
  --settle "$settle" --seconds "$seconds"
browser_status=$?
wait "$resources"
resources_status=$?
cat "$work/resources.txt"
if [ "$browser_status" != 0 ] || [ "$resources_status" != 0 ]; then
  echo "--- teejet-web log" >&2
  cat "$work/web.log" >&2
  exit 1
fi
