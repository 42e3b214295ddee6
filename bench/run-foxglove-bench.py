#!/usr/bin/env python3
"""run-foxglove-bench.py - teejet-web --foxglove at a full bus (docs/performance.md, "Foxglove").

teejet-gateway --can sim:32 with every telemetry message at 0.1 s (bench/full-poll.yaml), the
recording tests' typed subscriber (recording_sample_logger) as the judge of what was published,
teejet-web --foxglove and Foxglove's npm client (tests/foxglove/foxglove-client.mjs) subscribed
to every channel. Over one window: messages published per second (the subscriber's samples
stamped inside it), messages delivered per second (the client's, likewise), the ones missing,
and teejet-web's CPU (% of one core, /proc/PID/stat, 10 s each at most): without --foxglove (and no
page), with --foxglove and no client, and with the client over the window. Re-runs itself inside tests/netns/isolated: DDS and the WebSocket stay on this host.

  bench/run-foxglove-bench.py [--build-dir DIR] [--seconds S]
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

here = os.path.dirname(os.path.abspath(__file__))
root = os.path.dirname(here)
PORT = 18766
SETTLE_S = 3


def cpu_seconds(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def cpu_percent_over(pid, seconds):
    start_cpu, start = cpu_seconds(pid), time.monotonic()
    time.sleep(seconds)
    return 100 * (cpu_seconds(pid) - start_cpu) / (time.monotonic() - start)


def inside(args):
    build = args.build_dir
    work = tempfile.mkdtemp(prefix="teejet-foxglove-bench-")
    procs = []

    def start(argv, out=None, err=None):
        proc = subprocess.Popen(argv, stdout=open(os.path.join(work, out), "w") if out else
                                subprocess.DEVNULL,
                                stderr=open(os.path.join(work, err), "w") if err else
                                subprocess.DEVNULL)
        procs.append(proc)
        return proc

    try:
        start([f"{build}/gateway/app/teejet-gateway", "--can", "sim:32", "-c",
               f"{here}/full-poll.yaml", "--log-level", "warn"])
        subprocess.run([f"{build}/tools/valvectl/valvectl", "list", "--wait-for", "32",
                        "--timeout", "30"], check=True, stdout=subprocess.DEVNULL)
        start([f"{build}/tests/recording/recording_sample_logger"], out="logger.jsonl",
              err="logger.err")
        # The dashboard alone (no page), then with --foxglove and no client, then one client.
        plain = start([f"{build}/tools/teejet-web/teejet-web", "--listen", "127.0.0.1:18081"])
        time.sleep(SETTLE_S)
        without = cpu_percent_over(plain.pid, min(10, args.seconds))
        plain.terminate()
        plain.wait(timeout=15)
        web = start([f"{build}/tools/teejet-web/teejet-web", "--listen", "127.0.0.1:18081",
                     "--foxglove", str(PORT)], err="web.err")
        time.sleep(SETTLE_S)
        idle = cpu_percent_over(web.pid, min(10, args.seconds))
        client = start(["node", f"{root}/tests/foxglove/foxglove-client.mjs",
                        f"ws://127.0.0.1:{PORT}/", "--subscribe", "*", "--duration-ms",
                        str(int((args.seconds + 2 * SETTLE_S) * 1000))], out="client.jsonl")
        time.sleep(SETTLE_S)
        window_start = time.time_ns()
        busy = cpu_percent_over(web.pid, args.seconds)
        window_end = time.time_ns()
        client.wait(timeout=args.seconds + 30)
        procs[1].terminate()
        procs[1].wait(timeout=15)

        def stamped(path, key):
            kept = set()
            with open(os.path.join(work, path)) as f:
                for line in f:
                    line = json.loads(line)
                    if key == "timestamp" and line.get("event") != "message":
                        continue
                    stamp = int(line[key])
                    if window_start <= stamp <= window_end:
                        # Who and when: the two decoders print some values differently
                        # (a char, the last digits of a float).
                        data = line["data"] or {}
                        kept.add((line["topic"], data.get("serial"), data.get("gateway"),
                                  data.get("kind"), stamp))
            return kept
        published = stamped("logger.jsonl", "source_ns")
        delivered = stamped("client.jsonl", "timestamp")
        seconds = (window_end - window_start) / 1e9
        print(f"FOXGLOVE valves=32 poll=full window_s={seconds:.1f} "
              f"published_per_s={len(published) / seconds:.0f} "
              f"delivered_per_s={len(delivered) / seconds:.0f} "
              f"missing={len(published - delivered)} "
              f"web_cpu_percent: without_foxglove={without:.1f} no_client={idle:.1f} "
              f"one_client={busy:.1f}")
        with open(os.path.join(work, "web.err")) as f:
            dropped = [line.strip() for line in f if "dropped" in line or "behind" in line]
        if dropped:
            print("teejet-web said: " + " | ".join(dropped))
        return 0
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build-dir", default=os.path.join(root, "build"))
    parser.add_argument("--seconds", type=float, default=30)
    parser.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    args.build_dir = os.path.abspath(args.build_dir)
    if args.inside:
        return inside(args)
    return subprocess.call([f"{root}/tests/netns/isolated", "/usr/bin/python3",
                            os.path.abspath(__file__), "--inside", "--build-dir", args.build_dir,
                            "--seconds", str(args.seconds)])


if __name__ == "__main__":
    sys.exit(main())
