"""Few presses and a fitted scene against many presses from scratch, on a rig stand-in (issue 43).

For each scene and hidden draw, a rig stand-in (data/calibration/rig_standin.py: the scene's
identifiable parameters moved by up to 40 %, every effect on, including those the fit leaves
out) presses --n-test times for the test set and max(--n) times for a pool; a run takes N of
the pool (a quarter of them, at least 3, as validation presses), and runs exactly what
`experiment=calibrate` runs (runs/calibration/pretraining.py: the scene fit on the training
presses, the simulated sets, scratch / default-scene / fitted-scene candidates, the choice on
validation). Each candidate and the choice are scored on the test presses: mean R² over the
scene's targets. The fit's recovered parameters are compared with the hidden ones (within the
reported 95 % interval: 1.96 sd, on the log scale for parameters fitted on one).

    .venv/bin/python bench/calibrate.py --quick        # N = 20 and 200, 3 draws, smaller sets
    .venv/bin/python bench/calibrate.py                # N = 10, 20, 50, 100, 200, 3 draws x 3 seeds
    .venv/bin/python bench/calibrate.py --command-time --scenes rubber12   # the one command on 20 and 200 presses

Records (results/calibrate.jsonl): `<scene>/N=<n>` with the test R² per method and run,
`<scene>/recovery` with each parameter's hidden value, fit, sd and whether it was inside, and
`command/<scene>/N=<n>` with the one command's wall time.
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

for variable in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from hydra import compose, initialize_config_dir  # noqa: E402
from hydra.utils import instantiate  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.atomic import atomic_write  # noqa: E402
from common.result_records import RESULTS, latest, read_records, recording  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402
from data.calibration.identifiable import calibration_for  # noqa: E402
from data.calibration.rig_standin import hidden_parameters, rig_presses  # noqa: E402
from data.datamodules.regression import RegressionDataModule  # noqa: E402
from data.sensor_table import SensorTable  # noqa: E402
from runs.calibration.pretraining import CANDIDATES, calibrate_and_pretrain, predict  # noqa: E402
from runs.report.metrics import regression_metrics  # noqa: E402

MEASURED_CODE = ["data/calibration/", "runs/calibration/pretraining.py", "configs/experiment/calibrate.yaml",
                 "data/scenes/", "models/trees.py", "data/preprocessing/features.py"]
METHODS = (*CANDIDATES, "chosen")
FIGURE = ROOT / "bench" / "figures" / "calibrate_learning_curves.png"


class FrameSource:
    """An in-memory table with its declared split, for the datamodule."""

    def __init__(self, frame, channels, targets, split):
        self.frame, self.channels, self.targets, self.split, self.name = frame, channels, targets, split, "rig stand-in"

    def load(self):
        return SensorTable(self.frame.reset_index(drop=True), self.channels, self.targets, np.arange(len(self.frame)),
                           {"source": "rig stand-in"}, split=self.split)


def config(scene: str, seed: int, quick: bool, extra=()):
    overrides = [f"scene={scene}", "experiment=calibrate", "data.path=unused.csv", f"seed={seed}",
                 "scene.progress=false"]
    if quick:
        overrides += ["calibration.n_simulated=1000", "calibration.max_evaluations=40", "model.n_estimators=100"]
    overrides += list(extra)
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        return compose("config", overrides=overrides)


def one_run(cfg, scene, pool, test, n: int, seed: int) -> tuple[dict, dict]:
    """Test mean R² per method, and the fit, for N presses of the pool."""
    calibration = calibration_for(scene)
    targets = list(calibration.inputs) + list(calibration.outputs)
    channels = [c for c in pool.columns if c not in targets]
    chosen_rows = np.random.default_rng(seed).permutation(len(pool))[:n]
    presses = pool.iloc[chosen_rows]
    n_val = max(3, n // 4)
    split = np.r_[np.full(n - n_val, "train"), np.full(n_val, "val"), np.full(len(test), "test")]
    frame = pd.concat([presses, test], ignore_index=True)
    datamodule = RegressionDataModule(FrameSource(frame, channels, targets, split), cfg.data.features,
                                      split="predefined", val_fraction=0.25, calibration_fraction=0.0,
                                      seed=seed).setup()
    done = calibrate_and_pretrain(cfg, datamodule, scene)
    X_test, y_test = datamodule.test
    scores = {name: regression_metrics(y_test, predict(model, X_test, targets), targets)["average"]["r2"]
              for name, (model, *_) in done["candidates"].items()}
    scores["chosen"] = scores[done["chosen"]]
    return scores, done


def plot_learning_curves() -> Path:
    """The newest learning-curve records, one panel per scene: test R² against N per method
    (mean ± sd as error bars), written to FIGURE (docs/calibrate.md shows it)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = dict.fromkeys(r["name"] for r in read_records(RESULTS / "calibrate.jsonl") if "/N=" in r["name"] and not r["name"].startswith("command/"))
    records = [latest("calibrate", name) for name in names]
    scenes = list(dict.fromkeys(name.split("/")[0] for name in names))
    figure, axes = plt.subplots(1, len(scenes), figsize=(4.2 * len(scenes), 3.4), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        mine = sorted((int(r["name"].split("=")[1]), r["values"]["test_mean_r2"]) for r in records
                      if r["name"].startswith(scene + "/"))
        sizes = [n for n, _ in mine]
        for method in METHODS:
            values = [np.asarray(v[method], dtype=float) for _, v in mine]
            ax.errorbar(sizes, [x.mean() for x in values], yerr=[x.std(ddof=1) if len(x) > 1 else 0 for x in values],
                        marker="o", capsize=3, label=method.replace("_", " "))
        ax.set_xscale("log")
        ax.set_xlabel("calibration presses N")
        ax.set_ylabel("test R² (mean over targets)")
        ax.set_title(scene)
    axes[0][0].legend(fontsize=7)
    figure.tight_layout()
    FIGURE.parent.mkdir(exist_ok=True)
    atomic_write(FIGURE, lambda tmp: figure.savefig(tmp, dpi=90, format="png"))
    plt.close(figure)
    return FIGURE


def command_times(scene_name: str, sizes, record) -> None:
    """The one command's wall time on a stand-in rig's table of N presses (all its defaults)."""
    base = instantiate(config(scene_name, 0, False).scene)
    hidden = hidden_parameters(base, np.random.default_rng(999))
    with tempfile.TemporaryDirectory() as folder:
        for n in sizes:
            path = Path(folder) / f"presses_{n}.csv"
            rig_presses(base, hidden, 999, n).to_csv(path, index=False)
            command = [sys.executable, "train.py", "experiment=calibrate", f"scene={scene_name}", "data=table",
                       f"data.path={path}", f"hydra.run.dir={Path(folder) / f'run_{n}'}"]
            start = time.perf_counter()
            done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
            wall_s = time.perf_counter() - start
            if done.returncode != 0:
                raise SystemExit(f"the command failed on {n} presses: {done.stderr.strip().splitlines()[-1]}")
            record.add(f"command/{scene_name}/N={n}", {"wall_s": [wall_s], "presses": n,
                                                         "command": "python train.py experiment=calibrate "
                                                                    f"scene={scene_name} data=table "
                                                                    "data.path=<N presses>.csv"}, seeds=[0])
            print(f"{scene_name}, {n} presses: the one command took {wall_s:.0f} s", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["taxels", "capacitive6x6", "rubber12"])
    parser.add_argument("--n", nargs="+", type=int, default=None)
    parser.add_argument("--draws", type=int, default=3)
    parser.add_argument("--seeds", type=int, default=None, help="seeds per draw (3; --quick: 1)")
    parser.add_argument("--n-test", type=int, default=200)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--set", nargs="*", default=[], help="Hydra overrides, e.g. calibration.real_weight=0.2")
    parser.add_argument("--command-time", action="store_true",
                        help="time the one command (train.py experiment=calibrate) on N presses per scene instead")
    parser.add_argument("--plot-only", action="store_true", help="redraw the figure from the newest records")
    args = parser.parse_args()
    if args.command_time:
        with recording("calibrate", MEASURED_CODE) as record:
            for scene_name in args.scenes:
                command_times(scene_name, args.n or [20, 200], record)
        return
    if args.plot_only:
        print(f"wrote {plot_learning_curves().relative_to(ROOT)}")
        return
    sizes = args.n or ([20, 200] if args.quick else [10, 20, 50, 100, 200])
    seeds_per_draw = args.seeds or (1 if args.quick else 3)
    with recording("calibrate", MEASURED_CODE) as record:
        for scene_name in args.scenes:
            scores = {n: {m: [] for m in METHODS} for n in sizes}
            chosen = {n: [] for n in sizes}
            recovery, run_seeds = [], []
            for draw in range(args.draws):
                base = instantiate(config(scene_name, 0, args.quick, args.set).scene)
                hidden = hidden_parameters(base, np.random.default_rng(1000 + draw))
                everything = rig_presses(base, hidden, 1000 + draw, args.n_test + max(sizes))
                test, pool = everything.iloc[:args.n_test], everything.iloc[args.n_test:]
                for k in range(seeds_per_draw):
                    seed = draw * seeds_per_draw + k
                    run_seeds.append(seed)
                    cfg = config(scene_name, seed, args.quick, args.set)
                    scene = instantiate(cfg.scene)
                    for n in sizes:
                        start = time.perf_counter()
                        result, done = one_run(cfg, scene, pool, test, n, seed)
                        for method in METHODS:
                            scores[n][method].append(result[method])
                        chosen[n].append(done["chosen"])
                        if n == 20:
                            for p in done["fit"].parameters:
                                recovery.append({"parameter": p.path, "draw": draw, "seed": seed, "hidden": hidden[p.path],
                                                 "default": p.default, "fitted": p.value, "sd": p.sd,
                                                 "at_bound": p.at_bound,
                                                 "inside_95": bool(p.interval()[0] <= hidden[p.path] <= p.interval()[1])})
                        print(f"{scene_name} draw {draw} seed {seed} N={n}: "
                              + ", ".join(f"{m} {result[m]:.3f}" for m in METHODS)
                              + f" (chose {done['chosen']}; {time.perf_counter() - start:.0f} s)", flush=True)
            for n in sizes:
                record.add(f"{scene_name}/N={n}", {"test_mean_r2": scores[n], "chosen": chosen[n],
                                                   "draws": args.draws, "seeds_per_draw": seeds_per_draw,
                                                   "n_test": args.n_test, "quick": args.quick, "overrides": args.set}, seeds=run_seeds)
                print(f"{scene_name} N={n}: " + ", ".join(f"{m} {format_mean_sd(scores[n][m], '.3f')}" for m in METHODS))
            if recovery:
                record.add(f"{scene_name}/recovery", {"pairs": recovery}, seeds=run_seeds)
                inside = np.mean([r["inside_95"] for r in recovery])
                print(f"{scene_name}: {inside:.0%} of (parameter, run) pairs inside the reported 95 % interval")
    print(f"wrote {plot_learning_curves().relative_to(ROOT)}")


if __name__ == "__main__":
    main()
