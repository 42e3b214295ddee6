#!/usr/bin/python3
"""valve-sim and an independent python-can peer agree.

The peer builds and parses frames itself, straight from the protocol sheet (not with the
project's codec): I'm Here serials and addresses, Version Information, a move, the position,
readdressing after SIGUSR1. Runs inside tests/uml/uml-run (root, vcan0 up), with the Debian
python3 (python3-can). Usage: python_can_peer.py VALVE_SIM
"""

import os
import signal
import sys
import tempfile
import time

# sheet.py sits next to this script, whatever the working directory; no __pycache__ in the tree.
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..", "support"))
sys.dont_write_bytecode = True
from sheet import (check, finish, open_bus, print_log_on_failure, send,  # noqa: E402
                   start_valve_sim, stop_valve_sim, tenths, u16, u24, u32)
from waiting import latest  # noqa: E402 (tests/support)


class Peer:
    def __init__(self):
        self.bus = open_bus()

    def send(self, address, payload):
        send(self.bus, address, payload)

    def frames(self, seconds):
        """Every valve frame for `seconds`: (address, data, timestamp)."""
        deadline = time.monotonic() + seconds
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return
            message = self.bus.recv(timeout=left)
            if message is not None:
                yield message.arbitration_id & 0xFF, bytes(message.data), message.timestamp

    def reply(self, address, payload, reply_id, timeout=3.0):
        """Sends payload to the valve and returns the data of its first reply_id frame."""
        self.send(address, payload)
        for source, data, _ in self.frames(timeout):
            if source == address and data and data[0] == reply_id:
                return data
        return None

    def reply_when(self, done, address, payload, reply_id, seconds=3.0):
        """Asks every 20 ms until a reply satisfies done(data) or `seconds` pass; returns the
        last reply (None when the last ask got none), for the check to judge and report."""
        return latest(lambda: self.reply(address, payload, reply_id, timeout=1.0), seconds,
                      ok=lambda data: data is not None and done(data), interval=0.02)

    def i_am_here(self, done, seconds):
        """I'm Here frames until done(valves, stamps) holds or `seconds` pass: {serial: (address,
        part number, run mode)} as last announced, and the stamps of each serial."""
        valves, stamps = {}, {}
        for source, data, stamp in self.frames(seconds):
            if data[0] == 0x00 and len(data) >= 8:
                serial = u24(data, 4)
                valves[serial] = (source, u24(data, 1), data[7])
                stamps.setdefault(serial, []).append(stamp)
                if done(valves, stamps):
                    break
        return valves, stamps


def main():
    valve_sim = sys.argv[1]
    log = tempfile.NamedTemporaryFile(prefix="valve-sim-peer.", suffix=".log", delete=False)
    peer = Peer()
    simulator = start_valve_sim(
        valve_sim, ["--can", "vcan0", "--serials", "123457,TJV123456", "--dps", "180"], log)
    try:
        run(peer, simulator)
    finally:
        stop_valve_sim(simulator)
        peer.bus.shutdown()
        log.close()
        print_log_on_failure(log.name)
        os.unlink(log.name)
    finish()


def run(peer, simulator):
    # I'm Here: lowest serial at 0xD8, once a second, part number 0, application code. Three of
    # TJV123456 give two periods.
    valves, stamps = peer.i_am_here(
        lambda valves, stamps: len(stamps.get(123456, [])) >= 3 and 123457 in valves, 5.0)
    check(valves.get(123456) == (0xD8, 0, 0), "TJV123456 announces itself at 0xD8: %s" % valves)
    check(valves.get(123457) == (0xD9, 0, 0), "TJV123457 announces itself at 0xD9")
    periods = [b - a for a, b in zip(stamps.get(123456, []), stamps.get(123456, [])[1:])]
    check(periods and all(0.8 <= p <= 1.2 for p in periods),
          "I'm Here once a second: %s" % ["%.3f" % p for p in periods])

    data = peer.reply(0xD9, [0x10], 0x01)
    check(data is not None and list(data[1:7]) == [1, 0, 0, 1, 0, 0],
          "Version Information: application 1.00, boot loader 1.00 (%s)" % data)

    # Target Degrees 90.0 at 100 %, open: 0x02, speed, direction, degrees x 10 (MSB, LSB).
    # 90 degrees at 180 dps take 0.5 s; the position is asked until it reads 90.0 (or 3 s pass).
    peer.send(0xD9, [0x02, 100, 1] + tenths(90.0))
    data = peer.reply_when(lambda data: u16(data, 1) == 900, 0xD9, [0x11, 0], 0x02)
    check(data is not None and u16(data, 1) == 900,
          "position after the move: 90.0 degrees (%s)" % data)
    # Degrees from Position: close by 45.0.
    peer.send(0xD9, [0x03, 50, 0] + tenths(45.0))
    data = peer.reply(0xD9, [0x16, 0], 0x07)  # while it runs
    check(data is not None and list(data[1:4]) == [50, 0, 1],
          "speed 50 %%, closing, opening clockwise while running (%s)" % data)
    # 45 degrees at 90 dps: 0.5 s.
    data = peer.reply_when(lambda data: u16(data, 1) == 450, 0xD9, [0x11, 0], 0x02)
    check(data is not None and u16(data, 1) == 450,
          "position after closing 45: 45.0 degrees (%s)" % data)
    data = peer.reply(0xD9, [0x18, 0], 0x09)
    check(data is not None and u32(data, 1) == 2, "cycle count 2")
    data = peer.reply(0xD9, [0x15, 0], 0x06)
    check(data is not None and u16(data, 1) == 180 and data[3] == 0,
          "180 degrees per second, last direction close")
    data = peer.reply(0xD8, [0x11, 0], 0x02)
    check(data is not None and u16(data, 1) == 0, "the other valve has not moved")

    # SIGUSR1 adds TJV123455: it takes 0xD8 and the others move up one address.
    simulator.send_signal(signal.SIGUSR1)
    moved = {123455: 0xD8, 123456: 0xD9, 123457: 0xDA}
    valves, _ = peer.i_am_here(
        lambda valves, _: all(valves.get(s, (None,))[0] == a for s, a in moved.items()), 3.0)
    check(valves.get(123455, (None,))[0] == 0xD8, "TJV123455 added at 0xD8: %s" % valves)
    check(valves.get(123456, (None,))[0] == 0xD9, "TJV123456 moved to 0xD9")
    check(valves.get(123457, (None,))[0] == 0xDA, "TJV123457 moved to 0xDA")
    data = peer.reply(0xDA, [0x11, 0], 0x02)
    check(data is not None and u16(data, 1) == 450, "TJV123457 keeps its position at 0xDA")


if __name__ == "__main__":
    main()
