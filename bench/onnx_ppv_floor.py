"""How fast can a standard-op ONNX graph count MiniRocket's PPV features at all?

    .venv/bin/python bench/onnx_ppv_floor.py                    # lengths 150 251 427 1460, 9,996 features
    .venv/bin/python bench/onnx_ppv_floor.py --lengths 1460 --repeats 3

MiniRocket's features are proportions of positive values: for each of its 9,996 (kernel,
dilation, bias) triples, the share of the L positions where the kernel output exceeds the bias.
aeon computes them in one numba loop that never stores a comparison; onnxruntime runs each node
of a graph as its own pass over memory, so every formulation of the count stores 9,996 x L
intermediate values at least once. This bench times that count ALONE, with the kernel outputs
given as the graph's input (no transform, no head: a lower bound for any exported MiniRocket
that counts this way), in every formulation the standard operator sets offer:
  greater_cast_mean    Greater -> Cast(float) -> ReduceMean                 (models/rocket/minirocket.py)
  sub_sign_sum         Sub -> Sign -> ReduceSum, (sum + L) / 2L
  greater_uint8_matmul Greater -> Cast(uint8) -> MatMulInteger with ones    (bytes, not floats)
  binarizer_mean       Sub -> ai.onnx.ml Binarizer -> ReduceMean            (compare and cast in one node)
  relu_min_sum         Sub -> Mul(big) -> Clip(0, 1) -> ReduceMean          (saturating step; equal except
                       within 1/big of a bias)
one thread, batch 1, median of `--repeats` x 50 calls. The layout follows the exported graph: per
dilation, the 84 kernels' outputs (84, 1, L) against their biases (84, features at that dilation),
with MiniRocket's dilations and feature counts at each length (dilations_and_features). Compare
with aeon's predict per recording in bench/rocket_parity.py, run beside it under the same load.
Appends one record per length (each repeat's median per formulation) to results/onnx_ppv_floor.jsonl.
"""
import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import onnx  # noqa: E402
import onnxruntime as ort  # noqa: E402
from onnx import TensorProto, helper, numpy_helper  # noqa: E402

from common.result_records import recording  # noqa: E402
from models.rocket.minirocket import N_KERNELS, dilations_and_features  # noqa: E402

FORMULATIONS = ("greater_cast_mean", "sub_sign_sum", "greater_uint8_matmul", "binarizer_mean", "relu_min_sum",
                "kernel_blocks", "time_blocks")
BLOCK_ELEMENTS = 1 << 18   # comparisons per block in the blocked formulations: 1 MB of float 0/1, half of L2 here
CALLS = 50                 # calls per repeat; a repeat's figure is their median
# The graphs timed are built here, on MiniRocket's layout (dilations and features per length) and
# against the count its exported graph makes (greater_cast_mean).
MEASURED_CODE = ["bench/onnx_ppv_floor.py", "models/rocket/minirocket.py"]


