"""The parameters of a `_target_` of ours, read from its source file with `ast`, without importing
it: runs/config_checks.py checks a config before torch and scikit-learn are loaded, so a typo costs
a second, not a start-up. Targets outside this repository are not read (None: left to
instantiation).
"""
import ast
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NO_DEFAULT = object()   # a parameter without a default


@lru_cache(maxsize=None)
def module_constant(module: str, name: str) -> tuple:
    """A module-level tuple of strings, read from the source (the module imports torch or
    scikit-learn; this check runs before they are loaded)."""
    tree = ast.parse((ROOT / (module.replace(".", "/") + ".py")).read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == name for t in node.targets):
            return tuple(ast.literal_eval(node.value))
    raise LookupError(f"{module}.{name}")


@dataclass(frozen=True)
class Parameter:
    name: str
    default: object      # NO_DEFAULT, or the literal default (None when it is not a literal)
    annotation: ast.expr | None


@lru_cache(maxsize=None)
def target_signature(target: str) -> tuple[tuple[Parameter, ...], bool] | None:
    """(keyword parameters, takes **kwargs) of a class's __init__ or a function in this repo, read
    from its source; None when they cannot be known without importing it."""
    module, _, name = target.rpartition(".")
    path = ROOT / (module.replace(".", "/") + ".py")
    if not module or not path.is_file():
        return None
    tree = ast.parse(path.read_text())
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name == name:
            return _class_signature(node)
        if isinstance(node, ast.FunctionDef) and node.name == name:
            parameters, takes_kwargs = _signature(node, skip_first=False)
            forwarded = _forwarded_to(tree, node) if takes_kwargs else None
            if forwarded is None:
                return parameters, takes_kwargs
            # a factory (data.datamodules.regression.from_table) passes its **kwargs on to the
            # class it returns: it takes its own parameters and that class's
            own = {p.name for p in parameters}
            return parameters + tuple(p for p in forwarded[0] if p.name not in own), forwarded[1]
    return None


def _forwarded_to(tree: ast.Module, function: ast.FunctionDef):
    """The signature of the class of ours a function's return annotation names (imported by name
    into its module), or None."""
    returns = function.returns
    if not isinstance(returns, ast.Name):
        return None
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name == returns.id:
            return _class_signature(node)
        if isinstance(node, ast.ImportFrom) and any(alias.name == returns.id and alias.asname is None
                                                    for alias in node.names):
            return target_signature(f"{node.module}.{returns.id}")
    return None


def _class_signature(node: ast.ClassDef):
    init = next((f for f in node.body if isinstance(f, ast.FunctionDef) and f.name == "__init__"), None)
    return _signature(init, skip_first=True) if init else None


def _signature(function: ast.FunctionDef, skip_first: bool):
    arguments = function.args
    positional = arguments.posonlyargs + arguments.args
    defaults = [NO_DEFAULT] * (len(positional) - len(arguments.defaults)) + list(arguments.defaults)
    pairs = list(zip(positional, defaults)) + [(a, NO_DEFAULT if d is None else d)
                                                for a, d in zip(arguments.kwonlyargs, arguments.kw_defaults)]
    parameters = tuple(Parameter(a.arg, d if d is NO_DEFAULT else _literal(d), a.annotation) for a, d in pairs)
    return parameters[1:] if skip_first else parameters, arguments.kwarg is not None


def _literal(node: ast.expr):
    try:
        return ast.literal_eval(node)
    except (ValueError, TypeError, SyntaxError):  # a name or an expression: its type is unknown here
        return None


def target_parameters(target: str) -> tuple[str, ...] | None:
    """The keyword parameters of a target of ours; None when unknown or it takes **kwargs."""
    signature = target_signature(target)
    if signature is None or signature[1]:
        return None
    return tuple(p.name for p in signature[0])
