#!/usr/bin/env python3
"""teejet-record and teejet-replay end to end (issue 11), run inside a private network namespace.

A gateway with simulated valves (--can sim:4 --record-frames, one valve with a latched error),
an independent subscriber (sample_logger: typed Fast DDS readers, values decoded field by field)
and teejet-record start on one domain; valves move, an error is cleared, the gateway stops.

  record   the npm MCAP reader (tests/mcap-js/read-mcap.mjs: @mcap/core and Foxglove's omgidl
           decoders) reads every channel; per topic the messages equal, in order and value, what
           the subscriber received; --info agrees; the candump -L file holds every frame.
  sigkill  the recorder is killed mid-run: the file reads up to its last complete chunk.
  replay   the recording is replayed into a fresh domain: a new subscriber gets every recorded
           sample, in the recorded order per instance, with the recorded values and source
           timestamps, and teejet-replay reports its lateness. How closely the gaps follow the
           recording is a timing figure, measured by bench/run-recording-bench.sh.

Every wait has a deadline; every failure says what differed.
"""

import argparse
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from waiting import Timeout, eventually, first  # noqa: E402 (tests/support)


class Failure(Exception):
    pass


def check(condition, message):
    if not condition:
        raise Failure(message)


def wait_for_line(path, text, deadline_s, proc):
    """Until `text` appears in the file at `path`, or fail (at once when `proc` exited)."""
    def written():
        if not os.path.exists(path):
            return ""
        with open(path, errors="replace") as f:
            return f.read()

    def running():
        check(proc.poll() is None,
              f"{proc.args[0]} exited {proc.returncode} before saying '{text}'")

    eventually(written, deadline_s, f"'{text}' in {path}", ok=lambda seen: text in seen,
               interval=0.02, alive=running)


def print_failure(failure, work):
    """FAIL and the reason, then the end of every program's stderr in `work`."""
    print(f"FAIL: {failure}")
    for name in sorted(os.listdir(work)):
        if name.endswith(".err"):
            with open(os.path.join(work, name), errors="replace") as f:
                tail = f.read()[-2000:]
            if tail.strip():
                print(f"--- {name}\n{tail}")


class Run:
    def __init__(self, args, work):
        self.args = args
        self.work = work
        self.procs = []

    def path(self, name):
        return os.path.join(self.work, name)

    def start(self, name, argv, stdout=None, env=None):
        err = open(self.path(name + ".err"), "w")
        out = open(self.path(stdout), "w") if stdout else subprocess.DEVNULL
        proc = subprocess.Popen(argv, stdout=out, stderr=err, env=env)
        self.procs.append(proc)
        return proc

    def run(self, argv, timeout=60, expect=0, env=None):
        try:
            done = subprocess.run(argv, capture_output=True, text=True, timeout=timeout, env=env)
        except subprocess.TimeoutExpired as expired:
            # What it printed before it was killed tells a hang at start from one midway.
            out = expired.stdout.decode(errors="replace") if expired.stdout else ""
            err = expired.stderr.decode(errors="replace") if expired.stderr else ""
            raise Failure(f"{' '.join(argv)} did not finish within {timeout} s; it had printed "
                          f"{out.count(chr(10))} line(s) to stdout; stderr:\n{err[-2000:]}")
        if expect is not None and done.returncode != expect:
            raise Failure(f"{' '.join(argv)} exited {done.returncode}, expected {expect}\n"
                          f"{done.stdout}{done.stderr}")
        return done

    def stop(self, proc, sig=signal.SIGINT, timeout=15):
        proc.send_signal(sig)
        try:
            return proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            raise Failure(f"{proc.args[0]} did not stop within {timeout} s of {sig.name}")

    def cleanup(self):
        for proc in self.procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()

    def binary(self, relative):
        return os.path.join(self.args.build_dir, relative)

    def start_logger(self, name, domain):
        logger = self.start(name, [self.binary("tests/recording/recording_sample_logger"),
                                   "--domain", str(domain)], stdout=name + ".jsonl")
        wait_for_line(self.path(name + ".err"), "ready", 20, logger)
        return logger

    def start_recorder(self, output, extra=(), env=None):
        recorder = self.start("recorder", [self.binary("tools/teejet-record/teejet-record"),
                                           "-o", self.path(output), *extra], env=env)
        wait_for_line(self.path("recorder.err"), "recording to", 20, recorder)
        return recorder

    def start_gateway(self, valves=4, full_poll=False):
        config = self.path("gateway.yaml")
        with open(config, "w") as f:
            # TJV000003 starts with a latched high-voltage error, so that Clear Errors disposes.
            f.write("simulator:\n  errors: ['TJV000003:high-voltage:16.2:15.5']\n")
            if full_poll:
                # Every telemetry message at 0.1 s: about 81 samples a second per valve.
                f.write("poll:\n" + "".join(f"  {name}: 1\n" for name in (
                    "position", "temperature", "voltage", "current", "degrees_per_second",
                    "speed_direction", "run_time", "cycle_counts")))
        frames = [] if full_poll else ["--record-frames"]
        return self.start("gateway", [self.binary("gateway/app/teejet-gateway"), "--can",
                                      f"sim:{valves}", *frames, "-c", config,
                                      "--log-level", "warn"])

    def valvectl(self, *argv, timeout=30):
        return self.run([self.binary("tools/valvectl/valvectl"), *argv], timeout=timeout)

    def exercise_valves(self, command_readers):
        # Commands are VOLATILE: valvectl waits until the gateway, the recorder and the
        # subscriber all hear them, so that both have every command.
        readers = ["--command-readers", str(command_readers), "--timeout", "20"]
        self.valvectl("move", "TJV000001", "--to", "90", "--speed", "100", "--wait", *readers)
        self.valvectl("move", "TJV000002", "--to", "45", "--speed", "60", "--wait", *readers)
        self.valvectl("clear-errors", "TJV000003", "--wait", *readers)

    def read_mcap(self, recording, *extra, expect=0):
        done = self.run(["node", self.args.npm_reader, recording, *extra], timeout=120,
                        expect=expect)
        return [json.loads(line) for line in done.stdout.splitlines() if line.strip()], done

    def read_jsonl(self, name):
        """Every complete line: a program still running may be halfway through writing the last
        one (CI run 48 read a cut line of the live sample logger), which the next read gets."""
        with open(self.path(name)) as f:
            return [json.loads(line) for line in f if line.endswith("\n") and line.strip()]


