"""The seed's residual MLP (models/nets/resmlp.py) behind the estimator contract.

Training: Adam (lr 1e-3) on MSE + l1 * sum|W| + l2 * sum W^2 over the Linear weights (Keras-style
kernel regularisers, as in the seed), learning rate halved when validation loss plateaus,
early stopping on validation loss (`early_stopping_patience: null` trains every epoch) with the
best weights restored. A plain PyTorch loop, deterministic under `seed`. Inputs and targets are
standardised inside `fit` with the training rows' statistics (so GaussianNoise(0.02) means 2 % of
a feature's spread whatever its scale: on inputs of scale 1e-6 it would otherwise drown the
signal) and predictions come back in the units of y.
"""
import copy
import math

import numpy as np
import torch
from sklearn.utils.validation import check_is_fitted, validate_data
from torch import nn

from common.errors import InputError
from common.progress import progress
from data.splits.indices import carve_validation
from models.capabilities import declare
from models.estimator_base import TouchstoneRegressor
from models.nets.resmlp import ResMLP
from models.distributed import TrainingGroup, rank_seed
from common.standardise import mean_and_scale
from models.torch_runtime import count_parameters, flush_denormals, resolve_device


class ResMLPRegressor(TouchstoneRegressor):
    def __init__(self, widths=(256, 128, 96, 64), dropouts=(0.40, 0.35, 0.30, 0.25), noise_std=0.02,
                 lr=1e-3, l1=1e-5, l2=1e-4, batch_size=32, max_epochs=300, early_stopping_patience=30,
                 lr_plateau_patience=10, lr_factor=0.5, val_fraction=0.15, device="cpu", seed=0,
                 progress=True):
        self.widths = widths
        self.dropouts = dropouts
        self.noise_std = noise_std
        self.lr = lr
        self.l1 = l1
        self.l2 = l2
        self.batch_size = batch_size
        self.max_epochs = max_epochs
        self.early_stopping_patience = early_stopping_patience
        self.lr_plateau_patience = lr_plateau_patience
        self.lr_factor = lr_factor
        self.val_fraction = val_fraction
        self.device = device
        self.seed = seed
        self.progress = progress

    def __sklearn_tags__(self):
        tags = declare(super().__sklearn_tags__(), size="n_parameters")
        tags.target_tags.multi_output = True
        tags.non_deterministic = self.device != "cpu"
        return tags

    # -- helpers ----------------------------------------------------------------------------
    def _tensor(self, a):
        return torch.as_tensor(np.asarray(a, dtype=np.float32), device=self.device_)

    def _inputs(self, X):
        return self._tensor((np.asarray(X, dtype=np.float64) - self.feature_mean_) / self.feature_scale_)

    def _penalty(self):
        weights = [m.weight for m in self.module_.modules() if isinstance(m, nn.Linear)]
        return (self.l1 * sum(w.abs().sum() for w in weights)
                + self.l2 * sum((w * w).sum() for w in weights))

    def _mse(self, X, y):
        self.module_.eval()
        with torch.no_grad():
            return float(torch.mean((self.module_(X) - y) ** 2))

    # -- contract ---------------------------------------------------------------------------
    @flush_denormals()
    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        group = TrainingGroup()  # this process's part when several train the net (models/distributed.py)
        torch.manual_seed(self.seed)
        X, y = validate_data(self, X, y, multi_output=True, y_numeric=True, dtype=np.float64)
        self.single_output_ = y.ndim == 1
        y = y.reshape(len(X), -1)
        if len(X) < 2:
            raise InputError(f"resmlp needs at least 2 samples to train and early-stop, got {len(X)} sample")
        if X_val is None:  # no validation split given: carve one (grouped, seeded) for early stopping
            fit_rows, val_rows = carve_validation(len(X), self.val_fraction, self.seed, groups)
            X, y, X_val, y_val = X[fit_rows], y[fit_rows], X[val_rows], y[val_rows]
        X_val = np.asarray(X_val, dtype=np.float64)
        y_val = np.asarray(y_val, dtype=np.float64).reshape(len(X_val), -1)

        self.device_ = group.device(resolve_device(self.device))
        self.feature_mean_, self.feature_scale_ = mean_and_scale(X)
        self.target_mean_, self.target_scale_ = mean_and_scale(y)
        if not (np.isfinite(self.feature_scale_).all() and np.isfinite(self.target_scale_).all()):
            raise InputError("resmlp: inputs or targets are too large to standardise (overflow); rescale them")
        self.module_ = ResMLP(X.shape[1], y.shape[1], tuple(self.widths), tuple(self.dropouts),
                              self.noise_std).to(self.device_)
        trained = group.prepare(self.module_)
        if group.rank:  # rank 0 continues the run's seed stream, so one process trains as it always did
            torch.manual_seed(rank_seed(self.seed, group.rank))
        Xt, yt = self._inputs(X), self._tensor((y - self.target_mean_) / self.target_scale_)
        Xv, yv = self._inputs(X_val), self._tensor((y_val - self.target_mean_) / self.target_scale_)

        optimiser = torch.optim.Adam(self.module_.parameters(), lr=self.lr)
        plateau = torch.optim.lr_scheduler.ReduceLROnPlateau(
            optimiser, factor=self.lr_factor, patience=self.lr_plateau_patience)
        generator = torch.Generator().manual_seed(self.seed)
        best_loss, best_state, waited = math.inf, None, 0
        self.history_ = []
        self.step_losses_ = []  # the global batch's loss (with the weight penalty) at every optimiser step
        bar = progress(range(self.max_epochs), desc="resmlp", unit="epochs", enabled=self.progress and group.is_writer)
        for epoch in bar:
            self.module_.train()
            order = torch.randperm(len(Xt), generator=generator).to(self.device_)
            step_sums, step_sizes = [], []
            for start in range(0, len(order), self.batch_size):
                batch = order[start:start + self.batch_size]
                if len(batch) < group.smallest_batch():  # BatchNorm cannot normalise a batch of one in training
                    continue
                mine = group.shard(batch)
                loss = (torch.mean((trained(Xt[mine]) - yt[mine]) ** 2) * group.share(len(mine), len(batch))
                        + self._penalty())
                optimiser.zero_grad()
                loss.backward()
                optimiser.step()
                step_sums.append(loss.item() * len(batch) / group.size)
                step_sizes.append(len(batch))
            step_sums = group.totals(step_sums)
            self.step_losses_ += [s / n for s, n in zip(step_sums, step_sizes)]
            train_loss = sum(step_sums) / max(sum(step_sizes), 1)
            val_loss = group.agree(self._mse(Xv, yv))  # every rank validates; all act on rank 0's number
            if not (math.isfinite(train_loss) and math.isfinite(val_loss)):
                raise InputError(f"resmlp: training diverged at epoch {epoch + 1} (loss is "
                                 f"{train_loss if not math.isfinite(train_loss) else val_loss}); "
                                 "check the inputs' scale or lower model.lr")
            lr = optimiser.param_groups[0]["lr"]
            record = {"epoch": epoch + 1, "train_loss": train_loss, "val_loss": val_loss, "lr": lr}
            self.history_.append(record)
            if epoch_callback is not None:
                epoch_callback(record)
            bar.set_postfix(train=f"{train_loss:.4f}", val=f"{val_loss:.4f}", lr=f"{lr:.1e}")
            plateau.step(val_loss)
            if val_loss < best_loss:
                best_loss, waited = val_loss, 0
                best_state = copy.deepcopy(self.module_.state_dict())
            else:
                waited += 1
                if self.early_stopping_patience is not None and waited >= self.early_stopping_patience:
                    break
        bar.close()
        group.release(self.module_)
        self.module_.load_state_dict(best_state)
        self.module_.eval()
        self.best_val_loss_ = best_loss
        self.n_epochs_ = len(self.history_)
        return self

    def predict(self, X):
        check_is_fitted(self, "module_")
        X = validate_data(self, X, reset=False, dtype=np.float64)
        self.module_.eval()
        with torch.no_grad():
            out = self.module_(self._inputs(X)).cpu().numpy().astype(np.float64)
        out = out * self.target_scale_ + self.target_mean_
        return out[:, 0] if self.single_output_ else out

    @property
    def n_parameters_(self) -> int:
        return count_parameters(self.module_)
