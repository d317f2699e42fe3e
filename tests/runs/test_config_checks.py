"""Settings are checked by type and range before anything heavy runs (runs/config_checks.py), and
a trainer setting reaches every net of a run, the blend's members included."""
import logging
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hydra import compose, initialize_config_dir
from hydra.core.hydra_config import HydraConfig
from hydra.utils import instantiate
from omegaconf import OmegaConf

from common.errors import InputError
from models.resmlp_regressor import ResMLPRegressor
from runs.config_checks import check_config
from runs.run import run
from tests.conftest import CONFIG_DIR, tiny

ROOT = Path(__file__).resolve().parents[2]
EXPERIMENTS = sorted(p.stem for p in (ROOT / "configs" / "experiment").glob("*.yaml"))
MODELS = sorted(p.stem for p in (ROOT / "configs" / "model").glob("*.yaml"))
TIME_SERIES_MODELS = {m for m in MODELS if "base/timeseries_classifier" in (ROOT / "configs" / "model" / f"{m}.yaml").read_text()}


def composed(overrides, hydra_config=False):
    with initialize_config_dir(config_dir=CONFIG_DIR, version_base="1.3"):
        return compose(config_name="config", overrides=list(overrides), return_hydra_config=hydra_config)


def check_error(overrides) -> str:
    with pytest.raises(InputError) as caught:
        check_config(composed(overrides), overrides)
    return str(caught.value)


# -- wrong types and ranges: the key, the value and what it takes, in one line ----------------
@pytest.mark.parametrize("overrides, message", [
    (["seed=abc"], "seed must be an integer from 0 to 4294967295, got 'abc'"),
    (["seed=-1"], "seed must be an integer from 0 to 4294967295, got -1"),
    (["seed=4294967296"], "seed must be an integer from 0 to 4294967295, got 4294967296"),
    (["seed=1.5"], "seed must be an integer from 0 to 4294967295, got 1.5"),
    (["threads=abc"], "threads must be a positive integer or 'all', got 'abc'"),
    (["trainer.max_epochs=abc"], "trainer.max_epochs must be an integer >= 1, got 'abc'"),
    (["trainer.max_epochs=1.5"], "trainer.max_epochs must be an integer >= 1, got 1.5"),
    (["trainer.max_epochs=0"], "trainer.max_epochs must be an integer >= 1, got 0"),
    (["trainer.max_epochs=true"], "trainer.max_epochs must be an integer >= 1, got True"),
    (["trainer.batch_size=0"], "trainer.batch_size must be an integer >= 2, got 0"),
    (["trainer.early_stopping_patience=-1"], "trainer.early_stopping_patience must be an integer >= 0 or null, got -1"),
    (["trainer.lr_plateau_patience=null"], "trainer.lr_plateau_patience must be an integer >= 0, got None"),
    (["trainer.device=gpu"], "trainer.device must be one of cpu, cuda, cuda:<n>, auto, got 'gpu'"),
    (["trainer.progress=maybe"], "trainer.progress must be true or false, got 'maybe'"),
    (["+trainer.sparkle=1"], "trainer has no setting 'sparkle' (valid: max_epochs, batch_size, "),
    (["experiment=materials10", "trainer.lr=0"], "trainer.lr must be a number > 0, got 0"),
    (["experiment=materials10", "trainer.lr=inf"], "trainer.lr must be a number > 0, got inf"),
    (["experiment=materials10", "trainer.lr_factor=1.5"], "trainer.lr_factor must be a number in (0, 1), got 1.5"),
    (["experiment=materials10", "trainer.optimizer=rmsprop"], "trainer.optimizer must be one of sgd, adam, got 'rmsprop'"),
    (["experiment=materials10", "trainer.lr_milestones=[5,0]"],
     "trainer.lr_milestones must be a list of integers >= 1, got [5, 0]"),
    (["experiment=materials10", "trainer=reference", "trainer.max_batch_fraction=0"],
     "trainer.max_batch_fraction must be a number in (0, 1] or null, got 0"),
    (["experiment=materials10", "trainer=reference", "trainer.per_model.lstm_fcn.batch_size=1"],
     "trainer.per_model.lstm_fcn.batch_size must be an integer >= 2, got 1"),
    (["data.val_fraction=1.5"], "data.val_fraction must lie in (0, 1), got 1.5"),
    (["experiment=materials10", "data.test_fraction=0"], "data.test_fraction must be a number in (0, 1), got 0"),
    (["experiment=materials10", "data.window_step=0"], "data.window_step must be an integer >= 1 or null, got 0"),
    (["model=resmlp", "model.lr=-1"], "model.lr must be a number > 0, got -1"),
    (["model=resmlp", "model.l2=abc"], "model.l2 must be a number or null, got 'abc'"),
    (["model=resmlp", "model.widths=[a]"], "model.widths must be a list of numbers or null, got ['a']"),
    (["model=extra_trees", "model.n_estimators=1.5"], "model.n_estimators must be an integer >= 1, got 1.5"),
    (["model=extra_trees", "model.per_output=yes"], "model.per_output must be true or false or null, got 'yes'"),
    (["model=extra_trees", "model.max_features=[1]"], "model.max_features must be a number or a string or null, got [1]"),
    (["model=blend", "model.candidates.resmlp.estimator.noise_std=abc"],
     "model.candidates.resmlp.estimator.noise_std must be a number or null, got 'abc'"),
    (["scene.protocol=5"], "scene.protocol must be a string or null, got 5"),
    (["cost.budget_s=abc"], "cost.budget_s must be a number, got 'abc'"),
    (["export.opset=abc"], "export.opset must be an integer >= 1, got 'abc'"),
    (["experiment=materials10", "model=blend"],
     "model=blend learns from tables, one row per press; recordings train a time-series model"),
])
def test_a_wrong_setting_is_named_with_its_value_and_what_it_takes(overrides, message):
    error = check_error(overrides)
    assert error.startswith(message) and "\n" not in error


