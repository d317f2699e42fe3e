"""Data side of Touchstone: simulated scenes (scenes/), the physics they build on (physics/),
users' tables and recordings, features, splits, windows and the datamodules.

Nothing in this package imports `models/` or `export/`: data flows train.py -> data -> models -> export.
"""
