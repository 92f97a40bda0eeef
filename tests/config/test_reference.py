"""docs/configuration.md: generated, current, complete, and true to what the loader does.

The reference is generated from the settings classes (dsfd.config.reference). These tests
check it against the committed file, against the keys of the shipped panel files, and against
the loader's behaviour: every limit it documents is enforced at that key path (and is
inclusive or exclusive as written), every allowed-values list rejects a value outside it, and
every default it documents is what a panel without that key gets.
"""

from __future__ import annotations

import copy
import dataclasses
import subprocess
import sys
import types
import typing
from typing import Any, get_type_hints

import pytest
import yaml

from dsfd.config import ConfigError, PanelConfig, panel_from_mapping
from dsfd.config.reference import (
    DOC_PATH,
    Entry,
    entries,
    find,
    main,
    nearest,
    normalise,
    render_markdown,
)
from tests.conftest import PANELS, ROOT

TABLE = entries()
BY_KEY = {e.key: e for e in TABLE}


def test_the_committed_reference_is_current():
    committed = (ROOT / DOC_PATH).read_text(encoding="utf-8")
    assert committed == render_markdown(), (
        "docs/configuration.md is stale: run python -m dsfd.config.reference "
        "--out docs/configuration.md")


def test_the_generator_command_detects_a_stale_file(tmp_path, capsys):
    stale = tmp_path / "configuration.md"
    stale.write_text(render_markdown().replace("min_window_h", "min_windw_h"), encoding="utf-8")
    assert main(["--check", str(stale)]) == 1
    assert main(["--out", str(stale)]) == 0
    assert main(["--check", str(stale)]) == 0
    assert "stale" in capsys.readouterr().err


def _yaml_keys(node: Any, prefix: str = "") -> set[str]:
    """Every key path of a parsed YAML document, list items as ``[]``."""
    out: set[str] = set()
    if isinstance(node, dict):
        for key, value in node.items():
            path = f"{prefix}.{key}" if prefix else str(key)
            out.add(path)
            out |= _yaml_keys(value, path)
    elif isinstance(node, list):
        for item in node:
            out |= _yaml_keys(item, prefix + "[]")
    return out


@pytest.mark.parametrize("panel", sorted(PANELS.glob("*.yaml")), ids=lambda p: p.name)
def test_every_key_of_a_shipped_panel_is_documented(panel):
    keys = _yaml_keys(yaml.safe_load(panel.read_text(encoding="utf-8")))
    documented = (ROOT / DOC_PATH).read_text(encoding="utf-8")
    missing = sorted(k for k in keys if f"`{k}`" not in documented)
    assert missing == []


def _accepted_keys(cls: type, prefix: str = "") -> set[str]:
    """The keys the loader accepts: it builds each class from its ``init`` fields
    (dsfd.config.loader._build_dataclass), recursing into mappings and lists of mappings."""
    out: set[str] = set()
    hints = get_type_hints(cls)
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        key = f"{prefix}.{f.name}" if prefix else f.name
        out.add(key)
        tp = hints[f.name]
        union = typing.get_origin(tp) in (typing.Union, types.UnionType)
        for arg in (typing.get_args(tp) if union else (tp,)):
            if dataclasses.is_dataclass(arg):
                out |= _accepted_keys(arg, key)
            elif getattr(arg, "__origin__", None) is tuple and dataclasses.is_dataclass(
                    arg.__args__[0]):
                out |= _accepted_keys(arg.__args__[0], key + "[]")
    return out


def test_every_key_the_loader_accepts_is_documented_and_nothing_else():
    assert _accepted_keys(PanelConfig) == set(BY_KEY)
    assert len(BY_KEY) == len(TABLE)  # no key twice


def test_every_key_has_a_description_and_every_number_a_unit():
    assert [e.key for e in TABLE if len(e.doc.split()) < 2] == []
    # Integers that count (cycles, steps, evaluations, ids, addresses) have no unit; every
    # real number has one, "1" when it is dimensionless.
    numbers = [e for e in TABLE if e.type_text.split(" or ")[0] in ("number", "list of numbers")]
    assert len(numbers) > 100
    assert [e.key for e in numbers if e.unit is None] == []


