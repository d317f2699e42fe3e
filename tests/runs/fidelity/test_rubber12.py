"""The fidelity table's rows that hold for rubber12 (bench/fidelity.py, docs/fidelity.md) keep
holding, with margin: each test measures one observation of the seed paper on the scene the way
the table does (runs/fidelity/rubber12.py), at the same scene seeds 0-2 with fewer repeats, and
asserts it clear of the table's tolerance at every seed. Rows that do not hold are not asserted
(the table records them and why), except the part of row 11 that holds (x and y)."""
import json
from dataclasses import asdict

import numpy as np
import pytest

from runs.fidelity import rubber12 as checks
from runs.fidelity.observations import CHECKS, Row, markdown, scene_params
from runs.fidelity.rubber12 import SceneProbe


@pytest.fixture(scope="module")
def probe():
    return SceneProbe(scene_params("rubber12"), repeats=8)


def test_every_observation_of_the_notes_has_a_row():
    from runs.fidelity.observations import row_order
    numbers = sorted((fn.observation[1] for fn in CHECKS["rubber12"]), key=row_order)
    assert [n.rstrip("ab") for n in numbers] == ["1", "2", "3", "3", "4", "5", "6", "7", "8", "9", "10",
                                                 "11", "12", "13"]
    from runs.fidelity.observations import load_scene
    assert load_scene("fingertip") and len(CHECKS["fingertip"]) == 6      # seed 003: tests/runs/fidelity/test_fingertip.py


def by_seed(measured, key):
    """A row's number at each of the probe's seeds, after checking the row holds (on the mean and
    at every seed, the table's verdict)."""
    assert measured.holds, measured.value
    return np.array(measured.numbers["by_seed"][key])


def test_rows_are_measured_at_three_scene_seeds(probe):
    assert probe.seeds == (0, 1, 2) and [p.params["seed"] for p in probe.seeded] == [0, 1, 2]
    noise = [p.repeat_noise[0] for p in probe.seeded]
    assert not np.allclose(noise[0], noise[1])          # each seed its own specimen and noise draws


def test_repeat_variation_stays_below_the_labs(probe):
    cv = by_seed(checks.repeat_cv(probe), "max_cv")
    # cycle_response is sized to the paper's bound on the lab table's 90 pairs, so at one depth the
    # largest CV sits below the bound but well above the 0.3 % of the scene without it
    assert (cv > 0.4 * 0.023).all() and (cv < 0.023).all()


def test_force_varies_by_position_beyond_the_repeat_variation(probe):
    cv = by_seed(checks.force_varies_with_position(probe), "min_cv")
    assert (cv > 1.2 * 0.023).all()                                     # the smallest, at 3 mm


def test_cycle_response_is_sized_below_the_papers_repeat_cv():
    from runs.fidelity.rubber12_sizing import lab_repeat_cv
    cv = lab_repeat_cv(SceneProbe(scene_params("rubber12")))
    assert (cv < 0.023).all() and (cv > 0.5 * 0.023).all()


def test_resistance_is_nonlinear_in_depth(probe):
    assert (by_seed(checks.nonlinear_depth(probe), "median_departure") > 0.06).all()   # table: 9.0 ± 0.2 %, tolerance 5 %


def test_pressure_is_not_a_copy_of_depth(probe):
    assert (by_seed(checks.pressure_is_not_depth(probe), "corr") < 0.985).all()        # table: 0.973, tolerance 0.99


def test_mirror_ambiguity_is_worst_near_an_edge_midpoint(probe):
    measured = checks.mirror_ambiguity_worst_at_edges(probe)
    edge, centre = by_seed(measured, "edge"), by_seed(measured, "centre")
    assert (edge < 0.5 * centre).all()                  # table: 0.025 ± 0.015 vs 0.136 (seed 1: 0.043)


def test_depth_is_weakly_observable_at_small_depths(probe):
    assert (by_seed(checks.depth_weak_at_small_depths(probe), "shallow_ratio") < 0.7).all()   # table: 0.39 ± 0.01


def test_pressure_shows_over_many_channels(probe):
    assert (by_seed(checks.pressure_is_aggregate(probe), "effective_channels") > 4.0).all()   # table: 9.4, tolerance 3


def test_incremental_sensitivity_falls_at_high_force(probe):
    assert (by_seed(checks.saturation_at_high_force(probe), "ratio") < 0.8).all()   # table: 0.49, tolerance 1


def test_table_ii_position_is_as_accurate_as_on_the_papers_sensor(probe):
    """Row 11 does not hold: depth and pressure are easier here than on the paper's sensor
    (docs/fidelity.md). Its x and y do, within ±0.10 of the paper's 0.947 and 0.976 at every seed."""
    scores = np.array(checks.extra_trees_r2(probe).numbers["by_seed"])         # (seeds, x y z P)
    assert (scores[:, 0] > 0.90).all() and (scores[:, 1] > 0.92).all(), scores   # table: 0.978 ± 0.012, 0.973 ± 0.012


