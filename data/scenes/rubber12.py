"""Scene `rubber12`: a 50 x 50 mm carbon-black rubber sheet on a 6 mm gel, 12 edge electrodes.

Sensor (seed 000's lab): three electrodes per side at 1/4, 1/2 and 3/4 of the side, numbered
clockwise seen from above with y pointing up: e1-e3 along the top edge left to right, e4-e6
down the right edge, e7-e9 along the bottom right to left, e10-e12 up the left edge. A
flat cylindrical probe (7 mm diameter) indents the sheet at (x_mm, y_mm) to depth_mm.

Protocol: `lab` cycles through nine press points P1-P9 (a 3 x 3 grid, row by row from the
top-left) and `n_depth_steps` depths from 0.3 to 3.0 mm (5-50 % of the gel), repeating the
position-depth pairs until `n_samples` presses; at each point the depths go up
(`sequence: up`) or up and back down (`up_down`, where hysteresis shows); every press is
press-hold-retract. `random` draws positions and depths uniformly.

Each channel is the two-terminal resistance between an electrode pair from a real solve of
the sheet's current flow (data/physics/sheet_conduction.py); the default pattern `near_opposite`
measures each electrode against the one five places clockwise (the twelve-channel pattern that
comes closest to the lab's sensitivity map, docs/fidelity.md), giving channels r_01_ohm ...
r_12_ohm (r_01_norm ... after minmax_normalize, whose per-channel minimum and span the table
keeps in `normalisation`).

Physics comes only from the listed effects (data/scenes/rubber12_effects.py).
"""
import inspect
from functools import lru_cache

import numpy as np
import pandas as pd

from common.errors import InputError
from common.progress import progress
from data.physics.press_update import NearFarSolver, PatchUpdateSolver
from data.physics.sheet_conduction import SheetGrid, SheetSolver, pair_resistance_ohm
from data.scenes.contract import random_generator_for, resolve_effects
from data.scenes.rubber12_effects import EFFECTS, FIELD_EFFECTS, READING_EFFECTS
from data.sensor_table import SensorTable

TARGETS = ["x_mm", "y_mm", "depth_mm", "pressure_pa"]


def electrode_positions_mm(side_mm: float) -> np.ndarray:
    """Clockwise from the top-left: top (left to right), right (down), bottom (right to left), left (up)."""
    quarter = side_mm * np.array([0.25, 0.5, 0.75])
    top = np.column_stack([quarter, np.full(3, side_mm)])
    right = np.column_stack([np.full(3, side_mm), quarter[::-1]])
    bottom = np.column_stack([quarter[::-1], np.zeros(3)])
    left = np.column_stack([np.zeros(3), quarter])
    return np.vstack([top, right, bottom, left])


