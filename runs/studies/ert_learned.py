"""Study run `ert_learned`: a learned inverse against Tikhonov + calibration on the same test presses.

    python train.py experiment=ert_learned scene=ert_internal      (and scene=ert_boundary)

Per seed (one simulated sensor): the Tikhonov reconstruction is calibrated on the `calibration`
recording as in ert_localisation; the learned models train on `random` presses of sensor
seed + `train_sensor_offset` (0: the same sensor; otherwise another simulated instance, with its
own manufacturing spread: specimen variation, electrode position errors), passed through the
test sensor's calibrated reconstruction; all predict the same `single_point` test recording
(324 points x `test_forces_n`) of the sensor under test.

The training presses come in recordings as long as the test recording (`recording_presses:
test`), each with its own unloaded frame and baseline drift, so the models see many drift walks
and learn to ignore them; validation holds out whole recordings, never presses of a recording a
model trained on. The 95 % intervals are split-conformal (`conformal_on`): on the held-out
training recordings, or (`calibration_recordings`) on `n_conformal_recordings` recordings of
the test's press protocol (324 points x the test forces), sessions 1, 2, ... of the
`calibration` protocol: each its own noise, hysteresis and drift draws, independent of session
0, on which the Tikhonov reconstruction was fitted (re-using session 0 made its features
in-sample there: force error 0.9 N against 2-6 N on any other recording, so the intervals came
out too narrow). Presses inside one recording share its drift walk, so they are not
exchangeable but recordings are: the scores of all calibration recordings are pooled, and the
coverage a new recording gets is checked by leaving each calibration recording out in turn
(`loo_coverage_*`, calibration data only; models/uncertainty.py). Held-out random presses at
uniform forces are not exchangeable with the test (a third of the test presses sit at the
lightest force, where errors are largest). Inputs (`features`): the raw voltage changes, the
Tikhonov image, or (`tikhonov_peak_window`, physics-informed) the window of the Tikhonov image
around its peak: the models then learn the correction from the peak pixel to the press
(targets x - peak x, y - peak y, force), one implementation shared with the baseline
(TikhonovReconstruction.peak_window).

Models: the regression pipeline's estimators: `extra_trees`, `resmlp` (on standardised inputs;
95 % split-conformal intervals from their absolute residuals on the calibration set, Vovk et
al. 2005, Lei et al. JASA 2018), and `blend`, the pipeline's configured model (`model=blend`:
K-fold residual MLP, random forest and extra trees, stacked) with its own conformal intervals
(normalised scores |y - mean| / sigma); one conformal quantile for all (models/uncertainty.py).
The "val" score is localisation on the held-out recordings.
"""
from pathlib import Path

import numpy as np
import pandas as pd
from hydra.utils import instantiate
from omegaconf import OmegaConf
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from common.atomic import atomic_write_text
from common.errors import InputError
from models.resmlp_regressor import ResMLPRegressor
from models.trees import TreeRegressor
from models.uncertainty import (
    conformal_quantile,
    leave_one_group_out_coverage,
    normalised_scores,
)
from runs.report.metrics_file import mean_sd
from runs.studies.ert_tests import _plain, calibrate, scene_for

FACTORIES = {"extra_trees": lambda seed, **p: TreeRegressor(kind="extra_trees", seed=seed, n_jobs=1, **p),
             "resmlp": lambda seed, **p: ResMLPRegressor(seed=seed, progress=False, **p)}
FEATURES = ("voltages", "tikhonov_image", "tikhonov_peak_window")
CONFORMAL_ON = ("held_out", "calibration_recordings")


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


def _coverage(truth, lower, upper, loo) -> dict:
    inside = (truth >= lower) & (truth <= upper)
    out = {"coverage_x": float(inside[:, 0].mean()), "coverage_y": float(inside[:, 1].mean()),
           "coverage_force": float(inside[:, 2].mean()),
           "half_width_x_mm": float(np.mean(upper[:, 0] - lower[:, 0]) / 2),
           "half_width_force_n": float(np.mean(upper[:, 2] - lower[:, 2]) / 2)}
    if loo is not None:   # mean over calibration recordings, each scored against the others' quantile
        out.update({f"loo_coverage_{t}": float(v) for t, v in zip(("x", "y", "force"), loo.mean(axis=0))})
        out["loo_coverage_min"] = float(loo.min())
    return out


def _fit_and_interval(name, params, cfg, seed, X, y, groups, fit, held, X_test, X_cal, y_cal, cal_groups, coverage):
    """(test prediction, held-out prediction, lower, upper, leave-one-recording-out coverage or
    None) of one model; intervals split-conformal on (X_cal, y_cal) through conformal_quantile:
    the blend's normalised scores |y - mean| / sigma, the others' absolute residuals."""
    alpha = 1.0 - coverage
    scaler = StandardScaler().fit(X[fit])
    Xs, Xs_test, Xs_cal = scaler.transform(X), scaler.transform(X_test), scaler.transform(X_cal)
    if name == "blend":   # the pipeline's configured model and its own conformal intervals
        # the sensor's seed, as for the other models (the blend's candidates read ${seed})
        model = instantiate(OmegaConf.merge(cfg, {"seed": seed}).model, **(params or {}))
        model.fit(Xs[fit], y[fit], groups=groups[fit])
        model.calibrate(Xs_cal, y_cal, alpha=alpha)
        prediction, lower, upper = model.predict_interval(Xs_test, calibrated=True)
        scores = normalised_scores(y_cal, *model.predict_std(Xs_cal))
        held_prediction = model.predict(Xs[held])
    else:
        model = make_pipeline(StandardScaler(), FACTORIES[name](seed, **(params or {})))
        model.fit(Xs[fit], y[fit])
        held_prediction = model.predict(Xs[held])
        scores = np.abs(model.predict(Xs_cal) - y_cal)
        half_width = conformal_quantile(scores, alpha)
        prediction = model.predict(Xs_test)
        lower, upper = prediction - half_width, prediction + half_width
    loo = leave_one_group_out_coverage(scores, cal_groups, alpha) if len(np.unique(cal_groups)) > 1 else None
    return prediction, held_prediction, lower, upper, loo


