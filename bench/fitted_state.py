"""What the safe pipeline file costs against the pickle it replaced: save and load time, size.

    .venv/bin/python bench/fitted_state.py <run folder> [<run folder> ...] [--repeats 7]

For each run folder's pipeline.npz (models/fitted_state.py): the pipeline is loaded once (so
imports are not timed), then saved and loaded `repeats` times each way, as pipeline.npz and as
a pickle of the same object, in a temporary folder; prints the median and best wall time and
the file sizes, and checks that both copies predict the same on the run's examples. Appends
every repeat's time to results/fitted_state.jsonl.
"""
import argparse
import pickle
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from models.deployable import PIPELINE_FILE, load_pipeline, save_pipeline  # noqa: E402

# What the timing measures: the safe format's writer and reader, and the pipeline object they store
# (the pickle beside it is the standard library's).
MEASURED_CODE = ["models/fitted_state.py", "models/deployable.py"]


def timed(call, repeats: int) -> list[float]:
    """The wall time of each of `repeats` calls of `call()`, in milliseconds."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(1e3 * (time.perf_counter() - start))
    return times


def pair(npz: list[float], pickled: list[float]) -> str:
    """Median (best) of each, as the table prints them."""
    return (f"{statistics.median(npz):.1f} ({min(npz):.1f}) / "
            f"{statistics.median(pickled):.1f} ({min(pickled):.1f})")


def predictions(pipeline) -> np.ndarray:
    out = pipeline.predict_raw(pipeline.examples)
    return out[0] if isinstance(out, tuple) else out


def compare(run_dir: Path, repeats: int) -> dict:
    pipeline = load_pipeline(run_dir / PIPELINE_FILE)
    with tempfile.TemporaryDirectory() as folder:
        npz, pkl = Path(folder) / PIPELINE_FILE, Path(folder) / "pipeline.pkl"
        row = {"save_npz_ms": timed(lambda: save_pipeline(pipeline, npz), repeats),
               "save_pickle_ms": timed(lambda: pkl.write_bytes(pickle.dumps(pipeline)), repeats),
               "load_npz_ms": timed(lambda: load_pipeline(npz), repeats),
               "load_pickle_ms": timed(lambda: pickle.loads(pkl.read_bytes()), repeats),
               "size_npz_bytes": npz.stat().st_size, "size_pickle_bytes": pkl.stat().st_size}
        same = np.array_equal(predictions(load_pipeline(npz)), predictions(pickle.loads(pkl.read_bytes())))
    return {"run": run_dir.name, "model": type(pipeline.model).__name__, **row, "same_predictions": same}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", nargs="+", type=Path)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args(argv)
    print("| run | model | save npz / pickle (ms, median, best) | load npz / pickle (ms, median, best) "
          "| size npz / pickle (MB) | same predictions |")
    print("|---|---|---|---|---|---|")
    with recording("fitted_state", MEASURED_CODE) as record:
        rows = []
        for run_dir in args.runs:
            row = compare(run_dir, args.repeats)
            print(f"| {row['run']} | {row['model']} | {pair(row['save_npz_ms'], row['save_pickle_ms'])} | "
                  f"{pair(row['load_npz_ms'], row['load_pickle_ms'])} | "
                  f"{row['size_npz_bytes'] / 1e6:.2f} / {row['size_pickle_bytes'] / 1e6:.2f} | "
                  f"{row['same_predictions']} |")
            rows.append(row)
        record.add("save_load", {"repeats": args.repeats, "rows": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
