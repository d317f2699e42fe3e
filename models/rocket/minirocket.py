"""The MiniRocket transform (Dempster, Schmidt and Webb 2021, "MINIROCKET: a very fast (almost)
deterministic transform for time series classification"), multichannel as in its multivariate
variant, written as one torch module that both the eager pipeline and the ONNX export run.

The 84 kernels have length 9 and weights -1 at six positions and +2 at three (every choice of
three of nine), so a kernel's output is

    C = 3 * (x[t + a d] + x[t + b d] + x[t + c d]) - sum_j x[t + j d]     (j = 0..8, shifted by -4d)

(the paper's alpha = -X summed over the nine shifted copies and gamma = 3X at the kernel's three
positions). The nine shifted copies of the input are made once per dilation (one Gather) and
shared by all 84 kernels, whose outputs are one matrix product of their -1/+2 weights (84 x 9 per
channel, the channel combination folded in as zero weights) with the copies. The paper's own
shortcut, 3 x_a + (3 x_b + (3 x_c - total)) on shared pair sums, one addition per output, ran
slower as separate tensor operations: 3.5x slower in torch at 427 and 1,460 steps, and the
exported graph 1.2-1.4x slower in onnxruntime at 150-1,460 steps (measured side by side, CPU time
at load ~15): each of its operations is a pass over memory, where the matrix product keeps its
nine terms in registers. Every product w x is exact (w is -1, 0 or 2), so an output differs
between the two only by the order of its nine additions.
Dilations are 2^0 .. (length-1)/8 spaced exponentially, with as many features per kernel at each
as the paper's 10,000-feature budget gives (9,996 = 84 x 119). Half of the (dilation, kernel)
pairs, alternating, pool over the whole zero-padded output, the others over the part the padding
does not reach. Each (dilation, kernel) sees a random combination of 1 to min(channels, 9)
channels (summed before the kernel, as the convolution is linear); its biases are quantiles of
its output on one random training window, at the low-discrepancy quantiles (k * golden ratio)
mod 1; a feature is the proportion of positive values (PPV) of output minus bias.

Everything is float32; torch's and onnxruntime's matrix products may order the nine additions
differently, which matters only where a bias sits at an output value itself (signals with flat
stretches), where a rounding difference flips a comparison.
"""
import itertools
import math

import numpy as np
import torch
from torch import nn

from models.storable import storable

KERNEL_LENGTH = 9
KERNEL_POSITIONS = torch.tensor(list(itertools.combinations(range(KERNEL_LENGTH), 3)), dtype=torch.long)  # 84 x 3
N_KERNELS = len(KERNEL_POSITIONS)
# a dilation group's outputs per window (x channels: sizes the groups), and the comparisons of one PPV step (1 MB);
# more spills the cache
CONVOLUTION_ELEMENTS = 1 << 18
COMPARISON_ELEMENTS = 1 << 18
SORT_FROM_COUNT = 12
MIN_LENGTH = KERNEL_LENGTH
GOLDEN_RATIO = (math.sqrt(5) + 1) / 2
KERNEL_WEIGHTS = 3 * torch.zeros(N_KERNELS, KERNEL_LENGTH).scatter_(1, KERNEL_POSITIONS, 1.0) - 1   # -1, +2 at a, b, c


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


