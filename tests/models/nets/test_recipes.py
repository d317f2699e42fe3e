"""Net recipes on small sets (models/timeseries_classifier.py, data/splits/indices.py): the epoch
count chosen on stratified folds of the training recordings then a refit on all of them, sets with
one or two recordings per class, and InceptionTime as its paper's 5-network ensemble."""
import functools
import json

import numpy as np
import onnxruntime as ort
import pytest
import torch

from data.splits.indices import predefined_split, stratified_folds
from export.run_export import write_onnx
from models.deployable import TimeSeriesPipeline
from models.nets.inceptiontime import InceptionTime
from models import fold_epoch_choice
from models.timeseries_classifier import TimeSeriesClassifier
from runs.run import run

TINY_NET = functools.partial(InceptionTime, depth=3, filters=4, bottleneck=4, kernels=(9, 5, 3))


def tones(n_per_class=4, n_classes=3, steps=40, seed=0):
    """Recordings of `n_classes` classes told apart by a tone's frequency, noise added."""
    rng = np.random.default_rng(seed)
    t = np.arange(steps) / 20.0
    y = np.repeat(np.arange(n_classes), n_per_class)
    X = np.stack([[np.sin(2 * np.pi * (1 + 2 * c) * t + rng.uniform(0, 6)) + 0.3 * rng.standard_normal(steps)]
                  for c in y])
    return X.astype(np.float32), y


def classifier(**settings):
    return TimeSeriesClassifier(**{"network": TINY_NET, "optimizer": "adam", "lr": 1e-2, "lr_schedule": "plateau",
                                   "lr_plateau_patience": 50, "max_epochs": 6, "batch_size": 4, "progress": False,
                                   "seed": 0, **settings})


def test_folds_keep_recordings_together_and_spread_every_class():
    labels = np.repeat(["a", "b", "c"], 8)          # 4 recordings per class, 2 windows each
    groups = np.repeat(np.arange(12), 2)
    folds = stratified_folds(labels, groups, 2, seed=0)
    assert len(folds) == 2
    held_once = np.concatenate([held for _, held in folds])
    assert sorted(held_once) == list(range(24))     # every window held out exactly once
    for fit, held in folds:
        assert not set(groups[fit]) & set(groups[held])
        assert sorted(np.unique(labels[held], return_counts=True)[1]) == [4, 4, 4]  # 2 recordings of each class
    # One recording per class: still folds, every recording held out once, by a fit that never saw it.
    folds = stratified_folds(["a", "b", "c", "d"], np.arange(4), 3, seed=0)
    assert sorted(np.concatenate([held for _, held in folds])) == [0, 1, 2, 3]
    again = stratified_folds(["a", "b", "c", "d"], np.arange(4), 3, seed=0)           # same seed, same folds
    assert [list(held) for _, held in again] == [list(held) for _, held in folds]


def test_carving_validation_keeps_a_training_recording_of_every_class():
    values = np.array(["train"] * 6 + ["test"] * 3)
    two_each = np.array(["a", "a", "b", "b", "c", "c", "a", "b", "c"])
    train, val, _ = predefined_split(values, 0.25, 0, "rig.npz", strata=two_each)
    assert set(two_each[train]) == {"a", "b", "c"} and len(val) == 2     # ceil(0.25 x 6), never a class's last
    one_each = np.array(["a", "b", "c", "a", "b", "c"])
    values = np.array(["train"] * 3 + ["test"] * 3)
    train, val, _ = predefined_split(values, 0.25, 0, "rig.npz", strata=one_each)
    assert list(train) == [0, 1, 2] and len(val) == 0                    # nothing carved, nothing refused


