"""One regression run, top to bottom: fit, predict, intervals, analysis -> one result; then the
report side (runs/report/regression_report.py) writes it once: figures, TensorBoard, predictions
and the pipeline (runs/run.py then exports it and writes metrics.json).
"""
import logging
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf
from sklearn.base import is_classifier

from common.errors import InputError
from common.progress import phase, progress
from data.units import clip_columns
from models.capabilities import capabilities, fit, model_name, model_size
from models.deployable import RegressionPipeline, regression_pipeline
from runs.report.analysis import edge_vs_centre, feature_ablation, identifiability_map, interval_report
from runs.model_naming import model_record
from runs.report.metrics import mape_notes, regression_metrics
from runs.report.metrics_file import mean_sd
from runs.report.regression_report import write_regression_report
from runs.split_notes import split_note

log = logging.getLogger(__name__)
SHEET_TARGETS = {"x_mm", "y_mm", "depth_mm", "pressure_pa"}


@dataclass
class RegressionResult:
    """Everything a run computed; the report side only formats and writes it."""
    metrics: dict
    targets: list[str]
    test_rows: np.ndarray
    y_test: np.ndarray
    pred_test: np.ndarray
    pipeline: RegressionPipeline
    interval: tuple | None = None               # (mean, lower, upper) calibrated, on test
    importances: tuple | None = None            # (title, values) of a tree model that carries weight
    correlation: tuple | None = None            # (matrix, labels): targets and top features
    hparams: dict = field(default_factory=dict)


def _selection_report(model, targets) -> dict:
    report = {"candidates": model.names_, "weights_rule": model.weights, "mode": model.mode,
              "per_target": model.per_target,
              "selected": model.selected_(),
              "weights": {n: dict(zip(targets, map(float, model.weights_[i]))) for i, n in enumerate(model.names_)},
              "val_r2": {n: dict(zip(targets, map(float, model.val_r2_[i]))) for i, n in enumerate(model.names_)},
              "fallback_targets": [targets[k] for k in model.fallback_targets_],
              # stacking: targets where the stacked blend scored below its best candidate on
              # validation, so that candidate alone serves the target
              "stacking_fallback_targets": [targets[k] for k in model.stacking_fallback_targets_],
              "fit_time_s": model.fit_time_s_}
    folds = {n: m.fold_fit_time_s_ for n, m in model.models_.items() if capabilities(m).fold_costs}
    if folds:
        report["fold_fit_time_s"] = folds
    return report


def _fold_members(model) -> dict:
    """The models fitted K times: a blend's K-fold candidates, or the model itself."""
    members = model.models_ if capabilities(model).weighs_candidates else {"model": model}
    return {n: m for n, m in members.items() if capabilities(m).fold_costs}


def _fold_costs(model) -> dict:
    """Fit wall and CPU time of every fold model of a (weighted) K-fold blend."""
    folds = {n: {"fit_time_s": m.fold_fit_time_s_, "fit_cpu_time_s": m.fold_fit_cpu_time_s_}
             for n, m in _fold_members(model).items()}
    return {"folds": folds} if folds else {}


def _fold_warnings(model) -> list[str]:
    return sorted({m.fold_warning_ for m in _fold_members(model).values() if m.fold_warning_})


def _ablation_estimator(model, node):
    """The selected candidate, unblended, so the ablation costs one fit per feature group; `node`
    is the fitted model's config."""
    if capabilities(model).weighs_candidates:
        name = model.selected_()
        candidate = node.candidates[name]
        return name, instantiate(candidate.get("estimator", candidate))
    return type(model).__name__, instantiate(node)


def check_deployable(choice) -> None:
    """A choice that may pick a mixture of candidates is refused before any fitting."""
    if choice.ensemble:
        raise InputError("model.ensemble=true: a mixture of candidates is not exported as one ONNX graph yet; "
                         "set model.ensemble=false")


def _hparams(cfg: DictConfig) -> dict:
    """The choices that distinguish runs, flattened for TensorBoard's HPARAMS tab."""
    flat = {"seed": cfg.seed, "data.split": cfg.data.get("split")}
    model = OmegaConf.to_container(cfg.model, resolve=True)
    flat.update({f"model.{k}": v for k, v in model.items() if not k.startswith("_")})
    flat["model"] = model["_target_"].rsplit(".", 1)[-1]
    if "scene" in cfg and cfg.data.get("source") is not None:
        flat.update({f"scene.{k}": cfg.scene[k] for k in ("n_samples", "protocol") if k in cfg.scene})
    return flat


