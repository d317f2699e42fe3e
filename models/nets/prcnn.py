"""PR-CNN: the parallel residual 1-D CNN of the seed paper, for multi-modal time series.

    modality groups --> one residual conv block per group, in parallel (no mixing before fusion)
                    --> concatenate --> two 1-D conv fusion layers --> global average pool --> linear

Each branch sees only its own channels (tested: perturbing one group leaves the other
branch's activations untouched). Any number of groups and channels per group.

Parameter count: the paper reports 266,251 for two single-channel modalities at 2 x 1400
and 10 classes. With branch width 64 (kernels 8/5/3), fusion width 128 (kernels 5/3) this
configuration has 201,354; the paper does not give its layer sizes, and its odd total
implies an odd-sized parameter that no conv/BN/linear stack of even widths produces, so we
do not reproduce it exactly. The count does not depend on the window length.
"""
import torch
from torch import nn

from models.nets.conv_blocks import ResidualConvBlock, conv_bn_relu
from models.storable import storable


@storable
class PRCNN(nn.Module):
    def __init__(self, n_channels: int, n_classes: int, length: int | None = None, modalities=None,
                 branch_width: int = 64, fusion_width: int = 128, kernels=(8, 5, 3), fusion_kernels=(5, 3)):
        super().__init__()
        modalities = modalities or {f"channel_{c}": [c] for c in range(n_channels)}
        self.groups = {name: list(channels) for name, channels in modalities.items()}
        self.branches = nn.ModuleDict({name: ResidualConvBlock(len(channels), branch_width, kernels)
                                       for name, channels in self.groups.items()})
        width, fusion = branch_width * len(self.groups), []
        for kernel in fusion_kernels:
            fusion.append(conv_bn_relu(width, fusion_width, kernel))
            width = fusion_width
        self.fusion = nn.Sequential(*fusion)
        self.head = nn.Linear(width, n_classes)

    def branch_outputs(self, x) -> dict:
        return {name: self.branches[name](x[:, channels]) for name, channels in self.groups.items()}

    def forward(self, x):
        fused = self.fusion(torch.cat(list(self.branch_outputs(x).values()), dim=1))
        return self.head(fused.mean(dim=-1))
