"""A press on a sheet whose resting state is already solved: the transfer resistances after a
local conductance change by a low-rank (Woodbury) update of the resting sheet's solution
(PatchUpdateSolver), and its near/far split for presses that change few nodes (NearFarSolver).
The resting sheet and the readings from Z are data/physics/sheet_conduction.py.
"""
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from data.physics.sheet_conduction import SheetSolver


class PatchUpdateSolver:
    """Exact transfer resistances for many presses that each change only a small patch.

    A press changes the conductance of the few edges under the probe, so the grounded
    Laplacian changes only in the block of the nodes V those edges touch:
    L = L0 + S^T dL S, with S selecting V. The push-through form of the Woodbury identity gives

        Z = Z0 - P^T (I + dL G)^-1 dL P,   G = L0^-1[V, V],   P = L0^-1[V, electrodes],

    so with L0^-1 built once (densely, on the first press) per geometry and base conductance, each
    press costs one |V| x |V| solve instead of a sparse LU of the whole grid, and batches of
    presses are solved together.

    The dense solve grows as |V|^3, so V is first shrunk without approximation (one level of
    nested dissection): the grid is cut by lines every 4 nodes into cells of 3 x 3 interior
    nodes, each joined only to the 12 nodes around it. A cell whose whole interior the press
    touches is eliminated: its Schur complement onto those 12 nodes, with the press's
    conductances minus the resting sheet's (precomputed), enters dL in place of its edges, and
    its 9 nodes leave V (a 20 mm patch of the ERT skin on a 5 mm grid is exactly one cell: on
    ert_boundary's random presses |V| averages 90 nodes instead of 134). Eliminating a block of
    nodes is exact (L0^-1 restricted to the rest is the inverse of the resting sheet's Schur
    complement onto the rest), so the result is SheetSolver's to rounding (tested), not an
    approximation. Presses whose V still holds more than `max_patch_nodes` nodes fall back to
    the full sparse solve.
    """

    def __init__(self, solver: SheetSolver, base_conductance_s, max_patch_nodes: int = 300):
        """`base_conductance_s`: one sheet conductance for every node (siemens per square), or a
        per-node map (n_nodes**2,) for a sheet that is not uniform before any press."""
        self.solver = solver
        self.base_conductance_s = base_conductance_s
        self.max_patch_nodes = max_patch_nodes
        n_free = solver._free.size
        base_nodes = np.broadcast_to(np.asarray(base_conductance_s, dtype=float), (solver.grid.n_nodes ** 2,))
        self._base_nodes = base_nodes
        self._base_edges = solver.edge_conductance_s(base_nodes)
        # Endpoints of every edge in the free-unknown numbering (ground -> n_free).
        incidence = solver._incidence.tocoo()
        ends = np.full((incidence.shape[0], 2), n_free)
        ends[incidence.row, np.where(incidence.data > 0, 0, 1)] = incidence.col
        self._ends = ends
        self._n = n_free + 1
        self._build_cells()

    @cached_property
    def _inverse(self) -> np.ndarray:
        """The resting sheet's dense L0^-1 (free unknowns), built on the first press: the
        sensitivities need only its electrode columns. One extra row/column of zeros stands for
        the grounded electrode (potential 0): an edge into it changes only its other end's row,
        which the zeros reproduce exactly."""
        s = self.solver
        laplacian = (s._incidence.T @ sp.diags(self._base_edges) @ s._incidence).toarray()
        inverse = np.zeros((self._n, self._n))
        inverse[:-1, :-1] = np.linalg.inv(laplacian)
        return inverse

    @cached_property
    def _z0(self) -> np.ndarray:
        m = self.solver.n_electrodes - 1
        return self._inverse[:m, :m].copy()

    def _build_cells(self):
        """The 3 x 3-node cells between grid lines every 4 nodes that hold no electrode node:
        their interior and ring nodes (free numbering), their 24 edges, the local Laplacian pattern
        of those edges and the resting sheet's Schur complement onto the ring."""
        s, n = self.solver, self.solver.grid.n_nodes
        ground = s.n_electrodes - 1
        free = np.where(s.node_unknown > ground, s.node_unknown - 1, s.node_unknown)
        free[s.node_unknown == ground] = self._n - 1
        # local numbering: interior (r, c) -> 3 r + c; ring: top 9-11, bottom 12-14, left 15-17, right 18-20
        offset = np.array([(1 + r, 1 + c) for r in range(3) for c in range(3)]
                          + [(0, 1 + c) for c in range(3)] + [(4, 1 + c) for c in range(3)]
                          + [(1 + r, 0) for r in range(3)] + [(1 + r, 4) for r in range(3)])
        pairs = np.array([(3 * r + c, 3 * r + c + 1) for r in range(3) for c in range(2)]
                         + [(3 * r + c, 3 * r + c + 3) for r in range(2) for c in range(3)]
                         + [(c, 9 + c) for c in range(3)] + [(6 + c, 12 + c) for c in range(3)]
                         + [(3 * r, 15 + r) for r in range(3)] + [(3 * r + 2, 18 + r) for r in range(3)])
        starts = np.arange(0, n - 4, 4)
        oy, ox = [o.ravel() for o in np.meshgrid(starts, starts, indexing="ij")]
        nodes = (oy[:, None] + offset[None, :, 0]) * n + ox[:, None] + offset[None, :, 1]     # (cells, 21)
        plain = (s.node_unknown[nodes[:, :9]] >= s.n_electrodes).all(axis=1)
        nodes = nodes[plain]
        key = np.sort(s.edges, axis=1) @ np.array([n * n, 1])
        sorter = np.argsort(key)
        wanted = np.sort(np.stack([nodes[:, pairs[:, 0]], nodes[:, pairs[:, 1]]], axis=-1), axis=-1) @ np.array([n * n, 1])
        self._cell_edges = sorter[np.searchsorted(key, wanted, sorter=sorter)]               # (cells, 24)
        self._cell_interior, self._cell_ring = free[nodes[:, :9]], free[nodes[:, 9:]]
        # the interior block of the cell's Laplacian as a linear map of its 24 edge conductances;
        # each ring node hangs on one edge (the last 12) from one interior node
        pattern = np.zeros((len(pairs), 9, 9))
        for k, (a, b) in enumerate(pairs):
            pattern[k, a, a] += 1.0
            if b < 9:
                pattern[k, b, b] += 1.0
                pattern[k, a, b] = pattern[k, b, a] = -1.0
        self._cell_pattern = pattern.reshape(len(pairs), -1)
        self._cell_hook = pairs[12:, 0]
        self._edge_cell = np.full(len(s.edges), -1)
        self._edge_cell[self._cell_edges] = np.arange(len(nodes))[:, None]
        self._cell_schur0 = self._cell_schur(self._base_edges[self._cell_edges])

    def _cell_schur(self, edge_conductance: np.ndarray) -> np.ndarray:
        """(k, 12, 12) Schur complements onto the ring of cells with these (k, 24) edge conductances:
        diag(g) - g g^T * L_II^-1[hook, hook], g the ring edges' conductances."""
        interior = np.linalg.inv((edge_conductance @ self._cell_pattern).reshape(-1, 9, 9))
        ring = edge_conductance[:, 12:]
        schur = -(ring[:, :, None] * ring[:, None, :]) * interior[:, self._cell_hook[:, None], self._cell_hook[None, :]]
        schur[:, np.arange(12), np.arange(12)] += ring
        return schur

    def transfer_resistance(self, node_conductance_s: np.ndarray, chunk: int = 256) -> np.ndarray:
        """(n_presses, n_electrodes, n_electrodes) Z for (n_presses, n_nodes) conductance maps,
        solved `chunk` presses at a time."""
        g = np.atleast_2d(node_conductance_s)
        m = self.solver.n_electrodes
        z = np.zeros((len(g), m, m))
        z[:, :-1, :-1] = self._update(g, chunk=chunk)
        return z

    def _update(self, g: np.ndarray, changed: np.ndarray | None = None, chunk: int = 256) -> np.ndarray:
        """Z (grounded row and column dropped) for the conductance maps g; `changed` (n_presses,
        n_edges), when given, says which edges the exact update takes (the rest stay at the base
        map), else every edge one of whose nodes moved. Presses are solved in chunks of similar
        |V|, each padded to its largest (the padding nodes' dL rows are zero)."""
        s, m, width = self.solver, self.solver.n_electrodes - 1, self._n
        out = np.broadcast_to(self._z0, (len(g), m, m)).copy()
        if changed is None:
            # An edge changes only if one of its nodes does (testing the harmonic mean itself
            # would flag every edge: 2gg/(g+g) need not round back to g).
            moved = g != self.base_conductance_s
            changed = moved[:, s.edges[:, 0]] | moved[:, s.edges[:, 1]]
        row, edge = np.nonzero(changed)
        if row.size == 0:
            return out
        touched = np.zeros((len(g), width), dtype=bool)
        touched[row, self._ends[edge, 0]] = touched[row, self._ends[edge, 1]] = True
        # Cells whose whole interior is touched leave V; their rings join it.
        er, ec = np.nonzero(touched[:, self._cell_interior].all(axis=2))
        eliminated = np.zeros((len(g), len(self._cell_ring) + 1), dtype=bool)   # last column: no cell
        eliminated[er, ec] = True
        keep = ~eliminated[row, self._edge_cell[edge]]
        row, edge = row[keep], edge[keep]
        touched[er[:, None], self._cell_interior[ec]] = False
        touched[er[:, None], self._cell_ring[ec]] = True
        sizes = touched.sum(axis=1)

        def new_conductance(r, e):
            ga, gb = g[r, s.edges[e, 0]], g[r, s.edges[e, 1]]
            return s.edge_weight[e] * 2.0 * ga * gb / (ga + gb)

        delta = new_conductance(row, edge) - self._base_edges[edge]
        cell_edges = self._cell_edges[ec]
        cell_conductance = np.where(changed[er[:, None], cell_edges], new_conductance(er[:, None], cell_edges),
                                    self._base_edges[cell_edges])
        cell_change = self._cell_schur(cell_conductance) - self._cell_schur0[ec]
        # dL's entries: four per node-level edge, 144 per eliminated cell, summed where they meet
        node_a, node_b = self._ends[edge, 0], self._ends[edge, 1]
        ring = self._cell_ring[ec]
        entry_press = np.concatenate([np.repeat(row, 4), np.repeat(er, 144)])
        entry_i = np.concatenate([np.column_stack([node_a, node_b, node_a, node_b]).ravel(),
                                  np.repeat(ring, 12, axis=1).ravel()])
        entry_j = np.concatenate([np.column_stack([node_a, node_b, node_b, node_a]).ravel(),
                                  np.tile(ring, (1, 12)).ravel()])
        entry_value = np.concatenate([(delta[:, None] * [1.0, 1.0, -1.0, -1.0]).ravel(), cell_change.ravel()])

        for wide in np.flatnonzero(sizes > self.max_patch_nodes):  # too wide for a low-rank update
            out[wide] = s.transfer_resistance(g[wide])[:-1, :-1]
        order = np.flatnonzero(sizes <= self.max_patch_nodes)
        order = order[np.argsort(sizes[order], kind="stable")]
        slot = np.full(len(g), -1)
        slot[order] = np.arange(len(order))
        entry_slot = slot[entry_press]
        # entries grouped by chunk (a small integer key: numpy's stable sort is then a radix sort)
        n_chunks = -(-len(order) // chunk)
        entry_chunk = (entry_slot // chunk).astype(np.int16 if n_chunks < 2 ** 15 else np.int64)
        by_chunk = np.argsort(entry_chunk, kind="stable")
        bounds = np.searchsorted(entry_chunk[by_chunk], np.arange(n_chunks + 1))
        flat_inverse = self._inverse.ravel()
        for k, start in enumerate(range(0, len(order), chunk)):
            part = order[start:start + chunk]
            v = int(sizes[part[-1]])
            if v == 0:
                continue
            # V: each press's nodes first, then padding
            nodes = np.argsort(~touched[part], axis=1, kind="stable")[:, :v]
            local = np.zeros((len(part), width), dtype=np.int64)
            np.put_along_axis(local, nodes, np.arange(v)[None], axis=1)
            e = by_chunk[bounds[k]:bounds[k + 1]]
            p = entry_slot[e] - start
            dL = np.bincount((p * v + local[p, entry_i[e]]) * v + local[p, entry_j[e]], weights=entry_value[e],
                             minlength=len(part) * v * v).reshape(len(part), v, v)
            G = flat_inverse.take(nodes[:, :, None] * width + nodes[:, None, :])
            P = self._inverse[nodes, :m]
            M = dL @ G
            M[:, np.arange(v), np.arange(v)] += 1.0
            out[part] -= np.swapaxes(P, 1, 2) @ np.linalg.solve(M, dL @ P)
        return out


class NearFarSolver:
    """Transfer resistances for presses whose change is large near the probe and small but wide
    around it (a deflection that spreads over the gel's thickness touches hundreds of nodes,
    too many for PatchUpdateSolver's exact low-rank update at thousands of presses a second).

    Edges between two nodes whose conductance moves by more than `near_tolerance` (relative)
    form the near field and go through the exact Woodbury update; every other changed edge
    enters to first order (`near_tolerance` 0: every change exactly, PatchUpdateSolver's path),
    dZ = -sum_e dg_e (u(p_e) - u(q_e)) (u(p_e) - u(q_e))^T with the resting sheet's potentials u
    (the adjoint sensitivity, Geselowitz; Holder 2005 ch. 1; as in the ERT skin's Jacobian,
    data/ert/jacobian.py). The error is second order in the far-field
    change plus the near field's effect on the far field's sensitivity; it is measured against
    the full sparse solve in tests/data/scenes/test_contract.py (under 1 % of a press's signal at 0.01).
    """

    def __init__(self, patch: PatchUpdateSolver, near_tolerance: float = 0.01):
        self.patch = patch
        self.near_tolerance = near_tolerance
        m = patch.solver.n_electrodes - 1
        drop = patch._inverse[patch._ends[:, 0], :m] - patch._inverse[patch._ends[:, 1], :m]   # (n_edges, m)
        self._edge_sensitivity = -(drop[:, :, None] * drop[:, None, :]).reshape(len(drop), m * m)

    def transfer_resistance(self, node_conductance_s: np.ndarray, chunk: int = 256) -> np.ndarray:
        """(n_presses, n_electrodes, n_electrodes) Z for (n_presses, n_nodes) conductance maps."""
        p, s = self.patch, self.patch.solver
        g = np.atleast_2d(node_conductance_s)
        if self.near_tolerance == 0:        # everything near: the exact update
            return p.transfer_resistance(g, chunk=chunk)
        n, m = len(g), s.n_electrodes - 1
        a, b = s.edges[:, 0], s.edges[:, 1]
        z = np.zeros((n, m + 1, m + 1))
        for start in range(0, n, chunk):
            part = slice(start, min(start + chunk, n))
            gp = g[part]
            relative = np.abs(gp / p._base_nodes - 1.0)
            near = relative > self.near_tolerance
            exact = near[:, a] & near[:, b]
            moved = (relative > 0)
            linear = (moved[:, a] | moved[:, b]) & ~exact
            z[part, :-1, :-1] = p._update(gp, changed=exact, chunk=chunk)
            ga, gb = gp[:, a], gp[:, b]
            delta = np.where(linear, s.edge_weight * 2.0 * ga * gb / (ga + gb) - p._base_edges, 0.0)
            z[part, :-1, :-1] += (delta @ self._edge_sensitivity).reshape(len(gp), m, m)
        return z
