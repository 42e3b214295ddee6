#!/usr/bin/env node
// The independent MCAP reader of issue 11: reads a recording with code nobody here wrote
// (@mcap/core, and @foxglove/omgidl-parser + @foxglove/omgidl-serialization, which Foxglove
// itself decodes omgidl/cdr with), so that a bug in tools/mcap cannot hide behind a reader that
// shares its misunderstanding of the spec.
//
// Usage: read-mcap.mjs FILE [--counts] [--allow-incomplete]
//
// Prints one JSON line per message (file order):
//   {"topic", "schema", "sequence", "log_time", "publish_time", "data"}
// with 64-bit integers as decimal strings, enums as numbers and sequences as plain arrays;
// with --counts one JSON object instead: {"<topic>": n, ..., "messages", "channels", "chunks",
// "complete"}. A bad file gives one line "read-mcap: FILE: <reason>" on stderr and exit 1.

import fs from "node:fs";
import process from "node:process";

import { McapIndexedReader, McapStreamReader } from "@mcap/core";
// CommonJS packages: their default export is module.exports on every Node from 18 on.
import omgidlParser from "@foxglove/omgidl-parser";
import omgidlSerialization from "@foxglove/omgidl-serialization";
import lz4 from "@foxglove/wasm-lz4";
import zstd from "@foxglove/wasm-zstd";

const { parseIDL } = omgidlParser;
const { MessageReader } = omgidlSerialization;

const USAGE = "usage: read-mcap.mjs FILE [--counts] [--allow-incomplete]";

class ReadError extends Error {}

function parseArgs(argv) {
  const args = { file: undefined, counts: false, allowIncomplete: false };
  for (const arg of argv) {
    if (arg === "--counts") {
      args.counts = true;
    } else if (arg === "--allow-incomplete") {
      args.allowIncomplete = true;
    } else if (arg === "-h" || arg === "--help") {
      process.stdout.write(`${USAGE}\n`);
      process.exit(0);
    } else if (arg.startsWith("-")) {
      throw new ReadError(`unknown option '${arg}' (${USAGE})`);
    } else if (args.file === undefined) {
      args.file = arg;
    } else {
      throw new ReadError(`more than one file ('${args.file}', '${arg}'): ${USAGE}`);
    }
  }
  if (args.file === undefined) {
    throw new ReadError(`no file given: ${USAGE}`);
  }
  return args;
}

// Neither @mcap/core reader checks Data End's CRC of the data section; a flipped byte outside
// a chunk (a Schema, Channel or Message Index) would otherwise pass unnoticed.
const CRC_TABLE = (() => {
  const table = new Uint32Array(256);
  for (let n = 0; n < 256; n++) {
    let c = n;
    for (let k = 0; k < 8; k++) {
      c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    }
    table[n] = c >>> 0;
  }
  return table;
})();

function crc32(bytes) {
  let crc = 0xffffffff;
  for (let i = 0; i < bytes.length; i++) {
    crc = CRC_TABLE[(crc ^ bytes[i]) & 0xff] ^ (crc >>> 8);
  }
  return (crc ^ 0xffffffff) >>> 0;
}

// Data End is opcode 0x0F, length 4, CRC: 13 bytes that end where the reader now stands.
function checkDataSectionCrc(bytes, endOfDataEnd, expected) {
  const start = endOfDataEnd - 13;
  if (expected === 0 || start < 0 || bytes[start] !== 0x0f) {
    return;
  }
  const actual = crc32(bytes.subarray(0, start));
  if (actual !== expected) {
    throw new ReadError(
      `data section CRC ${actual} does not match Data End's ${expected} (a byte outside the ` +
        `chunks is damaged)`,
    );
  }
}

async function decompressHandlers() {
  await Promise.all([zstd.isLoaded, lz4.isLoaded]);
  return {
    zstd: (buffer, size) => zstd.decompress(buffer, Number(size)),
    lz4: (buffer, size) => lz4(buffer, Number(size)),
  };
}

