#!/usr/bin/env node
// A check of foxglove-client.mjs against mock servers, before anyone trusts it to judge
// teejet-web: each check starts its own FoxgloveServer (@foxglove/ws-protocol's, on `ws`) on
// 127.0.0.1 with an ephemeral port, advertising channels with the project's real IDL, and runs the
// client against it as the tests will.
//
// Usage: self_test.mjs      exit 0 with a one-line summary when every check passes; otherwise 1,
//                           naming each failed check (with the client's output on stderr).

import assert from "node:assert/strict";
import { spawn } from "node:child_process";
import { once } from "node:events";
import fs from "node:fs";
import path from "node:path";
import process from "node:process";
import { fileURLToPath } from "node:url";

import { WebSocketServer } from "ws";
// CommonJS packages: only their default import (module.exports) reaches every export.
import wsProtocol from "@foxglove/ws-protocol";
import omgidlParser from "@foxglove/omgidl-parser";
import omgidlSerialization from "@foxglove/omgidl-serialization";

const { FoxgloveServer } = wsProtocol;
const { parseIDL } = omgidlParser;
const { MessageReader, MessageWriter } = omgidlSerialization;

const HERE = path.dirname(fileURLToPath(import.meta.url));
const CLIENT = path.join(HERE, "foxglove-client.mjs");
const IDL_PATH = path.join(HERE, "..", "..", "idl", "teejet", "valve.idl");
const IDL = fs.readFileSync(IDL_PATH, "utf8");
const DEFINITIONS = parseIDL(IDL);

const SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"];
const POSITION_TOPIC = "teejet/valve/position";
const COMMAND_TOPIC = "teejet/valve/command";
const POSITION = { serial: 1, degrees: 12.5, received_ns: 123n };
const POSITION_BYTES = new MessageWriter("teejet::ValvePosition", DEFINITIONS).writeMessage(
  POSITION,
);
const FIRST_TIMESTAMP = 1000n;
const MESSAGES_PER_SUBSCRIBE = 3;
const CLIENT_DEADLINE_MS = 15000;

class CheckFailed extends Error {}

function fail(message) {
  throw new CheckFailed(message);
}

function expectEqual(actual, expected, what) {
  try {
    assert.deepStrictEqual(actual, expected);
  } catch {
    fail(`${what}: got ${JSON.stringify(actual)}, expected ${JSON.stringify(expected)}`);
  }
}

// Polls with a deadline: every wait here ends, in success or in a named failure.
async function waitFor(predicate, ms, what) {
  const deadline = Date.now() + ms;
  while (!predicate()) {
    if (Date.now() > deadline) fail(`${what} did not happen within ${ms} ms`);
    await new Promise((resolve) => setTimeout(resolve, 10));
  }
}

const ALL_CHANNELS = [
  { topic: POSITION_TOPIC, schemaName: "teejet::ValvePosition" },
  { topic: COMMAND_TOPIC, schemaName: "teejet::ValveCommand" },
];

// What a mock server does when a channel gets its first subscriber.
const sendPositions = (mock, channelId) => {
  if (channelId !== mock.channelIds.get(POSITION_TOPIC)) return;
  for (let i = 0n; i < BigInt(MESSAGES_PER_SUBSCRIBE); i++) {
    mock.server.sendMessage(channelId, FIRST_TIMESTAMP + i, POSITION_BYTES);
  }
};

