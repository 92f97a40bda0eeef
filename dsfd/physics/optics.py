"""Solar (or visible) sources of the DSF layers by the multilayer net-radiation method.

This module holds the multilayer balance of docs/model.md#multilayer and re-exports
the layer optics of :mod:`dsfd.physics.optics_glass` and :mod:`dsfd.physics.optics_louver`,
so that ``from dsfd.physics.optics import ...`` reaches the whole short-wave API.

Layers, outdoors to room: L1 (exterior pane) -> louver -> L2 -> L3 (the DGU). Node numbers of
the thermal network (docs/model.md#multilayer): 1 = L1, 2 = L2, 3 = L3, 4 = louver.

Band: the functions are band-agnostic. For the daylight proxy call them with the visible
glass data and a visible :class:`LouverOptics`.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dsfd.physics.optics_glass import (
    DGUBeam,
    GlassAngular,
    dgu_beam,
    glass_angular,
    glass_hemispherical,
)
from dsfd.physics.optics_louver import (
    NO_LOUVER,
    LouverOptics,
    NoLouverOptics,
    SlatBeam,
    SlatDiffuse,
    SlatInfrared,
    SlatSkyGround,
    direct_transmittance,
    slat_beam,
    slat_cell_hit_fractions,
    slat_cell_view_factors,
    slat_diffuse,
    slat_infrared,
    slat_sky_ground,
)

if TYPE_CHECKING:
    from dsfd.config.panel import Glazing

__all__ = [
    "NO_LOUVER",
    "DGUBeam",
    "GlassAngular",
    "GlassTriple",
    "LayerSources",
    "LouverOptics",
    "NoLouverOptics",
    "SlatBeam",
    "SlatDiffuse",
    "SlatInfrared",
    "SlatSkyGround",
    "dgu_beam",
    "direct_transmittance",
    "glass_angular",
    "glass_hemispherical",
    "glass_triples",
    "layer_absorption",
    "slat_beam",
    "slat_cell_hit_fractions",
    "slat_cell_view_factors",
    "slat_diffuse",
    "slat_infrared",
    "slat_sky_ground",
]

FloatArray = NDArray[np.float64]

#: Normal-incidence (transmittance, front reflectance, back reflectance) of one pane [-].
GlassTriple = tuple[float, float, float]


class LayerSources(NamedTuple):
    """Short-wave power per m² of façade [W/m2], all of one broadcast shape.

    ``beam + diffuse = s1 + s2 + s3 + s4 + transmitted + reflected``.
    """

    s1: FloatArray  #: absorbed in node 1, exterior pane L1
    s2: FloatArray  #: absorbed in node 2, cavity-side DGU pane L2
    s3: FloatArray  #: absorbed in node 3, room-side DGU pane L3
    s4: FloatArray  #: absorbed in node 4, the louver
    transmitted: FloatArray  #: entering the room, beam + diffuse
    transmitted_beam: FloatArray  #: entering the room as undeviated beam
    reflected: FloatArray  #: leaving the façade back outdoors


def glass_triples(
    glazing: Glazing, *, band: Literal["solar", "visible"] = "solar"
) -> tuple[GlassTriple, GlassTriple, GlassTriple]:
    """Normal-incidence triples (L1, L2, L3) for :func:`layer_absorption` from the config."""
    layers = (glazing.exterior, glazing.interior_outer, glazing.interior_inner)
    return tuple(  # type: ignore[return-value]
        (
            getattr(g, f"{band}_transmittance"),
            getattr(g, f"{band}_reflectance_front"),
            getattr(g, f"{band}_reflectance_back"),
        )
        for g in layers
    )


@lru_cache(maxsize=64)
def _glass_diffuse(
    glass: tuple[GlassTriple, GlassTriple, GlassTriple],
) -> tuple[GlassAngular, GlassAngular, GlassAngular, FloatArray]:
    """Hemispherical properties of L1, L2, L3 and the glass-only part of the 6x6 system."""
    h1, h2, h3 = (glass_hemispherical(*triple) for triple in glass)
    # Unknowns (F1, F2, F3, B1, B2, B3); rows F1, F2, F3, B1, B2, B3 of docs/model.md#multilayer.
    # The louver entries (rows F2 and B1) are added per slat angle.
    system = np.eye(6)
    system[0, 3] = -h1.R_b  # F1 = tau_1 F0 + rho^b_1 B1
    system[2, 1] = -h2.T  # F3 = tau_2 F2 + rho^b_2 B3
    system[2, 5] = -h2.R_b
    system[4, 1] = -h2.R_f  # B2 = tau_2 B3 + rho^f_2 F2 + s-_2
    system[4, 5] = -h2.T
    system[5, 2] = -h3.R_f  # B3 = rho^f_3 F3 (no short-wave from the room)
    system.flags.writeable = False
    return h1, h2, h3, system


# long: 103 lines, 72 of them the docstring, which derives the balance the code solves; the
# code itself is the three named steps below it (_beam_pass, _sky_and_ground, _diffuse_fluxes).
def layer_absorption(
    *,
    beam: ArrayLike,
    diffuse: ArrayLike,
    cos_aoi: ArrayLike,
    phi: ArrayLike,
    profile: ArrayLike,
    glass: tuple[GlassTriple, GlassTriple, GlassTriple],
    louver: LouverOptics | NoLouverOptics | None = None,
    diffuse_ground: ArrayLike | None = None,
    sky_ground: SlatSkyGround | None = None,
) -> LayerSources:
    """Absorbed, transmitted and reflected short-wave power of the four DSF layers.

    Parameters
    ----------
    beam : array_like
        Beam irradiance on the façade plane I_b,v = DNI max(cos θ, 0) [W/m2].
    diffuse : array_like
        Total diffuse irradiance on the façade plane I_d,v (sky + ground) [W/m2].
    cos_aoi : array_like
        Cosine of the beam's angle of incidence on the façade [-].
    phi : array_like
        Louver slat angle [rad] (0 horizontal, + towards the sky).
    profile : array_like
        Solar profile angle on the façade [rad].
    glass : tuple of three (T0, R_f0, R_b0)
        Normal-incidence properties of L1, L2, L3 in the band of interest [-], scalars;
        see :func:`glass_triples`.
    louver : LouverOptics, NoLouverOptics or None
        The louver in the same band; ``None`` means :data:`NO_LOUVER`.
    diffuse_ground : array_like, optional
        Ground-reflected part of ``diffuse`` [W/m2]. When given, the outdoor diffuse that
        L1 transmits reaches the louver with the sky / ground properties of docs/model.md#slat-cell
        instead of the uniform-diffuse ones (docs/model.md#louver-diffuse; 128 extra beam
        evaluations per slat angle).
    sky_ground : SlatSkyGround, optional
        The louver's sky / ground properties at ``phi`` (``louver.sky_ground(phi)``), when
        the caller keeps them for repeated angles; used only with ``diffuse_ground``.

    Returns
    -------
    LayerSources
        ``s1, s2, s3, s4, transmitted, transmitted_beam, reflected`` [W/m2], node-numbered
        per docs/model.md#multilayer, each of the broadcast shape of all array inputs. Time-step
        inputs of shape ``(n_steps,)`` with ``phi`` of shape ``(n_phi, 1)`` give
        ``(n_phi, n_steps)``.

    Notes
    -----
    docs/model.md#multilayer. Beam, with θ the angle of incidence::

        b1 = T_1(θ) I_b                       (beam in gap 1)
        b2 = tau_bb(phi, phi_s) b1            (beam in gap 2)
        S1_b = A_1,f(θ) I_b,  S4_b = alpha_b b1,  S2_b = A_2(θ) b2,  S3_b = A_3(θ) b2
        transmitted_beam = T_DGU(θ) b2        (docs/model.md#glass-optics)

    The louver turns ``tau_bd b1`` into inward diffuse in gap 2 and ``rho_bd b1`` into outward
    diffuse in gap 1; the DGU returns ``R_DGU,f(θ) b2`` into gap 2 as diffuse. Diffuse
    fluxes F_g (inward) and B_g (outward) in gaps g = 1 (L1-louver), 2 (louver-L2),
    3 (L2-L3), layers j = 1 L1, 2 louver, 3 L2, 4 L3::

        F_g = tau^f_g F_{g-1} + rho^b_g B_g + s+_g,      F_0 = I_d
        B_g = tau^b_{g+1} B_{g+1} + rho^f_{g+1} F_g + s-_g,   B_3 needs B_4 = 0

    (no short-wave from the room): a 6 x 6 linear system whose matrix depends on the slat
    angle only, inverted once per angle (batched ``np.linalg.inv``) and applied to every time
    step. Glass uses hemispherical properties (docs/model.md#glass-optics), the louver
    ``tau_dd, rho_dd`` at ``phi`` for the front and at ``-phi`` for the back. Absorbed diffuse
    ``S_j,d = alpha^f_j F_{j-1} + alpha^b_j B_j``; ``transmitted = transmitted_beam +
    tau_4 F_3``; ``reflected = R_1,f(θ) I_b + rho^f_1 I_d + tau_1 B_1``. Layer -> node
    (docs/model.md#multilayer)::

        s1 = S1_b + S_{j=1},d     s2 = A_2 b2 + S_{j=3},d
        s3 = A_3 b2 + S_{j=4},d   s4 = alpha_b b1 + S_{j=2},d

    The method is the simplified Edwards / Wright–Kotey equivalent-layer idea (EnergyPlus
    ER, "Equivalent Layer Fenestration Model").
    """
    lv = NO_LOUVER if louver is None else louver
    glass = tuple(tuple(float(v) for v in triple) for triple in glass)  # type: ignore[assignment]
    beam = np.asarray(beam, dtype=float)
    diffuse = np.asarray(diffuse, dtype=float)
    phi = np.asarray(phi, dtype=float)
    cos_aoi = np.asarray(cos_aoi, dtype=float)
    # The three panes in one vectorised call: leading axis = pane.
    normal = np.array(glass).T.reshape((3, 3) + (1,) * cos_aoi.ndim)
    panes = glass_angular(normal[0], normal[1], normal[2], cos_aoi)
    g1, g2, g3 = (GlassAngular(*(p[i] for p in panes)) for i in range(3))
    h1, h2, h3, glass_system = _glass_diffuse(glass)  # type: ignore[arg-type]
    front = lv.diffuse(phi)
    back = lv.diffuse(-phi)
    layers, gaps = _beam_pass(beam, g1, dgu_beam(g2, g3), lv.beam(phi, profile))
    if diffuse_ground is None:  # outdoor diffuse transmitted by L1: uniform
        gaps = gaps._replace(inward_1=h1.T * diffuse)
    else:  # or as sky + ground "pseudo-beams"
        split = lv.sky_ground(phi) if sky_ground is None else sky_ground
        layers, gaps = _sky_and_ground(layers, gaps, split, h1.T * diffuse,
                                       h1.T * np.asarray(diffuse_ground, dtype=float))
    F1, F2, F3, B1, B2, B3 = _diffuse_fluxes(glass_system, front, back, gaps)
    s1 = layers.s1 + h1.A_f * diffuse + h1.A_b * B1
    s4 = layers.s4 + front.alpha_d * F1 + back.alpha_d * B2
    s2 = layers.s2 + h2.A_f * F2 + h2.A_b * B3
    s3 = layers.s3 + h3.A_f * F3
    transmitted = layers.transmitted_beam + h3.T * F3
    reflected = g1.R_f * beam + h1.R_f * diffuse + h1.T * B1
    out = np.broadcast_arrays(s1, s2, s3, s4, transmitted, layers.transmitted_beam, reflected)
    return LayerSources(*(np.array(a) for a in out))


class _Absorbed(NamedTuple):
    """Short-wave absorbed per layer (node numbering) and the beam reaching the room."""

    s1: np.ndarray
    s2: np.ndarray
    s3: np.ndarray
    s4: np.ndarray
    transmitted_beam: np.ndarray


class _GapSources(NamedTuple):
    """Diffuse sources of the gaps: inward into gaps 1, 2 (s+), outward into gaps 1, 2 (s-)."""

    inward_1: np.ndarray | float
    inward_2: np.ndarray
    outward_1: np.ndarray
    outward_2: np.ndarray


def _beam_pass(beam: np.ndarray, g1: GlassAngular, dgu: DGUBeam,
               slat: SlatBeam) -> tuple[_Absorbed, _GapSources]:
    """The beam through L1, the louver and the DGU: what each layer absorbs and the
    diffuse it leaves in the gaps (layer_absorption's Notes)."""
    b1 = g1.T * beam
    b2 = slat.tau_bb * b1
    absorbed = _Absorbed(s1=g1.A_f * beam, s2=dgu.A_2 * b2, s3=dgu.A_3 * b2,
                         s4=slat.alpha_b * b1, transmitted_beam=dgu.T * b2)
    return absorbed, _GapSources(inward_1=0.0, inward_2=slat.tau_bd * b1,
                                 outward_1=slat.rho_bd * b1, outward_2=dgu.R_f * b2)


def _sky_and_ground(absorbed: _Absorbed, gaps: _GapSources, split: SlatSkyGround,
                    through_l1: np.ndarray, ground: np.ndarray
                    ) -> tuple[_Absorbed, _GapSources]:
    """The outdoor diffuse that L1 transmits (``through_l1``, of which ``ground`` comes
    from the ground) meets the louver with its sky and ground properties."""
    sky = through_l1 - ground
    absorbed = absorbed._replace(s4=absorbed.s4 + split.alpha_sky * sky
                                 + split.alpha_gnd * ground)
    return absorbed, _GapSources(
        inward_1=np.zeros_like(sky),
        inward_2=gaps.inward_2 + split.tau_sky * sky + split.tau_gnd * ground,
        outward_1=gaps.outward_1 + split.rho_sky * sky + split.rho_gnd * ground,
        outward_2=gaps.outward_2)


def _diffuse_fluxes(glass_system: FloatArray, front: SlatDiffuse, back: SlatDiffuse,
                    gaps: _GapSources) -> tuple[np.ndarray, ...]:
    """Diffuse net radiation (F1, F2, F3, B1, B2, B3) of the 6 x 6 system with the louver
    rows F2 = tau^f_LV F1 + rho^b_LV B2 + s+_2, B1 = tau^b_LV B2 + rho^f_LV F1 + s-_1."""
    shape = np.broadcast_shapes(front.tau_dd.shape, back.tau_dd.shape)
    system = np.empty((*shape, 6, 6))
    system[...] = glass_system
    system[..., 1, 0] = -front.tau_dd
    system[..., 1, 4] = -back.rho_dd
    system[..., 3, 0] = -front.rho_dd
    system[..., 3, 4] = -back.tau_dd
    rhs_shape = np.broadcast_shapes(*(np.shape(v) for v in gaps))
    rhs = np.zeros((*rhs_shape, 6, 1))
    rhs[..., 0, 0] = gaps.inward_1
    rhs[..., 1, 0] = gaps.inward_2
    rhs[..., 3, 0] = gaps.outward_1
    rhs[..., 4, 0] = gaps.outward_2
    # The matrix depends on phi only: one inverse per slat angle, then a product per time
    # step, is cheaper than broadcasting an LU solve over every time step.
    return tuple(np.moveaxis((np.linalg.inv(system) @ rhs)[..., 0], -1, 0))
