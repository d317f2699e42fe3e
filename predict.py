"""Predict with an exported Touchstone model, no training code needed:

    python predict.py model=outputs/<run>/model.onnx input=recording.csv output=pred.csv [threads=N]

Regression models read one row per press with the model's channel columns and write the
targets (units in the column names) and, when the model has them, 95 % interval bounds.
Classification models read one recording (rows = time steps, channel columns) and write one
row per consecutive window with the class probabilities. CSV or Parquet in and out.
Bad input (a file, a value that is not finite in the model's dtype, an output that is the input
or cannot be written, a malformed model) is one line on stderr, exit code 2, and no output file.
"""
import os
import sys
from pathlib import Path

from common.atomic import atomic_write
from common.errors import InputError
from data.readers.table_reader import read_table_file
from export.onnx_predictor import OnnxPredictor

KEYS = ("model", "input", "output", "threads")


def parse(argv) -> dict:
    args = {}
    for item in argv:
        key, sep, value = item.partition("=")
        if not sep or key not in KEYS:
            raise InputError(f"unknown argument '{item}'; expected {', '.join(k + '=...' for k in KEYS)}")
        args[key] = value
    missing = [k for k in ("model", "input", "output") if k not in args]
    if missing:
        raise InputError(f"missing {', '.join(k + '=...' for k in missing)}")
    return args


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


def write(result, output: Path) -> None:
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


def main(argv=None) -> int:
    try:
        args = parse(sys.argv[1:] if argv is None else argv)
        threads = thread_count(args["threads"]) if "threads" in args else None
        output = Path(args["output"])
        check_output(output, args)
        predictor = OnnxPredictor(args["model"], threads=threads)
        frame = read_table_file(args["input"])
        if predictor.kind == "regression":
            result = predictor.predict_table(frame, args["input"])
        else:
            result = predictor.predict_recording(frame, args["input"])
        write(result, output)
    except InputError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(f"wrote {len(result)} rows to {output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
