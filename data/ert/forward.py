"""The forward model of the ERT skin: the sheet solver that turns a conductance map into the
transfer-resistance matrix Z (data/physics/sheet_conduction.py, and press_update.py's exact
low-rank update for presses), built for the sensor the scene simulates or for the nominal
geometry a reconstruction is drawn from. Readings from Z are readings.py."""
from functools import lru_cache

import numpy as np

from data.ert.cells import patch_weights
from data.physics.press_update import PatchUpdateSolver
from data.physics.sheet_conduction import SheetGrid, SheetSolver


@lru_cache(maxsize=6)
def sheet_solver(side_mm, grid_nodes, electrode_width_mm, electrodes_mm, patch_mm, sheet_resistance_ohm_per_sq,
                 patch_base_resistance_scale, anisotropy=1.0) -> PatchUpdateSolver:
    """The patch-update solver for one sensor (geometry, base map, anisotropy), built once per
    process (arguments hashable: tuples)."""
    grid = SheetGrid(side_mm, grid_nodes, np.asarray(electrodes_mm, dtype=float), electrode_width_mm)
    solver = SheetSolver(grid, anisotropy)
    share = patch_weights(grid.node_xy_mm, side_mm, patch_mm)
    base = 1.0 / (sheet_resistance_ohm_per_sq * (share @ np.asarray(patch_base_resistance_scale)))
    return PatchUpdateSolver(solver, base, max_patch_nodes=700)


def nominal_sheet(geometry: dict) -> tuple[SheetSolver, float]:
    """(solver, uniform sheet conductance in siemens per square) of the nominal geometry
    (ERTScene.geometry()): what the designer drew, isotropic, no specimen spread."""
    grid = SheetGrid(geometry["side_mm"], geometry["grid_nodes"], np.asarray(geometry["electrodes_mm"], dtype=float),
                     geometry.get("electrode_width_mm", 0.0))
    return SheetSolver(grid), 1.0 / geometry["sheet_resistance_ohm_per_sq"]
