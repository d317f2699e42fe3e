"""Force per contact from a fitted regression pipeline, as one function of the contacts' 3 x 3
windows (n, 9) evaluated once per frame for all its contacts.

Through the pipeline itself (`predict_raw`: its features, scaler and model, each a framework
call) a frame costs ~200-400 us on this project's machine whatever the number of contacts, for
what is, with the study's default model (the paper's linear regression on the raw window), an
affine map of nine loads. So a pipeline that is affine in its readings by construction (raw
features only, a linear model) is folded once into weights and an offset by evaluating it at
the origin and at each unit reading, and each frame costs one small product: the same fitted
model, to rounding. Any other pipeline is called once per frame with all contacts as a batch.
"""
from collections.abc import Callable

import numpy as np

from data.preprocessing.features import enabled_groups
from models.classic_regressors import ClassicRegressor
from models.deployable import RegressionPipeline

LINEAR_KINDS = ("linear_regression", "svr")  # ClassicRegressor's SVR has a linear kernel


def force_reader(pipeline, target: str = "force_n") -> Callable[[np.ndarray], np.ndarray]:
    """windows (n, channels) -> the pipeline's `target` (n,), as fast as the pipeline allows."""
    column = pipeline.target_names.index(target)
    if is_affine(pipeline):
        n = len(pipeline.channel_names)
        at = pipeline.predict_raw(np.vstack([np.zeros(n), np.eye(n)]))[0][:, column]
        weights, offset = at[1:] - at[0], float(at[0])
        return lambda windows: windows @ weights + offset
    return lambda windows: pipeline.predict_raw(windows)[0][:, column]


def is_affine(pipeline) -> bool:
    """Whether the pipeline's prediction is affine in its raw readings by construction: raw
    features (its min-max normalisation, if any, is affine too) and a linear model."""
    return (isinstance(pipeline, RegressionPipeline) and enabled_groups(pipeline.feature_groups) == ["raw"]
            and isinstance(pipeline.model, ClassicRegressor) and pipeline.model.kind in LINEAR_KINDS)
