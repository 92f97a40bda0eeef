"""Options of the lumped model (the panel file's ``model`` section): time step, coupling,
sky, irradiance split and transposition, flow laws and the cavity-air profile.

Each option names the docs/model.md anchor of what it switches.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from dsfd.config.loader import setting

__all__ = ["ModelOptions"]


@dataclass(frozen=True, kw_only=True)
class ModelOptions:
    step_s: float = setting(60.0, doc="Model time step T", unit="s", gt=0, le=3600)
    coupling: Literal["implicit", "ping_pong"] = setting(
        "implicit", doc="Thermal–airflow coupling per step (docs/model.md#coupling)"
    )
    ping_pong_substeps: int = setting(
        1, doc="Sub-steps per step in ping-pong coupling (≤ 10 s each is stable)", ge=1, le=60
    )
    coupling_tolerance_k: float = setting(
        1e-6, doc="Fixed-point tolerance on the end-of-step cavity temperature", unit="K",
        gt=0, le=0.1,
    )
    coupling_max_iterations: int = setting(40, doc="Fixed-point evaluation limit", ge=2, le=200)
    zoh: Literal["eig", "expm"] = setting(
        "eig",
        doc="Exact ZOH via the symmetric eigen-decomposition (fast) or the augmented "
        "matrix exponential (Van Loan reference)",
    )
    sky_model: Literal["swinbank", "clark_allen"] = setting(
        "swinbank", doc="Sky temperature model (docs/model.md#sky)"
    )
    q_air_basis: Literal["ventilation_credit", "make_up_loss"] = setting(
        "ventilation_credit", doc="Accounting of Q_air (docs/model.md#q-air)"
    )
    decomposition: Literal["erbs", "disc"] = setting(
        "erbs", doc="Split of a measured GHI into beam and diffuse where DNI and DHI are not "
        "measured: Erbs (kt alone) or Maxwell's DISC (kt and the pressure-corrected air "
        "mass: closer to the measured beam on the bundled records, but the closed loop did "
        "worse with it on mixed days; docs/model.md#decomposition)"
    )
    transposition: Literal["haydavies", "isotropic"] = setting(
        "haydavies", doc="Sky-diffuse transposition onto the façade (docs/model.md#transposition)"
    )
    louver_flow_loss: bool = setting(
        True, doc="The slats' flow loss K_L(φ) (Borda–Carnot per slat row, "
        "docs/model.md#louver-flow-loss) adds to the form loss f of the orifice regimes and is in "
        "series with the power law of regimes 5-8, so the louver angle also changes the airflow; "
        "false: the paper's model, where f, c and n alone stand for the cavity's losses")
    cavity_air_profile: Literal["well_mixed", "exponential"] = setting(
        "exponential", doc="What the cavity-air state x5 stands for: 'exponential' (ISO 15099 "
        "ventilated gap: the mean of an air column warming exponentially from its inlet, "
        "which is what a mid-height probe reads and what sets the stack; the air leaves at "
        "T_in + k (x5 − T_in), 1 < k ≤ 2) or 'well_mixed' (the paper's model: the air leaves "
        "at x5)")
    cavity_air_probe: Literal["mean", "mid_height"] = setting(
        "mean", doc="What the x5 thermocouple is taken to read: 'mean' (the column mean x5, "
        "the paper's reading) or 'mid_height' (a probe halfway up the cavity: where the air "
        "crosses the cavity, regimes 5-8, it reads T_in + p(a) (x5 − T_in), up to 15 % more "
        "of the excess over the inlet than the mean, docs/model.md#cavity-probe). "
        "'mid_height' cut the README dry run's one-step cavity-air error by 28 % but raised "
        "it by 29 % under the paper's protocol, hence not the default yet")
    diagonal_flow: Literal["power_law", "orifice"] = setting(
        "power_law", doc="Flow law of the diagonal regimes 5-8 (docs/model.md#diagonal-flow): "
        "'power_law' (the paper's Q = c OR |Δp|^n, with c and n calibrated only while a "
        "diagonal regime runs) or 'orifice' (the two dampers and the cavity's form loss f in "
        "series, as regimes 1-4: c and n are not used, and every regime but 10 informs f)")
    louver_diffuse: Literal["sky_ground", "uniform"] = setting(
        "sky_ground", doc="How the outdoor diffuse light that the exterior pane transmits meets "
        "the louver: 'sky_ground' (its sky and ground parts with the slats' own properties for "
        "each, docs/model.md#louver-diffuse: slats tilted up see the bright sky, tilted down "
        "the dim ground) or 'uniform' (the paper's model: one hemispherical average)")
    slat_film: Literal["speed_dependent", "constant"] = setting(
        "speed_dependent", doc="The slats' convective film: 'speed_dependent' (h_ca2 is the "
        "film at slat_film_reference_speed_ms, scaled with the cavity speed by the cubic blend "
        "of natural convection and the laminar flat plate over the slat width, "
        "docs/model.md#slat-film: room air up the cavity at 0.14 m/s cools the slats 1.7 "
        "times as well as supply air at 0.03 m/s) or 'constant' (the paper's model: h_ca2 in "
        "every regime)")
    slat_film_reference_speed_ms: float = setting(
        0.1, doc="Cavity speed at which h_ca2 (its default, prior and estimate) is the slats' "
        "film, with slat_film: speed_dependent (the order of the cavity speeds of the "
        "paper's Table 1)", unit="m/s", gt=0, le=5)
    air_density_kgm3: float = setting(1.19, doc="Air density for heat capacities", unit="kg/m3",
                                      gt=0)
    air_heat_capacity_jkgk: float = setting(1006.0, doc="c_p of air", unit="J/(kg K)", gt=0)