def normalise(value):
    """The npm decoder gives an IDL char as a one-character string, the logger as its code."""
    if isinstance(value, dict):
        return {k: (ord(v) if k == "test" and isinstance(v, str) and len(v) <= 1 and v else
                    0 if k == "test" and v == "" else normalise(v)) for k, v in value.items()}
    if isinstance(value, list):
        return [normalise(v) for v in value]
    return value


def instance(topic, data):
    """The DDS instance a sample belongs to: DDS keeps order per instance (and per writer), and
    a reader takes a batch instance by instance, so order is compared per instance."""
    if topic.startswith("teejet/can/frame"):
        return (topic,)
    if topic.startswith("teejet/gateway/status"):
        return (topic, data.get("gateway"))
    if topic.startswith("teejet/valve/error"):
        return (topic, data.get("serial"), data.get("kind"))
    return (topic, data.get("serial"))


def logger_by_topic(lines):
    instances = {}
    for line in lines:
        topic = line["topic"] + ("/disposed" if line["disposed"] else "")
        instances.setdefault(instance(topic, line["data"]), []).append(line)
    return instances


def file_by_topic(messages):
    instances = {}
    for message in messages:
        instances.setdefault(instance(message["topic"], message["data"]), []).append(message)
    return instances


def held_stamps(messages):
    """The file's messages with the source timestamps teejet-replay gives them: per reliable topic,
    in file order, a publish time that would go back is held at the previous one (docs/topics.md,
    "Source timestamps never go back on a writer"); the best-effort frames keep theirs."""
    last, out = {}, []
    for message in messages:
        topic = message["topic"].removesuffix("/disposed")  # one writer writes and disposes
        if topic != "teejet/can/frame":
            held = max(int(message["publish_time"]), last.get(topic, 0))
            last[topic] = held
            message = dict(message, publish_time=type(message["publish_time"])(held))
        out.append(message)
    return out


def split_at(samples, settle_ns, time_key):
    """Samples published before `settle_ns`, and from it on."""
    cut = 0
    while cut < len(samples) and int(samples[cut][time_key]) < settle_ns:
        cut += 1
    return samples[:cut], samples[cut:]


# Telemetry writers keep only the last sample of an instance (KEEP_LAST 1): a reader that
# loses a datagram under load and asks again after the next sample was written gets a gap. At
# 2,600 samples/s with the compilers of a CI run on both cores, the recorder or the subscriber
# missed 1 of ~16,000 (stop 20 CI). The split test allows that many, and no more.
MAX_STATE_GAPS_PER_MILLION = 500


