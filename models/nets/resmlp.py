"""The seed's residual MLP for inverse regression from features (x, y, depth, pressure).

    input -> GaussianNoise(0.02, training only)
          -> 4 residual blocks of widths 256, 128, 96, 64 (dropout 0.40, 0.35, 0.30, 0.25)
          -> Linear(n_targets)
    block: Linear -> ReLU -> BatchNorm -> Dropout -> Linear -> ReLU -> BatchNorm, plus a
           linear projection of the block's input (the skip), added at the end.

How it trains lives in models/resmlp_regressor.py.
"""
import torch
from torch import nn

from common.errors import InputError
from models.storable import storable


@storable
class GaussianNoise(nn.Module):
    """Adds N(0, std^2) noise to the input while training; the identity at inference."""

    def __init__(self, std: float):
        super().__init__()
        self.std = std

    def forward(self, x):
        return x + self.std * torch.randn_like(x) if self.training and self.std > 0 else x


@storable
class ResidualBlock(nn.Module):
    def __init__(self, n_in: int, width: int, dropout: float):
        super().__init__()
        self.main = nn.Sequential(
            nn.Linear(n_in, width), nn.ReLU(), nn.BatchNorm1d(width), nn.Dropout(dropout),
            nn.Linear(width, width), nn.ReLU(), nn.BatchNorm1d(width))
        self.skip = nn.Linear(n_in, width)

    def forward(self, x):
        return self.main(x) + self.skip(x)


@storable
class ResMLP(nn.Module):
    def __init__(self, n_in: int, n_out: int, widths=(256, 128, 96, 64),
                 dropouts=(0.40, 0.35, 0.30, 0.25), noise_std=0.02):
        super().__init__()
        if len(widths) != len(dropouts):
            raise InputError(f"model.widths ({len(widths)}) and model.dropouts ({len(dropouts)}) differ in length")
        layers, n = [GaussianNoise(noise_std)], n_in
        for width, dropout in zip(widths, dropouts):
            layers.append(ResidualBlock(n, width, dropout))
            n = width
        self.body = nn.Sequential(*layers)
        self.head = nn.Linear(n, n_out)

    def forward(self, x):
        return self.head(self.body(x))
