"""One classification run on time-series windows, top to bottom: fit, predict, score -> one
result; then the report side (runs/report/classification_report.py) writes it once.

Reports what the seed paper reports (accuracy, validation loss, parameter count) plus macro-F1,
per-class accuracy, accuracy per force level, fit time, confusion matrices (PNG and TensorBoard)
and per-epoch curves. Choose on validation, report on test: the model sees validation windows
for its per-epoch curves and sweeps rank runs by validation accuracy; test windows are only
predicted once, after fitting, and scored beside validation.
"""
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from hydra.utils import instantiate

from models.deployable import TimeSeriesPipeline, timeseries_pipeline
from runs.report.classification_report import write_classification_report
from runs.report.metrics import classification_metrics


@dataclass
class ClassificationResult:
    metrics: dict
    classes: list[str]
    y_val: np.ndarray
    proba_val: np.ndarray
    val_window_recording: np.ndarray
    val_levels: np.ndarray | None
    y_test: np.ndarray
    proba_test: np.ndarray
    test_window_recording: np.ndarray
    test_levels: np.ndarray | None
    pipeline: TimeSeriesPipeline
    hparams: dict


def checkpoint_folder(output_dir) -> Path:
    """Where a run's per-epoch checkpoint lives: the run folder itself, not train.py's staging
    folder inside it (removed when a run fails), so an interrupted run keeps its checkpoint."""
    from hydra.core.hydra_config import HydraConfig
    if HydraConfig.initialized():
        return Path(HydraConfig.get().runtime.output_dir) / "checkpoint"
    return Path(output_dir) / "checkpoint"


def fit_and_evaluate(cfg, datamodule, epoch_callback=None, output_dir=None) -> ClassificationResult:
    (X_train, y_train), (X_val, y_val), (X_test, y_test) = datamodule.train, datamodule.val, datamodule.test
    summary = datamodule.summary()
    model = instantiate(cfg.model)
    if "modalities" in model.get_params():
        model.set_params(modalities=datamodule.modality_channels)
    if "checkpoint_path" in model.get_params():  # resumable training (docs/training_recipes.md)
        if cfg.trainer.get("checkpoint", False):
            model.set_params(checkpoint_path=str(checkpoint_folder(output_dir) / "last.pt"))
        model.set_params(resume_from=cfg.trainer.get("resume_from"))
    start, cpu_start = time.perf_counter(), time.process_time()
    model.fit(X_train, y_train, X_val, y_val, epoch_callback=epoch_callback)
    fit_time_s, fit_cpu_time_s = time.perf_counter() - start, time.process_time() - cpu_start
    if "checkpoint_path" in model.get_params():  # the deployed model refits from scratch, never from this run's files
        model.set_params(checkpoint_path=None, resume_from=None)
    proba, proba_test = model.predict_proba(X_val), model.predict_proba(X_test)
    name = type(model.module_).__name__ if hasattr(model, "module_") else type(model).__name__
    n_parameters = int(getattr(model, "n_parameters_", 0))
    metrics = {"model": name, "n_parameters": n_parameters, "fit_time_s": fit_time_s,
               "cost": {"fit_time_s": fit_time_s, "fit_cpu_time_s": fit_cpu_time_s, "n_parameters": n_parameters},
               "val": classification_metrics(y_val, proba, datamodule.classes, datamodule.val_levels_per_window),
               "test": classification_metrics(y_test, proba_test, datamodule.classes, datamodule.test_levels_per_window),
               "data": summary}
    if hasattr(model, "best_epoch_"):  # the epoch kept (best on validation), of how many run, at what batch
        metrics["training"] = {"epochs_run": model.n_epochs_, "best_epoch": model.best_epoch_,
                               "batch_size": model.batch_size_}
    hparams = {"model": name, "label": datamodule.label, "seed": cfg.seed,
               "augment": bool(datamodule.n_virtual_windows), "window": str(summary["window"])}
    return ClassificationResult(metrics, list(datamodule.classes), y_val, proba, datamodule.val_window_recording,
                                datamodule.val_levels_per_window, y_test, proba_test, datamodule.test_window_recording,
                                datamodule.test_levels_per_window, timeseries_pipeline(datamodule, model), hparams)


def run_classification(cfg, output_dir, datamodule, logger):
    """Fit, evaluate and report -> (metrics, the deployable pipeline); runs/run.py exports it,
    measures its costs and writes the metrics."""
    result = fit_and_evaluate(cfg, datamodule, logger.log_epoch, output_dir)
    write_classification_report(result, output_dir, logger)
    return result.metrics, result.pipeline
