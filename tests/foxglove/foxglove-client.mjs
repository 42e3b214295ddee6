#!/usr/bin/env node
// The independent Foxglove WebSocket client of the tests: it judges what `teejet-web --foxglove`
// serves with code nobody here wrote (@foxglove/ws-protocol's FoxgloveClient for the framing,
// `ws` for the WebSocket, Foxglove's omgidl parser and CDR reader/writer for the data), so that a
// bug in the server cannot hide behind a client that shares its misunderstanding of the spec.
//
// Usage: foxglove-client.mjs URL [options]          (URL: ws://127.0.0.1:PORT/)
//
//   --subprotocol NAME        the one subprotocol offered (default foxglove.websocket.v1)
//   --token T                 appended to the URL as ?token=T (percent-encoded)
//   --subscribe GLOB          (repeatable) subscribe to every advertised channel whose topic
//                             matches; '*' matches anything, '/' included
//   --subscribe-after-ms N    subscribe N ms after the first advertise instead of at once
//   --unsubscribe-after-ms N  unsubscribe everything N ms after the first subscribe, and
//                             subscribe to nothing more; keep listening
//   --duration-ms N           close and exit N ms after the open
//   --until-messages N        exit once N messages arrived
//   --until-topic-count T=N   (repeatable) exit once topic T got at least N messages
//   --until-status TEXT       (repeatable) exit once a status message holding TEXT arrived
//   --timeout-ms N            hard limit from the start: exit 3 naming what was awaited
//                             (default 20000, or --duration-ms + 5000 when that is longer)
//   --counts                  count messages instead of printing them; print counts at exit
//   --publish JSON            (repeatable, sent in order) a message to publish
//   --publish-topic T         (default teejet/valve/command)
//   --publish-encoding E      (default cdr; any other encoding sends the JSON text as is)
//   --publish-schema-name S   the schema when the server does not advertise the topic ...
//   --idl FILE                ... and the IDL file it is in
//   --publish-delay-ms N      between the client advertise and the first send (default 200)
//   --publish-interval-ms N   between two sends (default 0)
//   --never-read              after subscribing, stop reading the socket until --duration-ms
//   --pause-ms N              after subscribing, stop reading the socket for N ms, then read on
//
// Prints one JSON line per event on stdout, 64-bit integers as decimal strings, enums as numbers,
// sequences as plain arrays:
//   {"event":"open","protocol"}                     the subprotocol the server selected
//   {"event":"serverInfo",...}                      the message without op
//   {"event":"advertise","channels":[{id,topic,encoding,schemaName,schemaEncoding,
//                                     schema_bytes}]}   (schema text left out, too long)
//   {"event":"unadvertise","channelIds"}  {"event":"status","level","message","id"}
//   {"event":"removeStatus","statusIds"}  {"event":"time","timestamp"}
//   {"event":"subscribe","subscriptions":[{id,channel,topic}]}
//   {"event":"unsubscribe","subscriptions":[id,...]}
//   {"event":"message","topic","channel","subscription","timestamp","data"}
//                                 ("unsubscribed":true when it came after the unsubscribe,
//                                  "ms_after_unsubscribe": how long after it was sent)
//   {"event":"clientAdvertise","channel","topic","encoding","schemaName"}
//   {"event":"published","topic","channel","data"}  data with every field, defaults filled
//   {"event":"warning","message"}                   e.g. the server lacks clientPublish
//   {"event":"counts","per_topic":{topic:n},"messages","bytes","seconds"}
//                                 (--counts or --never-read; bytes: CDR payload bytes;
//                                  "after_unsubscribe" with --unsubscribe-after-ms)
//   {"event":"close","code","reason"}               only when the server closes
//   {"event":"error","message"}
//
// Exit status: 0 when everything asked for happened; 1 after any error line (a message that does
// not decode, a refused handshake, a subprotocol not selected, the server closing before the end
// asked for); 2 usage; 3 the timeout, or --duration-ms over before the --until-* were met.

