"""A rig stand-in: how a calibration is judged without a real rig (tests, bench/calibrate.py).

The stand-in is the scene with its identifiable parameters hidden: each moved from the scene's
value by a factor drawn uniformly in [1 - spread, 1 + spread] (40 %: a rig built to the paper's
recipe by another lab), kept inside its physical range, and every listed effect kept, including
those the fit leaves out (rubber12's temperature drift, the skin's per-cell fabrication gains
and drift, the taxels' noise): the fit never sees a rig its own model could reproduce exactly.
Its presses come from the scene's own learning protocol: rubber12 and taxels at random positions
and loads, the capacitive skin's robot at every cell and force level.
"""
import copy
import math

import numpy as np

from data.calibration.identifiable import calibration_for, get_value, set_value

SPREAD = 0.4


def hidden_parameters(scene, rng: np.random.Generator, spread: float = SPREAD) -> dict:
    """{path: value}: each declared parameter moved by up to +-spread, inside its range."""
    hidden = {}
    for p in calibration_for(scene).parameters:
        value = get_value(scene, p.path) * rng.uniform(1.0 - spread, 1.0 + spread)
        hidden[p.path] = float(np.clip(value, p.low, p.high))
    return hidden


def standin_scene(scene, hidden: dict, seed: int, n_presses: int):
    """The scene with the hidden values, set to press `n_presses` times by its learning protocol."""
    rig = copy.deepcopy(scene)
    for path, value in hidden.items():
        set_value(rig, path, value)
    rig.seed, rig.progress = int(seed), False
    if rig.name == "capacitive6x6":
        rig.protocol, rig.press_cells = "characterisation", "all"
        per_repetition = rig.rows * rig.cols * len(rig.force_levels_n)
        rig.n_repetitions = max(1, math.ceil(n_presses / per_repetition))
    else:
        rig.protocol = "random" if rig.name == "rubber12" else "random_loads"
        rig.n_samples = int(n_presses)
    return rig


def rig_presses(scene, hidden: dict, seed: int, n_presses: int):
    """`n_presses` presses of the stand-in rig as a frame (channels and targets), in random order."""
    calibration = calibration_for(scene)
    table = standin_scene(scene, hidden, seed, n_presses).generate()
    frame = table.frame[list(table.channel_columns) + list(calibration.inputs) + list(calibration.outputs)]
    order = np.random.default_rng(seed).permutation(len(frame))[:n_presses]
    return frame.iloc[order].reset_index(drop=True)
