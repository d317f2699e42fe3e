"""experiment=calibrate, top to bottom: the scene fitted to the user's calibration presses, a
model pretrained on it and the presses, chosen on validation against scratch and the default
scene; then the report (the fit's and the regression's) and back to runs/run.py, which exports
the chosen model to ONNX and writes metrics.json like every run's.

    python train.py experiment=calibrate scene=rubber12 data=table data.path=my_presses.csv
"""
import logging
from pathlib import Path

from hydra.utils import instantiate

from common.errors import InputError
from models.capabilities import model_name, model_size
from models.deployable import regression_pipeline
from runs.calibration.fit_report import write_fit_report
from runs.calibration.pretraining import calibrate_and_pretrain, predict
from runs.regression import RegressionResult
from runs.report.metrics import regression_metrics
from runs.report.regression_report import write_regression_report

log = logging.getLogger(__name__)


def run_calibration(cfg, output_dir: str | Path, datamodule, logger):
    """-> (metrics, the chosen model's deployable pipeline)."""
    if datamodule.task != "regression":
        raise InputError("experiment=calibrate learns the scene's targets (regression); the table has a class label")
    scene = instantiate(cfg.scene)
    done = calibrate_and_pretrain(cfg, datamodule, scene)
    chosen = done["chosen"]
    model, fit_time_s, fit_cpu_time_s = done["candidates"][chosen]
    targets = datamodule.target_names
    (X_val, y_val), (X_test, y_test) = datamodule.val, datamodule.test
    pred_test = predict(model, X_test, targets)
    metrics = {
        "model": model_name(model),
        "val": regression_metrics(y_val, predict(model, X_val, targets), targets),
        "test": regression_metrics(y_test, pred_test, targets),
        "fit_time_s": fit_time_s,
        **model_size(model),
        "cost": {"fit_time_s": fit_time_s, "fit_cpu_time_s": fit_cpu_time_s, "scene_fit_time_s": done["fit"].time_s, **model_size(model)},
        "data": datamodule.summary(),
        "choice": done["choice"],
        "calibration": done["fit"].summary(),
    }
    result = RegressionResult(metrics, targets, datamodule.test_idx, y_test, pred_test,
                              regression_pipeline(datamodule, model), hparams={"calibration.chosen": chosen})
    write_fit_report(Path(output_dir), cfg, done["fit"], done["choice"], logger)
    write_regression_report(result, Path(output_dir), logger, datamodule.feature_names)
    return metrics, result.pipeline
