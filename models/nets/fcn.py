"""FCN: the fully convolutional network for time-series classification (Wang et al., "Time
series classification from scratch with deep neural networks: a strong baseline", IJCNN 2017).

Three convolution blocks (128, 256, 128 filters; kernels 8, 5, 3; each BatchNorm and ReLU), global
average pooling over time and a linear classifier: ResCNN without its shortcuts. Added as a model
is added (docs/add_a_model.md): this file and configs/model/fcn.yaml; the time-series trainer
(models/timeseries_classifier.py) trains it and torch.onnx exports it.
"""
from torch import nn

from models.nets.conv_blocks import conv_bn_relu
from models.storable import storable


@storable
class FCN(nn.Module):
    def __init__(self, n_channels: int, n_classes: int, length: int | None = None, modalities=None,
                 widths=(128, 256, 128), kernels=(8, 5, 3)):
        super().__init__()
        inputs = (n_channels, *widths[:-1])
        self.body = nn.Sequential(*(conv_bn_relu(n_in, n_out, k) for n_in, n_out, k in zip(inputs, widths, kernels)))
        self.head = nn.Linear(widths[-1], n_classes)

    def forward(self, x):
        return self.head(self.body(x).mean(dim=-1))
