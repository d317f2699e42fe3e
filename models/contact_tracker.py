"""Real-time contact detection with ids that stay put, on a mutual-capacitance array (seed 001).

Egger, Srinivas & Brandstötter, "Real-Time Detection and Localization of Force on a Capacitive
Elastomeric Sensor Array Using Image Processing and Machine Learning", Sensors 25 (2025) 3011,
sections 2.4.3-2.5.2 and Algorithm 1. Per frame, as the paper:

1. threshold filter, eq. (6): a cell counts only above its rest mean + c * spread, where the mean
   and spread come from contact-free rest frames, eqs. (4)-(5), after discarding the first few
   (the paper discards 5 "unstable" samples);
2. grey scaling to [0, 1];
3. Otsu's threshold (Otsu 1979) on the grey image -> a binary image;
4. connected-component labelling, 4- or 8-connected;
5. tracking: this frame's clusters get the ids of last frame's clusters they resemble (Jaccard).

`threshold="variance"` is eq. (6) as printed and as the public code (capsensor-monitor,
src/processor.py) computes it: mean + c * sigma^2. A variance has squared units, so its meaning
changes with the board's gain; the default `"std"` uses mean + c * sigma, a spread in the reading's
own units (c = 5 keeps Gaussian noise above threshold about 3 times in 10 million cells).

Two segmentations:
- `"paper"`: the public code exactly: cells below threshold set to 0 and the rest kept as raw
  values, the frame min-max scaled, skimage's threshold_otsu (256 bins) over the whole frame
  (zeros included), skimage's label. The raw values carry the rest offset (~1,200 counts), so
  Otsu mostly separates the zeroed cells from the rest and the threshold decides alone; two
  contacts whose above-threshold halos touch are one cluster.
- `"ours"`: the load (reading minus rest mean) of cells above threshold, scaled by the largest
  load among each cell's neighbours so a light touch beside a firm one survives, Otsu over those
  cells (the exact between-class-variance maximum over the sorted values, vectorised; skimage's
  histogram version costs ~200 us a call on this machine), and components by steepest ascent (along
  rows and columns; diagonal peaks joined over a high saddle) to the
  local peaks (see _segment_ours; scipy.ndimage.label costs 20-35 us a call here and joins
  contacts whose halos touch).

Two trackers:
- `"paper"`: Algorithm 1 as the public code (processor_utils.track_clusters): each cluster takes
  the label of its most similar previous cluster (greedy, first maximum), new clusters count up
  from the largest label, then all clusters are renumbered 1..n. Any contact that disappears
  renumbers the others: an identity switch by design.
- `"global"` (ours): one assignment over the whole Jaccard matrix (scipy's linear_sum_assignment,
  Kuhn-Munkres) with a minimum overlap; pairs with no overlap may still match within a distance
  gate around the track's predicted centroid (fast moves) or its last one (a light touch whose
  centroid jumps between crossings, where the velocity estimate is noise); merge: the older id survives and the
  younger is remembered inside it, and the region is reported at the older member's cluster of a
  weighted k-means over the region; a lighter touch that loses its own peak to a firmer
  neighbour's flank while still pressed is merged into that region the same way (absorbed, not
  retired); split: the larger child keeps the id, unless the region holds remembered contacts,
  then children (also a detection reappearing within the gate of a remembered contact) and
  remembered contacts are matched by predicted position; a contact is retired only after
  `max_missing_frames` frames without a match, so a one-frame dropout does not renumber it.

Speed: a frame with no cell above threshold skips clustering (as the paper). Everything is a
handful of numpy calls on the few cells above threshold; ids and tracks are the only Python
loops (over contacts, not cells).
"""
import collections
import math

import numpy as np
from scipy.optimize import linear_sum_assignment
from sklearn.base import BaseEstimator

from data.contact_windows import window_indices
from data.errors import InputError
from models.frame_contacts import FrameContacts
from models.otsu_threshold import otsu_threshold
from models.paper_contact_tracking import paper_track_clusters

THRESHOLDS = ("std", "variance")
SEGMENTATIONS = ("ours", "paper")
TRACKINGS = ("global", "paper")
FORCE_FEATURES = ("peak", "sum", "mean", "window")
SETTLE_FRAMES, SETTLE_MM = 10, 2.0  # merged members that moved less than this over these frames are one contact
HISTORY_FRAMES = 10  # centroids kept per track for the velocity a merge remembers (1/6 s at 60 frames/s)
MAX, MIN = np.maximum.reduce, np.minimum.reduce


class _Track:
    """A contact followed over frames (ours). `memory`: contacts merged into this one, as
    (id, birth, x, y, vx, vy, frame) at the moment they merged, this track's own state included.
    `path`: its last HISTORY_FRAMES (frame, x, y), for the velocity a merge remembers."""
    __slots__ = ("id", "birth", "cells", "size", "x", "y", "vx", "vy", "missing", "memory", "path", "member_xy", "member_path", "member_still")

    def __init__(self, track_id, birth, cells, x, y, size, frame=None):
        self.id, self.birth, self.cells, self.size = track_id, birth, cells, size
        self.x, self.y, self.vx, self.vy, self.missing, self.memory = x, y, 0.0, 0.0, 0, []
        self.member_xy = None  # while merged: each member's position in the region (k-means), memory's order
        self.member_path = collections.deque(maxlen=SETTLE_FRAMES)  # ... over the last frames; None: settled
        self.member_still = 0  # frames in a row the members have been still
        self.path = collections.deque([(birth if frame is None else frame, x, y)], maxlen=HISTORY_FRAMES)

    def snapshot(self, frame):
        """(id, birth, x, y, vx, vy, frame). The velocity is the least-squares slope of the
        centroid over the last HISTORY_FRAMES frames, not the running average the gate uses:
        two contacts about to merge pull each other's centroids sideways for the last few
        frames, and the remembered velocity has to carry a contact through the whole merge
        (up to 30 frames) to give it its id back at the split."""
        vx, vy = self.vx, self.vy
        if len(self.path) >= 3:
            t, x, y = zip(*self.path)
            t_mean, x_mean, y_mean = sum(t) / len(t), sum(x) / len(x), sum(y) / len(y)
            spread = sum((a - t_mean) ** 2 for a in t)
            vx = sum((a - t_mean) * (b - x_mean) for a, b in zip(t, x)) / spread
            vy = sum((a - t_mean) * (b - y_mean) for a, b in zip(t, y)) / spread
        return (self.id, self.birth, self.x, self.y, vx, vy, frame)


