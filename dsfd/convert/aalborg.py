"""Convert the Aalborg "Cube" double-skin façade data (DSFModelica tables) to measured-data CSV.

Source: ``DamaAlessandro/DSFModelica`` (BSD-3-Clause, (c) 2021 DamaAlessandro), data of
the full-scale test facility "The Cube", Aalborg University (Kalyanova & Heiselberg, IEA
ECBCS Annex 43 / SHC Task 34), external air curtain mode, 1–7 October. Files read from
``SRC_DIR`` (Modelica ``CombiTimeTable`` text):

* ``BoundaryConditions10min.txt``: ``t[s] month day hour wind_dir[deg] wind[0.1 m/s]
  Ghtot[W/m2] Ghdiff[W/m2] T_ext[0.1 degC] Pa[Pa]``;
* ``DSFValidation10min.txt``: ``t[s] Tint Tei_M Tie_M Tii_M Tei_exp Tie_exp Tii_exp [degC]``
  (the ``_M`` model columns are zero in this file and ignored).

Conventions and assumptions (also written as ``#`` notes into the CSV):

* ``t`` is seconds since 1 October 00:00 CET (UTC+1) of ``year`` (not stated by the source;
  the solar geometry changes by < 0.1° between years);
* a boundary row at t is the mean over [t, t + 600 s) ("hour" h is the hour ending at h:00,
  and DSFModelica holds each row constant over its interval): it becomes the weather of the
  CSV row at t + 600 s (the measured-data CSV stamps interval means at the interval end);
  irradiance and wind direction are hourly values repeated over the six 10-min rows; the
  irradiance is interpolated linearly between the hour midpoints (``hourly="interpolate"``,
  default: the 10-min steps then see a smooth course instead of hourly jumps) or held;
* the glass temperatures are readings at t: Tei (exterior skin, cavity side) → ``x1_c``,
  Tie (interior skin, cavity side) → ``x2_c``, Tii (interior skin, room side) → ``x3_c``;
  Tint → ``t_room_c``;
* external air curtain mode: the exterior-skin openings stay open (regime 3, its flow
  direction decided by the model), ``or_pct`` 100; no louver, so no ``phi_deg``;
* ``irradiance="horizontal"`` (default): Ghtot and Ghdiff are global and diffuse
  HORIZONTAL irradiance → ``ghi_wm2``, ``dhi_wm2`` and ``dni_wm2 = (Ghtot − Ghdiff)/cos Z``
  (0 with the sun below 5°). Evidence: DSFModelica's ``PartialDSF.mo`` transposes them
  as horizontal values (Gdir = (Ghtot − Ghdiff)·cos θ/cos Z); the clear-hour maxima
  (422–451 W/m2 around noon, sun 25–29° high) match clear-sky GHI at 57° N in October
  (≈ 410–470) and not clear-sky irradiance on a south façade (≈ 650–750); and the lumped
  model predicts the measured glass temperatures better with this reading (1-step mean
  absolute difference 0.56 vs 0.62 °C uncalibrated). ``irradiance="facade"``: read them
  as façade-plane total and diffuse (the wording of this project's data README) →
  ``poa_wm2``, ``poa_diffuse_wm2``.
"""

from __future__ import annotations

import calendar
import re
from pathlib import Path
from typing import Literal

import numpy as np

from dsfd.measured import MeasuredData, MeasuredDataError
from dsfd.physics.solar import solar_position

BOUNDARY_FILE = "BoundaryConditions10min.txt"
VALIDATION_FILE = "DSFValidation10min.txt"
BOUNDARY_COLUMNS = ("t_s", "month", "day", "hour", "wind_dir_deg", "wind_dms", "ghtot_wm2",
                    "ghdiff_wm2", "t_ext_dc", "pa_pa")
VALIDATION_COLUMNS = ("t_s", "tint_c", "tei_m", "tie_m", "tii_m", "tei_c", "tie_c", "tii_c")
#: Site of the Cube (DSFModelica DSFValidation.mo) and its clock.
LATITUDE_DEG, LONGITUDE_DEG, UTC_OFFSET_S = 57.05, 9.93, 3600.0
INTERVAL_S = 600.0
MIN_COS_ZENITH = 0.087  # sun above 5°
ATTRIBUTION = ("Aalborg University 'The Cube' DSF data (Kalyanova & Heiselberg, IEA ECBCS "
               "Annex 43), via DamaAlessandro/DSFModelica (BSD-3-Clause, (c) 2021 "
               "DamaAlessandro)")


