"""Which variation between repeated presses would make rubber12's Table II row (fidelity row 11) hold?

The paper's extra trees reach x 0.947, y 0.976, z 0.852, P 0.867 on a random 15 % hold-out of
~450 lab presses, so every test press has repeats of its position-depth pair in training: what
keeps depth and pressure from being near perfect is how repeats differ. This measures row 11
(runs/fidelity/rubber12.py, the same function) on the default scene with one trial variation added
at a time, over seeds 0-2, and the largest repeat CV over the lab table's 90 position-depth pairs
(the paper bounds it by 2.3 %). The trial effects are candidates, not physics of the scene: they
are registered only while this script runs, and their sizes are the knobs being measured, not
sourced values (docs/fidelity.md, row 11's reason).

    .venv/bin/python bench/rubber12_repeat_variation.py            # every candidate, ~2 min
    .venv/bin/python bench/rubber12_repeat_variation.py --only gain_0.2 none

The lab protocol presses the ten depths of one point in a row (one indentation cycle), so press k
of the lab table belongs to cycle k // 10 and repeat k // 90; the trial effects use that order and
therefore apply to the lab table only. Appends one record per trial (R² and repeat CV per seed)
to results/rubber12_repeat_variation.jsonl.
"""
import argparse
import contextlib
import copy
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import data.scenes.rubber12_effects as effects  # noqa: E402
from common.result_records import recording  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402
from runs.fidelity.observations import SEEDS, scene_params  # noqa: E402
from runs.fidelity.rubber12 import PAPER_TABLE_II, SceneProbe, extra_trees_r2  # noqa: E402

DEPTHS, POINTS = 10, 9            # the lab table's order: cycle = 10 consecutive presses, repeat = 90
TOLERANCE = 0.1                   # row 11 holds at a seed when all four R² are within this of the paper's
# What row 11 measures: its function, the scene (effects, solver, configs), the features, and the
# trial effects, which live in this file.
MEASURED_CODE = ["runs/fidelity/rubber12.py", "data/scenes/", "data/physics/", "data/preprocessing/features.py",
                 "configs/scene/", "bench/rubber12_repeat_variation.py"]


def _per_cycle(n, rng, sd, every=DEPTHS):
    """One N(0, sd) draw per block of `every` consecutive presses."""
    block = np.arange(n) // every
    return sd * rng.standard_normal(block.max() + 1)[block]


def film_gain(state, rng, sd=0.0):
    """The film's response amplitude changes from one indentation cycle to the next."""
    scale = 1.0 + _per_cycle(len(state["x_mm"]), rng, sd)
    state["film_stretch"] = state["film_stretch"] * scale[:, None]
    state["film_area_strain"] = state["film_area_strain"] * scale[:, None]