// Everything in file order, as far as the file goes: a killed recorder leaves no footer, and
// what it wrote up to its last complete record is still a recording.
function readStream(bytes, handlers) {
  const stream = new McapStreamReader({
    decompressHandlers: handlers,
    validateCrcs: true,
    includeChunks: true,
  });
  stream.append(bytes);
  const schemas = new Map();
  const channels = new Map();
  const messages = [];
  let chunks = 0;
  for (let record; (record = stream.nextRecord()); ) {
    switch (record.type) {
      case "Schema":
        schemas.set(record.id, record);
        break;
      case "Channel":
        channels.set(record.id, record);
        break;
      case "Message":
        messages.push(record);
        break;
      case "Chunk":
        chunks++;
        break;
      case "DataEnd":
        checkDataSectionCrc(bytes, bytes.length - stream.bytesRemaining(), record.dataSectionCrc);
        break;
      default:
        break;
    }
  }
  return {
    schemas,
    channels,
    messages,
    chunks,
    complete: stream.done(),
    unread: stream.bytesRemaining(),
  };
}

function sameBytes(a, b) {
  if (a.byteLength !== b.byteLength) {
    return false;
  }
  for (let i = 0; i < a.byteLength; i++) {
    if (a[i] !== b[i]) {
      return false;
    }
  }
  return true;
}

function describe(message, channels) {
  const channel = channels.get(message.channelId);
  const topic = channel ? `"${channel.topic}"` : "(unknown)";
  return `channel ${message.channelId} ${topic} sequence ${message.sequence}`;
}

// The summary's way through the file (chunk indexes, message indexes) must find the very
// messages the stream found, and the Statistics must count them.
async function crossCheckIndexed(bytes, handlers, streamed) {
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
  };
  let indexed;
  const viaIndex = [];
  try {
    indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers: handlers });
    for await (const message of indexed.readMessages({ validateCrcs: true })) {
      viaIndex.push(message);
    }
  } catch (error) {
    throw new ReadError(`indexed read: ${firstLine(error)}`);
  }

  // The indexed reader yields in log time order (ties in file order); a stable sort of the
  // file order is the same order.
  const expected = [...streamed.messages].sort((a, b) =>
    a.logTime < b.logTime ? -1 : a.logTime > b.logTime ? 1 : 0,
  );
  if (viaIndex.length !== expected.length) {
    throw new ReadError(
      `the indexes lead to ${viaIndex.length} messages, reading the file through gives ` +
        `${expected.length}`,
    );
  }
  for (let i = 0; i < expected.length; i++) {
    const a = expected[i];
    const b = viaIndex[i];
    if (
      a.channelId !== b.channelId ||
      a.sequence !== b.sequence ||
      a.logTime !== b.logTime ||
      a.publishTime !== b.publishTime ||
      !sameBytes(a.data, b.data)
    ) {
      throw new ReadError(
        `message ${i + 1} in log time order differs: read through it is ` +
          `${describe(a, streamed.channels)} at ${a.logTime}, through the indexes ` +
          `${describe(b, streamed.channels)} at ${b.logTime}`,
      );
    }
  }

  const statistics = indexed.statistics;
  if (!statistics) {
    throw new ReadError("the summary has no Statistics record");
  }
  const counted = new Map();
  for (const message of streamed.messages) {
    counted.set(message.channelId, (counted.get(message.channelId) ?? 0n) + 1n);
  }
  for (const id of new Set([...counted.keys(), ...statistics.channelMessageCounts.keys()])) {
    const inFile = counted.get(id) ?? 0n;
    const inStatistics = statistics.channelMessageCounts.get(id) ?? 0n;
    if (inFile !== inStatistics) {
      const channel = streamed.channels.get(id);
      throw new ReadError(
        `channel ${id} "${channel?.topic ?? "?"}" has ${inFile} messages, the Statistics ` +
          `say ${inStatistics}`,
      );
    }
  }
  const checks = [
    ["messages", BigInt(streamed.messages.length), statistics.messageCount],
    ["channels", streamed.channels.size, statistics.channelCount],
    ["schemas", streamed.schemas.size, statistics.schemaCount],
    ["chunks", streamed.chunks, statistics.chunkCount],
    ["chunk indexes", streamed.chunks, indexed.chunkIndexes.length],
  ];
  for (const [what, inFile, inSummary] of checks) {
    if (Number(inFile) !== Number(inSummary)) {
      throw new ReadError(`the file has ${inFile} ${what}, the summary says ${inSummary}`);
    }
  }
}