def measurement_pairs(pattern, n_electrodes: int = 12) -> np.ndarray:
    """0-based electrode pairs; `adjacent` = each electrode against its clockwise neighbour,
    `near_opposite` = each electrode against the one five places clockwise (12 channels that all
    cross the sheet; the default, see docs/rubber12.md), `opposite` = each electrode against the
    one across the sheet (6 channels, point-symmetric: a press and its image through the centre
    read alike), or an explicit list of 1-based [i, j] pairs."""
    if pattern in ("adjacent", "near_opposite"):
        first = np.arange(n_electrodes)
        step = 1 if pattern == "adjacent" else n_electrodes // 2 - 1
        return np.column_stack([first, (first + step) % n_electrodes])
    if pattern == "opposite":
        first = np.arange(n_electrodes // 2)
        return np.column_stack([first, first + n_electrodes // 2])
    if isinstance(pattern, str):
        raise InputError(f"scene rubber12: unknown measurement pattern '{pattern}'; "
                         "expected adjacent, near_opposite, opposite or a list of [i, j] electrode pairs (1-12)")
    pairs = np.asarray(list(map(list, pattern)), dtype=np.int64)
    if pairs.ndim != 2 or pairs.shape[1] != 2 or pairs.min() < 1 or pairs.max() > n_electrodes \
            or (pairs[:, 0] == pairs[:, 1]).any():
        raise InputError(f"scene rubber12: measurement pairs must be [i, j] with 1 <= i != j <= "
                         f"{n_electrodes}, got {pairs.tolist()}")
    return pairs - 1


class Rubber12Scene:
    """Simulated presses on the rubber12 sheet; `generate()` returns a SensorTable."""

    name = "rubber12"

    def __init__(self, n_samples=450, protocol="lab", seed=0, effects=None,
                 side_mm=50.0, gel_thickness_mm=6.0, probe_radius_mm=3.5,
                 sheet_resistance_ohm_per_sq=1.0e4, electrode_width_mm=2.5, grid_nodes=33,
                 press_points_mm=(12.5, 25.0, 37.5), depth_range_mm=(0.3, 3.0), n_depth_steps=10,
                 position_range_mm=(5.0, 45.0), sequence="up", measurement="near_opposite",
                 near_field_tolerance=0.01, progress=True):
        self.n_samples = n_samples
        self.protocol = protocol
        self.seed = seed
        self.effects = effects
        self.side_mm = side_mm
        self.gel_thickness_mm = gel_thickness_mm
        self.probe_radius_mm = probe_radius_mm
        self.sheet_resistance_ohm_per_sq = sheet_resistance_ohm_per_sq
        self.electrode_width_mm = electrode_width_mm
        self.grid_nodes = grid_nodes
        self.press_points_mm = press_points_mm
        self.depth_range_mm = depth_range_mm
        self.n_depth_steps = n_depth_steps
        self.position_range_mm = position_range_mm
        self.sequence = sequence
        self.measurement = measurement
        self.near_field_tolerance = near_field_tolerance
        self.progress = progress

    # -- protocol ---------------------------------------------------------------------------
    def _check(self):
        if not isinstance(self.n_samples, int) or self.n_samples < 1:
            raise InputError(f"scene.n_samples must be a positive integer, got {self.n_samples!r}")
        low, high = self.depth_range_mm
        if not 0.0 <= low <= high <= self.gel_thickness_mm:
            raise InputError(f"scene.depth_range_mm must satisfy 0 <= low <= high <= gel thickness "
                             f"({self.gel_thickness_mm} mm), got {list(self.depth_range_mm)}")
        if self.protocol not in ("lab", "random"):
            raise InputError(f"scene.protocol must be 'lab' or 'random', got '{self.protocol}'")
        if not 0.0 <= self.near_field_tolerance < 1.0:
            raise InputError(f"scene.near_field_tolerance must be in [0, 1), got {self.near_field_tolerance}")
        if self.sequence not in ("up", "up_down"):
            raise InputError(f"scene.sequence must be 'up' or 'up_down', got '{self.sequence}'")
        if self.grid_nodes < 5 or (self.grid_nodes - 1) % 4 or self.sheet_resistance_ohm_per_sq <= 0:
            raise InputError(f"scene.grid_nodes must be 4k + 1 >= 5 (so electrodes sit on nodes) and "
                             f"sheet_resistance_ohm_per_sq > 0, got {self.grid_nodes} and "
                             f"{self.sheet_resistance_ohm_per_sq}")

    def press_points(self) -> np.ndarray:
        """P1..P9 as (x, y) in mm, row by row from the top-left."""
        grid = np.asarray(self.press_points_mm, dtype=float)
        return np.array([(x, y) for y in grid[::-1] for x in grid])

    def _presses(self):
        """x, y, depth (mm), a group id per press (one per position-depth pair) and whether the
        press is reached from a deeper one at the same point (the unloading branch)."""
        n = self.n_samples
        low, high = self.depth_range_mm
        if self.protocol == "lab":
            points = self.press_points()
            depth_steps = np.arange(self.n_depth_steps)
            if self.sequence == "up_down":
                depth_steps = np.r_[depth_steps, depth_steps[-2::-1]]
            step = np.arange(n) % (len(points) * len(depth_steps))
            point, level = step // len(depth_steps), depth_steps[step % len(depth_steps)]
            xy = points[point]
            depth = np.linspace(low, high, self.n_depth_steps)[level]
            unloading = np.r_[False, (point[1:] == point[:-1]) & (level[1:] < level[:-1])]
            cycle = np.arange(n) // len(depth_steps)          # one indentation cycle: a point's depth sweep
            return xy[:, 0], xy[:, 1], depth, point * self.n_depth_steps + level, unloading, cycle
        rng = random_generator_for(self.seed, "protocol")
        lo, hi = self.position_range_mm
        xy = rng.uniform(lo, hi, size=(n, 2))
        return (xy[:, 0], xy[:, 1], rng.uniform(low, high, size=n), np.arange(n), np.zeros(n, dtype=bool),
                np.arange(n))

    # -- simulation -------------------------------------------------------------------------
    def _solvers(self):
        return _solvers(float(self.side_mm), int(self.grid_nodes), float(self.electrode_width_mm),
                        float(self.sheet_resistance_ohm_per_sq), float(self.near_field_tolerance))

    def generate(self) -> SensorTable:
        """Run the protocol: `n_samples` presses through the listed effects."""
        self._check()
        return self.simulate(*self._presses())

    def simulate(self, x_mm, y_mm, depth_mm, groups=None, unloading=None, cycle=None,
                 chunk: int = 1024) -> SensorTable:
        """Readings for arbitrary presses (arrays of x, y, depth in mm), through the listed effects;
        `cycle` numbers each press's indentation cycle (default: every press its own)."""
        x, y, depth = (np.atleast_1d(np.asarray(v, dtype=float)) for v in (x_mm, y_mm, depth_mm))
        groups = np.arange(len(x)) if groups is None else np.asarray(groups)
        cycle = np.arange(len(x)) if cycle is None else np.asarray(cycle, dtype=int)
        unloading = np.zeros(len(x), dtype=bool) if unloading is None else np.asarray(unloading, dtype=bool)
        effects = resolve_effects(self.name, self.effects, EFFECTS)
        field_effects = [e for e in effects if e[0] in FIELD_EFFECTS]
        reading_effects = [e for e in effects if e[0] in READING_EFFECTS]
        pairs = measurement_pairs(self.measurement)
        solver, fast = self._solvers()
        geometry = {"probe_radius_mm": self.probe_radius_mm, "gel_thickness_mm": self.gel_thickness_mm,
                    "spacing_mm": solver.grid.spacing_mm, "side_mm": self.side_mm}
        node_xy = solver.grid.node_xy_mm
        base = 1.0 / self.sheet_resistance_ohm_per_sq

        n = len(x)
        readings, force, pressure = np.empty((n, len(pairs))), np.zeros(n), np.zeros(n)
        bar = progress(total=n, desc="rubber12", unit="presses", enabled=self.progress)
        # Field effects and the solve go chunk by chunk so memory stays flat in n_samples.
        for start in range(0, n, chunk):
            part = slice(start, min(start + chunk, n))
            state = {"x_mm": x[part], "y_mm": y[part], "depth_mm": depth[part],
                     "unloading": unloading[part], "cycle": cycle[part], "node_xy_mm": node_xy, "geometry": geometry}
            for name, fn, params in field_effects:
                # A field effect that draws (a per-sensor property) gets its own generator, the
                # same one in every chunk, so it draws the same sensor each time.
                if "rng" in inspect.signature(fn).parameters:
                    fn(state, random_generator_for(self.seed, name), **params)
                else:
                    fn(state, **params)
            scale = np.broadcast_to(state.get("conductance_scale", 1.0), (len(state["x_mm"]), len(node_xy)))
            z = fast.transfer_resistance(base * scale)
            readings[part] = pair_resistance_ohm(z, pairs)
            force[part] = state.get("force_n", 0.0)
            pressure[part] = state.get("pressure_pa", 0.0)
            bar.update(len(state["x_mm"]))
        bar.close()

        state = {"resistance_ohm": readings, "pairs": pairs, "force_n": force, "pressure_pa": pressure,
                 "probe_radius_mm": self.probe_radius_mm,
                 "channels": [f"r_{k + 1:02d}_ohm" for k in range(len(pairs))]}
        for name, fn, params in reading_effects:
            fn(state, random_generator_for(self.seed, name), **params)
        force, pressure = state["force_n"], state["pressure_pa"]

        channels = state["channels"]  # r_XX_norm after minmax_normalize
        frame = pd.DataFrame(state["resistance_ohm"], columns=channels)
        for column, values in zip(TARGETS, (x, y, depth, pressure)):
            frame[column] = values
        description = {"source": "scene", "scene": self.name, "protocol": self.protocol,
                       "effects": [name for name, _, _ in effects], "n_samples": n,
                       "force_n_range": [float(force.min()), float(force.max())]}
        return SensorTable(frame, channels, list(TARGETS), groups, description, state.get("normalisation"))

    def load(self) -> SensorTable:
        """Datamodule entry point: scenes and user tables both `load()` a SensorTable."""
        return self.generate()


@lru_cache(maxsize=4)
def _solvers(side_mm, grid_nodes, electrode_width_mm, sheet_resistance_ohm_per_sq, near_field_tolerance):
    """The exact sparse solver and the fast one for one geometry, built once per process (the
    dense baseline inverse takes ~0.2 s at 41 x 41 nodes). The fast one updates the near field
    exactly (Woodbury) and adds the rest of a press's change to first order (NearFarSolver);
    `near_field_tolerance` 0 makes it exact."""
    grid = SheetGrid(side_mm, grid_nodes, electrode_positions_mm(side_mm), electrode_width_mm)
    solver = SheetSolver(grid)
    return solver, NearFarSolver(PatchUpdateSolver(solver, 1.0 / sheet_resistance_ohm_per_sq), near_field_tolerance)
