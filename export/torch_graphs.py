"""Torch modules that wrap a pipeline's front end or a model for ONNX, and the torch exporter call
every torch piece goes through (export/converters/ say which model each wrapper serves).

The preprocessing steps themselves are not restated here: the min-max normalisation, the physics
features, the FSR calibration and the decimation are the data side's own torch code
(data/preprocessing/minmax_scaling.py, data/preprocessing/features.py, data/physics/force_sensing_resistor.py,
data/preprocessing/windows.py), the same code training ran. Normalisation and features run in float64; the
rest of the graph in float32.
"""
import contextlib
import io
import warnings

import numpy as np
import onnx
import torch
from torch import nn

from data.physics.force_sensing_resistor import CALIBRATION_KEYS, FsrCalibration
from data.preprocessing.features import PhysicsFeatures
from data.preprocessing.windows import decimate


class RegressionFrontEnd(nn.Module):
    """raw readings (float64) -> the data set's min-max normalisation, if the model was trained on
    normalised channels -> physics features -> training-split standardisation -> float32."""

    def __init__(self, groups, scaler_mean, scaler_scale, normalisation=None):
        super().__init__()
        self.normalise = normalisation.module() if normalisation is not None else nn.Identity()
        self.features = PhysicsFeatures(groups)
        self.register_buffer("scaler_mean", torch.as_tensor(np.asarray(scaler_mean), dtype=torch.float64))
        self.register_buffer("scaler_scale", torch.as_tensor(np.asarray(scaler_scale), dtype=torch.float64))

    def forward(self, readings):
        return ((self.features(self.normalise(readings)) - self.scaler_mean) / self.scaler_scale).float()


class ResMLPInUnits(nn.Module):
    """The residual MLP with its own input standardisation and target de-standardisation:
    features -> targets in units."""

    def __init__(self, regressor):
        super().__init__()
        self.net = regressor.module_.cpu().eval()
        self.register_buffer("feature_mean", torch.as_tensor(regressor.feature_mean_, dtype=torch.float32))
        self.register_buffer("feature_scale", torch.as_tensor(regressor.feature_scale_, dtype=torch.float32))
        self.register_buffer("target_mean", torch.as_tensor(regressor.target_mean_, dtype=torch.float32))
        self.register_buffer("target_scale", torch.as_tensor(regressor.target_scale_, dtype=torch.float32))

    def forward(self, features):
        return self.net((features - self.feature_mean) / self.feature_scale) * self.target_scale + self.target_mean


class WindowClassifier(nn.Module):
    """raw window [batch, channels, steps] -> FSR calibration -> decimation -> scaling -> net -> probabilities."""

    def __init__(self, pipeline):
        super().__init__()
        self.net = pipeline.model.module_.cpu().eval()
        self.decimate = pipeline.decimate
        calibration = pipeline.force_calibration
        self.calibrated_channel = calibration["index"] if calibration else None
        if calibration:
            self.calibration = FsrCalibration(**{k: v for k, v in calibration.items() if k in CALIBRATION_KEYS})
        # the datamodule's channel scaling followed by the classifier's own: one affine map
        model = pipeline.model
        mean = pipeline.channel_mean + model.channel_mean_ * pipeline.channel_std
        std = pipeline.channel_std * model.channel_std_
        self.register_buffer("channel_mean", torch.as_tensor(mean, dtype=torch.float64))
        self.register_buffer("channel_std", torch.as_tensor(std, dtype=torch.float64))

    def forward(self, window):
        x = window.double()
        k = self.calibrated_channel
        if k is not None:
            x = torch.cat([x[:, :k], self.calibration(x[:, k:k + 1]), x[:, k + 1:]], dim=1)
        x = decimate(x, self.decimate)  # block means in float64 (onnxruntime has no double AveragePool)
        x = ((x - self.channel_mean) / self.channel_std).float()
        return torch.softmax(self.net(x), dim=1)


def to_onnx(module: nn.Module, example: torch.Tensor, input_name: str, output_name: str, opset: int) -> onnx.ModelProto:
    """Trace `module` to ONNX with a dynamic batch axis, weights inside the proto.

    The TorchScript tracer (`dynamo=False`), not torch 2.13's default dynamo exporter: on these
    small graphs dynamo took 8-22 s for the feature front end and 3-4 s per residual MLP, the
    tracer under 1 s and 0.5 s (measured on this project's 2-core machine), which is most of
    what a first run spends exporting; parity with the eager pipeline is tested on hard inputs
    either way. (Dynamo's graph optimiser had also removed `x + 1e-8` as if it were `x + 0`.)
    """
    buffer = io.BytesIO()
    dynamic = {input_name: {0: "batch"}, output_name: {0: "batch"}}
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")  # the tracer's deprecation and shape-trace notes
        torch.onnx.export(module.eval(), (example,), buffer, dynamo=False, input_names=[input_name],
                          output_names=[output_name], dynamic_axes=dynamic, opset_version=opset)
    return onnx.load_from_string(buffer.getvalue())
