"""Time-series classifiers: architecture facts, branch isolation, training through Hydra."""
import json

import numpy as np
import pytest
import torch
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from models.torch_runtime import count_parameters
from models.nets.inceptiontime import InceptionTime
from models.nets.lstm_fcn import LSTMFCN
from models.nets.prcnn import PRCNN
from models.nets.rescnn import ResCNN
from models.runs.run import run


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


def test_a_tiny_training_run_on_the_fingertip_beats_chance(compose_config, tmp_path):
    cfg = compose_config(["experiment=textures13", *TINY])
    metrics = run(cfg, tmp_path)
    chance = 1 / 13
    assert metrics["val"]["accuracy"] > 5 * chance, metrics["val"]["accuracy"]
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert saved["n_parameters"] == metrics["n_parameters"] > 0 and saved["fit_time_s"] > 0
    assert set(saved["val"]["accuracy_by_force_level_n"]) == {"5.0", "20.0"}
    assert len(saved["val"]["per_class_accuracy"]) == 13
    assert (tmp_path / "confusion.png").stat().st_size > 0
    events = EventAccumulator(str(tmp_path / "tensorboard")).Reload()
    assert len(events.Scalars("accuracy/val")) == 6 and "confusion/val" in events.Tags()["images"]


@pytest.mark.parametrize("model", ["rescnn", "inceptiontime", "lstm_fcn"])
def test_baselines_train_through_hydra(compose_config, tmp_path, model):
    cfg = compose_config(["experiment=materials10", f"model={model}", "scene.passes_per_level=1",
                          "trainer.max_epochs=1", "trainer.progress=false", "trainer.device=cpu"])
    metrics = run(cfg, tmp_path)
    assert 0.0 <= metrics["val"]["accuracy"] <= 1.0 and np.isfinite(metrics["val"]["loss"])


def test_virtual_force_levels_run_through_hydra(compose_config, tmp_path):
    cfg = compose_config(["experiment=materials10", "augment=virtual_force_levels", "scene.passes_per_level=1",
                          "trainer.max_epochs=1", "trainer.progress=false", "trainer.device=cpu"])
    metrics = run(cfg, tmp_path)
    report = metrics["data"]["augment"]
    assert metrics["data"]["n_virtual_windows"] > 0
    assert report["targets"]["5.0" if "5.0" in report["targets"] else 5.0]["neighbours"] == [1.0, 10.0]
