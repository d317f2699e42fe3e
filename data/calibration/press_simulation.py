"""Presses simulated at given labels on any scene that can be calibrated: the forward model the
fit compares a rig's readings with, and the generator of the pretraining set.

Every scene simulates from its own inputs (rubber12: position and depth; taxels: position and
forces, which its simulate() takes in mN; capacitive6x6: a cell and an offset from its centre,
and a force); this module turns a table's target columns into them, so the fit and the
pretraining speak only of the table's columns.
"""
import copy

import numpy as np
import pandas as pd

from common.errors import InputError
from data.calibration.identifiable import calibration_for
from data.sensor_table import SensorTable

GRID_SHARE = 0.25   # a table with at most this share of distinct positions was pressed on a grid


def fit_model(scene):
    """A copy of the scene without the effects the fit does not model (identifiable.py), quiet."""
    model = copy.deepcopy(scene)
    dropped = calibration_for(scene).unmodelled
    model.effects = {name: params for name, params in (scene.effects or {}).items() if name not in dropped}
    model.progress = False
    return model


def _capacitive_presses(scene, labels: pd.DataFrame):
    """Each press's cell (row, col) and its offset (x, y) from that cell's centre, in mm."""
    x, y = labels["x_mm"].to_numpy(float), labels["y_mm"].to_numpy(float)
    row = np.clip(np.rint(y / scene.pitch_mm - 0.5).astype(np.int64), 0, scene.rows - 1)
    col = np.clip(np.rint(x / scene.pitch_mm - 0.5).astype(np.int64), 0, scene.cols - 1)
    offsets = np.column_stack([x - (col + 0.5) * scene.pitch_mm, y - (row + 0.5) * scene.pitch_mm])
    return np.column_stack([row, col]), offsets


def simulate_at(scene, labels: pd.DataFrame) -> SensorTable:
    """The scene's table for presses at `labels` (a frame holding the scene's input targets);
    the input targets are the labels themselves (a scene's sensed force would add its own noise)."""
    calibration = calibration_for(scene)
    missing = [c for c in calibration.inputs if c not in labels.columns]
    if missing:
        raise InputError(f"scene {scene.name}: presses need target column(s) {', '.join(missing)}")
    column = {name: labels[name].to_numpy(float) for name in calibration.inputs}
    if scene.name == "rubber12":
        table = scene.simulate(column["x_mm"], column["y_mm"], column["depth_mm"])
    elif scene.name == "taxels":
        table = scene.simulate(column["x_mm"], column["y_mm"], 1e3 * column["normal_n"],
                               1e3 * column["shear_x_n"], 1e3 * column["shear_y_n"])
    else:
        if scene.characterisation_channels != "cells":
            raise InputError("scene capacitive6x6: calibration reads every cell (characterisation_channels=cells)")
        cells, offsets = _capacitive_presses(scene, labels)
        table = scene.simulate(np.arange(len(labels)), cells, column["force_n"], offsets_mm=offsets)
    for name in calibration.inputs:
        table.frame[name] = column[name]
    return table


def channel_names(scene) -> list[str]:
    """The channels a scene reads, in its order: from one simulated press at rest-like labels."""
    calibration = calibration_for(scene)
    probe = {name: [1.0] for name in calibration.inputs}   # a press of some force: a sensed 0 N can read < 0
    if scene.name == "rubber12":
        probe.update(x_mm=[scene.side_mm / 2], y_mm=[scene.side_mm / 2])
    if scene.name == "capacitive6x6":
        probe.update(x_mm=[scene.pitch_mm / 2], y_mm=[scene.pitch_mm / 2])
    return list(simulate_at(fit_model(scene), pd.DataFrame(probe)).channel_columns)


def draw_labels(observed: pd.DataFrame, inputs, n: int, rng: np.random.Generator) -> pd.DataFrame:
    """`n` press labels distributed as the observed ones: a smoothed bootstrap (an observed
    press, moved by a normal step of Silverman's bandwidth per input), so the simulated set
    shares the rig's joint distribution of positions and loads (shear inside the friction cone,
    the depths the lab used) and still fills the gaps between the few calibration presses. When
    the table was pressed on a grid (the lab's nine points, the skin's cells) the positions are
    the grid's, unmoved. A quantity observed only >= 0 (a depth, a force) stays above half its smallest observed value."""
    inputs = list(inputs)
    values = observed[inputs].to_numpy(float)
    rows = rng.integers(0, len(values), n)
    d = len(inputs)
    bandwidth = values.std(axis=0) * (4.0 / ((d + 2) * len(values))) ** (1.0 / (d + 4))
    drawn = values[rows] + rng.standard_normal((n, d)) * bandwidth
    position = [k for k, name in enumerate(inputs) if name in ("x_mm", "y_mm")]
    points = observed[[inputs[k] for k in position]].drop_duplicates()
    if position and len(points) <= GRID_SHARE * len(observed):
        drawn[:, position] = values[rows][:, position]
    never_negative = values.min(axis=0) >= 0
    # reflected at 0, and no lighter than half the lightest observed (a scene's sensed force adds
    # noise, which must not make a press of almost no force negative)
    drawn[:, never_negative] = np.maximum(np.abs(drawn[:, never_negative]), 0.5 * values.min(axis=0)[never_negative])
    return pd.DataFrame(drawn, columns=inputs)
