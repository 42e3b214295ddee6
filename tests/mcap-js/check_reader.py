#!/usr/bin/env python3
"""Runs the independent MCAP reader (read-mcap.mjs) on recordings of known content.

  check_reader.py known_values --writer WRITE_KNOWN_RECORDING --topics TOPICS_HPP
      every value of every message of the zstd, lz4 and uncompressed files is what was written;
      every topic of the DDS contract has a channel
  check_reader.py bad_files --writer WRITE_KNOWN_RECORDING --topics TOPICS_HPP
      truncated, wrong magic, damaged chunk, damaged schema, damaged summary, unknown schema,
      undecodable message, missing and empty file: exit 1 and one clear line, never a stack trace

Fails (never skips) when node or the pinned npm packages are missing: tools/install-deps.sh
installs them.
"""

import argparse
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
READER = os.path.join(HERE, "read-mcap.mjs")
INSTALL_HINT = "run tools/install-deps.sh (it installs Node and the npm packages pinned in " \
               "tests/mcap-js/package-lock.json)"

failures = []


def check(condition, what):
    if not condition:
        failures.append(what)
        print(f"FAIL: {what}", file=sys.stderr)
    return condition


def require_node():
    node = shutil.which("node")
    if node is None:
        sys.exit(f"check_reader: node not found in PATH: {INSTALL_HINT}")
    with open(os.path.join(HERE, "package.json"), encoding="utf-8") as f:
        pinned = json.load(f)["dependencies"]
    for name, version in pinned.items():
        installed = os.path.join(HERE, "node_modules", name, "package.json")
        try:
            with open(installed, encoding="utf-8") as f:
                have = json.load(f)["version"]
        except OSError:
            sys.exit(f"check_reader: {name} is not installed in tests/mcap-js/node_modules: "
                     f"{INSTALL_HINT}")
        if have != version:
            sys.exit(f"check_reader: {name} {have} is installed, package.json pins {version}: "
                     f"{INSTALL_HINT}")
    return node


def run_reader(node, path, *options):
    result = subprocess.run([node, READER, path, *options], capture_output=True, text=True,
                            timeout=60, check=False)
    return result.returncode, result.stdout, result.stderr


def fround(value):
    return struct.unpack("<f", struct.pack("<f", value))[0]


def difference(expected, actual, where="data"):
    """The first place where actual differs from expected, or None. Floats in the expected
    values are float32 values: compared after rounding to float32, as the wire holds them."""
    if isinstance(expected, bool) or isinstance(actual, bool):
        same = type(expected) is type(actual) and expected == actual
        return None if same else f"{where}: expected {expected!r}, got {actual!r}"
    if isinstance(expected, float):
        if not isinstance(actual, (int, float)) or fround(expected) != actual:
            return f"{where}: expected float32 {fround(expected)!r}, got {actual!r}"
        return None
    if isinstance(expected, dict):
        if not isinstance(actual, dict) or set(expected) != set(actual):
            return f"{where}: expected fields {sorted(expected)}, got {actual!r}"
        for key in expected:
            found = difference(expected[key], actual[key], f"{where}.{key}")
            if found:
                return found
        return None
    if isinstance(expected, list):
        if not isinstance(actual, list) or len(expected) != len(actual):
            return f"{where}: expected {expected!r}, got {actual!r}"
        for i, (e, a) in enumerate(zip(expected, actual)):
            found = difference(e, a, f"{where}[{i}]")
            if found:
                return found
        return None
    if type(expected) is not type(actual) or expected != actual:
        return f"{where}: expected {expected!r}, got {actual!r}"
    return None


def compare_messages(expected, lines, what):
    check(len(lines) == len(expected),
          f"{what}: {len(lines)} messages, expected {len(expected)}")
    for i, (e, line) in enumerate(zip(expected, lines)):
        actual = json.loads(line)
        found = difference(e, actual, f"message {i + 1} ({e['topic']} #{e['sequence']})")
        if not check(found is None, f"{what}: {found}"):
            return


def contract_topics(out):
    """Every topic of the DDS contract, as the writer (built with it) lists them."""
    with open(os.path.join(out, "contract-topics.json"), encoding="utf-8") as f:
        return json.load(f)


