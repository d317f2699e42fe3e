"""Time-series classifiers: architecture facts, branch isolation, training through Hydra."""
import json

import numpy as np
import pandas as pd
import pytest
import torch
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from models.nets.inceptiontime import InceptionTime
from models.nets.lstm_fcn import LSTMFCN
from models.nets.prcnn import PRCNN
from models.nets.rescnn import ResCNN
from models.torch_runtime import count_parameters
from runs.run import run


def test_inceptiontime_has_the_papers_456074_parameters():
    assert count_parameters(InceptionTime(n_channels=2, n_classes=10, length=1400)) == 456_074


def test_reported_parameter_counts_of_the_other_networks():
    assert count_parameters(PRCNN(2, 10, 1400, {"te": [0], "pr": [1]})) == 201_354
    assert count_parameters(ResCNN(2, 10, 1400)) == 505_866
    assert count_parameters(LSTMFCN(2, 10, 1400)) == 1_051_658


@pytest.mark.parametrize("network", [PRCNN, ResCNN, InceptionTime, LSTMFCN])
def test_every_network_maps_windows_to_class_logits(network):
    model = network(n_channels=6, n_classes=4, length=50, modalities={"accelerometer": [0, 1, 2], "gyroscope": [3, 4, 5]})
    assert model(torch.randn(3, 6, 50)).shape == (3, 4)


def test_prcnn_branches_see_only_their_own_channels():
    torch.manual_seed(0)
    model = PRCNN(n_channels=3, n_classes=5, modalities={"triboelectric": [0], "piezoresistive": [1, 2]}).eval()
    x = torch.randn(4, 3, 60)
    perturbed = x.clone()
    perturbed[:, 1:] += torch.randn(4, 2, 60)
    with torch.no_grad():
        before, after = model.branch_outputs(x), model.branch_outputs(perturbed)
        assert torch.equal(before["triboelectric"], after["triboelectric"])
        assert not torch.allclose(before["piezoresistive"], after["piezoresistive"])
        assert not torch.allclose(model(x), model(perturbed))


TINY = ["scene.passes_per_level=2", "trainer.max_epochs=6", "trainer.lr_milestones=[4]",
        "trainer.progress=false", "trainer.device=cpu"]


def assert_predictions_match_metrics(run_dir, metrics):
    """predictions.csv holds every validation and test window once, and its share of correct rows
    is the accuracy metrics.json reports for that split."""
    predictions = pd.read_csv(run_dir / "predictions.csv")
    assert set(predictions["split"]) == {"val", "test"}
    for split in ("val", "test"):
        rows = predictions[predictions["split"] == split]
        assert len(rows) == metrics["data"][f"n_{split}_windows"]
        assert (rows["true"] == rows["predicted"]).mean() == pytest.approx(metrics[split]["accuracy"])
    val, test = (set(predictions.loc[predictions["split"] == s, "recording"]) for s in ("val", "test"))
    assert val and test and not val & test


def test_a_tiny_training_run_on_the_fingertip_beats_chance(compose_config, tmp_path):
    cfg = compose_config(["experiment=textures13", *TINY])
    metrics = run(cfg, tmp_path)
    chance = 1 / 13
    assert metrics["val"]["accuracy"] > 5 * chance, metrics["val"]["accuracy"]
    assert metrics["test"]["accuracy"] > 5 * chance, metrics["test"]["accuracy"]
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert saved["n_parameters"] == metrics["n_parameters"] > 0 and saved["fit_time_s"] > 0
    for split in ("val", "test"):
        assert set(saved[split]["accuracy_by_force_level_n"]) == {"5.0", "20.0"}
        assert len(saved[split]["per_class_accuracy"]) == 13
    assert saved["test"]["accuracy"] == metrics["test"]["accuracy"]
    assert_predictions_match_metrics(tmp_path, metrics)
    assert (tmp_path / "confusion.png").stat().st_size > 0 and (tmp_path / "confusion_test.png").stat().st_size > 0
    (run_events,) = (tmp_path / "tensorboard").iterdir()  # one TensorBoard run, named for what ran
    events = EventAccumulator(str(run_events)).Reload()
    assert len(events.Scalars("accuracy/val")) == 6
    assert {"figures/confusion", "figures/confusion_test"} <= set(events.Tags()["images"])
    assert events.Scalars("final/test_accuracy")[0].value == pytest.approx(metrics["test"]["accuracy"])
    assert {"hparam/val_accuracy", "hparam/test_accuracy"} <= set(events.Tags()["scalars"])
    assert "_hparams_/session_start_info" in events.PluginTagToContent("hparams")


def ten_tones_npz(path):
    """60 two-channel recordings of 10 classes told apart by a tone's frequency (1 to 10 Hz at
    50 Hz, random phase, noise): easy enough that any of the networks must beat chance in 8 epochs."""
    rng = np.random.default_rng(0)
    t = np.arange(200) / 50.0
    frequencies_hz = np.repeat(np.arange(1.0, 11.0), 12)
    X = np.stack([np.stack([np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi)) + 0.3 * rng.standard_normal(200),
                            rng.standard_normal(200)]) for f in frequencies_hz])
    np.savez(path, X=X, y=np.array([f"tone_{f:02.0f}hz" for f in frequencies_hz]))
    return path


@pytest.mark.parametrize("model", ["rescnn", "inceptiontime", "lstm_fcn"])
def test_baselines_train_through_hydra(compose_config, tmp_path, model):
    # Tones, not the fingertip: none of the baselines beats chance on a few fingertip recordings
    # in a test's budget, and a bound that cannot fail tests nothing.
    cfg = compose_config(["experiment=materials10", f"model={model}", "data=recordings_npz",
                          f"data.path={ten_tones_npz(tmp_path / 'tones.npz')}", "data.label=y",
                          "data.window_length=100", "data.window_step=50", "data.trim_start=0", "data.trim_end=0",
                          "trainer.max_epochs=8", "trainer.lr_milestones=[6]", "trainer.progress=false",
                          "trainer.device=cpu"])
    metrics = run(cfg, tmp_path / "run")
    chance = 1 / 10
    assert metrics["val"]["accuracy"] > 5 * chance, metrics["val"]["accuracy"]
    assert metrics["test"]["accuracy"] > 5 * chance, metrics["test"]["accuracy"]
    assert np.isfinite(metrics["val"]["loss"]) and np.isfinite(metrics["test"]["loss"])
    assert_predictions_match_metrics(tmp_path / "run", metrics)


def test_virtual_force_levels_run_through_hydra(compose_config, tmp_path):
    cfg = compose_config(["experiment=materials10", "augment=virtual_force_levels", "scene.passes_per_level=1",
                          "trainer.max_epochs=1", "trainer.progress=false", "trainer.device=cpu"])
    metrics = run(cfg, tmp_path)
    report = metrics["data"]["augment"]
    assert metrics["data"]["n_virtual_windows"] > 0
    assert report["targets"]["5.0" if "5.0" in report["targets"] else 5.0]["neighbours"] == [1.0, 10.0]
