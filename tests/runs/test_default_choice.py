"""The default model (model=auto) in whole runs: on a scene it chooses among the regression
variants on validation and reports its scores over repeated grouped splits while exporting one
model; on recordings it chooses a time-series model within the budget and says what it skipped."""
import json

import numpy as np
import pandas as pd
import pytest

from runs.run import run

TINY_REGRESSION = ["scene.n_samples=120", "scene.grid_nodes=21", "scene.progress=false", "trainer.max_epochs=3",
                   "trainer.progress=false", "data.n_folds=2",
                   "model.candidates.regression.kfold_blend.candidates.random_forest.estimator.n_estimators=5",
                   "model.candidates.regression.kfold_blend.candidates.extra_trees.estimator.n_estimators=5"]


def test_the_default_run_chooses_on_validation_and_reports_its_spread_over_grouped_splits(compose_config, tmp_path):
    metrics = run(compose_config([*TINY_REGRESSION, "spread.splits=2"]), tmp_path)
    choice, spread = metrics["choice"], metrics["spread"]
    assert choice["task"] == "regression" and set(choice["validation"]) == {"resmlp_seeds", "kfold_blend"}
    best = max(choice["validation"].values(), key=lambda s: s["r2"])["r2"]
    assert choice["validation"][choice["chosen"]]["r2"] == best
    assert metrics["val"]["average"]["r2"] == pytest.approx(best)   # the reported model is the chosen one
    assert spread["splits"] == 2 and spread["split"] == "grouped" and spread["split_seeds"] == [0, 1]
    for target in ("x_mm", "y_mm", "depth_mm", "pressure_pa"):
        r2 = spread["test"][target]["r2"]
        assert r2["n"] == 2
        # two values: each lies sd / sqrt(2) from their mean, this run's own among them
        assert abs(metrics["test"][target]["r2"] - r2["mean"]) == pytest.approx(r2["sd"] / np.sqrt(2), abs=1e-9)
    written = json.loads((tmp_path / "metrics.json").read_text())
    assert written["spread"]["test"]["average"]["r2"]["n"] == 2 and written["choice"]["chosen"] == choice["chosen"]
    assert (tmp_path / "model.onnx").is_file()


def test_a_declared_split_has_no_other_draws_to_spread_over(compose_config, tmp_path):
    rng = np.random.default_rng(0)
    n = 90
    frame = pd.DataFrame({"r_ohm": rng.uniform(900, 1100, n), "s_ohm": rng.uniform(900, 1100, n)})
    frame["depth_mm"] = (frame.r_ohm - 900) / 100 + 0.05 * rng.uniform(0, 1, n)
    frame["split"] = np.where(np.arange(n) < 60, "train", np.where(np.arange(n) < 75, "val", "test"))
    frame.to_csv(tmp_path / "rig.csv", index=False)
    cfg = compose_config(["data=table", f"data.path={tmp_path / 'rig.csv'}", "data.target_columns=[depth_mm]",
                          "model=extra_trees", "model.n_estimators=5", "spread.splits=3"])
    metrics = run(cfg, tmp_path / "run")
    assert metrics["spread"]["splits"] == 1 and "declares its split" in metrics["spread"]["note"]


def recordings(path, n=24, steps=64):
    """Two classes of tones, one channel: a net tells them apart in a few epochs."""
    rng = np.random.default_rng(0)
    t = np.arange(steps) / steps
    y = np.arange(n) % 2
    X = np.sin(2 * np.pi * (2 + 4 * y)[:, None] * t + rng.uniform(0, 6, (n, 1)))[:, None, :]
    np.savez(path, X=(X + 0.2 * rng.standard_normal(X.shape)).astype(np.float32), y=np.array(["low", "high"])[y])
    return path


def test_recordings_without_a_model_train_the_choice_within_its_budget(compose_config, tmp_path):
    path = recordings(tmp_path / "rig.npz")
    cfg = compose_config(["data=recordings_npz", f"data.path={path}", "trainer.max_epochs=2", "trainer.progress=false",
                          "model.budget_s=0.001", "model.skip_unwinnable=false"])   # the cheapest always runs; nothing
    metrics = run(cfg, tmp_path / "run")                                                # else fits in the budget
    choice = metrics["choice"]
    assert choice["task"] == "recordings" and choice["chosen"] == "minirocket" and list(choice["validation"]) == [
        "minirocket"]
    assert list(choice["skipped"]) == ["hydra_minirocket", "rocket_mixture", "prcnn", "rescnn", "inceptiontime"]   # by relative cost
    assert all("model.budget_s=0.001" in reason for reason in choice["skipped"].values())
    assert (tmp_path / "run" / "model.onnx").is_file()


