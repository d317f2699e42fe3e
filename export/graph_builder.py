"""Assemble one ONNX graph from several exported pieces plus the arithmetic that joins them.

onnx.compose merges two models at a time and refuses different opsets or IR versions; a
blend joins many pieces (a front end, K fold models per candidate, the weighting), so this
builder copies every piece's nodes and initialisers into one graph under a unique prefix,
wires its input to an existing tensor, and declares one opset per domain for the whole
model (the highest any piece needs; the operators used here kept their meaning across those
versions, which the parity tests check end to end).
"""
import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper


class GraphBuilder:
    def __init__(self, opset: int):
        self.opset = opset
        self.nodes, self.initializers, self.opsets = [], [], {"": opset}
        self._count = 0

    def name(self, stem: str) -> str:
        self._count += 1
        return f"{stem}_{self._count}"

    def add_model(self, model: onnx.ModelProto, inputs: dict[str, str], prefix: str) -> dict[str, str]:
        """Copy `model` in; its graph inputs read the tensors named in `inputs`; returns its outputs' names."""
        prefixed = onnx.compose.add_prefix(model, prefix=f"{prefix}/")
        graph = prefixed.graph
        rename = {f"{prefix}/{k}": v for k, v in inputs.items()}
        for node in graph.node:
            node.input[:] = [rename.get(i, i) for i in node.input]
            self.nodes.append(node)
        self.initializers.extend(graph.initializer)
        for entry in prefixed.opset_import:
            domain = entry.domain or ""
            self.opsets[domain] = max(self.opsets.get(domain, 0), entry.version)
        if prefixed.functions:
            raise ValueError("exported pieces with ONNX functions cannot be merged; export without them")
        return {o.name[len(prefix) + 1:]: o.name for o in graph.output}

    def const(self, array, stem="const") -> str:
        name = self.name(stem)
        self.initializers.append(numpy_helper.from_array(np.asarray(array), name))
        return name

    def op(self, op_type: str, inputs: list[str], stem: str | None = None, **attributes) -> str:
        output = self.name(stem or op_type.lower())
        self.nodes.append(helper.make_node(op_type, inputs, [output], **attributes))
        return output

    def identity(self, source: str, name: str) -> str:
        self.nodes.append(helper.make_node("Identity", [source], [name]))
        return name

    # -- arithmetic used by blends --------------------------------------------------------
    def stack(self, tensors: list[str]) -> str:
        axis = self.const(np.array([0], dtype=np.int64), "axis0")
        return self.op("Concat", [self.op("Unsqueeze", [t, axis]) for t in tensors], axis=0)

    def mean_and_variance(self, tensors: list[str]) -> tuple[str, str]:
        """Mean (float32) and unbiased variance (float64) over same-shaped float32 predictions
        (K >= 2). Computed in float64: squared deviations of far-extrapolated predictions
        overflow float32."""
        stacked = self.op("Cast", [self.stack(tensors)], to=TensorProto.DOUBLE)
        axis = self.const(np.array([0], dtype=np.int64), "axis0")
        mean = self.op("ReduceMean", [stacked, axis], keepdims=0)
        deviation = self.op("Sub", [stacked, mean])
        squares = self.op("ReduceSum", [self.op("Mul", [deviation, deviation]), axis], keepdims=0)
        variance = self.op("Div", [squares, self.const(np.array(len(tensors) - 1, dtype=np.float64))])
        return self.op("Cast", [mean], to=TensorProto.FLOAT), variance

    def half_width(self, model_variance: str, data_variance, conformal_scale) -> str:
        """A calibrated interval's half-width, q * sqrt(model variance + data variance), from a
        float64 model variance (eq. 23-24), as float32."""
        total = self.op("Add", [model_variance, self.const(np.asarray(data_variance, dtype=np.float64), "data_var")])
        half = self.op("Mul", [self.op("Sqrt", [total]),
                               self.const(np.asarray(conformal_scale, dtype=np.float64), "conformal")])
        return self.op("Cast", [half], to=TensorProto.FLOAT)

    def build(self, inputs, outputs, metadata: dict[str, str], ir_version: int = 10) -> onnx.ModelProto:
        graph = helper.make_graph(self.nodes, "touchstone", inputs, outputs, self.initializers)
        model = helper.make_model(graph, opset_imports=[helper.make_opsetid(d, v) for d, v in self.opsets.items()])
        model.ir_version = ir_version
        for key, value in metadata.items():
            model.metadata_props.append(onnx.StringStringEntryProto(key=key, value=value))
        onnx.checker.check_model(model)
        return model


def tensor(name: str, dims, dtype=TensorProto.FLOAT):
    return helper.make_tensor_value_info(name, dtype, dims)
