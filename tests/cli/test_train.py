"""End to end through Hydra: every model config composes with tiny settings and a run writes
every output; bad configs fail with one line and a non-zero exit."""
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from tests.conftest import tiny
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from runs.report.metrics_file import json_safe
from runs.run import run

ROOT = Path(__file__).resolve().parents[2]
CLASSIFIERS = {"prcnn", "rescnn", "inceptiontime", "lstm_fcn",   # tested in tests/models/nets/test_nets.py
               "inceptiontime_ensemble",                          # its averaging in tests/models/nets/test_recipes.py
               "fcn"}                                             # a new module by one file: tests/models/test_bring_your_own.py
ROCKET_CLASSIFIERS = {"minirocket", "hydra_minirocket", "rocket_mixture"}   # tested in tests/runs/test_rocket_runs.py,
                                                                   # tests/models/rocket/test_hydra.py, test_mixture.py
TABLE_CLASSIFIERS = {"mlp", "logistic_regression"}                # tested in tests/runs/test_table_classification.py
LIBRARY_CLASSIFIERS = {"gradient_boosting"}                       # by its YAML alone: tests/models/test_bring_your_own.py
MODELS = sorted(p.stem for p in (ROOT / "configs" / "model").glob("*.yaml")
                if p.stem not in CLASSIFIERS | ROCKET_CLASSIFIERS | TABLE_CLASSIFIERS | LIBRARY_CLASSIFIERS)
# common/atomic.py renders each output into tempfile.mkstemp(prefix=f".{name}.", suffix=suffix) in
# the output's folder: ".metrics.json.k2x9_a1b.json", ".parity.png.q0w8r7t6.png". A hidden
# name, then more name, a dot and more: what a crashed or forgotten atomic write leaves behind.
ATOMIC_TEMP_GLOB = ".?*.?*"


def atomic_leftovers(folder: Path) -> list[Path]:
    return [p for p in folder.rglob(ATOMIC_TEMP_GLOB) if p.is_file()]


def test_every_model_config_is_tested(compose_config):
    """Every configs/model/*.yaml trains in a parametrised run test: the regression models below,
    the time-series classifiers (which need recordings) in tests/models/nets/test_nets.py (prcnn through the
    textures13 experiment, the others in test_baselines_train_through_hydra), the table
    classifiers in tests/runs/test_table_classification.py. A classifier
    listed as a regression model, or the reverse, fails here."""
    for name in sorted(p.stem for p in (ROOT / "configs" / "model").glob("*.yaml")):
        overrides = [f"model={name}"] + (["experiment=materials10"] if name in CLASSIFIERS | ROCKET_CLASSIFIERS else [])
        target = compose_config(overrides).model._target_
        assert target.endswith("TimeSeriesClassifier") == (name in CLASSIFIERS), (name, target)
        assert target.endswith("RocketClassifier") == (name in ROCKET_CLASSIFIERS), (name, target)
        assert target.endswith("TableClassifier") == (name in TABLE_CLASSIFIERS), (name, target)
        assert target.endswith("Classifier") == (name in CLASSIFIERS | ROCKET_CLASSIFIERS | TABLE_CLASSIFIERS
                                                  | LIBRARY_CLASSIFIERS), (name, target)
    assert {"resmlp", "random_forest", "extra_trees", "decision_tree", "blend"} <= set(MODELS)