def merge_state_gaps(a, b, what, key):
    """Per instance of a KEEP_LAST 1 topic: the samples both sides got (same source timestamp),
    which must agree in order and values, and how many only one side got."""
    stamps_a = {sample["source_ns"] for sample in a}
    stamps_b = {message["publish_time"] for message in b}
    common = stamps_a & stamps_b
    both_a = [sample for sample in a if sample["source_ns"] in common]
    both_b = [message for message in b if message["publish_time"] in common]
    if len(common) != len(stamps_a | stamps_b):
        check(key[0] != "teejet/valve/command",
              f"{what}: {key}: a command only one side got (commands are KEEP_ALL)")
    return both_a, both_b, len(stamps_a ^ stamps_b)


def early_state_gaps(a, b, what, key):
    """Before the settle point, per instance of a KEEP_LAST 1 topic: the samples both sides got
    (same source timestamp) agree in order and values; of those only one side got, the ones
    before the other side's first sample are a late match, the others gaps (see
    MAX_STATE_GAPS_PER_MILLION). Returns (both got, late-match misses, gaps)."""
    stamps_a = [int(sample["source_ns"]) for sample in a]
    stamps_b = [int(message["publish_time"]) for message in b]
    common = set(stamps_a) & set(stamps_b)
    check([normalise(x["data"]) for x, t in zip(a, stamps_a) if t in common] ==
          [normalise(x["data"]) for x, t in zip(b, stamps_b) if t in common],
          f"{what}: {key}: the early samples both sides got differ")
    missed = gaps = 0
    for own, other in ((stamps_a, stamps_b), (stamps_b, stamps_a)):
        for stamp in set(own) - common:
            if not other or stamp < min(other):
                missed += 1
            else:
                check(key[0] != "teejet/valve/command",
                      f"{what}: {key}: a command only one side got (commands are KEEP_ALL)")
                gaps += 1
    return len(common), missed, gaps


def compare_topics(logged, recorded, what, settle_ns=0, prefix=False, allow_state_gaps=False):
    """Per instance: the same samples in the same order, with the same values and source
    timestamps. Before `settle_ns` (when the test starts commanding, long after every reader
    matched the gateway) a reader that matched the gateway's writer a moment after the other
    may have missed an instance's first samples (the writer keeps only the last one for late
    joiners): there the shorter list must be the end of the longer. With `prefix`, the file
    may end early (a killed recorder). With `allow_state_gaps`, a telemetry sample only one
    side got is counted, not failed (see MAX_STATE_GAPS_PER_MILLION). Returns per-topic counts
    and how many early samples one side missed."""
    missed = 0
    gaps = 0
    compared = 0
    frames_lost = frames_seen = 0
    topics_frame = "teejet/can/frame"
    counts = {}
    if not prefix:
        check(set(logged) == set(recorded),
              f"{what}: instances differ: subscriber only "
              f"{sorted(set(logged) - set(recorded), key=str)}, file only "
              f"{sorted(set(recorded) - set(logged), key=str)}")
    for key in sorted(recorded, key=str):
        early_a, a = split_at(logged.get(key, []), settle_ns, "source_ns")
        early_b, b = split_at(recorded[key], settle_ns, "publish_time")
        if allow_state_gaps:
            # Gaps come early too (under load: 1 in 10 runs of split at load 10).
            both, missed_here, gaps_here = early_state_gaps(early_a, early_b, what, key)
            compared += both
            missed += missed_here
            gaps += gaps_here
        else:
            shorter, longer = sorted((early_a, early_b), key=len)
            tail = longer[len(longer) - len(shorter):] if shorter else []
            check([normalise(x["data"]) for x in shorter] == [normalise(x["data"]) for x in tail],
                  f"{what}: {key}: the early samples differ beyond a late match")
            missed += len(longer) - len(shorter)
        if prefix:
            a = a[:len(b)]
        counts[key[0]] = counts.get(key[0], 0) + len(b) + len(early_b)
        if key[0] == topics_frame and len(a) != len(b):
            # Frames are BEST_EFFORT: under load either reader may lose some (5 of 340 at one
            # CI stop). The ones both got must agree in order and values.
            a, b, only_one_side = merge_state_gaps(a, b, what, key)
            frames_lost += only_one_side
            frames_seen += len(a) + only_one_side
        elif allow_state_gaps and len(a) != len(b):
            a, b, only_one_side = merge_state_gaps(a, b, what, key)
            gaps += only_one_side
        compared += len(a)
        check(len(a) == len(b), f"{what}: {key}: subscriber got {len(a)}, file holds {len(b)}")
        for i, (sample, message) in enumerate(zip(a, b)):
            check(normalise(message["data"]) == normalise(sample["data"]),
                  f"{what}: {key} #{i + 1}: file {message['data']} != subscriber {sample['data']}")
            check(message["publish_time"] == sample["source_ns"],
                  f"{what}: {key} #{i + 1}: publish time {message['publish_time']} != source "
                  f"timestamp {sample['source_ns']}")
    if frames_lost:
        print(f"{what}: {frames_lost} of {frames_seen} best-effort frames only one side got")
        check(frames_lost * 2 <= frames_seen,
              f"{what}: {frames_lost} of {frames_seen} best-effort frames only one side got")
    if allow_state_gaps:
        print(f"{what}: {gaps} telemetry sample(s) of {compared} only one side got")
        check(gaps * 1_000_000 <= compared * MAX_STATE_GAPS_PER_MILLION,
              f"{what}: {gaps} of {compared} samples only one side got: more than "
              f"{MAX_STATE_GAPS_PER_MILLION} per million")
    return counts, missed


