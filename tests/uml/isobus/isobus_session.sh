# shellcheck shell=bash
# Sourced by the ISOBUS scripts that run inside user-mode-linux, after `build` and `repo` are set:
# tests/uml/gateway/uml_session.sh (programs, $work, $pids, check, eventually), the kernel's J1939
# stack, the NAMEs, the wire (candump) and its helpers, and the other parties on the bus.
# Every regular expression here is extended (grep -E); awk here is mawk, which knows no {n}.

# shellcheck source=tests/uml/gateway/uml_session.sh
# shellcheck disable=SC2154 # build and repo are the caller's
source "$repo/tests/uml/gateway/uml_session.sh"
peer="$build/tests/uml/isobus/isobus_peer"
status_reader="$build/tests/uml/isobus/gateway_status_log"

domain=12
wire="$work/wire.log"
gateway_log="$work/gateway.log"
status_log="$work/status.log"
kernel_log="$work/kernel.log"

# Every process ends on SIGTERM within 5 s or is named and killed: a J1939 socket can keep its
# owner in the kernel, and a test that hangs in its cleanup says nothing about why.
cleanup() {
  local pid
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do
    eventually 5 exited "$pid" && continue
    echo "cleanup: $(tr '\0' ' ' <"/proc/$pid/cmdline" 2>/dev/null) (pid $pid," \
      "state $(awk '{print $3}' "/proc/$pid/stat" 2>/dev/null)) ignored SIGTERM; killing it"
    kill -KILL "$pid" 2>/dev/null || true
  done
  wait 2>/dev/null || true
  rm -rf "$work"
}

# uml-run loads CAN_RAW only: the J1939 stack is these tests' own.
j1939_module="/usr/lib/uml/modules/$(uname -r)/kernel/net/can/j1939/can-j1939.ko"
if ! grep -q '^can_j1939 ' /proc/modules && ! insmod "$j1939_module" 2>"$work/insmod.err"; then
  echo "SKIP: the kernel's J1939 stack (can-j1939) cannot load: $(cat "$work/insmod.err")" >&2
  exit 77
fi

# ---- NAMEs --------------------------------------------------------------------------------------
# The gateway's NAME from its isobus: section, worked out here from ISO 11783-5's bit layout (not
# with the gateway's code): industry group 2 (bits 60-62), device class 4 (49-55), function 128
# (40-47) are the defaults; manufacturer code (21-31) and identity number (0-20) are configured.
identity=111299
manufacturer=42
gw_name=$(printf '%016X' $((2 << 60 | 4 << 49 | 128 << 40 | manufacturer << 21 | identity)))
# le NAME: the NAME as Address Claimed carries it, 8 bytes least significant first.
le() {
  local i out=''
  for ((i = 14; i >= 0; i -= 2)); do out+=${1:i:2}; done
  echo "$out"
}

# ---- the wire -----------------------------------------------------------------------------------
# shellcheck disable=SC2034 # the patterns the scripts that source this use
request_all='vcan0 18EAFFFE#00EE00$'
claim="vcan0 18EEFFD5#$(le "$gw_name")\$"
# shellcheck disable=SC2034
cannot_claim="vcan0 18EEFFFE#$(le "$gw_name")\$"
# shellcheck disable=SC2034
probe='vcan0 18EAD5FE#00EE00$'
hex='[0-9A-F]'
from_d5="vcan0 $hex$hex$hex$hex$hex${hex}D5#"
# shellcheck disable=SC2034
poll="vcan0 18EF(D[89A-F]|E$hex|F[0-7])D5#"
not_after() { ! after "$@"; }
# first_after FILE LINE REGEX: the number of the first line after LINE that matches, or nothing.
# (awk reads to the end: a reader that stops early would fail the pipeline.)
first_after() {
  grep -nE -- "$3" "$1" | awk -F: -v from="$2" '!found && $1 > from { print $1; found = 1 }' ||
    true
}
found_after() { [ -n "$(first_after "$@")" ]; }
# count_between FIRST LAST REGEX: wire lines FIRST+1..LAST that match.
count_between() {
  if [ "$2" -le "$1" ]; then echo 0 && return; fi
  sed -n "$(($1 + 1)),$2p" "$wire" | grep -cE -- "$3" || true
}
stamp() { sed -n "$1p" "$wire" | sed -E 's/^\(([0-9.]+)\).*/\1/'; }
gap() { awk -v a="$(stamp "$1")" -v b="$(stamp "$2")" 'BEGIN { printf "%.3f", b - a }'; }
# request_then_claim_after LINE: a request for claims to everyone, then the claim, after LINE.
request_then_claim_after() {
  local request
  request=$(first_after "$wire" "$1" "$request_all")
  [ -n "$request" ] && found_after "$wire" "$request" "$claim"
}
# other_from_d5_after LINE: the first frame from 0xD5 after LINE that is not the gateway's claim.
other_from_d5_after() {
  grep -nE -- "$from_d5" "$wire" | grep -vE -- "$claim" |
    awk -F: -v from="$1" '!found && $1 > from { print $1; found = 1 }' || true
}
# excerpt NAME FIRST LAST [LINE...]: the claiming frames among wire lines FIRST..LAST (and the
# J1939 sockets' frames to 0xD5, from j1939acd's 0x8x or the test's address), and the LINEs
# given, prefixed for the record.
excerpt() {
  local name=$1 first=$2 last=$3
  shift 3
  awk -v from="$first" -v to="$last" -v extra=" $* " -v name="$name" -v h="$hex" \
    -v test="$test_address" '
    NR >= from && NR <= to && ($0 ~ (" 18E[AE]" h h h h "#") || $0 ~ (" 18EFD5(8" h "|" test ")#") ||
      index(extra, " " NR " ")) { print "excerpt: [" name "] " $0 }' "$wire"
}