def test_an_interpolated_value_names_where_it_comes_from(compose_config):
    cfg = compose_config(["model=resmlp"])
    cfg.model.batch_size = "${seed}"
    cfg.seed = 1   # a seed, but not a batch size
    with pytest.raises(InputError, match=r"^model.batch_size \(= \$\{seed\}\) must be an integer >= 2, got 1$"):
        check_config(cfg)


@pytest.mark.parametrize("overrides", [
    ["seed=0"], ["seed=4294967295"], ["trainer.max_epochs=1"], ["trainer.early_stopping_patience=null"],
    ["trainer.device=auto"], ["trainer.device=cuda:1"], ["model=resmlp", "model.lr=1"],   # an int where a float goes
    ["model=extra_trees", "model.max_features=0.5"], ["model=extra_trees", "model.max_features=null"],
    ["model=extra_trees", "model.max_depth=null"], ["threads=all"], ["trainer=tsc"],
    ["experiment=materials10", "trainer=reference", "trainer.per_model.lstm_fcn.max_epochs=3"],
])
def test_values_in_range_pass(overrides):
    assert check_config(composed(overrides)) == []


# -- end to end: train.py answers in one line, exit 2, before Hydra makes a run folder --------
@pytest.mark.parametrize("override, message", [
    ("seed=abc", "error: seed must be an integer from 0 to 4294967295, got 'abc'"),
    ("trainer.max_epochs=1.5", "error: trainer.max_epochs must be an integer >= 1, got 1.5"),
    ("trainer.batch_size=0", "error: trainer.batch_size must be an integer >= 2, got 0"),
])
def test_train_py_refuses_a_wrong_setting_in_one_line(tmp_path, override, message):
    result = subprocess.run([sys.executable, str(ROOT / "train.py"), override, f"hydra.run.dir={tmp_path / 'run'}"],
                            capture_output=True, text=True, cwd=tmp_path, timeout=300, env=dict(os.environ, CI="true"))
    assert result.returncode == 2, result.stderr
    assert result.stderr.strip() == message
    assert not (tmp_path / "run").exists()   # no run folder, no error.txt holding a Python message


def test_each_job_of_a_sweep_is_checked_when_it_runs(compose_config, tmp_path):
    """A sweep's jobs are composed by Hydra after train.py's check: run() checks each before any work."""
    cfg = compose_config(tiny("decision_tree"))
    cfg.seed = -1
    with pytest.raises(InputError, match=r"^seed must be an integer from 0 to 4294967295, got -1$"):
        run(cfg, tmp_path / "job")
    assert not (tmp_path / "job").exists()


# -- trainer settings reach every net ---------------------------------------------------------
def resmlp_candidate(overrides):
    return composed(["model=blend", *overrides]).model.candidates.resmlp.estimator


def test_the_default_blend_keeps_its_training_length():
    net = resmlp_candidate([])
    assert (net.max_epochs, net.early_stopping_patience, net.lr_plateau_patience, net.batch_size) == (100, 15, 5, 32)
    single = composed(["model=resmlp"]).model
    assert (single.max_epochs, single.early_stopping_patience, single.lr_plateau_patience) == (300, 30, 10)
    paper = resmlp_candidate(["+size=rubber12_paper"])
    assert (paper.max_epochs, paper.early_stopping_patience, paper.lr_plateau_patience) == (300, 30, 10)
    ert = resmlp_candidate(["experiment=ert_learned"])
    assert (ert.max_epochs, ert.early_stopping_patience, ert.lr_plateau_patience, ert.batch_size) == (150, 20, 10, 64)


def test_trainer_settings_reach_the_blends_net():
    blend = instantiate(composed(["model=blend", "trainer.max_epochs=7", "trainer.early_stopping_patience=2",
                                  "trainer.batch_size=16"]).model)
    net = blend.candidates["resmlp"].estimator
    assert (net.max_epochs, net.early_stopping_patience, net.batch_size) == (7, 2, 16)
    assert resmlp_candidate(["experiment=ert_learned", "trainer.max_epochs=7"]).max_epochs == 7


