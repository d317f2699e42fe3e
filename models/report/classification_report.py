"""The report of a classification run: confusion matrix (PNG and TensorBoard), final scalars and
hyper-parameters, predictions.csv, pipeline.pkl, metrics.json and the log line."""
import logging
from pathlib import Path

import numpy as np
import pandas as pd

from data.atomic import atomic_write, atomic_write_json
from models.deployable import save_pipeline
from models.report import plots

log = logging.getLogger(__name__)


def write_classification_report(result, output_dir, logger) -> None:
    output_dir = Path(output_dir)
    metrics, val = result.metrics, result.metrics["val"]
    figure = plots.confusion_figure(np.asarray(val["confusion_matrix"]), result.classes,
                                    f"{metrics['model']}: validation accuracy {val['accuracy']:.3f}")
    logger.log_figure("confusion/val", figure)
    for name in ("accuracy", "macro_f1", "loss"):
        logger.writer_.add_scalar(f"final/val_{name}", val[name])
    logger.writer_.add_scalar("cost/fit_time_s", metrics["fit_time_s"])
    logger.log_hparams(result.hparams, {"hparam/val_accuracy": val["accuracy"], "hparam/fit_time_s": metrics["fit_time_s"]})

    classes = np.asarray(result.classes)
    frame = pd.DataFrame({"recording": result.val_window_recording, "true": classes[result.y_val],
                          "predicted": classes[result.proba_val.argmax(axis=1)]})
    if result.val_levels is not None:
        frame["force_level_n"] = result.val_levels
    atomic_write(output_dir / "predictions.csv", lambda tmp: frame.to_csv(tmp, index=False))
    atomic_write(output_dir / "confusion.png", lambda tmp: figure.savefig(tmp, dpi=110, format="png"))
    plots.plt.close(figure)
    save_pipeline(result.pipeline, output_dir / "pipeline.pkl")
    atomic_write_json(output_dir / "metrics.json", metrics)
    log.info("%s (%d parameters) fitted in %.1f s: validation accuracy %.4f, macro-F1 %.4f, loss %.4f, by level %s",
             metrics["model"], metrics["n_parameters"], metrics["fit_time_s"], val["accuracy"], val["macro_f1"],
             val["loss"], val.get("accuracy_by_force_level_n"))
    log.info("outputs in %s", output_dir)
