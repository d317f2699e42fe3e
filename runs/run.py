"""A Touchstone run: seed everything, set up the datamodule, and hand over to the pipeline of its
task (regression on tabular presses, or classification of time-series windows).

A run that is not "fit one model on one datamodule" (a scene study such as a receptive-field
profile, a contact tracker on a stream) is a `study`: an experiment sets `study:` to a node with
a `_target_` function `(cfg, output_dir, **params) -> metrics dict`, and that function does
the whole run. Such experiments set `export: none` and `cost.measure_latency: false` when they
leave no model for export/ to convert.

train.py calls `run(cfg, output_dir)`; tests call it too with a composed config and a tmp_path.
"""
import logging
import random
from pathlib import Path

import numpy as np
import torch
from hydra.core.hydra_config import HydraConfig
from hydra.utils import call, instantiate
from omegaconf import DictConfig

from runs.classification import run_classification
from runs.config_checks import check_config
from runs.regression import run_regression

log = logging.getLogger(__name__)


def seed_everything(seed: int) -> None:
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)


def run(cfg: DictConfig, output_dir: str | Path) -> dict:
    # train.py checked the command's config before start-up; a sweep's job gets its own config
    # from Hydra, so each is checked here, and told which of its trainer overrides reach nothing.
    overrides = HydraConfig.get().overrides.task if HydraConfig.initialized() else ()
    for warning in check_config(cfg, overrides):
        log.warning(warning)
    seed_everything(cfg.seed)
    if cfg.get("study") is not None:
        return call(cfg.study, cfg, output_dir)
    datamodule = instantiate(cfg.data).setup()
    pipeline = run_classification if getattr(datamodule, "task", "regression") == "classification" else run_regression
    return pipeline(cfg, output_dir, datamodule)