import fs from "node:fs";
import process from "node:process";
import { performance } from "node:perf_hooks";

import WebSocket from "ws";
// CommonJS packages. @foxglove/ws-protocol has a "module" field, but Node ignores it and loads
// dist/cjs, whose re-exports (getters) Node's named-export detection does not see: only the
// default import, which is module.exports, reaches FoxgloveClient.
import wsProtocol from "@foxglove/ws-protocol";
import omgidlParser from "@foxglove/omgidl-parser";
import omgidlSerialization from "@foxglove/omgidl-serialization";

const { FoxgloveClient } = wsProtocol;
const { parseIDL } = omgidlParser;
const { MessageReader, MessageWriter } = omgidlSerialization;

const USAGE =
  "usage: foxglove-client.mjs URL [--subprotocol NAME] [--token T] [--subscribe GLOB]... " +
  "[--subscribe-after-ms N] [--unsubscribe-after-ms N] [--duration-ms N] [--until-messages N] " +
  "[--until-topic-count TOPIC=N]... [--until-status TEXT]... [--timeout-ms N] [--counts] [--publish JSON]... " +
  "[--publish-topic T] [--publish-encoding E] [--publish-schema-name S] [--idl FILE] " +
  "[--publish-delay-ms N] [--publish-interval-ms N] [--never-read] [--pause-ms N]";

const DEFAULT_TIMEOUT_MS = 20000;

class UsageError extends Error {}
class PublishError extends Error {}

function firstLine(error) {
  const text = error instanceof Error ? error.message : String(error);
  return text.split("\n")[0];
}

function count(option, text) {
  if (!/^\d+$/.test(text ?? "")) {
    throw new UsageError(`${option} wants a whole number of ms or messages, not '${text}'`);
  }
  return Number(text);
}

