"""The scene contract: only listed effects run, each on its own seeded stream, and the
patch solver is the exact solve, only faster."""
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf

import data.scenes.rubber12 as rubber12
from common.errors import InputError
from data.physics.press_update import NearFarSolver, PatchUpdateSolver
from data.physics.sheet_conduction import pair_resistance_ohm
from data.scenes.rubber12 import Rubber12Scene
from data.scenes.rubber12_effects import EFFECTS

SCENES = Path(__file__).resolve().parents[3] / "configs" / "scene"
DEFAULT_EFFECTS = OmegaConf.to_container(OmegaConf.load(SCENES / "rubber12.yaml").effects)


def scene(effects, **kwargs):
    return Rubber12Scene(effects=effects, progress=False, **{"n_samples": 60, "grid_nodes": 21, **kwargs})


def test_unlisted_effects_are_never_called(monkeypatch, counted_effects):
    spied, calls = counted_effects(EFFECTS)
    monkeypatch.setattr(rubber12, "EFFECTS", spied)
    monkeypatch.setattr(rubber12, "FIELD_EFFECTS", {n: rubber12.EFFECTS[n] for n in rubber12.FIELD_EFFECTS})
    monkeypatch.setattr(rubber12, "READING_EFFECTS", {n: rubber12.EFFECTS[n] for n in rubber12.READING_EFFECTS})
    scene({"contact": {}, "percolation": {}, "adc": {}}).generate()
    assert {n for n, c in calls.items() if c} == {"contact", "percolation", "adc"}


def test_an_effect_does_not_disturb_the_others_random_numbers():
    # temperature_drift with a zero coefficient changes nothing physical; the adc's noise must
    # come out identical with and without it in the list, because each stream is keyed by name.
    without = scene({"contact": {}, "percolation": {}, "adc": {}}).generate().frame
    with_idle = scene({"contact": {}, "percolation": {}, "temperature_drift": {"coefficient_per_c": 0.0},
                       "adc": {}}).generate().frame
    assert without.equals(with_idle)


def test_same_scene_and_seed_give_identical_bytes():
    a = scene(DEFAULT_EFFECTS, seed=11).generate().frame.to_numpy().tobytes()
    b = scene(DEFAULT_EFFECTS, seed=11).generate().frame.to_numpy().tobytes()
    assert a == b


def test_no_effects_means_no_response():
    frame = scene({}).generate().frame
    assert frame.filter(like="r_").nunique().max() == 1 and (frame["pressure_pa"] == 0).all()


@pytest.mark.parametrize("effects, message", [
    ({"contact": {}, "humidity": {}}, "scene rubber12: unknown effect 'humidity'; valid effects: adc, contact"),
    ({"percolation": {}}, "effect 'percolation' needs 'contact' listed too"),
    ({"contact": {}, "outlier_rejection": {}}, "effect 'outlier_rejection' needs 'adc' listed too"),
])
def test_effect_errors_name_the_scene_and_what_is_valid(effects, message):
    with pytest.raises(InputError, match=message):
        scene(effects).generate()


def _strained_conductance(solver):
    """Per-node conductance of presses near a corner, at the centre, near an edge and near an
    electrode, through the default scene's film strain, percolation and tunnelling."""
    state = {"x_mm": np.array([4.0, 25.0, 47.0, 12.5]), "y_mm": np.array([4.0, 25.0, 30.0, 49.0]),
             "depth_mm": np.array([3.0, 1.0, 2.0, 0.5]), "node_xy_mm": solver.grid.node_xy_mm,
             "geometry": {"probe_radius_mm": 3.5, "gel_thickness_mm": 6.0, "side_mm": 50.0,
                          "spacing_mm": solver.grid.spacing_mm}}
    for name in ("contact", "percolation", "tunneling"):
        EFFECTS[name](state, **DEFAULT_EFFECTS[name])
    return 1e-4 * state["conductance_scale"]


def test_patch_solver_equals_the_full_sparse_solve():
    solver, fast = rubber12._solvers(50.0, 33, 2.5, 1.0e4, 0.01)
    conductance = _strained_conductance(solver)
    patched = fast.patch.transfer_resistance(conductance)
    exact = np.stack([solver.transfer_resistance(g) for g in conductance])
    np.testing.assert_allclose(patched, exact, rtol=1e-9, atol=1e-9 * np.abs(exact).max())
    # a change too wide for the low-rank update takes the exact path and still agrees
    wide = PatchUpdateSolver(solver, 1e-4, max_patch_nodes=10).transfer_resistance(conductance[:2])
    np.testing.assert_allclose(wide, exact[:2], rtol=1e-12, atol=1e-12 * np.abs(exact).max())


def test_near_far_solver_is_close_to_the_full_solve_and_exact_at_zero_tolerance():
    # The scene's solver: exact near the probe, first order in the wide, weak rest of the strain.
    solver, fast = rubber12._solvers(50.0, 33, 2.5, 1.0e4, 0.01)
    conductance = _strained_conductance(solver)
    pairs = rubber12.measurement_pairs("near_opposite")
    exact = pair_resistance_ohm(np.stack([solver.transfer_resistance(g) for g in conductance]), pairs)
    rest = pair_resistance_ohm(solver.transfer_resistance(np.full(conductance.shape[1], 1e-4)), pairs)
    signal = np.abs(exact - rest).max(axis=1, keepdims=True)
    error = np.abs(pair_resistance_ohm(fast.transfer_resistance(conductance), pairs) - exact) / signal
    assert error.max() < 0.02, error.max()                 # measured: 0.7 % of the press's signal at worst
    # the wide strain really reaches past the near field, so the first-order part is exercised
    near = np.abs(conductance / 1e-4 - 1) > 0.01
    assert ((conductance != 1e-4) & ~near).sum(axis=1).min() > 5
    exact_path = NearFarSolver(fast.patch, near_tolerance=0.0).transfer_resistance(conductance)
    np.testing.assert_allclose(pair_resistance_ohm(exact_path, pairs), exact, rtol=1e-9)
