"""The configuration reference: every key of a panel file, read from the settings classes.

Each field of the frozen settings dataclasses is declared with :func:`dsfd.config.loader.setting`,
which records its description, unit, bounds and (for names a ``check`` enforces) its allowed
values; ``Literal`` types carry their own allowed values. This module walks those classes from
:class:`dsfd.config.panel.PanelConfig` down, exactly as the loader does (``dataclasses.fields``
with ``init``), and turns every key into an :class:`Entry`. docs/configuration.md is generated
from it, and ``dsfd check-config --explain KEY`` prints one entry::

    python -m dsfd.config.reference --out docs/configuration.md   # regenerate
    python -m dsfd.config.reference --check docs/configuration.md # exit 1 if stale

Key paths are dotted; an item of a list is written ``[]`` (``devices.entries[].tcp.host``),
and ``--explain`` also takes an index (``devices.entries[0].tcp.host``).
"""

from __future__ import annotations

import argparse
import dataclasses
import difflib
import json
import re
import sys
import textwrap
import types
import typing
from collections.abc import Sequence
from dataclasses import MISSING, dataclass
from pathlib import Path
from typing import Any, Literal, get_args, get_origin, get_type_hints

__all__ = ["Entry", "entries", "explain_text", "find", "main", "nearest", "normalise",
           "render_markdown"]

#: What the reference is generated into (relative to the repository).
DOC_PATH = "docs/configuration.md"
REGENERATE = "python -m dsfd.config.reference --out docs/configuration.md"
_WIDTH = 92  # columns of an --explain entry


@dataclass(frozen=True, kw_only=True)
class Entry:
    """One key of a panel file as the reference shows it."""

    key: str
    type_text: str
    unit: str | None
    default_text: str
    limits_text: str | None
    allowed_text: str | None
    doc: str
    section: bool  # a mapping (or list of mappings) whose keys follow

    @property
    def top(self) -> str:
        return self.key.split(".")[0].split("[")[0]


def entries(root: type | None = None) -> list[Entry]:
    """Every key the loader accepts under ``root`` (default: the whole panel file), in the
    order of the settings classes' fields, each section before its keys."""
    if root is None:
        from dsfd.config.panel import PanelConfig

        root = PanelConfig
    out: list[Entry] = []
    _walk(root, "", None, out)
    return out


def _walk(cls: type, prefix: str, parent_unit: str | None, out: list[Entry]) -> None:
    hints = get_type_hints(cls)
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        key = f"{prefix}.{f.name}" if prefix else f.name
        tp = hints[f.name]
        meta = f.metadata
        # A unit on a mapping-typed key (a calibrated parameter's default/lower/upper) is
        # the unit of the numbers inside it.
        unit = meta.get("unit") or (parent_unit if _is_number(tp) else None)
        inner, listed = _dataclass_inside(tp)
        out.append(Entry(key=key, type_text=_type_text(tp), unit=unit,
                         default_text=_default_text(f), limits_text=_limits_text(meta),
                         allowed_text=_allowed_text(tp, meta), doc=str(meta.get("doc", "")),
                         section=inner is not None))
        if inner is not None:
            _walk(inner, key + ("[]" if listed else ""), meta.get("unit"), out)


def _strip_none(tp: Any) -> tuple[list[Any], bool]:
    if get_origin(tp) in (typing.Union, types.UnionType):
        args = list(get_args(tp))
        return [a for a in args if a is not type(None)], type(None) in args
    return [tp], False


def _dataclass_inside(tp: Any) -> tuple[type | None, bool]:
    """The settings class of a mapping key or of the items of a list key, and which."""
    inner, _ = _strip_none(tp)
    if len(inner) == 1:
        t = inner[0]
        if dataclasses.is_dataclass(t):
            return typing.cast(type, t), False
        if get_origin(t) is tuple:
            args = get_args(t)
            if args and dataclasses.is_dataclass(args[0]):
                return typing.cast(type, args[0]), True
    return None, False


def _is_number(tp: Any) -> bool:
    inner, _ = _strip_none(tp)
    return all(t in (int, float) for t in inner)


_NAMES = {bool: "boolean", int: "integer", float: "number", str: "string"}


def _type_text(tp: Any) -> str:
    inner, nullable = _strip_none(tp)
    words = [_one_type(t) for t in inner]
    text = " or ".join(words) if len(words) < 3 else ", ".join(words[:-1]) + " or " + words[-1]
    return text + (" or null" if nullable else "")


