"""InceptionTime (Ismail Fawaz et al., Data Min. Knowl. Disc. 34, 2020), one network.

Six inception modules of 32 filters: a 1x1 bottleneck (32) feeding convolutions of kernels
39, 19 and 9, in parallel with a 3-wide max-pool followed by a 1x1 convolution; the four
outputs are concatenated (128 channels), batch-normalised and passed through ReLU. No conv
bias. A residual connection every three modules: the first shortcut is a 1x1 convolution +
BatchNorm (input -> 128 channels), the second an identity. Global average pooling, linear.

At 2 channels x 1400 steps and 10 classes this has exactly 456,074 trainable parameters, the
paper's figure (tested); the count does not depend on the length.
"""
import torch
from torch import nn

from models.nets.conv_blocks import same_conv
from models.storable import storable


@storable
class InceptionModule(nn.Module):
    def __init__(self, n_in: int, filters: int = 32, bottleneck: int = 32, kernels=(39, 19, 9)):
        super().__init__()
        self.bottleneck = nn.Conv1d(n_in, bottleneck, 1, bias=False)
        self.convs = nn.ModuleList(same_conv(bottleneck, filters, k, bias=False) for k in kernels)
        self.pool = nn.MaxPool1d(3, stride=1, padding=1)
        self.pool_conv = nn.Conv1d(n_in, filters, 1, bias=False)
        self.bn = nn.BatchNorm1d(filters * (len(kernels) + 1))
        self.relu = nn.ReLU()

    def forward(self, x):
        squeezed = self.bottleneck(x)
        branches = [conv(squeezed) for conv in self.convs] + [self.pool_conv(self.pool(x))]
        return self.relu(self.bn(torch.cat(branches, dim=1)))


@storable
class InceptionTime(nn.Module):
    def __init__(self, n_channels: int, n_classes: int, length: int | None = None, modalities=None,
                 depth: int = 6, filters: int = 32, bottleneck: int = 32, kernels=(39, 19, 9)):
        super().__init__()
        width = filters * (len(kernels) + 1)
        self.modules_ = nn.ModuleList(
            InceptionModule(n_channels if i == 0 else width, filters, bottleneck, kernels) for i in range(depth))
        # Shortcut after modules 3, 6, ...: a projection when the width changes, else identity.
        self.shortcuts = nn.ModuleList(
            nn.Sequential(nn.Conv1d(n_channels, width, 1, bias=False), nn.BatchNorm1d(width)) if i == 0
            else nn.Identity() for i in range(depth // 3))
        self.relu = nn.ReLU()
        self.head = nn.Linear(width, n_classes)

    def forward(self, x):
        residual = x
        for i, module in enumerate(self.modules_):
            x = module(x)
            if i % 3 == 2:
                x = self.relu(x + self.shortcuts[i // 3](residual))
                residual = x
        return self.head(x.mean(dim=-1))
