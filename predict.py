"""Predict with an exported Touchstone model, no training code needed:

    python predict.py model=outputs/<run>/model.onnx input=rig.csv output=pred.csv [threads=N]
    python predict.py --help model=outputs/<run>/model.onnx     # what this model expects

Row models (a regression, or a classifier of table rows) read one row per press with the model's
channel columns and write one row per input row: the targets (units in the column names) and,
when the model has them, 95 % interval bounds; or the predicted class and its probabilities.
Recording models (time-series classifiers) read recordings as training does, an NPZ
(data/readers/recording_reader.py, no pickles) or a long table (one row per time step, a recording
id column, a time column), and write one row per back-to-back window of each recording: its id,
the step the window starts at, the predicted class and its probabilities. CSV or Parquet out.
Bad input (a file, a value that is not finite in the model's dtype, a sample rate that is not the
model's, an output that is the input or cannot be written, a malformed model) is one line on
stderr, exit code 2, and no output file.

A live stream (input=- for standard input, a serial device such as /dev/ttyACM0, or
tcp://:PORT listening on localhost; docs/live.md) is predicted line by line as it arrives, one
output line per prediction, flushed (export/live/). Heavy imports wait until they are needed, so
--help answers in a second or two.
"""
import os
import sys
import textwrap
from pathlib import Path

from common.errors import InputError

# numpy, pandas, onnxruntime and the readers are imported where used: `--help` needs none of them.

# key: (default, what it is); None: required.
ARGUMENTS = {
    "model": (None, "the exported model, a run's model.onnx"),
    "input": (None, "CSV or Parquet (row models: one row per press; recording models: one row per time step), "
                    "or NPZ (recording models: X (n, channels, length), optional channel_names and sample_rate_hz, "
                    "as training reads it); or a live stream: - (standard input), a serial device (/dev/ttyACM0, "
                    "serial:///dev/ttyUSB0) or tcp://:PORT (listens on localhost), one line per reading: "
                    "[time_s,]channel values (docs/live.md)"),
    "output": ("- (standard output) for a stream; required for a file",
               "the predictions, CSV or Parquet by its suffix; written whole or not at all. A stream's: CSV or "
               "JSON lines (.jsonl), one line per prediction, flushed"),
    "threads": ("TOUCHSTONE_THREADS, else onnxruntime's default", "onnxruntime's intra-op threads; 0: one per core"),
    "recording_column": ("recording", "a table's recording id column, used when the file has it: each recording "
                                      "is cut into windows on its own and every output row carries its id "
                                      "(row models: the column is copied to the output)"),
    "time_column": ("time_s", "a long table's time in seconds, used when the file has it: rows in time order "
                              "within a recording, and its rate must be the model's"),
    "format": ("by output's suffix, else csv", "a stream's output: csv or jsonl"),
    "backlog": ("batch", "a stream arriving faster than the model: batch (predict the lines waiting together, "
                         "none lost), wait (one at a time; the rest wait in the input) or drop (only the newest)"),
    "batch": ("256", "backlog=batch: most lines in one model call"),
    "on_bad_line": ("skip", "a stream's malformed line: skip (reported on stderr with its line number) or stop "
                            "(exit 2)"),
    "hop": ("the model's window", "a recordings model on a stream: steps between predictions of its sliding window"),
    "rows": ("none", "with cols=: the stream is a contact grid's frames (rows x cols cells, row-major); the "
                     "contact tracker runs per frame, force from model= (the 3x3 window force model)"),
    "cols": ("none", "the contact grid's columns"),
    "pitch_mm": ("10", "the contact grid's cell pitch"),
    "n_rest_frames": ("60", "the tracker's baseline: the first frames, without contact"),
    "baud": ("115200", "a serial port's rate"),
    "summary": ("none", "a stream's end-of-stream summary also as JSON in this file"),
    "plot_file": ("none", "with a stream: the live view saved as PNG when the stream ends (works without a screen)"),
}
HELP = ("--help", "-h")
PLOT = "--plot"  # a stream drawn live (matplotlib) for a person at the rig
EXAMPLES = ["python predict.py model=outputs/<run>/model.onnx input=outputs/<run>/predictions.csv output=pred.csv",
            "python predict.py model=outputs/<run>/model.onnx input=rig.npz output=classes.csv",
            "cat /dev/ttyACM0 | python predict.py model=outputs/<run>/model.onnx input=- --plot",
            "python predict.py model=outputs/<run>/model.onnx input=/dev/ttyUSB0 baud=230400 output=live.csv",
            "python predict.py --help model=outputs/<run>/model.onnx"]
