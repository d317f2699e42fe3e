"""Association (our answer to the paper's sec. 2.5.2): which of this frame's detections is which
followed contact, as SORT (Bewley et al. 2016) associates: one score matrix, one assignment.

The paper matches each cluster to its most similar previous cluster (Jaccard), greedily. Here
one assignment over the whole matrix (scipy's linear_sum_assignment, Kuhn-Munkres) maximises
the total score: an overlap of Jaccard >= `min_jaccard` with the track's last cells scores
1 + Jaccard, in (1, 2]; a pair without enough overlap may still match by distance, scoring in
(0, 1] when the detection lies within `gate_mm` of the track's predicted centroid (a fast move)
or of its last one, whichever is nearer (a light touch's centroid jumps between crossings, and
its velocity estimate is then noise); 0 is no match.
"""
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from models.contact_tracking.detection import Detections


@dataclass(slots=True, eq=False)
class Association:
    detection_of: dict      # matched track index -> detection index
    track_of: dict          # the same pairs, detection index -> track index
    overlap: np.ndarray     # (tracks, detections): cells shared by each track's last cells and each detection

    def pair(self, track: int, detection: int) -> None:
        self.detection_of[track] = detection
        self.track_of[detection] = track

    def unpair(self, track: int) -> None:
        del self.track_of[self.detection_of.pop(track)]


def associate(tracks: list, detections: Detections, detection_cells: np.ndarray, min_jaccard: float,
              gate_mm: float) -> Association:
    """Match tracks (each with its last cells as a one-hot row, size, position and velocity in
    mm per frame, frames missing) to this frame's detections (detection_cells: their one-hot rows).

    When the overlap matches alone pair every track, or every detection, one to one (the usual
    frame), they are the assignment's unique optimum (each of those rows or columns holds one
    entry above 1, every other entry is at most 1), and the distances and the solver are skipped,
    as SORT skips its solver when the IoU matches are one to one."""
    overlap = np.array([t.cells for t in tracks]) @ detection_cells.T
    jaccard = overlap / (np.array([t.size for t in tracks])[:, None] + detections.n_cells - overlap)
    close = jaccard >= min_jaccard
    rows, cols = (index.tolist() for index in close.nonzero())
    one_to_one = len(set(rows)) == len(rows) and len(set(cols)) == len(cols)
    if not (one_to_one and len(rows) in close.shape):
        state = np.array([(t.x + t.vx * (t.missing + 1), t.y + t.vy * (t.missing + 1), t.x, t.y) for t in tracks])
        x, y = detections.xy_mm[:, 0], detections.xy_mm[:, 1]
        distance = np.minimum(np.hypot(state[:, 0:1] - x, state[:, 1:2] - y), np.hypot(state[:, 2:3] - x, state[:, 3:4] - y))
        score = np.where(close, jaccard + 1.0, np.maximum(1.0 - distance * (0.999 / gate_mm), 0.0))
        rows, cols = linear_sum_assignment(score, maximize=True)
        kept = (score[rows, cols] > 0).tolist()
        rows, cols = [t for t, keep in zip(rows.tolist(), kept) if keep], [d for d, keep in zip(cols.tolist(), kept) if keep]
    return Association(dict(zip(rows, cols)), dict(zip(cols, rows)), overlap)
