"""Track lifecycle (ours): contacts followed over frames, and the rules that carry their ids
through what the paper's Algorithm 1 renumbers. Each frame, as SORT's update (Bewley et al.
2016), with merges and splits between association and update:

1. associate (association.py);
2. merge: a fresh track left without a detection that a matched detection has taken in (most of
   its cells in the region, or some of them with its predicted centroid within a pitch of the
   region's, or none but still pressed where the steepest ascent runs into the region: a light
   touch that lost its peak to a firmer neighbour's flank) is remembered inside that region; the
   older id survives;
3. split: an unmatched detection lying mostly inside a matched track's last cells is its child,
   or one within the gate of where a contact merged into a matched track would be now; the
   larger child (by load) keeps the id, unless the region remembers contacts, then children and
   remembered contacts are matched by predicted position;
4. update matched tracks (a merged region is reported at its own member's k-means cluster);
   age the others and retire those unseen for more than `max_missing_frames` frames (a
   one-frame dropout keeps its id); new ids for what is left.
"""
import collections
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from models.contact_tracking.association import Association, associate
from models.contact_tracking.detection import Detections
from models.contact_tracking.grid import Grid

SETTLE_FRAMES, SETTLE_MM = 10, 2.0  # merged members that moved less than this over these frames are one contact
HISTORY_FRAMES = 10  # centroids kept per track for the velocity a merge remembers (1/6 s at 60 frames/s)
AHEAD_FRAMES = 30    # a remembered contact is carried on from where it merged for at most this (1/2 s)
MAX, MIN = np.maximum.reduce, np.minimum.reduce


@dataclass(frozen=True, slots=True)
class Member:
    """A contact merged into another's region, as it was at the merge."""
    id: int
    birth: int
    x: float
    y: float
    vx: float
    vy: float
    frame: int


@dataclass(slots=True, eq=False)
class Track:
    """A contact followed over frames. Position in mm, velocity in mm per frame (an exponential
    average, weight 0.3 on the newest step: a light touch's centroid jumps between crossings,
    which must not read as motion) for the gate's prediction."""
    id: int
    birth: int
    cells: np.ndarray        # one-hot row (float32) of its cells when last seen
    size: float              # their count
    x: float
    y: float
    path: collections.deque  # its last HISTORY_FRAMES (frame, x, y): the velocity a merge remembers
    vx: float = 0.0
    vy: float = 0.0
    missing: int = 0
    members: list = field(default_factory=list)  # contacts merged into it, itself first; empty: none
    member_xy: np.ndarray | None = None  # while merged: each member's position in the region, members' order
    member_path: collections.deque | None = None  # ... over the last SETTLE_FRAMES frames; None: settled
    member_still: int = 0    # frames in a row the members have been still


def new_track(track_id: int, frame: int, cells: np.ndarray, x: float, y: float, size: float) -> Track:
    return Track(track_id, frame, cells, float(size), float(x), float(y),
                 collections.deque([(frame, float(x), float(y))], maxlen=HISTORY_FRAMES))


def remember(track: Track, frame: int) -> Member:
    """The track as a merge remembers it. The velocity is the least-squares slope of the
    centroid over the last HISTORY_FRAMES frames, not the running average the gate uses: two
    contacts about to merge pull each other's centroids sideways for the last few frames, and
    the remembered velocity has to carry a contact through the whole merge (up to 30 frames) to
    give it its id back at the split."""
    vx, vy = track.vx, track.vy
    if len(track.path) >= 3:
        t, x, y = zip(*track.path)
        t_mean, x_mean, y_mean = sum(t) / len(t), sum(x) / len(x), sum(y) / len(y)
        spread = sum((a - t_mean) ** 2 for a in t)
        vx = sum((a - t_mean) * (b - x_mean) for a, b in zip(t, x)) / spread
        vy = sum((a - t_mean) * (b - y_mean) for a, b in zip(t, y)) / spread
    return Member(track.id, track.birth, track.x, track.y, vx, vy, frame)


def merge(host: Track, guest: Track, frame: int) -> None:
    """The guest's contact (and those merged into it) remembered inside the host's region."""
    if not host.members:
        host.members.append(remember(host, frame))
    host.members.append(remember(guest, frame))
    host.members.extend(guest.members[1:])
    restart_members(host)


def restart_members(track: Track) -> None:
    track.member_xy, track.member_path, track.member_still = None, collections.deque(maxlen=SETTLE_FRAMES), 0


def follow(track: Track, cells: np.ndarray, size: float, x: float, y: float, frame: int) -> None:
    """A track found again: its cells (one-hot row), their count and its centroid."""
    steps = track.missing + 1
    track.vx = 0.7 * track.vx + 0.3 * (x - track.x) / steps
    track.vy = 0.7 * track.vy + 0.3 * (y - track.y) / steps
    track.x, track.y, track.cells, track.size, track.missing = x, y, cells, float(size), 0
    track.path.append((frame, x, y))


