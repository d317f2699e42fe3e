"""metrics.json: the one writer, called once per run after every number (fit, evaluation,
export, latency) has joined the metrics; and the same numbers as TensorBoard scalars and a short
summary on the console, so every run type (pipelines and studies) speaks the same way.

Strict JSON: numpy numbers become Python numbers, a non-finite value becomes null (not defined),
tuples become lists. Values that are a mean with its spread are written as
{"mean": ..., "sd": ..., "n": ...}.
"""
import logging
from pathlib import Path

import numpy as np

from common.atomic import atomic_write_json
from common.spread import mean_and_sd

log = logging.getLogger("touchstone")
METRICS_FILE = "metrics.json"
SUMMARY_LINES = 24   # a study's console summary: its first numbers, the rest is in metrics.json


def json_safe(value):
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [json_safe(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if np.isfinite(value) else None
    return value


def mean_sd(values) -> dict:
    """The record metrics.json keeps of repeated measurements, {"mean", "sd", "n"}: common/spread.py's
    mean and sd (ddof 1; 0 for one value) with how many there were."""
    mean, sd = mean_and_sd(values)
    return {"mean": mean, "sd": sd, "n": int(np.size(values))}


def numbers(metrics: dict, prefix: str = ""):
    """(path, value) of every finite number in nested metrics, depth first."""
    for key, value in metrics.items():
        path = f"{prefix}/{key}" if prefix else str(key)
        if isinstance(value, dict):
            yield from numbers(value, path)
        elif isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_)) \
                and np.isfinite(value):
            yield path, float(value)


def write_metrics(output_dir, metrics: dict, logger=None) -> Path:
    """Write metrics.json atomically; a study's numbers also go to TensorBoard (`results/...`)
    and a short summary to the console (the pipelines' reports log their own tables)."""
    path = atomic_write_json(Path(output_dir) / METRICS_FILE, json_safe(metrics))
    if "choice" in metrics and logger is not None:   # what the default model chose and why (models/validation_choice.py)
        logger.log_text("choice/reason", metrics["choice"]["reason"])
        for tag, value in numbers(metrics["choice"]["validation"], "choice/validation"):
            logger.writer_.add_scalar(tag, value)
    if "study" in metrics:
        found = list(numbers({k: v for k, v in metrics.items() if k != "study"}))
        if logger is not None:
            for tag, value in found:
                logger.writer_.add_scalar(f"results/{tag}", value)
        shown = "\n".join(f"  {tag}: {value:.4g}" for tag, value in found[:SUMMARY_LINES])
        more = f"\n  ... {len(found) - SUMMARY_LINES} more in {path.name}" if len(found) > SUMMARY_LINES else ""
        log.info("%s results:\n%s%s", metrics["study"], shown, more)
    return path
