"""How much does K-fold blending steady a model? The rubber12 paper's eq. 17 claim, measured:
the residual MLP trained once per seed as a single model and as a K-fold blend on the same data,
and the spread of their test predictions across seeds compared (variance reduction =
1 - var_blend / var_single, averaged over test rows, per target). The paper reports 8.3 % for
its ResNN. bench/kfold_variance.py prints it; a slow test asserts it."""
import sys
import time
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate

from models.kfold_blend import KFoldBlend
from runs.report.metrics import regression_metrics

ROOT = Path(__file__).resolve().parents[2]


def measure(seeds: int = 5, folds: int = 5, overrides=()) -> dict:
    """Fit the net single and K-fold blended per seed; per target: test R² of each (one per seed),
    the prediction variance across seeds of each, and the variance reduction 1 - blend / single."""
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=["model=resmlp", "trainer.progress=false", "scene.progress=false",
                                            *overrides])
    datamodule = instantiate(cfg.data).setup()
    (X, y), (X_val, y_val), (X_test, y_test) = datamodule.train, datamodule.val, datamodule.test
    targets = datamodule.target_names
    groups = datamodule.table.groups[datamodule.train_idx] if datamodule.split in ("grouped", "predefined") else None
    predictions = {"single": [], "blend": []}
    r2 = {"single": [], "blend": []}
    seconds = {"single": 0.0, "blend": 0.0}
    for seed in range(seeds):
        net = instantiate(cfg.model, seed=seed)
        for kind, model in (("single", net), ("blend", KFoldBlend(net, n_folds=folds, seed=seed, progress=False))):
            start = time.perf_counter()
            # the single net early-stops on the validation split; each fold net carves its own
            # early-stopping rows from its K - 1 folds (grouped like the split)
            model.fit(X, y, X_val, y_val) if kind == "single" else model.fit(X, y, groups=groups)
            seconds[kind] += time.perf_counter() - start
            predicted = model.predict(X_test)
            predictions[kind].append(predicted)
            r2[kind].append([regression_metrics(y_test, predicted, targets)[t]["r2"] for t in targets])
        print(f"seed {seed} done", file=sys.stderr)
    spread = {k: np.stack(v).var(axis=0, ddof=1).mean(axis=0) for k, v in predictions.items()}
    return {"targets": targets, "n_train": len(X), "n_test": len(X_test),
            "r2": {k: np.asarray(v) for k, v in r2.items()}, "variance": spread,
            "reduction": 1.0 - spread["blend"] / spread["single"],
            "seconds_per_seed": {k: v / seeds for k, v in seconds.items()}}
