#!/usr/bin/env node
// The independent MCAP reader of issue 11: reads a recording with code nobody here wrote
// (@mcap/core, and @foxglove/omgidl-parser + @foxglove/omgidl-serialization, which Foxglove
// itself decodes omgidl/cdr with), so that a bug in tools/mcap cannot hide behind a reader that
// shares its misunderstanding of the spec.
//
// Usage: read-mcap.mjs FILE [--counts] [--allow-incomplete]
//
// Checks: chunk CRCs and the data section CRC while reading the file through; for a complete
// file, that the summary (chunk and message indexes, Statistics) leads to exactly the same
// messages; that every message decodes with its schema.
//
// Prints one JSON line per message (file order):
//   {"topic", "schema", "sequence", "log_time", "publish_time", "data"}
// with 64-bit integers as decimal strings, enums as numbers and sequences as plain arrays;
// with --counts one JSON object instead: {"<topic>": n, ..., "messages", "channels", "chunks",
// "complete"}. A bad file gives one line "read-mcap: FILE: <reason>" on stderr and exit 1; a
// file without footer is read up to its last complete record, and exit 0 only with
// --allow-incomplete. Usage errors exit 2.

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

// A growable typed array: a million messages as JS objects (BigInt times and all) cost a
// gigabyte; as columns, 26 bytes each.
class Column {
  constructor(Type) {
    this.Type = Type;
    this.values = new Type(1024);
    this.length = 0;
  }

  push(value) {
    if (this.length === this.values.length) {
      const grown = new this.Type(this.values.length * 2);
      grown.set(this.values);
      this.values = grown;
    }
    this.values[this.length++] = value;
  }
}

// Every message in file order, as far as the file goes: a killed recorder leaves no footer, and
// what it wrote up to its last complete record is still a recording. Fills `file` with what
// the file holds besides.
function* readStream(bytes, handlers, file) {
  const stream = new McapStreamReader({
    decompressHandlers: handlers,
    validateCrcs: true,
    includeChunks: true,
  });
  stream.append(bytes);
  Object.assign(file, { schemas: new Map(), channels: new Map(), messages: 0, chunks: 0 });
  for (let record; (record = stream.nextRecord()); ) {
    switch (record.type) {
      case "Schema":
        file.schemas.set(record.id, record);
        break;
      case "Channel":
        file.channels.set(record.id, record);
        break;
      case "Message":
        file.messages++;
        yield record;
        break;
      case "Chunk":
        file.chunks++;
        break;
      case "DataEnd":
        checkDataSectionCrc(bytes, bytes.length - stream.bytesRemaining(), record.dataSectionCrc);
        break;
      default:
        break;
    }
  }
  file.complete = stream.done();
  file.unread = stream.bytesRemaining();
}

function describe(message, channels) {
  const channel = channels.get(message.channelId);
  const topic = channel ? `"${channel.topic}"` : "(unknown)";
  return `channel ${message.channelId} ${topic} sequence ${message.sequence}`;
}

// What the indexed reader must find again of each message, in file order.
class Seen {
  constructor() {
    this.channel = new Column(Uint16Array);
    this.sequence = new Column(Uint32Array);
    this.logTime = new Column(BigUint64Array);
    this.publishTime = new Column(BigUint64Array);
    this.crc = new Column(Uint32Array);
  }

  add(message) {
    this.channel.push(message.channelId);
    this.sequence.push(message.sequence);
    this.logTime.push(message.logTime);
    this.publishTime.push(message.publishTime);
    this.crc.push(crc32(message.data));
  }

  // Indexes in log time order, ties in file order: the order of McapIndexedReader.
  logTimeOrder() {
    const n = this.logTime.length;
    const times = this.logTime.values;
    const order = new Uint32Array(n);
    let sorted = true;
    for (let i = 0; i < n; i++) {
      order[i] = i;
      sorted &&= i === 0 || times[i - 1] <= times[i];
    }
    if (!sorted) {
      const byTime = Array.from(order).sort((a, b) =>
        times[a] < times[b] ? -1 : times[a] > times[b] ? 1 : a - b,
      );
      order.set(byTime);
    }
    return order;
  }
}