def make_recording(run, output, extra=(), valves=4, full_poll=False, until_file=None):
    """Gateway, subscriber and recorder on domain 0; valves move; the gateway stops first."""
    logger = run.start_logger("logger", 0)
    recorder = run.start_recorder(output, extra)
    gateway = run.start_gateway(valves, full_poll)
    run.valvectl("list", "--wait-for", "4", "--timeout", "20")
    settle_ns = time.time_ns()
    run.exercise_valves(command_readers=3)
    if until_file:
        eventually(lambda: os.path.exists(run.path(until_file)), 60, f"a file {until_file}",
                   interval=0.1)
    check(run.stop(gateway, signal.SIGTERM) == 0, "the gateway did not exit 0")
    check(run.stop(recorder) == 0, "teejet-record did not exit 0 after SIGINT")
    check(run.stop(logger) == 0, "the subscriber did not exit 0")
    return run.read_jsonl("logger.jsonl"), settle_ns


def case_record(run):
    recording = run.path("run.mcap")
    logged, settle_ns = make_recording(run, "run.mcap", ["--candump", run.path("run.log")])
    messages, done = run.read_mcap(recording)
    counts, missed = compare_topics(logger_by_topic(logged), file_by_topic(messages), "record",
                                    settle_ns)
    for topic in ("teejet/valve/presence", "teejet/valve/position", "teejet/valve/command",
                  "teejet/valve/command_status", "teejet/valve/error",
                  "teejet/valve/error/disposed", "teejet/gateway/status", "teejet/can/frame"):
        check(counts.get(topic, 0) > 0, f"record: nothing on {topic}: {counts}")
    # The moves reached their targets in the recorded positions.
    finals = {}
    for message in messages:
        if message["topic"] == "teejet/valve/position":
            finals[message["data"]["serial"]] = message["data"]["degrees"]
    check(abs(finals.get(1, -1) - 90) <= 1 and abs(finals.get(2, -1) - 45) <= 1,
          f"record: last recorded positions {finals}, expected TJV000001 at 90, TJV000002 at 45")

    info = json.loads(run.run([run.binary("tools/teejet-record/teejet-record"), "--info",
                               recording, "--json"]).stdout)
    check(info["complete"], f"--info: not complete: {info}")
    info_counts = {c["topic"]: c["messages"] for c in info["channels"] if c["messages"] > 0}
    check(info_counts == counts, f"--info counts {info_counts} != {counts}")

    with open(run.path("run.log")) as f:
        lines = [line.rstrip("\n") for line in f]
    frames = [m["data"] for m in messages if m["topic"] == "teejet/can/frame"]
    check(len(lines) == len(frames), f"candump: {len(lines)} lines for {len(frames)} frames")
    for line, frame in zip(lines, frames):
        ident = f"{frame['id']:08X}" if frame["extended"] else f"{frame['id']:03X}"
        body = "".join(f"{b:02X}" for b in frame["data"])
        stamp = int(frame["stamp_ns"])
        expected = (f"({stamp // 10**9:010d}.{stamp // 1000 % 10**6:06d}) "
                    f"{frame['can_interface']} {ident}#{body}")
        check(line == expected, f"candump: '{line}' != '{expected}'")
    # valve-decode reads the recording's frame channel as it reads the candump text of it.
    decode = run.binary("tools/valve-decode/valve-decode")
    from_mcap = run.run([decode, recording]).stdout
    from_log = run.run([decode, run.path("run.log")]).stdout
    check(from_mcap == from_log and from_mcap.count("\n") == len(frames),
          f"valve-decode: {from_mcap.count(chr(10))} lines from the MCAP file, "
          f"{from_log.count(chr(10))} from its candump text; they differ or miss frames")
    print(f"record: {len(messages)} messages on {len(counts)} channels equal to the subscriber's "
          f"({missed} early sample(s) one of them missed by matching the gateway later); "
          f"{len(lines)} candump lines, valve-decode equal on both; "
          f"counts {json.dumps(counts, sort_keys=True)}")


