"""How much does K-fold blending steady a model? The rubber12 paper's eq. 17 claim, measured.

    .venv/bin/python bench/kfold_variance.py [--seeds 5] [--folds 5] [overrides ...]

Trains the residual MLP once per seed as a single model and as a K-fold blend on the same
data (the default rubber12 scene) and compares the spread of their test predictions across
seeds: variance reduction = 1 - var_blend / var_single, averaged over test rows, per target.
The rubber12 paper reports 8.3 % for its ResNN. Extra arguments are Hydra overrides.
Appended to results/kfold_variance.jsonl (`variance_k<K>`; a run with overrides only prints).
"""
import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from runs.fidelity.kfold_variance import measure  # noqa: E402

# What the spread measures: the study itself, the blending, the net and its config, and the
# default scene, features and split it is trained on.
MEASURED_CODE = ["runs/fidelity/kfold_variance.py", "models/kfold_blend.py", "models/resmlp_regressor.py",
                 "models/nets/resmlp.py", "configs/model/resmlp.yaml", "configs/trainer/", "configs/scene/", "data/"]


def print_table(args, result):
    r2, spread = result["r2"], result["variance"]
    print(f"\n{args.seeds} seeds, K = {args.folds}, {result['n_train']} training rows, {result['n_test']} test rows\n")
    print("| target | test R² single (mean ± sd) | test R² K-fold blend | prediction variance across seeds, single | blend | variance reduction |")
    print("|---|---|---|---|---|---|")
    for k, t in enumerate(result["targets"]):
        single, blend = r2["single"][:, k], r2["blend"][:, k]
        print(f"| {t} | {single.mean():.4f} ± {single.std(ddof=1):.4f} | {blend.mean():.4f} ± {blend.std(ddof=1):.4f} "
              f"| {spread['single'][k]:.4g} | {spread['blend'][k]:.4g} | {100 * result['reduction'][k]:.1f} % |")
    seconds = result["seconds_per_seed"]
    print(f"\nfit time: single {seconds['single']:.1f} s, blend {seconds['blend']:.1f} s per seed")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--folds", type=int, default=5)
    parser.add_argument("overrides", nargs="*")
    args = parser.parse_args(argv)
    with recording("kfold_variance", MEASURED_CODE) as record:
        result = measure(args.seeds, args.folds, args.overrides)
        print_table(args, result)
        # docs/pipeline.md and fidelity row 13 measure the default scene (K is in the name): overrides only print.
        # Values: test R² per seed (seeds x targets), the variances across seeds and the reduction per target.
        if not args.overrides:
            record.add(f"variance_k{args.folds}", {"folds": args.folds, **result}, seeds=list(range(args.seeds)))


if __name__ == "__main__":
    main()
