"""Whole runs and the contracts around them: the calibration split stays out of every other split,
the blend's `mode` and `per_target` switches reach the reported weights, a run repeats exactly,
a user's long-format recordings train end to end, and `fit` gives the process-wide
flush-denormal flag back as it found it."""
import json
from itertools import combinations

import numpy as np
import pandas as pd
import pytest
import torch
from tests.conftest import tiny
from hydra.utils import instantiate

from common.errors import InputError
from data.scenes.fingertip import FingertipScene
from models.resmlp_regressor import ResMLPRegressor
from models.torch_runtime import flushing_denormals
from runs.run import run

TARGETS = ["x_mm", "y_mm", "depth_mm", "pressure_pa"]


# -- the calibration split -------------------------------------------------------------------
@pytest.mark.parametrize("split", ["random", "grouped"])
def test_calibration_split_is_disjoint_from_train_validation_and_test(compose_config, split):
    # 180 lab presses: 90 position-depth groups of two repeats each, so a grouped split that let
    # one repeat into calibration and the other into training would show.
    cfg = compose_config(tiny("extra_trees") + ["scene.n_samples=180", f"data.split={split}"])
    assert cfg.data.calibration_fraction > 0
    dm = instantiate(cfg.data).setup()
    parts = {"train": dm.train_idx, "val": dm.val_idx, "cal": dm.cal_idx, "test": dm.test_idx}
    assert all(len(idx) > 0 for idx in parts.values()), {k: len(v) for k, v in parts.items()}
    assert abs(len(dm.cal_idx) / 180 - cfg.data.calibration_fraction) < 0.05
    for (a, ia), (b, ib) in combinations(parts.items(), 2):
        assert not set(ia.tolist()) & set(ib.tolist()), (a, b)
    assert sorted(np.concatenate(list(parts.values())).tolist()) == list(range(180))
    groups = dm.table.groups
    assert len(np.unique(groups)) == 90
    if split == "grouped":
        for (a, ia), (b, ib) in combinations(parts.items(), 2):
            assert not set(groups[ia].tolist()) & set(groups[ib].tolist()), (a, b)
    # what the blend calibrates on: the calibration split and the validation rows, both held out of fitting
    np.testing.assert_array_equal(dm.calibration[1], dm.y[np.r_[dm.cal_idx, dm.val_idx]])


# -- the blend's weighting switches ----------------------------------------------------------
def blend_selection(compose_config, tmp_path, *overrides):
    small_net = ["model.candidates.resmlp.estimator.widths=[16]", "model.candidates.resmlp.estimator.dropouts=[0.1]"]
    cfg = compose_config(tiny("blend") + ["analysis.ablation=false", *small_net, *overrides])
    metrics = run(cfg, tmp_path)
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert saved["selection"] == json.loads(json.dumps(metrics["selection"]))
    selection = saved["selection"]
    names = selection["candidates"]
    assert len(names) == 3
    weights = np.array([[selection["weights"][n][t] for t in TARGETS] for n in names])
    val_r2 = np.array([[selection["val_r2"][n][t] for t in TARGETS] for n in names])
    return selection, weights, val_r2


def test_blend_argmax_keeps_the_best_candidate_per_target(compose_config, tmp_path):
    # argmax is a switch of the paper's weighting (model.weights=paper); with stacking it is an error
    selection, weights, val_r2 = blend_selection(compose_config, tmp_path, "model.weights=paper", "model.mode=argmax")
    assert selection["mode"] == "argmax" and selection["per_target"] is True
    for k, target in enumerate(TARGETS):
        if target in selection["fallback_targets"]:   # every candidate R^2 <= 0 on validation: equal weights
            np.testing.assert_allclose(weights[:, k], 1.0 / len(weights))
            assert (val_r2[:, k] <= 0).all(), target
        else:                                         # one-hot on the best candidate
            np.testing.assert_array_equal(np.sort(weights[:, k]), [0.0, 0.0, 1.0])
            assert weights[np.argmax(val_r2[:, k]), k] == 1.0, target
    assert len(selection["fallback_targets"]) < len(TARGETS)  # the tiny run still selects somewhere
    with pytest.raises(InputError, match="argmax"):
        run(compose_config(tiny("blend") + ["model.weights=stacking", "model.mode=argmax"]), tmp_path / "stacked")


@pytest.mark.parametrize("weighting", ["paper", "stacking"])
def test_blend_without_per_target_weights_weighs_every_target_alike(compose_config, tmp_path, weighting):
    selection, weights, val_r2 = blend_selection(compose_config, tmp_path, f"model.weights={weighting}",
                                                 "model.per_target=false")
    assert selection["mode"] == "weighted" and selection["per_target"] is False
    np.testing.assert_allclose(weights.sum(axis=0), 1.0, rtol=1e-12)
    np.testing.assert_array_equal(weights, weights[:, :1].repeat(4, axis=1))  # one weight vector
    if weighting == "paper":
        # one weight per candidate, from its validation R^2 averaged over the targets (eq. 18-20)
        score = np.maximum(val_r2.mean(axis=1), 0.0)
        np.testing.assert_allclose(weights[:, 0], score / score.sum(), rtol=1e-9)


# -- determinism -----------------------------------------------------------------------------
MEASURED = ("time", "latency", "throughput", "reps", "cost")


