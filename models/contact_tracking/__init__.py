"""Contacts with stable ids on a capacitive array (seed 001), one file per step of the paper's
pipeline: baseline.py (rest mean, spread, threshold), detection.py (segmentation and centroids;
otsu_threshold.py), association.py (detections to tracks), tracks.py (track lifecycle: merges,
splits, retirement), paper.py (the seed's own segmentation and tracking, the reference), and
tracker.py, the estimator that composes them. frame_contacts.py is what it returns per frame;
force.py turns a fitted force pipeline into the per-frame force function; timing.py times the
per-frame loop (the study and bench/contacts.py share it)."""
from models.contact_tracking.frame_contacts import FrameContacts
from models.contact_tracking.tracker import ContactTracker

__all__ = ["ContactTracker", "FrameContacts"]
