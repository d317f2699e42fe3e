"""`ContactTracker`: contacts with ids that stay put, from a stream of mutual-capacitance frames
(seed 001: Egger, Srinivas & Brandstötter, "Real-Time Detection and Localization of Force on a
Capacitive Elastomeric Sensor Array Using Image Processing and Machine Learning", Sensors 25
(2025) 3011, sections 2.4.3-2.5.2 and Algorithm 1).

A thin estimator over the paper's steps, one file each: baseline and noise model (baseline.py,
eqs. 4-6), detection (detection.py, or the paper's own in paper.py), association
(association.py) and track lifecycle (tracks.py, or the paper's Algorithm 1 in paper.py); then
force per contact from a fitted model. A frame with no cell above threshold skips clustering
(as the paper).
"""
import math

import numpy as np
from sklearn.base import BaseEstimator

from common.errors import InputError
from models.contact_tracking.baseline import THRESHOLDS, above_threshold, fit_baseline, follow_drift
from models.contact_tracking.detection import Detections, describe, segment
from models.contact_tracking.frame_contacts import FrameContacts
from models.contact_tracking.grid import make_grid
from models.contact_tracking.paper import PaperClusters, segment_paper
from models.contact_tracking.tracks import Tracks

SEGMENTATIONS = ("ours", "paper")
TRACKINGS = ("global", "paper")
FORCE_FEATURES = ("peak", "sum", "mean", "window")
PADDING = np.zeros(1)
NONE, NO_IDS = np.zeros(0), np.zeros(0, dtype=np.int64)  # a frame without contact's per-contact arrays
NONE.flags.writeable = NO_IDS.flags.writeable = False


