#!/usr/bin/python3
"""Plots the valve positions (and, on request, another telemetry field) of a teejet-record
recording to a PNG, as Foxglove's Plot panel would show them.

The recording is read by the independent MCAP reader (tests/mcap-js/read-mcap.mjs: @mcap/core
and Foxglove's own omgidl/cdr decoders, installed by tools/install-deps.sh), so the picture shows
what another tool makes of the file, not what our own reader thinks is in it.

  tools/plot-recording.py run.mcap -o run.png     (Debian's python3, for python3-matplotlib)
  tools/plot-recording.py run.mcap -o run.png --field teejet/valve/current:amps --serial 1 --serial 2
"""

import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
READER = os.path.join(HERE, "..", "tests", "mcap-js", "read-mcap.mjs")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recording")
    parser.add_argument("-o", "--output", required=True, help="the PNG to write")
    parser.add_argument("--field", action="append", default=[],
                        help="TOPIC:FIELD to plot below the positions (repeatable)")
    parser.add_argument("--serial", action="append", type=int, default=[],
                        help="only these valves (default: every valve)")
    parser.add_argument("--title", default=None)
    args = parser.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        sys.exit("plot-recording: python3-matplotlib is missing: run tools/install-deps.sh")

    done = subprocess.run(["node", READER, args.recording], capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"plot-recording: {done.stderr.strip() or 'the MCAP reader failed'}")
    messages = [json.loads(line) for line in done.stdout.splitlines() if line.strip()]
    if not messages:
        sys.exit(f"plot-recording: {args.recording} holds no messages")
    start = min(int(m["log_time"]) for m in messages)

    panels = [("teejet/valve/position", "degrees")]
    for spec in args.field:
        topic, _, field = spec.rpartition(":")
        if not topic or not field:
            sys.exit(f"plot-recording: --field {spec}: expected TOPIC:FIELD")
        panels.append((topic, field))

    figure, axes = plt.subplots(len(panels), 1, sharex=True, squeeze=False,
                                figsize=(10, 3.2 * len(panels)))
    for (topic, field), axis in zip(panels, axes[:, 0]):
        series = {}
        for message in messages:
            if message["topic"] != topic or field not in message["data"]:
                continue
            serial = message["data"].get("serial")
            if args.serial and serial not in args.serial:
                continue
            # publish time = the CAN receive time of the frame the sample came from
            t = (int(message["publish_time"]) - start) / 1e9
            series.setdefault(serial, ([], []))
            series[serial][0].append(t)
            series[serial][1].append(message["data"][field])
        if not series:
            sys.exit(f"plot-recording: no {topic} samples with a field '{field}'")
        for serial in sorted(series):
            times, values = series[serial]
            axis.step(times, values, where="post", label=f"TJV{serial:06d}", linewidth=1.2)
        axis.set_ylabel(f"{topic.rsplit('/', 1)[-1]}.{field}")
        axis.grid(True, alpha=0.3)
        axis.legend(loc="upper left", fontsize="small", ncol=min(len(series), 8))
    axes[-1, 0].set_xlabel("seconds since the first message (CAN receive time)")
    axes[0, 0].set_title(args.title or os.path.basename(args.recording))
    figure.tight_layout()
    figure.savefig(args.output, dpi=100)
    print(f"plot-recording: {args.output}: {len(messages)} messages read, "
          f"{len(panels)} panel(s)")


if __name__ == "__main__":
    main()
