"""The Hydra transform (Dempster, Tan, Schmidt and Webb 2023, "HYDRA: competing convolutional
kernels for fast and accurate time series classification"), multichannel as in its multivariate
variant, and Hydra's features concatenated with MiniRocket's (the paper concatenates them with
MultiRocket's, "Hydra + MultiRocket"; MultiRocket is not written here), as torch modules that both the eager pipeline and the ONNX export run.

Hydra draws `n_groups` groups of `kernels_per_group` random kernels of length 9 (normal weights,
each kernel made zero-mean and scaled to unit absolute sum) at every dilation 2^0 .. 2^floor(
log2((length - 1) / 8)), zero-padded to the input's length. Half the groups see the input, half
its first difference. At each time step the kernels of a group compete: the kernel with the
largest output adds that output to its feature (soft count), the kernel with the smallest adds
one (hard count). A group sees the sum of a random draw (with replacement) of
clip(channels / 2, 2, 8) channels (one channel: itself). Features per window: dilations x 2
(input, difference) x 2 (max, min) x groups / 2 x kernels per group (1,024 per dilation by default).

The paper's sparse scaler then works on the features as data, before the linear head: a feature
is clipped at 0 and square-rooted, centred and divided by (its standard deviation + the fraction
of training windows where it is zero, to the 4th power, + 1e-8), and set to 0 wherever it was 0
(so a feature that is mostly zero stays small). The mask makes it non-linear, so it is part of
the module (Max, Sqrt, Sub, Div, Mul by NotEqual) and the classifier does not standardise these
columns again (`prescaled_from`).

The winner and loser are torch's max/argmin over the kernels, onnxruntime's ArgMax/ArgMin (the
first kernel on ties; on a constant stretch every zero-mean kernel outputs ~0 and rounding
decides), counted by an Equal against the kernel index, not a scatter.
"""
import math

import numpy as np
import torch
from torch import nn

from models.rocket.minirocket import KERNEL_LENGTH, MiniRocket
from models.storable import storable


MAX_COMBINED_CHANNELS = 8
SPARSE_EXPONENT = 4
SPARSE_EPSILON = 1e-8


def hydra_dilations(length: int) -> list[int]:
    """2^0 .. 2^floor(log2((length - 1) / 8)): the largest dilation whose kernel spans the input."""
    return [2 ** e for e in range(int(math.log2((length - 1) / (KERNEL_LENGTH - 1))) + 1)]


