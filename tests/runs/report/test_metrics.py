"""Scores that cannot mislead (issue 45): a percentage error is taken only over true values that
are not zero, and metrics.json says which rows MAPE left out."""
import numpy as np
import pytest

from runs.report.metrics import format_table, mape_notes, regression_metrics


def test_mape_leaves_out_zero_targets_instead_of_dividing_by_them():
    """A force that is sometimes 0 N printed MAPE 8.67e+06 % on the default run's user table."""
    y = np.array([0.0, 0.0, 1.0, 2.0, 4.0])
    predicted = np.array([0.1, 0.05, 1.1, 1.8, 4.4])
    scores = regression_metrics(y, predicted, ["force_n"])
    assert scores["force_n"]["mape_pct"] == pytest.approx(100 * np.mean([0.1 / 1.0, 0.2 / 2.0, 0.4 / 4.0]))
    assert scores["force_n"]["mae"] == pytest.approx(np.mean(np.abs(y - predicted)))   # MAE keeps every row


def test_a_value_within_rounding_of_zero_counts_as_zero():
    y = np.array([1e-9, 5.0, 10.0])
    scores = regression_metrics(y, y + 1.0, ["force_n"])
    assert scores["force_n"]["mape_pct"] == pytest.approx(100 * np.mean([1 / 5, 1 / 10]))


def test_all_zero_targets_have_no_mape_and_the_table_prints_a_dash():
    scores = regression_metrics(np.zeros(4), np.ones(4), ["delta_force_n"])
    assert scores["delta_force_n"]["mape_pct"] is None and scores["average"]["mape_pct"] is None
    assert "—" in format_table({"val": scores, "test": scores})


def test_the_notes_say_which_targets_and_rows_mape_left_out():
    y = np.array([[0.0, 3.0], [1.0, 4.0], [2.0, 5.0]])
    notes = mape_notes({"val": y, "test": y[1:]}, ["force_n", "depth_mm"])
    assert notes == ["val force_n: 1 of 3 true values are zero; MAPE is over the other 2 "
                     "(a percentage of zero is not defined)"]
