#!/usr/bin/env bash
# Runs inside user-mode-linux (tests/uml/uml-run), where vcan0 is a real SocketCAN interface:
# valve-sim and teejet-gateway as separate processes on vcan0, driven by valvectl, with candump
# confirming the frames on the wire. DDS stays on the guest's loopback.
# Usage: gateway_bench.sh BUILD_DIR REPO_DIR
set -euo pipefail
build=$1
repo=$2
# shellcheck source=tests/uml/gateway/uml_session.sh
source "$repo/tests/uml/gateway/uml_session.sh"
exits_with() {  # exits_with STATUS COMMAND...
  local expected=$1 status=0
  shift
  "$@" >"$work/last.txt" 2>&1 || status=$?
  [ "$status" -eq "$expected" ] || { echo "  exit $status: $(cat "$work/last.txt")"; return 1; }
}
on_wire() { grep -q "$1" "$work/wire.log"; }
ctl() { "$valvectl" --domain 9 --timeout 20 "$@"; }

candump -L vcan0 >"$work/wire.log" &
pids+=($!)
"$sim" --can vcan0 --valves 3 --dps 180 >"$work/sim.log" 2>&1 &
sim_pid=$!
pids+=("$sim_pid")
"$gateway" --can vcan0 --domain 9 --name uml-gateway >"$work/gateway.log" 2>&1 &
gateway_pid=$!
pids+=("$gateway_pid")

check "valvectl lists the 3 valves of a separate valve-sim process" \
  exits_with 0 ctl list --wait-for 3
cp "$work/last.txt" "$work/list.txt"
check "TJV000002 at 0xD9, online" grep -q "TJV000002  0xD9  yes" "$work/list.txt"

# The gateway armed its poll schedule at each valve's address: Request Position every 100 ms.
check "poll request (0x11, every 1 tenth) to 0xD9 on the wire" \
  eventually 5 on_wire "18EFD9D5#1101FFFFFFFFFFFF"

# A move: 45.0 deg = 450 = 0x01C2, speed 100 = 0x64, open = 1.
check "move --wait completed" exits_with 0 ctl move TJV000002 --to 45 --wait
check "Target Degrees frame on the wire, byte for byte" on_wire "18EFD9D5#02640101C2FFFFFF"
check "the valve reports 45.0 deg (02 01 C2)" eventually 5 on_wire "18EFD5D9#0201C2"

# Refused before the bus: out of range (valvectl, exit 64) and a baud change (gateway, exit 3).
check "out-of-range move refused by valvectl (64)" exits_with 64 ctl move TJV000002 --to 360
check "baud change rejected by the gateway (3)" exits_with 3 ctl baud TJV000002 --set 500000
check "the rejection names its reason" grep -q "not allowed" "$work/last.txt"
check "no Set Baud Rate frame on the wire" bash -c "! grep -q '#93A5' '$work/wire.log'"

# Readdressing: valve-sim adds TJV000000 on SIGUSR1, which takes 0xD8 and moves the others up.
kill -USR1 "$sim_pid"
readdressed() { ctl list >"$work/list2.txt" 2>&1 && grep -q "TJV000001  0xD9" "$work/list2.txt"; }
check "TJV000001 moved to 0xD9 when TJV000000 joined" eventually 10 readdressed
check "move after readdressing completed" exits_with 0 ctl move TJV000001 --to 30 --wait
# 30.0 deg = 0x012C, sent to TJV000001's new address 0xD9.
check "the command followed the serial to 0xD9" on_wire "18EFD9D5#026401012CFFFFFF"

check "stop --all" exits_with 0 ctl stop --all
for address in D8 D9 DA DB; do
  check "Stop to 0x$address on the wire" eventually 5 on_wire "18EF${address}D5#00FFFFFFFFFFFFFF"
done

# Offline: without valve-sim's I'm Here the valves go offline within the 3 s timeout.
kill -TERM "$sim_pid"
offline() { ctl list >"$work/list3.txt" 2>&1 && ! grep -q " yes " "$work/list3.txt"; }
check "every valve offline after valve-sim stopped" eventually 10 offline

kill -TERM "$gateway_pid"
check "gateway exits 0 on SIGTERM" wait "$gateway_pid"

echo "$failures failed"
[ "$failures" -eq 0 ]
