"""Scene benchmark: samples/s with a scene's full and minimal effect lists, what each effect
adds, and whether cost grows linearly with the sample count.

    .venv/bin/python bench/scenes.py            # all scenes, 4000 samples
    .venv/bin/python bench/scenes.py --n 2000 --scenes rubber12_lab

Marginal cost: effects are added one at a time, in the full list's order, on top of the
minimal list; each row is the time that effect added per 1000 samples.

Every figure is a mean +- sd over --repeats runs, run k at scene seed k (each seed draws its own
presses, specimen and noise), timed by the process's CPU time: the scenes run on one thread, so
on an idle machine it equals the wall time, and on a shared one it does not count the time other
processes held the core. The 1-minute load average is printed beside each scene.
Appends three records per scene (each seed's CPU seconds per sample) to results/scenes.jsonl.
"""
import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate
from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402

# full scene -> (minimal scene, the key that sets its size, samples per unit of that key).
# A rubber12 sample is one press; a fingertip sample is one recording (one pass, two channels
# of ~2,100 steps), and its size key counts passes per force level over 18 boards x 6 levels;
# a capacitive6x6 characterisation repetition is 4 cells x 10 force levels.
SCENES = {"rubber12_lab": ("rubber12_minimal", "n_samples", 1),
          "fingertip": ("fingertip_minimal", "passes_per_level", 18 * 6),
          "taxels": ("taxels_minimal", "n_samples", 1),
          "capacitive6x6": ("capacitive6x6_minimal", "n_repetitions", 40),
          "ert_boundary": ("ert_minimal", "n_samples", 1),
          "ert_internal": ("ert_minimal", "n_samples", 1)}
# What a scene's generation runs: the scenes and their effects, the physics they solve, the
# containers they fill, and the scene configs (the effect lists and their settings).
MEASURED_CODE = ["data/scenes/", "data/physics/", "data/sensor_table.py", "data/recording_set.py", "configs/scene/"]


def load(name: str, n_samples: int, effects=None):
    """The scene config `name` as Hydra composes it (variants inherit their base through
    `defaults:`), sized to about `n_samples` samples."""
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        composed = compose("config", overrides=[f"scene={name}", "seed=0"])
    cfg = OmegaConf.create(OmegaConf.to_container(composed.scene, resolve=True))
    size_key, per_unit = next((key, unit) for full, (minimal, key, unit) in SCENES.items() if name in (full, minimal))
    cfg[size_key] = max(1, n_samples // per_unit)
    if "progress" in cfg:
        cfg.progress = False
    if effects is not None:
        cfg.effects = effects
    return cfg


def n_generated(result) -> int:
    """Samples in what a scene generated: rows of a table, or recordings of a set."""
    return len(result.frame) if hasattr(result, "frame") else len(result)


def seconds(cfg, repeats: int) -> np.ndarray:
    """CPU seconds per generated sample, one run per scene seed 0 .. repeats - 1."""
    per_sample = []
    for seed in range(repeats):
        scene = instantiate(cfg, seed=seed)
        start = time.process_time()
        count = n_generated(scene.generate())
        per_sample.append((time.process_time() - start) / count)
    return np.array(per_sample)


def effect_lists(full: str, n: int, repeats: int) -> dict:
    """Samples/s with the full and with the minimal effect list."""
    full_cfg, minimal_cfg = load(full, n), load(SCENES[full][0], n)
    seconds(load(full, 10), 1)  # warm-up: solver factorisations are cached per process
    t_full, t_min = seconds(full_cfg, repeats), seconds(minimal_cfg, repeats)
    print(f"\n## {full} (~{n} samples; seeds 0-{repeats - 1}, mean ± sd; "
          f"load average {os.getloadavg()[0]:.1f})\n")
    print("| effect list | effects | samples/s |\n|---|---|---|")
    print(f"| full | {', '.join(full_cfg.effects)} | {format_mean_sd(1 / t_full, ',.0f')} |")
    print(f"| minimal | {', '.join(minimal_cfg.effects) or 'none'} | {format_mean_sd(1 / t_min, ',.0f')} |")
    return {"full_effects": list(full_cfg.effects), "minimal_effects": list(minimal_cfg.effects),
            "full_s_per_sample": t_full, "minimal_s_per_sample": t_min}


def effect_costs(full: str, n: int, repeats: int) -> dict:
    """Seconds per sample of the minimal list and of each list with one more effect, in order.
    Paired by seed: an effect's cost is the difference of two runs drawing the same presses."""
    print("\n| effect added (in order) | ms per 1000 samples |\n|---|---|")
    listed = OmegaConf.to_container(load(full, n).effects)
    base = {k: v for k, v in listed.items() if k in load(SCENES[full][0], n).effects}
    previous = seconds(load(full, n, base), repeats)
    print(f"| (minimal: {', '.join(base) or 'none'}) | {format_mean_sd(1e6 * previous, ',.2f')} |")
    costs = {"minimal": list(base), "minimal_s_per_sample": previous, "added": []}
    current = dict(base)
    for name, params in listed.items():
        if name in base:
            continue
        current[name] = params
        now = seconds(load(full, n, current), repeats)
        print(f"| + {name} | {format_mean_sd(1e6 * (now - previous), ',.2f')} |")
        costs["added"].append({"effect": name, "s_per_sample": now})
        previous = now
    return costs


def sizes(full: str, n: int, repeats: int) -> dict:
    """Samples/s at half, the same and twice the size: does cost grow linearly with the count?"""
    print("\n| samples | seconds | samples/s |\n|---|---|---|")
    rows = []
    for size in (n // 2, n, 2 * n):
        cfg = load(full, size)
        per_sample = seconds(cfg, repeats)
        count = n_generated(instantiate(cfg).generate())
        print(f"| {count} | {format_mean_sd(count * per_sample, ',.3f')} | {format_mean_sd(1 / per_sample, ',.0f')} |")
        rows.append({"samples": count, "s_per_sample": per_sample})
    return {"sizes": rows}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, default=4000, help="samples per timing (fingertip: recordings, ~n/4)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scenes", nargs="*", default=[s for s in SCENES if (ROOT / f"configs/scene/{s}.yaml").exists()])
    args = parser.parse_args(argv)
    with recording("scenes", MEASURED_CODE) as record:
        for full in args.scenes:
            n = args.n if SCENES[full][2] == 1 else args.n // 4  # fingertip: a recording costs ~4 presses
            settings = {"scene": full, "minimal_scene": SCENES[full][0], "requested_samples": n, "clock": "cpu"}
            # --n is in the name: a quick run at another size does not stand in for the default's.
            for table in (effect_lists, effect_costs, sizes):
                record.add(f"{full}/n{args.n}/{table.__name__}", {**settings, **table(full, n, args.repeats)},
                           seeds=list(range(args.repeats)))


if __name__ == "__main__":
    main()