def test_the_folds_choose_the_epoch_of_the_best_pooled_held_out_accuracy(monkeypatch):
    monkeypatch.setattr(fold_epoch_choice, "FOLD_CURVE_WINDOW", 3)   # a window that fits in 6 epochs
    X, y = tones()
    model = classifier(epoch_selection="folds", n_folds=2, max_epochs=6).fit(X, y)
    # By hand: each fold's network after e epochs, trained as the refit trains (the plateau on the
    # training loss: no validation windows given), predicting its held-out recordings.
    folds = stratified_folds(y, np.arange(len(y)), 2, 0)
    proba = np.zeros((6, len(y), 3))
    for fit, held in folds:
        for e in range(1, 7):
            proba[e - 1, held] = classifier(max_epochs=e).fit(X[fit], y[fit]).predict_proba(X[held])
    accuracy = (proba.argmax(axis=2) == y).mean(axis=1)
    loss = -np.log(proba[:, np.arange(len(y)), y]).mean(axis=1)
    # Each epoch scored by the mean over it and the epochs before it, FOLD_CURVE_WINDOW in all (3 here).
    window = [range(max(e - 2, 0), e + 1) for e in range(6)]
    accuracy = np.array([accuracy[list(w)].mean() for w in window])
    loss = np.array([loss[list(w)].mean() for w in window])
    best = max(range(6), key=lambda e: (accuracy[e], -loss[e]))
    assert model.best_epoch_ == best + 1 and model.n_epochs_ == best + 1        # the refit ran that many
    np.testing.assert_allclose(model.fold_curve_["accuracy"], accuracy)
    np.testing.assert_allclose(model.out_of_fold_proba_, proba[best], rtol=1e-4, atol=1e-5)
    assert all("val_loss" not in record for record in model.history_)      # the refit: every training window


def test_the_papers_rule_keeps_the_least_training_loss_and_validation_only_reports():
    X, y = tones()
    fit, held = np.arange(0, len(y), 2), np.arange(1, len(y), 2)
    model = classifier(epoch_selection="train_loss", max_epochs=8, lr_plateau_patience=1, lr_factor=0.5)
    model.fit(X[fit], y[fit], X[held], y[held])
    losses = [record["train_loss"] for record in model.history_]
    assert model.n_epochs_ == 8 and all("val_accuracy" in record for record in model.history_)   # every epoch run
    assert model.best_epoch_ == int(np.argmin(losses)) + 1
    # The kept weights are that epoch's: the same fit stopped there ends with them (nothing is chosen
    # on validation; an unseeded difference would show in the probabilities).
    stopped = classifier(epoch_selection="train_loss", max_epochs=model.best_epoch_, lr_plateau_patience=1,
                         lr_factor=0.5).fit(X[fit], y[fit], X[held], y[held])
    np.testing.assert_allclose(model.predict_proba(X), stopped.predict_proba(X), rtol=1e-5, atol=1e-6)
    # Validation never steers it: with wrong validation labels (a validation loss that rises) the
    # plateau, which would watch that loss under epoch_selection=validation, still follows the
    # training loss, and the fit is the same network.
    wrong = (y[held] + 1) % 3
    other = classifier(epoch_selection="train_loss", max_epochs=8, lr_plateau_patience=1,
                       lr_factor=0.5).fit(X[fit], y[fit], X[held], wrong)
    assert [r["lr"] for r in other.history_] == [r["lr"] for r in model.history_]
    np.testing.assert_allclose(other.predict_proba(X), model.predict_proba(X), rtol=1e-5, atol=1e-6)
    watching = classifier(epoch_selection="validation", max_epochs=8, lr_plateau_patience=1,
                          lr_factor=0.5).fit(X[fit], y[fit], X[held], wrong)
    assert [r["lr"] for r in watching.history_] != [r["lr"] for r in model.history_]


