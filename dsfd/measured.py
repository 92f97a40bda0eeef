"""The measured-data CSV: one row per sample, ISO-8601 UTC time, units in column names.

This is the exchange format between the façade (daemon log export, the simulated plant,
converted real data sets) and the off-line tools ``dsfd calibrate`` / ``dsfd validate``.
This module holds the table type and the time stamps; reading and writing the file is
:mod:`dsfd.storage.measured_csv`.

Schema (see also ``docs/measured-data-csv.md``)
-----------------------------------------------
``time_utc``
    Sample time, ISO-8601 with ``Z`` (e.g. ``2022-01-02T13:05:00Z``); strictly increasing.
    Rows are usually equally spaced; the sampling interval is their median spacing.
Controls, applied from this row's time until the next row:
    ``phi_deg`` louver angle [deg], ``afr`` commanded airflow regime 1..10, ``or_pct`` damper
    opening [%].
States, instantaneous readings at ``time_utc``:
    ``x1_c`` exterior pane, ``x2_c`` DGU outer pane, ``x3_c`` DGU inner pane, ``x4_c``
    louver slat, ``x5_c`` cavity air, ``t_room_c`` room air [°C]; ``v_cav_ms`` cavity
    anemometer speed (unsigned) [m/s].
Weather, mean over the interval that ENDS at ``time_utc`` (logger convention):
    ``t_out_c`` [°C], ``ghi_wm2``, ``dni_wm2``, ``dhi_wm2`` [W/m2], ``poa_wm2`` plane-of-façade
    global [W/m2], ``poa_diffuse_wm2`` plane-of-façade diffuse [W/m2] (with ``poa_wm2`` it
    replaces GHI/DNI/DHI for the façade: data sets that measured on the façade plane),
    ``wind_speed_ms`` [m/s], ``wind_dir_deg`` [deg from N], ``pressure_hpa`` [hPa],
    ``rh_pct`` [%].
Simulation extras (never needed, written by the simulated plant for analysis):
    columns starting with ``truth_`` (e.g. ``truth_x5_c``, ``truth_label``).

Every column but ``time_utc`` is optional: a façade without some sensors simply lacks
those columns. Empty cells are missing values (NaN). Any other column name is an error
naming the column, so a misspelt header cannot silently drop a sensor.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from datetime import UTC, datetime

import numpy as np

CONTROL_COLUMNS = ("phi_deg", "afr", "or_pct")
STATE_COLUMNS = ("x1_c", "x2_c", "x3_c", "x4_c", "x5_c", "t_room_c", "v_cav_ms")
WEATHER_COLUMNS = ("t_out_c", "ghi_wm2", "dni_wm2", "dhi_wm2", "poa_wm2", "poa_diffuse_wm2",
                   "wind_speed_ms", "wind_dir_deg", "pressure_hpa", "rh_pct")
KNOWN_COLUMNS = (*CONTROL_COLUMNS, *STATE_COLUMNS, *WEATHER_COLUMNS)
EXTRA_PREFIX = "truth_"


class MeasuredDataError(ValueError):
    """A measured-data file that cannot be used; the message names file, row and column."""


@dataclass(frozen=True, eq=False)
class MeasuredData:
    """A table of samples (see module docstring for the meaning of each column).

    Attributes
    ----------
    time_s : ndarray (n,), [s]
        UTC unix time of each row.
    columns : dict[str, ndarray]
        Column name → values (NaN where missing); ``afr`` as float (NaN if missing).
    source : str
        Where the data came from.
    notes : tuple of str
        Free-text provenance (e.g. "simulated plant, seed 3").
    """

    time_s: np.ndarray
    columns: dict[str, np.ndarray]
    source: str = ""
    notes: tuple[str, ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        n = self.time_s.shape[0]
        for name, values in self.columns.items():
            if values.shape != (n,):
                raise MeasuredDataError(f"column {name!r} has {values.shape[0]} values, "
                                        f"expected {n}")
        if n > 1 and not np.all(np.diff(self.time_s) > 0):
            bad = int(np.flatnonzero(np.diff(self.time_s) <= 0)[0]) + 1
            raise MeasuredDataError(f"{self.source}: time_utc not strictly increasing at "
                                    f"row {bad + 1}")

    def __len__(self) -> int:
        return int(self.time_s.shape[0])

    def has(self, name: str) -> bool:
        """True if the column exists and holds at least one value."""
        col = self.columns.get(name)
        return col is not None and bool(np.isfinite(col).any())

    def get(self, name: str) -> np.ndarray:
        """Column values, all-NaN if the column is absent."""
        col = self.columns.get(name)
        return col if col is not None else np.full(len(self), np.nan)

    @property
    def step_s(self) -> float:
        """Sampling interval: the median spacing of the rows [s]."""
        if len(self) < 2:
            raise MeasuredDataError(f"{self.source}: need at least two rows")
        return float(np.median(np.diff(self.time_s)))

    def window(self, start: int, stop: int) -> MeasuredData:
        """Rows ``start`` … ``stop − 1``."""
        return MeasuredData(self.time_s[start:stop],
                            {k: v[start:stop] for k, v in self.columns.items()},
                            self.source, self.notes)


def iso_utc(unix_s: float) -> str:
    """ISO-8601 UTC text of a unix time, seconds resolution unless fractional."""
    dt = datetime.fromtimestamp(unix_s, tz=UTC)
    text = dt.isoformat(timespec="milliseconds" if unix_s % 1 else "seconds")
    return text.replace("+00:00", "Z")


def parse_iso_utc(text: str) -> float:
    """Unix time of an ISO-8601 timestamp with ``Z`` or an explicit offset."""
    value = text.strip()
    if value.endswith("Z"):
        value = value[:-1] + "+00:00"
    dt = datetime.fromisoformat(value)
    if dt.tzinfo is None:
        raise ValueError("timestamp has no time zone (use Z for UTC)")
    return dt.timestamp()
