"""Panel configuration: YAML → frozen dataclasses, with key-path errors."""

from __future__ import annotations

from pathlib import Path

from dsfd.config.loader import ConfigError, ConfigIssue, build
from dsfd.config.panel import REGIME_OPENINGS, PanelConfig
from dsfd.config.parameters import FIT_NAMES, PARAMETER_NAMES, Param

__all__ = [
    "FIT_NAMES",
    "PARAMETER_NAMES",
    "REGIME_OPENINGS",
    "ConfigError",
    "ConfigIssue",
    "PanelConfig",
    "Param",
    "load_panel",
    "panel_from_mapping",
]


def panel_from_mapping(data: object, *, source: str | None = None) -> PanelConfig:
    """Build a :class:`PanelConfig` from an already parsed YAML document."""
    return build(PanelConfig, data, source=source)


def load_panel(path: str | Path) -> PanelConfig:
    """Read and validate one panel YAML file; raise :class:`ConfigError` naming key paths."""
    from dsfd.config.yaml_file import load_yaml  # only the edges read files

    data = load_yaml(path)
    return panel_from_mapping(data, source=str(path))
