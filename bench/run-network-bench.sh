#!/bin/bash
# run-network-bench.sh - a remote bench over a bad link, per deployment profile
# (docs/remote-benches.md): in user-mode-linux, netem "delay 50ms loss 1%" on each direction
# between the vehicle (teejet-gateway --can sim:4) and the bench (valvectl, teejet-record).
#   ds     routed, fastdds-lan-discovery-client.xml, fast-discovery-server on the vehicle
#   tcp    routed, fastdds-wan-tcp-gateway.xml / fastdds-wan-tcp-bench.xml
#   plain  bridged, fastdds-lan-multicast.xml, netem on the bench's veth (both directions)
# For each: the move acceptance latency (the bench's recorder's receive time of the command to
# that of its ACCEPTED status: a round trip plus the gateway's handling; median and max over
# --moves moves, each by a fresh valvectl), how long each valvectl ran (discovery included),
# the telemetry rate that reaches the bench (samples/s per topic, after the first 2 s), and how
# long after a commanding valvectl on the bench is SIGKILLed the gateway's fail-safe stops its
# valve (3 times; the participant lease of the profiles is 3 s).
# Every DDS program runs inside the lab (tests/network/lab-run --uml); nothing leaves it.
#
#   bench/run-network-bench.sh [--build-dir DIR] [--moves N] [--profiles "ds tcp plain"]
#                              [--netem "delay 50ms loss 1%"]
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
build=$root/build moves=10 profiles="ds tcp plain" netem="delay 50ms loss 1%" inside=0
while [ $# -gt 0 ]; do
  case $1 in
  --build-dir) build=$(cd "$2" && pwd) || exit 2; shift 2 ;;
  --moves) moves=$2; shift 2 ;;
  --profiles) profiles=$2; shift 2 ;;
  --netem) netem=$2; shift 2 ;;
  --inside) inside=1; shift ;;
  *) sed -n '14,15p' "${BASH_SOURCE[0]}" | sed 's/^# *//' >&2; exit 2 ;;
  esac
done
if [ "$inside" = 0 ]; then
  exec "$root/tests/network/lab-run" --uml --timeout 900 -- "${BASH_SOURCE[0]}" --inside \
    --build-dir "$build" --moves "$moves" --profiles "$profiles" --netem "$netem"
fi

exec python3 - "$root" "$build" "$moves" "$netem" $profiles <<'PY'
import json, os, re, shutil, statistics, struct, sys, tempfile, time

root, build, moves, netem, *profiles = sys.argv[1:]
moves = int(moves)
sys.path.insert(0, os.path.join(root, "tests", "network"))
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
from netlab import Lab, _sh, wait_until  # noqa: E402

GATEWAY = f"{build}/gateway/app/teejet-gateway"
VALVECTL = f"{build}/tools/valvectl/valvectl"
RECORD = f"{build}/tools/teejet-record/teejet-record"
CONFIG = f"{root}/config"
SERIAL = "TJV000002"
ATTEMPTS = 3  # Fast DDS 2.9.1 TCP leaves about 1 new participant in 8 unmatched (see the docs)


def mcap_messages(path):
    """(topic, log_time_ns, payload) of an uncompressed MCAP file, as teejet-record writes it."""
    channels, out = {}, []

    def records(data, pos, end):
        while pos + 9 <= end:
            op, length = data[pos], struct.unpack_from("<Q", data, pos + 1)[0]
            body = data[pos + 9:pos + 9 + length]
            pos += 9 + length
            if op == 0x04:  # Channel: id, schema id, topic
                cid = struct.unpack_from("<H", body, 0)[0]
                n = struct.unpack_from("<I", body, 4)[0]
                channels[cid] = body[8:8 + n].decode()
            elif op == 0x05:  # Message: channel, sequence, log time, publish time, data
                cid, _, log_time, _ = struct.unpack_from("<HIQQ", body, 0)
                out.append((channels[cid], log_time, body[22:]))
            elif op == 0x06:  # Chunk: start, end, size, crc, compression, records
                n = struct.unpack_from("<I", body, 28)[0]
                compression = body[32:32 + n].decode()
                if compression:
                    raise SystemExit(f"{path}: chunk compressed with {compression}")
                size = struct.unpack_from("<Q", body, 32 + n)[0]
                records(body, 40 + n, 40 + n + size)
            elif op in (0x0F, 0x02):  # DataEnd, Footer
                return

    data = open(path, "rb").read()
    records(data, 8, len(data))
    return out


def command_id(payload):  # ValveCommand / CommandStatus: encapsulation, serial, command_id
    return struct.unpack_from("<I", payload, 8)[0]


def status_state(payload):  # after serial, command_id and the origin string: kind, state
    n = struct.unpack_from("<I", payload, 12)[0]
    pos = 16 + n
    pos += (-(pos - 4)) % 4  # CDR aligns to 4 from the end of the encapsulation header
    return struct.unpack_from("<I", payload, pos + 4)[0]  # 0 = COMMAND_ACCEPTED