class ContactTracker(BaseEstimator):
    """Contacts with stable ids from a stream of mutual-capacitance frames.

    `fit(rest_frames)` learns the per-cell baseline; `update(frame)` returns a FrameContacts.
    Parameters (all plain values; nothing is computed here):
      rows, cols: grid; pitch_mm: cell spacing (centroids are in mm from the grid corner, cell
      (i, j) centred at ((j + 0.5) pitch, (i + 0.5) pitch)); discard_frames: first rest frames
      dropped (paper: 5); min_rest_frames: fewest rest frames left for a baseline;
      sensitivity: c of eq. (6); threshold: "std" | "variance"; min_spread: floor on sigma in
      "std" mode (a cell that never moved at rest, e.g. saturated, would otherwise fire on one
      count); segmentation: "ours" | "paper"; connectivity: 4 | 8; tracking: "global" | "paper";
      min_jaccard: least overlap for an overlap match; gate_mm: largest distance for a match
      without overlap (None: 2 pitches); max_missing_frames: frames a contact may be unseen
      before retirement; hold_sensitivity: c for cells next to a live contact (hysteresis
      thresholding, Canny 1986: a contact once found is followed down to a lower threshold, so a
      light touch near the detection limit does not flicker; new contacts still need
      `sensitivity`); None: one threshold, as the paper; force_model: callable(features) -> force_n, or a fitted
      regressor (predict), features one row per contact; force_feature: what the force model
      reads ("peak": the largest cell, as the characterisation presses at a cell centre; "sum",
      "mean"; "window": the 3 x 3 loads around the peak, the scene's `characterisation_channels:
      window` rows, so a model fitted on those presses by the regression pipeline serves); follow_drift: every
      frame, move the rest mean of each cell below threshold towards its reading by drift_rate
      (an exponential average; cells under a contact keep their mean); saddle_ratio: with
      connectivity 8, two diagonal peak cells are one contact when the larger of the two cells
      between them holds at least this fraction of the lower peak's load.
    """

    def __init__(self, rows=6, cols=6, pitch_mm=10.0, discard_frames=5, min_rest_frames=10, sensitivity=5.0,
                 threshold="std", min_spread=1.0, segmentation="ours", connectivity=8, tracking="global",
                 min_jaccard=0.1, gate_mm=None, max_missing_frames=3, hold_sensitivity=None, force_model=None,
                 force_feature="peak", follow_drift=False, drift_rate=0.02, saddle_ratio=0.6):
        self.rows = rows
        self.cols = cols
        self.pitch_mm = pitch_mm
        self.discard_frames = discard_frames
        self.min_rest_frames = min_rest_frames
        self.sensitivity = sensitivity
        self.threshold = threshold
        self.min_spread = min_spread
        self.segmentation = segmentation
        self.connectivity = connectivity
        self.tracking = tracking
        self.min_jaccard = min_jaccard
        self.gate_mm = gate_mm
        self.max_missing_frames = max_missing_frames
        self.hold_sensitivity = hold_sensitivity
        self.force_model = force_model
        self.force_feature = force_feature
        self.follow_drift = follow_drift
        self.drift_rate = drift_rate
        self.saddle_ratio = saddle_ratio

    # ----------------------------------------------------------------------------- fitting
    def _check_params(self):
        rows, cols = int(self.rows), int(self.cols)
        if rows < 1 or cols < 1:
            raise InputError(f"tracker grid must be at least 1 x 1, got {self.rows} x {self.cols}")
        for name, allowed in (("threshold", THRESHOLDS), ("segmentation", SEGMENTATIONS),
                              ("tracking", TRACKINGS), ("force_feature", FORCE_FEATURES)):
            if getattr(self, name) not in allowed:
                raise InputError(f"tracker.{name} must be one of {', '.join(allowed)}, got '{getattr(self, name)}'")
        if self.connectivity not in (4, 8):
            raise InputError(f"tracker.connectivity must be 4 or 8, got {self.connectivity}")
        if not self.pitch_mm > 0:
            raise InputError(f"tracker.pitch_mm must be positive, got {self.pitch_mm}")
        if not self.sensitivity >= 0:
            raise InputError(f"tracker.sensitivity (c of eq. 6) must be >= 0, got {self.sensitivity}")
        if self.min_rest_frames < 2:
            raise InputError(f"tracker.min_rest_frames must be at least 2 for a spread, got {self.min_rest_frames}")
        return rows, cols

    def _as_frames(self, frames, what: str) -> np.ndarray:
        try:
            array = np.asarray(frames, dtype=np.float64)
        except (ValueError, TypeError) as error:
            raise InputError(f"{what}: a cell is not a number ({str(error).splitlines()[0]})") from None
        n_cells = self.rows * self.cols
        if array.ndim == 0 or array.size == 0 or array.size % n_cells or (array.ndim >= 2 and array.shape[-1] not in (
                n_cells, self.cols)):
            shape = "x".join(map(str, array.shape))
            raise InputError(f"{what}: shape {shape} does not hold frames of {self.rows} x {self.cols} = {n_cells} cells")
        return array.reshape(-1, n_cells)

    def fit(self, rest_frames, y=None):
        """Learn the rest mean and spread per cell (eqs. 4-5, 1/N as the paper) from contact-free
        frames, after dropping the first `discard_frames`; reset the tracks."""
        rows, cols = self._check_params()
        frames = self._as_frames(rest_frames, "rest frames")
        if not np.isfinite(frames).all():
            raise InputError("rest frames: NaN or infinite cell value")
        usable = frames[int(self.discard_frames):]
        if len(usable) < self.min_rest_frames:
            raise InputError(f"rest frames: {len(frames)} given, {len(usable)} left after discarding "
                             f"{self.discard_frames}; a baseline needs at least {self.min_rest_frames}")
        self.n_cells_ = rows * cols
        self.mean_ = usable.mean(axis=0)
        self.variance_ = usable.var(axis=0)
        self.spread_ = np.maximum(np.sqrt(self.variance_), float(self.min_spread))
        self._set_threshold()
        row, col = np.divmod(np.arange(self.n_cells_), cols)
        self.cell_x_mm_ = (col + 0.5) * float(self.pitch_mm)
        self.cell_y_mm_ = (row + 0.5) * float(self.pitch_mm)
        # the 3 x 3 cells around each cell (itself included; at an edge, repeated edge cells, which
        # change no maximum and are weighted 0 in the centroid by window_weight_)
        dr, dc = np.meshgrid(np.arange(-1, 2), np.arange(-1, 2), indexing="ij")
        self.neighbourhood_ = (np.clip(row[:, None] + dr.reshape(-1), 0, rows - 1) * cols
                               + np.clip(col[:, None] + dc.reshape(-1), 0, cols - 1))
        inside = ((row[:, None] + dr.reshape(-1) >= 0) & (row[:, None] + dr.reshape(-1) < rows)
                  & (col[:, None] + dc.reshape(-1) >= 0) & (col[:, None] + dc.reshape(-1) < cols))
        self.window_weight_ = inside.astype(np.float64)  # the centroid's 3 x 3 window, whatever the connectivity
        # the climb to peaks steps along rows and columns only (the plus-shaped window); diagonal
        # neighbours are joined afterwards, peak to peak, only over a high saddle (_segment_ours)
        plus = (dr.reshape(-1) == 0) | (dc.reshape(-1) == 0)
        self.window_ = np.where(inside & plus, self.neighbourhood_, self.n_cells_)[:, plus]  # n_cells: padding
        # per cell, its 4 diagonal neighbours (window positions 0, 2, 6, 8) and the two cells each
        # diagonal step passes between (the shared row and column neighbours); padding outside
        diagonal, side = [0, 2, 6, 8], [(1, 3), (1, 5), (3, 7), (5, 7)]
        padded = window_indices(rows, cols)  # the force window too (data/contact_windows.py)
        self.diagonal_ = padded[:, diagonal]
        self.diagonal_sets_ = [frozenset(cells) for cells in self.diagonal_.tolist()]
        self.saddle_cells_ = np.stack([padded[:, [a for a, _ in side]], padded[:, [b for _, b in side]]])
        # (cell, window position, x|y): position 4 is the cell itself
        self.neighbourhood_t_ = np.ascontiguousarray(self.neighbourhood_.T)
        self.cell_xy_mm_ = np.stack([self.cell_x_mm_, self.cell_y_mm_], axis=1)
        # window position -> (column offset, row offset) in mm and 1: weight @ this = moments, total
        self.window_moments_ = np.stack([dc.reshape(-1) * float(self.pitch_mm), dr.reshape(-1) * float(self.pitch_mm),
                                         np.ones(9)], axis=1)
        self.window_xy_mm_ = np.stack([self.cell_x_mm_[self.neighbourhood_], self.cell_y_mm_[self.neighbourhood_]], axis=2)
        self.contact_numbers_ = np.arange(1, self.n_cells_ + 1)[:, None]
        self.no_force_ = np.full(self.n_cells_, np.nan)
        self.no_force_.flags.writeable = False
        self.no_load_ = np.zeros(self.n_cells_)
        self.no_load_.flags.writeable = False
        self.target_ = np.arange(self.n_cells_ + 1)   # scratch for _segment_ours: each core cell's climb target
        self.window_offsets_ = np.arange(self.n_cells_) * self.window_.shape[1]  # row starts in window_'s flat view
        self.shared_window_ = self._shared_window_table(16)
        self.contact_of_ = np.zeros(self.n_cells_ + 1, dtype=np.int64)  # scratch: contact number of each peak
        self.above_load_ = np.zeros(self.n_cells_ + 1)                  # scratch: load above threshold, padded
        self.padded_window_ = padded                                    # 3 x 3 window, outside -> padding cell
        self.value_ = np.full(self.n_cells_ + 1, -np.inf)     # scratch for _segment_ours
        self.padded_load_ = np.full(self.n_cells_ + 1, -np.inf)
        self.gate_mm_ = 2.0 * self.pitch_mm if self.gate_mm is None else float(self.gate_mm)
        self.grid_mm_ = np.array([cols, rows], dtype=np.float64) * float(self.pitch_mm)
        self.no_cell_contact_ = np.zeros(self.n_cells_ + 1, dtype=np.int64)
        self.no_cell_contact_.flags.writeable = False
        self.grid_ = (rows, cols, float(self.pitch_mm))
        self.reset()
        return self

    def _set_threshold(self):
        # eq. (6); "variance" keeps the public code's c * sigma^2 (no floor: exactly as it is)
        term = self.variance_ if self.threshold == "variance" else self.spread_
        self.threshold_ = self.mean_ + self.sensitivity * term
        hold = self.sensitivity if self.hold_sensitivity is None else min(self.hold_sensitivity, self.sensitivity)
        self.hold_threshold_ = self.mean_ + hold * term

    def reset(self):
        """Forget every track (a new recording with the same baseline)."""
        self.tracks_ = []
        self.track_cells_ = None    # the tracks' cells stacked (tracks x cells), None: to rebuild
        self.owner_ = None          # or track index + 1 on each cell of last frame's contacts, when every track was seen
        self.track_size_ = None     # with owner_: each track's cell count
        self.next_id_ = 1
        self.frame_index_ = -1
        self.prev_ids_ = np.zeros(0, dtype=np.int64)
        self.prev_cells_ = np.zeros((0, self.n_cells_), dtype=bool)
        self.near_contact_ = None   # cells next to last frame's contacts (hysteresis), None: none
        self.last_load_ = None      # the load of the last frame with contacts (ours)
        return self

    # ----------------------------------------------------------------------------- per frame
    def update(self, frame) -> FrameContacts:
        """The contacts of one frame (rows x cols, or rows*cols values row-major as the firmware sends)."""
        if not hasattr(self, "mean_"):
            raise InputError("tracker: call fit(rest_frames) before update(frame)")
        self.frame_index_ += 1
        try:
            x = np.asarray(frame, dtype=np.float64)
        except (ValueError, TypeError) as error:
            raise InputError(f"frame {self.frame_index_}: a cell is not a number "
                             f"({str(error).splitlines()[0]})") from None
        if x.ndim > 1 and x.shape != (self.rows, self.cols):
            raise InputError(f"frame {self.frame_index_}: a {' x '.join(map(str, x.shape))} frame, the tracker "
                             f"expects {self.rows} x {self.cols}")
        x = x.reshape(-1)
        if x.size != self.n_cells_:
            raise InputError(f"frame {self.frame_index_}: {x.size} cells, the tracker expects "
                             f"{self.rows} x {self.cols} = {self.n_cells_}")
        if not math.isfinite(np.add.reduce(x)):  # one reduction: any NaN or inf makes the sum non-finite
            raise InputError(f"frame {self.frame_index_}: NaN or infinite cell value")
        # eq. (6); the public code zeroes `data < threshold`, i.e. keeps `>=`
        above = x >= self.threshold_ if self.threshold == "variance" else x > self.threshold_
        if self.near_contact_ is not None:
            above |= self.near_contact_ & (x > self.hold_threshold_)
        if self.follow_drift:  # cells below threshold follow slow drift; touched cells stay put
            self.mean_ += self.drift_rate * (x - self.mean_) * ~above
            self._set_threshold()
        cells = above.nonzero()[0]
        if not len(cells):  # nothing above threshold: no clustering (paper, section 3.3)
            return self._no_contacts()
        load = x - self.mean_
        if self.segmentation == "paper":
            segments = self._segment_paper(x, above)
        else:
            segments = self._segment_ours(load, cells)
        if segments[1] == 0:
            return self._no_contacts()
        return self._describe(*segments, load, above)

    def _no_contacts(self) -> FrameContacts:
        self.near_contact_ = None
        if self.tracking == "paper":
            self.prev_ids_ = self.prev_ids_[:0]
            self.prev_cells_ = self.prev_cells_[:0]
        elif self.tracks_:
            self._age(self.tracks_)
        empty = np.zeros(0)
        return FrameContacts(self.frame_index_, np.zeros(0, dtype=np.int64), empty, empty, empty,
                             empty, empty, self.no_cell_contact_, self.grid_, self.no_load_)

    def _segment_ours(self, load, cells):
        """Grey scaling by the local peak, Otsu, then components -> (label per cell (flat, 0
        background), count, contact cells, their contact numbers 1..n, each contact's peak cell).

        Each above-threshold cell's load is divided by the largest load among its neighbours
        (itself included), so every contact peaks at 1 whatever its force and Otsu cuts each
        contact's core from its halo alike: a light touch beside a firm one is kept.
        Components: every core cell steps to its largest row or column neighbour in the core
        until it reaches a peak; the cells that reach one peak form one contact (connected
        components of the steepest-ascent forest: a watershed, Vincent & Soille 1991, at the
        resolution of the grid). Plain connected components (the paper) join two contacts whose
        halos touch; climbing to peaks keeps them apart as long as each has a peak cell of its
        own. With 8-connectivity two peaks that are diagonal neighbours are then one contact if
        the saddle between them is high (>= saddle_ratio of the lower peak: one touch between
        four crossings); diagonal steps on the climb itself would let a light touch's cells run
        up a firmer neighbour's flank (seen on the default stream: five-tap waves lost a contact
        and switched ids). Contacts whose peak cells are row or column neighbours are one: the
        grid's resolution. Pointer jumping (each cell's target replaced by its target's target)
        reaches the peaks in log2(path length) steps."""
        # (ufunc reductions rather than array methods throughout: a method's wrapper costs ~1 us)
        # (take, not fancy indexing, for the 2-d gather: ~2 us less a call on these sizes)
        local_peak = MAX(load.take(self.neighbourhood_t_.take(cells, axis=1)), axis=0)
        if self.threshold == "variance":  # `>=` admits a cell exactly at its rest mean: load 0
            local_peak = np.maximum(local_peak, 1e-12)
        grey = load[cells] / local_peak
        core = cells[grey >= otsu_threshold(grey)]
        value = self.value_  # load on core cells, -inf elsewhere and on the padding cell
        value.fill(-np.inf)
        value[core] = load[core]
        window = self.window_[core]
        target = self.target_  # only core cells' entries are written and read (they point at core cells)
        target[core] = window.ravel()[value[window].argmax(axis=1) + self.window_offsets_[:len(core)]]
        peak = self._climb(target, target[core])
        peaks = core[peak == core]
        if self.connectivity == 8 and len(peaks) > 1 and self._diagonal_peaks(peaks):
            # diagonal neighbours on the climb would let a light touch's cells run up a firmer
            # neighbour's flank across a diagonal (its cells have no 4-connected path there); two
            # diagonal peaks are one contact only when the saddle between them (the larger of the
            # two cells the step passes between) is at least `saddle_ratio` of the lower peak
            # (the prominence test of peak finding), e.g. one touch between four crossings
            diagonal = self.diagonal_[peaks]
            higher = value[diagonal]
            lower = value[peaks][:, None]
            saddle = np.maximum(*self._pad_load(load)[self.saddle_cells_[:, peaks]])
            join = ((higher > lower) | ((higher == lower) & (diagonal > peaks[:, None]))) \
                & (saddle >= self.saddle_ratio * lower) & (target[diagonal] == diagonal)
            joined = join.any(axis=1)
            if joined.any():
                best = np.where(join, higher, -np.inf).argmax(axis=1)
                target[peaks[joined]] = diagonal[joined, best[joined]]
                peak = self._climb(target, peak)
                peaks = core[peak == core]
        contact_of = self.contact_of_
        contact_of[peaks] = self.contact_numbers_[:len(peaks), 0]
        contact = contact_of[peak]
        labels = np.zeros(self.n_cells_ + 1, dtype=np.int64)  # padded: the last cell (outside) is 0
        labels[core] = contact
        return labels, len(peaks), core, contact, peaks

    def _diagonal_peaks(self, peaks) -> bool:
        """Whether any two peaks are diagonal neighbours (the only case the join can change); a
        handful of peaks: plain Python on sets, cheaper than four numpy calls."""
        peaks = set(peaks.tolist())
        diagonal = self.diagonal_sets_
        return not peaks.isdisjoint(frozenset().union(*map(diagonal.__getitem__, peaks)))

    @staticmethod
    def _climb(target, peak):
        """Pointer jumping: each cell's target replaced by its target's target until every cell
        points at a peak (a cell that is its own target)."""
        while True:  # two jumps per check: paths are short (a contact spans a few cells)
            further = target[target[peak]]
            if further.tobytes() == peak.tobytes():  # equal int64 arrays: ~10x cheaper than == and a reduction
                return peak
            peak = further

    def _pad_load(self, load):
        padded = self.padded_load_
        padded[:-1] = load
        return padded

    def _segment_paper(self, x, above):
        """The public code's processor.process: raw values kept above threshold, min-max scaled
        over the frame (sklearn MinMaxScaler: a constant frame scales to 0), skimage's Otsu,
        `>=`, skimage's label (connectivity None = 8)."""
        from skimage.filters import threshold_otsu
        from skimage.measure import label
        filtered = np.where(above, x, 0.0)
        low, high = filtered.min(), filtered.max()
        scaled = (filtered - low) / (high - low) if high > low else np.zeros_like(filtered)
        otsu = threshold_otsu(scaled)
        if math.isclose(otsu, 0):
            return None, 0, None, None, None
        binary = (scaled >= otsu).reshape(self.rows, self.cols)
        labels = label(binary, background=0, connectivity=None if self.connectivity == 8 else 1).reshape(-1)
        n = int(labels.max())
        if n == 0:
            return None, 0, None, None, None
        cells = labels.nonzero()[0]
        contact = labels[cells]
        labels = np.append(labels, 0)  # padded as _segment_ours: the last cell (outside) is 0
        on_contact = np.full((n, self.n_cells_), -np.inf)
        on_contact[contact - 1, cells] = (x - self.mean_)[cells]
        return labels, n, cells, contact, on_contact.argmax(axis=1)

    def _describe(self, labels, n, cells, contact, peak_cell, load, above) -> FrameContacts:
        """Per-contact figures from the label of every cell (flat), the contact cells, their
        contact numbers (1..n) and each contact's peak cell."""
        n_cells = np.bincount(contact, minlength=n + 1)[1:]
        peak = load[peak_cell]
        # centroid: load-weighted over the 3 x 3 cells around the contact's peak that are above
        # threshold and not another contact's (a touch controller's usual estimate; Otsu's core
        # alone can be one cell of the four a touch between crossings presses); window cells
        # outside the grid point at the padding cell, whose load is 0
        window = self.padded_window_[peak_cell]
        above_load = self.above_load_
        np.multiply(load, above, out=above_load[:-1])
        weight = above_load[window]
        allowed = None
        if n > 1:  # another contact's cells in the window do not count
            if n >= len(self.shared_window_):
                self.shared_window_ = self._shared_window_table(2 * n)
            allowed = self.shared_window_[self.contact_numbers_[:n], labels[window]]
            weight *= allowed
        # one product gives the load-weighted offsets from the peak cell (mm) and the total
        moments = np.dot(weight, self.window_moments_)
        total = moments[:, 2]
        xy_mm = self.cell_xy_mm_[peak_cell] + moments[:, :2] / total[:, None]
        if not min(total.tolist()) > 0:  # no positive load (threshold at the mean): the peak cell's centre
            xy_mm[total <= 0] = self.window_xy_mm_[peak_cell[total <= 0], 4]
        x_mm, y_mm = xy_mm[:, 0], xy_mm[:, 1]
        if self.tracking == "paper":
            one_hot = self._one_hot(cells, contact, n) > 0
            ids = paper_track_clusters(self.prev_ids_, self.prev_cells_, np.arange(1, n + 1), one_hot)
            self.prev_ids_, self.prev_cells_ = ids, one_hot
        else:
            ids = self._associate(cells, contact, n_cells, total, x_mm, y_mm, xy_mm, labels, load)
            self.last_load_ = load
        if self.hold_sensitivity is not None:
            self.near_contact_ = (labels > 0)[self.neighbourhood_].any(axis=1)
        contacts = FrameContacts(self.frame_index_, ids, x_mm, y_mm, n_cells, peak, self.no_force_[:n], labels,
                                 self.grid_, load)
        if self.force_model is not None:
            contacts.force_n = self._force(contacts, total, window, allowed)
        return contacts

    @staticmethod
    def _shared_window_table(n) -> np.ndarray:
        """(n + 1, n + 1) bool: entry (i, j) tells whether contact i may count a cell labelled j in
        its centroid window (j = 0, background, or j = i): one lookup instead of three comparisons."""
        numbers = np.arange(n + 1)
        return (numbers[None, :] == 0) | (numbers[None, :] == numbers[:, None])

    def _force(self, contacts, total, window, allowed) -> np.ndarray:
        """Force per contact from the force model. "window": the load of the 3 x 3 cells around
        the contact's peak as the characterisation presses give it (data/contact_windows.py: not
        thresholded, 0 outside the grid and on another contact's cells), one row per contact;
        the others: one number per contact."""
        if self.force_feature == "window":
            feature = np.append(contacts.load, 0.0)[window]
            if allowed is not None:
                feature *= allowed
        else:
            feature = {"peak": contacts.peak_load, "sum": total, "mean": contacts.mean_load}[self.force_feature]
            feature = feature.reshape(-1, 1)
        if hasattr(self.force_model, "predict"):
            return np.asarray(self.force_model.predict(feature), dtype=np.float64).reshape(-1)
        return np.asarray(self.force_model(feature), dtype=np.float64).reshape(-1)

    # ----------------------------------------------------------------------------- tracking (ours)
    def _new_track(self, cells, x, y, size) -> _Track:
        track = _Track(self.next_id_, self.frame_index_, cells, float(x), float(y), float(size))
        self.next_id_ += 1
        return track

    def _age(self, unmatched):
        """Unmatched tracks wait `max_missing_frames` frames before they are retired."""
        self._cells_to_tracks()
        for track in unmatched:
            track.missing += 1
        if unmatched:
            kept = [t for t in self.tracks_ if t.missing <= self.max_missing_frames]
            if len(kept) != len(self.tracks_):
                self.tracks_, self.track_cells_ = kept, None

    def _associate(self, cells, contact, det_size, det_load, det_x, det_y, xy_mm, labels, load) -> np.ndarray:
        """Ids for this frame's detections (cells and their detection numbers 1..n, labels: the
        detection number of every cell, padded; det_load:
        summed load, what "larger" means when a contact splits)."""
        n_det = len(det_x)
        tracks = self.tracks_
        if self.owner_ is not None and len(tracks) == n_det:
            # the usual frame, every track seen last frame: overlaps (tracks x detections) from one
            # count of (last frame's track, this frame's detection) pairs over this frame's cells.
            # If each track overlaps exactly one detection and each detection one track (Jaccard
            # >= min_jaccard, written without a division), that permutation is what the global
            # assignment below returns (overlap matches score above 1, all others at most 1)
            # (a handful of contacts: the test runs in plain Python, cheaper than a dozen numpy calls)
            pairs = n_det + 1
            inter = np.bincount(self.owner_[cells] * pairs + contact, minlength=pairs * pairs).tolist()
            jaccard, track_size, sizes = self.min_jaccard, self.track_size_, det_size.tolist()
            match = []
            for t in range(n_det):
                row = inter[(t + 1) * pairs + 1:(t + 2) * pairs]
                if row.count(0) == n_det - 1:  # one overlapping detection (the usual case): test it alone
                    d = row.index(max(row))
                    if row[d] * (1.0 + jaccard) < jaccard * (track_size[t] + sizes[d]):
                        break
                    match.append(d)
                    continue
                ok = [d for d in range(n_det) if row[d] * (1.0 + jaccard) >= jaccard * (track_size[t] + sizes[d])]
                if len(ok) != 1:
                    break
                match.append(ok[0])
            else:
                if len(set(match)) == n_det:
                    return self._follow_all(match, cells, contact, det_size, xy_mm, labels)
        det_cells = self._one_hot(cells, contact, n_det)
        self._cells_to_tracks()
        if not tracks:
            self.tracks_ = [self._new_track(det_cells[d], det_x[d], det_y[d], det_size[d]) for d in range(n_det)]
            self.track_cells_ = det_cells
            return np.array([t.id for t in self.tracks_], dtype=np.int64)
        # overlap of every track's last cells with every detection: one small matrix product
        if self.track_cells_ is None:
            self.track_cells_ = np.stack([t.cells for t in tracks])
        inter = self.track_cells_ @ det_cells.T
        if len(tracks) == n_det:
            # the usual frame: each track overlaps exactly one detection and each detection one
            # track (Jaccard >= min_jaccard, written without a division). Overlap matches score
            # above 1 and all others at most 1 below, so this permutation is what the assignment
            # below would return: skip the distance matrix and the solver
            ok = inter * (1.0 + self.min_jaccard) >= self.min_jaccard * (self.track_cells_.sum(axis=1)[:, None] + det_size)
            if ok.sum() == n_det and ok.any(axis=0).all() and ok.any(axis=1).all():
                return self._follow_all(ok.argmax(axis=1).tolist(), cells, contact, det_size, xy_mm, labels)
        state = np.array([(t.size, t.x + t.vx * (t.missing + 1), t.y + t.vy * (t.missing + 1), t.x, t.y)
                          for t in tracks])
        jaccard = inter / (state[:, :1] + det_size - inter)
        # the gate is around the predicted centroid or the last one, whichever is nearer: a light
        # touch's centroid jumps between crossings and its velocity estimate is then noise
        distance = np.minimum(np.hypot(state[:, 1:2] - det_x, state[:, 2:3] - det_y),
                              np.hypot(state[:, 3:4] - det_x, state[:, 4:5] - det_y))
        # overlap matches score in (1, 2], gated distance-only matches in (0, 1]; 0 = not allowed
        score = np.where(jaccard >= self.min_jaccard, jaccard + 1.0,
                         np.maximum(1.0 - distance * (0.999 / self.gate_mm_), 0.0))
        rows, cols = linear_sum_assignment(score, maximize=True)
        kept = score[rows, cols] > 0
        if len(tracks) == n_det and kept.all():  # every contact found again (some by distance)
            return self._follow_all(cols.tolist(), cells, contact, det_size, xy_mm, labels)
        det_of = {t: d for t, d, keep in zip(rows.tolist(), cols.tolist(), kept.tolist()) if keep}
        ids = np.zeros(n_det, dtype=np.int64)
        track_of = {d: t for t, d in det_of.items()}                    # detection -> track index
        fresh = [t.missing == 0 for t in tracks]                         # seen last frame
        # merge: a fresh unmatched track that a matched detection has taken in: most of its cells
        # in the region, or some of them with its predicted centroid within a pitch of the
        # region's (an Otsu core shrinks as two contacts join), or none of them but still
        # pressed and touching the region (a lighter touch whose peak a firmer neighbour's
        # spread has absorbed: no dip left between them, so no contact of its own)
        merged = set()
        for t in range(len(tracks)):
            if t in det_of or t in merged or not fresh[t]:
                continue
            d = int(np.argmax(inter[t]))
            if inter[t, d] <= 0:
                d = self._absorbing_detection(tracks[t], labels, track_of, load)
                if d is None:
                    continue
            elif d not in track_of:
                continue
            elif inter[t, d] < 0.5 * tracks[t].size and \
                    math.hypot(state[t, 1] - det_x[d], state[t, 2] - det_y[d]) > self.pitch_mm:
                continue
            m = track_of[d]
            older, younger = (t, m) if (tracks[t].birth, tracks[t].id) < (tracks[m].birth, tracks[m].id) else (m, t)
            host, guest = tracks[older], tracks[younger]
            if not host.memory:
                host.memory.append(host.snapshot(self.frame_index_))
            host.memory.append(guest.snapshot(self.frame_index_))
            host.memory.extend(guest.memory[1:] if guest.memory else [])
            host.member_xy = None
            host.member_path, host.member_still = collections.deque(maxlen=SETTLE_FRAMES), 0
            merged.add(younger)
            det_of.pop(m, None)
            det_of[older] = d
            track_of[d] = older
        # split: an unmatched detection lying mostly inside a matched track's last cells is its
        # child, or one within the gate of where a contact merged into a matched track would be
        # now (an absorbed touch reappears beside the region's cells, not inside them)
        matched = np.zeros(len(tracks))
        matched[list(det_of)] = 1.0
        hosts = None  # (track, its remembered members' predicted positions), built when first needed
        children = {}
        for d in range(n_det):
            if d in track_of:
                continue
            overlapping = inter[:, d] * matched
            t = int(np.argmax(overlapping))
            if overlapping[t] < 0.5 * det_size[d]:
                if hosts is None:
                    hosts = [(h, self._member_predictions(tracks[h].memory)) for h in det_of if tracks[h].memory]
                near = [(MIN(np.hypot(*(p - (det_x[d], det_y[d])).T)), h) for h, p in hosts]
                t = min(near)[1] if near and min(near)[0] <= self.gate_mm_ else None
            if t is not None:
                children.setdefault(t, [det_of[t]]).append(d)
        reinstated = []
        for t, kids in children.items():
            parent = tracks[t]
            if parent.memory:
                assigned = self._split_by_memory(parent, kids, det_x, det_y)
            else:  # the larger child (by load: force, not cell count) keeps the id
                assigned = {max(kids, key=lambda d: (det_load[d], -d)): parent.snapshot(self.frame_index_)}
            det_of.pop(t)
            back = set()
            for d, snap in assigned.items():
                if snap[0] == parent.id:
                    det_of[t] = d
                    track_of[d] = t
                    continue
                track = _Track(snap[0], snap[1], det_cells[d], float(det_x[d]), float(det_y[d]), float(det_size[d]),
                               frame=self.frame_index_)
                track.vx, track.vy = snap[4], snap[5]
                reinstated.append(track)
                ids[d] = track.id
                back.add(snap[0])
            parent.memory = [s for s in parent.memory if s[0] not in back]
            parent.member_xy = None
            parent.member_path, parent.member_still = collections.deque(maxlen=SETTLE_FRAMES), 0
            if len(parent.memory) == 1:  # only its own snapshot left: nothing merged any more
                parent.memory = []
        # update matched tracks; age the others; new ids for what is left
        unmatched, survivors = [], []
        for t, track in enumerate(tracks):
            if t in merged:
                continue
            survivors.append(track)
            d = det_of.get(t)
            if d is None:
                unmatched.append(track)
            else:
                self._move(track, d, det_cells, det_size, det_x, det_y, self.frame_index_)
                if track.memory:
                    self._update_members(track, np.flatnonzero(det_cells[d]), xy_mm[d])
                ids[d] = track.id
        self.tracks_ = survivors + reinstated
        self.track_cells_ = None
        self._age(unmatched)
        for d in np.flatnonzero(ids == 0).tolist():
            track = self._new_track(det_cells[d], det_x[d], det_y[d], det_size[d])
            self.tracks_.append(track)
            ids[d] = track.id
        return ids

    def _follow_all(self, cols, cells, contact, det_size, xy_mm, labels) -> np.ndarray:
        """Every track found again, track t at detection cols[t] (a list): the same update as
        _move, in plain floats (cheaper than numpy for a handful of contacts). The tracks'
        cells are kept as one image, owner_ (track index + 1 on each cell, 0 elsewhere), until
        a frame needs them per track (_cells_to_tracks)."""
        frame = self.frame_index_
        xy, sizes = xy_mm.tolist(), det_size.tolist()
        ids, track_of = [0] * len(cols), [0] * (len(cols) + 1)   # track_of: detection number -> track index + 1
        for t, (track, col) in enumerate(zip(self.tracks_, cols)):
            (x, y), steps = xy[col], track.missing + 1
            track.vx = 0.7 * track.vx + 0.3 * (x - track.x) / steps
            track.vy = 0.7 * track.vy + 0.3 * (y - track.y) / steps
            track.x, track.y, track.size, track.missing = x, y, sizes[col], 0
            track.path.append((frame, x, y))
            if track.memory:
                self._update_members(track, cells[contact == col + 1], xy_mm[col])
            ids[col], track_of[col + 1] = track.id, t + 1
        self.owner_ = np.array(track_of)[labels]
        self.track_size_, self.track_cells_ = [sizes[c] for c in cols], None
        return np.array(ids, dtype=np.int64)

    def _update_members(self, track, region_cells, xy_mm):
        """Where each member of a merged region is: a few Lloyd iterations of k-means (Lloyd 1982),
        k = the region's members, on the region's cells and their neighbours above threshold,
        weighted by load, started from each member's position last frame (at the merge: where
        it was). Two touches that one region covers pull a cluster each, so the region is
        reported with the older id (the merge rule) at the older member's cluster (written
        into xy_mm) rather than at the region's own centroid, which sits on the firmer touch
        and wanders between them, carrying the older id from one true contact to the other.
        The split still matches children by the motion each member had when it merged
        (_split_by_memory): two touches passing straight through each other leave one round
        region, whose k-means halves say nothing about who is who. Members that have all moved
        less than SETTLE_MM over the last SETTLE_FRAMES frames are a merge that stays (two
        touches pressed into one, the k-means only halving it): the region is then reported at
        its own centroid, still with the older id; still for three times as long, the merge is
        settled until the region splits (no k-means on it any more: a merge that stays costs
        nothing per frame)."""
        if track.member_path is None:  # settled: one touch until the region splits
            return
        cells = np.unique(self.neighbourhood_[region_cells])
        weight = self.above_load_[cells]
        cells, weight = cells[weight > 0], weight[weight > 0]
        if track.member_xy is None or len(track.member_xy) != len(track.memory):
            track.member_xy = np.array([(s[2], s[3]) for s in track.memory])
        centres = track.member_xy
        if len(cells) < len(centres):  # too few cells to place every member: the region's centroid
            return
        xy = self.cell_xy_mm_[cells]
        for _ in range(3):
            nearest = ((xy[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2).argmin(axis=1)
            total = np.bincount(nearest, weight, minlength=len(centres))
            has = total > 0
            for axis in (0, 1):
                moment = np.bincount(nearest, weight * xy[:, axis], minlength=len(centres))
                centres[has, axis] = moment[has] / total[has]
        track.member_path.append(centres.copy())
        path = track.member_path
        if len(path) == path.maxlen and MAX(np.hypot(*(path[-1] - path[0]).T)) < SETTLE_MM:
            # the members stopped moving: a merge that stays (one touch now), at the region's centroid;
            # still for three times as long, it is settled for good (no k-means until the split)
            track.member_still += 1
            if track.member_still >= 2 * SETTLE_FRAMES:
                track.member_path = None
            return
        track.member_still = 0
        own = [s[0] for s in track.memory].index(track.id)
        if total[own] > 0:
            xy_mm[:] = centres[own]

    def _absorbing_detection(self, track, labels, track_of, load):
        """The matched detection that has absorbed a lost track, or None. Absorbed: the track's
        last cells still carry their load (at least 60 % of last frame's peak there: a touch that
        lifts sheds it) and the steepest ascent over this frame's loads above threshold (rows and
        columns, as the segmentation climbs) from its highest cell ends on that detection's peak:
        the touch has no peak of its own any more, its load runs up a firmer neighbour's flank."""
        cells = np.flatnonzero(track.cells)
        if not len(cells) or self.last_load_ is None or MAX(load[cells]) < 0.6 * MAX(self.last_load_[cells]):
            return None
        above = self.above_load_  # this frame's load above threshold, 0 elsewhere and on the padding cell
        cell = int(cells[np.argmax(above[cells])])
        for _ in range(self.n_cells_):
            window = self.window_[cell]
            up = int(window[np.argmax(above[window])])
            if above[up] <= above[cell]:
                break
            cell = up
        d = int(labels[cell]) - 1
        return d if d in track_of else None

    def _member_predictions(self, snaps) -> np.ndarray:
        """(members, 2): where each merged contact would be now, carried on from its position
        and velocity when it merged for at most 30 frames (half a second at 60 frames/s)."""
        ahead = np.array([min(self.frame_index_ - s[6], 30) for s in snaps], dtype=np.float64)
        predicted = np.array([(s[2], s[3]) for s in snaps]) + np.array([(s[4], s[5]) for s in snaps]) * ahead[:, None]
        return np.clip(predicted, 0.0, self.grid_mm_)  # never off the sensor

    def _one_hot(self, cells, contact, n) -> np.ndarray:
        one_hot = np.zeros((n, self.n_cells_), dtype=np.float32)
        one_hot[contact - 1, cells] = 1.0
        return one_hot

    def _cells_to_tracks(self):
        """Each track's cells (one-hot rows) from the owner image, before a frame that changes
        the tracks or needs them one by one."""
        if self.owner_ is None:
            return
        owner, self.owner_ = self.owner_, None
        self.track_cells_ = (owner[:-1] == self.contact_numbers_[:len(self.tracks_)]).astype(np.float32)
        for track, cells in zip(self.tracks_, self.track_cells_):
            track.cells = cells

    @staticmethod
    def _move(track, d, det_cells, det_size, det_x, det_y, frame):
        """A track found again: its cells, its centroid, and a velocity (mm per frame, an
        exponential average with weight 0.3 on the newest step: a light touch's centroid jumps
        between crossings, which must not read as motion) for the distance gate's prediction."""
        steps = track.missing + 1
        x, y = float(det_x[d]), float(det_y[d])
        track.vx = 0.7 * track.vx + 0.3 * (x - track.x) / steps
        track.vy = 0.7 * track.vy + 0.3 * (y - track.y) / steps
        track.x, track.y, track.cells, track.size, track.missing = x, y, det_cells[d], float(det_size[d]), 0
        track.path.append((frame, x, y))

    def _split_by_memory(self, parent, kids, det_x, det_y) -> dict:
        """Children of a region that holds merged contacts get those contacts back by position:
        each remembered contact predicted from its velocity when it merged (at most 30 frames on),
        matched to the children by one assignment on distance; the region's own id is always placed.
        Returns child detection -> snapshot (id, birth, x, y, vx, vy, frame)."""
        snaps = parent.memory
        predicted = self._member_predictions(snaps)
        kid_xy = np.stack([det_x[kids], det_y[kids]], axis=1)
        cost = np.linalg.norm(predicted[:, None, :] - kid_xy[None, :, :], axis=2)
        own = next(i for i, s in enumerate(snaps) if s[0] == parent.id)
        cost[own] -= 1e6  # with more remembered contacts than children, the region's own id still gets one
        rows, cols = linear_sum_assignment(cost)
        return {kids[c]: snaps[r] for r, c in zip(rows, cols)}
