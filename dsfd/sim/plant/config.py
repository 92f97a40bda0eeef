"""Options and "true" parameters of the stratified truth plant (docs/model.md#truth-plant,
docs/model.md#plant-switches, docs/model.md#true-parameters).

:class:`PlantOptions` holds one switch per refinement of the truth plant over the lumped
model: the 17 lumped-equivalence switches (docs/model.md#plant-switches) plus the numerical and
actuator constants.
:meth:`PlantOptions.lumped_equivalent` sets every switch to the lumped model's setting,
which is what the N = 1 equivalence test (docs/model.md#plant-switches) runs.

:class:`TrueParameters` is the plant's hidden truth (docs/model.md#true-parameters): multipliers on
the convective correlations and the cavity form loss f_true, drawn from a seed, plus the
optional slow drift of the louver reflectance and one convective multiplier.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from dsfd.config.loader import setting
from dsfd.config.model import ModelOptions
from dsfd.config.panel import PanelConfig
from dsfd.config.parameters import CONVECTIVE_NAMES

SECONDS_PER_DAY = 86400.0


@dataclass(frozen=True, kw_only=True)
class PlantOptions:
    """Switches and constants of the truth plant; defaults are the full-fidelity plant.

    The first seventeen fields are the lumped-equivalence switches (docs/model.md#plant-switches),
    each documented with its lumped-model setting, and ``advection`` an eighteenth refinement
    (second-order vertical advection); :meth:`lumped_equivalent` sets all of them at once.
    """

    # --- the 17 lumped-equivalence switches (docs/model.md#plant-switches) ------------------------
    n_segments: int = setting(
        10, doc="docs/model.md#plant-switches: vertical segments N of the glazed height "
        "(lumped: 1)", ge=1, le=200)
    split_cavity: bool = setting(
        True, doc="docs/model.md#plant-switches, docs/model.md#plant-layout: cavity air split on "
        "either side of the louver into T5o / T5i (lumped: False, one T5)")
    plenums: bool = setting(
        True, doc="docs/model.md#plant-switches, docs/model.md#plant-layout: one adiabatic air "
        "node per damper row (lumped: False)")
    damper_model: Literal["orifice", "exponential"] = setting(
        "exponential", doc="docs/model.md#plant-switches, docs/model.md#plant-airflow: 'orifice' "
        "1/(C_d OR A_d)² (lumped) or the IBPSA exponential damper ζ(OR)/A_d²")
    louver_flow_resistance: bool = setting(
        True, doc="docs/model.md#plant-switches, docs/model.md#louver-flow-loss: louver-angle "
        "dependent cavity loss K_L(φ) of the orifice paths, and in series with the power law "
        "of diagonal_flow='power_law' (lumped: True, the lumped model's default "
        "model.louver_flow_loss)")
    diagonal_flow: Literal["power_law", "orifice"] = setting(
        "orifice", doc="docs/model.md#plant-switches: regimes 5–8 by c·OR·|ΔP|^n (lumped) or as "
        "orifices (docs/model.md#true-parameters)")
    convection: Literal["constant", "correlations"] = setting(
        "correlations", doc="docs/model.md#plant-switches: the six constant h's (lumped) or local "
        "correlations (Churchill–Chu/parallel plates, DOE-2 exterior, ISO 15099 room side)")
    slat_film_reference_speed_ms: float = setting(
        0.0, doc="docs/model.md#slat-film: with convection='constant', the slats' h_ca2 is "
        "the film at this cavity speed and scales with the speed as the lumped model's "
        "model.slat_film: speed_dependent (lumped: the panel's "
        "model.slat_film_reference_speed_ms); 0: constant, the paper's model",
        unit="m/s", ge=0, le=5)
    dgu_gap: Literal["constant_h", "iso15099"] = setting(
        "iso15099", doc="docs/model.md#plant-switches: h_ca4 constant (lumped) or the ISO 15099 "
        "closed-cavity Nu with the local pane temperature difference")
    radiation: Literal["three_layer", "three_layer_fine"] = setting(
        "three_layer_fine", doc="docs/model.md#plant-switches, docs/model.md#plant-heat-transfer: "
        "three-layer exchange (docs/model.md#longwave) with the lumped IR properties (M = 5) or "
        "with M = 10 and the slat-thickness correction; always full T⁴")
    optics: Literal["lumped", "fine"] = setting(
        "fine", doc="docs/model.md#plant-switches: lumped optics and forcing (M = 5, "
        "Erbs + Hay–Davies) or M = 10, slat thickness, sky/ground split, DIRINT + Perez")
    solar_time: Literal["step", "continuous"] = setting(
        "continuous", doc="docs/model.md#plant-switches, docs/model.md#time-convention: sun and "
        "optics at the step midpoint held over the step (lumped) or evaluated continuously")
    weather_hold: Literal["zoh", "linear"] = setting(
        "linear", doc="docs/model.md#plant-switches: weather held per model step (lumped) or "
        "interpolated linearly in time")
    air_properties: Literal["constant", "variable"] = setting(
        "variable", doc="docs/model.md#plant-switches: ρ_a, c_p of the model options in c5, c6 and "
        "ṁc_p (lumped) or ρ(T) at the site's standard pressure in the air heat capacities")
    actuators: Literal["ideal", "realistic"] = setting(
        "realistic", doc="docs/model.md#plant-switches: instantaneous (lumped) or louver rate "
        "limit, damper lag and OR quantisation")
    glass_vertical_conduction: bool = setting(
        True, doc="docs/model.md#plant-switches: conduction along the panes between segments "
        "(lumped: False)")
    sensors: Literal["ideal", "realistic"] = setting(
        "realistic", doc="docs/model.md#plant-switches: sensors return the true states (lumped "
        "comparison) or noisy, biased readings with configured faults")
    sky_model: Literal["lumped", "clark_allen"] = setting(
        "clark_allen", doc="docs/model.md#plant-switches: the lumped model's sky model (config) or "
        "Clark–Allen with the dew point from the relative humidity; T_gnd = T_o and p_atm in both")
    advection: Literal["upwind", "upwind2"] = setting(
        "upwind2", doc="Vertical advection of the cavity air: first-order upwind "
        "(docs/model.md#plant-layout) (lumped; converges as δz) or with the van Albada-limited "
        "second-order correction (converges as δz², see dsfd.sim.plant.advection) [ENG]")
    # --- constants ----------------------------------------------------------------------
    lateral_h_wm2k: float = setting(
        20.0, doc="docs/model.md#plant-layout: h_x of the exchange between the sub-cavities "
        "through the louver",
        unit="W/(m2 K)", ge=0)
    louver_rate_degs: float = setting(
        3.0, doc="docs/model.md#plant-sensors: louver motor speed", unit="deg/s", gt=0)
    damper_rise_time_s: float = setting(
        15.0, doc="docs/model.md#plant-sensors: 10–90 % rise time of the first-order damper "
        "lag", unit="s", gt=0)
    or_quantum_pct: float = setting(
        1.0, doc="docs/model.md#plant-sensors: damper opening resolution", unit="%", gt=0, le=100)
    glass_conductivity_wmk: float = setting(
        1.0, doc="docs/model.md#constants: glass conductivity for the vertical "
        "conduction", unit="W/(m K)", gt=0)
    optics_segments: int = setting(
        10, doc="docs/model.md#slat-cell: slat segments M of the fine optics and IR", ge=1, le=50)
    # --- drift (docs/model.md#true-parameters / issue 3: dirt) ------------------------------------
    drift_reflectance_per_day: float = setting(
        0.0, doc="Change of the louver solar reflectance (both faces) per day", unit="1/d")
    drift_h_name: str = setting(
        "h_ca2", doc="Which convective multiplier drifts (one of CONVECTIVE_NAMES)")
    drift_h_per_day: float = setting(
        0.0, doc="Relative change of that multiplier per day", unit="1/d")
    # --- integration --------------------------------------------------------------------
    rtol: float = setting(1e-4, doc="Relative tolerance of the Radau integration", gt=0)
    atol_k: float = setting(1e-3, doc="Absolute tolerance on temperatures", unit="K", gt=0)

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            choices = _literal_choices(f.type)
            value = getattr(self, f.name)
            if choices and value not in choices:
                raise ValueError(f"PlantOptions.{f.name} = {value!r}; choose one of {choices}")
        if not 1 <= self.n_segments <= 200:
            raise ValueError(f"PlantOptions.n_segments = {self.n_segments}; use 1..200")
        if self.drift_h_name not in CONVECTIVE_NAMES:
            raise ValueError(f"PlantOptions.drift_h_name = {self.drift_h_name!r}; "
                             f"choose one of {CONVECTIVE_NAMES}")

    @classmethod
    def lumped_equivalent(cls, model: ModelOptions | None = None,
                          **overrides: object) -> PlantOptions:
        """Every lumped-equivalence switch (docs/model.md#plant-switches) at the lumped model's
        setting (N = 1), others as given.

        ``model``: the panel's model options, whose ``diagonal_flow`` and ``louver_flow_loss``
        the flow switches follow and whose ``slat_film`` the slats' constant film does
        (default: the model's defaults, the paper's power law for regimes 5–8 with the
        louver's loss, the speed-dependent slat film).

        One air node is well mixed, so this plant is the lumped model with
        ``model.cavity_air_profile: well_mixed``; with more segments the column stratifies
        and the default exponential profile follows it more closely.
        """
        model = ModelOptions() if model is None else model
        lumped = dict(
            n_segments=1, split_cavity=False, plenums=False, damper_model="orifice",
            louver_flow_resistance=model.louver_flow_loss, diagonal_flow=model.diagonal_flow,
            slat_film_reference_speed_ms=(model.slat_film_reference_speed_ms
                                          if model.slat_film == "speed_dependent" else 0.0),
            convection="constant", dgu_gap="constant_h", radiation="three_layer",
            optics="lumped", solar_time="step",
            weather_hold="zoh", air_properties="constant", actuators="ideal",
            glass_vertical_conduction=False, sensors="ideal", sky_model="lumped",
            advection="upwind",
        )
        lumped.update(overrides)
        return cls(**lumped)

    def replace(self, **changes: object) -> PlantOptions:
        """A copy with some fields changed (validated)."""
        return dataclasses.replace(self, **changes)


def _literal_choices(annotation: object) -> tuple[str, ...]:
    text = str(annotation)
    if not text.startswith("Literal["):
        return ()
    inner = text[len("Literal["):-1]
    return tuple(part.strip().strip("'\"") for part in inner.split(","))


#: Range of the log-uniform f_true prior [-] (docs/model.md#true-parameters).
F_TRUE_RANGE = (20.0, 2000.0)


@dataclass(frozen=True, kw_only=True)
class TrueParameters:
    """The plant's hidden parameters (docs/model.md#true-parameters).

    Attributes
    ----------
    h_multipliers : tuple of 6 floats, [-]
        Multipliers m on (h_out, h_ca1, h_ca2, h_ca3, h_ca4, h_in): on the correlations
        (``convection='correlations'``) or on the config defaults (``'constant'``).
    f : float, [-]
        f_true of the path resistance Σ ζ(OR)(A_c/A_d)² + K_L(φ) + f_true (referenced to
        the cavity velocity).
    c, n : float
        Power-law coefficient [m3/(s Pa^n)] and exponent [-]; used only with
        ``diagonal_flow='power_law'`` (docs/model.md#true-parameters: no "true" value otherwise).
    """

    h_multipliers: tuple[float, float, float, float, float, float]
    f: float
    c: float
    n: float

    @classmethod
    def draw(cls, cfg: PanelConfig, rng: np.random.Generator) -> TrueParameters:
        """Seeded draw: m log-uniform in [0.5, 2], f_true log-uniform in [20, 2000]
        (docs/model.md#true-parameters)."""
        m = np.exp(rng.uniform(math.log(0.5), math.log(2.0), size=6))
        f = float(np.exp(rng.uniform(*(math.log(v) for v in F_TRUE_RANGE))))
        p = cfg.parameters
        return cls(h_multipliers=tuple(float(v) for v in m), f=f, c=p.c.default,
                   n=p.n.default)

    @classmethod
    def prior_centre(cls, cfg: PanelConfig) -> TrueParameters:
        """The centre of the true-parameter prior (docs/model.md#true-parameters): multipliers 1 and
        f_true = √(20·2000) ≈ 200 (the geometric mean of its log-uniform range); c, n the config's
        defaults."""
        p = cfg.parameters
        return cls(h_multipliers=(1.0,) * 6, f=math.sqrt(F_TRUE_RANGE[0] * F_TRUE_RANGE[1]),
                   c=p.c.default, n=p.n.default)

    @classmethod
    def nominal(cls, cfg: PanelConfig) -> TrueParameters:
        """Multipliers 1 and the config's default f, c, n."""
        p = cfg.parameters
        return cls(h_multipliers=(1.0,) * 6, f=p.f.default, c=p.c.default, n=p.n.default)

    def constant_h(self, cfg: PanelConfig) -> np.ndarray:
        """Constant h's m × config default [W/(m2 K)] for ``convection='constant'``."""
        defaults = cfg.parameters.values("default", CONVECTIVE_NAMES)
        return np.array(defaults) * np.array(self.h_multipliers)

    def lumped_theta(self, cfg: PanelConfig) -> np.ndarray:
        """The lumped θ that describes this plant exactly in the lumped-equivalent configuration
        (docs/model.md#plant-switches)."""
        return np.concatenate([self.constant_h(cfg), [self.f, self.c, self.n]])


def drift_factors(options: PlantOptions, elapsed_s: float) -> tuple[float, np.ndarray]:
    """Reflectance offset [-] and multiplier factors (6,) after ``elapsed_s`` of drift.

    Notes
    -----
    [ENG] Linear in time: Δρ = r_ρ·t_days; m_j → m_j (1 + r_h t_days) for the drifting
    multiplier (floored at 10 % of its start value).
    """
    days = elapsed_s / SECONDS_PER_DAY
    factors = np.ones(6)
    if options.drift_h_per_day:
        j = CONVECTIVE_NAMES.index(options.drift_h_name)
        factors[j] = max(0.1, 1.0 + options.drift_h_per_day * days)
    return options.drift_reflectance_per_day * days, factors
