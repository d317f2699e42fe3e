"""models/mixture_weights.py: score above the floor, normalised; equal weights where none is above."""
import numpy as np

from models.mixture_weights import above_floor_weights


def test_weights_are_the_scores_above_the_floor_normalised():
    np.testing.assert_allclose(above_floor_weights([0.9, 0.7, 0.4], 0.5), [0.4 / 0.6, 0.2 / 0.6, 0.0])


def test_rows_each_with_their_floor_and_equal_weights_where_nothing_is_above():
    weights = above_floor_weights([[0.9, 0.7], [0.3, 0.2]], [0.8, 0.5])
    np.testing.assert_allclose(weights, [[1.0, 0.0], [0.5, 0.5]])
