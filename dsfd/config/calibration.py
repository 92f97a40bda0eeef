"""Settings of the self-calibration (Eq. 3 of the paper): the ``calibration:`` section.

YAML shape (every key optional; the defaults suit a 1-minute controller cycle)::

    calibration:
      window_h: 4.0               # moving window of Eq. 3
      forgetting_factor: 0.7      # λ per hour of age: weight λ^(age/1 h)
      horizon_steps: 15           # lead times 1..15 of the multi-step residual
      start_stride_steps: 4       # a rollout starts every 4th step of the window
      start_smoothing_s: 480      # its measured start state smoothed over ±4 min
      update_interval_s: 600      # one on-line update every 10 min
      max_nfev: 8                 # model evaluations per on-line update
      offline_max_nfev: 40        # ... for the off-line batch fit
      flow_from_velocity: true    # f, c, n from the cavity speed, the rest from x1..x5
      loss: soft_l1               # robust loss (as scipy.optimize.least_squares names them)
      f_scale: 1.0                # soft threshold of the loss, in residual scales
      temperature_scale_k: 0.3    # residual scale of x1..x5
      velocity_scale_ms: 0.01     # residual scale of the cavity speed |v|
      adaptive_scales: true       # ... re-estimated per output at the start of each fit
      prior_weight: 1.0           # arrival-cost weight
      prior_log_sd: 0.7           # spread of the default θ (log space)
      prior_sd_n: 0.15            # spread of the default exponent n (linear)
      drift_log_sd_per_h: 0.05    # random-walk growth of the prior per √hour
      heat_offsets: true          # also fit heat-flux offsets on the measured nodes
      offset_sd_wm2: 20.0         # their prior spread
      offset_tracking_s: 600      # offsets follow each measurement between fits (τ)
      innovation_smoothing_s: [300, 1800, 1800, 300]  # ... through a low-pass per node x1..x4
      broyden_updates: 1          # Broyden Jacobian updates between finite differences
      identifiability_sd_ratio: 0.5  # < 1: a parameter moves only where the window determines it
      c_follows_f: true           # c keeps step with f while no window has a diagonal regime
      measurement_gain: [1, 0.3, 0.3, 1, 1]  # state update: weight of a reading of x1..x5
      reading_offset_tracking_s: [0, 0, 0, 120, 120]  # per-regime reading offsets of x1..x5
      reading_offset_memory_s: 3600   # ... decay of a regime's offsets while it is not applied
      spike_threshold_k: 3.0      # isolated temperature jumps treated as missing
      fixed: []                   # parameters never calibrated on this panel

Errors name the key path (``calibration.window_h``). References: the paper's Eq. 3; MHE
arrival cost: Rao, Rawlings & Mayne (2003); soft-L1 loss: Triggs et al. (2000) and the
``scipy.optimize.least_squares`` documentation; start smoothing: Savitzky & Golay (1964).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from dsfd.config.loader import Problem, setting
from dsfd.config.parameters import FIT_NAMES


@dataclass(frozen=True, kw_only=True)
class Calibration:
    """On-line self-calibration and the off-line batch fit (dsfd.estimation)."""

    window_h: float = setting(
        4.0, doc="Length of the moving window of Eq. 3", unit="h", gt=0.25, le=48)
    forgetting_factor: float = setting(
        0.7, doc="λ of Eq. 3 per hour of age: a residual t hours old is weighted λ^t",
        unit="1/h", gt=0, le=1)
    horizon_steps: int = setting(
        15, doc="Lead times 1..N of the multi-step prediction residual (the controller's "
        "horizon)", ge=1, le=120)
    start_stride_steps: int = setting(
        4, doc="A prediction rollout starts from the observed state every N-th step",
        ge=1, le=120)
    start_smoothing_s: float = setting(
        480.0, doc="Measured temperatures a rollout of the fit starts from are smoothed over "
        "this span centred on the start (quadratic Savitzky-Golay over the odd number of "
        "samples nearest to it: 9 at 1-minute data, none at 10-minute data; only where the "
        "controls stay constant and every sample is there; 0 = raw readings). A rollout "
        "that starts from a noisy reading is fitted best by a model that forgets its start "
        "fast, which pushed h_in and h_ca4 to their upper bounds on-line "
        "(errors-in-variables bias)", unit="s", ge=0, le=3600)
    update_interval_s: float = setting(
        600.0, doc="Time between on-line updates", unit="s", ge=0, le=86400)
    min_window_h: float = setting(
        0.25, doc="Data needed before the first on-line update: 15 min let the anemometer "
        "correct the default flow parameters within the first quarter hour (the "
        "identifiability test keeps what so short a window cannot determine at its prior; "
        "docs/model.md#slat-film has the README dry run with 1 h)", unit="h", gt=0, le=48)
    max_nfev: int = setting(
        8, doc="Residual evaluations (least-squares iterations) per on-line update", ge=1,
        le=500)
    broyden_updates: int = setting(
        1, doc="On-line: Broyden rank-one Jacobian updates between finite-difference "
        "Jacobians (0 = finite differences at every iteration)", ge=0, le=20)
    offline_max_nfev: int = setting(
        40, doc="Residual evaluations of the off-line batch fit", ge=1, le=5000)
    flow_from_velocity: bool = setting(
        True, doc="Fit the airflow parameters f, c, n to the cavity speed alone, then the "
        "heat-transfer coefficients and offsets to the temperatures alone (false: one joint "
        "fit, in which f, c, n also absorb the temperatures' model-form error)")
    loss: Literal["linear", "soft_l1", "huber", "cauchy", "arctan"] = setting(
        "soft_l1", doc="Robust loss ρ (the losses of scipy.optimize.least_squares)")
    f_scale: float = setting(
        1.0, doc="Soft threshold of the loss, in units of the residual scales",
        unit="1", gt=0, le=100)
    temperature_scale_k: float = setting(
        0.3, doc="Residual scale σ of the temperatures x1..x5", unit="K", gt=0, le=10)
    velocity_scale_ms: float = setting(
        0.01, doc="Residual scale σ of the cavity speed |v|", unit="m/s", gt=0, le=1)
    adaptive_scales: bool = setting(
        True, doc="Re-estimate each output's residual scale from its prediction errors at "
        "the start of every fit (within ½–3× the scales above)")
    prior_weight: float = setting(
        1.0, doc="Weight of the arrival cost (prior) term; 0 switches it off",
        unit="1", ge=0, le=1e6)
    identifiability_sd_ratio: float = setting(
        0.5, doc="Below 1, a parameter moves in an on-line window fit only if the window "
        "determines it: the window's data alone, with the first prior, shrink its standard "
        "deviation below this fraction of the first prior's (Fisher information at the start "
        "point, docs/model.md#identifiability). Undetermined ones stay where the prior puts "
        "them instead of drifting to a bound to absorb another parameter's error. 0.5 "
        "(default) kept every parameter off its bounds on the README dry run and on both "
        "plants of dsfd bench identify; 1 lets every excited parameter move (the paper's fit)",
        unit="1", gt=0, le=1)
    c_follows_f: bool = setting(
        True, doc="While a window has no diagonal regime (5-8) but f moves, c moves with it "
        "as the diagonal path's orifice law does (c ∝ 1/√(K_in + K_out), the cavity's share "
        "of K from f): an unexcited c keeps its last ratio to the other paths instead of its "
        "default. False holds c where it was (the paper's fit; docs/model.md#c-follows-f)")
    identifiability_always_fit: tuple[str, ...] = setting(
        ("f", "c"),
        doc="Parameters the identifiability test never holds: fitted whenever the window "
        "excites them (with identifiability_sd_ratio below 1). The damper paths' f and the "
        "diagonals' c, which the anemometer measures: held at their prior for hours on the "
        "README dry run, the cavity air predicted worse than persistence "
        "(docs/model.md#identifiability)", choices=FIT_NAMES)
    prior_log_sd: float = setting(
        0.7, doc="Standard deviation of log θ around the panel defaults (first prior)", unit="1",
        gt=0, le=5)
    prior_sd_n: float = setting(
        0.15, doc="Standard deviation of the exponent n around its default (first prior)", unit="1",
        gt=0, le=1)
    drift_log_sd_per_h: float = setting(
        0.05, doc="Random-walk growth of the prior spread of log θ per √hour, so the "
        "estimate can follow slow changes of the panel", unit="1/sqrt(h)", ge=0, le=5)
    heat_offsets: bool = setting(
        True, doc="Also fit a constant heat-flux offset on each measured glass/louver node "
        "(unmodelled sky, irradiance and sensor effects; offset-free estimation)")
    offset_sd_wm2: float = setting(
        20.0, doc="Prior spread of the heat-flux offsets", unit="W/m2", gt=0, le=1000)
    offset_bound_wm2: float = setting(
        200.0, doc="Bound on the magnitude of each heat-flux offset", unit="W/m2", gt=0,
        le=2000)
    offset_drift_wm2_per_h: float = setting(
        20.0, doc="Random-walk growth of the prior spread of the offsets per √hour",
        unit="W/m2/sqrt(h)", ge=0, le=1000)
    offset_tracking_s: float = setting(
        600.0, doc="Between window fits the offsets follow each new measurement with this time "
        "constant (recursive input-disturbance update); 0 switches it off", unit="s", ge=0,
        le=86400)
    innovation_smoothing_s: tuple[float, ...] = setting(
        (300.0, 1800.0, 1800.0, 300.0), doc="Time constant of the low-pass on the innovations "
        "the offsets of x1..x4 follow (one per node; white sensor noise averages out, "
        "persistent model errors pass). A node whose model error is small against its sensor "
        "noise needs a longer one: the steady-state Kalman gain of a random-walk offset seen "
        "through noise σ_y scales as σ_q/σ_y. The inner panes x2, x3 sit behind the cavity, "
        "their one-step model error is far below the 0.2 K thermocouple noise, and a 300 s "
        "low-pass let that noise walk their offsets", unit="s", ge=0, le=86400)
    reading_offset_tracking_s: tuple[float, ...] = setting(
        (0.0, 0.0, 0.0, 120.0, 120.0), doc="Time constant of the reading offsets of x1..x5 "
        "(one per sensor; 0: none): the output-disturbance model of the daemon's state "
        "update. Per commanded airflow regime, each offset follows the difference between the "
        "reading and the model's one-step prediction through a first-order low-pass; the "
        "predictions of the readings (one step and the horizon) add it, and the state takes "
        "the reading less it. It carries the static error of the fast nodes (the cavity air "
        "relaxes within a minute to a quasi-steady value the lumped balance misplaces by "
        "regime, docs/model.md#reading-offsets) without moving the heat into the room", unit="s",
        ge=0, le=86400)
    reading_offset_memory_s: float = setting(
        3600.0, doc="A regime's reading offsets decay towards 0 with this time constant while "
        "another regime is applied (an offset seen long ago is no longer known)", unit="s",
        gt=0, le=864000)
    measurement_gain: tuple[float, ...] = setting(
        (1.0, 0.3, 0.3, 1.0, 1.0), doc="State update: weight of a new reading of x1..x5 (one "
        "per state) against the model's one-step prediction (1 = take the reading as it is, "
        "the paper's update; lower filters white sensor noise, the steady-state Kalman gain "
        "of a sensor noise σ_y and a model error σ_m is about σ_m/σ_y for σ_m ≪ σ_y, so only "
        "the slow panes x2, x3 gain from it). The inner panes sit behind the cavity: their "
        "one-step model error is far below the 0.2 K thermocouple noise, and taking each "
        "reading as it is starts every prediction from that noise. A panel whose panes' "
        "model error exceeds the sensor noise (long sampling interval) wants 1", gt=0, le=1,
        unit="1")
    spike_threshold_k: float = setting(
        3.0, doc="A temperature sample that jumps by more than this from both neighbours "
        "(which agree) is treated as missing", unit="K", gt=0, le=100)
    fixed: tuple[str, ...] = setting(
        (), doc="Parameters held at their defaults on this panel (in addition to those the "
        "panel cannot excite)", choices=FIT_NAMES)

    def smoothing_samples(self, step_s: float) -> int:
        """Odd number of samples of :attr:`start_smoothing_s` at sampling interval
        ``step_s`` [s] (1 = no smoothing)."""
        return 2 * round(self.start_smoothing_s / (2.0 * step_s)) + 1

    def check(self) -> list[Problem]:
        out = []
        for key, names in (("fixed", self.fixed),
                           ("identifiability_always_fit", self.identifiability_always_fit)):
            for name in names:
                if name not in FIT_NAMES:
                    out.append(Problem(key, name,
                                       f"unknown parameter; known: {', '.join(FIT_NAMES)}"))
        if len(self.innovation_smoothing_s) != 4:
            out.append(Problem("innovation_smoothing_s", list(self.innovation_smoothing_s),
                               "need one time constant per offset node x1..x4"))
        if len(self.reading_offset_tracking_s) != 5:
            out.append(Problem("reading_offset_tracking_s",
                               list(self.reading_offset_tracking_s),
                               "need one time constant per measured state x1..x5"))
        if len(self.measurement_gain) != 5:
            out.append(Problem("measurement_gain", list(self.measurement_gain),
                               "need one gain per measured state x1..x5"))
        if self.min_window_h > self.window_h:
            out.append(Problem("min_window_h", self.min_window_h,
                               f"longer than window_h {self.window_h} h"))
        return out
