"""Choose a model on validation within a time budget, and say what was chosen and why.

One mechanism for every default that has to pick a model for data it has not seen: the
recordings default (the ROCKET family, then nets), a classification table's classifiers, and
the regression pipeline's blending variants. Candidates are fitted on the training rows,
cheapest first, each scored on the validation rows (never the test rows); the best wins. With
`ensemble=True` a validation-weighted mixture of the fitted candidates is one more candidate,
chosen only when it scores above the best single one on validation.

Budget: `budget_s` seconds for all fits. A candidate's cost is estimated before it runs as its
`relative_cost` (config, measured ratios of fit time, e.g. PR-CNN against MiniRocket on the same
data) times the measured seconds per unit of cost of the candidates already fitted; one whose
estimate does not fit in what is left of the budget is skipped, with the estimate as its reason
(`skipped_`). The cheapest candidate always runs, so a choice is always made.

Scores (higher is better): regression, R^2 averaged over targets; classification, accuracy,
and a costlier classifier replaces a cheaper one only when it is right on significantly more
validation rows: McNemar's paired test on the rows where exactly one of the two is right (b
against c), z = (b - c) / sqrt(b + c) above `significance_z` (1.96: 5 %, two-sided). On a small
validation set the accuracies move in steps of 1/n, and a net that early-stopped on those very
rows wins one-row differences by chance (measured on ArrowHead, 8 validation recordings, seeds
0-2: picking the highest accuracy chose InceptionTime, MiniRocket and PR-CNN, test accuracy
0.691, 0.891 and 0.497, where MiniRocket alone scores 0.861 ± 0.031). Exact ties likewise go to
the cheaper candidate. Not the lower log loss: a net keeps the epoch whose loss is lowest
on these very validation rows, so its loss there is optimistic and would win every tie (measured on
GunPoint, seeds 0-2: PR-CNN and ResCNN both at validation accuracy 1.0, ResCNN taken on its lower
loss, test accuracy 0.956 ± 0.037). The log loss is still reported.

Cost (`prefer`, classes only): `cheapest_within_noise` keeps, among the candidates that are not
significantly less accurate than the most accurate one (McNemar as above, against it), the cheapest
to predict: walked in fit-cost order, a later one replaces the one kept only when it is at least as
accurate and its measured latency (`latency_ms_`: median of a few single-row predict_proba calls,
eager) is below 1 / `latency_factor` of it (latencies drift between runs: a factor keeps the choice
reproducible; on ArrowHead's 36 rows PR-CNN at 0.72 was within noise of 0.86, and 4x faster).
`most_accurate` keeps the highest held-out accuracy (exact ties to the cheaper). Either way `trade_` (metrics.json `choice.trade`, the log and the reason
TensorBoard shows) says what the choice gave up against the most accurate candidate (the
accuracy difference with its 95 % paired interval) and what it saved (latency and fit time of each).
With `skip_unwinnable` (true: every class task; or a list of them), a costlier classifier is not
fitted when it could not change the choice: against one wrong on e rows, a candidate right on all
of them reaches z = sqrt(e) at most, so with sqrt(e) <= significance_z (`most_accurate`: e = 0) it is
named in `skipped_` with that reason. `halving` (successive halving, e.g. 3; null: off): every net
still worth fitting first trains for 1/halving of its epochs, only the best 1/halving go on (`rungs_`).

What the candidates are scored on (`score_on`): `validation` (and `auto`, which a run may resolve to
`training`), the validation rows given to `fit` (or carved from the training rows when none are);
`training`, every candidate fitted on all the training rows and scored on its own held-out
predictions of them (`out_of_fold_proba_`: the ROCKET family's exact leave-one-out, a net's
out-of-fold predictions from the stratified folds that choose its epoch count), so the winner is
trained on every row and none are spent on choosing (classes only). The run asks for it where the
validation recordings would otherwise be carved from the training recordings a file declares
(runs/classification.py; on ArrowHead's 36 the carve left 28 to train on, 8 to choose with). All are
scored on the same rows, paired; `scored_on_` (metrics.json `choice.scored_on`) says which, how many, how.

`candidates` is either {name: estimator} or {task: {name: estimator}} with task one of TASKS;
the second form (configs/model/auto.yaml) lets one config serve every kind of data, and `task`
(set by the run; "auto" reads it from the data: 3-D X is recordings, integer y a class label)
picks the set.
"""
import inspect
import logging
import math
import time

