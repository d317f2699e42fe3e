"""Torch modules that restate the deployed preprocessing for ONNX, and the torch exporter call.

`PhysicsFeatures` computes data/features.py's operators in float64 (so a constant sample's
shape statistics are exactly 0, as in numpy, and products of 1e9-ohm readings stay exact);
the rest of the graph runs in float32.
"""
import contextlib
import io
import logging
import warnings

import numpy as np
import onnx
import torch
from torch import nn

EPSILON = 1e-8


class PhysicsFeatures(nn.Module):
    def __init__(self, groups: list[str]):
        super().__init__()
        self.groups = list(groups)
        # Small constants as float64 buffers keep their exact values (a Python scalar passes
        # through float32 in the exporter: 1e-12 became 9.99999996e-13).
        self.register_buffer("epsilon", torch.tensor(EPSILON, dtype=torch.float64))
        self.register_buffer("relative_floor", torch.tensor(1e-12, dtype=torch.float64))
        self.register_buffer("tiny", torch.tensor(1e-300, dtype=torch.float64))

    def forward(self, r: torch.Tensor) -> torch.Tensor:
        r = r.double()
        mean = r.mean(dim=1, keepdim=True)
        centred = r - mean
        std = torch.sqrt((centred * centred).mean(dim=1, keepdim=True))
        resolvable = std > self.relative_floor * torch.maximum(mean.abs(), self.tiny)
        z = torch.where(resolvable, centred / torch.where(resolvable, std, torch.ones_like(std)), torch.zeros_like(centred))
        blocks = []
        for group in self.groups:
            if group == "raw":
                blocks.append(r)
            elif group == "log1p":
                blocks.append(torch.log1p(r.abs()))
            elif group == "sqrt":
                blocks.append(torch.sqrt(r.abs()))
            elif group == "zscore":
                blocks.append(torch.where(resolvable, centred / (std + self.epsilon), torch.zeros_like(centred)))
            elif group == "stats":
                skew = (z ** 3).mean(dim=1, keepdim=True)
                kurtosis = torch.where(resolvable, (z ** 4).mean(dim=1, keepdim=True) - 3.0, torch.zeros_like(mean))
                blocks.append(torch.cat([mean, torch.where(resolvable, std, torch.zeros_like(std)), skew, kurtosis], dim=1))
            elif group == "pair_products":
                blocks.append(r[:, :-1] * r[:, 1:])
            else:
                blocks.append(r[:, :-1] / (r[:, 1:] + self.epsilon))
        return torch.cat(blocks, dim=1)


class RegressionFrontEnd(nn.Module):
    """raw readings (float64) -> physics features -> training-split standardisation -> float32."""

    def __init__(self, groups, scaler_mean, scaler_scale):
        super().__init__()
        self.features = PhysicsFeatures(groups)
        self.register_buffer("scaler_mean", torch.as_tensor(np.asarray(scaler_mean), dtype=torch.float64))
        self.register_buffer("scaler_scale", torch.as_tensor(np.asarray(scaler_scale), dtype=torch.float64))

    def forward(self, readings):
        return ((self.features(readings) - self.scaler_mean) / self.scaler_scale).float()


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
        self.calibration = dict(pipeline.force_calibration or {})
        # the datamodule's channel scaling followed by the classifier's own: one affine map
        model = pipeline.model
        mean = pipeline.channel_mean + model.channel_mean_ * pipeline.channel_std
        std = pipeline.channel_std * model.channel_std_
        self.register_buffer("channel_mean", torch.as_tensor(mean, dtype=torch.float64))
        self.register_buffer("channel_std", torch.as_tensor(std, dtype=torch.float64))

    def _newtons(self, volts):
        c = self.calibration
        supply = c.get("supply_v", 3.3)
        v = torch.clamp(volts, 0.0, supply * (1 - 1e-9))
        resistance = c.get("divider_resistor_ohm", 1e4) * (supply - v) / torch.clamp(v, min=1e-12)
        effective = (c.get("fsr_resistance_1n_ohm", 1e4) / resistance) ** (1.0 / c.get("fsr_exponent", 0.9))
        saturation = c.get("fsr_saturation_n", 22.0)
        ratio = torch.clamp(effective / saturation, max=1 - 1e-6)
        force = torch.clamp(effective / (1.0 - ratio ** 4) ** 0.25, max=3 * saturation)
        return torch.where(v > 0, force, torch.zeros_like(force))

    def forward(self, window):
        x = window.double()
        if self.calibration:
            k = self.calibration["index"]
            x = torch.cat([x[:, :k], self._newtons(x[:, k:k + 1]), x[:, k + 1:]], dim=1)
        if self.decimate > 1:  # block means in float64 (onnxruntime has no double AveragePool)
            steps = x.shape[-1] // self.decimate
            x = x[..., :steps * self.decimate].unflatten(-1, (steps, self.decimate)).mean(dim=-1)
        x = ((x - self.channel_mean) / self.channel_std).float()
        return torch.softmax(self.net(x), dim=1)


def to_onnx(module: nn.Module, example: torch.Tensor, input_name: str, output_name: str, opset: int) -> onnx.ModelProto:
    """Dynamo export (torch 2.13's default) with a dynamic batch axis, weights inside the proto.

    optimize=False: the exporter's optimiser removed `x + 1e-8` as if it were `x + 0` (torch 2.13,
    onnxscript 0.7), which turns the features' guarded divisions into 0/0 = NaN. onnxruntime
    optimises the graph itself when it loads it.
    """
    module = module.eval()
    batch = torch.export.Dim("batch", min=1)
    for noisy in ("torch.onnx", "onnx_ir", "onnxscript"):  # "torchvision is not installed", pass-by-pass notes
        logging.getLogger(noisy).setLevel(logging.WARNING if noisy != "torch.onnx" else logging.ERROR)
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        program = torch.onnx.export(module, (example,), dynamo=True, input_names=[input_name],
                                    output_names=[output_name], dynamic_shapes=({0: batch},),
                                    opset_version=opset, verbose=False, optimize=False)
    return program.model_proto
