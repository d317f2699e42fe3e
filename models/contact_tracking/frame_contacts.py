"""What the contact tracker returns for one frame: its contacts as parallel arrays, kept apart
from the tracker's steps because applications read it without caring how the contacts were found."""
import numpy as np


class FrameContacts:
    """One frame's contacts: parallel arrays, one entry per contact; the id image, the areas and
    the mean loads are computed when asked for (most applications read centroids and ids only). A plain class
    with slots: built once per frame, where a frozen dataclass costs a few microseconds more.

    frame: frames updated since fit, from 0; ids: stable contact ids (int64), unique within the
    frame; x_mm, y_mm: load-weighted centroid (3 x 3 cells around the peak) from the grid's
    corner, column and row direction; n_cells: cells in the contact; mean_load, peak_load: mean
    and largest reading above the rest mean over its cells (RMC); force_n: from the force
    model, NaN without one; cell_contact: per cell (row-major, one padding entry at the end) 0
    or the contact's index + 1; grid: (rows, cols, pitch_mm); load: per cell, the reading above
    the rest mean (what mean_load averages over each contact's cells)."""
    __slots__ = ("frame", "ids", "x_mm", "y_mm", "n_cells", "peak_load", "force_n", "cell_contact", "grid", "load")

    def __init__(self, frame, ids, x_mm, y_mm, n_cells, peak_load, force_n, cell_contact, grid, load):
        self.frame, self.ids, self.x_mm, self.y_mm, self.n_cells = frame, ids, x_mm, y_mm, n_cells
        self.peak_load, self.force_n, self.cell_contact, self.grid, self.load = \
            peak_load, force_n, cell_contact, grid, load

    @property
    def mean_load(self) -> np.ndarray:
        """Mean load over each contact's cells."""
        n = len(self.ids)
        if n == 0:
            return np.zeros(0)
        total = np.bincount(self.cell_contact[:-1], weights=self.load, minlength=n + 1)[1:]
        return total / np.maximum(self.n_cells, 1)

    @property
    def labels(self) -> np.ndarray:
        """(rows, cols) int: 0 background, else the contact id on its cells."""
        rows, cols, _ = self.grid
        return np.r_[0, self.ids][self.cell_contact[:-1]].reshape(rows, cols)

    @property
    def area_mm2(self) -> np.ndarray:
        """n_cells * pitch^2."""
        return self.n_cells * self.grid[2] ** 2

    def __len__(self) -> int:
        return len(self.ids)

    def records(self) -> list[dict]:
        return [dict(frame=self.frame, id=int(i), x_mm=float(x), y_mm=float(y), cells=int(n),
                     area_mm2=float(a), mean_load=float(m), peak_load=float(p), force_n=float(f))
                for i, x, y, n, a, m, p, f in zip(self.ids, self.x_mm, self.y_mm, self.n_cells, self.area_mm2,
                                                  self.mean_load, self.peak_load, self.force_n)]