def case_sigkill(run):
    logger = run.start_logger("logger", 0)
    recording = run.path("killed.mcap")
    recorder = run.start_recorder("killed.mcap", ["--chunk-size", "4K"])
    gateway = run.start_gateway()
    run.valvectl("list", "--wait-for", "4", "--timeout", "20")
    settle_ns = time.time_ns()
    run.valvectl("move", "TJV000001", "--to", "80", "--speed", "100", "--wait", "--timeout", "20",
                 "--command-readers", "3")
    # Until the file holds at least two closed chunks and more, then no chance to finish it.
    first(lambda: os.path.getsize(recording) >= 20_000, 20)
    recorder.send_signal(signal.SIGKILL)
    recorder.wait(timeout=10)
    size = os.path.getsize(recording)
    messages, done = run.read_mcap(recording, expect=1)
    check("read-mcap" in done.stderr, f"incomplete file without --allow-incomplete: {done.stderr}")
    messages, done = run.read_mcap(recording, "--allow-incomplete")
    check(len(messages) > 0, "nothing readable in the killed recording")
    info = run.run([run.binary("tools/teejet-record/teejet-record"), "--info", recording,
                    "--json"])
    document = json.loads(info.stdout)
    check(not document["complete"] and "incomplete" in info.stderr,
          f"--info did not call the file incomplete: {info.stdout}{info.stderr}")
    check(document["messages"] == len(messages),
          f"--info reads {document['messages']} messages, the npm reader {len(messages)}")
    # Every message read is one the subscriber received, in the same order per topic.
    run.stop(gateway, signal.SIGTERM)
    run.stop(logger)
    logged = logger_by_topic(run.read_jsonl("logger.jsonl"))
    _, missed = compare_topics(logged, file_by_topic(messages), "sigkill", settle_ns, prefix=True)
    print(f"sigkill: file of {size} bytes; {len(messages)} messages readable, "
          f"the same as the subscriber's first ones; --info says incomplete")


# teejet-replay's summary on stderr, and its table of messages per topic below it.
REPLAY_SUMMARY = re.compile(r"teejet-replay: (\d+) messages published \((\d+) refused\), (\d+) "
                            r"pass\(es\); (\d+) went out over 1 ms late, the latest "
                            r"(\d+\.\d{3}) ms \(message (\d+)\)")
REPLAY_TOPIC_LINE = re.compile(r"^  (teejet/\S+) +(\d+)$", re.MULTILINE)


def check_replay_report(stderr, messages):
    """The replayer says it published every message once, with no refusal, and how late it was:
    the count over 1 ms within what it published, and a latest lateness that agrees with it.
    Returns the summary line."""
    summary = REPLAY_SUMMARY.search(stderr)
    check(summary, f"replay: no summary line from teejet-replay:\n{stderr}")
    published, refused, passes, late, latest_ms, latest_index = (
        int(value) if index != 4 else float(value) for index, value in enumerate(summary.groups()))
    check((published, refused, passes) == (len(messages), 0, 1),
          f"replay: teejet-replay published {published} ({refused} refused) in {passes} "
          f"pass(es); the file holds {len(messages)} messages to replay, in one pass")
    check(0 <= late <= published and (1 <= latest_index <= published or latest_ms == 0),
          f"replay: lateness counts out of range: {summary.group(0)}")
    # The latest is printed rounded to a microsecond.
    check(latest_ms >= 1.0 if late > 0 else latest_ms <= 1.0,
          f"replay: {late} message(s) over 1 ms late, but the latest {latest_ms} ms late")
    per_topic = {topic: int(count) for topic, count in REPLAY_TOPIC_LINE.findall(stderr)}
    in_file = {}
    for message in messages:
        in_file[message["topic"]] = in_file.get(message["topic"], 0) + 1
    check(per_topic == in_file, f"replay: published per topic {per_topic}, the file {in_file}")
    return summary.group(0)