class AalborgFormatError(MeasuredDataError):
    """A source table that cannot be read; the message names the file and line."""


def read_combi_table(path: Path, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Read a Modelica ``CombiTimeTable`` text file (``double tab1(rows,cols)`` + numbers)."""
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as exc:
        raise AalborgFormatError(f"{path}: cannot read: {exc.strerror or exc}") from None
    shape = None
    rows: list[list[float]] = []
    for no, line in enumerate(lines, start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        m = re.match(r"double\s+\w+\s*\(\s*(\d+)\s*,\s*(\d+)\s*\)", text)
        if m:
            shape = (int(m.group(1)), int(m.group(2)))
            continue
        if shape is None:
            raise AalborgFormatError(f"{path}: line {no}: data before the 'double tab(rows,"
                                     "cols)' line")
        try:
            values = [float(v) for v in text.split()]
        except ValueError:
            raise AalborgFormatError(f"{path}: line {no}: not a row of numbers: {text!r}"
                                     ) from None
        if len(values) != len(columns):
            raise AalborgFormatError(f"{path}: line {no}: {len(values)} values, expected "
                                     f"{len(columns)} ({', '.join(columns)})")
        rows.append(values)
    if shape is None:
        raise AalborgFormatError(f"{path}: no 'double tab1(rows,cols)' line")
    if shape != (len(rows), len(columns)):
        raise AalborgFormatError(f"{path}: header declares {shape[0]} x {shape[1]}, file has "
                                 f"{len(rows)} x {len(columns)}")
    table = np.array(rows, float)
    return {name: table[:, j] for j, name in enumerate(columns)}


def _interpolate_hourly(t_s: np.ndarray, hour: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Hourly means (repeated on the 10-min rows) interpolated linearly in time.

    Each hour's mean is placed at the hour's midpoint; every 10-min interval gets the
    value at its own midpoint (held beyond the first and last midpoints).
    """
    start = np.concatenate([[True], np.diff(hour) != 0])
    first = np.flatnonzero(start)
    stop = np.append(first[1:], len(t_s))
    mid = np.array([0.5 * (t_s[a] + t_s[b - 1] + INTERVAL_S) for a, b in zip(first, stop,
                                                                              strict=True)])
    return np.interp(t_s + 0.5 * INTERVAL_S, mid, values[first])


def convert_aalborg(src_dir: str | Path, *, year: int = 2006,
                    irradiance: Literal["facade", "horizontal"] = "horizontal",
                    hourly: Literal["interpolate", "hold"] = "interpolate") -> MeasuredData:
    """The Cube's 10-minute record as a measured-data table (see module docstring).

    Parameters
    ----------
    src_dir : path
        Folder with the DSFModelica 10-minute tables.
    year : int
        Year of the measurement (not in the source).
    irradiance : {"horizontal", "facade"}
        How to read Ghtot/Ghdiff (default horizontal, see the module docstring).
    hourly : {"interpolate", "hold"}
        The irradiance is hourly: interpolate it linearly between the hour midpoints
        (default) or hold each hour's value over its six rows.

    Returns
    -------
    MeasuredData
        Rows every 10 min from the first reading to one interval after the last.
    """
    src = Path(src_dir)
    bnd = read_combi_table(src / BOUNDARY_FILE, BOUNDARY_COLUMNS)
    val = read_combi_table(src / VALIDATION_FILE, VALIDATION_COLUMNS)
    t = bnd["t_s"]
    if t.shape != val["t_s"].shape or np.any(t != val["t_s"]):
        raise AalborgFormatError(f"{src}: the time columns of {BOUNDARY_FILE} and "
                                 f"{VALIDATION_FILE} differ")
    if np.any(np.abs(np.diff(t) - INTERVAL_S) > 1e-6):
        raise AalborgFormatError(f"{src / BOUNDARY_FILE}: rows are not {INTERVAL_S:g} s apart")
    origin = calendar.timegm((year, 10, 1, 0, 0, 0)) - UTC_OFFSET_S
    n = t.shape[0]
    time_s = origin + np.append(t, t[-1] + INTERVAL_S)
    nan = np.full(n + 1, np.nan)

    def states(values: np.ndarray) -> np.ndarray:  # readings at t: rows 0..n-1
        out = nan.copy()
        out[:n] = values
        return out

    def weather(values: np.ndarray) -> np.ndarray:  # mean over [t, t+600): rows 1..n
        out = nan.copy()
        out[1:] = values
        return out

    cols: dict[str, np.ndarray] = {
        "afr": np.full(n + 1, 3.0),
        "or_pct": np.full(n + 1, 100.0),
        "x1_c": states(val["tei_c"]),
        "x2_c": states(val["tie_c"]),
        "x3_c": states(val["tii_c"]),
        "t_room_c": states(val["tint_c"]),
        "t_out_c": weather(bnd["t_ext_dc"] / 10.0),
        "wind_speed_ms": weather(bnd["wind_dms"] / 10.0),
        "wind_dir_deg": weather(bnd["wind_dir_deg"] % 360.0),
        "pressure_hpa": weather(bnd["pa_pa"] / 100.0),
    }
    total, diffuse = bnd["ghtot_wm2"], bnd["ghdiff_wm2"]
    if hourly == "interpolate":
        total, diffuse = (_interpolate_hourly(t, bnd["hour"], v) for v in (total, diffuse))
    total = np.clip(total, 0.0, None)
    diffuse = np.minimum(np.clip(diffuse, 0.0, None), total)
    irradiance_cols = _irradiance_columns(origin + t + 0.5 * INTERVAL_S, total, diffuse,
                                          irradiance)
    cols.update({name: weather(v) for name, v in irradiance_cols.items()})
    notes = _conversion_notes(year=year, irradiance=irradiance, hourly=hourly)
    return MeasuredData(time_s, cols, str(src), notes)


def _irradiance_columns(mid_s: np.ndarray, total: np.ndarray, diffuse: np.ndarray,
                        irradiance: str) -> dict[str, np.ndarray]:
    """Ghtot/Ghdiff (clipped, diffuse ≤ total) as façade-plane columns, or as horizontal
    GHI, DHI and the DNI of their difference with the sun at the interval midpoints
    ``mid_s`` (all diffuse with the sun below MIN_COS_ZENITH)."""
    if irradiance == "facade":
        return {"poa_wm2": total, "poa_diffuse_wm2": diffuse}
    if irradiance == "horizontal":
        sun = solar_position(mid_s, LATITUDE_DEG, LONGITUDE_DEG)
        cos_z = np.cos(np.radians(sun.zenith_deg))
        up = cos_z > MIN_COS_ZENITH
        dni = np.where(up, (total - diffuse) / np.where(up, cos_z, 1.0), 0.0)
        return {"ghi_wm2": total, "dhi_wm2": np.where(up, diffuse, total), "dni_wm2": dni}
    raise ValueError(f"irradiance must be 'facade' or 'horizontal', not {irradiance!r}")


def _conversion_notes(*, year: int, irradiance: str, hourly: str) -> tuple[str, ...]:
    """Provenance of a converted record, for the measured-data notes."""
    return (
        ATTRIBUTION,
        f"converted by dsfd convert-aalborg from {BOUNDARY_FILE} and {VALIDATION_FILE}",
        f"year {year} assumed (not in the source); source clock CET = UTC+1",
        "boundary row t = mean over [t, t+600 s) -> CSV row t+600 s; irradiance and wind "
        "direction are hourly values in the source"
        + ("; irradiance interpolated linearly between hour midpoints" if hourly ==
           "interpolate" else " (held over the hour)"),
        f"Ghtot/Ghdiff read as {'facade-plane' if irradiance == 'facade' else 'horizontal'} "
        "irradiance",
        "x1 = Tei_exp, x2 = Tie_exp, x3 = Tii_exp, t_room = Tint; regime 3 (exterior "
        "openings) throughout",
    )