@pytest.mark.parametrize("model", MODELS)
def test_a_run_writes_every_output(compose_config, tmp_path, model):
    cfg = compose_config(tiny(model))
    # The leftover check below must be able to fail: a temp name made by common/atomic.py's rule
    # for each kind of output is caught by it.
    for name in ("metrics.json", "predictions.csv", "parity.png", "pipeline.npz"):
        target = tmp_path / name
        fd, temp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=target.suffix, dir=target.parent)
        os.close(fd)
        assert atomic_leftovers(tmp_path) == [Path(temp)], temp
        Path(temp).unlink()
    metrics = run(cfg, tmp_path)

    figures = {"parity", "residuals"}
    if model in ("random_forest", "extra_trees", "decision_tree"):
        figures |= {"importances", "correlation"}
    if model == "blend":
        figures |= {"importances", "correlation", "uncertainty", "identifiability"}
    if model == "auto":   # the chosen candidate's figures: a blend's, a seed ensemble's intervals, or a net's
        figures |= {"kfold_blend": {"importances", "correlation", "uncertainty", "identifiability"},
                    "resmlp_seeds": {"uncertainty", "identifiability"}, "resmlp": set()}[metrics["choice"]["chosen"]]
    for name in ["metrics.json", "predictions.csv"] + [f"{f}.png" for f in figures]:
        assert (tmp_path / name).stat().st_size > 0, name
    assert atomic_leftovers(tmp_path) == []  # no temp file of an atomic write is left behind
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert saved["fit_time_s"] > 0
    for split in ("val", "test"):
        assert set(saved[split]) == {"x_mm", "y_mm", "depth_mm", "pressure_pa", "average"}
        assert set(saved[split]["average"]) == {"r2", "mape_pct"}  # only unitless scores are averaged
    assert saved == json_safe(metrics)  # strict JSON: a value not defined (NaN) is written as null
    assert "NaN" not in (tmp_path / "metrics.json").read_text()

    predictions = pd.read_csv(tmp_path / "predictions.csv")
    assert len(predictions) == saved["data"]["n_test"]
    assert {"true_depth_mm", "depth_mm", "true_pressure_pa", "pressure_pa", "r_01_ohm"} <= set(predictions)

    (run_events,) = (tmp_path / "tensorboard").iterdir()  # one TensorBoard run, named for what ran
    events = EventAccumulator(str(run_events)).Reload()
    scalars = events.Tags()["scalars"]
    assert "test/x_mm/r2" in scalars and "cost/fit_time_s" in scalars
    assert set(events.Tags()["images"]) == {f"figures/{f}" for f in figures}
    if model in ("resmlp", "blend"):
        curves = "members/resmlp/fold0/" if model == "blend" else ""  # a blend's net: each fold's curves
        losses = events.Scalars(f"{curves}loss/train")
        assert [e.step for e in losses] == list(range(1, len(losses) + 1)) and len(losses) >= 2
        assert len(events.Scalars(f"{curves}loss/val")) == len(losses) and f"{curves}lr" in scalars
    assert "_hparams_/session_start_info" in events.PluginTagToContent("hparams")
    if model == "blend":
        weights = saved["selection"]["weights"]
        for target in ("x_mm", "depth_mm"):
            assert sum(w[target] for w in weights.values()) == pytest.approx(1.0)
        assert set(saved["uncertainty"]["coverage_calibrated"]) == {"x_mm", "y_mm", "depth_mm", "pressure_pa"}
        assert {"x_mm_lower95", "x_mm_upper95"} <= set(predictions)
        assert set(saved["ablation"]["delta_r2_without"]) == {"raw", "log1p", "sqrt", "zscore", "stats",
                                                            "pair_products", "pair_ratios"}
        assert np.isfinite(np.asarray(saved["identifiability"]["position_sigma_mm"], dtype=float)).any()
        assert "uncertainty/coverage_calibrated/x_mm" in scalars


def test_a_users_table_runs_like_a_scene(compose_config, tmp_path):
    from data.scenes.rubber12 import Rubber12Scene
    table = Rubber12Scene(n_samples=120, grid_nodes=21, progress=False,
                          effects={"contact": {}, "percolation": {}, "adc": {}}).generate()
    path = tmp_path / "rig.parquet"
    table.frame.to_parquet(path)
    cfg = compose_config(tiny("extra_trees") + ["data=table", f"data.path={path}", "data.split=grouped",
                                                "data.target_columns=[x_mm,y_mm,depth_mm,pressure_pa]"])
    metrics = run(cfg, tmp_path / "run")
    assert metrics["data"]["split"] == "grouped" and metrics["data"]["source"]["path"] == str(path)
    assert (tmp_path / "run" / "metrics.json").exists()


