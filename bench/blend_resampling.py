"""K-fold blending against one model per candidate on all training rows and against a seed
ensemble, on equal data over repeated grouped splits of the default scene.

    .venv/bin/python bench/blend_resampling.py [--splits 0 1 2 3 4] [overrides ...]

Per split (the datamodule's seed: a different grouped train/validation/test draw, every repeat of
a press on one side): the default blend's three candidates (resmlp, random forest, extra trees)
are fitted three ways on the same training rows: K-fold blended (the default, K = data.n_folds),
once on all rows, and as a seed ensemble of K members on all rows. Each set is blended by the
paper's validation weights (the one rule all three can use), the K-fold set by stacking too
(the default). Prints validation and test R^2 per target as mean ± sd over splits, the fit CPU
time of each (wall time depends on other work), and the load average before and after; appended
to results/blend_resampling.jsonl (a run with Hydra overrides only prints).
"""
import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate
from sklearn.metrics import r2_score

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from common.threads import apply_threads  # noqa: E402
from models.kfold_blend import KFoldBlend  # noqa: E402
from models.weighted_blend import ValidationWeightedBlend  # noqa: E402
from runs.run import seed_everything  # noqa: E402

# What the comparison measures: the two blendings, the three candidates and their configs, and the
# default scene, features and split they are fitted on.
MEASURED_CODE = ["models/kfold_blend.py", "models/weighted_blend.py", "models/trees.py", "models/resmlp_regressor.py",
                 "models/nets/resmlp.py", "configs/model/", "configs/trainer/", "configs/scene/", "data/"]


def scores(y, predicted) -> np.ndarray:
    return np.array([r2_score(y[:, k], predicted[:, k]) for k in range(y.shape[1])])


def one_split(seed: int, overrides: list[str]) -> tuple:
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=["scene.progress=false", "trainer.progress=false", "model=blend",
                                            f"seed={seed}", *overrides])
    seed_everything(seed)
    datamodule = instantiate(cfg.data).setup()
    (X, y), (X_val, y_val), (X_test, y_test) = datamodule.train, datamodule.val, datamodule.test
    groups = datamodule.table.groups[datamodule.train_idx]
    kfold = instantiate(cfg.model)
    estimators = {name: candidate.estimator for name, candidate in kfold.candidates.items()}
    sets = {
        "kfold": kfold,
        "single": ValidationWeightedBlend(estimators, weights="paper", seed=seed),
        "seeds": ValidationWeightedBlend({n: KFoldBlend(e, n_folds=cfg.data.n_folds, seed=seed, progress=False,
                                                        resample="seeds") for n, e in estimators.items()},
                                         weights="paper", seed=seed),
    }
    rows, seconds = {}, {}
    for kind, blend in sets.items():
        start = time.process_time()
        blend.fit(X, y, X_val, y_val, groups=groups)
        seconds[kind] = time.process_time() - start
        rows[f"{kind} blend, weights={blend.weights}"] = blend
        if kind == "kfold":
            rows["kfold blend, weights=paper"] = blend.reweighted("paper")
        for name, member in blend.models_.items():
            rows[f"{name} {kind}"] = member
    result = {name: {"val": scores(y_val, m.predict(X_val).reshape(y_val.shape)),
                     "test": scores(y_test, m.predict(X_test).reshape(y_test.shape))} for name, m in rows.items()}
    print(f"split {seed}: fit CPU seconds {', '.join(f'{k} {v:.1f}' for k, v in seconds.items())}; "
          f"load {os.getloadavg()[0]:.2f}", file=sys.stderr, flush=True)
    settings = {"protocol": cfg.scene.get("protocol"), "n_samples": cfg.scene.get("n_samples"),
                "split": datamodule.split, "n_folds": cfg.data.n_folds}
    return result, datamodule.target_names, seconds, settings


def print_table(splits, results, seconds, targets):
    print(f"\n{len(splits)} grouped splits {splits}; R^2 mean ± sd over splits")
    print(f"| model | part | {' | '.join(targets)} | mean |")
    print(f"|---|---|{'---|' * (len(targets) + 1)}")
    for name in results[0]:
        for part in ("val", "test"):
            values = np.array([r[name][part] for r in results])
            means = np.append(values, values.mean(axis=1, keepdims=True), axis=1)
            cells = [f"{means[:, k].mean():.3f} ± {means[:, k].std(ddof=1):.3f}" for k in range(means.shape[1])]
            print(f"| {name} | {part} | {' | '.join(cells)} |")
    for kind in seconds[0]:
        values = np.array([s[kind] for s in seconds])
        print(f"fit CPU seconds {kind}: {values.mean():.1f} ± {values.std(ddof=1):.1f}")


def record_splits(record, splits, results, seconds, targets, settings):
    """The R² table (per model and part: splits x targets) and the fit CPU seconds per split,
    rows in the printed order."""
    rows = [{"model": name, **{part: [r[name][part] for r in results] for part in ("val", "test")}}
            for name in results[0]]
    record.add("r2", {**settings, "targets": targets, "rows": rows}, seeds=splits)
    record.add("fit_cpu_s", {**settings, "by_kind": {kind: [s[kind] for s in seconds] for kind in seconds[0]}},
               seeds=splits)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--splits", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("overrides", nargs="*")
    args = parser.parse_args(argv)
    apply_threads(1)   # as train.py's default: one thread per process, so load from other work costs least
    print(f"load average before: {os.getloadavg()}")
    with recording("blend_resampling", MEASURED_CODE) as record:
        results, seconds = [], []
        for seed in args.splits:
            result, targets, fit_seconds, settings = one_split(seed, args.overrides)
            results.append(result)
            seconds.append(fit_seconds)
        print(f"load average after: {os.getloadavg()}")
        print_table(args.splits, results, seconds, targets)
        # docs/pipeline.md's table is the default scene's: a run with overrides measures another thing.
        if not args.overrides:
            record_splits(record, args.splits, results, seconds, targets, settings)


if __name__ == "__main__":
    main()