async function startMock({
  selectProtocol = true,
  channels = ALL_CHANNELS,
  onSubscribe = sendPositions,
} = {}) {
  const server = new FoxgloveServer({
    name: "self-test mock",
    capabilities: ["clientPublish"],
    supportedEncodings: ["cdr"],
  });
  const mock = {
    server,
    channelIds: new Map(),
    connections: [],
    requests: [],
    offered: [],
    clientChannels: [],
    published: [],
    unsubscribed: [],
    errors: [],
  };
  // The mock selects whatever single subprotocol the client offers, when it is one of the two
  // the project serves; with selectProtocol false it selects none, as a server that knows none.
  const wss = new WebSocketServer({
    host: "127.0.0.1",
    port: 0,
    handleProtocols: (protocols) => {
      if (!selectProtocol) return false;
      return [...protocols].find((p) => SUBPROTOCOLS.includes(p)) ?? false;
    },
  });
  await once(wss, "listening");
  mock.wss = wss;
  mock.url = `ws://127.0.0.1:${wss.address().port}/`;
  for (const { topic, schemaName } of channels) {
    mock.channelIds.set(
      topic,
      server.addChannel({
        topic,
        encoding: "cdr",
        schemaName,
        schema: IDL,
        schemaEncoding: "omgidl",
      }),
    );
  }
  wss.on("connection", (connection, request) => {
    const record = { connection, openedAt: Date.now(), closedAt: undefined };
    mock.connections.push(record);
    mock.requests.push(request.url);
    mock.offered.push(request.headers["sec-websocket-protocol"]);
    server.handleConnection(
      connection,
      `${request.socket.remoteAddress}:${request.socket.remotePort}`,
    );
    server.sendStatus({ level: 1, message: "self-test warning", id: "self-test-1" }, connection);
    connection.on("close", () => (record.closedAt = Date.now()));
  });
  server.on("subscribe", (channelId) => onSubscribe(mock, channelId));
  // The library reports a disconnect as an unsubscribe too: only one while the client is still
  // connected is the client's own.
  server.on("unsubscribe", (channelId) => {
    if (mock.connections.some(({ connection }) => connection.readyState === connection.OPEN)) {
      mock.unsubscribed.push(channelId);
    }
  });
  server.on("advertise", (channel) => mock.clientChannels.push(channel));
  server.on("message", ({ channel, data }) =>
    mock.published.push({ channel, data: Uint8Array.from(data) }),
  );
  server.on("error", (error) => mock.errors.push(error));
  return mock;
}

async function stopMock(mock) {
  for (const { connection } of mock.connections) connection.terminate();
  await new Promise((resolve) => mock.wss.close(resolve));
}

// Runs the client to its end (or kills it at the deadline), every stdout line parsed as JSON.
async function runClient(args, deadlineMs = CLIENT_DEADLINE_MS) {
  const child = spawn(process.execPath, [CLIENT, ...args], { stdio: ["ignore", "pipe", "pipe"] });
  let stdout = "";
  let stderr = "";
  child.stdout.setEncoding("utf8").on("data", (chunk) => (stdout += chunk));
  child.stderr.setEncoding("utf8").on("data", (chunk) => (stderr += chunk));
  const startedAt = Date.now();
  let killed = false;
  const timer = setTimeout(() => {
    killed = true;
    child.kill("SIGKILL");
  }, deadlineMs);
  const [code, signal] = await once(child, "close");
  clearTimeout(timer);
  const result = { code, signal, stdout, stderr, ms: Date.now() - startedAt, lines: [] };
  runClient.last = result;
  if (killed) fail(`the client was still running after ${deadlineMs} ms`);
  for (const [i, line] of stdout.split("\n").entries()) {
    if (line === "") continue;
    try {
      result.lines.push(JSON.parse(line));
    } catch {
      fail(`stdout line ${i + 1} is not JSON: ${line}`);
    }
  }
  result.events = (name) => result.lines.filter((line) => line.event === name);
  result.only = (name) => {
    const found = result.events(name);
    if (found.length !== 1) fail(`expected one '${name}' line, got ${found.length}`);
    return found[0];
  };
  return result;
}

function expectExit(result, code) {
  if (result.code !== code) {
    fail(`the client exited ${result.code ?? result.signal}, expected ${code}`);
  }
}

function expectNoErrors(result) {
  const errors = result.events("error");
  if (errors.length > 0) fail(`error lines: ${JSON.stringify(errors)}`);
}

function expectPositions(result, mock) {
  const messages = result.events("message");
  expectEqual(messages.length, MESSAGES_PER_SUBSCRIBE, "number of message lines");
  const subscription = result
    .events("subscribe")
    .flatMap((line) => line.subscriptions)
    .find((s) => s.topic === POSITION_TOPIC);
  if (!subscription) fail(`no subscribe line for ${POSITION_TOPIC}`);
  messages.forEach((message, i) =>
    expectEqual(
      message,
      {
        event: "message",
        topic: POSITION_TOPIC,
        channel: mock.channelIds.get(POSITION_TOPIC),
        subscription: subscription.id,
        timestamp: String(FIRST_TIMESTAMP + BigInt(i)),
        data: { serial: 1, degrees: 12.5, received_ns: "123" },
      },
      `message line ${i + 1}`,
    ),
  );
}

