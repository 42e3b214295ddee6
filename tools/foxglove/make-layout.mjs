#!/usr/bin/env node
// Builds config/foxglove/teejet-layout.json, the Foxglove / Lichtblick layout for teejet
// recordings and teejet-web's live Foxglove server (docs/foxglove-layout.md), from the panels
// below and the user scripts in config/foxglove/scripts/*.ts, which the layout embeds as
// userNodes: the .ts files are the ones to read, edit and test, the JSON is what people import.
//
// Usage: tools/foxglove/make-layout.mjs           write the layout
//        tools/foxglove/make-layout.mjs --check   exit 1 when the committed layout is not what
//                                                 this builds (tests/foxglove-layout runs it)
//
// Plain Node, no packages: anyone who edits a script can rebuild the layout.

import fs from "node:fs";
import path from "node:path";
import process from "node:process";
import { fileURLToPath } from "node:url";

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..", "..");
export const LAYOUT_FILE = path.join(ROOT, "config", "foxglove", "teejet-layout.json");
export const SCRIPTS_DIR = path.join(ROOT, "config", "foxglove", "scripts");

// Topic names carry no leading slash, so every path quotes its topic: the form Foxglove's own
// autocomplete writes, which every version of its message-path grammar reads.
const POSITION = '"teejet/valve/position"';
const PRESENCE = '"teejet/valve/presence"';

// The time plot and the online lanes follow these valves; a person sets them in the Variables
// sidebar to the serial's digits (TJV000102 -> 102). The defaults are the demo's simulated valves.
export const VALVE_VARIABLES = ["valve_a", "valve_b", "valve_c", "valve_d"];
const DEFAULT_SERIALS = [1, 2, 3, 4];

// Outputs of the user scripts, as each .ts file's `export const output` says (checked by the test).
const POSITIONS = "/studio_script/teejet_valve_positions";
const PRESENCE_TABLE = "/studio_script/teejet_valve_presence";
const GATEWAYS = "/studio_script/teejet_gateways";

// Foxglove keeps a panel's title under its own key, Lichtblick under another: both get it.
function titled(title, config) {
  return { ...config, foxglovePanelTitle: title, lichtblickPanelTitle: title };
}

function plot(title, xAxisVal, paths, extra = {}) {
  return titled(title, {
    paths: paths.map(({ value, label }) => ({
      value,
      enabled: true,
      timestampMethod: "receiveTime",
      label,
    })),
    minYValue: 0,
    maxYValue: 360,
    showXAxisLabels: true,
    showYAxisLabels: true,
    showLegend: true,
    legendDisplay: "floating",
    showPlotValuesInLegend: xAxisVal === "timestamp",
    isSynced: xAxisVal === "timestamp",
    xAxisVal,
    sidebarDimension: 240,
    ...extra,
  });
}

function panels() {
  return {
    "Plot!positionsnow": plot(
      "Every valve's position now (x: index in the positions table)",
      "index",
      [{ value: `${POSITIONS}.valves[:].degrees`, label: "degrees by valve index" }],
    ),
    "Plot!positionsovertime": plot(
      "Positions over time of valve_a .. valve_d (Variables)",
      "timestamp",
      VALVE_VARIABLES.map((name) => ({
        value: `${POSITION}{serial==$${name}}.degrees`,
        label: name,
      })),
    ),
    "StateTransitions!onlineovertime": titled("Online over time of valve_a .. valve_d", {
      paths: VALVE_VARIABLES.map((name) => ({
        value: `${PRESENCE}{serial==$${name}}.online`,
        label: `${name} online`,
        timestampMethod: "receiveTime",
      })),
      isSynced: true,
    }),
    "Table!positions": titled("Positions: index, valve, degrees", {
      topicPath: `${POSITIONS}.valves`,
    }),
    "Table!presence": titled("Valves: online, gateway, location, address", {
      topicPath: `${PRESENCE_TABLE}.valves`,
    }),
    "Table!gateways": titled("Gateways: bus state, valves, frames, decode errors", {
      topicPath: `${GATEWAYS}.gateways`,
    }),
  };
}

// react-mosaic's tree: plots on the left, tables on the right.
const MOSAIC = {
  direction: "row",
  splitPercentage: 55,
  first: {
    direction: "column",
    splitPercentage: 36,
    first: "Plot!positionsnow",
    second: {
      direction: "column",
      splitPercentage: 62,
      first: "Plot!positionsovertime",
      second: "StateTransitions!onlineovertime",
    },
  },
  second: {
    direction: "column",
    splitPercentage: 40,
    first: "Table!presence",
    second: {
      direction: "column",
      splitPercentage: 55,
      first: "Table!positions",
      second: "Table!gateways",
    },
  },
};

// One user script per .ts file, under the file's name, in the order of the names.
export function userScripts(scriptsDir = SCRIPTS_DIR) {
  const files = fs
    .readdirSync(scriptsDir)
    .filter((name) => name.endsWith(".ts"))
    .sort();
  if (files.length === 0) {
    throw new Error(`no user scripts (*.ts) in ${scriptsDir}`);
  }
  return Object.fromEntries(
    files.map((file) => {
      const name = path.basename(file, ".ts");
      const sourceCode = fs.readFileSync(path.join(scriptsDir, file), "utf8");
      return [`teejet-${name}`, { name: `teejet ${name}`, sourceCode }];
    }),
  );
}

export function buildLayout(scriptsDir = SCRIPTS_DIR) {
  return {
    configById: panels(),
    globalVariables: Object.fromEntries(VALVE_VARIABLES.map((n, i) => [n, DEFAULT_SERIALS[i]])),
    userNodes: userScripts(scriptsDir),
    playbackConfig: { speed: 1 },
    layout: MOSAIC,
  };
}

export function layoutText(scriptsDir = SCRIPTS_DIR) {
  return `${JSON.stringify(buildLayout(scriptsDir), null, 2)}\n`;
}

function main(argv) {
  const check = argv.includes("--check");
  const unknown = argv.filter((arg) => arg !== "--check");
  if (unknown.length > 0) {
    process.stderr.write(
      `make-layout: unknown argument '${unknown[0]}' (usage: make-layout.mjs [--check])\n`,
    );
    return 2;
  }
  const wanted = layoutText();
  const relative = path.relative(process.cwd(), LAYOUT_FILE);
  if (!check) {
    fs.writeFileSync(LAYOUT_FILE, wanted);
    process.stdout.write(`make-layout: wrote ${relative}\n`);
    return 0;
  }
  const committed = fs.existsSync(LAYOUT_FILE) ? fs.readFileSync(LAYOUT_FILE, "utf8") : "";
  if (committed !== wanted) {
    process.stderr.write(
      `make-layout: ${relative} is not what config/foxglove/scripts/*.ts and ` +
        `tools/foxglove/make-layout.mjs build: run tools/foxglove/make-layout.mjs\n`,
    );
    return 1;
  }
  process.stdout.write(`make-layout: ${relative} is up to date\n`);
  return 0;
}

if (process.argv[1] && path.resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  process.exitCode = main(process.argv.slice(2));
}
