"""Fitted ERT reconstructions as ONNX graphs: `tikhonov_to_onnx` (models/ert/tikhonov.py)
and `linear_image_to_onnx` (models/ert/: Gauss-Newton and GREIT, below the first).

TikhonovReconstruction:

`voltages` [batch, n_channels] float32 (changes from the unloaded frame)
  -> MatMul with Q^T (the precomputed regularised inverse, seed 002 eq. 4)      [batch, n_pixels]
  -> Reshape to an image and Conv with the Wiener kernel (the Gaussian deconvolution)
  -> Mul by the coefficient field W                                            per-pixel force (N)
  -> ReduceSum                                                                 force_n
  -> bilinear upsampling as two MatMuls (A img A^T) and ArgMax                 the peak: x_mm, y_mm
-> `prediction` [batch, 3] (x_mm, y_mm, force_n) and `force_pixels` [batch, n_pixels].

Everything is fixed after fit: the graph is a linear map, a convolution, a peak and a sum.

LinearImageReconstruction (models/ert/linear_image.py):
`voltages` -> MatMul with K (the transfer-matrix reduction, n_channels x n_z) -> MatMul with A^T
(the image map)                                                              `image` [batch, n_pixels]
  -> ReduceMax, Mul by the threshold, Sub, Relu                                 the read-out weights
  -> MatMul with the pixel centres, Div by the weights' sum                    x_mm, y_mm
  -> c0 + c1 m + c2 m^2 of the weights' sum m                                   force_n
-> `prediction` [batch, 3] and `image`.
"""
import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper
from sklearn.exceptions import NotFittedError
from sklearn.utils.validation import check_is_fitted

from common.errors import InputError


def _const(name, array, dtype=np.float32):
    return numpy_helper.from_array(np.asarray(array, dtype=dtype), name)


def _require_fitted(model, attribute: str) -> None:
    try:
        check_is_fitted(model, attribute)
    except NotFittedError:
        raise InputError(f"the {type(model).__name__} is not fitted; call fit before exporting it") from None


def tikhonov_to_onnx(model, opset: int = 17) -> onnx.ModelProto:
    """The reconstruction of a fitted TikhonovReconstruction as a self-contained ONNX model."""
    _require_fitted(model, "inverse_")
    n = model.pixels_per_side
    m = model.field_pixels
    n_channels = model.inverse_.shape[1]
    kernel = model.kernel_
    pad = kernel.shape[0] // 2
    step_mm = model.geometry["side_mm"] / m
    inits = [
        _const("inverse_t", model.inverse_.T),
        _const("image_shape", [-1, 1, n, n], np.int64),
        _const("kernel", kernel[None, None]),
        _const("coefficient_field", model.coefficient_field_.reshape(1, 1, n, n)),
        _const("flat_pixels", [-1, n * n], np.int64),
        _const("square", [-1, n, n], np.int64),
        _const("upsample", model.upsample_),
        _const("upsample_t", model.upsample_.T),
        _const("flat_field", [-1, m * m], np.int64),
        _const("width", [m], np.int64),
        _const("half", [0.5]),
        _const("step_mm", [step_mm]),
        _const("axis1", [1], np.int64),
    ]
    nodes = [
        helper.make_node("MatMul", ["voltages", "inverse_t"], ["image_flat"]),
        helper.make_node("Reshape", ["image_flat", "image_shape"], ["image"]),
        helper.make_node("Conv", ["image", "kernel"], ["sharp"], pads=[pad, pad, pad, pad]),
        helper.make_node("Mul", ["sharp", "coefficient_field"], ["force_image"]),
        helper.make_node("Reshape", ["force_image", "flat_pixels"], ["force_pixels"]),
        helper.make_node("ReduceSum", ["force_pixels", "axis1"], ["force_n"], keepdims=1),
        helper.make_node("Reshape", ["force_image", "square"], ["force_square"]),
        helper.make_node("MatMul", ["upsample", "force_square"], ["rows_up"]),
        helper.make_node("MatMul", ["rows_up", "upsample_t"], ["field"]),
        helper.make_node("Reshape", ["field", "flat_field"], ["field_flat"]),
        helper.make_node("ArgMax", ["field_flat"], ["peak"], axis=1, keepdims=1),
        helper.make_node("Mod", ["peak", "width"], ["column"]),
        helper.make_node("Div", ["peak", "width"], ["row"]),
        helper.make_node("Cast", ["column"], ["column_f"], to=TensorProto.FLOAT),
        helper.make_node("Cast", ["row"], ["row_f"], to=TensorProto.FLOAT),
        helper.make_node("Add", ["column_f", "half"], ["column_c"]),
        helper.make_node("Add", ["row_f", "half"], ["row_c"]),
        helper.make_node("Mul", ["column_c", "step_mm"], ["x_mm"]),
        helper.make_node("Mul", ["row_c", "step_mm"], ["y_mm"]),
        helper.make_node("Concat", ["x_mm", "y_mm", "force_n"], ["prediction"], axis=1),
    ]
    graph = helper.make_graph(
        nodes, "tikhonov_reconstruction",
        [helper.make_tensor_value_info("voltages", TensorProto.FLOAT, ["batch", n_channels])],
        [helper.make_tensor_value_info("prediction", TensorProto.FLOAT, ["batch", 3]),
         helper.make_tensor_value_info("force_pixels", TensorProto.FLOAT, ["batch", n * n])],
        inits)
    proto = helper.make_model(graph, opset_imports=[helper.make_opsetid("", opset)],
                              producer_name="touchstone")
    proto.ir_version = min(proto.ir_version, 9)
    helper.set_model_props(proto, {"inputs": f"voltages[{n_channels}] float32 (change from the unloaded frame, V)",
                                   "outputs": "prediction: x_mm, y_mm, force_n; force_pixels (N)"})
    onnx.checker.check_model(proto)
    return proto


