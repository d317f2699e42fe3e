"""The seed's own segmentation and cluster tracking (seed 001's public capsensor-monitor code,
src/processor.py and src/processor_utils.py), kept as the reference the tracker's `segmentation:
paper` and `tracking: paper` modes run and ours is compared against.

Segmentation: cells below threshold set to 0 and the rest kept as raw values, the frame min-max
scaled, skimage's threshold_otsu (256 bins) over the whole frame (zeros included), skimage's
label. The raw values carry the rest offset (~1,200 counts), so Otsu mostly separates the zeroed
cells from the rest and the threshold decides alone; two contacts whose above-threshold halos
touch are one cluster.

Tracking, Algorithm 1: each cluster takes the label of its most similar previous cluster
(Jaccard; greedy, first maximum), new clusters count up from the largest label, then all
clusters are renumbered 1..n. Any contact that disappears renumbers the others: an identity
switch by design.
"""
import math

import numpy as np

from models.contact_tracking.detection import Detections
from models.contact_tracking.grid import Grid


def segment_paper(x: np.ndarray, above: np.ndarray, load: np.ndarray, grid: Grid, connectivity: int):
    """The public code's processor.process: raw values kept above threshold, min-max scaled over
    the frame (sklearn MinMaxScaler: a constant frame scales to 0), skimage's Otsu, `>=`,
    skimage's label (connectivity None = 8). Returns (cluster cells, their cluster numbers 1..n,
    each cluster's largest-load cell), or None without a cluster."""
    from skimage.filters import threshold_otsu
    from skimage.measure import label
    filtered = np.where(above, x, 0.0)
    low, high = filtered.min(), filtered.max()
    scaled = (filtered - low) / (high - low) if high > low else np.zeros_like(filtered)
    otsu = threshold_otsu(scaled)
    if math.isclose(otsu, 0):
        return None
    binary = (scaled >= otsu).reshape(grid.rows, grid.cols)
    labels = label(binary, background=0, connectivity=None if connectivity == 8 else 1).reshape(-1)
    n = int(labels.max())
    if n == 0:
        return None
    cells = labels.nonzero()[0]
    number = labels[cells]
    on_cluster = np.full((n, grid.n_cells), -np.inf)
    on_cluster[number - 1, cells] = load[cells]
    return cells, number, on_cluster.argmax(axis=1)


def track_clusters(prev_ids, prev_cells, next_ids, next_cells):
    """The public code's track_clusters (capsensor-monitor src/processor_utils.py), same
    decisions, Jaccard vectorised. prev_cells/next_cells: one-hot (clusters x cells) bool.
    next_ids are the connected-component labels. Returns the renumbered ids 1..n."""
    if len(prev_ids) == 0 or len(next_ids) == 0:
        return np.asarray(next_ids, dtype=np.int64)
    inter = next_cells.astype(np.float32) @ prev_cells.T.astype(np.float32)
    union = next_cells.sum(1)[:, None] + prev_cells.sum(1)[None, :] - inter
    jaccard = np.where(inter > 0, inter / np.maximum(union, 1), 0.0)
    max_label = int(np.max(next_ids))
    assigned = []
    labels = []
    for row in jaccard:
        best = int(np.argmax(row))
        if math.isclose(row[best], 0):
            label = max_label
            max_label += 1
        else:
            label = int(prev_ids[best])
        if label in assigned:
            label += 1
            max_label = max(label, max_label)
        assigned.append(label)
        labels.append(label)
    order = sorted(range(len(labels)), key=lambda i: labels[i])  # stable, as list.sort
    renumbered = np.empty(len(labels), dtype=np.int64)
    renumbered[order] = np.arange(1, len(labels) + 1)
    return renumbered


class PaperClusters:
    """Last frame's clusters, labelled as the public code labels them (the tracker's `tracking:
    paper`); the same two calls as tracks.Tracks."""

    def __init__(self, n_cells: int):
        self.ids = np.zeros(0, dtype=np.int64)
        self.cells = np.zeros((0, n_cells), dtype=bool)

    def update(self, detections: Detections, frame: int) -> np.ndarray:
        cells = detections.one_hot() > 0
        self.ids = track_clusters(self.ids, self.cells, np.arange(1, detections.n + 1), cells)
        self.cells = cells
        return self.ids

    def nothing_seen(self) -> None:
        self.ids, self.cells = self.ids[:0], self.cells[:0]
