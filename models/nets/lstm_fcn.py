"""LSTM-FCN with dimension shuffle (Karim et al., IEEE Access 6, 2018).

Two branches on the same input: an LSTM that reads the *transposed* window (each channel is
one time step whose features are the whole series: the "dimension shuffle", two steps for
two channels, so it is fast), followed by dropout; and a fully convolutional branch (128, 256,
128 filters, kernels 8/5/3, BatchNorm, ReLU, global average pooling). Concatenated, linear.

Parameter count at 2 x 1400 and 10 classes: 1,051,658 (the LSTM over 1,400 features alone is
783,360 of the paper's 786,276; the standard conv branch adds 265,728). The paper's odd total
fits no standard configuration, so we keep the standard one. The LSTM's size grows with the
window length, so the CPU-sized windows make it much smaller.
"""
import torch
from torch import nn

from models.nets.conv_blocks import conv_bn_relu
from models.storable import storable


@storable
class LSTMFCN(nn.Module):
    def __init__(self, n_channels: int, n_classes: int, length: int, modalities=None, hidden: int = 128,
                 dropout: float = 0.8, widths=(128, 256, 128), kernels=(8, 5, 3)):
        super().__init__()
        self.lstm = nn.LSTM(input_size=length, hidden_size=hidden, batch_first=True)
        self.dropout = nn.Dropout(dropout)
        layers, width = [], n_channels
        for out, kernel in zip(widths, kernels):
            layers.append(conv_bn_relu(width, out, kernel))
            width = out
        self.fcn = nn.Sequential(*layers)
        self.head = nn.Linear(hidden + width, n_classes)

    def forward(self, x):
        _, (hidden, _) = self.lstm(x)            # x is (batch, channels, length): channels act as steps
        recurrent = self.dropout(hidden[-1])
        convolutional = self.fcn(x).mean(dim=-1)
        return self.head(torch.cat([recurrent, convolutional], dim=1))
