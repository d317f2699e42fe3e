"""Study runs for the ERT skin: the three tests of the ERT internal-electrode study (§5), on the
scene in `cfg.scene`.

    python train.py experiment=ert_localisation scene=ert_internal      (and scene=ert_boundary)
    python train.py experiment=ert_force scene=ert_internal
    python train.py experiment=ert_two_point scene=ert_internal

Each seed in `seeds` is one simulated sensor (its specimen variation and electrode errors) with
its own noise: a calibration recording (protocol `calibration`) fits the Tikhonov reconstruction
(models/ert/tikhonov.py, alpha chosen on a validation split of the calibration), and
separate recordings test it; `reconstruction.kind` picks another by its name in
models/ert/registry.py. Results are mean +- sd over presses per seed, then over seeds.

`experiment=ert_localisation` reports the paper's reconstruction (Tikhonov) as its reference row
and, beside it, the best of `compare.kinds` (GREIT and the learned inverses of
models/ert/registry.py) chosen on validation sensors (`compare.validation_seeds`: neither the test
sensors nor any kind's training sensors), each validation sensor calibrated and tested exactly as
a test sensor is; the chosen kind is then run on the test sensors, with its cost (fit time per
sensor, per-frame time at batch 1, the whole comparison's wall time).

Limit of quantification: 10 x the sd of the force estimated on blank frames (nothing pressed;
IUPAC, Currie, Anal. Chem. 40, 1968), divided by the indenter's area for a pressure. The paper's
supplementary procedure is not given.

Two-point test (the paper's supplement is not given, so this is ours): over `n_repeats` noisy
presses of the same two indenters, the reconstructed pressure at the two contact points (their
mean) is compared with the pressure at the mid-point; one-sided paired t-test (H1: the profile
dips between the contacts). The discrimination distance is the smallest distance from which
every larger distance is significant at `significance`.
"""
import logging
import time
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd
from hydra.utils import instantiate
from omegaconf import DictConfig, ListConfig, OmegaConf
from scipy import stats

from common.atomic import atomic_write_text
from common.errors import InputError
from data.scenes.contract import random_generator_for
from models.ert.reconstruction import per_frame_ms
from models.ert.registry import RECONSTRUCTIONS, reconstruction_class
from runs.report.figure_files import write_figures
from runs.report.plots import panel_grid
from runs.report.metrics_file import mean_sd

matplotlib.use("Agg")
import matplotlib.pyplot as plt

log = logging.getLogger(__name__)
PAPER_NAME = "the ERT internal-electrode study"   # our copy has no title, authors or venue
PAPER = {
    "ert_internal": {"localisation_mm": [8.13, 4.32], "force_error_n": [2.00, 1.18], "force_r": 0.983,
                     "loq_kpa": [49.38, 20.25], "two_point_mm": "35 (edge) - 55 (centre)"},
    "ert_boundary": {"localisation_mm": [23.72, 11.54], "force_error_n": [3.34, 1.88], "force_r": 0.929,
                     "loq_kpa": [48.36, 48.75], "two_point_mm": "45 (edge), > 60 elsewhere"},
}


def _plain(node):
    return OmegaConf.to_container(node, resolve=True) if isinstance(node, (DictConfig, ListConfig)) else node


def scene_for(cfg, **overrides):
    """The experiment's scene with some parameters replaced (protocol, seed, sizes)."""
    node = OmegaConf.to_container(cfg.scene, resolve=True)
    node.update({k: _plain(v) for k, v in overrides.items()})
    return instantiate(node)


# the paper's reconstruction: its settings are `reconstruction`'s plain keys, every other kind's
# sit in a block named after it
DEFAULT_KIND = "tikhonov"


