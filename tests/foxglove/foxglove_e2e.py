#!/usr/bin/env python3
"""teejet-web --foxglove end to end (issue 29), run inside a private network namespace.

A gateway with simulated valves, the independent subscriber of the recording tests
(recording_sample_logger: typed Fast DDS readers) and teejet-web --foxglove on one domain; the
client is Foxglove's own npm package (@foxglove/ws-protocol, decoding with
@foxglove/omgidl-serialization: tests/foxglove/foxglove-client.mjs), which nobody here wrote.

  stream    two clients at once, one under each subprotocol (foxglove.websocket.v1,
            foxglove.sdk.v1), subscribe to the positions while two valves move: every message
            decodes to a sample the subscriber saw, with its source timestamp as the message's
            timestamp, and every sample the subscriber saw after a client's first message of a
            valve reached that client. The channels carry the recording's encoding and schemas.
  late      a client that subscribes long after the valves announced themselves gets every
            valve's version (sent once, at start) and presence at once, equal to the
            subscriber's; after an unsubscribe nothing more of it arrives; once the gateway is
            killed and its lease ends, a new subscription gets none of its valves.
  commands  with --allow-commands and a token: a ValveCommand the client publishes (CDR, encoded
            by Foxglove's writer) moves TJV000002 to 90 degrees; the client is told the command id,
            and its statuses ACCEPTED then COMPLETED arrive on teejet/valve/command_status.
  refusals  read-only: no clientPublish, an advertise is refused with the reason; commands
            without a token configured are refused; no token in the URL, a wrong token, another
            topic, another encoding, 400 degrees: each refused with its reason, and no command
            reaches DDS; a foreign Host gets 403, a handshake without a Foxglove subprotocol 400.
  slow      32 valves at the full poll rate, each client's outbox bounded at 128 KiB: a client
            reading two thirds of the rate is told how many messages were dropped for it, and
            it and one that never reads are closed when they have not caught up in 10 s
            (teejet-web logs both); the npm client reading beside them gets every message the
            subscriber saw.

Every wait has a deadline; every failure says what differed.
"""

import argparse
import json
import os
import socket
import subprocess
import sys
import tempfile
import threading

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "..", "support"))
sys.path.insert(0, os.path.join(here, "..", "recording"))
from waiting import Timeout, eventually, scaled  # noqa: E402 (tests/support)
sys.path.insert(0, os.path.join(here, "..", "web"))
from recording_e2e import Failure, Run, check, print_failure, wait_for_line  # noqa: E402
from web_client import PING, PONG, TEXT, WebSocket  # noqa: E402 (tests/web)
from web_client import Failure as ClientFailure  # noqa: E402 (tests/web)

CLIENT = os.path.join(here, "foxglove-client.mjs")
SUBPROTOCOLS = ("foxglove.websocket.v1", "foxglove.sdk.v1")
PORT = 18765
TOKEN = "bench-secret-29"
COMMAND_TARGET_DEGREES, DIRECTION_OPEN = 2, 1
# What every valve of a gateway at the full poll rate publishes (version once).
FULL_POLL_TOPICS = ["teejet/valve/" + name for name in (
    "presence", "version", "position", "temperature", "voltage", "current", "degrees_per_second",
    "speed_direction", "run_time", "cycle_counts")]
ACCEPTED, COMPLETED = 0, 2


class Skip(Exception):
    pass


