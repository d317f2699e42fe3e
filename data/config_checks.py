"""Config mistakes found before anything heavy is imported, so a typo costs a second, not a start-up.

Hydra already refuses unknown groups, options and keys of the composed config. What it cannot see
is a key added with `+` (`+scene.sparkle=1`) that the component's constructor does not take: that
would surface only when the component is built, after torch and friends are loaded, as a
TypeError. Here each `_target_` of ours is looked up in its source file with `ast` (no import)
and the node's keys are checked against its parameters. Targets outside this repository
(scikit-learn, torch) and constructors taking **kwargs are left to instantiation.
"""
import ast
from functools import lru_cache
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from data.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
HYDRA_KEYS = {"_target_", "_convert_", "_partial_", "_recursive_", "_args_"}


@lru_cache(maxsize=None)
def target_parameters(target: str) -> tuple[str, ...] | None:
    """Keyword parameters of a class's __init__ or a function in this repo, read from its source;
    None when they cannot be known without importing it."""
    module, _, name = target.rpartition(".")
    path = ROOT / (module.replace(".", "/") + ".py")
    if not module or not path.is_file():
        return None
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.ClassDef) and node.name == name:
            init = next((f for f in node.body if isinstance(f, ast.FunctionDef) and f.name == "__init__"), None)
            return _parameters(init, skip_first=True) if init else None
        if isinstance(node, ast.FunctionDef) and node.name == name:
            return _parameters(node, skip_first=False)
    return None


def _parameters(function: ast.FunctionDef, skip_first: bool) -> tuple[str, ...] | None:
    if function.args.kwarg is not None:
        return None
    names = [a.arg for a in function.args.posonlyargs + function.args.args + function.args.kwonlyargs]
    return tuple(names[1:] if skip_first else names)


def check_target_keys(cfg: DictConfig) -> None:
    """Every node with a `_target_` of ours carries only keys its target takes."""
    def walk(node, where):
        if isinstance(node, dict):
            target = node.get("_target_")
            if isinstance(target, str):
                accepted = target_parameters(target)
                unknown = sorted(set(node) - HYDRA_KEYS - set(accepted or ()))
                if accepted is not None and unknown:
                    raise InputError(f"{where or 'config'} has no parameter '{unknown[0]}' (valid: "
                                     f"{', '.join(accepted)})")
            for key, value in node.items():
                walk(value, f"{where}.{key}" if where else str(key))
        elif isinstance(node, list):
            for index, value in enumerate(node):
                walk(value, f"{where}[{index}]")
    walk(OmegaConf.to_container(cfg, resolve=False), "")