def known_values(node, out):
    with open(os.path.join(out, "known.json"), encoding="utf-8") as f:
        expected = json.load(f)
    topics = contract_topics(out)
    check(len(topics) >= 16, f"the contract lists {len(topics)} topics, expected at least 16")
    counts = {}
    for message in expected:
        counts[message["topic"]] = counts.get(message["topic"], 0) + 1
    for topic in topics:
        check(counts.get(topic, 0) >= 2, f"known recording: topic {topic} has no channel with "
                                         f"at least two samples")
    check(any(t.endswith("/disposed") for t in counts), "known recording: no /disposed channel")

    for compression in ("zstd", "lz4", "none"):
        path = os.path.join(out, f"known-{compression}.mcap")
        failed_before = len(failures)
        code, stdout, stderr = run_reader(node, path)
        if not check(code == 0 and stderr == "", f"{compression}: exit {code}, stderr {stderr!r}"):
            continue
        compare_messages(expected, stdout.splitlines(), compression)

        code, stdout, stderr = run_reader(node, path, "--counts")
        check(code == 0 and stderr == "", f"{compression} --counts: exit {code}, {stderr!r}")
        summary = json.loads(stdout)
        chunks = summary.pop("chunks", 0)
        check(chunks > 1, f"{compression}: {chunks} chunks, the test wants several")
        wanted = dict(counts, messages=len(expected), channels=len(counts), complete=True)
        check(summary == wanted, f"{compression} --counts: got {summary}, expected {wanted}")
        if len(failures) == failed_before:
            print(f"{compression}: {len(expected)} messages on {len(counts)} channels in "
                  f"{chunks} chunks, every value as written")


def records(data):
    """(opcode, start, end) of each top-level record after the magic, as far as they are
    complete."""
    position, found = 8, []
    while position + 9 <= len(data):
        opcode = data[position]
        (length,) = struct.unpack_from("<Q", data, position + 1)
        end = position + 9 + length
        if end > len(data):
            break
        found.append((opcode, position, end))
        position = end
    return found


CHUNK, SCHEMA, MESSAGE, STATISTICS = 0x06, 0x03, 0x05, 0x0B


def chunk_records_start(data, start):
    """Where the (compressed) records of the Chunk record at start begin."""
    position = start + 9 + 8 + 8 + 8 + 4  # start/end time, uncompressed size, CRC
    (name_length,) = struct.unpack_from("<I", data, position)
    return position + 4 + name_length + 8


def messages_per_chunk(uncompressed):
    counts = []
    for opcode, start, end in records(uncompressed):
        if opcode != CHUNK:
            continue
        inner = chunk_records_start(uncompressed, start)
        position, n = inner, 0
        while position < end:
            (length,) = struct.unpack_from("<Q", uncompressed, position + 1)
            n += uncompressed[position] == MESSAGE
            position += 9 + length
        counts.append(n)
    return counts


def expect_clear_error(node, path, what, needle, *options):
    code, stdout, stderr = run_reader(node, path, *options)
    lines = stderr.splitlines()
    check(code == 1, f"{what}: exit {code}, expected 1 (stderr {stderr!r})")
    check(len(lines) == 1 and lines[0].startswith(f"read-mcap: {path}: "),
          f"{what}: expected one line 'read-mcap: {path}: ...', got {stderr!r}")
    check(needle in stderr, f"{what}: {needle!r} not in {stderr!r}")
    check("    at " not in stderr, f"{what}: stack trace: {stderr!r}")
    check(stdout == "", f"{what}: printed messages although it failed: {stdout[:200]!r}")
    print(f"{what}: exit {code}: {stderr.strip()}")


def write_variant(out, name, data):
    path = os.path.join(out, name)
    with open(path, "wb") as f:
        f.write(data)
    return path


