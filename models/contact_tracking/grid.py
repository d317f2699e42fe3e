"""The sensor's grid as lookup tables, built once when the tracker is fitted: which cells surround
each cell and where each cell lies. Every per-frame step gathers through these tables instead of
looping over cells.

Cells are numbered row-major; a table entry outside the grid points at a padding index
(`n_cells`), so arrays indexed by a table carry one extra entry at the end (0 load, or -inf
when a maximum is taken).
"""
from dataclasses import dataclass

import numpy as np

from data.preprocessing.contact_windows import OFFSETS, window_indices

DIAGONAL = [i for i, (dr, dc) in enumerate(OFFSETS) if dr and dc]                 # window positions 0, 2, 6, 8
PLUS = [i for i, (dr, dc) in enumerate(OFFSETS) if not (dr and dc)]               # the cell and its row and column neighbours
# the two cells a diagonal step passes between: the shared row neighbour and column neighbour
SADDLE = [(OFFSETS.index((dr, 0)), OFFSETS.index((0, dc))) for dr, dc in (OFFSETS[i] for i in DIAGONAL)]


@dataclass(frozen=True, eq=False)
class Grid:
    rows: int
    cols: int
    pitch_mm: float
    n_cells: int
    cell_xy_mm: np.ndarray     # (cells, 2): centre of cell (r, c) at ((c + 1/2) pitch, (r + 1/2) pitch)
    neighbourhood: np.ndarray  # (9, cells): the 3 x 3 cells around each cell, clipped at the edges (a repeat changes no maximum)
    window: np.ndarray         # (cells, 9): the 3 x 3 window, padded (data/preprocessing/contact_windows.py: the force model's too)
    plus: np.ndarray           # (cells, 5): the cell and its row and column neighbours, padded: the climb to peaks
    plus_starts: np.ndarray    # where each row of a (k, 5) gather starts in its flat view
    diagonal: np.ndarray       # (cells, 4): the diagonal neighbours, padded
    diagonal_sets: list        # the same as frozensets (a handful of peaks is cheaper to test in Python)
    saddle: np.ndarray         # (2, cells, 4): the two cells between a cell and each diagonal neighbour
    window_moments: np.ndarray  # (9, 3): each window position's (x, y) offset in mm and 1: weights @ this = moments, total
    numbers: np.ndarray        # (cells, 1): 1, 2, ...: detection numbers
    background: np.ndarray     # (cells + 1,) read-only zeros: the label image of a frame without contact

    @property
    def size_mm(self) -> tuple[float, float]:
        return self.cols * self.pitch_mm, self.rows * self.pitch_mm


def make_grid(rows: int, cols: int, pitch_mm: float) -> Grid:
    row, col = np.divmod(np.arange(rows * cols), cols)
    dr, dc = np.array(OFFSETS).T
    clipped = np.clip(row[:, None] + dr, 0, rows - 1) * cols + np.clip(col[:, None] + dc, 0, cols - 1)
    window = window_indices(rows, cols)
    plus = window[:, PLUS]
    background = np.zeros(rows * cols + 1, dtype=np.int64)
    background.flags.writeable = False
    return Grid(rows=rows, cols=cols, pitch_mm=pitch_mm, n_cells=rows * cols,
                cell_xy_mm=np.stack([(col + 0.5) * pitch_mm, (row + 0.5) * pitch_mm], axis=1),
                neighbourhood=np.ascontiguousarray(clipped.T), window=window, plus=plus,
                plus_starts=np.arange(rows * cols) * plus.shape[1], diagonal=window[:, DIAGONAL],
                diagonal_sets=[frozenset(cells) for cells in window[:, DIAGONAL].tolist()],
                saddle=np.stack([window[:, [a for a, _ in SADDLE]], window[:, [b for _, b in SADDLE]]]),
                window_moments=np.stack([dc * pitch_mm, dr * pitch_mm, np.ones(9)], axis=1),
                numbers=np.arange(1, rows * cols + 1)[:, None], background=background)