function parseArgs(argv) {
  const args = {
    url: undefined,
    subprotocol: "foxglove.websocket.v1",
    token: undefined,
    subscribe: [],
    subscribeAfterMs: 0,
    unsubscribeAfterMs: undefined,
    durationMs: undefined,
    untilMessages: undefined,
    untilTopicCount: new Map(),
    untilStatus: [],
    timeoutMs: undefined,
    counts: false,
    publish: [],
    publishTopic: "teejet/valve/command",
    publishEncoding: "cdr",
    publishSchemaName: undefined,
    idl: undefined,
    publishDelayMs: 200,
    publishIntervalMs: 0,
    neverRead: false,
    pauseMs: undefined,
  };
  const flags = {
    "--counts": () => (args.counts = true),
    "--never-read": () => (args.neverRead = true),
  };
  const valued = {
    "--subprotocol": (v) => (args.subprotocol = v),
    "--token": (v) => (args.token = v),
    "--subscribe": (v) => args.subscribe.push(v),
    "--subscribe-after-ms": (v, o) => (args.subscribeAfterMs = count(o, v)),
    "--unsubscribe-after-ms": (v, o) => (args.unsubscribeAfterMs = count(o, v)),
    "--duration-ms": (v, o) => (args.durationMs = count(o, v)),
    "--until-messages": (v, o) => (args.untilMessages = count(o, v)),
    "--until-topic-count": (v, o) => {
      const at = v.lastIndexOf("=");
      if (at <= 0) {
        throw new UsageError(`${o} wants TOPIC=N, not '${v}'`);
      }
      args.untilTopicCount.set(v.slice(0, at), count(o, v.slice(at + 1)));
    },
    "--timeout-ms": (v, o) => (args.timeoutMs = count(o, v)),
    "--until-status": (v) => args.untilStatus.push(v),
    "--publish": (v, o) => {
      let message;
      try {
        message = JSON.parse(v);
      } catch (error) {
        throw new UsageError(`${o} '${v}': not JSON (${firstLine(error)})`);
      }
      if (message === null || typeof message !== "object" || Array.isArray(message)) {
        throw new UsageError(`${o} '${v}': wants a JSON object`);
      }
      args.publish.push(message);
    },
    "--publish-topic": (v) => (args.publishTopic = v),
    "--publish-encoding": (v) => (args.publishEncoding = v),
    "--publish-schema-name": (v) => (args.publishSchemaName = v),
    "--idl": (v) => (args.idl = v),
    "--publish-delay-ms": (v, o) => (args.publishDelayMs = count(o, v)),
    "--publish-interval-ms": (v, o) => (args.publishIntervalMs = count(o, v)),
    "--pause-ms": (v, o) => (args.pauseMs = count(o, v)),
  };
  for (let i = 0; i < argv.length; i++) {
    const arg = argv[i];
    const eq = arg.startsWith("--") ? arg.indexOf("=") : -1;
    const name = eq > 0 ? arg.slice(0, eq) : arg;
    if (name === "-h" || name === "--help") {
      process.stdout.write(`${USAGE}\n`);
      process.exit(0);
    } else if (flags[name] && eq < 0) {
      flags[name]();
    } else if (valued[name]) {
      let value;
      if (eq > 0) {
        value = arg.slice(eq + 1);
      } else if (i + 1 < argv.length) {
        value = argv[++i];
      } else {
        throw new UsageError(`${name} wants a value`);
      }
      valued[name](value, name);
    } else if (arg.startsWith("-")) {
      throw new UsageError(`unknown option '${arg}'`);
    } else if (args.url === undefined) {
      args.url = arg;
    } else {
      throw new UsageError(`more than one URL ('${args.url}', '${arg}')`);
    }
  }
  if (args.url === undefined) {
    throw new UsageError("no URL given");
  }
  let url;
  try {
    url = new URL(args.url);
  } catch {
    throw new UsageError(`'${args.url}' is not a URL`);
  }
  if (url.protocol !== "ws:" && url.protocol !== "wss:") {
    throw new UsageError(`'${args.url}' is not a ws:// URL`);
  }
  if (args.token !== undefined) {
    // encodeURIComponent, not URLSearchParams: a space must travel as %20, which every server
    // decodes, rather than '+', which only form decoders read as a space.
    const query = url.search.length > 1 ? `${url.search}&` : "?";
    url.search = `${query}token=${encodeURIComponent(args.token)}`;
  }
  args.connectUrl = url.toString();
  // Error lines must not leak the token.
  args.shownUrl = `${url.origin}${url.pathname}`;
  if (args.neverRead) {
    if (args.durationMs === undefined) {
      throw new UsageError("--never-read wants --duration-ms: how long to stay connected");
    }
    if (
      args.untilMessages !== undefined ||
      args.untilTopicCount.size > 0 ||
      args.untilStatus.length > 0
    ) {
      throw new UsageError("--never-read reads nothing, so --until-* could never be met");
    }
  }
  if (args.publish.length > 0 && args.publishEncoding === "cdr") {
    if ((args.publishSchemaName === undefined) !== (args.idl === undefined)) {
      throw new UsageError("--publish-schema-name and --idl go together");
    }
    if (args.idl !== undefined) {
      try {
        args.idlText = fs.readFileSync(args.idl, "utf8");
      } catch (error) {
        throw new UsageError(`--idl ${args.idl}: ${error.code ?? firstLine(error)}`);
      }
    }
  }
  if (args.timeoutMs === undefined) {
    args.timeoutMs = Math.max(DEFAULT_TIMEOUT_MS, (args.durationMs ?? 0) + 5000);
  }
  return args;
}

