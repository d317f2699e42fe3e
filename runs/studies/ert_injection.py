"""Study run `ert_injection`: optimal pairwise injection (the ERT study's §4.2, fig. 9) and accuracy
against acquisition time, on the scene in `cfg.scene`.

    python train.py experiment=ert_injection scene=ert_internal      (and scene=ert_boundary)

1. Recruitment (data/physics/optimal_injection.py) on the nominal sensor's perturbation operator
   (every patch's linearised change, stacked): pairs, operator error and pair count per
   iteration; injection_selection.png is the paper's fig. 9 (pairs drawn per iteration; error and
   count against iteration).
2. Accuracy vs acquisition time: for injection sets of `pair_counts` pairs taken in recruitment
   order (optimal), in a random order, and the adjacent pairs alone, the Tikhonov reconstruction
   is calibrated and tested (single-point localisation at `test_force_n`) on each seed's
   recordings. A subset's channels are columns of the all-pairs recording (each reading is its
   own measurement with its own noise), so every set sees the same presses. Frame time =
   injections x measurements / switching rate (333 kHz, the ERT study's §3.4).
"""
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd

from common.atomic import atomic_write_text
from data.physics.optimal_injection import (
    all_pairs,
    perturbation_operator,
    recruit_pairs,
)
from models.ert.tikhonov import TikhonovReconstruction
from runs.report.figure_files import write_figures
from runs.report.plots import readable_log_axis
from runs.studies.ert_tests import PAPER_NAME, _plain, scene_for

matplotlib.use("Agg")
import matplotlib.pyplot as plt

ORDER_NAMES = {"optimal": "in recruitment order", "random": "in a random order", "adjacent": "adjacent pairs only"}
PAPER = {"pairs_recruited": 94, "iterations": 8, "operator_error_reduction_pct": 73.45}


def recruitment_for(scene, max_iterations: int, tie_tolerance: float, score: str = "leading_subspace"):
    """Recruitment on the scene's nominal sensor (no sensor effects)."""
    nominal = scene_for_nominal(scene)
    operator = perturbation_operator(nominal.transfer_jacobian(nominal.sensor()))
    return recruit_pairs(operator, nominal.n_electrodes, max_iterations=max_iterations, tie_tolerance=tie_tolerance,
                         score=score)


def scene_for_nominal(scene):
    scene.effects = {}
    return scene


def run_injection(cfg, output_dir, logger, seeds=(0, 1, 2), max_iterations=300, tie_tolerance=1e-6, score="leading_subspace",
                  pair_counts=(12, 24, 48, 94, 138, 276), switching_hz=333e3, test_force_n=10.0,
                  calibration=None, reconstruction=None) -> dict:
    output_dir = Path(output_dir)
    calibration, reconstruction = _plain(calibration) or {}, _plain(reconstruction) or {}
    scene = scene_for(cfg, injection="all")
    recruitment = recruitment_for(scene_for(cfg, injection="all"), max_iterations, tie_tolerance, score)
    order = recruitment.order
    per_iteration = pd.DataFrame({"iteration": np.arange(1, len(recruitment.error_per_iteration) + 1),
                                  "pairs": recruitment.count_per_iteration,
                                  "operator_error": recruitment.error_per_iteration})
    figures = {"injection_selection": _figure9(recruitment, np.asarray(scene.electrodes_mm, dtype=float),
                                               scene.side_mm, cfg.scene.name)}

    n_electrodes = scene.n_electrodes
    everything = all_pairs(n_electrodes)
    index_of = {tuple(p): k for k, p in enumerate(everything)}
    n_meas = len(scene.patterns()[1])
    rows = []
    for seed in seeds:
        cal = scene_for(cfg, seed=seed, protocol="calibration", injection="all", **calibration).generate()
        test = scene_for(cfg, seed=seed, protocol="single_point", injection="all", n_force_levels=1,
                         force_range_n=[test_force_n, test_force_n]).generate()
        rng = np.random.default_rng(seed)
        random_order = everything[rng.permutation(len(everything))]
        adjacent = np.array(sorted({tuple(sorted((k, (k + 1) % n_electrodes))) for k in range(n_electrodes)}))
        sets = [("optimal", k, order[:k]) for k in pair_counts if k <= len(order)]
        sets += [("random", k, random_order[:k]) for k in pair_counts]
        sets += [("adjacent", len(adjacent), adjacent)]
        for name, k, pairs in sets:
            columns = np.concatenate([np.arange(n_meas) + n_meas * index_of[tuple(p)] for p in pairs])
            geometry = {**scene.geometry(), "injection": (pairs + 1).tolist()}
            model = TikhonovReconstruction(geometry=geometry, seed=seed, **reconstruction)
            model.fit(cal.channels[:, columns], cal.targets)
            prediction = model.predict(test.channels[:, columns])
            error = np.hypot(*(prediction[:, :2] - test.targets[:, :2]).T)
            frame_s = k * n_meas / switching_hz
            rows.append({"seed": seed, "order": name, "pairs": int(k), "frame_ms": 1e3 * frame_s, "fps": 1.0 / frame_s,
                         "localisation_mm": float(error.mean()),
                         "force_abs_error_n": float(np.abs(prediction[:, 2] - test.targets[:, 2]).mean()),
                         "val_localisation_mm": model.validation_localisation_mm()})
    table = pd.DataFrame(rows)
    summary = table.groupby(["order", "pairs"]).agg(
        fps=("fps", "first"), localisation_mm=("localisation_mm", "mean"), localisation_sd_mm=("localisation_mm", "std"),
        force_abs_error_n=("force_abs_error_n", "mean"), val_localisation_mm=("val_localisation_mm", "mean")).reset_index()
    figures["accuracy_vs_time"] = _accuracy_vs_time_figure(summary, switching_hz, cfg.scene.name)
    write_figures(output_dir, figures, logger, prefix="ert")
    atomic_write_text(output_dir / "recruitment.csv", per_iteration.to_csv(index=False))
    atomic_write_text(output_dir / "accuracy_vs_time.csv", table.to_csv(index=False))
    eight = per_iteration[per_iteration.iteration == min(8, len(per_iteration))].iloc[0]
    metrics = {"scene": cfg.scene.name, "seeds": list(seeds), "paper": PAPER,
               "after_8_iterations": {"pairs": int(eight.pairs),
                                      "operator_error_reduction_pct": float(100 * (1 - eight.operator_error))},
               "iterations_to_94_pairs": int(np.searchsorted(per_iteration.pairs.to_numpy(), 94) + 1),
               "error_reduction_at_94_pairs_pct": float(100 * (1 - np.interp(94, per_iteration.pairs, per_iteration.operator_error))),
               "accuracy_vs_time": summary.round(4).astype(object).where(summary.notna(), None).to_dict(orient="records"),
               "val": {"localisation_mm": float(summary[summary.order == "optimal"].val_localisation_mm.min())}}
    return metrics


