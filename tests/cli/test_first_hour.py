"""A new user's first hour: threads as a setting, config mistakes in one line before start-up,
run folders that tell the truth, progress that suits where it goes, predictions.csv as a sample
input for predict.py."""
import logging
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch
import yaml
from tests.conftest import tiny

from common.errors import InputError
from common.progress import phase, progress
from common.threads import apply_threads, configured_threads, resolve_threads
from runs.config_checks import check_target_keys, target_parameters

ROOT = Path(__file__).resolve().parents[2]


def train(*overrides, cwd, env=None):
    return subprocess.run([sys.executable, str(ROOT / "train.py"), *overrides], capture_output=True, text=True,
                          cwd=cwd, timeout=600, env=dict(os.environ, CI="true", **(env or {})))


# -- threads ----------------------------------------------------------------------------------

@pytest.mark.parametrize("setting, expected", [(1, 1), ("3", 3), (2.0, 2), ("all", os.cpu_count() or 1)])
def test_thread_settings_resolve(setting, expected):
    assert resolve_threads(setting) == expected


@pytest.mark.parametrize("setting", [0, -1, 0.5, "abc", "", None, True])
def test_impossible_thread_settings_are_input_errors(setting):
    with pytest.raises(InputError, match="threads must be a positive integer or 'all'"):
        resolve_threads(setting)


def test_all_threads_are_shared_among_parallel_jobs():
    assert resolve_threads("all", parallel_jobs=os.cpu_count() or 1) == 1
    assert resolve_threads("all", parallel_jobs=10_000) == 1


def test_applying_threads_sets_every_library_and_child_processes():
    before = torch.get_num_threads()
    try:
        apply_threads(1)
        assert torch.get_num_threads() == 1 and configured_threads() == 1
        assert os.environ["OMP_NUM_THREADS"] == os.environ["OPENBLAS_NUM_THREADS"] == "1"
        child = subprocess.run([sys.executable, "-c", "import os; print(os.environ['TOUCHSTONE_THREADS'])"],
                               capture_output=True, text=True)
        assert child.stdout.strip() == "1"
    finally:
        torch.set_num_threads(before)


# -- config mistakes: one line, exit 2, before heavy imports ----------------------------------

def test_target_parameters_are_read_from_source_without_importing():
    assert "n_samples" in target_parameters("data.scenes.rubber12.Rubber12Scene")
    assert target_parameters("sklearn.svm.SVR") is None             # not ours: left to instantiation
    assert target_parameters("data.scenes.rubber12.NoSuchThing") is None


def test_a_key_the_target_does_not_take_is_named(compose_config):
    cfg = compose_config(["+scene.sparkle=1"])
    with pytest.raises(InputError, match=r"^scene has no parameter 'sparkle' \(valid: n_samples, "):
        check_target_keys(cfg)
    check_target_keys(compose_config([]))                               # the default config is clean


