"""The closest valid settings to a misspelt one, for the one-line error train.py prints.

Hydra answers an override of a key the config lacks (`data.target_colums=[x]`) with "To append
to your config use +data.target_colums=...", which is the wrong way for a key that exists under
another spelling: with `+` the typo would reach the data module as an unknown parameter. The
settings a command could have meant are the composed config's keys (without Hydra's own), and
the closest by spelling are offered instead.
"""
import difflib
import re

from omegaconf import DictConfig

NOT_A_KEY = re.compile(r"Could not override '([^']+)'")
CLOSE_ENOUGH = 0.75   # difflib's ratio: target_colums vs target_columns is 0.96, seed vs scene 0.67


def setting_keys(cfg: DictConfig, prefix: str = "") -> list[str]:
    """Every dotted key of the composed config, nodes and leaves, Hydra's own and `_target_`-style keys left out."""
    keys = []
    for key in cfg.keys():
        if str(key) == "hydra" and not prefix or str(key).startswith("_"):
            continue
        path = f"{prefix}{key}"
        keys.append(path)
        node = cfg._get_node(key)
        if isinstance(node, DictConfig) and not node._is_missing() and not node._is_none():
            keys.extend(setting_keys(node, path + "."))
    return keys


def closest_settings(key: str, keys: list[str], n: int = 3) -> list[str]:
    """Valid keys spelt most like `key`: those under the same parent first (data.target_colums ->
    data.target_columns), then any whose last part is close (seeds -> seed)."""
    parent, _, leaf = key.rpartition(".")
    same_parent = [k for k in keys if k.rpartition(".")[0] == parent]
    found = difflib.get_close_matches(key, same_parent, n=n, cutoff=CLOSE_ENOUGH)
    if not found:
        by_leaf = {k.rpartition(".")[2]: k for k in keys}
        found = [by_leaf[k] for k in difflib.get_close_matches(leaf, list(by_leaf), n=n, cutoff=CLOSE_ENOUGH)]
    return found


def misspelt_setting(message: str, compose_without) -> str | None:
    """The one-line error for Hydra's "Could not override 'KEY'" when a valid key is spelt like
    KEY, else None (Hydra's own message stands). `compose_without(key)` composes the command's
    config without that override (the keys a user could have meant)."""
    found = NOT_A_KEY.search(message)
    if not found:
        return None
    key = found.group(1).lstrip("+~")
    try:
        keys = setting_keys(compose_without(key))
    except Exception:   # another mistake in the same command: Hydra's message for this one stands
        return None
    close = closest_settings(key, keys)
    if not close:
        return None
    return f"{key} is not a setting; did you mean {' or '.join(close)}?"