def _one_type(t: Any) -> str:
    if dataclasses.is_dataclass(t):
        return "mapping"
    origin = get_origin(t)
    if origin is Literal:
        kinds = {type(a) for a in get_args(t)}
        return "integer" if kinds == {int} else "string"
    if origin is tuple:
        args = get_args(t)
        item = args[0]
        if dataclasses.is_dataclass(item):
            return "list of mappings"
        name = _NAMES.get(item, str(item))
        if len(args) == 2 and args[1] is Ellipsis:
            return f"list of {name}s"
        return f"list of {len(args)} {name}s"
    return _NAMES.get(t, str(t))


def _yaml(value: Any) -> str:
    """A default as it would be written in the YAML file."""
    if isinstance(value, tuple):
        return "[" + ", ".join(_yaml(v) for v in value) + "]"
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    text = repr(value)
    if isinstance(value, float) and "e" in text and "." not in text:
        # YAML 1.1 (PyYAML) reads 1e-06 as a string; 1.0e-06 is a number
        text = text.replace("e", ".0e")
    return text


def _default_text(f: dataclasses.Field) -> str:
    if f.default is not MISSING:
        return _yaml(f.default)
    if f.default_factory is not MISSING:
        made = f.default_factory()
        return "the defaults of its keys" if dataclasses.is_dataclass(made) else _yaml(made)
    return "required"


def _limits_text(meta: typing.Mapping[str, Any]) -> str | None:
    marks = (("gt", ">"), ("ge", "≥"), ("lt", "<"), ("le", "≤"))
    parts = [f"{sym} {_number(meta[k])}" for k, sym in marks if meta.get(k) is not None]
    return ", ".join(parts) or None


def _number(value: float) -> str:
    """A limit as written: whole numbers in full (BACnet's device instance ≤ 4194302 must
    not read as 4.1943e+06), others in the shortest form."""
    if isinstance(value, int) or (float(value).is_integer() and abs(value) < 1e15):
        return str(int(value))
    return f"{value:g}"


def _allowed_text(tp: Any, meta: typing.Mapping[str, Any]) -> str | None:
    if meta.get("choices"):
        return ", ".join(meta["choices"])
    inner, _ = _strip_none(tp)
    for t in inner:
        if get_origin(t) is Literal:
            return ", ".join(_yaml(a) for a in get_args(t))
    return None


# ----------------------------------------------------------------- lookup


_INDEX = re.compile(r"\[\d*\]")


def normalise(key: str) -> str:
    """``devices.entries[0].tcp.host`` → ``devices.entries[].tcp.host``."""
    return _INDEX.sub("[]", key.strip())


def find(key: str, table: Sequence[Entry] | None = None) -> Entry | None:
    """The entry of ``key`` (list indices allowed), or None."""
    want = normalise(key)
    for e in table if table is not None else entries():
        if e.key == want:
            return e
    return None


def nearest(key: str, table: Sequence[Entry] | None = None, *, n: int = 3) -> list[str]:
    """The documented keys most like ``key``: the closest full paths, and keys with the same
    last name elsewhere (a key put in the wrong section)."""
    keys = [e.key for e in (table if table is not None else entries())]
    want = normalise(key)
    out = difflib.get_close_matches(want, keys, n=n, cutoff=0.6)
    leaf = want.rsplit(".", 1)[-1]
    leaves = {k: k.rsplit(".", 1)[-1] for k in keys}
    near_leaf = set(difflib.get_close_matches(leaf, list(set(leaves.values())), n=2, cutoff=0.75))
    out += [k for k, lf in leaves.items() if lf in near_leaf and k not in out]
    return out[:n + 2]


def explain_text(e: Entry) -> str:
    """The entry as ``dsfd check-config --explain`` prints it."""
    unit = "1 (dimensionless)" if e.unit == "1" else e.unit
    rows = [("type", e.type_text), ("unit", None if e.section else unit),
            ("default", e.default_text), ("limits", e.limits_text),
            ("allowed", e.allowed_text), ("what", e.doc)]
    lines = [e.key]
    for name, value in rows:
        if value:
            lines += textwrap.wrap(value, width=_WIDTH, initial_indent=f"  {name + ':':9}",
                                   subsequent_indent=" " * 11, break_on_hyphens=False)
    return "\n".join(lines)


