"""Which columns are constant, and the mean and spread to standardise the others with.

A column that is constant in exact arithmetic can have a standard deviation of rounding noise
(three channels' kurtosis is -1.5 on every row, std 6.6e-16): dividing by it turns float noise
into values of order one, and a float64 model and its float32 ONNX graph then disagree. As
scikit-learn's StandardScaler does, a spread below ten machine epsilons of the column's
magnitude counts as zero.
"""
import numpy as np


def constant_columns(values: np.ndarray, axis=0, keepdims: bool = False) -> np.ndarray:
    values = np.asarray(values, dtype=np.float64)
    mean = values.mean(axis=axis, keepdims=keepdims)
    return values.std(axis=axis, keepdims=keepdims) <= 10 * np.finfo(np.float64).eps * np.abs(mean)


def mean_and_scale(values: np.ndarray, axis=0, keepdims: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Per-column mean and spread; constant columns get spread 1."""
    values = np.asarray(values, dtype=np.float64)
    spread = values.std(axis=axis, keepdims=keepdims)
    return values.mean(axis=axis, keepdims=keepdims), np.where(constant_columns(values, axis, keepdims), 1.0, spread)
