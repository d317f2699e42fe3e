"""The seed's own cluster tracking (seed 001, its public capsensor-monitor code), kept as the
reference `tracking: paper` mode of the contact tracker (models/contact_tracker.py) is compared
against: greedy Jaccard matching to the last frame's clusters, then renumbering 1..n.
"""
import math

import numpy as np


def paper_track_clusters(prev_ids, prev_cells, next_ids, next_cells):
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
