"""The reference training recipe (trainer=reference) and what every recipe now shares: the best
validation epoch is the model kept, BatchNorm statistics that settle, batches a training set allows."""
import functools
import logging

import pytest
import torch
from hydra.utils import instantiate
from torch import nn

from models.nets.prcnn import PRCNN
from models.timeseries_classifier import TimeSeriesClassifier
from runs.reference_tasks import MODELS, OPTIMUM, fit_one, generate, split

SMALL_PRCNN = functools.partial(PRCNN, branch_width=8, fusion_width=8)


def small(**params) -> TimeSeriesClassifier:
    settings = {"network": SMALL_PRCNN, "optimizer": "adam", "lr": 1e-3, "lr_schedule": "plateau", "lr_plateau_patience": 3,
                "min_lr": 1e-4, "batch_size": 64, "max_batch_fraction": 0.1, "max_epochs": 8, "recalibrate_batchnorm": True,
                "progress": False, "seed": 0}
    return TimeSeriesClassifier(**{**settings, **params})


def test_reference_recipe_composes_as_the_references_train(compose_config):
    cfg = compose_config(["experiment=materials10", "trainer=reference"])
    model = instantiate(cfg.model)
    assert (model.optimizer, model.lr, model.lr_schedule, model.lr_factor, model.lr_plateau_patience,
            model.min_lr) == ("adam", 1e-3, "plateau", 0.5, 50, 1e-4)
    assert (model.batch_size, model.max_batch_fraction, model.max_epochs) == (64, 0.1, 1500)
    lstm = instantiate(compose_config(["experiment=materials10", "trainer=reference", "model=lstm_fcn"]).model)
    assert (lstm.batch_size, lstm.max_epochs, lstm.lr_plateau_patience) == (128, 2000, 100)
    assert lstm.lr_factor == pytest.approx(2 ** (-1 / 3))
    paper = instantiate(compose_config(["experiment=materials10", "model=lstm_fcn"]).model)
    assert (paper.optimizer, paper.lr, paper.batch_size, paper.max_batch_fraction) == ("sgd", 0.05, 128, None)


@pytest.mark.parametrize("n_train, expected", [(200, 20), (1000, 64), (10, 2), (3, 2)])
def test_a_batch_is_never_more_than_a_tenth_of_the_training_set(n_train, expected):
    assert small().effective_batch_size(n_train) == expected
    assert small(max_batch_fraction=None).effective_batch_size(n_train) == min(64, n_train)


def test_the_kept_model_is_the_best_validation_epoch_not_the_last():
    X, y = generate("frequency", 60, seed=0)
    train, val, _ = split(y, 0)
    # lr 0.5 with SGD makes the later epochs worse than the best one: the last epoch is not the model
    model = small(optimizer="sgd", lr=0.5, lr_schedule="milestones", milestones=[], max_epochs=8)
    model.fit(X[train], y[train], X[val], y[val])
    scores = [(r["val_accuracy"], -r["val_loss"]) for r in model.history_]
    best = max(range(len(scores)), key=lambda i: scores[i])
    assert model.best_epoch_ == best + 1 < model.n_epochs_
    logits = model._logits(X[val])
    assert float((logits.argmax(1).numpy() == y[val]).mean()) == model.history_[best]["val_accuracy"]
    assert float(nn.CrossEntropyLoss()(logits, torch.as_tensor(y[val]))) == pytest.approx(
        model.history_[best]["val_loss"], rel=1e-5)


def test_early_stopping_ends_a_run_without_progress():
    X, y = generate("frequency", 40, seed=1)
    train, val, _ = split(y, 1)
    model = small(lr=1e-12, lr_schedule="milestones", milestones=[], early_stopping_patience=2, max_epochs=50)
    model.fit(X[train], y[train], X[val], y[val])
    assert model.n_epochs_ < 50 and model.n_epochs_ - model.best_epoch_ == 2


def test_the_patience_is_as_long_again_as_the_last_improvement_took_within_its_bounds():
    model = small(early_stopping_patience=100, early_stopping_min_patience=20)
    assert [model.patience(epoch) for epoch in (1, 20, 45, 100, 400)] == [20, 20, 45, 100, 100]
    assert small(early_stopping_patience=100).patience(5) == 100  # no minimum: a fixed patience
    assert small(early_stopping_patience=None).patience(5) is None  # every epoch runs


def test_what_counts_as_an_improvement_that_matters():
    model = small(early_stopping_min_delta=0.01)
    last = (0.8, 0.50, 5)  # accuracy, loss, epoch of the last improvement that mattered
    assert model._matters((0.9, 0.9, 6), last)  # a higher accuracy, whatever the loss
    assert model._matters((0.8, 0.48, 6), last) and not model._matters((0.8, 0.495, 6), last)
    assert not model._matters((0.7, 0.1, 6), last)
    assert not model._matters((1.0, 0.01, 6), (1.0, 0.5, 5))  # every window right: the loss no longer counts