def first_cycle(state, rng, extra=0.0):
    """Mullins-like: the first (virgin) cycle at each point responds (1 + extra) times the later ones."""
    scale = np.where(np.arange(len(state["x_mm"])) // (DEPTHS * POINTS) == 0, 1.0 + extra, 1.0)
    state["film_stretch"] = state["film_stretch"] * scale[:, None]
    state["film_area_strain"] = state["film_area_strain"] * scale[:, None]


def cnc_zero(state, rng, sd_mm=0.0):
    """The CNC's zero differs per cycle: the true indentation is the nominal depth + an offset."""
    depth = state.get("indentation_mm", state["depth_mm"])
    state["indentation_mm"] = np.maximum(depth + _per_cycle(len(depth), rng, sd_mm), 0.0)


def gel_stiffness(state, rng, sd=0.0):
    """The gel's stiffness (so the load cell's force) changes per cycle; the film does not see it."""
    scale = 1.0 + _per_cycle(len(state["x_mm"]), rng, sd)
    state["force_n"] = state["force_n"] * scale
    state["pressure_pa"] = state["pressure_pa"] * scale


def temperature_per_cycle(state, rng, coefficient_per_c=0.004, ambient_c=25.0, spread_c=1.0, reference_c=25.0,
                          correlation_s=0.0, hold_s=5.0, recovery_s=60.0):
    """temperature_drift with a temperature that drifts in time: constant over a cycle
    (correlation_s 0), or an Ornstein-Uhlenbeck drift (sd spread/2, clipped to the band) sampled at
    the lab's schedule (a 5 s hold per depth, 1 min recovery per cycle)."""
    n = state["resistance_ohm"].shape[0]
    if correlation_s <= 0:
        temperature = ambient_c + rng.uniform(-spread_c, spread_c, n // DEPTHS + 1)[np.arange(n) // DEPTHS]
    else:
        index = np.arange(n)
        time_s = index // DEPTHS * (DEPTHS * hold_s + recovery_s) + (index % DEPTHS + 1) * hold_s
        drift = np.empty(n)
        drift[0] = rng.normal(0.0, spread_c / 2)
        for k in range(1, n):
            keep = np.exp(-(time_s[k] - time_s[k - 1]) / correlation_s)
            drift[k] = keep * drift[k - 1] + np.sqrt(1 - keep**2) * spread_c / 2 * rng.standard_normal()
        temperature = ambient_c + np.clip(drift, -spread_c, spread_c)
    state["resistance_ohm"] = state["resistance_ohm"] * (1.0 + coefficient_per_c * (temperature - reference_c))[:, None]


TRIALS = {   # name -> (effects to add or override, the trial effect placed before this listed effect)
    "none": {},
    "adc_noise_x10": {"adc": {"noise_lsb": 10.0}},
    "no_temperature": {"temperature_drift": None},
    "temperature_pm3C": {"temperature_drift": {"spread_c": 3.0}},
    "temperature_pm5C": {"temperature_drift": {"spread_c": 5.0}},
    "temperature_per_cycle": {"temperature_drift": None, "temperature_per_cycle": {}},
    "temperature_drift_600s": {"temperature_drift": None, "temperature_per_cycle": {"correlation_s": 600.0}},
    "cnc_zero_0.1mm": {"cnc_zero": {"sd_mm": 0.1}},
    "cnc_zero_0.2mm": {"cnc_zero": {"sd_mm": 0.2}},
    "gel_stiffness_0.2": {"gel_stiffness": {"sd": 0.2}},
    "gain_0.1": {"film_gain": {"sd": 0.1}},
    "gain_0.2": {"film_gain": {"sd": 0.2}},
    "gain_0.3": {"film_gain": {"sd": 0.3}},
    "first_cycle_x1.3": {"first_cycle": {"extra": 0.3}},
    "first_cycle_x1.6": {"first_cycle": {"extra": 0.6}},
    "first_cycle_x2": {"first_cycle": {"extra": 1.0}},
}
PLACE = {"cnc_zero": "contact", "gel_stiffness": "percolation", "film_gain": "percolation",
         "first_cycle": "percolation", "temperature_per_cycle": "adc"}
TRIAL_EFFECTS = {"cnc_zero": cnc_zero, "gel_stiffness": gel_stiffness, "film_gain": film_gain,
                 "first_cycle": first_cycle, "temperature_per_cycle": temperature_per_cycle}
FIELD = {"cnc_zero", "gel_stiffness", "film_gain", "first_cycle"}


@contextlib.contextmanager
def trial_effects():
    """The trial effects in the scene's registries, at their place in the chain, while inside."""
    saved = dict(effects.EFFECTS), dict(effects.FIELD_EFFECTS), dict(effects.READING_EFFECTS)
    chain = {}
    for name, fn in saved[0].items():
        chain.update({trial: TRIAL_EFFECTS[trial] for trial, before in PLACE.items() if before == name})
        chain[name] = fn
    try:
        effects.EFFECTS.clear()
        effects.EFFECTS.update(chain)
        effects.FIELD_EFFECTS.update({k: v for k, v in TRIAL_EFFECTS.items() if k in FIELD})
        effects.READING_EFFECTS.update({k: v for k, v in TRIAL_EFFECTS.items() if k not in FIELD})
        yield
    finally:
        for registry, old in zip((effects.EFFECTS, effects.FIELD_EFFECTS, effects.READING_EFFECTS), saved):
            registry.clear()
            registry.update(old)


def lab_repeat_cv(probe: SceneProbe) -> np.ndarray:
    """Largest CV over the 5 repeats of each of the lab table's 90 position-depth pairs and its
    12 channels, at each seed (every listed effect but normalisation)."""
    worst = []
    for one in probe.seeded:
        listed = {k: v for k, v in one.params["effects"].items() if k != "minmax_normalize"}
        ohm = one.scene(listed, n_samples=5 * POINTS * DEPTHS, protocol="lab").generate().channels
        ohm = ohm.reshape(5, POINTS * DEPTHS, -1)
        worst.append((ohm.std(axis=0, ddof=1) / ohm.mean(axis=0)).max())
    return np.array(worst)


def measure(name: str) -> dict:
    """Row 11's R² per seed (x, y, z, P) and the lab table's largest repeat CV per seed, with one trial."""
    params = copy.deepcopy(scene_params("rubber12"))
    for effect, values in TRIALS[name].items():
        if values is None:
            params["effects"].pop(effect)
        else:
            params["effects"][effect] = {**params["effects"].get(effect, {}), **values}
    probe = SceneProbe(params, repeats=20)
    scores = np.array(extra_trees_r2(probe).numbers["by_seed"])            # (seeds, x y z P)
    return {"trial": name, "effect_changes": TRIALS[name],     # an effect set to None is removed
            "repeats": probe.repeats, "targets": ["x", "y", "z", "P"], "paper": PAPER_TABLE_II, "tolerance": TOLERANCE,
            "r2_by_seed": scores, "held_by_seed": (np.abs(scores - PAPER_TABLE_II) <= TOLERANCE).all(axis=1),
            "lab_repeat_cv_by_seed": lab_repeat_cv(probe)}


def table_row(measured: dict) -> str:
    held, cv = measured["held_by_seed"], measured["lab_repeat_cv_by_seed"]
    return (f"| {measured['trial']} | " + " | ".join(format_mean_sd(column, ".3f") for column in measured["r2_by_seed"].T) +
            f" | {held.sum()} of {len(held)} | {format_mean_sd(100 * cv, '.2f')} % |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=list(TRIALS), help="measure these trials only")
    args = parser.parse_args(argv)
    print(f"| trial (seeds {', '.join(map(str, SEEDS))}, mean ± sd) | R² x | R² y | R² z | R² P | "
          "seeds within ±0.10 on all four | largest repeat CV, lab table |")
    print("|---|---|---|---|---|---|---|")
    with trial_effects(), recording("rubber12_repeat_variation", MEASURED_CODE) as record:
        for name in args.only or TRIALS:
            measured = measure(name)
            print(table_row(measured), flush=True)
            record.add(name, measured, seeds=SEEDS)


if __name__ == "__main__":
    main()
