"""One classification run, top to bottom: fit, predict, score -> one result; then the report side
(runs/report/classification_report.py) writes it once. Two kinds of data come here: time-series
windows (recordings: the networks of models/timeseries_classifier.py) and classification tables
(one row per press, its target a class label: models/classic_classifiers.py).

Reports what the seed paper reports (accuracy, validation loss, parameter count) plus macro-F1,
per-class accuracy, accuracy per force level, fit time, confusion matrices (PNG and TensorBoard)
and per-epoch curves. Choose on validation, report on test: the model sees validation windows
for its per-epoch curves and sweeps rank runs by validation accuracy; test windows are only
predicted once, after fitting, and scored beside validation.

A table's classifier has its probabilities calibrated on the held-out rows no model is fitted on
(data/datamodules/regression.py calibration_idx: the calibration and validation rows), by
temperature scaling; with fewer than MIN_CALIBRATION_ROWS it stays uncalibrated, and the log and
metrics.json say so. Its model: a TableClassifier config (model=logistic_regression, model=mlp)
as it is; a tree config (model=extra_trees, random_forest, decision_tree) as the classifier of
that kind with the same settings; the default (model=auto) as the choice on validation among its
classification candidates (models/validation_choice.py), recordings among its recordings
candidates; model=blend, which only regresses, as the `classifier` its YAML names (model/blend.yaml:
extra trees). Other regressors are refused by name.
"""
import logging
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from hydra.utils import instantiate
from sklearn.base import is_classifier

from common.errors import InputError
from models.capabilities import capabilities, fit, model_name, model_size
from models.deployable import table_classifier_pipeline, timeseries_pipeline
from models.validation_choice import task_of
from runs.report.classification_report import write_classification_report
from runs.regression import check_deployable
from runs.report.metrics import classification_metrics
from runs.split_notes import split_note

log = logging.getLogger(__name__)
SIGNIFICANCE_Z = 1.96      # held-out loss increase (paired z) above which temperature scaling is not applied
MIN_CALIBRATION_ROWS = 20   # fewer: a temperature fitted on them is noise; probabilities stay as the classifier gives them


@dataclass
class ClassificationResult:
    metrics: dict
    classes: list[str]
    y_val: np.ndarray
    proba_val: np.ndarray
    val_ids: dict           # columns that say which sample each row is: its recording, or a table row's readings
    val_levels: np.ndarray | None
    y_test: np.ndarray
    proba_test: np.ndarray
    test_ids: dict
    test_levels: np.ndarray | None
    pipeline: object        # models/deployable.py: TimeSeriesPipeline or TableClassifierPipeline
    hparams: dict
    samples: str = "windows"   # what one scored sample is: a table's row or a recording's window


def checkpoint_folder(output_dir) -> Path:
    """Where a run's per-epoch checkpoint lives: the run folder itself, not train.py's staging
    folder inside it (removed when a run fails), so an interrupted run keeps its checkpoint."""
    from hydra.core.hydra_config import HydraConfig
    if HydraConfig.initialized():
        return Path(HydraConfig.get().runtime.output_dir) / "checkpoint"
    return Path(output_dir) / "checkpoint"


def table_classifier(cfg):
    """The classifier a classification table fits for the configured model (the module docstring)."""
    node = cfg.model
    model = instantiate(node)
    if capabilities(model).chooses:
        return model
    if capabilities(model).weighs_candidates and cfg.get("classifier") is not None:
        node = cfg.classifier
        model = instantiate(node)
    if capabilities(model).has_classifier:   # a tree regressor: the classifier of its kind, same settings
        return model.classifier()
    if is_classifier(model) and not capabilities(model).reads_windows:
        return model
    name = str(node.get("_target_")).rsplit(".", 1)[-1] + (f"(kind={node.kind})" if "kind" in node else "")
    raise InputError(f"{name} is a regression model; a classification table trains model=extra_trees, random_forest, "
                     "decision_tree, mlp or logistic_regression")


