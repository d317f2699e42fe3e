"""One regression run: datamodule -> model -> metrics -> analysis -> TensorBoard -> files.

Every artefact goes under `output_dir` and is written atomically.
"""
import inspect
import logging
import time
from pathlib import Path

import numpy as np
import pandas as pd
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from data.atomic import atomic_write, atomic_write_json
from models import plots
from models.deployable import regression_pipeline, save_pipeline
from models.analysis import (edge_vs_centre, feature_ablation, format_ablation, identifiability_map,
                             interval_report)
from models.metrics import format_table, regression_metrics

log = logging.getLogger(__name__)


def _hparams(cfg: DictConfig) -> dict:
    """The choices that distinguish runs, flattened for TensorBoard's HPARAMS tab."""
    flat = {"seed": cfg.seed, "data.split": cfg.data.get("split")}
    model = OmegaConf.to_container(cfg.model, resolve=True)
    flat.update({f"model.{k}": v for k, v in model.items() if not k.startswith("_")})
    flat["model"] = model["_target_"].rsplit(".", 1)[-1]
    if "scene" in cfg and cfg.data.get("source") is not None:
        flat.update({f"scene.{k}": cfg.scene[k] for k in ("n_samples", "protocol") if k in cfg.scene})
    return flat


def _model_size(model) -> dict:
    for attribute in ("n_parameters_", "n_nodes_"):
        if hasattr(model, attribute):
            return {attribute.rstrip("_"): int(getattr(model, attribute))}
    return {}


def _fit(model, datamodule, epoch_callback):
    (X_train, y_train), (X_val, y_val) = datamodule.train, datamodule.val
    extra = {}
    if "groups" in inspect.signature(model.fit).parameters and datamodule.split == "grouped":
        extra["groups"] = datamodule.table.groups[datamodule.train_idx]
    return model.fit(X_train, y_train, X_val, y_val, epoch_callback=epoch_callback, **extra)


def _selection_report(model, targets) -> dict:
    report = {"candidates": model.names_, "mode": model.mode, "per_target": model.per_target,
              "selected": model.selected_(),
              "weights": {n: dict(zip(targets, map(float, model.weights_[i]))) for i, n in enumerate(model.names_)},
              "val_r2": {n: dict(zip(targets, map(float, model.val_r2_[i]))) for i, n in enumerate(model.names_)},
              "fallback_targets": [targets[k] for k in model.fallback_targets_],
              "fit_time_s": model.fit_time_s_}
    folds = {n: m.fold_fit_time_s_ for n, m in model.models_.items() if hasattr(m, "fold_fit_time_s_")}
    if folds:
        report["fold_fit_time_s"] = folds
    return report


def _fold_costs(model) -> dict:
    """Fit wall and CPU time of every fold model of a (weighted) K-fold blend."""
    blends = model.models_ if hasattr(model, "weights_") else {"model": model}
    folds = {n: {"fit_time_s": m.fold_fit_time_s_, "fit_cpu_time_s": m.fold_fit_cpu_time_s_}
             for n, m in blends.items() if hasattr(m, "fold_fit_time_s_")}
    return {"folds": folds} if folds else {}


def _importances(model):
    if hasattr(model, "selected_tree_importances"):
        return model.selected_tree_importances()
    if hasattr(model, "feature_importances"):
        values = model.feature_importances()
        return None if values is None else (type(model).__name__, values)
    return None


def _ablation_estimator(model, cfg):
    """The selected candidate, unblended, so the ablation costs one fit per feature group."""
    if hasattr(model, "selected_"):
        name = model.selected_()
        candidate = cfg.model.candidates[name]
        return name, instantiate(candidate.get("estimator", candidate))
    return type(model).__name__, instantiate(cfg.model)