def _accuracy_vs_time_figure(summary, switching_hz, name):
    figure, axis = plt.subplots(figsize=(6.4, 4.4))
    for order, part in summary.groupby("order"):
        axis.errorbar(part.fps, part.localisation_mm, yerr=part.localisation_sd_mm, marker="o", capsize=3,
                      label=ORDER_NAMES.get(order, order))
    axis.set_xscale("log")
    readable_log_axis(axis, "x")
    axis.set(xlabel=f"frame rate at {switching_hz / 1e3:g} kHz switching (frames/s), log scale",
             ylabel="localisation error (mm)", title=f"{name}: localisation error against frame rate")
    axis.legend(title="injection pairs (mean ± sd over sensors)", fontsize=8, title_fontsize=8)
    figure.tight_layout()
    return figure


def _figure9(recruitment, electrodes, side_mm, name):
    figure = plt.figure(figsize=(12, 6.8))
    shown = min(6, len(recruitment.pairs_per_iteration))
    for i in range(shown):
        axis = figure.add_subplot(2, 4, i + 1 + (i >= 3))
        for earlier in recruitment.pairs_per_iteration[:i]:
            for a, b in earlier:
                axis.plot(*electrodes[[a, b]].T, color="0.75", lw=0.6)
        for a, b in recruitment.pairs_per_iteration[i]:
            axis.plot(*electrodes[[a, b]].T, color="C3", lw=1.2)
        axis.plot(*electrodes.T, "ks", ms=3)
        count = recruitment.count_per_iteration[i]
        axis.set(xlim=(-5, side_mm + 5), ylim=(-5, side_mm + 5), aspect="equal", xticks=[0, side_mm],
                 yticks=[0, side_mm], title=f"iteration {i + 1}: {count} pair{'s' if count != 1 else ''} in all")
        axis.set_xlabel("x (mm)", labelpad=-8, fontsize=8)
        axis.set_ylabel("y (mm)", labelpad=-14, fontsize=8)
        axis.tick_params(labelsize=7)
    axis = figure.add_subplot(1, 4, 4)
    iterations = np.arange(1, len(recruitment.error_per_iteration) + 1)
    error_line = axis.plot(iterations, recruitment.error_per_iteration, "C0-o", ms=3,
                           label="operator error (left axis)")
    axis.set(xlabel="iteration", ylabel="operator error, relative to no pairs (–)",
             xlim=(0, min(len(iterations), 40) + 1))
    twin = axis.twinx()
    count_line = twin.plot(iterations, recruitment.count_per_iteration, "C1-s", ms=3,
                           label="recruited pairs (right axis)")
    twin.set_ylabel("recruited pairs (count)")
    axis.legend(handles=error_line + count_line, loc="center right", fontsize=8)
    axis.set_title("error and pairs per iteration")
    figure.suptitle(f"{name}: injection pairs recruited per iteration (red: new; grey: earlier), "
                    f"as Fig. 9 of {PAPER_NAME}")
    figure.tight_layout()
    return figure
