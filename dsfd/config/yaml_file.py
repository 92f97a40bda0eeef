"""Reading a YAML file into plain data, refusing duplicate keys (the only module of
:mod:`dsfd.config` that imports ``yaml``: edges load files, the core takes the types)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from dsfd.config.loader import ConfigError, ConfigIssue

__all__ = ["load_yaml"]


class _DuplicateKeyLoader(yaml.SafeLoader):
    """SafeLoader that refuses duplicate mapping keys instead of silently keeping the last."""


def _construct_mapping(loader: _DuplicateKeyLoader, node: yaml.MappingNode, deep: bool = False):
    seen: dict[Any, Any] = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in seen:
            mark = key_node.start_mark
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key {key!r} (line {mark.line + 1})", mark
            )
        seen[key] = True
    return loader.construct_mapping(node, deep=deep)


_DuplicateKeyLoader.add_constructor(
    yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping
)


def load_yaml(path: str | Path) -> Any:
    """Parse a YAML file; syntax errors and duplicate keys become a :class:`ConfigError`."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError([ConfigIssue("", str(path), f"cannot read file: {exc}")]) from exc
    try:
        return yaml.load(text, Loader=_DuplicateKeyLoader)
    except yaml.YAMLError as exc:
        raise ConfigError([ConfigIssue("", str(path), f"invalid YAML: {exc}")], str(path)) from exc
