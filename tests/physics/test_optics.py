"""Short-wave optics: glass, DGU, louver slat cell and the multilayer balance
(docs/model.md#optics)."""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.physics.optics import (
    NO_LOUVER,
    LouverOptics,
    dgu_beam,
    direct_transmittance,
    glass_angular,
    glass_hemispherical,
    glass_triples,
    layer_absorption,
    slat_beam,
    slat_cell_hit_fractions,
    slat_cell_view_factors,
    slat_diffuse,
    slat_infrared,
    slat_sky_ground,
)

RAD = np.pi / 180.0

# ISO 15099 test louver of the EnergyPlus ER comparison table (docs/model.md#slat-cell).
ISO = dict(width=0.016, pitch=0.012)
SUWON = dict(width=0.05, pitch=0.045)
SUWON_GLASS = ((0.600, 0.170, 0.220), (0.775, 0.071, 0.071), (0.600, 0.220, 0.170))


def _faces(rho_up: float, rho_dn: float) -> dict[str, float]:
    return dict(reflectance_upper=rho_up, reflectance_lower=rho_dn)


# ------------------------------------------------------------------------------------------
# ISO 15099 reference vectors (docs/model.md#slat-cell), M = 5, tolerance ±0.002
# ------------------------------------------------------------------------------------------

ISO_BEAM_ROWS = [
    # rho_up, rho_dn, phi [deg], profile [deg], tau_bb, tau_bd, rho_bd
    (0.70, 0.70, -45.0, 0.0, 0.057, 0.141, 0.394),
    (0.70, 0.70, -45.0, 60.0, 0.0, 0.073, 0.558),
    (0.55, 0.55, -45.0, 0.0, 0.057, 0.090, 0.295),
    (0.55, 0.55, -45.0, 60.0, 0.0, 0.047, 0.430),
    (0.70, 0.40, -45.0, 0.0, 0.057, 0.096, 0.371),
    (0.70, 0.40, -45.0, 60.0, 0.0, 0.051, 0.544),
]


@pytest.mark.parametrize(("rho_up", "rho_dn", "phi", "profile", "tau_bb", "tau_bd", "rho_bd"),
                         ISO_BEAM_ROWS)
def test_iso15099_beam(rho_up, rho_dn, phi, profile, tau_bb, tau_bd, rho_bd):
    got = slat_beam(phi * RAD, profile * RAD, **ISO, **_faces(rho_up, rho_dn), segments=5)
    assert float(got.tau_bb) == pytest.approx(tau_bb, abs=0.002)
    assert float(got.tau_bd) == pytest.approx(tau_bd, abs=0.002)
    assert float(got.rho_bd) == pytest.approx(rho_bd, abs=0.002)


@pytest.mark.parametrize(("rho_up", "rho_dn", "phi", "tau_dd"), [
    (0.70, 0.70, -45.0, 0.332),
    (0.55, 0.55, -45.0, 0.294),
    (0.70, 0.40, -45.0, 0.291),
    (0.70, 0.40, -80.0, 0.038),
])
def test_iso15099_diffuse(rho_up, rho_dn, phi, tau_dd):
    got = slat_diffuse(phi * RAD, **ISO, **_faces(rho_up, rho_dn), segments=5)
    assert float(got.tau_dd) == pytest.approx(tau_dd, abs=0.002)


@pytest.mark.parametrize(("phi", "tau_ir", "eps_ir"), [(-45.0, 0.227, 0.729),
                                                       (-80.0, 0.0245, 0.890)])
def test_iso15099_infrared(phi, tau_ir, eps_ir):
    got = slat_infrared(phi * RAD, **ISO, emissivity=0.9, segments=5)
    assert float(got.tau_L) == pytest.approx(tau_ir, abs=0.002)
    assert float(got.eps_L) == pytest.approx(eps_ir, abs=0.002)


