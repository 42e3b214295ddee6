#!/usr/bin/env bash
# Runs inside user-mode-linux (tests/uml/uml-run): commands from a foreign or hostile DDS writer
# (issue 10, item 3), proven on the wire. teejet-gateway drives valve-sim's two valves on vcan0;
# hostile_writer sends every hostile value of the IDL's fields, an unknown serial, 10,000
# commands to one valve as fast as it can (HOSTILE_FLOOD, 3000 by default: the writer manages
# ~300 a second on UML's one CPU) and good moves. candump records every frame; each
# controller-to-valve frame is then checked against the sheet's ranges (every hostile value is
# outside them, so none of those got through), and the run commands to each valve in any second
# against the rate limit (100/s, burst 20, Stop on its own bucket). Every hostile case, the move
# of valve 2 amid the flood and the good moves must end as expected, every command outside the
# flood must have had its final status; statuses of the flood lost on the way are counted.
# Usage: gateway_hostile.sh BUILD_DIR REPO_DIR
set -euo pipefail
build=$1
repo=$2
# shellcheck source=tests/uml/gateway/uml_session.sh
source "$repo/tests/uml/gateway/uml_session.sh"
writer="$build/tests/uml/gateway/hostile_writer"

# on_wire PATTERN: candump has logged a frame matching PATTERN.
on_wire() { grep -q "$1" "$work/wire.log"; }

stdbuf -o0 candump -L vcan0 >"$work/wire.log" &
pids+=($!)
"$sim" --can vcan0 --valves 2 >"$work/sim.log" 2>&1 &
pids+=($!)
check "valve-sim's two valves announce themselves" eventually 10 on_wire "18EFD5D9#00"

# One gateway on this bus: a command for a serial it does not have is REJECTED, not ignored.
# The writer's exit is no commander lost: its last commands' Stops would muddy the count.
cat >"$work/gateway.yaml" <<'YAML'
gateway: {reject_unknown_serials: true, on_commander_lost: ignore}
YAML
"$gateway" --can vcan0 --domain 9 --config "$work/gateway.yaml" >"$work/gateway.log" 2>&1 &
pids+=($!)
check "the gateway polls both valves" eventually 15 \
  bash -c "grep -q 18EFD8D5#11 '$work/wire.log' && grep -q 18EFD9D5#11 '$work/wire.log'"

status=0
timeout "$(scaled_seconds 100)" "$writer" 9 1 2 99 "${HOSTILE_FLOOD:-3000}" >"$work/writer.out" 2>"$work/writer.err" || status=$?
# Everything the gateway sent while the writer ran, and nothing of its shutdown.
cp "$work/wire.log" "$work/wire.final"
cat "$work/writer.out"
check "every case ended as expected; every command outside the flood got its final status (exit $status)" \
  [ "$status" -eq 0 ]
check "no case ended unexpectedly" grep -q "unexpected 0$" "$work/writer.out"

# The sheet's rules, independently of the project's codec: controller 0xD5 to a valve's address
# (serial 1 is at 0xD8, serial 2 at 0xD9: valve-sim's order), the message ids the sheet defines,
# each field in its range; and no more run commands to a valve in any second than the limit.
check "every frame to a valve is within the sheet's ranges, and within the rate limit" \
  python3 - "$work/wire.final" "$work/writer.out" <<'PY'
import re, sys
wire, writer = sys.argv[1], sys.argv[2]
address_of = {1: 0xD8, 2: 0xD9}
expected = {}
for line in open(writer):
    m = re.match(r"run_frames (\d+) (\d+)", line)
    if m:
        expected[address_of[int(m.group(1))]] = int(m.group(2))
bad, run, frames = [], {0xD8: 0, 0xD9: 0}, 0
times = {}  # (address, is Stop) -> send times of run commands
text = open(wire).read()
# The copy may have caught candump in the middle of a line: only whole lines count.
for line in text.split("\n")[:-1]:
    m = re.match(r"\(\S+\) vcan0 ([0-9A-F]{8})#([0-9A-F]*)$", line.strip())
    if not m:
        bad.append("unreadable: " + line.strip())
        continue
    stamp = float(line.split(")")[0][1:])
    can_id, data = int(m.group(1), 16), bytes.fromhex(m.group(2))
    if can_id & 0xFFFF00FF != 0x18EF00D5:
        continue  # valve to controller
    frames += 1
    dest = (can_id >> 8) & 0xFF
    why = None
    if dest not in address_of.values():
        why = "no valve at this address"
    elif not data:
        why = "empty"
    else:
        mid = data[0]
        if mid in (0x00, 0x04):
            pass
        elif mid == 0x01:
            if data[1] > 100 or data[2] > 1: why = "manual out of range"
        elif mid in (0x02, 0x03):
            tenths = data[3] << 8 | data[4]
            directions = (0, 1, 2) if mid == 0x02 else (0, 1)
            if data[1] > 100 or data[2] not in directions or tenths > 3599:
                why = "degrees out of range"
        elif mid == 0x05:
            if data[1] > 100 or data[2] > 1: why = "milliseconds to run out of range"
        elif 0x10 <= mid <= 0x18:
            pass  # resend period: any u8
        elif mid == 0x93:
            if data[1] != 0x55: why = "a baud rate set (not allowed)"
        else:
            why = "message id the sheet does not define"
        if why is None and mid <= 0x05:
            run[dest] += 1
            times.setdefault((dest, mid == 0x00), []).append(stamp)
    if why:
        bad.append(f"{why}: {line.strip()}")
# A token bucket of 100/s holding 20 passes at most 120 in any one second.
busiest = 0
for key, stamps in times.items():
    start = 0
    for end, t in enumerate(stamps):
        while t - stamps[start] >= 1.0:
            start += 1
        busiest = max(busiest, end - start + 1)
        if end - start + 1 > 120:
            bad.append(f"{end - start + 1} run commands to 0x{key[0]:02X} within 1 s")
            break
print(f"{frames} controller-to-valve frames; run commands on the wire: "
      f"0xD8 {run[0xD8]}, 0xD9 {run[0xD9]} (busiest second: {busiest}); the writer saw "
      f"ACCEPTED for 0xD8 {expected.get(0xD8)}, 0xD9 {expected.get(0xD9)}")
for b in bad[:20]:
    print("bad frame:", b)
sys.exit(1 if bad else 0)
PY

echo "$failures failed"
if [ "$failures" -ne 0 ]; then
  for log in "$work"/*.err "$work"/gateway.log "$work"/sim.log; do echo "== $log" && tail -n 20 "$log"; done
fi
[ "$failures" -eq 0 ]
