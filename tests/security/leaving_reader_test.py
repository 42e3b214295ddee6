#!/usr/bin/env python3
"""A secure reader that leaves while the writer still repairs its history to it: the writer lives
on (docs/security.md, "RTPS protection"). Run inside tests/netns/isolated.

A site made by tools/pki with the project's governance; a writer with the gateway's role, the
gateway's position QoS and 3000 valves' positions (repaired to a late reader 256 at a time, from
Fast DDS's flow-controller thread); then READERS observers one after another, each taking 1000 of
them and leaving at once. With the governance's RTPS protection at SIGN, Fast DDS 2.9.1 aborted
the writer when the first of them left (8 of 8 runs: SecurityManager.cpp:2272, Assertion
'receiving_list.size() > 0'); teejet-gateway did the same, more rarely, when a valvectl left.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import threading

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from waiting import first  # noqa: E402 (tests/support)

VALVES = 3000
TAKEN = 1000
READERS = 3


class Writer:
    """The writer process; its stdout lines are collected as they come."""

    def __init__(self, argv, env):
        self.process = subprocess.Popen(argv, env=env, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                        text=True)
        self.lines = []
        self.lock = threading.Lock()
        threading.Thread(target=self._collect, daemon=True).start()

    def _collect(self):
        for line in self.process.stdout:
            with self.lock:
                self.lines.append(line.rstrip("\n"))

    def wait_for(self, predicate, deadline_s):
        """True once predicate(lines) holds; False when the deadline passes or the writer ends."""
        def holds():
            with self.lock:
                return predicate(self.lines)

        first(lambda: holds() or self.process.poll() is not None, deadline_s)
        return holds()

    def output(self):
        with self.lock:
            return "\n".join(self.lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--peer", required=True, help="the security_repair_peer program")
    parser.add_argument("--pki", required=True)
    parser.add_argument("--base", required=True, help="base profile (the loopback profile)")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory(prefix="teejet-leaving-reader-") as work:
        site = os.path.join(work, "site")

        def pki(*argv):
            subprocess.run([args.pki, *argv], check=True, capture_output=True, text=True)

        pki("init", site, "--site", "farm", "--days", "30")
        pki("issue", site, "gateway", "gw", "--days", "2")
        pki("issue", site, "observer", "watcher", "--days", "2")
        for name in ("gw", "watcher"):
            pki("profile", site, name, "--base", args.base)

        def env_for(name):
            env = dict(os.environ)
            env["FASTRTPS_DEFAULT_PROFILES_FILE"] = env["FASTDDS_DEFAULT_PROFILES_FILE"] = \
                os.path.join(site, f"{name}.xml")
            return env

        def peer(name, *argv):
            return [args.peer, os.path.join(site, f"{name}.xml"), *argv]

        writer = Writer(peer("gw", "write", str(VALVES)), env_for("gw"))
        failures = []
        try:
            if not writer.wait_for(lambda lines: f"wrote {VALVES}" in lines, 60):
                failures.append(f"the writer did not write its {VALVES} positions")
            for n in range(1, READERS + 1):
                if failures:
                    break
                reader = subprocess.run(peer("watcher", "read", str(TAKEN)), env=env_for("watcher"),
                                        stdin=subprocess.DEVNULL, capture_output=True, text=True,
                                        timeout=60)
                if reader.returncode != 0 or f"took {TAKEN}" not in reader.stdout:
                    failures.append(f"reader {n} exited {reader.returncode}: "
                                    f"{reader.stdout.strip()} {reader.stderr.strip()[-300:]}")
                # The writer has let reader n go once it counted no reader for the n-th time.
                elif not writer.wait_for(lambda lines: lines.count("readers 0") >= n, 30):
                    failures.append(f"the writer did not let reader {n} go (exit "
                                    f"{writer.process.poll()})")
                else:
                    print(f"ok   reader {n} took {TAKEN} of {VALVES} positions and left; "
                          "the writer runs on", flush=True)
        finally:
            if writer.process.poll() is None:
                writer.process.terminate()
            try:
                code = writer.process.wait(30)
            except subprocess.TimeoutExpired:
                writer.process.kill()
                code = writer.process.wait()
        if code != 0:
            failures.append(f"the writer exited {code} (0 on SIGTERM)")
        for failure in failures:
            print(f"FAIL {failure}")
        if failures:
            print("---- writer output\n" + writer.output())
            return 1
        print(f"ok   the writer outlived {READERS} readers that left during its repairs")
        return 0


if __name__ == "__main__":
    sys.exit(main())
