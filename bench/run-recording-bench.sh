#!/bin/bash
# run-recording-bench.sh - teejet-record at a full bus (docs/performance.md, "Recording"):
# teejet-gateway --can sim:32 with every telemetry message at 0.1 s (bench/full-poll.yaml,
# ~2,600 frames/s) and --record-frames (every frame on teejet/can/frame too), teejet-record for
# --seconds S with each compression; prints the recorder's message rate, its CPU (user+system
# from /proc, in % of one core), its peak RSS, the gateway's CPU, and the file size per minute.
#
# --replay instead measures how closely teejet-replay keeps a recording's timing (docs/
# performance.md, "Replay timing"): --can sim:4 --record-frames at the default poll schedule
# (what tests/recording's replay case records) recorded for --seconds S (default 20), then
# replayed --runs N times (default 2) into another domain with tests/recording's subscriber,
# alternately as the machine is (added_load=none; the load average is printed) and with one busy
# loop per core at normal priority (added_load=busy: as compilers load a CI machine). Per replay:
# the gap error (|replayed gap - recorded gap| between consecutive messages, as the subscriber
# received them) at p50/p99/max, and the replayer's own count of messages sent over 1 ms late.
# Runs inside tests/netns/isolated: DDS stays on this host.
#
#   bench/run-recording-bench.sh [--build-dir DIR] [--seconds S] [--compression "zstd lz4 none"]
#   bench/run-recording-bench.sh --replay [--build-dir DIR] [--seconds S] [--runs N]
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
build=$root/build seconds="" compressions="zstd lz4 none" inside=0 replay=0 runs=2
while [ $# -gt 0 ]; do
  case $1 in
  --build-dir) build=$(cd "$2" && pwd) || exit 2; shift 2 ;;
  --seconds) seconds=$2; shift 2 ;;
  --compression) compressions=$2; shift 2 ;;
  --replay) replay=1; shift ;;
  --runs) runs=$2; shift 2 ;;
  --inside) inside=1; shift ;;
  *) sed -n '18,19p' "${BASH_SOURCE[0]}" | sed 's/^# *//' >&2; exit 2 ;;
  esac
done
if [ -z "$seconds" ]; then
  seconds=60
  [ "$replay" = 1 ] && seconds=20
fi
if [ "$inside" = 0 ]; then
  replay_flag=()
  [ "$replay" = 1 ] && replay_flag=(--replay)
  exec "$root/tests/netns/isolated" "${BASH_SOURCE[0]}" --inside --build-dir "$build" \
    --seconds "$seconds" --compression "$compressions" --runs "$runs" "${replay_flag[@]}"
fi

work=$(mktemp -d /tmp/teejet-recording-bench.XXXXXX)
gateway="" busy=()
trap 'kill $gateway "${busy[@]}" 2>/dev/null; wait 2>/dev/null; rm -rf "$work"' EXIT
ticks=$(getconf CLK_TCK)
cpu_ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }

# The replay timing: one recording, replayed idle and busy in turn.
replay_timing() {
  local recording=$work/replay-source.mcap load logger
  "$build/tools/teejet-record/teejet-record" -o "$recording" -q &
  local recorder=$!
  "$build/gateway/app/teejet-gateway" --can sim:4 --record-frames --log-level warn &
  gateway=$!
  "$build/tools/valvectl/valvectl" list --wait-for 4 --timeout 20 >/dev/null || {
    echo "the gateway did not list 4 valves" >&2
    exit 1
  }
  sleep "$seconds"
  kill -INT $recorder && wait $recorder
  kill -TERM $gateway && wait $gateway
  gateway=""
  node "$root/tests/mcap-js/read-mcap.mjs" "$recording" >"$work/recorded.jsonl" || exit 1
  for _ in $(seq 1 "$runs"); do
    for load in none busy; do
      if [ "$load" = busy ]; then
        for _ in $(seq "$(nproc)"); do
          sh -c 'while :; do :; done' &
          busy+=($!)
        done
      fi
      "$build/tests/recording/recording_sample_logger" --domain 1 >"$work/replayed.jsonl" \
        2>"$work/logger.err" &
      logger=$!
      until grep -q ready "$work/logger.err" 2>/dev/null; do sleep 0.05; done
      local loadavg
      loadavg=$(cut -d' ' -f1 /proc/loadavg)
      "$build/tools/teejet-replay/teejet-replay" "$recording" --domain 1 \
        --wait-for-readers 20 2>"$work/replay.err"
      sleep 1 # the last best-effort frames reach the subscriber
      kill -INT $logger && wait $logger
      if [ ${#busy[@]} -gt 0 ]; then
        kill "${busy[@]}" && wait "${busy[@]}" 2>/dev/null
        busy=()
      fi
      python3 - "$work/recorded.jsonl" "$work/replayed.jsonl" "$work/replay.err" "$load" \
        "$loadavg" <<'PY'
import collections, json, re, sys
recorded = [json.loads(line) for line in open(sys.argv[1])]
recorded = [m for m in recorded if m["topic"] != "teejet/valve/command"]  # not replayed
received = collections.defaultdict(collections.deque)
for line in open(sys.argv[2]):
    sample = json.loads(line)
    topic = sample["topic"] + ("/disposed" if sample["disposed"] else "")
    received[(topic, sample["source_ns"])].append(int(sample["received_ns"]))
# Each replayed sample carries its recorded source timestamp: that pairs it with its message.
pairs = []
for message in recorded:
    arrivals = received.get((message["topic"], message["publish_time"]))
    if arrivals:
        pairs.append((int(message["log_time"]), arrivals.popleft()))
errors = sorted(abs((b[1] - a[1]) - (b[0] - a[0])) / 1e6 for a, b in zip(pairs, pairs[1:]))
pick = lambda q: errors[min(len(errors) - 1, int(q * len(errors)))]
summary = re.search(r"(\d+) went out over 1 ms late, the latest ([\d.]+) ms",
                    open(sys.argv[3]).read())
print(f"REPLAY added_load={sys.argv[4]} loadavg={sys.argv[5]} messages={len(recorded)} "
      f"received={len(pairs)} gap_error_ms p50={pick(0.5):.3f} p99={pick(0.99):.3f} "
      f"max={errors[-1]:.3f} over_1ms={sum(e > 1 for e in errors)} "
      f"over_5ms={sum(e > 5 for e in errors)} replayer_late_over_1ms={summary.group(1)} "
      f"replayer_latest_ms={summary.group(2)}")
PY
    done
  done
}
if [ "$replay" = 1 ]; then
  replay_timing
  exit 0
fi

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
