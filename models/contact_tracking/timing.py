"""Time the per-frame loop an application runs: `update` on each frame, the call alone
(perf_counter_ns around it), so that the study's in-run timing (metrics.json) and
bench/contacts.py measure the same thing."""
import time

import numpy as np

from models.contact_tracking.frame_contacts import FrameContacts


def timed_updates(tracker, frames) -> tuple[list[FrameContacts], np.ndarray]:
    """Each frame's contacts and the microseconds its `update` took."""
    clock, found = time.perf_counter_ns, []
    elapsed = np.empty(len(frames))
    for i, frame in enumerate(frames):
        start = clock()
        contacts = tracker.update(frame)
        elapsed[i] = clock() - start
        found.append(contacts)
    return found, elapsed / 1e3


def latency_summary(elapsed_us: np.ndarray) -> dict:
    """p50 and p99 per frame (us) and the frame count; NaN without a frame."""
    p50, p99 = np.percentile(elapsed_us, [50, 99]) if len(elapsed_us) else (np.nan, np.nan)
    return {"p50_us": float(p50), "p99_us": float(p99), "frames": int(len(elapsed_us))}
