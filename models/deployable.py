"""What a run deploys: raw sensor readings in, physical quantities or class probabilities out.

A deployable pipeline bundles the fitted preprocessing (features and scaler, or calibration,
decimation and channel scaling) with the fitted model, so that `predict_raw` on raw readings
is the eager reference that the exported ONNX graph must match. A regression model trained on
min-max normalised channels (scene rubber12_lab) takes raw readings all the same: the pipeline
keeps the data set's normalisation and applies it before the features. Runs save it as
`pipeline.npz` in their output folder, in a format that cannot run code when loaded
(models/fitted_state.py); export/ turns it into one ONNX file.
"""
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from common.errors import InputError
from data.physics.force_sensing_resistor import CALIBRATION_KEYS, calibrated_channel_name, fsr_force_n
from data.preprocessing.features import compute_features, enabled_groups
from data.preprocessing.minmax_scaling import MinMaxScaling
from data.preprocessing.windows import decimate
from models.capabilities import capabilities
from models.fitted_state import load_fitted, save_fitted
from models.storable import storable

PIPELINE_FILE = "pipeline.npz"  # in a run folder


@dataclass(kw_only=True)
class FeaturePipeline:
    """Rows of raw channel readings -> (the data set's min-max normalisation) -> physics features,
    standardised -> the model: what a regression and a table classifier share."""
    channel_names: list[str]  # the raw readings it takes
    feature_groups: list[str]
    feature_names: list[str]
    scaler_mean: np.ndarray
    scaler_scale: np.ndarray
    model: object
    description: dict = field(default_factory=dict)
    examples: np.ndarray | None = None  # raw test-split readings: predictions.csv, latency measurements
    normalisation: MinMaxScaling | None = None  # raw readings -> the channels it was trained on

    def features(self, readings) -> np.ndarray:
        """Standardised features of raw readings, normalised first if the training channels were."""
        if self.normalisation is not None:
            readings = self.normalisation.normalise(readings)
        return (compute_features(readings, self.feature_groups) - self.scaler_mean) / self.scaler_scale


@storable
@dataclass(kw_only=True)
class RegressionPipeline(FeaturePipeline):
    target_names: list[str]

    def predict_raw(self, readings):
        """(prediction in units, interval half-width or None) for raw channel readings."""
        X = self.features(readings)
        if capabilities(self.model).intervals and self.model.calibrated:
            mean, sigma = self.model.predict_std(X)
            return mean, self.model.conformal_scale_ * sigma
        return np.asarray(self.model.predict(X)).reshape(len(X), -1), None


@storable
@dataclass(kw_only=True)
class TableClassifierPipeline(FeaturePipeline):
    """A classification table's model: raw channel readings -> features -> class probabilities
    (models/classic_classifiers.py, calibrated; no normalisation: a user's raw table)."""
    label: str               # the target column whose classes it predicts
    classes: list[str]

    def predict_raw(self, readings) -> np.ndarray:
        return self.model.predict_proba(self.features(readings))


@storable
@dataclass
class TimeSeriesPipeline:
    channel_names: list[str]
    classes: list[str]
    force_calibration: dict | None
    decimate: int
    window_length: int
    channel_mean: np.ndarray
    channel_std: np.ndarray
    model: object
    description: dict = field(default_factory=dict)
    examples: np.ndarray | None = None  # raw validation windows, for latency measurements

    @property
    def raw_length(self) -> int:
        """Steps of one raw window at the recording rate."""
        return self.window_length * self.decimate

    def preprocess(self, windows) -> np.ndarray:
        x = np.asarray(windows, dtype=np.float64).copy()
        if self.force_calibration:
            calibration = {k: v for k, v in self.force_calibration.items() if k in CALIBRATION_KEYS}
            k = self.force_calibration["index"]
            x[:, k] = fsr_force_n(x[:, k], **calibration)
        x = decimate(x, self.decimate)
        return ((x - self.channel_mean) / self.channel_std).astype(np.float32)

    def predict_raw(self, windows):
        return self.model.predict_proba(self.preprocess(windows))


storable(MinMaxScaling)   # a regression pipeline's normalisation (data/preprocessing/minmax_scaling.py)
PIPELINES = (RegressionPipeline, TableClassifierPipeline, TimeSeriesPipeline)


def _front_end(datamodule, model) -> dict:
    """The fields a table's pipeline takes from its datamodule: its features and their scaling."""
    return dict(channel_names=list(datamodule.channel_names), feature_groups=enabled_groups(datamodule.features),
                feature_names=list(datamodule.feature_names), scaler_mean=datamodule.scaler.mean_.copy(),
                scaler_scale=datamodule.scaler.scale_.copy(), model=model,
                description={"source": datamodule.table.description},
                examples=datamodule.table.channels[datamodule.test_idx].copy())


def regression_pipeline(datamodule, model) -> RegressionPipeline:
    pipeline = RegressionPipeline(**_front_end(datamodule, model), target_names=list(datamodule.target_names),
                                  normalisation=datamodule.table.normalisation)
    if pipeline.normalisation is not None:  # deployed on the raw readings the channels came from
        pipeline.channel_names = list(pipeline.normalisation.raw_channels)
        pipeline.examples = pipeline.normalisation.raw(pipeline.examples)
    return pipeline


def table_classifier_pipeline(datamodule, model) -> TableClassifierPipeline:
    return TableClassifierPipeline(**_front_end(datamodule, model), label=datamodule.label,
                                   classes=list(datamodule.classes))


def timeseries_pipeline(datamodule, model) -> TimeSeriesPipeline:
    calibration = None
    if datamodule.force_calibration:
        calibration = dict(datamodule.force_calibration)
        calibration["index"] = datamodule.recordings.channel_names.index(
            calibrated_channel_name(calibration["channel"], calibration.get("renamed")))
    raw_names = list(datamodule.recordings.channel_names)
    if calibration:
        raw_names[calibration["index"]] = calibration["channel"]
    return TimeSeriesPipeline(raw_names, list(datamodule.classes), calibration, int(datamodule.decimate),
                              int(datamodule.X_train.shape[-1]), datamodule.channel_mean.reshape(1, -1, 1),
                              datamodule.channel_std.reshape(1, -1, 1), model,
                              {"label": datamodule.label, "sample_rate_hz": datamodule.recording_rate_hz},
                              datamodule.raw_examples)


def save_pipeline(pipeline, path) -> Path:
    return save_fitted(pipeline, path)


def load_pipeline(path):
    """A saved pipeline; InputError (one line) for a file that is not one."""
    pipeline = load_fitted(path)
    if not isinstance(pipeline, PIPELINES):
        raise InputError(f"{path}: holds a {type(pipeline).__name__}, not a deployable pipeline")
    return pipeline
