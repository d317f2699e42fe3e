"""The rubber12 paper's validation weights vs stacking, beside each candidate alone, over several seeds.

    .venv/bin/python bench/blend_weights.py [--seeds 0 1 2] [overrides ...]
    (default overrides: model=blend scene.protocol=random scene.n_samples=2000)
    .venv/bin/python bench/blend_weights.py model=blend scene.protocol=lab scene.n_samples=450   # the paper's 450 lab presses

Per seed: the default blend's three K-fold candidates are fitted once on the training split;
the paper's weights (eq. 18-20, from validation R^2) and the stacking weights (super learner on
the out-of-fold predictions, guarded on validation) are computed from the same fitted
candidates, so the comparison isolates the weighting. Prints validation and test R^2 per target
as mean ± sd over seeds, and which candidate scores best on validation per target at each seed
(the rubber12 paper's §IV-E: extra trees, weights 0, 0, 1). Weights are chosen on validation;
test is for reporting only. The split is the datamodule's (grouped by default: all repeats of a
position-depth pair on one side, so no press is in both training and validation). Appended to
results/blend_weights.jsonl as `r2` and `weights`, `r2/<the overrides>` etc. under other overrides.
"""
import argparse
import re
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
from common.threads import apply_threads, resolve_threads  # noqa: E402
from runs.run import seed_everything  # noqa: E402

DEFAULT = ["model=blend", "scene.protocol=random", "scene.n_samples=2000"]
BLENDS = ["blend, weights=paper", "blend, weights=stacking"]   # the rows beside the candidates alone
# What the comparison measures: the two weighting rules, the three candidates and their configs,
# and the scene, features and split they are fitted on.
MEASURED_CODE = ["models/weighted_blend.py", "models/kfold_blend.py", "models/trees.py", "models/resmlp_regressor.py",
                 "models/nets/resmlp.py", "configs/model/", "configs/trainer/", "configs/scene/", "data/"]


def scores(y, predicted) -> np.ndarray:
    return np.array([r2_score(y[:, k], predicted[:, k]) for k in range(y.shape[1])])


def one_seed(seed: int, overrides: list[str]) -> dict:
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=["scene.progress=false", "trainer.progress=false", f"seed={seed}",
                                            *overrides])
    apply_threads(resolve_threads(cfg.threads))   # the run's setting (1 by default): no idle torch threads spinning
    seed_everything(seed)
    datamodule = instantiate(cfg.data).setup()
    (X, y), (X_val, y_val), (X_test, y_test) = datamodule.train, datamodule.val, datamodule.test
    groups = datamodule.table.groups[datamodule.train_idx] if datamodule.split in ("grouped", "predefined") else None
    paper = instantiate(cfg.model, weights="paper")
    start = time.perf_counter()
    paper.fit(X, y, X_val, y_val, groups=groups)
    seconds = time.perf_counter() - start
    stacking = paper.reweighted("stacking")  # the same fitted candidates, the other rule
    rows = {name: model for name, model in paper.models_.items()}
    rows[BLENDS[0]], rows[BLENDS[1]] = paper, stacking
    result = {name: {"val": scores(y_val, m.predict(X_val).reshape(y_val.shape)),
                     "test": scores(y_test, m.predict(X_test).reshape(y_test.shape))} for name, m in rows.items()}
    result["weights"] = {"paper": paper.weights_, "stacking": stacking.weights_,
                         "stacking_fallback": stacking.stacking_fallback_targets_}
    result["fit_s"] = seconds
    print(f"seed {seed}: fitted in {seconds:.0f} s; stacking weights (candidates x targets)\n"
          f"{np.round(stacking.weights_, 3)}; fallback targets {stacking.stacking_fallback_targets_}",
          file=sys.stderr)
    settings = {"protocol": cfg.scene.get("protocol"), "n_samples": cfg.scene.get("n_samples"),
                "split": datamodule.split, "n_folds": cfg.data.n_folds}
    return result, datamodule.target_names, list(paper.models_), settings


def print_table(seeds, overrides, results, targets, candidates):
    names = candidates + BLENDS
    print(f"\n{' '.join(overrides)}; seeds {seeds}; R² mean ± sd over seeds\n")
    print("| model | split | " + " | ".join(targets) + " |")
    print("|---|---|" + "---|" * len(targets))
    for split in ("val", "test"):
        for name in names:
            values = np.array([r[name][split] for r in results])
            cells = [f"{m:.4f} ± {s:.4f}" for m, s in zip(values.mean(axis=0), values.std(axis=0, ddof=1))]
            print(f"| {name} | {'validation' if split == 'val' else 'test'} | " + " | ".join(cells) + " |")
    validation = np.array([[r[name]["val"] for name in candidates] for r in results])   # seeds x candidates x targets
    winners = validation.argmax(axis=1)
    print("\nbest candidate on validation per target, seed by seed (" + ", ".join(map(str, seeds)) + ")")
    for k, target in enumerate(targets):
        print(f"{target}: " + ", ".join(candidates[w] for w in winners[:, k]))
    paper = np.array([r["weights"]["paper"] for r in results]).mean(axis=0)
    stacking = np.array([r["weights"]["stacking"] for r in results]).mean(axis=0)
    print("\nmean weights over seeds (rows: " + ", ".join(candidates) + "; columns: " + ", ".join(targets) + ")")
    print("paper:\n" + str(np.round(paper, 3)) + "\nstacking:\n" + str(np.round(stacking, 3)))


def variant(overrides: list[str]) -> str:
    """The records' name suffix: none for the default overrides, else the overrides (sorted) in
    snake_case, so that the paper's 450 lab presses (docs/fidelity.md, row 12) keep their own records."""
    if sorted(overrides) == sorted(DEFAULT):
        return ""
    return "/" + re.sub(r"[^a-z0-9]+", "_", " ".join(sorted(overrides)).lower()).strip("_")


def record_seeds(record, seeds, overrides, results, targets, candidates, settings):
    """The R² table (per model and split: seeds x targets, with each seed's fit seconds) and the
    weights of both rules per seed (seeds x candidates x targets)."""
    common = {"overrides": overrides, **settings, "targets": targets, "candidates": candidates}
    rows = [{"model": name, **{split: [r[name][split] for r in results] for split in ("val", "test")}}
            for name in candidates + BLENDS]
    record.add("r2" + variant(overrides), {**common, "rows": rows, "fit_s": [r["fit_s"] for r in results]},
               seeds=seeds)
    record.add("weights" + variant(overrides),
               {**common, **{rule: [r["weights"][rule] for r in results]
                             for rule in ("paper", "stacking", "stacking_fallback")}}, seeds=seeds)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, nargs="*", default=[0, 1, 2])
    parser.add_argument("overrides", nargs="*")
    args = parser.parse_args(argv)
    overrides = args.overrides or DEFAULT
    with recording("blend_weights", MEASURED_CODE) as record:
        results = []
        for seed in args.seeds:
            result, targets, candidates, settings = one_seed(seed, overrides)
            results.append(result)
        print_table(args.seeds, overrides, results, targets, candidates)
        record_seeds(record, args.seeds, overrides, results, targets, candidates, settings)


if __name__ == "__main__":
    main()
