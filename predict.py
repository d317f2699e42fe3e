"""Predict with an exported Touchstone model, no training code needed:

    python predict.py model=outputs/<run>/model.onnx input=recording.csv output=pred.csv [threads=N]

Regression models read one row per press with the model's channel columns and write the
targets (units in the column names) and, when the model has them, 95 % interval bounds.
Classification models read one recording (rows = time steps, channel columns) and write one
row per consecutive window with the class probabilities. CSV or Parquet in and out.
Bad input is one line on stderr, exit code 2, and no output file.
"""
import sys
from pathlib import Path

from data.atomic import atomic_write
from data.errors import InputError
from data.table_files import read_table_file
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


def main(argv=None) -> int:
    try:
        args = parse(sys.argv[1:] if argv is None else argv)
        predictor = OnnxPredictor(args["model"], threads=thread_count(args["threads"]) if "threads" in args else None)
        frame = read_table_file(args["input"])
        if predictor.kind == "regression":
            result = predictor.predict_table(frame, args["input"])
        else:
            result = predictor.predict_recording(frame, args["input"])
        output = Path(args["output"])
        if output.suffix.lower() in (".parquet", ".pq"):
            atomic_write(output, lambda tmp: result.to_parquet(tmp, index=False))
        else:
            atomic_write(output, lambda tmp: result.to_csv(tmp, index=False))
    except InputError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(f"wrote {len(result)} rows to {output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
