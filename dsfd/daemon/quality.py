"""Sensor quality checks: every reading leaves this stage GOOD or flagged with a reason.

The drivers already flag what the device told them (timeout, disconnected, framing, NaN or
the point's ``nan_value`` code, station line missing → STALE). On top, per signal:

* **range** — outside the physical plausibility range of ``dsfd.signals`` → OUT_OF_RANGE;
* **rate** — a temperature that changed faster than ``max_rate_k_per_min`` since the previous
  reading → OUT_OF_RANGE with detail "rate of change" (a loose connector, a spike). The
  reference is the previous delivered value, flagged or not, so a real step is flagged once
  and then accepted, and a spike is flagged going up and coming back;
* **stuck** — the last ``stuck_window`` GOOD values identical → STUCK (thermocouple noise
  makes exact repeats impossible for a live sensor; irradiance and wind are exempt by
  default because they sit at 0 at night and in calm);
* **stale** — a sample older than ``max_sample_age_s`` (real seconds) at decision time →
  every reading STALE.

Flagged readings carry NaN, so nothing downstream (observer, calibration, optimiser) can use
them by accident. Logging follows "first occurrence loudly, repeats quietly, always counted":
a signal entering a bad state logs a WARNING, staying bad logs at DEBUG, returning to GOOD
logs INFO with the number of bad cycles; :attr:`QualityChecker.counts` counts every flag.
"""

from __future__ import annotations

import logging
import math
from collections import Counter, deque
from dataclasses import dataclass, field

from dsfd.config.daemon import QualitySettings
from dsfd.drivers.base import Quality, Reading, Sample
from dsfd.signals import SENSORS

__all__ = ["QualityChecker", "QualityReport"]

log = logging.getLogger(__name__)

#: Check names used in counters, logs and the decision trace.
RANGE, RATE, STUCK, STALE = "range", "rate", "stuck", "stale"


@dataclass(frozen=True)
class QualityReport:
    """Result of checking one sample.

    Attributes
    ----------
    sample : Sample
        The sample with flagged readings replaced by bad ones (NaN value, reason in detail).
    original : Sample
        The sample as the drivers delivered it (values of flagged readings, for the store).
    flags : dict[str, str]
        Signal → why it is not usable: a driver quality (``timeout``, ``disconnected``...)
        or a check (``range``, ``rate``, ``stuck``, ``stale``).
    new_faults : list[str]
        Signals that became bad this cycle.
    recovered : list[str]
        Signals that became GOOD again this cycle.
    """

    sample: Sample
    original: Sample
    flags: dict[str, str] = field(default_factory=dict)
    new_faults: list[str] = field(default_factory=list)
    recovered: list[str] = field(default_factory=list)

    @property
    def n_good(self) -> int:
        return sum(1 for r in self.sample.readings.values() if r.ok)


class QualityChecker:
    """Stateful checks over consecutive samples (one instance per daemon run)."""

    def __init__(self, settings: QualitySettings) -> None:
        self.settings = settings
        #: (signal, reason) → number of flagged readings.
        self.counts: Counter[tuple[str, str]] = Counter()
        self._recent: dict[str, deque[float]] = {}
        self._previous: dict[str, tuple[float, float]] = {}  # signal → (time_s, value)
        self._bad_since: dict[str, int] = {}  # signal → cycles bad so far
        self._bad_reason: dict[str, str] = {}

    def check(self, sample: Sample, *, age_s: float = 0.0) -> QualityReport:
        """Check ``sample``, which is ``age_s`` [s] old when the decision is taken.

        The age is measured in real seconds by the caller (the read time): with an
        accelerated clock a simulated age would count the computer's slowness ``speed``-fold.
        """
        st = self.settings
        readings: dict[str, Reading] = {}
        flags: dict[str, str] = {}
        for name, reading in sample.readings.items():
            checked, why = self._check_one(name, reading, sample.time_s, age_s, st)
            readings[name] = checked
            if why is not None:
                flags[name] = why
        report = QualityReport(Sample(sample.time_s, readings), sample, flags)
        self._account(report)
        return report

    def _check_one(self, name: str, reading: Reading, time_s: float, age_s: float,
                   st: QualitySettings) -> tuple[Reading, str | None]:
        if not reading.ok:
            return reading, reading.quality.value
        value = reading.value
        previous = self._previous.get(name)
        self._previous[name] = (time_s, value)
        if age_s > st.max_sample_age_s:
            return self._flag(reading, Quality.STALE, STALE,
                              f"sample {age_s:.0f} s old at decision time "
                              f"(limit {st.max_sample_age_s:g} s)")
        sig = SENSORS.get(name)
        if sig is not None and not sig.plausible(value):
            return self._flag(reading, Quality.OUT_OF_RANGE, RANGE,
                              f"{value:g} {sig.unit} outside the plausible range "
                              f"{sig.lower:g}..{sig.upper:g}")
        if name in st.rate_signals and previous is not None and time_s > previous[0]:
            rate = abs(value - previous[1]) / (time_s - previous[0]) * 60.0
            if math.isfinite(rate) and rate > st.max_rate_k_per_min:
                return self._flag(reading, Quality.OUT_OF_RANGE, RATE,
                                  f"rate of change {rate:.1f} K/min from {previous[1]:g} to "
                                  f"{value:g} (limit {st.max_rate_k_per_min:g} K/min)")
        if name in st.stuck_signals:
            recent = self._recent.setdefault(name, deque(maxlen=st.stuck_window))
            recent.append(value)
            if len(recent) == recent.maxlen and max(recent) == min(recent):
                return self._flag(reading, Quality.STUCK, STUCK,
                                  f"{len(recent)} identical readings {value:g}")
        return reading, None

    @staticmethod
    def _flag(reading: Reading, quality: Quality, why: str, detail: str
              ) -> tuple[Reading, str]:
        return Reading.bad(quality, reading.source, f"{reading.source}: {detail}"), why

    def _account(self, report: QualityReport) -> None:
        for name, reading in report.sample.readings.items():
            why = report.flags.get(name)
            if why is None:
                cycles = self._bad_since.pop(name, 0)
                if cycles:
                    self._bad_reason.pop(name, None)
                    report.recovered.append(name)
                    log.info("sensor %s GOOD again after %d flagged cycle(s)", name, cycles)
                continue
            self.counts[(name, why)] += 1
            first = name not in self._bad_since or self._bad_reason.get(name) != why
            self._bad_since[name] = self._bad_since.get(name, 0) + 1
            self._bad_reason[name] = why
            if first:
                report.new_faults.append(name)
                log.warning("sensor %s flagged %s: %s", name, why, reading.detail)
            else:
                log.debug("sensor %s still flagged %s (%d cycles): %s", name, why,
                          self._bad_since[name], reading.detail)

    def total_flags(self) -> int:
        """Flagged readings so far, all signals and reasons."""
        return sum(self.counts.values())
