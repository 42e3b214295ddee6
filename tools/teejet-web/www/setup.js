"use strict";
// The setup view (only with --allow-commands): put a valve at a place of its gateway's layout by
// picking it from the unassigned list, typing its serial, or scanning the QR code on the valve
// with the device's camera; leave a place empty. The layout change goes to the gateway whose
// layout holds the place, which judges it and answers (docs/web.md, docs/layout.md).
//
// The QR decoder is jsQR (npm, pinned in tools/teejet-web/qr/package-lock.json), served by
// teejet-web itself as jsQR.js: nothing is fetched from the internet. The sheet does not say what
// else the code holds, so any text with "TJV" and six digits is taken as the valve's serial.
window.TeejetSetup = class TeejetSetup {
  // api: {el, send(command), notice(text)}: the page's element builder and command sender.
  constructor(root, api) {
    this.root = root;
    this.api = api;
    this.places = [];
    this.unassigned = [];
    this.changes = new Map();  // request id or change id -> location, until answered
    this.scanning = null;      // {stream, timer} while the camera runs
    const { el } = api;
    this.serial = el("input", { id: "assign-serial", class: "cmd", size: 11,
                                placeholder: "TJV000000", autocomplete: "off", spellcheck: "false" });
    this.location = el("select", { id: "assign-location", class: "cmd" });
    this.move = el("input", { id: "assign-move", type: "checkbox", class: "cmd" });
    this.status = el("div", { id: "setup-status", class: "command-status", "aria-live": "polite" });
    this.video = el("video", { id: "scan-video", playsinline: "", muted: "" });
    this.canvas = el("canvas", { id: "scan-canvas", hidden: "" });
    this.scanHint = el("div", { id: "scan-hint", class: "hint" });
    const scanStart = el("button", { id: "scan-start", class: "cmd", type: "button" }, "Scan QR");
    const scanStop = el("button", { id: "scan-stop", class: "cmd", type: "button" }, "Stop camera");
    const form = el("form", { id: "assign-form", class: "cmd" },
      el("label", {}, "valve ", this.serial), scanStart,
      el("label", {}, "to ", this.location),
      el("label", { class: "hint" }, this.move, " take it from its place"),
      el("button", { id: "assign", class: "cmd", type: "submit" }, "Assign"));
    root.replaceChildren(
      el("h2", {}, "Setup"), form,
      el("div", { id: "scanner", hidden: "" }, this.video, this.canvas, scanStop),
      this.scanHint, this.status,
      el("div", { class: "setup-lists" },
         el("div", {}, el("h3", {}, "Unassigned valves"), el("ul", { id: "unassigned-list" })),
         el("div", {}, el("h3", {}, "Places"),
            el("table", { id: "setup-places" },
               el("thead", {}, el("tr", {}, ...["#", "location", "gateway", "serial", "state", ""]
                 .map((h) => el("th", {}, h)))),
               el("tbody")))));
    form.addEventListener("submit", (event) => {
      event.preventDefault();
      this.assign();
    });
    scanStart.addEventListener("click", () => this.startScan());
    scanStop.addEventListener("click", () => this.stopScan("camera stopped"));
    if (typeof window.jsQR !== "function") {
      scanStart.disabled = true;
      scanStart.title = "this teejet-web was installed without its QR decoder (jsQR.js)";
    }
  }

  // places: every place of every layout, in machine order; unassigned: rows of online valves
  // in no place ({serial, gateway, address}).
  refresh(places, unassigned) {
    const key = JSON.stringify([places.map((p) => [p.gateway, p.location, p.serial, p.state]),
                                unassigned.map((v) => [v.serial, v.gateway])]);
    if (key === this.shown) return;
    this.shown = key;
    this.places = places;
    this.unassigned = unassigned;
    this.fillLocations();
    this.fillUnassigned();
    this.fillPlaces();
  }

  fillLocations() {
    const { el } = this.api;
    const chosen = this.location.value;
    this.location.replaceChildren(...this.places.map((p) => el("option", {
      value: p.location, "data-gateway": p.gateway },
      `${p.order} ${p.location} — ${p.state === "empty" ? "empty" : p.serial}` +
      `${p.state === "missing" ? " (missing)" : ""}`)));
    // Keep the person's choice; else offer the first place that needs a valve.
    const needing = this.places.find((p) => p.state === "empty" || p.state === "missing");
    if (this.places.some((p) => p.location === chosen)) this.location.value = chosen;
    else if (needing) this.location.value = needing.location;
  }

  fillUnassigned() {
    const { el } = this.api;
    const list = this.root.querySelector("#unassigned-list");
    if (this.unassigned.length === 0) {
      list.replaceChildren(el("li", { class: "empty" }, "none: every online valve has a place"));
      return;
    }
    list.replaceChildren(...this.unassigned.map((v) => {
      const pick = el("button", { type: "button", class: "cmd pick-unassigned",
                                  "data-serial": v.serial }, v.serial);
      pick.addEventListener("click", () => this.choose(v.serial, "picked"));
      return el("li", {}, pick, ` on ${v.gateway} at ${v.address}`);
    }));
  }

  fillPlaces() {
    const { el } = this.api;
    const rows = this.places.map((p) => {
      const unassign = el("button", { type: "button", class: "cmd unassign",
                                      "data-location": p.location }, "Unassign");
      unassign.disabled = p.state === "empty";
      unassign.addEventListener("click", () => this.sendChange({ command: "unassign",
                                                                 location: p.location }));
      return el("tr", { "data-location": p.location, "data-state": p.state },
                el("td", {}, String(p.order)), el("td", {}, p.location),
                el("td", {}, p.gateway), el("td", {}, p.serial || "—"),
                el("td", { class: "place-state" }, p.state), el("td", {}, unassign));
    });
    this.root.querySelector("#setup-places tbody").replaceChildren(...rows);
  }

  // A valve is assigned on its own gateway's bus: offer that gateway's first place needing one.
  choose(serial, how) {
    this.serial.value = serial;
    const valve = this.unassigned.find((v) => v.serial === serial);
    const needing = valve && this.places.find((p) => p.gateway === valve.gateway &&
                                                     (p.state === "empty" || p.state === "missing"));
    if (needing) this.location.value = needing.location;
    this.say("chosen", `${how} ${serial}: choose its location and Assign`);
  }

  assign() {
    const match = /TJV\d{6}/.exec(this.serial.value.trim().toUpperCase());
    if (!match) {
      this.say("refused", "the serial is TJV and six digits, as printed on the valve");
      return;
    }
    if (!this.location.value) {
      this.say("refused", "no location to assign to: no gateway has a layout");
      return;
    }
    this.sendChange({ command: "assign", location: this.location.value, serial: match[0],
                      move: this.move.checked });
  }

  sendChange(command) {
    const id = this.api.send(command);
    if (id === null) return;
    this.changes.set(`request ${id}`, command.location);
    this.say("sent", `${command.command} ${command.location}: sent…`);
  }

  // The server's answer to a layout change the page sent: its change id, or why not.
  onSent(message) {
    const location = this.changes.get(`request ${message.id}`);
    if (location === undefined) return false;
    this.changes.delete(`request ${message.id}`);
    for (const c of message.changes || []) {
      if (c.error) {
        this.say("error", `${c.location}: not sent: ${c.error}`);
      } else {
        this.changes.set(`change ${c.gateway}/${c.change_id}`, c.location);
        this.say("sent", `${c.location} on ${c.gateway}: #${c.change_id} sent, waiting for it`);
      }
    }
    return true;
  }

  onRefused(message) {
    if (!this.changes.delete(`request ${message.id}`)) return false;
    this.say("refused", `refused: ${message.reason}`);
    return true;
  }

  // A gateway's answer (a "layout_change" status); only those of this page's changes.
  onStatus(status) {
    const key = `change ${status.gateway}/${status.change_id}`;
    if (!this.changes.delete(key)) return;
    const where = `${status.location} on ${status.gateway}`;
    if (status.state === "applied") {
      const holds = status.serial ? `${status.serial} sits there` : "empty";
      this.say("applied", `${where}: applied: ${holds}` +
               (status.reason ? ` (${status.reason})` : ""));
    } else {
      this.say(status.state, `${where}: ${status.state}: ${status.reason}`);
    }
  }

  say(state, text) {
    this.status.dataset.state = state;
    this.status.textContent = text;
  }

  // ---- the camera --------------------------------------------------------------------------

  async startScan() {
    if (this.scanning) return;
    // Browsers give the camera to secure pages only: https, or http to localhost.
    if (!navigator.mediaDevices || !navigator.mediaDevices.getUserMedia) {
      this.scanSays("no camera here: browsers allow it over https only (teejet-web --tls-cert) " +
                    "or on localhost; type the serial instead");
      return;
    }
    let stream;
    try {
      stream = await navigator.mediaDevices.getUserMedia(
        { video: { facingMode: { ideal: "environment" } }, audio: false });
    } catch (error) {
      this.scanSays(`no camera: ${error.name === "NotAllowedError"
        ? "the browser was not allowed to use it" : error.message || error.name}`);
      return;
    }
    this.root.querySelector("#scanner").hidden = false;
    this.video.srcObject = stream;
    await this.video.play().catch(() => {});
    this.scanning = { stream, timer: setInterval(() => this.scanFrame(), 150) };
    this.scanSays("hold the valve's QR code in front of the camera");
  }

  scanFrame() {
    const video = this.video;
    if (!this.scanning || video.readyState < video.HAVE_CURRENT_DATA || !video.videoWidth) return;
    // Decoding a phone camera's full frame costs too much: at most 640 pixels wide suffices.
    const scale = Math.min(1, 640 / video.videoWidth);
    const w = Math.round(video.videoWidth * scale), h = Math.round(video.videoHeight * scale);
    if (this.canvas.width !== w || this.canvas.height !== h) {
      this.canvas.width = w;
      this.canvas.height = h;
    }
    const g = this.canvas.getContext("2d", { willReadFrequently: true });
    g.drawImage(video, 0, 0, w, h);
    const code = window.jsQR(g.getImageData(0, 0, w, h).data, w, h,
                             { inversionAttempts: "attemptBoth" });
    if (!code) return;
    const serial = /TJV\d{6}/.exec(code.data.toUpperCase());
    if (!serial) {
      this.scanSays(`a QR code, but without a TJV serial: “${code.data.slice(0, 40)}”`);
      return;
    }
    this.stopScan(`scanned ${serial[0]}`);
    this.choose(serial[0], "scanned");
  }

  stopScan(text) {
    if (this.scanning) {
      clearInterval(this.scanning.timer);
      for (const track of this.scanning.stream.getTracks()) track.stop();
      this.scanning = null;
    }
    this.video.srcObject = null;
    this.root.querySelector("#scanner").hidden = true;
    this.scanSays(text);
  }

  scanSays(text) {
    this.scanHint.textContent = text;
  }
};
