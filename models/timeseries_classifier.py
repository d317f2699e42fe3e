"""Time-series classifiers behind the estimator contract: any network, two training recipes.

The network is given as a factory (Hydra `_partial_: true`) called at fit time with the data's
shape: network(n_channels=..., n_classes=..., length=..., modalities=...). Each channel is
standardised inside `fit` with the training windows' statistics, so windows of any scale (1e-6
or 1e6) train alike. Deterministic under `seed` on CPU; `device=auto` uses a GPU when there is one.

Recipes (configs/trainer/): the seed paper's (`trainer=tsc`: SGD, momentum 0.9, from lr 0.05
divided by 10 at fixed milestones, batch 128) and the reference implementations' (`trainer=reference`:
Adam at 1e-3, the learning rate multiplied by `lr_factor` after `lr_plateau_patience` epochs
without a lower loss, down to `min_lr`; small batches capped at a tenth of the training set;
many epochs). With validation windows to choose on (`epoch_selection=validation`) the epoch with
the best validation score (accuracy, ties broken by the lower validation loss) is restored at the
end. Early stopping ends training when no improvement that matters (a higher validation accuracy
or, while accuracy is below 1, the same accuracy with a validation loss lower by more than
`early_stopping_min_delta`; where nothing is chosen on validation while training, a training loss
lower by more than that) came for `patience(epoch of the last one)` epochs: as many again as it
took to get there, between `early_stopping_min_patience` and `early_stopping_patience`.

Choosing the number of epochs (`epoch_selection`): `validation` keeps the best epoch on the
validation windows given to `fit` (the seed paper's force-level split; without any, `max_epochs` and the
last one); `train_loss` is the reference implementations' own rule (dl-4-tsc, InceptionTime: every
epoch, the plateau on the training loss, the epoch of least training loss kept; validation windows
given are only scored); `folds` (trainer=reference) trains once per stratified fold of the training
recordings (data/splits/indices.py stratified_folds) as the refit will train (the plateau on the
training loss, the held-out fold only scored, at every epoch), takes the epoch of the best held-out
accuracy pooled over the folds (averaged over it and the 10 epochs before it), and refits on every
training window for that many epochs: the epoch count rests on every training recording, not a
small set's few validation recordings (a fold early-stopped on its own few held-out recordings
stops at a lucky early peak), and the validation split stays untouched for reporting. The folds' held-out predictions at the chosen epoch (`out_of_fold_proba_`, each training window
predicted by a fit that never saw its recording; `out_of_fold_method_` says how) are kept: a run
whose validation side is empty (every class has one training recording) reports them as its
validation scores, and the default model's choice scores the net on them when it trains on every
training recording (models/validation_choice.py).

`ensemble_size` > 1 trains that many networks with seeds seed, seed+1, ... (InceptionTime's
paper: 5) and averages their class probabilities (models/nets/member_average.py), one module,
so it exports to one ONNX graph.

Several processes (torchrun, submitit tasks) train one net as one process would (models/distributed.py).
With `recalibrate_batchnorm` the BatchNorm statistics are recomputed over all training windows after
every epoch's training, before it is scored (models/batchnorm_recalibration.py: why).

Resumable: with `checkpoint_path` the whole training state (weights, optimiser, schedule, RNG
states, best epoch, last improvement that mattered, history) is written after every epoch, and
`resume_from` continues from such a file to the same result as an uninterrupted fit (CPU); the
file's format and checks are models/training_checkpoint.py.
"""
import copy
import logging
import math
import time

import numpy as np
import torch
from torch import nn

from common.errors import InputError
from common.progress import HEARTBEAT_S, on_terminal, progress
from common.standardise import mean_and_scale
from data.splits.indices import stratified_folds
from models.batchnorm_recalibration import recalibrate_batchnorm
from models.capabilities import declare
from models.distributed import TrainingGroup, rank_seed
from models.epoch_callback import member_callback
from models.estimator_base import TouchstoneClassifier
from models import fold_epoch_choice
from models.fold_epoch_choice import best_epoch, each_folds_best_epoch, pooled_curve
from models.nets.member_average import MemberAverage
from models.torch_runtime import count_parameters, flush_denormals, resolve_device
from models.training_checkpoint import RESUME_KEYS, TrainingState, load_checkpoint, save_checkpoint

log = logging.getLogger(__name__)
OPTIMISERS = ("sgd", "adam")
SCHEDULES = ("milestones", "plateau")
EPOCH_SELECTIONS = ("validation", "folds", "train_loss")
CROSS_ENTROPY = nn.CrossEntropyLoss()


