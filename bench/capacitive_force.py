"""Force-from-capacitance table of a `experiment=capacitive_force` multirun: per model, mean ± sd over
seeds of the test R^2 and RMSE of force_n and of the correlation factor (Egger et al. 2025's slope: pressed
cell's RMC change against the model's predicted force on the test presses, counts per newton).

    .venv/bin/python bench/capacitive_force.py multirun/capacitive_force/<stamp>

Appends the per-run numbers to results/capacitive_force.jsonl.
"""
import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from common.run_status import run_status  # noqa: E402
from data.scenes.capacitive6x6 import correlation_factor_rmc_per_n, pressed_cell_rmc  # noqa: E402

# What the sweep's runs measured: the seven models, the scene, features and split, and the experiment's
# settings. The hashes are this checkout's: tabulate a sweep trained at the same commit.
MEASURED_CODE = ["models/classic_regressors.py", "models/trees.py", "models/resmlp_regressor.py",
                 "models/nets/resmlp.py", "models/kfold_blend.py", "models/weighted_blend.py", "runs/regression.py",
                 "data/", "configs/experiment/capacitive_force.yaml", "configs/model/", "configs/scene/"]


def run_row(run_dir: Path) -> dict:
    cfg = OmegaConf.load(run_dir / ".hydra" / "config.yaml")
    metrics = json.loads((run_dir / "metrics.json").read_text())
    predictions = pd.read_csv(run_dir / "predictions.csv")
    # predictions.csv: the test rows' channels, the predicted targets and true_<target>
    truth = predictions.rename(columns=lambda c: c.removeprefix("true_") if c.startswith("true_") else c + "_pred"
                               if c in ("force_n", "x_mm", "y_mm") else c)
    scene = cfg.scene
    rmc = pressed_cell_rmc(truth, scene.rows, scene.cols, scene.pitch_mm)
    force = metrics["test"]["force_n"]
    choices = OmegaConf.load(run_dir / ".hydra" / "hydra.yaml").hydra.runtime.choices
    return {"model": choices.model, "seed": cfg.seed,
            "r2": force["r2"], "rmse_n": force["rmse"],
            "median_abs_n": float(np.median(np.abs(truth["force_n_pred"] - truth["force_n"]))),
            "slope_pred": correlation_factor_rmc_per_n(rmc, truth["force_n_pred"].to_numpy()),
            "slope_true": correlation_factor_rmc_per_n(rmc, truth["force_n"].to_numpy()),
            "fit_s": metrics["cost"]["fit_time_s"]}


def print_table(frame: pd.DataFrame, order: list[str]):
    summary = frame.groupby("model").agg(["mean", "std", "count"]).reindex(order)
    print("| model | seeds | test R² (force) | test RMSE (N) | median abs. error (N) | correlation factor (counts/N) | fit (s) |")
    print("|---|---|---|---|---|---|---|")
    for model, row in summary.iterrows():
        print(f"| {model} | {int(row[('r2', 'count')])} | {row[('r2', 'mean')]:.4f} ± {row[('r2', 'std')]:.4f} "
              f"| {row[('rmse_n', 'mean')]:.4f} ± {row[('rmse_n', 'std')]:.4f} "
              f"| {row[('median_abs_n', 'mean')]:.4f} ± {row[('median_abs_n', 'std')]:.4f} "
              f"| {row[('slope_pred', 'mean')]:.2f} ± {row[('slope_pred', 'std')]:.2f} "
              f"| {row[('fit_s', 'mean')]:.1f} |")
    print(f"\nsensor's own slope (pressed cell's RMC vs the force sensor, test presses): "
          f"{frame['slope_true'].mean():.2f} ± {frame['slope_true'].std():.2f} counts/N")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("sweep_dir")
    args = parser.parse_args(argv)
    runs = sorted((p for p in Path(args.sweep_dir).iterdir() if p.is_dir() and run_status(p).state == "finished"),
                  key=lambda p: int(p.name))
    with recording("capacitive_force", MEASURED_CODE) as record:
        frame = pd.DataFrame([run_row(r) for r in runs])
        order = list(dict.fromkeys(frame["model"]))
        print_table(frame, order)
        # per model, in the sweep's order: one value per finished run (its seed in `seeds`)
        rows = [{"model": model, **frame[frame["model"] == model].drop(columns="model").to_dict("list")}
                for model in order]
        record.add("force_by_model", {"sweep": Path(args.sweep_dir).name, "rows": rows},
                   seeds=sorted(set(frame["seed"])))


if __name__ == "__main__":
    main()
