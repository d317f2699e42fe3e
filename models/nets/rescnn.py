"""Res-CNN baseline: the ResNet for time-series classification (Wang et al. 2017).

Three residual blocks of kernels 8/5/3 with 64, 128, 128 filters, global average pooling,
linear classifier; all channels mixed from the first layer.

Parameter count: 505,866 at 2 channels and 10 classes (independent of length), twice the
paper's "Res-CNN" 257,803; no standard variant matches that odd total, so we keep the
standard network and report its own count.
"""
from torch import nn

from models.nets.conv_blocks import ResidualConvBlock
from models.storable import storable


@storable
class ResCNN(nn.Module):
    def __init__(self, n_channels: int, n_classes: int, length: int | None = None, modalities=None,
                 widths=(64, 128, 128), kernels=(8, 5, 3)):
        super().__init__()
        blocks, width = [], n_channels
        for out in widths:
            blocks.append(ResidualConvBlock(width, out, kernels))
            width = out
        self.body = nn.Sequential(*blocks)
        self.head = nn.Linear(width, n_classes)

    def forward(self, x):
        return self.head(self.body(x).mean(dim=-1))