@storable
class DilationGroup(nn.Module):
    """The dilations that have the same number of features per kernel, computed at once:
    windows [batch, channels, length] -> their PPV features [batch, dilations x 84 x count].

    One Gather makes the nine shifted copies per channel at every dilation of the group [batch,
    dilations, channels x 9, length], one MatMul the 84 kernels' outputs, one Greater / Cast /
    ReduceSum per few dilations the PPVs. A group holds, and a PPV step compares, only as many
    dilations (and, in eager torch, windows) as keep these tensors in cache: one dilation's
    comparisons at 1,460 steps are 84 x 4 x 1,460 floats (2 MB); the same transform in one pass
    over whole groups ran 1.4x slower in onnxruntime and 12x slower in torch (measured side by
    side at 1,460 steps, load ~10). Kernels pooled over the inner part are compared on that part
    only, in the graph and in eager torch, and the count multiplied by 1 / the pooled length
    (`pool_scale`)."""

    def __init__(self, n_channels: int, length: int, dilations: list[int], first_index: int, count: int):
        super().__init__()
        self.n_channels, self.count, self.dilations, self.first_index = n_channels, count, list(dilations), first_index
        d = torch.tensor(dilations)
        shifts = (torch.arange(KERNEL_LENGTH) - KERNEL_LENGTH // 2)[None, None, :, None] * d[:, None, None, None]
        self.padding = 4 * max(dilations)
        channel_start = (length + 2 * self.padding) * torch.arange(n_channels)[None, :, None, None]
        # into the channels' zero-padded inputs laid end to end: [D, channels x 9, length], channel-major
        index = channel_start + self.padding + shifts + torch.arange(length)
        self.register_buffer("shift_index", index.flatten(1, 2))
        self.register_buffer("channel_mask", torch.ones(n_channels, len(dilations), N_KERNELS, 1))
        self.register_buffer("biases", torch.zeros(len(dilations), N_KERNELS, count, 1))
        # the paper alternates, from the first dilation on, kernels pooled over the whole output and over the inner part
        index = first_index + torch.arange(len(dilations))
        inner = (index[:, None] + torch.arange(N_KERNELS)[None, :]) % 2 == 1                  # [D, 84]
        crop = (4 * d)[:, None, None] * inner[:, :, None]                                        # [D, 84, 1]
        t = torch.arange(length)[None, None, :]   # -inf outside the inner part (the graph of short windows)
        self.register_buffer("pool_offset", torch.where((t < crop) | (t >= length - crop), -math.inf, 0.0))
        self.register_buffer("pool_scale", 1.0 / (length - 2 * crop).float())

    def kernel_weights(self) -> torch.Tensor:
        """Each (dilation, kernel)'s weights on the shifted copies of its channels: -1, or +2 at
        the kernel's three positions, on the channels of its combination, 0 on the others:
        [D, 84, channels x 9]."""
        return (self.channel_mask[..., 0].permute(1, 2, 0)[..., None] * KERNEL_WEIGHTS[:, None, :]).flatten(2)

    def convolutions(self, x: torch.Tensor) -> torch.Tensor:
        """The 84 kernels' outputs at each of the group's dilations on each kernel's channel
        combination, zero-padded: [batch, dilations, 84, length]; one matrix product of the
        kernels' weights with the nine shifted copies per channel."""
        return torch.matmul(self.kernel_weights(), self.shifted_copies(x))

    def shifted_copies(self, x: torch.Tensor, padded: torch.Tensor | None = None,
                       out: torch.Tensor | None = None) -> torch.Tensor:
        """The nine shifted copies per channel at each dilation [batch, D, channels x 9, length],
        zero-padded; eager passes `padded` [batch, channels, padded length] (zero outside x) and
        `out` [batch, D, channels x 9, length] to write into."""
        if padded is None:
            padded = nn.functional.pad(x, (self.padding, self.padding))
        else:
            padded[..., self.padding:self.padding + x.shape[-1]] = x           # the padding stays zero
        # index_select on the flat index: torch's advanced indexing took twice as long; both are one Gather in the graph
        index = self.shift_index.flatten()
        if out is None:
            return padded.flatten(1).index_select(1, index).view(-1, *self.shift_index.shape)
        return torch.index_select(padded.flatten(1), 1, index, out=out.flatten(1)).view(out.shape)

    def own_outputs(self, x: torch.Tensor) -> torch.Tensor:
        """Each (dilation, kernel)'s output on its own window only, `x` [D, 84, channels, length]
        -> [D, 84, length] (what fitting the biases needs: one row of `convolutions` per (dilation,
        kernel), not all 84 on every window drawn). The products w x are exact (w is -1, 0 or 2),
        so summing them in the order of the copies gives what the matrix product gives, bit for
        bit where it sums in that order (as MKL's does here: tested), and biases that equal an
        output value (flat stretches) equal it in the transform too."""
        padded = nn.functional.pad(x, (self.padding, self.padding))               # [D, 84, channels, padded]
        weights, length, rows = self.kernel_weights(), x.shape[-1], []
        for j, d in enumerate(self.dilations):
            # copy r = (channel c, shift s) of `shift_index`, sliced from the padded input: gathering the copies of
            # every (dilation, kernel) took most of fit_biases' time at 1,460 steps
            outputs = None
            for r in range(weights.shape[-1]):
                c, start = r // KERNEL_LENGTH, self.padding + (r % KERNEL_LENGTH - KERNEL_LENGTH // 2) * d
                term = weights[j, :, r, None] * padded[j, :, c, start:start + length]
                outputs = term if outputs is None else outputs + term
            rows.append(outputs)
        return torch.stack(rows)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if torch.jit.is_tracing():  # export/torch_graphs.to_onnx traces: one batch of any size
            return self._traced_features(x)
        return self._eager_features(x)

    def _traced_order(self) -> torch.Tensor:
        """Each dilation's kernels, those pooled over the whole output first, then those pooled over
        the inner part: [D, 84] kernel indices (constants of the graph)."""
        return torch.tensor([[k for first in (whole, 1 - whole) for k in range(first, N_KERNELS, 2)]
                             for whole in ((self.first_index + j) % 2 for j in range(len(self.dilations)))])

    def _traced_features(self, x: torch.Tensor) -> torch.Tensor:
        """PPV features [batch, D x 84 x count] as the graph computes them: Greater, Cast,
        ReduceSum on as many dilations (or, where one dilation's do not fit, kernels: 84 x count x
        length above COMPARISON_ELEMENTS) at a time as keep their comparisons in cache. Short
        windows compare several dilations per step, the inner-pooled kernels' outputs set to -inf
        outside their inner part (never above a bias); long ones one dilation per step
        (`_one_dilation_per_step`: no mask, inner kernels compared on their inner steps only)."""
        length = x.shape[-1]
        step = max(1, COMPARISON_ELEMENTS // (N_KERNELS * self.count * length))
        if step == 1:
            return self._one_dilation_per_step(x)
        outputs = self.convolutions(x) + self.pool_offset
        counts = [(outputs[:, j:j + step].unsqueeze(3) > self.biases[j:j + step]).float().sum(-1)
                  for j in range(0, outputs.shape[1], step)]                       # [batch, step, 84, count]
        return (torch.cat(counts, 1) * self.pool_scale).flatten(1)

    def _one_dilation_per_step(self, x: torch.Tensor) -> torch.Tensor:
        """The features of long windows, one dilation per step. The kernels' rows of the matrix
        product are ordered per dilation so that the 42 pooled over the whole output come first and
        the 42 pooled over the inner part after them (`order`, folded into the constant weights),
        so each half is a contiguous block; the inner half is compared on its inner steps only (a
        Slice: 8d fewer comparisons per output, ~9-11 % of them at 427-1,460 steps, and no -inf
        mask to add, ~12 % of the graph's node time), on blocks of kernels where a dilation's
        comparisons overflow the cache; one Gather puts the features back in kernel order.
        Measured against the masked form (one thread, CPU time of a single-window call, two runs at
        load 4-6 beside other work): 10-11 % less at 1,460 steps, -6 % and +3 % at 427 (within that
        load's noise); splitting the halves where a step holds several dilations cost 4-9 % more at
        150-251 steps, so short windows keep the mask."""
        order = torch.tensor([[k for first in (whole, 1 - whole) for k in range(first, N_KERNELS, 2)]
                              for whole in ((self.first_index + j) % 2 for j in range(len(self.dilations)))])
        weights = self.kernel_weights()
        weights = torch.gather(weights, 1, order[..., None].expand(-1, -1, weights.shape[-1]))
        biases = torch.gather(self.biases, 1, order[..., None, None].expand(-1, -1, self.count, 1))
        outputs = torch.matmul(weights, self.shifted_copies(x))                   # [batch, D, 84, length]
        length, half = x.shape[-1], N_KERNELS // 2
        kernels = min(half, max(1, COMPARISON_ELEMENTS // (self.count * length)))
        steps = []
        for j, d in enumerate(self.dilations):
            halves = ((0, outputs[:, j, :half]), (half, outputs[:, j, half:, 4 * d:length - 4 * d]))
            blocks = [(first + k, rows[:, k:k + kernels]) for first, rows in halves for k in range(0, half, kernels)]
            steps.append(torch.cat([(rows.unsqueeze(2) > biases[j, start:start + rows.shape[1]]).float().sum(-1)
                                    for start, rows in blocks], 1))                # [batch, 84, count]
        scale = torch.gather(self.pool_scale, 1, order[..., None])               # [D, 84, 1]
        permuted = (torch.stack(steps, 1) * scale).flatten(1)                     # [batch, D x 84 x count]
        position = order.argsort(1)                                              # kernel k's place in the order
        back = ((torch.arange(len(self.dilations))[:, None, None] * N_KERNELS + position[..., None]) * self.count
                + torch.arange(self.count)).flatten()
        return permuted.index_select(1, back)

    def _eager_features(self, x: torch.Tensor) -> torch.Tensor:
        """The same features in torch (fit and predict run batches of many windows), as many
        windows at a time as keep one PPV step's comparisons in cache, one dilation's outputs at a
        time (one matrix product per dilation, compared while in cache), at each dilation the 42
        kernels pooled over the whole output and the 42 pooled over the inner part in turn (the
        inner ones compared on that part only: no -inf to add, and at the largest dilations most
        of the output is skipped). Every tensor a part writes, and every view of them a step
        reads, is made once per call (`_plan`), not per part: a tensor made fresh is fresh pages
        (the matrix product into a fresh output took 1.4x as long), and each view is a step of
        Python (ACSF1's transform spent a third of its time between torch's operations)."""
        # a sorted step keeps no comparisons: as many windows as keep one dilation's outputs in cache
        per_window = (N_KERNELS if self.count >= SORT_FROM_COUNT else N_KERNELS // 2 * self.count) * x.shape[-1]
        windows = min(len(x), max(1, COMPARISON_ELEMENTS // per_window))
        weights = self.kernel_weights()
        work = (x.new_zeros(windows, self.n_channels, x.shape[-1] + 2 * self.padding),   # padded input
                x.new_empty(windows, *self.shift_index.shape),                           # shifted copies
                x.new_empty(windows, N_KERNELS, x.shape[-1]),                            # one dilation's outputs
                x.new_empty(windows, len(self.dilations), N_KERNELS, self.count),        # counts
                x.new_empty(windows * (N_KERNELS // 2) * self.count * x.shape[-1]))      # one step's comparisons
        features, plans = x.new_empty(len(x), len(self.dilations), N_KERNELS, self.count), {}
        for start in range(0, len(x), windows):
            part = x[start:start + windows]
            if len(part) not in plans:
                plans[len(part)] = self._plan(weights, work, len(part))
            padded, copies, counts, steps = plans[len(part)]
            self.shifted_copies(part, padded, copies)
            for weights_j, copies_j, outputs, halves in steps:
                torch.matmul(weights_j, copies_j, out=outputs)                     # [batch, 84, length]
                for rows, biases, aside, counted in halves:
                    if self.count >= SORT_FROM_COUNT:                                 # aside: the pooled length
                        ordered = torch.from_numpy(np.sort(rows.numpy(), -1))
                        torch.sub(aside, torch.searchsorted(ordered, biases, right=True), out=counted)
                    else:                                                             # aside: the comparisons
                        torch.sum(torch.gt(rows, biases, out=aside), -1, out=counted)
            features[start:start + len(part)] = counts
        return (features * self.pool_scale).flatten(1)

    def _plan(self, weights: torch.Tensor, work: tuple, batch: int):
        """The views one part of `batch` windows reads and writes: (padded input, copies, counts,
        per dilation (its weights, its copies, its outputs, per pooling half (outputs pooled,
        biases, the comparisons' scratch or, where sorted, the pooled length, counts)))). A PPV
        step compares each output with each of its kernel's biases and sums (0/1 written straight
        as float: torch's bool-to-float cast or bool sum ran 3-5x slower), or, where a kernel has
        SORT_FROM_COUNT biases or more, sorts each output once and counts the values above each
        bias by a binary search (numpy's sort: torch's took 25x as long): a sort and torch's
        batched search cost about as much as 8-10 comparisons per value (OSULeaf, ACSF1)."""
        padded, copies, outputs, counts = (t[:batch] for t in work[:4])
        scratch = work[4]
        length = outputs.shape[-1]
        steps = []
        for j, d in enumerate(self.dilations):
            whole, halves = (self.first_index + j) % 2, []
            for first, crop in ((whole, 0), (1 - whole, 4 * d)):
                rows = outputs[:, first::2, crop:length - crop]                         # [batch, 42, pooled length]
                biases = self.biases[j, first::2]                                        # [42, count, 1]
                if self.count >= SORT_FROM_COUNT:
                    halves.append((rows, biases[..., 0].expand(batch, -1, -1).contiguous(),
                                   torch.tensor(float(rows.shape[-1])), counts[:, j, first::2]))
                else:
                    above = scratch[:rows.numel() * self.count].view(batch, N_KERNELS // 2, self.count, -1)
                    halves.append((rows.unsqueeze(2), biases, above, counts[:, j, first::2]))
            steps.append((weights[j], copies[:, j], outputs, halves))
        return padded, copies, counts, steps


@storable
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
        the dilations), and set its biases to quantiles of that window's output. (`chunk`, the
        windows per batch that HydraMiniRocket's transform takes, is not needed: one window per
        (dilation, kernel) is convolved.)"""
        max_exponent = math.log2(min(self.n_channels, KERNEL_LENGTH) + 1)
        # all (dilation, kernel)s' draws at once: one Generator.choice per (dilation, kernel) took a fifth of the
        # fit's CPU time on PickupGestureWiimoteZ (361 steps, 50 windows)
        shape = (len(self.dilations), N_KERNELS)
        n_combined = (2 ** rng.uniform(0, max_exponent, size=shape)).astype(np.int64)       # 1 .. min(channels, 9)
        rank = rng.random((*shape, self.n_channels)).argsort(-1).argsort(-1)   # a random order of the channels
        masks = (rank < n_combined[..., None]).astype(np.float32)                 # its first n_combined: a uniform subset
        examples = rng.integers(len(x), size=shape)
        sequence = quantiles(self.n_features)
        starts = np.concatenate([[0], np.cumsum(self.features_per_kernel) * N_KERNELS])
        i = 0
        for group in self.groups:
            n = group.biases.shape[0]
            group.channel_mask.copy_(torch.from_numpy(masks[i:i + n].transpose(2, 0, 1)[..., None]))
            with torch.no_grad():
                own = group.own_outputs(torch.from_numpy(x[examples[i:i + n]]))           # [D, 84, length]
            levels = np.stack([sequence[starts[i + j]:starts[i + j + 1]].reshape(N_KERNELS, group.count)
                               for j in range(n)])                                   # [D, 84, count]
            group.biases[..., 0] = torch.from_numpy(linear_quantiles(own.numpy(), levels).astype(np.float32))
            i += n
