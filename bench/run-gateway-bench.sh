#!/bin/bash
# run-gateway-bench.sh - teejet-gateway latency and footprint (docs/performance.md, "Gateway
# latency and footprint"). Boots user-mode-linux once per run (tests/uml/uml-run: vcan0 and
# loopback only, so DDS never leaves the host), measures everything inside it and prints one
# table over all runs: median of the runs, and [lowest-highest] when there are several.
#
#   bench/run-gateway-bench.sh [--build-dir DIR] [--runs N] [--samples N] [--window-s S]
#                              [--raw-dir DIR] [--host]
#
#   --build-dir  where teejet-gateway, valve-sim and gateway_latency are built (default: build)
#   --runs       UML boots, each a complete set of measurements (default: 3)
#   --samples    measured samples per latency series, after 100 warm-up samples (default: 1000)
#   --window-s   CPU/memory window, after 8 s of settling (default: 30)
#   --raw-dir    keep every run's output and every latency (ns) there
#   --host       also measure on the host, inside tests/netns/isolated: the DDS baseline,
#                latency under load beside bare Fast DDS under the same load (a gateway in the
#                bench process, 31 simulated valves at full poll, gateway_latency --load-valves), and
#                teejet-gateway --can sim:32 (the embedded simulator's cost included), on the
#                default poll schedule and with every telemetry message at 0.1 s
#                (bench/full-poll.yaml)
#
# Exit status: 0; 77 when user-mode-linux cannot start; 1 when a run failed.
set -u

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
self=$here/$(basename "${BASH_SOURCE[0]}")
build=$root/build runs=3 samples=1000 window_s=30 raw_dir='' host=0 inside=''
settle_s=8
profile=$root/config/fastdds-loopback.xml

usage() {
  sed -n '5,6p' "${BASH_SOURCE[0]}" | sed 's/^# *//' >&2
  exit 2
}
while [ $# -gt 0 ]; do
  case $1 in
  --build-dir) build=$(cd "$2" && pwd) || exit 2; shift 2 ;;
  --runs) runs=$2; shift 2 ;;
  --samples) samples=$2; shift 2 ;;
  --window-s) window_s=$2; shift 2 ;;
  --raw-dir) mkdir -p "$2" && raw_dir=$(cd "$2" && pwd) || exit 2; shift 2 ;;
  --host) host=1; shift ;;
  --inside-uml | --inside-host) inside=$1; shift ;; # internal: the measuring half
  *) usage ;;
  esac
done

gateway=$build/gateway/app/teejet-gateway
valve_sim=$build/tools/valve-sim/valve-sim
bench=$build/bench/gateway_latency

# ---- The measuring half: runs inside UML (or the host's isolated namespace) -----------------

started=()
# shellcheck disable=SC2317 # invoked via trap
stop_started() {
  local pid
  for pid in "${started[@]}"; do stop_process "$pid"; done
  started=()
}
# shellcheck source=tools/lib/eventually.sh
source "$root/tools/lib/eventually.sh"
# shellcheck disable=SC2317 # invoked via eventually
gone() { ! kill -0 "$1" 2>/dev/null; }
# SIGTERM (the gateway then stops its valves and leaves DDS), SIGKILL if it hangs.
stop_process() {
  local pid=$1
  kill -TERM "$pid" 2>/dev/null || return 0
  eventually 5 gone "$pid" || kill -KILL "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  return 0
}
start() { # start LOGNAME COMMAND... ; the pid is in $last_pid
  "${@:2}" >>"$logs/$1.log" 2>&1 &
  last_pid=$!
  started+=("$last_pid")
}
start_gateway() { # start_gateway DOMAIN CAN [GATEWAY OPTIONS...]
  start gateway "$gateway" --can "$2" --domain "$1" --profile "$profile" --log-level warn "${@:3}"
  gateway_pid=$last_pid
}
series=(--samples "$samples" --warmup 100 --pace-min-ms 10 --pace-max-ms 20)
[ -n "$raw_dir" ] && series+=(--raw-dir "$raw_dir")

