"""Progress that suits where it goes.

On a terminal a long loop shows a tqdm bar. Where nobody watches a bar (output redirected to a
file, a Hydra log, CI with CI=true), carriage-return updates only bloat the file: each loop and
each phase writes one log line with its count and duration when it ends instead, and a loop
that runs longer than HEARTBEAT_S adds one line per HEARTBEAT_S so a long phase is never silent.

    for fold in progress(folds, desc="k-fold"): ...
    bar = progress(total=n, desc="rubber12", unit="press"); bar.update(k); bar.close()
    bar = progress(desc="reading rig.csv", unit="rows", announce=True)   # a first line at once, too
    with phase("ONNX export"): ...
"""
import logging
import os
import sys
import time
from contextlib import contextmanager

from tqdm.auto import tqdm

log = logging.getLogger("touchstone")
HEARTBEAT_S = 30.0


def on_terminal() -> bool:
    """A bar is worth drawing: stderr is a terminal and we are not under CI."""
    if os.environ.get("CI", "").strip().lower() in ("1", "true", "yes"):
        return False
    return sys.stderr.isatty()


class _Quiet:
    """tqdm's interface without drawing: counts, and logs one line at close."""

    def __init__(self, iterable, desc, total, unit, enabled):
        self.iterable, self.desc, self.total, self.unit = iterable, desc, total, unit
        self.enabled, self.n, self.postfix = enabled, 0, ""
        self.start = self.last_line = time.perf_counter()
        self.closed = False

    def __iter__(self):
        try:
            for item in self.iterable:
                self.n += 1  # counted on entry, so a loop left by `break` reports its last round
                self._heartbeat()
                yield item
        finally:  # also when the loop is left early (the generator is closed)
            self.close()

    def update(self, n=1):
        self.n += n
        self._heartbeat()

    def _heartbeat(self):
        now = time.perf_counter()
        if self.enabled and now - self.last_line >= HEARTBEAT_S:
            self.last_line = now
            of = f"/{self.total}" if self.total else ""
            last = f" ({self.postfix})" if self.postfix else ""  # a net's latest losses and validation accuracy
            log.info("%s: %d%s %s so far, %.0f s%s", self.desc, self.n, of, self.unit, now - self.start, last)

    def set_postfix(self, values=None, **kwargs):
        values = dict(values or {}, **kwargs)
        self.postfix = ", ".join(f"{k}={v}" for k, v in values.items())

    def close(self):
        if self.closed:
            return
        self.closed = True
        if self.enabled:
            seconds = time.perf_counter() - self.start
            last = f" ({self.postfix})" if self.postfix else ""
            log.info("%s: %d %s in %.1f s%s", self.desc, self.n, self.unit, seconds, last)


def progress(iterable=None, *, desc: str, total: int | None = None, unit: str = "it", enabled: bool = True,
             announce: bool = False):
    """A tqdm bar on a terminal, one log line at the end elsewhere; nothing at all when not enabled.
    `announce`: elsewhere, also a line when the loop starts (for a loop whose first heartbeat would
    come too late to tell the user that something is happening, such as reading a large file)."""
    if total is None and iterable is not None and hasattr(iterable, "__len__"):
        total = len(iterable)
    if enabled and on_terminal():
        return tqdm(iterable, desc=desc, total=total, unit=unit, leave=False)
    if enabled and announce:
        log.info("%s ...", desc)
    return _Quiet(iterable if iterable is not None else (), desc, total, unit, enabled)


@contextmanager
def phase(name: str, enabled: bool = True):
    """Log a phase's start and its duration, so a long silent step is never a mystery."""
    start = time.perf_counter()
    if enabled:
        log.info("%s ...", name)
    yield
    if enabled:
        log.info("%s: done in %.1f s", name, time.perf_counter() - start)