RATE_TOLERANCE = 0.01  # relative: time stamps rounded in a CSV still give the model's rate


def parse(argv) -> tuple[dict, bool]:
    """The key=value arguments and whether help was asked for (then only model= may be given)."""
    args, wants_help = {}, False
    for item in argv:
        if item in HELP:
            wants_help = True
            continue
        if item == PLOT:
            args[PLOT] = "yes"
            continue
        key, sep, value = item.partition("=")
        if not sep or key not in ARGUMENTS:
            raise InputError(f"unknown argument '{item}'; expected {', '.join(k + '=...' for k in ARGUMENTS)} "
                             "(--help lists them)")
        args[key] = value
    missing = [k for k, (default, _) in ARGUMENTS.items() if default is None and k not in args]
    if missing and not wants_help:
        raise InputError(f"missing {', '.join(k + '=...' for k in missing)} (--help lists the arguments)")
    return args, wants_help


def usage() -> str:
    lines = ["usage: python predict.py model=MODEL.onnx input=FILE output=FILE [key=value ...]",
             "       python predict.py model=MODEL.onnx input=-|DEVICE|tcp://:PORT [output=FILE] [--plot] [key=value ...]",
             "",
             "Predict with a model Touchstone exported, no training code needed.", ""]
    for key, (default, what) in ARGUMENTS.items():
        text = what + ("" if default is None else f" (default: {default})")
        lines.append(textwrap.fill(text, width=100, initial_indent=f"  {key + '=':<19}", subsequent_indent=" " * 21))
    lines.append(f"  {PLOT:<19}a stream drawn live (matplotlib: readings above, predictions below)")
    lines += ["", "Examples:"] + [f"  {example}" for example in EXAMPLES]
    return "\n".join(lines)


def _with_unit(column: str) -> str:
    from data.units import UNITS, unit_of
    unit = unit_of(column)
    return f"{column} ({UNITS[unit].quantity}, {unit})" if unit in UNITS else column


def model_inputs(predictor) -> str:
    """What `predictor` expects and writes, from its metadata."""
    what = predictor.metadata.get("model", "model")
    lines = [f"{predictor.path}: {predictor.kind} ({what}), Touchstone {predictor.metadata.get('touchstone_version', '?')}",
             f"  channels ({len(predictor.channels)}, in this order): "
             + ", ".join(_with_unit(c) for c in predictor.channels)]
    if predictor.reads_windows:
        rate = predictor.sample_rate_hz
        span = f" at {rate:g} Hz ({predictor.window_steps / rate:g} s)" if rate else " (sample rate unknown)"
        lines.append(f"  input: recordings (NPZ, or a table with one row per time step); windows of "
                     f"{predictor.window_steps} steps{span}")
    else:
        lines.append("  input: a table with one row per press and these channel columns")
    lines += predictor.reads.outputs(predictor, _with_unit)
    return "\n".join(lines)


def thread_count(text: str) -> int | None:
    """`threads=N`: N intra-op threads for onnxruntime; 0 = its default (one per core). Without
    the argument: TOUCHSTONE_THREADS if set, else onnxruntime's default."""
    if not (text.isascii() and text.isdigit()):  # digits only: no sign, no decimal point, not empty
        raise InputError(f"threads must be a non-negative integer (0 = onnxruntime's default), got {text!r}")
    return int(text)


