"""The simulated façade: the stratified truth plant with actuators, sensors and weather.

:class:`Plant` is what the daemon, the calibration tests and ``dsfd simulate --plant
truth`` drive::

    plant = Plant(cfg, PlantOptions(), seed=3, weather_series=load_weather("rmis-golden-2022-01"))
    plant.reset(start_s)
    plant.apply(Command(phi_deg=18.0, afr=1, or_pct=100.0))
    plant.advance(60.0)
    reading = plant.read_sensors()

Between commands the plant integrates its ODE (:mod:`dsfd.sim.plant.model`) with scipy's
Radau, one piece per model step of forcing (and at the louver's arrival), the airflow
solved inside the right-hand side. Everything is SI and kelvin inside; readings are in
the units of their names.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.integrate import Radau

from dsfd.config.panel import PanelConfig
from dsfd.physics.boundary import WeatherInputs
from dsfd.physics.constants import T_ZERO
from dsfd.sim.plant.actuators import (
    DAMPER_SHUT,
    Actuators,
    Command,
    damper_mask,
    validate_command,
)
from dsfd.sim.plant.comfort import PlantComfort, PlantComfortMeter
from dsfd.sim.plant.config import PlantOptions, TrueParameters, drift_factors
from dsfd.sim.plant.faults import FaultSpec, PlantFaults
from dsfd.sim.plant.flow import NETWORK, PAIR, FlowPiece, reg_coefficients
from dsfd.sim.plant.forcing import ForcingTables, station_ghi, weather_at
from dsfd.sim.plant.initial import initial_state
from dsfd.sim.plant.model import N_ACC, ROOM_FLOWS, Piece, PlantModel
from dsfd.sim.plant.sensors import SensorBank, SensorConfig
from dsfd.sim.plant.truth_state import TrueState, true_state
from dsfd.sim.replay import at_site, weather_inputs
from dsfd.weather import WeatherSeries
from dsfd.weather.series import interpolate

RoomSchedule = Callable[[np.ndarray], np.ndarray] | Sequence[tuple[float, float]] | None
_DIAGONAL_PAIRS = ({1, 2}, {0, 3})  # {ET, IB}, {EB, IT}


#: What the simulated station reports only where the panel's devices list the signal; without
#: it, the daemon models the standard atmosphere of the site's elevation and no humidity.
OPTIONAL_STATION_SIGNALS = ("pressure_hpa", "rh_pct")


def configured_signals(cfg: PanelConfig) -> frozenset[str]:
    """Sensor signals the panel's devices deliver (none for a simulation-only panel)."""
    if cfg.devices is None:
        return frozenset()
    return cfg.devices.sensor_signals()


@dataclass
class PlantStats:
    """Work counters since the last reset."""

    pieces: int = 0
    steps: int = 0
    rhs_evaluations: int = 0
    retries: int = 0


