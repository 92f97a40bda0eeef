"""Typed YAML loading into frozen dataclasses, with errors that name the key path.

Every settings class in dsfd is a frozen dataclass whose fields are declared with
:func:`setting`. :func:`build` walks a parsed YAML mapping against such a class and
collects *every* problem (unknown key, missing key, wrong type, out-of-range value,
failed cross-field check) as a :class:`ConfigIssue` carrying the dotted key path
(``facade.cavity_depth_m``, ``drivers.modbus[0].registers[2].address``) and the bad
value, then raises one :class:`ConfigError` holding them all.

Parsing the YAML text itself is :mod:`dsfd.config.yaml_file`, so that importing the settings
types does not import ``yaml`` (the pure core takes these types).

Cross-field checks live on the dataclass as a method ``check(self) -> list[Problem]``;
a :class:`Problem` names the offending key relative to that dataclass.
"""

from __future__ import annotations

import dataclasses
import datetime
import math
import types
import typing
from collections.abc import Mapping
from dataclasses import MISSING, dataclass, field
from typing import Any, Literal, TypeVar, get_args, get_origin, get_type_hints

T = TypeVar("T")

__all__ = [
    "ConfigError",
    "ConfigIssue",
    "Problem",
    "build",
    "setting",
]


@dataclass(frozen=True)
class ConfigIssue:
    """One configuration problem.

    Attributes
    ----------
    path : str
        Dotted key path in the YAML document, e.g. ``louver.slat_width_m``.
    value : object
        The offending value as read from YAML (``MISSING`` text if absent).
    message : str
        What is wrong and what is allowed.
    """

    path: str
    value: Any
    message: str

    def __str__(self) -> str:
        shown = "<missing>" if self.value is _ABSENT else repr(self.value)
        return f"{self.path or '<root>'}: {shown}: {self.message}"


class ConfigError(ValueError):
    """Raised with every :class:`ConfigIssue` found in one document."""

    def __init__(self, issues: list[ConfigIssue], source: str | None = None) -> None:
        self.issues = list(issues)
        self.source = source
        head = f"{source}: " if source else ""
        lines = [f"{head}{len(self.issues)} configuration error(s)"]
        lines += [f"  {issue}" for issue in self.issues]
        super().__init__("\n".join(lines))


@dataclass(frozen=True)
class Problem:
    """A cross-field check failure reported by a settings class's ``check`` method.

    ``key`` is relative to the dataclass that reports it (may be dotted).
    """

    key: str
    value: Any
    message: str


class _Absent:
    def __repr__(self) -> str:
        return "<missing>"


_ABSENT = _Absent()


def setting(
    default: Any = MISSING,
    *,
    doc: str,
    unit: str | None = None,
    ge: float | None = None,
    gt: float | None = None,
    le: float | None = None,
    lt: float | None = None,
    choices: tuple[str, ...] | None = None,
    default_factory: Any = MISSING,
) -> Any:
    """Declare a settings field with its documentation, unit and numeric bounds.

    Parameters
    ----------
    default : object, optional
        Default used when the key is absent; without one the key is required.
    doc : str
        One-line description shown in generated documentation and errors.
    unit : str, optional
        Unit of the value, e.g. ``"m"``, ``"W/(m2 K)"``, ``"deg"``.
    ge, gt, le, lt : float, optional
        Inclusive / exclusive numeric bounds (applied to every element of a tuple).
    choices : tuple of str, optional
        The allowed names of a string (or of every item of a list of strings) that the
        class's ``check`` method enforces, e.g. the sensor signals; documentation only here
        (``Literal`` types carry their own). Listed by docs/configuration.md.
    default_factory : callable, optional
        As for :func:`dataclasses.field`.
    """
    meta = {"doc": doc, "unit": unit, "ge": ge, "gt": gt, "le": le, "lt": lt,
            "choices": choices}
    if default_factory is not MISSING:
        return field(default_factory=default_factory, metadata=meta)
    return field(default=default, metadata=meta)


def build(cls: type[T], data: Any, *, source: str | None = None, prefix: str = "") -> T:
    """Build settings class ``cls`` from parsed YAML ``data`` or raise :class:`ConfigError`."""
    issues: list[ConfigIssue] = []
    result = _build_dataclass(cls, data, prefix, issues)
    if issues:
        raise ConfigError(issues, source)
    return typing.cast(T, result)


def _join(prefix: str, key: str) -> str:
    return f"{prefix}.{key}" if prefix else key


