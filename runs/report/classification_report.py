"""The report of a classification run: confusion matrices for validation and test (PNG and
TensorBoard), final scalars and hyper-parameters, predictions.csv (with class probabilities),
pipeline.npz and the log line (metrics.json: runs/report/metrics_file.py). Validation is what
runs are chosen on; test, never used for choosing, is reported beside it so the number a reader quotes is an honest one."""
import logging
from pathlib import Path

import numpy as np
import pandas as pd

from common.atomic import atomic_write
from runs.report import plots
from runs.report.figure_files import write_figures
from runs.report.regression_report import write_pipeline

log = logging.getLogger(__name__)

SPLIT_NAMES = {"val": "validation", "test": "test"}
FIGURE_NAMES = {"val": "confusion", "test": "confusion_test"}  # confusion.png: validation


def _split_frame(classes, split, ids, y_true, proba, levels) -> pd.DataFrame:
    """One row per window or table row: what it is (`ids`: its recording, or a table row's raw
    readings), then the columns predict.py writes, in its order (the predicted class, one
    probability per class, `p_<class>`), so the two files compare column by column, then the
    true class (and force level), so a user can rank, threshold or calibrate without re-running."""
    frame = pd.DataFrame({"split": split, **ids, "predicted": classes[proba.argmax(axis=1)]})
    for k, name in enumerate(classes):
        frame[f"p_{name}"] = proba[:, k]
    frame["true"] = classes[y_true]
    if levels is not None:
        frame["force_level_n"] = levels
    return frame


def write_classification_report(result, output_dir, logger) -> None:
    output_dir = Path(output_dir)
    metrics = result.metrics
    figures = {}
    for split in ("val", "test"):
        scores = metrics[split]
        figures[FIGURE_NAMES[split]] = plots.confusion_figure(np.asarray(scores["confusion_matrix"]), result.classes,
                                                f"{metrics['model']}: {SPLIT_NAMES[split]} accuracy {scores['accuracy']:.3f}",
                                                samples=result.samples)
        for name in ("accuracy", "macro_f1", "loss"):
            logger.writer_.add_scalar(f"final/{split}_{name}", scores[name])
    logger.writer_.add_scalar("cost/fit_time_s", metrics["fit_time_s"])
    logger.log_hparams(result.hparams, {"hparam/val_accuracy": metrics["val"]["accuracy"],
                                        "hparam/test_accuracy": metrics["test"]["accuracy"],
                                        "hparam/fit_time_s": metrics["fit_time_s"]})

    classes = np.asarray(result.classes)
    frame = pd.concat([
        _split_frame(classes, "val", result.val_ids, result.y_val, result.proba_val, result.val_levels),
        _split_frame(classes, "test", result.test_ids, result.y_test, result.proba_test, result.test_levels),
    ], ignore_index=True)
    atomic_write(output_dir / "predictions.csv", lambda tmp: frame.to_csv(tmp, index=False))
    write_figures(output_dir, figures, logger)
    write_pipeline(result.pipeline, output_dir)
    val, test = metrics["val"], metrics["test"]
    log.info("%s (%d parameters) fitted in %.1f s: validation accuracy %.4f (macro-F1 %.4f, loss %.4f%s); "
             "test accuracy %.4f (macro-F1 %.4f, loss %.4f%s)",
             metrics["model"], metrics["n_parameters"], metrics["fit_time_s"], val["accuracy"], val["macro_f1"],
             val["loss"], by_force_level(val), test["accuracy"], test["macro_f1"], test["loss"], by_force_level(test))


def by_force_level(split: dict) -> str:
    """', by level {...}' where the data has force levels (recordings pressed at known forces), else nothing."""
    levels = split.get("accuracy_by_force_level_n")
    return "" if levels is None else f", by level {levels}"