class FoxgloveRun(Run):
    def binary(self, relative):
        """The programs are given one by one (so that a sanitizer build knows to build them)."""
        return self.args.programs[os.path.basename(relative)]

    def start_web(self, *extra, env=None):
        web = self.start("web", [self.binary("tools/teejet-web/teejet-web"), "--listen",
                                 "127.0.0.1:18080", "--foxglove", str(PORT), *extra], env=env)
        wait_for_line(self.path("web.err"), "Foxglove: ws://", 20, web)
        return web

    def restart_web(self, web, *extra, env=None):
        self.stop(web)
        return self.start_web(*extra, env=env)

    def client(self, *argv, token=None, timeout=60, expect=0):
        """The npm client to its end: its JSON lines."""
        command = ["node", CLIENT, f"ws://127.0.0.1:{PORT}/", *argv]
        if token is not None:
            command += ["--token", token]
        done = self.run(command, timeout=timeout, expect=expect)
        return [json.loads(line) for line in done.stdout.splitlines() if line.strip()]

    def start_client(self, name, *argv):
        return self.start(name, ["node", CLIENT, f"ws://127.0.0.1:{PORT}/", *argv],
                          stdout=name + ".jsonl")

    def logged(self, topic=None):
        lines = self.read_jsonl("logger.jsonl")
        return [line for line in lines if topic is None or line["topic"] == topic]


def events(lines, kind):
    return [line for line in lines if line.get("event") == kind]


def messages(lines, topic=None):
    return [line for line in events(lines, "message") if topic is None or line["topic"] == topic]


def statuses(lines):
    return [line["message"] for line in events(lines, "status")]


def one_status(lines, text):
    found = [message for message in statuses(lines) if text in message]
    check(found, f"no status saying '{text}'; the client was told {statuses(lines)}")
    return found[0]


def valve_moving_session(run):
    """The gateway (4 valves), the subscriber and teejet-web (read-only)."""
    run.start_gateway()
    run.start_logger("logger", 0)
    run.valvectl("list", "--wait-for", "4", "--timeout", "20")
    return run.start_web()


def case_stream(run):
    valve_moving_session(run)
    clients = [run.start_client(f"client-{name}", "--subprotocol", name, "--subscribe",
                                "teejet/valve/position", "--duration-ms", "12000")
               for name in SUBPROTOCOLS]
    # While they listen, two valves move (each position change is a sample).
    run.valvectl("move", "TJV000001", "--to", "120", "--speed", "100", "--wait", "--timeout", "20")
    run.valvectl("move", "TJV000003", "--to", "45", "--speed", "60", "--wait", "--timeout", "20")
    for proc in clients:
        check(proc.wait(timeout=30) == 0, f"{proc.args[1]} {proc.args[3:]} exited "
              f"{proc.returncode}")
    logged = run.logged("teejet/valve/position")
    by_sample = {(line["data"]["serial"], line["data"]["received_ns"]): line for line in logged}
    for name in SUBPROTOCOLS:
        lines = run.read_jsonl(f"client-{name}.jsonl")
        check(events(lines, "open") and events(lines, "open")[0]["protocol"] == name,
              f"the client offering {name} was answered {events(lines, 'open')}")
        channels = [c for a in events(lines, "advertise") for c in a["channels"]
                    if c["topic"] == "teejet/valve/position"]
        check(len(channels) == 1 and channels[0]["encoding"] == "cdr" and
              channels[0]["schemaEncoding"] == "omgidl" and
              channels[0]["schemaName"] == "teejet::ValvePosition",
              f"{name}: the position channel is {channels}, not cdr/omgidl/teejet::ValvePosition")
        got = messages(lines, "teejet/valve/position")
        check(len(got) >= 10, f"{name}: only {len(got)} positions arrived while two valves moved")
        for message in got:
            key = (message["data"]["serial"], message["data"]["received_ns"])
            seen = by_sample.get(key)
            check(seen is not None, f"{name}: {message} is no sample the subscriber saw")
            check(seen["data"] == message["data"],
                  f"{name}: {message['data']} decoded, the subscriber saw {seen['data']}")
            check(seen["source_ns"] == message["timestamp"],
                  f"{name}: timestamp {message['timestamp']}, the sample's source timestamp "
                  f"is {seen['source_ns']}")
        # Nothing lost: from a client's first message of a valve to a second before its last
        # message (what was still on its way when it closed is not counted), every sample of
        # the subscriber's reached it.
        end = max(int(m["timestamp"]) for m in got) - 1_000_000_000
        received = {(m["data"]["serial"], m["data"]["received_ns"]) for m in got}
        for serial in {m["data"]["serial"] for m in got}:
            start = min(int(m["timestamp"]) for m in got if m["data"]["serial"] == serial)
            missing = [line for line in logged if line["data"]["serial"] == serial and
                       start <= int(line["source_ns"]) <= end and
                       (serial, line["data"]["received_ns"]) not in received]
            check(not missing, f"{name}: {len(missing)} positions of serial {serial} the "
                  f"subscriber saw never reached the client, e.g. {missing[:2]}")
        moved = {m["data"]["serial"] for m in got if m["data"]["degrees"] > 1}
        check({1, 3} <= moved, f"{name}: the moves of TJV000001 and TJV000003 are not in the "
              f"positions (valves seen moving: {sorted(moved)})")
        print(f"{name}: {len(got)} positions, each equal to the subscriber's sample")