def run_learned(cfg, output_dir, logger, seeds=(0, 1, 2), n_train=3000, models=None, test_forces_n=(4.0, 8.0, 12.0),
                coverage=0.95, conformal_fraction=0.2, calibration=None, reconstruction=None,
                features="voltages", half_width_px=2, recording_presses=None, train_force_range_n=None,
                train_position_range_mm=(0.0, 200.0), conformal_on="held_out", n_conformal_recordings=5,
                train_sensor_offset=0) -> dict:
    output_dir = Path(output_dir)
    models = _plain(models) or {"extra_trees": {"n_estimators": 200}}
    unknown = [m for m in models if m not in (*FACTORIES, "blend")]
    if unknown:
        raise InputError(f"ert_learned: unknown model '{unknown[0]}'; expected {', '.join(FACTORIES)} or blend")
    if features not in FEATURES:
        raise InputError(f"ert_learned: features must be one of {', '.join(FEATURES)}, got '{features}'")
    if conformal_on not in CONFORMAL_ON:
        raise InputError(f"ert_learned: conformal_on must be one of {', '.join(CONFORMAL_ON)}, got '{conformal_on}'")
    if conformal_on == "calibration_recordings" and int(n_conformal_recordings) < 1:
        raise InputError(f"ert_learned: n_conformal_recordings must be >= 1, got {n_conformal_recordings}")
    if int(train_sensor_offset) and set(seeds) & {seed + int(train_sensor_offset) for seed in seeds}:
        raise InputError(f"ert_learned: train_sensor_offset {train_sensor_offset} makes a training sensor one of the "
                         f"test sensors {list(seeds)}")
    rows = []
    for seed in seeds:
        forces = sorted(float(f) for f in test_forces_n)
        test = scene_for(cfg, seed=seed, protocol="single_point", n_force_levels=len(forces),
                         force_range_n=[forces[0], forces[-1]]).generate()
        extra = {} if train_force_range_n is None else {"force_range_n": list(_plain(train_force_range_n))}
        length = len(test.frame) if recording_presses == "test" else recording_presses
        train = scene_for(cfg, seed=seed + int(train_sensor_offset), protocol="random", n_samples=n_train,
                          position_range_mm=list(_plain(train_position_range_mm)), recording_presses=length,
                          **extra).generate()
        _, tikhonov = calibrate(cfg, seed, _plain(calibration) or {}, _plain(reconstruction) or {})
        rows.append({"seed": seed, "model": "tikhonov", **_scores(tikhonov.predict(test.channels), test.targets),
                     "val_localisation_mm": tikhonov.validation_localisation_mm()})
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
            X_cal, y_cal, cal_groups = X[held], y[held], groups[held]
        else:
            # recordings of the test's press protocol, sessions 1..K of `calibration` (session 0
            # fitted the Tikhonov reconstruction): exchangeable with the test recording
            X_cal, y_cal, cal_groups = [], [], []
            for session in range(1, int(n_conformal_recordings) + 1):
                cal = scene_for(cfg, seed=seed, protocol="calibration", n_force_levels=len(forces),
                                force_range_n=[forces[0], forces[-1]], session=session,
                                recording_presses=None).generate()
                X_k, offset_k = _features(features, tikhonov, cal.channels, half_width_px)
                X_cal.append(X_k), y_cal.append(cal.targets - offset_k), cal_groups.append(np.full(len(X_k), session))
            X_cal, y_cal, cal_groups = np.vstack(X_cal), np.vstack(y_cal), np.concatenate(cal_groups)
        for name, params in models.items():
            prediction, held_prediction, lower, upper, loo = _fit_and_interval(
                name, params, cfg, seed, X, y, groups, fit, held, X_test, X_cal, y_cal, cal_groups, coverage)
            rows.append({"seed": seed, "model": name, **_scores(prediction + offset_test, test.targets),
                         "val_localisation_mm": _scores(held_prediction + offset[held], train.targets[held])["localisation_mm"],
                         **_coverage(test.targets - offset_test, lower, upper, loo)})
    table = pd.DataFrame(rows)
    # per model, every score as {"mean", "sd"} over seeds
    summary = {model: {column: mean_sd(part[column].dropna()) for column in table.columns
                       if column not in ("seed", "model") and part[column].notna().any()}
               for model, part in table.groupby("model", sort=False)}
    atomic_write_text(output_dir / "learned_vs_tikhonov.csv", table.to_csv(index=False))
    best = min((m for m in models), key=lambda m: table[table.model == m].val_localisation_mm.mean())
    metrics = {"scene": cfg.scene.name, "seeds": list(seeds), "n_train": n_train, "features": features,
               "train_sensor_seeds": [seed + int(train_sensor_offset) for seed in seeds],
               "conformal_on": conformal_on,
               "n_conformal_recordings": int(n_conformal_recordings) if conformal_on == "calibration_recordings" else None,
               "recording_presses": recording_presses,
               "summary": summary,
               "best_on_validation": best,
               "val": {"localisation_mm": float(table[table.model == best].val_localisation_mm.mean())}}
    return metrics
