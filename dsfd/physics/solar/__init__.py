"""Solar geometry, GHI decomposition and transposition onto a (façade) plane.

Pure numpy: every function takes array_like inputs that broadcast against each other and
returns float arrays; times are UTC unix seconds, angles carry ``_deg`` in their names and
irradiances are in W/m2 (docs/model.md#solar). The implementation is split over
:mod:`~dsfd.physics.solar.position` (sun position, I0, angles on a plane, air mass),
:mod:`~dsfd.physics.solar.decomposition` (Erbs, DISC, DIRINT) and
:mod:`~dsfd.physics.solar.transposition` (isotropic, Hay–Davies, Perez); import the public
names from here.
"""

from dsfd.physics.solar.decomposition import (
    DISC_SOLAR_CONSTANT,
    DiscResult,
    ErbsResult,
    clearness_index,
    dirint,
    disc,
    erbs,
)
from dsfd.physics.solar.position import (
    SOLAR_CONSTANT,
    SolarPosition,
    apparent_elevation,
    day_of_year,
    extraterrestrial_irradiance,
    incidence_and_profile,
    relative_airmass,
    solar_position,
)
from dsfd.physics.solar.transposition import (
    FacadeIrradiance,
    SkyDiffuse,
    beam_on_surface,
    facade_irradiance,
    ground_diffuse,
    sky_diffuse_haydavies,
    sky_diffuse_isotropic,
    sky_diffuse_perez,
)

__all__ = [
    "DISC_SOLAR_CONSTANT",
    "SOLAR_CONSTANT",
    "DiscResult",
    "ErbsResult",
    "FacadeIrradiance",
    "SkyDiffuse",
    "SolarPosition",
    "apparent_elevation",
    "beam_on_surface",
    "clearness_index",
    "day_of_year",
    "dirint",
    "disc",
    "erbs",
    "extraterrestrial_irradiance",
    "facade_irradiance",
    "ground_diffuse",
    "incidence_and_profile",
    "relative_airmass",
    "sky_diffuse_haydavies",
    "sky_diffuse_isotropic",
    "sky_diffuse_perez",
    "solar_position",
]