function globToRegExp(glob) {
  const escaped = glob.replace(/[.+?^${}()|[\]\\]/g, "\\$&").replace(/\*/g, ".*");
  return new RegExp(`^${escaped}$`);
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

function emit(event) {
  process.stdout.write(`${JSON.stringify(event)}\n`);
}

// Waiting for the pipe: process.exit() would cut off what is still buffered.
async function drainStdout() {
  if (process.stdout.writableNeedDrain) {
    await new Promise((resolve) => process.stdout.once("drain", resolve));
  }
}

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// --- The schema side: parsing once per IDL text, a reader or writer once per type. ----------

const parsedIdl = new Map();

function definitionsOf(schema) {
  let definitions = parsedIdl.get(schema);
  if (!definitions) {
    definitions = parseIDL(schema);
    parsedIdl.set(schema, definitions);
  }
  return definitions;
}

const readers = new Map();

function readerFor(channel) {
  if (channel.encoding !== "cdr") {
    throw new Error(`message encoding '${channel.encoding}', not 'cdr'`);
  }
  if (channel.schemaEncoding !== "omgidl") {
    throw new Error(`schema encoding '${channel.schemaEncoding}', not 'omgidl'`);
  }
  const key = `${channel.schemaName}\0${channel.schema}`;
  let reader = readers.get(key);
  if (!reader) {
    reader = new MessageReader(channel.schemaName, definitionsOf(channel.schema));
    readers.set(key, reader);
  }
  return reader;
}

// MessageWriter writes 0 in place of anything of the wrong JS type (a uint64 given as a decimal
// string, a number given as a string) and ignores unknown fields, so a typo in a test would go
// out as a valid command. Every value is checked and converted here instead, and the fields not
// given get their zero, so that what the "published" line shows is exactly what was sent.
function completeMessage(byName, typeName, value, path) {
  const definition = byName.get(typeName);
  if (!definition || definition.aggregatedKind !== "struct") {
    throw new PublishError(`${path || typeName}: '${typeName}' is not a struct of the schema`);
  }
  if (value === undefined) {
    value = {};
  }
  if (value === null || typeof value !== "object" || Array.isArray(value)) {
    throw new PublishError(
      `${path || typeName}: ${typeName} wants an object, not ${JSON.stringify(value)}`,
    );
  }
  const fields = definition.definitions.filter((field) => field.isConstant !== true);
  const names = new Set(fields.map((field) => field.name));
  for (const key of Object.keys(value)) {
    if (!names.has(key)) {
      throw new PublishError(
        `${path ? `${path}: ` : ""}${typeName} has no field '${key}' ` +
          `(it has ${[...names].join(", ")})`,
      );
    }
  }
  const out = {};
  for (const field of fields) {
    const where = path ? `${path}.${field.name}` : field.name;
    const given = value[field.name];
    if (field.isArray === true) {
      if (given !== undefined && !Array.isArray(given)) {
        throw new PublishError(`${where}: wants an array, not ${JSON.stringify(given)}`);
      }
      const items = given ?? [];
      const fixed = field.arrayLengths?.[0];
      if (fixed !== undefined && items.length > fixed) {
        throw new PublishError(`${where}: an array of ${fixed}, given ${items.length}`);
      }
      const length = fixed ?? items.length;
      out[field.name] = Array.from({ length }, (_, i) =>
        completeValue(byName, field, items[i], `${where}[${i}]`),
      );
    } else {
      out[field.name] = completeValue(byName, field, given, where);
    }
  }
  return out;
}

function completeValue(byName, field, given, where) {
  if (field.isComplex === true) {
    return completeMessage(byName, field.type, given, where);
  }
  const wrong = (what) =>
    new PublishError(`${where}: wants ${what} (${field.type}), not ${JSON.stringify(given)}`);
  switch (field.type) {
    case "bool":
      if (given === undefined) return field.defaultValue ?? false;
      if (typeof given !== "boolean") throw wrong("true or false");
      return given;
    case "string":
    case "wstring":
      if (given === undefined) return field.defaultValue ?? "";
      if (typeof given !== "string") throw wrong("a string");
      return given;
    case "int64":
    case "uint64":
      if (given === undefined) return BigInt(field.defaultValue ?? 0);
      if (typeof given === "number" && Number.isSafeInteger(given)) return BigInt(given);
      if (typeof given === "string" && /^-?\d+$/.test(given)) return BigInt(given);
      throw wrong("an integer or a decimal string");
    case "float32":
    case "float64":
      if (given === undefined) return field.defaultValue ?? 0;
      if (typeof given !== "number") throw wrong("a number");
      return given;
    default:
      // Integers, enums (uint32 with enumType) and char (the parser makes it uint8).
      if (given === undefined) return field.defaultValue ?? 0;
      if (!Number.isInteger(given)) {
        throw wrong(field.enumType ? `the number of a ${field.enumType} enumerator` : "an integer");
      }
      return given;
  }
}

// --- The session. -------------------------------------------------------------------------

function run(args) {
  const patterns = args.subscribe.map(globToRegExp);
  const hasUntil =
    args.untilMessages !== undefined ||
    args.untilTopicCount.size > 0 ||
    args.untilStatus.length > 0;
  const state = {
    startedAt: performance.now(),
    openedAt: undefined,
    serverInfo: undefined,
    advertised: false,
    channels: new Map(),
    subscriptions: new Map(),
    subscribedChannels: new Map(),
    subscribeGateOpen: false,
    subscribedOnce: false,
    unsubscribedAll: false,
    messages: 0,
    bytes: 0,
    afterUnsubscribe: 0,
    unsubscribedAt: undefined, // performance.now() of the unsubscribe
    perTopic: new Map(),
    published: 0,
    publishesDone: args.publish.length === 0,
    errors: 0,
    finishing: false,
    closingOurselves: false,
    timers: [],
    statuses: [],
  };

  const error = (message) => {
    state.errors++;
    emit({ event: "error", message });
  };
  const later = (ms, what) => state.timers.push(setTimeout(what, ms));

  const untilMet = () => {
    if (args.untilMessages !== undefined && state.messages < args.untilMessages) {
      return false;
    }
    for (const [topic, n] of args.untilTopicCount) {
      if ((state.perTopic.get(topic) ?? 0) < n) {
        return false;
      }
    }
    return args.untilStatus.every((text) => state.statuses.some((m) => m.includes(text)));
  };

  // What the run still waits for, for the timeout's and an early close's error line.
  const awaited = () => {
    const what = [];
    if (state.openedAt === undefined) what.push("the WebSocket open");
    else if (!state.advertised && (patterns.length > 0 || args.publish.length > 0)) {
      what.push("the server's advertise");
    }
    if (args.untilMessages !== undefined && state.messages < args.untilMessages) {
      what.push(`--until-messages ${args.untilMessages} (got ${state.messages})`);
    }
    for (const [topic, n] of args.untilTopicCount) {
      const got = state.perTopic.get(topic) ?? 0;
      if (got < n) what.push(`--until-topic-count ${topic}=${n} (got ${got})`);
    }
    for (const text of args.untilStatus) {
      if (!state.statuses.some((m) => m.includes(text))) what.push(`--until-status '${text}'`);
    }
    if (!state.publishesDone) {
      what.push(`the --publish messages (${state.published} of ${args.publish.length} sent)`);
    }
    if (what.length === 0) {
      what.push(
        args.durationMs !== undefined ? `--duration-ms ${args.durationMs}` : "the server to close",
      );
    }
    return what.join(", ");
  };

  const ws = new WebSocket(args.connectUrl, [args.subprotocol]);
  const client = new FoxgloveClient({ ws });

  const finish = async (code) => {
    if (state.finishing) return;
    state.finishing = true;
    for (const timer of state.timers) clearTimeout(timer);
    if (args.counts || args.neverRead) {
      const seconds =
        state.openedAt === undefined ? 0 : (performance.now() - state.openedAt) / 1000;
      emit({
        event: "counts",
        per_topic: Object.fromEntries(state.perTopic),
        messages: state.messages,
        bytes: state.bytes,
        seconds: Number(seconds.toFixed(3)),
        ...(args.unsubscribeAfterMs !== undefined
          ? { after_unsubscribe: state.afterUnsubscribe }
          : {}),
      });
    }
    if (ws.readyState === WebSocket.OPEN || ws.readyState === WebSocket.CONNECTING) {
      state.closingOurselves = true;
      if (args.neverRead || ws.readyState === WebSocket.CONNECTING) {
        // The server's close frame sits behind everything it buffered for us: waiting for it
        // would mean reading it all.
        ws.terminate();
      } else {
        const closed = new Promise((resolve) => ws.once("close", resolve));
        ws.close(1000, "done");
        await Promise.race([closed, sleep(1000)]);
        ws.terminate();
      }
    }
    await drainStdout();
    process.exit(code !== 0 ? code : state.errors > 0 ? 1 : 0);
  };

  const checkDone = () => {
    if (state.finishing || !state.publishesDone) return;
    if (hasUntil ? untilMet() : args.durationMs === undefined && args.publish.length > 0) {
      finish(0);
    }
  };

  later(args.timeoutMs, () => {
    error(`timed out after --timeout-ms ${args.timeoutMs} waiting for ${awaited()}`);
    finish(3);
  });

  const subscribeMatching = () => {
    if (!state.subscribeGateOpen || state.unsubscribedAll || state.finishing) return;
    const fresh = [];
    for (const channel of state.channels.values()) {
      if (
        state.subscribedChannels.has(channel.id) ||
        !patterns.some((re) => re.test(channel.topic))
      ) {
        continue;
      }
      const id = client.subscribe(channel.id);
      state.subscriptions.set(id, { channel, active: true });
      state.subscribedChannels.set(channel.id, id);
      fresh.push({ id, channel: channel.id, topic: channel.topic });
    }
    if (fresh.length === 0) return;
    emit({ event: "subscribe", subscriptions: fresh });
    if (state.subscribedOnce) return;
    state.subscribedOnce = true;
    if (args.neverRead || args.pauseMs !== undefined) {
      // ws.pause(), not the socket's own pause: ws resumes its socket whenever its frame parser
      // drains, unless it knows it is paused.
      ws.pause();
      if (args.pauseMs !== undefined) later(args.pauseMs, () => ws.resume());
    }
    if (args.unsubscribeAfterMs !== undefined) {
      later(args.unsubscribeAfterMs, () => {
        const ids = [];
        for (const [id, subscription] of state.subscriptions) {
          if (!subscription.active) continue;
          client.unsubscribe(id);
          subscription.active = false;
          ids.push(id);
        }
        state.subscribedChannels.clear();
        state.unsubscribedAll = true;
        state.unsubscribedAt = performance.now();
        emit({ event: "unsubscribe", subscriptions: ids });
      });
    }
  };

  const publishAll = async () => {
    const serverChannel = [...state.channels.values()].find((c) => c.topic === args.publishTopic);
    let schemaName;
    let schema;
    if (serverChannel) {
      ({ schemaName, schema } = serverChannel);
    } else if (args.publishEncoding !== "cdr") {
      schemaName = args.publishSchemaName ?? "";
      schema = args.idlText ?? "";
    } else if (args.idlText !== undefined) {
      schemaName = args.publishSchemaName;
      schema = args.idlText;
    } else {
      error(
        `cannot publish on '${args.publishTopic}': the server did not advertise it, and no ` +
          "--publish-schema-name with --idl gives its schema",
      );
      finish(1);
      return;
    }
    if (!(state.serverInfo?.capabilities ?? []).includes("clientPublish")) {
      emit({
        event: "warning",
        message: "the server did not declare the clientPublish capability",
      });
    }
    const encodings = state.serverInfo?.supportedEncodings;
    if (Array.isArray(encodings) && !encodings.includes(args.publishEncoding)) {
      emit({
        event: "warning",
        message:
          `the server's supportedEncodings ${JSON.stringify(encodings)} lack ` +
          `'${args.publishEncoding}'`,
      });
    }

    // Everything is encoded before anything is sent: a bad --publish must not leave half a
    // sequence of commands on the bus.
    const outgoing = [];
    try {
      if (args.publishEncoding === "cdr") {
        const definitions = definitionsOf(schema);
        const byName = new Map(definitions.map((d) => [d.name, d]));
        const writer = new MessageWriter(schemaName, definitions);
        for (const message of args.publish) {
          const full = completeMessage(byName, schemaName, message, "");
          outgoing.push({ data: full, bytes: writer.writeMessage(full) });
        }
      } else {
        for (const message of args.publish) {
          outgoing.push({
            data: message,
            bytes: new TextEncoder().encode(JSON.stringify(message)),
          });
        }
      }
    } catch (e) {
      error(
        `cannot encode --publish as '${schemaName}' for '${args.publishTopic}': ${firstLine(e)}`,
      );
      finish(1);
      return;
    }

    const channel = client.advertise({
      topic: args.publishTopic,
      encoding: args.publishEncoding,
      schemaName,
      schema,
      schemaEncoding: "omgidl",
    });
    emit({
      event: "clientAdvertise",
      channel,
      topic: args.publishTopic,
      encoding: args.publishEncoding,
      schemaName,
    });
    await sleep(args.publishDelayMs);
    for (let i = 0; i < outgoing.length; i++) {
      if (state.finishing) return;
      if (i > 0 && args.publishIntervalMs > 0) {
        await sleep(args.publishIntervalMs);
        if (state.finishing) return;
      }
      client.sendMessage(channel, outgoing[i].bytes);
      state.published++;
      emit({
        event: "published",
        topic: args.publishTopic,
        channel,
        data: plain(outgoing[i].data),
      });
    }
    // Sent means handed to the kernel: leaving earlier could drop the last command unsent.
    while (ws.bufferedAmount > 0 && !state.finishing) {
      await sleep(5);
    }
    state.publishesDone = true;
    checkDone();
  };

  client.on("open", () => {
    state.openedAt = performance.now();
    emit({ event: "open", protocol: ws.protocol });
    if (ws.protocol !== args.subprotocol) {
      // ws refuses this itself during the handshake; this is the belt to its braces.
      error(
        `the server selected subprotocol '${ws.protocol}', not the offered '${args.subprotocol}'`,
      );
      finish(1);
      return;
    }
    if (args.durationMs !== undefined) {
      later(args.durationMs, () => {
        if (hasUntil && !untilMet()) {
          error(`--duration-ms ${args.durationMs} elapsed before ${awaited()}`);
          finish(3);
        } else if (!state.publishesDone) {
          error(`--duration-ms ${args.durationMs} elapsed before ${awaited()}`);
          finish(3);
        } else {
          finish(0);
        }
      });
    }
  });

  client.on("error", (e) => {
    if (state.finishing) return;
    const text = firstLine(e);
    if (state.openedAt === undefined) {
      const hint = /subprotocol/i.test(text) ? ` (offered '${args.subprotocol}')` : "";
      error(`connecting to ${args.shownUrl}: ${text}${hint}`);
    } else {
      error(text);
    }
  });

  client.on("close", (event) => {
    if (state.finishing || state.closingOurselves) return;
    if (state.openedAt === undefined) {
      // The handshake failed; the error line said why.
      finish(1);
      return;
    }
    emit({ event: "close", code: event.code, reason: event.reason });
    const waiting =
      args.durationMs !== undefined || (hasUntil && !untilMet()) || !state.publishesDone;
    if (waiting) {
      error(`the server closed the connection (code ${event.code}) before ${awaited()}`);
      finish(1);
    } else {
      finish(0);
    }
  });

  client.on("serverInfo", (message) => {
    const { op: _op, ...rest } = message;
    state.serverInfo = message;
    emit({ event: "serverInfo", ...rest });
  });

  client.on("status", (message) => {
    const { op: _op, ...rest } = message;
    emit({ event: "status", ...rest });
    state.statuses.push(String(message.message));
    checkDone();
  });

  client.on("removeStatus", (message) => {
    emit({ event: "removeStatus", statusIds: message.statusIds });
  });

  client.on("time", (message) => {
    emit({ event: "time", timestamp: message.timestamp.toString() });
  });

  client.on("advertise", (channels) => {
    if (state.finishing) return;
    if (!Array.isArray(channels)) {
      error(`advertise without a channels array: ${JSON.stringify(channels)}`);
      return;
    }
    const shown = [];
    for (const channel of channels) {
      const problems = [];
      if (!Number.isInteger(channel?.id) || channel.id < 0)
        problems.push("id not a non-negative integer");
      for (const key of ["topic", "encoding", "schemaName", "schema"]) {
        if (typeof channel?.[key] !== "string") problems.push(`${key} not a string`);
      }
      if (channel?.schemaEncoding !== undefined && typeof channel.schemaEncoding !== "string") {
        problems.push("schemaEncoding not a string");
      }
      if (problems.length > 0) {
        error(
          `advertised channel ${JSON.stringify(channel?.id)} '${channel?.topic}': ` +
            problems.join(", "),
        );
      }
      const { schema, ...rest } = channel ?? {};
      shown.push({
        ...rest,
        schema_bytes: typeof schema === "string" ? Buffer.byteLength(schema) : 0,
      });
      if (Number.isInteger(channel?.id)) state.channels.set(channel.id, channel);
    }
    emit({ event: "advertise", channels: shown });
    const first = !state.advertised;
    state.advertised = true;
    if (first) {
      if (args.subscribeAfterMs > 0) {
        later(args.subscribeAfterMs, () => {
          state.subscribeGateOpen = true;
          subscribeMatching();
        });
      } else {
        state.subscribeGateOpen = true;
      }
      if (args.publish.length > 0) {
        publishAll().catch((e) => {
          error(`publishing: ${firstLine(e)}`);
          finish(1);
        });
      }
    }
    subscribeMatching();
    checkDone();
  });

  client.on("unadvertise", (channelIds) => {
    if (state.finishing) return;
    emit({ event: "unadvertise", channelIds });
    for (const id of channelIds ?? []) {
      state.channels.delete(id);
      const subscription = state.subscribedChannels.get(id);
      if (subscription !== undefined) {
        // The server drops the subscription with the channel; a message for it after this is
        // still attributable (subscription ids are never reused) and still decoded.
        state.subscribedChannels.delete(id);
      }
    }
  });

  for (const name of [
    "advertiseServices",
    "unadvertiseServices",
    "parameterValues",
    "serviceCallResponse",
    "connectionGraphUpdate",
    "fetchAssetResponse",
    "serviceCallFailure",
  ]) {
    client.on(name, (message) => emit({ event: name, message: plain(message) }));
  }

  client.on("message", ({ subscriptionId, timestamp, data }) => {
    if (state.finishing) return;
    const subscription = state.subscriptions.get(subscriptionId);
    if (!subscription) {
      error(`message data for subscription ${subscriptionId}, which this client never made`);
      return;
    }
    const { channel } = subscription;
    state.messages++;
    state.bytes += data.byteLength;
    state.perTopic.set(channel.topic, (state.perTopic.get(channel.topic) ?? 0) + 1);
    if (!subscription.active) state.afterUnsubscribe++;
    let decoded;
    try {
      decoded = readerFor(channel).readMessage(
        new Uint8Array(data.buffer, data.byteOffset, data.byteLength),
      );
    } catch (e) {
      error(
        `channel ${channel.id} '${channel.topic}' (subscription ${subscriptionId}): ` +
          `cannot decode ${data.byteLength} bytes as '${channel.schemaName}': ${firstLine(e)}`,
      );
    }
    if (!args.counts && decoded !== undefined) {
      emit({
        event: "message",
        topic: channel.topic,
        channel: channel.id,
        subscription: subscriptionId,
        timestamp: timestamp.toString(),
        data: plain(decoded),
        ...(subscription.active
          ? {}
          : {
              unsubscribed: true,
              ms_after_unsubscribe: Math.round(performance.now() - state.unsubscribedAt),
            }),
      });
    }
    checkDone();
  });
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
  if (!(error instanceof UsageError)) throw error;
  process.stderr.write(`foxglove-client: ${error.message}\n${USAGE}\n`);
  process.exit(2);
}
run(args);
