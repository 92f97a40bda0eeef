"""Visual comfort: cut-off geometry, direct sun through the louver, view factor, DGPs.

Independent references: a 2-D ray cast through a stack of flat slats written here from first
principles; the textbook rule for horizontal slats (the direct beam is excluded once the
profile angle reaches atan(s/w): the slat's shadow on the vertical plane, w tan(profile),
covers the pitch; ASHRAE Handbook Fundamentals ch. 15, shading by horizontal louvers); a
numerical integral of the view-factor kernel; Wienold's DGPs with the EN 17037:2018
glare classes.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from dsfd.physics.comfort_geometry import corner_view_factor, window_view_factor
from dsfd.physics.comfort_visual import (
    cutoff_angles,
    dgp_simplified,
    direct_sun_wm2,
    eye_illuminance_lx,
    glare_class,
    illuminance_for_dgp,
)
from dsfd.physics.optics import LouverOptics, direct_transmittance, glass_triples


def _ray_cast_fraction(phi: float, profile: float, w: float, s: float, n: int = 4000) -> float:
    """Fraction of parallel rays entering one slat period that cross the slat layer."""
    cw, aw = 0.5 * w * math.cos(phi), 0.5 * w * math.sin(phi)
    passed = 0
    for z0 in aw + s * (np.arange(n) + 0.5) / n:  # entry heights over one period
        # Ray: z(x) = z0 - (x + cw) tan(profile); slat k: z = k s - x tan(phi), |x| <= cw.
        # The ray hits slat k where their difference changes sign on [-cw, cw].
        blocked = False
        for k in range(-4, 6):
            gap = [z0 - (x + cw) * math.tan(profile) - (k * s - x * math.tan(phi))
                   for x in (-cw, cw)]
            if gap[0] * gap[1] < 0:
                blocked = True
                break
        passed += not blocked
    return passed / n


@pytest.mark.parametrize(("w", "s"), [(0.05, 0.04), (0.08, 0.07), (0.025, 0.025)])
def test_horizontal_slats_cut_off_at_the_textbook_profile_angle(w, s):
    profile = math.atan(s / w)  # shadow w tan(profile) = s
    assert cutoff_angles(profile, width=w, pitch=s).lower == pytest.approx(0.0, abs=1e-12)
    below, above = cutoff_angles([profile - 0.05, profile + 0.05], width=w, pitch=s).lower
    assert below < 0.0 < above  # lower sun: tilt the slats down; higher: less tilt is enough


@pytest.mark.parametrize("profile_deg", [5.0, 20.0, 35.0, 50.0, 65.0])
def test_cut_off_against_a_ray_cast(profile_deg):
    w, s = 0.05, 0.04
    profile = math.radians(profile_deg)
    cut = cutoff_angles(profile, width=w, pitch=s)
    for edge, side in ((cut.lower, -1.0), (cut.upper, 1.0)):
        if np.isnan(edge):
            continue
        assert _ray_cast_fraction(edge + side * 0.01, profile, w, s) == 0.0  # beyond: dark
        assert _ray_cast_fraction(edge - side * 0.01, profile, w, s) > 0.0  # before: sun
    # The model's direct transmittance agrees with the ray cast at any angle.
    for phi_deg in (-60.0, -30.0, 0.0, 20.0, 45.0):
        ray = _ray_cast_fraction(math.radians(phi_deg), profile, w, s)
        assert direct_transmittance(math.radians(phi_deg), profile, width=w,
                                    pitch=s) == pytest.approx(ray, abs=1e-3)


def test_slats_narrower_than_the_pitch_cannot_cut_off_a_low_sun():
    # w < s: even the closed louver leaves a gap for a horizontal ray.
    assert np.isnan(cutoff_angles(0.0, width=0.03, pitch=0.04).lower)


def test_direct_sun_vanishes_beyond_the_cut_off_on_the_suwon_panel(suwon):
    lv = LouverOptics.from_config(suwon.louver, band="solar")
    glass = glass_triples(suwon.glazing, band="solar")
    profile, cos_aoi, beam = math.radians(30.0), math.cos(math.radians(40.0)), 600.0
    cut = cutoff_angles(profile, width=lv.width, pitch=lv.pitch).lower
    phi = np.array([cut - 0.2, cut - 0.01, cut + 0.05, cut + 0.3, profile])
    sun = direct_sun_wm2(beam_wm2=beam, cos_aoi=cos_aoi, phi=phi, profile=profile,
                         glass=glass, louver=lv)
    assert sun[:2].tolist() == [0.0, 0.0]
    assert np.all(sun[2:] > 0.0) and np.all(np.diff(sun[2:]) > 0)  # opens towards the sun
    # Only the louver's share changes with phi: sun / tau_bb is one glass transmittance,
    # below the beam itself.
    tau = direct_transmittance(phi[2:], profile, width=lv.width, pitch=lv.pitch)
    ratio = sun[2:] / tau
    assert np.allclose(ratio, ratio[0]) and 0.0 < ratio[0] < beam


def _kernel_integral(d: float, w: float, h: float, x0: float, z0: float) -> float:
    # dF = cos(t1) cos(t2) / (pi r^2) dA = d^2 / (pi (d^2 + x^2 + z^2)^2) dA
    value, _ = integrate.dblquad(
        lambda z, x: d * d / (math.pi * (d * d + (x - x0) ** 2 + (z - z0) ** 2) ** 2),
        0.0, w, 0.0, h, epsabs=1e-10)
    return value


@pytest.mark.parametrize(("d", "x0", "z0"), [(1.0, 0.6, 1.2), (0.5, 0.6, 0.6),
                                             (2.0, 0.1, 2.5), (1.0, -0.5, 1.0)])
def test_window_view_factor_against_the_kernel_integral(d, x0, z0):
    w, h = 1.2, 2.4
    got = window_view_factor(distance_m=d, width_m=w, height_m=h, lateral_m=x0, elevation_m=z0)
    assert got == pytest.approx(_kernel_integral(d, w, h, x0, z0), abs=1e-7)


def test_view_factor_limits():
    assert corner_view_factor(1e6, 1e6) == pytest.approx(0.25, abs=1e-5)  # a quadrant
    assert window_view_factor(distance_m=1e-3, width_m=10, height_m=10, lateral_m=5,
                              elevation_m=5) == pytest.approx(1.0, abs=1e-3)  # a whole wall
    assert corner_view_factor(0.0, 3.0) == 0.0


def test_a_lambertian_wall_filling_the_view_gives_its_exitance():
    # An infinite uniformly diffuse source of exitance M lights a parallel plane with E = M.
    e = eye_illuminance_lx(transmitted_wm2=100.0, transmitted_beam_wm2=0.0, view_factor=1.0,
                           luminous_efficacy_lmw=110.0)
    assert e == pytest.approx(11000.0)
    half = eye_illuminance_lx(transmitted_wm2=100.0, transmitted_beam_wm2=40.0,
                              view_factor=0.5, luminous_efficacy_lmw=110.0)
    assert half == pytest.approx(110.0 * (40.0 + 0.5 * 60.0))  # the beam counts in full


def test_dgps_class_limits_of_en17037_and_wienold():
    # Wienold (2009): DGPs = 6.22e-5 E_v + 0.184; EN 17037:2018 protection-from-glare
    # classes high / medium / minimum at DGP 0.35 / 0.40 / 0.45 (Wienold's "imperceptible",
    # "perceptible", "disturbing" boundaries). E_v at the boundaries by hand:
    # (0.35 - 0.184) / 6.22e-5 = 2668.8 lx, 0.40 -> 3472.7 lx, 0.45 -> 4276.5 lx.
    limits = np.array([0.35, 0.40, 0.45])
    ev = illuminance_for_dgp(limits)
    assert ev == pytest.approx([2668.8, 3472.7, 4276.5], abs=0.1)
    assert dgp_simplified(ev) == pytest.approx(limits)
    assert dgp_simplified(0.0) == pytest.approx(0.184)  # no light: the model's floor
    assert dgp_simplified(50000.0) == 1.0  # a probability
    assert [glare_class(float(dgp_simplified(e))) for e in (2000, 3000, 4000, 5000)] == [
        "high", "medium", "minimum", "none"]
