"""Time-series classifiers behind the estimator contract: any network + the paper's training.

Training as the seed paper: cross-entropy, mini-batches of 128, 40 epochs, SGD (momentum 0.9)
from lr 0.05 divided by 10 at epochs 5, 15 and 25; all configurable. The network is given as
a factory (Hydra `_partial_: true`) called at fit time with the data's shape:
network(n_channels=..., n_classes=..., length=..., modalities=...).
Deterministic under `seed` on CPU; `device=auto` uses a GPU when there is one. Each channel
is standardised inside `fit` with the training windows' statistics, so windows of any scale
(1e-6 or 1e6) train alike.
"""
import math
import time

import numpy as np
import torch
from sklearn.base import BaseEstimator, ClassifierMixin
from torch import nn
from data.progress import progress

from data.errors import InputError
from models.torch_runtime import count_parameters, flush_denormals, resolve_device


class TimeSeriesClassifier(BaseEstimator, ClassifierMixin):
    def __init__(self, network=None, modalities=None, lr=0.05, momentum=0.9, weight_decay=0.0,
                 milestones=(5, 15, 25), gamma=0.1, batch_size=128, max_epochs=40, device="cpu", seed=0,
                 progress=True):
        self.network = network
        self.modalities = modalities
        self.lr = lr
        self.momentum = momentum
        self.weight_decay = weight_decay
        self.milestones = milestones
        self.gamma = gamma
        self.batch_size = batch_size
        self.max_epochs = max_epochs
        self.device = device
        self.seed = seed
        self.progress = progress

    def _batches(self, X, size):
        for start in range(0, len(X), size):
            yield X[start:start + size]

    def _scaled(self, X) -> np.ndarray:
        return ((np.asarray(X, dtype=np.float64) - self.channel_mean_) / self.channel_std_).astype(np.float32)

    def _logits(self, X) -> torch.Tensor:
        self.module_.eval()
        with torch.no_grad():
            return torch.cat([self.module_(torch.as_tensor(b, device=self.device_)).float().cpu()
                              for b in self._batches(self._scaled(X), 512)])

    @flush_denormals()
    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None):
        torch.manual_seed(self.seed)
        X = np.asarray(X, dtype=np.float32)
        y = np.asarray(y, dtype=np.int64)
        if X.ndim != 3:
            raise InputError(f"time-series classifiers need windows of shape (n, channels, length), got {X.shape}")
        n_classes = int(max(y.max(), np.max(y_val) if y_val is not None else 0)) + 1
        self.channel_mean_ = X.astype(np.float64).mean(axis=(0, 2), keepdims=True)
        spread = X.astype(np.float64).std(axis=(0, 2), keepdims=True)
        self.channel_std_ = np.where(spread > 0, spread, 1.0)
        X = self._scaled(X)
        self.classes_ = np.arange(n_classes)
        self.device_ = resolve_device(self.device)
        self.module_ = self.network(n_channels=X.shape[1], n_classes=n_classes, length=X.shape[2],
                                    modalities=self.modalities).to(self.device_)
        optimiser = torch.optim.SGD(self.module_.parameters(), lr=self.lr, momentum=self.momentum,
                                    weight_decay=self.weight_decay)
        schedule = torch.optim.lr_scheduler.MultiStepLR(optimiser, milestones=list(self.milestones), gamma=self.gamma)
        loss_fn = nn.CrossEntropyLoss()
        generator = torch.Generator().manual_seed(self.seed)
        Xt, yt = torch.as_tensor(X), torch.as_tensor(y)
        self.history_ = []
        start = time.perf_counter()
        bar = progress(range(self.max_epochs), desc=type(self.module_).__name__, unit="epochs",
                       enabled=self.progress)
        for epoch in bar:
            self.module_.train()
            order = torch.randperm(len(Xt), generator=generator)
            total, correct, seen = 0.0, 0, 0
            for batch in self._batches(order, self.batch_size):
                if len(batch) < 2:  # BatchNorm cannot normalise a batch of one
                    continue
                xb, yb = Xt[batch].to(self.device_), yt[batch].to(self.device_)
                logits = self.module_(xb)
                loss = loss_fn(logits, yb)
                optimiser.zero_grad()
                loss.backward()
                optimiser.step()
                total += loss.item() * len(batch)
                correct += int((logits.argmax(1) == yb).sum())
                seen += len(batch)
            if not math.isfinite(total):
                raise InputError(f"{type(self.module_).__name__}: training diverged at epoch {epoch + 1} "
                                 "(loss is not finite); lower model.lr")
            record = {"epoch": epoch + 1, "train_loss": total / max(seen, 1), "train_accuracy": correct / max(seen, 1),
                      "lr": optimiser.param_groups[0]["lr"], "elapsed_s": time.perf_counter() - start}
            if X_val is not None:
                logits = self._logits(X_val)
                record["val_loss"] = float(loss_fn(logits, torch.as_tensor(np.asarray(y_val, dtype=np.int64))))
                record["val_accuracy"] = float((logits.argmax(1).numpy() == np.asarray(y_val)).mean())
            self.history_.append(record)
            if epoch_callback is not None:
                epoch_callback(record)
            bar.set_postfix({k: f"{v:.3f}" for k, v in record.items() if k.endswith(("loss", "accuracy"))})
            schedule.step()
        bar.close()
        self.module_.eval()
        self.n_features_in_ = X.shape[1]
        return self

    def predict_proba(self, X):
        return torch.softmax(self._logits(X), dim=1).numpy()

    def predict(self, X):
        return self.predict_proba(X).argmax(axis=1)

    @property
    def n_parameters_(self) -> int:
        return count_parameters(self.module_)