class ContactTracker(BaseEstimator):
    """Contacts with stable ids from a stream of mutual-capacitance frames.

    `fit(rest_frames)` learns the per-cell baseline; `update(frame)` returns a FrameContacts.
    Parameters (all plain values; nothing is computed here):
      rows, cols: grid; pitch_mm: cell spacing (centroids are in mm from the grid corner, cell
      (i, j) centred at ((j + 0.5) pitch, (i + 0.5) pitch)); discard_frames: first rest frames
      dropped (paper: 5); min_rest_frames: fewest rest frames left for a baseline;
      sensitivity: c of eq. (6); threshold: "std" | "variance"; min_spread: floor on sigma in
      "std" mode; segmentation: "ours" | "paper"; connectivity: 4 | 8; saddle_ratio: with
      connectivity 8, two diagonal peak cells are one contact when the larger of the two cells
      between them holds at least this fraction of the lower peak's load; tracking: "global"
      (ours) | "paper"; min_jaccard: least overlap for an overlap match; gate_mm: largest
      distance for a match without overlap (None: 2 pitches); max_missing_frames: frames a
      contact may be unseen before retirement; hold_sensitivity: c for cells next to a live
      contact (hysteresis; new contacts still need `sensitivity`), None: one threshold, as the
      paper; force_model: callable(features) -> force_n, or a fitted regressor (predict),
      features one row per contact; force_feature: what the force model reads ("peak": the
      largest cell, as the characterisation presses at a cell centre; "sum", "mean"; "window":
      the 3 x 3 loads around the peak, not thresholded, 0 outside the grid and on another
      contact's cells: the scene's `characterisation_channels: window` rows,
      data/preprocessing/contact_windows.py, so a model fitted on those presses serves); follow_drift: every
      frame, move the rest mean of each cell below threshold towards its reading by drift_rate.

    Learned: baseline_ (mean_, variance_, spread_, threshold_ read from it), grid_, tracks_
    (the contacts followed), frame_index_, near_contact_ (cells next to last frame's contacts).
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
    def fit(self, rest_frames, y=None):
        """Learn the rest mean and spread per cell from contact-free frames; reset the tracks."""
        rows, cols = self._check_params()
        frames = self._as_frames(rest_frames, "rest frames")
        self.baseline_ = fit_baseline(frames, self.discard_frames, self.min_rest_frames, self.threshold,
                                      self.sensitivity, self.hold_sensitivity, self.min_spread)
        self.grid_ = make_grid(rows, cols, float(self.pitch_mm))
        return self.reset()

    def reset(self):
        """Forget every track (a new recording with the same baseline)."""
        if self.tracking == "paper":
            self.tracks_ = PaperClusters(self.grid_.n_cells)
        else:
            gate_mm = 2.0 * self.pitch_mm if self.gate_mm is None else float(self.gate_mm)
            self.tracks_ = Tracks(self.grid_, self.min_jaccard, gate_mm, self.max_missing_frames)
        self.frame_index_ = -1
        self.near_contact_ = None
        return self

    mean_ = property(lambda self: self.baseline_.mean, doc="rest mean per cell (counts)")
    variance_ = property(lambda self: self.baseline_.variance, doc="rest variance per cell")
    spread_ = property(lambda self: self.baseline_.spread, doc="rest sigma per cell, floored at min_spread")
    threshold_ = property(lambda self: self.baseline_.threshold, doc="eq. (6) per cell")

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

    # ----------------------------------------------------------------------------- per frame
    def update(self, frame) -> FrameContacts:
        """The contacts of one frame (rows x cols, or rows*cols values row-major as the firmware sends)."""
        if not hasattr(self, "baseline_"):
            raise InputError("tracker: call fit(rest_frames) before update(frame)")
        self.frame_index_ += 1
        x = self._as_frame(frame)
        above = above_threshold(self.baseline_, x, self.near_contact_)
        if self.follow_drift:
            follow_drift(self.baseline_, x, above, self.drift_rate)
        cells = above.nonzero()[0]
        load = x - self.baseline_.mean
        if not len(cells):  # nothing above threshold: no clustering (paper, section 3.3)
            return self._no_contacts(load)
        if self.segmentation == "paper":
            segments = segment_paper(x, above, load, self.grid_, self.connectivity)
        else:
            segments = segment(load, cells, self.grid_, self.connectivity, self.saddle_ratio,
                               self.threshold == "variance")
        if segments is None:
            return self._no_contacts(load)
        detections = describe(*segments, load, above, self.grid_)
        ids = self.tracks_.update(detections, self.frame_index_)
        if self.hold_sensitivity is not None:
            self.near_contact_ = (detections.labels > 0)[self.grid_.neighbourhood].any(axis=0)
        contacts = FrameContacts(self.frame_index_, ids, detections.xy_mm[:, 0], detections.xy_mm[:, 1],
                                 detections.n_cells, detections.peak_load, np.full(detections.n, np.nan),
                                 detections.labels, (self.grid_.rows, self.grid_.cols, self.grid_.pitch_mm), load)
        if self.force_model is not None:
            contacts.force_n = self._force(contacts, detections)
        return contacts

    def _as_frame(self, frame) -> np.ndarray:
        try:
            x = np.asarray(frame, dtype=np.float64)
        except (ValueError, TypeError) as error:
            raise InputError(f"frame {self.frame_index_}: a cell is not a number "
                             f"({str(error).splitlines()[0]})") from None
        if x.ndim > 1 and x.shape != (self.rows, self.cols):
            raise InputError(f"frame {self.frame_index_}: a {' x '.join(map(str, x.shape))} frame, the tracker "
                             f"expects {self.rows} x {self.cols}")
        x = x.reshape(-1)
        if x.size != self.grid_.n_cells:
            raise InputError(f"frame {self.frame_index_}: {x.size} cells, the tracker expects "
                             f"{self.rows} x {self.cols} = {self.grid_.n_cells}")
        if not math.isfinite(np.add.reduce(x)):  # one reduction: any NaN or inf makes the sum non-finite
            raise InputError(f"frame {self.frame_index_}: NaN or infinite cell value")
        return x

    def _no_contacts(self, load: np.ndarray) -> FrameContacts:
        self.near_contact_ = None
        self.tracks_.nothing_seen()
        grid = self.grid_
        return FrameContacts(self.frame_index_, NO_IDS, NONE, NONE, NONE, NONE, NONE, grid.background,
                             (grid.rows, grid.cols, grid.pitch_mm), load)

    def _force(self, contacts: FrameContacts, detections: Detections) -> np.ndarray:
        """Force per contact from the force model: one call per frame, one row per contact."""
        if self.force_feature == "window":
            feature = np.concatenate((detections.load, PADDING))[detections.window]  # 0 outside the grid
            if detections.counted is not None:
                feature *= detections.counted
        elif self.force_feature == "sum":
            feature = detections.window_load.reshape(-1, 1)
        elif self.force_feature == "mean":
            feature = contacts.mean_load.reshape(-1, 1)
        else:
            feature = contacts.peak_load.reshape(-1, 1)
        predict = getattr(self.force_model, "predict", self.force_model)
        return np.asarray(predict(feature), dtype=np.float64).reshape(-1)