def test_iso15099_near_closed_beam():
    """E+ slat angle 10° (phi = -80°), rho 0.70 / 0.40, profile 0°.

    tau_bb = 0 and tau_bd = 0.012 are met (M = 5 gives 0.0109). rho_bd is NOT met at ±0.002:
    M = 5 gives 0.6308 against the table's 0.622 (see the xfail below). The method itself is
    right: it converges to 0.640 (M = 40: 0.6396, tau_bd 0.0088), which is what an independent
    Monte Carlo ray trace of the same flat Lambertian slats gives (0.6401 / 0.0085, 4e5
    rays). The ISO reference evidently differs from this slat-cell model in the near-closed
    case, so it is checked here at ±0.01 only.
    """
    got = slat_beam(-80.0 * RAD, 0.0, **ISO, **_faces(0.70, 0.40), segments=5)
    assert float(got.tau_bb) == 0.0
    assert float(got.tau_bd) == pytest.approx(0.012, abs=0.002)
    assert float(got.rho_bd) == pytest.approx(0.622, abs=0.01)
    fine = slat_beam(-80.0 * RAD, 0.0, **ISO, **_faces(0.70, 0.40), segments=40)
    assert float(fine.rho_bd) == pytest.approx(0.640, abs=0.002)


@pytest.mark.xfail(strict=True, reason="ISO table rho_bd(phi=-80°) = 0.622; slat cell M=5 "
                   "gives 0.631 (converged 0.640, Monte Carlo 0.640)")
def test_iso15099_near_closed_rho_bd_strict():
    got = slat_beam(-80.0 * RAD, 0.0, **ISO, **_faces(0.70, 0.40), segments=5)
    assert float(got.rho_bd) == pytest.approx(0.622, abs=0.002)


def test_iso15099_back_side():
    # Back side of the first row: the same functions at -phi, profile 60°.
    got = slat_beam(45.0 * RAD, 60.0 * RAD, **ISO, **_faces(0.70, 0.70))
    assert float(got.tau_bb) == pytest.approx(0.310, abs=0.002)


def test_suwon_illustrative_table():
    """Suwon louver table of docs/model.md#slat-cell (w 0.05, s 0.045, rho 0.05, profile 30°).

    This is a [PROTO] table, produced by a throw-away prototype of the same method: a
    regression check of this implementation against it, not an independent reference.
    The table is printed to 3 decimals; tolerance ±0.001.
    """
    rows = {  # phi: tau_bb, tau_bd, rho_bd, alpha_b, tau_dd, tau_ir, eps_ir
        -90: (0, 0, 0.047, 0.953, 0, 0, 0.905),
        -45: (0, 0.003, 0.033, 0.964, 0.276, 0.281, 0.677),
        0: (0.358, 0.009, 0.009, 0.623, 0.391, 0.399, 0.580),
        30: (1.000, 0, 0, 0, 0.339, 0.346, 0.624),
        60: (0.358, 0.001, 0.022, 0.618, 0.189, 0.192, 0.749),
        90: (0, 0, 0.047, 0.953, 0, 0, 0.905),
    }
    phi = np.array(list(rows)) * RAD
    beam = slat_beam(phi, 30.0 * RAD, **SUWON, **_faces(0.05, 0.05))
    dif = slat_diffuse(phi, **SUWON, **_faces(0.05, 0.05))
    ir = slat_infrared(phi, **SUWON, emissivity=0.9)
    got = np.stack([*beam, dif.tau_dd, ir.tau_L, ir.eps_L], axis=-1)
    np.testing.assert_allclose(got, np.array(list(rows.values())), atol=0.001)


# ------------------------------------------------------------------------------------------
# Slat cell: closure, view factors, hit fractions, symmetry, degenerate cases
# ------------------------------------------------------------------------------------------

PHI_GRID = np.radians(np.r_[-90.0, np.linspace(-89.0, 89.0, 37), 90.0])
PROFILE_GRID = np.radians(np.r_[-89.9, np.linspace(-85.0, 85.0, 35), 89.9])
FACE_CASES = [(0.7, 0.7), (0.7, 0.2), (0.0, 0.0), (0.05, 0.9), (0.999, 0.999)]
GEOMETRIES = [ISO, SUWON, dict(width=0.03, pitch=0.045)]  # w/s = 1.33, 1.11, 0.67


