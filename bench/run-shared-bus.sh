#!/bin/bash
# run-shared-bus.sh - teejet-gateway's CPU on a bus it shares with other ECUs (issue 27). Boots
# user-mode-linux (tests/uml/uml-run: vcan0 and loopback only, so DDS never leaves the host) with
# valve-sim's 32 valves on the default poll schedule and measures the gateway's CPU (utime+stime
# of /proc/PID/stat over a fixed window, bench/gateway_latency resources) in
#   (a) the valves alone, and
#   (b) the same plus ~2,000 frames/s of other ECUs' traffic (isobus_peer foreign: other PGNs and
#       destinations, 11-bit frames; none from 0xD5, no claim, no request), which the gateway's
#       kernel filters should keep out of the process entirely,
# alternating (a) and (b) for --rounds (the sender is paused with SIGSTOP in (a)), first with
# nobody reading DDS ("bare": the gateway's own cost), then with an ECU reading every topic
# ("ecu": also gives the gateway's frames_in from GatewayStatus); then
#   (c) valve-sim stopped, only foreign frames: frames_in must not move.
# Prints a table with the median over rounds and runs; the target is (b) within 10 % of (a).
# Nothing here passes or fails on timing.
#
#   bench/run-shared-bus.sh [--build-dir DIR] [--window-s S] [--settle-s S] [--rate FRAMES_PER_S]
#                           [--rounds N] [--runs N]
#
#   --build-dir  where teejet-gateway, valve-sim, gateway_latency and isobus_peer are built
#                (default: build)
#   --window-s   each CPU window (default: 20); --settle-s before each (default: 3)
#   --rate       foreign frames per second (default: 2000)
#   --rounds     (a), (b) pairs per reader in one boot (default: 2)
#   --runs       UML boots (default: 1)
#
# --inside-uml [--smoke] is the measuring half. tests/uml/isobus registers it with --smoke as the
# ctest uml_isobus_shared_bus_smoke: 3 s windows, one round with the ECU, and it fails only when a
# phase did not run or frames_in moved while only foreign frames were on the bus.
# Exit status: 0; 77 when user-mode-linux cannot start; 1 when a run failed.
set -u -o pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
self=$here/$(basename "${BASH_SOURCE[0]}")
build=$root/build window_s=20 settle_s=3 rate=2000 rounds=2 runs=1 inside=0 smoke=0
profile=$root/config/fastdds-loopback.xml

usage() {
  sed -n '17,18p' "${BASH_SOURCE[0]}" | sed 's/^# *//' >&2
  exit 2
}
while [ $# -gt 0 ]; do
  case $1 in
  --build-dir) build=$(cd "$2" && pwd) || exit 2; shift 2 ;;
  --window-s) window_s=$2; shift 2 ;;
  --settle-s) settle_s=$2; shift 2 ;;
  --rate) rate=$2; shift 2 ;;
  --rounds) rounds=$2; shift 2 ;;
  --runs) runs=$2; shift 2 ;;
  --inside-uml) inside=1; shift ;;
  --smoke) smoke=1; shift ;;
  *) usage ;;
  esac
done

gateway=$build/gateway/app/teejet-gateway
valve_sim=$build/tools/valve-sim/valve-sim
bench=$build/bench/gateway_latency
peer=$build/tests/uml/isobus/isobus_peer

# ---- The measuring half: runs inside UML --------------------------------------------------------

started=()
# shellcheck source=tools/lib/eventually.sh
source "$root/tools/lib/eventually.sh"
# shellcheck disable=SC2317 # invoked via eventually
gone() { ! kill -0 "$1" 2>/dev/null; }
# SIGCONT first (valve-sim and the sender may be paused), then SIGTERM (the gateway stops its
# valves and leaves DDS), SIGKILL if it hangs.
stop_process() {
  kill -CONT "$1" 2>/dev/null
  kill -TERM "$1" 2>/dev/null || return 0
  eventually 5 gone "$1" || kill -KILL "$1" 2>/dev/null
  wait "$1" 2>/dev/null
  return 0
}
# shellcheck disable=SC2317 # invoked via trap
stop_started() {
  local pid
  for pid in "${started[@]}"; do stop_process "$pid"; done
  started=()
}
start() { # start LOGNAME COMMAND... ; the pid is in $last_pid
  "${@:2}" >>"$logs/$1.log" 2>&1 &
  last_pid=$!
  started+=("$last_pid")
}
# phase LABEL [resources options...]: one window of the gateway's (and the others') CPU.
phase() {
  local label=$1
  shift
  "$bench" resources --label "$label" --pid "$gateway_pid" --pid "$sim_pid" "$@" \
    --interface vcan0 --settle-s "$settle_s" --window-s "$window_s" |
    grep -v -E '^(RSS|FD|THREAD|CPU)_SERIES ' | tee -a "$logs/results.txt"
}
with_ecu=(--subscribe --domain 30 --profile "$profile")
# pair READER OPTIONS...: (a) with the sender paused, (b) with it sending.
pair() {
  local reader=$1
  shift
  kill -STOP "$foreign_pid"
  phase "a-$reader" "$@" || return 1
  kill -CONT "$foreign_pid"
  phase "b-$reader" --pid "$foreign_pid" "$@" || return 1
}

