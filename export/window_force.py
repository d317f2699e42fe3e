"""An exported force model that reads the 3 x 3 window of loads around a contact's peak, as the
contact tracker calls it: windows (n, 9) -> force_n (n,). Checked once here, for the capacitive
tracking study and the live stream alike."""
from collections.abc import Callable

import numpy as np

from common.errors import InputError
from data.preprocessing.contact_windows import window_channel_names


def window_force(predictor, who: str, checked: bool = True) -> Callable[[np.ndarray], np.ndarray]:
    """The force reader of `predictor` (an OnnxPredictor); InputError naming `who` when the model
    does not read the window to force_n. `checked=False` runs the graph without predict_array's
    checks (a live loop checks every line itself and its output's finiteness per frame)."""
    if predictor.kind != "regression" or predictor.channels != window_channel_names() \
            or "force_n" not in predictor.targets:
        raise InputError(f"{who}: {predictor.path} does not read the 3x3 window to force_n; train it with "
                         "experiment=capacitive_force hydra.mode=RUN scene.characterisation_channels=window")
    column = predictor.targets.index("force_n")
    if checked:
        return lambda windows: predictor.predict_array(np.asarray(windows, dtype=np.float64))["prediction"][:, column]
    output = predictor.outputs.index("prediction")
    return lambda windows: np.asarray(predictor.run_graph(np.asarray(windows, dtype=predictor.input_dtype))[output],
                                      dtype=np.float64)[:, column]