def test_table_ii_r2_does_not_depend_on_the_unit_of_pressure(probe):
    """One forest fits all four targets; on raw targets pressure in pascals chose every split and x, y
    moved with pressure's unit (seed 1: y 0.79 with Pa, 0.95 with kPa). Standardised, the unit only
    changes rounding."""
    from data.preprocessing.features import FEATURE_GROUPS, compute_features
    one = probe.seeded[1]
    table = one.lab_table
    features = compute_features(table.channels, FEATURE_GROUPS)
    targets = table.frame[table.target_columns].to_numpy()
    in_pa = checks.hold_out_r2(features, targets, seed=1)
    in_kpa = checks.hold_out_r2(features, targets * np.array([1.0, 1.0, 1.0, 1e-3]), seed=1)
    assert np.abs(in_pa - in_kpa).max() < 0.04, (in_pa, in_kpa)


def test_a_row_that_flips_on_one_seed_does_not_hold_and_says_so():
    from runs.fidelity.observations import judged_over_seeds
    flipped = judged_over_seeds("x 0.9", [True, False, True], True, "x > 0.5", (0, 1, 2), {})
    assert flipped.holds is False and "holds at 2 of 3 (0, 2), and on the mean" in flipped.value
    assert judged_over_seeds("x 0.9", [True] * 3, True, "x > 0.5", (0, 1, 2), {}).holds is True
    never = judged_over_seeds("x 0.1", [False] * 3, False, "x > 0.5", (0, 1, 2), {})
    assert never.holds is False and "flips" not in never.value


def test_table_prints_every_row_with_a_verdict(probe, capsys):
    rows = [Row("rubber12", *fn.observation[1:], fn(probe)) for fn in CHECKS["rubber12"]   # model rows are slow
            if fn is not checks.extra_trees_r2 and fn.__module__ != "runs.fidelity.rubber12_selection"]
    text = markdown(rows)
    assert text.count("\n") == len(rows) + 1
    verdicts = [line.rsplit("|", 2)[-2].strip() for line in text.splitlines()[2:]]
    assert set(verdicts) <= {"holds", "does not hold", "not measured", "not supported by the paper"}
    assert "holds" in verdicts
    json.dumps([asdict(row) for row in rows])   # the --json output is serialisable


@pytest.mark.slow
def test_selection_rows_use_the_papers_statistics():
    from runs.fidelity.rubber12_selection import extra_trees_selected, uncertainty_pattern
    one = SceneProbe(scene_params("rubber12"), seeds=(0,))
    chosen = extra_trees_selected(one)
    assert set(chosen.numbers["val_r2"]) == {"resmlp", "random_forest", "extra_trees"}
    pattern = uncertainty_pattern(one)
    assert set(pattern.numbers) >= {"boundary / centre", "high / intermediate pressure"}
    assert "depth not judged" in pattern.value


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="row 13 does not hold on the scene since its cycle_response effect was sized "
                   "to the paper's repeat CV (issue 42): reductions -0.81/-0.61/0.14/0.13 (x, y, depth, P) over 3 seeds; "
                   "strict, so the day it holds again this marker must go")
def test_kfold_blending_steadies_the_net():
    """Row 13 (seed §IV-D: K-fold blending reduced the net's prediction variance, 8.3 %), measured
    as bench/kfold_variance.py prints it with the documented settings (table: 10.5-66.6 %), ~3 min."""
    from runs.fidelity.kfold_variance import measure
    reduction = measure(seeds=5, folds=5)["reduction"]
    assert (reduction > 0.05).all(), reduction


def test_every_scene_has_its_module_config_and_probe():
    from runs.fidelity.observations import CONFIGS, PROBES, SCENE_MODULES, load_scene
    assert set(CHECKS) == set(SCENE_MODULES) == set(CONFIGS) == {"rubber12", "fingertip", "capacitive6x6", "ert",
                                                                  "taxels"}
    for scene in CHECKS:
        assert load_scene(scene) and CHECKS[scene] and scene in PROBES


def test_a_scene_whose_module_is_not_written_is_reported_not_fatal(monkeypatch):
    from runs.fidelity.observations import PROBES, SCENE_MODULES, SceneConfig, load_scene, make_probe
    monkeypatch.setitem(SCENE_MODULES, "nowhere", "runs.fidelity.nowhere")
    assert load_scene("nowhere") is False
    monkeypatch.delitem(PROBES, "rubber12")        # a module that registers no probe gets the config
    probe = make_probe("rubber12", repeats=3)
    assert isinstance(probe, SceneConfig) and probe.repeats == 3 and "_target_" not in probe.params
