"""Press position from a reconstructed image with sub-pixel precision.

The arg-max pixel cannot resolve below half a pixel, and a finer grid alone does not help where
the image's peak is flat. The weighted centroid of the thresholded image (pixels above
`threshold` x the image's maximum, each weighted by how far it rises above that level) moves
continuously with the blob: what the paper reads as the peak of a 100 x 100 image becomes one
weighted mean. The weights go to zero continuously at the threshold, so a pixel crossing it
does not make the position jump.
"""
import numpy as np


def thresholded_weights(images: np.ndarray, threshold: float) -> np.ndarray:
    """(n_frames, n_pixels) max(image - threshold x max(image), 0)."""
    peak = images.max(axis=1, keepdims=True)
    return np.maximum(images - threshold * peak, 0.0)


def thresholded_centroid(images: np.ndarray, centres_mm: np.ndarray, threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """((n_frames, 2) centroid in mm, (n_frames,) the weights' sum) of the thresholded images."""
    weights = thresholded_weights(images, threshold)
    mass = weights.sum(axis=1)
    xy = weights @ centres_mm / np.maximum(mass, 1e-300)[:, None]
    return xy, mass
