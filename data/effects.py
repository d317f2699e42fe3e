"""The scene contract: a scene runs exactly the effects it lists, in order, each with its own seed.

A sensor module registers its effects in a dict `name -> function`. A scene config lists
the ones it wants under `effects:` (a mapping name -> parameters, in order). Nothing is on
by default: an effect that is not listed is never called, so it costs nothing.

Each effect draws from its own random stream, derived from the scene seed and the effect's
name, so adding or removing one effect leaves every other effect's random numbers unchanged.
"""
import inspect
import zlib
from collections.abc import Callable, Mapping

import numpy as np

from data.errors import InputError


def stream(seed: int, name: str) -> np.random.Generator:
    """Random generator for one named consumer (an effect, the protocol) under one scene seed."""
    return np.random.default_rng([int(seed), zlib.crc32(name.encode())])


def resolve_effects(scene: str, requested: Mapping | None,
                    registry: Mapping[str, Callable]) -> list[tuple[str, Callable, dict]]:
    """Check a scene's `effects:` mapping against a sensor's registry.

    Returns (name, function, params) in the listed order. An unknown effect or an unknown
    parameter is a one-line InputError naming the scene, the effect and what is valid.
    """
    resolved = []
    for name, params in (requested or {}).items():
        if name not in registry:
            raise InputError(f"scene {scene}: unknown effect '{name}'; "
                             f"valid effects: {', '.join(sorted(registry))}")
        params = dict(params or {})
        fn = registry[name]
        accepted = [p for p in inspect.signature(fn).parameters if p not in ("state", "rng")]
        extra = sorted(set(params) - set(accepted))
        if extra:
            raise InputError(f"scene {scene}: effect '{name}' has no parameter "
                             f"{', '.join(map(repr, extra))}; valid: {', '.join(accepted)}")
        resolved.append((name, fn, params))
    return resolved
