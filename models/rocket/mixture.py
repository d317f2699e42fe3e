"""A validation-weighted mixture of ROCKET-family members as one classifier and one module:
MiniRocket, Hydra and Hydra + MiniRocket (aeon's MultiRocket-Hydra with MiniRocket's features
in MultiRocket's place; MultiRocket is not written here), each a linear head on its own columns of
one Hydra + MiniRocket transform (models/rocket/hydra.py: MiniRocket's PPV features, then Hydra's
sparse-scaled counts), mixed by their held-out accuracy.

Fit: the transform once, then per member the head RocketClassifier fits (ridge with leave-one-out
penalty and softmax temperature, or logistic), on its columns, with its held-out probabilities of
the training windows. A member's weight is its held-out accuracy above the majority class's,
normalised (models/mixture_weights.py, the rule of the default model's ensemble); the mixture's
probabilities are the weighted sum of the members' softmaxes. The members' heads are one linear
layer (each reads zeros on the columns it does not use), so the eager pipeline and the exported
ONNX graph (export/converters/rocket_mixture.py) run one transform, one matrix product, a softmax
per member and the weighted sum: one graph.

Held-out predictions of the training windows (`out_of_fold_proba_`, what the default's choice
scores it on): each window's mixture of its members' held-out probabilities, with weights computed
from the other windows only (the accuracies and the majority class without that window), so the
weighting, too, never sees the window it scores.
"""
import numpy as np
import torch
from torch import nn

from common.errors import InputError
from models.mixture_weights import above_floor_weights
from models.rocket.classifier import RocketClassifier
from models.rocket.hydra import HydraMiniRocket
from models.storable import storable

MIXTURE_MEMBERS = ("minirocket", "hydra", "hydra_minirocket")   # which columns of the transform a head reads


@storable
class RocketMixtureModule(nn.Module):
    """windows [batch, channels, length] float32 (standardised) -> log of the mixture's class
    probabilities (a softmax of them gives the probabilities back), through the Hydra + MiniRocket
    transform and one linear layer holding every member's head."""

    def __init__(self, transform: HydraMiniRocket, n_members: int, n_classes: int):
        super().__init__()
        self.features = transform
        self.n_members, self.n_classes = int(n_members), int(n_classes)
        self.prescaled_from = transform.prescaled_from
        self.head = nn.Linear(transform.n_features, self.n_members * self.n_classes)
        self.register_buffer("member_weights", torch.full((self.n_members, 1), 1.0 / self.n_members))

    @property
    def groups(self):
        return self.features.groups

    def fit_biases(self, x: np.ndarray, rng: np.random.Generator, chunk: int) -> None:
        self.features.fit_biases(x, rng, chunk)

    def transform(self, x: torch.Tensor) -> torch.Tensor:
        return self.features.transform(x)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        logits = self.head(self.transform(x)).view(-1, self.n_members, self.n_classes)
        mixed = (torch.softmax(logits, dim=2) * self.member_weights).sum(1)
        return torch.log(mixed.clamp(min=1e-30))


class MixedRocketClassifier(RocketClassifier):
    member = "hydra_minirocket"   # the transform every member's columns come from

    def __init__(self, n_features=10_000, head="auto", ridge_max_samples=2_000, logistic_c=1.0,
                 logistic_max_iter=1_000, seed=0, n_folds=3, members=MIXTURE_MEMBERS):
        self.n_features = n_features
        self.head = head
        self.ridge_max_samples = ridge_max_samples
        self.logistic_c = logistic_c
        self.logistic_max_iter = logistic_max_iter
        self.seed = seed
        self.n_folds = n_folds
        self.members = members

    def _new_module(self, n_channels: int, length: int, n_classes: int):
        members = list(self.members)
        if len(members) < 2 or len(set(members)) != len(members) or not set(members) <= set(MIXTURE_MEMBERS):
            raise InputError(f"model.members must be two or more of {', '.join(MIXTURE_MEMBERS)}, got {self.members!r}")
        transform = HydraMiniRocket(n_channels, length, self.n_features, n_classes, self.seed)
        return RocketMixtureModule(transform, len(members), n_classes)

    def _columns(self, name: str, n_columns: int) -> slice:
        split = self.module_.prescaled_from
        return {"minirocket": slice(0, split), "hydra": slice(split, n_columns), "hydra_minirocket": slice(0, n_columns)}[name]

    def _fitted_head(self, Z, y, n_classes, groups):
        """Every member's head on its columns; weights by held-out accuracy above the majority's."""
        weights = np.zeros((Z.shape[1], len(self.members) * n_classes))
        intercept = np.zeros(len(self.members) * n_classes)
        held_out, methods = [], set()
        for m, name in enumerate(self.members):
            columns, outputs = self._columns(name, Z.shape[1]), slice(m * n_classes, (m + 1) * n_classes)
            w, b, proba, method = super()._fitted_head(Z[:, columns], y, n_classes, groups)
            weights[columns, outputs], intercept[outputs] = w, b
            held_out.append(proba)
            methods.add(method)
        held_out = np.stack(held_out, axis=1)                                       # [n, members, classes]
        right = (held_out.argmax(axis=2) == y[:, None]).astype(np.float64)          # [n, members]
        counts = np.bincount(y, minlength=n_classes).astype(np.float64)
        self.member_accuracy_ = dict(zip(self.members, right.mean(0).tolist()))
        self.member_weights_ = dict(zip(self.members, above_floor_weights(right.mean(0), counts.max() / len(y)).tolist()))
        with torch.no_grad():
            self.module_.member_weights.copy_(torch.tensor(list(self.member_weights_.values()))[:, None])
        # each window's weights from the other windows: their accuracies and their majority class
        others = len(y) - 1
        own_class = np.eye(n_classes)[y]
        floor = ((counts[None, :] - own_class).max(axis=1)) / others
        row_weights = above_floor_weights((right.sum(0)[None, :] - right) / others, floor)
        mixed = (held_out * row_weights[:, :, None]).sum(1)
        return weights, intercept, mixed, f"{' / '.join(sorted(methods))}, weights without the window"
