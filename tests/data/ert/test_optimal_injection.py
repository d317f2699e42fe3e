"""Iterative SVD recruitment of injection pairs (data/physics/optimal_injection.py)."""
import numpy as np

from data.physics.optimal_injection import (
    all_pairs,
    perturbation_operator,
    recruit_pairs,
)
from data.ert.jacobian import cell_jacobian
from data.physics.sheet_conduction import SheetGrid, SheetSolver

RING = [[20, 120], [60, 120], [100, 120], [120, 100], [120, 60], [120, 20], [100, 0], [60, 0], [20, 0],
        [0, 20], [0, 60], [0, 100]]


def operator(electrodes=RING):
    grid = SheetGrid(120.0, 25, np.asarray(electrodes, dtype=float), 0.0)
    return perturbation_operator(cell_jacobian(SheetSolver(grid), 5e-5, 120.0, 20.0))


def test_error_falls_monotonically_and_every_pair_is_recruited_once():
    result = recruit_pairs(operator(), 12, max_iterations=200)
    errors = np.array(result.error_per_iteration)
    assert np.all(np.diff(errors) <= 1e-12) and errors[0] < 1.0
    order = result.order
    assert len(order) == 66 and len({tuple(p) for p in order}) == 66
    # Subtracting non-orthogonal pair contributions one by one (the paper's scheme) leaves a
    # remainder even with every pair recruited: the error falls, then saturates (fig. 9(b)).
    assert errors[-1] < 0.5 * errors[0] and errors[-1] > 0.0


def test_symmetric_layout_recruits_symmetric_groups_and_long_pairs_first():
    result = recruit_pairs(operator(), 12, max_iterations=3)
    xy = np.asarray(RING, dtype=float)
    first = result.pairs_per_iteration[0]
    assert len(first) >= 2                      # ties: geometrically equivalent pairs come together
    lengths = np.linalg.norm(xy[all_pairs(12)[:, 0]] - xy[all_pairs(12)[:, 1]], axis=1)
    chosen = np.linalg.norm(xy[first[:, 0]] - xy[first[:, 1]], axis=1)
    assert chosen.min() > np.median(lengths)


def test_an_asymmetric_layout_breaks_the_ties():
    moved = [list(p) for p in RING]
    moved[1] = [55, 120]
    moved[4] = [120, 65]
    result = recruit_pairs(operator(moved), 12, max_iterations=1, tie_tolerance=1e-9)
    symmetric = recruit_pairs(operator(), 12, max_iterations=1, tie_tolerance=1e-9)
    assert len(result.pairs_per_iteration[0]) < len(symmetric.pairs_per_iteration[0])