function expectHandshakeLines(result, mock, protocol) {
  expectEqual(mock.offered, [protocol], "subprotocols the client offered");
  expectEqual(result.only("open"), { event: "open", protocol }, "open line");
  const info = result.only("serverInfo");
  expectEqual(info.name, "self-test mock", "serverInfo name");
  expectEqual(info.capabilities, ["clientPublish"], "serverInfo capabilities");
  expectEqual(
    result.only("status"),
    { event: "status", level: 1, message: "self-test warning", id: "self-test-1" },
    "status line",
  );
  const advertise = result.only("advertise");
  expectEqual(
    advertise.channels,
    ALL_CHANNELS.map(({ topic, schemaName }) => ({
      topic,
      encoding: "cdr",
      schemaName,
      schemaEncoding: "omgidl",
      id: mock.channelIds.get(topic),
      schema_bytes: Buffer.byteLength(IDL),
    })),
    "advertise line",
  );
}

const COMMAND_ZERO = {
  serial: 0,
  command_id: 0,
  origin: "",
  kind: 0,
  speed_percent: 0,
  direction: 0,
  degrees: 0,
  milliseconds: 0,
  telemetry: 0,
  resend_tenths: 0,
  bit_rate: 0,
};

// The published commands as the mock server decodes them, with the schema the client advertised.
function decodedPublished(mock) {
  return mock.published.map(({ channel, data }) => {
    expectEqual(
      {
        topic: channel.topic,
        encoding: channel.encoding,
        schemaName: channel.schemaName,
        schemaEncoding: channel.schemaEncoding,
        schemaIsTheIdl: channel.schema === IDL,
      },
      {
        topic: COMMAND_TOPIC,
        encoding: "cdr",
        schemaName: "teejet::ValveCommand",
        schemaEncoding: "omgidl",
        schemaIsTheIdl: true,
      },
      "the client's advertised channel",
    );
    return new MessageReader(channel.schemaName, parseIDL(channel.schema)).readMessage(data);
  });
}

const checks = [];
const check = (name, body) => checks.push({ name, body });

for (const protocol of SUBPROTOCOLS) {
  check(`subprotocol ${protocol}: selected, decoded, token in the URL`, async () => {
    const mock = await startMock();
    try {
      const token = "s3cret &?/x";
      const untilArgs =
        protocol === SUBPROTOCOLS[0]
          ? ["--until-messages", String(MESSAGES_PER_SUBSCRIBE)]
          : ["--until-topic-count", `${POSITION_TOPIC}=${MESSAGES_PER_SUBSCRIBE}`];
      const result = await runClient([
        mock.url,
        "--subprotocol",
        protocol,
        "--subscribe",
        "teejet/*/position",
        "--token",
        token,
        ...untilArgs,
      ]);
      expectExit(result, 0);
      expectNoErrors(result);
      expectHandshakeLines(result, mock, protocol);
      expectPositions(result, mock);
      expectEqual(
        result.only("subscribe").subscriptions.map((s) => s.topic),
        [POSITION_TOPIC],
        "topics the glob subscribed",
      );
      expectEqual(new URL(mock.requests[0], "ws://x").searchParams.get("token"), token, "token");
      if (!mock.requests[0].includes("%20"))
        fail(`a space in the token not sent as %20: ${mock.requests[0]}`);
    } finally {
      await stopMock(mock);
    }
  });
}

check("--counts: a counts line, no message lines", async () => {
  const mock = await startMock();
  try {
    const result = await runClient([
      mock.url,
      "--subscribe",
      "*",
      "--counts",
      "--until-messages",
      String(MESSAGES_PER_SUBSCRIBE),
    ]);
    expectExit(result, 0);
    expectNoErrors(result);
    expectEqual(result.events("message").length, 0, "message lines");
    const counts = result.only("counts");
    expectEqual(
      { per_topic: counts.per_topic, messages: counts.messages, bytes: counts.bytes },
      {
        per_topic: { [POSITION_TOPIC]: MESSAGES_PER_SUBSCRIBE },
        messages: MESSAGES_PER_SUBSCRIBE,
        bytes: MESSAGES_PER_SUBSCRIBE * POSITION_BYTES.byteLength,
      },
      "counts",
    );
    if (typeof counts.seconds !== "number") fail(`counts.seconds is ${counts.seconds}`);
    if (result.lines.at(-1).event !== "counts") fail("the counts line is not the last");
  } finally {
    await stopMock(mock);
  }
});

