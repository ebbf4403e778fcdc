"""Figures of the AMOS 2023 chapters (notebooks 07 and 08): each function draws one figure from a study result and
returns the matplotlib figure (saved by the notebook through :func:`cislunar.publish.plotting.save_figure`).

Every function checks that it was given the result object it draws (a wrong object is refused with an error naming
the argument, before a figure is opened)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.patches import Rectangle
from matplotlib.ticker import NullFormatter, ScalarFormatter

from cislunar.cr3bp.dynamics import check_system
from cislunar.cr3bp.orbits import PeriodicOrbit
from cislunar.cr3bp.propagation import propagate
from cislunar.cr3bp.torus import InvariantTorus
from cislunar.guidance import ssat
from cislunar.papers.greaves_scheeres_2023 import guidance_study as gs
from cislunar.papers.greaves_scheeres_2023 import station_keeping as sk
from cislunar.papers.greaves_scheeres_2023 import station_keeping_study as sks
from cislunar.utils import validation

__all__ = ["cost_over_directions", "grid_resolution", "informed_within_slices", "map_with_percentiles",
           "monte_carlo_range_errors", "policies_vs_coast", "range_and_fuel_maps", "ssat_scenario", "surfaces",
           "torus_and_nrho"]


def _surface(value, name="S"):
    return validation.instance(value, name, sk.StationKeepingSurface, "a StationKeepingSurface")


# ---------------------------------------------------------------------------------------------------------------
# Notebook 07
# ---------------------------------------------------------------------------------------------------------------
def ssat_scenario(system, pair):
    """Three panels: the pair about apolune (Moon-centred, 1000 km), range and Eq. 20 noise, and sqrt(J_rho)."""
    check_system(system)
    validation.instance(pair, "pair", gs.DemonstrationPair, "a DemonstrationPair")
    L = system.length_unit_km
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    hours = pair.hours
    for s, lab, c, ls in ((pair.target.x[0], "target (9:2 NRHO)", "k", "-"),
                          (pair.agent.x[0], f"agent, same orbit {pair.lag_hours * 60:.0f} min behind", "tab:red",
                           "--")):
        m = system.moon_centred(s) * L / 1e3
        axes[0].plot(m[:, 1], m[:, 2], color=c, lw=1.5, ls=ls, label=lab)
    axes[0].set_xlabel("y, Moon-centred (1000 km)")
    axes[0].set_ylabel("z (1000 km)")
    axes[0].set_title("three days about apolune")
    axes[0].legend(loc="upper right", fontsize=8)
    base = pair.baseline
    axes[1].plot(hours, base.range_km[0], color="tab:blue")
    axes[1].set_xlabel("time since the burn epoch (h)")
    axes[1].set_ylabel("agent-target range (km)", color="tab:blue")
    ax2 = axes[1].twinx()
    ax2.plot(hours, base.sigma_theta_rad[0] * 1e6, color="tab:orange")
    ax2.set_ylabel(r"$\sigma_\theta$ (Eq. 20) [µrad]", color="tab:orange")
    ax2.grid(False)  # one grid (the range axis'); a second one would not line up
    axes[1].axvline(pair.lead_hours, color="0.6", ls=":", lw=1)
    axes[1].text(pair.lead_hours + 1, 0.5, "apolune", transform=axes[1].get_xaxis_transform(), va="center",
                 fontsize=8, color="0.4")
    axes[2].semilogy(hours, base.range_sigma_km[0], color="k")
    axes[2].yaxis.set_major_formatter(ScalarFormatter())
    axes[2].yaxis.set_minor_formatter(NullFormatter())
    axes[2].set_yticks([12, 15, 20, 25, 30, 35])
    axes[2].set_xlabel("time since the burn epoch (h)")
    axes[2].set_ylabel(r"$\sqrt{J_\rho}$, 1-sigma range (km)")
    axes[2].set_title("no maneuver")
    fig.tight_layout()
    return fig


def policies_vs_coast(study):
    """Every policy as the change of sqrt(J_rho(tau_f)) against no burn (percent), one panel per burn size."""
    validation.instance(study, "study", gs.PolicyStudy, "a PolicyStudy")
    fig, axes = plt.subplots(1, len(study.results), figsize=(12, 4.8), sharey=False)
    for ax, (dv, r) in zip(np.atleast_1d(axes), study.results.items()):
        h = r.coast_hours
        rel = lambda v, r=r: 100 * (v / r.none - 1)  # percent change of sqrt(J_rho) against no burn
        ax.fill_between(h, rel(r.perp_best), rel(r.perp_worst), color="tab:green", alpha=0.2, lw=0,
                        label="perpendicular to LOS (range over the circle)")
        ax.axhline(0, color="k", ls="--", lw=1.2, label="no burn")
        ax.plot(h, rel(r.grid_median), color="0.5", label="median random direction")
        ax.plot(h, rel(r.mmd), "o-", color="magenta", label="MMD (selected sign)")
        ax.plot(h, rel(r.mmd_other), "x:", color="magenta", label="MMD (rejected sign)")
        ax.plot(h, rel(r.optimum), "s-", color="tab:blue", ms=4, label="true minimiser")
        ax.set_xscale("log")
        ax.set_xticks(h, [f"{x:g}" for x in h])
        ax.minorticks_off()
        ax.set_xlabel("coast time $\\tau_f-\\tau_0$ (h)")
        ax.set_ylabel(r"$\sqrt{J_\rho(\tau_f)}$ relative to no burn [%]")
        ax.set_title(f"burn magnitude {dv} m/s")
    handles, labels = np.atleast_1d(axes)[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, bbox_to_anchor=(0.5, 0.0))
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    return fig


def _azel_deg(v):
    v = np.atleast_2d(v)
    return np.degrees(np.arctan2(v[:, 1], v[:, 0])), np.degrees(np.arcsin(np.clip(v[:, 2], -1, 1)))


def cost_over_directions(dmap):
    """sqrt(J_rho) over the sphere of burn directions (azimuth/elevation), MMD axis, minimiser, line of sight."""
    validation.instance(dmap, "dmap", gs.DirectionMap, "a DirectionMap")
    fig, ax = plt.subplots(figsize=(9, 4.5))
    az, el = _azel_deg(dmap.directions)
    sc = ax.scatter(az, el, c=dmap.range_sigma_km, s=8, cmap="viridis")
    fig.colorbar(sc, ax=ax, label=rf"$\sqrt{{J_\rho}}$ after {dmap.coast_hours:.0f} h (km)")
    paz, pel = _azel_deg(ssat.perpendicular_directions(dmap.line_of_sight, 361))
    order = np.argsort(paz)
    ax.plot(paz[order], pel[order], "-", color="k", lw=1.2, label="perpendicular to the LOS")
    for sgn, mk in ((1, "^"), (-1, "v")):
        a, e = _azel_deg(sgn * dmap.mmd_direction)
        ax.plot(a, e, mk, color="magenta", ms=11, mec="k", label="MMD axis" if sgn == 1 else None)
    for sgn, lab in ((1, "line of sight (towards the target)"), (-1, "away from the target")):
        a, e = _azel_deg(sgn * dmap.line_of_sight)  # drawn as rings, so that a minimiser next to them stays visible
        ax.plot(a, e, "o", mfc="none", mec="cyan" if sgn == 1 else "k", mew=2, ms=18, label=lab)
    a, e = _azel_deg(dmap.optimum_direction)
    ax.plot(a, e, "*", color="tab:red", ms=13, mec="k", label="true minimiser")
    ax.set_title(f"{dmap.coast_hours:.0f}-h coast, {dmap.dv_m_s} m/s: the true minimiser lies "
                 f"{dmap.los_angle_deg:.0f} deg from the line of sight")
    ax.set_xlabel("burn azimuth in the rotating frame (deg)")
    ax.set_ylabel("burn elevation (deg)")
    ax.set_xlim(-180, 180)
    ax.set_ylim(-90, 90)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=3, fontsize=8, markerscale=0.6,
              labelspacing=1.0)
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Notebook 08
# ---------------------------------------------------------------------------------------------------------------
def torus_and_nrho(system, orbit, torus):
    """Fig. 2: the torus surface about apoapsis (+-1.5 d, Moon-centred, 1000 km) with the NRHO arc, and the ring
    relative to the target at five times (km, equal axes)."""
    check_system(system)
    validation.instance(orbit, "orbit", PeriodicOrbit)
    validation.instance(torus, "torus", InvariantTorus)
    L, HR = system.length_unit_km, 3600.0 / system.time_unit_s
    th_plot = np.linspace(0, 2 * np.pi, 49)
    fig = plt.figure(figsize=(13, 6))
    t_plot = np.linspace(-36.0, 36.0, 61) * HR
    surf = system.moon_centred(torus.states(th_plot[:-1], t_plot)) * L / 1e3
    surf = np.concatenate([surf, surf[:1]], axis=0)
    fwd = system.moon_centred(propagate(system, orbit.x0, t_plot[t_plot >= 0]).x) * L / 1e3
    back = system.moon_centred(propagate(system, orbit.x0, -t_plot[t_plot >= 0]).x) * L / 1e3
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax.plot_surface(surf[..., 0], surf[..., 1], surf[..., 2], color="tab:red", alpha=0.3, lw=0, shade=True)
    ring0 = system.moon_centred(torus.ring(0.0, 97)) * L / 1e3
    ax.plot(ring0[:, 0], ring0[:, 1], ring0[:, 2], color="tab:red", lw=2, label="initial ring (apoapsis)")
    for arc in (fwd, back):
        ax.plot(arc[:, 0], arc[:, 1], arc[:, 2], color="k", lw=2)
    ax.plot([], [], color="k", label="target: 9:2 NRHO")
    ax.set_xlabel("x (1000 km)", labelpad=8)
    ax.set_ylabel("y (1000 km)", labelpad=8)
    ax.set_zlabel("z (1000 km)", labelpad=8)
    ax.set_title("$\\pm$1.5 days about apoapsis")
    ax.view_init(elev=18, azim=-60)
    ax.legend(loc="upper left")
    ax = fig.add_subplot(1, 2, 2, projection="3d")
    th_ring = np.linspace(0, 2 * np.pi, 97)
    for h, col in ((-24, "C0"), (-12, "C5"), (0, "tab:red"), (12, "C3"), (24, "C4")):
        tgt = propagate(system, orbit.x0, np.array([0.0, h * HR])).x[-1] if h else orbit.x0
        rel = (torus.states(th_ring, [h * HR])[:, 0, :3] - tgt[:3]) * L
        ax.plot(rel[:, 0], rel[:, 1], rel[:, 2], color=col, lw=2 if h == 0 else 1.4,
                label=f"{h:+d} h" + (" (apoapsis)" if h == 0 else ""))
    ax.plot([0], [0], [0], "k*", ms=10, label="target")
    ax.set_aspect("equal")
    ax.set_xlabel("x - x$_{target}$ (km)", labelpad=6)
    ax.set_ylabel("y - y$_{target}$ (km)", labelpad=6)
    ax.set_zlabel("z - z$_{target}$ (km)", labelpad=6)
    ax.set_title("the ring relative to the target")
    ax.view_init(elev=22, azim=-60)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return fig


def _informed_segments(surf):
    """Index runs of the u* line without jumps of more than a quarter turn in phase."""
    ph = surf.phase[surf.informed]
    cuts = np.flatnonzero(np.abs(np.diff(ph)) > 0.25) + 1
    return np.split(np.arange(ph.size), cuts)


#: How the two readings of Eq. 25 are drawn: (label, colour, line style, marker).  Magenta is the paper's colour;
#: the projection reading is drawn dashed in red with squares, so the two stay apart where they cross.
_READING_STYLES = {"angle": ("u*, Eq. 25 read as an angle (cosine)", "magenta", "-", "o"),
                   "projection": ("u*, Eq. 25 read as a projection", "tab:red", "--", "s")}


def _surface_plot(ax, S, Z, title, zlabel, log=False, flip=False, projection=None):
    """3-D surface over (normalised phase, time from apoapsis) with the informed line in magenta (and the
    projection reading's line when ``projection``, the same surface reselected, is given)."""
    P, H = np.meshgrid(S.phase, S.t_arrival_hours)
    Zp = np.log10(Z) if log else Z
    ax.plot_surface(P, H, Zp, cmap="viridis", lw=0, alpha=0.85, rcount=60, ccount=60)
    for reading, surf in (("angle", S), ("projection", projection)):
        if surf is None:
            continue
        label, col, ls, mk = _READING_STYLES[reading]
        zl = Zp[np.arange(surf.t_arrival.size), surf.informed]
        for n_seg, seg in enumerate(_informed_segments(surf)):  # break the line where u* jumps across phase 0 = 1
            ax.plot(surf.phase[surf.informed][seg], surf.t_arrival_hours[seg], zl[seg], color=col, ls=ls, lw=2.5,
                    marker=mk, ms=3.5, label=label if n_seg == 0 else None, zorder=5)
    ax.set_xlabel("normalised phase $\\theta_0/2\\pi$ [-]", labelpad=6)
    ax.set_ylabel("time from apoapsis (h)", labelpad=6)
    ax.set_zlabel(zlabel, labelpad=6)
    ax.set_title(title)
    if flip:
        ax.invert_yaxis()


def _projection_of(S, projection):
    """``projection`` checked: None, or ``S`` with u* chosen by the projection reading (same maneuvers)."""
    if projection is None:
        return None
    _surface(projection, "projection")
    if projection.range_sigma_km.shape != S.range_sigma_km.shape or not np.array_equal(projection.dv1, S.dv1):
        raise ValueError("projection must be the same surface with u* reselected (S.reselect('projection'))")
    return projection


def _legend_below(fig, ax, rect_bottom=0.1):
    """The axes' legend centred below the panels (off the data)."""
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="lower center", ncol=len(handles), fontsize=9, frameon=False)
        fig.tight_layout(rect=(0, rect_bottom, 1, 1))
    else:
        fig.tight_layout()