def bad_files(node, out):
    with open(os.path.join(out, "known.json"), encoding="utf-8") as f:
        expected = json.load(f)
    files = {}
    for compression in ("zstd", "lz4", "none"):
        with open(os.path.join(out, f"known-{compression}.mcap"), "rb") as f:
            files[compression] = f.read()
    per_chunk = messages_per_chunk(files["none"])
    check(len(per_chunk) >= 3, f"known recording has {len(per_chunk)} chunks, need 3")

    # A killed recorder: the file stops in the middle of its third chunk. The chunks are cut at
    # the same messages whatever the compression, so the prefix is the same for all three.
    prefix = sum(per_chunk[:2])
    for compression, data in files.items():
        chunks = [r for r in records(data) if r[0] == CHUNK]
        start, end = chunks[2][1], chunks[2][2]
        path = write_variant(out, f"truncated-{compression}.mcap", data[:(start + end) // 2])
        expect_clear_error(node, path, f"truncated {compression}", "file ends early")
        code, stdout, stderr = run_reader(node, path, "--allow-incomplete")
        check(code == 0, f"truncated {compression} --allow-incomplete: exit {code}, {stderr!r}")
        check(stderr.startswith(f"read-mcap: {path}: warning: file ends early")
              and stderr.count("\n") == 1,
              f"truncated {compression} --allow-incomplete: warning {stderr!r}")
        check(f"read {prefix} messages" in stderr,
              f"truncated {compression}: expected 'read {prefix} messages' in {stderr!r}")
        compare_messages(expected[:prefix], stdout.splitlines(), f"truncated {compression}")
        code, stdout, _ = run_reader(node, path, "--allow-incomplete", "--counts")
        summary = json.loads(stdout) if code == 0 else {}
        check(summary.get("messages") == prefix and summary.get("chunks") == 2
              and summary.get("complete") is False,
              f"truncated {compression} --counts: exit {code}, {stdout!r}")
        print(f"truncated {compression} --allow-incomplete: exit {code}, "
              f"{len(stdout.splitlines())} of {len(expected)} messages: the first {prefix}")

    data = bytearray(files["zstd"])
    data[1] = ord("X")
    expect_clear_error(node, write_variant(out, "magic.mcap", data), "wrong magic", "magic")

    # One bit inside the first chunk's records: uncompressed, only the CRC can notice;
    # compressed, the decompressor or the CRC.
    for compression, needle in (("none", "Incorrect chunk CRC"), ("zstd", "")):
        data = bytearray(files[compression])
        _, start, end = next(r for r in records(data) if r[0] == CHUNK)
        data[(chunk_records_start(data, start) + end) // 2] ^= 0x10
        path = write_variant(out, f"flipped-{compression}.mcap", data)
        expect_clear_error(node, path, f"flipped byte in a {compression} chunk", needle)

    # One bit in a comment of the IDL text in a Schema record: outside any chunk, only the
    # data section CRC in Data End covers it.
    data = bytearray(files["lz4"])
    _, start, end = next(r for r in records(data) if r[0] == SCHEMA)
    comment = data.index(b"// Units are", start, end)
    data[comment + 3] ^= 0x20
    expect_clear_error(node, write_variant(out, "schema-damaged.mcap", data),
                       "flipped byte in a schema", "data section CRC")

    # The summary (after Data End) is covered by the footer's CRC, which the indexed reader checks.
    data = bytearray(files["zstd"])
    _, start, end = next(r for r in records(data) if r[0] == STATISTICS)
    data[start + 9] ^= 0x01  # the message count
    expect_clear_error(node, write_variant(out, "summary-damaged.mcap", data),
                       "flipped byte in the summary", "indexed read: Incorrect summary CRC")

    expect_clear_error(node, os.path.join(out, "unknown-schema.mcap"), "unknown schema",
                       'channel 0 "teejet/valve/position" sequence 1: schema '
                       "'teejet::NoSuchType'")
    expect_clear_error(node, os.path.join(out, "undecodable.mcap"), "undecodable message",
                       '"teejet/valve/position" sequence 2: cannot decode as '
                       "'teejet::ValvePosition'")
    expect_clear_error(node, os.path.join(out, "no-such-file.mcap"), "missing file",
                       "cannot read: ENOENT")
    expect_clear_error(node, write_variant(out, "empty.mcap", b""), "empty file",
                       "file ends early")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("mode", choices=["known_values", "bad_files"])
    parser.add_argument("--writer", required=True, help="the write_known_recording program")
    args = parser.parse_args()
    node = require_node()
    with tempfile.TemporaryDirectory(prefix="mcap-js-") as out:
        written = subprocess.run([args.writer, out], timeout=60, check=False)
        if written.returncode != 0:
            sys.exit(f"check_reader: {args.writer} failed (exit {written.returncode})")
        if args.mode == "known_values":
            known_values(node, out)
        else:
            bad_files(node, out)
    if failures:
        sys.exit(f"check_reader {args.mode}: {len(failures)} failure(s)")
    print(f"check_reader {args.mode}: all passed")


if __name__ == "__main__":
    main()