def fit_reconstruction(kind: str, cfg, seed: int, X, y, params: dict):
    """The reconstruction registered as `kind` (models/ert/registry.py) for sensor `seed` of the
    scene in `cfg`, its hyper-parameters chosen (and Tikhonov's coefficient field fitted) on the
    validation presses (X, y): a calibration recording, never test presses. Those that train on
    simulated presses (GREIT, the learned inverses) train on other sensors, never `seed`."""
    model = reconstruction_class(kind).for_sensor(scene_for(cfg, seed=seed).geometry(),
                                                  OmegaConf.to_container(cfg.scene, resolve=True), seed, **params)
    seeds = model.training_sensor_seeds()
    if seed in seeds:
        raise InputError(f"{kind}: training_seed {seeds[0]} puts the sensor under test (seed {seed}) "
                         f"among the training sensors; choose another training_seed")
    return model.fit(X, y)


def calibrate(cfg, seed, calibration: dict, reconstruction: dict):
    """(scene, fitted reconstruction) from one calibration recording of sensor `seed`.
    `reconstruction`: `kind` (default tikhonov); its other plain keys are the Tikhonov
    reconstruction's parameters, and a block named after another kind holds that kind's
    (`{kind: greit, greit: {presses_per_sensor: 600}}`), so switching kind on the command line
    leaves the Tikhonov settings where they are."""
    scene = scene_for(cfg, seed=seed, protocol="calibration", **calibration)
    table = scene.generate()
    params = dict(reconstruction)
    kind = params.pop("kind", DEFAULT_KIND)
    blocks = {name: params.pop(name) for name in RECONSTRUCTIONS if name != DEFAULT_KIND and name in params}
    chosen = params if kind == DEFAULT_KIND else dict(blocks.get(kind) or {})
    return scene, fit_reconstruction(kind, cfg, seed, table.channels, table.targets, chosen)


def limit_of_quantification(cfg, seed, model, n_blank: int) -> dict:
    scene = scene_for(cfg, seed=seed, protocol="blank", n_samples=n_blank)
    sd = float(model.predict(scene.generate().channels)[:, 2].std(ddof=1))
    area_mm2 = np.pi * (float(scene.indenter_diameter_mm) / 2.0) ** 2
    return {"loq_n": 10.0 * sd, "loq_kpa": 10.0 * sd / area_mm2 * 1e3}


def single_point_study(cfg, seeds=(0, 1, 2), calibration=None, reconstruction=None,
                       test_forces_n=(10.0,), n_blank=100) -> tuple[pd.DataFrame, dict]:
    """Presses on the 18 x 18 grid at `test_forces_n` for every seed: a frame of predictions."""
    rows, loq, val, cost = [], [], [], []
    for seed in seeds:
        began = time.perf_counter()
        scene, model = calibrate(cfg, seed, _plain(calibration) or {}, _plain(reconstruction) or {})
        fit_s = time.perf_counter() - began
        forces = sorted(float(f) for f in test_forces_n)
        test = scene_for(cfg, seed=seed, protocol="single_point", n_force_levels=len(forces),
                         force_range_n=[forces[0], forces[-1]]).generate()
        prediction = model.predict(test.channels)
        cost.append({"seed": seed, "fit_s": fit_s, "per_frame_ms": per_frame_ms(model.predict, test.channels)})
        frame = pd.DataFrame(test.targets, columns=["x_mm", "y_mm", "force_n"])
        frame[["x_pred_mm", "y_pred_mm", "force_pred_n"]] = prediction
        frame["seed"] = seed
        frame["error_mm"] = np.hypot(frame.x_pred_mm - frame.x_mm, frame.y_pred_mm - frame.y_mm)
        frame["force_error_n"] = frame.force_pred_n - frame.force_n
        rows.append(frame)
        loq.append({"seed": seed, "chosen": model.chosen_hyperparameters(),
                    **limit_of_quantification(cfg, seed, model, n_blank)})
        val.append(model.validation_localisation_mm())
    return pd.concat(rows, ignore_index=True), {"loq": loq, "val_localisation_mm": val, "cost": cost}


