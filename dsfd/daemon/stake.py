"""The energy at stake of a parameter or solar finding, from what the daemon stored
(docs/model.md#energy-at-stake).

A ``parameter_shift`` finding of a θ parameter says that one heat or air path of the façade
moved; this adds what the move costs (a heat-flux offset's finding names a sensor first, and a
sensor reading off changes no heat path, so it gets none):
:func:`dsfd.control.stake.energy_at_stake` over the last :data:`STAKE_WINDOW_S` of stored
cycles (the weather readings and the commands applied, read as ``dsfd export`` reads them),
with θ now against θ now with that one parameter at its value before the
change. A ``solar_gain_shift`` (dirt, or slats off their read-back) moves no parameter of θ
but the share of the computed sun the façade takes: it is costed with
:func:`dsfd.control.stake.solar_energy_at_stake`, θ now with the sun as computed against the
same with the share it lost given back. The result joins the finding as one more piece of
evidence (signal ``energy_at_stake``, kWh per week) and a sentence of its action.

Runs in the findings thread (a week of one-minute cycles: about 0.4–1 s to read, 6–8 s of
CPU to simulate twice per finding), only when a detector reports a costed finding; the
week is read once per check however many there are. The detectors report an open finding
again at every run (hourly, the solar detector every 6 h), so :class:`StakeCache` costs a
finding when it is first reported and then every :data:`STAKE_EVERY_S`, and lends the last
figure to the checks between.
"""

from __future__ import annotations

import dataclasses
import math
import sqlite3
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.control.stake import EnergyAtStake, energy_at_stake, solar_energy_at_stake
from dsfd.estimation.diagnostics import Evidence, Finding
from dsfd.estimation.lifecycle import key_of
from dsfd.estimation.params import FIT_NAMES, OFFSET_NAMES
from dsfd.estimation.solar_response import SOLAR_SIGNAL
from dsfd.estimation.stepdata import StepData, model_config, step_data
from dsfd.measured import MeasuredDataError
from dsfd.physics.model import LumpedModel
from dsfd.storage.history import HistoryError, measured_from_history, read_history
from dsfd.storage.parameter_series import offsets_of

__all__ = ["STAKE_EVERY_S", "STAKE_SIGNAL", "STAKE_WINDOW_S", "StakeCache", "costed",
           "stake_record", "theta_at", "with_stake"]

#: The record the stake is costed over: the last week, as the issue asks.
STAKE_WINDOW_S = 7 * 86400.0
STAKE_SIGNAL = "energy_at_stake"
#: How often an open finding's stake is costed again: a week's record moves little in 6 h,
#: and costing is the findings thread's largest expense.
STAKE_EVERY_S = 6 * 3600.0


def theta_at(conn: sqlite3.Connection, time_s: float, *, before: bool = False
             ) -> np.ndarray | None:
    """The fit vector (θ and the heat-flux offsets, :data:`FIT_NAMES` order) of the last
    ``parameters`` row at or before ``time_s`` (strictly before it if ``before``: what held
    when a change began); None if there is none or it is incomplete."""
    names = [n for n in FIT_NAMES if not n.startswith("q_")]
    row = conn.execute(f"SELECT {', '.join(names)}, other FROM parameters WHERE time_s "
                       f"{'<' if before else '<='} ? ORDER BY time_s DESC LIMIT 1",
                       (time_s,)).fetchone()
    if row is None or any(v is None for v in row[:-1]):
        return None
    other = offsets_of(row[-1])
    values = dict(zip(names, row[:-1], strict=True))
    return np.array([float(values.get(n, other.get(n, 0.0))) for n in FIT_NAMES])


def stake_record(panel: PanelConfig, state_dir: Path, now_s: float) -> StepData | None:
    """The last :data:`STAKE_WINDOW_S` of stored cycles as model steps, or None when the
    store cannot give a usable record. Read once per check and shared by its findings."""
    try:
        data = measured_from_history(read_history(state_dir, since_s=now_s - STAKE_WINDOW_S,
                                                  until_s=now_s))
        steps = step_data(panel, data)
    except (HistoryError, MeasuredDataError, ValueError):
        return None
    return steps if steps.n_steps >= 2 else None