def _calibrate(model, datamodule) -> dict:
    """Temperature-scale the model's probabilities on the calibration rows -> what metrics.json says of it."""
    rows = datamodule.calibration_idx
    if rows.size < MIN_CALIBRATION_ROWS:
        note = (f"too few calibration rows to calibrate the class probabilities ({rows.size} < {MIN_CALIBRATION_ROWS}, "
                "calibration and validation rows together); they are the classifier's own")
        log.warning(note)
        return {"method": None, "rows": int(rows.size), "note": note}
    X_test, y_test = datamodule.test
    before = classification_metrics(y_test, model.predict_proba(X_test), datamodule.classes)["loss"]
    held_out = cross_fitted_losses(model, *datamodule.calibration, datamodule.classes, datamodule.seed)
    model.calibrate(*datamodule.calibration)
    kept = held_out["z"] <= SIGNIFICANCE_Z
    if not kept:   # chosen on the calibration rows, never on test: the classifier's own probabilities win
        model.temperature_beta_ = 1.0
    after = classification_metrics(y_test, model.predict_proba(X_test), datamodule.classes)["loss"]
    report = {"method": "temperature" if kept else None, "rows": int(rows.size),
              "temperature_beta": model.temperature_beta_, "held_out_loss": held_out,
              "test_loss_uncalibrated": before, "test_loss": after}
    choice = (f"held-out log loss on the {rows.size} calibration rows (each half's temperature judged on the other) "
              f"{held_out['uncalibrated']:.4f} uncalibrated, {held_out['calibrated']:.4f} calibrated, paired z "
              f"{held_out['z']:.2f}")
    if not kept:
        report["note"] = f"temperature scaling not applied: it raised the {choice} > {SIGNIFICANCE_Z}"
        log.warning(report["note"])
        return report
    log.info("class probabilities calibrated on %d held-out rows (temperature scaling, beta %.3f; %s): test log loss "
             "%.4f -> %.4f", rows.size, model.temperature_beta_, choice, before, after)
    if after > before:   # reported, not acted on: test is never chosen on
        report["note"] = (f"temperature scaling made the test log loss worse ({before:.4f} -> {after:.4f}); kept "
                          f"because it was chosen on the calibration rows ({choice})")
        log.warning(report["note"])
    return report


def cross_fitted_losses(model, X_cal, y_cal, classes, seed) -> dict:
    """The log loss of the calibration rows with and without temperature scaling, each half's
    temperature fitted on the other half: the held-out criterion that decides whether scaling
    is kept. `z`: the paired per-row loss increase scaling brings, over its standard error; as
    with a costlier candidate (models/validation_choice.py), the documented default (scaled)
    gives way only to a significant difference, not to one within noise. Leaves the model
    calibrated on the last half (the caller calibrates it on all)."""
    y_cal = np.asarray(y_cal)
    halves = np.array_split(np.random.default_rng(seed).permutation(len(y_cal)), 2)
    uncalibrated = model.predict_proba(X_cal)
    scaled = np.empty_like(uncalibrated)
    for fit_rows, judged in ((halves[0], halves[1]), (halves[1], halves[0])):
        model.calibrate(X_cal[fit_rows], y_cal[fit_rows])
        scaled[judged] = model.predict_proba(X_cal[judged])
    loss = {name: classification_metrics(y_cal, proba, classes)["loss"]
            for name, proba in (("uncalibrated", uncalibrated), ("calibrated", scaled))}
    rows = np.arange(len(y_cal))
    increase = np.log(np.clip(uncalibrated[rows, y_cal], 1e-12, 1)) - np.log(np.clip(scaled[rows, y_cal], 1e-12, 1))
    spread = increase.std(ddof=1) / np.sqrt(len(increase)) if len(increase) > 1 else 0.0
    loss["z"] = float(increase.mean() / spread) if spread > 0 else 0.0
    return loss


def _table_ids(datamodule, rows) -> dict:
    """A table row's raw channel readings: predictions.csv is then a ready input for predict.py."""
    return {name: datamodule.table.channels[rows, k] for k, name in enumerate(datamodule.channel_names)}


