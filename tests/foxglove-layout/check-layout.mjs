#!/usr/bin/env node
// Judges config/foxglove/teejet-layout.json (docs/foxglove-layout.md) with Foxglove's own code
// (foxglove.mjs: @foxglove/studio-base 1.48.0) on messages that Foxglove's omgidl decoders read
// from a recording:
//
//   - the committed layout is what tools/foxglove/make-layout.mjs builds from
//     config/foxglove/scripts/*.ts, and embeds each script exactly;
//   - its shape is a layout Foxglove and Lichtblick import (configById, globalVariables,
//     playbackConfig, userNodes; the mosaic's panels are the configured ones, of panel types
//     Foxglove has), and each panel's config type checks against Foxglove's own config types;
//   - every message path parses with Foxglove's grammar, names a topic of the recording and of
//     docs/topics.md (or a script's output), and walks fields that its datatype has; every
//     variable it uses is one of the layout's;
//   - each user script passes Foxglove's user-script transformer (type checked against the types
//     Foxglove generates from the recording's schemas, inputs, output, output datatypes); run as
//     Foxglove runs it on the recording's messages in order, it outputs one row per valve or
//     gateway with the latest values, in the shape of its output datatype;
//   - the panels' paths, evaluated by Foxglove on those outputs and messages, show every valve
//     (the index plot), exactly the chosen valves' samples (the time plot and online lanes,
//     valves chosen by the variables), and one table row per valve or gateway;
//   - the same with 40 valves of two gateways whose messages are written and read back by
//     Foxglove's CDR serializer: any number of valves, any serials.
//
// Usage: check-layout.mjs --writer WRITE_KNOWN_RECORDING   the recording of known values that
//                                                          tests/mcap-js writes (ctest)
//        check-layout.mjs --recording FILE.mcap            any teejet-record recording
//
// Exit 0: all passed; 1: a check failed (each failure on stderr); 2: usage; 77 (skipped): the
// npm packages of tests/foxglove-layout are not installed (tools/install-deps.sh installs them).

import { execFileSync } from "node:child_process";
import fs from "node:fs";
import module from "node:module";
import os from "node:os";
import path from "node:path";
import process from "node:process";
import { fileURLToPath, pathToFileURL } from "node:url";

const HERE = path.dirname(fileURLToPath(import.meta.url));
const ROOT = path.resolve(HERE, "..", "..");
const INSTALL_HINT =
  "run tools/install-deps.sh (it installs the npm packages pinned in " +
  "tests/foxglove-layout/package-lock.json)";
const USAGE = "usage: check-layout.mjs --writer WRITE_KNOWN_RECORDING | --recording FILE.mcap";

const failures = [];
function check(condition, what) {
  if (!condition) {
    failures.push(what);
    process.stderr.write(`FAIL: ${what}\n`);
  }
  return condition;
}

function say(line) {
  process.stdout.write(`${line}\n`);
}

// Before anything imports them: skipped without the packages, failed with other versions.
function requirePackages() {
  if (typeof module.register !== "function") {
    say(`SKIP: node ${process.version} has no module.register (Node 18.19 or 20.6 and newer)`);
    process.exit(77);
  }
  const pinned = JSON.parse(fs.readFileSync(path.join(HERE, "package.json"), "utf8")).dependencies;
  for (const [name, version] of Object.entries(pinned)) {
    const installed = path.join(HERE, "node_modules", name, "package.json");
    if (!fs.existsSync(installed)) {
      say(`SKIP: ${name} is not installed in tests/foxglove-layout/node_modules: ${INSTALL_HINT}`);
      process.exit(77);
    }
    const have = JSON.parse(fs.readFileSync(installed, "utf8")).version;
    if (have !== version) {
      process.stderr.write(
        `check-layout: ${name} ${have} is installed, package.json pins ${version}: ` +
          `${INSTALL_HINT}\n`,
      );
      process.exit(1);
    }
  }
}

function parseArgs(argv) {
  const args = {};
  for (let i = 0; i < argv.length; i++) {
    const arg = argv[i];
    if ((arg === "--writer" || arg === "--recording") && i + 1 < argv.length) {
      args[arg.slice(2)] = argv[++i];
    } else {
      process.stderr.write(`check-layout: unexpected argument '${arg}' (${USAGE})\n`);
      process.exit(2);
    }
  }
  if ((args.writer === undefined) === (args.recording === undefined)) {
    process.stderr.write(`check-layout: give one of --writer and --recording (${USAGE})\n`);
    process.exit(2);
  }
  return args;
}

const args = parseArgs(process.argv.slice(2));
requirePackages();

const fx = await import("./foxglove.mjs");
const { default: ts } = await import("typescript");
const { McapStreamReader } = await import("@mcap/core");
const { parseIDL } = (await import("@foxglove/omgidl-parser")).default;
const { MessageReader, MessageWriter } = (await import("@foxglove/omgidl-serialization")).default;
const { default: zstd } = await import("@foxglove/wasm-zstd");
const { default: lz4 } = await import("@foxglove/wasm-lz4");
const makeLayout = await import(pathToFileURL(path.join(ROOT, "tools/foxglove/make-layout.mjs")));

const LAYOUT_FILE = makeLayout.LAYOUT_FILE;
const SCRIPTS_DIR = makeLayout.SCRIPTS_DIR;
const IDL_FILE = path.join(ROOT, "idl/teejet/valve.idl");
const POSITION = "teejet/valve/position";
const PRESENCE = "teejet/valve/presence";
const GATEWAY_STATUS = "teejet/gateway/status";

