"""Waiting for a condition with a deadline, for the Python test scripts (the C++ suites have
tests/support/eventually.hpp). Poll, and on timeout fail naming what was awaited and the last
value seen: never sleep-and-hope, never wait without an end.

Import it with the path computed from the script's own place, e.g. for tests/web/x.py:
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
"""

import os
import time


def scaled(seconds):
    """`seconds` times TEEJET_DEADLINE_SCALE where that is set (a whole number; tools/test sets it
    for every test, the user-mode-linux tests through their own cache variable;
    tests/support/eventually.hpp reads the same): a deadline only bounds how long a failure
    takes to show."""
    return seconds * max(1, int(os.environ.get("TEEJET_DEADLINE_SCALE") or 1))


class Timeout(AssertionError):
    """A condition did not hold within its deadline."""


def latest(probe, timeout, ok=bool, interval=0.05, alive=None):
    """probe()'s first value that ok() accepts within `timeout` seconds (scaled()), else the last
    value seen: for callers whose own check judges and reports it.

    The probe runs once more after the deadline passed. `alive`, if given, runs before each probe
    and raises when waiting is pointless (a process the condition depends on exited)."""
    deadline = time.monotonic() + scaled(timeout)
    while True:
        if alive is not None:
            alive()
        seen = probe()
        if ok(seen) or time.monotonic() >= deadline:
            return seen
        time.sleep(interval)


def eventually(probe, timeout, what, ok=bool, interval=0.05, alive=None):
    """probe()'s first value that ok() accepts, within `timeout` seconds (see latest()).

    Raises Timeout naming `what` and the last value seen."""
    seen = latest(probe, timeout, ok, interval, alive)
    if not ok(seen):
        raise Timeout(f"{what} not within {scaled(timeout):g} s; last seen: {seen!r}")
    return seen


def first(probe, timeout, interval=0.05):
    """probe()'s first true value within `timeout` seconds, else None: for callers that decide
    themselves what a timeout means."""
    return latest(probe, timeout, interval=interval) or None