import numpy as np
from sklearn.base import clone
from sklearn.metrics import accuracy_score, log_loss, r2_score
from sklearn.utils.validation import check_is_fitted

from common.errors import InputError
from data.splits.indices import carve_validation
from models.capabilities import capabilities, declare
from models.epoch_callback import member_callback
from models.estimator_base import TouchstoneEstimator
from models.mixture_weights import above_floor_weights
from models.paired_accuracy import accuracy_difference, best_reachable_z, significantly_better

log = logging.getLogger(__name__)
TASKS = ("regression", "classification", "recordings")
SCORE_ON = ("auto", "validation", "training")
PREFER = ("cheapest_within_noise", "most_accurate")
LATENCY_CALLS = 5          # single-row predict_proba calls per candidate (the median is kept)
LATENCY_BUDGET_S = 0.5     # ... or fewer, once they took this long
ENSEMBLE = "ensemble"


def task_of(X, y) -> str:
    """What kind of data (X, y) is: recordings (channels x steps per sample), class labels or quantities."""
    if np.ndim(X) == 3:
        return "recordings"
    return "classification" if np.asarray(y).dtype.kind in "iub" and np.ndim(y) == 1 else "regression"


def _fit_kwargs(estimator, **kwargs) -> dict:
    """The keyword arguments among `kwargs` that the estimator's fit takes (plain scikit-learn
    estimators take none of the run's validation rows, callbacks or groups)."""
    accepted = inspect.signature(estimator.fit).parameters
    return {k: v for k, v in kwargs.items() if k in accepted and v is not None}


