"""Training across processes (models/distributed.py): two gloo processes compute what one process
computes with the same global batch and seed, and train.py under torchrun writes one run folder."""
import functools
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch
from torch import nn

from common.errors import InputError
from models.distributed import SynchronisedBatchNorm, TrainingGroup, fit_in_processes, rank_seed
from models.nets.lstm_fcn import LSTMFCN
from models.nets.prcnn import PRCNN
from models.resmlp_regressor import ResMLPRegressor
from models.timeseries_classifier import TimeSeriesClassifier
from runs.reference_tasks import generate, split

ROOT = Path(__file__).resolve().parents[2]
TOLERANCE = 1e-5  # in the loss at every optimiser step (issue 30's goal)


@pytest.fixture(scope="module")
def windows():
    X, y = generate("phase", 60, seed=1)
    train, val, _ = split(y, 1)
    return X[train], y[train], X[val], y[val]


def assert_same_steps(one, two):
    assert len(one.step_losses_) == len(two.step_losses_) > 0
    difference = np.abs(np.array(one.step_losses_) - np.array(two.step_losses_)).max()
    assert difference <= TOLERANCE, difference


def test_the_residual_mlp_trains_on_two_processes_as_on_one():
    """BatchNorm synchronised, dropout and input noise off (they draw per rank). 45 rows in
    batches of 16: the last global batch (13) splits 7 / 6, so the shares are weighted."""
    rng = np.random.default_rng(0)
    X = rng.normal(size=(53, 6))
    y = np.c_[X[:, 0] * X[:, 1], np.sin(X[:, 2])] + 0.05 * rng.normal(size=(53, 2))
    model = ResMLPRegressor(widths=(16, 8), dropouts=(0.0, 0.0), noise_std=0.0, batch_size=16, max_epochs=6,
                            early_stopping_patience=None, progress=False, seed=2)
    one = model.fit(X[:45], y[:45], X[45:], y[45:])
    two = fit_in_processes(model, 2, X[:45], y[:45], X[45:], y[45:])
    assert_same_steps(one, two)
    assert len(one.step_losses_) == 6 * 3
    np.testing.assert_allclose(two.predict(X), one.predict(X), atol=1e-4)
    # the eval-mode statistics are the global ones too, and the deployed module is plain BatchNorm again
    assert not any(isinstance(m, SynchronisedBatchNorm) for m in two.module_.modules())
    for a, b in zip(one.module_.state_dict().values(), two.module_.state_dict().values()):
        torch.testing.assert_close(a, b, atol=1e-4, rtol=1e-4)


def test_prcnn_with_batchnorm_trains_on_two_processes_as_on_one(windows):
    """At lr 1e-3. At 3e-3 the two part by 4e-4 after ten steps: a convolution's bias before
    BatchNorm has a true gradient of zero, Adam scales its float noise (which depends on the
    order of the sums) to full-size steps; with those biases off they agree within 1e-7 there too."""
    model = TimeSeriesClassifier(network=functools.partial(PRCNN, branch_width=8, fusion_width=8), optimizer="adam",
                                 lr=1e-3, lr_schedule="plateau", batch_size=8, max_epochs=4, recalibrate_batchnorm=True,
                                 progress=False, seed=4)
    one = model.fit(*windows)
    two = fit_in_processes(model, 2, *windows)
    assert_same_steps(one, two)
    for a, b in zip(one.history_, two.history_):
        assert b["val_loss"] == pytest.approx(a["val_loss"], abs=TOLERANCE)
        assert b["train_accuracy"] == a["train_accuracy"] and b["val_accuracy"] == a["val_accuracy"]
    np.testing.assert_allclose(two.predict_proba(windows[2]), one.predict_proba(windows[2]), atol=1e-4)


def test_a_two_process_run_resumes_on_two_processes_and_only_there(windows, tmp_path):
    """Dropout draws per rank, so the checkpoint keeps every rank's RNG state: resumed on two
    processes the run ends as the uninterrupted one; on one process it is refused."""
    def model(max_epochs, name, resume_from=None):
        return TimeSeriesClassifier(network=functools.partial(LSTMFCN, hidden=8, widths=(8, 8, 8), dropout=0.5),
                                    optimizer="adam", lr=3e-3, lr_schedule="plateau", lr_plateau_patience=1,
                                    batch_size=8, max_epochs=max_epochs, progress=False, seed=3,
                                    checkpoint_path=str(tmp_path / name / "last.pt"), resume_from=resume_from)
    whole = fit_in_processes(model(4, "whole"), 2, *windows)
    fit_in_processes(model(2, "cut"), 2, *windows)
    resumed = fit_in_processes(model(4, "resumed", resume_from=str(tmp_path / "cut")), 2, *windows)
    keep = lambda h: [{k: v for k, v in r.items() if k not in ("elapsed_s", "epoch_s")} for r in h]
    assert keep(resumed.history_) == keep(whole.history_)
    with pytest.raises(InputError, match="world_size"):
        model(4, "alone", resume_from=str(tmp_path / "cut")).fit(*windows)