@pytest.mark.parametrize("geometry", GEOMETRIES)
@pytest.mark.parametrize(("rho_up", "rho_dn"), FACE_CASES)
def test_energy_closure(geometry, rho_up, rho_dn):
    faces = _faces(rho_up, rho_dn)
    beam = slat_beam(PHI_GRID[:, None], PROFILE_GRID, **geometry, **faces)
    assert all(np.all(np.isfinite(x)) for x in beam)
    assert all(np.all(x >= -1e-12) for x in beam)
    np.testing.assert_allclose(sum(beam), 1.0, rtol=0, atol=1e-12)
    dif = slat_diffuse(PHI_GRID, **geometry, **faces)
    np.testing.assert_allclose(sum(dif), 1.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("segments", [1, 5, 10])
def test_energy_closure_segments_and_edge_correction(segments):
    kw = dict(**SUWON, **_faces(0.3, 0.6), segments=segments, thickness=0.0015)
    beam = slat_beam(PHI_GRID[:, None], PROFILE_GRID, **kw)
    np.testing.assert_allclose(sum(beam), 1.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sum(slat_diffuse(PHI_GRID, **kw)), 1.0, rtol=0, atol=1e-12)
    ir = slat_infrared(PHI_GRID, **SUWON, emissivity=0.9, segments=segments, thickness=0.0015)
    np.testing.assert_allclose(sum(ir), 1.0, rtol=0, atol=1e-12)


def test_edge_correction_off_by_default_and_small():
    thin = slat_beam(PHI_GRID[:, None], PROFILE_GRID, **SUWON, **_faces(0.3, 0.3))
    thick = slat_beam(PHI_GRID[:, None], PROFILE_GRID, **SUWON, **_faces(0.3, 0.3),
                      thickness=0.0015)
    # Horizontal slats, profile 0: the edges block t/s of the aperture.
    b0 = slat_beam(0.0, 0.0, **SUWON, **_faces(0.3, 0.3), thickness=0.0015)
    assert float(b0.tau_bb) == pytest.approx(1.0 - 0.0015 / 0.045, abs=1e-12)
    assert np.all(thick.tau_bb <= thin.tau_bb + 1e-15)
    d = slat_diffuse(0.3, **SUWON, **_faces(0.3, 0.3), thickness=0.0015)
    d0 = slat_diffuse(0.3, **SUWON, **_faces(0.3, 0.3))
    assert float(d.tau_dd) == pytest.approx(float(d0.tau_dd) * (1 - 0.0015 / 0.045), abs=1e-14)
    with pytest.raises(ValueError, match="thickness"):
        slat_beam(0.0, 0.0, **SUWON, **_faces(0.3, 0.3), thickness=0.05)


@pytest.mark.parametrize("geometry", GEOMETRIES)
def test_view_factors_reciprocity_and_row_sums(geometry):
    segments = 5
    view = slat_cell_view_factors(PHI_GRID, **geometry, segments=segments)
    assert view.shape == (PHI_GRID.size, 2 * segments + 2, 2 * segments + 2)
    length = np.r_[geometry["pitch"], geometry["pitch"],
                   np.full(2 * segments, geometry["width"] / segments)]
    area_view = length[:, None] * view
    np.testing.assert_allclose(area_view, np.swapaxes(area_view, -1, -2), rtol=0, atol=1e-15)
    np.testing.assert_allclose(view.sum(axis=-1), 1.0, rtol=0, atol=1e-13)
    assert np.all(view >= 0.0)
    assert np.all(np.diagonal(view, axis1=-2, axis2=-1) == 0.0)
    # Segments on the same flat slat do not see each other.
    lower = slice(2, 2 + segments)
    assert np.all(view[:, lower, lower] < 1e-12)
    # Aperture-to-aperture closed form, E+ ER: F_01 = (|Lo Ui| + |Uo Li| - 2w) / (2s).
    w, s = geometry["width"], geometry["pitch"]
    cw, aw = 0.5 * w * np.cos(PHI_GRID), 0.5 * w * np.sin(PHI_GRID)
    lo_ui = np.hypot(2 * cw, s - 2 * aw)
    uo_li = np.hypot(2 * cw, s + 2 * aw)
    np.testing.assert_allclose(view[:, 0, 1], np.abs(lo_ui + uo_li - 2 * w) / (2 * s),
                               rtol=0, atol=1e-14)


@pytest.mark.parametrize("geometry", GEOMETRIES)
def test_direct_transmittance_equals_inner_aperture_hit_fraction(geometry):
    hits = slat_cell_hit_fractions(PHI_GRID[:, None], PROFILE_GRID, **geometry)
    analytic = direct_transmittance(PHI_GRID[:, None], PROFILE_GRID, **geometry)
    np.testing.assert_allclose(hits[..., 1], analytic, rtol=0, atol=1e-12)
    np.testing.assert_allclose(hits.sum(axis=-1), 1.0, rtol=0, atol=1e-13)
    assert np.all(hits[..., 0] == 0.0)
    assert np.all(hits >= 0.0)


def test_diffuse_and_infrared_even_in_phi():
    faces = _faces(0.4, 0.4)
    a, b = slat_diffuse(PHI_GRID, **SUWON, **faces), slat_diffuse(-PHI_GRID, **SUWON, **faces)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-13)
    a, b = (slat_infrared(p, **ISO, emissivity=0.9) for p in (PHI_GRID, -PHI_GRID))
    for x, y in zip(a, b, strict=True):
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-13)
    # Unequal faces: reflectance differs between sides, transmittance does not (reciprocity).
    c = slat_diffuse(PHI_GRID, **SUWON, **_faces(0.7, 0.2))
    d = slat_diffuse(-PHI_GRID, **SUWON, **_faces(0.7, 0.2))
    np.testing.assert_allclose(c.tau_dd, d.tau_dd, rtol=0, atol=1e-13)
    assert np.max(np.abs(c.rho_dd - d.rho_dd)) > 0.1


