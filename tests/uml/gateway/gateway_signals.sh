#!/usr/bin/env bash
# Runs inside user-mode-linux (tests/uml/uml-run): every ending of teejet-gateway that can run
# code sends Stop to every valve first, whatever became of its log. A vehicle computer closes
# terminals, restarts journald and fills disks; none of that may leave a valve turning. valve-sim
# drives three valves on vcan0 and candump is the witness of the Stop frames.
# Usage: gateway_signals.sh BUILD_DIR REPO_DIR
set -euo pipefail
# SIGQUIT's default action dumps core: a gateway that still took it so would litter the tree.
ulimit -c 0
build=$1
repo=$2
# Whatever a case left running is killed outright: no second Stop may muddy the next case.
end_signal=KILL
# shellcheck source=tests/uml/gateway/uml_session.sh
source "$repo/tests/uml/gateway/uml_session.sh"

addresses=(D8 D9 DA)
wire_lines() { wc -l <"$work/wire.log"; }
# on_wire_after LINE PATTERN: PATTERN in a frame candump logged after its first LINE lines.
on_wire_after() { tail -n +"$(($1 + 1))" "$work/wire.log" | grep -q "$2"; }
all_polled_after() {  # the gateway asked every valve for its position: it knows them all
  local address
  for address in "${addresses[@]}"; do on_wire_after "$1" "18EF${address}D5#11" || return 1; done
}

# Unbuffered: a frame is in the file as soon as candump has it, not when a block fills.
stdbuf -o0 candump -L vcan0 >"$work/wire.log" &
pids+=($!)
"$sim" --can vcan0 --valves 3 >"$work/sim.log" 2>&1 &
pids+=($!)
# Both run once the I Am Here of the last valve has been logged.
check "valve-sim's three valves announce themselves" eventually 10 on_wire_after 0 "18EFD5DA#00"

# run_case NAME SIGNAL EXPECTED_STATUS STDOUT: STDOUT is "file", "full" (/dev/full) or
# "closed-pipe" (a pipe whose reader exits once the gateway runs).
run_case() {
  local name=$1 signal=$2 expected=$3 stdout=$4 start pid marker status address
  start=$(wire_lines)
  case $stdout in
    file) "$gateway" --can vcan0 --domain 9 >"$work/$name.out" 2>"$work/$name.err" & ;;
    full) "$gateway" --can vcan0 --domain 9 >/dev/full 2>"$work/$name.err" & ;;
    closed-pipe)
      mkfifo "$work/$name.fifo"
      "$gateway" --can vcan0 --domain 9 >"$work/$name.fifo" 2>"$work/$name.err" &
      exec 3<"$work/$name.fifo"
      ;;
  esac
  pid=$!
  pids+=("$pid")
  check "$name: the gateway polls all three valves" eventually 30 all_polled_after "$start"
  # The reader goes away as a log collector does when it is restarted: the next log line hits
  # a pipe nobody reads.
  [ "$stdout" = closed-pipe ] && exec 3<&-
  marker=$(wire_lines)
  kill -"$signal" "$pid"
  check "$name: the gateway exits" eventually 15 exited "$pid"
  exited "$pid" || kill -KILL "$pid"
  status=0
  wait "$pid" || status=$?
  check "$name: exit status $expected (got $status)" [ "$status" -eq "$expected" ]
  for address in "${addresses[@]}"; do
    check "$name: Stop to 0x$address on the wire after SIG$signal" \
      eventually 5 on_wire_after "$marker" "18EF${address}D5#00FFFFFFFFFFFFFF"
  done
  [ "$stdout" = file ] && check "$name: the log says so" \
    grep -q "stopped 3 valve(s) on exit" "$work/$name.out"
  return 0
}

run_case term-closed-pipe TERM 0 closed-pipe
run_case term-dev-full TERM 0 full
run_case hup HUP 129 file
run_case int INT 0 file
run_case quit QUIT 131 file

echo "$failures failed"
if [ "$failures" -ne 0 ]; then
  for log in "$work"/*.err "$work"/*.out; do echo "== $log" && tail -n 20 "$log"; done
  echo "== wire: $(wc -l <"$work/wire.log") frames, the last:" && tail -n 5 "$work/wire.log"
fi
[ "$failures" -eq 0 ]
