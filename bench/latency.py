"""What a prediction costs: eager Python pipeline vs onnxruntime, per model family, in one run.

    .venv/bin/python bench/latency.py [--families resmlp extra_trees ...] [--reps 200]

For each family: train on the default rubber12 scene (time-series families: materials10,
1 epoch: latency does not depend on training), export, then time single-sample latency (p50,
p99 over --reps calls after warm-up) and batch-1024 throughput for the eager pipeline (numpy
features + scikit-learn or torch) and for onnxruntime with 1 intra-op thread and with its
default. Also prints the parity (max relative difference, and rows where a float32 tree took
another branch) on 1024 simulated inputs. Figures drift between runs by ~10-20 %.
"""
import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydra import compose, initialize_config_dir  # noqa: E402

from data.fingertip import FingertipScene  # noqa: E402
from data.rubber12 import Rubber12Scene  # noqa: E402
from export.run_export import export_run  # noqa: E402
from export.runtime import OnnxPredictor  # noqa: E402
from models.deployable import load_pipeline  # noqa: E402
from models.run import run  # noqa: E402

REGRESSION = ["resmlp", "random_forest", "extra_trees", "decision_tree", "blend"]
CLASSIFICATION = ["prcnn", "rescnn", "inceptiontime", "lstm_fcn"]


def timings(call, sample, reps):
    for _ in range(max(3, reps // 20)):
        call(sample)
    times = []
    for _ in range(reps):
        start = time.perf_counter()
        call(sample)
        times.append(time.perf_counter() - start)
    return np.percentile(times, 50), np.percentile(times, 99)


def throughput(call, batch, reps=3):
    call(batch)
    start = time.perf_counter()
    for _ in range(reps):
        call(batch)
    return reps * len(batch) / (time.perf_counter() - start)


def train_and_export(family, folder):
    if family in REGRESSION:
        overrides = [f"model={family}", "scene.progress=false", "trainer.progress=false",
                     "analysis.ablation=false", "analysis.progress=false"]
    else:
        overrides = ["experiment=materials10", f"model={family}", "scene.passes_per_level=2",
                     "trainer.max_epochs=1", "trainer.progress=false", "trainer.device=cpu"]
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=overrides)
    run(cfg, folder)
    return export_run(folder), load_pipeline(Path(folder) / "pipeline.pkl")


def inputs(family, pipeline):
    if family in REGRESSION:
        table = Rubber12Scene(n_samples=1024, protocol="random", seed=7, effects={"contact": {}, "percolation": {}},
                              progress=False).generate()
        return table.channels
    recordings = FingertipScene(boards="materials10", passes_per_level=2, effects={}).generate()
    windows = recordings.signals[:, :, 30:30 + pipeline.raw_length]
    return np.resize(windows, (1024,) + windows.shape[1:])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--families", nargs="*", default=REGRESSION + CLASSIFICATION)
    parser.add_argument("--reps", type=int, default=200)
    args = parser.parse_args(argv)
    rows = []
    for family in args.families:
        with tempfile.TemporaryDirectory() as folder:
            path, pipeline = train_and_export(family, folder)
            size = os.path.getsize(path)
            data = inputs(family, pipeline)
            one, batch = data[:1], data[:1024]
            if family in REGRESSION:
                eager = lambda x: pipeline.predict_raw(x)  # noqa: E731
                runners = {t: (lambda p: (lambda x: p.predict_array(x)))(OnnxPredictor(path, threads=t)) for t in (1, None)}
                reference = pipeline.predict_raw(batch)[0]
                onnx_out = runners[None](batch)["prediction"]
            else:
                eager = lambda x: pipeline.predict_raw(x)  # noqa: E731
                runners = {t: (lambda p: (lambda x: p.predict_windows(x)))(OnnxPredictor(path, threads=t)) for t in (1, None)}
                reference = pipeline.predict_raw(batch)
                onnx_out = runners[None](batch)
            relative = np.abs(onnx_out - reference) / (np.abs(reference).max(axis=0) + 1e-12)
            flipped = int((relative.max(axis=1) > 1e-4).sum())
            reps = args.reps if family not in ("random_forest", "blend") else max(20, args.reps // 10)
            e50, e99 = timings(eager, one, reps)
            o1 = timings(runners[1], one, args.reps)
            od = timings(runners[None], one, args.reps)
            rows.append((family, size, e50, e99, o1[0], o1[1], od[0], od[1], throughput(eager, batch),
                         throughput(runners[1], batch), throughput(runners[None], batch), relative.max(), flipped))
            print(f"{family} done", file=sys.stderr)
    print(f"\ncores: {os.cpu_count()}; latency at batch 1 in microseconds (p50 / p99); throughput at batch 1024 in samples/s\n")
    print("| family | ONNX size | eager p50 / p99 | ORT 1 thread p50 / p99 | ORT default p50 / p99 | speed-up (p50, best ORT) "
          "| eager /s | ORT 1 thread /s | ORT default /s | max rel. diff | rows over 1e-4 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for f, size, e50, e99, a50, a99, d50, d99, te, t1, td, diff, flips in rows:
        print(f"| {f} | {size / 1e6:.1f} MB | {1e6 * e50:,.0f} / {1e6 * e99:,.0f} | {1e6 * a50:,.0f} / {1e6 * a99:,.0f} "
              f"| {1e6 * d50:,.0f} / {1e6 * d99:,.0f} | {e50 / min(a50, d50):,.0f}× | {te:,.0f} | {t1:,.0f} | {td:,.0f} "
              f"| {diff:.1e} | {flips} / 1024 |")


if __name__ == "__main__":
    main()