def test_recordings_choose_the_better_model_on_validation_when_the_budget_allows(compose_config, tmp_path):
    path = recordings(tmp_path / "rig.npz")
    cfg = compose_config(["data=recordings_npz", f"data.path={path}", "trainer.max_epochs=2", "trainer.progress=false",
                          "model.budget_s=null", "model.candidates.recordings.hydra_minirocket.n_features=840",
                          "model.skip_unwinnable=false", "~model.candidates.recordings.minirocket", "~model.candidates.recordings.rocket_mixture",
                          "~model.candidates.recordings.rescnn", "~model.candidates.recordings.inceptiontime"])
    metrics = run(cfg, tmp_path / "run")
    choice = metrics["choice"]
    assert set(choice["validation"]) == {"hydra_minirocket", "prcnn"} and not choice["skipped"]
    accuracy = {name: score["accuracy"] for name, score in choice["validation"].items()}
    assert choice["chosen"] == max(accuracy, key=accuracy.get) or "not significantly more (McNemar" in choice["reason"]
    assert metrics["val"]["accuracy"] == pytest.approx(choice["validation"][choice["chosen"]]["accuracy"])


def declared_train_test(path, n=36, steps=64):
    """Tones as above with a declared train / test split and no validation: 24 train, 12 test."""
    recordings(path, n, steps)
    with np.load(path) as data:
        X, y = data["X"], data["y"]
    np.savez(path, X=X, y=y, split=np.where(np.arange(n) % 3 == 2, "test", "train"))
    return X[np.arange(n) % 3 == 2]


def test_a_declared_train_test_split_chooses_on_held_out_training_predictions_and_trains_on_every_recording(
        compose_config, tmp_path, monkeypatch):
    """Every candidate fits all 24 training recordings (none carved off for validation), is scored
    on its own held-out predictions of them (ROCKET: leave-one-out; the net: its folds'), and no
    test recording reaches the choice."""
    from models.rocket.classifier import RocketClassifier
    from models.timeseries_classifier import TimeSeriesClassifier
    X_test = declared_train_test(tmp_path / "rig.npz")
    seen = []
    for cls in (RocketClassifier, TimeSeriesClassifier):
        for method in ("fit", "predict_proba"):
            def spy(self, X, *args, _real=getattr(cls, method), _method=method, **kwargs):
                seen.append((type(self).__name__, _method, np.asarray(X)))
                return _real(self, X, *args, **kwargs)
            monkeypatch.setattr(cls, method, spy)
    overrides = ["data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}", "trainer.max_epochs=2",
                 "trainer.progress=false", "model.budget_s=null", "cost.onnx_latency_calls=0",
                 "model.candidates.recordings.hydra_minirocket.n_features=840", "model.skip_unwinnable=false",
                 "~model.candidates.recordings.minirocket", "~model.candidates.recordings.rocket_mixture",
                 "~model.candidates.recordings.rescnn", "~model.candidates.recordings.inceptiontime"]
    metrics = run(compose_config(overrides), tmp_path / "run")
    choice = metrics["choice"]
    assert choice["scored_on"] == {"rows": "training, held out", "n": 24,
                                   "by": {"hydra_minirocket": "leave-one-out", "prcnn": "3 stratified folds"}}
    assert "held-out accuracy over all 24 training recordings" in choice["reason"]
    assert metrics["data"]["n_train_recordings"] + metrics["data"]["n_val_recordings"] == 24
    assert metrics["data"]["n_fit_recordings"] == 24 and "trained on every one" in metrics["data"]["validation"]
    assert metrics["val"]["accuracy"] == pytest.approx(choice["validation"][choice["chosen"]]["accuracy"])
    fits = [(name, len(X)) for name, method, X in seen if method == "fit"]
    assert ("RocketClassifier", 24) in fits and ("TimeSeriesClassifier", 24) in fits   # the choice's fits: all 24
    assert max(n for _, n in fits) == 24                                               # none saw a test recording
    # The run's first call on 12 recordings is the reported model's test prediction (folds hold out 8):
    # the windows as the datamodule hands them over; nothing before it, the choice included, saw one.
    first_test = next(k for k, (_, method, X) in enumerate(seen) if method == "predict_proba" and len(X) == len(X_test))
    test_rows = {row.tobytes() for row in seen[first_test][2]}
    assert first_test > 0 and not any(row.tobytes() in test_rows for _, _, X in seen[:first_test] for row in X)
    again = run(compose_config(overrides), tmp_path / "again")   # same seed, same choice and scores
    assert again["choice"]["validation"] == choice["validation"] and again["test"] == metrics["test"]