def train(*overrides, cwd):
    return subprocess.run([sys.executable, str(ROOT / "train.py"), *overrides, f"hydra.run.dir={cwd}/run"],
                          capture_output=True, text=True, cwd=cwd, timeout=300)


@pytest.mark.parametrize("overrides, message, code", [
    (["model=gradient_magic"], "Could not find 'model/gradient_magic' Available options in 'model': auto blend", 2),
    (["scene.n_samples=-5"], "error: scene.n_samples must be a positive integer, got -5", 2),
    (["scene.sparkle=1"], "Could not override 'scene.sparkle'", 2),
    (["+scene.effects.sparkle={}"], "error: scene rubber12: unknown effect 'sparkle'", 2),
    (["scene=fingertip"], "error: scene fingertip produces a RecordingSet, not one row per press; for recordings use data=timeseries", 2),
])
def test_bad_config_values_fail_with_a_clear_message(tmp_path, overrides, message, code):
    result = train(*overrides, cwd=tmp_path)
    assert result.returncode == code, result.stderr
    assert message in result.stderr
    assert "Traceback" not in result.stderr
    assert not (tmp_path / "run" / "metrics.json").exists()
    assert result.stderr.strip().count("\n") == 0  # exactly one line


def snapshot(folder: Path) -> dict[str, bytes | None]:
    """Every path under `folder` with its content (None for a folder)."""
    return {str(p.relative_to(folder)): (p.read_bytes() if p.is_file() else None) for p in folder.rglob("*")}


def test_train_py_writes_under_the_run_dir_only(tmp_path):
    # A user's working directory with their own files in it, and a run dir elsewhere: train.py
    # must leave the working directory exactly as it was and put every output in the run dir.
    work, runs = tmp_path / "work", tmp_path / "runs"
    (work / "data").mkdir(parents=True)
    (work / "notes.txt").write_text("my notes\n")
    (work / "data" / "rig.csv").write_text("r_01_ohm\n1.0\n")
    before = snapshot(work)
    result = subprocess.run([sys.executable, str(ROOT / "train.py"), *tiny("decision_tree"), "cost.budget_s=0.05",
                             f"hydra.run.dir={runs}/run"], capture_output=True, text=True, cwd=work, timeout=300)
    assert result.returncode == 0, result.stderr
    assert snapshot(work) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["runs", "work"]
    assert sorted(p.name for p in runs.iterdir()) == ["run"]
    run_dir = runs / "run"
    assert (run_dir / "metrics.json").exists() and (run_dir / ".hydra" / "config.yaml").exists()
    assert (run_dir / "model.onnx").stat().st_size > 0  # export=onnx is on by default
    assert atomic_leftovers(run_dir) == []


@pytest.mark.parametrize("failing_step, overrides", [
    ("export", ["export.opset=1"]),                               # no ONNX exporter supports opset 1
    ("cost measurement", ["cost.measure_latency=true", "cost.budget_s=-1", "export=none"]),  # a negative budget is refused
])
def test_a_run_that_fails_late_leaves_nothing_that_looks_finished(tmp_path, failing_step, overrides):
    run_dir = tmp_path / "run"
    result = subprocess.run([sys.executable, str(ROOT / "train.py"), *tiny("decision_tree"), *overrides,
                             f"hydra.run.dir={run_dir}"], capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert result.returncode != 0, f"the {failing_step} step did not fail"
    left = sorted(p.name for p in run_dir.iterdir())
    assert "error.txt" in left and (run_dir / "error.txt").read_text().strip()
    # training and the report succeeded before the failure, yet no finished-run artefact is left
    for artefact in ("metrics.json", "pipeline.npz", "model.onnx", "predictions.csv", "tensorboard", ".staging"):
        assert artefact not in left, (failing_step, left)