def test_mirror_symmetry_beam():
    # z -> -z maps (phi, profile, upper, lower) to (-phi, -profile, lower, upper).
    a = slat_beam(PHI_GRID[:, None], PROFILE_GRID, **SUWON, **_faces(0.7, 0.2))
    b = slat_beam(-PHI_GRID[:, None], -PROFILE_GRID, **SUWON, **_faces(0.2, 0.7))
    for x, y in zip(a, b, strict=True):
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-12)


def test_closed_louver_is_the_limit_and_finite():
    for phi in (-np.pi / 2, np.pi / 2):
        near = phi * (1 - 1e-9)
        for geometry in GEOMETRIES:
            exact = slat_beam(phi, PROFILE_GRID, **geometry, **_faces(0.3, 0.6))
            limit = slat_beam(near, PROFILE_GRID, **geometry, **_faces(0.3, 0.6))
            for x, y in zip(exact, limit, strict=True):
                np.testing.assert_allclose(x, y, rtol=0, atol=1e-6)
            d_exact = slat_diffuse(phi, **geometry, **_faces(0.3, 0.6))
            d_limit = slat_diffuse(near, **geometry, **_faces(0.3, 0.6))
            np.testing.assert_allclose(np.array(d_exact), np.array(d_limit), atol=1e-6)
    # Overlapping black slats (w > s) closed: nothing passes.
    closed = slat_diffuse(np.pi / 2, **SUWON, **_faces(0.0, 0.0))
    assert float(closed.tau_dd) == pytest.approx(0.0, abs=1e-15)
    assert float(closed.alpha_d) == pytest.approx(1.0, abs=1e-15)
    # Gapped slats (w < s) closed: the gap 1 - w/s passes straight through.
    gapped = slat_beam(np.pi / 2, 0.0, width=0.03, pitch=0.045, **_faces(0.0, 0.0))
    assert float(gapped.tau_bb) == pytest.approx(1 - 0.03 / 0.045, abs=1e-12)


def test_rays_parallel_to_slats_pass_straight_through():
    phi = np.radians(np.linspace(-80, 80, 17))
    got = slat_beam(phi, phi, **SUWON, **_faces(0.5, 0.5))
    np.testing.assert_allclose(got.tau_bb, 1.0, atol=1e-12)
    np.testing.assert_allclose(got.tau_bd + got.rho_bd + got.alpha_b, 0.0, atol=1e-12)


def test_zero_reflectance():
    beam = slat_beam(PHI_GRID[:, None], PROFILE_GRID, **SUWON, **_faces(0.0, 0.0))
    assert np.all(beam.tau_bd == 0.0)
    assert np.all(beam.rho_bd == 0.0)
    np.testing.assert_allclose(beam.alpha_b, 1.0 - beam.tau_bb, atol=1e-13)
    dif = slat_diffuse(PHI_GRID, **SUWON, **_faces(0.0, 0.0))
    assert np.all(dif.rho_dd == 0.0)
    view = slat_cell_view_factors(PHI_GRID, **SUWON)
    np.testing.assert_allclose(dif.tau_dd, view[:, 0, 1], atol=1e-15)