def blocked_nodes(formulation: str, biases: np.ndarray, length: int, k: int) -> tuple[list, list]:
    """Greater -> Cast -> ReduceSum on blocks of at most BLOCK_ELEMENTS comparisons, so that
    each node's output stays in cache: `kernel_blocks` splits the 84 kernels (a Split of the
    outputs, each block against its biases, a Concat of the counts), `time_blocks` the L steps
    (a Split along time, each block's partial counts added)."""
    name, count = (lambda base: f"{base}{k}"), biases.shape[1]
    per_row = count * length
    inits = [numpy_helper.from_array(np.array([2], dtype=np.int64), name("axes")),
             numpy_helper.from_array(np.float32(1.0 / length), name("scale"))]
    nodes = []
    if formulation == "kernel_blocks":
        rows = max(1, BLOCK_ELEMENTS // per_row)
        sizes = [min(rows, N_KERNELS - s) for s in range(0, N_KERNELS, rows)]
        inits.append(numpy_helper.from_array(np.array(sizes, dtype=np.int64), name("sizes")))
        nodes.append(helper.make_node("Split", [name("c"), name("sizes")], [name(f"c_{b}_") for b in range(len(sizes))], axis=0))
        for b, start in enumerate(range(0, N_KERNELS, rows)):
            block = f"{b}_{k}"
            inits.append(numpy_helper.from_array(biases[start:start + rows, :, None].astype(np.float32), f"biases_{block}"))
            nodes += [helper.make_node("Greater", [name(f"c_{b}_"), f"biases_{block}"], [f"above_{block}"]),
                      helper.make_node("Cast", [f"above_{block}"], [f"above_f_{block}"], to=TensorProto.FLOAT),
                      helper.make_node("ReduceSum", [f"above_f_{block}", name("axes")], [f"count_{block}"], keepdims=0)]
        nodes.append(helper.make_node("Concat", [f"count_{b}_{k}" for b in range(len(sizes))], [name("total")], axis=0))
    else:
        steps = max(1, BLOCK_ELEMENTS // (N_KERNELS * count))
        sizes = [min(steps, length - s) for s in range(0, length, steps)]
        inits += [numpy_helper.from_array(np.array(sizes, dtype=np.int64), name("sizes")),
                  numpy_helper.from_array(biases[:, :, None].astype(np.float32), name("biases"))]
        nodes.append(helper.make_node("Split", [name("c"), name("sizes")], [name(f"c_{b}_") for b in range(len(sizes))], axis=2))
        for b in range(len(sizes)):
            block = f"{b}_{k}"
            nodes += [helper.make_node("Greater", [name(f"c_{b}_"), name("biases")], [f"above_{block}"]),
                      helper.make_node("Cast", [f"above_{block}"], [f"above_f_{block}"], to=TensorProto.FLOAT),
                      helper.make_node("ReduceSum", [f"above_f_{block}", name("axes")], [f"count_{block}"], keepdims=0)]
        partial = f"count_0_{k}"
        for b in range(1, len(sizes)):
            nodes.append(helper.make_node("Add", [partial, f"count_{b}_{k}"], [f"sum_{b}_{k}"]))
            partial = f"sum_{b}_{k}"
        nodes.append(helper.make_node("Identity", [partial], [name("total")]))
    nodes.append(helper.make_node("Mul", [name("total"), name("scale")], [name("ppv")]))
    return nodes, inits


def count_nodes(formulation: str, biases: np.ndarray, length: int, k: int) -> tuple[list, list]:
    """Nodes and initialisers from one dilation's kernel outputs `c{k}` (84, 1, L) to its
    (84, features) PPVs `ppv{k}` against `biases` (84, features)."""
    def name(base):
        return f"{base}{k}"

    def const(base, value):
        return numpy_helper.from_array(np.asarray(value), name(base))

    if formulation in ("kernel_blocks", "time_blocks"):
        return blocked_nodes(formulation, biases, length, k)
    inits = [const("biases", biases[:, :, None].astype(np.float32)), const("axes", np.array([2], dtype=np.int64))]
    c, b, axes = name("c"), name("biases"), name("axes")
    if formulation == "greater_cast_mean":
        nodes = [helper.make_node("Greater", [c, b], [name("above")]),
                 helper.make_node("Cast", [name("above")], [name("above_f")], to=TensorProto.FLOAT),
                 helper.make_node("ReduceMean", [name("above_f"), axes], [name("ppv")], keepdims=0)]
    elif formulation == "sub_sign_sum":   # a tie's sign 0 counts half: the exported graph uses Greater
        inits += [const("half", np.float32(0.5 / length)), const("offset", np.float32(0.5))]
        nodes = [helper.make_node("Sub", [c, b], [name("d")]), helper.make_node("Sign", [name("d")], [name("s")]),
                 helper.make_node("ReduceSum", [name("s"), axes], [name("total")], keepdims=0),
                 helper.make_node("Mul", [name("total"), name("half")], [name("scaled")]),
                 helper.make_node("Add", [name("scaled"), name("offset")], [name("ppv")])]
    elif formulation == "greater_uint8_matmul":
        inits = inits[:1] + [const("ones", np.ones((length, 1), dtype=np.uint8)), const("scale", np.float32(1.0 / length)),
                             const("shape", np.array(biases.shape, dtype=np.int64))]
        nodes = [helper.make_node("Greater", [c, b], [name("above")]),
                 helper.make_node("Cast", [name("above")], [name("above_u8")], to=TensorProto.UINT8),
                 helper.make_node("MatMulInteger", [name("above_u8"), name("ones")], [name("count")]),
                 helper.make_node("Cast", [name("count")], [name("count_f")], to=TensorProto.FLOAT),
                 helper.make_node("Mul", [name("count_f"), name("scale")], [name("scaled")]),
                 helper.make_node("Reshape", [name("scaled"), name("shape")], [name("ppv")])]
    elif formulation == "binarizer_mean":
        nodes = [helper.make_node("Sub", [c, b], [name("d")]),
                 helper.make_node("Binarizer", [name("d")], [name("above_f")], domain="ai.onnx.ml", threshold=0.0),
                 helper.make_node("ReduceMean", [name("above_f"), axes], [name("ppv")], keepdims=0)]
    elif formulation == "relu_min_sum":
        inits += [const("big", np.float32(1e6)), const("low", np.float32(0.0)), const("high", np.float32(1.0))]
        nodes = [helper.make_node("Sub", [c, b], [name("d")]), helper.make_node("Mul", [name("d"), name("big")], [name("e")]),
                 helper.make_node("Clip", [name("e"), name("low"), name("high")], [name("step")]),
                 helper.make_node("ReduceMean", [name("step"), axes], [name("ppv")], keepdims=0)]
    else:
        raise ValueError(f"unknown formulation {formulation}")
    return nodes, inits


def count_graph(formulation: str, biases: list, length: int) -> onnx.ModelProto:
    """A graph from each dilation's kernel outputs (84, 1, L) to all its PPVs, concatenated."""
    nodes, inits = [], []
    for k, per_dilation in enumerate(biases):
        more_nodes, more_inits = count_nodes(formulation, per_dilation, length, k)
        nodes += more_nodes
        inits += more_inits
    nodes.append(helper.make_node("Concat", [f"ppv{k}" for k in range(len(biases))], ["ppv"], axis=1))
    inputs = [helper.make_tensor_value_info(f"c{k}", TensorProto.FLOAT, [N_KERNELS, 1, length])
              for k in range(len(biases))]
    graph = helper.make_graph(nodes, formulation, inputs, [helper.make_tensor_value_info("ppv", TensorProto.FLOAT, None)],
                              inits)
    return helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18), helper.make_opsetid("ai.onnx.ml", 3)])