def predicted_members(members: list, frame: int, size_mm) -> np.ndarray:
    """(members, 2): where each merged contact would be now, carried on from its position and
    velocity when it merged for at most AHEAD_FRAMES frames, never off the sensor."""
    ahead = np.array([min(frame - m.frame, AHEAD_FRAMES) for m in members], dtype=np.float64)
    predicted = np.array([(m.x, m.y) for m in members]) + np.array([(m.vx, m.vy) for m in members]) * ahead[:, None]
    return np.clip(predicted, 0.0, size_mm)


def place_members(track: Track, detections: Detections, d: int, grid: Grid) -> None:
    """Where each member of a merged region is: a few Lloyd iterations of k-means (Lloyd 1982),
    k = the region's members, on the region's cells and their neighbours above threshold,
    weighted by load, started from each member's position last frame (at the merge: where it
    was). Two touches that one region covers pull a cluster each, so the region is reported
    with the older id (the merge rule) at the older member's cluster (written into the
    detection's centroid) rather than at the region's own centroid, which sits on the firmer
    touch and wanders between them, carrying the older id from one true contact to the other.
    The split still matches children by the motion each member had when it merged
    (split_by_memory): two touches passing straight through each other leave one round region,
    whose k-means halves say nothing about who is who. Members that have all moved less than
    SETTLE_MM over the last SETTLE_FRAMES frames are a merge that stays (two touches pressed
    into one, the k-means only halving it): the region is then reported at its own centroid;
    still for three times as long, the merge is settled until the region splits (no k-means on
    it any more: a merge that stays costs nothing per frame)."""
    if track.member_path is None:  # settled: one touch until the region splits
        return
    cells = np.unique(grid.neighbourhood[:, detections.cells[detections.number == d + 1]])
    weight = detections.above_load[cells]
    cells, weight = cells[weight > 0], weight[weight > 0]
    if track.member_xy is None or len(track.member_xy) != len(track.members):
        track.member_xy = np.array([(m.x, m.y) for m in track.members])
    centres = track.member_xy
    if len(cells) < len(centres):  # too few cells to place every member: the region's centroid
        return
    xy = grid.cell_xy_mm[cells]
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
        track.member_still += 1
        if track.member_still >= 2 * SETTLE_FRAMES:
            track.member_path = None
        return
    track.member_still = 0
    own = [m.id for m in track.members].index(track.id)
    if total[own] > 0:
        detections.xy_mm[d] = centres[own]


def split_by_memory(parent: Track, kids: list, detections: Detections, frame: int, size_mm) -> dict:
    """Children of a region that remembers merged contacts get those contacts back by position:
    each remembered contact predicted from its velocity when it merged, matched to the children
    by one assignment on distance; the region's own id is always placed. Returns child
    detection -> Member."""
    predicted = predicted_members(parent.members, frame, size_mm)
    cost = np.linalg.norm(predicted[:, None, :] - detections.xy_mm[kids][None, :, :], axis=2)
    own = next(i for i, m in enumerate(parent.members) if m.id == parent.id)
    cost[own] -= 1e6  # with more remembered contacts than children, the region's own id still gets one
    rows, cols = linear_sum_assignment(cost)
    return {kids[c]: parent.members[r] for r, c in zip(rows, cols)}


