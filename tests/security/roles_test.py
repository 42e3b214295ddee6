#!/usr/bin/env python3
"""DDS-Security roles, end to end: a site made by tools/pki, teejet-gateway with simulated valves,
and valvectl as each kind of participant a user meets (docs/security.md).

    --hosts local     every program in this process's network namespace (run it under
                      tests/netns/isolated); the base profile is --base (loopback)
    --hosts bridged|routed
                      gateway on "vehicle", valvectl on "bench" (tests/network/netlab.py; run it
                      under tests/network/lab-run); base profiles are UDP unicast with initial
                      peers, written here, since multicast does not cross the routed lab

Cases (what a user notices):
  commander  lists the 4 valves of --can sim:4, moves one to 90 degrees and sees it COMPLETED
  observer   lists them too, but its move fails at once naming the command topic, and the valve
             stays where it was; so does its assign (valvectl assign), naming the layout change
             topic, while the commander's assign is applied and saved in the gateway's layout file
  refused    no security at all, a certificate of another CA with the same names, a revoked
             certificate (still holding the permissions signed before the revocation), the key
             and certificate that rotation replaced: each finds no gateway; an expired
             certificate and a grant whose subject is written O-first cannot even start a
             participant
  rotated    the new key and certificate list the valves
  web        (with --web, --hosts local) teejet-web as the observer lists the valves on
             GET /api/valves, and with --allow-commands its page's move is answered with the
             refusal and nothing moves; as the commander the page's move completes
The refused cases run in parallel with short deadlines; the whole run takes about 10 s locally.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "web"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
import web_client  # noqa: E402 (tests/web)
from waiting import Timeout, first, latest  # noqa: E402 (tests/support)

SERIALS = ["TJV000001", "TJV000002", "TJV000003", "TJV000004"]
# How long a refused participant looks for the gateway (it starts once a granted one has found
# it). A granted one finds a running gateway in 0.2 to 1.2 s locally; across the routed lab
# under user-mode-linux with delay and loss it took up to 4.2 s from the gateway's start.
REFUSED_LOOKS_FOR = 4
REFUSED_LOOKS_FOR_WITH_NETEM = 10
SKIP = 77


class LocalHosts:
    """Every "host" is this network namespace (tests/netns/isolated made it private)."""

    def __init__(self):
        self.processes = []

    def address(self, _host):
        return "127.0.0.1"

    def spawn(self, _host, argv, env=None, log=None):
        with open(log, "w") as output:
            process = subprocess.Popen(argv, env=env, stdin=subprocess.DEVNULL, stdout=output,
                                       stderr=subprocess.STDOUT)
        self.processes.append(process)
        return process

    def run(self, _host, argv, timeout=30, env=None):
        return subprocess.run(argv, env=env, stdin=subprocess.DEVNULL, capture_output=True,
                              text=True, timeout=timeout)

    def close(self):
        for process in self.processes:
            if process.poll() is None:
                process.terminate()
                try:
                    process.wait(5)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()


# A UDP-only base profile for one lab host: its own address, unicast discovery to its peers (the
# routed lab carries no multicast). The 3 s lease is the loopback profile's (the gateway's
# fail-safe relies on it).
UNICAST_BASE = """<?xml version="1.0" encoding="UTF-8" ?>
<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <profiles>
    <transport_descriptors>
      <transport_descriptor>
        <transport_id>teejet_lab_udp</transport_id>
        <type>UDPv4</type>
        <interfaceWhiteList><address>{own}</address></interfaceWhiteList>
      </transport_descriptor>
    </transport_descriptors>
    <participant profile_name="teejet_lab_unicast" is_default_profile="true">
      <rtps>
        <useBuiltinTransports>false</useBuiltinTransports>
        <userTransports><transport_id>teejet_lab_udp</transport_id></userTransports>
        <builtin>
          <discovery_config>
            <leaseDuration><sec>3</sec></leaseDuration>
            <leaseAnnouncement><sec>1</sec></leaseAnnouncement>
          </discovery_config>
          <metatrafficUnicastLocatorList>
            <locator><udpv4><address>{own}</address></udpv4></locator>
          </metatrafficUnicastLocatorList>
          <initialPeersList>
{peers}
          </initialPeersList>
        </builtin>
        <defaultUnicastLocatorList>
          <locator><udpv4><address>{own}</address></udpv4></locator>
        </defaultUnicastLocatorList>
      </rtps>
    </participant>
  </profiles>