def test_a_set_with_two_or_one_recordings_per_class_trains(compose_config, tmp_path):
    for per_class in (2, 1):
        X, y = tones(n_per_class=per_class + 2)
        split = np.tile(["train"] * per_class + ["test"] * 2, 3)
        path = tmp_path / f"{per_class}_each.npz"
        np.savez(path, X=X, y=np.array([f"tone{c}" for c in y]), split=split)
        cfg = compose_config(["data=recordings_npz", f"data.path={path}", "model=inceptiontime",
                              "model.network.depth=3", "model.network.filters=4", "model.network.bottleneck=4",
                              "trainer.max_epochs=3", "trainer.progress=false", "trainer.device=cpu",
                              "trainer.checkpoint=false", "cost.onnx_latency_calls=0"])
        metrics = run(cfg, tmp_path / f"run{per_class}")
        training = json.loads((tmp_path / f"run{per_class}" / "metrics.json").read_text())["training"]
        assert training["epoch_selection"] == "folds" and len(training["fold_best_epochs"]) >= 2
        assert training["best_epoch"] == training["epochs_run"]   # the refit's epochs are the kept model's
        assert metrics["data"]["n_test_recordings"] == 6
        if per_class == 1:   # nothing to carve: validation is the folds' held-out predictions
            assert metrics["data"]["n_val_recordings"] == 0 and "out-of-fold" in metrics["data"]["validation"]
            assert metrics["val"]["accuracy"] == pytest.approx(training["out_of_fold_accuracy"])


def fitted_ensemble():
    X, y = tones()
    return classifier(ensemble_size=2, max_epochs=3).fit(X[::2], y[::2], X[1::2], y[1::2]), X


def test_the_ensemble_averages_its_members_probabilities():
    model, X = fitted_ensemble()
    members = model.module_.members
    assert len(members) == 2 and model.best_epoch_ == [m for m in model.best_epoch_]
    with torch.no_grad():
        x = torch.as_tensor(model._scaled(X))
        each = [torch.softmax(member(x), dim=1).numpy() for member in members]
    assert not np.allclose(each[0], each[1], atol=1e-3)           # two networks (seeds 0 and 1), not one twice
    np.testing.assert_allclose(model.predict_proba(X), np.mean(each, axis=0), rtol=1e-5, atol=1e-6)
    alone = classifier(max_epochs=3, seed=1).fit(X[::2], tones()[1][::2], X[1::2], tones()[1][1::2])
    np.testing.assert_allclose(alone.predict_proba(X), each[1], rtol=1e-4, atol=1e-5)   # member 1 is the seed-1 fit


def test_an_ensemble_on_folds_keeps_each_members_choice():
    X, y = tones()
    model = classifier(ensemble_size=2, max_epochs=3, epoch_selection="folds", n_folds=2).fit(X, y)
    member1 = classifier(max_epochs=3, epoch_selection="folds", n_folds=2, seed=1).fit(X, y)
    assert len(model.fold_epochs_run_) == len(model.best_epoch_) == 2     # one entry per member
    assert model.fold_epochs_run_[1] == member1.fold_epochs_run_ and model.best_epoch_[1] == member1.best_epoch_


def test_the_ensemble_exports_to_one_onnx_graph_that_matches_eager(tmp_path):
    model, X = fitted_ensemble()
    pipeline = TimeSeriesPipeline(["tone"], ["0", "1", "2"], None, 1, X.shape[2], np.zeros((1, 1, 1)),
                                  np.ones((1, 1, 1)), model, {}, X[:4])
    path = write_onnx(pipeline, tmp_path / "model.onnx")
    assert not list(tmp_path.glob("*.data"))                        # weights inside the one file
    session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    (name,) = [i.name for i in session.get_inputs()]
    onnx_proba = session.run(None, {name: X})[0]
    np.testing.assert_allclose(onnx_proba, pipeline.predict_raw(X), rtol=1e-4, atol=1e-5)


def test_an_npz_declared_split_is_the_split_without_saying_so(compose_config, tmp_path):
    """`data=recordings_npz data.path=...` and nothing else: the NPZ's own split array decides."""
    from hydra.utils import instantiate
    X, y = tones(n_per_class=6)
    split = np.tile(["train"] * 3 + ["val", "test", "test"], 3)
    np.savez(tmp_path / "rig.npz", X=X, y=y, split=split)
    dm = instantiate(compose_config(["data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}"]).data).setup()
    assert dm.split == "predefined" and "declares" in dm.split_source
    for side, rows in (("train", dm.train_recordings), ("val", dm.val_recordings), ("test", dm.test_recordings)):
        np.testing.assert_array_equal(rows, np.flatnonzero(split == side))