def check_output(output: Path, args: dict) -> None:
    """Before any work: the output is a file predict.py may create or replace, and neither the
    input nor the model (compared as resolved paths, so symlinks and relative paths count)."""
    for key in ("input", "model"):
        if same_file(Path(args[key]), output):
            raise InputError(f"output={output} is the {key} file {args[key]}; predict.py never overwrites its "
                             f"{key}, name another output")
    if output.is_dir():
        raise InputError(f"output={output} is a folder; name a file in it, e.g. {output / 'pred.csv'}")
    if output.exists() and not output.is_file():
        raise InputError(f"output={output} exists and is not a regular file")
    folder = output.parent
    while not folder.exists():  # atomic_write creates the missing folders under the nearest existing one
        folder = folder.parent
    if not folder.is_dir():
        raise InputError(f"output={output}: {folder} is a file, not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(f"output={output}: folder {folder} is not writable")


def same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve() or (a.exists() and b.exists() and os.path.samefile(a, b))
    except (OSError, RuntimeError) as error:  # a symlink loop, a path too long
        raise InputError(f"cannot resolve {a} or {b} ({error})".splitlines()[0]) from None


def check_sample_rate(predictor, rate: float | None, source: str, said_by: str) -> None:
    """A recording at another rate than the model's windows would be classified as if it were at
    the model's: refused (either rate unknown: nothing to compare)."""
    model_rate = predictor.sample_rate_hz
    if rate is not None and model_rate is not None and abs(rate / model_rate - 1) > RATE_TOLERANCE:
        raise InputError(f"{source}: {said_by} {rate:g} Hz, but the model's windows are {model_rate:g} Hz; "
                         f"resample the recordings to {model_rate:g} Hz")


def npz_input(predictor, path: str) -> list:
    """An NPZ's recordings, channels put in the model's order by name; ids are X's indices."""
    import numpy as np

    from data.readers.recording_reader import npz_recordings, read_npz
    from export.onnx_predictor import Recording
    arrays = read_npz(path, required=("X",))
    X, names, rate = npz_recordings(arrays, path)
    missing = [c for c in predictor.channels if c not in names]
    if missing:
        hint = "; save the names as channel_names" if "channel_names" not in arrays else ""
        raise InputError(f"{path}: the model reads channels {', '.join(predictor.channels)}; the NPZ has "
                         f"{', '.join(names)}{hint}")
    check_sample_rate(predictor, rate, path, "sample_rate_hz says")
    order = [names.index(c) for c in predictor.channels]
    return [Recording(k, X[k, order].astype(np.float64), lambda step: f"step {step}") for k in range(len(X))]


def table_input(predictor, frame, source: str, args: dict) -> tuple[list, str | None]:
    """A long table's recordings as training reads them (recording_reader.table_recordings): by
    id when the file has the recording column, in time order when it has the time column; each
    step keeps its file row for messages. Also the id column used (None: one unnamed recording)."""
    import numpy as np

    from data.readers.recording_reader import median_step_rate, table_recordings
    from data.readers.table_reader import check_columns_exist, check_numeric_columns, where
    from export.onnx_predictor import Recording
    frame = frame.reset_index(drop=True)  # row k is the file's data row k, for messages
    columns = {key: args.get(key, ARGUMENTS[key][0]) for key in ("recording_column", "time_column")}
    for key, column in columns.items():
        if key in args:  # named on the command line: it must be there
            check_columns_exist(frame, [column], key.replace("_column", ""), source)
    id_column = columns["recording_column"] if columns["recording_column"] in frame.columns else None
    time_column = columns["time_column"] if columns["time_column"] in frame.columns else None
    check_numeric_columns(frame, predictor.channels, "channel", source)
    if time_column:
        check_numeric_columns(frame, [time_column], "time", source)
    if id_column:
        groups = table_recordings(frame, id_column, time_column, source)
    else:
        groups = [(None, frame.sort_values(time_column, kind="stable") if time_column else frame)]
    if time_column:
        rate = median_step_rate(groups if id_column else groups[0][1], time_column, source,
                                remedy="check the time column (seconds)")
        check_sample_rate(predictor, rate, source, f"time column '{time_column}' gives")
    recordings = [Recording(None if id_column is None else name, part[predictor.channels].to_numpy(np.float64).T,
                            lambda step, rows=part.index.to_numpy(): where(source, int(rows[step])))
                  for name, part in groups]
    return recordings, id_column


def predict(predictor, args: dict):
    """The predictions for args['input'] and a note on what was left out (or '')."""
    from data.readers.table_reader import read_table_file
    source = args["input"]
    if Path(source).suffix.lower() == ".npz":
        if not predictor.reads_windows:
            raise InputError(f"{source}: an NPZ holds recordings; this {predictor.kind} model reads one row per "
                             "press from a CSV or Parquet table")
        recordings, id_column = npz_input(predictor, source), "recording"
    else:
        frame = read_table_file(source)
        if not predictor.reads_windows:
            result = predictor.predict_table(frame, source)
            id_column = args.get("recording_column", ARGUMENTS["recording_column"][0])
            if id_column in frame.columns:
                result.insert(0, id_column, frame[id_column].to_numpy())
            return result, ""
        recordings, id_column = table_input(predictor, frame, source, args)
    result = predictor.predict_recordings(recordings, source, id_column or "recording")
    unused = sum(r.values.shape[1] % predictor.window_steps for r in recordings)
    note = f" from {len(recordings)} recording{'s' * (len(recordings) != 1)}"
    if unused:
        note += f" ({unused} steps after the last whole window of a recording are not predicted)"
    return result, note


def write(result, output: Path) -> None:
    from common.atomic import atomic_write
    parquet = output.suffix.lower() in (".parquet", ".pq")
    try:
        atomic_write(output, lambda tmp: result.to_parquet(tmp, index=False) if parquet
                     else result.to_csv(tmp, index=False))
    except OSError as error:  # e.g. a read-only file system, a full disk, permissions root ignores
        culprit = Path(error.filename) if error.filename else output
        if culprit in output.parents:
            what = f"create folder {culprit}"
        elif culprit.parent == output.parent and culprit != output:  # the temporary file written beside it
            what = f"create a file in {output.parent}"
        else:
            what = f"write {culprit}"
        raise InputError(f"output={output}: cannot {what} ({error.strerror or type(error).__name__})") from None


def whole(args: dict, key: str, least: int = 1) -> int | None:
    """A whole-number argument (None when not given), at least `least`."""
    if key not in args:
        return None
    text = args[key]
    if not (text.isascii() and text.isdigit() and int(text) >= least):
        raise InputError(f"{key} must be a whole number >= {least}, got {text!r}")
    return int(text)


def stream(args: dict, threads: int | None) -> int:
    """A live stream, line by line (export/live/): predictions on the output as they are made, the
    summary on stderr at the end."""
    from export.live.backlog import Backlog
    from export.live.kinds import RowStream, TrackerStream, WindowStream
    from export.live.loop import run_stream
    from export.live.sources import open_source
    from export.live.writer import FORMATS
    from export.onnx_predictor import OnnxPredictor

    output = args.get("output", "-")
    if output != "-":
        check_output(Path(output), args)
    fmt = args.get("format", "jsonl" if output.endswith(".jsonl") else "csv")
    if fmt not in FORMATS:
        raise InputError(f"format must be one of {', '.join(FORMATS)}, got {fmt!r}")
    grid = [whole(args, "rows"), whole(args, "cols")]
    if (grid[0] is None) != (grid[1] is None):
        raise InputError("rows= and cols= go together: the contact grid's size")
    backlog = Backlog(args.get("backlog", "batch"), whole(args, "batch") or 256, warn=_say)
    # one intra-op thread unless told: a single line is too small to share, and the loop is one thread
    predictor = OnnxPredictor(args["model"], threads=1 if threads is None else threads)
    if grid[0] is not None:
        try:
            pitch_mm = float(args.get("pitch_mm", "10"))
        except ValueError:
            raise InputError(f"pitch_mm must be a number of millimetres, got {args['pitch_mm']!r}") from None
        kind = TrackerStream(predictor, *grid, pitch_mm, whole(args, "n_rest_frames", least=10) or 60)
    elif predictor.reads_windows:
        kind = WindowStream(predictor, whole(args, "hop"))
    else:
        kind = RowStream(predictor)
    plot = None
    if PLOT in args or "plot_file" in args:
        from export.live.plot import LivePlot
        where = "standard input" if args["input"] == "-" else args["input"]
        plot = LivePlot(kind.input_columns, kind.columns, f"{Path(args['model']).name} on {where}",
                        show=PLOT in args, file=args.get("plot_file"))
    source = open_source(args["input"], whole(args, "baud") or 115200, announce=_say)
    _say(f"reading {source.name}: one prediction per {'frame' if grid[0] else 'line'} "
         f"({kind.unit} of {len(kind.input_columns)} values, optionally after time_s); Ctrl-C or the input's end stops")
    summary = run_stream(source, kind, backlog, (output, fmt), args.get("on_bad_line", "skip"), warn=_say,
                         plot=plot)
    if plot is not None:
        plot.finish()
    _say(summary.text(kind.unit))
    if "summary" in args:
        from common.atomic import atomic_write_text
        atomic_write_text(Path(args["summary"]), summary.json() + "\n")
    return 0


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def main(argv=None) -> int:
    try:
        args, wants_help = parse(sys.argv[1:] if argv is None else argv)
        threads = thread_count(args["threads"]) if "threads" in args else None
        if wants_help:
            text = usage()
            if "model" in args:
                from export.onnx_predictor import OnnxPredictor
                text += "\n\nThis model:\n" + model_inputs(OnnxPredictor(args["model"], threads=threads))
            else:
                text += "\n\nAdd model=<file> to --help to list what that model expects."
            print(text)
            return 0
        from export.live.sources import is_stream
        if is_stream(args["input"]):
            return stream(args, threads)
        if "output" not in args:
            raise InputError("missing output=... (--help lists the arguments)")
        output = Path(args["output"])
        check_output(output, args)
        from export.onnx_predictor import OnnxPredictor
        predictor = OnnxPredictor(args["model"], threads=threads)
        result, note = predict(predictor, args)
        write(result, output)
    except InputError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # before a stream opened (a socket waiting for its connection): nothing written
        print("interrupted", file=sys.stderr)
        return 130
    print(f"wrote {len(result)} rows{note} to {output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
