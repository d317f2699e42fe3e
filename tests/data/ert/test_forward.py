"""The generalised sheet solver (data/physics/sheet_conduction.py), the ERT readings and Jacobian
(data/ert/) checked against independent answers: the full sparse solve, reciprocity, an analytic
uniform sheet, finite differences."""
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

from common.errors import InputError
from data.ert.cells import patch_weights
from data.ert.jacobian import channel_jacobian, transfer_resistance_jacobian
from data.ert.protocol import injection_pairs, measurement_pairs
from data.ert.readings import four_terminal_matrix, four_terminal_voltage_v
from data.physics.press_update import PatchUpdateSolver
from data.physics.sheet_conduction import SheetGrid, SheetSolver

INTERNAL = np.array([[0, 40], [0, 80], [40, 120], [80, 120], [120, 80], [120, 40], [80, 0], [40, 0],
                     [40, 40], [80, 80], [40, 80]], dtype=float)


def grid(electrodes=INTERNAL, nodes=25, side=120.0, width=0.0):
    return SheetGrid(side, nodes, electrodes, width)


def pressed_maps(solver, rng, n=4, base=5e-5):
    """Per-node conductance maps, each with one square patch made more conductive."""
    share = patch_weights(solver.grid.node_xy_mm, solver.grid.side_mm, 20.0)
    factor = np.ones((n, share.shape[1]))
    factor[np.arange(n), rng.integers(0, factor.shape[1], n)] = rng.uniform(1.5, 10.0, n)
    return base * (factor @ share.T)


def node_potentials_by_hand(grid_, conductance, a, b):
    """Independent check: assemble the node Laplacian with electrode nodes merged by a penalty
    (huge conductances between an electrode's nodes), inject +1 A at a and -1 A at b, solve."""
    n = grid_.n_nodes
    index = np.arange(n * n).reshape(n, n)
    pairs = [(index[i, j], index[i, j + 1], 0.5 if i in (0, n - 1) else 1.0) for i in range(n) for j in range(n - 1)]
    pairs += [(index[i, j], index[i + 1, j], 0.5 if j in (0, n - 1) else 1.0) for i in range(n - 1) for j in range(n)]
    rows, cols, vals = [], [], []
    for p, q, w in pairs:
        g = w * 2 * conductance[p] * conductance[q] / (conductance[p] + conductance[q])
        rows += [p, q, p, q]; cols += [p, q, q, p]; vals += [g, g, -g, -g]
    for members in grid_.electrode_nodes():
        for p in members[1:]:
            g = 1e6
            rows += [members[0], p, members[0], p]; cols += [members[0], p, p, members[0]]; vals += [g, g, -g, -g]
    laplacian = sp.csr_matrix((vals, (rows, cols)), shape=(n * n, n * n)).tolil()
    nodes = grid_.electrode_nodes()
    current = np.zeros(n * n)
    current[nodes[a][0]], current[nodes[b][0]] = 1.0, -1.0
    ground = nodes[b][0]
    laplacian[ground, :] = 0.0
    laplacian[ground, ground] = 1.0
    current[ground] = 0.0
    return spsolve(laplacian.tocsr(), current), nodes


def test_four_terminal_readings_match_an_independent_sparse_solve():
    g = grid()
    solver = SheetSolver(g)
    conductance = pressed_maps(solver, np.random.default_rng(0), n=1)[0]
    z = solver.transfer_resistance(conductance)
    inj, meas = np.array([[0, 4], [2, 9]]), measurement_pairs("successive", len(INTERNAL))
    v = four_terminal_voltage_v(z, inj, meas, current_a=1.0)
    for k, (a, b) in enumerate(inj):
        potentials, nodes = node_potentials_by_hand(g, conductance, a, b)
        electrode_v = np.array([potentials[members[0]] for members in nodes])
        expected = electrode_v[meas[:, 0]] - electrode_v[meas[:, 1]]
        np.testing.assert_allclose(v[k], expected, rtol=1e-5, atol=1e-5 * np.abs(expected).max())


def test_patch_update_equals_the_full_sparse_solve_with_internal_electrodes_and_a_varied_base():
    g = grid()
    solver = SheetSolver(g)
    rng = np.random.default_rng(1)
    base = 5e-5 * rng.uniform(0.8, 1.2, g.n_nodes ** 2)
    maps = base * pressed_maps(solver, rng, n=6, base=1.0)
    fast = PatchUpdateSolver(solver, base).transfer_resistance(maps)
    exact = np.stack([solver.transfer_resistance(m) for m in maps])
    np.testing.assert_allclose(fast, exact, rtol=1e-9, atol=1e-9 * np.abs(exact).max())