class TimeSeriesClassifier(TouchstoneClassifier):
    def __init__(self, network=None, modalities=None, optimizer="sgd", lr=0.05, momentum=0.9, weight_decay=0.0,
                 lr_schedule="milestones", milestones=(5, 15, 25), gamma=0.1, lr_factor=0.5,
                 lr_plateau_patience=50, min_lr=0.0, early_stopping_patience=None, early_stopping_min_patience=None,
                 early_stopping_min_delta=0.0, batch_size=128,
                 max_batch_fraction=None, max_epochs=40, recalibrate_batchnorm=False, device="cpu", seed=0,
                 progress=True, checkpoint_path=None, resume_from=None, epoch_selection="validation", n_folds=3,
                 ensemble_size=1):
        self.network = network
        self.modalities = modalities
        self.optimizer = optimizer
        self.lr = lr
        self.momentum = momentum
        self.weight_decay = weight_decay
        self.lr_schedule = lr_schedule
        self.milestones = milestones
        self.gamma = gamma
        self.lr_factor = lr_factor
        self.lr_plateau_patience = lr_plateau_patience
        self.min_lr = min_lr
        self.early_stopping_patience = early_stopping_patience
        self.early_stopping_min_patience = early_stopping_min_patience
        self.early_stopping_min_delta = early_stopping_min_delta
        self.batch_size = batch_size
        self.max_batch_fraction = max_batch_fraction
        self.max_epochs = max_epochs
        self.recalibrate_batchnorm = recalibrate_batchnorm
        self.device = device
        self.seed = seed
        self.progress = progress
        self.checkpoint_path = checkpoint_path
        self.resume_from = resume_from
        self.epoch_selection = epoch_selection
        self.n_folds = n_folds
        self.ensemble_size = ensemble_size

    def __sklearn_tags__(self):
        return declare(super().__sklearn_tags__(), epochs=True, reads_windows=True, named_by="network",
                       size="n_parameters", holds_out_training=self.epoch_selection == "folds")

    # -- helpers ----------------------------------------------------------------------------
    def _batches(self, X, size):
        return (X[start:start + size] for start in range(0, len(X), size))

    def _scaled(self, X) -> np.ndarray:
        return ((np.asarray(X, dtype=np.float64) - self.channel_mean_) / self.channel_std_).astype(np.float32)

    def _logits(self, X) -> torch.Tensor:
        self.module_.eval()
        with torch.no_grad():
            return torch.cat([self.module_(torch.as_tensor(b, device=self.device_)).float().cpu()
                              for b in self._batches(self._scaled(X), 512)])

    def _check_settings(self, n_train: int):
        if self.optimizer not in OPTIMISERS:
            raise InputError(f"trainer.optimizer must be one of {', '.join(OPTIMISERS)}, got {self.optimizer!r}")
        if self.lr_schedule not in SCHEDULES:
            raise InputError(f"trainer.lr_schedule must be one of {', '.join(SCHEDULES)}, got {self.lr_schedule!r}")
        if not (int(self.batch_size) >= 2 and int(self.max_epochs) >= 1 and float(self.lr) > 0):
            raise InputError(f"trainer needs batch_size >= 2, max_epochs >= 1 and lr > 0 (got {self.batch_size}, "
                             f"{self.max_epochs}, {self.lr})")
        if n_train < 2:
            raise InputError(f"time-series classifiers need at least 2 training windows, got {n_train}")
        if self.epoch_selection not in EPOCH_SELECTIONS:
            raise InputError(f"trainer.epoch_selection must be one of {', '.join(EPOCH_SELECTIONS)}, "
                             f"got {self.epoch_selection!r}")
        for name in ("n_folds", "ensemble_size"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < (2 if name == "n_folds" else 1):
                raise InputError(f"{'trainer' if name == 'n_folds' else 'model'}.{name} must be a whole number >= "
                                 f"{2 if name == 'n_folds' else 1}, got {value!r}")
        if self.ensemble_size > 1 and self.resume_from is not None:
            raise InputError("trainer.resume_from continues one network; an ensemble (model.ensemble_size > 1) "
                             "trains again from the start")

    def effective_batch_size(self, n_train: int) -> int:
        """The reference implementations' rule (Fawaz et al. 2019, dl-4-tsc classifiers/resnet.py
        and fcn.py: `mini_batch_size = int(min(x_train.shape[0] / 10, batch_size))`): never more
        than a fraction of the training set, so that an epoch is several optimiser steps and the
        BatchNorm statistics see many batches; at least 2 (BatchNorm needs two windows)."""
        size = int(self.batch_size)
        if self.max_batch_fraction is not None:
            size = min(size, int(n_train * float(self.max_batch_fraction)))
        return max(2, min(size, n_train))

    def _optimiser(self):
        if self.optimizer == "adam":
            return torch.optim.Adam(self.module_.parameters(), lr=self.lr, weight_decay=self.weight_decay)
        return torch.optim.SGD(self.module_.parameters(), lr=self.lr, momentum=self.momentum,
                               weight_decay=self.weight_decay)

    def _schedule(self, optimiser):
        if self.lr_schedule == "plateau":
            return torch.optim.lr_scheduler.ReduceLROnPlateau(optimiser, factor=self.lr_factor,
                                                              patience=self.lr_plateau_patience, min_lr=self.min_lr)
        return torch.optim.lr_scheduler.MultiStepLR(optimiser, milestones=list(self.milestones), gamma=self.gamma)

    def _fingerprint(self, shape) -> dict:
        return {"module": type(self.module_).__name__, "shape": list(shape), "n_classes": len(self.classes_),
                "n_parameters": count_parameters(self.module_),
                **{k: (list(v) if isinstance(v, tuple) else v) for k, v in self.get_params().items() if k in RESUME_KEYS}}

    @staticmethod
    def _better(score, best) -> bool:
        """Higher validation accuracy, ties broken by lower validation loss."""
        return best is None or score[0] > best[0] or (score[0] == best[0] and score[1] < best[1])

    def _matters(self, score, improved) -> bool:
        """An improvement that resets early stopping's count, against the score of the last one
        (`improved`: accuracy, loss, epoch): a higher validation accuracy or, while some validation
        windows are still wrong, the same accuracy with a validation loss lower by more than
        early_stopping_min_delta. Once every validation window is right, a lower loss is only more
        confidence: it still picks the kept epoch but no longer holds training (a tiny set ran 731
        epochs at validation accuracy 1.0 while its loss crept down)."""
        return improved is None or score[0] > improved[0] or (
            score[0] == improved[0] < 1.0 and score[1] < improved[1] - self.early_stopping_min_delta)

    def patience(self, improved_epoch: int) -> int | None:
        """Epochs to wait after the last improvement that mattered, at epoch `improved_epoch`:
        as many again as it took to get there, at least early_stopping_min_patience and at most
        early_stopping_patience (a set learnt in 10 epochs is not waited on for 100; one still
        learning at epoch 300 gets the whole patience). Without a minimum: the patience, fixed."""
        if self.early_stopping_patience is None:
            return None
        if self.early_stopping_min_patience is None:
            return int(self.early_stopping_patience)
        return min(int(self.early_stopping_patience), max(int(self.early_stopping_min_patience), improved_epoch))

    # -- contract ---------------------------------------------------------------------------
    @flush_denormals()
    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        """`groups`: the recording of each training window (folds keep a recording's windows
        together); None: every window is its own recording."""
        X, y = np.asarray(X, dtype=np.float32), np.asarray(y, dtype=np.int64)
        if X.ndim != 3:
            raise InputError(f"time-series classifiers need windows of shape (n, channels, length), got {X.shape}")
        self._check_settings(len(X))
        if X_val is not None and len(X_val) == 0:
            X_val = y_val = None
        n_classes = int(max(y.max(), np.max(y_val) if y_val is not None else 0)) + 1
        if self.ensemble_size > 1:
            return self._fit_ensemble(X, y, X_val, y_val, n_classes, epoch_callback, groups)
        if self.epoch_selection == "folds":
            return self._fit_on_folds(X, y, n_classes, epoch_callback, groups)
        return self._train(X, y, X_val, y_val, n_classes, epoch_callback, int(self.max_epochs))

    def _member(self, **changes) -> "TimeSeriesClassifier":
        """A fit of this recipe that writes no checkpoint (folds and ensemble members)."""
        return type(self)(**{**self.get_params(), "checkpoint_path": None, "resume_from": None, "ensemble_size": 1,
                             **changes})

    def _fit_on_folds(self, X, y, n_classes, epoch_callback, groups):
        """Epoch count = the epoch of the best pooled held-out accuracy (ties: lower pooled held-out
        loss), each averaged over it and the epochs before it (models/fold_epoch_choice.py), of folds
        trained as the refit trains: the plateau on the training loss, the held-out recordings only
        scored at every epoch, so fold and refit follow one schedule. A fold that
        stopped early (its training loss no longer falls by early_stopping_min_delta) keeps its last
        held-out predictions for the later epochs."""
        groups = np.arange(len(X)) if groups is None else np.asarray(groups)
        if len(groups) != len(X):
            raise InputError(f"{len(groups)} recording ids for {len(X)} training windows")
        folds, curves = stratified_folds(y, groups, self.n_folds, self.seed), []
        for k, (fit_rows, held_rows) in enumerate(folds):
            fold = self._member(epoch_selection="train_loss")
            fold.held_out_proba_ = []     # filled by _train at every epoch
            fold._train(X[fit_rows], y[fit_rows], X[held_rows], y[held_rows], n_classes,
                        member_callback(epoch_callback, f"fold{k}"), int(self.max_epochs))
            curves.append(np.stack(fold.held_out_proba_))          # (epochs run, held-out windows, classes)
        proba = pooled_curve(folds, curves, len(X), n_classes)
        best, accuracy, loss = best_epoch(proba, y)
        epochs = best + 1
        self.out_of_fold_proba_ = proba[best].astype(np.float64)
        self.fold_epochs_run_ = [len(curve) for curve in curves]
        self.fold_best_epochs_ = each_folds_best_epoch(folds, curves, y)
        self.fold_curve_ = {"accuracy": accuracy.tolist(), "loss": loss.tolist()}
        self.out_of_fold_method_ = f"{len(folds)} stratified folds"   # the epoch: best_epoch_
        log.info("epochs chosen on %d stratified folds' pooled held-out curve: epoch %d (held-out accuracy %.3f, "
                 "loss %.4f, each the mean of %d epochs to it; of %d run); refitting on all %d windows", len(folds), epochs,
                 accuracy[best], loss[best], fold_epoch_choice.FOLD_CURVE_WINDOW, len(proba), len(X))
        self._train(X, y, None, None, n_classes, epoch_callback, epochs)
        self.best_epoch_ = epochs
        return self

    def _fit_ensemble(self, X, y, X_val, y_val, n_classes, epoch_callback, groups):
        """Members with seeds seed, seed+1, ...: one module averaging their probabilities."""
        members = []
        for m in range(self.ensemble_size):
            member = self._member(seed=self.seed + m)
            member.fit(X, y, X_val, y_val, member_callback(epoch_callback, f"member{m}"), groups)
            members.append(member)
        self.channel_mean_, self.channel_std_ = members[0].channel_mean_, members[0].channel_std_
        # Each member standardised with the same statistics (the same training windows): one map in front.
        self.module_ = MemberAverage([member.module_ for member in members]).eval()
        self.device_ = members[0].device_
        self.classes_ = np.arange(n_classes)
        self.history_ = [{**record, "member": m} for m, member in enumerate(members) for record in member.history_]
        self.best_epoch_ = [member.best_epoch_ for member in members]
        self.n_epochs_ = [member.n_epochs_ for member in members]
        self.batch_size_ = members[0].batch_size_
        self.improved_epoch_ = [member.improved_epoch_ for member in members]
        if self.epoch_selection == "folds":
            self.out_of_fold_proba_ = np.mean([member.out_of_fold_proba_ for member in members], axis=0)
            self.fold_best_epochs_ = [member.fold_best_epochs_ for member in members]
            self.fold_epochs_run_ = [member.fold_epochs_run_ for member in members]
            self.out_of_fold_method_ = f"{members[0].out_of_fold_method_}, {len(members)} members averaged"
        self.n_features_in_ = X.shape[1]
        return self

    def _train(self, X, y, X_val, y_val, n_classes, epoch_callback, max_epochs):
        """One network on (X, y), the best epoch on (X_val, y_val) kept; without them, `max_epochs`
        epochs and the last one kept. Build (or resume), then per epoch: train, score, keep the
        best and judge early stopping, checkpoint, report."""
        group = TrainingGroup()  # this process's part when several train the net (models/distributed.py)
        X, trained = self._build_network(X, n_classes, group)
        run = self._training_state(X, group)
        data = (torch.as_tensor(X), torch.as_tensor(y))
        validation = None if X_val is None else (X_val, torch.as_tensor(np.asarray(y_val, dtype=np.int64)))
        start, elapsed_before = time.perf_counter(), run.elapsed_s
        self.step_losses_ = []  # the global batch's mean loss at every optimiser step of this fit
        first_epoch = max_epochs if run.stopped else run.epoch   # a resumed run that had stopped early: done
        bar = progress(range(first_epoch, max_epochs), desc=type(self.module_).__name__, unit="epochs",
                       enabled=self.progress and group.is_writer)
        for epoch in bar:
            epoch_start = time.perf_counter()
            train_loss, train_accuracy = self._train_epoch(trained, run, data, group, epoch)
            record = {"epoch": epoch + 1, "train_loss": train_loss, "train_accuracy": train_accuracy,
                      "lr": run.optimiser.param_groups[0]["lr"], "epoch_s": time.perf_counter() - epoch_start,
                      "elapsed_s": elapsed_before + time.perf_counter() - start}
            score = self._epoch_score(record, validation, group, epoch)
            self.history_.append(record)
            patience = self._keep_best_and_judge_stopping(run, score, record)
            self._save_checkpoint(run, group)
            if epoch_callback is not None:
                epoch_callback(record)
            bar.set_postfix({k: f"{v:.3f}" for k, v in record.items() if k.endswith(("loss", "accuracy"))})
            if run.stopped:
                log.info("%s: stopped at epoch %d, no improvement that matters since epoch %d (val accuracy %.3f, "
                         "val loss %.4f; patience %d epochs)", type(self.module_).__name__, epoch + 1, run.improved[2],
                         run.improved[0], run.improved[1], patience)
                break
        bar.close()
        group.release(self.module_)
        return self._keep_chosen_epoch(run, validation is not None, X.shape[1])

    def _build_network(self, X, n_classes, group: TrainingGroup):
        """The standardised training windows and a freshly seeded network for them; returns (the
        windows, the module as it trains: wrapped when several processes train it)."""
        torch.manual_seed(self.seed)
        self.channel_mean_, self.channel_std_ = mean_and_scale(X, axis=(0, 2), keepdims=True)
        X = self._scaled(X)
        self.classes_ = np.arange(n_classes)
        self.device_ = group.device(resolve_device(self.device))
        self.module_ = self.network(n_channels=X.shape[1], n_classes=n_classes, length=X.shape[2],
                                    modalities=self.modalities).to(self.device_)
        trained = group.prepare(self.module_)
        if group.rank:  # rank 0 continues the run's seed stream, so one process trains as it always did
            torch.manual_seed(rank_seed(self.seed, group.rank))
        return X, trained

    def _training_state(self, X, group: TrainingGroup) -> TrainingState:
        """Optimiser, schedule and batch order of a fresh fit, or as `resume_from` left them."""
        self.batch_size_ = self.effective_batch_size(len(X))
        optimiser = self._optimiser()
        fingerprint = {**self._fingerprint(X.shape[1:]), "world_size": group.size}  # dropout draws per rank
        run = TrainingState(self.module_, optimiser, self._schedule(optimiser),
                            torch.Generator().manual_seed(self.seed), fingerprint)
        if self.resume_from is not None:
            run.restore(load_checkpoint(self.resume_from, fingerprint), group.rank, group.size)
        self.history_ = run.history
        return run

    def _train_epoch(self, trained, run: TrainingState, data, group: TrainingGroup, epoch: int):
        """One pass over the training windows in the generator's order, each rank its shard of
        every batch; returns the epoch's training loss and accuracy."""
        Xt, yt = data
        self.module_.train()
        order = torch.randperm(len(Xt), generator=run.generator)
        step_sums, step_sizes, correct, seen = [], [], 0, 0
        # A bar over the batches on a terminal; off a terminal, log lines only once epochs are
        # long enough that the epoch loop's own heartbeat would leave minutes silent.
        long_epochs = bool(self.history_) and self.history_[-1].get("epoch_s", 0.0) > HEARTBEAT_S
        batches = progress(list(self._batches(order, self.batch_size_)), desc=f"epoch {epoch + 1}", unit="batches",
                           enabled=self.progress and group.is_writer and (on_terminal() or long_epochs))
        for batch in batches:
            if len(batch) < group.smallest_batch():  # BatchNorm cannot normalise a batch of one
                continue
            mine = group.shard(batch)
            xb, yb = Xt[mine].to(self.device_), yt[mine].to(self.device_)
            logits = trained(xb)
            loss = CROSS_ENTROPY(logits, yb) * group.share(len(mine), len(batch))
            run.optimiser.zero_grad()
            loss.backward()
            run.optimiser.step()
            step_sums.append(loss.item() * len(batch) / group.size)
            step_sizes.append(len(batch))
            correct += int((logits.argmax(1) == yb).sum())
            seen += len(mine)
        *step_sums, correct, seen = group.totals([*step_sums, correct, seen])
        self.step_losses_ += [s / n for s, n in zip(step_sums, step_sizes)]
        total = sum(step_sums)
        if not math.isfinite(total):
            raise InputError(f"{type(self.module_).__name__}: training diverged at epoch {epoch + 1} "
                             "(loss is not finite); lower trainer.lr")
        if self.recalibrate_batchnorm:
            recalibrate_batchnorm(self.module_, self._batches(Xt, 512), self.device_, group)
        return total / max(seen, 1), correct / max(seen, 1)

    def _epoch_score(self, record: dict, validation, group: TrainingGroup, epoch: int) -> tuple:
        """What the kept epoch is chosen on (`_better`): the validation accuracy and loss (written
        into `record`); the least training loss (epoch_selection=train_loss); else the last epoch."""
        if validation is not None:  # every rank validates; all act on rank 0's numbers (train_loss: only reports)
            X_val, y_val_t = validation
            logits = self._logits(X_val)
            record["val_loss"], record["val_accuracy"] = group.agree(
                (float(CROSS_ENTROPY(logits, y_val_t)), float((logits.argmax(1).numpy() == y_val_t.numpy()).mean())))
            if getattr(self, "held_out_proba_", None) is not None:   # a fold of epoch_selection=folds
                self.held_out_proba_.append(torch.softmax(logits, dim=1).numpy())
        if self.epoch_selection == "train_loss":  # the references' checkpoint: the least training loss
            return (0.0, record["train_loss"])
        if validation is None:  # nothing to choose on: the last epoch is the model
            return (float(epoch), 0.0)
        return (record["val_accuracy"], record["val_loss"])

    def _keep_best_and_judge_stopping(self, run: TrainingState, score: tuple, record: dict) -> int | None:
        """Keep the epoch's weights if it scores best, note an improvement that matters, step the
        learning rate and decide whether training stops (run.stopped); returns the patience."""
        if self._better(score, run.best):
            run.best, run.best_state = score, copy.deepcopy(self.module_.state_dict())
        if self._matters(score, run.improved):
            run.improved = (*score, record["epoch"])
        if self.lr_schedule == "plateau":  # the references watch the loss; we watch validation's
            train_loss = record["train_loss"]
            run.schedule.step(train_loss if self.epoch_selection == "train_loss" else record.get("val_loss", train_loss))
        else:
            run.schedule.step()
        patience = self.patience(run.improved[2])
        run.stopped = patience is not None and record["epoch"] - run.improved[2] >= patience
        run.epoch, run.elapsed_s = record["epoch"], record["elapsed_s"]
        return patience

    def _save_checkpoint(self, run: TrainingState, group: TrainingGroup):
        if self.checkpoint_path is not None:
            rank_rngs = group.gather(torch.get_rng_state())   # every rank takes part; one writes
            if group.is_writer:
                save_checkpoint(self.checkpoint_path, run.checkpoint(rank_rngs))

    def _keep_chosen_epoch(self, run: TrainingState, validated: bool, n_channels: int):
        """Load the kept epoch's weights and note which epoch it was, how many ran and the last
        improvement that mattered."""
        if run.best_state is not None:
            self.module_.load_state_dict(run.best_state)
        self.module_.eval()
        if self.epoch_selection == "train_loss":
            self.best_epoch_ = next((r["epoch"] for r in self.history_ if r["train_loss"] == run.best[1]), len(self.history_))
        else:
            self.best_epoch_ = next((r["epoch"] for r in self.history_ if validated
                                     and (r["val_accuracy"], r["val_loss"]) == run.best), len(self.history_))
        self.n_epochs_ = len(self.history_)
        self.improved_epoch_ = run.improved[2] if run.improved is not None else 0  # the last improvement that mattered
        self.n_features_in_ = n_channels
        return self

    def predict_proba(self, X):
        return torch.softmax(self._logits(X), dim=1).numpy()

    def predict(self, X):
        return self.predict_proba(X).argmax(axis=1)

    @property
    def n_parameters_(self) -> int:
        return count_parameters(self.module_)
