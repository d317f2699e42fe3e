"""K-fold blending against one model per candidate on all training rows and against a seed
ensemble, on equal data over repeated grouped splits of the default scene.

    .venv/bin/python bench/blend_resampling.py [--splits 0 1 2 3 4] [overrides ...]

Per split (the datamodule's seed: a different grouped train/validation/test draw, every repeat of
a press on one side): the default blend's three candidates (resmlp, random forest, extra trees)
are fitted three ways on the same training rows: K-fold blended (the default, K = data.n_folds),
once on all rows, and as a seed ensemble of K members on all rows. Each set is blended by the
paper's validation weights (the one rule all three can use), the K-fold set by stacking too
(the default). Prints validation and test R^2 per target as mean ± sd over splits, the fit CPU
time of each (wall time depends on other work), and the load average before and after.
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

from common.threads import apply_threads  # noqa: E402
from models.kfold_blend import KFoldBlend  # noqa: E402
from models.weighted_blend import ValidationWeightedBlend  # noqa: E402
from runs.run import seed_everything  # noqa: E402


def scores(y, predicted) -> np.ndarray:
    return np.array([r2_score(y[:, k], predicted[:, k]) for k in range(y.shape[1])])


def one_split(seed: int, overrides: list[str]) -> dict:
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
    return result, datamodule.target_names, seconds


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--splits", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("overrides", nargs="*")
    args = parser.parse_args(argv)
    apply_threads(1)   # as train.py's default: one thread per process, so load from other work costs least
    print(f"load average before: {os.getloadavg()}")
    results, seconds = [], []
    for seed in args.splits:
        result, targets, fit_seconds = one_split(seed, args.overrides)
        results.append(result)
        seconds.append(fit_seconds)
    print(f"load average after: {os.getloadavg()}")
    print(f"\n{len(args.splits)} grouped splits {args.splits}; R^2 mean ± sd over splits")
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


if __name__ == "__main__":
    main()
