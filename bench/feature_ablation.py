"""Feature-group ablation over several seeds: the change in test R^2 when one group is removed.

    .venv/bin/python bench/feature_ablation.py [--seeds 0 1 2] [overrides ...]
    (default: model=random_forest on the default scene and split)

Each seed draws its own scene, split and model seed; the table shows mean ± sd over seeds, so a
change smaller than its spread reads as "no difference within noise". Appended to
results/feature_ablation.jsonl (default overrides only: a run with others only prints).
"""
import argparse
import sys
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from runs.report.analysis import feature_ablation  # noqa: E402
from runs.run import seed_everything  # noqa: E402

# What the ablation measures: the refits per group, the forest and its config, and the default
# scene, its features (data/preprocessing/features.py) and split.
MEASURED_CODE = ["runs/report/analysis.py", "models/trees.py", "configs/model/random_forest.yaml",
                 "configs/model/base/", "configs/scene/", "data/"]


def one_seed(seed: int, overrides: list[str]) -> tuple[dict, str]:
    """The ablation of one seed's scene, split and model, and the split's kind."""
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=["scene.progress=false", "trainer.progress=false", f"seed={seed}",
                                            *overrides])
    seed_everything(seed)
    datamodule = instantiate(cfg.data).setup()
    ablation = feature_ablation(instantiate(cfg.model), datamodule, progress=False)
    print(f"seed {seed} done", file=sys.stderr)
    return ablation, cfg.data.split


def print_table(overrides, split, seeds, runs):
    targets = list(runs[0]["all_groups_r2"])
    print(f"\n{' '.join(overrides)}; split {split}; seeds {seeds}; test R² mean ± sd over seeds\n")
    print("| without | " + " | ".join(targets) + " |\n|---|" + "---|" * len(targets))
    full = np.array([[r["all_groups_r2"][t] for t in targets] for r in runs])
    print("| (all groups: R²) | " + " | ".join(f"{m:.4f} ± {s:.4f}" for m, s in zip(full.mean(0), full.std(0, ddof=1))) + " |")
    for group in runs[0]["delta_r2_without"]:
        delta = np.array([[r["delta_r2_without"][group][t] for t in targets] for r in runs])
        print(f"| {group} | " + " | ".join(f"{m:+.4f} ± {s:.4f}" for m, s in zip(delta.mean(0), delta.std(0, ddof=1))) + " |")


def record_runs(record, overrides, split, seeds, runs):
    """Test R² with all groups and its change without each group, seeds x targets, groups as printed."""
    targets = list(runs[0]["all_groups_r2"])

    def per_seed(pick):
        return [[pick(r)[t] for t in targets] for r in runs]

    record.add("ablation", {"overrides": overrides, "split": split, "targets": targets,
                            "all_groups_r2": per_seed(lambda r: r["all_groups_r2"]),
                            "without": [{"group": group, "delta_r2": per_seed(lambda r: r["delta_r2_without"][group])}
                                        for group in runs[0]["delta_r2_without"]]}, seeds=seeds)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, nargs="*", default=[0, 1, 2])
    parser.add_argument("overrides", nargs="*")
    args = parser.parse_args(argv)
    overrides = args.overrides or ["model=random_forest"]
    with recording("feature_ablation", MEASURED_CODE) as record:
        runs = []
        for seed in args.seeds:
            ablation, split = one_seed(seed, overrides)
            runs.append(ablation)
        print_table(overrides, split, args.seeds, runs)
        # docs/pipeline.md's table is the default's (model=random_forest): other overrides only print.
        if not args.overrides:
            record_runs(record, overrides, split, args.seeds, runs)


if __name__ == "__main__":
    main()
