#!/usr/bin/python3
"""Motion physics end to end: moves commanded over vcan0 reach their targets at the configured
speed. Position telemetry (Request Position, resent every 0.1 s) is timed with the kernel's
receive stamps; the peer decodes the frames itself from the protocol sheet.

Runs inside tests/uml/uml-run (root, vcan0 up; the guest has one slow CPU, hence the
tolerances). Usage: motion_physics.py VALVE_SIM
"""

import os
import sys
import tempfile
import time

# sheet.py sits next to this script, whatever the working directory; no __pycache__ in the tree.
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
sys.dont_write_bytecode = True
from sheet import (check, finish, open_bus, print_log_on_failure, send,  # noqa: E402
                   start_valve_sim, stop_valve_sim, tenths, u16)

# Telemetry comes every 0.1 s: the first report at the target lags the arrival by up to that.
REACH_TOLERANCE_EARLY = 0.05
REACH_TOLERANCE_LATE = 0.20
RATE_TOLERANCE = 0.05  # relative, of the least-squares slope


def wait_for_valve(bus, address, seconds=10.0):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        message = bus.recv(timeout=0.2)
        if message and message.arbitration_id & 0xFF == address and message.data[0] == 0x00:
            return True
    return False


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
    """Checks arrival time and speed of one move; prints the measured figures."""
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
    check(expected - REACH_TOLERANCE_EARLY <= took <= expected + REACH_TOLERANCE_LATE,
          "%s: reached %.1f after %.3f s (expected %.3f s, +%.2f/-%.2f)"
          % (name, target, took, expected, REACH_TOLERANCE_LATE, REACH_TOLERANCE_EARLY))
    moving = [(t, d) for t, d in travelled if 0.0 < d < distance]
    if len(moving) < 4:
        check(False, "%s: only %d samples while moving" % (name, len(moving)))
        return
    rate = slope(moving)
    check(abs(rate - dps) <= RATE_TOLERANCE * dps,
          "%s: %.2f deg/s measured over %d samples (configured %.1f, +-%d %%)"
          % (name, rate, len(moving), dps, RATE_TOLERANCE * 100))
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
