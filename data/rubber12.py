"""Scene `rubber12`: a 50 x 50 mm carbon-black rubber sheet on a 6 mm gel, 12 edge electrodes.

Sensor (seed 000's lab): three electrodes per side at 1/4, 1/2 and 3/4 of the side, numbered
clockwise seen from above with y pointing up: e1-e3 along the top edge left to right, e4-e6
down the right edge, e7-e9 along the bottom right to left, e10-e12 up the left edge. A
flat cylindrical probe (7 mm diameter) indents the sheet at (x_mm, y_mm) to depth_mm.

Protocol: `lab` cycles through nine press points P1-P9 (a 3 x 3 grid, row by row from the
top-left) and `n_depth_steps` depths from 0.3 to 3.0 mm (5-50 % of the gel), repeating the
90 position-depth pairs until `n_samples` presses; `random` draws positions and depths
uniformly. Each channel is the two-terminal resistance between an electrode pair from a real
solve of the sheet's current flow (data/conduction.py); the default pattern measures each
electrode against its clockwise neighbour, giving channels r_01_ohm ... r_12_ohm.

Physics comes only from the listed effects (data/rubber12_effects.py).
"""
import numpy as np
import pandas as pd
from tqdm.auto import tqdm

from data.conduction import SheetGrid, SheetSolver, pair_resistance_ohm
from data.effects import resolve_effects, stream
from data.errors import InputError
from data.rubber12_effects import EFFECTS, FIELD_EFFECTS
from data.table import SensorTable

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
    `opposite` = each electrode against the one across the sheet, or an explicit list of
    1-based [i, j] pairs."""
    if pattern == "adjacent":
        first = np.arange(n_electrodes)
        return np.column_stack([first, (first + 1) % n_electrodes])
    if pattern == "opposite":
        first = np.arange(n_electrodes // 2)
        return np.column_stack([first, first + n_electrodes // 2])
    if isinstance(pattern, str):
        raise InputError(f"scene rubber12: unknown measurement pattern '{pattern}'; "
                         "expected adjacent, opposite or a list of [i, j] electrode pairs (1-12)")
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
                 sheet_resistance_ohm_per_sq=1.0e4, electrode_width_mm=2.5, grid_nodes=41,
                 press_points_mm=(12.5, 25.0, 37.5), depth_range_mm=(0.3, 3.0), n_depth_steps=10,
                 position_range_mm=(5.0, 45.0), measurement="adjacent", progress=True):
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
        self.measurement = measurement
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
        if self.grid_nodes < 5 or self.sheet_resistance_ohm_per_sq <= 0:
            raise InputError("scene.grid_nodes must be >= 5 and sheet_resistance_ohm_per_sq > 0")

    def press_points(self) -> np.ndarray:
        """P1..P9 as (x, y) in mm, row by row from the top-left."""
        grid = np.asarray(self.press_points_mm, dtype=float)
        return np.array([(x, y) for y in grid[::-1] for x in grid])

    def _presses(self):
        """x, y, depth (mm) and a group id per press (one group per position-depth pair)."""
        n = self.n_samples
        low, high = self.depth_range_mm
        if self.protocol == "lab":
            points = self.press_points()
            depths = np.linspace(low, high, self.n_depth_steps)
            pair = np.arange(n) % (len(points) * len(depths))
            xy = points[pair // len(depths)]
            return xy[:, 0], xy[:, 1], depths[pair % len(depths)], pair
        rng = stream(self.seed, "protocol")
        lo, hi = self.position_range_mm
        xy = rng.uniform(lo, hi, size=(n, 2))
        return xy[:, 0], xy[:, 1], rng.uniform(low, high, size=n), np.arange(n)

    # -- simulation -------------------------------------------------------------------------
    def _solver(self) -> SheetSolver:
        grid = SheetGrid(self.side_mm, self.grid_nodes, electrode_positions_mm(self.side_mm),
                         self.electrode_width_mm)
        return SheetSolver(grid)

    def generate(self) -> SensorTable:
        self._check()
        effects = resolve_effects(self.name, self.effects, EFFECTS)
        pairs = measurement_pairs(self.measurement)
        solver = self._solver()
        x, y, depth, groups = self._presses()
        state = {"x_mm": x, "y_mm": y, "depth_mm": depth,
                 "force_n": np.zeros_like(depth), "pressure_pa": np.zeros_like(depth),
                 "node_xy_mm": solver.grid.node_xy_mm,
                 "geometry": {"probe_radius_mm": self.probe_radius_mm,
                              "gel_thickness_mm": self.gel_thickness_mm}}

        field_effects = [e for e in effects if e[0] in FIELD_EFFECTS]
        reading_effects = [e for e in effects if e[0] not in FIELD_EFFECTS]
        for name, fn, params in field_effects:
            fn(state, stream(self.seed, name), **params)

        base = 1.0 / self.sheet_resistance_ohm_per_sq
        scale = np.broadcast_to(state.get("conductance_scale", 1.0), (len(x), solver.grid.n_nodes**2))
        readings = np.empty((len(x), len(pairs)))
        # Presses that share one conductance map (no effect touched it) share one solve.
        uniform = not np.ndim(state.get("conductance_scale", 1.0))
        bar = tqdm(total=len(x), desc="rubber12: solving current flow", unit="press",
                   disable=not self.progress or len(x) < 500 or uniform, leave=False)
        for k in range(len(x)):
            if uniform and k > 0:
                readings[k] = readings[0]
                continue
            readings[k] = pair_resistance_ohm(solver.transfer_resistance(base * scale[k]), pairs)
            bar.update()
        bar.close()

        state["resistance_ohm"] = readings
        for name, fn, params in reading_effects:
            fn(state, stream(self.seed, name), **params)

        channels = [f"r_{k + 1:02d}_ohm" for k in range(len(pairs))]
        frame = pd.DataFrame(state["resistance_ohm"], columns=channels)
        for column, values in zip(TARGETS, (x, y, depth, state["pressure_pa"])):
            frame[column] = values
        description = {"source": "scene", "scene": self.name, "protocol": self.protocol,
                       "effects": [name for name, _, _ in effects], "n_samples": len(x),
                       "force_n_range": [float(state["force_n"].min()), float(state["force_n"].max())]}
        return SensorTable(frame, channels, list(TARGETS), groups, description)

    def load(self) -> SensorTable:
        """Datamodule entry point: scenes and user tables both `load()` a SensorTable."""
        return self.generate()
