#!/usr/bin/env python3
"""The boom strip of a large sprayer in a real browser, run inside a private network namespace.

Two gateways, one per boom half and CAN bus, each with 32 simulated valves (--can sim:32) and a
layout of 32 places: `left` (left-master, section-01..section-31, orders 1-32) and `right`
(section-32..section-62, right-master, orders 33-64). The left layout also has section-07 waiting
for TJV000099 (never seen: missing) and section-21 empty; TJV000020, at section-19, latches a
high-voltage error at power-up. A teejet-web with --allow-commands; moves
are sent over its WebSocket naming the valves by location.

  (a) with the left gateway alone: the strip shows its 32 places in machine order with every
      state a glance should tell (open, closed, moving, error, missing, empty); a picture of it
      is kept as web-boom-32.png and copied to --screenshot PATH when given (docs/web.md's);
  (b) with both, 64 places in machine order across the two gateways, readable on a laptop
      (1366x768) and on a phone (390x844): the strip is no wider than the window, no cell's name
      is cut, the names are at least 10 px, and the whole strip fits in one window height.
      Pictures: web-boom-64-laptop.png, web-boom-64-phone.png.

Exit 77 (skipped) when chromium, chromedriver or python3-selenium is missing. Every wait is a
condition with a deadline; every failure says what differed.
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

# browser_test exits 77 without python3-selenium.
from browser_test import BOOM_JS, By, browser_missing, check, drive, parse_arguments
from browser_test import start_browser, wait_for_server
from web_client import WebSocket

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from waiting import eventually  # noqa: E402 (tests/support)

PORT = 18184


def left_layout():
    # section-n holds TJV(n+1) but section-07 (waits for TJV000099) and section-21 (empty); so
    # TJV000008 and TJV000022 sit nowhere.
    places = ["  - {name: left-master, order: 1, role: master, serial: TJV000001, opened_deg: 360}"]
    for n in range(1, 32):
        serial = {7: "TJV000099", 21: None}.get(n, f"TJV{n + 1:06d}")
        places.append(f"  - {{name: section-{n:02d}, order: {n + 1}"
                      + (f", serial: {serial}}}" if serial else "}"))
    return "default: {closed_deg: 0, opened_deg: 90}\nlocations:\n" + "\n".join(places) + "\n"


def right_layout():
    places = [f"  - {{name: section-{n:02d}, order: {n + 1}, serial: TJV{n + 69:06d}}}"
              for n in range(32, 63)]
    places.append("  - {name: right-master, order: 64, role: master, serial: TJV000132, "
                  "opened_deg: 360}")
    return "default: {closed_deg: 0, opened_deg: 90}\nlocations:\n" + "\n".join(places) + "\n"


def start_gateway(gateway, work, name, layout, config, log):
    paths = {}
    for kind, text in (("layout", layout), ("config", config)):
        paths[kind] = os.path.join(work, f"{name}-{kind}.yaml")
        with open(paths[kind], "w") as out:
            out.write(text)
    return subprocess.Popen([gateway, "--can", "sim:32", "--name", name, "--layout", paths["layout"],
                             "-c", paths["config"]],
                            stdout=open(log, "w"), stderr=subprocess.STDOUT)


def boom(driver):
    return driver.execute_script(BOOM_JS)


def send_moves(port, moves):
    """Each (location, degrees, speed %) as a page's move naming the valve by its place."""
    page = WebSocket(port)
    for n, (location, degrees, speed) in enumerate(moves):
        answer = page.answer(json.dumps({"id": n, "command": "move", "location": location,
                                         "degrees": degrees, "speed_percent": speed,
                                         "direction": "shortest"}))
        check(answer["type"] == "sent" and "command_id" in answer["commands"][0],
              f"move of {location}: {answer}")
    return page


def every_state(driver, artifacts, screenshot):
    """(a): the 32 places of the left boom with every state there is."""
    opened = [f"section-{n:02d}" for n in range(1, 14) if n != 7]
    eventually(lambda: boom(driver), 30, "the left boom's 32 places", ok=lambda b: len(b) == 32)
    send_moves(PORT, [(place, 90, 100) for place in opened]
                      + [("left-master", 180, 100), ("section-15", 80, 3)])
    wanted = dict([(p, "open") for p in opened + ["left-master"]]
                  + [("section-15", "moving"), ("section-19", "error"), ("section-07", "missing"),
                     ("section-21", "empty"), ("section-16", "closed")])
    cells = eventually(lambda: boom(driver), 30, f"the left boom's 32 places with {wanted}",
                       ok=lambda b: len(b) == 32
                       and all(dict(b).get(p) == s for p, s in wanted.items()))
    order = [p for p, _ in cells]
    check(order == ["left-master"] + [f"section-{n:02d}" for n in range(1, 32)],
          f"the strip's order: {order}")
    path = os.path.join(artifacts, "web-boom-32.png")
    check(driver.find_element(By.ID, "boom").screenshot(path), f"could not save {path}")
    if screenshot:
        shutil.copyfile(path, screenshot)
    states = sorted({s for _, s in cells})
    print(f"(a) 32 places in machine order, states {states}; picture {path}"
          + (f", copied to {screenshot}" if screenshot else ""))


