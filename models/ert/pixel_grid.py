"""The pixel grid a reconstruction images the sheet on."""
import numpy as np


def pixel_centres_mm(side_mm: float, pixels_per_side: int, margin_mm: float = 0.0) -> np.ndarray:
    """(n^2, 2) x, y of an n x n pixel grid over [-margin, side + margin]^2, rows in y."""
    width = side_mm + 2.0 * margin_mm
    axis = (np.arange(pixels_per_side) + 0.5) * width / pixels_per_side - margin_mm
    xx, yy = np.meshgrid(axis, axis)
    return np.column_stack([xx.ravel(), yy.ravel()])