def test_a_saturated_task_stops_once_only_the_loss_creeps_down():
    """A tiny set learnt in a few epochs: validation accuracy saturates at 1 and the loss keeps
    creeping down. Counting every lower loss as progress (a fixed patience of 100 after the last
    better score) cannot stop before epoch 101; improvements that matter stop it far earlier, at
    full accuracy, while the loss was still falling (the old rule would still be waiting)."""
    X, y = generate("phase", 60, seed=11, length=200)
    train, val, test = split(y, 0)
    model = small(lr_plateau_patience=50, batch_size=64, max_epochs=300, early_stopping_patience=100,
                  early_stopping_min_patience=20, early_stopping_min_delta=0.01)
    model.fit(X[train], y[train], X[val], y[val])
    assert model.n_epochs_ <= 60, model.n_epochs_
    assert model.history_[model.best_epoch_ - 1]["val_accuracy"] == 1.0
    assert float((model.predict(X[test]) == y[test]).mean()) >= 0.9
    scores = [(r["val_accuracy"], -r["val_loss"]) for r in model.history_]
    assert model.n_epochs_ == model.improved_epoch_ + model.patience(model.improved_epoch_) < 101
    assert any(scores[e] > max(scores[:e]) for e in range(model.improved_epoch_, model.n_epochs_)), \
        "the loss kept falling while the count ran: the old rule would have gone on"


def test_progress_lines_off_a_terminal_show_the_validation_accuracy(caplog, monkeypatch):
    """Every periodic line (each epoch here) after the first epoch, and the closing one, carry the
    last epoch's validation numbers, not just a count."""
    monkeypatch.setenv("CI", "true")
    monkeypatch.setattr("common.progress.HEARTBEAT_S", 0.0)
    X, y = generate("frequency", 40, seed=1)
    train, val, _ = split(y, 1)
    with caplog.at_level(logging.INFO, logger="touchstone"):
        small(max_epochs=3, progress=True).fit(X[train], y[train], X[val], y[val])
    lines = [r.getMessage() for r in caplog.records if r.getMessage().startswith("PRCNN: ")]
    assert [line.split(" epochs")[0] for line in lines] == ["PRCNN: 1/3", "PRCNN: 2/3", "PRCNN: 3/3", "PRCNN: 3"]
    assert all("val_loss=" in line and "val_accuracy=" in line for line in lines[1:]), lines


def test_recalibrated_batchnorm_holds_the_training_set_statistics():
    X, y = generate("phase", 40, seed=2)
    model = small(max_epochs=2).fit(X, y)
    first = model.module_.branches["channel_0"].body[0][1]  # conv -> BatchNorm of the first branch
    seen = []
    hook = first.register_forward_hook(lambda module, inputs, output: seen.append(inputs[0]))
    model.module_.eval()
    with torch.no_grad():
        model.module_(torch.as_tensor(model._scaled(X)))
    hook.remove()
    activations = seen[0]
    torch.testing.assert_close(first.running_mean, activations.mean(dim=(0, 2)), rtol=1e-4, atol=1e-5)
    torch.testing.assert_close(first.running_var, activations.var(dim=(0, 2)), rtol=1e-3, atol=1e-5)


def test_recalibration_leaves_the_training_trajectory_unchanged():
    """Training batches normalise with their own statistics and the recalibration draws no random
    numbers: the weights after each epoch are the same with and without it."""
    X, y = generate("frequency", 40, seed=3)
    weights = []
    for recalibrate in (False, True):
        model = small(max_epochs=3, recalibrate_batchnorm=recalibrate).fit(X, y)
        weights.append({k: v for k, v in model.module_.state_dict().items() if "running" not in k and "num_batches" not in k})
    for key in weights[0]:
        assert torch.equal(weights[0][key], weights[1][key]), key


def test_a_tiny_generated_task_reaches_its_optimum():
    row = fit_one("frequency", "prcnn", epochs=15, n=100, seed=0,
                  overrides=["model.network.branch_width=8", "model.network.fusion_width=8"])
    assert row["val_accuracy"] == OPTIMUM and row["test_accuracy"] == OPTIMUM, row


@pytest.mark.slow
@pytest.mark.parametrize("task", ["frequency", "phase", "imu6"])
@pytest.mark.parametrize("model", MODELS)
def test_every_network_reaches_the_optimum_with_the_reference_recipe(task, model):
    row = fit_one(task, model, epochs=30, n=300, seed=0)
    assert row["test_accuracy"] >= OPTIMUM - 0.02, row