def localisation_per_seed(frame: pd.DataFrame, extra: dict) -> pd.DataFrame:
    """Mean and sd of the localisation error per seed, over the presses at or above that sensor's
    limit of quantification (the paper's §5.1 rule); `frame` gains the column `above_loq`."""
    loq = {row["seed"]: row["loq_n"] for row in extra["loq"]}
    frame["above_loq"] = frame.force_n >= frame.seed.map(loq)
    return frame[frame.above_loq].groupby("seed").error_mm.agg(["mean", "std"])


def checked_comparison(kinds, validation_seeds, seeds) -> tuple[list[str], list[int]]:
    """(kinds, validation seeds) of a comparison, refused in one line when a kind is not a learned or
    GREIT reconstruction of the registry or the validation sensors are missing or hold a test sensor."""
    kinds, validation_seeds = list(kinds or []), [int(s) for s in validation_seeds or []]
    if not kinds:
        return [], validation_seeds
    if not validation_seeds or set(validation_seeds) & {int(s) for s in seeds}:
        raise InputError(f"ert_localisation: compare.validation_seeds {validation_seeds} must be given and hold none "
                         f"of the test sensors {list(seeds)}")
    unknown = [kind for kind in kinds if kind not in RECONSTRUCTIONS or kind == DEFAULT_KIND]
    if unknown:
        raise InputError(f"ert_localisation: compare.kinds {unknown} are not learned or GREIT reconstructions of "
                         f"models/ert/registry.py (expected some of "
                         f"{', '.join(k for k in RECONSTRUCTIONS if k != DEFAULT_KIND)})")
    return kinds, validation_seeds


def best_reconstruction(cfg, kinds, validation_seeds, seeds, calibration=None, reconstruction=None,
                        test_force_n=10.0, n_blank=100) -> dict | None:
    """The kind of `kinds` with the lowest mean localisation error on the validation sensors, then
    its localisation on the test sensors `seeds`, with its cost. None when `kinds` is empty."""
    kinds, validation_seeds = checked_comparison(kinds, validation_seeds, seeds)
    if not kinds:
        return None
    began = time.perf_counter()
    base = dict(_plain(reconstruction) or {})
    validation = {}
    for kind in kinds:
        start = time.perf_counter()
        frame, extra = single_point_study(cfg, validation_seeds, calibration, {**base, "kind": kind},
                                          (test_force_n,), n_blank)
        validation[kind] = {"localisation_mm": mean_sd(localisation_per_seed(frame, extra)["mean"]),
                            "per_frame_ms": mean_sd([c["per_frame_ms"] for c in extra["cost"]]),
                            "seconds": time.perf_counter() - start}
    chosen = min(kinds, key=lambda kind: validation[kind]["localisation_mm"]["mean"])
    frame, extra = single_point_study(cfg, seeds, calibration, {**base, "kind": chosen}, (test_force_n,), n_blank)
    per_seed = localisation_per_seed(frame, extra)
    return {"kind": chosen, "chosen_on": f"validation sensors {validation_seeds}",
            "validation": validation,
            "localisation_mm": mean_sd(per_seed["mean"]), "localisation_sd_mm": mean_sd(per_seed["std"]),
            "presses_used": int(frame.above_loq.sum()), "presses": len(frame),
            "reconstruction_cost": {"fit_s": mean_sd([c["fit_s"] for c in extra["cost"]]),
                                    "per_frame_ms": mean_sd([c["per_frame_ms"] for c in extra["cost"]]),
                                    "comparison_wall_s": time.perf_counter() - began},
            "chosen": [r["chosen"] for r in extra["loq"]]}