def _recording_groups(model, datamodule) -> dict:
    """The recording of every training window, for a model that folds them."""
    if not capabilities(model).epochs:
        return {}
    if len(datamodule.train_window_recording) != len(datamodule.y_train):
        if model.epoch_selection == "folds":
            raise InputError("trainer.epoch_selection=folds cannot fold virtual force-level windows (they belong to "
                             "no recording); use trainer.epoch_selection=validation with augment")
        return {}
    return {"groups": datamodule.train_window_recording}


def _validation_can_join_training(datamodule) -> bool:
    """The validation recordings were carved from the training recordings the file declares, and every
    training window belongs to a recording (none is virtual), so a model that holds recordings out
    itself can train on all of them."""
    return (getattr(datamodule, "validation_carved", False) and len(datamodule.y_val) > 0
            and len(datamodule.train_window_recording) == len(datamodule.y_train))


def _scores_on_training(choice, datamodule) -> bool:
    """Whether the default model trains its candidates on every training recording and scores them on
    their held-out predictions (model.score_on=auto: where validation can join training, or where
    there is none: every class has one training recording, so nothing could be carved)."""
    if choice.score_on != "auto":
        return choice.score_on == "training"
    every_window_a_recording = len(datamodule.train_window_recording) == len(datamodule.y_train)
    return _validation_can_join_training(datamodule) or (len(datamodule.y_val) == 0 and every_window_a_recording)


class Side:
    """What differs between the two kinds of classification data, decided once per run."""
    task = None
    samples = "windows"

    def __init__(self, datamodule):
        self.datamodule = datamodule


class Rows(Side):
    """A classification table: one row per press (models/classic_classifiers.py or a library
    classifier), probabilities calibrated on the held-out rows."""
    task = "classification"
    samples = "rows"

    def model(self, cfg):
        return table_classifier(cfg)

    def pools_validation(self, model) -> bool:
        return False

    def calibrate(self, model) -> dict:
        if capabilities(model).calibrates_probabilities:
            return _calibrate(model, self.datamodule)
        return {"method": None, "rows": int(self.datamodule.calibration_idx.size),
                "note": f"{model_name(model)} does not calibrate its probabilities; they are the classifier's own"}

    def evaluated(self, model, summary, val_recordings) -> tuple:
        """(pipeline, validation ids, test ids, hyper-parameters beyond the common ones)."""
        dm = self.datamodule
        return (table_classifier_pipeline(dm, model), _table_ids(dm, dm.val_idx), _table_ids(dm, dm.test_idx), {})


class Windows(Side):
    """Windows of recordings (the networks of models/timeseries_classifier.py, the ROCKET family)."""
    task = "recordings"

    def model(self, cfg):
        model = instantiate(cfg.model)
        if not (capabilities(model).reads_windows or capabilities(model).chooses):
            raise InputError(f"{model_name(model)} classifies table rows (one per press); recordings train "
                             "model=prcnn, rescnn, inceptiontime or lstm_fcn")
        return model

    def pools_validation(self, model) -> bool:
        """A model that scores itself on held-out predictions of every training recording (a net
        choosing its epoch count on folds, trainer=reference, or a ROCKET member, the ridge head's
        leave-one-out) trains, like the default model, on every training recording the file
        declares instead of the 80 % left by the validation carve (issue 27: on ArrowHead 36, not 28)."""
        return capabilities(model).holds_out_training and _validation_can_join_training(self.datamodule)

    def calibrate(self, model) -> None:
        return None

    def evaluated(self, model, summary, val_recordings) -> tuple:
        dm = self.datamodule
        return (timeseries_pipeline(dm, model), {"recording": val_recordings}, {"recording": dm.test_window_recording},
                {"augment": bool(dm.n_virtual_windows), "window": str(summary["window"])})


SIDES = {side.task: side for side in (Rows, Windows)}


