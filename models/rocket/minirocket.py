"""The MiniRocket transform (Dempster, Schmidt and Webb 2021, "MINIROCKET: a very fast (almost)
deterministic transform for time series classification"), multichannel as in its multivariate
variant, written as one torch module that both the eager pipeline and the ONNX export run.

The 84 kernels have length 9 and weights -1 at six positions and +2 at three (every choice of
three of nine), so a kernel's output is

    C = 3 * (x[t + a d] + x[t + b d] + x[t + c d]) - sum_j x[t + j d]     (j = 0..8, shifted by -4d)

(the paper's alpha = -X summed over the nine shifted copies and gamma = 3X at the kernel's three
positions). The nine shifted copies of the input are made once per dilation and shared by all 84
kernels, and so are the nine `3 x_c - total` and the 36 pair sums built from them: each kernel
output is one addition more, the graph never runs 84 convolutions.
Dilations are 2^0 .. (length-1)/8 spaced exponentially, with as many features per kernel at each
as the paper's 10,000-feature budget gives (9,996 = 84 x 119). Half of the (dilation, kernel)
pairs, alternating, pool over the whole zero-padded output, the others over the part the padding
does not reach. Each (dilation, kernel) sees a random combination of 1 to min(channels, 9)
channels (summed before the kernel, as the convolution is linear); its biases are quantiles of
its output on one random training window, at the low-discrepancy quantiles (k * golden ratio)
mod 1; a feature is the proportion of positive values (PPV) of output minus bias.

Everything is float32 and the additions run in a fixed order, so onnxruntime reproduces the eager
features exactly up to the last bit of the mean; on signals with flat stretches many biases sit
at an output value itself, where a rounding difference flips a comparison.
"""
import itertools
import math

import numpy as np
import torch
from torch import nn

KERNEL_LENGTH = 9
KERNEL_POSITIONS = torch.tensor(list(itertools.combinations(range(KERNEL_LENGTH), 3)), dtype=torch.long)  # 84 x 3
N_KERNELS = len(KERNEL_POSITIONS)
PAIR_POSITIONS = torch.tensor(list(itertools.combinations(range(KERNEL_LENGTH), 2)), dtype=torch.long)  # 36 x 2
KERNEL_PAIR = torch.tensor([PAIR_POSITIONS.tolist().index([b, c]) for _, b, c in KERNEL_POSITIONS.tolist()])
PAIR_START = [sum(KERNEL_LENGTH - 1 - b for b in range(first)) for first in range(KERNEL_LENGTH)]  # first pair (b, c) with b >= first
# per window, at most: a dilation group's outputs (x channels), and the comparisons of one PPV step; more spills the cache
CONVOLUTION_ELEMENTS = 1 << 18
COMPARISON_ELEMENTS = 1 << 19
MIN_LENGTH = KERNEL_LENGTH
GOLDEN_RATIO = (math.sqrt(5) + 1) / 2


def dilations_and_features(length: int, n_features: int, max_dilations_per_kernel: int = 32):
    """(dilations, features per kernel at each): the paper's exponential spacing of dilations up
    to (length - 1) / 8, its feature budget spread over them, the remainder one at a time."""
    per_kernel = n_features // N_KERNELS
    n_dilations = min(per_kernel, max_dilations_per_kernel)
    multiplier = per_kernel / n_dilations
    max_exponent = math.log2((length - 1) / (KERNEL_LENGTH - 1))
    dilations, counts = np.unique(np.floor(np.logspace(0, max_exponent, n_dilations, base=2)).astype(np.int64),
                                  return_counts=True)
    counts = (counts * multiplier).astype(np.int64)
    for k in range(per_kernel - int(counts.sum())):
        counts[k % len(counts)] += 1
    return [int(d) for d in dilations], [int(c) for c in counts]


def quantiles(n: int) -> np.ndarray:
    """The first n of the low-discrepancy sequence (k * golden ratio) mod 1, k = 1, 2, ..."""
    return (np.arange(1, n + 1) * GOLDEN_RATIO) % 1


