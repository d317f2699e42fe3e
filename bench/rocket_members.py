"""Does Hydra earn its cost? Touchstone's model=minirocket against model=hydra_minirocket (and aeon's
MiniRocket and MultiRocket-Hydra beside them) on the equal-length UCR/UEA sets aeon ships, one run.

    .venv/bin/python bench/rocket_members.py                          # every set, seeds 0 1 2
    .venv/bin/python bench/rocket_members.py --sets GunPoint --seeds 0

aeon runs from its own venv (bench/.venv-aeon, bench/requirements-aeon.txt) in a subprocess that
reads each set from its installed package's files and writes the arrays to a temporary NPZ the
Touchstone side reads (identical inputs). Every fit is one thread. Reported per set and method,
mean +- sd over seeds: test accuracy, fit seconds, and for Touchstone's members onnxruntime's
batch-1 latency per recording (one thread, median of up to 100 calls) of the exported pipeline.
The load average is printed beside the timings; both sides meet the same load in the same run.
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

from common.threads import apply_threads  # noqa: E402

AEON_VENV = ROOT / "bench" / ".venv-aeon"
SETS = ("ItalyPowerDemand", "JapaneseVowels_eq", "BasicMotions", "GunPoint", "ArrowHead", "PickupGestureWiimoteZ_eq",
        "OSULeaf", "ACSF1")
MEMBERS = ("minirocket", "hydra_minirocket")
LATENCY_CALLS = 100

AEON_SIDE = r'''
import json, sys, time
import numpy as np
from pathlib import Path
import aeon
from aeon.datasets import load_from_ts_file
from aeon.classification.convolution_based import MiniRocketClassifier, MultiRocketHydraClassifier

sets, seeds, folder = sys.argv[1].split(","), [int(s) for s in sys.argv[2].split(",")], Path(sys.argv[3])
data = Path(aeon.__file__).parent / "datasets" / "data"
warm = load_from_ts_file(str(data / "GunPoint" / "GunPoint_TRAIN.ts"))
for cls in (MiniRocketClassifier, MultiRocketHydraClassifier):   # numba compiles here, not in the timings
    cls(random_state=0).fit(*warm).predict(warm[0][:2])
results = {}
for name in sets:
    family = name.removesuffix("_eq")
    X, y = load_from_ts_file(str(data / family / f"{name}_TRAIN.ts"))
    X_test, y_test = load_from_ts_file(str(data / family / f"{name}_TEST.ts"))
    np.savez(folder / f"{name}.npz", X=np.asarray(X, dtype=np.float64), y=np.asarray(y).astype(str),
             X_test=np.asarray(X_test, dtype=np.float64), y_test=np.asarray(y_test).astype(str))
    for label, cls in (("aeon MiniRocket", MiniRocketClassifier), ("aeon MultiRocketHydra", MultiRocketHydraClassifier)):
        rows = []
        for seed in seeds:
            model = cls(random_state=seed, n_jobs=1)
            start = time.perf_counter(); model.fit(X, y); fit_s = time.perf_counter() - start
            start = time.perf_counter(); predicted = model.predict(X_test); batch_s = time.perf_counter() - start
            rows.append({"seed": seed, "accuracy": float(np.mean(predicted == y_test)), "fit_s": fit_s,
                         "latency_ms": 1e3 * batch_s / len(X_test)})
        results[f"{name}|{label}"] = rows
print(json.dumps(results))
'''


def aeon_results(sets, seeds, folder) -> dict:
    python = AEON_VENV / "bin" / "python"
    if not python.exists():
        sys.exit(f"error: no aeon venv at {AEON_VENV}; create it: python3 -m venv {AEON_VENV} && "
                 f"{python.parent / 'pip'} install -r {ROOT / 'bench' / 'requirements-aeon.txt'}")
    single = {k: "1" for k in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")}
    done = subprocess.run([str(python), "-c", AEON_SIDE, ",".join(sets), ",".join(map(str, seeds)), str(folder)],
                          capture_output=True, text=True, env={**os.environ, **single}, check=False)
    if done.returncode:
        sys.exit(f"error: aeon side failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def touchstone_rows(data, member, seeds) -> list[dict]:
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
        start = time.perf_counter()
        model = RocketClassifier(seed=seed, member=member).fit(X, y)
        fit_s = time.perf_counter() - start
        eager = model.predict_proba(windows.astype(np.float64))
        pipeline = TimeSeriesPipeline([f"c{c}" for c in range(n_channels)], classes, None, 1, length,
                                      np.zeros((1, n_channels, 1)), np.ones((1, n_channels, 1)), model)
        options = ort.SessionOptions()
        options.intra_op_num_threads = options.inter_op_num_threads = 1
        session = ort.InferenceSession(export_pipeline(pipeline, 17, "bench").SerializeToString(), options,
                                       providers=["CPUExecutionProvider"])
        onnx_proba = session.run(None, {"window": windows})[0]
        calls = []
        for i in range(5 + min(len(windows), LATENCY_CALLS)):
            start = time.perf_counter()
            session.run(None, {"window": windows[i % len(windows)][None]})
            calls.append(time.perf_counter() - start)
        rows.append({"seed": seed, "accuracy": float(np.mean(eager.argmax(1) == y_test)), "fit_s": fit_s,
                     "latency_ms": 1e3 * float(np.median(calls[5:])), "n_features": model.module_.n_features,
                     "onnx_eager_max_abs": float(np.abs(onnx_proba - eager).max()), "length": length,
                     "channels": n_channels, "load_average": os.getloadavg()[0]})
    return rows


def spread(rows, key, digits=3) -> str:
    values = np.array([r[key] for r in rows], dtype=float)
    return f"{values.mean():.{digits}f} ± {values.std(ddof=1) if len(values) > 1 else 0.0:.{digits}f}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", nargs="+", default=list(SETS), choices=SETS)
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--json", type=Path, help="also write every row to this file")
    args = parser.parse_args()
    apply_threads(1)
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        print(f"aeon side ... (load average {os.getloadavg()[0]:.1f})", flush=True)
        results = aeon_results(args.sets, args.seeds, folder)
        for name in args.sets:
            data = np.load(folder / f"{name}.npz")
            for member in MEMBERS:
                results[f"{name}|Touchstone {member}"] = touchstone_rows(data, member, args.seeds)
            print(f"{name} done (load average {os.getloadavg()[0]:.1f})", flush=True)
    print("\n| set | length x channels | method | accuracy | fit s | latency ms per recording | features | "
          "ONNX-eager max gap | load average |")
    print("|---|---|---|---|---|---|---|---|---|")
    for key, rows in results.items():
        name, method = key.split("|")
        line = f"| {name} | {{}} | {method} | {spread(rows, 'accuracy')} | {spread(rows, 'fit_s', 2)} | {spread(rows, 'latency_ms', 2)}"
        if method.startswith("Touchstone"):
            print(line.format(f"{rows[0]['length']} x {rows[0]['channels']}") + f" | {rows[0]['n_features']} | "
                  f"{max(r['onnx_eager_max_abs'] for r in rows):.1e} | {np.mean([r['load_average'] for r in rows]):.1f} |")
        else:
            print(line.format("") + " (predict's batch share) | | | |")
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
