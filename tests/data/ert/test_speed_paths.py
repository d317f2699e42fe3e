"""The ERT scene's fast forward paths equal the plain computations to rounding: the patch solver
(Woodbury update with eliminated 3 x 3 cells, data/physics/press_update.py) against a full
sparse solve per press, on the scenes' own presses (both electrode layouts, patch-wide and
local contact), the four-terminal readings against the superposition formula term by term, and
SensorTable's one-pass check of its values against the column-by-column one it stands for."""
import numpy as np
import pandas as pd
import pytest
from hydra.utils import instantiate
from omegaconf import OmegaConf

from common.errors import InputError
from data.ert.cells import patch_weights
from data.ert.protocol import injection_pairs, measurement_pairs
from data.ert.readings import four_terminal_voltage_v
from data.physics.press_update import PatchUpdateSolver
from data.physics.sheet_conduction import SheetGrid, SheetSolver
from data.readers.table_reader import check_model_block, check_model_values


@pytest.mark.parametrize("name", ["ert_boundary", "ert_internal", "ert_physical_boundary", "ert_physical_internal"])
def test_scene_presses_through_the_patch_solver_equal_the_full_sparse_solve(compose_config, name):
    cfg = compose_config([f"scene={name}", "seed=4", "scene.protocol=random", "scene.n_samples=24",
                          "scene.two_contact_probability=0.3"])
    scene = instantiate(OmegaConf.to_container(cfg.scene, resolve=True))
    sensor = scene.sensor()
    solver = scene._solver(sensor)
    maps = scene.node_conductance_s(scene._contacts()[0], sensor)
    fast = scene.transfer_resistance(scene._contacts()[0], sensor)
    exact = np.stack([solver.solver.transfer_resistance(g) for g in maps])
    rest = solver.solver.transfer_resistance(solver._base_nodes)
    signal = np.abs(exact - rest).max(axis=(1, 2))
    assert signal.min() > 1e-6 * np.abs(rest).max()                  # every press moves Z
    np.testing.assert_allclose(fast, exact, rtol=1e-9, atol=1e-12 * np.abs(exact).max())
    assert (np.abs(fast - exact).max(axis=(1, 2)) / signal).max() < 1e-8   # also relative to the press's own change
    # the presses really take the cell elimination (a loaded patch's whole interior is touched)
    moved = maps != solver.base_conductance_s
    touched = np.zeros((len(maps), solver._n), dtype=bool)
    changed = moved[:, solver.solver.edges[:, 0]] | moved[:, solver.solver.edges[:, 1]]
    row, edge = np.nonzero(changed)
    touched[row, solver._ends[edge, 0]] = touched[row, solver._ends[edge, 1]] = True
    assert touched[:, solver._cell_interior].all(axis=2).any(axis=1).mean() > 0.5


def test_cells_next_to_wide_and_internal_electrodes_and_a_varied_base_stay_exact():
    # 10 mm edge electrodes cover three border nodes (ring nodes that share one unknown), two
    # internal electrodes sit in what would be cell interiors (those cells are not eliminated),
    # and the sheet is not uniform at rest.
    electrodes = np.array([[0, 40], [0, 80], [40, 120], [80, 120], [120, 80], [120, 40], [80, 0], [40, 0],
                           [50, 50], [70, 75]], dtype=float)
    grid = SheetGrid(120.0, 25, electrodes, 10.0)
    solver = SheetSolver(grid)
    rng = np.random.default_rng(7)
    base = 5e-5 * rng.uniform(0.8, 1.2, grid.n_nodes ** 2)
    share = patch_weights(grid.node_xy_mm, grid.side_mm, 20.0)
    factor = np.ones((12, share.shape[1]))
    for k in range(12):                                   # one to four loaded patches per press
        factor[k, rng.choice(share.shape[1], rng.integers(1, 5), replace=False)] = rng.uniform(1.5, 10.0)
    maps = base * (factor @ share.T)
    patch = PatchUpdateSolver(solver, base)
    fast = patch.transfer_resistance(maps, chunk=5)
    exact = np.stack([solver.transfer_resistance(g) for g in maps])
    np.testing.assert_allclose(fast, exact, rtol=1e-9, atol=1e-12 * np.abs(exact).max())
    assert len(patch._cell_ring) == 6 * 6 - 2           # the internal electrodes' cells are not eliminated
    assert (patch._cell_ring < solver.n_electrodes - 1).any()   # some rings run through a wide electrode


def test_four_terminal_readings_equal_the_superposition_formula_for_every_pair():
    rng = np.random.default_rng(0)
    z = rng.normal(size=(3, 7, 7))                      # not symmetric: the formula's index order counts
    inj, meas = injection_pairs("all", 7), measurement_pairs("successive", 7)
    v = four_terminal_voltage_v(z, inj, meas, current_a=2e-3)
    assert v.shape == (3, len(inj), len(meas))
    for n in range(3):
        for k, (a, b) in enumerate(inj):
            for i, (c, d) in enumerate(meas):
                expected = 2e-3 * (z[n, c, a] - z[n, c, b] - z[n, d, a] + z[n, d, b])
                assert v[n, k, i] == pytest.approx(expected, rel=1e-12, abs=1e-15)
    np.testing.assert_array_equal(four_terminal_voltage_v(z[1], inj, meas, 2e-3), v[1])


@pytest.mark.parametrize("column, value", [("b_v", np.nan), ("c_kpa", -1.0), ("a_v", 1e39), ("c_kpa", np.inf)])
def test_the_block_check_of_a_tables_values_names_the_first_bad_column_and_row(column, value):
    frame = pd.DataFrame({"a_v": [0.1, 0.2, 0.3], "b_v": [1.0, 2.0, 3.0], "c_kpa": [5.0, 6.0, 7.0]})
    frame.loc[1, column] = value
    with pytest.raises(InputError) as block:
        check_model_block(frame, list(frame.columns), "channel", "rig.csv")
    with pytest.raises(InputError) as one_by_one:
        for name in frame.columns:
            check_model_values(frame[name].to_numpy(dtype=np.float64), name, "channel", "rig.csv")
    assert str(block.value) == str(one_by_one.value) and f"'{column}'" in str(block.value) and "line 3" in str(block.value)
    check_model_block(frame.drop(index=1), list(frame.columns), "channel", "rig.csv")    # the rest passes
