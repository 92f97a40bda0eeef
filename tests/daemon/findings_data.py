"""Databases the daemon could have written, for the findings check
(tests/daemon/test_findings_stage.py) and the report's diagnostics section
(tests/report/test_report_diagnostics.py): synthetic readings with a known change."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np

from dsfd.storage.timeseries import Store

__all__ = ["DAYS", "NIGHT_STEP_NIGHT", "STEP_AT", "STEP_S", "SUWON", "T0", "night_database",
           "residual_database", "write_database"]

STEP_S = 120.0  # two-minute cycles: five readings in every 10-min block
DAYS = 7
T0 = 1.7e9
STEP_AT = T0 + 6.5 * 86400.0
OUTPUTS = (*(f"x{i}_c" for i in range(1, 6)), "v_cav_ms")
#: Where the night database's nights are (the Suwon test unit) and its room air [°C].
SUWON = {"latitude_deg": 37.3, "longitude_deg": 127.0, "room_c": 21.0}
#: The night database's thermocouple step starts on this night (counted from 0).
NIGHT_STEP_NIGHT = 15


def write_database(tmp_path: Path, t: np.ndarray, readings: dict[str, np.ndarray],
                   predictions: dict[str, np.ndarray]) -> Path:
    """A database the daemon could have written: one cycle per ``t``, GOOD readings and
    the ``model`` table's columns given."""
    store = Store.open(tmp_path)
    run = store.begin_run(panel="p", mode="test", version="0", config_path=None)
    store.close()
    n = t.size
    db = tmp_path / "timeseries.sqlite"
    with sqlite3.connect(db) as conn:
        conn.executemany("INSERT INTO samples (run_id, cycle, time_s, signal, value, quality) "
                         "VALUES (?, ?, ?, ?, ?, 'good')",
                         [(run, c, t[c], name, float(v[c])) for name, v in readings.items()
                          for c in range(n)])
        conn.executemany("INSERT INTO decisions (run_id, cycle, slot, time_s, time_utc, "
                         "method, phi_deg, afr, or_pct, write_status, cycle_ms) VALUES "
                         "(?, ?, ?, ?, 't', 'mpc', 0.0, 10, 0.0, 'dry-run', 1.0)",
                         [(run, c, c, t[c]) for c in range(n)])
        cols = ", ".join(["run_id", "cycle", "time_s", *predictions])
        conn.executemany(f"INSERT INTO model ({cols}) VALUES "
                         f"({', '.join('?' for _ in range(3 + len(predictions)))})",
                         [(run, c, t[c], *(float(m[c]) for m in predictions.values()))
                          for c in range(n)])
    return db


def residual_database(tmp_path: Path, *, new_control: bool = False,
                      record_control: bool = False) -> Path:
    """Seven days of cycles: predictions follow a daily cycle, readings are the prediction
    plus AR(1) noise (0.3 K or 0.02 m/s sd), and x3 reads 1 K high from day 6.5 on.

    ``new_control``: instead of the x3 step, from day 6.5 for three hours the controller
    applies regime 2, never used before (regime 7 from 07:00 to 17:00 of the day, else 1),
    under which the model's x2 is 1.5 K too high (its form error, not a change of the
    façade). ``record_control``: the ``model`` table holds the applied regime
    (``applied_afr``), as the daemon writes it."""
    rng = np.random.default_rng(7)
    n = int(DAYS * 86400 / STEP_S)
    t = T0 + np.arange(n) * STEP_S
    hour = (t - T0) / 3600.0 % 24.0
    regime = np.where((hour >= 7.0) & (hour < 17.0), 7.0, 1.0)
    unusual = (t >= STEP_AT) & (t < STEP_AT + 3 * 3600.0) if new_control else np.zeros(n, bool)
    regime[unusual] = 2.0
    readings, predictions = {}, {}
    for name in OUTPUTS:
        sd = 0.02 if name == "v_cav_ms" else 0.3
        pred = (0.1 if name == "v_cav_ms" else 20.0) + sd * np.sin(2 * np.pi * t / 86400.0)
        noise = np.zeros(n)
        for i in range(1, n):  # AR(1), phi 0.5: correlated like one-step errors are
            noise[i] = 0.5 * noise[i - 1] + rng.normal(0, sd * np.sqrt(1 - 0.25))
        readings[name] = pred + noise + (np.where(t >= STEP_AT, 1.0, 0.0)
                                         if name == "x3_c" and not new_control else 0.0)
        predictions[f"pred_{name}"] = pred + (1.5 * unusual if name == "x2_c" else 0.0)
    if record_control:
        predictions["applied_afr"] = regime
    return write_database(tmp_path, t, readings, predictions)


def night_database(tmp_path: Path, step_k: float) -> tuple[Path, np.ndarray]:
    """Three weeks of 10-min cycles in Suwon: the exterior pane sits 0.5 ± 0.3 K (night to
    night) above the outdoor air, and ``step_k`` more from night :data:`NIGHT_STEP_NIGHT`
    on (a thermocouple step); the database and its cycle times."""
    rng = np.random.default_rng(3)
    days = 21
    t = T0 + 600.0 * np.arange(days * 144)
    night_id = ((t - T0 + 12 * 3600) // 86400).astype(int)  # T0 is 07:13 in Suwon: 19:13-19:13
    t_out = 2.0 + 4.0 * np.sin(2 * np.pi * (t - T0) / 86400.0)
    x1 = (t_out + rng.normal(0.5, 0.3, days + 2)[night_id] + rng.normal(0, 0.2, t.size)
          + np.where(night_id >= NIGHT_STEP_NIGHT, step_k, 0.0))
    room = np.full(t.size, SUWON["room_c"])
    return write_database(tmp_path, t, {"x1_c": x1, "t_out_c": t_out, "t_room_c": room},
                          {}), t