def linear_quantiles(values: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """np.quantile's default (linear) method row by row, each row at its own levels:
    values [..., length], levels [..., count] -> [..., count]."""
    ordered = np.sort(values, axis=-1)
    position = levels * (values.shape[-1] - 1)
    below = np.floor(position).astype(np.int64)
    above = np.minimum(below + 1, values.shape[-1] - 1)
    low, high = np.take_along_axis(ordered, below, -1), np.take_along_axis(ordered, above, -1)
    return low + (high - low) * (position - below)


class DilationGroup(nn.Module):
    """The dilations that have the same number of features per kernel, computed at once:
    windows [batch, channels, length] -> their PPV features [batch, dilations x 84 x count].

    One Gather makes the nine shifted copies at every dilation of the group [batch, channels,
    dilations, 9, length], four Gathers and two Adds the 84 kernels' outputs, one Greater / Cast /
    ReduceSum per few dilations the PPVs. A group holds, and a PPV step compares, only as many
    dilations (and, in eager torch, windows) as keep these tensors in cache: one dilation's
    comparisons at 1,460 steps are 84 x 4 x 1,460 floats (2 MB); the same transform in one pass
    over whole groups ran 1.4x slower in onnxruntime and 12x slower in torch (measured side by
    side at 1,460 steps, load ~10). Kernels pooled over the inner part get -inf
    outside it (`pool_offset`: never above a bias) and their count divided by the inner length
    (`pool_scale`)."""

    def __init__(self, n_channels: int, length: int, dilations: list[int], first_index: int, count: int):
        super().__init__()
        self.n_channels, self.count, self.dilations = n_channels, count, list(dilations)
        d = torch.tensor(dilations)
        shifts = (torch.arange(KERNEL_LENGTH) - KERNEL_LENGTH // 2)[None, :, None] * d[:, None, None]
        self.padding = 4 * max(dilations)
        self.register_buffer("shift_index", self.padding + shifts + torch.arange(length)[None, None, :])
        self.register_buffer("pair_positions", PAIR_POSITIONS.clone())                 # 36 x 2
        self.register_buffer("kernel_first", KERNEL_POSITIONS[:, 0].clone())          # each kernel's a
        self.register_buffer("kernel_pair", KERNEL_PAIR.clone())                       # and its (b, c) pair
        self.register_buffer("channel_mask", torch.ones(n_channels, len(dilations), N_KERNELS, 1))
        self.register_buffer("biases", torch.zeros(len(dilations), N_KERNELS, count, 1))
        # the paper alternates, from the first dilation on, kernels pooled over the whole output and over the inner part
        index = first_index + torch.arange(len(dilations))
        inner = (index[:, None] + torch.arange(N_KERNELS)[None, :]) % 2 == 1                  # [D, 84]
        crop = (4 * d)[:, None, None] * inner[:, :, None]                                        # [D, 84, 1]
        t = torch.arange(length)[None, None, :]
        self.register_buffer("pool_offset", torch.where((t < crop) | (t >= length - crop), -math.inf, 0.0))
        self.register_buffer("pool_scale", 1.0 / (length - 2 * crop).float())

    def convolutions(self, x: torch.Tensor) -> torch.Tensor:
        """The 84 kernels' outputs at each of the group's dilations on each kernel's channel
        combination, zero-padded: [batch, dilations, 84, length]. Kernel (a, b, c) is
        3 x_a + (3 x_b + (3 x_c - sum_j x_j)): the nine `3 x_c - total` and the 36 pair sums are
        shared, so each of the 84 outputs costs one addition."""
        padded = nn.functional.pad(x, (self.padding, self.padding))
        copies = padded[:, :, self.shift_index]                      # [batch, channels, D, 9, length]
        total = copies[:, :, :, 0]
        for j in range(1, KERNEL_LENGTH):
            total = total + copies[:, :, :, j]
        shifted = 3 * copies                                         # gamma = 3X
        last = shifted - total.unsqueeze(3)                          # 3 x_c - sum_j x_j (alpha = -X)
        if torch.jit.is_tracing():  # onnxruntime: four Gathers ran faster than 15 Slices, Adds and Concats
            pairs = (shifted.index_select(3, self.pair_positions[:, 0])
                     + last.index_select(3, self.pair_positions[:, 1]))
            per_channel = (shifted.index_select(3, self.kernel_first)
                           + pairs.index_select(3, self.kernel_pair))  # [batch, channels, D, 84, length]
        else:  # torch: the same additions on slices (index_select took a quarter of the eager transform). Pairs
            # (b, c) in lexicographic order are, for each b, 3 x_b + last[b + 1:]; kernels (a, b, c) in
            # itertools.combinations order are, for each a, 3 x_a + the pairs with b > a (a tail of the pairs)
            pairs = torch.cat([shifted[:, :, :, b:b + 1] + last[:, :, :, b + 1:] for b in range(KERNEL_LENGTH - 1)], 3)
            per_channel = torch.cat([shifted[:, :, :, a:a + 1] + pairs[:, :, :, PAIR_START[a + 1]:]
                                     for a in range(KERNEL_LENGTH - 2)], 3)
        if self.n_channels == 1:
            return per_channel[:, 0]
        combined = per_channel[:, 0] * self.channel_mask[0]
        for c in range(1, self.n_channels):
            combined = combined + per_channel[:, c] * self.channel_mask[c]
        return combined

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        length = x.shape[-1]
        comparisons = N_KERNELS * self.count * length                  # per window and dilation
        if torch.jit.is_tracing():  # export/torch_graphs.to_onnx traces: one batch of any size
            return self._features(x, max(1, COMPARISON_ELEMENTS // comparisons))
        # eager (fit and predict run batches of many windows): a few windows at a time as well
        windows = max(1, min(CONVOLUTION_ELEMENTS // (len(self.dilations) * N_KERNELS * self.n_channels * length),
                             COMPARISON_ELEMENTS // comparisons))
        step = max(1, COMPARISON_ELEMENTS // (windows * comparisons))
        return torch.cat([self._features(part, step) for part in x.split(windows)])

    def _features(self, x: torch.Tensor, step: int) -> torch.Tensor:
        """PPV features [batch, D x 84 x count], `step` dilations at a time so that their
        comparisons stay in cache."""
        outputs = self.convolutions(x) + self.pool_offset                         # [batch, D, 84, length]
        features = []
        for j in range(0, outputs.shape[1], step):
            pooled, biases = outputs[:, j:j + step].unsqueeze(3), self.biases[j:j + step]
            if torch.jit.is_tracing():   # Greater, Cast, ReduceSum
                counts = (pooled > biases).float().sum(-1)
            else:  # the same 0/1 written straight as float: torch's bool-to-float cast took 2/3 of the transform
                shape = (*pooled.shape[:3], biases.shape[2], pooled.shape[-1])    # [batch, step, 84, count, length]
                counts = torch.gt(pooled, biases, out=torch.empty(shape)).sum(-1)
            features.append(counts * self.pool_scale[j:j + step])                # [batch, step, 84, count]
        return torch.cat(features, 1).flatten(1)


class MiniRocket(nn.Module):
    """windows [batch, channels, length] float32 (standardised) -> PPV features [batch, n_features]
    (`transform`: dilation groups in turn, within one by dilation, kernel, bias), or -> class
    logits through the fitted linear head (`forward`)."""

    def __init__(self, n_channels: int, length: int, n_features: int = 10_000, n_classes: int = 2):
        super().__init__()
        self.n_channels, self.length = int(n_channels), int(length)
        self.dilations, self.features_per_kernel = dilations_and_features(self.length, n_features)
        groups = []
        for count in sorted(set(self.features_per_kernel)):
            members = [i for i, c in enumerate(self.features_per_kernel) if c == count]
            # consecutive runs only, so that a group's dilation indices are first_index, first_index + 1, ...
            runs = np.split(members, np.nonzero(np.diff(members) > 1)[0] + 1)
            most = max(1, CONVOLUTION_ELEMENTS // (N_KERNELS * self.n_channels * self.length))  # dilations per group
            groups += [(int(run[s]), len(run[s:s + most]), count) for run in runs for s in range(0, len(run), most)]
        self.groups = nn.ModuleList([DilationGroup(self.n_channels, self.length, self.dilations[i:i + n], i, count)
                                     for i, n, count in sorted(groups)])
        self.head = nn.Linear(self.n_features, n_classes)

    @property
    def n_features(self) -> int:
        return N_KERNELS * sum(self.features_per_kernel)

    def transform(self, x: torch.Tensor) -> torch.Tensor:
        return torch.cat([group(x) for group in self.groups], dim=1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.transform(x))

    def fit_biases(self, x: np.ndarray, rng: np.random.Generator, chunk: int) -> None:
        """Draw each (dilation, kernel)'s channel combination and training window (in the order of
        the dilations), and set its biases to quantiles of that window's output."""
        max_exponent = math.log2(min(self.n_channels, KERNEL_LENGTH) + 1)
        masks = np.zeros((len(self.dilations), N_KERNELS, self.n_channels), dtype=np.float32)
        examples = np.zeros((len(self.dilations), N_KERNELS), dtype=np.int64)
        for i in range(len(self.dilations)):
            for k in range(N_KERNELS):
                n_combined = int(2 ** rng.uniform(0, max_exponent))
                masks[i, k, rng.choice(self.n_channels, n_combined, replace=False)] = 1.0
            examples[i] = rng.integers(len(x), size=N_KERNELS)
        sequence = quantiles(self.n_features)
        starts = np.concatenate([[0], np.cumsum(self.features_per_kernel) * N_KERNELS])
        i = 0
        for group in self.groups:
            n = group.biases.shape[0]
            group.channel_mask.copy_(torch.from_numpy(masks[i:i + n].transpose(2, 0, 1)[..., None]))
            unique, where = np.unique(examples[i:i + n], return_inverse=True)
            where = torch.from_numpy(where.reshape(n, N_KERNELS))
            own = torch.zeros(n, N_KERNELS, self.length)
            with torch.no_grad():
                for s in range(0, len(unique), chunk):
                    outputs = group.convolutions(torch.from_numpy(x[unique[s:s + chunk]]))   # [chunk, D, 84, length]
                    for e in range(outputs.shape[0]):
                        mine = where == s + e
                        own[mine] = outputs[e][mine]
            levels = np.stack([sequence[starts[i + j]:starts[i + j + 1]].reshape(N_KERNELS, group.count)
                               for j in range(n)])                                   # [D, 84, count]
            group.biases[..., 0] = torch.from_numpy(linear_quantiles(own.numpy(), levels).astype(np.float32))
            i += n