def case_replay(run):
    recording = run.path("run.mcap")
    make_recording(run, "run.mcap")
    messages, _ = run.read_mcap(recording)
    # Commands are not replayed unless asked (a gateway in the domain would move its valves).
    messages = [m for m in messages if m["topic"] != "teejet/valve/command"]
    logger = run.start_logger("replayed", 1)
    replay = run.run([run.binary("tools/teejet-replay/teejet-replay"), recording, "--domain", "1",
                      "--wait-for-readers", "20"], timeout=120)
    summary = check_replay_report(replay.stderr, messages)

    def printed_all():
        with open(run.path("replayed.jsonl")) as f:
            return sum(1 for line in f if line.strip()) >= len(messages)

    # The replayer waits for reliable readers' acknowledgements, not for the best-effort frames
    # to be taken: until the subscriber printed as many samples, or what it missed shows below.
    first(printed_all, 30)
    check(run.stop(logger) == 0, "the replay subscriber did not exit 0")
    received = run.read_jsonl("replayed.jsonl")
    logged, recorded = logger_by_topic(received), file_by_topic(held_stamps(messages))
    # Frames go out best effort, as the gateway sends them: under load a subscriber may miss
    # some (20 of 482 in one CI run), but each it gets is the file's, in the file's order.
    frames_key = ("teejet/can/frame",)
    frames_got, frames_held = logged.pop(frames_key, []), recorded.pop(frames_key, [])
    held = iter(frames_held)
    in_order = all(any(normalise(f["data"]) == normalise(sample["data"])
                       and f["publish_time"] == sample["source_ns"] for f in held)
                   for sample in frames_got)
    check(in_order, "replay: the frames received are not the file's frames in the file's order")
    # Per instance of every reliable topic (the order DDS keeps): the same samples in the same
    # order, with the same values and source timestamps; none missing, none added.
    _, missed = compare_topics(logged, recorded, "replay")
    check(missed == 0, f"replay: the subscriber missed {missed} sample(s)")
    reliable = len(messages) - len(frames_held)
    check(len(received) - len(frames_got) == reliable,
          f"replay: the subscriber got {len(received) - len(frames_got)} samples of reliable "
          f"topics, the file holds {reliable}")
    print(f"replay: {len(frames_got)} of {len(frames_held)} best-effort frames received")
    span = (int(messages[-1]["log_time"]) - int(messages[0]["log_time"])) / 1e9
    print(f"replay: {len(messages)} samples over {span:.3f} s, each as recorded and in the "
          f"recorded order per instance; {summary}")

    # Into the domain of a live gateway of the recording's: refused before anything is
    # published (the dashboard would show its valves jumping between live and recorded), unless
    # told to.
    gateway = run.start_gateway()
    run.valvectl("list", "--wait-for", "4", "--timeout", "20")
    replay_bin = run.binary("tools/teejet-replay/teejet-replay")
    refused = run.run([replay_bin, recording, "--wait-for-readers", "0"], expect=1)
    check(re.search(r"gateway '[^']+' of the recording is live on domain 0: its state and the "
                    r"recorded one would mix; nothing was published", refused.stderr) and
          "messages published" not in refused.stderr,
          f"replay into the live gateway's domain: {refused.stderr}")
    forced = run.run([replay_bin, recording, "--wait-for-readers", "0", "--rate", "100",
                      "--topic", "teejet/gateway/status", "--into-live-gateways"])
    check("messages published" in forced.stderr, f"--into-live-gateways: {forced.stderr}")
    check(run.stop(gateway, signal.SIGTERM) == 0, "the second gateway did not exit 0")
    print("replay: refused where the recording's gateway was live; published with "
          "--into-live-gateways")


def case_split(run):
    """--max-size: every file is complete and stands alone, starting with the last sample of
    every instance the recorder knew (all 32 valves' presence), and together they hold what
    the subscriber received (32 valves, every telemetry at 0.1 s: about 2,600 samples/s)."""
    logged, settle_ns = make_recording(run, "split.mcap", ["--max-size", "1M", "--compression",
                                                            "none"],
                                       valves=32, full_poll=True, until_file="split_001.mcap")
    files = sorted(name for name in os.listdir(run.work) if name.startswith("split_"))
    check(len(files) >= 2, f"split: {files}: expected at least two files")
    live = []
    for index, name in enumerate(files):
        messages, _ = run.read_mcap(run.path(name))
        info = json.loads(run.run([run.binary("tools/teejet-record/teejet-record"), "--info",
                                   run.path(name), "--json"]).stdout)
        check(info["complete"], f"split: {name} is not complete")
        if index > 0:
            # The file opens with the state carried over: log time = the split, publish time =
            # the sample's own.
            split_at_ns = int(messages[0]["log_time"])
            carried = [m for m in messages if int(m["log_time"]) == split_at_ns]
            serials = {m["data"]["serial"] for m in carried if m["topic"] == "teejet/valve/presence"}
            check(serials == set(range(1, 33)),
                  f"split: {name} starts with presence of {sorted(serials)}, not all 32 valves")
            events = [m["topic"] for m in carried if m["topic"] in ("teejet/valve/command",
                                                                     "teejet/can/frame")]
            check(not events, f"split: {name} starts with events, not state: {events}")
            messages = messages[len(carried):]
        live += messages
    # What the recorder took from DDS is all in the files (the carried state aside): splitting
    # lost nothing.
    with open(run.path("recorder.err")) as err:
        summary = re.search(r"teejet-record: (\d+) messages in", err.read())
    check(summary and int(summary.group(1)) == len(live),
          f"split: the recorder reported {summary and summary.group(1)} messages, the files hold "
          f"{len(live)} besides the carried state")
    counts, missed = compare_topics(logger_by_topic(logged), file_by_topic(live), "split",
                                    settle_ns, allow_state_gaps=True)
    print(f"split: {len(files)} files ({', '.join(files)}), each complete and standing alone; "
          f"together {len(live)} messages equal to the subscriber's")


