"""What a run's predictions cost. Every run that exports a model records the file's size and its
batch-1 latency in onnxruntime on one thread (p50 and p99 over a fixed number of calls,
`cost.onnx_latency_calls`), so every sweep's Pareto report has a latency for every job. With
`cost.measure_latency` (extras=thorough) the comparison instead: latency at batch 1 and
throughput at batch 1024, eager and in onnxruntime (one intra-op thread and its default), with
the thread settings and core count.

Measured in-process on the run's own raw test inputs, after warm-up; the comparison repeats
calls until a time budget is spent (at least 5 calls; slow eager pipelines get fewer
repetitions, recorded as `reps`). runs/run.py adds them to the run's metrics before
metrics.json is written.

A fair eager baseline: the eager pipeline is timed as a deployed user would call it, in-process,
with every scikit-learn estimator inside it (forests included) predicting on one job
(`n_jobs=1`): at batch 1, joblib's dispatch to a thread pool costs more than the trees
themselves, and models/trees.py already predicts on one job after fitting. The metrics say so
(`cost.eager_baseline`).
"""
import logging
import os
import time
from pathlib import Path

import numpy as np
import torch

from common.errors import InputError
from common.progress import progress
from export.onnx_predictor import OnnxPredictor

log = logging.getLogger(__name__)


def latency_us(call, sample, budget_s: float = 1.0, min_reps: int = 5, max_reps: int = 500) -> dict:
    for _ in range(2):
        call(sample)
    times, spent = [], 0.0
    while len(times) < max_reps and (len(times) < min_reps or spent < budget_s):
        start = time.perf_counter()
        call(sample)
        times.append(time.perf_counter() - start)
        spent += times[-1]
    return {"p50": 1e6 * float(np.percentile(times, 50)), "p99": 1e6 * float(np.percentile(times, 99)), "reps": len(times)}


def throughput_per_s(call, batch, budget_s: float = 1.0) -> float:
    call(batch)
    count, start = 0, time.perf_counter()
    while count == 0 or time.perf_counter() - start < budget_s:
        call(batch)
        count += 1
    return count * len(batch) / (time.perf_counter() - start)


EAGER_BASELINE = ("in-process numpy features + the fitted estimator; scikit-learn estimators (forests "
                  "included) predict with n_jobs=1, torch with torch_threads threads")


def single_job(model, seen=None) -> int:
    """Set n_jobs=1 on every scikit-learn estimator reachable from `model` (its attributes, lists
    and dicts of estimators: blends, k-fold copies, MultiOutputRegressor); returns how many had an
    n_jobs setting."""
    seen = set() if seen is None else seen
    if id(model) in seen or isinstance(model, (str, bytes, int, float, np.ndarray)) or model is None:
        return 0
    seen.add(id(model))
    count = 0
    if "n_jobs" in getattr(model, "__dict__", {}):   # (only ours and scikit-learn's objects are walked, below)
        model.n_jobs = 1
        count += 1
    children = model.values() if isinstance(model, dict) else model if isinstance(model, (list, tuple)) else \
        getattr(model, "__dict__", {}).values()
    for child in children:  # ours and scikit-learn's objects only (not torch modules' internals)
        if isinstance(child, (list, tuple, dict)) or type(child).__module__.split(".")[0] in ("sklearn", "models"):
            count += single_job(child, seen)
    return count


def _onnx_call(model_path, threads: int):
    """The exported model's own entry for one batch: windows or rows, as its metadata says."""
    predictor = OnnxPredictor(model_path, threads=threads)
    return predictor.predict_windows if predictor.reads_windows else predictor.predict_array


def measure(pipeline, model_path=None, budget_s: float = 1.0, compare: bool = True, calls: int = 100) -> dict:
    """What predictions cost. Always, when the run exported model_path: its size and its batch-1
    latency in onnxruntime on one thread, p50 and p99 of `calls` calls after warm-up (cheap enough
    for every run; 0 calls: the size only). With `compare`, instead of those calls: latency and
    throughput of the eager pipeline and of onnxruntime on one thread and on its default,
    `budget_s` seconds of calls per figure."""
    if compare and not budget_s > 0:
        raise InputError(f"cost.budget_s must be a positive number of seconds, got {budget_s}")
    exported = model_path is not None and Path(model_path).is_file()
    cost = {"cores": os.cpu_count(), **({"model_size_bytes": Path(model_path).stat().st_size} if exported else {})}
    if pipeline.examples is None or len(pipeline.examples) == 0:
        return cost
    one = pipeline.examples[:1]
    if not compare:
        if exported and calls > 0:
            cost["onnx_threads"] = {"onnx_1_thread": 1}
            cost["latency_batch1_us"] = {"onnx_1_thread": latency_us(_onnx_call(model_path, 1), one, 0.0,
                                                                     min_reps=calls, max_reps=calls)}
        return cost
    batch = np.resize(pipeline.examples, (1024,) + pipeline.examples.shape[1:])
    n_single = single_job(getattr(pipeline, "model", None))
    runners = {"eager": pipeline.predict_raw}
    if exported:
        for name, threads in (("onnx_1_thread", 1), ("onnx_default", 0)):
            runners[name] = _onnx_call(model_path, threads)
    cost.update({"torch_threads": torch.get_num_threads(), "eager_baseline": EAGER_BASELINE,
                 "eager_estimators_set_to_one_job": n_single,
                 "onnx_threads": {"onnx_1_thread": 1, "onnx_default": "onnxruntime default (all cores)"},
                 "latency_batch1_us": {}, "throughput_batch1024_per_s": {}})
    for name, call in progress(runners.items(), desc="latency", unit="runtimes"):
        cost["latency_batch1_us"][name] = latency_us(call, one, budget_s)
        cost["throughput_batch1024_per_s"][name] = throughput_per_s(call, batch, budget_s)
    return cost


def log_costs(cost: dict, logger=None) -> None:
    """The costs as TensorBoard scalars (through the run's one logger) and one log line."""
    latency = cost.get("latency_batch1_us", {})
    if logger is not None:
        for name, values in latency.items():
            logger.writer_.add_scalar(f"cost/latency_p50_us/{name}", values["p50"])
            logger.writer_.add_scalar(f"cost/latency_p99_us/{name}", values["p99"])
        for name, value in cost.get("throughput_batch1024_per_s", {}).items():
            logger.writer_.add_scalar(f"cost/throughput_per_s/{name}", value)
        if "model_size_bytes" in cost:
            logger.writer_.add_scalar("cost/model_size_bytes", cost["model_size_bytes"])
    log.info("cost: fit %.2f s wall, %.2f s CPU; batch-1 latency p50 %s; %d cores",
             cost.get("fit_time_s", float("nan")), cost.get("fit_cpu_time_s", float("nan")),
             ", ".join(f"{k} {v['p50']:,.0f} us" for k, v in latency.items()), cost.get("cores", 0))
