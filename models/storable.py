"""The classes whose instances a fitted-state file (models/fitted_state.py) may hold: a registry
the classes join themselves, so no list of names is kept by hand.

A class registers where it is defined (`@storable`; Touchstone's estimators by deriving from
models/estimator_base.py) or, for a library's class, in the module of ours that puts it into a
fitted model (models/forest_kinds.py registers scikit-learn's forests); torch.nn's layers, which
every network is made of, are registered below. A class belongs here when its state is data (arrays, numbers,
strings, containers and other registered objects) and building it from that state (`__new__`,
then `__setstate__` or the attributes) runs nothing but its own bookkeeping.

Loading never imports what a file names, with one exception that keeps the registry complete
without a list of modules: a name under `models.` that has not registered yet is looked up by
importing that module of ours (what its import does is define and register classes), and the
class must then be registered. Every class a file names is thus Touchstone's, a library class
one of ours registered, or a torch.nn layer.
"""
import importlib.util

import torch

REGISTRY = "the storable-class registry (models/storable.py)"
OWN_PACKAGE = "models."


def class_name(cls) -> str:
    return f"{cls.__module__}.{cls.__qualname__}"


# full name -> class; read directly by the loader (models/fitted_state.py), which calls
# storable_class only for a name not registered yet
STORABLE: dict[str, type] = {}
CALLED: set[str] = set()   # rebuilt by calling them with their sizes (scikit-learn's Cython Tree), not __new__


def storable(*classes: type, called: bool = False):
    """Register `classes` as storable (usable as a class decorator: `@storable`). `called`:
    pickle rebuilds them by calling the class with arguments, which the loader then does too."""
    for cls in classes:
        STORABLE[class_name(cls)] = cls
        if called:
            CALLED.add(class_name(cls))
    return classes[0] if len(classes) == 1 else classes


def is_storable(cls) -> bool:
    return STORABLE.get(class_name(cls)) is cls


class NotStorable(LookupError):
    """A name the registry does not hold; the message names the class and the registry."""

    def __init__(self, name):
        self.name = name
        super().__init__(f"class {str(name)[:200]!r} is not in {REGISTRY}")


def storable_class(name):
    """The registered class of a full name; one of our model modules not imported yet is imported
    first (it registers its classes); anything else unregistered is NotStorable."""
    if type(name) is not str:
        raise NotStorable(name)
    if name not in STORABLE and name.startswith(OWN_PACKAGE) and _own_module(name.rpartition(".")[0]):
        importlib.import_module(name.rpartition(".")[0])
    if name not in STORABLE:
        raise NotStorable(name)
    return STORABLE[name]


def _own_module(module: str) -> bool:
    """Whether `module` is a module file of our models package (nothing else is imported for a name)."""
    if not all(part.isidentifier() for part in module.split(".")):
        return False
    try:
        return importlib.util.find_spec(module) is not None
    except ImportError:   # a parent that is no package of ours
        return False


def torch_layers() -> list[type]:
    """torch.nn's own layers and containers (torch.nn.modules: torch builds them from their tensors
    and settings); not its parallel wrappers, whose state joins a process group."""
    return [cls for cls in vars(torch.nn).values() if isinstance(cls, type) and issubclass(cls, torch.nn.Module)
            and cls.__module__.startswith("torch.nn.modules.")]


storable(*torch_layers())
