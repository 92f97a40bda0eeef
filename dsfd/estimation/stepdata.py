"""Measured data → model steps: what the calibrator, the observer and the replay consume.

A measured-data table (:class:`dsfd.measured.MeasuredData`) has one row per sample. Its
conventions (see :mod:`dsfd.measured`) fix how rows become model steps:

* step k runs from row k to row k + 1 (``T = t_{k+1} − t_k``, the sampling interval);
* the controls of row k (``phi_deg``, ``afr``, ``or_pct``) apply over step k;
* weather columns are means over the interval ENDING at their row, so step k takes the
  weather of row k + 1, evaluated at the step midpoint t_k + T/2 (docs/model.md#time-convention);
* states (``x1_c`` … ``x5_c``, ``t_room_c``, ``v_cav_ms``) are readings at their row time:
  x(t_k) is row k, and the room temperature of step k is the mean of rows k and k + 1.

The optics depend on the louver angle and time only, never on θ, so they are computed once
here for every step (:class:`~dsfd.physics.forcing.FacadeOptics`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dsfd.config.panel import Facade, PanelConfig, Room
from dsfd.measured import MeasuredData, MeasuredDataError, iso_utc
from dsfd.physics.boundary import WeatherInputs, model_weather
from dsfd.physics.constants import T_ZERO
from dsfd.physics.coupling import StepInputs
from dsfd.physics.forcing import FacadeOptics, Forcing, facade_forcing, step_inputs

#: Measured state columns x1..x5, in state order.
STATE_COLUMNS = ("x1_c", "x2_c", "x3_c", "x4_c", "x5_c")
#: Relative tolerance on the row spacing for a step to count as one model step.
SPACING_TOLERANCE = 0.02


@dataclass(frozen=True, eq=False)
class StepData:
    """Model steps of a measured record (n steps between n + 1 rows).

    Attributes
    ----------
    time_s : ndarray (n + 1,), [s]
        UTC unix time of each row (step k runs from ``time_s[k]`` to ``time_s[k + 1]``).
    step_s : float, [s]
        Model step T (the data's sampling interval).
    valid : ndarray (n,), bool
        Step k spans exactly one sampling interval (no gap in the record).
    regime : ndarray (n,), int
        Commanded airflow regime of step k.
    or_ : ndarray (n,), [-]
        Damper opening ratio 0..1.
    phi_rad : ndarray (n,), [rad]
        Louver angle.
    inputs : StepInputs
        Exogenous model inputs per step, fields (n,) or (n, 4) / (n, 3).
    y_k : ndarray (n + 1, 5), [K]
        Measured x1..x5 at each row, NaN where missing.
    v_ms : ndarray (n + 1,), [m/s]
        Measured cavity speed |v| at each row, NaN where missing.
    present : tuple of str
        Measured outputs that hold at least one value (``x1`` … ``x5``, ``v``).
    notes : tuple of str
        What was assumed for absent columns.
    """

    time_s: np.ndarray
    step_s: float
    valid: np.ndarray
    regime: np.ndarray
    or_: np.ndarray
    phi_rad: np.ndarray
    inputs: StepInputs
    y_k: np.ndarray
    v_ms: np.ndarray
    present: tuple[str, ...]
    notes: tuple[str, ...] = ()

    @property
    def n_steps(self) -> int:
        return int(self.regime.shape[0])

    def window(self, start: int, stop: int) -> StepData:
        """Steps ``start`` … ``stop − 1`` (rows ``start`` … ``stop``)."""
        rows = slice(start, stop + 1)
        steps = slice(start, stop)
        return StepData(
            time_s=self.time_s[rows], step_s=self.step_s, valid=self.valid[steps],
            regime=self.regime[steps], or_=self.or_[steps], phi_rad=self.phi_rad[steps],
            inputs=self.inputs.at((steps,)), y_k=self.y_k[rows], v_ms=self.v_ms[rows],
            present=self.present, notes=self.notes)


def _filled(time_s: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Linear interpolation in time over missing values, held constant beyond the ends."""
    ok = np.isfinite(values)
    if ok.all():
        return values
    return np.interp(time_s, time_s[ok], values[ok])


def _controls(cfg: PanelConfig, data: MeasuredData, notes: list[str]):
    n_rows = len(data)
    src = data.source or "measured data"
    if not data.has("afr"):
        raise MeasuredDataError(f"{src}: column 'afr' (commanded airflow regime) is required")
    afr = np.array(data.get("afr"), float)
    ok = np.isfinite(afr)
    afr[: int(np.flatnonzero(ok)[0])] = afr[ok][0]  # leading gaps: the first command
    # hold the last commanded regime over missing cells
    afr = afr[np.maximum.accumulate(np.where(np.isfinite(afr), np.arange(n_rows), 0))]
    allowed = cfg.openings.available_regimes()
    bad = ~np.isin(afr, allowed)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise MeasuredDataError(
            f"{src}: data row {row + 1} ({iso_utc(data.time_s[row])}), column 'afr': regime "
            f"{afr[row]:g} is not available on panel {cfg.panel.id} (available: {allowed})")
    if data.has("phi_deg"):
        phi = _filled(data.time_s, data.get("phi_deg"))
    else:
        phi = np.zeros(n_rows)
        if cfg.louver is not None:
            notes.append("no phi_deg column: louver assumed at 0 deg")
    if data.has("or_pct"):
        or_ = _filled(data.time_s, data.get("or_pct")) / 100.0
    else:
        or_ = np.ones(n_rows)
        notes.append("no or_pct column: dampers assumed fully open")
    return afr.astype(int), np.radians(phi), np.clip(or_, 0.0, 1.0)


def weather_of_steps(data: MeasuredData, *, room: Room, facade: Facade,
                     notes: list[str] | None = None, elevation_m: float = 0.0) -> WeatherInputs:
    """Weather of each step (from the row that ends it) at the step midpoints, SI units,
    for a panel with these ``room`` and ``facade`` sections and a site at ``elevation_m``
    [m] (what was not measured)."""
    notes = [] if notes is None else notes
    src = data.source or "measured data"
    t_rows = data.time_s
    t_mid = 0.5 * (t_rows[:-1] + t_rows[1:])

    def col(name: str) -> np.ndarray:
        return data.get(name)[1:]

    def filled(name: str) -> np.ndarray:
        return _filled(t_rows[1:], col(name))

    if not data.has("t_out_c"):
        raise MeasuredDataError(f"{src}: column 't_out_c' (outdoor air temperature) is required")
    poa_ok = data.has("poa_wm2") and data.has("poa_diffuse_wm2")
    if not (data.has("ghi_wm2") or poa_ok):
        raise MeasuredDataError(f"{src}: irradiance missing: need column 'ghi_wm2' or both "
                                "'poa_wm2' and 'poa_diffuse_wm2'")
    if not data.has("wind_speed_ms"):
        notes.append("no wind_speed_ms column: calm assumed")
    t_in_c = None
    if data.has("t_room_c"):
        room_rows = _filled(t_rows, data.get("t_room_c"))
        t_in_c = 0.5 * (room_rows[:-1] + room_rows[1:])
    else:
        notes.append(f"no t_room_c column: room at {room.t_in_c:g} degC")

    def optional(name: str, fill: bool = True) -> np.ndarray | None:
        if not data.has(name):
            return None
        return filled(name) if fill else col(name)

    pressure_hpa = optional("pressure_hpa")
    return model_weather(
        time_s=t_mid, t_out_c=filled("t_out_c"), ghi_wm2=optional("ghi_wm2"),
        dni_wm2=optional("dni_wm2", fill=False), dhi_wm2=optional("dhi_wm2", fill=False),
        wind_speed_ms=optional("wind_speed_ms"), wind_dir_deg=optional("wind_dir_deg"),
        pressure_pa=None if pressure_hpa is None else pressure_hpa * 100.0,
        rh_pct=optional("rh_pct", fill=False), t_in_c=t_in_c,
        poa_global_wm2=filled("poa_wm2") if poa_ok else None,
        poa_diffuse_wm2=filled("poa_diffuse_wm2") if poa_ok else None,
        room=room, facade_azimuth_deg=facade.azimuth_deg, elevation_m=elevation_m)


def step_data(cfg: PanelConfig, data: MeasuredData) -> StepData:
    """Cut a measured record into model steps for panel ``cfg``.

    The model step of ``cfg`` is ignored: the step is the data's sampling interval (use a
    model built with :func:`model_config` for the same data).

    Raises
    ------
    MeasuredDataError
        Fewer than two rows, no ``afr``/``t_out_c``/irradiance columns, or a regime the
        panel does not have (the message names the file, row and column).
    """
    src = data.source or "measured data"
    if len(data) < 2:
        raise MeasuredDataError(f"{src}: need at least two rows")
    notes: list[str] = []
    step_s = data.step_s
    regime, phi, or_ = _controls(cfg, data, notes)
    weather = weather_of_steps(data, room=cfg.room, facade=cfg.facade, notes=notes,
                               elevation_m=cfg.site.elevation_m)
    forcing = facade_forcing(cfg, weather)
    column = Forcing(*(np.asarray(v)[:, None] for v in forcing))
    loads = FacadeOptics(cfg).loads(column, phi[:-1])
    inputs = step_inputs(column, loads)
    inputs = StepInputs(*(np.asarray(v)[:, 0] for v in inputs))
    y = np.stack([data.get(c) for c in STATE_COLUMNS], axis=-1) + T_ZERO
    v = np.abs(data.get("v_cav_ms"))
    present = tuple(c[:2] for c in STATE_COLUMNS if data.has(c))
    if data.has("v_cav_ms"):
        present += ("v",)
    spacing = np.diff(data.time_s)
    valid = np.abs(spacing - step_s) <= SPACING_TOLERANCE * step_s
    valid &= np.isfinite(weather.t_out_k)
    return StepData(time_s=np.asarray(data.time_s, float), step_s=step_s, valid=valid,
                    regime=regime[:-1], or_=or_[:-1], phi_rad=phi[:-1], inputs=inputs,
                    y_k=y, v_ms=v, present=present, notes=tuple(notes))


def model_config(cfg: PanelConfig, step_s: float) -> PanelConfig:
    """``cfg`` with the model step set to the data's sampling interval ``step_s`` [s]."""
    import dataclasses

    if abs(cfg.model.step_s - step_s) < 1e-9:
        return cfg
    return dataclasses.replace(cfg, model=dataclasses.replace(cfg.model, step_s=float(step_s)))
