"""Where a press loads the ERT skin's fabric patches: each indenter's footprint, spread by the foam
beneath (`foam_spread`), integrated over each patch. The scene turns the loads into conductance
(data/scenes/ert_effects.py); the learned inverse (models/ert/learned_readings_inverse.py) takes
them as the image it should reconstruct."""
import numpy as np
from scipy.special import ndtr


def _disk_samples(radius_mm: float, n_rings: int = 4, n_angles: int = 12) -> np.ndarray:
    """Points over a disk, each standing for an equal share of its area: equal-area rings
    (radii at sqrt of the ring mid-areas) times angles offset by half a step, so the set is
    mirror symmetric in x and y (a mirrored press loads mirrored patches exactly)."""
    r = radius_mm * np.sqrt((np.arange(n_rings) + 0.5) / n_rings)
    angle = (np.arange(n_angles) + 0.5) * 2.0 * np.pi / n_angles
    rr, aa = np.meshgrid(r, angle, indexing="ij")
    return np.column_stack([(rr * np.cos(aa)).ravel(), (rr * np.sin(aa)).ravel()])


def patch_loads_n(contacts: np.ndarray, side_mm: float, patch_mm: float, radius_mm: float,
                  spread_sd_mm: float) -> np.ndarray:
    """(n_presses, n_patches) load on each patch from (n_presses, n_contacts, 3) contacts
    [x_mm, y_mm, force_n]: each indenter's footprint, blurred by a Gaussian of sd
    `spread_sd_mm` (foam_spread; 0 = none), integrated over each patch and kept on the sheet.
    Shares below 1e-3 of a contact's load are dropped so a press changes few patches."""
    n_side = int(round(side_mm / patch_mm))
    edges = np.arange(n_side + 1) * patch_mm
    samples = _disk_samples(radius_mm)
    loads = np.zeros((len(contacts), n_side * n_side))
    for k in range(contacts.shape[1]):
        pressed = np.flatnonzero(contacts[:, k, 2] != 0.0)   # an absent second indenter loads nothing
        px = contacts[pressed, k, 0:1] + samples[None, :, 0]       # (n, n_samples)
        py = contacts[pressed, k, 1:2] + samples[None, :, 1]
        if spread_sd_mm > 0:
            cx = ndtr((edges[None, None, :] - px[..., None]) / spread_sd_mm)
            cy = ndtr((edges[None, None, :] - py[..., None]) / spread_sd_mm)
            wx, wy = np.diff(cx, axis=-1), np.diff(cy, axis=-1)  # (n, n_samples, n_side)
        else:
            ix = np.clip((px / patch_mm).astype(int), 0, n_side - 1)
            iy = np.clip((py / patch_mm).astype(int), 0, n_side - 1)
            wx = np.eye(n_side)[ix]
            wy = np.eye(n_side)[iy]
        share = (np.swapaxes(wy, 1, 2) @ wx).reshape(len(pressed), n_side * n_side)     # sum over samples of wy wx
        share /= np.maximum(share.sum(axis=1, keepdims=True), 1e-300)
        share[share < 1e-3] = 0.0
        share /= np.maximum(share.sum(axis=1, keepdims=True), 1e-300)
        loads[pressed] += share * contacts[pressed, k, 2:3]
    return loads