def fit_and_evaluate(cfg, datamodule, epoch_callback=None, output_dir=None) -> ClassificationResult:
    (X_train, y_train), (X_val, y_val), (X_test, y_test) = datamodule.train, datamodule.val, datamodule.test
    summary = datamodule.summary()
    summary["split_note"] = split_note(summary, cfg.data.get("group_columns"))   # a table's own grouping
    side = SIDES[task_of(X_train, y_train)](datamodule)   # the data's shape says: rows of a table, or windows
    model = side.model(cfg)
    choice = model if capabilities(model).chooses else None   # model=auto: chosen on validation
    # The rows the model is fitted on; with the choice scored on held-out training predictions, the
    # carved validation recordings join them (each candidate then holds rows out itself).
    X_fit, y_fit = X_train, y_train
    fit_recordings = getattr(datamodule, "train_window_recording", None)
    fit_levels = getattr(datamodule, "train_levels_per_window", None)
    pooled = False
    if choice is not None:
        check_deployable(choice.set_params(task=side.task))
        pooled = side.task == "recordings" and _scores_on_training(choice, datamodule)
        choice.set_params(score_on="training" if pooled else "validation")
        if side.task == "recordings":
            choice.set_candidate_params(modalities=datamodule.modality_channels)
        if pooled:   # a net's held-out predictions are those of the folds that choose its epochs
            choice.set_candidate_params(epoch_selection="folds")
    else:
        pooled = side.pools_validation(model)
    if pooled:
        X_fit, y_fit = np.concatenate([X_train, X_val]), np.concatenate([y_train, y_val])
        fit_recordings = np.concatenate([fit_recordings, datamodule.val_window_recording])
        if fit_levels is not None and datamodule.val_levels_per_window is not None:
            fit_levels = np.concatenate([fit_levels, datamodule.val_levels_per_window])
    if "modalities" in model.get_params():
        model.set_params(modalities=datamodule.modality_channels)
    if "checkpoint_path" in model.get_params():  # resumable training (docs/training_recipes.md)
        if cfg.trainer.get("checkpoint", False):
            model.set_params(checkpoint_path=str(checkpoint_folder(output_dir) / "last.pt"))
        model.set_params(resume_from=cfg.trainer.get("resume_from"))
    start, cpu_start = time.perf_counter(), time.process_time()
    if pooled:
        fit(model, X_fit, y_fit, epoch_callback=epoch_callback, groups=fit_recordings)
    else:  # windows of one recording stay in one fold when a net chooses its epochs on folds
        fit(model, X_train, y_train, X_val, y_val, epoch_callback=epoch_callback,
            **(_recording_groups(model, datamodule) if side.task == "recordings" else {}))
    fit_time_s, fit_cpu_time_s = time.perf_counter() - start, time.process_time() - cpu_start
    if choice is not None:   # from here on the run reports and deploys the chosen candidate
        model = choice.chosen_model_
        _say_choosing_and_fitting(choice, fit_time_s)
    offers = capabilities(model)
    if "checkpoint_path" in model.get_params():  # the deployed model refits from scratch, never from this run's files
        model.set_params(checkpoint_path=None, resume_from=None)
    calibration = side.calibrate(model)
    proba_test = model.predict_proba(X_test)
    val_levels = getattr(datamodule, "val_levels_per_window", None)
    val_recordings = getattr(datamodule, "val_window_recording", None)
    if pooled:  # the validation recordings were trained on: every training recording is scored held out
        proba, y_val, val_recordings, val_levels = model.out_of_fold_proba_, y_fit, fit_recordings, fit_levels
        summary["validation"] = (f"held-out predictions ({model.out_of_fold_method_}) of all {len(np.unique(fit_recordings))} "
                                 f"training recordings, the {summary['n_val_recordings']} carved for validation "
                                 "among them: the model is trained on every one")
        summary["n_fit_recordings"] = int(len(np.unique(fit_recordings)))
    elif len(y_val) == 0:  # every class has one training recording: nothing could be carved
        if not offers.holds_out_training:
            raise InputError(f"{type(model).__name__} has no validation recordings to be scored on (every class has "
                             "one training recording); declare 'val' recordings in the file's split")
        proba, y_val = model.out_of_fold_proba_, y_train  # each predicted by a fit that never saw it
        val_recordings, val_levels = datamodule.train_window_recording, datamodule.train_levels_per_window
        summary["validation"] = "out-of-fold predictions on the training recordings (no validation recordings)"
    else:
        proba = model.predict_proba(X_val)
    name = model_name(model)
    n_parameters = model_size(model).get("n_parameters", 0)
    test_levels = getattr(datamodule, "test_levels_per_window", None)
    metrics = {"model": name, "n_parameters": n_parameters, "fit_time_s": fit_time_s,
               "cost": {"fit_time_s": fit_time_s, "fit_cpu_time_s": fit_cpu_time_s, "n_parameters": n_parameters},
               "val": classification_metrics(y_val, proba, datamodule.classes, val_levels),
               "test": classification_metrics(y_test, proba_test, datamodule.classes, test_levels),
               "data": summary}
    if calibration is not None:
        metrics["calibration"] = calibration
    if choice is not None:
        metrics["choice"] = choice.report()
        if choice.chosen_ in choice.fit_time_s_:   # the chosen model's own fit, apart from choosing it
            metrics["cost"]["chosen_fit_time_s"] = choice.fit_time_s_[choice.chosen_]
    if offers.epochs:  # the epoch kept (best on validation), of how many run, at what batch
        metrics["training"] = {"epochs_run": model.n_epochs_, "best_epoch": model.best_epoch_,
                               "batch_size": model.batch_size_, "epoch_selection": model.epoch_selection}
        if offers.holds_out_training:  # the folds that chose the epoch count
            metrics["training"]["fold_best_epochs"] = model.fold_best_epochs_
            metrics["training"]["out_of_fold_accuracy"] = float(
                (model.out_of_fold_proba_.argmax(axis=1) == y_fit).mean())
    pipeline, val_ids, test_ids, more_hparams = side.evaluated(model, summary, val_recordings)
    hparams = {"model": name, "label": datamodule.label, "seed": cfg.seed, **more_hparams}
    return ClassificationResult(metrics, list(datamodule.classes), y_val, proba, val_ids, val_levels, y_test,
                                proba_test, test_ids, test_levels, pipeline, hparams, samples=side.samples)