class Tracks:
    """The contacts followed so far and the rules that carry their ids (the tracker's `tracking:
    global`); the same two calls as paper.PaperClusters."""

    def __init__(self, grid: Grid, min_jaccard: float, gate_mm: float, max_missing_frames: int):
        self.grid, self.min_jaccard, self.gate_mm, self.max_missing_frames = grid, min_jaccard, gate_mm, max_missing_frames
        self.live: list[Track] = []
        self.next_id = 1
        self.last_load = None  # the load of the last frame with detections: what a lost track's cells carried

    def update(self, detections: Detections, frame: int) -> np.ndarray:
        """This frame's ids, one per detection."""
        ids = np.zeros(detections.n, dtype=np.int64)
        cells = detections.one_hot()
        if self.live:
            match = associate(self.live, detections, cells, self.min_jaccard, self.gate_mm)
            merged = self._merge_lost(match, detections, frame)
            reinstated = self._split(match, detections, cells, frame, ids)
            self._update_matched(match, merged, reinstated, detections, cells, frame, ids)
        for d in np.flatnonzero(ids == 0).tolist():
            self.live.append(new_track(self.next_id, frame, cells[d], *detections.xy_mm[d], detections.n_cells[d]))
            ids[d] = self.next_id
            self.next_id += 1
        self.last_load = detections.load
        return ids

    def nothing_seen(self) -> None:
        self._age(self.live)

    def _age(self, unseen: list) -> None:
        for track in unseen:
            track.missing += 1
        if unseen:
            self.live = [t for t in self.live if t.missing <= self.max_missing_frames]

    def _merge_lost(self, match: Association, detections: Detections, frame: int) -> set:
        """Step 2; returns the merged (younger) tracks' indices."""
        merged = set()
        for t, track in enumerate(self.live):
            if t in match.detection_of or t in merged or track.missing:
                continue
            d = self._taken_in_by(track, match.overlap[t], match, detections)
            if d is None:
                continue
            m = match.track_of[d]
            older, younger = sorted((t, m), key=lambda i: (self.live[i].birth, self.live[i].id))
            merge(self.live[older], self.live[younger], frame)
            merged.add(younger)
            match.detection_of.pop(m, None)
            match.pair(older, d)
        return merged

    def _taken_in_by(self, track: Track, overlap: np.ndarray, match: Association, detections: Detections):
        """The matched detection whose region has taken in a lost track, or None: the one holding
        most of its cells, or some of them with its predicted centroid within a pitch (an Otsu
        core shrinks as two contacts join), or none of them (absorbed_by)."""
        d = int(np.argmax(overlap))
        if overlap[d] <= 0:
            return self._absorbed_by(track, match, detections)
        if d not in match.track_of:
            return None
        x, y = detections.xy_mm[d].tolist()
        if overlap[d] < 0.5 * track.size and math.hypot(track.x + track.vx - x, track.y + track.vy - y) > self.grid.pitch_mm:
            return None
        return d

    def _absorbed_by(self, track: Track, match: Association, detections: Detections):
        """The matched detection that has absorbed a lost track, or None. Absorbed: the track's
        last cells still carry their load (at least 60 % of last frame's peak there: a touch that
        lifts sheds it) and the steepest ascent over this frame's loads above threshold (rows and
        columns, as the segmentation climbs) from its highest cell ends on that detection's peak:
        the touch has no peak of its own any more, its load runs up a firmer neighbour's flank."""
        cells = np.flatnonzero(track.cells)
        if self.last_load is None or MAX(detections.load[cells]) < 0.6 * MAX(self.last_load[cells]):
            return None
        above = detections.above_load
        cell = int(cells[np.argmax(above[cells])])
        for _ in range(self.grid.n_cells):
            window = self.grid.plus[cell]
            up = int(window[np.argmax(above[window])])
            if above[up] <= above[cell]:
                break
            cell = up
        d = int(detections.labels[cell]) - 1
        return d if d in match.track_of else None

    def _split(self, match: Association, detections: Detections, cells: np.ndarray, frame: int, ids) -> list:
        """Step 3; returns the tracks reinstated from memory (their ids written into `ids`)."""
        reinstated = []
        for t, kids in self._children(match, detections, frame).items():
            parent = self.live[t]
            match.unpair(t)
            if not parent.members:  # the larger child (by load: force, not cell count) keeps the id
                match.pair(t, max(kids, key=lambda d: (detections.window_load[d], -d)))
                continue
            back = set()
            for d, member in split_by_memory(parent, kids, detections, frame, self.grid.size_mm).items():
                if member.id == parent.id:
                    match.pair(t, d)
                    continue
                track = new_track(member.id, frame, cells[d], *detections.xy_mm[d], detections.n_cells[d])
                track.birth, track.vx, track.vy = member.birth, member.vx, member.vy
                reinstated.append(track)
                ids[d] = track.id
                back.add(member.id)
            parent.members = [m for m in parent.members if m.id not in back]
            if len(parent.members) == 1:  # only itself left: nothing merged any more
                parent.members = []
            restart_members(parent)
        return reinstated

    def _children(self, match: Association, detections: Detections, frame: int) -> dict:
        """Matched track -> its detection and the unmatched detections that split off it."""
        unmatched = [d for d in range(detections.n) if d not in match.track_of]
        if not unmatched:
            return {}
        matched = np.zeros(len(self.live))
        matched[list(match.detection_of)] = 1.0
        hosts = None  # (track, its remembered members' predicted positions), built when first needed
        children = {}
        for d in unmatched:
            overlapping = match.overlap[:, d] * matched
            t = int(np.argmax(overlapping))
            if overlapping[t] < 0.5 * detections.n_cells[d]:
                if hosts is None:
                    hosts = [(h, predicted_members(self.live[h].members, frame, self.grid.size_mm))
                             for h in match.detection_of if self.live[h].members]
                near = [(MIN(np.hypot(*(p - detections.xy_mm[d]).T)), h) for h, p in hosts]
                t = min(near)[1] if near and min(near)[0] <= self.gate_mm else None
            if t is not None:
                children.setdefault(t, [match.detection_of[t]]).append(d)
        return children

    def _update_matched(self, match: Association, merged: set, reinstated: list, detections: Detections,
                        cells: np.ndarray, frame: int, ids) -> None:
        """Step 4 for the tracks there were: follow the matched, age the others."""
        survivors, unseen = [], []
        xy, sizes = detections.xy_mm.tolist(), detections.n_cells.tolist()  # before place_members moves a centroid
        for t, track in enumerate(self.live):
            if t in merged:
                continue
            survivors.append(track)
            d = match.detection_of.get(t)
            if d is None:
                unseen.append(track)
                continue
            follow(track, cells[d], sizes[d], *xy[d], frame)
            if track.members:
                place_members(track, detections, d, self.grid)
            ids[d] = track.id
        self.live = survivors + reinstated
        self._age(unseen)
