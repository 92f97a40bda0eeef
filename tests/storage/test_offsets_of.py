"""The heat-flux offsets of a ``parameters`` row's ``other`` JSON, read the same way by the
parameter detector and the energy at stake: a malformed or foreign ``other`` gives no offsets
(read as 0 by theta_at) instead of an exception in the findings thread."""

from __future__ import annotations

import sqlite3

import numpy as np

from dsfd.daemon.stake import theta_at
from dsfd.estimation.params import FIT_NAMES
from dsfd.storage.parameter_series import offsets_of


def test_only_numeric_offsets_of_a_json_object_are_read():
    assert offsets_of('{"q_x1": 3.5, "q_x3": -2, "q_x2": "x", "fit": "ok"}') == {
        "q_x1": 3.5, "q_x3": -2.0}
    for bad in (None, "", "not json", "[1, 2]", "7"):
        assert offsets_of(bad) == {}


def test_theta_at_reads_a_row_with_a_malformed_other_as_zero_offsets():
    names = [n for n in FIT_NAMES if not n.startswith("q_")]
    conn = sqlite3.connect(":memory:")
    conn.execute(f"CREATE TABLE parameters (time_s REAL, {', '.join(names)}, other TEXT)")
    conn.execute(f"INSERT INTO parameters VALUES (10.0, {', '.join('1.5' for _ in names)}, "
                 "'{broken')")
    theta = theta_at(conn, 20.0)
    assert theta is not None and theta.shape == (len(FIT_NAMES),)
    assert np.all(theta[[FIT_NAMES.index(n) for n in names]] == 1.5)
    assert np.all(theta[[FIT_NAMES.index(n) for n in FIT_NAMES if n.startswith("q_")]] == 0.0)
