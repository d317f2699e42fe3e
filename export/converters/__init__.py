"""ONNX converters, one module per model family, registered by class (registry.py). Every module
of this package is imported here, so a family's converters register by the family's file being
in this folder."""
import importlib
import pkgutil

for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")