def run_localisation(cfg, output_dir, logger, seeds=(0, 1, 2), calibration=None, reconstruction=None, test_force_n=10.0,
                     n_blank=100, compare=None) -> dict:
    """Single-point localisation (the ERT study's §5.1, fig. 12): error of the field's peak, presses
    above the limit of quantification only. The top-level figures are the reference row (the
    paper's Tikhonov unless reconstruction.kind says otherwise); `best` is the best of
    `compare.kinds` chosen on `compare.validation_seeds` (module docstring), None without kinds."""
    output_dir = Path(output_dir)
    compare = _plain(compare) or {}
    checked_comparison(compare.get("kinds"), compare.get("validation_seeds"), seeds)     # before any sensor is run
    began = time.perf_counter()
    frame, extra = single_point_study(cfg, seeds, calibration, reconstruction, (test_force_n,), n_blank)
    per_seed = localisation_per_seed(frame, extra)
    used = frame[frame.above_loq]
    reference_kind = (_plain(reconstruction) or {}).get("kind", DEFAULT_KIND)
    metrics = {"scene": cfg.scene.name, "seeds": list(seeds), "kind": reference_kind,
               "reconstruction_cost": {"fit_s": mean_sd([c["fit_s"] for c in extra["cost"]]),
                                       "per_frame_ms": mean_sd([c["per_frame_ms"] for c in extra["cost"]]),
                                       "wall_s": time.perf_counter() - began},
               "localisation_mm_per_seed": [{"seed": int(s), "mean": float(r["mean"]), "sd": float(r["std"])}
                                            for s, r in per_seed.iterrows()],
               "localisation_mm": mean_sd(per_seed["mean"]),           # mean (over seeds) of per-seed means
               "localisation_sd_mm": mean_sd(per_seed["std"]),
               "presses_used": len(used), "presses": len(frame),
               "loq_kpa": mean_sd([r["loq_kpa"] for r in extra["loq"]]),
               "chosen": [r["chosen"] for r in extra["loq"]],
               "paper": PAPER.get(cfg.scene.name, {}),
               "val": {"localisation_mm": float(np.mean(extra["val_localisation_mm"]))},
               "best": best_reconstruction(cfg, compare.get("kinds"), compare.get("validation_seeds"), seeds,
                                           calibration, reconstruction, test_force_n, n_blank)}
    if metrics["best"] is not None:
        best = metrics["best"]
        cost = best["reconstruction_cost"]
        log.info(f"localisation: {reference_kind} (reference) {metrics['localisation_mm']['mean']:.2f} mm; best of "
                 f"{', '.join(best['validation'])} on validation sensors: {best['kind']} "
                 f"{best['localisation_mm']['mean']:.2f} mm (fit {cost['fit_s']['mean']:.1f} s per sensor, "
                 f"{cost['per_frame_ms']['mean']:.3f} ms per frame)")
    electrodes = OmegaConf.to_container(cfg.scene.electrodes_mm, resolve=True)
    figure = _error_map(frame[frame.seed == seeds[0]], cfg.scene.side_mm, electrodes, metrics)
    write_figures(output_dir, {"localisation_map": figure}, logger, prefix="ert")
    atomic_write_text(output_dir / "localisation.csv", frame.to_csv(index=False))
    return metrics


def run_force(cfg, output_dir, logger, seeds=(0, 1, 2), calibration=None, reconstruction=None,
              test_forces_n=(4.0, 8.0, 12.0), n_blank=100) -> dict:
    """Force estimation (the ERT study's §5.3, fig. 14): the field's integral against the reference."""
    output_dir = Path(output_dir)
    frame, extra = single_point_study(cfg, seeds, calibration, reconstruction, test_forces_n, n_blank)
    per_seed = []
    for seed, part in frame.groupby("seed"):
        error = part.force_error_n.abs()
        per_seed.append({"seed": int(seed), "abs_error_n": float(error.mean()), "abs_error_sd_n": float(error.std()),
                         "rmse_n": float(np.sqrt((part.force_error_n ** 2).mean())),
                         "r": float(np.corrcoef(part.force_n, part.force_pred_n)[0, 1])})
    table = pd.DataFrame(per_seed)
    metrics = {"scene": cfg.scene.name, "seeds": list(seeds), "test_forces_n": list(test_forces_n),
               "force_error_n": mean_sd(table.abs_error_n), "force_error_sd_n": mean_sd(table.abs_error_sd_n),
               "rmse_n": mean_sd(table.rmse_n), "r": mean_sd(table.r),
               "loq_kpa": mean_sd([r["loq_kpa"] for r in extra["loq"]]),
               "per_reference_force": [{"force_n": float(f), "estimated_n": {"mean": float(r["mean"]), "sd": float(r["std"])}}
                                       for f, r in frame.groupby("force_n").force_pred_n.agg(["mean", "std"]).iterrows()],
               "paper": PAPER.get(cfg.scene.name, {}),
               "val": {"localisation_mm": float(np.mean(extra["val_localisation_mm"]))}}
    figure = _force_figure(frame, seeds[0], cfg.scene.name, metrics["r"]["mean"], metrics["force_error_n"]["mean"])
    write_figures(output_dir, {"force": figure}, logger, prefix="ert")
    atomic_write_text(output_dir / "force.csv", frame.to_csv(index=False))
    return metrics


