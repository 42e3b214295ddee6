"""What the python-can peers of valve-sim share: the frames of the protocol sheet, built and
parsed here independently of the project's codec, the checks and their report, and starting and
stopping valve-sim. Imported by the scripts in this directory (see import_sheet there).

Exits 77 (SKIP) on import when python3-can is missing.
"""

import signal
import subprocess
import sys

try:
    import can
except ImportError:
    print("SKIP: python3-can is not installed for", sys.executable)
    sys.exit(77)

CONTROLLER = 0xD5
FAILURES = []


def check(condition, what):
    print(("ok: " if condition else "FAIL: ") + what)
    if not condition:
        FAILURES.append(what)


# ---- frames -------------------------------------------------------------------------------------

def to_valve(address):  # 0x18EF<valve>D5
    return 0x18EF0000 | address << 8 | CONTROLLER


def open_bus():
    """vcan0, valve to controller frames only: 0x18EFD5xx."""
    return can.interface.Bus(
        channel="vcan0", interface="socketcan",
        can_filters=[{"can_id": 0x18EFD500, "can_mask": 0x1FFFFF00, "extended": True}])


def send(bus, address, payload):
    bus.send(can.Message(arbitration_id=to_valve(address), data=bytes(payload),
                         is_extended_id=True))


def tenths(degrees):
    """Degrees x 10 as two bytes, MSB first."""
    value = round(degrees * 10)
    return [value >> 8, value & 0xFF]


def u16(data, offset):
    return data[offset] << 8 | data[offset + 1]


def u24(data, offset):
    return data[offset] << 16 | data[offset + 1] << 8 | data[offset + 2]


def u32(data, offset):
    return u24(data, offset) << 8 | data[offset + 3]


# ---- valve-sim ----------------------------------------------------------------------------------

def start_valve_sim(valve_sim, args, log):
    """valve-sim ARGS with stdout and stderr to the file `log`."""
    return subprocess.Popen([valve_sim] + args, stdout=log, stderr=subprocess.STDOUT)


def stop_valve_sim(simulator):
    """SIGTERM to a valve-sim still running, which must then exit 0 within 10 s."""
    if simulator.poll() is None:
        simulator.send_signal(signal.SIGTERM)
        try:
            code = simulator.wait(timeout=10)
        except subprocess.TimeoutExpired:
            simulator.kill()
            code = "killed"
        check(code == 0, "SIGTERM: valve-sim exits 0 (got %s)" % code)


def print_log_on_failure(log_path):
    if FAILURES:
        print("--- valve-sim log")
        print(open(log_path).read())


def finish():
    """Exits 1 if a check failed."""
    if FAILURES:
        print("%d check(s) failed" % len(FAILURES))
        sys.exit(1)
    print("all passed")