def test_a_null_patience_trains_every_epoch():
    """trainer=tsc (patience null) reaches the blend's net too: null means no early stopping."""
    assert resmlp_candidate(["trainer=tsc"]).early_stopping_patience is None
    rng = np.random.default_rng(0)
    X, y = rng.normal(size=(40, 3)), rng.normal(size=40)
    settings = dict(widths=(8,), dropouts=(0.1,), lr=0.0, max_epochs=5, progress=False)  # lr 0: never improves
    assert len(ResMLPRegressor(early_stopping_patience=0, **settings).fit(X, y).history_) == 2
    assert len(ResMLPRegressor(early_stopping_patience=None, **settings).fit(X, y).history_) == 5


@pytest.mark.parametrize("overrides, warned", [
    (["model=extra_trees", "trainer.max_epochs=5"],
     ["trainer.max_epochs=5: no part of this run reads it (model: TreeRegressor); ignored"]),
    (["model=resmlp", "trainer.max_epochs=5"], []),
    (["trainer.max_epochs=5"], []),                                     # the blend's net
    (["model=resmlp", "+trainer.resume_from=old_run"],
     ["trainer.resume_from=old_run: no part of this run reads it (model: ResMLPRegressor); ignored"]),
    (["experiment=materials10", "trainer.resume_from=old_run"], []),     # the time-series classifiers resume
    (["experiment=materials10", "model=prcnn", "trainer=reference", "trainer.per_model.lstm_fcn.max_epochs=3"],
     ["trainer.per_model.lstm_fcn.max_epochs=3: no part of this run reads it (model: TimeSeriesClassifier); ignored"]),
    (["experiment=materials10", "model=lstm_fcn", "trainer=reference", "trainer.per_model.lstm_fcn.max_epochs=3"], []),
    (["model=extra_trees", "trainer.max_epochs=5", "trainer.progress=false", "seed=3"],
     ["trainer.max_epochs=5, trainer.progress=false: no part of this run reads them (model: TreeRegressor); ignored"]),
])
def test_a_trainer_setting_that_reaches_nothing_is_one_warning(overrides, warned):
    assert check_config(composed(overrides), overrides) == warned


def test_the_run_logs_the_warning_of_its_own_overrides(tmp_path, caplog):
    """A sweep's job (here: as Hydra sets it up) logs which of its trainer overrides reach nothing."""
    overrides = tiny("decision_tree") + ["trainer.max_epochs=5", "analysis.ablation=false"]
    HydraConfig.instance().set_config(composed(overrides, hydra_config=True))
    try:
        with caplog.at_level(logging.WARNING, logger="runs.run"):
            run(composed(overrides), tmp_path)
    finally:
        HydraConfig.instance().cfg = None
    assert [r.getMessage() for r in caplog.records if r.name == "runs.run"] == [
        "trainer.max_epochs=5, trainer.progress=false: no part of this run reads them (model: TreeRegressor); ignored"]


# -- every experiment composes with its models and passes the checks --------------------------
def task_models(experiment: str) -> list[str]:
    """The models an experiment can run: the time-series classifiers for recordings, the others
    for presses (experiment=taxel_inverse sizes model.n_estimators, so trees only)."""
    if experiment in ("taxel_inverse", "calibrate"):
        return ["decision_tree", "extra_trees", "random_forest"]
    time_series = composed([f"experiment={experiment}"]).data._target_.endswith("TimeSeriesDataModule")
    return sorted(m for m in MODELS if (m in TIME_SERIES_MODELS) == time_series)


def with_its_file(experiment: str, folder) -> list[str]:
    """An experiment on the user's own presses (experiment=calibrate) needs data.path, as its user gives it."""
    if not OmegaConf.is_missing(composed([f"experiment={experiment}"]).data, "path"):
        return [f"experiment={experiment}"]
    presses = folder / "presses.csv"
    presses.write_text("x_mm,y_mm,depth_mm\n1,2,0.5\n")
    return [f"experiment={experiment}", f"data.path={presses}"]


@pytest.mark.parametrize("experiment", EXPERIMENTS)
def test_every_experiment_passes_the_checks(experiment, tmp_path):
    assert check_config(composed(with_its_file(experiment, tmp_path))) == []


@pytest.mark.parametrize("model", MODELS)
def test_every_model_passes_the_checks(model):
    context = ["experiment=materials10"] if model in TIME_SERIES_MODELS else []
    assert check_config(composed(context + [f"model={model}"])) == []


@pytest.mark.slow
@pytest.mark.parametrize("experiment", EXPERIMENTS)
def test_every_experiment_passes_the_checks_with_each_model(experiment, tmp_path):
    """Every model of the experiment's task passes; any other is a one-line InputError, not a
    traceback (a classifier on presses, the blend on recordings, a net where trees are sized)."""
    usable = task_models(experiment)
    for model in MODELS:
        cfg = composed(with_its_file(experiment, tmp_path) + [f"model={model}"])
        if model in usable:
            assert check_config(cfg) == [], model
        else:
            try:
                check_config(cfg)
            except InputError as error:
                assert "\n" not in str(error), (model, str(error))
