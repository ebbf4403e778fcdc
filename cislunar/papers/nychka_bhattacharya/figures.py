"""Figures of notebooks 11 and 12 (Nychka & Bhattacharya): each function draws one figure from a study result and
returns it; the notebook saves it with :func:`cislunar.publish.plotting.save_figure`.

Each function checks that its result arguments are the package's result objects and its numbers are valid before
drawing anything.

Axes: positions in LU (rotating frame), gamma in km where labelled, times in TU or minutes, angles in deg.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import matplotlib.ticker as mticker
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from cislunar.cr3bp.dynamics import check_system
from cislunar.estimation import lpv
from cislunar.papers.nychka_bhattacharya import observer_simulation as obs
from cislunar.papers.nychka_bhattacharya import robust as rb
from cislunar.papers.nychka_bhattacharya import sensing_precision as sp
from cislunar.papers.nychka_bhattacharya.scenarios import Fig1Scene, Scenario
from cislunar.publish import plotting
from cislunar.utils import validation

__all__ = ["fig1_analogue", "fig3_window", "resonant_orbit", "bandwidth", "precision_per_sensor", "trade_curve", "sensitivity", "fig3_observers"]


def resonant_orbit(scenario):
    """The orbit whose scheduling parameters bound the polytope, with the primaries (a :class:`Scenario`)."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    lo, hi = scenario.r13_range
    fig, ax = plt.subplots(figsize=(5.5, 5))
    plotting.plot_rotating(ax, scenario.model.spatial(scenario.states), label="2:1 resonant orbit")
    plotting.plot_primaries(ax, scenario.model.system)
    ax.legend(loc="upper right")
    ax.set_title(f"scheduling box from this orbit: r13 in [{lo:.3f}, {hi:.3f}] LU")
    return fig


def bandwidth(bw):
    """H-infinity precision and gain against the bandwidth bound R (a :class:`BandwidthStudy`)."""
    bw = validation.instance(bw, "bw", sp.BandwidthStudy)
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.6))
    ax[0].semilogx(bw.radii, bw.noise_deg, "o-", label="bandwidth-bounded optimum")
    ax[0].axhline(bw.limit_deg, color="k", ls="--", lw=0.8,
                  label=rf"limit $\sin^{{-1}}(\gamma/\max r_{{13}})$ = {bw.limit_deg:.4f}°")
    ax[0].set_xlabel("bandwidth bound R [1/TU]")
    ax[0].set_ylabel(r"allowable $\theta_1$ noise [deg]")
    ax[0].legend(loc="lower right")
    ax[1].loglog(bw.radii, bw.gain_norm, "s-", color="C1")
    ax[1].set_xlabel("bandwidth bound R [1/TU]")
    ax[1].set_ylabel(r"gain norm $\|L\|_2$ [non-dim.]")
    fig.suptitle(r"H$_\infty$ (Theorem 2) at $\gamma$ = 0.0013 LU: precision and gain against the bandwidth bound")
    for a in ax:
        a.xaxis.set_minor_formatter(mticker.NullFormatter())
    return fig


def precision_per_sensor(designs):
    """Fig. 2 analogue: the optimal precision of each of the six sensors (a :class:`Designs`)."""
    designs = validation.instance(designs, "designs", sp.Designs)
    fig, ax = plt.subplots(figsize=(7.5, 3.8))
    w = 0.38
    xs = np.arange(6)
    for i, (norm, label) in enumerate((("h2", "H2 (Thm 1)"),
                                       ("hinf", rf"H$_\infty$ (Thm 2, R = {designs.pole_radius:.0f}/TU)"))):
        d = designs.all[norm]
        pos = xs + (i - 0.5) * w
        ax.bar(pos[d.used], d.kappa[d.used], w, label=label, color=f"C{i}")
        for x in pos[~d.used]:
            ax.text(x, 1.5, "unused", rotation=90, ha="center", va="bottom", fontsize=8, color=f"C{i}")
    ax.set_yscale("log")
    ax.set_ylim(1, 2e4)
    ax.set_xticks(xs, lpv.SENSOR_NAMES)
    ax.set_xlabel("sensor [-]")
    ax.set_ylabel(r"precision $\kappa_i = \sqrt{\beta_i}$" "\n" r"[H$_\infty$: per unit output; H2: TU$^{-1/2}$]")
    ax.set_title(rf"Fig. 2 analogue: optimal sensing precision, $\gamma$ = {designs.gamma} LU, $\|\beta\|_1$")
    ax.legend(loc="upper right")
    return fig


