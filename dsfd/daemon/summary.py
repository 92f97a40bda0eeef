"""What the controller did over a run, in counters of bounded size (printed at the end).

A daemon runs for months: nothing here grows with the number of cycles except integers
(fallback reasons are grouped by their leading phrase, a bounded set).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from dsfd.config.panel import REGIME_NAMES
from dsfd.daemon.loop import CycleOutcome
from dsfd.estimation.params import FIT_NAMES, ParameterSpace

if TYPE_CHECKING:
    from dsfd.daemon.calibration import CalibrationStage

__all__ = ["REGIME_NAMES", "RunSummary", "at_bound"]

#: Heat flows into the room reported by the simulated plant, and how they are printed.
_HEAT_LABELS = {"q_sol_trans": "solar transmitted", "q_cv_rd": "convection+long-wave",
                "q_air": "ventilation air", "q_da": "daylight credit"}
_J_PER_KWH = 3.6e6


@dataclass
class RunSummary:
    """Counters over the cycles of one run."""

    panel: str
    mode: str
    cycles: int = 0
    methods: Counter[str] = field(default_factory=Counter)
    regimes: Counter[int] = field(default_factory=Counter)
    fallbacks: Counter[str] = field(default_factory=Counter)
    louver_moves: int = 0
    wind_override_cycles: int = 0
    flagged_readings: int = 0
    flags_by_reason: Counter[str] = field(default_factory=Counter)
    write_failures: int = 0
    manual_overrides: int = 0
    calibration_updates: int = 0
    calibration_attempts: int = 0
    skipped_slots: int = 0
    store_failures: int = 0
    decide_ms_total: float = 0.0
    cycle_ms_total: float = 0.0
    first_time_s: float | None = None
    last_time_s: float | None = None
    seasons: Counter[str] = field(default_factory=Counter)
    louver_angles: Counter[float] = field(default_factory=Counter)
    #: Cycle and time [s, UTC] of the first calibration update of the run.
    first_update: tuple[int, float] | None = None
    #: Calibrated parameters when the run started and when it ended, and those at a bound.
    theta_start: dict[str, float] = field(default_factory=dict)
    theta_end: dict[str, float] = field(default_factory=dict)
    at_bound: tuple[str, ...] = ()
    #: Why the first update waits, and the update interval (from the configuration).
    calibration_wait_h: float | None = None
    calibration_interval_s: float | None = None
    #: Heat into the room over the run [J] by flow (simulated plant only) and its hours.
    room_heat_j: dict[str, float] | None = None
    room_heat_h: float = 0.0
    _last_phi: float | None = None

    def add(self, out: CycleOutcome) -> None:
        self.cycles += 1
        self.methods[out.method] += 1
        cmd = out.command
        self.regimes[cmd.afr] += 1
        if self._last_phi is not None and cmd.phi_deg != self._last_phi:
            self.louver_moves += 1
        self._last_phi = cmd.phi_deg
        self.louver_angles[cmd.phi_deg] += 1
        self.seasons["unknown" if out.heating is None
                     else "heating" if out.heating else "cooling"] += 1
        if out.fallback:
            self.fallbacks[out.fallback.split(":")[0]] += 1
        self.wind_override_cycles += out.safety.wind_override
        self.flagged_readings += len(out.quality.flags)
        self.flags_by_reason.update(out.quality.flags.values())
        self.write_failures += out.write_status == "failed"
        self.manual_overrides += out.manual_override
        if out.calibration is not None:
            self.calibration_attempts += 1
            self.calibration_updates += out.calibration.updated
            if out.calibration.updated and self.first_update is None:
                self.first_update = (out.cycle, out.time_s)
        self.skipped_slots += out.skipped_slots
        self.store_failures += not out.store_ok
        self.decide_ms_total += out.timings_ms.get("decide", 0.0)
        self.cycle_ms_total += out.cycle_ms
        if self.first_time_s is None:
            self.first_time_s = out.time_s
        self.last_time_s = out.time_s

    def start_calibration(self, stage: CalibrationStage) -> None:
        """Note the parameters the run starts from (priors or the resumed state)."""
        self.theta_start = stage.theta_by_name()
        self.calibration_wait_h = stage.cfg.calibration.min_window_h
        self.calibration_interval_s = stage.cfg.calibration.update_interval_s

    def finish(self, stage: CalibrationStage, *, room_heat_j: Mapping[str, float] | None = None,
               room_heat_h: float = 0.0) -> None:
        """Note the final parameters and, for a simulated plant, the heat into the room."""
        self.theta_end = stage.theta_by_name()
        self.at_bound = at_bound(self.theta_end, stage.space)
        if room_heat_j is not None:
            self.room_heat_j = dict(room_heat_j)
            self.room_heat_h = room_heat_h

    def as_dict(self) -> dict[str, object]:
        n = max(self.cycles, 1)
        return {
            "panel": self.panel, "mode": self.mode, "cycles": self.cycles,
            "decisions_by_method": dict(self.methods),
            "regimes_used": {str(k): v for k, v in sorted(self.regimes.items())},
            "louver_moves": self.louver_moves,
            "fallbacks": dict(self.fallbacks),
            "wind_override_cycles": self.wind_override_cycles,
            "flagged_readings": self.flagged_readings,
            "flags_by_reason": dict(self.flags_by_reason),
            "write_failures": self.write_failures,
            "manual_overrides": self.manual_overrides,
            "calibration_updates": self.calibration_updates,
            "calibration_attempts": self.calibration_attempts,
            "skipped_slots": self.skipped_slots,
            "store_failures": self.store_failures,
            "decision_ms_mean": self.decide_ms_total / n,
            "cycle_ms_mean": self.cycle_ms_total / n,
            "seasons": dict(self.seasons),
            "louver_angles": {f"{k:g}": v for k, v in sorted(self.louver_angles.items())},
            "first_calibration_update_cycle": None if self.first_update is None
            else self.first_update[0],
            "theta_start": self.theta_start, "theta_end": self.theta_end,
            "theta_at_bound": list(self.at_bound),
            "room_heat_kwh": None if self.room_heat_j is None else {
                k: v / _J_PER_KWH for k, v in self.room_heat_j.items()},
        }

    def lines(self) -> list[str]:
        """The human summary printed when the run ends."""
        from dsfd.measured import iso_utc

        d = self.as_dict()
        span = ""
        if self.first_time_s is not None and self.last_time_s is not None:
            hours = (self.last_time_s - self.first_time_s) / 3600.0
            span = (f", {iso_utc(self.first_time_s)} to {iso_utc(self.last_time_s)} "
                    f"({hours:.1f} h)")
        n = max(self.cycles, 1)
        methods = ", ".join(f"{_METHODS.get(k, k)} {v}" for k, v in self.methods.most_common())
        seasons = ", ".join(f"{k} {v}" for k, v in self.seasons.most_common())
        regimes = "; ".join(f"{k} {REGIME_NAMES.get(k, '?')} {_pct(v, n)}"
                            for k, v in self.regimes.most_common()) or "none"
        angles = ", ".join(f"{k:g}° {_pct(v, n)}"
                           for k, v in sorted(self.louver_angles.items())) or "none"
        fallbacks = ", ".join(f"{k} ({v})" for k, v in self.fallbacks.most_common()) or "none"
        flags = ", ".join(f"{k} {v}" for k, v in self.flags_by_reason.most_common())
        out = [
            f"dsfd run summary — panel {self.panel} ({self.mode})",
            f"  cycles:               {self.cycles}{span}",
            f"  decided by:           {methods or 'nothing'}"
            + (f" (objective: {seasons} cycles)" if seasons else ""),
            f"  airflow regimes:      {regimes} of the cycles",
            f"  louver:               {self.louver_moves} "
            f"move{'' if self.louver_moves == 1 else 's'}; {angles} of the cycles",
        ]
        if self.room_heat_j is not None:
            total = sum(self.room_heat_j.values()) / _J_PER_KWH
            parts = ", ".join(f"{_HEAT_LABELS.get(k, k)} {v / _J_PER_KWH:.2f}"
                              for k, v in self.room_heat_j.items())
            out.append(f"  heat into the room:   {total:.2f} kWh in {self.room_heat_h:.1f} h "
                       f"(simulated plant: {parts} kWh)")
        out += [
            f"  fallbacks:            {sum(self.fallbacks.values())}: {fallbacks}",
            f"  wind override:        {self.wind_override_cycles} cycles",
            f"  faults:               {self.flagged_readings} flagged readings"
            + (f" ({flags})" if flags else "")
            + f", {self.write_failures} failed writes, {self.manual_overrides} manual "
            "overrides",
            *self._calibration_lines(),
            f"  mean decision time:   {d['decision_ms_mean']:.1f} ms "
            f"(mean cycle {d['cycle_ms_mean']:.1f} ms, {self.skipped_slots} skipped slots, "
            f"{self.store_failures} store failures)",
        ]
        return out

    def _calibration_lines(self) -> list[str]:
        from dsfd.measured import iso_utc

        line = (f"  calibration:          {self.calibration_updates} updates of "
                f"{self.calibration_attempts} attempts")
        if self.first_update is not None:
            cycle, t = self.first_update
            line += f"; the first at cycle {cycle} ({iso_utc(round(t))})"
        elif self.calibration_wait_h is not None:
            line += "; none yet"
        if self.calibration_wait_h is not None and self.calibration_interval_s is not None:
            line += (f" — it needs calibration.min_window_h = {self.calibration_wait_h:g} h "
                     f"of data, then updates every {self.calibration_interval_s / 60:g} min")
        out = [line]
        if not (self.theta_start and self.theta_end):
            return out
        changed = [k for k in self.theta_end
                   if abs(self.theta_end[k] - self.theta_start.get(k, 0.0)) > 1e-9]
        if not changed:
            return [*out, "  parameters:           unchanged"]
        mark = " (* at a bound)" if set(changed) & set(self.at_bound) else ""
        for title, names in (("parameters", [k for k in changed if not k.startswith("q_")]),
                             ("heat-flux offsets", [k for k in changed if k.startswith("q_")])):
            if names:
                shown = ", ".join(f"{k} {_num(self.theta_start[k])}→{_num(self.theta_end[k])}"
                                  + ("*" if k in self.at_bound else "") for k in names)
                out.append(f"  {title + ':':<22}{shown}"
                           + (" W/m²" if title != "parameters" else ""))
        out[-1] += mark
        return out


def at_bound(theta: Mapping[str, float], space: ParameterSpace) -> tuple[str, ...]:
    """Free parameters of the fit vector (by name, in ``FIT_NAMES`` order) sitting at a
    bound of ``space`` (relative tolerance 1e-6)."""
    out = []
    for name, lo, hi, fixed in zip(FIT_NAMES, space.lower, space.upper, space.fixed,
                                   strict=True):
        v = theta.get(name)
        if v is None or fixed or not lo < hi:
            continue
        if v <= lo + 1e-6 * abs(lo) or v >= hi - 1e-6 * abs(hi):
            out.append(name)
    return tuple(out)


#: How the decision methods read in the summary.
_METHODS = {"mpc": "optimiser", "rule": "rule-based baseline", "safe": "safe position",
            "manual": "manual hold"}


def _num(v: float) -> str:
    return f"{v:.3g}"


def _pct(count: int, total: int) -> str:
    """``count`` of ``total`` in whole percent; a rare but present case shows as "<1 %"."""
    pct = 100.0 * count / total
    return "<1 %" if 0 < pct < 0.5 else f"{pct:.0f} %"