def surfaces(S, which="burns", projection=None):
    """Fig. 3 (``which="burns"``: first and second burn) or Figs. 4-5 (``"range_fuel"``: log10 sqrt(J_rho) in m,
    the no-maneuver wall clipped to the largest maneuver value, and total fuel) as 3-D surfaces with u*: the angle
    reading of Eq. 25 from ``S`` in magenta, the projection reading (``projection``, the same surface reselected)
    dashed in red; the legend sits below the panels."""
    _surface(S)
    validation.choice(which, "which", ("burns", "range_fuel"))
    projection = _projection_of(S, projection)
    fig = plt.figure(figsize=(13, 6))
    ax1 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2, projection="3d")
    if which == "burns":
        _surface_plot(ax1, S, S.dv1_m_s, "Fig. 3: first burn", r"$\|\Delta v_1\|$ (m/s)", projection=projection)
        _surface_plot(ax2, S, S.dv2_m_s, "Fig. 3: second burn", r"$\|\Delta v_2\|$ (m/s)", projection=projection)
    else:
        still = S.fuel_m_s < 1e-9  # the agent's own torus point (phase 0): no maneuver
        log_sig = np.log10(S.range_sigma_km * 1e3)
        z_top = log_sig[~still].max()  # z range from the maneuvers; the no-maneuver column is clipped to it
        _surface_plot(ax1, S, np.minimum(log_sig, z_top),
                      "Fig. 4: range uncertainty at $t_f$ (phase-0 wall clipped)", r"$\log_{10}\sqrt{J_\rho}$ (m)",
                      projection=projection)
        ax1.set_zlim(log_sig[~still].min(), z_top)
        _surface_plot(ax2, S, S.fuel_m_s, "Fig. 5: total fuel (time axis flipped)",
                      r"$\|\Delta v_1\|+\|\Delta v_2\|$ (m/s)", flip=True, projection=projection)
    _legend_below(fig, ax1, 0.08)
    return fig