READABLE_JS = """
const strip = document.querySelector('#boom-strip'), box = strip.getBoundingClientRect();
const cells = [...strip.querySelectorAll('.boom-cell')];
return {width: window.innerWidth, height: window.innerHeight,
        page_width: document.documentElement.scrollWidth,
        strip_width: box.width, strip_height: box.height,
        cut: cells.filter(c => [...c.children].some(s => s.scrollWidth > s.clientWidth + 0.5))
                  .map(c => c.dataset.location),
        smallest_font: Math.min(...cells.map(c => parseFloat(
            getComputedStyle(c.querySelector('.boom-name')).fontSize))),
        right_edge: Math.max(...cells.map(c => c.getBoundingClientRect().right)),
        rows: new Set(cells.map(c => Math.round(c.getBoundingClientRect().top))).size};
"""


def readable(driver, artifacts, size, name):
    """(b) at one window size: every cell whole, inside the window, in one window's height."""
    width, height = size
    driver.set_window_size(width, height)
    seen = eventually(lambda: driver.execute_script(READABLE_JS), 10,
                      f"the page laid out at {width} px wide",
                      ok=lambda r: abs(r["width"] - width) < 40)
    check(seen["page_width"] <= seen["width"] and seen["right_edge"] <= seen["width"],
          f"{name}: the boom is wider than the window: {seen}")
    check(not seen["cut"], f"{name}: cut names: {seen['cut']}")
    check(seen["smallest_font"] >= 10, f"{name}: names in {seen['smallest_font']} px type")
    check(seen["strip_height"] <= seen["height"],
          f"{name}: the strip ({seen['strip_height']:.0f} px) is taller than the window: {seen}")
    path = os.path.join(artifacts, f"web-boom-64-{name}.png")
    strip = driver.find_element(By.ID, "boom")
    driver.execute_script("arguments[0].scrollIntoView()", strip)
    check(strip.screenshot(path), f"could not save {path}")
    print(f"(b) {name} {width}x{height}: 64 cells in {seen['rows']} rows, "
          f"{seen['strip_width']:.0f}x{seen['strip_height']:.0f} px, names >= "
          f"{seen['smallest_font']} px, none cut; picture {path}")


def main():
    args = parse_arguments("also copy the 32-place picture here (docs/images/web-boom-32.png)")
    missing = browser_missing()
    if missing:
        print(missing)
        return 77
    work = tempfile.mkdtemp(prefix="teejet-web-boom-")
    logs = {name: os.path.join(work, f"{name}.log") for name in ("left", "right", "web")}
    processes = [start_gateway(args.gateway, work, "left", left_layout(),
                               "simulator:\n  errors: [\"TJV000020:high-voltage:16.2:15.5\"]\n",
                               logs["left"])]
    web = subprocess.Popen([args.web, "--listen", f"127.0.0.1:{PORT}", "--allow-commands"],
                           stdout=open(logs["web"], "w"), stderr=subprocess.STDOUT)
    processes.append(web)
    start = time.monotonic()

    def start_driver():
        wait_for_server(PORT, web, 15)
        return start_browser(work)

    def steps(driver):
        driver.get(f"http://127.0.0.1:{PORT}/")
        every_state(driver, args.artifacts, args.screenshot)
        processes.append(start_gateway(args.gateway, work, "right", right_layout(),
                                       "simulator: {first_serial: TJV000101}\n", logs["right"]))
        cells = eventually(lambda: boom(driver), 30, "64 places in machine order",
                           ok=lambda b: len(b) == 64)
        order = [p for p, _ in cells]
        check(order[31:34] == ["section-31", "section-32", "section-33"]
              and order[-1] == "right-master", f"the strip's order across the gateways: {order}")
        readable(driver, args.artifacts, (1366, 768), "laptop")
        readable(driver, args.artifacts, (390, 844), "phone")

    if drive(start_driver, steps, processes, logs,
             os.path.join(args.artifacts, "web-boom-failure.png")):
        return 1
    print(f"PASS in {time.monotonic() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
