"""What one cycle stores: its outcome turned into the rows of ``docs/storage-schema.md``."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from dsfd.measured import iso_utc
from dsfd.storage.timeseries import CycleRecord

if TYPE_CHECKING:
    from dsfd.daemon.calibration import CalibrationStage
    from dsfd.daemon.loop import CycleOutcome
    from dsfd.daemon.weather import CycleWeather

__all__ = ["cycle_record"]


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
    }
    params = None
    cal = out.calibration
    if cal is not None and cal.updated:
        params = ("online", calibration.theta_by_name(), cal.cost, f"{cal.n_residuals} residuals")
    elif out.cycle == 1:
        params = ("resumed" if calibration.resumed else "prior", calibration.theta_by_name(),
                  None, calibration.resume_message)
    events = []
    if out.manual_override:
        events.append(("warning", "manual_override", "actuators moved since the last "
                       "verified write"))
    for name in out.quality.new_faults:
        r = out.quality.sample.readings[name]
        events.append(("warning", "sensor_fault", f"{name}: {r.quality.value}: {r.detail}"))
    for name in out.quality.recovered:
        events.append(("info", "sensor_recovered", name))
    return CycleRecord(cycle=out.cycle, time_s=out.time_s, samples=samples, decision=decision,
                       parameters=params, events=events)


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None