def _say_choosing_and_fitting(choice, fit_time_s: float) -> None:
    """The default's fit time is every candidate's fit and the choosing: the log says how much of
    it was the chosen model's own fit (a report line "X fitted in 17.9 s" read as X's own fit where
    it took 0.7 s)."""
    own = choice.fit_time_s_.get(choice.chosen_)
    fitted = ", ".join(f"{name} {seconds:.1f} s" for name, seconds in choice.fit_time_s_.items())
    log.info("model choice took %.1f s in all (fits: %s; the rest scoring and timing them); the chosen %s's own "
             "fit: %s", fit_time_s, fitted, choice.chosen_, "a mixture of them" if own is None else f"{own:.1f} s")


def _log_trade(trade: dict, logger) -> None:
    """TensorBoard choice/trade/...: what the choice gave up against the most accurate candidate and saved."""
    given = trade["accuracy_given_up"]
    for tag, value in (("accuracy_given_up", given["difference"]), ("accuracy_given_up_low95", given["interval95"][0]),
                       ("accuracy_given_up_high95", given["interval95"][1]),
                       ("latency_saved_ms", trade["latency_saved_ms"])):
        logger.writer_.add_scalar(f"choice/trade/{tag}", value)
    for name, ms in trade["latency_ms"].items():
        logger.writer_.add_scalar(f"choice/latency_ms/{name}", ms)


def run_classification(cfg, output_dir, datamodule, logger):
    """Fit, evaluate and report -> (metrics, the deployable pipeline); runs/run.py exports it,
    measures its costs and writes the metrics."""
    result = fit_and_evaluate(cfg, datamodule, logger.log_epoch, output_dir)
    if logger is not None and (result.metrics.get("choice") or {}).get("trade") is not None:
        _log_trade(result.metrics["choice"]["trade"], logger)
    write_classification_report(result, output_dir, logger)
    return result.metrics, result.pipeline
