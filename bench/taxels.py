"""Taxel benchmarks: strain evaluations (load-taxel pairs per second) and scene samples per second.

    OMP_NUM_THREADS=1 .venv/bin/python bench/taxels.py                 # both, default sizes
    .venv/bin/python bench/taxels.py --pairs 2000000 --samples 4000
    .venv/bin/python bench/taxels.py --summarise multirun/taxel_inverse/<sweep>   # per-target table
    .venv/bin/python bench/taxels.py --covers        # what bumps, ridges and hairs do (Fig. 6, 9, 10)

Pairs: many loads (random positions, normal and shear forces) against the 2 x 2 array's taxels,
through the half-space strain (data/physics/elastic_half_space.py, Boussinesq + Cerruti, full
tensor) and the bonded-layer base traction (data/physics/bonded_layer.py, kernels cached). Scene:
`generate()` of each taxels variant on random loads, after one warm-up call (the bonded-layer
kernels are built once per process, ~1 s). Both print mean ± sd over --repeats timings of process
CPU time (one thread: OMP_NUM_THREADS=1), which a shared machine's load inflates less than wall time. --summarise reads a taxel_inverse
sweep's job folders and prints mean ± sd over seeds of each target's validation and test R^2 and
test RMSE by cover and thickness (the best per target chosen on validation). Every mode appends
its raw numbers (per repeat, per job) to results/taxels.jsonl (common/result_records.py).
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from common.spread import mean_and_sd  # noqa: E402
from data.physics.bonded_layer import base_traction_pa, layer_kernels  # noqa: E402
from data.physics.elastic_half_space import point_load_strain  # noqa: E402
from common.run_status import run_status  # noqa: E402

VARIANTS = ("taxels_minimal", "taxels_flat", "taxels", "taxels_bump", "taxels_ridge", "taxels_hair")
SEED = 0   # the loads' generator and the scenes' seed
# What the timings and cover signatures measure: the strain physics, the taxel scene and its
# variants' configs, and the fidelity probe --covers reads them through.
MEASURED_CODE = ["data/physics/", "data/scenes/taxels.py", "data/scenes/taxels_effects.py",
                 "runs/fidelity/taxels.py", *(f"configs/scene/{variant}.yaml" for variant in VARIANTS)]
# What --summarise reads: a taxel_inverse sweep's runs, i.e. the whole training pipeline. Its
# record's code hashes are this checkout's: summarise a sweep run on the current code.
SWEEP_CODE = ["train.py", "data/", "models/", "runs/", "configs/"]


def pairs_per_second(n_pairs: int, repeats: int) -> dict:
    """Load-taxel pairs per CPU second of each strain path, one rate per repeat."""
    rng = np.random.default_rng(SEED)
    n_loads = n_pairs // 4
    taxels = np.array([[-0.75, -0.75], [0.75, -0.75], [-0.75, 0.75], [0.75, 0.75]]) * 1e-3
    loads = rng.uniform(-1.5e-3, 1.5e-3, (n_loads, 1, 2))
    force = rng.uniform(0.001, 0.01, (n_loads, 1))
    shear = rng.uniform(-0.003, 0.003, (2, n_loads, 1))
    dx, dy = taxels[None, :, 0] - loads[..., 0], taxels[None, :, 1] - loads[..., 1]
    layer_kernels(0.5)
    out = {}
    for name, fn in (("half_space_strain", lambda: point_load_strain(dx, dy, 580e-6, force, shear[0], shear[1], 2.4e6, 0.5)),
                     ("bonded_layer_traction", lambda: base_traction_pa(dx, dy, 580e-6, force, shear[0], shear[1], 0.5))):
        out[name] = [n_loads * 4 / _timed(fn) for _ in range(repeats)]
    return out


def _timed(fn) -> float:
    start = time.process_time()
    fn()
    return time.process_time() - start


def scene_samples_per_second(n_samples: int, repeats: int, variants) -> dict:
    """Scene samples per CPU second of each variant's generate(), one rate per repeat."""
    from hydra import compose, initialize_config_dir
    from hydra.utils import instantiate
    out = {}
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        for variant in variants:
            cfg = compose("config", overrides=[f"scene={variant}", f"seed={SEED}", f"scene.n_samples={n_samples}",
                                               "scene.protocol=random_loads"])
            instantiate(cfg.scene).generate()  # warm-up: kernels, imports
            out[variant] = [n_samples / _timed(lambda: instantiate(cfg.scene).generate()) for _ in range(repeats)]
    return out


def sweep_rows(sweep_dir: Path) -> list[dict]:
    """One row per finished job and target: its cover, thickness, seed and scores."""
    import yaml
    rows = []
    for job in sorted(p for p in sweep_dir.iterdir() if p.is_dir() and run_status(p).state == "finished"):
        overrides = dict(o.split("=", 1) for o in yaml.safe_load((job / ".hydra" / "overrides.yaml").read_text()))
        metrics = json.loads((job / "metrics.json").read_text())
        for target, row in metrics["test"].items():
            if target != "average":
                thickness_um = float(overrides.get("scene.cover_thickness_um", "nan"))
                rows.append({"cover": overrides.get("scene", "taxels"), "thickness_um": thickness_um,
                             "seed": overrides.get("seed"), "target": target, "val_r2": metrics["val"][target]["r2"],
                             "r2": row["r2"], "rmse": row["rmse"]})
    return rows