def fit_and_evaluate(cfg: DictConfig, datamodule, epoch_callback=None) -> RegressionResult:
    analysis = cfg.get("analysis", {})
    (X_train, y_train), (X_val, y_val), (X_test, y_test) = datamodule.train, datamodule.val, datamodule.test
    targets = datamodule.target_names
    model, node = instantiate(cfg.model), cfg.model
    if is_classifier(model):
        what = f"model.kind={cfg.model.kind}" if "kind" in cfg.model else model_name(model)
        raise InputError(f"{what} classifies, but {datamodule.table.source_name}'s target(s) "
                         f"{', '.join(targets)} are quantities (regression): choose a regression model, or set "
                         "data.task=classification for a class label")
    choice = model if capabilities(model).chooses else None
    if choice is not None:
        choice.set_params(task="regression")
        check_deployable(choice)
    groups = datamodule.table.groups[datamodule.train_idx] if datamodule.split in ("grouped", "predefined") else None

    start, cpu_start = time.perf_counter(), time.process_time()
    fit(model, X_train, y_train, X_val, y_val, epoch_callback=epoch_callback, groups=groups)
    fit_time_s, fit_cpu_time_s = time.perf_counter() - start, time.process_time() - cpu_start
    if choice is not None:   # from here on the run reports and deploys the chosen candidate
        model, node = choice.chosen_model_, cfg.model.candidates.regression[choice.chosen_]
    offers = capabilities(model)

    def predict(X):
        """(n, n_targets) even for one target (scikit-learn returns a vector), within each target's
        physical range (data/units.py: a pressure, a depth or a force's magnitude is >= 0), as
        predict.py reports them."""
        return clip_columns(model.predict(X), targets)

    pred_test = predict(X_test)
    metrics = {
        **model_record(model, choice),
        "val": regression_metrics(y_val, predict(X_val), targets),
        "test": regression_metrics(y_test, pred_test, targets),
        "fit_time_s": fit_time_s,
        **model_size(model),
        "cost": {"fit_time_s": fit_time_s, "fit_cpu_time_s": fit_cpu_time_s, **model_size(model),
                 **_fold_costs(model)},
        "data": datamodule.summary(),
    }
    metrics["data"]["split_note"] = split_note(metrics["data"], cfg.data.get("group_columns"))
    notes = mape_notes({"val": y_val, "test": y_test}, targets)
    if notes:
        metrics["metric_notes"] = {"mape_pct": notes}
    if choice is not None:
        metrics["choice"] = choice.report()
    warnings = _fold_warnings(model)
    if warnings:
        metrics["warnings"] = warnings
    result = RegressionResult(metrics, targets, datamodule.test_idx, y_test, pred_test,
                              regression_pipeline(datamodule, model), hparams=_hparams(cfg))
    result.hparams["model"] = metrics["model"]   # TensorBoard names the model metrics.json names
    if choice is not None:
        result.hparams["model.chosen"] = choice.chosen_

    if offers.weighs_candidates:
        metrics["selection"] = _selection_report(model, targets)
    if offers.intervals:
        X_cal, y_cal = datamodule.calibration
        model.calibrate(X_cal, y_cal)
        metrics["uncertainty"], mean, sigma = interval_report(model, X_test, y_test, targets)
        metrics["uncertainty"]["calibration_rows"] = len(y_cal)
        metrics["uncertainty"].update(coverage_warnings(metrics["uncertainty"], len(y_test)))
        if model.calibration_note_:
            log.warning(model.calibration_note_)
            metrics["uncertainty"]["calibration_note"] = model.calibration_note_
        result.interval = tuple(clip_columns(part, targets) for part in model.predict_interval(X_test, calibrated=True))
        if SHEET_TARGETS <= set(targets):
            xy = y_test[:, [targets.index("x_mm"), targets.index("y_mm")]]
            ident = identifiability_map(xy, y_test[:, targets.index("depth_mm")], sigma, np.abs(y_test - mean),
                                        targets, bins=analysis.get("identifiability_bins", 5))
            position_sigma = np.hypot(sigma[:, targets.index("x_mm")], sigma[:, targets.index("y_mm")])
            ident["position_sigma_edge_vs_centre_mm"] = edge_vs_centre(xy, position_sigma)
            metrics["identifiability"] = ident

    result.importances = weighted_importances(model, metrics) if offers.importances else None
    if result.importances is not None:
        values = result.importances[1]
        top = np.argsort(values)[::-1][:10]
        table = np.column_stack([datamodule.y[datamodule.train_idx], datamodule.X[datamodule.train_idx][:, top]])
        result.correlation = (np.nan_to_num(np.corrcoef(table, rowvar=False)),
                              targets + [datamodule.feature_names[i] for i in top])
        metrics["top_features"] = {datamodule.feature_names[i]: float(values[i]) for i in top}

    splits = cfg.get("spread", {}).get("splits", 1)
    if splits > 1:
        with phase(f"scores over {splits} splits: this run's and {splits - 1} more ({metrics['model']} refitted "
                   "on each)"):
            metrics["spread"] = split_spread(node, datamodule, metrics, splits)

    if analysis.get("ablation", False):
        name, estimator = _ablation_estimator(model, node)
        metrics["ablation"] = {"model": name, **feature_ablation(estimator, datamodule,
                                                                    progress=analysis.get("progress", True))}
    return result


