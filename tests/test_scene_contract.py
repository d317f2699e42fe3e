"""The scene contract: only listed effects run, each on its own seeded stream, and the
patch solver is the exact solve, only faster."""
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf

import data.scenes.rubber12 as rubber12
from data.physics.sheet_conduction import PatchUpdateSolver
from data.errors import InputError
from data.scenes.rubber12 import Rubber12Scene
from data.scenes.rubber12_effects import EFFECTS

SCENES = Path(__file__).resolve().parents[1] / "configs" / "scene"
DEFAULT_EFFECTS = OmegaConf.to_container(OmegaConf.load(SCENES / "rubber12.yaml").effects)


def scene(effects, **kwargs):
    return Rubber12Scene(effects=effects, progress=False, **{"n_samples": 60, "grid_nodes": 21, **kwargs})


def test_unlisted_effects_are_never_called(monkeypatch):
    calls = {name: 0 for name in EFFECTS}

    def spy(name, fn):
        def wrapped(*args, **kwargs):
            calls[name] += 1
            return fn(*args, **kwargs)
        wrapped.__signature__ = __import__("inspect").signature(fn)
        return wrapped

    monkeypatch.setattr(rubber12, "EFFECTS", {name: spy(name, fn) for name, fn in EFFECTS.items()})
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


def test_patch_solver_equals_the_full_sparse_solve():
    solver, fast = rubber12._solvers(50.0, 33, 2.5, 1.0e4)
    state = {"x_mm": np.array([4.0, 25.0, 47.0, 12.5]), "y_mm": np.array([4.0, 25.0, 30.0, 49.0]),
             "depth_mm": np.array([3.0, 1.0, 2.0, 0.5]), "node_xy_mm": solver.grid.node_xy_mm,
             "geometry": {"probe_radius_mm": 3.5, "gel_thickness_mm": 6.0}}
    EFFECTS["contact"](state)
    EFFECTS["percolation"](state)
    EFFECTS["tunneling"](state)
    conductance = 1e-4 * state["conductance_scale"]
    patched = fast.transfer_resistance(conductance)
    exact = np.stack([solver.transfer_resistance(g) for g in conductance])
    np.testing.assert_allclose(patched, exact, rtol=1e-9, atol=1e-9 * np.abs(exact).max())
    # a change too wide for the low-rank update takes the exact path and still agrees
    wide = PatchUpdateSolver(solver, 1e-4, max_patch_nodes=10).transfer_resistance(conductance)
    np.testing.assert_allclose(wide, exact, rtol=1e-12, atol=1e-12 * np.abs(exact).max())
