"""What the live loop does when the input arrives faster than the model predicts (backlog=...).

    wait   take one line at a time; the rest wait in the pipe, serial buffer or socket, so a
           writer that can be slowed down is (a pipe blocks it), and a serial port's own buffer
           overflows at the port, never in this process
    batch  (default) take every line waiting, up to `batch` of them, and predict them in one call:
           the same predictions, fewer calls, no line lost
    drop   keep only the newest line waiting: the freshest prediction, older lines counted as
           dropped (a recordings model starts its window again after a gap)

Whichever it is, the backlog is said once on stderr, and memory stays bounded
(export/live/sources.py reads only when fewer lines wait than one batch).
"""
from common.errors import InputError

MODES = ("batch", "wait", "drop")
MAX_BATCH = 256


class Backlog:
    def __init__(self, mode: str = "batch", batch: int = MAX_BATCH, warn=print):
        if mode not in MODES:
            raise InputError(f"backlog must be one of {', '.join(MODES)}, got {mode!r}")
        if batch < 1:
            raise InputError(f"batch must be a positive whole number, got {batch}")
        self.mode, self.batch, self._warn = mode, batch if mode == "batch" else 1, warn
        self.warned = False

    def next_lines(self, source) -> list[tuple[int, str]]:
        """The next lines to predict; [] at the end of the stream."""
        if self.mode == "drop":
            source.skip_to_newest()
        return source.take(self.batch)

    def check(self, source, taken: int) -> None:
        """After a prediction of `taken` lines: say once when lines were already waiting for the
        model (more than one taken, some waiting now, or some dropped)."""
        if self.warned:
            return
        waiting = max(source.waiting(), taken - 1)
        if waiting or source.dropped:
            self.warned = True
            action = {"wait": "they wait in the input (backlog=wait)",
                      "batch": f"predicting them in batches of up to {self.batch} (backlog=batch)",
                      "drop": "keeping only the newest (backlog=drop; the summary counts the dropped)"}[self.mode]
            self._warn(f"input arrives faster than the model predicts ({max(waiting, source.dropped)} lines "
                       f"waiting): {action}")
