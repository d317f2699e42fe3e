"""The scene contract: a scene runs exactly the effects it lists, each with its own seed.

A sensor module registers its effects in a dict `name -> function`, in the order its physical
chain applies them (the load before the material's response, the analogue reading before the
ADC). A scene config lists the ones it wants under `effects:` (a mapping name -> parameters).
Nothing is on by default: an effect that is not listed is never called, so it costs nothing.
Listed effects run in the chain's order, not the listing's: a variant that adds one effect to
its base scene (Hydra merges mappings by appending keys) cannot put it in the wrong place.

Each effect draws from its own random generator, derived from the scene seed and the effect's
name, so adding or removing one effect leaves every other effect's random numbers unchanged.
"""
import inspect
import zlib
from collections.abc import Callable, Mapping

import numpy as np

from common.errors import InputError


def random_generator_for(seed: int, name: str) -> np.random.Generator:
    """Random generator for one named consumer (an effect, the protocol) under one scene seed."""
    return np.random.default_rng([int(seed), zlib.crc32(name.encode())])


def resolve_effects(scene: str, requested: Mapping | None,
                    registry: Mapping[str, Callable]) -> list[tuple[str, Callable, dict]]:
    """Check a scene's `effects:` mapping against a sensor's registry.

    Returns (name, function, params) in the registry's (the physical chain's) order. An unknown effect or an unknown
    parameter is a one-line InputError naming the scene, the effect and what is valid.
    """
    requested = dict(requested or {})
    unknown = [name for name in requested if name not in registry]
    if unknown:
        raise InputError(f"scene {scene}: unknown effect '{unknown[0]}'; "
                         f"valid effects: {', '.join(sorted(registry))}")
    resolved = []
    for name, params in sorted(requested.items(), key=lambda item: list(registry).index(item[0])):
        params = dict(params or {})
        fn = registry[name]
        accepted = [p for p in inspect.signature(fn).parameters if p not in ("state", "rng")]
        extra = sorted(set(params) - set(accepted))
        if extra:
            raise InputError(f"scene {scene}: effect '{name}' has no parameter "
                             f"{', '.join(map(repr, extra))}; valid: {', '.join(accepted)}")
        resolved.append((name, fn, params))
    return resolved
