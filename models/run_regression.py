"""One regression run, end to end: datamodule -> model -> metrics -> TensorBoard -> files.

train.py calls `run(cfg, output_dir)`; tests call it too with a composed config and a
tmp_path. Every artefact goes under `output_dir` and is written atomically.
"""
import logging
import random
import time
from pathlib import Path

import numpy as np
import pandas as pd
import torch
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from data.atomic import atomic_write, atomic_write_json
from models.metrics import format_table, regression_metrics
from models.plots import parity_figure

log = logging.getLogger(__name__)


def seed_everything(seed: int) -> None:
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)


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


def run(cfg: DictConfig, output_dir: str | Path) -> dict:
    output_dir = Path(output_dir)
    seed_everything(cfg.seed)

    datamodule = instantiate(cfg.data).setup()
    (X_train, y_train), (X_val, y_val), (X_test, y_test) = datamodule.train, datamodule.val, datamodule.test
    targets = datamodule.target_names
    log.info("data: %s", {k: v for k, v in datamodule.summary().items() if k != "source"})

    model = instantiate(cfg.model)
    with instantiate(cfg.logger, log_dir=str(output_dir / "tensorboard")) as logger:
        start = time.perf_counter()
        model.fit(X_train, y_train, X_val, y_val, epoch_callback=logger.log_epoch)
        fit_time_s = time.perf_counter() - start

        pred_val, pred_test = model.predict(X_val), model.predict(X_test)
        metrics = {
            "model": model.__class__.__name__,
            "val": regression_metrics(y_val, pred_val, targets),
            "test": regression_metrics(y_test, pred_test, targets),
            "fit_time_s": fit_time_s,
            **_model_size(model),
            "data": datamodule.summary(),
        }
        logger.log_metrics(metrics["val"], "val")
        logger.log_metrics(metrics["test"], "test")
        logger.writer_.add_scalar("cost/fit_time_s", fit_time_s)
        figure = parity_figure(y_test, pred_test, targets, {t: metrics["test"][t]["r2"] for t in targets})
        logger.log_figure("parity/test", figure)
        logger.log_hparams(_hparams(cfg), {"hparam/val_r2": metrics["val"]["average"]["r2"],
                                           "hparam/test_r2": metrics["test"]["average"]["r2"],
                                           "hparam/fit_time_s": fit_time_s})

    frame = pd.DataFrame({**{f"true_{t}": y_test[:, k] for k, t in enumerate(targets)},
                          **{f"pred_{t}": pred_test[:, k] for k, t in enumerate(targets)}})
    frame.insert(0, "row", datamodule.test_idx)
    atomic_write(output_dir / "predictions.csv", lambda tmp: frame.to_csv(tmp, index=False))
    atomic_write(output_dir / "parity.png", lambda tmp: figure.savefig(tmp, dpi=110, format="png"))
    atomic_write_json(output_dir / "metrics.json", metrics)

    log.info("%s fitted in %.2f s\n%s", metrics["model"], fit_time_s, format_table(metrics))
    log.info("outputs in %s", output_dir)
    return metrics