def _informed_markers(ax, surf, projection=None, reading="angle"):
    """u* (magenta open circles, or red crosses if ``surf`` itself is the projection reading's surface; the
    projection reading as red crosses when given) and the best maneuver of each slice (orange open squares) on a
    map."""
    if reading == "projection":  # the colour and marker of the projection reading on every figure
        ax.plot(surf.phase[surf.informed], surf.t_arrival_hours, "x", color="tab:red", ms=6, mew=1.5,
                label="u*, projection reading")
    for n_seg, seg in enumerate(_informed_segments(surf) if reading == "angle" else ()):
        ax.plot(surf.phase[surf.informed][seg], surf.t_arrival_hours[seg], "o", color="magenta", mfc="none", ms=5,
                mew=1.2, label=("u* (informed)" if projection is None else "u*, angle reading") if n_seg == 0
                else None)
    if projection is not None:
        ax.plot(projection.phase[projection.informed], projection.t_arrival_hours, "x", color="tab:red", ms=6,
                mew=1.5, label="u*, projection reading")
    ax.plot(surf.phase[surf.best], surf.t_arrival_hours, "s", color="tab:orange", mfc="none", mew=1.2, ms=5,
            label="best of each slice")


def _range_map(ax, surf, fig, projection=None, reading="angle"):
    """Map of sqrt(J_rho): colours from the maneuvers only, no-maneuver cells hatched, u* and the slice best."""
    none = surf.fuel_m_s < 1e-9
    sig_m = surf.range_sigma_km * 1e3
    norm = LogNorm(vmin=sig_m[~none].min(), vmax=sig_m[~none].max())
    im = ax.pcolormesh(surf.phase, surf.t_arrival_hours, np.ma.masked_where(none, sig_m), shading="nearest",
                       cmap="viridis", norm=norm)
    cb = fig.colorbar(im, ax=ax, label=r"$\sqrt{J_\rho}$ at $t_f$ (m)")
    cb.set_ticks([t for t in (10, 20, 50, 100, 200, 500, 1000) if norm.vmin <= t <= norm.vmax])
    cb.ax.yaxis.set_major_formatter(ScalarFormatter())
    cb.ax.yaxis.set_minor_formatter(NullFormatter())
    dp, dt = surf.phase[1] - surf.phase[0], surf.t_arrival_hours[1] - surf.t_arrival_hours[0]
    for i in np.flatnonzero(none.all(axis=0)):  # columns without a maneuver in any slice
        ax.add_patch(Rectangle((surf.phase[i] - dp / 2, surf.t_arrival_hours[0] - dt / 2), dp,
                               np.ptp(surf.t_arrival_hours) + dt, facecolor="0.85", edgecolor="0.3", hatch="////",
                               lw=0.5, label=f"no maneuver: {sig_m[none].min() / 1e3:.1f} km"))
    _informed_markers(ax, surf, projection, reading)
    ax.set_xlabel(r"normalised phase $\theta_0/2\pi$ [-]")
    ax.set_ylabel("time from apoapsis (h)")