check("--publish: the server's schema, in order, every field as given or zero", async () => {
  const mock = await startMock();
  try {
    const first = {
      serial: 7,
      command_id: 42,
      origin: "self-test",
      kind: 2,
      speed_percent: 50,
      direction: 1,
      degrees: 90.5,
    };
    const second = { serial: 7, command_id: 43 };
    const result = await runClient([
      mock.url,
      "--publish",
      JSON.stringify(first),
      "--publish",
      JSON.stringify(second),
      "--publish-delay-ms",
      "50",
    ]);
    expectExit(result, 0);
    expectNoErrors(result);
    const expected = [
      { ...COMMAND_ZERO, ...first },
      { ...COMMAND_ZERO, ...second },
    ];
    expectEqual(
      result.events("published").map(({ topic, data }) => ({ topic, data })),
      expected.map((data) => ({ topic: COMMAND_TOPIC, data })),
      "published lines",
    );
    await waitFor(() => mock.published.length >= 2, 5000, "the mock receiving both commands");
    expectEqual(decodedPublished(mock), expected, "commands the mock decoded");
    expectEqual(mock.errors.map(String), [], "mock server errors");
  } finally {
    await stopMock(mock);
  }
});

check("--publish with --idl when the server does not advertise the topic", async () => {
  const mock = await startMock({ channels: ALL_CHANNELS.slice(0, 1) });
  try {
    const command = { serial: 9, kind: 4, origin: "idl" };
    const result = await runClient([
      mock.url,
      "--publish",
      JSON.stringify(command),
      "--publish-schema-name",
      "teejet::ValveCommand",
      "--idl",
      IDL_PATH,
      "--publish-delay-ms",
      "0",
    ]);
    expectExit(result, 0);
    expectNoErrors(result);
    await waitFor(() => mock.published.length >= 1, 5000, "the mock receiving the command");
    expectEqual(
      decodedPublished(mock),
      [{ ...COMMAND_ZERO, ...command }],
      "command the mock decoded",
    );
  } finally {
    await stopMock(mock);
  }
});

check("--publish with an unknown field: error, exit 1, nothing sent", async () => {
  const mock = await startMock();
  try {
    const result = await runClient([
      mock.url,
      "--publish",
      '{"serial":7,"colour":1}',
      "--publish-delay-ms",
      "0",
    ]);
    expectExit(result, 1);
    const error = result.only("error");
    if (!error.message.includes("'colour'"))
      fail(`error line does not name the field: ${error.message}`);
    expectEqual(result.events("published").length, 0, "published lines");
    expectEqual(mock.clientChannels.length + mock.published.length, 0, "what the mock received");
  } finally {
    await stopMock(mock);
  }
});

check("--never-read: the server's send buffer fills, the client stays connected", async () => {
  const threshold = 4 << 20;
  const flood = { filledAt: undefined, sent: 0, stoppedBy: undefined };
  // Big valid messages, so that a buffer of megabytes fills in a few thousand sends.
  const big = new MessageWriter("teejet::ValveCommand", DEFINITIONS).writeMessage({
    ...COMMAND_ZERO,
    origin: "x".repeat(4096),
  });
  const mock = await startMock({
    onSubscribe: (m, channelId) => {
      const connection = m.connections[0].connection;
      const deadline = Date.now() + 10000;
      const burst = () => {
        if (connection.readyState !== connection.OPEN) return void (flood.stoppedBy = "close");
        if (connection.bufferedAmount > threshold) return void (flood.filledAt = Date.now());
        if (Date.now() > deadline) return void (flood.stoppedBy = "deadline");
        for (let i = 0; i < 200; i++) {
          m.server.sendMessage(channelId, BigInt(flood.sent++), big);
        }
        setImmediate(burst);
      };
      burst();
    },
  });
  try {
    const durationMs = 2500;
    const result = await runClient([
      mock.url,
      "--subscribe",
      COMMAND_TOPIC,
      "--never-read",
      "--duration-ms",
      String(durationMs),
    ]);
    expectExit(result, 0);
    expectNoErrors(result);
    if (flood.filledAt === undefined) {
      fail(
        `the mock's send buffer never passed ${threshold} bytes ` +
          `(stopped by ${flood.stoppedBy}, ${flood.sent} sent)`,
      );
    }
    const record = mock.connections[0];
    await waitFor(() => record.closedAt !== undefined, 5000, "the mock seeing the client close");
    const connectedMs = record.closedAt - record.openedAt;
    if (connectedMs < durationMs - 100) fail(`connected only ${connectedMs} ms of ${durationMs}`);
    if (flood.filledAt > record.closedAt) fail("the buffer filled only after the client left");
    const counts = result.only("counts");
    if (!(counts.messages < flood.sent / 2)) {
      fail(`the client read ${counts.messages} of ${flood.sent} messages: it kept reading`);
    }
  } finally {
    await stopMock(mock);
  }
});

