"""Multi-touch sessions: who touches where, when and how hard (seed 001's live tests, sec. 3.6:
taps, holds, glides, and contacts that cross, merge and split).

Sessions are sensor-independent: positions in mm on a width x height patch, forces in N, contact
radii in mm, one row per frame and contact (TRUTH_COLUMNS of data/readers/contact_streams.py). A scene
turns them into frames (data/scenes/capacitive6x6.py, protocol `stream`).
"""
from dataclasses import dataclass

import numpy as np
import pandas as pd

from common.errors import InputError
from data.readers.contact_streams import TRUTH_COLUMNS

SESSIONS = ("tap", "hold", "glide", "cross", "merge", "split")


@dataclass
class Choreography:
    """What the sessions may use: the patch, the frame rate and the ranges to draw from."""
    width_mm: float
    height_mm: float
    margin_mm: float
    frame_rate_hz: float
    max_contacts: int = 5
    force_range_n: tuple = (0.3, 3.0)
    radius_range_mm: tuple = (3.0, 5.0)
    speed_range_mm_s: tuple = (15.0, 40.0)
    min_separation_mm: float = 20.0
    ramp_s: float = 0.07          # a finger lands and lifts over ~4 frames at 60 Hz

    def n_frames(self, seconds: float) -> int:
        return max(1, int(round(seconds * self.frame_rate_hz)))


def _track(start, x, y, force, radius, ramp_in=0, ramp_out=0):
    """One contact over consecutive frames from `start` (session-local); force ramps in/out."""
    n = len(x)
    force = np.broadcast_to(np.asarray(force, dtype=float), (n,)).copy()
    envelope = np.ones(n)
    if ramp_in:
        k = min(ramp_in, n)
        envelope[:k] = np.minimum(envelope[:k], np.arange(1, k + 1) / (ramp_in + 1))
    if ramp_out:
        k = min(ramp_out, n)
        envelope[n - k:] = np.minimum(envelope[n - k:], np.arange(k, 0, -1) / (ramp_out + 1))
    return {"frame": start + np.arange(n), "x_mm": np.asarray(x, dtype=float) * np.ones(n),
            "y_mm": np.asarray(y, dtype=float) * np.ones(n), "force_n": force * envelope,
            "radius_mm": np.broadcast_to(np.asarray(radius, dtype=float), (n,)).copy()}


def _spread_points(rng, k, c: Choreography):
    """Up to k points inside the margins, pairwise at least min_separation_mm apart (rejection
    sampling; fewer points when the patch cannot hold k)."""
    points = []
    for _ in range(400):
        if len(points) == k:
            break
        p = rng.uniform([c.margin_mm, c.margin_mm], [c.width_mm - c.margin_mm, c.height_mm - c.margin_mm])
        if all(np.hypot(*(p - q)) >= c.min_separation_mm for q in points):
            points.append(p)
    return np.array(points).reshape(-1, 2)


def _force(rng, c, size=None):
    return rng.uniform(*c.force_range_n, size)


def _radius(rng, c, size=None):
    return rng.uniform(*c.radius_range_mm, size)


def session_tap(rng, n_frames, c: Choreography):
    """Waves of 1..max_contacts short taps (0.15-0.35 s) at separated points, every 0.6 s."""
    tracks, ramp, wave = [], c.n_frames(c.ramp_s), c.n_frames(0.6)
    for start in range(0, n_frames - c.n_frames(0.2), wave):
        points = _spread_points(rng, int(rng.integers(1, c.max_contacts + 1)), c)
        for x, y in points:
            begin = start + int(rng.integers(0, c.n_frames(0.1) + 1))
            length = min(c.n_frames(rng.uniform(0.15, 0.35)), n_frames - begin)
            if length >= 2:
                tracks.append(_track(begin, np.full(length, x), np.full(length, y), _force(rng, c),
                                     _radius(rng, c), ramp, ramp))
    return tracks