def commander_killed(lab, bench_profile, gateway_log, attempt):
    """ms from SIGKILL of a jogging valvectl on the bench to the gateway's fail-safe stop."""
    log = f"{gateway_log}.jog{attempt}"
    before = open(gateway_log).read().count("fail-safe stopped")
    for _ in range(ATTEMPTS):
        jog = lab.spawn("bench", [VALVECTL, "--profile", bench_profile, "--timeout", "20", "jog",
                                  SERIAL, "--ms", "60000", "--speed", "20", "--wait"], log=log)
        if wait_until(lambda: "ACCEPTED" in open(log).read() or jog.poll() is not None, 60) and \
                jog.poll() is None:
            break
    else:
        raise SystemExit("no jog was accepted")
    killed = time.time()
    jog.kill()
    lines = wait_until(lambda: [l for l in open(gateway_log).read().splitlines()
                                if "fail-safe stopped" in l][before:], 60)
    if not lines:
        raise SystemExit("the gateway's fail-safe did not stop the valve within 60 s")
    stamp = time.mktime(time.strptime(lines[0][1:20], "%Y-%m-%d %H:%M:%S")) + \
        int(lines[0][21:24]) / 1000
    return round((stamp - killed) * 1000)


def run_profile(name):
    topology = "bridged" if name == "plain" else "routed"
    gateway_profile, bench_profile = {
        "ds": ("fastdds-lan-discovery-client.xml",) * 2,
        "tcp": ("fastdds-wan-tcp-gateway.xml", "fastdds-wan-tcp-bench.xml"),
        "plain": ("fastdds-lan-multicast.xml",) * 2,
    }[name]
    gateway_profile, bench_profile = f"{CONFIG}/{gateway_profile}", f"{CONFIG}/{bench_profile}"
    scratch = tempfile.mkdtemp(prefix=f"network-bench-{name}-")
    with Lab(topology, netem=netem if topology == "routed" else None) as lab:
        if topology == "bridged":
            # The bridge has no router to carry netem: the bench's veth gets it at both ends.
            _sh("tc", "qdisc", "add", "dev", "p-bench", "root", "netem", *netem.split())
            _sh("ip", "netns", "exec", "bench", "tc", "qdisc", "add", "dev", "eth0", "root",
                "netem", *netem.split())
        if name == "ds":
            lab.spawn("vehicle", ["fast-discovery-server", "-i", "0", "-l",
                                  lab.address("vehicle"), "-p", "11811"])
        lab.spawn("vehicle", [GATEWAY, "--can", "sim:4", "--profile", gateway_profile,
                              "--name", "vehicle"], log=f"{scratch}/gateway.log")
        recording = f"{scratch}/bench.mcap"
        for attempt in range(ATTEMPTS):
            log = f"{scratch}/record-{attempt}.log"
            recorder = lab.spawn("bench", [RECORD, "--profile", bench_profile, "--progress",
                                           "--compression", "none", "-o", recording], log=log)
            if wait_until(lambda: any(int(n.replace(",", "")) > 0 for n in
                                      re.findall(r"([0-9][0-9,]*) msgs", open(log).read())), 20):
                break
            lab.stop(recorder)
        else:
            raise SystemExit(f"{name}: the recorder on the bench received nothing")
        runs, restarts = [], 0
        for i in range(moves):
            for attempt in range(ATTEMPTS):
                started = time.monotonic()
                result = lab.run("bench", [VALVECTL, "--profile", bench_profile, "--json",
                                           "--timeout", "20", "--command-readers", "2", "move",
                                           SERIAL, "--to", str(30 + 30 * (i % 2))], timeout=120)
                if result.returncode != 2:
                    break
                restarts += 1
            if result.returncode != 0:
                raise SystemExit(f"{name}: valvectl move exited {result.returncode}: "
                                 f"{result.stderr.strip()}")
            runs.append(time.monotonic() - started)
        lab.stop(recorder)
        failsafe = [commander_killed(lab, bench_profile, f"{scratch}/gateway.log", i)
                    for i in range(3)]
    messages = mcap_messages(recording)
    shutil.rmtree(scratch, ignore_errors=True)
    sent = {command_id(p): t for topic, t, p in messages if topic == "teejet/valve/command"}
    accepted = {}
    for topic, t, p in messages:
        if topic == "teejet/valve/command_status" and status_state(p) == 0:
            accepted.setdefault(command_id(p), t)
    latencies = sorted((accepted[c] - sent[c]) / 1e6 for c in sent if c in accepted)
    start = min(t for _, t, _ in messages) + 2e9
    end = max(t for _, t, _ in messages)
    rates = {}
    for topic, t, _ in messages:
        if start <= t <= end and not topic.startswith("teejet/valve/command"):
            rates[topic] = rates.get(topic, 0) + 1
    seconds = (end - start) / 1e9
    return {"profile": name, "topology": topology, "netem": netem, "moves": moves,
            "commands_recorded": len(sent), "accepted_recorded": len(latencies),
            "accept_latency_ms": {"median": round(statistics.median(latencies), 1),
                                  "max": round(latencies[-1], 1),
                                  "min": round(latencies[0], 1)} if latencies else None,
            "valvectl_run_s": {"median": round(statistics.median(runs), 2),
                               "max": round(max(runs), 2)},
            "valvectl_restarts": restarts,
            "failsafe_stop_after_kill_ms": failsafe,
            "telemetry_window_s": round(seconds, 1),
            "samples_per_s": {t.split("/")[-1]: round(n / seconds, 1)
                              for t, n in sorted(rates.items())}}


for name in profiles:
    print(json.dumps(run_profile(name)), flush=True)
PY