# What the smoke test checks: functional only, never a figure's size.
failures=0
expect() { # expect DESCRIPTION COMMAND...
  local description=$1
  shift
  if "$@"; then echo "ok: $description"; else echo "FAIL: $description"; failures=$((failures + 1)); fi
}
# field LABEL RECORD KEY: KEY's value in the RECORD line (SUBSCRIBER, BUS) of phase LABEL.
field() {
  sed -n "s/^$2 label=$1 .*$3=\([0-9.]*\).*/\1/p" "$logs/results.txt" | tail -n 1
}
check_smoke() {
  local label c_bus c_in
  for label in a-ecu b-ecu c-ecu; do
    expect "$label: the gateway's CPU was measured" \
      grep -q "^RESOURCES label=$label process=teejet-gateway " "$logs/results.txt"
  done
  expect "a-ecu: the ECU saw the 32 valves" \
    grep -q "^SUBSCRIBER label=a-ecu .*valves_seen=32" "$logs/results.txt"
  c_bus=$(field c-ecu BUS frames_per_s)
  c_in=$(field c-ecu SUBSCRIBER gateway_frames_in_per_s)
  expect "c: foreign frames were on the bus (${c_bus:-none}/s)" \
    awk -v r="${c_bus:-0}" -v want="$rate" 'BEGIN { exit !(r >= want / 4) }'
  expect "c: the gateway's frames_in did not move with only foreign frames on the bus (${c_in:-none}/s)" \
    [ "$c_in" = "0.0" ]
  echo "$failures failed"
  [ "$failures" -eq 0 ]
}

measure_in_uml() {
  start valve-sim "$valve_sim" --can vcan0 --valves 32
  sim_pid=$last_pid
  start gateway "$gateway" --can vcan0 --domain 30 --profile "$profile" --log-level warn
  gateway_pid=$last_pid
  start foreign "$peer" foreign vcan0 --rate "$rate"
  foreign_pid=$last_pid
  if [ "$smoke" = 0 ]; then
    for _ in $(seq "$rounds"); do pair bare || return 1; done
  fi
  for _ in $(seq "$rounds"); do pair ecu "${with_ecu[@]}" || return 1; done
  # (c) the valves silent (SIGSTOP), only foreign frames: none may reach the gateway.
  kill -STOP "$sim_pid"
  phase c-ecu --pid "$foreign_pid" "${with_ecu[@]}" || return 1
  kill -CONT "$sim_pid"
  stop_process "$foreign_pid" # it prints its totals into foreign.log
  grep -h "^foreign " "$logs/foreign.log" | sed 's/^/FOREIGN /' | tee -a "$logs/results.txt"
  stop_started
  if [ "$smoke" = 1 ]; then check_smoke || return 1; fi
}