def test_sky_ground_split():
    faces = _faces(0.3, 0.3)
    phi = np.radians(np.linspace(-90, 90, 13))
    split = slat_sky_ground(phi, **SUWON, **faces)
    np.testing.assert_allclose(split.tau_sky + split.rho_sky + split.alpha_sky, 1.0, atol=1e-12)
    np.testing.assert_allclose(split.tau_gnd + split.rho_gnd + split.alpha_gnd, 1.0, atol=1e-12)
    # Sky and ground together are the uniform diffuse (2-D Lambertian) case.
    uniform = slat_diffuse(phi, **SUWON, **faces)
    np.testing.assert_allclose(0.5 * (split.tau_sky + split.tau_gnd), uniform.tau_dd, atol=5e-4)
    np.testing.assert_allclose(0.5 * (split.rho_sky + split.rho_gnd), uniform.rho_dd, atol=5e-4)
    # Equal faces: the sky seen at phi is the ground seen at -phi.
    mirrored = slat_sky_ground(-phi, **SUWON, **faces)
    np.testing.assert_allclose(split.tau_sky, mirrored.tau_gnd, atol=1e-13)


def test_broadcasting_and_cache_consistency():
    phi = np.radians(np.arange(-90, 91, 18))[:, None]
    profile = np.radians(np.linspace(-10, 70, 15))
    lv = LouverOptics(**SUWON, reflectance_upper=0.07, reflectance_lower=0.07)
    grid = lv.beam(phi, profile)
    assert grid.tau_bb.shape == (11, 15)
    uncached = slat_beam(phi, profile, **SUWON, **_faces(0.07, 0.07), cache=False)
    paired = slat_beam(np.broadcast_to(phi, (11, 15)), np.broadcast_to(profile, (11, 15)),
                       **SUWON, **_faces(0.07, 0.07))
    for a, b, c in zip(grid, uncached, paired, strict=True):
        np.testing.assert_allclose(a, b, atol=1e-15)
        np.testing.assert_allclose(a, c, atol=1e-15)
    scalar = lv.beam(0.0, 0.0)
    assert np.shape(scalar.tau_bb) == ()
    assert lv.diffuse(phi).tau_dd.shape == (11, 1)


def test_no_louver():
    beam = NO_LOUVER.beam(np.zeros((3, 1)), np.zeros(4))
    assert beam.tau_bb.shape == (3, 4)
    assert np.all(beam.tau_bb == 1.0)
    assert all(np.all(x == 0.0) for x in beam[1:])
    dif = NO_LOUVER.diffuse(0.0)
    assert (float(dif.tau_dd), float(dif.rho_dd), float(dif.alpha_d)) == (1.0, 0.0, 0.0)
    ir = NO_LOUVER.infrared(0.0)
    assert (float(ir.eps_L), float(ir.tau_L), float(ir.rho_L)) == (0.0, 1.0, 0.0)


def test_louver_optics_from_config(suwon):
    solar = LouverOptics.from_config(suwon.louver)
    assert (solar.width, solar.pitch, solar.reflectance_upper) == (0.05, 0.045, 0.07)
    assert solar.thickness == 0.0 and solar.segments == 5
    visible = LouverOptics.from_config(suwon.louver, band="visible", segments=10,
                                       edge_correction=True)
    assert (visible.reflectance_lower, visible.segments, visible.thickness) == (0.05, 10, 0.0015)
    assert glass_triples(suwon.glazing) == SUWON_GLASS
    assert glass_triples(suwon.glazing, band="visible")[0] == (0.840, 0.055, 0.078)


# ------------------------------------------------------------------------------------------
# Glass and DGU
# ------------------------------------------------------------------------------------------


