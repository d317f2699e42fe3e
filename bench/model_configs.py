"""Every model config and study at seed 0, as a user runs it: the scores each run writes and the
predictions its exported ONNX file gives through predict.py; appended to results/model_configs.jsonl.

    .venv/bin/python bench/model_configs.py                 # every case (about 20 min on 2 cores)
    .venv/bin/python bench/model_configs.py --only extra_trees capacitive_tracking
    .venv/bin/python bench/model_configs.py --check --only regression/resmlp   # compare, record nothing

A code change that should move no number (a refactor) is judged against these records:
tests/bench/test_model_configs.py (slow) re-runs every case and compares each printed digit.
Classification tables use a generated three-region pad table (written next to the runs); the
recordings nets train two epochs on two passes per level (their numbers are for parity, not
accuracy); studies run with their experiment's own settings.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import differences, latest, recording  # noqa: E402

REGRESSORS = ["auto", "blend", "decision_tree", "extra_trees", "gaussian_process", "linear_regression",
              "random_forest", "resmlp", "ridge", "svr"]
TABLE_CLASSIFIERS = ["auto", "logistic_regression", "mlp", "random_forest", "extra_trees", "decision_tree"]
RECORDINGS_MODELS = ["prcnn", "rescnn", "inceptiontime", "lstm_fcn", "minirocket", "hydra_minirocket"]
SMALL_RECORDINGS = ["experiment=materials10", "scene.passes_per_level=2", "trainer.max_epochs=2"]
STUDIES = {"capacitive_tracking": ["experiment=capacitive_tracking"],
           "taxel_receptive_field": ["experiment=taxel_receptive_field"],
           "ert_localisation": ["experiment=ert_localisation", "scene=ert_internal"],
           "ert_injection": ["experiment=ert_injection"],
           "capacitive_force_svr": ["experiment=capacitive_force", "hydra.mode=RUN", "model=svr"]}
# Everything a run goes through: a refactor anywhere here should leave these records reproduced.
MEASURED_CODE = ["common/", "data/", "models/", "export/", "runs/", "configs/", "train.py", "predict.py"]


def cases(pads_csv: Path) -> dict[str, list[str]]:
    """case name -> train.py overrides (seed 0 added by the caller)."""
    table = ["data=table", f"data.path={pads_csv}", "data.target_columns=[region]"]
    return {**{f"regression/{m}": [f"model={m}"] for m in REGRESSORS},
            **{f"table_classification/{m}": [*table, f"model={m}"] for m in TABLE_CLASSIFIERS},
            **{f"recordings/{m}": [*SMALL_RECORDINGS, f"model={m}"] for m in RECORDINGS_MODELS},
            **{f"study/{name}": overrides for name, overrides in STUDIES.items()}}


def pads(path: Path, n: int = 240, seed: int = 0) -> Path:
    """Presses on three regions of a pad: two resistances follow the press's x, one is noise."""
    rng = np.random.default_rng(seed)
    region = rng.integers(0, 3, n)
    x = np.array([-10.0, 0.0, 10.0])[region] + rng.normal(0, 3, n)
    pd.DataFrame({"r_01_ohm": 1000 + 20 * x + rng.normal(0, 20, n), "r_02_ohm": 1000 - 15 * x + rng.normal(0, 20, n),
                  "r_03_ohm": 900 + rng.normal(0, 30, n),
                  "region": np.array(["left", "middle", "right"])[region]}).to_csv(path, index=False)
    return path


# One thread everywhere, whatever the caller's environment says: a float32 tree ensemble in
# onnxruntime sums its trees in another order on more threads (last digits differ).
SINGLE_THREAD = {"CI": "true", "TOUCHSTONE_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
                 "OPENBLAS_NUM_THREADS": "1"}


def python(arguments: list[str]) -> None:
    done = subprocess.run([sys.executable, *arguments], cwd=ROOT, env={**os.environ, **SINGLE_THREAD},
                          capture_output=True, text=True)
    if done.returncode != 0:
        tail = (done.stderr or done.stdout).strip().splitlines()[-3:]
        raise RuntimeError(f"`{' '.join(arguments)}` exited {done.returncode}: {' | '.join(tail)}")


