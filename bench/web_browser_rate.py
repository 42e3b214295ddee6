#!/usr/bin/python3
"""What reaches a browser from teejet-web (docs/performance.md, "Dashboard").

Opens the dashboard in headless Chromium (Selenium, chromedriver), waits for --valves cards,
settles, then measures for --seconds on the page's own WebSocket (wrapped before the page's script
runs, so the count is independent of the page's code): update messages per second, valve entries
per second, bytes per second, the gap between updates (p50/p99/max) and the delay from the
server's stamp_ms to the browser's receipt (same host clock); plus the page's own
window.teejetDashboard.stats (frames painted), the browser's own main-thread time for each frame
that shows a change (script, style, layout and paint: p50/p99/max), the frames over 50 ms
whatever their cause (Long Animation Frames), and the CPU of Chromium's processes.
Run it inside the bench's network namespace (bench/run-web-bench.sh), never on the host.
"""

import argparse
import os
import sys
import time

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.support.ui import WebDriverWait

WRAP = r"""
(() => {
  const Native = window.WebSocket;
  const s = {updates: 0, valves: 0, bytes: 0, delays: [], gaps: [], last: 0, on: false};
  window.__webBench = s;
  function Wrapped(url, protocols) {
    const ws = protocols === undefined ? new Native(url) : new Native(url, protocols);
    ws.addEventListener('message', (event) => {
      if (!s.on) return;
      const now = performance.timeOrigin + performance.now();
      const message = JSON.parse(event.data);
      if (message.type !== 'update') return;
      s.updates += 1;
      s.valves += (message.valves || []).length;
      s.bytes += event.data.length;
      s.delays.push(now - message.stamp_ms);
      if (s.last) s.gaps.push(now - s.last);
      s.last = now;
      s.measureNextFrame();
    });
    return ws;
  }
  Wrapped.prototype = Native.prototype;
  for (const k of ['CONNECTING', 'OPEN', 'CLOSING', 'CLOSED']) Wrapped[k] = Native[k];
  window.WebSocket = Wrapped;

  // The browser's own time per frame that shows a change: from the start of the frame's
  // animation frame callbacks (ours first: it is asked for when an update arrives, before the
  // page's handler writes it, and before each of the page's own) to the first task after that
  // frame, which runs once the browser has done its script, style, layout and paint on the main
  // thread. A frame is asked for only where the page changes something anyway.
  s.frames = [];
  s.longFrames = 0;
  s.longestFrame = 0;
  const nativeFrame = window.requestAnimationFrame.bind(window);
  const after = new MessageChannel();
  let frameStart = null;
  let measuring = false;
  after.port1.onmessage = () => {
    if (frameStart !== null && s.on) s.frames.push(performance.now() - frameStart);
    frameStart = null;
    measuring = false;
  };
  s.measureNextFrame = () => {
    if (!s.on || measuring) return;
    measuring = true;
    nativeFrame(() => {
      frameStart = performance.now();
      after.port2.postMessage(0);
    });
  };
  window.requestAnimationFrame = (callback) => {
    s.measureNextFrame();
    return nativeFrame(callback);
  };
  // Frames over 50 ms, whoever caused them (Long Animation Frames).
  if ((PerformanceObserver.supportedEntryTypes || []).includes('long-animation-frame')) {
    new PerformanceObserver((list) => {
      if (!s.on) return;
      for (const entry of list.getEntries()) {
        s.longFrames += 1;
        s.longestFrame = Math.max(s.longestFrame, entry.duration);
      }
    }).observe({type: 'long-animation-frame'});
  } else {
    s.longFrames = null;
  }
})();
"""


def cpu_ticks_of(names):
    total = 0
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open(f"/proc/{pid}/stat") as f:
                stat = f.read()
        except OSError:
            continue
        comm = stat[stat.index("(") + 1:stat.rindex(")")]
        if comm in names:
            fields = stat[stat.rindex(")") + 2:].split()
            total += int(fields[11]) + int(fields[12])
    return total


def quantile(values, q):
    if not values:
        return float("nan")
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--url", required=True)
    parser.add_argument("--valves", type=int, default=32)
    parser.add_argument("--seconds", type=float, default=30)
    parser.add_argument("--settle", type=float, default=5)
    args = parser.parse_args()

    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for flag in ("--headless=new", "--no-sandbox", "--window-size=1400,1000"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    try:
        driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": WRAP})
        driver.get(args.url)
        WebDriverWait(driver, 30).until(
            lambda d: len(d.find_elements("css selector", "[data-serial]")) >= args.valves,
            f"the page did not show {args.valves} valves within 30 s")
        time.sleep(args.settle)  # the window starts once the page and the valves are steady
        hz = os.sysconf("SC_CLK_TCK")
        page0 = driver.execute_script("return window.teejetDashboard && window.teejetDashboard.stats")
        chromium0 = cpu_ticks_of({"chromium", "chrome"})
        driver.execute_script("window.__webBench.on = true")
        start = time.monotonic()
        time.sleep(args.seconds)  # the measured window itself, not a wait for a condition
        driver.execute_script("window.__webBench.on = false")
        elapsed = time.monotonic() - start
        chromium1 = cpu_ticks_of({"chromium", "chrome"})
        page1 = driver.execute_script("return window.teejetDashboard && window.teejetDashboard.stats")
        s = driver.execute_script(
            "const s = window.__webBench; return {updates: s.updates, valves: s.valves, "
            "bytes: s.bytes, gaps: s.gaps, delays: s.delays, frames: s.frames, "
            "longFrames: s.longFrames, longestFrame: s.longestFrame}")
        cards = len(driver.find_elements("css selector", "[data-serial]"))
    finally:
        driver.quit()
    painted = "n/a"
    if page0 and page1 and "frames_painted" in page1:
        painted = f"{(page1['frames_painted'] - page0['frames_painted']) / elapsed:.1f}/s"
    print(f"WEB_BROWSER cards={cards} seconds={elapsed:.1f} updates={s['updates']} "
          f"updates_per_s={s['updates'] / elapsed:.1f} valve_entries_per_s={s['valves'] / elapsed:.0f} "
          f"bytes_per_s={s['bytes'] / elapsed:.0f} "
          f"gap_ms_p50={quantile(s['gaps'], 0.5):.1f} gap_ms_p99={quantile(s['gaps'], 0.99):.1f} "
          f"gap_ms_max={max(s['gaps'] or [float('nan')]):.1f} "
          f"delay_ms_p50={quantile(s['delays'], 0.5):.1f} delay_ms_p99={quantile(s['delays'], 0.99):.1f} "
          f"delay_ms_max={max(s['delays'] or [float('nan')]):.1f} "
          f"frames_painted={painted} frames_measured={len(s['frames'])} "
          f"frame_ms_p50={quantile(s['frames'], 0.5):.1f} frame_ms_p99={quantile(s['frames'], 0.99):.1f} "
          f"frame_ms_max={max(s['frames'] or [float('nan')]):.1f} "
          f"long_frames={'n/a' if s['longFrames'] is None else s['longFrames']} "
          f"long_frame_ms_max={s['longestFrame']:.1f} "
          f"chromium_cpu={100 * (chromium1 - chromium0) / hz / elapsed:.1f}%")
    return 0 if s["updates"] > 0 and cards >= args.valves else 1


if __name__ == "__main__":
    sys.exit(main())
