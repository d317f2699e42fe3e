"""The ROCKET-family classifier behind the estimator contract: a random-kernel transform
(`member`: MiniRocket, models/rocket/minirocket.py, or Hydra + MiniRocket, models/rocket/hydra.py;
models/rocket/mixture.py mixes members, each a head on its columns of one transform),
its features standardised (Hydra's by its own sparse scaler), and a linear head.

Heads, as the papers advise: up to `ridge_max_samples` training windows, ridge regression onto
+-1 class indicators with the penalty chosen by efficient leave-one-out (models/rocket/ridge_loo.py);
beyond, where the n x n Gram matrix grows too costly, multinomial logistic regression (L2, lbfgs).
On recordings sets a window is a recording (one window each), so the switch is by recordings.
Ridge scores are not probabilities: they are turned into ones by a softmax at one temperature,
chosen to minimise the log loss of the leave-one-out scores (no window is scored by a fit that
saw it). The standardisation, the head and the temperature fold into one linear layer of the
module, so the eager pipeline and the exported graph compute the same map.

Held-out predictions on the training windows (`out_of_fold_proba_`, what the default model's
choice scores a candidate on when it trains on every training recording, models/validation_choice.py):
the ridge head's exact leave-one-out scores through the same softmax, free with the fit, when every
window is its own recording; otherwise (the logistic head, or windows that share a recording: `groups`)
the head refitted on `n_folds` stratified folds by recording (the transform and its scaling are the
full fit's: they see no label). `out_of_fold_method_` says which.

Each channel is standardised with the training windows' statistics first (as the networks do),
so that channels of different scales weigh alike in a kernel's channel combination.
Deterministic under `seed`; no epochs: `fit` never calls the epoch callback.
"""
import logging

import numpy as np
import torch
from scipy.optimize import minimize_scalar
from scipy.special import log_softmax
from sklearn.linear_model import LogisticRegression

from common.errors import InputError
from common.standardise import mean_and_scale
from data.splits.indices import stratified_folds
from models.capabilities import declare
from models.estimator_base import TouchstoneClassifier
from models.rocket.hydra import HydraMiniRocket
from models.rocket.minirocket import MIN_LENGTH, N_KERNELS, MiniRocket
from models.rocket.ridge_loo import class_indicators, ridge_loo

log = logging.getLogger(__name__)
HEADS = ("auto", "ridge", "logistic")
MEMBERS = ("minirocket", "hydra_minirocket")   # models/rocket/minirocket.py, models/rocket/hydra.py
WORK_ELEMENTS = 8_000_000   # elements of a transform batch's largest tensor (32 MB): bounds the memory a batch takes
MAX_TEMPERATURE = 10.0     # ridge scores are about +-1: at most a logit gap of ~20 where leave-one-out never errs (log loss -> 0 as t grows)


