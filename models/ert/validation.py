"""The one check of what an ERT reconstruction is given: its geometry, frames of voltages and the
presses it is fitted on (calibration or validation presses of the sensor under test), refused in
one line naming what was expected."""
import numpy as np
import scipy.sparse as sp

from common.errors import InputError


def required_geometry(geometry) -> dict:
    """The nominal geometry a reconstruction is built from, refused when missing."""
    if geometry is None:
        raise InputError("model.geometry is required: the scene's nominal geometry (ERTScene.geometry())")
    return geometry


def checked_voltages(X, n_channels: int) -> np.ndarray:
    """Frames of voltages as float, refused in one line unless dense, real, (n_frames, n_channels)
    and finite."""
    if sp.issparse(X):
        raise InputError("voltages must be a dense array: sparse input is not supported (every channel reads)")
    X = np.asarray(X)
    if np.iscomplexobj(X):
        raise InputError("Complex data not supported: voltages are changes of a DC voltage, real")
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[1] != n_channels:
        raise InputError(f"voltages must have shape (n_frames, {n_channels}), got {X.shape}")
    if not np.isfinite(X).all():
        raise InputError("voltages contain NaN or infinite values")
    return X


def checked_presses(X, y, n_channels: int, quantification_limit_n: float,
                    role: str = "validation") -> tuple[np.ndarray, np.ndarray]:
    """(voltages, targets x_mm, y_mm, force_n) of the presses at or above the quantification limit:
    a press below it is indistinguishable from noise, so it cannot tell settings apart. `role`
    names the set in the messages (calibration, validation)."""
    if y is None:
        raise InputError(f"a reconstruction requires y to be passed, but the target y is None: the {role} presses' "
                         f"x_mm, y_mm, force_n")
    X = checked_voltages(X, n_channels)
    y = np.asarray(y, dtype=float)
    if y.ndim != 2 or y.shape[1] < 3 or len(y) != len(X):
        raise InputError(f"{role} targets must have shape ({len(X)}, 3) (x_mm, y_mm, force_n), got {y.shape}")
    usable = y[:, 2] >= quantification_limit_n
    if usable.sum() < 4:
        raise InputError(f"the {role} set has {int(usable.sum())} presses at or above the quantification "
                         f"limit ({quantification_limit_n} N); at least 4 are needed")
    return X[usable], y[usable, :3]
