#!/bin/bash
# run-many-clients.sh - what many valvectl runs at once cost, and whether each meets the gateway
# (docs/performance.md, "Many clients at once"). Inside tests/netns/isolated (loopback profile:
# DDS stays on this host): one teejet-gateway --can sim:4, then N `valvectl watch` started at
# once; after --window-s seconds it sums the clients' CPU (utime+stime of /proc/PID/stat since
# their start), the gateway's, and counts the clients whose screen shows the gateway's last valve.
# Nothing here passes or fails on timing.
#
#   bench/run-many-clients.sh [--build-dir DIR] [--valvectl PATH] [--clients N] [--window-s S]
#
#   --build-dir  where teejet-gateway and valvectl are built (default: build)
#   --valvectl   another valvectl to compare with (default: the build directory's)
#   --clients    how many at once (default: 60); --window-s (default: 25)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
build="$here/../build" valvectl="" clients=60 window=25 inside=""
while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) build=$2; shift 2 ;;
    --valvectl) valvectl=$2; shift 2 ;;
    --clients) clients=$2; shift 2 ;;
    --window-s) window=$2; shift 2 ;;
    --inside) inside=1; shift ;;
    *) echo "run-many-clients.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
build=$(cd "$build" && pwd)
valvectl=${valvectl:-$build/tools/valvectl/valvectl}
if [ -z "$inside" ]; then
  exec "$here/../tests/netns/isolated" "$0" --build-dir "$build" --valvectl "$valvectl" \
    --clients "$clients" --window-s "$window" --inside
fi

work=$(mktemp -d)
pids=()
cleanup() {
  kill -INT "${pids[@]}" 2>/dev/null || true
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
cpu_ticks() { local f; read -r -a f < "/proc/$1/stat"; echo $((f[13] + f[14])); }

"$build/gateway/app/teejet-gateway" --can sim:4 --name rig-1 > "$work/gateway.log" 2>&1 &
gateway=$!
pids+=("$gateway")
# The clients start once the gateway's four valves are online.
if ! "$valvectl" --timeout 30 list --wait-for 4 > /dev/null; then
  echo "run-many-clients.sh: the gateway's 4 valves were not listed within 30 s" >&2
  exit 1
fi
gateway_before=$(cpu_ticks "$gateway")
clients_pids=()
for i in $(seq 1 "$clients"); do
  "$valvectl" watch > "$work/client.$i" 2>&1 &
  clients_pids+=($!)
  pids+=($!)
done
sleep "$window"
ticks=0
for p in "${clients_pids[@]}"; do ticks=$((ticks + $(cpu_ticks "$p"))); done
gateway_ticks=$(($(cpu_ticks "$gateway") - gateway_before))
hz=$(getconf CLK_TCK)
seeing=$(grep -l TJV000004 "$work"/client.* | wc -l)
seconds() { awk -v t="$1" -v hz="$hz" 'BEGIN { printf "%.1f", t / hz }'; }
echo "MANY clients=$clients window_s=$window clients_cpu_s=$(seconds "$ticks")" \
  "gateway_cpu_s=$(seconds "$gateway_ticks") clients_showing_valves=$seeing"
