#!/usr/bin/env python3
"""The dashboard over https in headless Chromium, run inside a private network namespace.

A gateway with 4 simulated valves (--can sim:4) and teejet-web with --allow-commands and a
certificate of the test's own web CA (tools/pki web). Chromium trusts that CA the way a bench
laptop does, through the NSS database of its (temporary) HOME, and nothing is waived: no
--ignore-certificate-errors. The page loads from https://127.0.0.1:PORT/, connects its wss, shows
the 4 cards online, and a move of TJV000003 to 90 degrees typed and clicked in the page reaches
"completed" in the card's status line.

Exit 77 (skipped) when chromium, chromedriver, python3-selenium or certutil is missing.
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile

# browser_test exits 77 without python3-selenium.
from browser_test import SERIALS, Failure, card, cards, check, degrees, stop_processes
from browser_test import By, Select, Service, webdriver

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from waiting import Timeout, eventually  # noqa: E402 (tests/support)

PORT = 18190
PKI = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "pki")


def trusting_home(work, ca):
    """A HOME whose NSS database trusts `ca` for servers, as a bench laptop's after import."""
    home = os.path.join(work, "home")
    nssdb = os.path.join(home, ".pki", "nssdb")
    os.makedirs(nssdb)
    subprocess.run(["certutil", "-d", f"sql:{nssdb}", "-N", "--empty-password"], check=True)
    subprocess.run(["certutil", "-d", f"sql:{nssdb}", "-A", "-t", "C,,", "-n", "teejet-test",
                    "-i", ca], check=True)
    return home


def start_browser(work, home):
    os.environ["HOME"] = home  # chromedriver and Chromium read the NSS database under it
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium")
    for argument in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                     "--window-size=1400,1000", "--disable-gpu", "--no-first-run",
                     f"--user-data-dir={os.path.join(work, 'chromium')}"):
        options.add_argument(argument)
    service = Service(shutil.which("chromedriver"), log_path=os.path.join(work, "chromedriver.log"))
    return webdriver.Chrome(service=service, options=options)


def https_page(driver):
    driver.get(f"https://127.0.0.1:{PORT}/")
    eventually(lambda: (driver.execute_script("return location.protocol"),
                        driver.find_element(By.ID, "connection").get_attribute("data-state")
                        if driver.find_elements(By.ID, "connection") else None,
                        [(c["serial"], c["online"]) for c in cards(driver)]),
               20, "https:, a connected page and 4 online cards TJV000001..TJV000004",
               ok=lambda seen: seen == ("https:", "connected", [(s, "true") for s in SERIALS]))
    print("https page: 4 cards online over wss")
    target = driver.find_element(By.CSS_SELECTOR, '.card[data-serial="TJV000003"]')
    before = card(driver, "TJV000003")
    check(degrees(before["position"]) is not None and abs(degrees(before["position"]) - 90) > 5,
          f"TJV000003 is already at {before['position']}: the move would prove nothing")
    for selector, value in ((".move-degrees", "90"), (".move-speed", "100")):
        field = target.find_element(By.CSS_SELECTOR, selector)
        field.clear()
        field.send_keys(value)
    Select(target.find_element(By.CSS_SELECTOR, ".move-direction")).select_by_value("shortest")
    target.find_element(By.CSS_SELECTOR, ".move-send").click()
    final = eventually(lambda: card(driver, "TJV000003"), 30,
                       "a final status of the move in TJV000003's status line",
                       ok=lambda c: c["final"] == "true")
    check(final["state"] == "completed", f"TJV000003's status line: {final['status']!r}")
    print(f"move from the https page: {final['status']!r}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--gateway", required=True)
    parser.add_argument("--web", required=True)
    args = parser.parse_args()
    for program in ("chromium", "chromedriver", "certutil"):
        if not shutil.which(program):
            print(f"SKIP: {program} is not installed (tools/install-deps.sh)")
            return 77
    work = tempfile.mkdtemp(prefix="teejet-web-browser-tls-")
    pki = os.path.join(work, "pki")
    subprocess.run([PKI, "web", pki, "teejet-web", "--ip", "127.0.0.1"], check=True,
                   capture_output=True)
    home = trusting_home(work, os.path.join(pki, "web-ca.pem"))
    logs = {name: os.path.join(work, f"{name}.log") for name in ("gateway", "web")}
    gateway = subprocess.Popen([args.gateway, "--can", "sim:4"],
                               stdout=open(logs["gateway"], "w"), stderr=subprocess.STDOUT)
    web = subprocess.Popen([args.web, "--listen", f"127.0.0.1:{PORT}", "--allow-commands",
                            "--tls-cert", f"{pki}/web/teejet-web/cert.pem",
                            "--tls-key", f"{pki}/web/teejet-web/key.pem"],
                           stdout=open(logs["web"], "w"), stderr=subprocess.STDOUT)
    driver = None
    try:
        driver = start_browser(work, home)
        https_page(driver)
    except (Failure, Timeout) as failure:
        print(f"FAIL: {failure}")
        if driver:
            print(f"page at the failure: {driver.current_url} {driver.title!r}")
        for name, path in logs.items():
            print(f"--- {name}.log\n{open(path).read()[-3000:]}")
        return 1
    finally:
        if driver:
            driver.quit()
        stop_processes((web, gateway))
    if web.returncode != 0:
        print(f"FAIL: teejet-web exited {web.returncode} after SIGTERM")
        return 1
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