</dds>
"""


class Suite:
    def __init__(self, args, hosts, work):
        self.args = args
        self.hosts = hosts
        self.work = work
        self.site = os.path.join(work, "site")
        self.failures = []
        self.gateway_log = os.path.join(work, "gateway.log")
        self.refused_looks_for = REFUSED_LOOKS_FOR_WITH_NETEM if args.netem else REFUSED_LOOKS_FOR

    # ---- helpers ---------------------------------------------------------------------------

    def pki(self, *argv):
        result = subprocess.run([self.args.pki, *argv], capture_output=True, text=True)
        if result.returncode != 0:
            raise RuntimeError(f"tools/pki {' '.join(argv)} failed: {result.stderr.strip()}")
        return result.stdout

    def base_for(self, host):
        if self.args.hosts == "local":
            return self.args.base
        path = os.path.join(self.work, f"base-{host}.xml")
        if not os.path.exists(path):
            peers = [self.hosts.address(h) for h in ("vehicle", "bench") if h != host]
            locators = "\n".join(f"            <locator><udpv4><address>{p}</address></udpv4>"
                                 "</locator>" for p in peers)
            with open(path, "w") as out:
                out.write(UNICAST_BASE.format(own=self.hosts.address(host), peers=locators))
        return path

    def profile_with_files(self, name, moved, out_name=None):
        """NAME's bench profile in the work directory, its security files taken from elsewhere:
        MOVED maps each site path to the one the profile names instead."""
        path = os.path.join(self.work, f"{out_name or name}.xml")
        self.pki("profile", self.site, name, "--base", self.base_for("bench"), "--out", path)
        with open(path) as source:
            text = source.read()
        for site_path, kept_path in moved.items():
            text = text.replace(f"file://{site_path}", f"file://{kept_path}")
        with open(path, "w") as out:
            out.write(text)
        return path

    def env_for(self, profile, host="bench"):
        # The profile is also the process's default file: loaded once, its transports are not
        # declared twice (Fast DDS refuses a second file that repeats a transport id).
        env = dict(os.environ)
        env["FASTRTPS_DEFAULT_PROFILES_FILE"] = profile
        env["FASTDDS_DEFAULT_PROFILES_FILE"] = profile
        # Fast DDS reads a grant's validity in local time: the benches run 10 h behind UTC and
        # the vehicle 14 h ahead (POSIX zones, no tzdata needed), where a grant written for the
        # hour it was issued would not have started yet or would look older than it is.
        env["TZ"] = "XST10" if host == "bench" else "YST-14"
        return env

    def valvectl_argv(self, profile, *argv, timeout=None):
        command = [self.args.valvectl, "--profile", profile]
        if timeout is not None:
            command += ["--timeout", str(timeout)]
        return command + list(argv)

    def valvectl(self, profile, *argv, timeout=None, host="bench"):
        return self.hosts.run(host, self.valvectl_argv(profile, *argv, timeout=timeout),
                              timeout=60, env=self.env_for(profile))

    def listing_when(self, profile, until, deadline_s=20):
        """`valvectl --json list` as PROFILE until `until(positions)` holds or DEADLINE_S passes:
        the last run and its positions by serial. A move reports COMPLETED within the gateway's
        tolerance (1 degree) and the valve comes to rest on its target a moment later, so an
        exact position is a condition to wait for, not to read once."""
        end = time.monotonic() + deadline_s  # each run's --timeout ends with the wait

        def listing():
            run = self.valvectl(profile, "--json", "list", "--wait-for", "4",
                                timeout=max(1, min(20, end - time.monotonic())))
            return run, self.positions(run.stdout) if run.returncode == 0 else {}

        return latest(listing, deadline_s, ok=lambda seen: until(seen[1]), interval=0)

    def check(self, name, condition, detail):
        print(f"{'ok  ' if condition else 'FAIL'} {name}" + ("" if condition else f": {detail}"),
              flush=True)
        if not condition:
            self.failures.append(name)

    # ---- the site ----------------------------------------------------------------------------

    def make_site(self):
        self.pki("init", self.site, "--site", "farm", "--days", "30")
        for role, name in [("gateway", "gw"), ("commander", "bench"), ("observer", "watcher"),
                           ("commander", "leaver"), ("commander", "misfiled"),
                           ("commander", "rotor")]:
            self.pki("issue", self.site, role, name, "--days", "2")
        self.pki("issue", self.site, "commander", "late", "--expired")
        # What the revoked participant keeps: its profile and the permissions and CRL from
        # before the revocation.
        stale = os.path.join(self.work, "stale")
        os.makedirs(stale)
        for name in ("permissions.p7s", "crl.pem"):
            shutil.copy(os.path.join(self.site, name), stale)
        leaver = self.profile_with_files(
            "leaver", {f"{self.site}/permissions.p7s": f"{stale}/permissions.p7s",
                       f"{self.site}/crl.pem": f"{stale}/crl.pem"})
        # The same participant once it has the site's new CRL and permissions (its profile names
        # the site's files, which the revocation rewrites): it cannot start.
        informed = os.path.join(self.work, "leaver-informed.xml")
        self.pki("profile", self.site, "leaver", "--base", self.base_for("bench"), "--out",
                 informed)
        self.pki("revoke", self.site, "leaver")
        # Rotation: the key and certificate before `issue --replace` stay with their profile and
        # the CRL of that time (with the new CRL they would not even start).
        rotor_old = os.path.join(self.work, "rotor-old")
        shutil.copytree(os.path.join(self.site, "participants", "rotor"), rotor_old)
        shutil.copy(os.path.join(self.site, "crl.pem"), rotor_old)
        rotor_old_profile = self.profile_with_files(
            "rotor", {f"{self.site}/participants/rotor/": f"{rotor_old}/",
                      f"{self.site}/crl.pem": f"{rotor_old}/crl.pem"}, out_name="rotor-old")
        self.pki("issue", self.site, "commander", "rotor", "--replace", "--days", "2")
        # The subject written the way round X.509 stores it (O first), not as Fast DDS prints it.
        with open(os.path.join(self.site, "participants", "misfiled", "subject"), "w") as out:
            out.write("O=farm,OU=commander,CN=misfiled\n")
        self.pki("sign", self.site)
        # Another CA made the same way, with the same site and participant names.
        forged = os.path.join(self.work, "forged")
        self.pki("init", forged, "--site", "farm")
        self.pki("issue", forged, "commander", "bench")

        self.profiles = {"leaver": leaver, "rotor-old": rotor_old_profile}
        for name, host in [("gw", "vehicle"), ("bench", "bench"), ("watcher", "bench"),
                           ("misfiled", "bench"), ("late", "bench"), ("rotor", "bench")]:
            self.pki("profile", self.site, name, "--base", self.base_for(host))
            self.profiles[name] = os.path.join(self.site, f"{name}.xml")
        self.pki("profile", forged, "bench", "--base", self.base_for("bench"))
        self.profiles["forged"] = os.path.join(forged, "bench.xml")
        self.profiles["plain"] = self.base_for("bench")
        self.profiles["leaver-informed"] = informed

    # ---- the cases ---------------------------------------------------------------------------

    def start_web(self, profile, port, *extra):
        log = os.path.join(self.work, f"web-{port}.log")
        self.hosts.spawn("bench", [self.args.web, "--profile", profile, "--listen",
                                   f"127.0.0.1:{port}", *extra],
                         env=self.env_for(profile), log=log)
        return log

    def web_valves(self, port, until=lambda positions: True, deadline_s=20):
        """GET /api/valves until it lists the 4 valves with their positions and `until(positions)`
        holds; positions by serial."""
        def positions_of(listed):
            return {row["serial"]: row["position"] for row in listed}
        rows = latest(
            lambda: web_client.valves(port), deadline_s,
            ok=lambda listed: sorted(row["serial"] for row in listed) == SERIALS
            and all(row["position"] is not None for row in listed) and until(positions_of(listed)))
        return positions_of(rows)

    def web_move(self, port, serial, degrees):
        """A page's move: the answer, and the final status when one came (20 s at most)."""
        page = web_client.WebSocket(port)
        page.receive()  # the snapshot
        answer = page.answer(json.dumps({"command": "move", "serial": serial, "degrees": degrees,
                                         "speed_percent": 100, "direction": "shortest"}),
                             deadline_s=20)
        commands = answer.get("commands") or [{}]
        command_id = commands[0].get("command_id")
        if command_id is None:
            return answer, None

        def final_state():
            message = page.receive()
            for status in message.get("statuses", []) if message["type"] == "update" else []:
                if status["command_id"] == command_id and status["state"] != "accepted":
                    return status["state"]
            return None

        return answer, first(final_state, 20, interval=0)

    def web_cases(self):
        observer_log = self.start_web(self.profiles["watcher"], 18181)
        seen = self.web_valves(18181, lambda positions: positions[SERIALS[0]] == 90.0)
        self.check("teejet-web as the observer lists the 4 valves on /api/valves",
                   sorted(seen) == SERIALS and seen.get(SERIALS[0]) == 90.0,
                   f"{seen}, log: {open(observer_log).read().strip()[-300:]}")

        self.start_web(self.profiles["watcher"], 18182, "--allow-commands")
        self.web_valves(18182)
        answer, final = self.web_move(18182, SERIALS[1], 45)
        error = (answer.get("commands") or [{}])[0].get("error", "")
        self.check("the observer's page move is answered with the refusal, nothing is sent",
                   answer["type"] == "sent" and "may not write teejet/valve/command" in error
                   and final is None, f"answer {answer}, final {final}")

        commander_log = self.start_web(self.profiles["bench"], 18183, "--allow-commands")
        self.web_valves(18183)
        answer, final = self.web_move(18183, SERIALS[2], 45)
        seen = self.web_valves(18183, lambda positions: positions[SERIALS[2]] == 45.0)
        self.check("teejet-web as the commander moves TJV000003 to 45 degrees from its page",
                   final == "completed" and seen.get(SERIALS[2]) == 45.0
                   and seen.get(SERIALS[1]) == 0.0,
                   f"answer {answer}, final {final}, positions {seen}, "
                   f"log: {open(commander_log).read().strip()[-300:]}")

    def positions(self, listing):
        return {row["serial"]: row.get("position") for row in json.loads(listing)}

    def run(self):
        making = time.monotonic()
        self.make_site()
        # tools/pki runs openssl 186 times: most of the run's time, and what a loaded machine
        # stretches most (24 to 45 s at load 7 to 10 on 2 cores, against 6 to 9 s of cases).
        print(f"     (site made by tools/pki in {time.monotonic() - making:.2f} s)", flush=True)
        started = time.monotonic()
        # Four places hold the four valves; a fifth is empty, for the assign cases.
        self.layout_file = os.path.join(self.work, "boom.yaml")
        with open(self.layout_file, "w") as layout:
            layout.write("locations:\n" + "".join(
                f"  - {{name: section-0{i + 1}, order: {i + 1}, serial: {serial}}}\n"
                for i, serial in enumerate(SERIALS)) + "  - {name: section-05, order: 5}\n")
        gateway = self.hosts.spawn(
            "vehicle", [self.args.gateway, "--can", "sim:4", "--profile", self.profiles["gw"],
                        "--layout", self.layout_file],
            env=self.env_for(self.profiles["gw"], "vehicle"), log=self.gateway_log)
        try:
            self.cases()
        except (web_client.Failure, Timeout, subprocess.TimeoutExpired, OSError,
                ValueError) as error:
            self.check("the cases ran to their end", False, f"{type(error).__name__}: {error}")

        self.check("the gateway is still running", gateway.poll() is None,
                   f"exit {gateway.returncode}")
        print(f"     (all cases: {time.monotonic() - started:.2f} s)")
        if self.failures:
            for name in sorted(os.listdir(self.work)):
                if name.endswith(".log"):
                    with open(os.path.join(self.work, name)) as text:
                        print(f"---- {name}\n" + text.read())
        return 1 if self.failures else 0

    def cases(self):
        started = time.monotonic()
        listing = self.valvectl(self.profiles["bench"], "--json", "list", "--wait-for", "4",
                                timeout=20)
        found = sorted(row["serial"] for row in json.loads(listing.stdout or "[]"))
        self.check("commander lists the 4 valves", listing.returncode == 0 and found == SERIALS,
                   f"exit {listing.returncode}, {found}, stderr: {listing.stderr.strip()}")
        print(f"     (gateway start to commander's list: {time.monotonic() - started:.2f} s)")

        # The refused participants look for the gateway meanwhile, each with its own deadline.
        refused = {}
        for case in ("plain", "forged", "leaver", "leaver-informed", "late", "misfiled",
                     "rotor-old"):
            log = os.path.join(self.work, f"{case}.log")
            refused[case] = (log, self.hosts.spawn(
                "bench", self.valvectl_argv(self.profiles[case], "list", "--wait-for", "4",
                                            timeout=self.refused_looks_for),
                env=self.env_for(self.profiles[case]), log=log))

        move = self.valvectl(self.profiles["bench"], "move", SERIALS[0], "--to", "90", "--wait")
        self.check("commander moves TJV000001 to 90 degrees",
                   move.returncode == 0 and "COMPLETED" in move.stdout,
                   f"exit {move.returncode}, stdout: {move.stdout.strip()[-200:]}, "
                   f"stderr: {move.stderr.strip()[-300:]}")

        seen, positions = self.listing_when(
            self.profiles["watcher"],
            lambda listed: sorted(listed) == SERIALS and listed[SERIALS[0]] == 90.0)
        self.check("observer lists the 4 valves with positions",
                   sorted(positions) == SERIALS and positions[SERIALS[0]] == 90.0,
                   f"exit {seen.returncode}, {positions}, stderr: {seen.stderr.strip()}")

        rotated = self.valvectl(self.profiles["rotor"], "list", "--wait-for", "4")
        self.check("the rotated key and certificate list the 4 valves", rotated.returncode == 0,
                   f"exit {rotated.returncode}, stderr: {rotated.stderr.strip()}")

        refused_move = self.valvectl(self.profiles["watcher"], "move", SERIALS[1], "--to", "45")
        self.check("observer's move is refused at once, naming the command topic",
                   refused_move.returncode == 1
                   and "may not write teejet/valve/command" in refused_move.stderr,
                   f"exit {refused_move.returncode}, stderr: {refused_move.stderr.strip()}")

        refused_assign = self.valvectl(self.profiles["watcher"], "assign", "section-05",
                                       SERIALS[1], "--move")
        self.check("observer's assign is refused at once, naming the layout change topic",
                   refused_assign.returncode == 1
                   and "may not write teejet/layout/change" in refused_assign.stderr,
                   f"exit {refused_assign.returncode}, stderr: {refused_assign.stderr.strip()}")
        assign = self.valvectl(self.profiles["bench"], "assign", "section-05", SERIALS[3], "--move")
        with open(self.layout_file) as layout:
            saved = layout.read()
        self.check("commander assigns TJV000004 to section-05, and the gateway saves it",
                   assign.returncode == 0
                   and "section-05 on " in assign.stdout and "APPLIED: TJV000004 sits there"
                   in assign.stdout and "name: \"section-05\", order: 5, role: section, "
                   "serial: TJV000004" in saved,
                   f"exit {assign.returncode}, stdout: {assign.stdout.strip()}, stderr: "
                   f"{assign.stderr.strip()[-300:]}, file:\n{saved}")

        after, positions = self.listing_when(
            self.profiles["bench"], lambda listed: listed.get(SERIALS[0]) == 90.0)
        self.check("the observer's valve did not move (TJV000002 at 0, TJV000001 at 90)",
                   positions.get(SERIALS[1]) == 0.0 and positions.get(SERIALS[0]) == 90.0,
                   f"exit {after.returncode}, {positions}")

        expected = {
            "plain": (2, "no gateway found", "no security (plain profile) finds no gateway"),
            "forged": (2, "no gateway found", "a certificate of another CA finds no gateway"),
            "leaver": (2, "no gateway found",
                       "a revoked certificate with its old permissions finds no gateway"),
            "leaver-informed": (1, "certificate revoked in the CRL",
                                "a revoked certificate with the new CRL cannot start a "
                                "participant, and the error names revocation"),
            "late": (1, "cannot create a DDS participant",
                     "an expired certificate cannot start a participant"),
            "rotor-old": (2, "no gateway found",
                          "the key and certificate replaced by rotation find no gateway"),
            "misfiled": (1, "cannot create a DDS participant",
                         "a grant whose subject is written O-first cannot start a participant"),
        }
        for case, (log, process) in refused.items():
            try:
                code = process.wait(self.refused_looks_for + 20)
            except subprocess.TimeoutExpired:
                code = None
            with open(log) as text:
                output = text.read()
            want_code, want_text, name = expected[case]
            self.check(name, code == want_code and want_text in output,
                       f"exit {code}, output: {output.strip()[-400:]}")

        if self.args.web:
            self.web_cases()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gateway", required=True)
    parser.add_argument("--valvectl", required=True)
    parser.add_argument("--pki", required=True)
    parser.add_argument("--base", help="base profile for --hosts local (the loopback profile)")
    parser.add_argument("--hosts", choices=["local", "bridged", "routed"], default="local")
    parser.add_argument("--netem", help="netem for the routed lab, e.g. 'delay 20ms'")
    parser.add_argument("--web", help="teejet-web: its cases too (only with --hosts local)")
    args = parser.parse_args()
    if args.hosts == "local" and not args.base:
        parser.error("--hosts local needs --base")
    if args.web and args.hosts != "local":
        parser.error("--web needs --hosts local (the test reaches teejet-web on its own loopback)")

    with tempfile.TemporaryDirectory(prefix="teejet-security-") as work:
        if args.hosts == "local":
            hosts = LocalHosts()
            try:
                return Suite(args, hosts, work).run()
            finally:
                hosts.close()
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                        "network"))
        from netlab import Lab, LabUnavailable  # noqa: E402 (found only under tests/network)
        try:
            with Lab(args.hosts, netem=args.netem) as lab:
                return Suite(args, lab, work).run()
        except LabUnavailable as why:
            print(f"SKIP: {why}")
            return SKIP


if __name__ == "__main__":
    sys.exit(main())
