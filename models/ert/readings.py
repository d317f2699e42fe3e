"""The channels of an ERT frame through the transfer-resistance matrix, and the pixel Jacobian.

Every four-terminal reading is a fixed combination of the entries of the grounded, symmetric
transfer matrix Z (V = I (Z_ca - Z_cb - Z_da + Z_db), data/physics/sheet_conduction.py), so a
frame of n_injections x n_measurements channels is K z + noise with z the N(N-1)/2 unique
entries of Z (N electrodes, one grounded) and K = `transfer_basis`. For white noise u = K^T v
is a sufficient statistic for z, and every map of the form (...) J^T or (...) Y^T over simulated
frames factors through it exactly, so the reconstructions take u (276 numbers for 24
electrodes) instead of the 6,624 channels: a frame costs one (n_channels x n_z) product, then
maps of n_z columns.
"""
import numpy as np
import scipy.sparse as sp

from data.physics.press_update import PatchUpdateSolver
from data.physics.sheet_conduction import SheetGrid, SheetSolver, four_terminal_matrix
from common.errors import InputError
from data.scenes.ert import injection_pairs, measurement_pairs, patch_weights


def unique_transfer_entries(n_electrodes: int) -> np.ndarray:
    """(n_z, 2) index pairs i <= j of Z's unique entries; the last electrode is ground (its row
    and column are zero)."""
    m = n_electrodes - 1
    i, j = np.triu_indices(m)
    return np.column_stack([i, j])


def transfer_basis(geometry: dict) -> sp.csr_matrix:
    """(n_channels, n_z) sparse K with channels = K z (z: `unique_transfer_entries` of Z)."""
    n = len(geometry["electrodes_mm"])
    readings = four_terminal_matrix(injection_pairs(geometry["injection"], n),
                                    measurement_pairs(geometry["measurement"], n), n, geometry["current_a"])
    entries = unique_transfer_entries(n)
    k = np.arange(len(entries))
    fold = sp.csr_matrix((np.ones(2 * len(k)), (np.concatenate([entries[:, 0] * n + entries[:, 1],
                                                                entries[:, 1] * n + entries[:, 0]]),
                                                np.concatenate([k, k]))), shape=(n * n, len(k)))
    fold.data[:] = 1.0     # a diagonal entry appears twice at one place: it counts once
    return (readings @ fold).tocsr()


def pixel_centres_mm(side_mm: float, pixels_per_side: int, margin_mm: float = 0.0) -> np.ndarray:
    """(n^2, 2) x, y of an n x n pixel grid over [-margin, side + margin]^2, rows in y."""
    width = side_mm + 2.0 * margin_mm
    axis = (np.arange(pixels_per_side) + 0.5) * width / pixels_per_side - margin_mm
    xx, yy = np.meshgrid(axis, axis)
    return np.column_stack([xx.ravel(), yy.ravel()])


def pixel_sensitivity(geometry: dict, pixels_per_side: int) -> np.ndarray:
    """(n_z, n_pixels) d z / d (relative conductance of each pixel of an n x n grid over the
    sheet) at the nominal, uniform sheet: the adjoint sensitivity of
    PatchUpdateSolver.transfer_resistance_jacobian, folded to Z's unique entries. The channels'
    Jacobian is transfer_basis(geometry) @ this."""
    electrodes = np.asarray(geometry["electrodes_mm"], dtype=float)
    grid = SheetGrid(geometry["side_mm"], geometry["grid_nodes"], electrodes, geometry.get("electrode_width_mm", 0.0))
    solver = PatchUpdateSolver(SheetSolver(grid), 1.0 / geometry["sheet_resistance_ohm_per_sq"])
    # a node on a pixel border belongs to the pixels that meet there in equal shares: assigning it
    # to one side shifts every image by half a node spacing
    share = patch_weights(grid.node_xy_mm, geometry["side_mm"], geometry["side_mm"] / pixels_per_side)
    dz = solver.transfer_resistance_jacobian(share)                          # (n_pixels, N, N)
    entries = unique_transfer_entries(len(electrodes))
    return dz[:, entries[:, 0], entries[:, 1]].T


def checked_voltages(X, n_channels: int) -> np.ndarray:
    """Frames of voltages as float, refused in one line unless (n_frames, n_channels) and finite."""
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[1] != n_channels:
        raise InputError(f"voltages must have shape (n_frames, {n_channels}), got {X.shape}")
    if not np.isfinite(X).all():
        raise InputError("voltages contain NaN or infinite values")
    return X
