"""What the safe pipeline file costs against the pickle it replaced: save and load time, size.

    .venv/bin/python bench/fitted_state.py <run folder> [<run folder> ...] [--repeats 7]

For each run folder's pipeline.npz (models/fitted_state.py): the pipeline is loaded once (so
imports are not timed), then saved and loaded `repeats` times each way, as pipeline.npz and as
a pickle of the same object, in a temporary folder; prints the median and best wall time and
the file sizes, and checks that both copies predict the same on the run's examples.
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

from models.deployable import PIPELINE_FILE, load_pipeline, save_pipeline  # noqa: E402


def timed(call, repeats: int) -> tuple[float, float]:
    """(median, best) wall time of `call()` in milliseconds."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(1e3 * (time.perf_counter() - start))
    return statistics.median(times), min(times)


def predictions(pipeline) -> np.ndarray:
    out = pipeline.predict_raw(pipeline.examples)
    return out[0] if isinstance(out, tuple) else out


def compare(run_dir: Path, repeats: int) -> dict:
    pipeline = load_pipeline(run_dir / PIPELINE_FILE)
    with tempfile.TemporaryDirectory() as folder:
        npz, pkl = Path(folder) / PIPELINE_FILE, Path(folder) / "pipeline.pkl"
        row = {"save npz": timed(lambda: save_pipeline(pipeline, npz), repeats),
               "save pickle": timed(lambda: pkl.write_bytes(pickle.dumps(pipeline)), repeats),
               "load npz": timed(lambda: load_pipeline(npz), repeats),
               "load pickle": timed(lambda: pickle.loads(pkl.read_bytes()), repeats),
               "size npz": npz.stat().st_size, "size pickle": pkl.stat().st_size}
        same = np.array_equal(predictions(load_pipeline(npz)), predictions(pickle.loads(pkl.read_bytes())))
    row["same predictions"] = same
    return row


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", nargs="+", type=Path)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args(argv)
    print("| run | model | save npz / pickle (ms, median, best) | load npz / pickle (ms, median, best) "
          "| size npz / pickle (MB) | same predictions |")
    print("|---|---|---|---|---|---|")
    for run_dir in args.runs:
        row = compare(run_dir, args.repeats)
        model = type(load_pipeline(run_dir / PIPELINE_FILE).model).__name__
        pair = "{:.1f} ({:.1f}) / {:.1f} ({:.1f})".format
        print(f"| {run_dir.name} | {model} | {pair(*row['save npz'], *row['save pickle'])} | "
              f"{pair(*row['load npz'], *row['load pickle'])} | "
              f"{row['size npz'] / 1e6:.2f} / {row['size pickle'] / 1e6:.2f} | {row['same predictions']} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
