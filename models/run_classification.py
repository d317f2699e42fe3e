"""One classification run on time-series windows: datamodule -> classifier -> metrics -> files.

Reports what the seed paper reports (accuracy, validation loss, parameter count) plus macro-F1,
per-class accuracy, accuracy per validation force level, fit time, a confusion matrix (PNG and
TensorBoard) and per-epoch curves.
"""
import logging
import time
from pathlib import Path

import numpy as np
import pandas as pd
from hydra.utils import instantiate
from sklearn.metrics import confusion_matrix, f1_score, log_loss

from data.atomic import atomic_write, atomic_write_json
from models import plots
from models.deployable import save_pipeline, timeseries_pipeline

log = logging.getLogger(__name__)


def classification_metrics(y_true, proba, classes, levels=None) -> dict:
    predicted = proba.argmax(axis=1)
    labels = np.arange(len(classes))
    matrix = confusion_matrix(y_true, predicted, labels=labels)
    per_class = np.divide(matrix.diagonal(), matrix.sum(axis=1), out=np.full(len(classes), np.nan),
                          where=matrix.sum(axis=1) > 0)
    result = {"accuracy": float((predicted == y_true).mean()),
              "macro_f1": float(f1_score(y_true, predicted, labels=labels, average="macro", zero_division=0)),
              "loss": float(log_loss(y_true, np.clip(proba, 1e-12, 1), labels=labels)),
              "per_class_accuracy": {c: float(a) for c, a in zip(classes, per_class)},
              "confusion_matrix": matrix.tolist()}
    if levels is not None:
        result["accuracy_by_force_level_n"] = {float(d): float((predicted[levels == d] == y_true[levels == d]).mean())
                                               for d in np.unique(levels)}
    return result


def run_classification(cfg, output_dir, datamodule) -> dict:
    output_dir = Path(output_dir)
    (X_train, y_train), (X_val, y_val) = datamodule.train, datamodule.val
    summary = datamodule.summary()
    log.info("data: %s", {k: v for k, v in summary.items() if k not in ("source", "augment")})
    model = instantiate(cfg.model)
    if "modalities" in model.get_params():
        model.set_params(modalities=datamodule.modality_channels)
    with instantiate(cfg.logger, log_dir=str(output_dir / "tensorboard")) as logger:
        start, cpu_start = time.perf_counter(), time.process_time()
        model.fit(X_train, y_train, X_val, y_val, epoch_callback=logger.log_epoch)
        fit_time_s, fit_cpu_time_s = time.perf_counter() - start, time.process_time() - cpu_start
        proba = model.predict_proba(X_val)
        metrics = {"model": type(model.module_).__name__ if hasattr(model, "module_") else type(model).__name__,
                   "n_parameters": int(getattr(model, "n_parameters_", 0)), "fit_time_s": fit_time_s,
                   "cost": {"fit_time_s": fit_time_s, "fit_cpu_time_s": fit_cpu_time_s,
                            "n_parameters": int(getattr(model, "n_parameters_", 0))},
                   "val": classification_metrics(y_val, proba, datamodule.classes, datamodule.val_levels_per_window),
                   "data": summary}
        figure = plots.confusion_figure(np.asarray(metrics["val"]["confusion_matrix"]), datamodule.classes,
                                        f"{metrics['model']}: validation accuracy {metrics['val']['accuracy']:.3f}")
        logger.log_figure("confusion/val", figure)
        for name in ("accuracy", "macro_f1", "loss"):
            logger.writer_.add_scalar(f"final/val_{name}", metrics["val"][name])
        logger.writer_.add_scalar("cost/fit_time_s", fit_time_s)
        logger.log_hparams({"model": metrics["model"], "label": datamodule.label, "seed": cfg.seed,
                            "augment": bool(datamodule.n_virtual_windows), "window": str(summary["window"])},
                           {"hparam/val_accuracy": metrics["val"]["accuracy"], "hparam/fit_time_s": fit_time_s})

    frame = pd.DataFrame({"recording": datamodule.val_window_recording, "true": np.asarray(datamodule.classes)[y_val],
                          "predicted": np.asarray(datamodule.classes)[proba.argmax(axis=1)]})
    if datamodule.val_levels_per_window is not None:
        frame["force_level_n"] = datamodule.val_levels_per_window
    atomic_write(output_dir / "predictions.csv", lambda tmp: frame.to_csv(tmp, index=False))
    atomic_write(output_dir / "confusion.png", lambda tmp: figure.savefig(tmp, dpi=110, format="png"))
    plots.plt.close(figure)
    save_pipeline(timeseries_pipeline(datamodule, model), output_dir / "pipeline.pkl")
    atomic_write_json(output_dir / "metrics.json", metrics)
    val = metrics["val"]
    log.info("%s (%d parameters) fitted in %.1f s: validation accuracy %.4f, macro-F1 %.4f, loss %.4f, by level %s",
             metrics["model"], metrics["n_parameters"], fit_time_s, val["accuracy"], val["macro_f1"], val["loss"],
             val.get("accuracy_by_force_level_n"))
    log.info("outputs in %s", output_dir)
    return metrics
