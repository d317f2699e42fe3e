"""Scene benchmark: samples/s with a scene's full and minimal effect lists, what each effect
adds, and whether cost grows linearly with the sample count.

    .venv/bin/python bench/scenes.py            # all scenes, 4000 samples
    .venv/bin/python bench/scenes.py --n 2000 --scenes rubber12_lab

Marginal cost: effects are added one at a time, in the full list's order, on top of the
minimal list; each row is the time that effect added per 1000 samples. Best of --repeats runs.
"""
import argparse
import sys
import time
from pathlib import Path

from hydra import compose, initialize_config_dir
from hydra.utils import instantiate
from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

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


def seconds(cfg, repeats: int) -> float:
    """Best wall time per generated sample over `repeats` runs."""
    best = float("inf")
    for _ in range(repeats):
        scene = instantiate(cfg)
        start = time.perf_counter()
        count = n_generated(scene.generate())
        best = min(best, (time.perf_counter() - start) / count)
    return best


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, default=4000, help="samples per timing (fingertip: recordings, ~n/4)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scenes", nargs="*", default=[s for s in SCENES if (ROOT / f"configs/scene/{s}.yaml").exists()])
    args = parser.parse_args(argv)

    for full in args.scenes:
        minimal, _, per_unit = SCENES[full]
        n = args.n if per_unit == 1 else args.n // 4  # fingertip: a recording costs ~4 presses
        full_cfg, minimal_cfg = load(full, n), load(minimal, n)
        seconds(load(full, 10), 1)  # warm-up: solver factorisations are cached per process
        t_full, t_min = seconds(full_cfg, args.repeats), seconds(minimal_cfg, args.repeats)
        print(f"\n## {full} (~{n} samples, best of {args.repeats})\n")
        print("| effect list | effects | samples/s |\n|---|---|---|")
        print(f"| full | {', '.join(full_cfg.effects)} | {1 / t_full:,.0f} |")
        print(f"| minimal | {', '.join(minimal_cfg.effects) or 'none'} | {1 / t_min:,.0f} |")

        print("\n| effect added (in order) | ms per 1000 samples |\n|---|---|")
        listed = OmegaConf.to_container(full_cfg.effects)
        base = {k: v for k, v in listed.items() if k in minimal_cfg.effects}
        previous = seconds(load(full, n, base), args.repeats)
        print(f"| (minimal: {', '.join(base) or 'none'}) | {1e6 * previous:.2f} |")
        current = dict(base)
        for name, params in listed.items():
            if name in base:
                continue
            current[name] = params
            now = seconds(load(full, n, current), args.repeats)
            print(f"| + {name} | {1e6 * (now - previous):+.2f} |")
            previous = now

        print("\n| samples | seconds | samples/s |\n|---|---|---|")
        for size in (n // 2, n, 2 * n):
            cfg = load(full, size)
            per_sample = seconds(cfg, args.repeats)
            count = n_generated(instantiate(cfg).generate())
            print(f"| {count} | {count * per_sample:.3f} | {1 / per_sample:,.0f} |")


if __name__ == "__main__":
    main()
