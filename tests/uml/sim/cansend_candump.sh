#!/bin/bash
# valve-sim on vcan0 against the can-utils a user would reach for: requests sent with cansend,
# replies read by candump -L, byte for byte against the protocol sheet. Runs inside
# tests/uml/uml-run (root, vcan0 up). Usage: cansend_candump.sh VALVE_SIM
set -u

VALVE_SIM=${1:?usage: cansend_candump.sh VALVE_SIM}
for tool in cansend candump stdbuf; do
  command -v "$tool" >/dev/null || { echo "SKIP: $tool not installed"; exit 77; }
done

WORK=$(mktemp -d "${TMPDIR:-/tmp}/valve-sim-cansend.XXXXXX")
DUMP=$WORK/dump.log
SIM_PID=
DUMP_PID=
cleanup() {
  [ -n "$SIM_PID" ] && kill -KILL "$SIM_PID" 2>/dev/null
  [ -n "$DUMP_PID" ] && kill "$DUMP_PID" 2>/dev/null
  wait 2>/dev/null
  rm -rf "$WORK"
}
trap cleanup EXIT

failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
pass() { echo "ok: $*"; }

# Waits up to $2 seconds for a candump line matching the extended regex $1 after line $3 (0 =
# anywhere); prints the line number of the match. Polls the log every 50 ms until the line is
# there or the deadline passes: the condition decides, never a fixed sleep.
wait_for_line() {
  local pattern=$1 timeout=$2 after=${3:-0} deadline line
  deadline=$(($(date +%s%N) + timeout * 1000000000))
  while [ "$(date +%s%N)" -lt "$deadline" ]; do
    line=$(tail -n +"$((after + 1))" "$DUMP" | grep -n -E -m1 "$pattern" | cut -d: -f1)
    if [ -n "$line" ]; then
      echo $((after + line))
      return 0
    fi
    sleep 0.05
  done
  return 1
}
# Like wait_for_line, for the $4-th matching line after line $3; prints its line number.
wait_for_nth_line() {
  local pattern=$1 timeout=$2 at=$3 count=$4
  for _ in $(seq "$count"); do
    at=$(wait_for_line "$pattern" "$timeout" "$at") || return 1
  done
  echo "$at"
}
lines() { wc -l <"$DUMP"; }
LINE='^\([0-9]{10}\.[0-9]{6}\) vcan0 '

stdbuf -oL candump -L vcan0 >"$DUMP" &
DUMP_PID=$!
# Two valves; the second has a latched high-voltage error (16.2 V, limit 15.5 V).
"$VALVE_SIM" --can vcan0 --serials 123456,123457 --start 45 \
  --inject-error TJV123457:high-voltage:16.2:15.5 >"$WORK/sim.log" 2>&1 &
SIM_PID=$!

# I'm Here: id 0, part number 0, serial 123456 = 0x01E240, application mode.
if wait_for_line "${LINE}18EFD5D8#0000000001E24000$" 10 >/dev/null; then
  pass "I'm Here of TJV123456 from 0xD8"
else
  fail "no I'm Here from 0xD8"; cat "$WORK/sim.log"; exit 1
fi
wait_for_line "${LINE}18EFD5D9#0000000001E24100$" 5 >/dev/null &&
  pass "I'm Here of TJV123457 from 0xD9" || fail "no I'm Here of TJV123457 from 0xD9"

# Request Position, send once: the reply is Position 45.0 degrees = 450 = 0x01C2.
start=$(lines)
cansend vcan0 18EFD8D5#1100
if wait_for_line "${LINE}18EFD5D8#0201C2FFFFFFFFFF$" 5 "$start" >/dev/null; then
  pass "Request Position answered with 45.0 degrees"
else
  fail "no Position 0201C2 after 18EFD8D5#1100"
fi

# Request Version Information: application 1.00, boot loader 1.00.
start=$(lines)
cansend vcan0 18EFD8D5#10
wait_for_line "${LINE}18EFD5D8#01010000010000FF$" 5 "$start" >/dev/null &&
  pass "Request Version answered" || fail "no Version Information reply"

# Baud rate: set 500k (0xA5, 1), then request (0x55): both answered 0x93 0xA5 1.
start=$(lines)
cansend vcan0 18EFD8D5#93A501
wait_for_line "${LINE}18EFD5D8#93A501FFFFFFFFFF$" 5 "$start" >/dev/null &&
  pass "Set CAN Baud Rate answered" || fail "no reply to the baud-rate set"
start=$(lines)
cansend vcan0 18EFD8D5#935500
wait_for_line "${LINE}18EFD5D8#93A501FFFFFFFFFF$" 5 "$start" >/dev/null &&
  pass "Request CAN Baud Rate answered with 500k" || fail "no reply to the baud-rate request"

# The latched error repeats once a second (16.2 V = 0x00A2, limit 15.5 V = 0x009B) ...
first=$(wait_for_line "${LINE}18EFD5D9#1000A2009BFFFFFF$" 5)
if [ -n "$first" ] && wait_for_line "${LINE}18EFD5D9#1000A2009BFFFFFF$" 3 "$first" >/dev/null; then
  pass "High Voltage Error latched and repeated"
else
  fail "High Voltage Error not repeated"
fi
# ... until Clear Errors; afterwards only I'm Here comes from 0xD9. Clear Errors has no reply,
# so a Request Version follows it: valve-sim answers frames in order, so once that reply is in
# the log the clear has been applied. From there, three I'm Here of 0xD9 span two seconds, in
# which an error still latched (repeated once a second on the same clock) would have come again.
start=$(lines)
cansend vcan0 18EFD9D5#04
cansend vcan0 18EFD9D5#10
cleared=$(wait_for_line "${LINE}18EFD5D9#01010000010000FF$" 5 "$start")
if [ -z "$cleared" ]; then
  fail "no Version reply after Clear Errors"
elif ! wait_for_nth_line "${LINE}18EFD5D9#0000000001E24100$" 3 "$cleared" 3 >/dev/null; then
  fail "TJV123457 stopped announcing itself"
elif tail -n +"$((cleared + 1))" "$DUMP" | grep -q '18EFD5D9#10'; then
  fail "High Voltage Error after Clear Errors"
else
  pass "Clear Errors ends the repeats"
fi

# SIGTERM: a clean exit 0.
kill -TERM "$SIM_PID"
wait "$SIM_PID"
status=$?
SIM_PID=
[ "$status" -eq 0 ] && pass "SIGTERM: exit 0" || fail "SIGTERM: exit $status"

if [ "$failures" -ne 0 ]; then
  echo "--- candump -L vcan0"; cat "$DUMP"
  echo "--- valve-sim"; cat "$WORK/sim.log"
  exit 1
fi
echo "all passed"