def trade_curve(tc, gamma, length_unit_km):
    """Required precision and Eq. 24 allowance against gamma (a :class:`TradeCurve`); ``gamma`` (LU) is marked,
    ``length_unit_km`` converts LU to km."""
    tc = validation.instance(tc, "tc", sp.TradeCurve)
    validation.positive(gamma, "gamma")
    validation.positive(length_unit_km, "length_unit_km")
    fig, ax = plt.subplots(1, 2, figsize=(8.5, 3.8), layout="constrained")
    for norm, label in (("h2", "H2"), ("hinf", r"H$_\infty$")):
        ax[0].loglog(tc.gammas * length_unit_km, tc.kappa[norm], "o-", label=label)
        ax[1].loglog(tc.gammas * length_unit_km, tc.noise_deg[norm], "o-", label=label)
    for a in ax:
        a.axvline(gamma * length_unit_km, color="k", lw=0.8, ls=":",
                  label=rf"paper's $\gamma$ = {gamma} LU ({gamma * length_unit_km:.0f} km)")
        a.set_xlabel(r"$\gamma$ [km]")
    fig.legend(*ax[0].get_legend_handles_labels(), loc="outside lower center", ncol=3)
    ax[0].set_ylabel(r"required precision $\kappa_{\sin\theta_1}$" "\n"
                     r"[H$_\infty$: per unit output; H2: TU$^{-1/2}$]")
    ax[1].set_ylabel(r"Eq. 24 allowance $\sin^{-1}(1/\kappa)$" "\n"
                     r"[H$_\infty$: deg RMS; H2: intensity, deg$\sqrt{\rm TU}$]")
    fig.suptitle("trade curve: precision needed for a position-error bound")
    return fig


