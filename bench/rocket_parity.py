"""Touchstone's MiniRocket against aeon's on the equal-length UCR/UEA sets aeon ships, in one run.

    .venv/bin/python bench/rocket_parity.py                       # every set, seeds 0 1 2
    .venv/bin/python bench/rocket_parity.py --sets GunPoint --seeds 0

aeon pins numpy and pandas below this project's versions, so it runs in its own venv
(bench/.venv-aeon, from bench/requirements-aeon.txt) in a subprocess: it reads each set from its
installed package's files, writes the arrays to a temporary NPZ that the Touchstone side reads
(identical inputs), and fits MiniRocketClassifier (its transform, StandardScaler, RidgeClassifierCV)
one thread per seed. Touchstone's side fits models/rocket on the same arrays and exports the
deployable pipeline to ONNX as a run does. Reported per set, mean +- sd over seeds: test accuracy,
fit time (both one thread), aeon's predict per recording (one call per recording, and the whole
test set's call divided by its size), onnxruntime's batch-1 latency (one thread, median), and the
largest gap between the ONNX and the eager probabilities. The load average is printed beside the
timings: other processes share the cores, and both sides meet the same load in the same run.
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
SETS = ("ACSF1", "ArrowHead", "BasicMotions", "GunPoint", "ItalyPowerDemand", "OSULeaf", "JapaneseVowels_eq",
        "PickupGestureWiimoteZ_eq")
LATENCY_CALLS = 100

AEON_SIDE = r'''
import json, sys, time
import numpy as np
from pathlib import Path
import aeon
from aeon.datasets import load_from_ts_file
from aeon.classification.convolution_based import MiniRocketClassifier

sets, seeds, folder = sys.argv[1].split(","), [int(s) for s in sys.argv[2].split(",")], Path(sys.argv[3])
data = Path(aeon.__file__).parent / "datasets" / "data"
warm = load_from_ts_file(str(data / "GunPoint" / "GunPoint_TRAIN.ts"))
MiniRocketClassifier(n_kernels=1000, random_state=0).fit(*warm).predict(warm[0][:2])  # numba compiles here, not in the timings
results = {}
for name in sets:
    family = name.removesuffix("_eq")
    X, y = load_from_ts_file(str(data / family / f"{name}_TRAIN.ts"))
    X_test, y_test = load_from_ts_file(str(data / family / f"{name}_TEST.ts"))
    np.savez(folder / f"{name}.npz", X=np.asarray(X, dtype=np.float64), y=np.asarray(y).astype(str),
             X_test=np.asarray(X_test, dtype=np.float64), y_test=np.asarray(y_test).astype(str))
    rows = []
    for seed in seeds:
        model = MiniRocketClassifier(random_state=seed, n_jobs=1)
        start = time.perf_counter(); model.fit(X, y); fit_s = time.perf_counter() - start
        start = time.perf_counter(); predicted = model.predict(X_test); batch_s = time.perf_counter() - start
        calls = []
        for i in range(min(len(X_test), %d)):
            start = time.perf_counter(); model.predict(X_test[i:i + 1]); calls.append(time.perf_counter() - start)
        rows.append({"seed": seed, "accuracy": float(np.mean(predicted == y_test)), "fit_s": fit_s,
                     "predict_per_recording_ms": 1e3 * batch_s / len(X_test), "predict_call_ms": 1e3 * float(np.median(calls))})
    results[name] = rows
print(json.dumps(results))
''' % LATENCY_CALLS


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


def touchstone_results(name, seeds, folder) -> list[dict]:
    import onnxruntime as ort
    from export.pipelines import export_pipeline
    from models.deployable import TimeSeriesPipeline
    from models.rocket.classifier import RocketClassifier

    data = np.load(folder / f"{name}.npz")
    classes = sorted(set(data["y"]))
    y, y_test = (np.searchsorted(classes, data[k]) for k in ("y", "y_test"))
    X, X_test = data["X"], data["X_test"]
    rows = []
    for seed in seeds:
        start = time.perf_counter()
        model = RocketClassifier(seed=seed).fit(X, y)
        fit_s = time.perf_counter() - start
        windows = X_test.astype(np.float32)   # what the graph takes; the eager side sees the same values
        eager = model.predict_proba(windows.astype(np.float64))
        n_channels, length = X.shape[1], X.shape[2]
        pipeline = TimeSeriesPipeline([f"c{c}" for c in range(n_channels)], classes, None, 1, length,
                                      np.zeros((1, n_channels, 1)), np.ones((1, n_channels, 1)), model)
        options = ort.SessionOptions()
        options.intra_op_num_threads = options.inter_op_num_threads = 1
        session = ort.InferenceSession(export_pipeline(pipeline, 17, "bench").SerializeToString(), options,
                                       providers=["CPUExecutionProvider"])
        onnx_proba = session.run(None, {"window": windows})[0]
        for i in range(5):
            session.run(None, {"window": windows[i % len(windows)][None]})
        calls = []
        for i in range(min(len(windows), LATENCY_CALLS)):
            start = time.perf_counter()
            session.run(None, {"window": windows[i][None]})
            calls.append(time.perf_counter() - start)
        rows.append({"seed": seed, "accuracy": float(np.mean(eager.argmax(1) == y_test)), "fit_s": fit_s,
                     "onnx_accuracy": float(np.mean(onnx_proba.argmax(1) == y_test)),
                     "onnx_eager_max_abs": float(np.abs(onnx_proba - eager).max()),
                     "onnx_latency_ms": 1e3 * float(np.median(calls)), "head": model.head_, "length": length,
                     "channels": n_channels,
                     "alpha": getattr(model, "alpha_", None)})
    return rows


def spread(rows, key) -> str:
    values = np.array([r[key] for r in rows], dtype=float)
    return f"{values.mean():.3f} ± {values.std(ddof=1) if len(values) > 1 else 0.0:.3f}"


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
        peer = aeon_results(args.sets, args.seeds, folder)
        ours = {}
        for name in args.sets:
            ours[name] = touchstone_results(name, args.seeds, folder)
            ours[name][0]["load_average"] = os.getloadavg()[0]
            print(f"{name} done (load average {os.getloadavg()[0]:.1f})", flush=True)
    print("\n| set | length | aeon accuracy | Touchstone accuracy | aeon fit s | Touchstone fit s | aeon predict ms "
          "(per recording in a batch / one call) | ONNX latency ms | ONNX-eager max gap |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in args.sets:
        a, t = peer[name], ours[name]
        print(f"| {name} | {t[0]['length']} | {spread(a, 'accuracy')} | {spread(t, 'accuracy')} | "
              f"{spread(a, 'fit_s')} | {spread(t, 'fit_s')} | {spread(a, 'predict_per_recording_ms')} / "
              f"{spread(a, 'predict_call_ms')} | {spread(t, 'onnx_latency_ms')} | "
              f"{max(r['onnx_eager_max_abs'] for r in t):.1e} |")
    if args.json:
        args.json.write_text(json.dumps({"aeon": peer, "touchstone": ours}, indent=1))


if __name__ == "__main__":
    main()