def session_hold(rng, n_frames, c: Choreography):
    """1..max_contacts contacts held for the whole session, each force swaying +/- 15 %."""
    tracks, ramp = [], c.n_frames(c.ramp_s)
    begin, end = c.n_frames(0.1), n_frames - c.n_frames(0.1)
    t = np.arange(end - begin) / c.frame_rate_hz
    for x, y in _spread_points(rng, int(rng.integers(1, c.max_contacts + 1)), c):
        sway = 1.0 + 0.15 * np.sin(2 * np.pi * t / rng.uniform(1.0, 2.0) + rng.uniform(0, 2 * np.pi))
        tracks.append(_track(begin, np.full(len(t), x), np.full(len(t), y), _force(rng, c) * sway,
                             _radius(rng, c), ramp, ramp))
    return tracks


def _lanes(rng, k, low, high, separation):
    """k distinct lane coordinates in [low, high], at least `separation` apart (fewer if needed)."""
    slots = np.arange(low, high + 1e-9, separation)
    return np.sort(rng.choice(slots, size=min(k, len(slots)), replace=False))


def session_glide(rng, n_frames, c: Choreography):
    """1..3 contacts gliding across the patch along separate horizontal lanes, staggered."""
    tracks, ramp = [], c.n_frames(c.ramp_s)
    k = int(rng.integers(1, min(3, c.max_contacts) + 1))
    span = c.width_mm - 2 * c.margin_mm
    for y in _lanes(rng, k, c.margin_mm, c.height_mm - c.margin_mm, c.min_separation_mm):
        speed = rng.uniform(*c.speed_range_mm_s)
        length = min(c.n_frames(span / speed), n_frames - c.n_frames(0.2))
        begin = int(rng.integers(c.n_frames(0.05), max(c.n_frames(0.05) + 1, n_frames - length)))
        length = min(length, n_frames - begin)
        x = c.margin_mm + np.linspace(0.0, span, length)
        if rng.random() < 0.5:
            x = x[::-1]
        tracks.append(_track(begin, x, np.full(length, y), _force(rng, c), _radius(rng, c), ramp, ramp))
    return tracks


def session_cross(rng, n_frames, c: Choreography):
    """Two contacts on crossing paths (one along x, one along y through the patch's centre) that
    pass the crossing point a moment apart: at their closest they are 0.5-0.75 min_separation_mm
    apart (one to one and a half pitches on the default skin), near but not merged."""
    ramp = c.n_frames(c.ramp_s)
    speed = rng.uniform(*c.speed_range_mm_s)
    xc, yc = c.width_mm / 2, c.height_mm / 2
    closest = rng.uniform(0.5, 0.75) * c.min_separation_mm
    delay_s = np.sqrt(2.0) * closest / speed   # |t_a - t_b| v / sqrt(2) = closest distance
    t_mid = n_frames / c.frame_rate_hz / 2
    tracks = []
    for axis, t_pass in ((0, t_mid - delay_s / 2), (1, t_mid + delay_s / 2)):
        half = (c.width_mm if axis == 0 else c.height_mm) / 2 - c.margin_mm
        begin = max(0, int(round((t_pass - half / speed) * c.frame_rate_hz)))
        end = min(n_frames, int(round((t_pass + half / speed) * c.frame_rate_hz)))
        t = np.arange(begin, end) / c.frame_rate_hz
        along = np.clip(speed * (t - t_pass), -half, half)
        x, y = (xc + along, np.full(len(t), yc)) if axis == 0 else (np.full(len(t), xc), yc + along)
        tracks.append(_track(begin, x, y, _force(rng, c), _radius(rng, c), ramp, ramp))
    return tracks


