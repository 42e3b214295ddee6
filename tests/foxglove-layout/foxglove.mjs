// Foxglove's own code, from the pinned @foxglove/studio-base 1.48.0 (the last Foxglove Studio
// published to npm; Lichtblick, its open fork, keeps the same layout format, message-path grammar
// and user-script pipeline), so that the layout is judged by what Foxglove runs, not by our
// reading of its documentation:
//   parseMessagePath       its message-path grammar (nearley), as compiled into its bundle
//   evaluatePath           simpleGetMessagePathDataItems: what a path picks out of a message
//   transformUserScript    the user-script transformer: compile, type check against the types
//                          generated from the data source, inputs/output, output datatypes
//   declarationsDir        its panel config types (.d.ts), for type checking panel configs

import fs from "node:fs";
import { register } from "node:module";
import path from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";

import nearley from "nearley";
import ts from "typescript";

const HERE = path.dirname(fileURLToPath(import.meta.url));
export const STUDIO_BASE = path.join(HERE, "node_modules", "@foxglove", "studio-base");
export const declarationsDir = path.join(STUDIO_BASE, "src");

register(pathToFileURL(path.join(HERE, "studio-base-hooks.mjs")));

// generateRosLib calls a factory signature that TypeScript 4.9 deprecated, and TypeScript says
// so on stderr: nothing about the scripts.
ts.Debug.enableDeprecationWarnings = false;

async function studioModule(relative) {
  return import(pathToFileURL(path.join(STUDIO_BASE, "src", relative)).href);
}

// The package ships parseRosPath.js without the grammar it imports (grammar.ne, compiled by a
// webpack loader); the compiled grammar is in the package's bundle, as the one module that nearley
// generated with the rules of a topic name ("slashID") and a quoted string.
function loadGrammar() {
  const bundle = fs.readFileSync(path.join(STUDIO_BASE, "assets", "index.js"), "utf8");
  const rule = bundle.indexOf('{"name": "slashID"');
  const start = bundle.lastIndexOf("// Generated automatically by nearley", rule);
  const endMarker = "})();";
  const end = bundle.indexOf(endMarker, rule);
  if (rule < 0 || start < 0 || end < 0 || !bundle.slice(start, end).includes('"quotedString"')) {
    throw new Error(
      "the message-path grammar was not found in @foxglove/studio-base/assets/index.js " +
        "(not the pinned 1.48.0? run tools/install-deps.sh)",
    );
  }
  // The generated module assigns the grammar to module.exports when there is one.
  const module = { exports: {} };
  new Function("module", "window", bundle.slice(start, end + endMarker.length))(module, {});
  if (module.exports?.ParserStart !== "main") {
    throw new Error("the message-path grammar of @foxglove/studio-base did not load");
  }
  return nearley.Grammar.fromCompiled(module.exports);
}

const grammar = loadGrammar();

// As parseRosPath.js does: the first parse, or undefined when the text is no message path.
export function parseMessagePath(text) {
  const parser = new nearley.Parser(grammar);
  try {
    return parser.feed(text).results[0];
  } catch {
    return undefined;
  }
}

const { simpleGetMessagePathDataItems } = await studioModule(
  "components/MessagePathSyntax/simpleGetMessagePathDataItems.js",
);

// Global variables filled in as fillInGlobalVariablesInPath (useCachedGetMessagePathDataItems.js,
// which imports React, so it is not loaded here) does: a filter's variable gives its value when
// that is a number or a string and no value otherwise (the filter then matches nothing); a
// slice's variable gives Number(value), or the whole array when that is not a number.
export function fillInGlobalVariables(parsed, globalVariables) {
  const bound = (v, otherwise) => {
    if (typeof v !== "object") return v;
    const n = Number(globalVariables[v.variableName]);
    return Number.isNaN(n) ? otherwise : n;
  };
  return {
    ...parsed,
    messagePath: parsed.messagePath.map((part) => {
      if (part.type === "slice") {
        return { ...part, start: bound(part.start, 0), end: bound(part.end, Infinity) };
      }
      if (part.type === "filter" && typeof part.value === "object") {
        const variable = globalVariables[part.value.variableName];
        const usable = typeof variable === "number" || typeof variable === "string";
        return { ...part, value: usable ? variable : undefined };
      }
      return part;
    }),
  };
}

// What the path picks out of one message event ({topic, receiveTime, message}).
export function evaluatePath(parsed, messageEvent, globalVariables) {
  return simpleGetMessagePathDataItems(
    messageEvent,
    fillInGlobalVariables(parsed, globalVariables),
  );
}

const { default: transform } = await studioModule(
  "players/UserNodePlayer/nodeTransformerWorker/transform.js",
);
const { generateTypesLib } = await studioModule(
  "players/UserNodePlayer/nodeTransformerWorker/generateTypesLib.js",
);
const { default: generateRosLib } = await studioModule(
  "players/UserNodePlayer/nodeTransformerWorker/generateRosLib.js",
);
const { DiagnosticSeverity } = await studioModule("players/UserNodePlayer/types.js");

// As UserNodePlayer does for each user script: the types library and the ROS library generated
// from the data source's topics and datatypes, then the transformer. topics: [{name,
// schemaName}]; datatypes: Map of schema name to {definitions}. Returns the transformer's node
// data (diagnostics, inputTopics, outputTopic, outputDatatype, datatypes, transpiledCode) and
// the errors among its diagnostics.
export function transformUserScript({ name, sourceCode, topics, datatypes }) {
  const foxgloveTopics = topics.map((t) => ({ ...t, datatype: t.schemaName }));
  const typesLib = generateTypesLib({ topics: foxgloveTopics, datatypes });
  const rosLib = generateRosLib({ topics: foxgloveTopics, datatypes });
  const result = transform({
    name,
    sourceCode,
    topics: foxgloveTopics,
    rosLib,
    typesLib,
    datatypes,
  });
  const errors = result.diagnostics.filter((d) => d.severity === DiagnosticSeverity.Error);
  return { ...result, errors };
}

// As the runtime worker runs a transpiled script: CommonJS through new Function, its default
// export called with each message event and the global variables.
export function instantiateUserScript(transpiledCode) {
  const exports = {};
  const require = (id) => {
    throw new Error(`the script requires '${id}' at run time; only types may be imported`);
  };
  new Function("exports", "require", transpiledCode)(exports, require);
  if (typeof exports.default !== "function") {
    throw new Error("the script has no default export function");
  }
  return exports.default;
}
