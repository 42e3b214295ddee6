#!/usr/bin/env python3
"""The dashboard page in a real browser (issue 13), run inside a private network namespace.

A gateway with 4 simulated valves (--can sim:4), one teejet-web with --allow-commands and one
read-only, and headless Chromium driven by Selenium through chromedriver:

  (a) the page shows exactly the cards TJV000001..TJV000004, all online;
  (b) a move of TJV000002 to 90 degrees typed and clicked in the page reaches "completed" in the
      card's status line, and the dial's reading and needle follow to 90 +- 1; meanwhile the
      page writes to no other valve's card;
  (c) the read-only page has no command controls in its DOM, and a WebSocket opened by the page's
      own JavaScript that sends a move gets "refused" with the read-only reason; the valve stays;
  (d) a screenshot of the commanding page after the move (the plot showing it) is kept in the
      working directory as web-dashboard.png, and copied to --screenshot PATH when given;
  (e) when the read-only teejet-web stops, its page says it is reconnecting, and it is back with
      its 4 cards by itself once teejet-web runs again;
  (f) with --token, the page asks for it: a Stop without it is refused with the reason shown in
      the card; with it the command is sent and reaches its final status;
  (g) DNS rebinding: the browser resolves attacker.test to 127.0.0.1 (--host-resolver-rules); a
      page loaded as http://attacker.test:PORT/ gets 403, and the WebSocket its script opens
      to the commanding teejet-web to move TJV000004 is refused: the valve stays where it was;
  (h) clickjacking: a page of another local port that frames the dashboard gets no dashboard in
      its frame (the frame's document has no #cards);
  (i) the gateway's layout (--layout: section-01..03 hold TJV000001..3, section-04 is empty):
      the boom strip shows the four places in machine order, section-04 "empty"; the cards are
      titled by place with the serial beneath, and TJV000004 says it is unassigned;
  (j) Identify on TJV000003's card jogs it out and back twice: its status line ends "identified,
      back at 0.0°" and the dial is back at 0;
  (k) the setup view: the unassigned list shows TJV000004; the fake camera (Chromium's
      --use-file-for-fake-video-capture, a video of a QR code that qrencode made of a label
      holding "TJV000004" among other text) is scanned into the serial field; Assign to
      section-04 (offered first: it is empty) ends "applied: TJV000004 sits there"; the boom
      strip and TJV000004's card then show it at section-04, the unassigned list is empty, and
      the gateway's layout file holds TJV000004 at section-04.

Exit 77 (skipped) when chromium, chromedriver, python3-selenium or qrencode is missing. Every wait is a
condition with a deadline; every failure says what differed.
"""

import argparse
import functools
import http.server
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from waiting import Timeout, eventually  # noqa: E402 (tests/support)
from qr_video import QrencodeMissing, write_qr_video  # noqa: E402 (beside this file)

COMMANDS_PORT = 18180
READONLY_PORT = 18181
TOKEN_PORT = 18182
TOKEN = "s3cret"
FRAMING_PORT = 18183
REBOUND_NAME = "attacker.test"
SERIALS = ["TJV000001", "TJV000002", "TJV000003", "TJV000004"]
# What the valve's QR label holds: the sheet does not say, so the serial among other text.
QR_LABEL = "TeeJet valve SN:TJV000004 P/N 364E"
READ_ONLY_REASON = ("commands are disabled: teejet-web runs read-only (start it with "
                    "--allow-commands)")

try:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select
except ImportError:
    print("SKIP: python3-selenium is not installed (tools/install-deps.sh)")
    sys.exit(77)


class Failure(Exception):
    pass


def check(condition, message):
    if not condition:
        raise Failure(message)


def wait_for_server(port, process, seconds):
    def answer():
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/valves", timeout=2):
                return "answered"
        except OSError as error:  # not listening yet: the next try is the condition
            return str(error)

    eventually(answer, seconds, f"an answer of teejet-web on port {port}",
               ok=lambda seen: seen == "answered",
               alive=lambda: check(process.poll() is None,
                                   f"teejet-web on {port} exited {process.returncode}"))


