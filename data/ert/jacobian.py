"""The one Jacobian of the ERT skin: how the transfer-resistance matrix Z moves when the sheet's
conductance changes, by the adjoint (Geselowitz) sensitivity, and its views: per square cell
(fabric patch or image pixel), on the frame's channels (the scene's baseline drift), and on Z's
unique entries (the reconstructions, models/ert/, which map them to channels through
readings.transfer_basis).

The two channel views sum the same four terms of each reading in different orders, so they agree
to rounding, not bit for bit; each caller keeps the one its recorded results were made with.
"""
import numpy as np

from data.ert.cells import patch_weights
from data.ert.forward import nominal_sheet
from data.ert.readings import four_terminal_matrix, unique_transfer_entries
from data.physics.sheet_conduction import SheetSolver


def transfer_resistance_jacobian(solver: SheetSolver, base_conductance_s, node_to_parameter: np.ndarray) -> np.ndarray:
    """dZ / d theta at the base map (a sheet conductance for every node, or one for all), shape
    (n_parameters, n_electrodes, n_electrodes), where parameter k scales node conductances by
    (1 + theta_k * node_to_parameter[:, k]).

    Adjoint (Geselowitz) sensitivity: for edge conductance g_e between nodes p and q,
    dZ_ij/dg_e = -(u_i(p) - u_i(q)) (u_j(p) - u_j(q)), u_i the potentials for a unit current
    into electrode i (Holder 2005, ch. 1; Polydorides & Lionheart, Meas. Sci. Technol. 13,
    2002). The harmonic-mean edge conductance w 2 g_p g_q / (g_p + g_q) has
    d/d g_p = w 2 g_q^2 / (g_p + g_q)^2, which the chain rule carries to theta.
    """
    s, m = solver, solver.n_electrodes - 1
    base_nodes = np.broadcast_to(np.asarray(base_conductance_s, dtype=float), (s.grid.n_nodes ** 2,))
    # each node's row among the free unknowns; the grounded electrode's nodes read the last,
    # all-zero row (potential 0)
    ground = s.n_electrodes - 1
    row = np.where(s.node_unknown > ground, s.node_unknown - 1, s.node_unknown)
    row[s.node_unknown == ground] = s.n_unknowns - 1
    potentials = np.zeros((s.n_unknowns, m))
    potentials[:-1] = s.unit_potentials(base_nodes)
    drop = potentials[row[s.edges[:, 0]]] - potentials[row[s.edges[:, 1]]]      # (n_edges, m)
    gp, gq = base_nodes[s.edges[:, 0]], base_nodes[s.edges[:, 1]]
    dg_dgp = s.edge_weight * 2.0 * gq ** 2 / (gp + gq) ** 2
    dg_dgq = s.edge_weight * 2.0 * gp ** 2 / (gp + gq) ** 2
    weight = np.asarray(node_to_parameter, dtype=float)
    d_edge = (dg_dgp * gp)[:, None] * weight[s.edges[:, 0]] + (dg_dgq * gq)[:, None] * weight[s.edges[:, 1]]
    i, j = np.triu_indices(m)                                 # dZ is symmetric: one triangle
    upper = -(d_edge.T @ (drop[:, i] * drop[:, j]))
    dz = np.zeros((weight.shape[1], m + 1, m + 1))
    dz[:, i, j] = upper
    dz[:, j, i] = upper
    return dz


def cell_jacobian(solver: SheetSolver, base_conductance_s, side_mm: float, cell_mm: float) -> np.ndarray:
    """(n_cells, n_electrodes, n_electrodes) dZ / d (relative conductance of each square cell of
    side `cell_mm`, rows in y), a node on a cell border shared equally (cells.patch_weights)."""
    return transfer_resistance_jacobian(solver, base_conductance_s,
                                        patch_weights(solver.grid.node_xy_mm, side_mm, cell_mm))


def channel_jacobian(dz: np.ndarray, injections: np.ndarray, measurements: np.ndarray, current_a: float) -> np.ndarray:
    """(n_channels, n_parameters) d voltage / d theta from dZ / d theta, through the four-terminal
    readings of the whole Z."""
    to_channels = four_terminal_matrix(injections, measurements, dz.shape[-1], current_a)
    return np.asarray(to_channels @ dz.reshape(len(dz), -1).T)


def pixel_sensitivity(geometry: dict, pixels_per_side: int) -> np.ndarray:
    """(n_z, n_pixels) d z / d (relative conductance of each pixel of an n x n grid over the
    sheet) at the nominal, uniform sheet, z the unique entries of Z
    (readings.unique_transfer_entries). The channels' Jacobian is readings.transfer_basis(geometry)
    @ this."""
    solver, conductance_s = nominal_sheet(geometry)
    dz = cell_jacobian(solver, conductance_s, geometry["side_mm"], geometry["side_mm"] / pixels_per_side)
    entries = unique_transfer_entries(len(geometry["electrodes_mm"]))
    return dz[:, entries[:, 0], entries[:, 1]].T
