"""Steady current flow in a thin conductive sheet with electrodes on its edges or inside it.

The sheet is a square grid of nodes (finite volumes). Each node has a sheet conductance
(siemens per square); neighbouring nodes are joined by the series (harmonic-mean)
conductance of their two half cells, which is the 5-point discretisation of the Laplace
equation div(sigma grad V) = 0 with no-flux (Neumann) edges. Electrodes are perfect
contacts: all nodes under one electrode share one potential.

Solving the grounded system once for a unit current into each electrode gives the
transfer-resistance matrix Z (ohms); any two-terminal reading between electrodes i and j
is then R_ij = Z_ii + Z_jj - 2 Z_ij, and any four-terminal reading (current I into a, out of
b; voltage between c and d) is V = I (Z_ca - Z_cb - Z_da + Z_db) by superposition (Holder,
*Electrical Impedance Tomography*, 2005, ch. 1; the ERT skin's four-terminal readings are
data/ert/readings.py), so every injection and measurement pattern costs one factorisation. Z is
symmetric (the Laplacian is), which is the reciprocity theorem V_ab,cd = V_cd,ab.

Electrodes: one whose centre lies on the sheet's border covers the border nodes within half its
width (rubber12's edge electrodes); one inside the sheet covers every node within half its
width (a point electrode, width 0, takes its nearest node).
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from common.errors import InputError


@dataclass(frozen=True)
class SheetGrid:
    """Geometry of a square sheet: node coordinates and which nodes each electrode covers."""
    side_mm: float
    n_nodes: int                       # nodes per side
    electrode_xy_mm: np.ndarray        # (n_electrodes, 2) electrode centres, on the edges or inside
    electrode_width_mm: float

    @property
    def spacing_mm(self) -> float:
        return self.side_mm / (self.n_nodes - 1)

    @property
    def node_xy_mm(self) -> np.ndarray:
        """(n_nodes**2, 2) node coordinates, row-major in y then x (node = iy * n + ix)."""
        axis = np.linspace(0.0, self.side_mm, self.n_nodes)
        yy, xx = np.meshgrid(axis, axis, indexing="ij")
        return np.column_stack([xx.ravel(), yy.ravel()])

    def electrode_nodes(self) -> list[np.ndarray]:
        """Nodes each electrode covers: border nodes within half a width of an edge electrode,
        any nodes within half a width of an internal one; the nearest such node when the width
        covers none (a point electrode). Electrodes outside the sheet or sharing a node are bad input."""
        xy = self.node_xy_mm
        on_edge = ((xy == 0.0) | (xy == self.side_mm)).any(axis=1)
        tolerance = 1e-9 * self.side_mm
        half = self.electrode_width_mm / 2 + tolerance
        centres = np.asarray(self.electrode_xy_mm, dtype=float).reshape(-1, 2)
        if not np.isfinite(centres).all() or (centres < -tolerance).any() or (centres > self.side_mm + tolerance).any():
            outside = centres[~((centres >= -tolerance) & (centres <= self.side_mm + tolerance)).all(axis=1)]
            raise InputError(f"electrode at {np.round(outside[0], 3).tolist()} mm lies outside the "
                             f"{self.side_mm:g} x {self.side_mm:g} mm sheet")
        nodes = []
        for centre in centres:
            centre_on_edge = bool(((np.abs(centre) <= tolerance) | (np.abs(centre - self.side_mm) <= tolerance)).any())
            candidates = on_edge if centre_on_edge else np.ones(len(xy), dtype=bool)
            distance = np.abs(xy - centre).max(axis=1)
            members = np.flatnonzero(candidates & (distance <= half))
            if members.size == 0:
                members = np.flatnonzero(candidates)[[np.argmin(distance[candidates])]]
            nodes.append(members)
        owner = np.full(len(xy), -1)
        for k, members in enumerate(nodes):
            shared = members[owner[members] >= 0]
            if shared.size:
                raise InputError(f"electrodes {owner[shared[0]] + 1} and {k + 1} both cover the node at "
                                 f"{xy[shared[0]].tolist()} mm; move them apart or refine the grid")
            owner[members] = k
        return nodes


class SheetSolver:
    """Transfer resistances of a sheet for any per-node conductance map.

    Built once per geometry (edge list, node-to-unknown map); `transfer_resistance`
    then costs one sparse LU per conductance map.
    """

    def __init__(self, grid: SheetGrid, anisotropy: float = 1.0):
        """`anisotropy`: sheet conductance along x over that along y (1 = isotropic); the two
        directions take sqrt(anisotropy) and 1/sqrt(anisotropy) of the node conductance."""
        if not anisotropy > 0:
            raise InputError(f"sheet anisotropy must be > 0, got {anisotropy}")
        self.grid = grid
        n = grid.n_nodes
        index = np.arange(n * n).reshape(n, n)
        # Edges between horizontal and vertical neighbours. Edges that run along the sheet's
        # border join two half-width cells, so they carry half the conductance.
        horizontal = np.column_stack([index[:, :-1].ravel(), index[:, 1:].ravel()])
        vertical = np.column_stack([index[:-1, :].ravel(), index[1:, :].ravel()])
        self.edges = np.vstack([horizontal, vertical])
        weight_h = np.ones((n, n - 1)); weight_h[[0, -1], :] = 0.5
        weight_v = np.ones((n - 1, n)); weight_v[:, [0, -1]] = 0.5
        self.edge_weight = np.concatenate([weight_h.ravel() * np.sqrt(anisotropy), weight_v.ravel() / np.sqrt(anisotropy)])

        # Unknowns: each free node has its own potential; each electrode's nodes share one.
        electrode_nodes = grid.electrode_nodes()
        n_electrodes = len(electrode_nodes)
        is_electrode = np.zeros(n * n, dtype=bool)
        for members in electrode_nodes:
            is_electrode[members] = True
        unknown = np.empty(n * n, dtype=np.int64)
        unknown[~is_electrode] = np.arange(n_electrodes, n_electrodes + (~is_electrode).sum())
        for k, members in enumerate(electrode_nodes):
            unknown[members] = k
        self.n_electrodes = n_electrodes
        self.node_unknown = unknown
        self.n_unknowns = n_electrodes + int((~is_electrode).sum())

        # Signed incidence matrix (edges x unknowns); edges inside one electrode carry no current.
        a, b = unknown[self.edges[:, 0]], unknown[self.edges[:, 1]]
        keep = a != b
        self.edges, self.edge_weight = self.edges[keep], self.edge_weight[keep]
        rows = np.repeat(np.arange(keep.sum()), 2)
        cols = np.column_stack([a[keep], b[keep]]).ravel()
        vals = np.tile([1.0, -1.0], keep.sum())
        incidence = sp.csr_matrix((vals, (rows, cols)), shape=(keep.sum(), self.n_unknowns))
        # The last electrode is ground: drop its column so the Laplacian is non-singular.
        ground = n_electrodes - 1
        self._free = np.setdiff1d(np.arange(self.n_unknowns), [ground])
        self._incidence = incidence[:, self._free].tocsc()
        self._rhs = np.zeros((self._free.size, n_electrodes - 1))
        self._rhs[np.arange(n_electrodes - 1), np.arange(n_electrodes - 1)] = 1.0

    def edge_conductance_s(self, node_conductance_s: np.ndarray) -> np.ndarray:
        """Series conductance of the two half cells on each edge (harmonic mean), in siemens."""
        ga = node_conductance_s[self.edges[:, 0]]
        gb = node_conductance_s[self.edges[:, 1]]
        return self.edge_weight * 2.0 * ga * gb / (ga + gb)

    def transfer_resistance(self, node_conductance_s: np.ndarray) -> np.ndarray:
        """(n_electrodes, n_electrodes) matrix Z in ohms, grounded at the last electrode.

        `node_conductance_s` is the sheet conductance of every node (siemens per square),
        shape (n_nodes**2,); it must be positive everywhere.
        """
        potentials = self.unit_potentials(node_conductance_s)
        z = np.zeros((self.n_electrodes, self.n_electrodes))
        z[:-1, :-1] = potentials[: self.n_electrodes - 1]
        return z

    def unit_potentials(self, node_conductance_s: np.ndarray) -> np.ndarray:
        """(n_unknowns - 1, n_electrodes - 1) potentials of every free unknown for a unit current
        into each electrode but the grounded last one (one sparse LU)."""
        g = self.edge_conductance_s(node_conductance_s)
        laplacian = (self._incidence.T @ sp.diags(g) @ self._incidence).tocsc()
        return splu(laplacian).solve(self._rhs)


def pair_resistance_ohm(z: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Two-terminal resistance between electrode pairs (0-based) from transfer matrices Z of
    shape (..., n_electrodes, n_electrodes): R_ij = Z_ii + Z_jj - 2 Z_ij."""
    i, j = pairs[:, 0], pairs[:, 1]
    return z[..., i, i] + z[..., j, j] - 2.0 * z[..., i, j]
