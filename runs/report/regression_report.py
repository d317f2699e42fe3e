"""The report of a regression run: one call turns a RegressionResult into figures, TensorBoard
scalars and hyper-parameters, predictions.csv, pipeline.npz and log lines (metrics.json is
written once by runs/report/metrics_file.py after export and latency).

Nothing here fits or predicts: runs/regression.py computed everything.
"""
import logging
from pathlib import Path

import pandas as pd

from common.atomic import atomic_write
from models.capabilities import capabilities
from models.deployable import PIPELINE_FILE, save_pipeline
from runs.model_naming import fit_time_words
from runs.report import plots
from runs.report.analysis import format_ablation
from runs.report.figure_files import write_figures
from runs.report.metrics import format_table

log = logging.getLogger(__name__)


def regression_figures(result, feature_names) -> dict:
    targets, y, pred = result.targets, result.y_test, result.pred_test
    model = result.metrics["model"]
    figures = {"parity": plots.parity_figure(y, pred, targets, {t: result.metrics["test"][t]["r2"] for t in targets},
                                             model=model),
               "residuals": plots.residual_figure(y, pred, targets, model=model)}
    if result.interval is not None:
        figures["uncertainty"] = plots.uncertainty_figure(y, *result.interval, targets, model=model)
    if "identifiability" in result.metrics:
        figures["identifiability"] = plots.identifiability_figure(result.metrics["identifiability"])
    if result.importances is not None:
        title, values = result.importances
        figures["importances"] = plots.importance_figure(feature_names, values, title)
        figures["correlation"] = plots.correlation_figure(*result.correlation)
    return figures


def _log_to_tensorboard(logger, result, figures) -> None:
    metrics = result.metrics
    logger.log_metrics(metrics["val"], "val")
    logger.log_metrics(metrics["test"], "test")
    logger.writer_.add_scalar("cost/fit_time_s", metrics["fit_time_s"])
    for split, values in (metrics.get("uncertainty") or {}).items():
        if split.startswith("coverage_"):
            for target, value in values.items():
                logger.writer_.add_scalar(f"uncertainty/{split}/{target}", value)
    final = {"hparam/val_r2": metrics["val"]["average"]["r2"], "hparam/test_r2": metrics["test"]["average"]["r2"],
             "hparam/fit_time_s": metrics["fit_time_s"]}
    spread = metrics.get("spread", {})
    for part in ("val", "test"):
        for target, scores in spread.get(part, {}).items():
            for name, value in scores.items():
                logger.writer_.add_scalar(f"spread/{part}/{target}/{name}_mean", value["mean"])
                logger.writer_.add_scalar(f"spread/{part}/{target}/{name}_sd", value["sd"])
    if "test" in spread:
        final["hparam/test_r2_mean_over_splits"] = spread["test"]["average"]["r2"]["mean"]
        final["hparam/test_r2_sd_over_splits"] = spread["test"]["average"]["r2"]["sd"]
    logger.log_hparams(result.hparams, final)


def _predictions_frame(result) -> pd.DataFrame:
    """One row per test press: the raw readings the deployed model takes (so the file is a
    ready input for predict.py), then the prediction columns predict.py writes, with its names
    and in its order (every target, then each target's _lower95 and _upper95:
    export/onnx_predictor.py), so the two files compare column by column, then the truth
    (true_x_mm)."""
    targets, pipeline = result.targets, result.pipeline
    frame = pd.DataFrame(pipeline.examples, columns=pipeline.channel_names)
    frame.insert(0, "row", result.test_rows)
    for k, t in enumerate(targets):
        frame[t] = result.pred_test[:, k]
    for k, t in enumerate(targets):
        if result.interval is not None:
            frame[f"{t}_lower95"], frame[f"{t}_upper95"] = result.interval[1][:, k], result.interval[2][:, k]
    for k, t in enumerate(targets):
        frame[f"true_{t}"] = result.y_test[:, k]
    return frame


def _log_summary(metrics, output_dir) -> None:
    log.info("%s\n%s", fit_time_words(metrics), format_table(metrics))
    for note in metrics.get("metric_notes", {}).get("mape_pct", []):
        log.warning("MAPE: %s", note)
    if "importances_note" in metrics:
        log.info(metrics["importances_note"])
    if "choice" in metrics:
        log.info("model choice: %s", metrics["choice"]["reason"])
    if "test" in metrics.get("spread", {}):
        spread = metrics["spread"]
        log.info("test R2 over %d %s splits (mean ± sd): %s", spread["splits"], spread["split"],
                 ", ".join(f"{t} {v['r2']['mean']:.3f} ± {v['r2']['sd']:.3f}" for t, v in spread["test"].items()))
    for warning in metrics.get("warnings", []):
        log.warning(warning)
    if "selection" in metrics:
        log.info("blend weights (per target): %s",
                 {n: {t: round(w, 3) for t, w in row.items()} for n, row in metrics["selection"]["weights"].items()})
    if "uncertainty" in metrics:
        u = metrics["uncertainty"]
        log.info("95 %% interval coverage on test, raw -> calibrated: %s",
                 {t: f"{u['coverage_raw'][t]:.3f} -> {u['coverage_calibrated'][t]:.3f}"
                  + (" (below target)" if u["coverage_calibrated"][t] < u["nominal"] else "") for t in u["coverage_raw"]})
        for warning in u.get("warnings", []):
            log.warning("interval coverage: %s", warning)
        log.info("Spearman(sigma, |error|): %s", {t: round(v, 3) for t, v in u["spearman_sigma_vs_abs_error"].items()})
    if "ablation" in metrics:
        log.info("feature-group ablation (%s), change in test R2:\n%s", metrics["ablation"]["model"],
                 format_ablation(metrics["ablation"]))


def write_pipeline(pipeline, output_dir: Path) -> None:
    """pipeline.npz, for a model whose fitted state is storable; a library estimator's is not
    (models/capabilities.py): its run deploys model.onnx alone."""
    if capabilities(pipeline.model).storable:
        save_pipeline(pipeline, output_dir / PIPELINE_FILE)
    else:
        log.info("%s: no %s (a library estimator's fitted state is not stored); model.onnx is what this run deploys",
                 type(pipeline.model).__name__, PIPELINE_FILE)


def write_regression_report(result, output_dir, logger, feature_names) -> None:
    output_dir = Path(output_dir)
    figures = regression_figures(result, feature_names)
    _log_to_tensorboard(logger, result, figures)
    frame = _predictions_frame(result)
    atomic_write(output_dir / "predictions.csv", lambda tmp: frame.to_csv(tmp, index=False))
    write_figures(output_dir, figures, logger)
    write_pipeline(result.pipeline, output_dir)
    _log_summary(result.metrics, output_dir)