// ------------------------------------------------------------------------------------------
// The data: a recording read as Foxglove reads one
// ------------------------------------------------------------------------------------------

function timeOf(ns) {
  return { sec: Number(ns / 1_000_000_000n), nsec: Number(ns % 1_000_000_000n) };
}

// Datatypes as Foxglove's MCAP support builds them from an omgidl schema: every definition of
// the IDL under its name (the IDL has no unions, the one kind it converts).
function datatypesOf(definitions) {
  return new Map(definitions.map((d) => [d.name, { name: d.name, definitions: d.definitions }]));
}

function nextRecord(reader, file) {
  try {
    return reader.nextRecord();
  } catch (error) {
    throw new Error(`${file}: not a readable MCAP file: ${error.message}`);
  }
}

// Channels ({topic: schemaName}), datatypes and message events ({topic, schemaName,
// receiveTime, message}) in log-time order, decoded as Foxglove decodes omgidl/cdr: each
// schema's IDL by @foxglove/omgidl-parser, each message by @foxglove/omgidl-serialization;
// receive time = the message's log time.
async function readRecording(file) {
  await Promise.all([zstd.isLoaded, lz4.isLoaded]);
  const reader = new McapStreamReader({
    validateCrcs: true,
    decompressHandlers: {
      zstd: (buffer, size) => zstd.decompress(buffer, Number(size)),
      lz4: (buffer, size) => lz4(buffer, Number(size)),
    },
  });
  let bytes;
  try {
    bytes = fs.readFileSync(file);
  } catch (error) {
    throw new Error(`cannot read the recording ${file}: ${error.code ?? error.message}`);
  }
  reader.append(bytes);
  const schemas = new Map();
  const channelsById = new Map();
  const decoders = new Map();
  const channels = new Map();
  const datatypes = new Map();
  const events = [];
  for (let record; (record = nextRecord(reader, file)); ) {
    if (record.type === "Schema") {
      schemas.set(record.id, record);
    } else if (record.type === "Channel") {
      channelsById.set(record.id, record);
    } else if (record.type === "Message") {
      const channel = channelsById.get(record.channelId);
      const schema = schemas.get(channel.schemaId);
      if (!decoders.has(schema.id)) {
        if (schema.encoding !== "omgidl" || channel.messageEncoding !== "cdr") {
          throw new Error(
            `${file}: channel "${channel.topic}" is ${schema.encoding}/` +
              `${channel.messageEncoding}, not omgidl/cdr`,
          );
        }
        const definitions = parseIDL(new TextDecoder().decode(schema.data));
        for (const [name, datatype] of datatypesOf(definitions)) datatypes.set(name, datatype);
        decoders.set(schema.id, new MessageReader(schema.name, definitions));
      }
      channels.set(channel.topic, schema.name);
      events.push({
        topic: channel.topic,
        schemaName: schema.name,
        logTime: record.logTime,
        receiveTime: timeOf(record.logTime),
        message: decoders.get(schema.id).readMessage(record.data),
      });
    }
  }
  if (!reader.done()) {
    throw new Error(`${file}: the file ends early (a recorder that was killed?)`);
  }
  events.sort((a, b) => (a.logTime < b.logTime ? -1 : a.logTime > b.logTime ? 1 : 0));
  return { channels, datatypes, events };
}