def placed_by_hand(scene, test, sd_mm: float) -> np.ndarray:
    """The readings of `test` (a two_point recording of `scene`) re-simulated with each indenter off
    its mark by N(0, sd_mm) per axis, kept on the sheet."""
    f = test.frame
    contacts = np.stack([f[["x1_mm", "y1_mm", "force_n"]].to_numpy(), f[["x2_mm", "y2_mm", "force2_n"]].to_numpy()], 1)
    contacts[:, 0, 2] -= contacts[:, 1, 2]                      # force_n is the total of both
    rng = random_generator_for(scene.seed, f"session{int(scene.session)}/two_point/placement")
    contacts[..., :2] = np.clip(contacts[..., :2] + rng.normal(0.0, sd_mm, contacts[..., :2].shape), 0.0, scene.side_mm)
    return scene.simulate(contacts).channels


def run_two_point(cfg, output_dir, logger, seeds=(0, 1, 2), calibration=None, reconstruction=None, n_repeats=10,
                  significance=0.05, placement_sd_mm=0.0) -> dict:
    """Two-point discrimination (the ERT study's §5.2, table 2) with the paired dip test (module docstring)."""
    if placement_sd_mm < 0:
        raise InputError(f"ert_two_point: placement_sd_mm must be >= 0, got {placement_sd_mm}")
    output_dir = Path(output_dir)
    tables, distances = [], {}
    for seed in seeds:
        scene, model = calibrate(cfg, seed, _plain(calibration) or {}, _plain(reconstruction) or {})
        if not model.offers_pressure_field:
            raise InputError(f"ert_two_point reads the calibrated pressure field, which {type(model).__name__} does "
                             f"not offer: reconstruction.kind must be tikhonov")
        two_point = scene_for(cfg, seed=seed, protocol="two_point", n_repeats=n_repeats)
        test = two_point.generate()
        readings = placed_by_hand(two_point, test, placement_sd_mm) if placement_sd_mm > 0 else test.channels
        field = model.pressure_field_kpa(readings)
        step = scene.side_mm / field.shape[-1]
        pick = lambda x, y: field[np.arange(len(field)),
                                  np.clip((y / step).astype(int), 0, field.shape[-1] - 1),
                                  np.clip((x / step).astype(int), 0, field.shape[-1] - 1)]
        f = test.frame
        peaks = 0.5 * (pick(f.x1_mm.to_numpy(), f.y1_mm.to_numpy()) + pick(f.x2_mm.to_numpy(), f.y2_mm.to_numpy()))
        middle = pick(f.x_mm.to_numpy(), f.y_mm.to_numpy())
        rows = []
        for (location, distance), index in f.groupby(["location", "distance_mm"]).groups.items():
            difference = peaks[index] - middle[index]
            if np.allclose(difference, difference[0]):
                p = 0.0 if difference[0] > 0 else 1.0       # no spread: the sign decides
            else:
                p = float(stats.ttest_1samp(difference, 0.0, alternative="greater").pvalue)
            rows.append({"seed": seed, "location": int(location), "distance_mm": float(distance), "p": p,
                         "dip_kpa": float(difference.mean())})
        table = pd.DataFrame(rows)
        tables.append(table)
        for location, part in table.groupby("location"):
            part = part.sort_values("distance_mm")
            significant = (part.p < significance).to_numpy()
            j = len(significant)
            while j > 0 and significant[j - 1]:
                j -= 1
            first = part.distance_mm.iloc[j] if j < len(part) else np.inf
            distances.setdefault(int(location), []).append(float(first))
    table = pd.concat(tables, ignore_index=True)
    pivot = table[table.seed == seeds[0]].pivot(index="location", columns="distance_mm", values="p")
    metrics = {"scene": cfg.scene.name, "seeds": list(seeds), "test": "one-sided paired t-test, peaks vs mid-point",
               "significance": significance,
               "discrimination_mm_per_location": {k: [d if np.isfinite(d) else "> max" for d in v]
                                                  for k, v in distances.items()},
               "p_table_seed0": {int(k): {float(d): float(p) for d, p in row.items()} for k, row in pivot.iterrows()},
               "paper": PAPER.get(cfg.scene.name, {})}
    atomic_write_text(output_dir / "two_point.csv", table.to_csv(index=False))
    return metrics