def session_merge(rng, n_frames, c: Choreography):
    """Two contacts approach until their discs touch; the later one ends there and the earlier
    one (the older id) carries on as one contact with both forces and the joint area."""
    ramp = c.n_frames(c.ramp_s)
    speed = rng.uniform(*c.speed_range_mm_s)
    yc, xc = c.height_mm / 2, c.width_mm / 2
    gap = min(c.width_mm - 2 * c.margin_mm, rng.uniform(1.5, 2.0) * c.min_separation_mm)
    (fa, fb), (ra, rb) = _force(rng, c, 2), _radius(rng, c, 2)
    a_start, b_start = 0, c.n_frames(0.1)
    meet = b_start + c.n_frames(max(gap / 2 - (ra + rb) / 2, 0.0) / speed)
    hold = max(n_frames - meet - c.n_frames(0.1), 2)
    t = np.arange(meet) / c.frame_rate_hz
    xa = np.clip(xc - gap / 2 + speed * (t - b_start / c.frame_rate_hz).clip(0), None, xc - (ra + rb) / 2)
    xb = np.clip(xc + gap / 2 - speed * (t[b_start:] - b_start / c.frame_rate_hz), xc + (ra + rb) / 2, None)
    a_before = _track(a_start, xa, np.full(len(xa), yc), fa, ra, ramp, 0)
    a_after = _track(meet, np.full(hold, xc), np.full(hold, yc), fa + fb, np.hypot(ra, rb), 0, ramp)
    b = _track(b_start, xb, np.full(len(xb), yc), fb, rb, ramp, 0)
    a = {k: np.concatenate([a_before[k], a_after[k]]) for k in a_before}
    return [a, b]


def session_split(rng, n_frames, c: Choreography):
    """One wide contact holds, then splits in two that move apart: the larger child (60 % of the
    force) keeps the id, the smaller one is a new contact."""
    ramp = c.n_frames(c.ramp_s)
    speed = rng.uniform(*c.speed_range_mm_s)
    yc, xc = c.height_mm / 2, c.width_mm / 2
    force, radius = _force(rng, c), _radius(rng, c)
    split_at = c.n_frames(0.6)
    travel = min(c.width_mm / 2 - c.margin_mm, 0.75 * c.min_separation_mm)
    after = max(n_frames - split_at - c.n_frames(0.1), 2)
    t = np.arange(after) / c.frame_rate_hz
    offset = np.minimum(speed * t, travel)
    parent = _track(0, np.full(split_at, xc), np.full(split_at, yc), force, radius * np.sqrt(2), ramp, 0)
    larger = _track(split_at, xc - offset, np.full(after, yc), 0.6 * force, radius, 0, ramp)
    smaller = _track(split_at, xc + offset, np.full(after, yc), 0.4 * force, radius, 0, ramp)
    a = {k: np.concatenate([parent[k], larger[k]]) for k in parent}
    return [a, smaller]


SESSION_BUILDERS = {"tap": session_tap, "hold": session_hold, "glide": session_glide,
                    "cross": session_cross, "merge": session_merge, "split": session_split}


def choreograph(sessions, rng, c: Choreography, n_rest_frames: int, session_s: float, gap_s: float):
    """Ground truth for a stream: rest frames, then each session followed by a gap without
    contact. Returns (truth DataFrame with TRUTH_COLUMNS, total frame count). Contact ids are
    unique over the stream, numbered in order of appearance."""
    unknown = [s for s in sessions if s not in SESSION_BUILDERS]
    if unknown:
        raise InputError(f"stream: unknown session '{unknown[0]}'; valid: {', '.join(SESSIONS)}")
    parts, start, next_id = [], n_rest_frames, 0
    n_session, n_gap = c.n_frames(session_s), c.n_frames(gap_s)
    for name in sessions:
        tracks = SESSION_BUILDERS[name](rng, n_session, c)
        for track in sorted(tracks, key=lambda tr: int(tr["frame"][0])):
            part = pd.DataFrame(track)
            part["frame"] += start
            part["contact_id"] = next_id
            part["session"] = name
            parts.append(part[part["force_n"] > 0])
            next_id += 1
        start += n_session + n_gap
    truth = pd.concat(parts, ignore_index=True) if parts else pd.DataFrame(columns=TRUTH_COLUMNS)
    truth = truth[TRUTH_COLUMNS].sort_values(["frame", "contact_id"], kind="stable").reset_index(drop=True)
    truth["frame"] = truth["frame"].astype(np.int64)
    truth["contact_id"] = truth["contact_id"].astype(np.int64)
    return truth, start