# ---- the parties --------------------------------------------------------------------------------
# record_wire: candump bound to every CAN interface, which outlives vcan0 going down or away.
record_wire() {
  stdbuf -o0 candump -L any >"$wire" 2>"$work/candump.err" &
  pids+=($!)
  # A frame sent once its receiver is in the kernel's list is recorded (tests/uml/README.md).
  check "candump records the bus" eventually 5 grep -Eq '^ +any +000 +00000000 .* raw' \
    /proc/net/can/rcvlist_all
}
# hold_j1939: a J1939 socket bound to vcan0 keeps the kernel's J1939 instance there, with its
# cache of which NAME holds which address, alive; it also logs the NAMEs the kernel gives frames.
hold_j1939() {
  "$peer" hold vcan0 >>"$kernel_log" 2>&1 &
  hold_pid=$!
  pids+=("$hold_pid")
  check "the kernel's J1939 stack runs on vcan0" eventually 5 grep -q "holding the J1939 instance" \
    "$kernel_log"
}
# claim_test_address: the J1939 sockets that send from a static address (0x90, outside
# j1939acd's range and the valves') belong to an ECU that claimed it and answers requests like
# any neighbour, so that the gateway takes their PGN 0xEF00 frames to 0xD5 for a neighbour's, not
# for broken valve frames.
test_address=90
test_name=A00C810000000090
claim_test_address() {
  local mark
  mark=$(lines "$wire")
  "$peer" ecu vcan0 --name "$test_name" --address "0x$test_address" --answers 1000000 \
    >"$work/test-ecu.log" 2>&1 &
  pids+=($!)
  check "the test's own ECU claims 0x$test_address" eventually 5 found_after "$wire" "$mark" \
    "vcan0 18EEFF$test_address#$(le "$test_name")"
}
start_valves() {
  "$sim" --can vcan0 --valves 3 --dps 180 >"$work/sim.log" 2>&1 &
  pids+=($!)
  check "valve-sim's three valves announce themselves" eventually 10 found_after "$wire" 0 \
    "vcan0 18EFD5DA#00"
}
# start_gateway: GatewayStatus read into status.log, the gateway with the NAME above.
start_gateway() {
  printf 'isobus:\n  identity_number: %d\n  manufacturer_code: %d\n' "$identity" "$manufacturer" \
    >"$work/gateway.yaml"
  "$status_reader" "$domain" >"$status_log" 2>"$work/status.err" &
  pids+=($!)
  "$gateway" --config "$work/gateway.yaml" --can vcan0 --domain "$domain" >"$gateway_log" 2>&1 &
  gateway_pid=$!
  pids+=("$gateway_pid")
}
# by_name EXIT DATA FROM...: one J1939 frame (PGN 0xEF00, DATA) to the gateway's NAME, from a NAME
# (--from-name) or a static address (--from-address); true when the send ended with EXIT
# (0 sent, 2 EADDRNOTAVAIL: the kernel knows no address for a NAME).
by_name() {
  local expected=$1 data=$2 rc=0
  shift 2
  "$peer" send vcan0 "$@" --to-name "$gw_name" --pgn 0xEF00 --data "$data" >"$work/send.out" 2>&1 ||
    rc=$?
  [ "$rc" -eq "$expected" ]
}
status_after() { after "$status_log" "$1" "$2"; }
statuses_beyond() { [ "$(lines "$status_log")" -gt "$1" ]; }
log_has() { grep -Eq -- "$1" "$gateway_log"; }
log_count() { grep -Ec -- "$1" "$gateway_log" || true; }
log_more_than() { [ "$(log_count "$1")" -gt "$2" ]; }  # PATTERN COUNT
move() {  # TARGET [OPTIONS...]: valvectl's exit status and output on one line
  local rc=0 output
  output=$("$valvectl" --domain "$domain" --timeout 20 move TJV000002 --to "$@" 2>&1) || rc=$?
  echo "$rc $(echo "$output" | tr '\n' '|')"
}
# report: the count, the gateway's claiming log, and on failure what each party said.
report() {
  echo "$failures failed"
  echo "== the gateway's log of claiming"
  grep -E "claim|address|NAME|bus is back|link|interface" "$gateway_log" | head -n 40 || true
  echo "== last GatewayStatus" && tail -n 1 "$status_log"
  if [ "$failures" -ne 0 ]; then
    echo "== gateway log (last 40)" && tail -n 40 "$gateway_log"
    echo "== kernel (isobus_peer hold)" && head -n 40 "$kernel_log"
    echo "== last send"
    cat "$work/send.out" 2>/dev/null || true
    echo "== status (last 3)" && tail -n 3 "$status_log" && cat "$work/status.err"
    echo "== wire: claiming frames"
    grep -E " 18E[AE]| 18EFD5(8.|$test_address)#" "$wire" | head -n 60 || true
    echo "== processes"
    ps -eo pid,stat,pcpu,etime,args || true
  fi
}