if [ "$inside" = 1 ]; then
  logs=$(mktemp -d "${TMPDIR:-/tmp}/shared-bus.XXXXXX") || exit 1
  trap 'stop_started; rm -rf "$logs"' EXIT
  trap 'exit 130' INT
  trap 'exit 143' TERM
  if [ "$smoke" = 1 ]; then window_s=3 settle_s=2 rounds=1; fi
  measure_in_uml
  rc=$?
  stop_started
  if [ "$rc" != 0 ]; then # the logs of what we started say why
    for log in "$logs"/*.log; do [ -s "$log" ] && sed "s|^|$(basename "$log" .log): |" "$log" >&2; done
  fi
  exit "$rc"
fi

# ---- The driving half: boot, collect, tabulate --------------------------------------------------

for program in "$gateway" "$valve_sim" "$bench" "$peer"; do
  [ -x "$program" ] || { echo "missing $program: build first (cmake --build ${build#"$root"/})" >&2; exit 1; }
done
out=$(mktemp -d "${TMPDIR:-/tmp}/shared-bus-out.XXXXXX") || exit 1
trap 'rm -rf "$out"' EXIT

# Boot and start-up, the windows, and a DDS discovery for each window with the ECU.
windows=$((4 * rounds + 1))
uml_timeout=$((120 + windows * (settle_s + window_s + 5)))
failed=0
for run in $(seq "$runs"); do
  # UML shares the host's CPUs: a busy host shows in the figures, so every run notes the load.
  echo "LOAD run=$run loadavg_1min=$(cut -d' ' -f1 /proc/loadavg)" >"$out/run$run.txt"
  echo "run $run/$runs: user-mode-linux, $windows windows of $window_s s (up to $uml_timeout s)" >&2
  "$root/tests/uml/uml-run" --timeout "$uml_timeout" -- "$self" --inside-uml --build-dir "$build" \
    --window-s "$window_s" --settle-s "$settle_s" --rate "$rate" --rounds "$rounds" \
    >>"$out/run$run.txt"
  rc=$?
  [ "$rc" = 77 ] && exit 77
  [ "$rc" = 0 ] || { echo "run $run failed (exit $rc)" >&2; failed=1; }
done

# One row per phase: the median over rounds and runs, [lowest-highest] when there are several;
# then (b)/(a) of the gateway's CPU medians, bare and with the ECU.
cat "$out"/run*.txt | awk -v window="$window_s" -v rounds="$rounds" -v runs="$runs" '
function value(key,    i, kv) {
  for (i = 2; i <= NF; i++) { split($i, kv, "="); if (kv[1] == key) return kv[2] }
  return ""
}
function add(row, column, v) {
  if (v == "") return
  n = ++count[row, column]; values[row, column, n] = v + 0
  if (!(row in seen)) { seen[row] = 1; order[++rows] = row }
}
function median(row, column,    n, i, j, t, a) {
  n = count[row, column]
  if (n == 0) return ""
  for (i = 1; i <= n; i++) a[i] = values[row, column, i]
  for (i = 2; i <= n; i++) for (j = i; j > 1 && a[j - 1] > a[j]; j--) { t = a[j]; a[j] = a[j - 1]; a[j - 1] = t }
  low[row, column] = a[1]; high[row, column] = a[n]
  return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
}
function cell(row, column, digits,    m) {
  m = median(row, column)
  if (m == "") return "-"
  if (count[row, column] == 1) return sprintf("%." digits "f", m)
  return sprintf("%." digits "f [%." digits "f-%." digits "f]", m, low[row, column], high[row, column])
}
$1 == "LOAD" { loads = loads (loads == "" ? "" : ", ") value("loadavg_1min") }
$1 == "RESOURCES" {
  process = value("process")
  column = process == "teejet-gateway" ? "gateway" : process == "valve-sim" ? "sim" : "sender"
  add(value("label"), column, value("cpu_percent"))
}
$1 == "BUS" { add(value("label"), "bus", value("frames_per_s")) }
$1 == "SUBSCRIBER" {
  add(value("label"), "in", value("gateway_frames_in_per_s"))
  add(value("label"), "samples", value("samples_per_s"))
}
$1 == "FOREIGN" { add("foreign", "rate", value("rate")) }
END {
  printf "\nGateway CPU on a shared bus: 32 valves (valve-sim), %d run(s) x %d round(s), window %s s;\n", runs, rounds, window
  print "CPU in % of one core, median [lowest-highest] over rounds and runs."
  print "(a) valves only, (b) + foreign frames, (c) valve-sim stopped, foreign frames only;"
  print "bare: nobody reads DDS; ecu: an ECU reads every topic (gives frames_in and samples/s)\n"
  print "| phase | frames/s on the bus | gateway CPU % | gateway frames_in/s | ECU samples/s | valve-sim CPU % | foreign sender CPU % |"
  print "|---|---|---|---|---|---|---|"
  for (r = 1; r <= rows; r++) {
    row = order[r]
    if (row == "foreign") continue
    printf "| %s | %s | %s | %s | %s | %s | %s |\n", row, cell(row, "bus", 0), cell(row, "gateway", 2),
      cell(row, "in", 1), cell(row, "samples", 0), cell(row, "sim", 2), cell(row, "sender", 2)
  }
  print "\n| reader | gateway CPU (a) | gateway CPU (b) | (b)/(a) | (b) within 10 % of (a) |"
  print "|---|---|---|---|---|"
  for (m = 1; m <= 2; m++) {
    reader = m == 1 ? "bare" : "ecu"
    a = median("a-" reader, "gateway"); b = median("b-" reader, "gateway")
    if (a == "" || b == "") continue
    ratio = a > 0 ? b / a : 0
    printf "| %s | %.2f | %.2f | %.3f | %s |\n", reader, a, b, ratio, (ratio <= 1.10 ? "yes" : "no")
  }
  printf "\nForeign frames sent per second: %s. Host load average (1 min) at each boot: %s (2 = both host CPUs busy).\n", cell("foreign", "rate", 0), loads
}'
exit "$failed"