def test_glass_normal_incidence_and_closure():
    rng = np.random.default_rng(7)
    T0 = rng.uniform(0.05, 0.92, 200)
    R0 = rng.uniform(0.0, 1.0, 200) * (1 - T0) * 0.5
    cos = np.linspace(0.0, 1.0, 91)[:, None]
    g = glass_angular(T0, R0, R0 * 1.2, cos)
    np.testing.assert_allclose(g.T + g.R_f + g.A_f, 1.0, atol=1e-15)
    np.testing.assert_allclose(g.T + g.R_b + g.A_b, 1.0, atol=1e-15)
    assert np.all(g.A_f > -1e-12) and np.all(g.A_b > -1e-12)
    np.testing.assert_allclose(g.T[-1], T0, atol=1e-15)
    np.testing.assert_allclose(g.R_f[-1], R0, atol=1e-15)
    assert np.all(g.T[0] == 0.0)
    assert np.all(np.diff(g.T, axis=0) >= -1e-12)  # T rises towards normal incidence


def test_glass_curve_set_selection():
    # Either side of T0 = 0.645 the two curve sets give different shapes of T(θ)/T0.
    c = 0.5
    clear = glass_angular(0.66, 0.1, 0.1, c).T / 0.66
    bronze = glass_angular(0.64, 0.1, 0.1, c).T / 0.64
    assert float(clear) == pytest.approx(-0.0015 + 3.355 * c - 3.840 * c**2 + 1.460 * c**3
                                         + 0.0288 * c**4, abs=1e-12)
    assert float(bronze) == pytest.approx(-0.002 + 2.813 * c - 2.341 * c**2 - 0.05725 * c**3
                                          + 0.599 * c**4, abs=1e-12)
    # Array input selects per element.
    both = glass_angular(np.array([0.66, 0.64]), 0.1, 0.1, c).T / np.array([0.66, 0.64])
    np.testing.assert_allclose(both, [float(clear), float(bronze)], atol=1e-15)


def test_glass_hemispherical():
    for T0, Rf, Rb in (*SUWON_GLASS, (0.84, 0.055, 0.078), (0.1, 0.3, 0.05)):
        h = glass_hemispherical(T0, Rf, Rb)
        for x in h:
            assert 0.0 < float(x) < 1.0
        assert float(h.T + h.R_f + h.A_f) == pytest.approx(1.0, abs=1e-14)
        assert float(h.T + h.R_b + h.A_b) == pytest.approx(1.0, abs=1e-14)
        assert float(h.T) < T0 and float(h.R_f) > Rf  # diffuse is more oblique than normal
    # The normalised quadrature maps a constant to itself: R0 = 1 stays 1.
    assert float(glass_hemispherical(0.0, 1.0, 1.0).R_f) == pytest.approx(1.0, abs=1e-14)


def test_dgu_identity():
    rng = np.random.default_rng(3)
    n = 1000
    parts = rng.dirichlet([2, 1, 1], size=(n, 2))  # T, R, A of each pane, front and back
    outer = glass_angular(parts[:, 0, 0], parts[:, 0, 1], rng.uniform(0, 1 - parts[:, 0, 0]),
                          rng.uniform(0, 1, n))
    inner = glass_angular(parts[:, 1, 0], parts[:, 1, 1], rng.uniform(0, 1 - parts[:, 1, 0]),
                          rng.uniform(0, 1, n))
    dgu = dgu_beam(outer, inner)
    np.testing.assert_allclose(dgu.T + dgu.R_f + dgu.A_2 + dgu.A_3, 1.0, atol=1e-14)
    assert np.all(np.array(dgu) >= -1e-14)
    # Second pane transparent and non-reflecting: the DGU is the first pane.
    clear = glass_angular(1.0, 0.0, 0.0, 1.0)
    first = glass_angular(0.7, 0.1, 0.15, 1.0)
    single = dgu_beam(first, clear)
    assert float(single.T) == pytest.approx(0.7)
    assert float(single.A_2) == pytest.approx(0.2)
    assert float(single.A_3) == 0.0


# ------------------------------------------------------------------------------------------
# Multilayer balance (docs/model.md#multilayer)
# ------------------------------------------------------------------------------------------


def _random_glass(rng: np.random.Generator) -> tuple:
    out = []
    for _ in range(3):
        T0 = rng.uniform(0.05, 0.9)
        out.append((T0, rng.uniform(0, 1 - T0), rng.uniform(0, 1 - T0)))
    return tuple(out)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("with_louver", [True, False])
