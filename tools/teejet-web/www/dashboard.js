"use strict";
// The teejet-web page: one WebSocket (/ws, messages in docs/web.md), one card per valve, a plot,
// gateway health and, only when the server's snapshot allows them, command controls. In
// read-only mode the controls are never built, so that no click can even try.
(function () {
  const SVG = "http://www.w3.org/2000/svg";
  const HISTORY_MS = 5 * 60 * 1000 + 10000;  // the longest plot window, and a little
  const COLORS = ["#1565c0", "#c62828", "#2e7d32", "#6a1b9a", "#ef6c00", "#00838f", "#5d4037",
                  "#ad1457", "#827717", "#37474f"];
  const FINAL = new Set(["completed", "rejected", "timed_out", "superseded", "refused", "error",
                         "identified"]);

  const valves = new Map();    // serial -> {data, card, history: [[t, json]], color}
  const gateways = new Map();  // name -> element
  const shownGateways = new Map();  // name -> the status it shows (JSON), to skip repeats
  const places = new Map();    // "gateway/location" -> place JSON (docs/web.md)
  const sentCommands = new Map();  // request id -> serials it was for (until answered)
  // Valves being identified: serial -> {steps: [[degrees, direction], ...], at, requestId,
  // commandId, start}. Each step is a move sent once the one before it completed.
  const identifying = new Map();
  const JOG_DEGREES = 10;
  let policy = null;           // {allowed, token_required} from the snapshot
  let setup = null;            // the setup view (setup.js), with commands allowed only
  // What the valves tell and what commands take, from the codec's table (docs/web.md):
  // {commands: {move: {degrees: {min, max, step, unit}, ...}, request: {telemetry: [...]}},
  //  telemetry: {position: {degrees: {type, unit, step}}, current: {...}, ...}}.
  let protocol = { commands: {}, telemetry: {} };
  let socket = null;
  let nextId = 1;
  let retryMs = 500;
  let plotDirty = true;
  let framePending = false;
  // The server's clock minus this browser's, from the latest update: the plot's "now" keeps
  // moving in the server's time while no valve changes (the server then sends nothing).
  let serverOffsetMs = null;

  // Read by the benchmark (bench/): how many updates reach the page and how often it paints.
  const stats = { messages: 0, updates_per_s: 0, valve_updates: 0, valve_updates_per_s: 0,
                  last_message_ms: null, frames_painted: 0 };
  const recent = [];  // [performance.now(), valves in the message] of the last 5 s
  window.teejetDashboard = { stats };

  const $ = (id) => document.getElementById(id);
  const plot = new window.TeejetPlot($("plot"), $("plot-legend"));

  function el(tag, attrs, ...children) {
    const node = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === "class") node.className = v; else node.setAttribute(k, v);
    }
    node.append(...children);
    return node;
  }

  function svg(tag, attrs) {
    const node = document.createElementNS(SVG, tag);
    for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
    return node;
  }

  // Write to the page only what changed: each write makes the browser restyle (and often lay
  // out) what it touched, and with hundreds of cards an update rewriting them all costs it a
  // whole core (measured at 8 gateways x 32 valves: docs/performance.md, "Dashboard").
  function setText(node, text) {
    if (node.textContent !== text) node.textContent = text;
  }
  function setAttr(node, name, value) {
    if (node.getAttribute(name) !== value) node.setAttribute(name, value);
  }
  function setData(node, name, value) {
    if (node.dataset[name] !== value) node.dataset[name] = value;
  }

  const dash = "—";
  const fixed = (v, digits, unit) => (v === null || v === undefined ? dash
                                      : `${Number(v).toFixed(digits)}${unit}`);
  // Decimals a field's resolution needs: 0.1 -> 1, 0.01 -> 2, 1 -> 0.
  const decimals = (step) => Math.max(0, Math.round(-Math.log10(step || 1)));
  const withUnit = (unit) => (!unit ? "" : unit.startsWith("°") && unit !== "°C" && unit !== "°/s"
                                                ? unit : ` ${unit}`);
  function reading(value, field) {
    if (value === null || value === undefined) return dash;
    if (field && field.type === "number") return fixed(value, decimals(field.step), withUnit(field.unit));
    return String(value);
  }
  // Every number the valves report, as "subject.field", for the plot.
  function numericFields() {
    const fields = [];
    for (const [subject, described] of Object.entries(protocol.telemetry)) {
      for (const [name, field] of Object.entries(described)) {
        if (field.type === "number") fields.push({ key: `${subject}.${name}`, subject, name, field });
      }
    }
    return fields;
  }
  const label = (subject, name, count) => (count > 1 ? `${subject} ${name}` : subject)
    .replaceAll("_", " ");
  function telemetryValue(data, key) {
    const [subject, name] = key.split(".");
    const told = data.telemetry && data.telemetry[subject];
    return told ? told[name] ?? null : null;
  }

  // ---- connection ----------------------------------------------------------------------------

  function setConnection(state, text) {
    const badge = $("connection");
    badge.dataset.state = state;
    badge.textContent = text;
  }

  function connect() {
    setConnection(socket ? "reconnecting" : "connecting", "connecting…");
    const ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws`);
    socket = ws;
    ws.onopen = () => { retryMs = 500; setConnection("connected", "connected"); };
    ws.onmessage = (event) => onMessage(JSON.parse(event.data));
    ws.onclose = () => {
      if (socket !== ws) return;
      // Back off, so that a restarting server is not hammered by every open page.
      const wait = retryMs;
      retryMs = Math.min(retryMs * 2, 10000);
      setConnection("reconnecting", `reconnecting in ${(wait / 1000).toFixed(1)} s`);
      setTimeout(connect, wait);
    };
  }

  function onMessage(message) {
    const now = performance.now();
    stats.messages += 1;
    stats.last_message_ms = Date.now();
    if (message.type === "snapshot") {
      onSnapshot(message);
    } else if (message.type === "update") {
      stats.valve_updates += message.valves.length;
      recent.push([now, message.valves.length]);
      updateRates(now);
      serverOffsetMs = message.stamp_ms - Date.now();
      for (const p of message.places || []) showPlace(p);
      for (const v of message.valves) showValve(v, message.stamp_ms);
      for (const g of message.gateways) showGateway(g);
      for (const s of message.statuses) showStatus(s);
      if ((message.places || []).length || message.valves.length) paintBoom();
    } else if (message.type === "sent") {
      if (setup && setup.onSent(message)) sentCommands.delete(message.id); else onSent(message);
    } else if (message.type === "refused") {
      if (setup && setup.onRefused(message)) sentCommands.delete(message.id);
      else onRefused(message);
    }
  }

  function updateRates(now) {
    while (recent.length && recent[0][0] < now - 5000) recent.shift();
    stats.updates_per_s = recent.length / 5;
    stats.valve_updates_per_s = recent.reduce((sum, r) => sum + r[1], 0) / 5;
  }
  setInterval(() => updateRates(performance.now()), 1000);

  function onSnapshot(message) {
    const next = message.commands || { allowed: false, token_required: false };
    const nextProtocol = message.protocol || { commands: {}, telemetry: {} };
    const protocolChanged = JSON.stringify(nextProtocol) !== JSON.stringify(protocol);
    protocol = nextProtocol;
    if (protocolChanged) buildPlotFields();
    if (!policy || policy.allowed !== next.allowed || policy.token_required !== next.token_required ||
        protocolChanged) {
      // Another server (or another mode) behind the same address: rebuild every control.
      policy = next;
      for (const v of valves.values()) v.card.remove();
      valves.clear();
      buildGlobalControls();
    }
    $("mode").textContent = policy.allowed
      ? (policy.token_required ? "commands allowed (token)" : "commands allowed") : "read-only";
    const stamp = Date.now();
    places.clear();
    for (const p of message.places || []) showPlace(p);
    for (const v of message.valves) showValve(v, stamp);
    for (const g of message.gateways) showGateway(g);
    paintBoom();
  }

  // ---- the boom: every place in machine order ------------------------------------------------

  function showPlace(place) {
    places.set(`${place.gateway}/${place.location}`, place);
  }

  // The place a valve sits at, if any.
  function placeOf(data) {
    return data.location ? places.get(`${data.gateway}/${data.location}`) : undefined;
  }

  // What a glance at the boom should tell: open, closed, moving, error, missing, empty.
  function boomState(place) {
    if (place.state !== "ok") return place.state;
    const valve = valves.get(place.serial);
    if (!valve) return "ok";
    const d = valve.data;
    if ((d.errors || []).length > 0) return "error";
    if (d.target !== null && d.target !== undefined) return "moving";
    if (d.position === null) return "ok";
    const closed = place.closed_deg ?? 0, opened = place.opened_deg ?? 90;
    if (opened < 360 && d.position >= opened - 1) return "open";
    if (d.position <= closed + 1) return "closed";
    return "open";
  }

  let paintedBoom = "";  // what the strip shows, to leave the DOM alone when nothing changed
  function paintBoom() {
    const ordered = [...places.values()].sort((a, b) =>
      a.order - b.order || a.gateway.localeCompare(b.gateway));
    const cells = ordered.map((place) => [place, boomState(place)]);
    const shown = JSON.stringify(cells.map(([p, state]) => [p.gateway, p.location, p.serial, state]));
    if (shown !== paintedBoom) {
      paintedBoom = shown;
      $("boom").hidden = cells.length === 0;
      $("boom-strip").replaceChildren(...cells.map(([place, state]) =>
        el("div", { class: "boom-cell", role: "listitem", "data-state": state,
                    "data-location": place.location,
                    title: `${place.location} (${place.gateway}): ${place.serial || "no valve"}, ${state}` },
           el("span", { class: "boom-name" }, place.location),
           el("span", { class: "boom-state" }, state))));
    }
    for (const valve of valves.values()) titleCard(valve);
    if (setup) setup.refresh(ordered, unassignedValves());
  }

  // Online valves in no place, while some gateway has a layout.
  function unassignedValves() {
    if (places.size === 0) return [];
    return [...valves.values()].map((v) => v.data)
      .filter((d) => d.online && !d.gateway_lost && !placeOf(d))
      .sort((a, b) => (a.serial < b.serial ? -1 : 1))
      .map((d) => ({ serial: d.serial, gateway: d.gateway, address: hexAddress(d.address) }));
  }

  // ---- valves --------------------------------------------------------------------------------

  function showValve(data, stampMs) {
    let valve = valves.get(data.serial);
    if (!valve) {
      valve = { data, history: [], color: COLORS[valves.size % COLORS.length] };
      valve.card = buildCard(data.serial, valve);
      valves.set(data.serial, valve);
      placeCard(valve.card);
    }
    valve.data = data;
    valve.history.push([stampMs, data]);
    while (valve.history.length && valve.history[0][0] < stampMs - HISTORY_MS) valve.history.shift();
    fillCard(valve);
    titleCard(valve);
    if (valve.card.querySelector(".plot-pick").checked) requestPaint();
  }

  // In machine order (the order of the place each sits at), then the valves in no place, by
  // serial: a new valve takes its place among the others.
  function sortKey(card) {
    return [Number(card.dataset.order || 1e6), card.dataset.serial];
  }
  function placeCard(card) {
    const cards = $("cards");
    const [order, serial] = sortKey(card);
    const after = [...cards.children].find((c) => {
      const [o, s] = sortKey(c);
      return o > order || (o === order && s > serial);
    });
    cards.insertBefore(card, after || null);
  }

  // A card is titled by its valve's place, with the serial beneath; a valve online in no place
  // of a layout says so.
  function titleCard(valve) {
    const card = valve.card, d = valve.data, place = placeOf(d);
    const title = place ? place.location : d.serial;
    const order = place ? String(place.order) : "";
    const unassigned = !place && places.size > 0 && d.online;
    setText(card.querySelector("h2"), title);
    setText(card.querySelector(".card-serial"), place ? d.serial : unassigned ? "unassigned" : "");
    setData(card, "unassigned", String(unassigned));
    if (card.dataset.order !== order) {
      card.dataset.order = order;
      placeCard(card);
    }
  }

  function buildCard(serial, valve) {
    const dial = svg("svg", { class: "dial", viewBox: "-60 -60 120 120", role: "img" });
    dial.append(svg("circle", { class: "face", r: 54 }));
    for (let d = 0; d < 360; d += 30) {
      dial.append(svg("line", { class: "tick", x1: 0, y1: -54, x2: 0, y2: d % 90 ? -49 : -44,
                                transform: `rotate(${d})` }));
    }
    dial.append(svg("line", { class: "target", x1: 0, y1: -30, x2: 0, y2: -54, visibility: "hidden" }));
    dial.append(svg("line", { class: "needle", x1: 0, y1: 8, x2: 0, y2: -46 }));
    dial.append(svg("circle", { class: "hub", r: 4 }));

    const pick = el("input", { type: "checkbox", class: "plot-pick" });
    pick.checked = valves.size < 4;  // the first few are plotted until the operator chooses
    pick.addEventListener("change", requestPaint);
    // One line per field the valves report (the position is the dial), then the target.
    const readings = el("dl", { class: "readings" });
    for (const [subject, described] of Object.entries(protocol.telemetry)) {
      if (subject === "position") continue;
      const names = Object.keys(described);
      for (const name of names) {
        readings.append(el("dt", {}, label(subject, name, names.length)),
                        el("dd", { class: "telemetry", "data-key": `${subject}.${name}` }, dash));
      }
    }
    readings.append(el("dt", {}, "target"), el("dd", { class: "target" }, dash));
    const card = el("article", { class: "card", "data-serial": serial },
      el("header", {}, el("div", {}, el("h2", {}, serial), el("div", { class: "card-serial" })),
         el("label", { class: "hint" }, pick, " plot")),
      el("div", { class: "meta" }),
      el("div", { class: "dial-row" }, dial,
         el("div", {}, el("div", { class: "position" }, dash), readings)),
      el("div", { class: "errors" }, el("ul", { class: "error-list" })));
    card.querySelector(".position").style.color = valve.color;
    if (policy.allowed) card.append(buildCommands(serial));
    card.append(el("div", { class: "command-status" }));
    return card;
  }

  // As the protocol sheet writes addresses: 0xD8.
  function hexAddress(address) {
    return typeof address === "number"
      ? `0x${address.toString(16).toUpperCase().padStart(2, "0")}` : dash;
  }

  // A dial's needle (or target mark) at `degrees`, hidden without a value.
  function showDegrees(line, degrees) {
    if (degrees === null || degrees === undefined) {
      setAttr(line, "visibility", "hidden");
      if (line.hasAttribute("data-degrees")) line.removeAttribute("data-degrees");
    } else {
      setAttr(line, "visibility", "visible");
      setAttr(line, "transform", `rotate(${degrees})`);
      setData(line, "degrees", String(degrees));
    }
  }

  function fillCard(valve) {
    const d = valve.data, card = valve.card;
    // A valve whose gateway vanished may still be moving: say that nobody knows.
    const state = d.gateway_lost ? "unknown" : String(d.online);
    setData(card, "online", state);
    // Two gateways report this serial online: two valves carry it, or something replays it.
    const others = d.also_reported_by || [];
    setData(card, "contested", String(others.length > 0));
    const meta = JSON.stringify([state, d.address, d.gateway, d.boot_mode, others]);
    if (valve.shownMeta !== meta) {
      valve.shownMeta = meta;
      const online = el("span", { class: "online-state", "data-online": state },
                        d.gateway_lost ? "unknown (gateway lost)" : d.online ? "online" : "offline");
      card.querySelector(".meta").replaceChildren(
        `address ${hexAddress(d.address)} · gateway ${d.gateway || dash} · `, online,
        d.boot_mode ? " · boot mode" : "",
        ...(others.length > 0
          ? [" · ", el("span", { class: "contested" },
                       `also online on ${others.join(", ")}: commands but Stop refused`)]
          : []));
    }
    setText(card.querySelector(".position"), fixed(d.position, 1, "°"));
    showDegrees(card.querySelector(".needle"), d.position);
    showDegrees(card.querySelector(".target"), d.target);
    for (const dd of card.querySelectorAll("dd.telemetry")) {
      const [subject, name] = dd.dataset.key.split(".");
      setText(dd, reading(telemetryValue(d, dd.dataset.key), protocol.telemetry[subject][name]));
    }
    setText(card.querySelector("dd.target"), fixed(d.target, 1, "°"));
    const errors = d.errors || [];
    const shownErrors = JSON.stringify(errors);
    if (valve.shownErrors !== shownErrors) {
      valve.shownErrors = shownErrors;
      card.querySelector(".error-list").replaceChildren(...errors.map((e) => el("li", {}, e)));
    }
    const clear = card.querySelector(".clear-errors");
    if (clear && clear.disabled !== (errors.length === 0)) clear.disabled = errors.length === 0;
  }

  // ---- commands (built only when the snapshot allows them) -----------------------------------

  function buildGlobalControls() {
    const box = $("global-commands");
    box.replaceChildren();
    if (setup) setup.stopScan("");
    setup = null;
    $("setup").hidden = true;
    $("setup").replaceChildren();
    if (!policy.allowed) return;
    setup = new window.TeejetSetup($("setup"), { el, send: (command) => send(command, null) });
    const setupToggle = el("button", { id: "setup-toggle", class: "cmd", type: "button",
                                       title: "put valves at their places in the layout" }, "Setup");
    setupToggle.addEventListener("click", () => { $("setup").hidden = !$("setup").hidden; });
    box.append(setupToggle);
    if (policy.token_required) {
      box.append(el("label", {}, "token ",
                    el("input", { id: "token", class: "cmd", type: "password", size: 12 })));
    }
    const stopAll = el("button", { id: "stop-all", class: "cmd danger", type: "button" }, "Stop all");
    stopAll.addEventListener("click", () => send({ command: "stop_all" }, null));
    box.append(stopAll);
  }

  function number(attrs) { return el("input", Object.assign({ type: "number", class: "cmd" }, attrs)); }

  function options(cls, values) {
    return el("select", { class: `cmd ${cls}` }, ...values.map((v) => el("option", { value: v }, v)));
  }

  function form(cls, onSubmit, ...children) {
    const f = el("form", { class: `cmd ${cls}` }, ...children);
    f.addEventListener("submit", (event) => { event.preventDefault(); onSubmit(f); });
    return f;
  }

  // A number input with the range, step and unit of a command's field.
  function fieldInput(command, name, cls, value, title) {
    const field = (protocol.commands[command] || {})[name] || {};
    return number({ class: `cmd ${cls}`, min: field.min ?? 0, max: field.max ?? 0,
                    step: field.step ?? 1, value, title });
  }

  // A select of a command field's words, `preferred` chosen when it is one of them.
  function wordOptions(command, name, cls, preferred) {
    const words = ((protocol.commands[command] || {})[name] || {}).words || [];
    const select = options(cls, words);
    if (words.includes(preferred)) select.value = preferred;
    return select;
  }

  function buildCommands(serial) {
    const value = (f, cls) => f.querySelector(`.${cls}`).value;
    const move = form("move", (f) => send({
      command: "move", serial, degrees: Number(value(f, "move-degrees")),
      speed_percent: Number(value(f, "move-speed")), direction: value(f, "move-direction") }, serial),
      "move", fieldInput("move", "degrees", "move-degrees", 0, "degrees"), "°",
      fieldInput("move", "speed_percent", "move-speed", 100, "speed %"), "%",
      wordOptions("move", "direction", "move-direction", "shortest"),
      el("button", { class: "cmd move-send", type: "submit" }, "Move"));
    const stop = el("button", { class: "cmd stop", type: "button" }, "Stop");
    stop.addEventListener("click", () => send({ command: "stop", serial }, serial));
    const clear = el("button", { class: "cmd clear-errors", type: "button" }, "Clear Errors");
    clear.addEventListener("click", () => send({ command: "clear_errors", serial }, serial));
    const jog = form("jog", (f) => send({
      command: "jog", serial, milliseconds: Number(value(f, "jog-ms")),
      speed_percent: Number(value(f, "jog-speed")), direction: value(f, "jog-direction") }, serial),
      "jog", fieldInput("jog", "milliseconds", "jog-ms", 200, "ms"), "ms at",
      fieldInput("jog", "speed_percent", "jog-speed", 50, "speed %"), "%",
      wordOptions("jog", "direction", "jog-direction", "open"),
      el("button", { class: "cmd jog-send", type: "submit" }, "Jog"));
    const identify = el("button", { class: "cmd identify", type: "button",
                                     title: "two short jogs out and back, ending where it started, "
                                            + "so that the person at the boom sees which valve it is" },
                        "Identify");
    identify.addEventListener("click", () => startIdentify(serial));
    const request = form("request", (f) => {
      const telemetry = value(f, "request-telemetry");
      send({ command: "request", serial, telemetry,
             resend_tenths: 0 }, serial);
    }, "request", options("request-telemetry", (protocol.commands.request || {}).telemetry || []),
      el("button", { class: "cmd request-send", type: "submit" }, "Request"));
    return el("div", { class: "commands cmd" }, move,
              el("div", {}, stop, " ", clear, " ", identify), jog, request);
  }

  // As valvectl identify does: two jogs of JOG_DEGREES out and back with Target Degrees, within
  // the mechanics of the valve's place (else 0..359.9), each followed to completed.
  function startIdentify(serial) {
    const valve = valves.get(serial);
    if (!valve || valve.data.position === null) {
      setStatus(serial, "error", "identify: the valve's position is not known yet");
      return;
    }
    const start = valve.data.position, place = placeOf(valve.data);
    const full = !place || place.opened_deg === null || place.opened_deg >= 360;
    const low = full ? 0 : place.closed_deg, high = full ? 359.9 : place.opened_deg;
    const opens = start + JOG_DEGREES <= high || start - JOG_DEGREES < low;
    const out = Math.min(high, Math.max(low, start + (opens ? JOG_DEGREES : -JOG_DEGREES)));
    const there = [out, opens ? "open" : "close"], back = [start, opens ? "close" : "open"];
    identifying.set(serial, { steps: [there, back, there, back], at: 0, start });
    identifyStep(serial);
  }

  function identifyStep(serial) {
    const job = identifying.get(serial);
    if (job.at === job.steps.length) {
      identifying.delete(serial);
      setStatus(serial, "identified", `identified, back at ${fixed(job.start, 1, "°")}`);
      return;
    }
    const [degrees, direction] = job.steps[job.at];
    job.requestId = nextId;
    job.commandId = null;
    send({ command: "move", serial, degrees: Math.round(degrees * 10) / 10, speed_percent: 100,
           direction }, serial);
  }

  // A final status of the identify's current move: the next step, or the end of it.
  function identifyHeard(status) {
    const job = identifying.get(status.serial);
    if (!job || job.commandId !== status.command_id || !FINAL.has(status.state)) return false;
    if (status.state !== "completed") {
      identifying.delete(status.serial);
      setStatus(status.serial, status.state, `identify stopped: move ${status.state}`
                + (status.reason ? ` (${status.reason})` : ""));
      return true;
    }
    job.at += 1;
    identifyStep(status.serial);
    return true;
  }

  function send(command, serial) {
    const id = nextId++;
    const message = Object.assign({ id }, command);
    const token = $("token");
    if (token) message.token = token.value;
    if (!socket || socket.readyState !== WebSocket.OPEN) {
      notice(`${command.command}: not connected to teejet-web`);
      return null;
    }
    sentCommands.set(id, serial);
    if (serial) setStatus(serial, "sent", `${command.command}: sent…`);
    socket.send(JSON.stringify(message));
    return id;
  }

  function onSent(message) {
    sentCommands.delete(message.id);
    for (const c of message.commands) {
      const job = identifying.get(c.serial);
      if (job && job.requestId === message.id) {
        if (c.error) identifying.delete(c.serial); else job.commandId = c.command_id;
      }
      if (c.error) setStatus(c.serial, "error", `not sent: ${c.error}`);
      else setStatus(c.serial, "sent", `#${c.command_id}: sent, waiting for the gateway`);
    }
  }

  function onRefused(message) {
    const serial = sentCommands.get(message.id);
    sentCommands.delete(message.id);
    if (serial && identifying.get(serial)?.requestId === message.id) identifying.delete(serial);
    if (serial) setStatus(serial, "refused", `refused: ${message.reason}`);
    notice(`refused: ${message.reason}`);
  }

  function showStatus(status) {
    if (status.event === "layout_change") {
      if (setup) setup.onStatus(status);
      return;
    }
    if (identifyHeard(status)) return;
    const reason = status.reason ? ` (${status.reason})` : "";
    setStatus(status.serial, status.state,
              `${status.kind} #${status.command_id}: ${status.state}${reason}`);
  }

  function setStatus(serial, state, text) {
    const valve = valves.get(serial);
    if (!valve) return;
    const line = valve.card.querySelector(".command-status");
    line.dataset.state = state;
    line.dataset.final = String(FINAL.has(state));
    line.textContent = text;
  }

  function notice(text) {
    const box = $("notices");
    box.replaceChildren(el("div", {}, text), ...[...box.children].slice(0, 2));
  }

  // ---- gateways ------------------------------------------------------------------------------

  // One line per gateway (name, bus state, valves online), its counters folded under it: eight
  // gateways fit beside the plot. A gateway that needs a look (lost, bus not error-active)
  // unfolds by itself once; the person folds it again.
  function showGateway(g) {
    const shown = JSON.stringify(g);
    if (shownGateways.get(g.gateway) === shown) return;
    shownGateways.set(g.gateway, shown);
    let panel = gateways.get(g.gateway);
    if (!panel) {
      $("gateway-list").querySelector(".empty")?.remove();
      panel = el("details", { class: "gateway", "data-gateway": g.gateway },
                 el("summary", {}), el("table", {}));
      gateways.set(g.gateway, panel);
      const list = $("gateway-list");
      const after = [...list.children].find((c) => c.dataset.gateway > g.gateway);
      list.insertBefore(panel, after || null);
    }
    const row = (label, value, attrs) => el("tr", {}, el("td", {}, label),
                                            el("td", attrs || {}, String(value)));
    // Its address claim on a bus shared with ISOBUS ECUs (docs/isobus.md): given up to another
    // ECU, it sends nothing and refuses every command.
    const claim = g.address_claim || { state: "off", neighbours: [] };
    const yielded = claim.state === "yielded";
    const trouble = g.lost || g.bus_state !== "error_active" || yielded;
    if (trouble && panel.dataset.trouble !== "true") panel.open = true;
    panel.dataset.trouble = String(trouble);
    panel.dataset.lost = String(g.lost);
    panel.querySelector("summary").replaceChildren(
      el("span", { class: "gateway-name" }, g.gateway),
      el("span", { class: "bus-state", "data-state": g.bus_state }, g.bus_state),
      el("span", { class: "gateway-valves" }, `${g.valves_online}/${g.valves_known} online`),
      g.lost ? el("span", { class: "lost" }, "LOST (no word from it)") : "",
      yielded ? el("span", { class: "yielded" }, `${claim.address} given up`) : "");
    panel.querySelector("table").replaceChildren(
         row("interface", g.can_interface),
         row("bus state", g.bus_state, { class: "bus-state", "data-state": g.bus_state }),
         row("tx / rx errors", `${g.tx_errors} / ${g.rx_errors}`),
         row("frames in / out", `${g.frames_in} / ${g.frames_out}`),
         row("decode errors", g.decode_errors),
         row("dropped", g.rx_dropped),
         row("valves online / known", `${g.valves_online} / ${g.valves_known}`),
         ...claimRows(claim, row));
  }

  // The claim of the gateway's address, and each ECU that claimed one on its bus (its NAME's
  // function, manufacturer and identity as the server decoded them).
  function claimRows(claim, row) {
    const rows = [];
    if (claim.state === "yielded") {
      rows.push(row(`address ${claim.address}`, `given up to NAME ${claim.holder.name}`,
                    { class: "yielded" }));
    } else if (claim.state !== "off") {
      rows.push(row(`address ${claim.address}`, `${claim.state} as NAME ${claim.name.name}`));
    } else {
      rows.push(row("address claiming", "off"));
    }
    if (claim.violations > 0) rows.push(row("address violations", claim.violations));
    if (claim.claims_in_valve_range > 0) {
      rows.push(row("ECU claims at valve addresses", claim.claims_in_valve_range,
                    { class: "yielded" }));
    }
    for (const n of claim.neighbours) {
      const what = `NAME ${n.name.name} (function ${n.name.function}, ` +
                   `manufacturer ${n.name.manufacturer_code}, identity ${n.name.identity_number})`;
      rows.push(row(`neighbour ${n.address}`, what, { class: "neighbour" }));
    }
    return rows;
  }

  // ---- plot ----------------------------------------------------------------------------------

  // At most one paint per animation frame, and besides the once-a-second tick of the time axis,
  // none while no new data came.
  function requestPaint() {
    plotDirty = true;
    if (framePending) return;
    framePending = true;
    requestAnimationFrame(paint);
  }

  // The plot's fields: every number the valves report, position first.
  function buildPlotFields() {
    const select = $("plot-field");
    const chosen = select.value || "position.degrees";
    const fields = numericFields();
    const perSubject = (subject) => fields.filter((f) => f.subject === subject).length;
    select.replaceChildren(...fields.map((f) => el("option", { value: f.key },
      `${label(f.subject, f.name, perSubject(f.subject))}${f.field.unit ? ` (${f.field.unit})` : ""}`)));
    select.value = fields.some((f) => f.key === chosen) ? chosen : (fields[0] || {}).key || "";
    requestPaint();
  }

  function paint() {
    framePending = false;
    if (!plotDirty) return;
    plotDirty = false;
    const field = $("plot-field").value;
    const windowS = Number($("plot-window").value);
    let nowMs = 0;
    const series = [];
    for (const [serial, valve] of [...valves.entries()].sort((a, b) => (a[0] < b[0] ? -1 : 1))) {
      if (valve.history.length) nowMs = Math.max(nowMs, valve.history[valve.history.length - 1][0]);
      if (!valve.card.querySelector(".plot-pick").checked) continue;
      series.push({ label: serial, color: valve.color,
                    points: valve.history.map(([t, d]) => [t, telemetryValue(d, field)]) });
    }
    if (serverOffsetMs !== null) nowMs = Math.max(nowMs, Date.now() + serverOffsetMs);
    const chosen = $("plot-field").selectedOptions[0];
    plot.draw(series, nowMs || Date.now(), windowS, chosen ? chosen.textContent : "");
    stats.frames_painted += 1;
  }

  $("plot-field").addEventListener("change", requestPaint);
  $("plot-window").addEventListener("change", requestPaint);
  window.addEventListener("resize", requestPaint);
  // Once a second without data: the time axis moves on and still values extend to "now".
  setInterval(requestPaint, 1000);

  connect();
  requestPaint();
})();
