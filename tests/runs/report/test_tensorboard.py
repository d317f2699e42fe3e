"""TensorBoard reads at a glance, and every exported run records its latency: the run list as
TensorBoard builds it (one run per training run, named for what ran, its hyper-parameters inside
it), a blend's members' curves under the blend's run, and a sweep's Pareto report with a
latency for every configuration."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator
from tensorboard.backend.event_processing.event_multiplexer import EventMultiplexer
from tensorboard.plugins.hparams import metadata

from models.kfold_blend import KFoldBlend
from models.resmlp_regressor import ResMLPRegressor
from models.trees import TreeRegressor
from models.weighted_blend import ValidationWeightedBlend
from runs.report.tensorboard_logger import TEXT_LIMIT, TensorBoardLogger, flat_hparams

ROOT = Path(__file__).resolve().parents[3]
QUICK = ["scene.n_samples=120", "scene.grid_nodes=21", "scene.progress=false", "analysis.progress=false"]


def session_hparams(run_dir) -> dict:
    """The hyper-parameters of a run's own event file, as TensorBoard's HPARAMS tab reads them."""
    content = EventAccumulator(str(run_dir)).Reload().PluginTagToContent(metadata.PLUGIN_NAME)
    start = metadata.parse_session_start_info_plugin_data(content[metadata.SESSION_START_INFO_TAG])
    return {name: value.WhichOneof("kind") for name, value in start.hparams.items()}


def test_hparams_are_flattened_to_numbers_and_short_strings():
    flat = flat_hparams({"seed": 3, "model": {"_target_": "models.weighted_blend.ValidationWeightedBlend",
                                              "_convert_": "all", "per_target": True, "seed": None,
                                              "candidates": {"resmlp": {"estimator": {"widths": list(range(100)),
                                                                                      "lr": 1e-3}}}}})
    assert flat["seed"] == 3 and flat["model.candidates.resmlp.estimator.lr"] == 1e-3
    assert flat["model._target_"] == "ValidationWeightedBlend" and "model._convert_" not in flat
    assert flat["model.per_target"] == "True" and flat["model.seed"] == "None"
    widths = flat["model.candidates.resmlp.estimator.widths"]
    assert len(widths) == TEXT_LIMIT and widths.startswith("[0, 1, 2") and widths.endswith("(100 items)")
    assert all(isinstance(v, (int, float, str)) and not isinstance(v, bool) for v in flat.values())


def test_every_member_of_a_blend_logs_its_curves_under_the_blend_run(tmp_path):
    rng = np.random.default_rng(0)
    X, y = rng.normal(size=(80, 4)), rng.normal(size=(80, 2))
    net = ResMLPRegressor(widths=(8,), dropouts=(0.1,), max_epochs=3, batch_size=16, early_stopping_patience=None,
                          progress=False)
    blend = ValidationWeightedBlend(candidates={
        "resmlp": KFoldBlend(net, n_folds=2, progress=False),
        "resmlp_alone": net,
        "tree": TreeRegressor(kind="decision_tree", max_depth=3)})
    with TensorBoardLogger(str(tmp_path / "run")) as logger:
        blend.fit(X[:60], y[:60], X[60:], y[60:], epoch_callback=logger.log_epoch)
    scalars = EventAccumulator(str(tmp_path / "run")).Reload()
    tags = set(scalars.Tags()["scalars"])
    for member in ("resmlp/fold0", "resmlp/fold1", "resmlp_alone"):
        steps = [e.step for e in scalars.Scalars(f"members/{member}/loss/train")]
        assert steps == [1, 2, 3], member
        assert {f"members/{member}/loss/val", f"members/{member}/lr"} <= tags
    assert not any(t.startswith(("loss/", "members/tree")) for t in tags)  # every curve says whose it is
    assert [p.name for p in tmp_path.iterdir()] == ["run"]                # one run, no sub-runs


def test_a_sweep_and_a_run_list_one_named_run_each_with_latency_in_every_report(tmp_path):
    """`tensorboard --logdir` a folder holding outputs/ and multirun/ lists every run once, named
    by what ran; every exported run's metrics.json holds its onnxruntime latency and size, and
    the sweep's pareto.csv a latency for every configuration."""
    sweep = [sys.executable, "train.py", "-m", "model=decision_tree,linear_regression", *QUICK,
             f"hydra.sweep.dir={tmp_path / 'multirun' / 'sweep'}"]
    single = [sys.executable, "train.py", "model=decision_tree", "seed=2", *QUICK,
              f"hydra.run.dir={tmp_path / 'outputs' / 'day' / 'run'}"]
    for command in (sweep, single):
        done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr[-2000:]

    runs = EventMultiplexer().AddRunsFromDirectory(str(tmp_path)).Reload().Runs()  # TensorBoard's run list
    assert sorted(runs) == sorted([
        "outputs/day/run/tensorboard/rubber12·decision_tree·seed2",
        "multirun/sweep/0/tensorboard/rubber12·decision_tree·seed0·trial0",
        "multirun/sweep/1/tensorboard/rubber12·linear_regression·seed0·trial1"])
    for run in runs:
        hparams = session_hparams(tmp_path / run)  # inside the run's own event file
        assert {"seed", "model", "model.kind", "data.split"} <= set(hparams), run
        assert set(hparams.values()) <= {"number_value", "string_value"}
        assert "hparam/val_r2" in runs[run]["scalars"] and "cost/latency_p50_us/onnx_1_thread" in runs[run]["scalars"]

    job = json.loads((tmp_path / "outputs" / "day" / "run" / "metrics.json").read_text())
    latency = job["cost"]["latency_batch1_us"]["onnx_1_thread"]
    assert 0 < latency["p50"] <= latency["p99"] and latency["reps"] == 100
    assert job["cost"]["model_size_bytes"] == (tmp_path / "outputs" / "day" / "run" / "model.onnx").stat().st_size
    pareto = pd.read_csv(tmp_path / "multirun" / "sweep" / "pareto.csv")
    assert len(pareto) == 2 and (pareto["latency_p50_us_mean"] > 0).all() and (pareto["model_size_bytes_mean"] > 0).all()