CARDS_JS = """
return [...document.querySelectorAll('#cards .card')].map(c => ({
  serial: c.dataset.serial, online: c.dataset.online,
  position: c.querySelector('.position').textContent,
  title: c.querySelector('h2').textContent,
  beneath: c.querySelector('.card-serial').textContent,
  unassigned: c.dataset.unassigned,
  needle: c.querySelector('.needle').getAttribute('data-degrees'),
  status: c.querySelector('.command-status').textContent,
  state: c.querySelector('.command-status').dataset.state || null,
  final: c.querySelector('.command-status').dataset.final || null}));
"""


def cards(driver):
    return driver.execute_script(CARDS_JS)


def card(driver, serial):
    return next((c for c in cards(driver) if c["serial"] == serial), None)


def open_page(driver, port):
    driver.get(f"http://127.0.0.1:{port}/")
    eventually(lambda: (driver.find_element(By.ID, "connection").get_attribute("data-state"),
                        [(c["serial"], c["online"]) for c in cards(driver)]),
               15, "4 online cards TJV000001..TJV000004 and a connected page",
               ok=lambda seen: seen[0] == "connected" and seen[1] == [(s, "true") for s in SERIALS])


BOOM_JS = """
return [...document.querySelectorAll('#boom-strip .boom-cell')].map(c =>
  [c.dataset.location, c.dataset.state]);
"""
LAYOUT = """locations:
  - {name: section-01, order: 1, serial: TJV000001}
  - {name: section-02, order: 2, serial: TJV000002}
  - {name: section-03, order: 3, serial: TJV000003}
  - {name: section-04, order: 4}
"""


def boom_and_titles(driver):
    boom = eventually(lambda: driver.execute_script(BOOM_JS), 10,
                      "the boom strip with section-01..04, section-04 empty",
                      ok=lambda b: [p for p, _ in b] == ["section-01", "section-02", "section-03",
                                                         "section-04"]
                      and b[3][1] == "empty" and all(s != "missing" for _, s in b))
    titled = [(c["title"], c["beneath"], c["unassigned"]) for c in cards(driver)]
    check(titled == [("section-01", "TJV000001", "false"), ("section-02", "TJV000002", "false"),
                     ("section-03", "TJV000003", "false"), ("TJV000004", "unassigned", "true")],
          f"card titles (title, beneath, unassigned): {titled}")
    print(f"(i) boom strip {boom}; cards titled by place, TJV000004 unassigned")


def degrees(text):
    try:
        return float(text.rstrip("°"))
    except (AttributeError, ValueError):
        return None


SETUP_JS = """
const q = (s) => document.querySelector(s);
return {visible: !q('#setup').hidden,
        unassigned: [...document.querySelectorAll('#unassigned-list .pick-unassigned')]
                      .map(b => b.dataset.serial),
        serial: q('#assign-serial') ? q('#assign-serial').value : null,
        location: q('#assign-location') ? q('#assign-location').value : null,
        hint: q('#scan-hint') ? q('#scan-hint').textContent : null,
        status: q('#setup-status') ? q('#setup-status').textContent : null,
        state: q('#setup-status') ? (q('#setup-status').dataset.state || null) : null};
"""


# Which cards the page writes to while it runs: the serial of every card a DOM change touched.
# An update rewrites only what changed, so a move touches the moving valve's card alone (a page
# rewriting every card on every update cost Chromium a whole core at 256 valves).
CARD_WRITES_JS = """
const cards = document.getElementById('cards');
const touched = new Set();
const observer = new MutationObserver((records) => {
  for (const record of records) {
    const node = record.target.nodeType === Node.ELEMENT_NODE ? record.target
                                                              : record.target.parentElement;
    const card = node && node.closest('.card');
    touched.add(card ? card.dataset.serial : '(outside a card)');
  }
});
observer.observe(cards, {subtree: true, childList: true, characterData: true, attributes: true});
window.__cardWrites = () => { observer.disconnect(); return [...touched].sort(); };
"""


