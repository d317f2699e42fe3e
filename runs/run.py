"""A Touchstone run, top to bottom: check and seed, fit and report (the task's pipeline or a
study), export the model to ONNX, measure what a prediction costs (every exported model's
onnxruntime latency and size; the eager-vs-onnxruntime comparison with cost.measure_latency),
and write metrics.json once.

A run that is not "fit one model on one datamodule" (a scene study such as a receptive-field
profile, a contact tracker on a stream) is a `study`: an experiment sets `study:` to a node with
a `_target_` function `(cfg, output_dir, logger, **params) -> metrics dict` that does the whole
run's work and writes its own tables and figures; its metrics are written here like any run's.
Studies leave no pipeline, so nothing is exported for them.

Every artefact has one writer, called once: figures, predictions and pipeline.npz by the
report (runs/report/), model.onnx by export/pipelines.write_onnx, metrics.json by
runs/report/metrics_file.write_metrics, TensorBoard through the one logger opened here.
train.py calls `run(cfg, output_dir, config_hash)`; tests call it with a composed config.
"""
import logging
import random
from pathlib import Path

import numpy as np
import torch
from hydra.core.hydra_config import HydraConfig
from hydra.utils import call, instantiate
from omegaconf import DictConfig

from common.distributed import launched_world_size
from common.progress import phase
from export.latency import log_costs, measure
from export.pipelines import write_onnx
from models.capabilities import capabilities
from runs.calibration.run import run_calibration
from runs.classification import run_classification
from runs.config_checks import check_config
from runs.regression import run_regression
from runs.report.metrics_file import write_metrics
from runs.report.tensorboard_logger import run_name

log = logging.getLogger(__name__)


def seed_everything(seed: int) -> None:
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)


def run(cfg: DictConfig, output_dir: str | Path, config_hash: str = "unknown") -> dict:
    # train.py checked the command's config before start-up; a sweep's job gets its own config
    # from Hydra, so each is checked here, and told which of its trainer overrides reach nothing.
    overrides = HydraConfig.get().overrides.task if HydraConfig.initialized() else ()
    for warning in check_config(cfg, overrides):
        log.warning(warning)
    seed_everything(cfg.seed)
    output_dir = Path(output_dir)
    with instantiate(cfg.logger, log_dir=str(output_dir / "tensorboard" / run_name(cfg))) as logger:
        if cfg.get("study") is not None:
            metrics = {"study": cfg.study._target_.rsplit(".", 1)[-1], **call(cfg.study, cfg, output_dir, logger)}
        else:
            datamodule = instantiate(cfg.data).setup()
            task = getattr(datamodule, "task", "regression")
            fit_and_report = run_classification if task == "classification" else run_regression
            if cfg.get("calibration") is not None:   # experiment=calibrate: the scene fitted to the presses first
                fit_and_report = run_calibration
            metrics, pipeline = fit_and_report(cfg, output_dir, datamodule, logger)
            model_path = None
            if cfg.export.enabled and not capabilities(pipeline.model).onnx_exportable:
                log.warning("%s declares no ONNX export: model.onnx is not written", type(pipeline.model).__name__)
            elif cfg.export.enabled:
                with phase("ONNX export"):
                    model_path = write_onnx(pipeline, output_dir / cfg.export.file, cfg.export.opset, config_hash)
            if model_path is not None or cfg.cost.measure_latency:
                with phase("latency measurement"):
                    metrics["cost"].update(measure(pipeline, model_path, cfg.cost.budget_s,
                                                   compare=cfg.cost.measure_latency, calls=cfg.cost.onnx_latency_calls))
                log_costs(metrics["cost"], logger)
        metrics["world_size"] = launched_world_size()  # processes that trained it (torchrun, submitit tasks)
        write_metrics(output_dir, metrics, logger)
    return metrics