# ----------------------------------------------------------------- against the loader


def _full_panel() -> dict:
    """suwon-south with every optional section present (MQTT with TLS, an override input,
    actuator position feedback registers, a BACnet device with a foreign-device registration)."""
    data = yaml.safe_load((PANELS / "suwon-south.yaml").read_text(encoding="utf-8"))
    data["mqtt"] = {"host": "broker.example", "tls": {}}
    data["devices"]["entries"][0]["override_input"] = {"table": "coil", "address": 3}
    for actuator in data["devices"]["entries"][0]["actuators"]:
        actuator["feedback"] = {"address": 200 + actuator["address"]}
    data["bacnet"] = {"device_instance": 41001, "address": "127.0.0.1/8",
                      "foreign_device": {"bbmd": "127.0.0.2:47808"}}
    panel_from_mapping(data)  # valid as it stands
    return data


FULL = _full_panel()


def _locate(data: Any, key: str, *, last: bool = False) -> tuple[dict, str, str] | None:
    """The mapping that holds ``key`` in ``data``, the last name and the concrete path (the
    first list item that has the key), or None when the key cannot be in the document.
    Absent sections on the way are added empty (``{}``: the defaults of their keys) when no
    item has them. ``last``: the last list item that has the key (a register at the end of
    a map, where a longer default data type overlaps nothing)."""
    parts = key.replace("[]", ".[]").split(".")

    def walk(node: Any, i: int, path: str, create: bool) -> tuple[dict, str, str] | None:
        part = parts[i]
        if part == "[]":
            items = list(enumerate(node if isinstance(node, list) else []))
            for n, item in items[::-1] if last else items:
                if (hit := walk(item, i + 1, f"{path}[{n}]", create)) is not None:
                    return hit
            return None
        if not isinstance(node, dict):
            return None
        here = f"{path}.{part}" if path else part
        if i == len(parts) - 1:
            return node, part, here
        if create and node.get(part) is None and parts[i + 1] != "[]":
            node[part] = {}  # an absent section: its keys' defaults
        return walk(node[part], i + 1, here, create) if part in node else None

    return walk(data, 0, "", False) or walk(data, 0, "", True)


def _issues(data: dict) -> list:
    try:
        panel_from_mapping(data)
    except ConfigError as exc:
        return exc.issues
    return []


def _with(key: str, value: Any) -> tuple[dict, str]:
    data = copy.deepcopy(FULL)
    where = _locate(data, key)
    assert where is not None, f"{key}: not settable in the test panel"
    holder, name, path = where
    holder[name] = value
    return data, path


def _bounds(e: Entry) -> list[tuple[str, float]]:
    marks = {">": "gt", "≥": "ge", "<": "lt", "≤": "le"}
    out = []
    for part in (e.limits_text or "").split(", "):
        if part:
            sym, number = part.split(" ")
            out.append((marks[sym], float(number)))
    return out


LIMITED = [e for e in TABLE if e.limits_text]
CHOICES = [e for e in TABLE if e.allowed_text]
DEFAULTED = [e for e in TABLE if not e.section and e.default_text != "required"]


def _is_list(e: Entry) -> bool:
    return e.type_text.startswith("list")


def _is_int(e: Entry) -> bool:
    return e.type_text.split(" or ")[0] in ("integer", "list of integers")


@pytest.mark.parametrize("entry", LIMITED, ids=lambda e: e.key)
def test_each_documented_limit_is_enforced_at_its_key_path(entry):
    for kind, bound in _bounds(entry):
        step = 1 if _is_int(entry) else max(abs(bound) * 1e-3, 1e-6)
        outside = {"gt": bound, "ge": bound - step, "lt": bound, "le": bound + step}[kind]
        edge = {"gt": bound + step, "ge": bound, "lt": bound - step, "le": bound}[kind]
        if _is_int(entry):
            outside, edge = int(outside), int(edge)
        for value, rejected in ((outside, True), (edge, False)):
            data, path = _with(entry.key, [value] if _is_list(entry) else value)
            out_of_range = [i for i in _issues(data)
                            if i.path.startswith(path) and "out of range" in i.message]
            assert bool(out_of_range) == rejected, (entry.key, kind, bound, value)