@pytest.mark.parametrize("overrides, message", [
    (["+scene.sparkle=1"], "error: scene has no parameter 'sparkle'"),
    (["data=table"], "error: data.path needs a value (add data.path=...)"),
    (["data.n_folds=0"], "error: data.n_folds must be an integer >= 2"),
    (["data.test_fraction=0.6", "data.val_fraction=0.5"], "must be below 1 (training needs rows), got 1.25"),
    (["data.val_fraction=-0.1"], "error: data.val_fraction must lie in (0, 1), got -0.1"),
    (["threads=0"], "error: threads must be a positive integer or 'all', got 0"),
    (["scen=1"], "error: scen is not a setting; did you mean scene?"),
])
def test_config_mistakes_are_one_line_exit_2_and_no_run_folder(tmp_path, overrides, message):
    result = train(*overrides, f"hydra.run.dir={tmp_path / 'run'}", cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [result.stderr.strip()] and message in result.stderr
    assert not (tmp_path / "run").exists()                              # found before Hydra made a folder
    assert "Traceback" not in result.stdout + result.stderr


# -- run folders ------------------------------------------------------------------------------

def test_runs_started_together_get_their_own_folders_and_failures_say_so(tmp_path):
    """Two runs started in the same second (no hydra.run.dir given): each has its own folder whose
    .hydra/ describes it; a run failing on a value its scene checks leaves error.txt and a log
    ending in the error, and nothing that looks finished."""
    env = dict(os.environ, CI="true")
    runs = [subprocess.Popen([sys.executable, str(ROOT / "train.py"), f"scene.n_samples={-k}", "model=decision_tree"],
                             cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            for k in (1, 2)]
    outputs = [run.communicate(timeout=600) for run in runs]
    assert [run.returncode for run in runs] == [2, 2], outputs
    folders = sorted(p for p in (tmp_path / "outputs").glob("*/*") if p.is_dir())
    assert len(folders) == 2
    for folder in folders:
        overrides = yaml.safe_load((folder / ".hydra" / "overrides.yaml").read_text())
        samples = next(o for o in overrides if o.startswith("scene.n_samples="))
        error = (folder / "error.txt").read_text().strip()
        assert error == f"scene.n_samples must be a positive integer, got {samples.split('=')[1]}"
        assert (folder / "train.log").read_text().strip().endswith(error)
        assert not (folder / "metrics.json").exists() and not (folder / "model.onnx").exists()


# -- progress ---------------------------------------------------------------------------------

def test_progress_off_a_terminal_is_one_line_per_loop(caplog, monkeypatch):
    monkeypatch.setenv("CI", "true")
    with caplog.at_level(logging.INFO, logger="touchstone"):
        total = 0
        for value in progress(range(5), desc="folds", unit="folds"):
            total += value
            if value == 3:
                break
        bar = progress(total=10, desc="presses", unit="presses")
        bar.update(4)
        bar.update(6)
        bar.set_postfix(loss=0.5)
        bar.close()
        bar.close()                                                     # closing twice logs once
        for _ in progress(range(3), desc="silent", enabled=False):
            pass
        with phase("export"):
            pass
    lines = [r.getMessage() for r in caplog.records]
    assert total == 6
    assert [line.split(" in ")[0] for line in lines] == ["folds: 4 folds", "presses: 10 presses", "export ...",
                                                          "export: done"]
    assert lines[1].endswith("(loss=0.5)") and all("\r" not in line for line in lines)


# -- predictions.csv is a sample input for predict.py ----------------------------------------

def predict_own_test_rows(run: Path, output: Path) -> None:
    """predict.py on a run's own predictions.csv (a ready input: it holds the raw readings)."""
    predicted = subprocess.run([sys.executable, str(ROOT / "predict.py"), f"model={run / 'model.onnx'}",
                                f"input={run / 'predictions.csv'}", f"output={output}"],
                               capture_output=True, text=True, cwd=output.parent, timeout=300)
    assert predicted.returncode == 0, predicted.stderr


def test_predictions_csv_feeds_predict_py_with_the_same_columns(tmp_path):
    run = tmp_path / "run"
    result = train(*tiny("extra_trees"), f"hydra.run.dir={run}", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    predict_own_test_rows(run, tmp_path / "pred.csv")
    ours, theirs = pd.read_csv(run / "predictions.csv"), pd.read_csv(tmp_path / "pred.csv")
    targets = ["x_mm", "y_mm", "depth_mm", "pressure_pa"]
    assert list(theirs.columns) == targets
    assert {f"r_{k:02d}_ohm" for k in range(1, 13)} | set(targets) | {f"true_{t}" for t in targets} <= set(ours)
    np.testing.assert_allclose(theirs[targets].to_numpy(), ours[targets].to_numpy(), rtol=1e-4, atol=1e-3)


def test_a_long_loop_off_a_terminal_says_how_far_it_is(caplog, monkeypatch):
    monkeypatch.setenv("CI", "true")
    monkeypatch.setattr("common.progress.HEARTBEAT_S", 0.0)    # every round counts as long
    with caplog.at_level(logging.INFO, logger="touchstone"):
        for _ in progress(range(3), desc="epochs", unit="epochs"):
            pass
    lines = [r.getMessage() for r in caplog.records]
    assert [line.split(" so far")[0] for line in lines[:3]] == ["epochs: 1/3 epochs", "epochs: 2/3 epochs",
                                                               "epochs: 3/3 epochs"]
    assert lines[3].startswith("epochs: 3 epochs in ")


def _predicted_columns(frame: pd.DataFrame, channels: list[str]) -> list[str]:
    """predictions.csv's columns after the row id and the channels, before the truth."""
    return [c for c in frame.columns if c not in ("row", "split", *channels) and not c.startswith("true")]


@pytest.mark.parametrize("kind", ["intervals", "classes"])
def test_predictions_csv_has_exactly_predict_pys_columns_in_its_order(tmp_path, kind):
    """README "What a run writes": the prediction columns of predictions.csv are predict.py's, by name
    and order (before: each target's bounds followed it, where predict.py writes every target first)."""
    run = tmp_path / "run"
    if kind == "intervals":
        overrides, channels = tiny("blend"), [f"r_{k:02d}_ohm" for k in range(1, 13)]
    else:
        rng = np.random.default_rng(0)
        region = rng.integers(0, 3, 150)
        channels = ["r_01_ohm", "r_02_ohm"]
        pd.DataFrame({"r_01_ohm": 1000 + 200 * region + rng.normal(0, 50, 150), "r_02_ohm": rng.normal(900, 30, 150),
                      "region": np.array(["left", "middle", "right"])[region]}).to_csv(tmp_path / "pads.csv", index=False)
        overrides = ["data=table", f"data.path={tmp_path / 'pads.csv'}", "data.target_columns=[region]",
                     "model=logistic_regression"]
    result = train(*overrides, f"hydra.run.dir={run}", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    predict_own_test_rows(run, tmp_path / "pred.csv")
    ours, theirs = pd.read_csv(run / "predictions.csv"), pd.read_csv(tmp_path / "pred.csv")
    assert _predicted_columns(ours, channels) == list(theirs.columns)
    if kind == "intervals":
        assert list(theirs.columns)[4:6] == ["x_mm_lower95", "x_mm_upper95"]