def test_each_rank_draws_its_own_dropout_from_the_run_seed():
    assert rank_seed(7, 0) == 7  # one process trains exactly as before
    seeds = {rank_seed(seed, rank) for seed in range(3) for rank in range(4)}
    assert len(seeds) == 12 and rank_seed(7, 1) == rank_seed(7, 1)


def test_alone_the_training_group_changes_nothing():
    group = TrainingGroup()
    batch = torch.arange(5)
    assert (group.rank, group.size) == (0, 1) and torch.equal(group.shard(batch), batch)
    assert group.share(5, 5) == 1.0 and group.totals([1.5, 2.0]) == [1.5, 2.0] and group.agree("x") == "x"
    module = nn.Sequential(nn.Linear(3, 4), nn.BatchNorm1d(4))
    assert group.prepare(module) is module and type(module[1]) is nn.BatchNorm1d


def test_train_py_under_torchrun_writes_one_run_folder_from_rank_zero(tmp_path):
    """Default folder name (time and process id differ between ranks): one folder, rank 0's files
    only (one train.log and .hydra/, no rank's private stage left), metrics.json world_size 2."""
    torchrun = shutil.which("torchrun", path=str(Path(sys.executable).parent))
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    env = {**os.environ, "CI": "true", "TMPDIR": str(scratch), "OMP_NUM_THREADS": "1"}
    result = subprocess.run(
        [torchrun, "--standalone", "--nproc_per_node=2", str(ROOT / "train.py"), "model=resmlp",
         "scene.n_samples=100", "scene.grid_nodes=21", "scene.progress=false", "trainer.max_epochs=2",
         "trainer.progress=false"], capture_output=True, text=True, cwd=tmp_path, env=env, timeout=300)
    assert result.returncode == 0, result.stderr[-3000:]
    (folder,) = (tmp_path / "outputs").glob("*/*")
    assert json.loads((folder / "status.json").read_text())["state"] == "finished"
    assert json.loads((folder / "metrics.json").read_text())["world_size"] == 2
    log = (folder / "train.log").read_text()
    assert log.count("training with 2 processes") == 1 and log.count("threads: 1 per process") == 1
    assert (folder / ".hydra" / "config.yaml").is_file() and (folder / "model.onnx").is_file()
    assert list(scratch.glob("touchstone-rank*")) == []


def test_a_config_mistake_under_torchrun_is_one_line_from_rank_zero_and_no_folder(tmp_path):
    torchrun = shutil.which("torchrun", path=str(Path(sys.executable).parent))
    result = subprocess.run([torchrun, "--standalone", "--nproc_per_node=2", str(ROOT / "train.py"), "model=resmlp",
                             "trainer.max_epochs=0"], capture_output=True, text=True, cwd=tmp_path,
                            env={**os.environ, "CI": "true"}, timeout=300)
    assert result.returncode != 0
    errors = [line for line in result.stderr.splitlines() if line.startswith("error: ")]
    assert errors == ["error: trainer.max_epochs must be an integer >= 1, got 0"]
    assert "exitcode: 2" in result.stderr and "SIGABRT" not in result.stderr  # every rank ends with code 2
    assert not (tmp_path / "outputs").exists()


@pytest.mark.slow
def test_a_sweep_job_with_two_submitit_tasks_trains_on_both(tmp_path):
    """Hydra's submitit launcher with tasks_per_node=2 (the local executor here, SLURM on a cluster):
    both tasks join one process group through submitit's environment; the job folder is rank 0's."""
    result = subprocess.run(
        [sys.executable, str(ROOT / "train.py"), "-m", "hydra/launcher=submitit_local",
         "hydra.launcher.tasks_per_node=2", "model=resmlp", "scene.n_samples=100", "scene.grid_nodes=21", "scene.progress=false", "trainer.max_epochs=2",
         "trainer.progress=false", f"hydra.sweep.dir={tmp_path / 'sweep'}"],
        capture_output=True, text=True, cwd=tmp_path, env={**os.environ, "CI": "true"}, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    job = tmp_path / "sweep" / "0"
    assert json.loads((job / "status.json").read_text())["state"] == "finished"
    assert json.loads((job / "metrics.json").read_text())["world_size"] == 2
    assert (job / "train.log").read_text().count("training with 2 processes") == 1