def range_and_fuel_maps(S, projection=None):
    """Figs. 4 and 5 as maps (range uncertainty of the maneuvers, total fuel) with u* (both readings when
    ``projection``, the same surface reselected, is given) and the slice best."""
    _surface(S)
    projection = _projection_of(S, projection)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    _range_map(axes[0], S, fig, projection)
    axes[0].set_title("Fig. 4 as a map: range uncertainty (maneuvers only)")
    im = axes[1].pcolormesh(S.phase, S.t_arrival_hours, S.fuel_m_s, shading="nearest", cmap="viridis")
    fig.colorbar(im, ax=axes[1], label="total fuel (m/s)")
    _informed_markers(axes[1], S, projection)
    axes[1].set_title("Fig. 5 as a map: total fuel")
    axes[1].set_xlabel(r"normalised phase $\theta_0/2\pi$ [-]")
    axes[1].set_ylabel("time from apoapsis (h)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(handles), fontsize=8)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return fig


def _slice_profiles(ax, surf, n_show=3):
    """sqrt(J_rho) over phase (maneuvers only) for n_show arrival slices, u* and the slice best marked."""
    moving = surf.fuel_m_s > 1e-9
    for n, j in enumerate(np.linspace(0, surf.t_arrival.size - 1, n_show).round().astype(int)):
        col = f"C{n}"
        m = moving[j]
        ax.plot(surf.phase[m], surf.range_sigma_km[j, m] * 1e3, ".-", color=col, ms=3, lw=1,
                label=f"arrival {surf.t_arrival_hours[j]:+.1f} h")
        ax.plot(surf.phase[surf.informed[j]], surf.informed_range_sigma_km[j] * 1e3, "o", ms=10, mfc="none",
                mec="magenta", mew=2)
        ax.plot(surf.phase[surf.best[j]], surf.best_range_sigma_km[j] * 1e3, "s", ms=8, mfc="none", mec="k",
                mew=1.5)
    ax.plot([], [], "o", ms=10, mfc="none", mec="magenta", mew=2, label="u* (informed)")
    ax.plot([], [], "s", ms=8, mfc="none", mec="k", mew=1.5, label="best of the slice")
    ax.set_yscale("log")
    lo, hi = ax.get_ylim()
    ax.set_yticks([t for t in (5, 10, 20, 50, 100, 200, 500, 1000) if lo <= t <= hi])
    ax.yaxis.set_major_formatter(ScalarFormatter())
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel(r"normalised phase $\theta_0/2\pi$ [-]")
    ax.set_ylabel(r"$\sqrt{J_\rho}$ at $t_f$ (m)")


def _percentile_panel(ax, surfaces_):
    """Percentile of u* within its slice against the arrival time, one line per (label, surface, style)."""
    for label, surf, style in surfaces_:
        ax.plot(surf.t_arrival_hours, surf.informed_percentile, style, ms=4, label=label)
    ax.axhspan(0, 25, color="tab:green", alpha=0.15, lw=0)
    ax.text(0.02, 12.5, "valley: best quartile", transform=ax.get_yaxis_transform(), va="center", fontsize=8)
    ax.axhline(50, color="0.4", ls="--", lw=1)
    ax.text(0.02, 52, "random pick (average)", transform=ax.get_yaxis_transform(), va="bottom", fontsize=8)
    ax.set_ylim(0, 100)
    ax.set_xlabel("time from apoapsis of the arrival (h)")
    ax.set_ylabel("percentile of u* in its slice [%]")


def informed_within_slices(S):
    """sqrt(J_rho) over phase for three arrival slices, and the percentile of u* in every slice."""
    _surface(S)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4))
    _slice_profiles(axes[0], S)
    axes[0].set_title("three arrival slices (maneuvers only)")
    axes[0].legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3, fontsize=8)
    _percentile_panel(axes[1], [("tracking from the first burn (baseline)", S, "o-")])
    axes[1].set_title("where u* ranks (0 % = best of its slice)")
    axes[1].legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), fontsize=8)
    fig.tight_layout()
    return fig


