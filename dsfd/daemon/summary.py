"""What the controller did over a run, in counters of bounded size (printed at the end).

A daemon runs for months: nothing here grows with the number of cycles except integers
(fallback reasons are grouped by their leading phrase, a bounded set).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

from dsfd.daemon.loop import CycleOutcome

__all__ = ["RunSummary"]


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
    _last_phi: float | None = None

    def add(self, out: CycleOutcome) -> None:
        self.cycles += 1
        self.methods[out.method] += 1
        cmd = out.command
        self.regimes[cmd.afr] += 1
        if self._last_phi is not None and cmd.phi_deg != self._last_phi:
            self.louver_moves += 1
        self._last_phi = cmd.phi_deg
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
        self.skipped_slots += out.skipped_slots
        self.store_failures += not out.store_ok
        self.decide_ms_total += out.timings_ms.get("decide", 0.0)
        self.cycle_ms_total += out.cycle_ms
        if self.first_time_s is None:
            self.first_time_s = out.time_s
        self.last_time_s = out.time_s

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
        }

    def lines(self) -> list[str]:
        """The human summary printed when the run ends."""
        from dsfd.measured import iso_utc

        d = self.as_dict()
        span = ""
        if self.first_time_s is not None and self.last_time_s is not None:
            span = f" from {iso_utc(self.first_time_s)} to {iso_utc(self.last_time_s)}"
        methods = ", ".join(f"{k} {v}" for k, v in sorted(self.methods.items())) or "none"
        regimes = ", ".join(f"{k}: {v}" for k, v in d["regimes_used"].items()) or "none"
        fallbacks = ", ".join(f"{k} ({v})" for k, v in self.fallbacks.most_common()) or "none"
        flags = ", ".join(f"{k} {v}" for k, v in self.flags_by_reason.most_common())
        return [
            f"dsfd run summary — panel {self.panel} ({self.mode})",
            f"  cycles:               {self.cycles}{span}",
            f"  decisions by method:  {methods}",
            f"  regimes used:         {regimes} (cycles)",
            f"  louver moves:         {self.louver_moves}",
            f"  fallbacks:            {sum(self.fallbacks.values())}: {fallbacks}",
            f"  wind override:        {self.wind_override_cycles} cycles",
            f"  faults:               {self.flagged_readings} flagged readings"
            + (f" ({flags})" if flags else "")
            + f", {self.write_failures} failed writes, {self.manual_overrides} manual "
            "overrides",
            f"  calibration updates:  {self.calibration_updates} of "
            f"{self.calibration_attempts} attempts",
            f"  mean decision time:   {d['decision_ms_mean']:.1f} ms "
            f"(mean cycle {d['cycle_ms_mean']:.1f} ms, {self.skipped_slots} skipped slots, "
            f"{self.store_failures} store failures)",
        ]
