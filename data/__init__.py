"""Data side of Touchstone: simulated scenes, users' tables, features and the shared datamodule.

Nothing in this package imports `models/`: data flows train.py -> data -> models -> export.
"""
