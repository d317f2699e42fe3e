"""Fitted state in a format that cannot run code: what a run saves of its deployable pipeline.

A pickle names the functions that rebuild it, so loading one runs whatever its author chose.
This format names no functions. `save_fitted(obj, path)` writes one NPZ file, read back with
`np.load(..., allow_pickle=False)`:

    structure        the object graph as a JSON document (stored as uint8 bytes)
    blob_0, blob_1   every array, laid end to end, one flat array per dtype (few zip members,
                     so a forest of thousands of trees saves and loads in one read per dtype)

In the JSON, numbers, strings, booleans and null stand for themselves; everything else is an
object with one tag: list, tuple, set, frozenset, dict and ordered_dict (a JSON object when the
keys are strings, else [key, value] pairs), array (blob, offset, shape, order), scalar (a 0-d
array), bytes, tensor (its array, device, whether it is a Parameter and requires grad), device,
random_state / generator (numpy's, by their state), factory (a network factory, see below), and
object: a class named by its full name with the state its own pickling protocol
(`__reduce_ex__`) gives, restored the way pickle restores it (`cls.__new__`, then `__setstate__`
or the attributes) - but only for a class in the storable-class registry (models/storable.py:
classes register themselves, a library's class is registered by the model of ours that holds
it), checked before anything of the class is called. The one class built by calling it is
scikit-learn's Cython Tree (registered `called`), with its sizes. A container, array, tensor or
object met a second time is {"ref": id} to the "id" its first occurrence carries, so shared
objects stay shared (an LSTM's flat weights are its parameters) and cycles through objects
resolve.

Nothing callable is stored: a function, a lambda, a class or a module anywhere in the graph is
refused when saving (TypeError naming where it sits), so a new model type that holds one fails
loudly in the round-trip tests instead of writing a file that cannot be read. The one exception
is a network factory, the `functools.partial(NetClass, **settings)` a time-series classifier
is configured with (Hydra's `_partial_: true`): stored as the class name and its keyword
values, rebuilt as a plain functools.partial of a registered torch.nn.Module class, which is
only called if the loaded estimator is fitted again.

Loading a file that is not such a file - not a zip, a member missing, bad JSON, a truncated
blob, an object array, a class not on the list - is a one-line InputError naming the file.
"""
import contextlib
import copyreg
import functools
import gc
import json
import math
from collections import OrderedDict
from pathlib import Path

import numpy as np
import torch

from common.atomic import atomic_write
from common.errors import InputError
from models.storable import CALLED, REGISTRY, STORABLE, NotStorable, class_name, is_storable, storable_class

FORMAT, VERSION = "touchstone fitted state", 1
STRUCTURE = "structure"

# numpy's bit generators, rebuilt by name for a Generator's state
BIT_GENERATORS = ("MT19937", "PCG64", "PCG64DXSM", "Philox", "SFC64")
PLAIN = (type(None), bool, int, float, str)  # JSON's own values (exact types: no subclasses)
CONTAINERS = {list: "list", tuple: "tuple", set: "set", frozenset: "frozenset"}


class Unstorable(TypeError):
    """Something in the graph is not data; `where` is the attribute path to it."""

    def __init__(self, reason: str, where: str = ""):
        self.reason, self.where = reason, where
        super().__init__(f"cannot store {where or 'the object'}: {reason}")

    def inside(self, step: str) -> "Unstorable":
        return Unstorable(self.reason, step + self.where)


