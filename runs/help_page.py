"""`python train.py --help`: one short page of the settings a user changes first, each with one
line, generated from the configs (runs/help_page.yaml names the keys and the config file whose
comment describes each; it is no Hydra config, so it lives beside this code, not in configs/);
`--help-all` is Hydra's full dump.

A description is the comment beside the key in its config file (continuation comment lines
joined), so the page cannot drift from the configs; a group lists its options from the files
in configs/<group>/ and the default this command composes.
"""
import re
import textwrap
from pathlib import Path

from omegaconf import OmegaConf

HELP_FILE = Path(__file__).with_suffix(".yaml")
WIDTH = 100
KEY_COLUMN = 24
LONGEST = 110       # a longer comment is cut at its first clause: the page is one line per setting
MOST_OPTIONS = 24
FULL = ("Every setting: python train.py --help-all (Hydra's full config); explained in docs/configuration.md.\n"
        "Mistakes are one line and exit code 2 (a misspelt key gets the closest valid ones).")


def key_comment(config_file: Path, key: str) -> str | None:
    """The comment beside `key`'s last part in `config_file`, with the comment-only lines under it
    that continue it (indented to the same column); None when the line has no comment."""
    leaf = key.rpartition(".")[2]
    lines = config_file.read_text().splitlines()
    for number, line in enumerate(lines):
        found = re.match(rf"^\s*{re.escape(leaf)}:[^#]*#\s?(.*)$", line)
        if not found:
            continue
        column = line.index("#")
        parts = [found.group(1).strip()]
        for more in lines[number + 1:]:
            if not more.strip().startswith("#") or more.index("#") != column:
                break
            parts.append(more.strip()[1:].strip())
        return first_clause(" ".join(parts))
    return None


def first_clause(text: str) -> str:
    """`text`, or, when longer than LONGEST, up to its first '; ' or '. ' (the rest is in the config)."""
    if len(text) <= LONGEST:
        return text
    cut = re.search(r"; |(?<!e\.g)(?<!i\.e)\. ", text)
    return text[:cut.start()].rstrip() if cut else text


def group_options(config_dir: Path, group: str) -> list[str]:
    """The options of a config group: its YAML files (base/ folders hold what they share)."""
    return sorted(p.stem for p in (config_dir / group).glob("*.yaml"))


def shown_value(cfg, key: str) -> str:
    """The value this command composes for `key`, '??? (needed)' for one a run must be given."""
    parent, _, leaf = key.rpartition(".")
    node = OmegaConf.select(cfg, parent) if parent else cfg
    if not OmegaConf.is_config(node) or leaf not in node.keys():   # `in` skips a missing value
        group = key.partition(".")[0]
        choice = OmegaConf.select(cfg, f"hydra.runtime.choices.{group}", default=None)
        return f"not used with {group}={choice}" if choice else "not in this config"
    if OmegaConf.is_missing(node, leaf):
        return "??? (needed)"
    value = OmegaConf.select(cfg, key)
    return str(OmegaConf.to_container(value) if OmegaConf.is_config(value) else value)


def entry_lines(name: str, value: str, description: str) -> list[str]:
    head = f"  {name:<{KEY_COLUMN}}"
    text = f"{description} [{value}]" if description else f"[{value}]"
    return textwrap.wrap(text, WIDTH, initial_indent=head, subsequent_indent=" " * len(head),
                         break_on_hyphens=False)


def help_page(config_dir: Path, cfg) -> str:
    """The page for the composed config `cfg` (composed with return_hydra_config=True)."""
    spec = OmegaConf.load(HELP_FILE)
    choices = OmegaConf.select(cfg, "hydra.runtime.choices", default={}) or {}
    lines = [spec.title, ""]
    for section, entries in spec.sections.items():
        lines.append(f"{section}:")
        for entry in entries:
            if "group" in entry:
                options = group_options(config_dir, entry.group)
                default = choices.get(entry.group) or "none"
                more = f", ... {len(options) - MOST_OPTIONS} more" if len(options) > MOST_OPTIONS else ""
                lines += entry_lines(entry.group, f"default: {default}",
                                     f"{entry.describe} (options: {', '.join(options[:MOST_OPTIONS])}{more})")
                continue
            described = key_comment(config_dir / entry["from"], entry.key) if "from" in entry else None
            lines += entry_lines(entry.key, shown_value(cfg, entry.key), described or entry.get("describe", ""))
        lines.append("")
    lines.append(FULL)
    return "\n".join(lines)