class Plant:
    """Stratified truth façade with actuators, sensors and real-weather replay.

    Parameters
    ----------
    cfg : PanelConfig
    options : PlantOptions, optional
        Switches; default the full-fidelity plant.
    seed : int
        Seeds the true parameters, the sensor biases and the noise.
    weather_series : WeatherSeries
        Weather to replay; moved to the panel's site (same local solar time).
    params : TrueParameters, optional
        Override the seeded draw.
    sensors : SensorConfig, optional
    room_schedule : callable or sequence of (unix_s, degC), optional
        Room air temperature; default constant ``cfg.room.t_in_c``.
    faults : sequence of FaultSpec
        Slow physical and sensor faults (:mod:`dsfd.sim.plant.faults`); relative starts
        count from each :meth:`reset`.
    """

    def __init__(self, cfg: PanelConfig, options: PlantOptions | None = None, *, seed: int,
                 weather_series: WeatherSeries, params: TrueParameters | None = None,
                 sensors: SensorConfig | None = None, room_schedule: RoomSchedule = None,
                 faults: Sequence[FaultSpec] = ()) -> None:
        self.cfg = cfg
        self.options = options or PlantOptions()
        self.seed = seed
        rng_p, rng_s = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))
        self.params = params or TrueParameters.draw(cfg, rng_p)
        self.series = at_site(weather_series, cfg)
        self.model = PlantModel(cfg, self.options, self.params)
        self.sensor_config = sensors or SensorConfig()
        self.fault_specs = tuple(faults)
        self.faults = PlantFaults(self.fault_specs, 0.0, step_deg=self._louver_step())
        #: Sensors with their seeded fixed biases (kept across resets).
        self.sensor_bank = SensorBank(self.sensor_config, rng_s,
                                      ideal=self.options.sensors == "ideal")
        self._room = room_schedule
        #: Station channels that only a configured signal reports (a barometer, a hygrometer).
        self._optional_station = frozenset(OPTIONAL_STATION_SIGNALS) - configured_signals(cfg)
        opt = self.options
        self.actuators = Actuators.for_options(ideal=opt.actuators == "ideal",
                                               rate_degs=opt.louver_rate_degs,
                                               rise_time_s=opt.damper_rise_time_s)
        self._t: float | None = None
        self._comfort: PlantComfortMeter | None = None
        self.stats = PlantStats()

    # ------------------------------------------------------------------ boundary
    def room_c(self, t_s: np.ndarray | float) -> np.ndarray:
        """Room air temperature [°C] at unix times ``t_s``."""
        t = np.asarray(t_s, float)
        if self._room is None:
            return np.full(t.shape, self.cfg.room.t_in_c)
        if callable(self._room):
            return np.broadcast_to(np.asarray(self._room(t), float), t.shape).copy()
        pts = np.asarray(self._room, float)
        return np.interp(t, pts[:, 0], pts[:, 1])

    @property
    def time_s(self) -> float:
        """Current plant time (UTC unix seconds)."""
        if self._t is None:
            raise RuntimeError("call Plant.reset(start_s) first")
        return self._t

    @property
    def start_s(self) -> float:
        """UTC start of the run (the last :meth:`reset`) [s]."""
        if self._t is None:
            raise RuntimeError("call Plant.reset(start_s) first")
        return self._t0

    @property
    def command(self) -> Command:
        """The last accepted command."""
        return self._command

    # ------------------------------------------------------------------ API
    def reset(self, start_s: float, *, command: Command | Mapping | None = None,
              x0: np.ndarray | None = None) -> None:
        """Start a run at ``start_s`` with the actuators at rest at ``command``.

        Parameters
        ----------
        start_s : float, [s]
            UTC unix time; model steps of ``cfg.model.step_s`` start here.
        command : Command, optional
            Initial actuator positions (default louver 0°, regime 10, OR 100 %).
        x0 : array, optional, [K]
            Initial temperatures: six lumped states (replicated over the segments; x5
            for every air node) or a full node vector. Default: the lumped steady state of
            the first step (docs/model.md#initial-state).
        """
        cmd = validate_command(self.cfg, command or Command(0.0, 10, 100.0),
                               or_quantum_pct=self._quantum)
        self.tables = ForcingTables(self.cfg, self.options, self.series, self.room_c, start_s,
                                    self.model.phis)
        self._t0 = self._t = float(start_s)
        self._command = cmd
        self.faults = PlantFaults(self.fault_specs, self._t0, step_deg=self._louver_step())
        self._onsets = [t for t in self.faults.onsets_s if t > self._t0]
        self.sensor_bank.config = dataclasses.replace(
            self.sensor_config, faults=self.sensor_config.faults + self.faults.sensor_faults())
        self.actuators.reset(*self._true_targets(self._t), self._t)
        T = initial_state(self, cmd, x0)
        self._y = np.concatenate([T, np.zeros(N_ACC)])
        self._u0 = self.model.stored_energy(T)
        self._h: float | None = None
        self._jac = None
        self._jac_ok = False
        self._last_len = float(self.cfg.model.step_s)
        self._eval_t: float | None = None
        self.sensor_bank.reset()
        self.stats = PlantStats()

    @property
    def _quantum(self) -> float | None:
        return self.options.or_quantum_pct if self.options.actuators == "realistic" else None

    def _targets(self, cmd: Command) -> np.ndarray:
        return damper_mask(cmd.afr) * (cmd.or_pct / 100.0)

    def _louver_step(self) -> float | None:
        return None if self.cfg.louver is None else float(self.cfg.louver.step_deg)

    def _true_targets(self, t: float) -> tuple[float, np.ndarray]:
        """Where the command sends the louver and the dampers at ``t``, faults included
        (a stuck blade, slipped slats); the read-back still reports the command."""
        lv = self.cfg.louver
        return self.faults.actuate(t, self._command.phi_deg, self._targets(self._command),
                                   None if lv is None else lv.angles_deg())

    def apply(self, command: Command | Mapping) -> Command:
        """Validate and apply a command (raises :class:`~dsfd.sim.plant.actuators.CommandError`).

        Returns the command as executed (OR quantised to ``or_quantum_pct``).
        """
        cmd = validate_command(self.cfg, command, or_quantum_pct=self._quantum)
        t = self.time_s
        self._command = cmd
        self.actuators.command(t, *self._true_targets(t))
        self._jac_ok = False
        self._eval_t = None
        return cmd

    def advance(self, seconds: float) -> None:
        """Integrate the plant forward by ``seconds`` [s]."""
        if not seconds > 0:
            raise ValueError(f"advance needs a positive duration, got {seconds}")
        t = self.time_s
        t_end = t + float(seconds)
        dt = float(self.cfg.model.step_s)
        act = self.actuators
        while t < t_end - 1e-9:
            k = math.floor((t - self._t0) / dt + 1e-9)
            stop = min(t_end, self._t0 + (k + 1) * dt)
            if act.louver_moving(t):
                stop = min(stop, act.louver_arrival_s())
            if self._onsets:
                stop = min(stop, self._onsets[0])
            self._integrate(k, t, stop)
            t = stop
            act.settle(t)
            if self._onsets and t >= self._onsets[0] - 1e-9:
                # an actuator fault begins: the blades and slats leave the commanded targets
                self._onsets.pop(0)
                act.command(t, *self._true_targets(t))
                self._jac_ok = False
        self._t = t_end
        self._last_len = float(seconds)
        self._eval_t = None

    def _piece(self, k: int, t: float) -> Piece:
        table, row = self.tables.step(k)
        act, opt = self.actuators, self.options
        fa = table.a[row]
        target_open = (self.faults.open_mask(t, damper_mask(self._command.afr))
                       & (self.model.openings.area_m2 > 0))
        y_now = act.dampers_at(t)
        active = tuple(int(i) for i in np.flatnonzero(
            (target_open | (y_now > DAMPER_SHUT)) & (self.model.openings.area_m2 > 0)))
        dp_t = self.model.dp_t
        k_factor = self.faults.resistance_factor(t)
        solar = self.faults.solar_factor(t)
        if len(active) == 2:
            a, b = active
            power = opt.diagonal_flow == "power_law" and set(active) in _DIAGONAL_PAIRS
            or_eff = max(min(y_now[a], y_now[b]), self.model.openings.floor)
            n = self.params.n
            # resistance × r: Q = c (ΔP/r)^n, so the coefficient takes r^-n
            coef = self.params.c * or_eff * k_factor ** -n
            flow = FlowPiece(PAIR, a=a, b=b, power=power, power_coef=coef,
                             n=n, abcd_n=reg_coefficients(n), dp_t=dp_t)
        elif len(active) > 2:
            flow = FlowPiece(NETWORK, active=active, dp_t=dp_t)
        else:
            flow = FlowPiece(0)
        _, factors = drift_factors(opt, t - self._t0)
        src_a = table.src_a[row] * solar
        return Piece(ts=self._t0 + k * self.tables.dt, inv_len=1.0 / self.tables.dt, fa=fa,
                     fd=table.b[row] - fa, src_a=src_a,
                     src_d=table.src_b[row] * solar - src_a,
                     windward=bool(table.windward[row]), act=act,
                     phi_moving=act.louver_moving(t),
                     dampers_moving=not act.dampers_settled(t),
                     target_open=target_open, flow=flow,
                     h_scale=np.asarray(self.params.h_multipliers) * factors,
                     pc=getattr(self.model.ctx, "pc", 0.0) if self.model.ctx else 0.0,
                     k_factor=k_factor)

    def _integrate(self, k: int, t0: float, t1: float) -> None:
        model = self.model
        model.set_piece(self._piece(k, t0), t0)
        opt = self.options
        atol = np.full(model.ny, opt.atol_k)
        atol[model.nn:] = 1.0
        first = None if self._h is None else min(self._h, t1 - t0)
        before = model.evaluations
        # Start from the previous piece's Jacobian when the actuators have not been
        # commanded since (Radau re-evaluates it itself if Newton struggles).
        reuse = self._jac if self._jac_ok else None

        def jac(t: float, y: np.ndarray):
            nonlocal reuse
            if reuse is not None:
                out, reuse = reuse, None
                return out
            self._jac = model.jac(t, y)
            return self._jac

        for attempt in range(2):
            solver = Radau(model.rhs, t0, self._y, t1, rtol=opt.rtol, atol=atol, jac=jac,
                           first_step=first)
            while solver.status == "running":
                msg = solver.step()
                self.stats.steps += 1
            if solver.status == "finished":
                break
            if attempt:
                raise RuntimeError(f"plant integration failed at t = {solver.t:.1f} s: {msg}")
            # Once more from the start of the piece, tighter and with a fresh Jacobian.
            atol, first, reuse = atol / 10.0, min(1e-3, t1 - t0), None
            opt = opt.replace(rtol=opt.rtol / 10.0)
            self.stats.retries += 1
        self._y = solver.y
        self._jac_ok = self._jac is not None
        if t1 - t0 > 0.5 * self.tables.dt:
            self._h = float(solver.h_abs)
        self.stats.pieces += 1
        self.stats.rhs_evaluations += model.evaluations - before

    # ------------------------------------------------------------------ outputs
    def _evaluate(self) -> dict:
        """Flows and conductances at the current state (cached until the state changes)."""
        t = self.time_s
        if self._eval_t != t:
            k = min(math.floor((t - self._t0) / self.tables.dt + 1e-9),
                    self.tables.n_steps - 1)
            k = max(k, 0)
            self.model.set_piece(self._piece(k, t), t)
            self.model.rhs(t, self._y)
            self._eval_t = t
            self._eval = self.model.last
        return self._eval

    def comfort(self) -> PlantComfort:
        """Direct sun, glare, supply air and radiant asymmetry now, from the plant's own
        optics and air paths (docs/model.md#plant-comfort)."""
        if self._comfort is None:
            self._comfort = PlantComfortMeter(self)
        return self._comfort.measure(self, self._evaluate())

    def true_state(self) -> TrueState:
        """All segment temperatures, flows, the realised label and the mid-height states."""
        return true_state(self, self._evaluate())

    def station_weather(self) -> dict[str, float]:
        """True station values: means over the interval that ends now (logger convention).

        GHI is that of the plant's sky (:func:`~dsfd.sim.plant_forcing.station_ghi`). The
        pressure is the one the plant's air has (the record's, moved to the site's elevation
        by :func:`~dsfd.sim.replay.at_site`), and the humidity the record's: what a station
        at the site reports (docs/model.md#inputs).
        """
        t = self.time_s - 0.5 * min(self._last_len, float(self.cfg.model.step_s))
        w = weather_at(self.series, self.cfg, np.array([t]), self.room_c(np.array([t])))
        rh = interpolate(self.series, np.array([t]))["rh_pct"]
        return {"t_out_c": float(w.t_out_k[0] - T_ZERO),
                "ghi_wm2": float(station_ghi(self.cfg.site, w)[0]),
                "wind_speed_ms": float(w.wind_speed_ms[0]),
                "wind_dir_deg": float(w.wind_dir_deg[0]),
                "pressure_hpa": float(w.pressure_pa[0]) / 100.0,
                "rh_pct": float(rh[0])}

    def read_sensors(self) -> dict[str, float]:
        """Sensor readings now: ``x1_c..x5_c, t_room_c, v_cav_ms, t_out_c, ghi_wm2,
        wind_speed_ms, wind_dir_deg, pressure_hpa, rh_pct`` (NaN on dropout)."""
        st = self.true_state()
        true = {f"x{i + 1}_c": float(st.x_sensor_k[i] - T_ZERO) for i in range(5)}
        true["t_room_c"] = float(self.room_c(self.time_s))
        true["v_cav_ms"] = abs(st.v_probe_ms)
        true.update((k, v) for k, v in self.station_weather().items()
                    if k not in self._optional_station)
        return self.sensor_bank.read(true, self.time_s)

    def perfect_forecast(self, n_steps: int) -> WeatherInputs:
        """The weather of the next ``n_steps`` model steps as the lumped model takes it
        (step midpoints, kelvin, room from the schedule)."""
        dt = float(self.cfg.model.step_s)
        mid = self.time_s + (np.arange(n_steps) + 0.5) * dt
        return weather_inputs(self.series, self.cfg, start_s=self.time_s, n_steps=n_steps,
                              t_in_c=self.room_c(mid))

    def room_heat_j(self) -> dict[str, float]:
        """Heat into the room since the reset [J]: ``q_cv_rd`` (convection and long-wave
        from the inner pane), ``q_sol_trans`` (transmitted solar), ``q_air`` (docs/model.md#q-air
        with the panel's ``model.q_air_basis``) and ``q_da`` (daylighting benefit,
        docs/model.md#q-da).

        The integrals run inside the plant's ODE, so they are exact for the plant, not
        sampled; the difference of two calls is the heat of the interval between them.
        """
        nn = self.model.nn
        return {k: float(v) for k, v in zip(ROOM_FLOWS, self._y[nn + 4:nn + 8], strict=True)}

    def energy_balance(self) -> dict[str, float]:
        """Energy accounting since the reset (docs/model.md#energy-balance) [J].

        ``stored_j`` = ΔU; ``solar_j`` = ∫S_abs; ``boundary_j`` = ∫Q_bnd,in (convection and
        long-wave at the exterior and room faces); ``enthalpy_j`` = ∫(H_in − H_out);
        ``residual_j`` = ΔU − (solar + boundary + enthalpy); ``scale_j`` =
        max(∫S_abs, ∫|Q_bnd|).
        """
        nn = self.model.nn
        stored = self.model.stored_energy(self._y[:nn]) - self._u0
        solar, bnd, enth, bnd_abs = (float(v) for v in self._y[nn:nn + 4])
        return {"stored_j": stored, "solar_j": solar, "boundary_j": bnd, "enthalpy_j": enth,
                "residual_j": stored - (solar + bnd + enth), "scale_j": max(solar, bnd_abs)}