class Encoder:
    """Object graph -> (JSON-able structure, flat arrays by dtype)."""

    def __init__(self):
        self.memo = {}         # id(obj) -> (node id, obj): the obj kept alive so its id is not reused
        self.nodes = []        # node id -> its node
        self.referenced = set()
        self.blobs = {}        # dtype -> (blob index, list of flat parts, elements so far)

    def encode(self, obj):
        kind = type(obj)
        if kind in PLAIN:
            return obj
        seen = self.memo.get(id(obj))
        if seen is not None:
            self.referenced.add(seen[0])
            return {"ref": seen[0]}
        node_id = len(self.nodes)
        self.memo[id(obj)] = (node_id, obj)
        self.nodes.append(None)
        node = self.nodes[node_id] = self._node(obj, kind)
        node["id"] = node_id
        return node

    def structure(self, obj):
        """The JSON-able structure of `obj`; ids kept only where a ref names them (smaller and
        faster to read)."""
        root = self.encode(obj)
        for node_id, node in enumerate(self.nodes):
            if node_id not in self.referenced:
                del node["id"]
        return root

    def _child(self, value, step: str):
        try:
            return self.encode(value)
        except Unstorable as error:
            raise error.inside(step) from None

    def _node(self, obj, kind) -> dict:
        if kind in CONTAINERS:
            return {CONTAINERS[kind]: [self._child(v, f"[{i}]") for i, v in enumerate(obj)]}
        if kind is dict or kind is OrderedDict:  # string keys: a JSON object; others: [key, value] pairs
            tag = "dict" if kind is dict else "ordered_dict"
            if all(type(k) is str for k in obj):
                return {tag: {k: self._child(v, f".{k}") for k, v in obj.items()}}
            return {tag: [[self._child(k, "(a key)"), self._child(v, f"[{k!r}]")] for k, v in obj.items()]}
        if kind is np.ndarray:
            return self._array(obj)
        if isinstance(obj, np.generic):
            return {"scalar": self._array(np.asarray(obj))}
        if kind is bytes:
            return {"bytes": self._array(np.frombuffer(obj, dtype=np.uint8))}
        if kind is torch.Tensor or kind is torch.nn.Parameter:
            return self._tensor(obj)
        if kind is torch.device:
            return {"device": str(obj)}
        if kind is np.random.RandomState:
            return {"random_state": self._child(obj.get_state(legacy=False), "(state)")}
        if kind is np.random.Generator:
            bits = obj.bit_generator
            return {"generator": type(bits).__name__, "state": self._child(bits.state, "(state)")}
        if isinstance(obj, functools.partial):
            return self._factory(obj)
        return self._object(obj, kind)

    def _array(self, array: np.ndarray) -> dict:
        if array.dtype.hasobject:
            raise Unstorable(f"an array of Python objects (dtype {array.dtype}) is not data")
        order = "F" if array.flags.f_contiguous and not array.flags.c_contiguous else "C"
        index, parts, size = self.blobs.setdefault(array.dtype, (len(self.blobs), [], 0))
        parts.append(array.ravel(order=order))
        self.blobs[array.dtype] = (index, parts, size + array.size)
        return {"array": index, "offset": size, "shape": list(array.shape), "order": order}

    def _tensor(self, tensor: torch.Tensor) -> dict:
        values = tensor.detach().cpu()
        try:
            array = values.numpy()
        except TypeError as error:  # a dtype numpy lacks (bfloat16, ...)
            raise Unstorable(f"a tensor of dtype {tensor.dtype} ({error})") from None
        return {"tensor": self._array(array), "device": str(tensor.device),
                "parameter": type(tensor) is torch.nn.Parameter, "requires_grad": tensor.requires_grad}

    def _factory(self, factory: functools.partial) -> dict:
        cls = factory.func
        if not (isinstance(cls, type) and issubclass(cls, torch.nn.Module) and is_storable(cls)):
            raise Unstorable(f"a callable ({factory!r}) is not data; only a factory of a network class in {REGISTRY} "
                             "is stored")
        return {"factory": class_name(cls), "args": self._child(tuple(factory.args), "(args)"),
                "keywords": self._child(dict(factory.keywords), "(keywords)")}

    def _object(self, obj, kind) -> dict:
        name = class_name(kind)
        if not is_storable(kind) and callable(obj):  # a function, lambda, method, class, ...
            raise Unstorable(f"{getattr(obj, '__qualname__', repr(obj))!r} ({name}) is code, not data")
        if not is_storable(kind):
            raise Unstorable(f"class {name} is not in {REGISTRY}; register it (models.storable.storable) if its "
                             "state is data")
        reduced = obj.__reduce_ex__(4)
        if isinstance(reduced, str) or len(reduced) > 3 and any(part is not None for part in reduced[3:]):
            raise Unstorable(f"{name} pickles itself in a way this format does not store")
        rebuild, args, state = (tuple(reduced) + (None,))[:3]
        if rebuild is copyreg.__newobj__ and len(args) == 1 and args[0] is kind:
            node = {"object": name}
        elif rebuild is kind and name in CALLED:
            node = {"object": name, "args": self._child(tuple(args), "(args)")}
        else:
            raise Unstorable(f"{name} is rebuilt by {rebuild!r}, which this format does not call")
        if state is not None:
            node["state"] = self._child(state, "" if type(state) is dict else "(state)")
        return node

    def arrays(self) -> dict[str, np.ndarray]:
        return {f"blob_{index}": np.concatenate(parts) if parts else np.empty(0)
                for index, parts, _ in self.blobs.values()}