def without_timings(value):
    """metrics.json minus what a clock measures: keys naming a time, latency, throughput,
    repetition count or cost, and every seconds figure (a key ending in _s)."""
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items()
                if not (any(word in k for word in MEASURED) or k.endswith("_s"))}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


# the whole run, feature ablation included, for the trees; the net's ablation would be 7 more fits
SMALL = {"extra_trees": ["analysis.ablation=true"], "resmlp": ["model.widths=[16]", "model.dropouts=[0.1]", "trainer.max_epochs=3",
                                       "analysis.ablation=false"]}


@pytest.mark.parametrize("model", sorted(SMALL))
def test_same_config_and_seed_give_the_same_run(compose_config, tmp_path, model):
    def metrics_of(seed, folder):
        run(compose_config(tiny(model) + SMALL[model] + [f"seed={seed}"]), tmp_path / folder)
        return json.loads((tmp_path / folder / "metrics.json").read_text())

    a, b = metrics_of(5, "first"), metrics_of(5, "second")
    assert without_timings(a)["test"]["average"]["r2"] == a["test"]["average"]["r2"]  # scores stay in
    assert "fit_time_s" in a and "fit_time_s" not in without_timings(a)
    assert ("ablation" in without_timings(a)) is (model == "extra_trees")
    assert without_timings(a) == without_timings(b)
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "first" / "predictions.csv"),
                                  pd.read_csv(tmp_path / "second" / "predictions.csv"), check_exact=True)
    # and the seed matters: another one gives another run
    assert without_timings(metrics_of(6, "third")) != without_timings(a)


# -- a user's long-format recordings ---------------------------------------------------------
def write_long_table(path):
    """The fingertip scene's recordings as one row per time step, in recordings_table's columns."""
    recordings = FingertipScene(boards=["glass/flat", "wood/flat", "bakelite/flat"],
                                force_levels_n=[1, 5, 10, 15, 20, 25], passes_per_level=2, effects={}).generate()
    n, _, steps = recordings.signals.shape
    frame = pd.DataFrame({
        "recording": np.repeat(np.arange(n), steps),
        "time_s": np.tile(recordings.time_s, n),
        **{c: recordings.channel(c).reshape(-1) for c in recordings.channel_names},
        "material": np.repeat(recordings.labels["material"].to_numpy(), steps),
        "force_level_n": np.repeat(recordings.labels["force_level_n"].to_numpy(), steps),
    })
    frame.sample(frac=1.0, random_state=0).to_csv(path, index=False)  # row order must not matter
    return recordings


def test_recordings_table_trains_end_to_end(compose_config, tmp_path):
    path = tmp_path / "rig.csv"
    recordings = write_long_table(path)
    cfg = compose_config(["experiment=materials10", "data=recordings_table", f"data.path={path}",
                          "data.source.channel_columns=[triboelectric_na,piezoresistive_v]",
                          "data.source.force_column=force_level_n", "data.split=force_level",
                          "data.test_fraction=0.5", "data.decimate=10", "trainer.max_epochs=2", "trainer.lr_milestones=[1]", "trainer.progress=false",
                          "trainer.device=cpu"])
    metrics = run(cfg, tmp_path / "run")
    saved = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert saved["val"]["accuracy"] == metrics["val"]["accuracy"]
    rows = pd.read_csv(tmp_path / "run" / "predictions.csv")
    for split in ("val", "test"):  # the reported accuracy is what the written predictions score
        part = rows[rows["split"] == split]
        assert len(part) and saved[split]["accuracy"] == pytest.approx((part["true"] == part["predicted"]).mean())
    assert np.isfinite(saved["val"]["loss"])
    assert set(saved["val"]["accuracy_by_force_level_n"]) == {"5.0", "20.0"}
    assert len(saved["val"]["per_class_accuracy"]) == 3
    data = saved["data"]
    assert data["source"] == {"source": "table", "path": str(path)}  # it learned from the file
    assert data["classes"] == ["bakelite", "glass", "wood"] and data["channels"][0] == "triboelectric_na"
    # 3 boards x 2 passes at each of the 4 training levels; the 12 at 5 and 20 N go to validation and test
    assert data["n_train_recordings"] == 24 and data["n_val_recordings"] + data["n_test_recordings"] == 12
    assert len(recordings) == 36 and data["n_train_windows"] > 0
    assert (tmp_path / "run" / "predictions.csv").stat().st_size > 0


# -- the flush-denormal flag -----------------------------------------------------------------
def tiny_resmlp():
    return ResMLPRegressor(widths=(8,), dropouts=(0.1,), max_epochs=2, batch_size=16, progress=False)


@pytest.mark.parametrize("before", [False, True])
def test_fit_restores_the_flush_denormal_flag(before):
    rng = np.random.default_rng(0)
    X, y = rng.normal(size=(60, 5)), rng.normal(size=(60, 2))
    during = []
    try:
        assert torch.set_flush_denormal(before) or not before  # the CPU supports the flag
        assert flushing_denormals() is before
        model = tiny_resmlp().fit(X, y, epoch_callback=lambda record: during.append(flushing_denormals()))
        assert during == [True, True]  # on while it trains ...
        assert flushing_denormals() is before  # ... and given back as it was
        assert model.predict(X).shape == (60, 2)
        with pytest.raises(InputError):  # a fit that fails gives it back too
            tiny_resmlp().fit(X[:1], y[:1])
        assert flushing_denormals() is before
    finally:
        torch.set_flush_denormal(False)
    assert not flushing_denormals()