check(
  "--unsubscribe-after-ms: the server sees the unsubscribe, the client keeps listening",
  async () => {
    const mock = await startMock();
    try {
      const result = await runClient([
        mock.url,
        "--subscribe",
        POSITION_TOPIC,
        "--unsubscribe-after-ms",
        "200",
        "--duration-ms",
        "800",
      ]);
      expectExit(result, 0);
      expectNoErrors(result);
      expectPositions(result, mock);
      const subscription = result.only("subscribe").subscriptions[0].id;
      expectEqual(result.only("unsubscribe").subscriptions, [subscription], "unsubscribe line");
      expectEqual(
        mock.unsubscribed,
        [mock.channelIds.get(POSITION_TOPIC)],
        "channels the mock saw unsubscribed",
      );
      const unsubscribeAt = result.lines.findIndex((line) => line.event === "unsubscribe");
      const lastMessageAt = result.lines.findLastIndex((line) => line.event === "message");
      if (lastMessageAt > unsubscribeAt) fail("message lines after the unsubscribe line");
    } finally {
      await stopMock(mock);
    }
  },
);

check("undecodable message data: error line, exit 1", async () => {
  const mock = await startMock({
    onSubscribe: (m, channelId) =>
      m.server.sendMessage(channelId, 5n, new Uint8Array([0, 1, 0, 0, 7])),
  });
  try {
    const result = await runClient([
      mock.url,
      "--subscribe",
      POSITION_TOPIC,
      "--until-messages",
      "1",
    ]);
    expectExit(result, 1);
    const error = result.only("error");
    if (!error.message.includes("teejet::ValvePosition")) fail(`error line: ${error.message}`);
    expectEqual(result.events("message").length, 0, "message lines");
  } finally {
    await stopMock(mock);
  }
});

check("--timeout-ms: exit 3 naming what was awaited", async () => {
  const mock = await startMock();
  try {
    const result = await runClient([
      mock.url,
      "--subscribe",
      POSITION_TOPIC,
      "--until-messages",
      "100",
      "--timeout-ms",
      "1000",
    ]);
    expectExit(result, 3);
    const error = result.only("error");
    if (!error.message.includes(`--until-messages 100 (got ${MESSAGES_PER_SUBSCRIBE})`)) {
      fail(`error line does not name what was awaited: ${error.message}`);
    }
  } finally {
    await stopMock(mock);
  }
});

for (const durationMs of [undefined, 5000]) {
  const what =
    durationMs === undefined ? "exit 0 with nothing awaited" : "exit 1 before --duration-ms";
  check(`server closes the connection: close line, ${what}`, async () => {
    const mock = await startMock({
      onSubscribe: (m) => m.connections[0].connection.close(4001, "bye"),
    });
    try {
      const result = await runClient([
        mock.url,
        "--subscribe",
        POSITION_TOPIC,
        ...(durationMs === undefined ? [] : ["--duration-ms", String(durationMs)]),
      ]);
      expectEqual(
        result.only("close"),
        { event: "close", code: 4001, reason: "bye" },
        "close line",
      );
      if (durationMs === undefined) {
        expectExit(result, 0);
        expectNoErrors(result);
      } else {
        expectExit(result, 1);
        if (!result.only("error").message.includes("before --duration-ms")) {
          fail(`error line: ${result.only("error").message}`);
        }
      }
    } finally {
      await stopMock(mock);
    }
  });
}

check("the server selects no subprotocol: error line, exit 1", async () => {
  const mock = await startMock({ selectProtocol: false });
  try {
    const result = await runClient([mock.url, "--subscribe", "*", "--duration-ms", "1000"]);
    expectExit(result, 1);
    expectEqual(result.events("open").length, 0, "open lines");
    const error = result.only("error");
    if (!/subprotocol/.test(error.message) || !error.message.includes(SUBPROTOCOLS[0])) {
      fail(`error line does not name the subprotocol: ${error.message}`);
    }
  } finally {
    await stopMock(mock);
  }
});

const failed = [];
for (const { name, body } of checks) {
  runClient.last = undefined;
  try {
    await body();
  } catch (error) {
    const reason = error instanceof CheckFailed ? error.message : error.stack;
    failed.push(name);
    process.stderr.write(`self_test: FAILED: ${name}: ${reason}\n`);
    if (runClient.last) {
      process.stderr.write(
        `  client stdout:\n${runClient.last.stdout}  client stderr:\n${runClient.last.stderr}\n`,
      );
    }
  }
}
if (failed.length > 0) {
  process.stdout.write(
    `self_test: ${failed.length} of ${checks.length} checks failed: ${failed.join("; ")}\n`,
  );
  process.exit(1);
}
process.stdout.write(`self_test: all ${checks.length} checks of foxglove-client.mjs passed\n`);
