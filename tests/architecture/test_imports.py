"""The package layering of docs/architecture: imports flow one way, the core stays pure."""

from __future__ import annotations

import subprocess
import sys

import pytest

import dsfd
from tests.architecture.imports import cycles, package_graph

#: The pure core and what it may import (config types and the leaf modules).
CORE = {"physics", "estimation", "control"}
CORE_MAY_IMPORT = CORE | {"config", "measured", "signals", "registers"}
#: Third-party modules of the edges that the core must not load, even indirectly.
EDGE_LIBRARIES = ("yaml", "pymodbus", "serial", "sqlite3", "structlog")


def test_no_package_level_import_cycle():
    assert cycles(package_graph()) == []


def test_the_cycle_finder_finds_a_cycle():
    # The check above can only fail if cycles() sees one when there is one.
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


@pytest.mark.parametrize("package", sorted(CORE))
def test_the_core_imports_only_config_types_and_the_core(package):
    extra = package_graph().get(package, set()) - CORE_MAY_IMPORT
    assert not extra, f"dsfd.{package} imports {sorted(extra)}"


def test_importing_the_core_loads_no_edge_library():
    code = ("import sys\n"
            "import dsfd.physics.model, dsfd.estimation, dsfd.control.optimiser\n"
            f"print(','.join(m for m in {EDGE_LIBRARIES!r} if m in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == ""


def test_import_dsfd_is_light_and_every_public_name_resolves():
    code = ("import sys, dsfd\n"
            "print(','.join(m for m in sys.modules if m.startswith('dsfd.')))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == ""  # names load on first use
    for name in dsfd.__all__:
        assert getattr(dsfd, name) is not None
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        _ = dsfd.nope
