"""Detection (the paper's sec. 2.5.1, steps 2-4 of its pipeline, with our choices): one frame's
cells above threshold -> its contacts, each a peak and the cells that climb to it, with a
load-weighted centroid.

1. grey scaling: each above-threshold cell's load (reading minus rest mean) divided by the
   largest load among its 3 x 3 neighbours (itself included), so every contact peaks at 1
   whatever its force and Otsu cuts each contact's core from its halo alike: a light touch
   beside a firm one keeps its core;
2. Otsu's threshold (Otsu 1979) over those cells, exact (otsu_threshold.py);
3. components: every core cell steps to its largest row or column neighbour in the core until
   it reaches a peak; the cells that reach one peak form one contact (the connected components
   of the steepest-ascent forest: a watershed, Vincent & Soille 1991, at the resolution of the
   grid). Plain connected components (the paper's) join two contacts whose halos touch;
   climbing keeps them apart as long as each has a peak cell of its own. Diagonal steps on the
   climb would let a light touch's cells run up a firmer neighbour's flank, so with
   8-connectivity two peaks that are diagonal neighbours are joined afterwards, only over a
   high saddle (one touch between four crossings);
4. centroid: load-weighted over the 3 x 3 cells around the peak that are above threshold and not
   another contact's (a touch controller's usual estimate; Otsu's core alone can be one cell of
   the four a touch between crossings presses).

The paper's own segmentation (min-max scaling, skimage's Otsu and labelling) is in paper.py and
returns the same three arrays, so `describe` serves both.

Speed: a handful of numpy calls on the few cells above threshold; ufunc reductions rather than
array methods (a method's wrapper costs ~1 us here), `take` rather than a 2-d fancy index.
"""
import functools
from dataclasses import dataclass

import numpy as np

from models.contact_tracking.grid import Grid
from models.contact_tracking.otsu_threshold import otsu_threshold

MAX = np.maximum.reduce


@dataclass(slots=True, eq=False)
class Detections:
    """One frame's contacts before tracking, numbered 1..n on the cells; arrays per detection
    are indexed 0..n-1."""
    labels: np.ndarray      # per cell, with the padding entry (0) at the end: detection number, 0 background
    cells: np.ndarray       # the detections' cells, ascending
    number: np.ndarray      # each of those cells' detection number
    peak_cell: np.ndarray   # (n,)
    n_cells: np.ndarray     # (n,) cells per detection
    window_load: np.ndarray  # (n,) load over the centroid's window: the larger of two children
    xy_mm: np.ndarray       # (n, 2) centroids
    window: np.ndarray      # (n, 9) the 3 x 3 cells around each peak (padding outside the grid)
    counted: np.ndarray | None  # (n, 9) whether each window cell is not another detection's; None: one detection
    load: np.ndarray        # per cell: reading minus rest mean
    above_load: np.ndarray  # per cell, padded: the load where above threshold, 0 elsewhere

    @property
    def n(self) -> int:
        return len(self.peak_cell)

    @property
    def peak_load(self) -> np.ndarray:
        return self.load[self.peak_cell]

    def one_hot(self) -> np.ndarray:
        """(n, cells) float32: 1 on each detection's cells."""
        one_hot = np.zeros((self.n, len(self.load)), dtype=np.float32)
        one_hot[self.number - 1, self.cells] = 1.0
        return one_hot