def case_late(run):
    valve_moving_session(run)
    # Versions are sent once, when a valve starts: only the state a subscription starts from
    # can bring them now.
    lines = run.client("--subscribe", "teejet/valve/version", "--subscribe",
                       "teejet/valve/presence", "--until-topic-count", "teejet/valve/version=4",
                       "--until-topic-count", "teejet/valve/presence=4", "--timeout-ms", "15000")
    logged = run.logged()
    for topic in ("teejet/valve/version", "teejet/valve/presence"):
        got = {m["data"]["serial"]: m for m in messages(lines, topic)}
        check(sorted(got) == [1, 2, 3, 4], f"{topic}: the late client got serials {sorted(got)}")
        for serial, message in got.items():
            samples = [line for line in logged
                       if line["topic"] == topic and line["data"]["serial"] == serial]
            check(any(s["data"] == message["data"] and s["source_ns"] == message["timestamp"]
                      for s in samples),
                  f"{topic} of {serial}: {message['data']} is none of the subscriber's samples")
    # An unsubscribe ends the flow: presence comes every second, so two seconds after it none.
    # What the server sent before it read the unsubscribe may still arrive: a grace, scaled
    # (a sanitizer's server reads it late), before the two seconds that must stay silent.
    grace_ms = int(scaled(1) * 1000)
    lines = run.client("--subscribe", "teejet/valve/presence", "--unsubscribe-after-ms", "1500",
                       "--duration-ms", str(1500 + grace_ms + 2000))
    unsubscribed = [line for line in lines if line.get("event") == "message" and
                    line.get("unsubscribed") and line.get("ms_after_unsubscribe", 0) > grace_ms]
    check(events(lines, "unsubscribe"), f"the client sent no unsubscribe: {lines[-3:]}")
    check(not unsubscribed, f"{len(unsubscribed)} presences arrived more than {grace_ms} ms "
          f"after the unsubscribe, e.g. {unsubscribed[:1]}")
    # A gateway killed: once its lease ends (3 s in the loopback profile), a new subscription
    # starts from nothing of it, not from valves that look online.
    gateway = run.procs[0]
    gateway.kill()
    gateway.wait()

    def presences_of_a_new_subscription():
        lines = run.client("--subscribe", "teejet/valve/presence", "--duration-ms", "1000")
        return [m["data"]["serial"] for m in messages(lines, "teejet/valve/presence")]
    eventually(presences_of_a_new_subscription, 30,
               "a new subscription without the killed gateway's valves", ok=lambda seen: not seen,
               interval=0.5)
    print("late: every valve's version and presence at once; nothing after the unsubscribe; "
          "nothing of a killed gateway")


def move_command(degrees, serial=2):
    return json.dumps({"serial": serial, "kind": COMMAND_TARGET_DEGREES, "speed_percent": 100,
                       "direction": DIRECTION_OPEN, "degrees": degrees})


