"""Study run `ert_learned`: a learned inverse against Tikhonov + calibration on the same test presses.

    python train.py experiment=ert_learned scene=ert_internal      (and scene=ert_boundary)

Per seed (one simulated sensor): the Tikhonov reconstruction is calibrated on the `calibration`
recording as in ert_localisation; the learned models train on `random` presses of the same
sensor; all predict the same `single_point` test recording (324 points x `test_forces_n`).

The training presses come in recordings as long as the test recording (`recording_presses:
test`), each with its own unloaded frame and baseline drift, so the models see many drift walks
and learn to ignore them; validation and conformal calibration hold out whole recordings, never
presses of a recording a model trained on. The 95 % intervals are calibrated (`conformal_on`)
on the held-out recordings, or on a `calibration_recording`: a recording of the test's press
protocol (324 points x the test forces, its own noise and drift draws), which is exchangeable
with the test recording as split-conformal coverage requires; random presses at uniform forces
are not (a third of the test presses sit at the lightest force, where errors are largest). Inputs (`features`): the raw voltage changes, the
Tikhonov image, or (`tikhonov_peak_window`, physics-informed) the window of the Tikhonov image
around its peak: the models then learn the correction from the peak pixel to the press
(targets x - peak x, y - peak y, force), one implementation shared with the baseline
(TikhonovReconstruction.peak_window).

Models: the regression pipeline's estimators: `extra_trees`, `resmlp` (on standardised inputs;
95 % split-conformal intervals from their absolute residuals on the held-out recordings, Vovk et
al. 2005, Lei et al. JASA 2018), and `blend`, the pipeline's configured model (`model=blend`:
K-fold residual MLP, random forest and extra trees, stacked) with its own conformal intervals
(models/uncertainty.py: normalised scores |y - mean| / sigma on the held-out recordings).
The "val" score is localisation on the held-out recordings.
"""
from pathlib import Path

import numpy as np
import pandas as pd
from hydra.utils import instantiate
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from data.atomic import atomic_write_json, atomic_write_text
from data.errors import InputError
from models.resmlp_regressor import ResMLPRegressor
from models.runs.ert_tests import _plain, calibrate, scene_for
from models.trees import TreeRegressor

FACTORIES = {"extra_trees": lambda seed, **p: TreeRegressor(kind="extra_trees", seed=seed, n_jobs=1, **p),
             "resmlp": lambda seed, **p: ResMLPRegressor(seed=seed, progress=False, **p)}
FEATURES = ("voltages", "tikhonov_image", "tikhonov_peak_window")


def _scores(prediction, targets) -> dict:
    error = np.hypot(*(prediction[:, :2] - targets[:, :2]).T)
    force = prediction[:, 2] - targets[:, 2]
    return {"localisation_mm": float(error.mean()), "localisation_sd_mm": float(error.std()),
            "force_abs_error_n": float(np.abs(force).mean()), "force_rmse_n": float(np.sqrt((force ** 2).mean()))}


def _features(kind, tikhonov, X, half_width_px=2) -> tuple[np.ndarray, np.ndarray]:
    """(inputs, offset): the models predict targets - offset from the inputs."""
    if kind == "voltages":
        return X, np.zeros((len(X), 3))
    if kind == "tikhonov_image":
        return tikhonov.force_pixels(X), np.zeros((len(X), 3))
    if kind == "tikhonov_peak_window":
        peak_xy_mm, inputs = tikhonov.peak_window(X, half_width_px)
        return inputs, np.column_stack([peak_xy_mm, np.zeros(len(X))])
    raise InputError(f"ert_learned: features must be one of {', '.join(FEATURES)}, got '{kind}'")


def _coverage(truth, lower, upper) -> dict:
    inside = (truth >= lower) & (truth <= upper)
    return {"coverage_x": float(inside[:, 0].mean()), "coverage_y": float(inside[:, 1].mean()),
            "coverage_force": float(inside[:, 2].mean()),
            "half_width_x_mm": float(np.mean(upper[:, 0] - lower[:, 0]) / 2),
            "half_width_force_n": float(np.mean(upper[:, 2] - lower[:, 2]) / 2)}


def _fit_and_interval(name, params, cfg, seed, X, y, groups, fit, held, X_test, X_cal, y_cal, coverage):
    """(test prediction, held-out prediction, lower, upper) of one model; intervals split-conformal
    on (X_cal, y_cal)."""
    scaler = StandardScaler().fit(X[fit])
    Xs, Xs_test, Xs_cal = scaler.transform(X), scaler.transform(X_test), scaler.transform(X_cal)
    if name == "blend":   # the pipeline's configured model and its own conformal intervals
        model = instantiate(cfg.model, **(params or {}))
        model.fit(Xs[fit], y[fit], groups=groups[fit])
        model.calibrate(Xs_cal, y_cal, alpha=1.0 - coverage)
        prediction, lower, upper = model.predict_interval(Xs_test, calibrated=True)
        return prediction, model.predict(Xs[held]), lower, upper
    model = make_pipeline(StandardScaler(), FACTORIES[name](seed, **(params or {})))
    model.fit(Xs[fit], y[fit])
    held_prediction = model.predict(Xs[held])
    residual = np.abs(model.predict(Xs_cal) - y_cal)
    rank = min(int(np.ceil((len(y_cal) + 1) * coverage)), len(y_cal)) - 1
    half_width = np.sort(residual, axis=0)[rank]
    prediction = model.predict(Xs_test)
    return prediction, held_prediction, prediction - half_width, prediction + half_width