def summarise(rows: list[dict]) -> str:
    """Markdown table: per target, cover and thickness, validation and test R^2 and test RMSE,
    mean ± sd over seeds; the best configuration per target is chosen on VALIDATION R^2."""
    import pandas as pd
    frame = pd.DataFrame(rows)
    grouped = frame.groupby(["target", "cover", "thickness_um"]).agg(
        val_mean=("val_r2", "mean"), val_sd=("val_r2", "std"), r2_mean=("r2", "mean"), r2_sd=("r2", "std"),
        rmse_mean=("rmse", "mean"), rmse_sd=("rmse", "std"), seeds=("seed", "count")).reset_index()
    lines = ["| target | cover | thickness (um) | val R² (mean ± sd) | test R² (mean ± sd) | test RMSE (mean ± sd) | seeds |",
             "|---|---|---|---|---|---|---|"]
    for r in grouped.itertuples():
        lines.append(f"| {r.target} | {r.cover} | {r.thickness_um:.0f} | {r.val_mean:.3f} ± {r.val_sd:.3f} | "
                     f"{r.r2_mean:.3f} ± {r.r2_sd:.3f} | {r.rmse_mean:.4g} ± {r.rmse_sd:.2g} | {r.seeds} |")
    best = grouped.loc[grouped.groupby("target").val_mean.idxmax()]
    lines.append("")
    lines.append("Chosen on validation R² per target (test R² beside it): " + "; ".join(
        f"{r.target}: {r.cover} at {r.thickness_um:.0f} um (val {r.val_mean:.3f}, test {r.r2_mean:.3f} ± {r.r2_sd:.3f})"
        for r in best.itertuples()))
    return "\n".join(lines)


def cover_effects() -> dict:
    """The surface structures' signatures, measured by the fidelity rows on the variants
    taxels_bump, taxels_ridge, taxels_hair (runs/fidelity/taxels.py): Fig. 9, bumps vs flat under
    a 3 mm probe; Fig. 10c-d, the ridge's direction selectivity; Fig. 6, the hair's shear ratio."""
    from runs.fidelity import taxels as rows
    from runs.fidelity.observations import scene_params
    probe = rows.TaxelsProbe(scene_params("taxels"), repeats=3)
    bump, ridge = rows.bump_raises_lateral_sensitivity(probe), rows.ridge_direction_selective(probe)
    return {"fig9_bump": {"value": bump.value, "holds": bump.holds, **bump.numbers},
            "fig10_ridge": {"value": ridge.value, "holds": ridge.holds, **ridge.numbers},
            "fig6_hair_shear_ratio": rows.hair_shear_ratio(probe)}


def covers_text(covers: dict) -> str:
    hair = covers["fig6_hair_shear_ratio"]
    return "\n".join([
        f"  Fig. 9  {covers['fig9_bump']['value']}",
        f"  Fig. 10 {covers['fig10_ridge']['value']}",
        f"  Fig. 6  peak |gamma_x| / peak |eps_z| of a moving load: hair {hair['hair']:.2f}, flat {hair['flat']:.2f}"])


def print_rates(rates: dict, unit: str) -> None:
    for name, values in rates.items():
        rate, sd = mean_and_sd(values)
        print(f"  {name:24s} {rate:14,.0f} ± {sd:,.0f} {unit}")


def speed(args, record) -> None:
    """Both timings, printed as mean ± sd and recorded per repeat."""
    print(f"strain evaluation, {args.pairs:,} load-taxel pairs, process CPU time, mean ± sd of {args.repeats}:")
    pairs = pairs_per_second(args.pairs, args.repeats)
    print_rates(pairs, "pairs/s")
    record.add("strain_pairs", {"pairs": args.pairs, "repeats": args.repeats, "clock": "process CPU time",
                                "pairs_per_s": pairs}, seeds=[SEED])
    print(f"scene generate(), random_loads, {args.samples:,} samples, process CPU time, mean ± sd of {args.repeats}:")
    samples = scene_samples_per_second(args.samples, args.repeats, args.variants)
    print_rates(samples, "samples/s")
    record.add("scene_samples", {"samples": args.samples, "repeats": args.repeats, "protocol": "random_loads",
                                 "clock": "process CPU time", "samples_per_s": samples}, seeds=[SEED])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pairs", type=int, default=1_000_000, help="load-taxel pairs per strain timing")
    parser.add_argument("--samples", type=int, default=4000, help="scene samples per timing")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--variants", nargs="*", default=list(VARIANTS))
    parser.add_argument("--summarise", type=Path, default=None, help="a taxel_inverse sweep folder")
    parser.add_argument("--covers", action="store_true", help="print the surface structures' signatures")
    args = parser.parse_args(argv)
    if args.covers:
        with recording("taxels", MEASURED_CODE) as record:
            covers = cover_effects()
            print(covers_text(covers))
            record.add("covers", covers, seeds=[0, 1, 2])   # the bump's three sets of probe positions
        return
    if args.summarise is not None:
        with recording("taxels", SWEEP_CODE) as record:
            rows = sweep_rows(args.summarise)
            print(summarise(rows))
            record.add("inverse_sweep", {"sweep": str(args.summarise), "rows": rows},
                       seeds=sorted({int(row["seed"]) for row in rows if row["seed"] is not None}))
        return
    with recording("taxels", MEASURED_CODE) as record:
        speed(args, record)


if __name__ == "__main__":
    main()