// One MessageReader per schema, built when a message first needs it.
function makeDecoder(streamed) {
  const readers = new Map();
  return (message) => {
    const channel = streamed.channels.get(message.channelId);
    const where = describe(message, streamed.channels);
    if (channel.messageEncoding !== "cdr") {
      throw new ReadError(`${where}: message encoding '${channel.messageEncoding}', not 'cdr'`);
    }
    const schema = streamed.schemas.get(channel.schemaId);
    if (!schema) {
      throw new ReadError(`${where}: no schema (schema id ${channel.schemaId})`);
    }
    let reader = readers.get(schema.id);
    if (!reader) {
      if (schema.encoding !== "omgidl") {
        throw new ReadError(`${where}: schema encoding '${schema.encoding}', not 'omgidl'`);
      }
      try {
        const definitions = parseIDL(new TextDecoder().decode(schema.data));
        reader = new MessageReader(schema.name, definitions);
      } catch (error) {
        throw new ReadError(`${where}: schema '${schema.name}': ${firstLine(error)}`);
      }
      readers.set(schema.id, reader);
    }
    try {
      return { schema: schema.name, data: reader.readMessage(message.data) };
    } catch (error) {
      throw new ReadError(`${where}: cannot decode as '${schema.name}': ${firstLine(error)}`);
    }
  };
}

function plain(value) {
  if (typeof value === "bigint") {
    return value.toString();
  }
  if (typeof value === "number" && !Number.isFinite(value)) {
    return String(value);
  }
  if (ArrayBuffer.isView(value)) {
    return Array.from(value, plain);
  }
  if (Array.isArray(value)) {
    return value.map(plain);
  }
  if (value !== null && typeof value === "object") {
    const out = {};
    for (const [key, field] of Object.entries(value)) {
      out[key] = plain(field);
    }
    return out;
  }
  return value;
}

function firstLine(error) {
  const text = error instanceof Error ? error.message : String(error);
  return text.split("\n")[0];
}

async function main(args) {
  let bytes;
  try {
    bytes = fs.readFileSync(args.file);
  } catch (error) {
    throw new ReadError(`cannot read: ${error.code ?? firstLine(error)}`);
  }
  const handlers = await decompressHandlers();
  let streamed;
  try {
    streamed = readStream(bytes, handlers);
  } catch (error) {
    if (error instanceof ReadError) {
      throw error;
    }
    throw new ReadError(firstLine(error));
  }

  if (streamed.complete) {
    await crossCheckIndexed(bytes, handlers, streamed);
  } else {
    const what =
      `file ends early (no footer: ${streamed.unread} of ${bytes.length} bytes after the ` +
      `last complete record)`;
    if (!args.allowIncomplete) {
      throw new ReadError(`${what}; --allow-incomplete reads the ${streamed.messages.length} ` +
                          `messages before that`);
    }
    process.stderr.write(
      `read-mcap: ${args.file}: warning: ${what}; read ${streamed.messages.length} messages ` +
        `up to there\n`,
    );
  }

  // Every message is decoded even for --counts: a count of undecodable samples proves nothing.
  const decode = makeDecoder(streamed);
  const lines = [];
  const counts = {};
  for (const channel of streamed.channels.values()) {
    counts[channel.topic] ??= 0;
  }
  for (const message of streamed.messages) {
    const { schema, data } = decode(message);
    const topic = streamed.channels.get(message.channelId).topic;
    counts[topic] += 1;
    if (!args.counts) {
      lines.push(
        JSON.stringify({
          topic,
          schema,
          sequence: message.sequence,
          log_time: message.logTime.toString(),
          publish_time: message.publishTime.toString(),
          data: plain(data),
        }),
      );
    }
  }
  if (args.counts) {
    lines.push(
      JSON.stringify({
        ...counts,
        messages: streamed.messages.length,
        channels: streamed.channels.size,
        chunks: streamed.chunks,
        complete: streamed.complete,
      }),
    );
  }
  await writeLines(lines);
}

// In blocks, and waiting for the pipe: process.exit() would cut off what is still buffered.
async function writeLines(lines) {
  const block = 2000;
  for (let i = 0; i < lines.length; i += block) {
    const text = `${lines.slice(i, i + block).join("\n")}\n`;
    if (!process.stdout.write(text)) {
      await new Promise((resolve) => process.stdout.once("drain", resolve));
    }
  }
}

// A reader of our output that stops early (head) is not an error of ours.
process.stdout.on("error", (error) => {
  if (error.code === "EPIPE") {
    process.exit(0);
  }
  throw error;
});

let args;
try {
  args = parseArgs(process.argv.slice(2));
} catch (error) {
  process.stderr.write(`read-mcap: ${firstLine(error)}\n`);
  process.exit(2);
}
try {
  await main(args);
} catch (error) {
  // Our own errors are the reason; anything else is a library's message, still one line.
  process.stderr.write(`read-mcap: ${args.file}: ${firstLine(error)}\n`);
  process.exitCode = 1;
}
