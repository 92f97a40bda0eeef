"""The plant's true state in engineering terms (for tests, analysis and ``truth_*`` columns)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from dsfd.physics.airflow import ALL_OPEN, CLOSED, PATHS
from dsfd.physics.constants import R_AIR, T_ZERO

if TYPE_CHECKING:
    from dsfd.sim.plant.plant import Plant

KINDS = ("g1", "g2", "g3", "lv", "ao", "ai", "g6")


@dataclass(frozen=True)
class TrueState:
    """Snapshot of the plant (SI, kelvin).

    Attributes
    ----------
    time_s : float, [s]
    segments_k : dict[str, ndarray (N,)], [K]
        Per kind from the bottom: ``g1`` L1, ``g2`` L2, ``g3`` L3, ``lv`` louver, ``ao``
        outer (or only) cavity air, ``ai`` inner cavity air (= ``ao`` without a split),
        ``g6`` DGU gap gas.
    z_m : ndarray (N,), [m]
        Segment centres above the bottom of the glazed section.
    plenums_k : tuple of 2 floats, [K]
        Bottom and top plenum air (NaN without plenums).
    x_mid_k : ndarray (6,), [K]
        x1..x6 at mid-height (x5 = mean of the sub-cavities).
    x_sensor_k : ndarray (5,), [K]
        x1..x5 at the thermocouple heights.
    t_outlet_k : float, [K]
        Mass-weighted temperature of the air leaving the cavity (NaN without flow).
    m_dot_kgs : ndarray (4,), [kg/s]
        Flows through EB, ET, IB, IT, positive into the cavity.
    v_cav_ms : float, [m/s]
        Signed net upward mean cavity velocity (docs/model.md#cavity-velocity).
    v_probe_ms : float, [m/s]
        The same at the anemometer height (local density).
    label : int
        Realised regime label.
    phi_deg : float, [deg]
        Actual louver angle.
    dampers : ndarray (4,), [-]
        Actual blade positions.
    """

    time_s: float
    segments_k: dict[str, np.ndarray]
    z_m: np.ndarray
    plenums_k: tuple[float, float]
    x_mid_k: np.ndarray
    x_sensor_k: np.ndarray
    t_outlet_k: float
    m_dot_kgs: np.ndarray
    v_cav_ms: float
    v_probe_ms: float
    label: int
    phi_deg: float
    dampers: np.ndarray

    def truth_columns(self) -> dict[str, float]:
        """The ``truth_*`` columns of the measured-data CSV (°C, m/s, label)."""
        out = {f"truth_x{i + 1}_c": float(self.x_mid_k[i] - T_ZERO) for i in range(6)}
        out["truth_outlet_c"] = float(self.t_outlet_k - T_ZERO)
        out["truth_v_cav_ms"] = float(self.v_cav_ms)
        out["truth_label"] = float(self.label)
        out["truth_phi_deg"] = float(self.phi_deg)
        return out


def realised_label(afr: int, m_dot: list[float] | np.ndarray) -> int:
    """Label from the commanded regime and the flow direction (docs/model.md#regimes)."""
    if afr in PATHS:
        inlet, _, pos, neg, _ = PATHS[afr]
        return pos if m_dot[inlet] >= 0.0 else neg
    return ALL_OPEN if afr == ALL_OPEN else CLOSED


def true_state(plant: Plant, ev: dict) -> TrueState:
    """Build the :class:`TrueState` of ``plant`` from its last right-hand-side evaluation."""
    model = plant.model
    lay, geo = model.lay, model.geo
    T = plant._y[:model.nn]
    segs = {k: T[lay.sl(k)].copy() for k in KINDS}
    z = geo.centres(lay.n)
    air = 0.5 * (segs["ao"] + segs["ai"])
    profiles = [segs["g1"], segs["g2"], segs["g3"], segs["lv"], air, segs["g6"]]
    mid = 0.5 * geo.height
    x_mid = np.array([np.interp(mid, z, prof) for prof in profiles])
    sc = plant.sensor_config
    x5_profile = {"mean": air, "outer": segs["ao"], "inner": segs["ai"]}[sc.x5_location]
    x_sensor = np.array([
        np.interp(mid if h is None else h, z, prof)
        for h, prof in zip(sc.heights_m, [*profiles[:4], x5_profile], strict=True)])
    fl = ev["flows"]
    m = np.asarray(fl["m"], float)
    out_w = np.where(m < 0, -m, 0.0)
    t_node = model.opening_temperatures(fl, ev["face_out"], ev["m_cav"])
    t_outlet = float(out_w @ t_node / out_w.sum()) if out_w.sum() > 0 else math.nan
    p = ev["p"]
    area = model.openings.cavity_area_m2
    m_cav = ev["m_cav"]
    t_probe = float(np.interp(sc.anemometer_height_m, z, air))
    plen = (float(T[lay.pb]), float(T[lay.pt])) if lay.plenums else (math.nan, math.nan)
    return TrueState(
        time_s=plant.time_s,
        segments_k=segs,
        z_m=z,
        plenums_k=plen,
        x_mid_k=x_mid,
        x_sensor_k=x_sensor,
        t_outlet_k=t_outlet,
        m_dot_kgs=m,
        v_cav_ms=m_cav / (fl["rho_mean"] * area),
        v_probe_ms=m_cav / (p / (R_AIR * t_probe) * area),
        label=realised_label(plant.command.afr, m),
        phi_deg=float(ev["phi_deg"]),
        dampers=plant.actuators.dampers_at(plant.time_s),
    )
