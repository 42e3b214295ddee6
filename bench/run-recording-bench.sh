#!/bin/bash
# run-recording-bench.sh - teejet-record at a full bus (docs/performance.md, "Recording"):
# teejet-gateway --can sim:32 with every telemetry message at 0.1 s (bench/full-poll.yaml,
# ~2,600 frames/s) and --record-frames (every frame on teejet/can/frame too), teejet-record for
# --seconds S with each compression; prints the recorder's message rate, its CPU (user+system
# from /proc, in % of one core), its peak RSS, the gateway's CPU, and the file size per minute.
# Runs inside tests/netns/isolated: DDS stays on this host.
#
#   bench/run-recording-bench.sh [--build-dir DIR] [--seconds S] [--compression "zstd lz4 none"]
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
build=$root/build seconds=60 compressions="zstd lz4 none" inside=0
while [ $# -gt 0 ]; do
  case $1 in
  --build-dir) build=$(cd "$2" && pwd) || exit 2; shift 2 ;;
  --seconds) seconds=$2; shift 2 ;;
  --compression) compressions=$2; shift 2 ;;
  --inside) inside=1; shift ;;
  *) sed -n '9p' "${BASH_SOURCE[0]}" | sed 's/^# *//' >&2; exit 2 ;;
  esac
done
if [ "$inside" = 0 ]; then
  exec "$root/tests/netns/isolated" "${BASH_SOURCE[0]}" --inside --build-dir "$build" \
    --seconds "$seconds" --compression "$compressions"
fi

work=$(mktemp -d /tmp/teejet-recording-bench.XXXXXX)
trap 'kill $gateway 2>/dev/null; wait 2>/dev/null; rm -rf "$work"' EXIT
ticks=$(getconf CLK_TCK)
cpu_ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }

"$build/gateway/app/teejet-gateway" --can sim:32 --record-frames -c "$here/full-poll.yaml" \
  --log-level warn &
gateway=$!
"$build/tools/valvectl/valvectl" list --wait-for 32 --timeout 20 > /dev/null || {
  echo "the gateway did not list 32 valves" >&2
  exit 1
}
sleep 2 # every poll running

for compression in $compressions; do
  file=$work/bench-$compression.mcap
  gateway_before=$(cpu_ticks $gateway)
  "$build/tools/teejet-record/teejet-record" -o "$file" --duration "$seconds" \
    --compression "$compression" -q &
  recorder=$!
  peak_rss=0 recorder_ticks=0
  while kill -0 $recorder 2>/dev/null; do
    if [ -r /proc/$recorder/stat ]; then
      recorder_ticks=$(cpu_ticks $recorder 2>/dev/null || echo "$recorder_ticks")
      rss=$(awk '/VmHWM/ {print $2}' /proc/$recorder/status 2>/dev/null || echo 0)
      [ "${rss:-0}" -gt "$peak_rss" ] && peak_rss=$rss
    fi
    sleep 0.5
  done
  wait $recorder
  gateway_after=$(cpu_ticks $gateway)
  info=$("$build/tools/teejet-record/teejet-record" --info "$file" --json)
  python3 - "$info" "$seconds" "$recorder_ticks" "$ticks" "$peak_rss" \
    "$((gateway_after - gateway_before))" "$compression" <<'PY'
import json, sys
info = json.loads(sys.argv[1])
seconds, rec_ticks, hz, rss, gw_ticks = float(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5]), int(sys.argv[6])
counts = {c["topic"]: c["messages"] for c in info["channels"]}
frames = counts.get("teejet/can/frame", 0)
print(f"RECORDING compression={sys.argv[7]} seconds={info['duration_s']:.1f} "
      f"messages={info['messages']} rate={info['messages'] / info['duration_s']:.0f}/s "
      f"frames={frames / info['duration_s']:.0f}/s recorder_cpu={100 * rec_ticks / hz / seconds:.1f}% "
      f"recorder_peak_rss={rss}KiB gateway_cpu={100 * gw_ticks / hz / seconds:.1f}% "
      f"file={info['size']}B per_minute={info['size'] / info['duration_s'] * 60 / 2**20:.2f}MiB "
      f"chunks={info['chunks']}")
PY
done