def run_learned(cfg, output_dir, seeds=(0, 1, 2), n_train=3000, models=None, test_forces_n=(4.0, 8.0, 12.0),
                coverage=0.95, conformal_fraction=0.2, calibration=None, reconstruction=None,
                features="voltages", half_width_px=2, recording_presses=None, train_force_range_n=None,
                train_position_range_mm=(0.0, 200.0), conformal_on="held_out") -> dict:
    output_dir = Path(output_dir)
    models = _plain(models) or {"extra_trees": {"n_estimators": 200}}
    unknown = [m for m in models if m not in (*FACTORIES, "blend")]
    if unknown:
        raise InputError(f"ert_learned: unknown model '{unknown[0]}'; expected {', '.join(FACTORIES)} or blend")
    if features not in FEATURES:
        raise InputError(f"ert_learned: features must be one of {', '.join(FEATURES)}, got '{features}'")
    if conformal_on not in ("held_out", "calibration_recording"):
        raise InputError(f"ert_learned: conformal_on must be held_out or calibration_recording, got '{conformal_on}'")
    rows = []
    for seed in seeds:
        forces = sorted(float(f) for f in test_forces_n)
        test = scene_for(cfg, seed=seed, protocol="single_point", n_force_levels=len(forces),
                         force_range_n=[forces[0], forces[-1]]).generate()
        extra = {} if train_force_range_n is None else {"force_range_n": list(_plain(train_force_range_n))}
        length = len(test.frame) if recording_presses == "test" else recording_presses
        train = scene_for(cfg, seed=seed, protocol="random", n_samples=n_train,
                          position_range_mm=list(_plain(train_position_range_mm)), recording_presses=length,
                          **extra).generate()
        _, tikhonov = calibrate(cfg, seed, _plain(calibration) or {}, _plain(reconstruction) or {})
        rows.append({"seed": seed, "model": "tikhonov", **_scores(tikhonov.predict(test.channels), test.targets),
                     "val_localisation_mm": float(tikhonov.validation_scores_.min(axis=0)[0])})
        # Held out: whole recordings (with one recording, groups are presses).
        groups = np.asarray(train.groups)
        order = np.random.default_rng(seed).permutation(np.unique(groups))
        n_held = max(int(round(conformal_fraction * len(order))), 1)
        is_held = np.isin(groups, order[:n_held])
        held, fit = np.flatnonzero(is_held), np.flatnonzero(~is_held)
        X, offset = _features(features, tikhonov, train.channels, half_width_px)
        X_test, offset_test = _features(features, tikhonov, test.channels, half_width_px)
        y = train.targets - offset
        if conformal_on == "held_out":
            X_cal, y_cal = X[held], y[held]
        elif conformal_on == "calibration_recording":
            # a recording of the test's press protocol (the `calibration` protocol: same presses,
            # its own noise, hysteresis and drift draws), so calibration and test are exchangeable
            cal = scene_for(cfg, seed=seed, protocol="calibration", n_force_levels=len(forces),
                            force_range_n=[forces[0], forces[-1]]).generate()
            X_cal, offset_cal = _features(features, tikhonov, cal.channels, half_width_px)
            y_cal = cal.targets - offset_cal
        else:
            raise InputError(f"ert_learned: conformal_on must be held_out or calibration_recording, got '{conformal_on}'")
        for name, params in models.items():
            prediction, held_prediction, lower, upper = _fit_and_interval(
                name, params, cfg, seed, X, y, groups, fit, held, X_test, X_cal, y_cal, coverage)
            rows.append({"seed": seed, "model": name, **_scores(prediction + offset_test, test.targets),
                         "val_localisation_mm": _scores(held_prediction + offset[held], train.targets[held])["localisation_mm"],
                         **_coverage(test.targets - offset_test, lower, upper)})
    table = pd.DataFrame(rows)
    summary = table.drop(columns="seed").groupby("model").agg(["mean", "std"])
    summary.columns = [f"{a}_{b}" for a, b in summary.columns]
    atomic_write_text(output_dir / "learned_vs_tikhonov.csv", table.to_csv(index=False))
    best = min((m for m in models), key=lambda m: table[table.model == m].val_localisation_mm.mean())
    metrics = {"scene": cfg.scene.name, "seeds": list(seeds), "n_train": n_train, "features": features,
               "conformal_on": conformal_on,
               "recording_presses": recording_presses,
               "summary": summary.round(4).astype(object).where(summary.notna(), None).reset_index().to_dict(orient="records"),
               "best_on_validation": best,
               "val": {"localisation_mm": float(table[table.model == best].val_localisation_mm.mean())}}
    atomic_write_json(output_dir / "ert_metrics.json", metrics)
    return metrics