def weighted_importances(model, metrics) -> tuple | None:
    """(figure title, values) of the model's feature importances, or None. A blend gives those of its
    heaviest candidate that has them, which may be a tree the blend gave weight 0 (its figure then
    showed a model that predicts nothing): such importances are left out, and metrics.json says why."""
    given = model.importances()
    if given is None:
        return None
    name, values = given
    if not capabilities(model).weighs_candidates:
        return f"feature importances: {metrics['model']} (top 20)", values
    weights = metrics["selection"]["weights"][name]
    if not any(w > 0 for w in weights.values()):
        metrics["importances_note"] = (f"no importances figure: {name}, the only candidate with importances, "
                                       "has weight 0 for every target in the blend")
        return None
    shown = ", ".join(f"{t} {w:.2f}" for t, w in weights.items())
    return f"feature importances: {name}, blend weight {shown} (top 20)", values


def coverage_warnings(uncertainty: dict, n_test: int) -> dict:
    """Warnings for the calibrated intervals: a target whose test coverage is below the nominal 95 %,
    and one whose calibration lowered it. The conformal scale is set on the calibration rows,
    where it reaches the nominal coverage by construction; the test rows are not chosen on, so
    a shortfall there is reported, not corrected (on 70 test rows one row is 1.4 points)."""
    nominal, warnings = uncertainty["nominal"], []
    for target, calibrated in uncertainty["coverage_calibrated"].items():
        raw = uncertainty["coverage_raw"][target]
        if calibrated < nominal:
            lowered = f", lowered by calibration from {raw:.3f}" if calibrated < raw else ""
            warnings.append(f"{target}: calibrated {100 * nominal:.0f} % intervals cover {calibrated:.3f} of the "
                            f"{n_test} test rows, below the {nominal:.2f} target{lowered}")
    return {"warnings": warnings} if warnings else {}


def split_spread(node, datamodule, first: dict, splits: int) -> dict:
    """Validation and test scores per target over `splits` draws of the split: this run's own (its
    `first` metrics) and splits - 1 more (datamodule.resplit, grouped as this one), the model of
    `node` refitted on each. One fit per split: a choice is made and intervals are calibrated
    on this run's split only; the exported model is this run's."""
    if datamodule.split == "predefined":
        return {"splits": 1, "note": "the data declares its split (data.declared_split=ignore draws others)"}
    runs, seeds = [first], [datamodule.seed]
    for k in progress(range(1, splits), desc="refits on the other splits", unit="splits"):
        other = datamodule.resplit(datamodule.seed + k)
        groups = other.table.groups[other.train_idx] if other.split == "grouped" else None
        model = instantiate(node)
        fit(model, *other.train, *other.val, groups=groups)
        runs.append({part: regression_metrics(y, clip_columns(model.predict(X), other.target_names), other.target_names)
                     for part, (X, y) in (("val", other.val), ("test", other.test))})
        seeds.append(other.seed)
    names = [*datamodule.target_names, "average"]
    spread = {"splits": len(runs), "split": datamodule.split, "split_seeds": seeds}
    for part in ("val", "test"):
        spread[part] = {t: {m: mean_sd([r[part][t][m] for r in runs]) for m in first[part][t]
                            if all(r[part][t][m] is not None for r in runs)} for t in names}
    return spread


def run_regression(cfg: DictConfig, output_dir: str | Path, datamodule, logger):
    """Fit, evaluate and report -> (metrics, the deployable pipeline); runs/run.py exports it,
    measures its costs and writes the metrics."""
    with phase(f"fitting and evaluating on {len(datamodule.train_idx):,} training rows"):
        result = fit_and_evaluate(cfg, datamodule, logger.log_epoch)
    write_regression_report(result, output_dir, logger, datamodule.feature_names)
    return result.metrics, result.pipeline