class ValidationChoice(TouchstoneEstimator):
    def __init__(self, candidates=None, task="auto", budget_s=None, relative_cost=None, ensemble=True,
                 val_fraction=0.15, significance_z=1.96, seed=0, score_on="auto", prefer="cheapest_within_noise",
                 skip_unwinnable: bool | list = True, latency_factor=2.0, halving: int | None = None):
        self.candidates = candidates
        self.halving = halving
        self.prefer = prefer
        self.skip_unwinnable = skip_unwinnable
        self.latency_factor = latency_factor
        self.score_on = score_on
        self.task = task
        self.significance_z = significance_z
        self.budget_s = budget_s
        self.relative_cost = relative_cost
        self.ensemble = ensemble
        self.val_fraction = val_fraction
        self.seed = seed

    def __sklearn_tags__(self):
        return declare(super().__sklearn_tags__(), chooses=True, reads_windows=True)

    def candidate_set(self, task: str) -> dict:
        """{name: estimator} this choice fits for data of `task`."""
        candidates = self.candidates or {}
        if candidates and all(hasattr(v, "fit") for v in candidates.values()):
            return dict(candidates)
        if task not in candidates or not candidates[task]:
            raise InputError(f"model.candidates has no candidates for {task} data (it has: "
                             f"{', '.join(candidates) or 'none'})")
        return dict(candidates[task])

    def set_candidate_params(self, **params) -> "ValidationChoice":
        """Set `params` on every candidate that takes them (a run tells each time-series net its modalities)."""
        sets = [self.candidates] if all(hasattr(v, "fit") for v in self.candidates.values()) else \
            list(self.candidates.values())
        for candidates in sets:
            for estimator in candidates.values():
                taken = {k: v for k, v in params.items() if k in estimator.get_params()}
                if taken:
                    estimator.set_params(**taken)
        return self

    def _check_params(self):
        if self.budget_s is not None and not (isinstance(self.budget_s, (int, float)) and self.budget_s > 0):
            raise InputError(f"model.budget_s must be a positive number of seconds or null, got {self.budget_s!r}")
        for name, cost in (self.relative_cost or {}).items():
            if not (isinstance(cost, (int, float)) and cost > 0):
                raise InputError(f"model.relative_cost.{name} must be a positive number, got {cost!r}")
        if not (isinstance(self.significance_z, (int, float)) and self.significance_z >= 0):
            raise InputError(f"model.significance_z must be a number >= 0, got {self.significance_z!r}")
        if self.prefer not in PREFER:
            raise InputError(f"model.prefer must be one of {', '.join(PREFER)}, got {self.prefer!r}")
        if not (isinstance(self.skip_unwinnable, bool) or (isinstance(self.skip_unwinnable, (list, tuple))
                                                          and set(self.skip_unwinnable) <= set(TASKS))):
            raise InputError(f"model.skip_unwinnable must be true, false or a list of {', '.join(TASKS)}, "
                             f"got {self.skip_unwinnable!r}")
        if self.halving is not None and (isinstance(self.halving, bool) or not isinstance(self.halving, int)
                                         or self.halving < 2):
            raise InputError(f"model.halving must be a whole number >= 2 or null, got {self.halving!r}")
        if not (isinstance(self.latency_factor, (int, float)) and self.latency_factor >= 1):
            raise InputError(f"model.latency_factor must be a number >= 1, got {self.latency_factor!r}")
        if self.score_on not in SCORE_ON:
            raise InputError(f"model.score_on must be one of {', '.join(SCORE_ON)}, got {self.score_on!r}")

    def _score(self, y_val, output) -> tuple:
        """A sortable score, higher is better, and its readable form."""
        if self.task_ == "regression":
            y2 = np.asarray(y_val, dtype=np.float64).reshape(len(y_val), -1)
            r2 = float(np.mean([r2_score(y2[:, k], output.reshape(y2.shape)[:, k]) for k in range(y2.shape[1])]))
            return (r2,), {"r2": r2}
        accuracy = float(accuracy_score(y_val, self.classes_[output.argmax(axis=1)]))
        loss = float(log_loss(y_val, np.clip(output, 1e-15, 1), labels=self.classes_))
        return (accuracy,), {"accuracy": accuracy, "loss": loss}

    def _output(self, model, X=None):
        """What a candidate is scored on: predictions (regression) or class probabilities, of X, or
        (X None) its held-out predictions of its own training rows."""
        if self.task_ == "regression":
            return np.asarray(model.predict(X), dtype=np.float64)
        given = model.predict_proba(X) if X is not None else model.out_of_fold_proba_
        proba = np.zeros((len(given), len(self.classes_)))
        proba[:, np.searchsorted(self.classes_, model.classes_)] = given
        return proba / proba.sum(axis=1, keepdims=True)   # a float32 net's rows sum to 1 only up to rounding

    def _held_out(self, name, model):
        """A candidate's held-out predictions of its training rows (score_on=training)."""
        if getattr(model, "out_of_fold_proba_", None) is None:
            raise InputError(f"model.score_on=training: candidate {name} gives no held-out predictions of its "
                             "training rows (out_of_fold_proba_); a net needs trainer.epoch_selection=folds")
        self.scored_on_["by"][name] = model.out_of_fold_method_
        return self._output(model)

    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        self._check_params()
        self.task_ = task_of(X, y) if self.task == "auto" else self.task
        if self.task_ not in TASKS:
            raise InputError(f"model.task must be auto or one of {', '.join(TASKS)}, got '{self.task}'")
        candidates = self.candidate_set(self.task_)
        on_training = self.score_on == "training"
        if on_training:
            if self.task_ == "regression":
                raise InputError("model.score_on=training scores held-out class predictions; regression "
                                 "chooses on validation rows (model.score_on=validation)")
            if X_val is not None:
                raise InputError("model.score_on=training fits every candidate on all training rows; "
                                 "validation rows would go unused (pool them with the training rows)")
            self.scored_on_ = {"rows": "training, held out", "n": len(y), "by": {}}
        elif X_val is None or y_val is None:
            fit_rows, val_rows = carve_validation(len(X), self.val_fraction, self.seed, groups)
            X, y, X_val, y_val = X[fit_rows], y[fit_rows], X[val_rows], y[val_rows]
            groups = None if groups is None else np.asarray(groups)[fit_rows]
        if not on_training:
            self.scored_on_ = {"rows": "validation", "n": len(y_val)}
        y_scored = np.asarray(y) if on_training else y_val    # the rows every candidate is scored on, paired
        if self.task_ != "regression":
            self.classes_ = np.unique(np.concatenate([np.asarray(y), np.asarray(y_scored)]))
            self.majority_accuracy_ = float(np.unique(y_scored, return_counts=True)[1].max() / len(y_scored))
        costs = {name: float((self.relative_cost or {}).get(name, 1.0)) for name in candidates}
        order = sorted(candidates, key=lambda name: costs[name])   # stable: ties keep the listed order
        self.models_, self.scores_, self.fit_time_s_, self.skipped_, self.latency_ms_ = {}, {}, {}, {}, {}
        ranks, outputs, start, spent_per_cost = {}, {}, time.perf_counter(), []
        self.unit_ = "recordings" if self.task_ == "recordings" else "rows"
        def fitted(name, estimator, label):
            """(the fitted clone, its seconds, what it is scored on)."""
            began = time.perf_counter()
            model = clone(estimator).fit(X, y, **_fit_kwargs(
                estimator, X_val=X_val, y_val=y_val, groups=groups,
                epoch_callback=member_callback(epoch_callback, label) if epoch_callback else None))
            seconds = time.perf_counter() - began
            return model, seconds, self._held_out(name, model) if on_training else self._output(model, X_val)

        nets = [name for name in order if self._halves(candidates[name])] if self.halving else []
        self.rungs_ = {}
        for name in order:
            reason = self.skipped_.get(name) or self._why_not(name, costs[name], time.perf_counter() - start,
                                                               spent_per_cost, outputs, y_scored)
            if reason is None and len(nets) > 1 and name in nets and not self.rungs_:
                self._first_rung(nets[nets.index(name):], candidates, costs, fitted, start, spent_per_cost,
                                 outputs, y_scored)
                reason = self.skipped_.get(name)
            if reason is not None:
                self.skipped_[name] = reason
                log.info("model choice: %s skipped, %s", name, reason)
                continue
            model, self.fit_time_s_[name], outputs[name] = fitted(name, candidates[name], name)
            spent_per_cost.append(self.fit_time_s_[name] / costs[name])
            ranks[name], self.scores_[name] = self._score(y_scored, outputs[name])
            self.models_[name] = model
            if self.task_ != "regression":
                self.latency_ms_[name] = self._latency_ms(model, X_val if X_val is not None else X)
            log.info("model choice: %s's own fit took %.1f s%s; %s %s", name, self.fit_time_s_[name],
                     f", {self.latency_ms_[name]:.2f} ms per {self.unit_[:-1]} (eager, batch 1)"
                     if name in self.latency_ms_ else "", "held-out" if on_training else "validation",
                     ", ".join(f"{k} {v:.4f}" for k, v in self.scores_[name].items()))
        self.choosing_s_ = time.perf_counter() - start
        self.ties_, self.trade_ = None, None
        best = (max(ranks, key=lambda name: ranks[name]) if self.task_ == "regression"   # max keeps the first (cheapest) of equals
                else self._preferred(outputs, y_scored))
        self.ensemble_weights_ = None
        if self.ensemble and len(self.models_) > 1:
            weights = self._ensemble_weights()
            if weights is not None:
                mixed = sum(w * outputs[name] for name, w in weights.items())
                rank, self.scores_[ENSEMBLE] = self._score(y_scored, mixed)
                if rank > ranks[best]:
                    best, self.ensemble_weights_ = ENSEMBLE, weights
        self.chosen_ = best
        self.n_features_in_ = np.shape(X)[1]   # columns of a table, channels of windows
        self.reason_ = self._reason(ranks)
        log.info("model choice: %s", self.reason_)
        return self

    def _why_not(self, name, cost, elapsed, spent_per_cost, outputs, y_scored) -> str | None:
        """Why candidate `name` is not fitted (None: it is): it does not fit in the budget, or,
        for classes with skip_unwinnable, no candidate could change the choice any more."""
        if not self.models_:
            return None                                   # the cheapest always runs
        if self._skips_unwinnable():
            kept, y_scored = self._preferred(outputs, y_scored, quiet=True), np.asarray(y_scored)
            # held out of its own training rows, a row whose class has no other is never predicted right
            classes, counts = np.unique(y_scored, return_counts=True)
            winnable = ~np.isin(y_scored, classes[counts == 1]) if self.score_on == "training" else True
            errors = int(np.sum((self.classes_[outputs[kept].argmax(axis=1)] != y_scored) & winnable))
            reachable = best_reachable_z(errors)
            if self.prefer == "most_accurate" and errors == 0:
                return f"{kept} is right on every held-out {self.unit_[:-1]} any candidate could get right"
            if self.prefer == "cheapest_within_noise" and reachable <= self.significance_z:
                return (f"{kept} is wrong on {errors} of {len(y_scored)} scored {self.unit_} (of those a candidate "
                        f"could get right: not the only one of its class held out): right on all of them, a candidate "
                        f"would reach McNemar z = {reachable:.2f} <= {self.significance_z:g}, so none can be "
                        "significantly more accurate (model.prefer=most_accurate or model.skip_unwinnable=false "
                        "fits it anyway)")
        if self.budget_s is not None:
            estimate = cost * float(np.mean(spent_per_cost))
            if elapsed + estimate > self.budget_s:
                return (f"estimated {estimate:.1f} s (relative cost {cost:g} x {np.mean(spent_per_cost):.2f} s "
                        f"measured per unit) exceeds the {max(self.budget_s - elapsed, 0):.1f} s left of "
                        f"model.budget_s={self.budget_s:g}")
        return None

    @staticmethod
    def _halves(estimator) -> bool:
        """A candidate trained for epochs (a net): successive halving applies to it."""
        return capabilities(estimator).epochs and "max_epochs" in estimator.get_params()

    def _first_rung(self, nets, candidates, costs, fitted, start, spent_per_cost, outputs, y_scored):
        """Successive halving's first rung: every net still worth fitting (the budget judged on (1 +
        1/halving) of its cost) trained for 1/halving of its epochs and scored as a full fit would be;
        only the best 1/halving (ties: the cheaper) fit in full, the others are named in skipped_."""
        for name in nets:
            # judged on its rung and the full fit it may lead to: a rung whose full fit cannot follow buys nothing
            reason = self._why_not(name, costs[name] * (1 + 1 / self.halving), time.perf_counter() - start,
                                   spent_per_cost, outputs, y_scored)
            if reason is not None:
                self.skipped_[name] = reason
                continue
            epochs = max(1, math.ceil(candidates[name].get_params()["max_epochs"] / self.halving))
            estimator = clone(candidates[name]).set_params(max_epochs=epochs)
            _, seconds, output = fitted(name, estimator, f"{name}/rung1")
            spent_per_cost.append(seconds / (costs[name] / self.halving))
            accuracy = self._score(y_scored, output)[1]["accuracy"]
            self.rungs_[name] = {"epochs": epochs, "accuracy": accuracy, "fit_time_s": seconds}
            log.info("model choice: %s, successive halving's first rung (%d epochs, %.1f s): held-out accuracy %.4f",
                     name, epochs, seconds, accuracy)
        ranked = sorted(self.rungs_, key=lambda name: -self.rungs_[name]["accuracy"])   # stable: the cheaper first
        going_on = ranked[:math.ceil(len(ranked) / self.halving)]
        for name in ranked[len(going_on):]:
            self.skipped_[name] = (f"successive halving: {self.rungs_[name]['epochs']} epochs gave held-out accuracy "
                                   f"{self.rungs_[name]['accuracy']:.4f} where {going_on[0]} gave "
                                   f"{self.rungs_[going_on[0]]['accuracy']:.4f}; only the best {len(going_on)} of "
                                   f"{len(ranked)} went on to a full fit (model.halving={self.halving:g})")

    def _skips_unwinnable(self) -> bool:
        """skip_unwinnable: true (every class task), false, or the tasks it applies to."""
        tasks = self.skip_unwinnable if isinstance(self.skip_unwinnable, (list, tuple)) else (
            ("classification", "recordings") if self.skip_unwinnable else ())
        return self.task_ != "regression" and self.task_ in tasks

    @staticmethod
    def _latency_ms(model, X) -> float:
        """Median milliseconds of a single-row predict_proba (eager), over a few calls."""
        row, times = X[:1], []
        began = time.perf_counter()
        while len(times) < LATENCY_CALLS and (not times or time.perf_counter() - began < LATENCY_BUDGET_S):
            call = time.perf_counter()
            model.predict_proba(row)
            times.append(time.perf_counter() - call)
        return 1e3 * float(np.median(times))

    def _right(self, outputs, y_val) -> dict:
        return {name: self.classes_[proba.argmax(axis=1)] == np.asarray(y_val) for name, proba in outputs.items()}

    def _preferred(self, outputs, y_val, quiet=False) -> str:
        """The classifier kept among those fitted (in cost order) by `prefer` (the module docstring);
        unless `quiet`, the ties and the trade are noted (ties_, trade_)."""
        right = self._right(outputs, y_val)
        accuracy = {name: float(r.mean()) for name, r in right.items()}
        top = max(right, key=lambda name: accuracy[name])   # max keeps the first (cheapest to fit) of equals
        tied = [name for name in right if accuracy[name] == accuracy[top]]
        if self.prefer == "most_accurate":
            kept, rule = top, "the cheapest to fit"
        else:
            within = [name for name in right if not significantly_better(right[top], right[name], self.significance_z)]
            kept = within[0]
            for name in within[1:]:   # never trading held-out accuracy for latency: "within noise" is wide on few rows
                faster = self.latency_ms_[name] * self.latency_factor < self.latency_ms_[kept]
                kept = name if faster and accuracy[name] >= accuracy[kept] else kept
            rule = f"the cheapest to predict within noise (latency below 1/{self.latency_factor:g} of the next)"
        if not quiet:
            if len(tied) > 1:
                self.ties_ = (f"{', '.join(tied)} tie at held-out accuracy {accuracy[top]:.4f}; "
                              f"broken by cost: {rule}")
                log.info("model choice: %s", self.ties_)
            self.trade_ = self._trade(kept, top, right)
        return kept

    def _trade(self, kept, top, right) -> dict:
        """What keeping `kept` gave up against the most accurate `top` and what it saved."""
        trade = {"prefer": self.prefer, "kept": kept, "most_accurate": top,
                 "accuracy_given_up": accuracy_difference(right[top], right[kept]),
                 "latency_ms": dict(self.latency_ms_), "fit_time_s": dict(self.fit_time_s_)}
        trade["latency_saved_ms"] = self.latency_ms_[top] - self.latency_ms_[kept]
        return trade

    def _ensemble_weights(self) -> dict | None:
        """Weights of the validation-weighted mixture: the candidates' validation score above
        what a constant predicts (R^2 0; the majority class's accuracy), normalised; None when
        fewer than two candidates beat that."""
        key = "r2" if self.task_ == "regression" else "accuracy"
        floor = 0.0 if self.task_ == "regression" else self.majority_accuracy_
        names = [n for n in self.scores_ if n in self.models_]
        weights = above_floor_weights([self.scores_[n][key] for n in names], floor)
        if np.sum([self.scores_[n][key] > floor for n in names]) < 2:
            return None
        return {n: float(w) for n, w in zip(names, weights) if w > 0}

    def _reason(self, ranks) -> str:
        metric = "R^2" if self.task_ == "regression" else "accuracy"
        key = "r2" if self.task_ == "regression" else "accuracy"
        shown = ", ".join(f"{n} {s[key]:.4f}" for n, s in self.scores_.items())
        rows = "validation"
        if self.score_on == "training":
            how = "; ".join(f"{n} {m}" for n, m in self.scored_on_["by"].items())
            rows = "held-out training"
            text = (f"chose {self.chosen_} on held-out {metric} over all {self.scored_on_['n']} training "
                    f"{self.unit_}, each predicted by a fit without it ({how}), trained on all of them ({shown})")
        else:
            text = f"chose {self.chosen_} on validation {metric} over {self.scored_on_['n']} {self.unit_} ({shown})"
        if self.ties_:
            text += f"; {self.ties_}"
        trade = self.trade_ if self.chosen_ != ENSEMBLE else None
        if trade is not None and trade["kept"] != trade["most_accurate"]:
            top, given = trade["most_accurate"], trade["accuracy_given_up"]
            low, high = given["interval95"]
            text += (f"; {top} is right on more {rows} {self.unit_} but not significantly more (McNemar z "
                     f"{given['z']:.2f} <= {self.significance_z:g}), so the cheaper one stays (model.prefer="
                     f"{self.prefer}): gave up {given['difference']:.4f} accuracy (95 % interval {low:.4f} to "
                     f"{high:.4f}), saved {trade['latency_saved_ms']:.2f} ms per {self.unit_[:-1]} "
                     f"({self.latency_ms_[self.chosen_]:.2f} against {self.latency_ms_[top]:.2f} ms, eager batch 1; "
                     f"fits {self.fit_time_s_[self.chosen_]:.1f} s against {self.fit_time_s_[top]:.1f} s)")
        if self.skipped_:
            by_reason = {why: [n for n, w in self.skipped_.items() if w == why] for why in self.skipped_.values()}
            text += "; not fitted: " + "; ".join(f"{', '.join(names)} ({why})" for why, names in by_reason.items())
        return text

    @property
    def chosen_model_(self):
        """The estimator the run deploys (None when the validation-weighted ensemble won)."""
        check_is_fitted(self, "chosen_")
        return None if self.chosen_ == ENSEMBLE else self.models_[self.chosen_]

    def predict(self, X):
        check_is_fitted(self, "chosen_")
        if self.task_ == "regression":
            if self.ensemble_weights_ is None:
                return self.models_[self.chosen_].predict(X)
            return sum(w * np.asarray(self.models_[n].predict(X)) for n, w in self.ensemble_weights_.items())
        return self.classes_[self.predict_proba(X).argmax(axis=1)]

    def predict_proba(self, X):
        check_is_fitted(self, "chosen_")
        names = self.ensemble_weights_ or {self.chosen_: 1.0}
        return sum(w * self._output(self.models_[n], X) for n, w in names.items())

    def report(self) -> dict:
        """What metrics.json says of the choice."""
        check_is_fitted(self, "chosen_")
        return {"task": self.task_, "chosen": self.chosen_, "reason": self.reason_, "budget_s": self.budget_s,
                "scored_on": self.scored_on_, "validation": self.scores_, "fit_time_s": self.fit_time_s_, "skipped": self.skipped_,
                "ensemble_weights": self.ensemble_weights_, "prefer": self.prefer, "latency_ms": self.latency_ms_,
                "ties": self.ties_, "trade": self.trade_, "choosing_s": self.choosing_s_,
                "rungs": self.rungs_}