def setup_view(driver, layout, artifacts):
    driver.find_element(By.ID, "setup-toggle").click()
    seen = eventually(lambda: driver.execute_script(SETUP_JS), 10,
                      "the setup view listing TJV000004 as unassigned",
                      ok=lambda v: v["visible"] and v["unassigned"] == ["TJV000004"])
    check(seen["location"] == "section-04",
          f"the setup view offers {seen['location']!r} first, not the empty section-04")
    driver.find_element(By.ID, "scan-start").click()
    scanned = eventually(lambda: driver.execute_script(SETUP_JS), 20,
                         "the camera's QR code read into the serial field",
                         ok=lambda v: v["serial"] == "TJV000004")
    check(scanned["hint"] == "scanned TJV000004", f"the scanner says {scanned['hint']!r}")
    driver.find_element(By.ID, "assign").click()
    done = eventually(lambda: driver.execute_script(SETUP_JS), 20,
                      "the gateway's answer to the assignment in the setup view",
                      ok=lambda v: v["state"] not in (None, "sent", "chosen"))
    check(done["state"] == "applied" and done["status"].startswith("section-04 on ")
          and done["status"].endswith(": applied: TJV000004 sits there"),
          f"the setup view's status: {done['status']!r} (state {done['state']})")
    boom = eventually(lambda: driver.execute_script(BOOM_JS), 10,
                      "section-04 holding its valve on the boom strip",
                      ok=lambda b: dict(b).get("section-04") not in (None, "empty"))
    placed = eventually(lambda: card(driver, "TJV000004"), 10, "TJV000004's card titled section-04",
                        ok=lambda c: c["title"] == "section-04" and c["beneath"] == "TJV000004")
    after = eventually(lambda: driver.execute_script(SETUP_JS), 10, "no valve left unassigned",
                       ok=lambda v: v["unassigned"] == [])
    with open(layout) as text:
        saved = [line for line in text if "section-04" in line]
    check(len(saved) == 1 and "TJV000004" in saved[0],
          f"the gateway's layout file at section-04: {saved}")
    path = os.path.join(artifacts, "web-setup.png")
    check(driver.find_element(By.ID, "setup").screenshot(path), f"could not save {path}")
    print(f"(k) setup view: scanned {scanned['serial']!r} from the camera, {done['status']!r}; "
          f"boom {boom}, card {placed['title']}/{placed['beneath']}, "
          f"unassigned {after['unassigned']}; layout file: {saved[0].strip()}; picture: {path}")