// The summary's way through the file (chunk indexes, message indexes) must find the very
// messages the stream found, and the Statistics must count them.
async function crossCheckIndexed(bytes, handlers, file, seen, counted) {
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
  };
  const order = seen.logTimeOrder();
  const where = (i) =>
    describe(
      { channelId: seen.channel.values[i], sequence: seen.sequence.values[i] },
      file.channels,
    ) + ` at ${seen.logTime.values[i]}`;
  let indexed;
  let found = 0;
  try {
    indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers: handlers });
    for await (const message of indexed.readMessages({ validateCrcs: true })) {
      if (found >= order.length) {
        throw new ReadError(
          `the indexes lead to more messages than the ${order.length} in the file`,
        );
      }
      const i = order[found++];
      if (
        message.channelId !== seen.channel.values[i] ||
        message.sequence !== seen.sequence.values[i] ||
        message.logTime !== seen.logTime.values[i] ||
        message.publishTime !== seen.publishTime.values[i] ||
        crc32(message.data) !== seen.crc.values[i]
      ) {
        throw new ReadError(
          `message ${found} in log time order differs: read through it is ${where(i)}, ` +
            `through the indexes ${describe(message, file.channels)} at ${message.logTime}`,
        );
      }
    }
  } catch (error) {
    if (error instanceof ReadError) {
      throw error;
    }
    throw new ReadError(`indexed read: ${firstLine(error)}`);
  }
  if (found !== order.length) {
    throw new ReadError(
      `the indexes lead to ${found} messages, reading the file through gives ${order.length}`,
    );
  }

  const statistics = indexed.statistics;
  if (!statistics) {
    throw new ReadError("the summary has no Statistics record");
  }
  for (const id of new Set([...counted.keys(), ...statistics.channelMessageCounts.keys()])) {
    const inFile = BigInt(counted.get(id) ?? 0);
    const inStatistics = statistics.channelMessageCounts.get(id) ?? 0n;
    if (inFile !== inStatistics) {
      const channel = file.channels.get(id);
      throw new ReadError(
        `channel ${id} "${channel?.topic ?? "?"}" has ${inFile} messages, the Statistics ` +
          `say ${inStatistics}`,
      );
    }
  }
  const checks = [
    ["messages", file.messages, statistics.messageCount],
    ["channels", file.channels.size, statistics.channelCount],
    ["schemas", file.schemas.size, statistics.schemaCount],
    ["chunks", file.chunks, statistics.chunkCount],
    ["chunk indexes", file.chunks, indexed.chunkIndexes.length],
  ];
  for (const [what, inFile, inSummary] of checks) {
    if (Number(inFile) !== Number(inSummary)) {
      throw new ReadError(`the file has ${inFile} ${what}, the summary says ${inSummary}`);
    }
  }
}

// One MessageReader per schema, built when a message first needs it.
function makeDecoder() {
  const readers = new Map();
  return (message, file) => {
    const channel = file.channels.get(message.channelId);
    const where = describe(message, file.channels);
    if (channel.messageEncoding !== "cdr") {
      throw new ReadError(`${where}: message encoding '${channel.messageEncoding}', not 'cdr'`);
    }
    const schema = file.schemas.get(channel.schemaId);
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
      return { topic: channel.topic, schema: schema.name, data: reader.readMessage(message.data) };
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

// A ReadError as is; anything else is a library's message, still one line.
function asReadError(error) {
  return error instanceof ReadError ? error : new ReadError(firstLine(error));
}

async function main(args) {
  let bytes;
  try {
    bytes = fs.readFileSync(args.file);
  } catch (error) {
    throw new ReadError(`cannot read: ${error.code ?? firstLine(error)}`);
  }
  const handlers = await decompressHandlers();

  // First everything is checked and decoded, so that a bad file prints no message at all; the
  // second pass through the file prints. Keeping the decoded messages instead would take a
  // gigabyte per million.
  const decode = makeDecoder();
  const seen = new Seen();
  const counted = new Map();
  const file = {};
  try {
    for (const message of readStream(bytes, handlers, file)) {
      decode(message, file);
      seen.add(message);
      counted.set(message.channelId, (counted.get(message.channelId) ?? 0) + 1);
    }
  } catch (error) {
    throw asReadError(error);
  }

  if (file.complete) {
    await crossCheckIndexed(bytes, handlers, file, seen, counted);
  } else {
    const what =
      `file ends early (no footer: ${file.unread} of ${bytes.length} bytes after the ` +
      `last complete record)`;
    if (!args.allowIncomplete) {
      throw new ReadError(
        `${what}; --allow-incomplete reads the ${file.messages} messages before that`,
      );
    }
    process.stderr.write(
      `read-mcap: ${args.file}: warning: ${what}; read ${file.messages} messages up to there\n`,
    );
  }

  if (args.counts) {
    const counts = {};
    for (const channel of file.channels.values()) {
      counts[channel.topic] = (counts[channel.topic] ?? 0) + (counted.get(channel.id) ?? 0);
    }
    await write(
      `${JSON.stringify({
        ...counts,
        messages: file.messages,
        channels: file.channels.size,
        chunks: file.chunks,
        complete: file.complete,
      })}\n`,
    );
    return;
  }
  let block = [];
  const again = {};
  for (const message of readStream(bytes, handlers, again)) {
    const { topic, schema, data } = decode(message, again);
    block.push(
      JSON.stringify({
        topic,
        schema,
        sequence: message.sequence,
        log_time: message.logTime.toString(),
        publish_time: message.publishTime.toString(),
        data: plain(data),
      }),
    );
    if (block.length === 2000) {
      await write(`${block.join("\n")}\n`);
      block = [];
    }
  }
  if (block.length > 0) {
    await write(`${block.join("\n")}\n`);
  }
}

// Waiting for the pipe: process.exit() would cut off what is still buffered.
async function write(text) {
  if (!process.stdout.write(text)) {
    await new Promise((resolve) => process.stdout.once("drain", resolve));
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