def case_late(run):
    """A recorder started long after the gateway still gets every valve's state at once: the
    presence, telemetry and latched error of each valve and the gateway's status, published
    before it existed (TRANSIENT_LOCAL with the topics' own QoS)."""
    gateway = run.start_gateway()
    run.valvectl("list", "--wait-for", "4", "--timeout", "20")
    run.valvectl("move", "TJV000002", "--to", "30", "--speed", "100", "--wait", "--timeout", "20")
    started_ns = time.time_ns()
    recorder = run.start_recorder("late.mcap")

    def serials(samples, topic):
        return {m["data"]["serial"] for m in samples if m["topic"] == topic}

    # Until the recording holds what a late joiner must get, read as it grows (chunks close at
    # least once a second): each reader matches the gateway's writer on its own, and at load 10
    # presence had not come within a --duration of 1 s (1 of 10 runs).
    def has_state():
        samples, _ = run.read_mcap(run.path("late.mcap"), "--allow-incomplete", expect=None)
        return (serials(samples, "teejet/valve/version") == {1, 2, 3, 4} and
                serials(samples, "teejet/valve/presence") == {1, 2, 3, 4} and
                serials(samples, "teejet/valve/error") == {3} and
                all(any(m["topic"] == topic for m in samples) for topic in (
                    "teejet/valve/position", "teejet/valve/voltage", "teejet/gateway/status")))
    first(has_state, 30, interval=0.2)
    check(run.stop(recorder) == 0, "teejet-record did not exit 0 after SIGINT")
    # --duration ends a recording by itself, with a complete file.
    timed = run.start("timed-recorder", [run.binary("tools/teejet-record/teejet-record"), "-o",
                                         run.path("timed.mcap"), "--duration", "0.5"])
    check(timed.wait(timeout=30) == 0, "teejet-record --duration 0.5 did not exit 0")
    info = json.loads(run.run([run.binary("tools/teejet-record/teejet-record"), "--info",
                               run.path("timed.mcap"), "--json"]).stdout)
    check(info["complete"], f"late: the --duration recording is not complete: {info}")
    run.stop(gateway, signal.SIGTERM)
    messages, _ = run.read_mcap(run.path("late.mcap"))
    early = [m for m in messages if int(m["publish_time"]) < started_ns]
    # Published once, when the valves came up: only a late joiner's copy of the writer's
    # history can bring it. (Presence comes again with each I'm Here.)
    check(serials(early, "teejet/valve/version") == {1, 2, 3, 4},
          f"late: teejet/valve/version published before the recorder started: "
          f"valves {sorted(serials(early, 'teejet/valve/version'))}")
    # The valve repeats its latched error, so the sample may be newer than the recorder.
    check(serials(messages, "teejet/valve/error") == {3},
          "late: the latched error of TJV000003 is missing")
    check(serials(messages, "teejet/valve/presence") == {1, 2, 3, 4},
          f"late: presence of {sorted(serials(messages, 'teejet/valve/presence'))}")
    for topic in ("teejet/valve/position", "teejet/valve/voltage", "teejet/gateway/status"):
        check(any(m["topic"] == topic for m in messages), f"late: nothing on {topic}")
    positions = [m["data"]["degrees"] for m in messages
                 if m["topic"] == "teejet/valve/position" and m["data"]["serial"] == 2]
    check(abs(positions[0] - 30) <= 1, f"late: TJV000002 first recorded at {positions[0]}, not 30")
    print(f"late: a recorder started after the gateway got {len(early)} samples published "
          f"before it existed (every valve's version), then presence, telemetry, the latched "
          f"error and the status")


