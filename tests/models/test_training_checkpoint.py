"""Resumable training: a run killed after k epochs and continued from its checkpoint ends exactly
where the uninterrupted run ends (same seed, CPU)."""
import functools

import numpy as np
import pytest
import torch

from common.errors import InputError
from models.nets.lstm_fcn import LSTMFCN
from models.timeseries_classifier import TimeSeriesClassifier
from models.training_checkpoint import CHECKPOINT_KEYS
from runs.reference_tasks import generate, split

# LSTM-FCN for its dropout: the resumed run must continue the global RNG stream, not restart it
SMALL_LSTM_FCN = functools.partial(LSTMFCN, hidden=8, widths=(8, 8, 8), dropout=0.5)


class Interrupted(Exception):
    pass


def estimator(**params):
    # a plateau patience of 1 and early stopping patience 3: the schedule and the counters are
    # mid-way when the run is killed, so resuming must restore them
    settings = {"network": SMALL_LSTM_FCN, "optimizer": "adam", "lr": 3e-3, "lr_schedule": "plateau", "lr_factor": 0.5,
                "lr_plateau_patience": 1, "min_lr": 1e-4, "early_stopping_patience": 3, "batch_size": 8,
                "max_batch_fraction": 0.1, "max_epochs": 8, "recalibrate_batchnorm": True, "progress": False, "seed": 3}
    return TimeSeriesClassifier(**{**settings, **params})


@pytest.fixture(scope="module")
def data():
    X, y = generate("phase", 60, seed=5)
    train, val, _ = split(y, 5)
    return X[train], y[train], X[val], y[val]


def kill_after(k):
    def callback(record):
        if record["epoch"] == k:
            raise Interrupted
    return callback


def same_history(a, b):
    keep = lambda h: [{k: v for k, v in r.items() if k not in ("elapsed_s", "epoch_s")} for r in h]
    return keep(a) == keep(b)


@pytest.mark.parametrize("k", [1, 4])
def test_a_killed_run_resumed_ends_exactly_as_the_uninterrupted_one(data, tmp_path, k):
    whole = estimator(checkpoint_path=str(tmp_path / "whole" / "last.pt")).fit(*data)
    with pytest.raises(Interrupted):
        estimator(checkpoint_path=str(tmp_path / "cut" / "last.pt")).fit(*data, epoch_callback=kill_after(k))
    checkpoint = torch.load(tmp_path / "cut" / "last.pt", weights_only=True)  # tensors and plain values only
    assert checkpoint["epoch"] == k and set(checkpoint) == set(CHECKPOINT_KEYS)
    resumed = estimator(checkpoint_path=str(tmp_path / "resumed" / "last.pt"),
                        resume_from=str(tmp_path / "cut")).fit(*data)
    assert same_history(whole.history_, resumed.history_)
    assert resumed.best_epoch_ == whole.best_epoch_ and resumed.n_epochs_ == whole.n_epochs_
    for key, value in whole.module_.state_dict().items():
        assert torch.equal(value, resumed.module_.state_dict()[key]), key
    np.testing.assert_array_equal(whole.predict_proba(data[2]), resumed.predict_proba(data[2]))


def test_an_uninterrupted_control_differs_from_another_seed(data, tmp_path):
    """The comparison above can fail: another seed gives other weights."""
    a, b = estimator().fit(*data), estimator(seed=4).fit(*data)
    assert not torch.equal(a.module_.lstm.weight_ih_l0, b.module_.lstm.weight_ih_l0)


def test_resuming_with_another_configuration_is_a_one_line_error(data, tmp_path):
    with pytest.raises(Interrupted):
        estimator(checkpoint_path=str(tmp_path / "last.pt")).fit(*data, epoch_callback=kill_after(2))
    with pytest.raises(InputError, match="another configuration .*lr"):
        estimator(lr=1e-2, resume_from=str(tmp_path / "last.pt")).fit(*data)
    with pytest.raises(InputError, match="no checkpoint"):
        estimator(resume_from=str(tmp_path / "nowhere")).fit(*data)


def test_a_run_through_hydra_keeps_its_checkpoint_in_the_run_folder(compose_config, tmp_path):
    from runs.run import run
    X, y = generate("frequency", 40, seed=0)
    np.savez(tmp_path / "rig.npz", X=X, y=y)
    common = ["data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}", "model=prcnn", "trainer=reference",
              "trainer.max_epochs=3", "trainer.progress=false", "trainer.device=cpu",
              "model.network.branch_width=8", "model.network.fusion_width=8"]
    whole = run(compose_config(common), tmp_path / "whole")
    assert torch.load(tmp_path / "whole" / "checkpoint" / "last.pt", weights_only=True)["epoch"] == 3
    resumed = run(compose_config(common + [f"trainer.resume_from={tmp_path / 'whole'}"]), tmp_path / "again")
    assert resumed["val"] == whole["val"] and resumed["test"] == whole["test"]
