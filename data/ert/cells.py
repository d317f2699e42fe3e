"""Square cells over the sheet's grid nodes: the 20 mm fabric patches of the scene and the pixels
of a reconstruction's image are both cells, and a node's conductance follows the cells it lies in."""
import numpy as np


def patch_weights(node_xy_mm: np.ndarray, side_mm: float, patch_mm: float) -> np.ndarray:
    """(n_nodes, n_patches) share of each node's cell under each patch: 1 inside a patch, split
    equally between the patches that meet on a patch border (so the map is mirror symmetric;
    assigning a border node to one side would shift every image by half a node spacing)."""
    n = int(round(side_mm / patch_mm))
    position = node_xy_mm / patch_mm
    tolerance = 1e-9
    low = np.clip(np.ceil(position - 1 - tolerance).astype(int), 0, n - 1)   # patches whose closed square holds the node
    high = np.clip(np.floor(position + tolerance).astype(int), 0, n - 1)
    weights = np.zeros((len(node_xy_mm), n * n))
    for ix_choice in (low[:, 0], high[:, 0]):
        for iy_choice in (low[:, 1], high[:, 1]):
            np.add.at(weights, (np.arange(len(node_xy_mm)), iy_choice * n + ix_choice), 0.25)
    return weights