def segment(load: np.ndarray, cells: np.ndarray, grid: Grid, connectivity: int, saddle_ratio: float,
            inclusive: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Steps 1-3: (core cells, their detection numbers 1..n, each detection's peak cell), from
    the load and the cells above threshold. `inclusive`: the threshold admits a cell exactly at
    its rest mean (load 0), whose grey level needs a positive divisor."""
    local_peak = MAX(load.take(grid.neighbourhood.take(cells, axis=1)), axis=0)
    if inclusive:
        local_peak = np.maximum(local_peak, 1e-12)
    grey = load[cells] / local_peak
    core = cells[grey >= otsu_threshold(grey)]
    value = np.full(grid.n_cells + 1, -np.inf)  # load on core cells only
    value[core] = load[core]
    plus = grid.plus[core]
    target = np.empty(grid.n_cells + 1, dtype=np.int64)  # each core cell's step (only core entries are read)
    target[core] = plus.ravel()[value[plus].argmax(axis=1) + grid.plus_starts[:len(core)]]
    peak = _climb(target, target[core])
    peaks = core[peak == core]
    if connectivity == 8 and len(peaks) > 1 and _any_diagonal_neighbours(peaks, grid):
        peak = _join_diagonal_peaks(peaks, peak, target, value, load, grid, saddle_ratio)
        peaks = core[peak == core]
    number_of = np.empty(grid.n_cells + 1, dtype=np.int64)  # written at the peaks, read at the peaks
    number_of[peaks] = grid.numbers[:len(peaks), 0]
    return core, number_of[peak], peaks


def _climb(target: np.ndarray, peak: np.ndarray) -> np.ndarray:
    """Pointer jumping: each cell's target replaced by its target's target until every cell
    points at a peak (a cell that is its own target); log2(path length) steps."""
    while True:  # two jumps per check: paths are short (a contact spans a few cells)
        further = target[target[peak]]
        if further.tobytes() == peak.tobytes():  # equal int64 arrays: ~10x cheaper than == and a reduction
            return peak
        peak = further


def _any_diagonal_neighbours(peaks: np.ndarray, grid: Grid) -> bool:
    """Whether two peaks are diagonal neighbours, the only case the join can change (a handful
    of peaks: plain Python on sets, cheaper than four numpy calls)."""
    peaks = set(peaks.tolist())
    return not peaks.isdisjoint(frozenset().union(*map(grid.diagonal_sets.__getitem__, peaks)))


def _join_diagonal_peaks(peaks, peak, target, value, load, grid: Grid, saddle_ratio: float) -> np.ndarray:
    """Two peaks that are diagonal neighbours are one contact when the saddle between them (the
    larger of the two cells the diagonal passes between) holds at least `saddle_ratio` of the
    lower peak's load (the prominence test of peak finding): the lower peak steps to the higher
    one (ties: to the larger cell number) and the climb is redone. Returns each core cell's peak."""
    diagonal = grid.diagonal[peaks]
    higher = value[diagonal]
    lower = value[peaks][:, None]
    saddle = np.maximum(*np.append(load, -np.inf)[grid.saddle[:, peaks]])
    is_peak = np.zeros(grid.n_cells + 1, dtype=bool)
    is_peak[peaks] = True
    join = (((higher > lower) | ((higher == lower) & (diagonal > peaks[:, None])))
            & (saddle >= saddle_ratio * lower) & is_peak[diagonal])
    joined = join.any(axis=1)
    if not joined.any():
        return peak
    best = np.where(join, higher, -np.inf).argmax(axis=1)
    target[peaks[joined]] = diagonal[joined, best[joined]]
    return _climb(target, peak)


def describe(core: np.ndarray, number: np.ndarray, peaks: np.ndarray, load: np.ndarray, above: np.ndarray,
             grid: Grid) -> Detections:
    """Step 4 and the per-detection figures, from the segmentation's three arrays."""
    n = len(peaks)
    labels = np.zeros(grid.n_cells + 1, dtype=np.int64)
    labels[core] = number
    above_load = np.zeros(grid.n_cells + 1)
    np.multiply(load, above, out=above_load[:-1])
    window = grid.window[peaks]
    weight = above_load[window]
    counted = None
    if n > 1:  # another detection's cells in the window do not count
        counted = _may_count(1 << n.bit_length())[grid.numbers[:n], labels[window]]
        weight *= counted
    moments = np.dot(weight, grid.window_moments)  # load-weighted offsets from the peak cell (mm), and the total
    total = moments[:, 2]
    xy_mm = grid.cell_xy_mm[peaks] + moments[:, :2] / total[:, None]
    if not min(total.tolist()) > 0:  # no positive load (threshold at the mean): the peak cell's centre
        xy_mm[total <= 0] = grid.cell_xy_mm[peaks[total <= 0]]
    return Detections(labels, core, number, peaks, np.bincount(number, minlength=n + 1)[1:], total, xy_mm,
                      window, counted, load, above_load)


@functools.lru_cache(maxsize=8)
def _may_count(size: int) -> np.ndarray:
    """(size, size) bool: whether detection i may count a cell labelled j in its window (j = 0,
    background, or j = i): one lookup instead of three comparisons (sizes: powers of two)."""
    numbers = np.arange(size)
    return (numbers[None, :] == 0) | (numbers[None, :] == numbers[:, None])