def save_fitted(obj, path) -> Path:
    """Write `obj` (a graph of data and listed classes) to `path` atomically; TypeError, naming
    where it sits, for anything that is not data."""
    encoder = Encoder()
    try:
        with gc_paused():
            root = encoder.structure(obj)
            text = json.dumps({"format": FORMAT, "version": VERSION, "root": root}, separators=(",", ":"))
    except Unstorable as error:
        raise TypeError(f"{path}: cannot store {type(obj).__name__}{error.where}: {error.reason}") from None
    arrays = {STRUCTURE: np.frombuffer(text.encode(), dtype=np.uint8), **encoder.arrays()}

    def write(tmp: Path):
        with open(tmp, "wb") as handle:
            np.savez(handle, **arrays)
    return atomic_write(path, write)


class Decoder:
    """(JSON structure, blobs) -> the object graph, building only listed classes."""

    def __init__(self, blobs: dict[int, np.ndarray]):
        self.blobs = blobs
        self.objects = {}

    def decode(self, node):
        if type(node) in PLAIN:
            return node
        if type(node) is not dict:
            raise ValueError(f"unexpected {type(node).__name__} in the structure")
        if "ref" in node:
            return self.objects[_integer(node["ref"])]
        node_id = node.get("id")
        if node_id is not None and (_integer(node_id) in self.objects):
            raise ValueError(f"id {node_id} defined twice")
        for tag in ("list", "set", "frozenset", "tuple"):
            if tag in node:
                return self._sequence(tag, node[tag], node_id)
        if "dict" in node or "ordered_dict" in node:
            mapping = self._register(node_id, {} if "dict" in node else OrderedDict())
            items = node.get("dict", node.get("ordered_dict"))
            if type(items) is dict:  # string keys
                for key, value in items.items():
                    mapping[key] = self.decode(value)
            else:
                for key, value in _pairs(items):
                    key = self.decode(key)
                    mapping[key] = self.decode(value)
            return mapping
        if "object" in node:
            return self._object(node, node_id)
        return self._register(node_id, self._value(node))

    def _register(self, node_id, obj):
        if node_id is not None:  # only nodes that a ref names carry an id
            self.objects[node_id] = obj
        return obj

    def _sequence(self, tag: str, items, node_id):
        if type(items) is not list:
            raise ValueError(f"{tag} is not a list")
        if tag == "list":  # registered before its items, as pickle does, so it may contain itself
            values = self._register(node_id, [])
            values.extend(self.decode(item) for item in items)
            return values
        kind = {"set": set, "frozenset": frozenset, "tuple": tuple}[tag]
        return self._register(node_id, kind(self.decode(item) for item in items))

    def _value(self, node: dict):
        if "array" in node:
            return self._array(node)
        if "scalar" in node:
            return self._array(node["scalar"])[()]
        if "bytes" in node:
            return self._array(node["bytes"]).tobytes()
        if "tensor" in node:
            tensor = torch.from_numpy(self._array(node["tensor"])).to(torch.device(str(node["device"])))
            if node["parameter"] is True:
                return torch.nn.Parameter(tensor, requires_grad=node["requires_grad"] is True)
            return tensor.requires_grad_(node["requires_grad"] is True)
        if "device" in node:
            return torch.device(str(node["device"]))
        if "random_state" in node:
            generator = np.random.RandomState()
            generator.set_state(self.decode(node["random_state"]))
            return generator
        if "generator" in node:
            if node["generator"] not in BIT_GENERATORS:
                raise ValueError(f"unknown bit generator {node['generator']!r}")
            bits = getattr(np.random, node["generator"])()
            bits.state = self.decode(node["state"])
            return np.random.Generator(bits)
        if "factory" in node:
            cls = _registered(node["factory"])
            if not issubclass(cls, torch.nn.Module):
                raise ValueError(f"a factory of {node['factory']}, which is not a network")
            return functools.partial(cls, *self.decode(node["args"]), **self.decode(node["keywords"]))
        raise ValueError(f"unknown node {sorted(node)[:3]}")

    def _array(self, node) -> np.ndarray:
        if type(node) is not dict:
            raise ValueError("an array entry is not an object")
        blob = self.blobs[_integer(node["array"])]
        if blob.ndim != 1:
            raise ValueError("a blob is not one-dimensional")
        offset, shape, order = _integer(node["offset"]), [_integer(n) for n in node["shape"]], node["order"]
        size = math.prod(shape)
        if offset < 0 or min(shape, default=0) < 0 or offset + size > len(blob) or order not in ("C", "F"):
            raise ValueError(f"an array entry outside its blob (blob of {len(blob)}, offset {offset}, shape {shape})")
        return blob[offset:offset + size].reshape(shape, order=order)

    def _object(self, node: dict, node_id):
        cls = _registered(node["object"])
        if "args" in node:
            if node["object"] not in CALLED:
                raise ValueError(f"{node['object']} is not built by calling it")
            obj = cls(*self.decode(node["args"]))
        else:
            obj = cls.__new__(cls)
        self._register(node_id, obj)
        if "state" in node:
            set_state(obj, self.decode(node["state"]))
        return obj