@storable
class HydraDilation(nn.Module):
    """One dilation: [batch, channels, length] -> [batch, 2 x 2 x groups/2 x kernels] (input then
    difference; within each, max soft counts then min hard counts, by group and kernel)."""

    def __init__(self, n_channels: int, dilation: int, n_groups: int, kernels_per_group: int,
                 rng: np.random.Generator):
        super().__init__()
        self.dilation, self.half, self.kernels_per_group = int(dilation), n_groups // 2, kernels_per_group
        weights = rng.standard_normal((2, self.half * kernels_per_group, 1, KERNEL_LENGTH))
        weights -= weights.mean(-1, keepdims=True)
        weights /= np.abs(weights).sum(-1, keepdims=True)
        mix = np.zeros((2, self.half, n_channels), dtype=np.float32)    # how often each group drew each channel
        n_drawn = 1 if n_channels == 1 else int(np.clip(n_channels // 2, 2, MAX_COMBINED_CHANNELS))
        drawn = rng.integers(n_channels, size=(2, self.half, n_drawn))
        for source in range(2):
            for g in range(self.half):
                np.add.at(mix[source, g], drawn[source, g], 1.0)
        self.register_buffer("weights", torch.from_numpy(weights.astype(np.float32)))
        self.register_buffer("mix", torch.from_numpy(mix))
        self.register_buffer("kernel_index", torch.arange(kernels_per_group))

    def counts(self, x: torch.Tensor, source: int) -> torch.Tensor:
        combined = torch.matmul(self.mix[source], x)                              # [batch, groups/2, length]
        outputs = nn.functional.conv1d(combined, self.weights[source], dilation=self.dilation,
                                       padding=4 * self.dilation, groups=self.half)
        # kernels last: torch reduces a contiguous last axis several times faster than a middle one
        outputs = outputs.view(x.shape[0], self.half, self.kernels_per_group, -1).transpose(2, 3).contiguous()
        best, winner = outputs.max(-1, keepdim=True)                                # [batch, g, length, 1]
        loser = outputs.argmin(-1, keepdim=True)
        soft = ((winner == self.kernel_index) * best).sum(2)                        # [batch, g, k]
        hard = (loser == self.kernel_index).to(outputs.dtype).sum(2)
        return torch.cat([soft, hard], dim=1).flatten(1)

    def forward(self, x: torch.Tensor, difference: torch.Tensor) -> torch.Tensor:
        return torch.cat([self.counts(x, 0), self.counts(difference, 1)], dim=1)


@storable
class Hydra(nn.Module):
    """windows [batch, channels, length] float32 (standardised) -> sparse-scaled Hydra features."""

    def __init__(self, n_channels: int, length: int, rng: np.random.Generator, n_groups: int = 64,
                 kernels_per_group: int = 8):
        super().__init__()
        self.dilations = nn.ModuleList([HydraDilation(n_channels, d, n_groups, kernels_per_group, rng)
                                        for d in hydra_dilations(length)])
        self.n_features = len(self.dilations) * 2 * n_groups * kernels_per_group
        self.register_buffer("sparse_mean", torch.zeros(self.n_features))
        self.register_buffer("sparse_scale", torch.ones(self.n_features))

    def counts(self, x: torch.Tensor) -> torch.Tensor:
        difference = x[..., 1:] - x[..., :-1]
        return torch.cat([d(x, difference) for d in self.dilations], dim=1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        root = self.counts(x).clamp(min=0).sqrt()
        return (root - self.sparse_mean) * (root != 0).to(root.dtype) / self.sparse_scale

    def fit_scaler(self, counts: torch.Tensor) -> None:
        """The sparse scaler's statistics on the training windows' counts."""
        root = counts.double().clamp(min=0).sqrt()
        epsilon = (root == 0).double().mean(0) ** SPARSE_EXPONENT + SPARSE_EPSILON
        self.sparse_mean.copy_(root.mean(0))
        self.sparse_scale.copy_(root.std(0) + epsilon)   # torch's std: n - 1, as the paper's code


@storable
class HydraMiniRocket(nn.Module):
    """MiniRocket's PPV features, then Hydra's sparse-scaled ones: the transform `transform=
    hydra_minirocket` gives RocketClassifier, with MiniRocket's interface (`groups` for batch
    sizes, `fit_biases`, `head`); columns from `prescaled_from` on are not standardised again."""

    def __init__(self, n_channels: int, length: int, n_features: int = 10_000, n_classes: int = 2,
                 seed: int = 0, n_groups: int = 64, kernels_per_group: int = 8):
        super().__init__()
        self.minirocket = MiniRocket(n_channels, length, n_features, n_classes)
        # Hydra's kernels from their own stream, so MiniRocket's draws equal model=minirocket's at the same seed
        self.hydra = Hydra(n_channels, length, np.random.default_rng([seed, 1]), n_groups, kernels_per_group)
        self.prescaled_from = self.minirocket.n_features
        self.head = nn.Linear(self.minirocket.n_features + self.hydra.n_features, n_classes)

    @property
    def groups(self):
        return self.minirocket.groups

    @property
    def n_features(self) -> int:
        return self.head.in_features

    def fit_biases(self, x: np.ndarray, rng: np.random.Generator, chunk: int) -> None:
        self.minirocket.fit_biases(x, rng, chunk)
        with torch.no_grad():
            self.hydra.fit_scaler(torch.cat([self.hydra.counts(torch.from_numpy(x[s:s + chunk]))
                                             for s in range(0, len(x), chunk)]))

    def transform(self, x: torch.Tensor) -> torch.Tensor:
        return torch.cat([self.minirocket.transform(x), self.hydra(x)], dim=1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.transform(x))