def commanding_page(driver, artifacts, screenshot, layout):
    open_page(driver, COMMANDS_PORT)
    check(driver.find_elements(By.ID, "stop-all"), "the commanding page has no Stop all button")
    mode = driver.find_element(By.ID, "mode").text
    check(mode == "commands allowed", f"mode badge: {mode!r}, not 'commands allowed'")
    print("(a) 4 cards TJV000001..TJV000004 online")
    boom_and_titles(driver)

    target = driver.find_element(By.CSS_SELECTOR, '.card[data-serial="TJV000002"]')
    before = card(driver, "TJV000002")
    check(degrees(before["position"]) is not None and abs(degrees(before["position"]) - 90) > 5,
          f"TJV000002 is already at {before['position']}: the move would prove nothing")
    field = target.find_element(By.CSS_SELECTOR, ".move-degrees")
    field.clear()
    field.send_keys("90")
    speed = target.find_element(By.CSS_SELECTOR, ".move-speed")
    speed.clear()
    speed.send_keys("100")
    Select(target.find_element(By.CSS_SELECTOR, ".move-direction")).select_by_value("shortest")
    frames_before = driver.execute_script("return window.teejetDashboard.stats.frames_painted")
    driver.execute_script(CARD_WRITES_JS)
    target.find_element(By.CSS_SELECTOR, ".move-send").click()
    final = eventually(lambda: card(driver, "TJV000002"), 30,
                       "a final status of the move in TJV000002's status line",
                       ok=lambda c: c["final"] == "true")
    check(final["state"] == "completed" and "completed" in final["status"],
          f"TJV000002's status line: {final['status']!r} (state {final['state']}), not completed")
    check(final["status"].startswith("target_degrees #"),
          f"status line {final['status']!r} does not name the target_degrees command")
    moved = eventually(lambda: card(driver, "TJV000002"), 10,
                       "TJV000002's dial at 90 +- 1 (reading and needle)",
                       ok=lambda c: (degrees(c["position"]) is not None and c["needle"] is not None
                                     and abs(degrees(c["position"]) - 90) <= 1
                                     and abs(float(c["needle"]) - 90) <= 1))
    # The simulated valve then comes to rest on its target; (c) watches it stay there.
    eventually(lambda: card(driver, "TJV000002"), 10, "TJV000002 at rest on 90.0",
               ok=lambda c: c["position"] == "90.0°" and c["needle"] == "90")
    others = [c for c in cards(driver) if c["serial"] != "TJV000002" and c["state"] is not None]
    check(not others, f"a status line on a valve that was not commanded: {others}")
    written = driver.execute_script("return window.__cardWrites()")
    check(written == ["TJV000002"],
          f"the page wrote to the cards of {written} while only TJV000002 moved")
    print(f"(b) move to 90 completed: status {final['status']!r}, dial {moved['position']}, "
          f"needle {moved['needle']}")

    # The plot has painted the movement, on its shortest window, before the picture is taken.
    Select(driver.find_element(By.ID, "plot-window")).select_by_value("60")
    eventually(lambda: driver.execute_script("return window.teejetDashboard.stats"), 5,
               "a plot repaint after the move",
               ok=lambda s: s["frames_painted"] > frames_before + 1)
    stats = driver.execute_script("return window.teejetDashboard.stats")
    for key in ("messages", "updates_per_s", "valve_updates", "valve_updates_per_s",
                "last_message_ms", "frames_painted"):
        check(key in stats, f"window.teejetDashboard.stats has no {key}: {stats}")
    check(stats["messages"] > 0 and stats["valve_updates"] > 0, f"page statistics: {stats}")
    path = os.path.join(artifacts, "web-dashboard.png")
    check(driver.save_screenshot(path), f"could not save the screenshot to {path}")
    print(f"(d) screenshot: {path}")
    if screenshot:
        shutil.copyfile(path, screenshot)
        print(f"(d) copied to {screenshot}")
    identify(driver)
    setup_view(driver, layout, artifacts)
    return moved


def identify(driver):
    start = card(driver, "TJV000003")["position"]
    driver.find_element(By.CSS_SELECTOR, '.card[data-serial="TJV000003"] .identify').click()
    done = eventually(lambda: card(driver, "TJV000003"), 40,
                      "the end of TJV000003's identify in its status line",
                      ok=lambda c: c["final"] == "true")
    check(done["state"] == "identified" and done["status"] == f"identified, back at {start}",
          f"TJV000003's status line after identify: {done['status']!r} (state {done['state']})")
    back = eventually(lambda: card(driver, "TJV000003"), 10, f"TJV000003's dial back at {start}",
                      ok=lambda c: c["position"] == start)
    print(f"(j) identify: {done['status']!r}, dial {back['position']}")


