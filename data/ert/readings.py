"""The channels of an ERT frame from the transfer-resistance matrix Z (data/physics/sheet_conduction.py).

Every four-terminal reading (current I into a, out of b; voltage between c and d) is
V = I (Z_ca - Z_cb - Z_da + Z_db) by superposition (Holder, *Electrical Impedance Tomography*,
2005, ch. 1; seed 002 eq. 2), so every injection and measurement pattern costs one solve of Z.
Z is grounded at the last electrode and symmetric, so a frame of n_injections x n_measurements
channels is K z + noise with z the N(N-1)/2 unique entries of Z (N electrodes, one grounded) and
K = `transfer_basis`. For white noise u = K^T v is a sufficient statistic for z, and every map of
the form (...) J^T or (...) Y^T over simulated frames factors through it exactly, so the
reconstructions (models/ert/) take u (276 numbers for 24 electrodes) instead of the 6,624
channels: a frame costs one (n_channels x n_z) product, then maps of n_z columns.
"""
import numpy as np
import scipy.sparse as sp

from data.ert.protocol import injection_pairs, measurement_pairs


def four_terminal_voltage_v(z: np.ndarray, injection_pairs: np.ndarray, measurement_pairs: np.ndarray,
                            current_a: float = 1.0) -> np.ndarray:
    """Voltages V_c - V_d for current `current_a` into a and out of b, from transfer matrices Z of
    shape (..., n_electrodes, n_electrodes): V = I (Z_ca - Z_cb - Z_da + Z_db) by superposition.

    Returns shape (..., n_injections, n_measurements), injection-major (seed 002 eq. 2 with
    pairwise patterns P_j = e_a - e_b and M_i = e_c - e_d)."""
    z = np.asarray(z, dtype=float)
    # Column differences first (the potential each injection's terminal sets up between c and d),
    # then the injection pairs as a +-1 matrix product, which BLAS forms in the output's
    # injection-major layout: v[..., k, i] = y[..., a_k, i] - y[..., b_k, i].
    y = np.swapaxes(z[..., measurement_pairs[:, 0], :] - z[..., measurement_pairs[:, 1], :], -1, -2)
    pairs = np.zeros((len(injection_pairs), z.shape[-1]))
    pairs[np.arange(len(injection_pairs)), injection_pairs[:, 0]] = 1.0
    pairs[np.arange(len(injection_pairs)), injection_pairs[:, 1]] = -1.0
    v = pairs @ y
    v *= current_a
    return v


def four_terminal_matrix(injection_pairs: np.ndarray, measurement_pairs: np.ndarray, n_electrodes: int,
                         current_a: float = 1.0) -> sp.csr_matrix:
    """The same readings as a sparse linear map from Z flattened row-major (n_electrodes**2) to
    the (n_injections * n_measurements) channels, injection-major: a Jacobian of Z maps through it."""
    a, b = np.repeat(injection_pairs[:, 0], len(measurement_pairs)), np.repeat(injection_pairs[:, 1], len(measurement_pairs))
    c, d = np.tile(measurement_pairs[:, 0], len(injection_pairs)), np.tile(measurement_pairs[:, 1], len(injection_pairs))
    rows = np.repeat(np.arange(len(a)), 4)
    cols = np.column_stack([c * n_electrodes + a, c * n_electrodes + b, d * n_electrodes + a, d * n_electrodes + b]).ravel()
    vals = np.tile([current_a, -current_a, -current_a, current_a], len(a))
    return sp.csr_matrix((vals, (rows, cols)), shape=(len(a), n_electrodes ** 2))


def unique_transfer_entries(n_electrodes: int) -> np.ndarray:
    """(n_z, 2) index pairs i <= j of Z's unique entries; the last electrode is ground (its row
    and column are zero)."""
    m = n_electrodes - 1
    i, j = np.triu_indices(m)
    return np.column_stack([i, j])


def transfer_basis(geometry: dict) -> sp.csr_matrix:
    """(n_channels, n_z) sparse K with channels = K z (z: `unique_transfer_entries` of Z) for a
    nominal geometry (ERTScene.geometry())."""
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
