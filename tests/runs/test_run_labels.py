"""What a run writes says what it did (issue 45): metrics.json, the log and TensorBoard name the
chosen model and its members the same way, count the splits one way, say a split in the words of
the data the run read, leave out importances of a candidate that carries no weight, and say
where MAPE, temperature scaling or interval calibration could mislead."""
import json
import logging

import numpy as np
import pandas as pd
import pytest

from runs.classification import _calibrate
from runs.regression import coverage_warnings, weighted_importances
from runs.run import run
from runs.split_notes import split_note

TINY_REGRESSION = ["scene.n_samples=120", "scene.grid_nodes=21", "scene.progress=false", "trainer.max_epochs=3",
                   "trainer.progress=false", "data.n_folds=2",
                   "model.candidates.regression.kfold_blend.candidates.random_forest.estimator.n_estimators=5",
                   "model.candidates.regression.kfold_blend.candidates.extra_trees.estimator.n_estimators=5"]


def test_a_default_run_names_the_chosen_model_its_members_and_its_splits_one_way(compose_config, tmp_path, caplog):
    """Before: metrics.json said "KFoldBlend" for resmlp_seeds, the log "KFoldBlend fitted in 8.82 s"
    (the whole choice) and "scores over 5 splits (KFoldBlend refitted on each)" beside "splits: 4 splits"."""
    with caplog.at_level(logging.INFO):
        metrics = run(compose_config([*TINY_REGRESSION, "spread.splits=2"]), tmp_path)
    written = json.loads((tmp_path / "metrics.json").read_text())
    chosen = written["choice"]["chosen"]
    assert written["model"] == chosen == metrics["model"]
    assert written["model_class"] in ("KFoldBlend", "ValidationWeightedBlend")
    if chosen == "resmlp_seeds":
        assert written["members"].startswith("2 ") and "seed-ensemble members" in written["members"]
    else:
        assert written["members"] == "blend of resmlp, random_forest, extra_trees"
    log = caplog.text
    assert f"{chosen} ({written['members']}) fitted in " in log and "choosing among 2 candidates took" in log
    assert "KFoldBlend fitted" not in log and "KFoldBlend refitted" not in log
    assert f"scores over 2 splits: this run's and 1 more ({chosen} refitted on each)" in log
    assert "refits on the other splits: 1 splits" in log
    assert written["data"]["split_note"].startswith("every repeat of a position-depth pair")   # a scene's own words
    assert tensorboard_hparams(tmp_path)["model"] == chosen        # was "ValidationChoice"


