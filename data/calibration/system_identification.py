"""System identification: the scene's declared parameters fitted to a rig's calibration presses.

The scene (without the effects it cannot match press by press, identifiable.py) simulates every
press at the table's labels; scipy's bounded least squares (trust-region reflective) moves the
parameters, each on its declared range mapped to [0, 1] (log scale where declared), to match the
readings. Residuals are per channel in units of that channel's spread over the presses, so a
channel in ohms and rubber12's pressure column in pascals weigh alike. The Jacobian is taken by
finite differences of 1 % of each range: the scenes' solvers are accurate to about that much
(rubber12's near-field tolerance), so a smaller step would differentiate their rounding.

Uncertainty: from the Jacobian at the optimum, the larger of the Gauss-Newton sd (s^2 (J^T J)^-1,
s^2 the residual variance per degree of freedom, so what the model cannot explain widens it)
and the cluster-robust one with presses as clusters (what a press's channels share counted
once: _standard_errors). A parameter at its bound is flagged: its covariance is not a confidence
interval there. Readings no parameter in range can produce (ohms given as kilo-ohms, a channel
of the opposite sign) are caught after the fit by each channel's gain against the simulation.
"""
import copy
import logging
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from common.errors import InputError
from data.calibration.identifiable import (calibration_for, from_unit_interval, get_value, set_value,
                                           to_unit_interval)
from data.calibration.press_simulation import fit_model, simulate_at

log = logging.getLogger("touchstone")
DIFF_STEP = 0.01          # finite-difference step, share of each parameter's range
AT_BOUND = 0.005          # within this share of a bound: flagged
GAIN_RANGE = (1 / 3, 3)   # a channel's least-squares gain against the simulation outside this: impossible readings
OFFSET_LEVEL = 3.0        # a column whose mean magnitude is this many spreads has a level, checked too
LIVE_CHANNEL = 0.1        # channels whose simulated spread is below this share of the largest are not gain-checked


@dataclass
class FittedParameter:
    path: str
    unit: str
    value: float
    sd: float
    default: float
    low: float
    high: float
    at_bound: bool
    what: str
    log: bool = False

    def interval(self, z: float = 1.959964) -> tuple[float, float]:
        """The two-sided interval of z sd (95 % by default): on the log scale for a parameter
        fitted on one (value x/÷ exp(z sd / value), never below 0), else value ± z sd."""
        if self.log:
            factor = float(np.exp(z * self.sd / self.value))
            return self.value / factor, self.value * factor
        return self.value - z * self.sd, self.value + z * self.sd


@dataclass
class FitResult:
    scene: str
    parameters: list[FittedParameter]
    columns: list[str]                # channels, then the scene's output targets
    measured: np.ndarray              # (presses, columns)
    simulated: np.ndarray             # at the fitted parameters
    simulated_default: np.ndarray     # at the scene's own parameters
    n_evaluations: int
    time_s: float
    message: str
    notes: dict = field(default_factory=dict)

    @property
    def residual_rms(self) -> dict:
        return dict(zip(self.columns, map(float, np.sqrt(np.mean((self.simulated - self.measured) ** 2, axis=0)))))

    @property
    def default_residual_rms(self) -> dict:
        return dict(zip(self.columns, map(float, np.sqrt(np.mean((self.simulated_default - self.measured) ** 2,
                                                                  axis=0)))))

    def summary(self) -> dict:
        return {"scene": self.scene, "presses": len(self.measured), "evaluations": self.n_evaluations,
                "time_s": self.time_s, "message": self.message,
                "parameters": {p.path: {"value": p.value, "sd": p.sd, "unit": p.unit, "default": p.default,
                                        "range": [p.low, p.high], "interval_95": list(p.interval()),
                                        "at_bound": p.at_bound, "what": p.what}
                               for p in self.parameters},
                "residual_rms": self.residual_rms, "default_residual_rms": self.default_residual_rms,
                "not_identifiable": self.notes.get("not_identifiable", {}),
                "unmodelled_effects": self.notes.get("unmodelled", []),
                "noise_from_residuals": self.notes.get("noise")}


def _scaled(values: np.ndarray) -> np.ndarray:
    """Each column's spread over the presses (its mean magnitude when it does not vary)."""
    spread = values.std(axis=0)
    fallback = np.abs(values).mean(axis=0)
    return np.where(spread > 1e-12 * np.maximum(fallback, 1e-300), spread, np.maximum(fallback, 1.0))


