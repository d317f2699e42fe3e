"""Press position from a reconstructed image with sub-pixel precision, and the window of pixels
around an image's peak that a learned correction reads.

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


def window_around_peak(images: np.ndarray, pixels_per_side: int,
                       half_width_px: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(row iy (n,), column ix (n,), window (n, (2h + 1)^2)) of each flat image's arg-max pixel and
    the pixels around it, zero beyond the grid. The window moves with the press, so what a model
    learns from it carries over between places."""
    n, h = int(pixels_per_side), int(half_width_px)
    padded = np.pad(images.reshape(-1, n, n), ((0, 0), (h, h), (h, h)))
    peak = images.argmax(axis=1)
    iy, ix = peak // n, peak % n
    offsets = np.arange(2 * h + 1)
    window = padded[np.arange(len(images))[:, None, None], iy[:, None, None] + offsets[None, :, None],
                    ix[:, None, None] + offsets[None, None, :]].reshape(len(images), -1)
    return iy, ix, window