def _registered(name) -> type:
    """The registered class of a full name: the registry read directly, models/storable.py asked
    only for a name not registered yet (or refused)."""
    found = STORABLE.get(name) if type(name) is str else None
    return found if found is not None else storable_class(name)


def set_state(obj, state):
    """As pickle's BUILD: the class's __setstate__, or the state's attributes (and slots)."""
    setstate = getattr(obj, "__setstate__", None)
    if setstate is not None:
        setstate(state)
        return
    slots = None
    if isinstance(state, tuple) and len(state) == 2:
        state, slots = state
    if state:
        obj.__dict__.update(state)
    for key, value in (slots or {}).items():
        setattr(obj, key, value)


def _integer(value) -> int:
    if type(value) is not int:
        raise ValueError(f"expected an integer, got {value!r}"[:120])
    return value


def _pairs(pairs):
    if type(pairs) is not list or any(type(p) is not list or len(p) != 2 for p in pairs):
        raise ValueError("a mapping is neither an object nor a list of [key, value] pairs")
    return pairs


@contextlib.contextmanager
def gc_paused():
    """The cyclic garbage collector off while a graph is built or taken apart: its passes over
    the hundreds of thousands of new containers of a big forest tripled the load time (there is
    no garbage to find meanwhile; it runs again afterwards)."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def load_fitted(path):
    """The object graph saved by save_fitted; InputError (one line, naming the file) for any
    file that is not one, or that names a class off the list."""
    path = Path(path)
    try:
        archive = np.load(path, allow_pickle=False)  # an object array or a pickle is refused unread
        if not isinstance(archive, np.lib.npyio.NpzFile):
            raise ValueError("a single .npy array, not an NPZ archive")
        with archive, gc_paused():
            members = set(archive.files)
            if STRUCTURE not in members:
                raise ValueError(f"no '{STRUCTURE}' member")
            document = json.loads(archive[STRUCTURE].tobytes().decode())
            blobs = {int(name[len("blob_"):]): archive[name] for name in members
                     if name.startswith("blob_") and name[len("blob_"):].isdigit()}
            if type(document) is not dict or document.get("format") != FORMAT:
                raise ValueError("not a Touchstone fitted-state document")
            if document.get("version") != VERSION:
                raise ValueError(f"format version {document.get('version')!r}; this Touchstone reads version {VERSION}")
            return Decoder(blobs).decode(document["root"])
    except NotStorable as error:
        raise InputError(f"{path}: names class {str(error.name)[:200]!r}, which is not on the list of classes a "
                         f"fitted-state file may build ({REGISTRY}); refused") from None
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except InputError:
        raise
    except Exception as error:  # every way a file can be malformed (RecursionError too) is the same answer
        reason = str(error).splitlines()[0][:200] if str(error) else ""
        raise InputError(f"{path}: not a readable fitted-state file ({type(error).__name__}"
                         f"{': ' + reason if reason else ''})") from None

