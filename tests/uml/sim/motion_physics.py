#!/usr/bin/python3
"""Motion physics end to end: moves commanded over vcan0 reach their targets, never faster than
the configured speed, without overshoot. Position telemetry (Request Position, resent every
0.1 s) is timed with the kernel's receive stamps; the peer decodes the frames itself from the
protocol sheet. How long a move took and the speed measured on the bus are printed, not judged
from above: a loaded machine delays the telemetry (the speed model itself is checked against an
injected clock in tests/sim/motion_tests.cpp).

Runs inside tests/uml/uml-run (root, vcan0 up; the guest has one slow CPU).
Usage: motion_physics.py VALVE_SIM
"""

import os
import sys
import tempfile
import time

# sheet.py sits next to this script, whatever the working directory; no __pycache__ in the tree.
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..", "support"))
sys.dont_write_bytecode = True
from sheet import (check, finish, open_bus, print_log_on_failure, send,  # noqa: E402
                   start_valve_sim, stop_valve_sim, tenths, u16)
from waiting import first  # noqa: E402 (tests/support)

# Telemetry comes every 0.1 s, stamped by the receiving kernel: a report can only come late,
# so a move cannot seem shorter than the physics allows by more than the clock's grain.
REACH_TOLERANCE_EARLY = 0.05


def wait_for_valve(bus, address, seconds=10.0):
    """True once the valve at `address` announced itself (I'm Here) within `seconds`."""
    def announced():
        message = bus.recv(timeout=0.2)
        return message and message.arbitration_id & 0xFF == address and message.data[0] == 0x00

    return first(announced, seconds, interval=0) is not None


def track(bus, address, command, target, expected_seconds, wrap=False):
    """Sends `command` and collects (stamp, degrees) until the position has stayed at `target`
    for 0.3 s. Returns the command's send time and the samples."""
    while bus.recv(timeout=0):  # forget older telemetry
        pass
    sent = time.time()
    send(bus, address, command)
    samples = []
    deadline = time.monotonic() + expected_seconds * 2 + 3
    reached_at = None
    while time.monotonic() < deadline:
        message = bus.recv(timeout=0.5)
        if message is None or message.arbitration_id & 0xFF != address:
            continue
        if message.data[0] != 0x02:
            continue
        degrees = u16(message.data, 1) / 10.0
        samples.append((message.timestamp, degrees))
        if abs(degrees - target) < 0.05:
            reached_at = reached_at or message.timestamp
            if message.timestamp - reached_at >= 0.3:
                break
        else:
            reached_at = None
    return sent, samples


def slope(points):
    n = len(points)
    mean_t = sum(t for t, _ in points) / n
    mean_d = sum(d for _, d in points) / n
    num = sum((t - mean_t) * (d - mean_d) for t, d in points)
    den = sum((t - mean_t) ** 2 for t, _ in points)
    return num / den


def judge(name, sent, samples, start, target, dps, unwrap=None):
    """Checks that one move arrives, never sooner than its speed allows, moving steadily
    towards the target without overshoot; prints the time it took and the speed measured."""
    if not samples:
        check(False, name + ": no position telemetry")
        return
    # Positions relative to the start along the direction of travel (unwrapped for 360).
    travelled = [(t, unwrap(d) if unwrap else abs(d - start)) for t, d in samples]
    distance = unwrap(target) if unwrap else abs(target - start)
    arrival = next((t for t, d in travelled if abs(d - distance) < 0.05), None)
    expected = distance / dps
    if arrival is None:
        check(False, "%s: never reached %.1f (last %s)" % (name, target, samples[-1]))
        return
    took = arrival - sent
    check(took >= expected - REACH_TOLERANCE_EARLY,
          "%s: reached %.1f after %.3f s, not sooner than %.1f deg/s allows (%.3f s, -%.2f)"
          % (name, target, took, dps, expected, REACH_TOLERANCE_EARLY))
    moving = [(t, d) for t, d in travelled if 0.0 < d < distance]
    if len(moving) < 4:
        check(False, "%s: only %d samples while moving" % (name, len(moving)))
        return
    backwards = [(a, b) for a, b in zip(moving, moving[1:]) if b[1] < a[1]]
    check(not backwards, "%s: each of %d reports while moving nearer the target (%d not: %s)"
          % (name, len(moving), len(backwards), backwards[:3]))
    print("measure: %s: reached after %.3f s (%.3f s at %.1f deg/s), %.2f deg/s over %d samples"
          % (name, took, expected, dps, slope(moving), len(moving)))
    overshoot = [d for _, d in travelled if d > distance + 0.05]
    check(not overshoot, "%s: no overshoot past the target" % name)


def main():
    valve_sim = sys.argv[1]
    work = tempfile.mkdtemp(prefix="valve-sim-motion.")
    config = os.path.join(work, "sim.yaml")
    with open(config, "w") as out:
        # 0xD8: limited 0..90 at 90 dps. 0xD9: a full-turn valve at 120 dps, starting at 300.
        out.write("valves:\n"
                  "  - serial: 1\n"
                  "  - serial: 2\n    opened: 360\n    dps: 120\n    start: 300\n")
    log_path = os.path.join(work, "sim.log")
    log = open(log_path, "w")
    bus = open_bus()
    simulator = start_valve_sim(valve_sim, ["--can", "vcan0", "--config", config], log)
    started = time.monotonic()
    try:
        check(wait_for_valve(bus, 0xD8) and wait_for_valve(bus, 0xD9), "both valves announced")
        send(bus, 0xD8, [0x11, 1])  # position every 0.1 s
        send(bus, 0xD9, [0x11, 1])

        # 0 -> 90 at 100 %: 1.0 s at 90 deg/s.
        sent, samples = track(bus, 0xD8, [0x02, 100, 1] + tenths(90.0), 90.0, 1.0)
        judge("0->90 at 100%", sent, samples, 0.0, 90.0, 90.0)
        # 90 -> 0 at 50 %: 2.0 s at 45 deg/s (the direction byte is ignored by a limited valve).
        sent, samples = track(bus, 0xD8, [0x02, 50, 1] + tenths(0.0), 0.0, 2.0)
        judge("90->0 at 50%", sent, samples, 90.0, 0.0, 45.0)
        # Full turn, shortest path 300 -> 60 opens through 0: 120 degrees, 1.0 s at 120 deg/s.
        sent, samples = track(bus, 0xD9, [0x02, 100, 2] + tenths(60.0), 60.0, 1.0)
        judge("300->60 shortest, full turn", sent, samples, 300.0, 60.0, 120.0,
              unwrap=lambda d: (d - 300.0) % 360.0)
    finally:
        stop_valve_sim(simulator)
        bus.shutdown()
        log.close()
        print_log_on_failure(log_path)
        os.unlink(log_path)
        os.unlink(config)
        os.rmdir(work)
    print("bench time %.1f s" % (time.monotonic() - started))
    finish()


if __name__ == "__main__":
    main()
