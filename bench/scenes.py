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

from hydra.utils import instantiate
from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# (full scene, minimal scene): the minimal list is the least that still responds to a touch.
SCENES = {"rubber12_lab": "rubber12_minimal", "fingertip": "fingertip_minimal"}


def load(name: str, n_samples: int, effects=None):
    cfg = OmegaConf.load(ROOT / "configs" / "scene" / f"{name}.yaml")
    cfg.seed = 0
    cfg.progress = False
    cfg.n_samples = n_samples
    if effects is not None:
        cfg.effects = effects
    return cfg


def seconds(cfg, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        scene = instantiate(cfg)
        start = time.perf_counter()
        scene.generate()
        best = min(best, time.perf_counter() - start)
    return best


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, default=4000, help="samples per timing")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scenes", nargs="*", default=[s for s in SCENES if (ROOT / f"configs/scene/{s}.yaml").exists()])
    args = parser.parse_args(argv)

    for full in args.scenes:
        minimal = SCENES[full]
        full_cfg = load(full, args.n)
        minimal_cfg = load(minimal, args.n)
        seconds(load(full, 10), 1)  # warm-up: solver factorisations are cached per process
        t_full, t_min = seconds(full_cfg, args.repeats), seconds(minimal_cfg, args.repeats)
        print(f"\n## {full} ({args.n} samples, best of {args.repeats})\n")
        print("| effect list | effects | samples/s |\n|---|---|---|")
        print(f"| full | {', '.join(full_cfg.effects)} | {args.n / t_full:,.0f} |")
        print(f"| minimal | {', '.join(minimal_cfg.effects) or 'none'} | {args.n / t_min:,.0f} |")

        print("\n| effect added (in order) | ms per 1000 samples |\n|---|---|")
        listed = OmegaConf.to_container(full_cfg.effects)
        base = {k: v for k, v in listed.items() if k in minimal_cfg.effects}
        previous = seconds(load(full, args.n, base), args.repeats)
        print(f"| (minimal: {', '.join(base) or 'none'}) | {1e6 * previous / args.n:.2f} |")
        current = dict(base)
        for name, params in listed.items():
            if name in base:
                continue
            current[name] = params
            now = seconds(load(full, args.n, current), args.repeats)
            print(f"| + {name} | {1e6 * (now - previous) / args.n:+.2f} |")
            previous = now

        print("\n| samples | seconds | samples/s |\n|---|---|---|")
        for n in (args.n // 2, args.n, 2 * args.n):
            t = seconds(load(full, n), args.repeats)
            print(f"| {n} | {t:.3f} | {n / t:,.0f} |")


if __name__ == "__main__":
    main()
