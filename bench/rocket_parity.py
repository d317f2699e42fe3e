"""Touchstone's ROCKET members against aeon's on the equal-length UCR/UEA sets aeon ships, in one run.

    .venv/bin/python bench/rocket_parity.py                       # MiniRocket vs MiniRocket, every set, seeds 0 1 2
    .venv/bin/python bench/rocket_parity.py --sets GunPoint --seeds 0
    .venv/bin/python bench/rocket_parity.py --cpu-time              # both sides timed by CPU time (a loaded machine)
    .venv/bin/python bench/rocket_parity.py --members minirocket hydra_minirocket --aeon MiniRocket MultiRocketHydra
                                                                  # does Hydra earn its cost?

aeon pins numpy and pandas below this project's versions, so it runs in its own venv
(bench/.venv-aeon, from bench/requirements-aeon.txt) in a subprocess: it reads each set from its
installed package's files, writes the arrays to a temporary NPZ that the Touchstone side reads
(identical inputs), and fits its classifiers one thread per seed (MiniRocketClassifier: its
transform, StandardScaler, RidgeClassifierCV). Touchstone's side fits models/rocket (`--members`)
on the same arrays and exports the deployable pipeline to ONNX as a run does. Reported per set and
method, mean +- sd over seeds: test accuracy, fit time (both one thread), latency per recording
(aeon: its predict's share of one call on the whole test set / one call per recording;
Touchstone: onnxruntime batch-1, one thread, median), the largest gap between the ONNX and the
eager probabilities, and the load average: other processes share the cores, and both sides meet
the same load in the same run. Appends one record per set and method (each seed's figures) to
results/rocket_parity.jsonl.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402
from common.threads import apply_threads  # noqa: E402

AEON_VENV = ROOT / "bench" / ".venv-aeon"
SETS = ("ItalyPowerDemand", "JapaneseVowels_eq", "BasicMotions", "GunPoint", "ArrowHead", "PickupGestureWiimoteZ_eq",
        "OSULeaf", "ACSF1")
MEMBERS = ("minirocket", "hydra_minirocket")
AEON_CLASSIFIERS = ("MiniRocket", "MultiRocketHydra")
LATENCY_CALLS = 100
# Touchstone's side: the ROCKET members, the deployable pipeline around them and its ONNX export;
# and aeon's pin, since the other side of every comparison is the aeon it installs.
MEASURED_CODE = ["models/rocket/", "models/deployable.py", "export/", "bench/requirements-aeon.txt"]

AEON_SIDE = r'''
import json, sys, time
import numpy as np
from pathlib import Path
import aeon
from aeon.datasets import load_from_ts_file
from aeon.classification import convolution_based

sets, seeds, folder = sys.argv[1].split(","), [int(s) for s in sys.argv[2].split(",")], Path(sys.argv[3])
classifiers = {name: getattr(convolution_based, f"{name}Classifier") for name in sys.argv[4].split(",")}
clock = time.process_time if sys.argv[5] == "cpu" else time.perf_counter
data = Path(aeon.__file__).parent / "datasets" / "data"
for warm in ("GunPoint", "BasicMotions"):   # numba compiles here (one channel, several), not in the timings
    X, y = load_from_ts_file(str(data / warm / f"{warm}_TRAIN.ts"))
    for cls in classifiers.values():
        cls(random_state=0).fit(X, y).predict(X[:2])
results = {}
for name in sets:
    family = name.removesuffix("_eq")
    X, y = load_from_ts_file(str(data / family / f"{name}_TRAIN.ts"))
    X_test, y_test = load_from_ts_file(str(data / family / f"{name}_TEST.ts"))
    np.savez(folder / f"{name}.npz", X=np.asarray(X, dtype=np.float64), y=np.asarray(y).astype(str),
             X_test=np.asarray(X_test, dtype=np.float64), y_test=np.asarray(y_test).astype(str))
    for label, cls in classifiers.items():
        rows = []
        for seed in seeds:
            model = cls(random_state=seed, n_jobs=1)
            start = clock(); model.fit(X, y); fit_s = clock() - start
            start = clock(); predicted = model.predict(X_test); batch_s = clock() - start
            calls = []
            for i in range(min(len(X_test), %d)):
                start = clock(); model.predict(X_test[i:i + 1]); calls.append(clock() - start)
            rows.append({"seed": seed, "accuracy": float(np.mean(predicted == y_test)), "fit_s": fit_s,
                         "batch_share_ms": 1e3 * batch_s / len(X_test), "latency_ms": 1e3 * float(np.median(calls))})
        results[f"{name}|aeon {label}"] = rows
print(json.dumps(results))
''' % LATENCY_CALLS


def aeon_results(sets, seeds, folder, classifiers, clock_name="wall") -> dict:
    python = AEON_VENV / "bin" / "python"
    if not python.exists():
        sys.exit(f"error: no aeon venv at {AEON_VENV}; create it: python3 -m venv {AEON_VENV} && "
                 f"{python.parent / 'pip'} install -r {ROOT / 'bench' / 'requirements-aeon.txt'}")
    single = {k: "1" for k in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")}
    done = subprocess.run([str(python), "-c", AEON_SIDE, ",".join(sets), ",".join(map(str, seeds)), str(folder),
                           ",".join(classifiers), clock_name], capture_output=True, text=True,
                          env={**os.environ, **single}, check=False)
    if done.returncode:
        sys.exit(f"error: aeon side failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def touchstone_rows(data, member, seeds, clock=time.perf_counter) -> list[dict]:
    import onnxruntime as ort
    from export.pipelines import export_pipeline
    from models.deployable import TimeSeriesPipeline
    from models.rocket.classifier import RocketClassifier

    classes = sorted(set(data["y"]))
    y, y_test = (np.searchsorted(classes, data[k]) for k in ("y", "y_test"))
    X, windows = data["X"], data["X_test"].astype(np.float32)   # the graph takes float32; eager sees the same values
    n_channels, length = X.shape[1], X.shape[2]
    rows = []
    for seed in seeds:
        start = clock()
        model = RocketClassifier(seed=seed, member=member).fit(X, y)
        fit_s = clock() - start
        eager = model.predict_proba(windows.astype(np.float64))
        pipeline = TimeSeriesPipeline([f"c{c}" for c in range(n_channels)], classes, None, 1, length,
                                      np.zeros((1, n_channels, 1)), np.ones((1, n_channels, 1)), model)
        options = ort.SessionOptions()
        options.intra_op_num_threads = options.inter_op_num_threads = 1
        session = ort.InferenceSession(export_pipeline(pipeline, 17, "bench").SerializeToString(), options,
                                       providers=["CPUExecutionProvider"])
        onnx_proba = session.run(None, {"window": windows})[0]
        calls = []
        for i in range(5 + min(len(windows), LATENCY_CALLS)):   # the first five warm the session up
            start = clock()
            session.run(None, {"window": windows[i % len(windows)][None]})
            calls.append(clock() - start)
        rows.append({"seed": seed, "accuracy": float(np.mean(eager.argmax(1) == y_test)), "fit_s": fit_s,
                     "latency_ms": 1e3 * float(np.median(calls[5:])), "n_features": model.module_.n_features,
                     "onnx_accuracy": float(np.mean(onnx_proba.argmax(1) == y_test)),
                     "onnx_eager_max_abs": float(np.abs(onnx_proba - eager).max()), "head": model.head_,
                     "alpha": getattr(model, "alpha_", None), "load_average": os.getloadavg()[0]})
    return rows


def print_table(results: dict, shapes: dict, sets: list):
    print("\n| set | length x channels | method | accuracy | fit s | latency ms per recording | features | "
          "ONNX-eager max gap | load average |")
    print("|---|---|---|---|---|---|---|---|---|")
    for key in sorted(results, key=lambda k: (sets.index(k.split("|")[0]), k)):
        rows, (name, method) = results[key], key.split("|")
        seeds = {k: [r[k] for r in rows] for k in rows[0]}   # each measurement over the seeds
        line = (f"| {name} | {shapes[name][0]} x {shapes[name][1]} | {method} | "
                f"{format_mean_sd(seeds['accuracy'], '.3f')} | {format_mean_sd(seeds['fit_s'])} | ")
        if method.startswith("Touchstone"):
            print(line + f"{format_mean_sd(seeds['latency_ms'])} (ONNX, one call) | {rows[0]['n_features']} | "
                  f"{max(r['onnx_eager_max_abs'] for r in rows):.1e} | "
                  f"{np.mean([r['load_average'] for r in rows]):.1f} |")
        else:
            print(line + f"{format_mean_sd(seeds['batch_share_ms'])} (batch share) / "
                  f"{format_mean_sd(seeds['latency_ms'])} (one call) | | | |")


def record_results(record, results: dict, shapes: dict, cpu_time: bool):
    """One record per set and method, each figure a list over its seeds. The clock is in the
    name: CPU-time figures do not stand in for wall-clock ones."""
    for key, rows in results.items():
        name, method = key.split("|")
        values = {"set": name, "length": shapes[name][0], "channels": shapes[name][1], "method": method,
                  "clock": "cpu" if cpu_time else "wall", "threads": 1, "latency_calls": LATENCY_CALLS,
                  **{column: [row[column] for row in rows] for column in rows[0] if column != "seed"}}
        record.add(f"{name}/{method.lower().replace(' ', '_')}" + ("/cpu_time" if cpu_time else ""), values,
                   seeds=[row["seed"] for row in rows])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", nargs="+", default=list(SETS), choices=SETS)
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--members", nargs="+", default=["minirocket"], choices=MEMBERS,
                        help="Touchstone's models/rocket members")
    parser.add_argument("--aeon", nargs="+", default=["MiniRocket"], choices=AEON_CLASSIFIERS,
                        help="aeon's convolution-based classifiers")
    parser.add_argument("--json", type=Path, help="also write every row to this file")
    parser.add_argument("--cpu-time", action="store_true",
                        help="time fits and calls by the process's CPU time on both sides, not the wall clock: on a "
                             "loaded machine it leaves out the time other processes hold the core (not the cache "
                             "they evict)")
    args = parser.parse_args()
    apply_threads(1)
    shapes = {}
    with tempfile.TemporaryDirectory() as folder, recording("rocket_parity", MEASURED_CODE) as record:
        folder = Path(folder)
        print(f"aeon side ... (load average {os.getloadavg()[0]:.1f})", flush=True)
        results = aeon_results(args.sets, args.seeds, folder, args.aeon, "cpu" if args.cpu_time else "wall")
        for name in args.sets:
            data = np.load(folder / f"{name}.npz")
            shapes[name] = data["X"].shape[2], data["X"].shape[1]     # length, channels
            for member in args.members:
                results[f"{name}|Touchstone {member}"] = touchstone_rows(
                    data, member, args.seeds, time.process_time if args.cpu_time else time.perf_counter)
            print(f"{name} done (load average {os.getloadavg()[0]:.1f})", flush=True)
        print_table(results, shapes, args.sets)
        record_results(record, results, shapes, args.cpu_time)
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
