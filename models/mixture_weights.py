"""The weights of a validation-weighted mixture, one rule for every mixture of classifiers or
regressors that is weighted by held-out scores (the default model's ensemble candidate,
models/validation_choice.py; the ROCKET-family mixture, models/rocket/mixture.py): each member's
score above what a constant predicts (R^2 0; the majority class's accuracy), normalised to sum to 1.
A member at or below that floor gets weight 0."""
import numpy as np


def above_floor_weights(scores, floor) -> np.ndarray:
    """scores [..., members] and floor [...] (or a number) -> weights [..., members], each row
    summing to 1; a row where no member is above its floor gets equal weights (nothing to weight by)."""
    scores = np.asarray(scores, dtype=np.float64)
    above = np.clip(scores - np.asarray(floor, dtype=np.float64)[..., None], 0.0, None)
    total = above.sum(axis=-1, keepdims=True)
    equal = np.full_like(scores, 1.0 / scores.shape[-1])
    return np.where(total > 0, above / np.where(total > 0, total, 1.0), equal)