def read_only_page(driver):
    open_page(driver, READONLY_PORT)
    mode = driver.find_element(By.ID, "mode").text
    check(mode == "read-only", f"mode badge: {mode!r}, not 'read-only'")
    # A healthy gateway is one folded line: eight fit beside the plot.
    panels = eventually(lambda: driver.execute_script("""
      return [...document.querySelectorAll('#gateway-list details.gateway')].map(
          p => ({open: p.open, line: p.querySelector('summary').textContent}));"""), 15,
                        "one folded gateway line saying 4/4 online",
                        ok=lambda seen: len(seen) == 1 and "4/4 online" in seen[0]["line"])
    check(not panels[0]["open"] and "error_active" in panels[0]["line"],
          f"the gateway's line: {panels}")
    # Folded under it: its claim of 0xD5 on the bus (docs/isobus.md).
    claim = eventually(lambda: driver.execute_script(
        "return document.querySelector('#gateway-list details.gateway table').textContent;"), 15,
                       "the gateway's claim of 0xD5 in its panel",
                       ok=lambda text: "claimed as NAME 0x2008800000000000" in text)
    check("address 0xD5" in claim, f"the gateway's panel: {claim!r}")
    controls = driver.execute_script("""
      return [...document.querySelectorAll(
          '.cmd, button, form, #stop-all, #token, input:not(.plot-pick), ' +
          'select:not(#plot-field):not(#plot-window)')].map(e => e.outerHTML.slice(0, 80));""")
    check(controls == [], f"command controls in the read-only page's DOM: {controls}")
    before = card(driver, "TJV000002")
    answer = driver.execute_async_script("""
      const done = arguments[arguments.length - 1];
      const ws = new WebSocket(`ws://${location.host}/ws`);
      ws.onmessage = (event) => {
        const message = JSON.parse(event.data);
        if (message.type === 'snapshot') {
          ws.send(JSON.stringify({id: 41, command: 'move', serial: 'TJV000002', degrees: 10,
                                  speed_percent: 100, direction: 'shortest'}));
        } else if (message.type === 'refused' || message.type === 'sent') {
          ws.close();
          done(message);
        }
      };
      ws.onerror = () => done({type: 'websocket error'});""")
    check(answer == {"type": "refused", "id": 41, "reason": READ_ONLY_REASON},
          f"answer to a move from the read-only page: {answer}")
    # The valve does not move: watch it while the page takes 3 more updates. Each one comes
    # with new gateway counters (a poll of the valves, about once a second) or a changed valve,
    # so that is over a second of polls: enough for a sent move to start turning it.
    messages = driver.execute_script("return window.teejetDashboard.stats.messages")
    eventually(lambda: driver.execute_script("return window.teejetDashboard.stats.messages"), 15,
               "3 more messages on the read-only page", ok=lambda n: n >= messages + 3)
    after = card(driver, "TJV000002")
    check(after["position"] == before["position"] and after["needle"] == before["needle"],
          f"TJV000002 moved on a read-only page: {before['position']} -> {after['position']}")
    print(f"(c) read-only: no controls, move refused ({answer['reason']!r}), TJV000002 stays at "
          f"{after['position']}")


def token_page(driver):
    open_page(driver, TOKEN_PORT)
    mode = driver.find_element(By.ID, "mode").text
    check(mode == "commands allowed (token)", f"mode badge: {mode!r}")
    check(driver.find_elements(By.ID, "token"), "no token field on a page that needs one")
    stop = driver.find_element(By.CSS_SELECTOR, '.card[data-serial="TJV000003"] .stop')
    stop.click()
    refused = eventually(lambda: card(driver, "TJV000003"), 10,
                         "TJV000003's Stop without a token answered",
                         ok=lambda c: c["state"] == "refused")
    check(refused["status"] == 'refused: missing or wrong "token"',
          f"status line of a Stop without the token: {refused['status']!r}")
    driver.find_element(By.ID, "token").send_keys(TOKEN)
    stop.click()
    sent = eventually(lambda: card(driver, "TJV000003"), 15,
                      "TJV000003's Stop with the token reaching the gateway",
                      ok=lambda c: c["state"] not in ("refused", "sent", None))
    check(sent["status"].startswith("stop #"), f"status line of a Stop with the token: "
                                                f"{sent['status']!r} ({sent['state']})")
    print(f"(f) token: refused without it, {sent['status']!r} with it")


def valve_position(port, serial):
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/valves", timeout=5) as response:
        return next(v["position"] for v in json.load(response) if v["serial"] == serial)


def rebinding(driver):
    """A page of attacker.test, its name rebound to 127.0.0.1, tries to move a valve."""
    before = valve_position(COMMANDS_PORT, "TJV000004")
    check(before is not None and abs(before - 200) > 5,
          f"TJV000004 is at {before}: a move to 200 would prove nothing")
    driver.get(f"http://{REBOUND_NAME}:{COMMANDS_PORT}/")
    body = driver.find_element(By.TAG_NAME, "body").text
    check("does not serve this Host name" in body, f"the page of {REBOUND_NAME}: {body[:200]!r}")
    outcome = driver.execute_async_script("""
      const done = arguments[arguments.length - 1];
      const seen = [];
      const ws = new WebSocket(`ws://${location.host}/ws`);
      ws.onopen = () => {
        seen.push('open');
        ws.send(JSON.stringify({id: 1, command: 'move', serial: 'TJV000004', degrees: 200,
                                speed_percent: 100, direction: 'shortest'}));
      };
      ws.onmessage = (event) => seen.push(JSON.parse(event.data).type);
      ws.onclose = () => { seen.push('closed'); done(seen); };""")
    check(outcome == ["closed"], f"the rebound page's WebSocket: {outcome}, not closed unopened")
    # The valve would start turning within a poll; it was never sent a command, so it stays.
    after = valve_position(COMMANDS_PORT, "TJV000004")
    check(after == before, f"TJV000004 moved from {before} to {after} for a rebound page")
    print(f"(g) rebinding: {REBOUND_NAME} got 403, its WebSocket {outcome}, TJV000004 stays at "
          f"{after}")