def identify(scene, presses: pd.DataFrame, max_evaluations: int = 60) -> tuple[FitResult, object]:
    """Fit the scene's declared parameters to `presses` (the scene's channel names and target
    columns) -> (the fit, the scene object with the fitted values, every listed effect kept)."""
    calibration = calibration_for(scene)
    parameters = calibration.parameters
    if len(presses) < len(parameters):
        raise InputError(f"calibration of scene {scene.name} needs at least {len(parameters)} presses (one per "
                         f"identifiable parameter) to fit on, got {len(presses)}")
    model = fit_model(scene)
    columns = None
    labels = presses[list(calibration.inputs)]

    def readings(scene_now) -> np.ndarray:
        nonlocal columns
        table = simulate_at(scene_now, labels)
        columns = columns or list(table.channel_columns) + list(calibration.outputs)
        return table.frame[columns].to_numpy(float)

    default_readings = readings(model)
    measured = presses[columns].to_numpy(float)
    scale = _scaled(measured)
    start = np.array([np.clip(to_unit_interval(p, get_value(model, p.path)), 0.0, 1.0) for p in parameters])
    calls, best, began = [0], [np.inf], time.perf_counter()

    def with_values(u) -> object:
        trial = copy.copy(model)
        for p, value in zip(parameters, u):
            set_value(trial, p.path, from_unit_interval(p, value))
        return trial

    def residuals(u) -> np.ndarray:
        calls[0] += 1
        r = ((readings(with_values(u)) - measured) / scale).ravel()
        best[0] = min(best[0], float(np.mean(r**2)))
        if calls[0] % 10 == 0:
            log.info("scene fit: %d simulations of %d presses, best mean squared residual %.4g (%.1f s)",
                     calls[0], len(presses), best[0], time.perf_counter() - began)
        return r

    log.info("scene fit: %s, %d parameters (%s) on %d presses, %d readings each", scene.name, len(parameters),
             ", ".join(p.path.rsplit(".", 1)[-1] for p in parameters), len(presses), len(columns))
    fit = least_squares(residuals, start, bounds=(0.0, 1.0), method="trf", diff_step=DIFF_STEP,
                        x_scale=1.0, max_nfev=max_evaluations, ftol=1e-10, xtol=1e-10, gtol=1e-10)
    simulated = readings(with_values(fit.x))
    _check_gains(scene.name, columns, measured, simulated)

    sd_unit = _standard_errors(fit.jac, fit.fun, len(presses))
    fitted_scene = copy.deepcopy(scene)
    results = []
    for p, u, sd in zip(parameters, fit.x, sd_unit):
        value = from_unit_interval(p, u)
        slope = value * (np.log(p.high) - np.log(p.low)) if p.log else p.high - p.low   # d value / d u
        set_value(fitted_scene, p.path, value)
        results.append(FittedParameter(p.path, p.unit, value, float(sd * slope), get_value(model, p.path), p.low,
                                       p.high, bool(u < AT_BOUND or u > 1 - AT_BOUND), p.what, p.log))
    notes = {"not_identifiable": calibration.not_identifiable, "unmodelled": list(calibration.unmodelled)}
    if calibration.noise_path and calibration.noise_path.split(".")[1] in (scene.effects or {}):
        # what the fit leaves unexplained, per channel: the rig's noise level (an upper bound)
        channel_rms = np.sqrt(np.mean((simulated - measured) ** 2, axis=0))[:len(columns) - len(calibration.outputs)]
        noise = float(np.median(channel_rms))
        set_value(fitted_scene, calibration.noise_path, noise)
        notes["noise"] = (*calibration.noise_path.split(".")[1:], noise)
    result = FitResult(scene.name, results, columns, measured, simulated, default_readings, calls[0],
                       time.perf_counter() - began, fit.message, notes)
    log.info("scene fit: done in %.1f s, %d simulations; %s", result.time_s, calls[0],
             "; ".join(f"{p.path.rsplit('.', 1)[-1]} {p.value:.4g} ± {p.sd:.2g}{' (at bound)' if p.at_bound else ''}"
                       for p in results))
    return result, fitted_scene


def _standard_errors(jacobian: np.ndarray, residuals: np.ndarray, n_presses: int) -> np.ndarray:
    """Each parameter's sd (in its [0, 1] coordinate): the larger of the Gauss-Newton one,
    s^2 (J^T J)^-1, and the cluster-robust (sandwich) one with presses as clusters. A press's
    channels share its errors (a drifted temperature, a thicker spot of gel move all of them),
    which the first treats as independent and so understates; the second counts each press's
    residuals together, with the small-sample factor n / (n - p)."""
    p = jacobian.shape[1]
    bread = np.linalg.pinv(jacobian.T @ jacobian)
    classical = np.sum(residuals**2) / max(residuals.size - p, 1) * bread
    scores = np.einsum("nc,ncp->np", residuals.reshape(n_presses, -1), jacobian.reshape(n_presses, -1, p))
    robust = bread @ (scores.T @ scores) @ bread * n_presses / max(n_presses - p, 1)
    return np.sqrt(np.clip(np.maximum(np.diag(classical), np.diag(robust)), 0.0, None))


def _check_gains(scene: str, columns, measured, simulated) -> None:
    """Stop on a channel the scene cannot produce at any parameter in range: its least-squares
    gain against the fitted simulation (deviations from each column's mean) is far from 1 or
    negative by more than twice its own sd, or its level (a reading with an offset, as ohms) is
    off by as much: the mark of a wrong unit or sign convention."""
    m, s = measured - measured.mean(axis=0), simulated - simulated.mean(axis=0)
    spread = np.sqrt(np.mean(s**2, axis=0))
    for k, column in enumerate(columns):
        if spread[k] < LIVE_CHANNEL * spread.max() or spread[k] == 0:
            continue
        gain = float(np.sum(m[:, k] * s[:, k]) / np.sum(s[:, k] ** 2))
        # the gain's own sd from the scatter about it: a few noisy presses must not stop a good rig
        gain_sd = float(np.sqrt(np.sum((m[:, k] - gain * s[:, k]) ** 2) / max(len(m) - 1, 1) / np.sum(s[:, k] ** 2)))
        checks = [(gain, gain_sd, "change")]
        if np.mean(np.abs(simulated[:, k])) > OFFSET_LEVEL * spread[k]:   # a reading with a level (ohms)
            checks.append((float(np.mean(np.abs(measured[:, k])) / np.mean(np.abs(simulated[:, k]))), 0.0, "level"))
        for ratio, sd, what in checks:
            if ratio + 2 * sd < GAIN_RANGE[0] or ratio - 2 * sd > GAIN_RANGE[1]:
                raise InputError(f"calibration: channel '{column}' reads {ratio:.3g} x the {what} scene {scene} "
                                 f"simulates at its best-fitting parameters in range; check the channel's unit "
                                 f"and sign convention (or its mapping, calibration.channel_map)")
