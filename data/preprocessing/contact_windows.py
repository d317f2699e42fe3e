"""The 3 x 3 cells around a cell of a capacitive array: what a contact's force is read from.

A touch controller reads a contact's force from the cells around its peak (seed 001 fits force
to the pressed cell's RMC, sec. 3.5; a touch between crossings shares its load with the
neighbours, so the window is the steadier reading). One definition serves both sides: the
scene's characterisation presses (`characterisation_channels: window`, the training rows of the
force model) and the contact tracker (models/contact_tracking/, the same window around each
contact's peak cell), so a force model fitted on the presses reads the tracker's windows
unchanged. Cells outside the grid point at a padding index (rows * cols) whose load is 0.
"""
import numpy as np

OFFSETS = [(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1)]   # row-major; index 4 is the cell itself


def window_indices(rows: int, cols: int) -> np.ndarray:
    """(rows * cols, 9) flat indices of each cell's 3 x 3 window; rows * cols outside the grid."""
    row, col = np.divmod(np.arange(rows * cols), cols)
    dr, dc = np.array(OFFSETS).T
    r, c = row[:, None] + dr, col[:, None] + dc
    inside = (r >= 0) & (r < rows) & (c >= 0) & (c < cols)
    return np.where(inside, r * cols + c, rows * cols)


def window_channel_names() -> list[str]:
    """Channel names of a window, e.g. rmc_window_r-1_c+0 for the cell above the peak."""
    return [f"rmc_window_r{dr:+d}_c{dc:+d}" for dr, dc in OFFSETS]


def windows_around_peaks(loads: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """(n, 9): the load of the 3 x 3 cells around each row's largest cell (0 outside the grid)."""
    loads = np.asarray(loads, dtype=np.float64).reshape(-1, rows * cols)
    padded = np.concatenate([loads, np.zeros((len(loads), 1))], axis=1)
    window = window_indices(rows, cols)[loads.argmax(axis=1)]
    return np.take_along_axis(padded, window, axis=1)