def test_reciprocity_swapping_injection_and_measurement_pairs():
    solver = SheetSolver(grid())
    z = solver.transfer_resistance(pressed_maps(solver, np.random.default_rng(2), n=1)[0])
    pairs = injection_pairs("all", len(INTERNAL))
    v = four_terminal_voltage_v(z, pairs, pairs)
    np.testing.assert_allclose(v, v.T, rtol=1e-9, atol=1e-12 * np.abs(v).max())
    assert np.abs(v - np.diag(np.diag(v))).max() > 0.0   # not trivially symmetric


def test_uniform_sheet_with_bar_electrodes_has_the_analytic_linear_potential():
    # Full-width bars on the left and right edges drive a uniform current; the potential is
    # linear in x, so two internal point electrodes d apart read V = I R_sq d / W exactly.
    side, r_sq = 120.0, 2.0e4
    electrodes = np.array([[0.0, 60.0], [120.0, 60.0], [30.0, 60.0], [90.0, 40.0]])
    index = np.arange(25 * 25).reshape(25, 25)
    nodes = [index[:, 0], index[:, -1]]                       # the whole left and right edges

    class Mixed(SheetGrid):
        def electrode_nodes(self):
            return nodes + SheetGrid(side, 25, electrodes[2:], 0.0).electrode_nodes()

    solver = SheetSolver(Mixed(side, 25, electrodes, 0.0))
    z = solver.transfer_resistance(np.full(25 * 25, 1.0 / r_sq))
    v = four_terminal_voltage_v(z, np.array([[0, 1]]), np.array([[2, 3], [0, 1]]), current_a=1e-3)[0]
    np.testing.assert_allclose(v[0], 1e-3 * r_sq * 60.0 / side, rtol=1e-9)
    np.testing.assert_allclose(v[1], 1e-3 * r_sq * 1.0, rtol=1e-9)     # one square between the bars


def test_jacobian_matches_finite_differences():
    g = grid()
    solver = SheetSolver(g)
    base = 5e-5 * np.random.default_rng(3).uniform(0.8, 1.2, g.n_nodes ** 2)
    weight = patch_weights(g.node_xy_mm, g.side_mm, 20.0)
    dz = transfer_resistance_jacobian(solver, base, weight)
    inj, meas = injection_pairs("all", len(INTERNAL)), measurement_pairs("successive", len(INTERNAL))
    jacobian = channel_jacobian(dz, inj, meas, 1.0)
    z0 = solver.transfer_resistance(base)
    for k in (0, 7, 20, 35):
        step = 1e-6
        z1 = solver.transfer_resistance(base * (1 + step * weight[:, k]))
        finite = (four_terminal_voltage_v(z1, inj, meas) - four_terminal_voltage_v(z0, inj, meas)).ravel() / step
        np.testing.assert_allclose(jacobian[:, k], finite, rtol=1e-4, atol=1e-4 * np.abs(finite).max())
        assert np.abs(finite).max() > 0


def test_four_terminal_matrix_equals_the_direct_readings():
    solver = SheetSolver(grid())
    z = solver.transfer_resistance(pressed_maps(solver, np.random.default_rng(4), n=1)[0])
    inj, meas = injection_pairs("all", len(INTERNAL)), measurement_pairs("successive", len(INTERNAL))
    direct = four_terminal_voltage_v(z, inj, meas, 2e-4).ravel()
    np.testing.assert_allclose(four_terminal_matrix(inj, meas, len(INTERNAL), 2e-4) @ z.ravel(), direct, rtol=1e-12)


@pytest.mark.parametrize("electrodes, message", [
    ([[0, 40], [130, 40]], "lies outside the 120 x 120 mm sheet"),
    ([[0, 40], [0, 41]], "both cover the node"),
    ([[60, 60], [61, 59]], "both cover the node"),
])
def test_bad_electrodes_are_one_line_input_errors(electrodes, message):
    with pytest.raises(InputError, match=message):
        SheetSolver(grid(np.array(electrodes, dtype=float)))


def test_internal_point_electrode_takes_its_nearest_node():
    g = grid(np.array([[0.0, 40.0], [52.0, 58.0]]))
    nodes = g.electrode_nodes()
    assert len(nodes[1]) == 1
    np.testing.assert_allclose(g.node_xy_mm[nodes[1][0]], [50.0, 60.0])