def time_ms(session, feed, repeats: int, clock=time.perf_counter) -> list[float]:
    """Each repeat's median milliseconds per call, after five warm-up calls."""
    for _ in range(5):
        session.run(None, feed)
    medians = []
    for _ in range(repeats):
        calls = []
        for _ in range(CALLS):
            start = clock()
            session.run(None, feed)
            calls.append(clock() - start)
        medians.append(1e3 * float(np.median(calls)))
    return medians


def measure_length(length: int, args, rng, options, clock) -> dict:
    """Each formulation's per-repeat milliseconds at one length, checked to count as numpy does."""
    _, counts = dilations_and_features(length, 9_996)
    outputs = [rng.normal(size=(N_KERNELS, 1, length)).astype(np.float32) for _ in counts]
    biases = [np.sort(rng.normal(size=(N_KERNELS, count)), axis=1).astype(np.float32) for count in counts]
    reference = np.concatenate([(c > b[:, :, None]).mean(axis=2) for c, b in zip(outputs, biases)], axis=1)
    feed = {f"c{k}": c for k, c in enumerate(outputs)}
    ms = {}
    for formulation in args.formulations:
        session = ort.InferenceSession(count_graph(formulation, biases, length).SerializeToString(), options,
                                       providers=["CPUExecutionProvider"])
        ppv = session.run(None, feed)[0]
        assert np.abs(ppv - reference).max() <= 1.0 / length + 1e-6, formulation   # the same counts, up to a tie
        ms[formulation] = time_ms(session, feed, args.repeats, clock)
    return {"length": length, "dilations": len(counts), "features_per_kernel": reference.shape[1],
            "comparisons": reference.size * length, "ms_by_repeat": ms, "load_average": os.getloadavg()[0]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lengths", nargs="+", type=int, default=[150, 251, 427, 1460])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--cpu-time", action="store_true",
                        help="time each call by the process's CPU time, not the wall clock: on a loaded machine "
                             "it leaves out the time other processes hold the core (not the cache they evict)")
    parser.add_argument("--formulations", nargs="+", default=list(FORMULATIONS), choices=FORMULATIONS)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    options = ort.SessionOptions()
    options.intra_op_num_threads = options.inter_op_num_threads = 1
    clock = time.process_time if args.cpu_time else time.perf_counter
    print("| length | dilations, features x L (comparisons) | " + " | ".join(args.formulations) + " | load average |")
    print("|---|---|" + "---|" * len(args.formulations) + "---|")
    # The clock is in the name: CPU-time figures do not stand in for wall-clock ones.
    name_suffix = "_cpu_time" if args.cpu_time else ""
    settings = {"clock": "cpu" if args.cpu_time else "wall", "threads": 1, "batch": 1, "calls_per_repeat": CALLS}
    with recording("onnx_ppv_floor", MEASURED_CODE) as record:
        for length in args.lengths:
            row = measure_length(length, args, rng, options, clock)
            cells = [f"{np.median(ms):.2f}" for ms in row["ms_by_repeat"].values()]
            print(f"| {length} | {row['dilations']}, {row['features_per_kernel']} x {length} "
                  f"({row['comparisons'] / 1e6:.1f} M) | " + " | ".join(cells) + f" | {row['load_average']:.1f} |",
                  flush=True)
            record.add(f"length_{length}{name_suffix}", {**row, **settings}, seeds=[0])


if __name__ == "__main__":
    main()