def run_regression(cfg: DictConfig, output_dir: str | Path, datamodule) -> dict:
    output_dir = Path(output_dir)
    analysis = cfg.get("analysis", {})
    (X_val, y_val), (X_test, y_test) = datamodule.val, datamodule.test
    targets = datamodule.target_names
    log.info("data: %s", {k: v for k, v in datamodule.summary().items() if k != "source"})

    model = instantiate(cfg.model)
    figures = {}
    with instantiate(cfg.logger, log_dir=str(output_dir / "tensorboard")) as logger:
        start, cpu_start = time.perf_counter(), time.process_time()
        _fit(model, datamodule, logger.log_epoch)
        fit_time_s, fit_cpu_time_s = time.perf_counter() - start, time.process_time() - cpu_start

        pred_val, pred_test = model.predict(X_val), model.predict(X_test)
        metrics = {
            "model": model.__class__.__name__,
            "val": regression_metrics(y_val, pred_val, targets),
            "test": regression_metrics(y_test, pred_test, targets),
            "fit_time_s": fit_time_s,
            **_model_size(model),
            "cost": {"fit_time_s": fit_time_s, "fit_cpu_time_s": fit_cpu_time_s, **_model_size(model),
                     **_fold_costs(model)},
            "data": datamodule.summary(),
        }
        figures["parity"] = plots.parity_figure(y_test, pred_test, targets, {t: metrics["test"][t]["r2"] for t in targets})
        figures["residuals"] = plots.residual_figure(y_test, pred_test, targets)

        if hasattr(model, "weights_"):
            metrics["selection"] = _selection_report(model, targets)
        if hasattr(model, "predict_std"):
            model.calibrate(*datamodule.calibration)
            report, mean, sigma = interval_report(model, X_test, y_test, targets)
            metrics["uncertainty"] = report
            _, lower, upper = model.predict_interval(X_test, calibrated=True)
            figures["uncertainty"] = plots.uncertainty_figure(y_test, mean, lower, upper, targets)
            if {"x_mm", "y_mm", "depth_mm", "pressure_pa"} <= set(targets):
                xy = y_test[:, [targets.index("x_mm"), targets.index("y_mm")]]
                error = np.abs(y_test - mean)
                ident = identifiability_map(xy, y_test[:, targets.index("depth_mm")], sigma, error, targets,
                                            bins=analysis.get("identifiability_bins", 5))
                position_sigma = np.hypot(sigma[:, targets.index("x_mm")], sigma[:, targets.index("y_mm")])
                ident["position_sigma_edge_vs_centre_mm"] = edge_vs_centre(xy, position_sigma)
                metrics["identifiability"] = ident
                figures["identifiability"] = plots.identifiability_figure(ident)

        importances = _importances(model)
        if importances is not None:
            name, values = importances
            figures["importances"] = plots.importance_figure(datamodule.feature_names, values,
                                                             f"feature importances: {name} (top 20)")
            top = np.argsort(values)[::-1][:10]
            table = np.column_stack([datamodule.y[datamodule.train_idx], datamodule.X[datamodule.train_idx][:, top]])
            labels = targets + [datamodule.feature_names[i] for i in top]
            figures["correlation"] = plots.correlation_figure(np.nan_to_num(np.corrcoef(table, rowvar=False)), labels)
            metrics["top_features"] = {datamodule.feature_names[i]: float(values[i]) for i in top}

        if analysis.get("ablation", False):
            name, estimator = _ablation_estimator(model, cfg)
            metrics["ablation"] = {"model": name, **feature_ablation(estimator, datamodule,
                                                                        progress=analysis.get("progress", True))}

        logger.log_metrics(metrics["val"], "val")
        logger.log_metrics(metrics["test"], "test")
        logger.writer_.add_scalar("cost/fit_time_s", fit_time_s)
        for split, values in (metrics.get("uncertainty") or {}).items():
            if split.startswith("coverage_"):
                for target, value in values.items():
                    logger.writer_.add_scalar(f"uncertainty/{split}/{target}", value)
        for name, figure in figures.items():
            logger.log_figure(f"{name}/test", figure)
        logger.log_hparams(_hparams(cfg), {"hparam/val_r2": metrics["val"]["average"]["r2"],
                                           "hparam/test_r2": metrics["test"]["average"]["r2"],
                                           "hparam/fit_time_s": fit_time_s})

    frame = pd.DataFrame({**{f"true_{t}": y_test[:, k] for k, t in enumerate(targets)},
                          **{f"pred_{t}": pred_test[:, k] for k, t in enumerate(targets)}})
    if "uncertainty" in metrics:
        for k, t in enumerate(targets):
            frame[f"lower95_{t}"], frame[f"upper95_{t}"] = lower[:, k], upper[:, k]
    frame.insert(0, "row", datamodule.test_idx)
    atomic_write(output_dir / "predictions.csv", lambda tmp: frame.to_csv(tmp, index=False))
    for name, figure in figures.items():
        atomic_write(output_dir / f"{name}.png", lambda tmp, f=figure: f.savefig(tmp, dpi=110, format="png"))
        plots.plt.close(figure)
    save_pipeline(regression_pipeline(datamodule, model), output_dir / "pipeline.pkl")
    atomic_write_json(output_dir / "metrics.json", metrics)

    log.info("%s fitted in %.2f s\n%s", metrics["model"], fit_time_s, format_table(metrics))
    if "selection" in metrics:
        log.info("validation weights (per target): %s",
                 {n: {t: round(w, 3) for t, w in row.items()} for n, row in metrics["selection"]["weights"].items()})
    if "uncertainty" in metrics:
        u = metrics["uncertainty"]
        log.info("95 %% interval coverage on test, raw -> calibrated: %s",
                 {t: f"{u['coverage_raw'][t]:.3f} -> {u['coverage_calibrated'][t]:.3f}" for t in targets})
        log.info("Spearman(sigma, |error|): %s", {t: round(v, 3) for t, v in u["spearman_sigma_vs_abs_error"].items()})
    if "ablation" in metrics:
        log.info("feature-group ablation (%s), change in test R2:\n%s", metrics["ablation"]["model"],
                 format_ablation(metrics["ablation"]))
    log.info("outputs in %s", output_dir)
    return metrics