def _force_figure(frame, seed, scene_name, r, abs_error_n):
    """The force RMSE over the sheet for one simulated sensor, and the estimated against the
    reference force over all of them."""
    figure, axes = panel_grid(2, panel_width=5.2, panel_height=4.4)
    first = frame[frame.seed == seed]
    rmse_map = first.groupby(["x_mm", "y_mm"]).force_error_n.apply(lambda e: np.sqrt((e ** 2).mean())).reset_index()
    sc = axes[0].scatter(rmse_map.x_mm, rmse_map.y_mm, c=rmse_map.force_error_n, s=40, cmap="viridis", marker="s")
    figure.colorbar(sc, ax=axes[0], label="force RMSE over the reference forces (N)")
    axes[0].set(xlabel="press x (mm)", ylabel="press y (mm)", aspect="equal",
                title=f"RMSE per press point, simulated sensor seed={seed}")
    axes[1].errorbar(*frame.groupby("force_n").force_pred_n.agg(["mean", "std"]).reset_index().values.T, fmt="o",
                     capsize=4, label="estimated (mean ± sd over presses)")
    limits = [0, frame.force_n.max() * 1.3]
    axes[1].plot(limits, limits, "k--", lw=1, label="estimated = reference")
    axes[1].set(xlabel="reference force (N)", ylabel="estimated force (N)",
                title=f"all sensors: r = {r:.3f}, mean |error| = {abs_error_n:.2f} N")
    axes[1].legend(fontsize=8)
    figure.suptitle(f"{scene_name}: force from the reconstructed pressure field (as Fig. 14 of {PAPER_NAME})")
    figure.tight_layout()
    return figure


def _error_map(frame, side_mm, electrodes_mm, metrics):
    figure, axis = plt.subplots(figsize=(5.8, 6.4))
    axis.scatter(frame.x_mm, frame.y_mm, s=14, facecolors="none", edgecolors="k", lw=0.7, label="true")
    for _, row in frame.iterrows():
        axis.plot([row.x_mm, row.x_pred_mm], [row.y_mm, row.y_pred_mm], "r-", lw=0.7)
    axis.plot(frame.x_pred_mm, frame.y_pred_mm, "rx", ms=3, label="estimated")
    xy = np.asarray(electrodes_mm, dtype=float)
    axis.plot(xy[:, 0], xy[:, 1], "bs", ms=5, label="electrodes")
    axis.set(xlim=(-5, side_mm + 5), ylim=(-5, side_mm + 5), aspect="equal", xlabel="x (mm)", ylabel="y (mm)",
             title=f"{metrics['scene']}, simulated sensor seed={int(frame.seed.iloc[0])}: localisation error\n"
                   f"{frame.error_mm.mean():.2f} ± {frame.error_mm.std():.2f} mm (as Fig. 12 of {PAPER_NAME})")
    axis.title.set_fontsize(9)
    axis.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=3, fontsize=8)
    figure.tight_layout()
    return figure