# libfaketime (Debian package faketime), thread-safe build: Fast DDS runs threads.
FAKETIME_LIB = "/usr/lib/x86_64-linux-gnu/faketime/libfaketimeMT.so.1"
SKIP = 77


class Skip(Exception):
    pass


def case_clock_step(run):
    """A recorder whose wall clock steps back an hour mid-run (libfaketime reading its offset
    from a file, the monotonic clock left alone, as an NTP or GPS correction would do): the file
    spans the run, not an hour, and replay publishes all of it without waiting the hour. Before,
    the log times followed the wall clock: a 14 s file read as 3,599.97 s and replay waited."""
    if not os.path.exists(FAKETIME_LIB):
        raise Skip(f"{FAKETIME_LIB} not found (Debian package faketime)")
    offset = run.path("clock-offset")
    with open(offset, "w") as f:
        f.write("+0\n")
    env = dict(os.environ, LD_PRELOAD=FAKETIME_LIB, FAKETIME_TIMESTAMP_FILE=offset,
               FAKETIME_NO_CACHE="1", DONT_FAKE_MONOTONIC="1")
    gateway = run.start_gateway()
    run.valvectl("list", "--wait-for", "4", "--timeout", "20")
    recorder = run.start_recorder("stepped.mcap", env=env)
    readers = ["--command-readers", "2", "--timeout", "20"]
    run.valvectl("move", "TJV000001", "--to", "60", "--speed", "100", "--wait", *readers)
    with open(offset, "w") as f:
        f.write("-3600\n")
    # The control: a process under the same settings now reads a clock an hour behind.
    probe = run.run(["python3", "-c", "import time; print(time.time())"], env=env)
    lag = time.time() - float(probe.stdout)
    check(3500 < lag < 3700, f"libfaketime did not step the clock (the probe is {lag:.1f} s off)")
    run.valvectl("move", "TJV000001", "--to", "10", "--speed", "100", "--wait", *readers)
    code = run.stop(recorder)
    check(code == 0, f"teejet-record did not exit 0 after SIGINT (exit {code})")
    run.stop(gateway, signal.SIGTERM)
    record = run.binary("tools/teejet-record/teejet-record")
    info = json.loads(run.run([record, "--info", run.path("stepped.mcap"), "--json"]).stdout)
    span_s = (info["end_ns"] - info["start_ns"]) / 1e9
    check(info["complete"] and info["clock_steps"] == 0 and span_s < 600,
          f"clock-step: the recording spans {span_s:.1f} s with {info['clock_steps']} clock "
          f"step(s): {info}")
    commands = next(c["messages"] for c in info["channels"] if c["topic"] ==
                    "teejet/valve/command")
    check(commands == 2, f"clock-step: {commands} commands recorded, not the 2 sent")
    replayed = run.run([run.binary("tools/teejet-replay/teejet-replay"), run.path("stepped.mcap"),
                        "--domain", "7", "--rate", "100", "--wait-for-readers", "0"], timeout=120)
    published = int(re.search(r"(\d+) messages published", replayed.stderr).group(1))
    check(published == info["messages"] - commands,
          f"clock-step: replay published {published} of {info['messages'] - commands}: "
          f"{replayed.stderr}")
    print(f"clock-step: the recorder's clock stepped back 3600 s mid-run; the file spans "
          f"{span_s:.1f} s ({info['messages']} messages, 0 steps in its log times) and replay "
          f"published all {published} (commands held back)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build-dir", required=True)
    parser.add_argument("--npm-reader", required=True)
    parser.add_argument("case", choices=["record", "sigkill", "replay", "split", "late",
                                         "clock-step"])
    args = parser.parse_args()
    if subprocess.run(["node", "--version"], capture_output=True).returncode != 0 or \
            not os.path.isdir(os.path.join(os.path.dirname(args.npm_reader), "node_modules")):
        print("FAIL: node or the npm reader's packages are missing: run tools/install-deps.sh")
        return 1
    with tempfile.TemporaryDirectory(prefix="teejet-recording-") as work:
        run = Run(args, work)
        try:
            {"record": case_record, "sigkill": case_sigkill, "replay": case_replay,
             "split": case_split, "late": case_late,
             "clock-step": case_clock_step}[args.case](run)
        except Skip as skipped:
            print(f"SKIP: {skipped}")
            return SKIP
        except (Failure, Timeout, subprocess.TimeoutExpired) as failure:
            print_failure(failure, work)
            return 1
        finally:
            run.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main())