class RocketClassifier(TouchstoneClassifier):
    def __init__(self, n_features=10_000, head="auto", ridge_max_samples=2_000, logistic_c=1.0,
                 logistic_max_iter=1_000, seed=0, member="minirocket", n_folds=3):
        self.n_features = n_features
        self.head = head
        self.ridge_max_samples = ridge_max_samples
        self.logistic_c = logistic_c
        self.logistic_max_iter = logistic_max_iter
        self.seed = seed
        self.member = member
        self.n_folds = n_folds

    def __sklearn_tags__(self):
        tags = declare(super().__sklearn_tags__(), holds_out_training=True, reads_windows=True, named_by="network",
                       size="n_parameters")
        tags.input_tags.two_d_array, tags.input_tags.three_d_array = False, True   # windows (n, channels, steps)
        return tags

    def _checked(self, X) -> np.ndarray:
        X = np.asarray(X, dtype=np.float64)
        if X.ndim != 3:
            raise InputError(f"ROCKET classifiers need windows of shape (n, channels, length), got {X.shape}")
        if X.shape[2] < MIN_LENGTH:
            raise InputError(f"ROCKET classifiers need windows of at least {MIN_LENGTH} steps (the kernel length), "
                             f"got {X.shape[2]}")
        if not np.isfinite(X).all():
            raise InputError("ROCKET classifiers need finite windows; got NaN or infinite values")
        return X

    def _scaled(self, X) -> np.ndarray:
        return ((self._checked(X) - self.channel_mean_) / self.channel_std_).astype(np.float32)

    def _chunk(self, shape) -> int:
        """Windows per transform batch: a dilation group's largest tensor is windows x dilations x
        84 x (biases per kernel, or channels) x length."""
        most = max(g.biases.shape[0] * max(g.count, shape[1]) for g in self.module_.groups)
        return max(1, WORK_ELEMENTS // (most * N_KERNELS * shape[2]))

    def _features(self, X: np.ndarray) -> np.ndarray:
        step = self._chunk(X.shape)
        with torch.no_grad():
            return torch.cat([self.module_.transform(torch.from_numpy(X[s:s + step]))
                              for s in range(0, len(X), step)]).numpy().astype(np.float64)

    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        """`groups`: the recording of each training window (held-out predictions keep a recording's
        windows together); None: every window is its own recording."""
        if self.head not in HEADS:
            raise InputError(f"model.head must be one of {', '.join(HEADS)}, got {self.head!r}")
        if self.member not in MEMBERS:
            raise InputError(f"model.member must be one of {', '.join(MEMBERS)}, got {self.member!r}")
        if self.n_features < N_KERNELS:
            raise InputError(f"model.n_features must be at least {N_KERNELS} (one per kernel), got {self.n_features}")
        X, y = self._checked(X), np.asarray(y, dtype=np.int64)
        if len(X) < 2:
            raise InputError(f"ROCKET classifiers need at least 2 training windows, got {len(X)}")
        n_classes = int(max(y.max(), np.max(y_val) if y_val is not None and len(y_val) else 0)) + 1
        self.classes_ = np.arange(n_classes)
        self.channel_mean_, self.channel_std_ = mean_and_scale(X, axis=(0, 2), keepdims=True)
        X = self._scaled(X)
        rng = np.random.default_rng(self.seed)
        self.module_ = self._new_module(X.shape[1], X.shape[2], n_classes)
        self.module_.fit_biases(X, rng, self._chunk(X.shape))
        features = self._features(X)
        feature_mean, feature_scale = mean_and_scale(features)
        prescaled = getattr(self.module_, "prescaled_from", features.shape[1])   # Hydra's columns: sparse-scaled already
        feature_mean[prescaled:], feature_scale[prescaled:] = 0.0, 1.0
        Z = (features - feature_mean) / feature_scale
        self.head_ = self.head if self.head != "auto" else ("ridge" if len(X) <= self.ridge_max_samples else "logistic")
        weights, intercept, self.out_of_fold_proba_, self.out_of_fold_method_ = self._fitted_head(Z, y, n_classes, groups)
        with torch.no_grad():  # standardisation and head folded: logits = features @ W' + b'
            folded = weights / feature_scale[:, None]
            self.module_.head.weight.copy_(torch.from_numpy(folded.T.astype(np.float32)))
            self.module_.head.bias.copy_(torch.from_numpy((intercept - feature_mean @ folded).astype(np.float32)))
        self.n_features_in_ = X.shape[1]
        return self

    def _new_module(self, n_channels: int, length: int, n_classes: int):
        """The transform and its (not yet fitted) linear head, of the member asked for."""
        if self.member == "minirocket":
            return MiniRocket(n_channels, length, self.n_features, n_classes)
        return HydraMiniRocket(n_channels, length, self.n_features, n_classes, self.seed)

    def _fitted_head(self, Z, y, n_classes, groups):
        """(weights, intercept) of the head on standardised features Z, giving the module's head
        outputs, and the held-out probabilities of the training windows with how they were held out."""
        weights, intercept, loo_logits = self._head(Z, y, n_classes, report=True)
        return weights, intercept, *self._held_out(Z, y, n_classes, loo_logits, groups)

    def _head(self, Z, y, n_classes, report=False):
        """(weights, intercept) giving logits, and the leave-one-out logits (ridge) or None."""
        if self.head_ == "logistic":
            return (*self._logistic(Z, y, n_classes), None)
        fit = ridge_loo(Z, class_indicators(y, n_classes))
        picked = np.arange(len(y)), y
        result = minimize_scalar(lambda t: -log_softmax(t * fit.loo_predictions, axis=1)[picked].mean(),
                                 bounds=(1e-2, MAX_TEMPERATURE), method="bounded")
        temperature = float(result.x)
        if report:
            self.alpha_, self.temperature_ = fit.alpha, temperature
            log.info("ridge head: alpha %.3g by leave-one-out, softmax temperature %.3g", fit.alpha, temperature)
        return fit.coef * temperature, fit.intercept * temperature, fit.loo_predictions * temperature

    def _held_out(self, Z, y, n_classes, loo_logits, groups) -> tuple[np.ndarray, str]:
        """(each training window's probabilities from a head fitted without its recording, how)."""
        groups = np.arange(len(y)) if groups is None else np.asarray(groups)
        if len(groups) != len(y):
            raise InputError(f"{len(groups)} recording ids for {len(y)} training windows")
        if loo_logits is not None and np.unique(groups).size == len(y):
            return np.exp(log_softmax(loo_logits, axis=1)), "leave-one-out"
        logits = np.zeros((len(y), n_classes))
        folds = stratified_folds(y, groups, self.n_folds, self.seed)
        for fit_rows, held_rows in folds:
            weights, intercept, _ = self._head(Z[fit_rows], y[fit_rows], n_classes)
            logits[held_rows] = Z[held_rows] @ weights + intercept
        return np.exp(log_softmax(logits, axis=1)), f"{len(folds)} stratified folds"

    def _logistic(self, Z, y, n_classes):
        model = LogisticRegression(C=self.logistic_c, max_iter=self.logistic_max_iter).fit(Z, y)
        weights, intercept = np.zeros((Z.shape[1], n_classes)), np.zeros(n_classes)
        seen = model.classes_
        if len(seen) == 2:  # one score column z for the second class: logits (-z/2, z/2) give sigmoid(z)
            weights[:, seen[0]], weights[:, seen[1]] = -model.coef_[0] / 2, model.coef_[0] / 2
            intercept[seen[0]], intercept[seen[1]] = -model.intercept_[0] / 2, model.intercept_[0] / 2
        else:
            weights[:, seen] = model.coef_.T
            intercept[seen] = model.intercept_
        unseen = np.setdiff1d(np.arange(n_classes), seen)
        intercept[unseen] = -1e4     # a class no training window has: never predicted (log-probability -1e4)
        return weights, intercept

    def transform(self, X) -> np.ndarray:
        """The PPV features of windows (before standardisation)."""
        return self._features(self._scaled(X))

    def predict_proba(self, X):
        X = self._scaled(X)
        step = self._chunk(X.shape)
        with torch.no_grad():
            logits = torch.cat([self.module_(torch.from_numpy(X[s:s + step])) for s in range(0, len(X), step)])
        return torch.softmax(logits, dim=1).numpy()

    def predict(self, X):
        return self.predict_proba(X).argmax(axis=1)

    @property
    def n_parameters_(self) -> int:
        """Learned numbers: the biases and the folded head (the kernels are fixed, the channel
        combinations drawn)."""
        return int(sum(b.numel() for name, b in self.module_.named_buffers() if name.rsplit(".", 1)[-1] == "biases")
                   + sum(p.numel() for p in self.module_.head.parameters()))