def case_commands(run):
    run.start_gateway()
    run.start_logger("logger", 0)
    run.valvectl("list", "--wait-for", "4", "--timeout", "20")
    token_file = run.path("token")
    with open(token_file, "w") as f:
        f.write(TOKEN + "\n")
    os.chmod(token_file, 0o600)
    run.start_web("--allow-commands", "--token-file", token_file)
    for name in SUBPROTOCOLS:
        lines = run.client("--subprotocol", name, "--subscribe", "teejet/valve/command_status",
                           "--publish", move_command(90 if name == SUBPROTOCOLS[0] else 30),
                           "--until-topic-count", "teejet/valve/command_status=2",
                           "--until-status", "sent to TJV000002", "--timeout-ms", "30000",
                           token=TOKEN)
        info = events(lines, "serverInfo")[0]
        check("clientPublish" in info["capabilities"] and info["supportedEncodings"] == ["cdr"],
              f"serverInfo with a token: {info}")
        sent = one_status(lines, "sent to TJV000002")
        command_id = int(sent.split("#")[1].split()[0])

        def final_status():
            return [line["data"]["state"] for line in run.logged("teejet/valve/command_status")
                    if line["data"]["command_id"] == command_id]
        states = eventually(final_status, 30, f"COMPLETED of command #{command_id}",
                            ok=lambda seen: COMPLETED in seen)
        check(states[0] == ACCEPTED, f"command #{command_id}: statuses {states}")
        got = [m["data"]["state"] for m in messages(lines, "teejet/valve/command_status")
               if m["data"]["command_id"] == command_id]
        check(got and got[0] == ACCEPTED, f"{name}: the client saw statuses {got} of "
              f"#{command_id}")
        print(f"{name}: command #{command_id} published, statuses {states}")
    positions = [line["data"]["degrees"] for line in run.logged("teejet/valve/position")
                 if line["data"]["serial"] == 2]
    check(any(abs(p - 90) < 0.05 for p in positions), f"TJV000002 never reached 90: {positions}")


def refused(run, text, *argv, token=None):
    """A client that publishes as `argv` says and waits for the status saying `text`."""
    lines = run.client(*argv, "--until-status", text, "--timeout-ms", "20000", token=token,
                       expect=None)
    one_status(lines, text)
    return lines


def case_refusals(run):
    web = valve_moving_session(run)
    lines = refused(run, "advertise refused: commands are disabled: teejet-web runs read-only",
                    "--publish", move_command(90))
    check("clientPublish" not in events(lines, "serverInfo")[0]["capabilities"],
          "a read-only teejet-web announces clientPublish")

    web = run.restart_web(web, "--allow-commands")
    refused(run, "takes commands from Foxglove only with a token", "--publish", move_command(90))

    token_file = run.path("token")
    with open(token_file, "w") as f:
        f.write(TOKEN + "\n")
    os.chmod(token_file, 0o600)
    run.restart_web(web, "--allow-commands", "--token-file", token_file)
    refused(run, "commands need the token: connect with ws://HOST:PORT/?token=TOKEN",
            "--publish", move_command(90))
    refused(run, 'command not sent: missing or wrong "token"', "--publish", move_command(90),
            token="wrong")
    refused(run, "command not sent: target_degrees: degrees 400 is outside 0 to 359.9",
            "--publish", move_command(400), token=TOKEN)
    refused(run, "command not sent: unknown serial TJV000077: no gateway knows it",
            "--publish", move_command(90, serial=77), token=TOKEN)
    idl = os.path.join(here, "..", "..", "idl", "teejet", "valve.idl")
    refused(run, "(teejet/valve/presence) refused: only teejet/valve/command takes messages",
            "--publish-topic", "teejet/valve/presence", "--publish-schema-name",
            "teejet::ValvePresence", "--idl", idl, "--publish", json.dumps({"serial": 2}),
            token=TOKEN)
    refused(run, 'refused: encoding "json": only "cdr"', "--publish-encoding", "json",
            "--publish", move_command(90), token=TOKEN)
    # None of them reached DDS: the subscriber heard no command at all.
    commands = run.logged("teejet/valve/command")
    check(not commands, f"refused commands reached DDS: {commands}")

    def handshake(host, protocol):
        with socket.create_connection(("127.0.0.1", PORT), timeout=10) as sock:
            sock.sendall((f"GET / HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\n"
                          "Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                          f"Sec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: {protocol}\r\n"
                          "\r\n").encode())
            answer = b""
            while True:
                chunk = sock.recv(4096)
                if not chunk:
                    return answer.decode(errors="replace")
                answer += chunk
    answer = handshake("rebound.example:18765", SUBPROTOCOLS[0])
    check(answer.startswith("HTTP/1.1 403"), f"a foreign Host was answered {answer[:80]!r}")
    answer = handshake(f"127.0.0.1:{PORT}", "chat")
    check(answer.startswith("HTTP/1.1 400") and "foxglove.websocket.v1" in answer,
          f"a handshake offering only 'chat' was answered {answer!r}")
    print("refusals: each with its reason, no command reached DDS")


