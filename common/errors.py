"""Errors that mean "the user's input is wrong", as opposed to a bug.

train.py (and later predict.py) turns these into one line on stderr and exit code 2;
anything else keeps its traceback because it is ours to fix.
"""


class InputError(ValueError):
    """Bad data, bad config value or bad file: the message names the culprit and what was expected."""