def map_with_percentiles(S_map, map_title, panels, panel_title, *, reading: str = "angle"):
    """A range map of ``S_map`` next to the percentile of u* for each ``(label, surface, style)`` of ``panels``;
    ``reading`` ("angle" or "projection"): which reading of Eq. 25 chose ``S_map``'s u* (its markers on the map:
    magenta circles or red crosses, as on every other figure)."""
    _surface(S_map, "S_map")
    validation.choice(reading, "reading", ("angle", "projection"))
    validation.instance(map_title, "map_title", str, "a str")
    validation.instance(panel_title, "panel_title", str, "a str")
    if isinstance(panels, (str, bytes, dict)) or not hasattr(panels, "__iter__"):
        raise validation.ArgumentTypeError(f"panels must be a sequence of (label, surface, style) tuples; got "
                                           f"{type(panels).__name__}")
    panels = list(panels)
    if not panels:
        raise ValueError("panels must hold at least one (label, surface, style) tuple")
    for n, panel in enumerate(panels):
        if not isinstance(panel, (tuple, list)) or len(panel) != 3:
            raise validation.ArgumentTypeError(f"panels[{n}] must be a (label, surface, style) tuple; got "
                                               f"{type(panel).__name__} {panel!r:.60}")
        validation.instance(panel[0], f"panels[{n}] label", str, "a str")
        _surface(panel[1], f"panels[{n}] surface")
        validation.instance(panel[2], f"panels[{n}] style", str, "a str")
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
    _range_map(axes[0], S_map, fig, reading=reading)
    axes[0].set_title(map_title)
    axes[0].legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=8)
    _percentile_panel(axes[1], panels)
    axes[1].set_title(panel_title)
    axes[1].legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), fontsize=8)
    fig.tight_layout()
    return fig