def raw_client(topic_prefix, receive_buffer=128 * 1024):
    """A client of a few lines over a socket whose receive buffer stays as set (Node cannot set
    it; the kernel doubles it), subscribed to every channel advertised so far whose topic starts
    with `topic_prefix`: once it stops reading, the kernel holds that much for it, and
    teejet-web's outbox the rest. Below loopback's 64 KiB segment the window would reopen only
    at TCP's persist timer, seconds later."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.settimeout(10)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, receive_buffer)
    sock.connect(("127.0.0.1", PORT))
    sock.sendall((f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{PORT}\r\nUpgrade: websocket\r\n"
                  "Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                  f"Sec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: {SUBPROTOCOLS[0]}\r\n"
                  "\r\n").encode())
    client = WebSocket.after_request(sock)
    check(client.status.startswith("HTTP/1.1 101"), f"the handshake was answered {client.status}")
    check(client.receive()["op"] == "serverInfo", "the first message is no serverInfo")
    # Channels are advertised with their first sample: wait for the telemetry of full poll.
    topics = {}

    def advertised():
        message = client.receive()
        for channel in message.get("channels", []):
            if channel["topic"].startswith(topic_prefix):
                topics[channel["topic"]] = channel["id"]
        return len(topics)
    eventually(advertised, 20, f"the telemetry channels under {topic_prefix}",
               ok=lambda count: count >= len(FULL_POLL_TOPICS), interval=0)
    channels = sorted(topics.values())
    client.send(json.dumps({"op": "subscribe", "subscriptions": [
        {"id": i, "channelId": channel} for i, channel in enumerate(channels)]}))
    return client


class SlowReader(threading.Thread):
    """Reads 64 KiB a second, about two thirds of what a subscription to every valve topic of
    32 valves at the full poll brings: it falls behind for good. Whole segments, so that the
    kernel's window reopens at once; the statuses found in what it read are kept. Once teejet-web
    says it closed the connection, `drain` lets it read on at once to the close: what the
    kernel still held for it (its send buffer grows to megabytes) would take the slow pace
    longer than any deadline."""

    def __init__(self, client):
        super().__init__(daemon=True)
        self.client = client
        self.statuses = []
        self.closed = False
        self.drain = threading.Event()

    def run(self):
        data = b""
        try:
            while True:
                chunk = self.client.sock.recv(65536)
                if not chunk:
                    break
                data = self.frames(data + chunk)
                self.drain.wait(1)
        except OSError:
            pass
        self.closed = True

    def frames(self, data):
        """Takes the whole frames off `data`; what is left of the next one."""
        while len(data) >= 2:
            length, at = data[1] & 0x7F, 2
            if length == 126:
                length, at = int.from_bytes(data[2:4], "big"), 4
            elif length == 127:
                length, at = int.from_bytes(data[2:10], "big"), 10
            if len(data) < at + length:
                break
            opcode, payload, data = data[0] & 0x0F, data[at:at + length], data[at + length:]
            if opcode == PING:
                self.client.sock.sendall(self.client.frame(payload, opcode=PONG))
            elif opcode == TEXT:
                message = json.loads(payload.decode())
                if message.get("op") == "status":
                    self.statuses.append(message["message"])
        return data


def case_slow(run):
    run.start_gateway(valves=32, full_poll=True)
    run.start_logger("logger", 0)
    run.valvectl("list", "--wait-for", "32", "--timeout", "30")
    # Each client's outbox holds 128 KiB here (1 MiB by default): about a second and a half of
    # every valve topic of 32 valves at this rate (2,650 messages, 100 kB a second).
    web = run.start_web(env={**os.environ, "TEEJET_WEB_FOXGLOVE_STALL_S": "10",
                             "TEEJET_WEB_FOXGLOVE_QUEUE_KB": "128"})
    reader = run.start_client("reader", "--subscribe", "teejet/valve/*", "--duration-ms", "30000")
    stalled = raw_client("teejet/valve/")
    slow = SlowReader(raw_client("teejet/valve/", receive_buffer=64 * 1024))
    slow.start()
    told = eventually(lambda: [s for s in slow.statuses if "messages for this connection" in s],
                      30, "a status telling the slow client of its dropped messages")[0]
    wait_for_line(run.path("web.err"), "falls behind", 30, web)
    slow_port = slow.client.sock.getsockname()[1]
    wait_for_line(run.path("web.err"), f"port {slow_port} has not caught up for 10 s: closed", 30,
                  web)
    slow.drain.set()
    eventually(lambda: slow.closed, 30, "the close of the client that does not catch up")
    closed = eventually(
        lambda: [line for line in open(run.path("web.err")) if "has not caught up" in line], 30,
        "both slow clients closed", ok=lambda lines: len(lines) == 2)
    check(reader.wait(timeout=40) == 0, f"the reader exited {reader.returncode}")
    check(all("for 10 s: closed" in line for line in closed), f"closed: {closed}")
    stalled.sock.close()
    lines = run.read_jsonl("reader.jsonl")
    got = messages(lines)
    received = {(m["topic"], m["data"]["serial"], m["data"].get("received_ns"), m["timestamp"])
                for m in got}
    first = {}
    for m in got:
        first.setdefault((m["topic"], m["data"]["serial"]), int(m["timestamp"]))
    end = max(int(m["timestamp"]) for m in got) - 1_000_000_000
    missing = []
    for line in run.logged():
        key = (line["topic"], line["data"].get("serial"))
        if line["disposed"] or key not in first or not first[key] <= int(line["source_ns"]) <= end:
            continue
        if (line["topic"], line["data"]["serial"], line["data"].get("received_ns"),
                line["source_ns"]) not in received:
            missing.append(line)
    check(len(got) > 5000, f"the reader got only {len(got)} messages in 30 s of a full poll")
    check(not missing, f"the reader missed {len(missing)} samples beside the slow clients, "
          f"e.g. {missing[:2]}")
    print(f"slow: both slow clients closed, one told '{told}'; the reader "
          f"got {len(got)} messages, none missed")


CASES = {"stream": case_stream, "late": case_late, "commands": case_commands,
         "refusals": case_refusals, "slow": case_slow}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    for program in ("gateway", "web", "valvectl", "logger"):
        parser.add_argument(f"--{program}", required=True, help=f"the {program} program to run")
    parser.add_argument("case", choices=sorted(CASES))
    args = parser.parse_args()
    args.programs = {os.path.basename(path): path
                     for path in (args.gateway, args.web, args.valvectl, args.logger)}
    if subprocess.run(["node", "--version"], capture_output=True).returncode != 0 or \
            not os.path.isdir(os.path.join(here, "node_modules")):
        print("FAIL: node or the packages of tests/foxglove are missing: run tools/install-deps.sh")
        return 1
    with tempfile.TemporaryDirectory(prefix="teejet-foxglove-") as work:
        run = FoxgloveRun(args, work)
        try:
            CASES[args.case](run)
        except (Failure, ClientFailure, Timeout, subprocess.TimeoutExpired) as failure:
            print_failure(failure, work)
            return 1
        finally:
            run.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main())