def test_multilayer_energy_closure(seed, with_louver):
    rng = np.random.default_rng(seed)
    n = 15
    beam = rng.uniform(0, 900, n)
    diffuse = rng.uniform(0, 400, n)
    cos_aoi = rng.uniform(0, 1, n)
    profile = rng.uniform(-1.5, 1.5, n)
    phi = np.radians(np.arange(-90, 91, 18))[:, None]
    louver = LouverOptics(width=rng.uniform(0.01, 0.08), pitch=rng.uniform(0.01, 0.08),
                          reflectance_upper=rng.uniform(0, 0.95),
                          reflectance_lower=rng.uniform(0, 0.95)) if with_louver else None
    glass = _random_glass(rng)
    for ground in (None, 0.4 * diffuse):
        out = layer_absorption(beam=beam, diffuse=diffuse, cos_aoi=cos_aoi, phi=phi,
                               profile=profile, glass=glass, louver=louver, diffuse_ground=ground)
        assert all(x.shape == (11, n) for x in out)
        balance = out.s1 + out.s2 + out.s3 + out.s4 + out.transmitted + out.reflected
        incident = np.broadcast_to(beam + diffuse, balance.shape)
        np.testing.assert_allclose(balance, incident, rtol=1e-12, atol=1e-12)
        assert all(np.all(x >= -1e-9) for x in out)
        assert np.all(out.transmitted_beam <= out.transmitted + 1e-12)
        if not with_louver:
            assert np.all(out.s4 == 0.0)


def test_multilayer_node_mapping_and_limits():
    n = 4
    beam, diffuse = np.full(n, 500.0), np.full(n, 100.0)
    cos_aoi, profile = np.full(n, 0.8), np.full(n, 0.5)
    # No louver: beam reaches the room as T_1 T_DGU; the louver node absorbs nothing.
    out = layer_absorption(beam=beam, diffuse=np.zeros(n), cos_aoi=cos_aoi, phi=0.0,
                           profile=profile, glass=SUWON_GLASS)
    g = [glass_angular(*t, 0.8) for t in SUWON_GLASS]
    dgu = dgu_beam(g[1], g[2])
    np.testing.assert_allclose(out.transmitted_beam, 500.0 * g[0].T * dgu.T, rtol=1e-14)
    assert np.all(out.s4 == 0.0) and np.all(out.s2 > 0.0) and np.all(out.s3 > 0.0)
    # A closed black louver (w > s): all short-wave behind L1 ends in node 4 (the louver);
    # L2, L3 and the room get nothing.
    black = LouverOptics(**SUWON, reflectance_upper=0.0, reflectance_lower=0.0)
    shut = layer_absorption(beam=beam, diffuse=diffuse, cos_aoi=cos_aoi, phi=np.pi / 2,
                            profile=profile, glass=SUWON_GLASS, louver=black)
    for x in (shut.s2, shut.s3, shut.transmitted):
        np.testing.assert_allclose(x, 0.0, atol=1e-12)
    h1 = glass_hemispherical(*SUWON_GLASS[0])
    expected_s4 = g[0].T * beam + float(h1.T) * diffuse
    np.testing.assert_allclose(shut.s4, expected_s4, rtol=1e-12)
    np.testing.assert_allclose(shut.s1, g[0].A_f * beam + float(h1.A_f) * diffuse, rtol=1e-12)


def test_multilayer_sky_ground_equals_uniform_when_split_is_even():
    # With equal faces, the split uses the sky properties for the sky part and the ground
    # ones for the rest; for a horizontal louver sky = ground, so the uniform result follows
    # to quadrature accuracy.
    lv = LouverOptics(**SUWON, reflectance_upper=0.3, reflectance_lower=0.3)
    kw = dict(beam=np.zeros(2), diffuse=np.full(2, 200.0), cos_aoi=np.ones(2), phi=0.0,
              profile=np.zeros(2), glass=SUWON_GLASS, louver=lv)
    uniform = layer_absorption(**kw)
    split = layer_absorption(**kw, diffuse_ground=np.full(2, 100.0))
    np.testing.assert_allclose(split.s4, uniform.s4, rtol=2e-3)
    np.testing.assert_allclose(split.transmitted, uniform.transmitted, rtol=2e-3)
