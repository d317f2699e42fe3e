"""Building blocks shared by the 1-D convolutional time-series classifiers."""
from torch import nn

from models.storable import storable


def same_conv(n_in: int, n_out: int, kernel: int, bias: bool = True) -> nn.Sequential:
    """Conv1d whose output has the input's length: explicit zero padding (k-1)//2 left and k//2
    right, which PyTorch's padding='same' would otherwise do by copying the input for even k."""
    return nn.Sequential(nn.ConstantPad1d(((kernel - 1) // 2, kernel // 2), 0.0), nn.Conv1d(n_in, n_out, kernel, bias=bias))


def conv_bn_relu(n_in: int, n_out: int, kernel: int, relu: bool = True) -> nn.Sequential:
    """Conv1d ('same' length) -> BatchNorm -> ReLU, the unit every time-series ResNet stacks."""
    layers = [same_conv(n_in, n_out, kernel), nn.BatchNorm1d(n_out)]
    if relu:
        layers.append(nn.ReLU())
    return nn.Sequential(*layers)


@storable
class ResidualConvBlock(nn.Module):
    """Three convolutions (kernels 8, 5, 3 by default) plus a shortcut, then ReLU
    (Wang et al., "Time series classification from scratch with deep neural networks", 2017).
    The shortcut is a 1x1 convolution + BatchNorm when the width changes, else BatchNorm."""

    def __init__(self, n_in: int, n_out: int, kernels=(8, 5, 3)):
        super().__init__()
        layers, width = [], n_in
        for i, kernel in enumerate(kernels):
            layers.append(conv_bn_relu(width, n_out, kernel, relu=i < len(kernels) - 1))
            width = n_out
        self.body = nn.Sequential(*layers)
        self.shortcut = (nn.Sequential(nn.Conv1d(n_in, n_out, 1), nn.BatchNorm1d(n_out)) if n_in != n_out
                         else nn.BatchNorm1d(n_out))
        self.relu = nn.ReLU()

    def forward(self, x):
        return self.relu(self.body(x) + self.shortcut(x))
