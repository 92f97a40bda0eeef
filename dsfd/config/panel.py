"""Settings of one façade panel: site, geometry, glazing, louver, openings, model options.

One YAML file per panel maps onto :class:`PanelConfig`. Units are in the key names
(``cavity_depth_m``, ``azimuth_deg``); inside the physics everything is SI and kelvin.
References for the defaults: docs/model.md#constants (geometry, materials), docs/model.md#convection
(convection), docs/model.md#airflow (airflow), docs/model.md#q-da (daylight proxy),
docs/model.md#parameters (parameter bounds).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from dsfd.config.bacnet import Bacnet
from dsfd.config.calibration import Calibration
from dsfd.config.comfort import Comfort, Occupancy
from dsfd.config.control import Control
from dsfd.config.daemon import DaemonSettings
from dsfd.config.devices import Devices
from dsfd.config.loader import Problem, setting
from dsfd.config.model import ModelOptions
from dsfd.config.mqtt import Mqtt, topic_problem
from dsfd.config.parameters import PARAMETER_NAMES
from dsfd.config.safety import Safety

#: Damper sets of the ten airflow regimes (docs/model.md#regimes).
REGIME_OPENINGS: dict[int, frozenset[str]] = {
    1: frozenset({"interior_bottom", "interior_top"}),
    2: frozenset({"interior_bottom", "interior_top"}),
    3: frozenset({"exterior_bottom", "exterior_top"}),
    4: frozenset({"exterior_bottom", "exterior_top"}),
    5: frozenset({"interior_bottom", "exterior_top"}),
    6: frozenset({"interior_top", "exterior_bottom"}),
    7: frozenset({"interior_top", "exterior_bottom"}),
    8: frozenset({"interior_bottom", "exterior_top"}),
    9: frozenset({"exterior_bottom", "exterior_top", "interior_bottom", "interior_top"}),
    10: frozenset(),
}
#: What each commanded airflow regime does (docs/model.md#regimes; the dampers set
#: the path, the pressures the direction, so 1/2, 3/4, 5/8 and 6/7 share damper sets).
REGIME_NAMES: dict[int, str] = {
    1: "room air up the cavity", 2: "room air down the cavity",
    3: "outdoor air curtain up", 4: "outdoor air curtain down",
    5: "exhaust room→IB→ET→out", 6: "exhaust room→IT→EB→out",
    7: "supply out→EB→IT→room", 8: "supply out→ET→IB→room",
    9: "all dampers open", 10: "closed",
}
#: The regime with every damper closed (no opening may be commanded in it).
CLOSED_REGIME = 10


@dataclass(frozen=True, kw_only=True)
class PanelInfo:
    id: str = setting(doc="Panel identifier used in logs, state paths and the database")
    description: str = setting("", doc="Free text")


@dataclass(frozen=True, kw_only=True)
class Site:
    latitude_deg: float = setting(doc="Latitude, north positive", unit="deg", ge=-90, le=90)
    longitude_deg: float = setting(doc="Longitude, east positive", unit="deg", ge=-180, le=180)
    elevation_m: float = setting(0.0, doc="Site elevation above sea level", unit="m", ge=-500)
    utc_offset_h: float = setting(
        0.0, doc="Local standard time offset, for display only", unit="h", ge=-14, le=14
    )
    albedo: float = setting(0.2, doc="Ground reflectance for ground-diffuse", unit="1", ge=0, le=1)
    terrain: Literal["ocean", "flat", "rough", "city"] = setting(
        "city", doc="Wind-profile terrain class (EnergyPlus ER exponent/boundary layer)"
    )
    facade_height_m: float = setting(
        5.0, doc="Height of the panel centre above ground, for the wind profile", unit="m", gt=0
    )


@dataclass(frozen=True, kw_only=True)
class Facade:
    azimuth_deg: float = setting(
        doc="Outward normal, clockwise from north (south = 180)", unit="deg", ge=0, lt=360
    )
    width_m: float = setting(doc="Panel (cavity) width W", unit="m", gt=0, le=20)
    glazed_height_m: float = setting(doc="Glazed height H_g", unit="m", gt=0, le=50)
    cavity_depth_m: float = setting(
        doc="Cavity depth D between exterior pane and interior DGU", unit="m", gt=0, le=3
    )


@dataclass(frozen=True, kw_only=True)
class GlassLayer:
    """Spectrally averaged properties at normal incidence (EnergyPlus WindowGlassMaterials).

    "Front" faces outdoors.
    """

    thickness_m: float = setting(doc="Pane thickness", unit="m", gt=0, le=0.05)
    solar_transmittance: float = setting(doc="Solar transmittance at normal incidence",
                                         unit="1", ge=0, le=1)
    solar_reflectance_front: float = setting(doc="Solar reflectance, outdoor side",
                                             unit="1", ge=0, le=1)
    solar_reflectance_back: float = setting(doc="Solar reflectance, room side",
                                            unit="1", ge=0, le=1)
    visible_transmittance: float = setting(doc="Visible transmittance", unit="1", ge=0, le=1)
    visible_reflectance_front: float = setting(doc="Visible reflectance, outdoor side",
                                               unit="1", ge=0, le=1)
    visible_reflectance_back: float = setting(doc="Visible reflectance, room side",
                                              unit="1", ge=0, le=1)
    emissivity_front: float = setting(doc="Hemispherical IR emissivity, outdoor side",
                                      unit="1", gt=0, le=1)
    emissivity_back: float = setting(doc="Hemispherical IR emissivity, room side",
                                     unit="1", gt=0, le=1)
    density_kgm3: float = setting(2500.0, doc="Glass density", unit="kg/m3", gt=0)
    heat_capacity_jkgk: float = setting(840.0, doc="Specific heat capacity", unit="J/(kg K)", gt=0)

    def check(self) -> list[Problem]:
        out = []
        for band in ("solar", "visible"):
            tau = getattr(self, f"{band}_transmittance")
            for side in ("front", "back"):
                rho = getattr(self, f"{band}_reflectance_{side}")
                if tau + rho > 1.0:
                    out.append(
                        Problem(
                            f"{band}_reflectance_{side}",
                            rho,
                            f"{band} transmittance + reflectance exceeds 1 ({tau} + {rho})",
                        )
                    )
        return out


@dataclass(frozen=True, kw_only=True)
class Glazing:
    exterior: GlassLayer = setting(doc="Exterior single pane (L1, state x1)")
    interior_outer: GlassLayer = setting(doc="Cavity-side pane of the interior DGU (L2, x2)")
    interior_inner: GlassLayer = setting(doc="Room-side pane of the interior DGU (L3, x3)")
    interior_gap_m: float = setting(doc="DGU gas gap (x6)", unit="m", gt=0, le=0.1)


@dataclass(frozen=True, kw_only=True)
class Louver:
    slat_width_m: float = setting(doc="Slat width w", unit="m", gt=0)
    slat_pitch_m: float = setting(doc="Vertical slat spacing s", unit="m", gt=0)
    slat_thickness_m: float = setting(doc="Slat thickness", unit="m", gt=0)
    solar_reflectance_upper: float = setting(doc="Solar reflectance of the upper face",
                                             unit="1", ge=0, lt=1)
    solar_reflectance_lower: float = setting(doc="Solar reflectance of the lower face",
                                             unit="1", ge=0, lt=1)
    visible_reflectance_upper: float = setting(doc="Visible reflectance, upper face",
                                               unit="1", ge=0, lt=1)
    visible_reflectance_lower: float = setting(doc="Visible reflectance, lower face",
                                               unit="1", ge=0, lt=1)
    emissivity: float = setting(0.9, doc="IR emissivity of both faces", unit="1", gt=0, le=1)
    density_kgm3: float = setting(1400.0, doc="Slat material density", unit="kg/m3", gt=0)
    heat_capacity_jkgk: float = setting(1000.0, doc="Slat heat capacity", unit="J/(kg K)", gt=0)
    segments: int = setting(5, doc="Slat segments in the slat-cell optics (ISO 15099: 5)", ge=1,
                            le=50)
    step_deg: float = setting(18.0, doc="Motor step of the louver angle", unit="deg", gt=0, le=90)

    def check(self) -> list[Problem]:
        out = []
        if self.slat_thickness_m >= self.slat_pitch_m:
            out.append(Problem("slat_thickness_m", self.slat_thickness_m,
                               f"slat thicker than the slat pitch {self.slat_pitch_m} m"))
        if abs(180.0 / self.step_deg - round(180.0 / self.step_deg)) > 1e-9:
            out.append(Problem("step_deg", self.step_deg,
                               "180 deg must be a whole number of steps"))
        return out

    def angles_deg(self) -> tuple[float, ...]:
        """The louver positions the motor can reach, from −90° to +90° [deg]."""
        n = round(180.0 / self.step_deg)
        return tuple(-90.0 + i * self.step_deg for i in range(n + 1))


@dataclass(frozen=True, kw_only=True)
class Opening:
    area_m2: float = setting(doc="Free area of the fully open damper A_d", unit="m2", gt=0)
    discharge_coefficient: float = setting(0.6, doc="Discharge coefficient C_d",
                                           unit="1", gt=0, le=1)


@dataclass(frozen=True, kw_only=True)
class WindPressure:
    """Wind pressure coefficients of the bottom and top openings vs wind incidence.

    Default: the Aalborg "Cube" pair (DSFModelica ``CpValues.txt``,
    docs/model.md#driving-pressures).
    """

    incidence_deg: tuple[float, ...] = setting(
        (0, 15, 30, 45, 60, 75, 90, 105, 120, 135, 150, 165, 180),
        doc="Wind incidence angle from the façade normal, ascending 0..180", unit="deg",
        ge=0, le=180,
    )
    cp_bottom: tuple[float, ...] = setting(
        (0.644, 0.609, 0.527, 0.336, 0.103, -0.245, -0.532, -0.617, -0.594, -0.445, -0.383,
         -0.314, -0.299),
        doc="C_p at the bottom openings", unit="1", ge=-3, le=3,
    )
    cp_top: tuple[float, ...] = setting(
        (0.794, 0.721, 0.585, 0.363, 0.077, -0.299, -0.637, -0.749, -0.691, -0.538, -0.460,
         -0.368, -0.363),
        doc="C_p at the top openings", unit="1", ge=-3, le=3,
    )

    def check(self) -> list[Problem]:
        out = []
        n = len(self.incidence_deg)
        if n < 2:
            out.append(Problem("incidence_deg", self.incidence_deg, "need at least two angles"))
        if any(b <= a for a, b in zip(self.incidence_deg, self.incidence_deg[1:], strict=False)):
            out.append(Problem("incidence_deg", self.incidence_deg, "must be strictly ascending"))
        for key in ("cp_bottom", "cp_top"):
            if len(getattr(self, key)) != n:
                out.append(Problem(key, getattr(self, key),
                                   f"needs {n} values, one per incidence angle"))
        return out


@dataclass(frozen=True, kw_only=True)
class Openings:
    """The four dampers; absent ones are ``null``. Bottom row at z = 0, top at z = stack height."""

    exterior_bottom: Opening | None = setting(doc="Damper EB (exterior skin, bottom)")
    exterior_top: Opening | None = setting(doc="Damper ET (exterior skin, top)")
    interior_bottom: Opening | None = setting(doc="Damper IB (interior skin, bottom)")
    interior_top: Opening | None = setting(doc="Damper IT (interior skin, top)")
    stack_height_m: float = setting(
        doc="Vertical distance between bottom and top damper centres Δz", unit="m", gt=0, le=60
    )
    min_opening_ratio: float = setting(
        0.01, doc="Floor on OR for an open damper set (docs/model.md#openings)",
        unit="1", gt=0, le=1
    )
    room_pressure_pa: float = setting(
        0.0, doc="Room pressure P_i at z = 0 relative to outdoors", unit="Pa", ge=-50, le=50
    )
    regularisation_pa: float = setting(
        0.01, doc="Pressure below which flow laws are regularised "
        "(docs/model.md#regularisation)", unit="Pa",
        gt=0, le=1,
    )
    wind_pressure: WindPressure = setting(
        default_factory=WindPressure, doc="C_p pair of the bottom/top openings"
    )

    def present(self) -> frozenset[str]:
        """Names of the dampers this panel has."""
        return frozenset(
            k for k in ("exterior_bottom", "exterior_top", "interior_bottom", "interior_top")
            if getattr(self, k) is not None
        )

    def available_regimes(self) -> tuple[int, ...]:
        """Airflow regimes (1..10) whose damper set exists on this panel."""
        have = self.present()
        return tuple(r for r, need in REGIME_OPENINGS.items() if need <= have)


@dataclass(frozen=True, kw_only=True)
class Room:
    t_in_c: float = setting(22.0, doc="Room air temperature when not measured", unit="degC",
                            ge=5, le=40)
    t_mrt_c: float | None = setting(
        None, doc="Room mean radiant temperature; null = room air temperature", unit="degC",
        ge=5, le=45,
    )
    floor_depth_m: float = setting(6.0, doc="Depth of the daylit floor behind the panel",
                                   unit="m", gt=0, le=30)


@dataclass(frozen=True, kw_only=True)
class Daylight:
    """Daylighting proxy Q_DA (docs/model.md#q-da)."""

    luminous_efficacy_lmw: float = setting(110.0, doc="Luminous efficacy K", unit="lm/W", gt=0)
    utilisation: float = setting(0.3, doc="Coefficient of utilisation CU", unit="1", ge=0, le=1)
    lighting_power_wm2: float = setting(10.0, doc="Lighting power density LPD", unit="W/m2", ge=0)
    illuminance_setpoint_lx: float = setting(500.0, doc="Work-plane set-point E_set", unit="lx",
                                             gt=0)


@dataclass(frozen=True, kw_only=True)
class Bounded:
    """A calibrated parameter: default (prior) and bounds."""

    default: float = setting(doc="Default: the model's value before any calibration and the "
                             "centre of the calibration's prior")
    lower: float = setting(doc="Lower bound the calibration keeps the parameter above", gt=0)
    upper: float = setting(doc="Upper bound the calibration keeps the parameter below", gt=0)

    def check(self) -> list[Problem]:
        if self.lower >= self.upper:
            return [Problem("lower", self.lower, f"must be below upper {self.upper}")]
        if not self.lower <= self.default <= self.upper:
            return [Problem("default", self.default,
                            f"outside the bounds [{self.lower}, {self.upper}]")]
        return []


@dataclass(frozen=True, kw_only=True)
class Parameters:
    """Calibrated vector θ (docs/model.md#parameters)."""

    h_out: Bounded = setting(doc="L1 exterior ↔ outdoor air", unit="W/(m2 K)")
    h_ca1: Bounded = setting(doc="L1 cavity face ↔ cavity air", unit="W/(m2 K)")
    h_ca2: Bounded = setting(doc="Louver (slat area) ↔ cavity air", unit="W/(m2 K)")
    h_ca3: Bounded = setting(doc="L2 cavity face ↔ cavity air", unit="W/(m2 K)")
    h_ca4: Bounded = setting(doc="DGU faces ↔ gap gas (each face)", unit="W/(m2 K)")
    h_in: Bounded = setting(doc="L3 room face ↔ room air", unit="W/(m2 K)")
    f: Bounded = setting(doc="Cavity form-loss factor (regimes 1–4, 9)", unit="1")
    c: Bounded = setting(doc="Power-law flow coefficient at OR = 1 (regimes 5–8)",
                         unit="m3/(s Pa^n)")
    n: Bounded = setting(doc="Power-law exponent (regimes 5–8)", unit="1")

    def values(self, what: Literal["default", "lower", "upper"],
               names: tuple[str, ...] = PARAMETER_NAMES) -> tuple[float, ...]:
        """Defaults or bounds of the parameters ``names`` (default θ), in that order."""
        return tuple(getattr(getattr(self, name), what) for name in names)

    def check(self) -> list[Problem]:
        if not (self.n.lower >= 0.5 and self.n.upper <= 1.0):
            return [Problem("n", (self.n.lower, self.n.upper), "n bounds must lie in [0.5, 1]")]
        return []


@dataclass(frozen=True, kw_only=True)
class PanelConfig:
    """Everything dsfd knows about one panel."""

    panel: PanelInfo = setting(doc="Identity of the panel")
    site: Site = setting(doc="Location and surroundings")
    facade: Facade = setting(doc="Geometry of the façade panel")
    glazing: Glazing = setting(doc="Glass layers")
    louver: Louver | None = setting(doc="Rotating louver in the cavity; null if none")
    openings: Openings = setting(doc="Dampers and airflow boundary")
    room: Room = setting(default_factory=Room, doc="Room-side boundary")
    daylight: Daylight = setting(default_factory=Daylight, doc="Daylighting proxy")
    occupancy: Occupancy | None = setting(
        None, doc="Weekly occupancy schedule in local time; null: never occupied, no comfort "
        "limit applies (dsfd.config.comfort)")
    comfort: Comfort = setting(default_factory=Comfort, doc="Comfort limits while occupied: "
                               "direct sun, glare, draught, radiant asymmetry")
    model: ModelOptions = setting(default_factory=ModelOptions, doc="Lumped-model options "
                                  "(dsfd.config.model)")
    parameters: Parameters = setting(doc="Calibrated parameters: defaults and bounds")
    calibration: Calibration = setting(
        default_factory=Calibration, doc="On-line self-calibration and off-line fit settings "
        "(dsfd.config.calibration)"
    )
    control: Control = setting(default_factory=Control, doc="Optimal control and baseline")
    devices: Devices | None = setting(
        None, doc="Modbus devices and the weather station the daemon reads and commands; "
        "null for simulation-only panels (dsfd.config.devices)"
    )
    daemon: DaemonSettings = setting(
        default_factory=DaemonSettings, doc="Controller daemon: state, cycle, budgets, "
        "sensor quality checks (dsfd.config.daemon)")
    safety: Safety = setting(
        default_factory=Safety, doc="Safety pipeline before every write: safe state, wind, "
        "limits, louver move interval (dsfd.config.safety)")
    mqtt: Mqtt | None = setting(
        None, doc="Connection to an MQTT broker: state, Home Assistant discovery, commands; "
        "null: none (dsfd.config.mqtt)")
    bacnet: Bacnet | None = setting(
        None, doc="BACnet/IP device for the building management system: points, COV, "
        "priority-array commands; null: none, nothing listens (dsfd.config.bacnet)")

    def check(self) -> list[Problem]:
        out = []
        lv = self.louver
        if lv is not None and lv.slat_width_m >= self.facade.cavity_depth_m:
            out.append(Problem("louver.slat_width_m", lv.slat_width_m,
                               f"slat wider than the cavity depth {self.facade.cavity_depth_m} m"))
        if self.openings.stack_height_m < self.facade.glazed_height_m * 0.5:
            out.append(Problem("openings.stack_height_m", self.openings.stack_height_m,
                               "shorter than half the glazed height"))
        for name in self.openings.present():
            op = getattr(self.openings, name)
            limit = self.facade.width_m * self.openings.stack_height_m
            if op.area_m2 > limit:
                out.append(Problem(f"openings.{name}.area_m2", op.area_m2,
                                   f"larger than the panel face {limit:.3g} m2"))
        mq = self.mqtt
        if mq is not None and mq.base_topic is None and (why := topic_problem(
                mq.base_topic_for(self.panel.id))):
            out.append(Problem("mqtt.base_topic", None, f"the default dsfd/<panel id> "
                               f"({mq.base_topic_for(self.panel.id)!r}) {why}: set it"))
        return out
