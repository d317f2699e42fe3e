"""Study run `ert_learned`: a learned inverse against Tikhonov + calibration on the same test presses.

    python train.py experiment=ert_learned scene=ert_internal      (and scene=ert_boundary)

Per seed (one simulated sensor): the learned models (the regression pipeline's estimators:
extra trees and the residual MLP, on standardised voltages) train on `random` presses of that
sensor; the Tikhonov reconstruction is calibrated on the `calibration` recording as in
ert_localisation; both predict the same `single_point` test recording (324 points x
`test_forces_n`). 95 % intervals for the learned models are split-conformal (Vovk et al. 2005;
Lei et al., JASA 2018): the `conformal_fraction` of the random presses held out from training
gives, per target, the ceil((n+1) 0.95)-th smallest absolute residual as the half-width.
The "val" score is the learned models' localisation error on that held-out split.
"""
from pathlib import Path

import numpy as np
import pandas as pd
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from data.atomic import atomic_write_json, atomic_write_text
from data.errors import InputError
from models.resmlp_regressor import ResMLPRegressor
from models.runs.ert_tests import _plain, calibrate, scene_for
from models.trees import TreeRegressor

FACTORIES = {"extra_trees": lambda seed, **p: TreeRegressor(kind="extra_trees", seed=seed, n_jobs=1, **p),
             "resmlp": lambda seed, **p: ResMLPRegressor(seed=seed, progress=False, **p)}


def _scores(prediction, targets) -> dict:
    error = np.hypot(*(prediction[:, :2] - targets[:, :2]).T)
    force = prediction[:, 2] - targets[:, 2]
    return {"localisation_mm": float(error.mean()), "localisation_sd_mm": float(error.std()),
            "force_abs_error_n": float(np.abs(force).mean()), "force_rmse_n": float(np.sqrt((force ** 2).mean()))}


def _features(kind, tikhonov, X):
    """Model inputs: `voltages` (the raw voltage changes) or `tikhonov_image` (the calibrated
    reconstruction's force per pixel, TikhonovReconstruction.force_pixels: the same linear map,
    deconvolution and coefficient field as the Tikhonov baseline, so a drift of the base fabric
    shows as a small dense image and a press as a peak)."""
    if kind == "voltages":
        return X
    if kind == "tikhonov_image":
        return tikhonov.force_pixels(X)
    raise InputError(f"ert_learned: features must be voltages or tikhonov_image, got '{kind}'")


def run_learned(cfg, output_dir, seeds=(0, 1, 2), n_train=3000, models=None, test_forces_n=(4.0, 8.0, 12.0),
                coverage=0.95, conformal_fraction=0.2, calibration=None, reconstruction=None,
                features="voltages", recording_presses=None) -> dict:
    output_dir = Path(output_dir)
    models = _plain(models) or {"extra_trees": {"n_estimators": 200}}
    rows = []
    for seed in seeds:
        forces = sorted(float(f) for f in test_forces_n)
        n_test = 324 * len(forces)
        # Training recordings as long as the test recording (null = one long recording): each
        # takes its own unloaded frame and drifts from it, as the test recording does.
        train = scene_for(cfg, seed=seed, protocol="random", n_samples=n_train, position_range_mm=[0.0, 200.0],
                          recording_presses=n_test if recording_presses == "test" else recording_presses).generate()
        test = scene_for(cfg, seed=seed, protocol="single_point", n_force_levels=len(forces),
                         force_range_n=[forces[0], forces[-1]]).generate()
        _, tikhonov = calibrate(cfg, seed, _plain(calibration) or {}, _plain(reconstruction) or {})
        rows.append({"seed": seed, "model": "tikhonov", **_scores(tikhonov.predict(test.channels), test.targets),
                     "val_localisation_mm": float(tikhonov.validation_scores_.min(axis=0)[0])})
        # Conformal / validation split: whole recordings (groups) held out, never presses of a
        # recording the models trained on (with one recording, groups are presses).
        groups = np.unique(train.groups)
        order = np.random.default_rng(seed).permutation(groups)
        n_conformal = max(int(round(conformal_fraction * len(groups))), 1)
        is_held = np.isin(train.groups, order[:n_conformal])
        held, fit = np.flatnonzero(is_held), np.flatnonzero(~is_held)
        X, y = _features(features, tikhonov, train.channels), train.targets
        X_test = _features(features, tikhonov, test.channels)
        for name, params in models.items():
            model = make_pipeline(StandardScaler(), FACTORIES[name](seed, **(params or {})))
            model.fit(X[fit], y[fit])
            residual = np.abs(model.predict(X[held]) - y[held])
            rank = min(int(np.ceil((len(held) + 1) * coverage)), len(held)) - 1
            half_width = np.sort(residual, axis=0)[rank]
            prediction = model.predict(X_test)
            inside = np.abs(prediction - test.targets) <= half_width
            rows.append({"seed": seed, "model": name, **_scores(prediction, test.targets),
                         "val_localisation_mm": _scores(model.predict(X[held]), y[held])["localisation_mm"],
                         "coverage_x": float(inside[:, 0].mean()), "coverage_y": float(inside[:, 1].mean()),
                         "coverage_force": float(inside[:, 2].mean()),
                         "half_width_x_mm": float(half_width[0]), "half_width_force_n": float(half_width[2])})
    table = pd.DataFrame(rows)
    summary = table.drop(columns="seed").groupby("model").agg(["mean", "std"])
    summary.columns = [f"{a}_{b}" for a, b in summary.columns]
    atomic_write_text(output_dir / "learned_vs_tikhonov.csv", table.to_csv(index=False))
    best = min((m for m in models), key=lambda m: table[table.model == m].val_localisation_mm.mean())
    metrics = {"scene": cfg.scene.name, "seeds": list(seeds), "n_train": n_train, "features": features,
               "recording_presses": recording_presses,
               "summary": summary.round(4).astype(object).where(summary.notna(), None).reset_index().to_dict(orient="records"),
               "best_on_validation": best,
               "val": {"localisation_mm": float(table[table.model == best].val_localisation_mm.mean())}}
    atomic_write_json(output_dir / "ert_metrics.json", metrics)
    return metrics