measure_in_uml() {
  # Each phase on its own DDS domain, so that nothing of a finished phase can match.
  "$bench" baseline --label uml --domain 20 --profile "$profile" "${series[@]}" || return 1

  # Latency through the gateway, the bench valve alone on the bus.
  start_gateway 21 vcan0
  "$bench" gateway --label idle --can vcan0 --domain 21 --profile "$profile" "${series[@]}" ||
    return 1
  stop_started

  # The same on a full bus: 31 simulated valves (0xD8..0xF6) on the default poll schedule beside
  # the bench valve (0xF7), 32 in all.
  start valve-sim "$valve_sim" --can vcan0 --valves 31
  start_gateway 22 vcan0
  "$bench" gateway --label loaded --can vcan0 --domain 22 --profile "$profile" "${series[@]}" ||
    return 1
  stop_started

  # Footprint: 32 simulated valves on the default poll schedule; first nobody reads DDS, then an
  # ECU reads every topic. Then 10 valves with the ECU, for the scale.
  start valve-sim "$valve_sim" --can vcan0 --valves 32
  sim_pid=$last_pid
  start_gateway 23 vcan0
  "$bench" resources --label uml-32 --pid "$gateway_pid" --pid "$sim_pid" --interface vcan0 \
    --settle-s "$settle_s" --window-s "$window_s" || return 1
  "$bench" resources --label uml-32-ecu --pid "$gateway_pid" --pid "$sim_pid" --interface vcan0 \
    --subscribe --domain 23 --profile "$profile" --settle-s "$settle_s" \
    --window-s "$window_s" || return 1
  stop_started
  start valve-sim "$valve_sim" --can vcan0 --valves 10
  sim_pid=$last_pid
  start_gateway 24 vcan0
  "$bench" resources --label uml-10-ecu --pid "$gateway_pid" --pid "$sim_pid" --interface vcan0 \
    --subscribe --domain 24 --profile "$profile" --settle-s "$settle_s" \
    --window-s "$window_s" || return 1
  stop_started
}

measure_on_host() {
  # tests/netns/isolated names the profile in the environment too; every program here gets it
  # with --profile, and a second load of the same file only logs errors.
  unset FASTDDS_DEFAULT_PROFILES_FILE
  "$bench" baseline --label host --domain 87 --profile "$profile" "${series[@]}" || return 1
  # Latency under load, gateway and bare Fast DDS side by side: an in-process gateway with 31
  # simulated valves on a virtual bus, every telemetry message at 0.1 s (~2,600 frames/s), an
  # ECU in the bench reading every position; the bench valve beside them.
  local load=(--load-valves 31 --load-config "$here/full-poll.yaml")
  "$bench" baseline --label host-full "${load[@]}" --domain 85 --profile "$profile" \
    "${series[@]}" || return 1
  "$bench" gateway --label host-full "${load[@]}" --domain 86 --profile "$profile" \
    "${series[@]}" || return 1
  start_gateway 88 sim:32
  "$bench" resources --label host-sim32 --pid "$gateway_pid" --settle-s "$settle_s" \
    --window-s "$window_s" || return 1
  "$bench" resources --label host-sim32-ecu --pid "$gateway_pid" --subscribe --domain 88 \
    --profile "$profile" --settle-s "$settle_s" --window-s "$window_s" || return 1
  stop_started
  # Every telemetry message at the fastest resend (0.1 s): ~2,600 frames/s.
  start_gateway 89 sim:32 -c "$here/full-poll.yaml"
  "$bench" resources --label host-sim32-full --pid "$gateway_pid" --settle-s "$settle_s" \
    --window-s "$window_s" || return 1
  # The same with every core kept out of idle (bench/warm-cores): the gateway's own cost without
  # the virtual machine's wake-up-from-idle cost (docs/performance.md).
  "$here/warm-cores" "$bench" resources --label host-sim32-full-warm --pid "$gateway_pid" \
    --settle-s 2 --window-s "$window_s" || return 1
  stop_started
}