# ----------------------------------------------------------------- Markdown


def _md_entry(e: Entry) -> list[str]:
    facts = [e.type_text + (f" [{e.unit}]" if e.unit and not e.section else "")]
    facts.append(f"default `{e.default_text}`" if e.default_text != "required"
                 else "**required**")
    if e.default_text == "the defaults of its keys":
        facts[-1] = "default: the defaults of its keys"
    if e.limits_text:
        facts.append(f"limits {e.limits_text}")
    if e.allowed_text:
        facts.append(f"one of `{e.allowed_text}`" if ", " not in e.allowed_text
                     else "one of " + ", ".join(f"`{a}`" for a in e.allowed_text.split(", ")))
    level = "###" if e.section else "####"
    return [f"{level} `{e.key}`", "", e.doc.rstrip(".") + ".", "", " · ".join(facts), ""]


def render_markdown(table: Sequence[Entry] | None = None) -> str:
    """docs/configuration.md: an index of the sections, then every key."""
    table = list(table if table is not None else entries())
    tops = [e for e in table if "." not in e.key]
    head = [
        "# Panel configuration reference",
        "",
        "<!-- Generated from the settings classes in dsfd/config/ by",
        f"     `{REGENERATE}`;",
        "     tests/config/test_reference.py fails when it is stale. Do not edit by hand. -->",
        "",
        "One YAML file per façade panel (`config/panels/`): site, façade geometry, the three",
        "glass layers, the louver (or `louver: null`), the four dampers (absent ones `null`),",
        "room, daylight proxy, model options and the calibrated parameters with their bounds,",
        "and for the daemon its devices, safety pipeline, state and (optionally) MQTT link.",
        "Units are in the key names (`cavity_depth_m`, `azimuth_deg`). Unknown keys, wrong",
        "types, out-of-range values and inconsistent geometry are errors that name the key",
        "path and the bad value (`dsfd check-config FILE`, and `dsfd run` before it opens",
        "anything), e.g.",
        "",
        "```",
        "facade.cavity_dept_m: 0.25: unknown key (did you mean 'cavity_depth_m'?)",
        "louver.slat_width_m: 0.05: slat wider than the cavity depth 0.04 m",
        "```",
        "",
        "Shipped panels: `suwon-south` (the paper's unit: 250 mm cavity, black PVC louver),",
        "`suwon-south-400-white` (400 mm cavity, white louver), `suwon-south-no-louver`,",
        "`aalborg-cube` (the Aalborg 'Cube' façade of `dsfd convert-aalborg`).",
        "",
        "This page lists every key. `dsfd check-config --explain KEY` prints one entry:",
        "",
        "```sh",
        "dsfd check-config --explain calibration.min_window_h",
        "dsfd check-config config/panels/*.yaml",
        "```",
        "",
        "An item of a list is written `[]` (`devices.entries[].tcp.host`); a section that may be",
        "`null` (no louver, no devices, no MQTT) lists its keys for when it is given.",
        "Units in brackets; `[1]` is a dimensionless number.",
        "",
        "| section | what |",
        "|---|---|",
    ]
    head += [f"| [`{e.key}`](#{e.key}) | {e.doc.rstrip('.')} |" for e in tops]
    body: list[str] = []
    for e in table:
        if "." not in e.key:
            body += ["", f"## {e.key}", "", e.doc.rstrip(".") + ".", "",
                     f"{e.type_text} · " + (f"default: {e.default_text}"
                                             if e.default_text != "required"
                                             else "**required**"), ""]
        else:
            body += _md_entry(e)
    return "\n".join(head + body).rstrip() + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m dsfd.config.reference",
        description="Write the panel configuration reference (Markdown) generated from the "
        "settings classes.")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--out", type=Path, help=f"write it here (e.g. {DOC_PATH})")
    group.add_argument("--check", type=Path, metavar="FILE",
                       help="exit 1 if FILE differs from what would be generated")
    args = parser.parse_args(argv)
    text = render_markdown()
    if args.check is not None:
        if args.check.read_text(encoding="utf-8") != text:
            print(f"{args.check} is stale: run {REGENERATE}", file=sys.stderr)
            return 1
        print(f"{args.check} is current")
        return 0
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")
        print(f"wrote {args.out} ({len(text.splitlines())} lines)")
        return 0
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