def costed(f: Finding) -> bool:
    """Whether ``f`` gets an energy at stake: a ``parameter_shift`` of a θ parameter (not of
    a heat-flux offset, whose action names a sensor first), or a ``solar_gain_shift`` that
    says by how much the share of the sun changed (the solar detector's, or a coefficient's
    change the daylight split told as the sun's, docs/model.md#daylight-split)."""
    if f.kind == "solar_gain_shift":
        return _solar_share(f) is not None
    name = f.evidence[0].signal.removeprefix("parameter:") if f.evidence else ""
    return f.kind == "parameter_shift" and name in FIT_NAMES and name not in OFFSET_NAMES


def _solar_share(f: Finding) -> float | None:
    """The change of the share of the computed sun a solar finding gives (its
    ``solar_response`` evidence), or None."""
    shares = [e.shift for e in f.evidence if e.signal == SOLAR_SIGNAL and math.isfinite(e.shift)]
    return shares[0] if shares else None


def _stake(conn: sqlite3.Connection, f: Finding, now_s: float, panel: PanelConfig,
           steps: StepData) -> EnergyAtStake | None:
    if not costed(f):
        return None
    now = theta_at(conn, now_s)
    model = LumpedModel(model_config(panel, steps.step_s))
    if f.kind == "solar_gain_shift":  # costed: it has a share
        share = _solar_share(f)
        return None if now is None or share is None else solar_energy_at_stake(
            model, steps, now, share)
    before = theta_at(conn, f.start_s, before=True)
    if now is None or before is None:
        return None
    changed = now.copy()
    i = FIT_NAMES.index(f.evidence[0].signal.removeprefix("parameter:"))
    changed[i] = before[i]  # only this parameter's move is costed
    return energy_at_stake(model, steps, changed, now)


def with_stake(conn: sqlite3.Connection, f: Finding, now_s: float, *, panel: PanelConfig,
               steps: StepData | None) -> Finding:
    """``f`` (a ``parameter_shift``) with its energy at stake over ``steps`` (the check's
    :func:`stake_record`) added, or unchanged when the stored record cannot say (no
    parameters before the change, no usable week)."""
    s = None if steps is None else _stake(conn, f, now_s, panel, steps)
    if s is None or not math.isfinite(s.per_week_kwh):
        return f
    ev = Evidence(signal=STAKE_SIGNAL, shift=s.per_week_kwh, shift_sd=math.nan,
                  unit="kWh/week", since_s=now_s - s.days * 86400.0, statistic=math.nan,
                  threshold=math.nan)
    if abs(s.per_week_kwh) < 0.005:  # what would print as "about 0.00"
        what = "moves the cost by less than 0.01 kWh a week"
    else:
        verb = "costs" if s.per_week_kwh >= 0 else "saves"
        what = f"{verb} about {abs(s.per_week_kwh):.2f} kWh a week"
    note = (f"; over the last {s.days:.1f} days' weather and commands the change {what} "
            "(the model's J, Eq. 4/5)")
    return dataclasses.replace(f, evidence=(*f.evidence, ev), action=f.action + note)


@dataclass
class StakeCache:
    """The stakes of the costed findings of one daemon run, costed at most every
    ``every_s`` per finding (module docstring).

    ``costings`` counts the findings costed; the figures live in memory, so a restarted
    daemon costs each open finding at its first check.
    """

    panel: PanelConfig
    state_dir: Path
    every_s: float = STAKE_EVERY_S
    costings: int = 0
    #: Per finding key: when it was costed, and the evidence and sentence the costing added.
    _last: dict[tuple[str, str], tuple[float, tuple[Evidence, ...], str]] = field(
        default_factory=dict)

    def apply(self, conn: sqlite3.Connection, found: list[Finding], now_s: float
              ) -> list[Finding]:
        """``found`` with the stake of each costed finding: costed now if due (new, or
        costed ``every_s`` ago), else the last costing's evidence and sentence."""
        due = {id(f) for f in found if costed(f) and not self._fresh(f, now_s)}
        week = stake_record(self.panel, self.state_dir, now_s) if due else None
        out = []
        for f in found:
            if id(f) in due:
                g = with_stake(conn, f, now_s, panel=self.panel, steps=week)
                self._last[key_of(f)] = (now_s, g.evidence[len(f.evidence):],
                                         g.action[len(f.action):])
                self.costings += 1
                f = g
            elif costed(f):
                _, extra, note = self._last[key_of(f)]
                f = dataclasses.replace(f, evidence=(*f.evidence, *extra),
                                        action=f.action + note)
            out.append(f)
        return out

    def _fresh(self, f: Finding, now_s: float) -> bool:
        last = self._last.get(key_of(f))
        return last is not None and abs(now_s - last[0]) < self.every_s