def framing(driver, work):
    """Another local site frames the dashboard to trick a click: the frame stays empty."""
    with open(os.path.join(work, "frame.html"), "w") as page:
        page.write(f'<!doctype html><iframe id="victim" width="800" height="600" '
                   f'src="http://127.0.0.1:{COMMANDS_PORT}/"></iframe>')
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=work)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", FRAMING_PORT), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        driver.get(f"http://127.0.0.1:{FRAMING_PORT}/frame.html")

        def frame_content():
            driver.switch_to.default_content()
            driver.switch_to.frame(driver.find_element(By.ID, "victim"))
            return driver.execute_script(
                "return {url: document.URL, ready: document.readyState, "
                "cards: document.getElementById('cards') !== null}")

        # Blocked, the frame holds Chromium's error document once it is done loading.
        seen = eventually(frame_content, 10, "the framed dashboard loaded or blocked",
                          ok=lambda seen: seen["ready"] == "complete" and
                          seen["url"] != "about:blank")
        check(not seen["cards"], f"the dashboard showed in another site's frame: {seen}")
        print(f"(h) framing: the frame holds {seen['url']!r}, no dashboard")
    finally:
        driver.switch_to.default_content()
        server.shutdown()
        server.server_close()


def reconnects(driver, restart):
    """The page shows that its server went away, and comes back by itself when it returns."""
    stopped = restart.stop()
    eventually(lambda: (driver.find_element(By.ID, "connection").get_attribute("data-state"),
                        driver.find_element(By.ID, "connection").text),
               10, "the connection badge saying reconnecting",
               ok=lambda seen: seen[0] == "reconnecting" and seen[1].startswith("reconnecting in"))
    check(stopped == 0, f"the read-only teejet-web exited {stopped} after SIGTERM")
    restart.start()
    eventually(lambda: (driver.find_element(By.ID, "connection").get_attribute("data-state"),
                        [(c["serial"], c["online"]) for c in cards(driver)]),
               20, "the page connected again with 4 online cards",
               ok=lambda seen: seen[0] == "connected" and seen[1] == [(s, "true") for s in SERIALS])
    print("(e) the page showed reconnecting while teejet-web was down, and came back by itself")


class Restartable:
    def __init__(self, argv, log):
        self.argv, self.log = argv, log
        self.process = None
        self.start()

    def start(self):
        self.process = subprocess.Popen(self.argv, stdout=open(self.log, "a"),
                                        stderr=subprocess.STDOUT)

    def stop(self):
        self.process.terminate()
        try:
            return self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            return self.process.wait()

    def poll(self):
        return self.process.poll()

    def terminate(self):
        self.process.terminate()

    def wait(self, timeout):
        return self.process.wait(timeout=timeout)

    def kill(self):
        self.process.kill()

    @property
    def returncode(self):
        return self.process.returncode


def start_browser(work, camera_video=None, window="1400,1000"):
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium")
    arguments = ["--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                 f"--window-size={window}", "--disable-gpu", "--no-first-run",
                 "--hide-scrollbars", f"--user-data-dir={os.path.join(work, 'chromium')}",
                 f"--host-resolver-rules=MAP {REBOUND_NAME} 127.0.0.1"]
    if camera_video:
        # The camera is a file (an absolute path: Chromium resolves a relative one against its
        # own working directory), and no permission prompt is shown for it.
        arguments += ["--use-fake-device-for-media-stream", "--use-fake-ui-for-media-stream",
                      f"--use-file-for-fake-video-capture={os.path.abspath(camera_video)}"]
    for argument in arguments:
        options.add_argument(argument)
    service = Service(shutil.which("chromedriver"), log_path=os.path.join(work, "chromedriver.log"))
    return webdriver.Chrome(service=service, options=options)