def sensitivity(study, reading, gamma, pole_radius):
    """The sensitivity study in three rows sharing the orbit axis, sorted by max r13 (see notebook 11): a
    :class:`SensitivityStudy`, its :class:`SensitivityReading`, the bound ``gamma`` (LU) and the H-infinity
    bandwidth bound ``pole_radius`` (1/TU) the study used."""
    study = validation.instance(study, "study", sp.SensitivityStudy)
    reading = validation.instance(reading, "reading", sp.SensitivityReading)
    validation.positive(gamma, "gamma")
    validation.positive(pole_radius, "pole_radius")
    TU_MIN = reading.minutes_per_tu
    hinf, h2i, j = study.hinf_deg, study.h2_intensity_deg, reading.level_index
    dt01, dteq = reading.dt_01, reading.dt_eq
    order = np.argsort(study.r13_max)
    xo = np.arange(order.size)
    n_s, n_l = len(study.structures), study.levels.size
    fig, ax = plt.subplots(3, 1, figsize=(7.5, 9.0), sharex=True, layout="constrained")
    for a in ax:
        for x in xo[reading.hinf_in_band[order, 0, j]]:
            a.axvspan(x - 0.45, x + 0.45, color="C7", alpha=0.15, lw=0, zorder=0)
    # (a) H-infinity: optimum against its unbounded-gain limit
    ax[0].axhspan(0.075, 0.085, color="C2", alpha=0.2, lw=0)
    ax[0].plot(xo, hinf[order, 0, j], "o", color="C1", ms=6, zorder=3)
    ax[0].plot(xo, np.degrees(np.arcsin(gamma / study.r13_max[order])), "_", color="k", ms=16, mew=1.2, zorder=4)
    ax[0].set_ylabel(r"H$_\infty$ allowable noise [deg]")
    ax[0].set_title(r"(a) H$_\infty$ (energy bound, an angle RMS directly)", fontsize=10, loc="left")
    ax[0].legend(handles=[
        Line2D([], [], color="C1", marker="o", ls="", label=rf"optimum, R = {pole_radius:.0f}/TU"),
        Line2D([], [], color="k", marker="_", ms=12, mew=1.2, ls="", label=r"limit $\sin^{-1}(\gamma/\max r_{13})$"),
        Patch(color="C2", alpha=0.2, label="paper's 0.08 deg (printed digits)"),
        Patch(color="C7", alpha=0.15, label=r"orbit with H$_\infty$ in the paper's band")],
        loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
    # (b) H2 read directly: every structure and level, side by side within an orbit's slot
    slot = 0.8 / (n_s * n_l)
    colours = plt.cm.viridis(np.linspace(0.0, 0.8, n_l))
    for s_i in range(n_s):
        for l_i in range(n_l):
            dx = (s_i * n_l + l_i + 0.5) * slot - 0.4
            ax[1].plot(xo + dx, h2i[order, s_i, l_i], ["o", "s"][s_i % 2], color=colours[l_i], ms=4.5,
                       mfc=colours[l_i] if s_i == 0 else "none", mew=1.2, ls="", zorder=3)
    ax[1].axhspan(0.05, 0.15, color="C2", alpha=0.2, lw=0)
    ax[1].set_yscale("log")
    ax[1].set_ylabel("H2 allowance read\nas an angle [deg]")
    ax[1].set_title("(b) H2 read directly (a white-noise intensity, not an angle)", fontsize=10, loc="left")
    key = [Line2D([], [], color="0.3", marker="o", ls="", label="accelerations"),
           Line2D([], [], color="0.3", marker="s", mfc="none", mew=1.2, ls="", label="all four states")]
    key += [Patch(color=colours[l_i], label=f"level {lvl:g}") for l_i, lvl in enumerate(study.levels)]
    key += [Patch(color="C2", alpha=0.2, label="paper's 0.1 deg (printed digits)")]
    ax[1].legend(handles=key, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8, title="disturbance on",
                 title_fontsize=8)
    # (c) H2 per sample: the sampling intervals that give the paper's number
    k0 = (order, 0, j)
    ax[2].vlines(xo, study.dt_for_h2(0.15)[k0] * TU_MIN, study.dt_for_h2(0.05)[k0] * TU_MIN,
                 color="C0", lw=5, alpha=0.35, zorder=2)
    ax[2].plot(xo, dt01[k0] * TU_MIN, "o", color="C0", ms=6, zorder=3)
    ax[2].plot(xo, dteq[k0] * TU_MIN, "_", color="C1", ms=18, mew=2.0, zorder=2.5)
    ax[2].set_yscale("log")
    ax[2].set_ylabel(r"sampling interval $\Delta t$ [min]")
    ax[2].set_title(f"(c) H2 per sample (accelerations, level {study.levels[j]:g})", fontsize=10, loc="left")
    ax[2].legend(handles=[Line2D([], [], color="C0", lw=5, alpha=0.35, label="per-sample noise 0.05-0.15 deg"),
                          Line2D([], [], color="C0", marker="o", ls="", label="per-sample noise 0.1 deg"),
                          Line2D([], [], color="C1", marker="_", ms=14, mew=2.0, ls="",
                                 label=r"H2 > H$_\infty$ for $\Delta t$ below")],
                 loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
    ax[2].set_xticks(xo, [f"{study.orbits[i][0]}:{study.orbits[i][1]}\nrp {study.orbits[i][2]:.2f}\n"
                          f"{study.r13_max[i]:.2f}" for i in order], fontsize=8)
    ax[2].set_xlim(-0.5, order.size - 0.5)
    ax[2].set_xlabel(r"resonant orbit p:q, perigee $r_p$ of the Keplerian guess [LU], $\max r_{13}$ [LU]; "
                     r"sorted by $\max r_{13}$")
    fig.suptitle(r"Allowable $\theta_1$ noise at $\gamma$ = 0.0013 LU over the inputs the paper leaves unstated",
                 fontsize=11)
    for a in ax[1:]:  # plain numbers at 1-2-5 steps: readable whether the data span one decade or several
        a.yaxis.set_major_locator(mticker.LogLocator(subs=(1.0, 2.0, 5.0)))
        a.yaxis.set_major_formatter(mticker.FuncFormatter(lambda v, _: f"{v:g}"))
        a.yaxis.set_minor_formatter(mticker.NullFormatter())
    return fig


def fig3_observers(sim, conv, crossings, system, gamma, sigma_deg):
    """Fig. 3 analogue: (a), (b) truth and estimate of each LPV observer with a magnified start; (c)-(e) position
    error of H2, H-infinity and the EKF against the guarantees and the paper's accuracy level of each observer
    (``conv.level``; see notebook 12).

    ``sim``, ``conv`` and ``crossings`` are the :class:`Fig3Runs`, :class:`Convergence` and :class:`LineCrossings`
    of one run; ``system`` converts LU to km; ``gamma`` (LU) and ``sigma_deg`` (deg) are labelled.
    """
    sim = validation.instance(sim, "sim", obs.Fig3Runs)
    conv = validation.instance(conv, "conv", obs.Convergence)
    crossings = validation.instance(crossings, "crossings", obs.LineCrossings)
    system = check_system(system, "system")
    validation.positive(gamma, "gamma")
    validation.positive(sigma_deg, "sigma_deg", allow_zero=True)
    KM, t, truth, runs, span = system.length_unit_km, sim.t, sim.truth, sim.runs, sim.period
    fig = plt.figure(figsize=(8.5, 9.4), layout="constrained")
    top, bottom = fig.subfigures(2, 1, height_ratios=[1.62, 1.0])
    ax_orb = top.subplots(1, 2)
    n_tr = int(np.searchsorted(t, 0.3))
    n_in = int(np.searchsorted(t, 0.1))
    xlim = (-0.45, 1.08)  # the Moon (x = 0.99) in view; the empty right half holds the legend and the inset
    ymax = 1.08 * max(np.abs(truth[:, 1]).max(), *(np.abs(runs[n].x_hat[:, 1]).max() for n in ("h2", "hinf")))
    for a, n, title in ((ax_orb[0], "h2", "(a) H2 observer"), (ax_orb[1], "hinf", r"(b) H$_\infty$ observer")):
        xh = runs[n].x_hat
        a.plot(truth[:, 0], truth[:, 1], color="0.7", lw=3.0, label="truth", zorder=1)
        a.plot(xh[:, 0], xh[:, 1], color="C0", lw=0.7, label="estimate", zorder=2)
        a.plot(xh[:n_tr, 0], xh[:n_tr, 1], color="C3", lw=1.4, label="estimate, first 0.3 TU", zorder=3)
        a.plot(*xh[0, :2], "o", color="C3", ms=5, label="initial estimate", zorder=4)
        plotting.plot_primaries(a, system)
        a.set_xlabel("x [LU]")
        a.set_ylabel("y [LU]")
        a.set_aspect("equal")
        a.set_xlim(*xlim)
        a.set_ylim(-ymax, ymax)
        a.set_title(title, fontsize=10)
        a.legend(loc="upper right", fontsize=8)
        box = (0.52, 0.08, 0.45, 0.37)  # inset position, fraction of the axes
        ins = a.inset_axes(box)
        seg = np.vstack([truth[:n_in, :2], xh[:n_in, :2]])
        mid, half = seg.mean(axis=0), 0.6 * np.ptp(seg, axis=0)
        shape = box[3] * 2 * ymax / (box[2] * np.ptp(xlim))  # height / width of the inset in the parent's data units
        half = np.array([max(half[0], half[1] / shape), max(half[1], half[0] * shape)])  # same scale on x and y
        ins.plot(truth[:n_in, 0], truth[:n_in, 1], color="0.6", lw=2.5)
        ins.plot(xh[:n_in, 0], xh[:n_in, 1], color="C3", lw=1.0)
        ins.plot(*xh[0, :2], "o", color="C3", ms=4)
        ins.set_xlim(mid[0] - half[0], mid[0] + half[0])
        ins.set_ylim(mid[1] - half[1], mid[1] + half[1])
        ins.tick_params(labelsize=6.5)
        ins.xaxis.set_major_locator(plt.MaxNLocator(3))
        ins.yaxis.set_major_locator(plt.MaxNLocator(4))
        ins.set_title("first 0.1 TU, magnified", fontsize=7.5)
        a.indicate_inset_zoom(ins, edgecolor="0.3")
    top.suptitle(f"Truth and estimate, {sigma_deg} deg angle noise", fontsize=11)
    ax_err = bottom.subplots(1, 3, sharey=True)
    for a, (n, title, c) in zip(ax_err, (("h2", "(c) H2", "C0"), ("hinf", r"(d) H$_\infty$", "C1"),
                                         ("ekf", "(e) EKF (beyond paper)", "C2"))):
        a.axvspan(0.0, 0.05 * span, color="0.85", lw=0, zorder=0)
        a.semilogy(t, runs[n].position_error * KM, lw=0.4, color=c, alpha=0.4, zorder=1)
        a.semilogy(t, crossings.running_rms[n] * KM, lw=1.6, color=c, zorder=3)
        if n in conv.bound:
            a.axhline(conv.bound[n] * KM, color="k", ls="--", lw=1.0, zorder=4)
            if np.isfinite(conv.first[n]):
                a.plot(conv.first[n], conv.bound[n] * KM, "v", color="k", ms=6, zorder=5)
        a.axhline(conv.level.get(n, gamma) * KM, color="k", ls=":", lw=0.8, zorder=2)
        a.set_xlabel("t [TU]")
        a.set_title(title, fontsize=10)
    ax_err[0].set_ylabel("position error [km]")
    ax_err[0].set_ylim(5.0, 5e4)
    key = [Line2D([], [], color="0.4", lw=0.6, alpha=0.6, label="error at each sample"),
           Line2D([], [], color="0.4", lw=1.6, label="running RMS over 0.1 TU"),
           Line2D([], [], color="k", ls="--", lw=1.0, label=r"guaranteed RMS (LMI, exact $\rho$)"),
           Line2D([], [], color="k", ls="", marker="v", label="first below the guarantee"),
           Line2D([], [], color="k", ls=":", lw=0.8,
                  label=r"paper's accuracy level: $\gamma$ = 0.0013 LU (H$_\infty$: $\gamma \cdot 0.1/0.08$; EKF: $\gamma$)"),
           Patch(color="0.85", label="first 5 % of the period")]
    bottom.legend(handles=key, loc="outside lower center", ncol=3, fontsize=8)
    bottom.suptitle("Position error (colour: observer)", fontsize=11)
    return fig


def fig1_analogue(scene, system):
    """Fig. 1 analogue (a :class:`Fig1Scene`): platform orbit and platforms (black), the RSO and its orbit (magenta),
    the lines of sight to the RSO, and one platform's celestial-navigation angles theta1 (at the Earth) and theta2
    (at the Moon); axes in km, legend beside the plot."""
    scene = validation.instance(scene, "scene", Fig1Scene)
    system = check_system(system, "system")
    KM, mu = system.length_unit_km, system.mu
    earth, moon = np.array([-mu, 0.0]) * KM, np.array([1.0 - mu, 0.0]) * KM
    fig, ax = plt.subplots(figsize=(8.5, 5.6), layout="constrained")
    ax.plot(*(scene.orbit[:, :2] * KM).T, color="0.25", lw=1.0, label=scene.labels[0])
    ax.plot(*(scene.rso_orbit[:, :2] * KM).T, color="m", lw=1.0, ls="--", label=scene.labels[1])
    P, R = scene.platforms[:, :2] * KM, scene.rso[:2] * KM
    for i, p in enumerate(P):
        ax.plot([p[0], R[0]], [p[1], R[1]], color="m", lw=0.6, alpha=0.6, label="line of sight to the RSO" if i == 0
                else None, zorder=2)
    ax.plot(*P.T, "o", color="k", ms=6, label=f"{len(P)} platforms", zorder=4)
    ax.plot(*R, "o", color="m", ms=8, label="RSO", zorder=5)
    p0 = P[1 % len(P)]
    for c, name in ((earth, "Earth"), (moon, "Moon")):
        ax.plot([c[0], p0[0]], [c[1], p0[1]], color="C0", lw=0.9, ls=":", zorder=1,
                label=r"navigation lines (angles $\theta_1$ at the Earth, $\theta_2$ at the Moon)" if name == "Earth"
                else None)
    ax.plot([earth[0], moon[0]], [0, 0], color="C0", lw=0.9, ls=":", zorder=1)
    for c, lab, off in ((earth, r"$\theta_1$", (0.06, 0.03)), (moon, r"$\theta_2$", (-0.12, 0.03))):
        ax.annotate(lab, c + np.array(off) * KM, color="C0", fontsize=10)
    ax.plot(*earth, "o", color="C0", ms=9, label="Earth")
    ax.plot(*moon, "o", color="0.55", ms=5, label="Moon")
    ax.set_aspect("equal")
    ax.set_xlabel("x, rotating frame [km]")
    ax.set_ylabel("y, rotating frame [km]")
    ax.xaxis.set_major_formatter(mticker.FuncFormatter(lambda v, _: f"{v / 1e3:.0f}k" if v else "0"))
    ax.yaxis.set_major_formatter(mticker.FuncFormatter(lambda v, _: f"{v / 1e3:.0f}k" if v else "0"))
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    ax.set_title("Fig. 1 analogue: resonant-orbit platforms tracking an RSO", fontsize=11)
    return fig


def fig3_window(ws, system):
    """Fig. 3 at the sampling interval of a :class:`WindowStudy`: position error of the nominal observers
    (triangulated and exact rho) and of the robust ones, with the nominal and robust guarantees drawn; rows: the
    large and the small initial error; columns: H2, H-infinity."""
    ws = validation.instance(ws, "ws", rb.WindowStudy)
    KM = check_system(system, "system").length_unit_km
    fig, ax = plt.subplots(2, 2, figsize=(9.0, 6.6), sharex=True, sharey=True, layout="constrained")
    style = {"nominal": ("C0", "-", r"nominal LMI, triangulated $\rho$"),
             "nominal, exact rho": ("0.55", "-", r"nominal LMI, true $\rho$"),
             "robust": ("C3", "-", r"robust LMI, triangulated $\rho$")}
    for i, start in enumerate(("large", "small")):
        for j, (n, title) in enumerate((("h2", "H2"), ("hinf", r"H$_\infty$"))):
            a = ax[i, j]
            for design, (c, ls, _) in style.items():
                a.semilogy(ws.t, ws.errors[(design, n, start)] * KM, color=c, ls=ls, lw=1.0, marker=".", ms=2.5)
            a.axhline(ws.guarantee[("nominal", n)] * KM, color="C0", ls="--", lw=1.1)
            a.axhline(ws.guarantee[("robust", n)] * KM, color="C3", ls="--", lw=1.1)
            a.set_title(f"{title}, initial error {ws.e0[start] * KM:,.0f} km", fontsize=10)
            a.axvspan(ws.t[0], 0.1 * (ws.t[-1] - ws.t[0]), color="0.9", lw=0, zorder=0)
            nom, rob = ws.errors[("nominal", n, start)], ws.errors[("robust", n, start)]
            if np.nanmedian(np.abs(nom - rob) / rob) < 0.01:  # one trace drawn over the other: say so
                a.text(0.02, 0.03, "nominal and robust (triangulated) overlap", transform=a.transAxes, ha="left",
                       va="bottom", fontsize=8, color="0.3")
        ax[i, 0].set_ylabel("position error [km]")
    for a in ax[1]:
        a.set_xlabel("t [TU]")
    key = [Line2D([], [], color=c, ls=ls, marker=".", label=lab) for c, ls, lab in style.values()]
    key += [Line2D([], [], color="C0", ls="--", label=r"nominal guarantee (assumes true $\rho$)"),
            Line2D([], [], color="C3", ls="--", label=r"robust guarantee $\sqrt{3}\,\gamma^*$"),
            Patch(color="0.9", label="first 10 % (not in the RMS)")]
    fig.legend(handles=key, loc="outside lower center", ncol=3, fontsize=8)
    fig.suptitle(f"Fig. 3 at a {ws.dt * check_system(system, 'system').time_unit_s / 60:.0f}-min sampling interval "
                 "(H2 allows 0.1 deg per sample), 0.1 deg angle noise", fontsize=11)
    return fig