def test_the_default_fits_no_costlier_candidate_that_could_not_win_and_says_what_the_choice_cost(
        compose_config, tmp_path, caplog):
    """Tones MiniRocket gets (nearly) all right: no candidate could be significantly more accurate,
    so none is fitted, each named with the reason; the log says the choosing apart from the chosen
    model's own fit, and metrics.json holds the trade and both times."""
    declared_train_test(tmp_path / "rig.npz")
    overrides = ["data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}", "trainer.progress=false",
                 "cost.onnx_latency_calls=0", "model.candidates.recordings.minirocket.n_features=840"]
    with caplog.at_level("INFO"):
        metrics = run(compose_config(overrides), tmp_path / "run")
    choice = metrics["choice"]
    assert choice["chosen"] == "minirocket" and list(choice["validation"]) == ["minirocket"]
    assert list(choice["skipped"]) == ["hydra_minirocket", "rocket_mixture", "prcnn", "rescnn", "inceptiontime"]
    assert all("can be significantly more accurate" in why and "of 24 scored recordings" in why
               for why in choice["skipped"].values())
    assert choice["prefer"] == "cheapest_within_noise" and choice["trade"]["kept"] == "minirocket"
    assert choice["latency_ms"]["minirocket"] > 0
    assert metrics["cost"]["chosen_fit_time_s"] == choice["fit_time_s"]["minirocket"] <= metrics["fit_time_s"]
    assert "the chosen minirocket's own fit:" in caplog.text and "model choice took" in caplog.text


@pytest.mark.parametrize("chosen_model, holds_out_itself", [(["model=minirocket", "model.n_features=840"], True),
                                                            (["model=prcnn", "trainer=reference"], True),
                                                            (["model=prcnn", "trainer=tsc"], False)])
def test_a_chosen_model_that_holds_out_itself_trains_on_every_declared_training_recording(
        compose_config, tmp_path, chosen_model, holds_out_itself):
    """A ROCKET member (leave-one-out) or a net choosing its epochs on folds (trainer=reference)
    trains on all 24 declared training recordings and is scored on its held-out predictions of
    them; a net early-stopped on validation (trainer=tsc) still needs the carved ones."""
    declared_train_test(tmp_path / "rig.npz")
    overrides = ["data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}", "trainer.max_epochs=2",
                 "trainer.progress=false", "cost.onnx_latency_calls=0", *chosen_model]
    metrics = run(compose_config(overrides), tmp_path / "run")
    n_carved = metrics["data"]["n_val_recordings"]
    assert metrics["data"]["n_train_recordings"] + n_carved == 24 and n_carved > 0
    if holds_out_itself:
        assert metrics["data"]["n_fit_recordings"] == 24 and "trained on every one" in metrics["data"]["validation"]
    else:
        assert "n_fit_recordings" not in metrics["data"]


def test_one_training_recording_per_class_trains_with_leave_one_out_scoring(compose_config, tmp_path):
    """Nothing can be carved for validation: the default scores on held-out training predictions
    (no traceback), and fits nothing costlier, since no held-out prediction of a class's only
    recording can be right."""
    rng = np.random.default_rng(0)
    t = np.arange(64) / 64
    y = np.array([0, 1, 2, 0, 1, 2])
    X = np.sin(2 * np.pi * (2 + 3 * y)[:, None] * t)[:, None, :] + 0.1 * rng.standard_normal((6, 1, 64))
    np.savez(tmp_path / "rig.npz", X=X.astype(np.float32), y=np.array(["a", "b", "c"])[y],
             split=np.array(["train"] * 3 + ["test"] * 3))
    metrics = run(compose_config(["data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}", "trainer.progress=false",
                                  "cost.onnx_latency_calls=0"]), tmp_path / "run")
    choice = metrics["choice"]
    assert choice["chosen"] == "minirocket" and choice["scored_on"]["by"] == {"minirocket": "leave-one-out"}
    assert "wrong on 0 of 3 scored recordings (of those a candidate could get right" in choice["skipped"]["prcnn"]
    assert "leave-one-out" in metrics["data"]["validation"]
