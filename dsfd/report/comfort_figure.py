"""The report's comfort figure: glare and the sun cut-off over the day, occupied periods shaded.

Drawn from what the daemon stores: the measured weather of each cycle, the louver angle in
effect and the run's configuration (its site, façade, louver, ``occupancy:`` and
``comfort:``). The quantities are recomputed with the model's optics and the pure comfort
functions (docs/model.md#comfort), so the figure needs no comfort column and reads any log.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from dsfd.config import ConfigError, panel_from_mapping
from dsfd.config.panel import PanelConfig
from dsfd.control.comfort import view_factors
from dsfd.control.occupancy import occupied
from dsfd.physics.boundary import model_weather
from dsfd.physics.comfort_visual import (
    cutoff_angles,
    dgp_simplified,
    eye_illuminance_lx,
    glare_class,
)
from dsfd.physics.forcing import FacadeOptics, facade_forcing
from dsfd.report.plotting import OUTSIDE, WIDTH_IN, Context, broken, nothing, time_axis

__all__ = ["CAPTION", "LoggedComfort", "comfort_figure", "logged_comfort"]

CAPTION = ("Recomputed for every logged cycle from its measured weather and the louver angle "
           "in effect, with the model's optics (docs/model.md#comfort): the glare at a seated "
           "occupant's eye facing the façade, and the louver against the angle that just "
           "keeps the sun's beam out. Shaded: occupied by the run's schedule.")

_OCCUPIED = "#dfe9f5"
_BEAM = "#ffd9a8"


class LoggedComfort(NamedTuple):
    """Comfort quantities of the logged cycles (arrays over the cycles)."""

    occupied: np.ndarray  # bool
    dgp: np.ndarray  # [-]
    direct_sun_wm2: np.ndarray
    cutoff_lower_deg: np.ndarray  # NaN where the sun does not shine on the façade
    cutoff_upper_deg: np.ndarray
    dgp_limit: float
    direct_sun_limit_wm2: float


def logged_comfort(cfg: PanelConfig, time_s: np.ndarray, t_out_c: np.ndarray,
                   ghi_wm2: np.ndarray, phi_deg: np.ndarray) -> LoggedComfort:
    """The comfort of each cycle as the model's optics see it (NaN where a reading is missing).

    ``time_s`` are the instants the readings stand for (the middle of the interval they
    average), ``phi_deg`` the louver angle in effect.
    """
    ok = np.isfinite(t_out_c) & np.isfinite(ghi_wm2)
    w = model_weather(time_s=time_s, t_out_c=np.where(ok, t_out_c, 0.0),
                      ghi_wm2=np.where(ok, ghi_wm2, 0.0), room=cfg.room,
                      facade_azimuth_deg=cfg.facade.azimuth_deg,
                      elevation_m=cfg.site.elevation_m)
    f = facade_forcing(cfg, w)
    phi = np.radians(np.nan_to_num(np.asarray(phi_deg, float)))
    sol, vis = FacadeOptics(cfg).layers(f, phi)
    f_eye, _ = view_factors(cfg)
    e_v = eye_illuminance_lx(transmitted_wm2=vis.transmitted,
                             transmitted_beam_wm2=vis.transmitted_beam, view_factor=f_eye,
                             luminous_efficacy_lmw=cfg.daylight.luminous_efficacy_lmw)
    bad = ~ok | ~np.isfinite(phi_deg)
    lit = (f.beam_wm2 > 0.0) & ~bad
    if cfg.louver is None:
        lower = upper = np.full(time_s.shape, np.nan)
    else:
        cut = cutoff_angles(np.radians(f.profile_deg), width=cfg.louver.slat_width_m,
                            pitch=cfg.louver.slat_pitch_m)
        lower = np.where(lit, np.degrees(cut.lower), np.nan)
        upper = np.where(lit, np.degrees(cut.upper), np.nan)
    return LoggedComfort(
        occupied=occupied(time_s, occupancy=cfg.occupancy, utc_offset_h=cfg.site.utc_offset_h),
        dgp=np.where(bad, np.nan, dgp_simplified(e_v)),
        direct_sun_wm2=np.where(bad, np.nan, sol.transmitted_beam),
        cutoff_lower_deg=lower, cutoff_upper_deg=upper,
        dgp_limit=cfg.comfort.dgp_max, direct_sun_limit_wm2=cfg.comfort.direct_sun_max_wm2)


def _shade_occupied(ctx: Context, ax: Axes, occ: np.ndarray, *, label: bool) -> None:
    """Light bands over the occupied cycles (each cycle's interval ends at its stamp)."""
    t = ctx.history.time_s
    if not occ.any():
        return
    edges = np.flatnonzero(np.diff(np.concatenate([[0], occ.astype(int), [0]])))
    step = ctx.kpis.step_s
    for i, (a, b) in enumerate(zip(edges[::2], edges[1::2], strict=True)):
        lo, hi = ctx.local(np.array([t[a] - step, t[b - 1]]))
        ax.axvspan(lo, hi, color=_OCCUPIED, lw=0, zorder=0,
                   label="occupied" if label and i == 0 else None)


def comfort_figure(ctx: Context) -> Figure:
    """DGPs with the class limit, and the louver against the sun's cut-off angle."""
    h = ctx.history
    fig = Figure(figsize=(WIDTH_IN, 7.0), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True, height_ratios=[1.0, 1.2])
    fig.suptitle("Occupant comfort: glare at the eye, and the louver against the sun "
                 "cut-off angle", fontsize=13, x=0.01, ha="left")
    cfg, why = _panel(ctx)
    if cfg is None or not len(h):
        for ax in axes:
            nothing(ax, why if len(h) else "no cycles logged")
            ax.set_axis_off()
        return fig
    # A reading is the mean of the interval that ends at its stamp, which the previous
    # cycle's position held.
    time_mid = h.time_s - ctx.kpis.step_s / 2
    phi = h.applied()["phi_deg"]
    held = np.concatenate([phi[:1], phi[:-1]])
    c = logged_comfort(cfg, time_mid, h.good("t_out_c"), h.good("ghi_wm2"), held)
    _glare_panel(ctx, axes[0], c, cfg)
    _cutoff_panel(ctx, axes[1], c)
    return fig


#: The sections the figure's optics and limits need (the rest, e.g. the stage budgets a
#: closed-loop simulation lifts beyond their bounds, stays out of the way).
_SECTIONS = ("panel", "site", "facade", "glazing", "louver", "openings", "room", "daylight",
             "model", "parameters", "occupancy", "comfort")


def _panel(ctx: Context) -> tuple[PanelConfig | None, str]:
    """The run's panel, or None and why not."""
    if ctx.config is None:
        return None, ("no panel configuration stored with this log (older dsfd) and none "
                      "given (--config): the comfort cannot be recomputed")
    doc = {k: v for k, v in ctx.config.items() if k in _SECTIONS}
    try:
        return panel_from_mapping(doc), ""
    except ConfigError as exc:
        return None, f"the stored configuration does not load: {exc}"


def _glare_panel(ctx: Context, ax: Axes, c: LoggedComfort, cfg: PanelConfig) -> None:
    _shade_occupied(ctx, ax, c.occupied, label=True)
    ax.plot(*broken(ctx, c.dgp), color="#d62728", lw=1.3, label="DGPs at the eye")
    ax.axhline(c.dgp_limit, color="black", ls="--", lw=1.0,
               label=f"limit {c.dgp_limit:g} (EN 17037 {glare_class(c.dgp_limit)})")
    ax.set_ylim(0.15, 1.02)
    ax.set_ylabel("simplified daylight glare\nprobability DGPs [-] (≤ 1)")
    occ = c.occupied & np.isfinite(c.dgp)
    if occ.any():
        above = np.mean(c.dgp[occ] > c.dgp_limit)
        sun = np.mean(c.direct_sun_wm2[occ] > c.direct_sun_limit_wm2)
        ax.set_title(f"occupied cycles: DGPs above {c.dgp_limit:g} in {above:.0%}, direct "
                     f"sun above {c.direct_sun_limit_wm2:g} W/m² in {sun:.0%} (eye "
                     f"{cfg.comfort.occupant_distance_m:g} m from the pane, "
                     f"{cfg.comfort.eye_height_m:g} m high)", fontsize=9, loc="left")
    else:
        ax.set_title("the panel has no occupancy: schedule: never occupied, no comfort limit "
                     "applies" if cfg.occupancy is None else "no occupied cycle in this log",
                     fontsize=9, loc="left", color="#555555")
    if not np.isfinite(c.dgp).any():
        nothing(ax, "no good weather readings to recompute the glare from")
    ax.legend(**OUTSIDE)
    time_axis(ctx, ax, label=False)


def _cutoff_panel(ctx: Context, ax: Axes, c: LoggedComfort) -> None:
    _shade_occupied(ctx, ax, c.occupied, label=False)
    t, lower = broken(ctx, c.cutoff_lower_deg)
    _, upper = broken(ctx, c.cutoff_upper_deg)
    lo_band = np.where(np.isfinite(lower), lower, -90.0)
    hi_band = np.where(np.isfinite(upper), upper, 90.0)
    sunny = np.isfinite(lower) | np.isfinite(upper)
    ax.fill_between(t, lo_band, hi_band, where=sunny, color=_BEAM, lw=0, step=None,
                    label="beam passes the slats")
    ax.plot(t, lower, color="#ff7f0e", lw=1.2, label="cut-off (slats tilted against the sun)")
    ax.plot(t, upper, color="#ff7f0e", lw=1.0, ls=":", label="cut-off (slats closed upward)")
    ax.step(*broken(ctx, ctx.history.applied()["phi_deg"]), where="post", color="black",
            lw=1.4, label="louver angle")
    # Where the occupants got the sun: a red rug under the angles.
    sun = c.occupied & (c.direct_sun_wm2 > c.direct_sun_limit_wm2)
    if sun.any():
        ts, flag = broken(ctx, np.where(sun, -86.0, np.nan))
        ax.plot(ts, flag, color="#d62728", lw=5, solid_capstyle="butt",
                label=f"occupied, direct sun > {c.direct_sun_limit_wm2:g} W/m²")
    ax.set_ylim(-95, 95)
    ax.set_yticks(range(-90, 91, 30))
    ax.set_ylabel("slat angle [deg]\n(+: outdoor tip up)")
    if not sunny.any():
        nothing(ax, "the sun did not shine on the façade in this log")
    ax.legend(**OUTSIDE)
    time_axis(ctx, ax, label=True)