if [ -n "$inside" ]; then
  logs=$(mktemp -d "${TMPDIR:-/tmp}/gateway-bench.XXXXXX") || exit 1
  trap 'stop_started; rm -rf "$logs"' EXIT
  trap 'exit 130' INT
  trap 'exit 143' TERM
  if [ "$inside" = --inside-uml ]; then measure_in_uml; else measure_on_host; fi
  rc=$?
  stop_started
  if [ "$rc" != 0 ]; then # the logs of what we started say why
    for log in "$logs"/*.log; do [ -s "$log" ] && sed "s|^|$(basename "$log" .log): |" "$log" >&2; done
  fi
  exit "$rc"
fi

# ---- The driving half: boot, collect, tabulate ----------------------------------------------

for program in "$gateway" "$valve_sim" "$bench"; do
  [ -x "$program" ] || { echo "missing $program: build first (cmake --build ${build#"$root"/})" >&2; exit 1; }
done
out=$(mktemp -d "${TMPDIR:-/tmp}/gateway-bench-out.XXXXXX") || exit 1
trap 'rm -rf "$out"' EXIT

# Boot, six latency series (up to ~40 ms a sample under load) and four footprint windows.
uml_timeout=$((180 + 6 * (samples + 100) * 40 / 1000 + 4 * (settle_s + window_s)))
failed=0
for run in $(seq "$runs"); do
  # UML shares the host's CPUs: a busy host shows in the tails, so every run notes the load.
  echo "LOAD run=$run loadavg_1min=$(cut -d' ' -f1 /proc/loadavg)" >"$out/run$run.txt"
  echo "run $run/$runs: user-mode-linux (up to $uml_timeout s)" >&2
  run_raw=''
  [ -n "$raw_dir" ] && run_raw=$raw_dir/run$run && mkdir -p "$run_raw"
  # shellcheck disable=SC2046 # the optional --raw-dir pair
  "$root/tests/uml/uml-run" --timeout "$uml_timeout" -- "$self" --inside-uml --build-dir "$build" \
    --samples "$samples" --window-s "$window_s" $([ -n "$run_raw" ] && echo --raw-dir "$run_raw") \
    >>"$out/run$run.txt"
  rc=$?
  [ "$rc" = 77 ] && exit 77
  [ "$rc" = 0 ] || { echo "run $run failed (exit $rc)" >&2; failed=1; }
  if [ "$host" = 1 ]; then
    echo "run $run/$runs: host, tests/netns/isolated" >&2
    # shellcheck disable=SC2046
    "$root/tests/netns/isolated" "$self" --inside-host --build-dir "$build" --samples "$samples" \
      --window-s "$window_s" $([ -n "$run_raw" ] && echo --raw-dir "$run_raw") >>"$out/run$run.txt"
    rc=$?
    [ "$rc" = 0 ] || { echo "run $run on the host failed (exit $rc)" >&2; failed=1; }
  fi
  [ -n "$run_raw" ] && cp "$out/run$run.txt" "$run_raw/results.txt"
done

# One row per measurement: the median over the runs, [lowest-highest] when there are several.
cat "$out"/run*.txt | awk -v runs="$runs" '
function value(key,    i, kv) {
  for (i = 2; i <= NF; i++) { split($i, kv, "="); if (kv[1] == key) return kv[2] }
  return ""
}
function add(row, column, v) {
  if (v == "") return
  n = ++count[row, column]; values[row, column, n] = v
  if (!(row in seen)) { seen[row] = 1; order[++rows] = row }
}
function cell(row, column, digits,    n, i, j, t, a, text) {
  n = count[row, column]
  if (n == 0) return "-"
  for (i = 1; i <= n; i++) a[i] = values[row, column, i] + 0
  for (i = 2; i <= n; i++) for (j = i; j > 1 && a[j - 1] > a[j]; j--) { t = a[j]; a[j] = a[j - 1]; a[j - 1] = t }
  text = sprintf("%." digits "f", n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2)
  if (n > 1) text = text sprintf(" [%." digits "f-%." digits "f]", a[1], a[n])
  return text
}
function lost(row,    i, total) {
  for (i = 1; i <= count[row, "n"]; i++) total += values[row, "lost", i]
  return total + 0
}
$1 == "RESULT" {
  row = value("label") " " value("metric")
  add(row, "n", value("n")); add(row, "lost", value("lost"))
  add(row, "p50", value("p50_us")); add(row, "p90", value("p90_us"))
  add(row, "p99", value("p99_us")); add(row, "max", value("max_us"))
}
$1 == "RESOURCES" {
  row = value("label") " " value("process")
  add(row, "cpu", value("cpu_percent")); add(row, "rss", value("rss_kib") / 1024)
  add(row, "hwm", value("hwm_kib") / 1024)
}
$1 == "LOAD" { loads = loads (loads == "" ? "" : ", ") value("loadavg_1min") }
$1 == "BUS" { add(value("label") " bus", "fps", value("frames_per_s")) }
$1 == "SUBSCRIBER" {
  row = value("label") " gateway"
  add(row, "samples", value("samples_per_s")); add(row, "valves", value("valves_seen"))
  add(row, "in", value("gateway_frames_in_per_s")); add(row, "out", value("gateway_frames_out_per_s"))
}
END {
  printf "\nLatency, microseconds (%d run(s); median [lowest-highest] of the runs)\n\n", runs
  print "| run | measurement | p50 | p90 | p99 | max | samples, lost |"
  print "|---|---|---|---|---|---|---|"
  for (r = 1; r <= rows; r++) {
    row = order[r]
    if (count[row, "p50"] == 0 && count[row, "n"] == 0) continue
    split(row, part, " ")
    printf "| %s | %s | %s | %s | %s | %s | %d x %s, %d |\n", part[1], part[2], cell(row, "p50", 0),
      cell(row, "p90", 0), cell(row, "p99", 0), cell(row, "max", 0), count[row, "n"], values[row, "n", 1], lost(row)
  }
  printf "\nHost load average (1 min) at the start of each run: %s (2 = both host CPUs busy)\n", loads
  printf "\nFootprint over the window (%d run(s); CPU in %% of one core, memory in MiB)\n\n", runs
  print "| run | process | CPU % | VmRSS | VmHWM | frames/s on the bus | ECU samples/s | valves the ECU sees | gateway frames in/s, out/s |"
  print "|---|---|---|---|---|---|---|---|---|"
  for (r = 1; r <= rows; r++) {
    row = order[r]
    if (count[row, "cpu"] == 0) continue
    split(row, part, " ")
    printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s, %s |\n", part[1], part[2],
      cell(row, "cpu", 1), cell(row, "rss", 1), cell(row, "hwm", 1), cell(part[1] " bus", "fps", 0),
      cell(part[1] " gateway", "samples", 0), cell(part[1] " gateway", "valves", 0),
      cell(part[1] " gateway", "in", 0), cell(part[1] " gateway", "out", 0)
  }
}'
exit "$failed"
