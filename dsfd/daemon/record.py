"""What one cycle stores: its outcome turned into the rows of ``docs/storage-schema.md``."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from dsfd.measured import iso_utc
from dsfd.physics.comfort_thermal import asymmetry_limit_k, supply_air_min_c
from dsfd.physics.constants import T_ZERO
from dsfd.storage.timeseries import CycleRecord

if TYPE_CHECKING:
    from dsfd.config.comfort import Comfort
    from dsfd.control.occupancy import OccupancyOverride
    from dsfd.daemon.calibration import CalibrationStage
    from dsfd.daemon.outcome import CycleOutcome
    from dsfd.daemon.weather import CycleWeather

__all__ = ["comfort_row", "cycle_record"]


def cycle_record(out: CycleOutcome, weather: CycleWeather, calibration: CalibrationStage
                 ) -> CycleRecord:
    """The rows of one cycle for :meth:`Store.append` (schema: ``docs/storage-schema.md``)."""
    # Flagged readings keep the value the device delivered (why was it flagged?).
    delivered = out.quality.original.readings
    samples = [(name, _finite(delivered[name].value), r.quality.value, r.detail)
               for name, r in sorted(out.quality.sample.readings.items())]
    proposed = out.proposed
    trace = out.safety.trace_dicts()
    if proposed is not None:
        trace = [{"stage": f"decide:{proposed.method}", "set": {
            "phi_deg": proposed.phi_deg, "afr": proposed.afr, "or_pct": proposed.or_pct},
            "why": " | ".join(proposed.trace)}, *trace]
    if out.occupancy is not None:
        trace.append({"stage": "occupancy", "set": {"occupied": out.occupancy.occupied,
                                                    "source": out.occupancy.source},
                      "why": out.occupancy.why})
    if out.comfort is not None:  # the command's comfort and what bound its choice
        trace.append({"stage": "comfort", "set": {}, "why": out.comfort.describe()})
    if weather.notes:
        trace.append({"stage": "inputs", "set": {}, "why": "; ".join(weather.notes)})
    cmd = out.command
    decision: dict[str, Any] = {
        "slot": out.slot, "time_s": out.time_s, "time_utc": iso_utc(round(out.time_s, 3)),
        "method": out.method, "fallback_reason": out.fallback, "heating": out.heating,
        "cost_j": None if proposed is None else proposed.cost_j,
        "proposed_phi_deg": None if proposed is None else proposed.phi_deg,
        "proposed_afr": None if proposed is None else proposed.afr,
        "proposed_or_pct": None if proposed is None else proposed.or_pct,
        "phi_deg": cmd.phi_deg, "afr": cmd.afr, "or_pct": cmd.or_pct,
        "write_status": out.write_status,
        "write_errors": list(out.write.errors) if out.write is not None else [],
        "trace": trace, "timings_ms": out.timings_ms,
        "cycle_ms": sum(v for k, v in out.timings_ms.items() if k != "total"),
        "skipped_slots": out.skipped_slots,
        "run_elapsed_s": out.run_elapsed_s,
        "hold_source": None if out.hold is None else out.hold.source,
        "hold_expires_s": None if out.hold is None else out.hold.expires_s,
        "hold_command_id": None if out.hold is None else out.hold.command_id,
        "objective_mode": out.objective_mode, "mode_command_id": out.mode_command_id,
        **_override_columns(out.occupancy_override),
    }
    params = None
    cal = out.calibration
    if cal is not None and cal.updated:
        params = ("online", calibration.theta_by_name(), cal.cost, f"{cal.n_residuals} residuals")
    elif out.cycle == 1:
        params = (calibration.origin, calibration.theta_by_name(), None,
                  calibration.resume_message)
    events = list(out.events)
    for name in out.quality.new_faults:
        r = out.quality.sample.readings[name]
        events.append(("warning", "sensor_fault", f"{name}: {r.quality.value}: {r.detail}"))
    for name in out.quality.recovered:
        events.append(("info", "sensor_recovered", name))
    return CycleRecord(cycle=out.cycle, time_s=out.time_s, samples=samples, decision=decision,
                       parameters=params, events=events, model=model_row(out),
                       command_results=out.command_results,
                       comfort=comfort_row(out, calibration.cfg.comfort),
                       # the state's sd with its θ (schema 8): what the parameter detector
                       # weighs a change of the history against
                       parameter_sd=None if params is None else
                       calibration.posterior_sd_by_name())


def _override_columns(o: OccupancyOverride | None) -> dict[str, Any]:
    return {"occupancy_override": None if o is None else
            ("occupied" if o.occupied else "unoccupied"),
            "occupancy_until_s": None if o is None else o.until_s,
            "occupancy_command_id": None if o is None else o.command_id}


def comfort_row(out: CycleOutcome, limits: Comfort) -> dict[str, Any] | None:
    """The ``comfort`` table's row of one cycle (schema 6): the occupancy, the comfort
    quantities of the command with the limits in force (the asymmetry's for the side the
    pane is on), and the broken limits; None if the occupancy is unknown."""
    occ = out.occupancy
    if occ is None:
        return None
    row: dict[str, Any] = {"occupied": occ.occupied, "occupancy_source": occ.source}
    c = out.comfort
    if c is not None:
        row.update(
            direct_sun_wm2=_finite(c.direct_sun_wm2), dgp=_finite(c.dgp),
            supply_air_c=None if c.supply_air_c is None else _finite(c.supply_air_c),
            asymmetry_k=_finite(c.asymmetry_k), direct_sun_max_wm2=limits.direct_sun_max_wm2,
            dgp_max=limits.dgp_max, supply_air_min_c=supply_air_min_c(limits),
            asymmetry_max_k=asymmetry_limit_k(limits.category, warm=c.asymmetry_k > 0.0),
            violations=list(c.violations))
    return row


def model_row(out: CycleOutcome) -> dict[str, Any]:
    """The ``model`` table's row of one cycle (units as in the column names; NULL unknown)."""
    row: dict[str, Any] = {}
    est = out.estimate
    if est is not None:
        row.update(_celsius("est", est.x_k, 6))
        pred = est.prediction
        if pred is not None:
            row.update(_celsius("pred", pred.x_k, 5))
            row["pred_v_cav_ms"] = _finite(pred.v_cav_ms)
            row.update({f"{k}_w": _finite(v) for k, v in pred.heat_w.items()})
    if out.horizon_x_k is not None:
        row["horizon_s"] = out.horizon_s
        row.update(_celsius("hz", out.horizon_x_k, 5))
    if out.applied is not None:
        row.update(applied_phi_deg=float(out.applied.phi_deg), applied_afr=int(out.applied.afr),
                   applied_or_pct=float(out.applied.or_pct))
    if out.plant_heat_j is not None:
        row.update({f"plant_{k}_j": _finite(v) for k, v in out.plant_heat_j.items()})
    return row


def _celsius(prefix: str, x_k: Any, n: int) -> dict[str, float | None]:
    return {f"{prefix}_x{i + 1}_c": _finite(float(x_k[i]) - T_ZERO) for i in range(n)}


def _finite(value: float) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None