def tensorboard_hparams(run_dir) -> dict:
    """The string hyper-parameters of the run's TensorBoard session (its HPARAMS tab)."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator
    from tensorboard.plugins.hparams import metadata
    for folder in sorted({p.parent for p in run_dir.glob("tensorboard/**/events.out.tfevents.*")}):
        content = EventAccumulator(str(folder)).Reload().PluginTagToContent(metadata.PLUGIN_NAME)
        if metadata.SESSION_START_INFO_TAG in content:
            start = metadata.parse_session_start_info_plugin_data(content[metadata.SESSION_START_INFO_TAG])
            return {name: value.string_value for name, value in start.hparams.items()}
    raise AssertionError("no TensorBoard session with hyper-parameters")


def test_a_users_table_gets_its_own_split_note():
    """Before: a CSV without positions read "every repeat of a position-depth pair on one side"."""
    summary = {"split": "grouped", "split_note": "every repeat of a position-depth pair on one side",
               "source": {"source": "table", "path": "rig.csv"}}
    assert "position-depth" not in split_note(summary, None)
    assert split_note(summary, None).startswith("each row its own group (no data.group_columns)")
    assert split_note(summary, ["press_id"]).startswith("rows that share press_id (data.group_columns)")
    scene = {**summary, "source": {"source": "scene", "scene": "rubber12"}}
    assert split_note(scene, None) == summary["split_note"]


def test_a_table_run_reports_mape_over_non_zero_forces_and_its_own_split(compose_config, tmp_path):
    rng = np.random.default_rng(0)
    force = np.round(np.abs(rng.normal(0, 2, 160)) * (rng.random(160) > 0.25), 3)   # a quarter at 0 N
    pd.DataFrame({"r_01_ohm": 1000 + 50 * force + rng.normal(0, 5, 160), "r_02_ohm": 900 - 30 * force,
                  "force_n": force}).to_csv(tmp_path / "rig.csv", index=False)
    cfg = compose_config(["data=table", f"data.path={tmp_path / 'rig.csv'}", "data.target_columns=[force_n]",
                          "model=extra_trees", "model.n_estimators=10"])
    metrics = run(cfg, tmp_path / "run")
    assert metrics["test"]["force_n"]["mape_pct"] < 1000          # was 1e6 % and more with zeros divided by
    assert any(note.startswith("test force_n: ") for note in metrics["metric_notes"]["mape_pct"])
    assert "position-depth" not in metrics["data"]["split_note"]


class _Blend:
    """A stand-in for a blend whose only candidate with importances has weight 0."""
    def __sklearn_tags__(self):
        from sklearn.base import BaseEstimator

        from models.capabilities import declare
        return declare(BaseEstimator().__sklearn_tags__(), weighs_candidates=True, importances=True)

    def importances(self):
        return "random_forest", np.array([0.7, 0.3])


@pytest.mark.parametrize("weight, drawn", [(0.0, False), (0.4, True)])
def test_importances_of_a_candidate_without_weight_are_not_drawn(weight, drawn):
    metrics = {"model": "kfold_blend", "selection": {"weights": {"random_forest": {"force_n": weight}}}}
    given = weighted_importances(_Blend(), metrics)
    assert (given is not None) == drawn
    if drawn:
        assert "random_forest, blend weight force_n 0.40" in given[0]
    else:
        assert "weight 0" in metrics["importances_note"]


def test_coverage_below_the_target_is_a_warning_beside_the_number():
    """Before: 'depth_mm': '0.929 -> 0.843' without a word."""
    uncertainty = {"nominal": 0.95, "coverage_raw": {"x_mm": 0.929, "depth_mm": 0.929},
                   "coverage_calibrated": {"x_mm": 0.957, "depth_mm": 0.843}}
    (warning,) = coverage_warnings(uncertainty, 70)["warnings"]
    assert warning.startswith("depth_mm: calibrated 95 % intervals cover 0.843 of the 70 test rows, below the 0.95 "
                              "target, lowered by calibration from 0.929")


class _Classifier:
    """Probabilities p ** beta renormalised; `calibrate` sets beta to `fitted` (a bad temperature
    when fitted is far from 1), as a TableClassifier's temperature scaling would."""
    def __init__(self, fitted):
        self.fitted, self.temperature_beta_ = fitted, 1.0

    def predict_proba(self, X):
        raw = np.column_stack([X[:, 0], 1 - X[:, 0]]) ** self.temperature_beta_
        return raw / raw.sum(axis=1, keepdims=True)

    def calibrate(self, X, y):
        self.temperature_beta_ = self.fitted
        return self


class _Rows:
    """The datamodule's calibration and test rows: p(class 0) in X, labels drawn from it."""
    def __init__(self, seed=0, n=120):
        rng = np.random.default_rng(seed)
        p = rng.uniform(0.05, 0.95, (2 * n, 1))
        y = (rng.random(2 * n) > p[:, 0]).astype(int)
        self.calibration, self.test = (p[:n], y[:n]), (p[n:], y[n:])
        self.calibration_idx, self.classes, self.seed = np.arange(n), np.array(["a", "b"]), seed


def test_temperature_scaling_that_raises_its_held_out_loss_is_not_applied():
    """The classifier's probabilities are right; a temperature of 4 makes them overconfident."""
    model = _Classifier(fitted=4.0)
    report = _calibrate(model, _Rows())
    assert report["method"] is None and model.temperature_beta_ == 1.0
    assert report["note"].startswith("temperature scaling not applied: it raised the held-out log loss")
    assert report["held_out_loss"]["calibrated"] > report["held_out_loss"]["uncalibrated"]


def test_temperature_scaling_kept_on_calibration_rows_says_when_test_got_worse():
    model = _Classifier(fitted=1.02)     # within noise on the calibration rows: the documented default stays
    rows = _Rows()
    rows.test = (rows.test[0], 1 - rows.test[1])   # test labels flipped: any sharpening hurts there
    report = _calibrate(model, rows)
    assert report["method"] == "temperature" and model.temperature_beta_ == 1.02
    assert report["test_loss"] > report["test_loss_uncalibrated"]
    assert report["note"].startswith("temperature scaling made the test log loss worse")
