#!/usr/bin/python3
"""What every network test relies on: hosts reach each other only as the topology says.

Unicast crosses the bridge and the router; multicast crosses the bridge and not the router (so a
profile that needs multicast really fails across it); no host shares /dev/shm with another (so
Fast DDS cannot bypass the network). Usage: lab-run [--uml] -- netlab_selftest.py [--netem]
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from netlab import SKIP, Lab, LabUnavailable  # noqa: E402
from waiting import first  # noqa: E402 (tests/support)

PYTHON = "/usr/bin/python3"

RECEIVE = r"""
import socket, struct, sys
group, port = sys.argv[1], int(sys.argv[2])
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
s.bind(("", port))
if group != "-":
    s.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP,
                 struct.pack("4s4s", socket.inet_aton(group), socket.inet_aton("0.0.0.0")))
s.settimeout(float(sys.argv[3]) + 120)
print("ready", flush=True)
try:
    data, peer = s.recvfrom(100)
    print(data.decode(), peer[0])
except socket.timeout:
    print("nothing")
"""

SEND = r"""
import socket, sys, time
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 8)
for _ in range(int(sys.argv[3])):
    s.sendto(b"hello", (sys.argv[1], int(sys.argv[2])))
    time.sleep(0.05)
"""

failures = []


def check(what, condition, got=None):
    print(f"{'ok' if condition else 'FAILED'}: {what}" + ("" if condition or got is None else f" (got {got!r})"))
    if not condition:
        failures.append(what)


def datagram(lab, sender, receiver, destination, group="-", wait=2.0):
    """What RECEIVER gets when SENDER sends to DESTINATION (port 7400, the DDS discovery port)."""
    log = f"/run/netlab/{receiver}.out"
    listener = lab.spawn(receiver, [PYTHON, "-c", RECEIVE, group, "7400", str(wait)], log=log)

    def output():
        with open(log) as out:
            return out.read().split("\n")

    if not first(lambda: "ready" in output(), 30):
        return "the listener never got ready"
    # The listener outlives the sender however long a loaded machine takes to start it: it is
    # stopped only once every datagram is out and it had `wait` seconds more to see one.
    lab.run(sender, [PYTHON, "-c", SEND, destination, "7400", str(int(wait / 0.05))],
            timeout=wait + 60)
    first(lambda: len(output()) > 2, wait)
    lab.stop(listener)
    lines = output()
    return lines[1].strip() if len(lines) > 2 else "nothing"


def shm_is_private(lab):
    lab.run("vehicle", ["sh", "-c", "echo vehicle > /dev/shm/netlab-marker"])
    seen_by_bench = lab.run("bench", ["sh", "-c", "cat /dev/shm/netlab-marker 2>/dev/null || true"])
    return seen_by_bench.stdout.strip() == "" and not os.path.exists("/dev/shm/netlab-marker")


def main():
    with Lab("bridged") as lab:
        got = datagram(lab, "bench", "vehicle", lab.address("vehicle"))
        check("bridged: unicast bench -> vehicle", got == "hello 192.0.2.3", got)
        got = datagram(lab, "bench", "vehicle", "239.255.0.1", "239.255.0.1")
        check("bridged: multicast bench -> vehicle", got == "hello 192.0.2.3", got)
        check("bridged: /dev/shm is per host", shm_is_private(lab))

    netem = "delay 50ms loss 1%" if "--netem" in sys.argv else None
    try:
        with Lab("routed", netem=netem) as lab:
            got = datagram(lab, "bench", "vehicle", lab.address("vehicle"))
            check("routed: unicast bench -> vehicle through the router", got == "hello 198.51.100.2", got)
            got = datagram(lab, "bench", "vehicle", "239.255.0.1", "239.255.0.1", 1.0)
            check("routed: multicast does not cross the router", got == "nothing", got)
            if netem:
                rtt = lab.run("bench", [PYTHON, "-c", RTT, lab.address("vehicle")], timeout=30)
                # The delay is there both ways; how much the host adds to it is not judged.
                check(f"routed: netem round trip {rtt.stdout.strip()} ms is at least 100 ms",
                      rtt.returncode == 0 and 100 <= float(rtt.stdout or 0))
    except LabUnavailable as why:
        print(f"SKIP: {why}")
        return SKIP
    return 1 if failures else 0


# The lowest of 20 TCP connects' round trips (a SYN and its RST: no listener is needed).
RTT = r"""
import socket, sys, time
best = None
for _ in range(20):
    s = socket.socket()
    s.settimeout(2)
    start = time.monotonic()
    try:
        s.connect((sys.argv[1], 9))
    except (ConnectionRefusedError, socket.timeout):
        pass
    elapsed = (time.monotonic() - start) * 1000
    s.close()
    best = elapsed if best is None else min(best, elapsed)
print(round(best, 1))
"""

if __name__ == "__main__":
    sys.exit(main())