def grid_resolution(grid, no_maneuver_m):
    """Median percentile and sqrt(J_rho) of u* against the ring-angle count, both readings, both agent phases."""
    validation.instance(grid, "grid", sks.GridStudy, "a GridStudy")
    no_maneuver_m = validation.positive(no_maneuver_m, "no_maneuver_m")
    n_grid = grid.n_grid
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4))
    for agent, col in ((0.0, "C0"), (0.75, "C1")):
        for crit, mk, ls in (("angle", "o", "-"), ("projection", "s", "--")):
            lab = f"agent phase {agent:.2f}, {crit} reading"
            axes[0].plot(n_grid, grid.series(agent, crit, "percentile"), ls, marker=mk, color=col, label=lab)
            axes[1].plot(n_grid, grid.series(agent, crit, "sigma_m"), ls, marker=mk, color=col, label=lab)
    axes[1].axhline(no_maneuver_m, color="k", ls=":", lw=1.2)
    axes[1].text(n_grid[0], no_maneuver_m / 1.4, "no maneuver (agent phase 0)", fontsize=8, va="top")
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xticks(n_grid, [str(n) for n in n_grid])
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("ring angles in the set [-]")
    axes[0].axhspan(0, 25, color="tab:green", alpha=0.15, lw=0)
    axes[0].set_ylim(0, 100)
    axes[0].set_ylabel("median percentile of u* in its slice [%]")
    axes[0].set_title("where u* ranks (0 % = best of its slice)")
    axes[1].set_yscale("log")
    axes[1].set_ylabel(r"median $\sqrt{J_\rho}$ of u* at $t_f$ (m)")
    axes[1].yaxis.set_major_formatter(ScalarFormatter())
    axes[1].set_title("range uncertainty of u*")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8)
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    return fig