def linear_image_to_onnx(model, opset: int = 17) -> onnx.ModelProto:
    """A fitted LinearImageReconstruction (GaussNewtonReconstruction, GreitReconstruction) as one ONNX model."""
    _require_fitted(model, "image_map_")
    n_pixels, n_channels = model.image_map_.shape[0], model.compression_.shape[1]
    c0, c1, c2 = model.force_coefficients_
    inits = [
        _const("reduction", model.compression_.T),
        _const("image_map_t", model.image_map_.T),
        _const("threshold", [model.threshold_]),
        _const("centres", model.pixel_centres_mm_),
        _const("axis1", [1], np.int64),
        _const("tiny", [1e-30]),
        _const("c0", [c0]), _const("c1", [c1]), _const("c2", [c2]),
    ]
    nodes = [
        helper.make_node("MatMul", ["voltages", "reduction"], ["transfer"]),
        helper.make_node("MatMul", ["transfer", "image_map_t"], ["image"]),
        helper.make_node("ReduceMax", ["image"], ["peak"], axes=[1], keepdims=1),
        helper.make_node("Mul", ["peak", "threshold"], ["level"]),
        helper.make_node("Sub", ["image", "level"], ["above"]),
        helper.make_node("Relu", ["above"], ["weights"]),
        helper.make_node("ReduceSum", ["weights", "axis1"], ["mass"], keepdims=1),
        helper.make_node("Max", ["mass", "tiny"], ["denominator"]),
        helper.make_node("MatMul", ["weights", "centres"], ["moments"]),
        helper.make_node("Div", ["moments", "denominator"], ["xy_mm"]),
        helper.make_node("Mul", ["mass", "c2"], ["quadratic"]),
        helper.make_node("Add", ["quadratic", "c1"], ["slope"]),
        helper.make_node("Mul", ["slope", "mass"], ["varying"]),
        helper.make_node("Add", ["varying", "c0"], ["force_n"]),
        helper.make_node("Concat", ["xy_mm", "force_n"], ["prediction"], axis=1),
    ]
    graph = helper.make_graph(
        nodes, f"{type(model).__name__}",
        [helper.make_tensor_value_info("voltages", TensorProto.FLOAT, ["batch", n_channels])],
        [helper.make_tensor_value_info("prediction", TensorProto.FLOAT, ["batch", 3]),
         helper.make_tensor_value_info("image", TensorProto.FLOAT, ["batch", n_pixels])],
        inits)
    proto = helper.make_model(graph, opset_imports=[helper.make_opsetid("", opset)], producer_name="touchstone")
    proto.ir_version = min(proto.ir_version, 9)
    helper.set_model_props(proto, {"inputs": f"voltages[{n_channels}] float32 (change from the unloaded frame, V)",
                                   "outputs": "prediction: x_mm, y_mm, force_n; image"})
    onnx.checker.check_model(proto)
    return proto


def predict_with_onnx(session, voltages: np.ndarray) -> np.ndarray:
    """Run an onnxruntime session of the graph above on (n_frames, n_channels) voltages; a wrong
    width is a one-line InputError, not an onnxruntime traceback."""
    expected = session.get_inputs()[0].shape[1]
    voltages = np.asarray(voltages, dtype=np.float32)
    if voltages.ndim != 2 or voltages.shape[1] != expected:
        raise InputError(f"voltages must have shape (n_frames, {expected}), got {voltages.shape}")
    return session.run(["prediction"], {"voltages": voltages})[0]
