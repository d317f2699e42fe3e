"""The live loop, one thread: take lines (export/live/backlog.py), parse them
(data/readers/stream_lines.py), predict (export/live/kinds.py), write one line per prediction
(export/live/writer.py), and count it all (export/live/summary.py).

Every output line carries the input line's number, its time stamp (the rig's own when the line has
one, else seconds since the stream opened) and `latency_us`: from the moment the line was taken
to its prediction ready to write (a batch's lines share their batch's). A bad line is reported on
stderr with its number and skipped, or ends the stream with exit 2 under on_bad_line=stop; the
end of the input (or Ctrl-C) ends it cleanly, with the summary.
"""
import time

from common.errors import InputError
from data.readers.stream_lines import BadLine, LineFormat
from export.live.summary import Summary
from export.live.writer import Writer

BAD_LINE = ("skip", "stop")
MOST_REPORTED = 1000   # a sensor sending garbage for hours must not bury the terminal


def run_stream(source, kind, backlog, writer_args: tuple, on_bad_line: str = "skip", warn=print,
               plot=None) -> Summary:
    """Predict every line of `source` with `kind` until the input ends; the Summary. Raises
    InputError (the stream stopped, nothing kept) for a bad line under on_bad_line=stop."""
    if on_bad_line not in BAD_LINE:
        raise InputError(f"on_bad_line must be one of {', '.join(BAD_LINE)}, got {on_bad_line!r}")
    parser, summary = LineFormat(kind.input_columns), Summary()
    output, fmt = writer_args
    writer = Writer(output, fmt, ["line", "time_s"] + kind.columns + ["latency_us"], kind.holds_lists)
    opened, cpu = time.perf_counter(), time.process_time()
    kept = False
    try:
        try:
            _loop(source, kind, backlog, parser, writer, summary, on_bad_line, warn, plot, opened)
        except KeyboardInterrupt:  # a person at the rig ends a live stream with Ctrl-C: a clean end
            warn("interrupted: ending the stream")
        kept = True
    finally:
        summary.seconds = time.perf_counter() - opened
        summary.cpu_seconds = time.process_time() - cpu
        summary.dropped = source.dropped
        summary.waiting_for_window = summary.read - summary.skipped - summary.predicted
        writer.finish(keep=kept)
        source.close()
    return summary


def _loop(source, kind, backlog, parser, writer, summary, on_bad_line, warn, plot, opened) -> None:
    dropped = 0
    while lines := backlog.next_lines(source):
        taken = time.perf_counter()
        if source.dropped != dropped:
            dropped = source.dropped
            kind.gap()
        parsed = []
        for number, text in lines:
            try:
                item = parser.parse(text)
            except BadLine as error:
                summary.read += 1
                _bad(f"{source.name}: line {number}: {error}", summary, on_bad_line, warn)
                continue
            if item is not None:
                summary.read += 1
                parsed.append((number, *item))  # time_s stays None without one: a window checks the rig's rate
        if not parsed:
            backlog.check(source, len(lines))
            continue
        rows = kind.predict(parsed, summary.model)
        latency_us = round((time.perf_counter() - taken) * 1e6, 1)
        arrival = round(taken - opened, 6)   # the time stamp of a line without one
        good = []
        for number, stamp, values in rows:
            if isinstance(values, str):
                _bad(f"{source.name}: line {number}: {values}", summary, on_bad_line, warn)
            else:
                good.append([number, arrival if stamp is None else stamp, *values, latency_us])
                summary.latency.add(latency_us)
        if good:
            writer.write(good)
            summary.predicted += len(good)
        if plot is not None:
            plot.update(parsed, good)
        backlog.check(source, len(lines))


def _bad(message: str, summary, on_bad_line: str, warn) -> None:
    summary.skipped += 1
    if on_bad_line == "stop":
        raise InputError(f"{message} (on_bad_line=stop)")
    if summary.skipped <= MOST_REPORTED:
        warn(f"skipped {message}")
    if summary.skipped == MOST_REPORTED:
        warn(f"{MOST_REPORTED} bad lines reported: further ones are counted in the summary, not printed")