def onnx_predictions(folder: Path) -> dict | None:
    """predict.py's output on the run's own test rows (a table run's predictions.csv is a ready
    input), every numeric column as a list; None where the run exports nothing predict.py reads so."""
    if not (folder / "model.onnx").is_file() or not (folder / "predictions.csv").is_file():
        return None
    try:
        python(["predict.py", f"model={folder}/model.onnx", f"input={folder}/predictions.csv",
                f"output={folder}/onnx_predictions.csv", "threads=1"])
    except RuntimeError as error:           # a recordings model reads its NPZ, not a table
        return {"not_predicted": str(error)[-200:]}
    frame = pd.read_csv(folder / "onnx_predictions.csv")
    return {column: frame[column].tolist() for column in frame.columns if pd.api.types.is_numeric_dtype(frame[column])}


def measure(name: str, overrides: list[str], folder: Path) -> dict:
    """One case: the run's metrics.json (without timings, which no refactor keeps) and its ONNX output."""
    python(["train.py", *overrides, "seed=0", f"hydra.run.dir={folder}"])
    # The temporary folder's name differs run to run: it is no result, so it is written as <tmp>.
    metrics = json.loads((folder / "metrics.json").read_text().replace(str(folder.parent), "<tmp>"))
    shown = [o.replace(str(folder.parent), "<tmp>") for o in overrides]
    return {"overrides": shown, "metrics": without_timings(metrics), "onnx": onnx_predictions(folder)}


TIMING_WORDS = ("time", "_s", "latency", "cost", "seconds", "throughput", "load", "elapsed", "_us", "_ms")


# a duration inside a sentence (the choice's reason: "saved 6.53 ms per row ... fits 0.0 s against 0.1 s")
NUMBER = r"\d+(?:\.\d+)?(?:e[-+]?\d+)?"
DURATION_IN_TEXT = re.compile(rf"{NUMBER}(?: against {NUMBER})? ?(?:ms|µs|us|s)\b")   # "0.23 against 6.81 ms" too


def without_timings(value):
    """A metrics tree with every duration, latency and load taken out (keys that name one, and
    durations written into sentences): what a same-seed rerun repeats."""
    if isinstance(value, dict):
        return {key: without_timings(item) for key, item in value.items()
                if not any(word in key for word in TIMING_WORDS)}
    if isinstance(value, list):
        return [without_timings(item) for item in value]
    if isinstance(value, str):
        return DURATION_IN_TEXT.sub("<duration>", value)
    return value


def check(chosen: dict, tmp: Path) -> int:
    """Re-run each case and compare it with its newest record (6 decimals): a refactor's judge."""
    failed = 0
    for name, overrides in chosen.items():
        # records written before durations inside sentences were masked get the same masking
        recorded = without_timings(latest("model_configs", name)["values"])
        found = differences(recorded, measure(name, overrides, tmp / name.replace("/", "-")), 6)
        failed += bool(found)
        print(f"{name}: " + ("reproduced" if not found else f"{len(found)} difference(s): " + "; ".join(found[:5])),
              flush=True)
    return 1 if failed else 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", nargs="+", help="case names or their last part (e.g. extra_trees)")
    parser.add_argument("--check", action="store_true", help="compare with the newest records; record nothing")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="model_configs-") as tmp:
        chosen = {name: overrides for name, overrides in cases(pads(Path(tmp) / "pads.csv")).items()
                  if not args.only or name in args.only or name.split("/")[-1] in args.only}
        if args.check:
            return check(chosen, Path(tmp))
        with recording("model_configs", MEASURED_CODE) as record:
            for number, (name, overrides) in enumerate(chosen.items(), start=1):
                print(f"[{number}/{len(chosen)}] {name}: python train.py {' '.join(overrides)} seed=0", flush=True)
                record.add(name, measure(name, overrides, Path(tmp) / name.replace("/", "-")), seeds=[0])
    return 0


if __name__ == "__main__":
    sys.exit(main())
