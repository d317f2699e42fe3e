"""What a prediction costs: eager Python pipeline vs onnxruntime, per model family, in one run.

    .venv/bin/python bench/latency.py [--families resmlp extra_trees ...] [--budget 3]

For each family: train on the default rubber12 scene (time-series families: materials10,
1 epoch: latency does not depend on training), export, then measure with export/latency.py
(what every run records): batch-1 latency p50/p99 and batch-1024 throughput, eager (numpy
features + scikit-learn or torch, forests predicting with n_jobs=1 as a deployed user would call
them at batch 1) and onnxruntime with 1 intra-op thread and its default.
Also prints the parity on the run's test inputs (max relative difference, and rows over 1e-4:
where a float32 tree took another branch). Figures drift between runs by ~10-20 %.
Appends one record per family (its costs and parity) to results/latency.jsonl.
"""
import argparse
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydra import compose, initialize_config_dir  # noqa: E402

from common.result_records import recording  # noqa: E402
from export.latency import EAGER_BASELINE, measure  # noqa: E402
from export.run_export import export_run  # noqa: E402
from export.onnx_predictor import OnnxPredictor  # noqa: E402
from models.deployable import RegressionPipeline, load_pipeline  # noqa: E402
from runs.run import run  # noqa: E402

REGRESSION = ["resmlp", "random_forest", "extra_trees", "decision_tree", "blend"]
CLASSIFICATION = ["prcnn", "rescnn", "inceptiontime", "lstm_fcn"]
# What a prediction runs through: the exported graphs and the latency code, the eager pipelines
# and their features, and the models' settings (a forest's size is its latency).
MEASURED_CODE = ["export/", "models/", "data/preprocessing/", "configs/model/"]


def overrides(family) -> list[str]:
    """The run each family is trained in: the default scene, or materials10 for a time series."""
    if family in REGRESSION:
        return [f"model={family}", "scene.progress=false", "trainer.progress=false",
                "analysis.ablation=false", "analysis.progress=false"]
    return ["experiment=materials10", f"model={family}", "scene.passes_per_level=2",
            "trainer.max_epochs=1", "trainer.progress=false", "trainer.device=cpu"]


def train_and_export(family, folder):
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=overrides(family))
    run(cfg, folder)
    return export_run(folder), load_pipeline(Path(folder) / "pipeline.npz"), cfg.seed


def parity(path, pipeline):
    predictor = OnnxPredictor(path)
    batch = pipeline.examples
    if isinstance(pipeline, RegressionPipeline):
        out, reference = predictor.predict_array(batch)["prediction"], pipeline.predict_raw(batch)[0]
    else:
        out, reference = predictor.predict_windows(batch), pipeline.predict_raw(batch)
    relative = np.abs(out - reference) / (np.abs(reference).max(axis=0) + 1e-12)
    return relative.max(), int((relative.max(axis=1) > 1e-4).sum()), len(batch)


def measure_family(family: str, budget: float, record) -> tuple:
    """One family's costs and parity, recorded as they were measured (export/latency.py keeps
    each figure's p50 / p99 and call count, not the single calls)."""
    with tempfile.TemporaryDirectory() as folder:
        path, pipeline, seed = train_and_export(family, folder)
        cost = measure(pipeline, path, budget)
        diff, flips, n = parity(path, pipeline)
    record.add(family, {"family": family, "overrides": overrides(family), "budget_s": budget, "cost": cost,
                        "parity_max_rel_diff": diff, "parity_rows_over_1e-4": flips, "parity_rows": n},
               seeds=[seed])
    print(f"{family} done", file=sys.stderr)
    return family, cost, diff, flips, n


def print_table(rows: list[tuple]):
    load = os.getloadavg()
    print(f"\ncores: {os.cpu_count()}; load average {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f} (1 / 5 / 15 min; "
          "timings are fair only on a quiet machine); latency at batch 1 in µs (p50 / p99); throughput at batch "
          f"1024 in samples/s.\neager baseline: {EAGER_BASELINE}.\n")
    print("| family | ONNX size | eager p50 / p99 | ORT 1 thread p50 / p99 | ORT default p50 / p99 | speed-up (p50, best ORT) "
          "| eager /s | ORT 1 thread /s | ORT default /s | max rel. diff | rows over 1e-4 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for family, cost, diff, flips, n in rows:
        lat, thr = cost["latency_batch1_us"], cost["throughput_batch1024_per_s"]
        e, a, d = lat["eager"], lat["onnx_1_thread"], lat["onnx_default"]
        print(f"| {family} | {cost['model_size_bytes'] / 1e6:.1f} MB | {e['p50']:,.0f} / {e['p99']:,.0f} "
              f"| {a['p50']:,.0f} / {a['p99']:,.0f} | {d['p50']:,.0f} / {d['p99']:,.0f} "
              f"| {e['p50'] / min(a['p50'], d['p50']):,.0f}× | {thr['eager']:,.0f} | {thr['onnx_1_thread']:,.0f} "
              f"| {thr['onnx_default']:,.0f} | {diff:.1e} | {flips} / {n} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--families", nargs="*", default=REGRESSION + CLASSIFICATION)
    parser.add_argument("--budget", type=float, default=3.0, help="seconds of calls per figure")
    args = parser.parse_args(argv)
    with recording("latency", MEASURED_CODE) as record:
        rows = [measure_family(family, args.budget, record) for family in args.families]
        print_table(rows)


if __name__ == "__main__":
    main()
