"""The capacitive fidelity rows that hold (runs/fidelity/capacitive6x6.py, docs/fidelity.md) keep
holding, with margin, on one seed; the paper-configured models are what they say; the tree wins
(row 4a); the model ranking under both protocols is measured (slow).
Row 1 (time per frame) is not asserted: no timed assertions."""
import numpy as np
import pytest

from runs.fidelity import capacitive6x6 as rows
from runs.fidelity.observations import CHECKS, scene_params


@pytest.fixture(scope="module")
def probe():
    return rows.CapacitiveProbe(scene_params("capacitive6x6"), seeds=[0])


def test_every_observation_of_seed_001_has_a_row():
    assert [fn.observation[1] for fn in CHECKS["capacitive6x6"]] == ["1", "2", "3", "4a", "4b", "5", "6"]


def test_the_two_protocols_split_differently():
    table = rows.CapacitiveProbe(scene_params("capacitive6x6", ["scene.n_repetitions=10"]), seeds=[0]).tables[0]
    for protocol in rows.PROTOCOLS:
        train, test = rows.split(table, protocol, seed=0)
        assert len(np.intersect1d(train, test)) == 0 and len(train) + len(test) == len(table.frame)
        assert abs(len(test) / len(table.frame) - rows.TEST_FRACTION) < 0.05
    train, test = rows.split(table, "by repetition", seed=0)
    assert not set(table.groups[train]) & set(table.groups[test])        # whole repetitions apart
    train, test = rows.split(table, "paper", seed=0)
    assert set(table.groups[train]) & set(table.groups[test])            # the paper's split mixes them


def test_detection_limit_peak_and_linearity_are_the_papers(probe):
    numbers = rows.detection_limit_and_linearity(probe).numbers
    assert 0.07 < np.mean(numbers["lod_n"]) < 0.15                  # table: 0.108, tolerance 0.05-0.2 N
    assert 115 < np.mean(numbers["peak_counts"]) < 190              # table: 143, tolerance 100-225 counts
    assert 0.995 < np.mean(numbers["line_r2"]) < 0.999              # table: 0.9967, tolerance 0.99; the paper 0.995-0.998


def test_decision_tree_reaches_the_papers_own_accuracy(probe):
    numbers = rows.decision_tree_accuracy(probe).numbers
    assert 0.03 < np.mean(numbers["rmse"]) < 0.08                   # table: 0.04, tolerance 0.022-0.117 N
    assert np.mean(numbers["r2"]) > 0.995                           # tolerance 0.99
    assert abs(np.mean(numbers["slope"]) / 51.76 - 1) < 0.15        # table: 47, tolerance ±20 %


def test_tracker_keeps_labels_consistent(probe):
    numbers = rows.labels_stay_consistent(probe).numbers
    assert np.mean(numbers["idf1"]) > 0.95                          # table: 0.97, tolerance 0.9


def test_roughness_tells_steps_from_a_smooth_curve():
    force = np.linspace(0.1, 3.0, 300)
    noise = 0.01 * np.random.default_rng(0).standard_normal(300)
    steps = np.round(force * 2) / 2                                 # a tree's plateaus, 0.5 N apart
    assert rows.roughness(force, force + noise) < 0.015 < 0.1 < rows.roughness(force, steps)


def test_paper_configured_models_are_one_per_sensor_from_its_own_reading():
    """The paper-configured linear regression is, press for press, a least-squares line from the
    pressed cell's reading to force fitted on that cell's training presses alone."""
    probe = rows.CapacitiveProbe(scene_params("capacitive6x6", ["scene.n_repetitions=10"]), seeds=[0])
    table = probe.tables[0]
    train, test = rows.split(table, "paper", seed=0)
    rmc, force, cell = rows._pressed_cell_rmc(table), table.frame["force_n"].to_numpy(), rows._pressed_cell_index(table)
    expected = np.empty(len(test))
    for which in np.unique(cell):
        slope, intercept = np.polyfit(rmc[train][cell[train] == which], force[train][cell[train] == which], 1)
        expected[cell[test] == which] = slope * rmc[test][cell[test] == which] + intercept
    rmse = np.sqrt(np.mean((expected - force[test]) ** 2))
    assert probe.fit("paper", 0, "linear_regression", "paper-configured")["rmse"] == pytest.approx(rmse, rel=1e-9)
    assert len(probe.fit("paper", 0, "gaussian_process", "paper-configured")["sweep"]) == rows.SWEEP_PRESSES


def test_the_paper_configured_tree_is_best_by_a_margin():
    """Row 4a as it is judged (docs/fidelity.md): the paper-configured tree beats every other
    model on the paper's split and on the split by repetition, because the default sensor's
    response bends as the paper's does; the linear models' R² lies in the paper's 0.995-0.998
    band; the GP with scikit-learn 1.2.2's default kernel (fixed, no noise term) predicts some
    presses far off the force (row 5)."""
    probe = rows.CapacitiveProbe(scene_params("capacitive6x6", ["scene.n_repetitions=20"]), seeds=[0])
    for protocol in rows.PROTOCOLS:
        rmse = {m: v.mean() for m, v in probe.per_model(protocol, "rmse", configuration="paper-configured").items()}
        assert rmse["decision_tree"] < 0.6 * min(rmse["linear_regression"], rmse["svr"])   # table: 0.018 vs 0.059 N
        assert rmse["gaussian_process"] > 1.0                                          # table: several N
        assert rmse["decision_tree"] == min(rmse.values())                            # row 4a's criterion
    r2 = probe.per_model("paper", "r2", configuration="paper-configured")
    assert 0.99 < r2["linear_regression"].mean() < 0.999 < r2["decision_tree"].mean()   # the paper: 0.995-0.998, 0.9996


@pytest.mark.slow
def test_model_ranking_is_measured_under_both_protocols():
    """Rows 3-4a as bench/fidelity.py measures them on one seed (~1 min): every model scored
    under both splits, and the ranking reported for each."""
    probe = rows.CapacitiveProbe(scene_params("capacitive6x6"), seeds=[0])
    measured = rows.decision_tree_is_best(probe)
    assert len(measured.numbers["best"]) == len(rows.PROTOCOLS) * len(rows.CONFIGURATIONS)
    for configuration in rows.CONFIGURATIONS:
        for protocol in rows.PROTOCOLS:
            assert f"{configuration}, {protocol}: " in measured.value
        r2 = probe.per_model(protocol, "r2")
        assert r2["linear_regression"].min() > 0.995                # the paper: linear > 0.995