// The topic table of docs/topics.md: topic -> type.
function documentedTopics() {
  const text = fs.readFileSync(path.join(ROOT, "docs/topics.md"), "utf8");
  const topics = new Map();
  for (const match of text.matchAll(/^\| `(teejet\/[^`]+)` \| `(teejet::\w+)` \|/gm)) {
    topics.set(match[1], match[2]);
  }
  return topics;
}

// ------------------------------------------------------------------------------------------
// The layout file
// ------------------------------------------------------------------------------------------

function checkUpToDate(layoutText) {
  check(
    layoutText === makeLayout.layoutText(),
    `${path.relative(ROOT, LAYOUT_FILE)} is not what tools/foxglove/make-layout.mjs builds ` +
      `from config/foxglove/scripts/*.ts: run tools/foxglove/make-layout.mjs`,
  );
  const layout = JSON.parse(layoutText);
  const files = fs
    .readdirSync(SCRIPTS_DIR)
    .filter((f) => f.endsWith(".ts"))
    .sort();
  const embedded = Object.values(layout.userNodes ?? {}).map((node) => node.sourceCode);
  for (const file of files) {
    const source = fs.readFileSync(path.join(SCRIPTS_DIR, file), "utf8");
    check(
      embedded.includes(source),
      `the layout embeds no user script equal to config/foxglove/scripts/${file}`,
    );
  }
  check(
    embedded.length === files.length,
    `the layout has ${embedded.length} user scripts, config/foxglove/scripts has ` +
      `${files.length}`,
  );
  say(`layout: up to date with make-layout.mjs; embeds ${files.join(", ")} exactly`);
}

function isPlainObject(value) {
  return typeof value === "object" && value !== null && !Array.isArray(value);
}

function mosaicLeaves(node, where = "layout") {
  if (typeof node === "string") return [node];
  if (
    !check(
      isPlainObject(node) && "first" in node && "second" in node,
      `${where}: a mosaic node is a panel id or {first, second, direction}`,
    )
  ) {
    return [];
  }
  check(
    node.direction === "row" || node.direction === "column",
    `${where}.direction: "${node.direction}", expected "row" or "column"`,
  );
  check(
    node.splitPercentage === undefined ||
      (typeof node.splitPercentage === "number" &&
        node.splitPercentage > 0 &&
        node.splitPercentage < 100),
    `${where}.splitPercentage: ${node.splitPercentage}, expected 0 < x < 100`,
  );
  return [
    ...mosaicLeaves(node.first, `${where}.first`),
    ...mosaicLeaves(node.second, `${where}.second`),
  ];
}

// What Foxglove 1.48 offers as panels: the `type: "..."` of its panel list.
function foxglovePanelTypes() {
  const list = fs.readFileSync(path.join(fx.declarationsDir, "panels/index.js"), "utf8");
  return new Set([...list.matchAll(/\btype: "(\w+)"/g)].map((m) => m[1]));
}

// The checks of Lichtblick's validateLayoutData (its "Import layout from file"), and that the
// mosaic shows exactly the configured panels.
function checkShape(layout) {
  check(isPlainObject(layout.configById), `"configById" must be an object`);
  check(isPlainObject(layout.globalVariables), `"globalVariables" must be an object`);
  check(
    isPlainObject(layout.playbackConfig) && typeof layout.playbackConfig.speed === "number",
    `"playbackConfig" must be an object with a numeric "speed"`,
  );
  check(isPlainObject(layout.userNodes), `"userNodes" must be an object`);
  for (const [id, node] of Object.entries(layout.userNodes ?? {})) {
    check(
      isPlainObject(node) && typeof node.name === "string" && typeof node.sourceCode === "string",
      `userNodes["${id}"] must be {name, sourceCode}`,
    );
  }
  const leaves = mosaicLeaves(layout.layout);
  const ids = Object.keys(layout.configById ?? {});
  check(
    JSON.stringify([...leaves].sort()) === JSON.stringify([...ids].sort()),
    `the mosaic shows panels [${leaves}], configById has [${ids}]`,
  );
  check(new Set(leaves).size === leaves.length, `the mosaic shows a panel twice: [${leaves}]`);
  const known = foxglovePanelTypes();
  for (const id of ids) {
    const type = id.split("!")[0];
    check(/^\w+![\w-]+$/.test(id), `panel id "${id}" is not "<type>!<name>"`);
    check(known.has(type), `panel "${id}": Foxglove has no panel type "${type}"`);
    const config = layout.configById[id];
    check(
      config.foxglovePanelTitle === config.lichtblickPanelTitle,
      `panel "${id}": the Foxglove and Lichtblick titles differ`,
    );
  }
  for (const [name, value] of Object.entries(layout.globalVariables ?? {})) {
    check(
      typeof value === "number" || typeof value === "string",
      `global variable ${name} = ${JSON.stringify(value)}: a filter takes a number or a ` +
        `string only`,
    );
  }
  say(
    `layout: the shape Foxglove and Lichtblick import; ${ids.length} panels of types ` +
      `${[...new Set(ids.map((id) => id.split("!")[0]))].join(", ")}`,
  );
}

// Each panel's config as a literal of Foxglove's own config type (excess keys, missing keys,
// values outside a type's union are errors); the whole layout as Foxglove's LayoutData.
function typeCheckConfigs(layout) {
  const declaration = (relative) => JSON.stringify(path.join(fx.declarationsDir, relative));
  // The Table panel keeps its config type private: its text, from the panel's declarations.
  const tableDts = path.join(fx.declarationsDir, "panels/Table/index.d.ts");
  const tableSource = ts.createSourceFile(
    tableDts,
    fs.readFileSync(tableDts, "utf8"),
    ts.ScriptTarget.ES2020,
    true,
  );
  const tableConfig = tableSource.statements.find(
    (s) => ts.isTypeAliasDeclaration(s) && s.name.text === "Config",
  );
  if (!check(tableConfig, `no type Config in ${tableDts}`)) return;
  const typeOfPanel = {
    Plot: "PlotConfig",
    StateTransitions: "StateTransitionConfig",
    Table: "TableConfig",
  };
  let source =
    `import type { PlotConfig } from ${declaration("panels/Plot/types")};\n` +
    `import type { StateTransitionConfig } from ` +
    `${declaration("panels/StateTransitions/types")};\n` +
    `import type { LayoutData } from ${declaration("context/CurrentLayoutContext/actions")};\n` +
    `type TableConfig = ${tableConfig.type.getText()};\n`;
  let panels = 0;
  for (const [id, config] of Object.entries(layout.configById)) {
    const type = typeOfPanel[id.split("!")[0]];
    if (!check(type, `panel "${id}": the check knows no config type for it`)) continue;
    // The titles belong to the panel's frame (Foxglove's PanelToolbar reads its key from any
    // panel's config; Lichtblick's is another), not to the panel's own config type.
    const { lichtblickPanelTitle, foxglovePanelTitle, ...foxgloveConfig } = config;
    check(
      typeof foxglovePanelTitle === "string" && foxglovePanelTitle.length > 0,
      `panel "${id}": no title`,
    );
    panels++;
    source += `// ${id}\n`;
    source += `export const panel${panels}: ${type} = ${JSON.stringify(foxgloveConfig)};\n`;
  }
  source += `export const layout: LayoutData = ${JSON.stringify(layout)};\n`;

  const file = path.join(HERE, "layout-configs.check.ts");
  const options = {
    strict: true,
    noEmit: true,
    skipLibCheck: true,
    target: ts.ScriptTarget.ES2020,
    moduleResolution: ts.ModuleResolutionKind.NodeJs,
    types: [],
  };
  const host = ts.createCompilerHost(options);
  const getSourceFile = host.getSourceFile.bind(host);
  host.getSourceFile = (name, target, ...rest) =>
    name === file
      ? ts.createSourceFile(name, source, target)
      : getSourceFile(name, target, ...rest);
  const fileExists = host.fileExists.bind(host);
  host.fileExists = (name) => name === file || fileExists(name);
  const program = ts.createProgram([file], options, host);
  const sourceFile = program.getSourceFile(file);
  const diagnostics = [
    ...program.getSyntacticDiagnostics(sourceFile),
    ...program.getSemanticDiagnostics(sourceFile),
  ];
  for (const d of diagnostics) {
    const { line } = sourceFile.getLineAndCharacterOfPosition(d.start ?? 0);
    const panel = source
      .split("\n")
      .slice(0, line + 1)
      .reverse()
      .find((l) => l.startsWith("// ") || l.startsWith("export const layout"));
    check(
      false,
      `panel config against Foxglove's types (${panel?.replace(/^\/\/ /, "") ?? "?"}): ` +
        ts.flattenDiagnosticMessageText(d.messageText, " "),
    );
  }
  if (diagnostics.length === 0) {
    say(
      `layout: every panel config type checks against Foxglove's PlotConfig, ` +
        `StateTransitionConfig and the Table's Config; the whole as LayoutData`,
    );
  }
}

// ------------------------------------------------------------------------------------------
// Message paths
// ------------------------------------------------------------------------------------------

// Every message path of the layout: {panel, kind, value}.
function layoutPaths(layout) {
  const paths = [];
  for (const [panel, config] of Object.entries(layout.configById)) {
    const type = panel.split("!")[0];
    if (type === "Table") {
      paths.push({ panel, kind: "table", value: config.topicPath });
    } else {
      for (const p of config.paths ?? []) {
        paths.push({
          panel,
          kind: type === "Plot" ? `plot:${config.xAxisVal}` : "state",
          value: p.value,
        });
      }
    }
  }
  return paths;
}

const NUMERIC = new Set([
  "bool",
  "int8",
  "uint8",
  "int16",
  "uint16",
  "int32",
  "uint32",
  "int64",
  "uint64",
  "float32",
  "float64",
]);

// Walks a parsed path through the datatypes (this check's walk; Foxglove's needs React): each
// name a field of the current message, each slice on an array, each filter on a message whose
// fields it names. Returns {complex, type, isArray} of what the path picks, or {error}.
function walkPath(parsed, rootDatatype, datatypes) {
  const fieldOf = (datatype, name) =>
    datatypes.get(datatype)?.definitions.find((f) => f.name === name && f.isConstant !== true);
  let state = { complex: true, type: rootDatatype, isArray: false };
  for (const part of parsed.messagePath) {
    if (part.type === "name") {
      if (!state.complex || state.isArray) {
        return { error: `".${part.name}" on ${state.isArray ? "an array" : state.type}` };
      }
      const field = fieldOf(state.type, part.name);
      if (!field) return { error: `${state.type} has no field "${part.name}"` };
      state = {
        complex: field.isComplex === true,
        type: field.type,
        isArray: field.isArray === true,
      };
    } else if (part.type === "slice") {
      if (!state.isArray) return { error: `a slice on ${state.type}, not an array` };
      state = { ...state, isArray: false };
    } else if (part.type === "filter") {
      if (!state.complex || state.isArray) return { error: `a filter on ${state.type}` };
      let type = state.type;
      for (const [i, name] of part.path.entries()) {
        const field = fieldOf(type, name);
        if (!field) return { error: `filter {${part.repr}}: ${type} has no field "${name}"` };
        if (i < part.path.length - 1 && field.isComplex !== true) {
          return { error: `filter {${part.repr}}: "${name}" is no message` };
        }
        type = field.type;
      }
      if (part.value === undefined) return { error: `filter {${part.repr}} compares with nothing` };
    }
  }
  return state;
}

function variablesOf(parsed) {
  const names = [];
  for (const part of parsed.messagePath) {
    for (const v of [part.value, part.start, part.end]) {
      if (typeof v === "object" && v !== null && "variableName" in v) names.push(v.variableName);
    }
  }
  return names;
}

// channels: the recording's topic -> schema name; datatypes: the recording's.
function checkPaths(layout, channels, datatypes, documented, outputs) {
  let count = 0;
  for (const { panel, kind, value } of layoutPaths(layout)) {
    const where = `panel "${panel}" path ${value}`;
    const parsed = fx.parseMessagePath(value);
    if (!check(parsed, `${where}: Foxglove's message-path grammar does not parse it`)) continue;
    count++;
    const topic = parsed.topicName;
    const output = outputs.get(topic);
    if (topic.startsWith("/studio_script/") && !output) {
      check(
        false,
        `${where}: no user script that passes Foxglove's transformer outputs "${topic}"`,
      );
      continue;
    }
    if (!output) {
      check(documented.has(topic), `${where}: topic "${topic}" is not in docs/topics.md`);
      check(channels.has(topic), `${where}: topic "${topic}" is not in the recording`);
    }
    const root = output ? output.outputDatatype : channels.get(topic);
    if (!check(root, `${where}: no datatype for topic "${topic}"`)) continue;
    const walked = walkPath(parsed, root, output ? output.datatypes : datatypes);
    if (!check(!walked.error, `${where}: ${walked.error}`)) continue;
    for (const name of variablesOf(parsed)) {
      check(
        name in layout.globalVariables,
        `${where}: variable $${name} is not in the layout's globalVariables`,
      );
    }
    if (kind.startsWith("plot") || kind === "state") {
      check(
        !walked.complex && !walked.isArray && NUMERIC.has(walked.type),
        `${where}: picks ${walked.isArray ? "an array of " : ""}${walked.type}, not a number ` +
          `to plot`,
      );
    } else {
      check(
        walked.isArray && walked.complex,
        `${where}: a table of rows needs an array of messages, the path picks ${walked.type}`,
      );
    }
  }
  say(`paths: ${count} message paths parse with Foxglove's grammar and walk their datatypes`);
}

// ------------------------------------------------------------------------------------------
// User scripts
// ------------------------------------------------------------------------------------------

// Every field of the output datatype present with its type, and nothing else: what the Table
// and Plot panels expect of the topic.
function conforms(value, datatype, datatypes, where) {
  const definition = datatypes.get(datatype);
  if (!definition) return `${where}: unknown datatype ${datatype}`;
  const fields = definition.definitions.filter((f) => f.isConstant !== true);
  const extra = Object.keys(value).filter((k) => !fields.some((f) => f.name === k));
  if (extra.length > 0) return `${where}: fields ${extra} are not in its datatype ${datatype}`;
  for (const field of fields) {
    const items = field.isArray ? value[field.name] : [value[field.name]];
    if (!Array.isArray(items)) return `${where}.${field.name}: not an array`;
    for (const [i, item] of items.entries()) {
      const at = field.isArray ? `${where}.${field.name}[${i}]` : `${where}.${field.name}`;
      if (field.isComplex) {
        if (!isPlainObject(item)) return `${at}: not a message`;
        const inner = conforms(item, field.type, datatypes, at);
        if (inner) return inner;
      } else {
        const js =
          { string: "string", bool: "boolean", int64: "bigint", uint64: "bigint" }[field.type] ??
          "number";
        if (typeof item !== js) return `${at}: ${typeof item}, its datatype says ${field.type}`;
      }
    }
  }
  return undefined;
}

function transformScripts(layout, topics, datatypes, documented) {
  const outputs = new Map();
  for (const [id, node] of Object.entries(layout.userNodes)) {
    const result = fx.transformUserScript({
      name: node.name,
      sourceCode: node.sourceCode,
      topics,
      datatypes,
    });
    const messages = result.errors.map(
      (e) =>
        `${e.message}${e.startLineNumber !== undefined ? ` (line ${e.startLineNumber + 1})` : ""}`,
    );
    if (
      !check(
        result.errors.length === 0,
        `user script ${id}: Foxglove's transformer reports: ${messages.join("; ")}`,
      )
    ) {
      continue;
    }
    check(
      result.outputTopic.startsWith("/studio_script/"),
      `user script ${id}: output "${result.outputTopic}" is not under /studio_script/`,
    );
    check(
      !topics.some((t) => t.name === result.outputTopic),
      `user script ${id}: output "${result.outputTopic}" is a topic of the recording`,
    );
    for (const input of result.inputTopics) {
      check(documented.has(input), `user script ${id}: input "${input}" is not in docs/topics.md`);
    }
    outputs.set(result.outputTopic, { id, ...result });
    say(
      `script ${id}: passes Foxglove's transformer: ${result.inputTopics.join(", ")} -> ` +
        `${result.outputTopic} (${result.outputDatatype})`,
    );
  }
  return outputs;
}

// The script run as Foxglove runs it: fresh, on every message of its inputs in order, with the
// layout's variables. Returns its outputs as message events of its output topic.
function runScript(output, events, globalVariables) {
  const script = fx.instantiateUserScript(output.transpiledCode);
  const produced = [];
  for (const event of events) {
    if (!output.inputTopics.includes(event.topic)) continue;
    const message = script({ ...event }, globalVariables);
    if (message !== undefined) {
      produced.push({ topic: output.outputTopic, receiveTime: event.receiveTime, message });
    }
  }
  return produced;
}

function outputWithInput(outputs, input) {
  return [...outputs.values()].find((o) => o.inputTopics.includes(input));
}

function valveName(serial) {
  return `TJV${String(serial).padStart(6, "0")}`;
}

function seconds(time) {
  return time.sec + time.nsec / 1e9;
}

// What each table must show: the latest message per key, computed from the messages.
function expectedRows(events, datatypes) {
  const last = (topic, key) => {
    const byKey = new Map();
    for (const e of events) if (e.topic === topic) byKey.set(key(e.message), e);
    return byKey;
  };
  const enumNames = (name) =>
    new Map(
      datatypes
        .get(name)
        .definitions.filter((d) => d.isConstant)
        .map((d) => [d.value, d.name]),
    );
  const busStates = enumNames("teejet::BusState");
  const claims = enumNames("teejet::AddressClaimState");

  const positions = last(POSITION, (m) => m.serial);
  const newestPosition = Math.max(...[...positions.values()].map((e) => seconds(e.receiveTime)));
  const positionRows = [...positions.keys()]
    .sort((a, b) => a - b)
    .map((serial, index) => ({
      index,
      valve: valveName(serial),
      serial,
      degrees: positions.get(serial).message.degrees,
      age_s:
        Math.round((newestPosition - seconds(positions.get(serial).receiveTime)) * 1000) / 1000,
    }));

  const presence = last(PRESENCE, (m) => m.serial);
  const presenceRows = [...presence.keys()]
    .sort((a, b) => a - b)
    .map((serial) => {
      const m = presence.get(serial).message;
      return {
        valve: valveName(serial),
        online: m.online,
        gateway: m.gateway,
        location: m.location,
        address: `0x${m.address.toString(16).toUpperCase().padStart(2, "0")}`,
        boot_mode: m.boot_mode,
        serial,
      };
    });

  const statuses = last(GATEWAY_STATUS, (m) => m.gateway);
  const newestStatus = Math.max(...[...statuses.values()].map((e) => seconds(e.receiveTime)));
  const gatewayRows = [...statuses.keys()].sort().map((name) => {
    const e = statuses.get(name);
    const m = e.message;
    return {
      gateway: m.gateway,
      can_interface: m.can_interface,
      bus_state: busStates.get(m.bus_state) ?? String(m.bus_state),
      valves_online: m.valves_online,
      valves_known: m.valves_known,
      frames_in: Number(m.frames_in),
      decode_errors: Number(m.decode_errors),
      address_claim: claims.get(m.address_claim) ?? String(m.address_claim),
      age_s: Math.round((newestStatus - seconds(e.receiveTime)) * 1000) / 1000,
    };
  });
  return {
    [POSITION]: { count: "valve_count", rows: "valves", expected: positionRows },
    [PRESENCE]: { count: "valve_count", rows: "valves", expected: presenceRows },
    [GATEWAY_STATUS]: { count: "gateway_count", rows: "gateways", expected: gatewayRows },
  };
}

function sameJson(a, b) {
  return JSON.stringify(a) === JSON.stringify(b);
}

// Runs every script on the events and holds its last output against the expected rows; then
// evaluates every panel path on the outputs and the events. Returns the scripts' outputs.
function checkScriptsOn(what, layout, outputs, events, datatypes) {
  const expected = expectedRows(events, datatypes);
  const produced = new Map();
  for (const [topic, { count, rows, expected: wanted }] of Object.entries(expected)) {
    const output = outputWithInput(outputs, topic);
    if (!check(output, `${what}: no user script reads ${topic}`)) continue;
    const results = runScript(output, events, layout.globalVariables);
    const inputs = events.filter((e) => e.topic === topic).length;
    check(
      results.length === inputs,
      `${what}: script ${output.id} answered ${results.length} of ${inputs} messages`,
    );
    for (const [i, r] of results.entries()) {
      const wrong = conforms(r.message, output.outputDatatype, output.datatypes, `output ${i + 1}`);
      if (!check(!wrong, `${what}: script ${output.id}: ${wrong}`)) break;
    }
    const final = results.at(-1)?.message;
    produced.set(output.outputTopic, results);
    if (!check(final, `${what}: script ${output.id} output nothing`)) continue;
    check(
      final[count] === wanted.length,
      `${what}: script ${output.id}: ${count} ${final[count]}, expected ${wanted.length}`,
    );
    check(
      final[rows].length === wanted.length,
      `${what}: script ${output.id}: ${final[rows].length} rows, expected one per key: ` +
        `${wanted.length}`,
    );
    for (let i = 0; i < Math.max(final[rows].length, wanted.length); i++) {
      if (
        !check(
          sameJson(final[rows][i], wanted[i]),
          `${what}: script ${output.id} row ${i}: ${JSON.stringify(final[rows][i])}, ` +
            `expected ${JSON.stringify(wanted[i])}`,
        )
      ) {
        break;
      }
    }
    say(
      `${what}: script ${output.id}: ${inputs} messages of ${topic} -> ${final[rows].length} ` +
        `rows, each with the latest values`,
    );
  }
  checkPanelsShow(what, layout, outputs, produced, events, expected);
  return produced;
}

// What Foxglove's path evaluation picks for each panel out of the last output of each script
// (index plot, tables) and out of every input message (time plot, online lanes), with the valve
// variables set to the first valves of the data.
function checkPanelsShow(what, layout, outputs, produced, events, expected) {
  const serials = expected[POSITION].expected.map((row) => row.serial);
  const presenceSerials = expected[PRESENCE].expected.map((row) => row.serial);
  const valveVariables = makeLayout.VALVE_VARIABLES;
  // The first valves of the data; a variable beyond them names a serial that no valve has.
  const variables = { ...layout.globalVariables };
  valveVariables.forEach((name, i) => {
    variables[name] = serials[i] ?? 0x1000000 + i;
  });

  for (const { panel, kind, value } of layoutPaths(layout)) {
    const parsed = fx.parseMessagePath(value);
    if (!parsed) continue;
    const where = `${what}: panel "${panel}" path ${value}`;
    const outputEvents = produced.get(parsed.topicName);
    if (kind === "plot:index" || kind === "table") {
      if (!check(outputEvents?.length, `${where}: its topic got no message`)) continue;
      const items = fx.evaluatePath(parsed, outputEvents.at(-1), variables);
      if (kind === "plot:index") {
        // The Plot's index axis: item i at x = i.
        const wanted = expected[POSITION].expected.map((row) => row.degrees);
        if (
          check(
            sameJson(items, wanted),
            `${where}: the index plot shows ${JSON.stringify(items)}, expected every ` +
              `valve's latest degrees ${JSON.stringify(wanted)}`,
          )
        ) {
          say(
            `${what}: the index plot shows all ${items.length} valves, x = their order by serial`,
          );
        }
      } else {
        const table = expected[outputs.get(parsed.topicName).inputTopics[0]];
        check(
          items.length === 1 && sameJson(items[0], table?.expected),
          `${where}: the table gets ${JSON.stringify(items).slice(0, 200)}, expected one ` +
            `array with a row per valve or gateway`,
        );
      }
    } else {
      // A time series: every input message the path picks a value from, in order.
      const series = events.flatMap((e) => fx.evaluatePath(parsed, e, variables));
      const variable = variablesOf(parsed).find((n) => valveVariables.includes(n));
      if (!check(variable, `${where}: the time series names no valve variable`)) continue;
      const serial = variables[variable];
      const field = parsed.messagePath.at(-1).name;
      const wanted = events
        .filter((e) => e.topic === parsed.topicName && e.message.serial === serial)
        .map((e) => e.message[field]);
      check(
        sameJson(series, wanted),
        `${where}: with $${variable} = ${serial} it shows ` +
          `${JSON.stringify(series).slice(0, 200)}, expected that valve's ${wanted.length} ` +
          `samples ${JSON.stringify(wanted).slice(0, 200)}`,
      );
      const known = (parsed.topicName === PRESENCE ? presenceSerials : serials).includes(serial);
      check(
        known ? series.length > 0 : series.length === 0,
        `${where}: with $${variable} = ${serial} it shows ${series.length} samples`,
      );
    }
  }
  say(
    `${what}: the time plot and the online lanes show exactly the samples of the valves that ` +
      `valve_a .. valve_d name, and each table one row per valve or gateway`,
  );
}

// ------------------------------------------------------------------------------------------
// Many valves: messages written by Foxglove's CDR serializer and read back by its reader
// ------------------------------------------------------------------------------------------

function manyValves(datatypes) {
  const definitions = parseIDL(fs.readFileSync(IDL_FILE, "utf8"));
  const codec = (type) => ({
    writer: new MessageWriter(type, definitions, { kind: 1 }), // CDR little endian, as Fast DDS
    reader: new MessageReader(type, definitions),
  });
  const codecs = {
    [POSITION]: codec("teejet::ValvePosition"),
    [PRESENCE]: codec("teejet::ValvePresence"),
    [GATEWAY_STATUS]: codec("teejet::GatewayStatus"),
  };
  const schemaNames = {
    [POSITION]: "teejet::ValvePosition",
    [PRESENCE]: "teejet::ValvePresence",
    [GATEWAY_STATUS]: "teejet::GatewayStatus",
  };
  // 40 serials in no order, from 1 to the largest 24-bit one; two gateways of 20 valves.
  const serials = [];
  for (let i = 0; i < 40; i++) serials.push(1 + ((i * 7919 * 104729) % 0xffffff));
  serials[7] = 0xffffff;
  const gatewayOf = (i) => (i % 2 === 0 ? "boom-left" : "boom-right");
  const events = [];
  let ns = 1_763_942_400_000_000_000n;
  const add = (topic, message) => {
    ns += 1_000_000n;
    const data = codecs[topic].writer.writeMessage(message);
    events.push({
      topic,
      schemaName: schemaNames[topic],
      logTime: ns,
      receiveTime: timeOf(ns),
      message: codecs[topic].reader.readMessage(data),
    });
  };
  const presence = (i, online) =>
    add(PRESENCE, {
      serial: serials[i],
      address: 0xd8 + (i % 32),
      online,
      part_number: 0x1234,
      boot_mode: false,
      last_seen_ns: ns,
      gateway: gatewayOf(i),
      location: `section-${String(i + 1).padStart(2, "0")}`,
    });
  const status = (name, online) =>
    add(GATEWAY_STATUS, {
      // Each gateway host has its own can0: the name, not the interface, tells gateways apart.
      gateway: name,
      can_interface: "can0",
      bus_state: 1,
      tx_errors: 0,
      rx_errors: 3,
      frames_in: ns % 100000n,
      frames_out: 5n,
      decode_errors: 2n,
      rx_dropped: 0n,
      valves_online: online,
      valves_known: 20,
      stamp_ns: ns,
      gateways_seen: 2,
      serials_online: [],
      locations_known: 20,
      address_claim: 2,
      source_address: 0xd5,
      name: 0n,
      address_holder: 0n,
      address_violations: 0n,
      claims_in_valve_range: 0n,
      neighbours: [],
    });
  serials.forEach((_, i) => presence(i, true));
  for (let round = 0; round < 5; round++) {
    serials.forEach((serial, i) => {
      add(POSITION, { serial, degrees: Math.fround((i * 9 + round * 0.7) % 360), received_ns: ns });
    });
    status("boom-left", 20);
    status("boom-right", round < 3 ? 20 : 19);
  }
  // A valve goes offline, and one of the second gateway's stays silent for the last round.
  presence(3, false);
  serials.forEach((serial, i) => {
    if (i !== 5) add(POSITION, { serial, degrees: Math.fround((i * 11) % 360), received_ns: ns });
  });
  for (const topic of [POSITION, PRESENCE, GATEWAY_STATUS]) {
    check(datatypes.has(schemaNames[topic]), `the recording has no datatype ${schemaNames[topic]}`);
  }
  return events;
}

// ------------------------------------------------------------------------------------------

// Values write_known_recording.cpp wrote, as the tables must show them: anchors that do not
// come from the same messages the expectations above are computed from.
function checkKnownValues(produced) {
  const last = (topic) => produced.get(topic)?.at(-1)?.message;
  const positions = last("/studio_script/teejet_valve_positions");
  check(
    sameJson(
      positions?.valves.map((r) => [r.valve, r.degrees]),
      [
        ["TJV000001", 0],
        ["TJV1193046", Math.fround(0.1)],
        ["TJV16777215", Math.fround(359.9)],
      ],
    ),
    `known recording: positions ${JSON.stringify(positions?.valves)}`,
  );
  const presence = last("/studio_script/teejet_valve_presence");
  check(
    sameJson(
      presence?.valves.map((r) => [
        r.valve,
        r.online,
        r.gateway,
        r.location,
        r.address,
        r.boot_mode,
      ]),
      [
        ["TJV000001", true, "", "section-32-chars-abcdefghijklmno", "0xE0", false],
        ["TJV1193046", true, "boom-left", "", "0xD8", false],
        [
          "TJV16777215",
          false,
          "gateway-64-chars-0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJK",
          "",
          "0xF7",
          true,
        ],
      ],
    ),
    `known recording: presence ${JSON.stringify(presence?.valves)}`,
  );
  const gateways = last("/studio_script/teejet_gateways");
  check(
    sameJson(
      gateways?.gateways.map((r) => [
        r.gateway.slice(0, 9),
        r.can_interface,
        r.bus_state,
        r.valves_online,
        r.valves_known,
        r.frames_in,
        r.decode_errors,
        r.address_claim,
      ]),
      // frames_in 2^53 + 1 shows as the nearest double, 2^53
      [
        ["boom-left", "can0", "BUS_ERROR_ACTIVE", 24, 32, 2 ** 53, 0, "CLAIM_YIELDED"],
        ["gateway-6", "vcan31", "BUS_OFF", 0, 0, 0, 7, "CLAIM_OFF"],
      ],
    ),
    `known recording: gateways ${JSON.stringify(gateways?.gateways)}`,
  );
  say("known recording: the tables show the values write_known_recording wrote");
}

async function main() {
  let recordingFile = args.recording;
  let scratch;
  if (args.writer) {
    scratch = fs.mkdtempSync(path.join(os.tmpdir(), "foxglove-layout-"));
    try {
      execFileSync(args.writer, [scratch], {
        stdio: ["ignore", "inherit", "inherit"],
        timeout: 60_000,
      });
    } catch (error) {
      const how =
        typeof error.status === "number" ? `exit ${error.status}` : (error.code ?? error.signal);
      throw new Error(`the writer ${args.writer} failed: ${how}`);
    }
    recordingFile = path.join(scratch, "known-zstd.mcap");
  }
  try {
    const layoutText = fs.readFileSync(LAYOUT_FILE, "utf8");
    const layout = JSON.parse(layoutText);
    checkUpToDate(layoutText);
    checkShape(layout);
    typeCheckConfigs(layout);

    const { channels, datatypes, events } = await readRecording(recordingFile);
    say(
      `recording: ${events.length} messages on ${channels.size} channels of ` +
        `${path.basename(recordingFile)}, decoded by Foxglove's omgidl reader`,
    );
    const documented = documentedTopics();
    check(documented.size >= 16, `docs/topics.md lists ${documented.size} topics, expected 16+`);
    const topics = [...channels].map(([name, schemaName]) => ({ name, schemaName }));
    for (const [topic, schema] of channels) {
      if (documented.has(topic)) {
        check(
          documented.get(topic) === schema,
          `topic ${topic}: docs/topics.md says ${documented.get(topic)}, the recording ${schema}`,
        );
      }
    }
    const outputs = transformScripts(layout, topics, datatypes, documented);
    for (const output of outputs.values()) {
      for (const input of output.inputTopics) {
        check(channels.has(input), `script ${output.id}: input "${input}" is not in the recording`);
      }
    }
    checkPaths(layout, channels, datatypes, documented, outputs);

    const produced = checkScriptsOn("recording", layout, outputs, events, datatypes);
    if (args.writer) checkKnownValues(produced);
    checkScriptsOn("40 valves", layout, outputs, manyValves(datatypes), datatypes);
  } finally {
    if (scratch) fs.rmSync(scratch, { recursive: true, force: true });
  }
  if (failures.length > 0) {
    process.stderr.write(`check-layout: ${failures.length} failure(s)\n`);
    return 1;
  }
  say("check-layout: all passed");
  return 0;
}

try {
  process.exitCode = await main();
} catch (error) {
  // One line that says what could not be done; a stack trace only for a bug of this script.
  const expected =
    error instanceof Error && !(error instanceof TypeError || error instanceof ReferenceError);
  process.stderr.write(`check-layout: ${expected ? error.message : error.stack}\n`);
  process.exitCode = 1;
}