def monte_carlo_range_errors(mcs):
    """RMS range error at t_f per policy and execution level, the filter's 1-sigma and the covariance analysis."""
    validation.instance(mcs, "mcs", sks.MonteCarloStudy, "a MonteCarloStudy")
    summary = mcs.summary
    fig, ax = plt.subplots(figsize=(8.5, 4.6))
    labels = list(dict.fromkeys(p for p, _ in summary))
    xpos = np.arange(len(labels))
    for off, tag, col, mk in ((-0.2, "perfect", "tab:blue", "o"), (0.0, "small", "tab:green", "D"),
                              (0.2, "exec", "tab:orange", "^")):
        a, r = mcs.levels[tag]
        for n, p in enumerate(labels):
            if (p, tag) not in summary:  # no maneuver: nothing to execute
                ax.text(xpos[n] + off, summary[(p, "perfect")]["ca"] / 1.5, "no burn", rotation=90, ha="center",
                        va="top", fontsize=8, color=col)
                continue
            ax.plot(xpos[n] + off, summary[(p, tag)]["rms"], mk, color=col, ms=8,
                    label=("perfect burns" if tag == "perfect" else
                           f"execution errors {a * 1e3:g} mm/s + {r * 100:g} %") if n == 0 else None)
            ax.plot(xpos[n] + off, summary[(p, tag)]["fsig"], "_", color="k", ms=16, mew=1.5, zorder=4,
                    label="filter 1-sigma" if (n, tag) == (0, "perfect") else None)
    for n, p in enumerate(labels):  # the covariance analysis (perfect burns) the filter is compared with
        ax.hlines(summary[(p, "perfect")]["ca"], xpos[n] - 0.32, xpos[n] + 0.32, color="k", ls=":", lw=1.5,
                  label="covariance analysis (perfect burns)" if n == 0 else None)
    ax.set_yscale("log")
    ax.set_xticks(xpos, labels, fontsize=8)
    ax.set_xlim(-0.5, len(labels) - 0.5)
    ax.set_xlabel("choice of the burns [-]")
    ax.set_ylabel("RMS range error at $t_f$ [m]")
    ax.set_title(f"iterated EKF, {mcs.n_trials} runs each")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=3, fontsize=8)
    fig.tight_layout()
    return fig