def _build_dataclass(cls: type, data: Any, path: str, issues: list[ConfigIssue]) -> Any:
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        issues.append(ConfigIssue(path, data, f"expected a mapping for {cls.__name__}"))
        return None
    hints = get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    for key in data:
        if key not in fields:
            close = _closest(str(key), list(fields))
            hint = f" (did you mean {close!r}?)" if close else ""
            issues.append(
                ConfigIssue(_join(path, str(key)), data[key], f"unknown key{hint}")
            )
    kwargs: dict[str, Any] = {}
    n_before = len(issues)
    for name, f in fields.items():
        sub = _join(path, name)
        if name not in data:
            if f.default is MISSING and f.default_factory is MISSING:
                issues.append(ConfigIssue(sub, _ABSENT, "required key is missing"))
            continue
        value = _convert(hints[name], data[name], sub, issues, f.metadata)
        if value is not _ABSENT:
            kwargs[name] = value
    if len(issues) != n_before:
        return None
    try:
        obj = cls(**kwargs)
    except (TypeError, ValueError) as exc:
        issues.append(ConfigIssue(path, data, str(exc)))
        return None
    check = getattr(obj, "check", None)
    if callable(check):
        for problem in check():
            issues.append(ConfigIssue(_join(path, problem.key), problem.value, problem.message))
    return obj


def _convert(tp: Any, value: Any, path: str, issues: list[ConfigIssue], meta: Mapping) -> Any:
    origin = get_origin(tp)
    args = get_args(tp)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        if len(inner) == 1:
            return _convert(inner[0], value, path, issues, meta)
        trial: list[ConfigIssue] = []
        for candidate in inner:
            trial.clear()
            out = _convert(candidate, value, path, trial, meta)
            if not trial:
                return out
        issues.extend(trial)
        return _ABSENT
    if origin is Literal:
        if value in args and type(value) is type(args[args.index(value)]):
            return value
        choices = ", ".join(repr(a) for a in args)
        issues.append(ConfigIssue(path, value, f"must be one of {choices}"))
        return _ABSENT
    if origin is tuple:
        if not isinstance(value, list | tuple):
            issues.append(ConfigIssue(path, value, "expected a list"))
            return _ABSENT
        if len(args) == 2 and args[1] is Ellipsis:
            items = [
                _convert(args[0], v, f"{path}[{i}]", issues, meta) for i, v in enumerate(value)
            ]
        else:
            if len(value) != len(args):
                issues.append(ConfigIssue(path, value, f"expected a list of {len(args)} items"))
                return _ABSENT
            items = [
                _convert(a, v, f"{path}[{i}]", issues, meta)
                for i, (a, v) in enumerate(zip(args, value, strict=True))
            ]
        return _ABSENT if any(i is _ABSENT for i in items) else tuple(items)
    if dataclasses.is_dataclass(tp):
        n = len(issues)
        obj = _build_dataclass(tp, value, path, issues)
        return _ABSENT if len(issues) != n else obj
    if tp is bool:
        if isinstance(value, bool):
            return value
        issues.append(ConfigIssue(path, value, "expected true or false"))
        return _ABSENT
    if tp is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return _bounded(value, path, issues, meta)
        issues.append(ConfigIssue(path, value, "expected an integer"))
        return _ABSENT
    if tp is float:
        if isinstance(value, int | float) and not isinstance(value, bool):
            fv = float(value)
            if not math.isfinite(fv):
                issues.append(ConfigIssue(path, value, "expected a finite number"))
                return _ABSENT
            return _bounded(fv, path, issues, meta)
        issues.append(ConfigIssue(path, value, "expected a number"))
        return _ABSENT
    if tp is str:
        if isinstance(value, str):
            return value
        if isinstance(value, datetime.date):  # YAML 1.1 reads an unquoted 2026-12-25 as a date
            return value.isoformat()
        issues.append(ConfigIssue(path, value, "expected a string"))
        return _ABSENT
    raise TypeError(f"unsupported settings type {tp!r} at {path}")  # programming error


def _bounded(value: float, path: str, issues: list[ConfigIssue], meta: Mapping) -> Any:
    unit = f" {meta['unit']}" if meta.get("unit") not in (None, "1") else ""
    checks = (
        ("ge", lambda b: value >= b, ">="),
        ("gt", lambda b: value > b, ">"),
        ("le", lambda b: value <= b, "<="),
        ("lt", lambda b: value < b, "<"),
    )
    for key, ok, sym in checks:
        bound = meta.get(key)
        if bound is not None and not ok(bound):
            issues.append(ConfigIssue(path, value, f"out of range: must be {sym} {bound}{unit}"))
            return _ABSENT
    return value


def _closest(word: str, candidates: list[str]) -> str | None:
    import difflib

    hits = difflib.get_close_matches(word, candidates, n=1, cutoff=0.75)
    return hits[0] if hits else None