@pytest.mark.parametrize("entry", CHOICES, ids=lambda e: e.key)
def test_each_documented_list_of_allowed_values_is_enforced(entry):
    allowed = [yaml.safe_load(a) for a in entry.allowed_text.split(", ")]
    bad = "not_one_of_them" if isinstance(allowed[0], str) else max(allowed) + 7
    data, path = _with(entry.key, [bad] if _is_list(entry) else bad)
    assert any(i.path.startswith(path) for i in _issues(data)), entry.key
    first, _ = _with(entry.key, [allowed[0]] if _is_list(entry) else allowed[0])
    assert not [i for i in _issues(first) if i.path.startswith(entry.key.split("[")[0])
                and "one of" in i.message], entry.key


def _attribute(obj: Any, concrete: str) -> Any:
    for part in concrete.replace("[", ".[").split("."):
        obj = obj[int(part[1:-1])] if part.startswith("[") else getattr(obj, part)
    return obj


@pytest.mark.parametrize("entry", DEFAULTED, ids=lambda e: e.key)
def test_each_documented_default_is_what_a_panel_without_the_key_gets(entry):
    data = copy.deepcopy(FULL)
    where = _locate(data, entry.key.rsplit(".", 1)[0] + ".x", last=True)
    assert where is not None, entry.key
    holder, _, path = where
    name = entry.key.rsplit(".", 1)[1]
    holder.pop(name, None)
    concrete = path.rsplit(".", 1)[0] + "." + name
    value = _attribute(panel_from_mapping(data), concrete)
    expected = yaml.safe_load(entry.default_text)
    if expected == "the defaults of its keys" or dataclasses.is_dataclass(value):
        return  # a section's default: its keys' defaults, checked one by one
    assert (list(value) if isinstance(value, tuple) else value) == expected, concrete


# ----------------------------------------------------------------- dsfd check-config --explain


def _dsfd(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "dsfd", *args], capture_output=True,
                          text=True, cwd=ROOT, timeout=120)


def test_explain_prints_one_entry_with_unit_default_and_limits():
    done = _dsfd("check-config", "--explain", "calibration.min_window_h")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "calibration.min_window_h"
    fields: dict[str, str] = {}
    for ln in lines[1:]:  # "  key:     value", then the value's wrapped lines
        key, sep, value = ln.partition(":")
        if sep and key.startswith("  ") and not key.startswith("   "):
            fields[key.strip()] = value.strip()
        else:
            fields["what"] += " " + ln.strip()
    assert fields["unit"] == "h" and fields["default"] == "0.25"
    assert fields["limits"] == "> 0, ≤ 48" and "first on-line update" in fields["what"]
    # the loader agrees: 48 h is allowed by the limit, 48.1 h is not
    assert not [i for i in _issues(_with("calibration.min_window_h", 48.0)[0])
                if "out of range" in i.message]
    assert any("out of range" in i.message
               for i in _issues(_with("calibration.min_window_h", 48.1)[0]))


def test_explain_takes_a_list_index_and_lists_allowed_values():
    done = _dsfd("check-config", "--explain", "devices.entries[1].serial.parity")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("devices.entries[].serial.parity\n")
    assert 'allowed: "N", "E", "O"' in done.stdout


def test_explain_of_an_unknown_key_exits_2_naming_it_and_the_nearest_keys():
    done = _dsfd("check-config", "--explain", "calibration.min_windw_h")
    assert done.returncode == 2 and done.stdout == ""
    assert "'calibration.min_windw_h'" in done.stderr
    assert "calibration.min_window_h" in done.stderr
    # a key put in the wrong section is found by its last name
    assert "calibration.min_window_h" in nearest("control.min_window_h")
    assert find("devices.entries[3].tcp.host") == BY_KEY["devices.entries[].tcp.host"]
    assert normalise("a[12].b[0]") == "a[].b[]"


def test_check_config_without_files_or_explain_is_a_usage_error():
    done = _dsfd("check-config")
    assert done.returncode == 2 and "--explain" in done.stderr