def stop_processes(processes):
    """SIGTERM each, SIGKILL what has not exited 10 s later (their exit status stays readable)."""
    for process in processes:
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()


def parse_arguments(screenshot_help):
    parser = argparse.ArgumentParser()
    parser.add_argument("--gateway", required=True)
    parser.add_argument("--web", required=True)
    parser.add_argument("--artifacts", default=os.getcwd(),
                        help="where the pictures are kept (default: the working directory)")
    parser.add_argument("--screenshot", help=screenshot_help)
    return parser.parse_args()


def browser_missing():
    """Why the page cannot be tested here (a SKIP line), or None."""
    for program in ("chromium", "chromedriver"):
        if not shutil.which(program):
            return f"SKIP: {program} is not installed (tools/install-deps.sh)"
    return None


def drive(start_driver, steps, processes, logs, failure_picture):
    """Runs steps(driver) on the browser start_driver() opens; on a failure prints it, a picture
    of the page and the end of every log. Stops the browser and the processes either way. 0 when
    the steps passed, 1 otherwise."""
    driver = None
    try:
        driver = start_driver()
        steps(driver)
    except (Failure, Timeout) as failure:
        print(f"FAIL: {failure}")
        if driver:
            driver.save_screenshot(failure_picture)
            print(f"page at the failure: {failure_picture}")
        for name, path in logs.items():
            if os.path.exists(path):
                print(f"--- {name}.log\n{open(path).read()[-3000:]}")
        return 1
    finally:
        if driver:
            driver.quit()
        stop_processes(reversed(processes))
    return 0


def main():
    args = parse_arguments("also copy the screenshot here (the README's)")
    missing = browser_missing()
    if missing:
        print(missing)
        return 77
    work = tempfile.mkdtemp(prefix="teejet-web-browser-")
    camera_video = os.path.join(work, "valve-label.y4m")
    try:
        write_qr_video(QR_LABEL, camera_video, frames=2)
    except QrencodeMissing as missing:
        print(f"SKIP: {missing}")
        return 77
    logs = {name: os.path.join(work, f"{name}.log") for name in ("gateway", "web", "web-ro", "web-token")}
    layout = os.path.join(work, "boom.yaml")
    with open(layout, "w") as text:
        text.write(LAYOUT)
    processes = [subprocess.Popen([args.gateway, "--can", "sim:4", "--layout", layout],
                                  stdout=open(logs["gateway"], "w"), stderr=subprocess.STDOUT)]
    commanding = subprocess.Popen([args.web, "--listen", f"127.0.0.1:{COMMANDS_PORT}",
                                   "--allow-commands"],
                                  stdout=open(logs["web"], "w"), stderr=subprocess.STDOUT)
    read_only = Restartable([args.web, "--listen", f"127.0.0.1:{READONLY_PORT}"], logs["web-ro"])
    with_token = subprocess.Popen([args.web, "--listen", f"127.0.0.1:{TOKEN_PORT}",
                                   "--allow-commands", "--token", TOKEN],
                                  stdout=open(logs["web-token"], "w"), stderr=subprocess.STDOUT)
    processes += [commanding, read_only, with_token]
    start = time.monotonic()

    def start_driver():
        wait_for_server(COMMANDS_PORT, commanding, 15)
        wait_for_server(READONLY_PORT, read_only, 15)
        return start_browser(work, camera_video)

    def steps(driver):
        commanding_page(driver, args.artifacts, args.screenshot, layout)
        rebinding(driver)
        framing(driver, work)
        read_only_page(driver)
        reconnects(driver, read_only)
        wait_for_server(TOKEN_PORT, with_token, 15)
        token_page(driver)

    if drive(start_driver, steps, processes, logs,
             os.path.join(args.artifacts, "web-dashboard-failure.png")):
        return 1
    for process, name in ((commanding, "commanding"), (read_only, "read-only"),
                          (with_token, "token")):
        if process.returncode != 0:
            print(f"FAIL: the {name} teejet-web exited {process.returncode} after SIGTERM")
            return 1
    print(f"PASS in {time.monotonic() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
