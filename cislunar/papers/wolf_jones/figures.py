"""Figures of the Wolf & Jones test-case notebooks (05, 06): each takes study results and returns a figure.

Distances in 10^3 km or km as labelled, times in days, accelerations in mm/s^2; rotating frame of the Earth-Moon
CR3BP (Moon-centred where the label says so, barycentric otherwise).
"""

from __future__ import annotations

import re

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection

from cislunar.cr3bp.dynamics import check_system
from cislunar.cr3bp.propagation import propagate
from cislunar.papers.wolf_jones import _checks, global_search, plan_size_study, readings_study
from cislunar.papers.wolf_jones import keep_out_diagnosis as kod
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.papers.wolf_jones import test_case_studies as studies
from cislunar.papers.wolf_jones.claims.process_noise_readings import CORR_LIMIT, WEAK_FACTOR
from cislunar.publish import plotting
from cislunar.utils import validation

__all__ = ["convergence", "trajectories", "relative_motion", "thrust", "crlb_axes", "pareto", "equal_impulse",
           "keep_out_motivation", "absolute_trajectory", "relative_three_planes", "z_mirror", "thrust_profiles",
           "crlb_objects", "noise_readings", "pareto_fronts", "keep_out_sweep", "figure_readings", "departure_figure",
           "figure_keep_out_diagnosis"]


def _floor(v):
    return max(abs(v), 1e-16)


def _show(show, n: int) -> list:
    """Indices of the weights to draw: a non-empty sequence of integers in [0, n)."""
    idx = list(_checks.integers(show, "show", minimum=0))
    if max(idx) >= n:
        raise ValueError(f"show must hold indices below {n} (the number of weights); got {idx}")
    return idx


def _same_length(n: int, **vectors) -> dict:
    """Finite 1-D vectors, each of ``n`` entries (``n`` None: the length of the first)."""
    out = {}
    for name, value in vectors.items():
        out[name] = _checks.vector(value, name, n=n)
        n = out[name].size if n is None else n
    return out


def _window_days(value) -> np.ndarray:
    w = validation.as_array(value, "window_days", shape=(2,))
    if not w[0] < w[1]:
        raise ValueError(f"window_days must be (start, end) with start < end; got {w}")
    return w


def convergence(penalty: studies.PenaltyStudy):
    """Predicted decrease, trust radius and largest defect per iteration: our solver against the printed one."""
    validation.instance(penalty, "penalty", studies.PenaltyStudy)
    ha, hp = penalty.cold.history, penalty.printed["history"]
    its, itp = [h["iteration"] for h in ha], [h["iteration"] for h in hp]
    fig, axes = plt.subplots(1, 3, figsize=(14, 3.8))
    axes[0].semilogy(its, [_floor(h["predicted"]) for h in ha], "o-", ms=3, label="augmented Lagrangian")
    axes[0].semilogy(itp, [_floor(h["predicted"]) for h in hp], ".-", ms=3, color="C3",
                     label=r"printed: L1 penalty, linear MI ($\gamma = 10^3$)")
    axes[0].set(xlabel="iteration [-]", ylabel="|predicted decrease| [-]")
    axes[1].semilogy(its, [h["eta"] for h in ha], "o-", ms=3)
    axes[1].semilogy(itp, [h["eta"] for h in hp], ".-", ms=3, color="C3")
    axes[1].set(xlabel="iteration [-]", ylabel=r"trust-region radius $\eta$ [-]")
    axes[2].semilogy(its, [max(h["max_defect"], 1e-16) for h in ha], "o-", ms=3)
    axes[2].semilogy(itp, [max(h["max_defect"], 1e-16) for h in hp], ".-", ms=3, color="C3")
    axes[2].set(xlabel="iteration [-]", ylabel="largest defect [LU, LU/TU]")
    fig.suptitle(r"SCvx on test case 1, $\alpha_h = 5\times10^{-3}$, from the ballistic DRO")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    return fig


def trajectories(case: studies.Case1Sweep, show):
    """Fig. 1 analogue: the plans of the alpha_h indices ``show``, Moon-centred, thrust arcs red, coasts blue."""
    validation.instance(case, "case", studies.Case1Sweep)
    show = _show(show, len(case.alphas))
    sc, em, mps = case.scenario, case.scenario.system, case.scenario.system.velocity_unit_km_s * 1e3
    ref_dro = propagate(em, sc.observer_x0, np.linspace(0.0, sc.duration, 600)).x
    fig, axes = plt.subplots(1, 2, figsize=(10, 5.6))
    for ax, i in zip(axes, show):
        td, xd, ud = studies.dense_flight(case, case.best[i])
        pos = (xd[:, :2] - [1 - em.mu, 0]) * em.length_unit_km / 1e3
        thrust = np.linalg.norm(ud, axis=1) > 0.01 * sc.a_max
        segs = np.stack([pos[:-1], pos[1:]], axis=1)
        ax.add_collection(LineCollection(segs, colors=np.where(thrust[:-1] | thrust[1:], "tab:red", "tab:blue"),
                                         lw=1.6))
        rp = (ref_dro[:, :2] - [1 - em.mu, 0]) * em.length_unit_km / 1e3
        ax.plot(rp[:, 0], rp[:, 1], "k--", lw=0.9, label="reference DRO")
        ax.plot([], [], color="tab:blue", label="coast")
        ax.plot([], [], color="tab:red", label="thrust")
        ax.plot(0, 0, "o", color="0.5", ms=5, label="Moon")
        b = case.best[i]
        ax.set(xlabel="x - x_Moon [1000 km]", ylabel="y [1000 km]", aspect="equal",
               title=rf"$\alpha_h$ = {case.alphas[i]:g}: {b.impulse * mps:.1f} m/s, I = {b.information:.1f} nats")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8, bbox_to_anchor=(0.5, 0.0))
    fig.suptitle("Fig. 1 analogue: observer trajectory, Moon-centred rotating frame (thrust: |a| above 1 % of a_max)")
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return fig


def relative_motion(alphas, rel_km):
    """Fig. 2 analogue: position relative to the reference DRO (``rel_km`` per alpha_h, km), x-y plane."""
    alphas = _checks.vector(alphas, "alphas")
    rel_km = _checks.sequence(rel_km, "rel_km")
    if len(rel_km) != alphas.size:
        raise ValueError(f"rel_km must hold one array per weight ({alphas.size}); got {len(rel_km)}")
    rel_km = [validation.as_array(r, f"rel_km[{i}]", ndim=(2,), last=3) for i, r in enumerate(rel_km)]
    fig, ax = plt.subplots(figsize=(6.5, 5.5))
    cmap = plt.get_cmap("viridis")
    for j, (a, rel) in enumerate(zip(alphas, rel_km)):
        ax.plot(rel[:, 0] / 1e3, rel[:, 1] / 1e3, color=cmap(j / max(1, len(alphas) - 1)), lw=1.2,
                label=rf"$\alpha_h$={a:g}")
    ax.plot(0, 0, "o", color="C2", ms=6, label="start")
    ax.set(xlabel=r"$\Delta x$ [1000 km]", ylabel=r"$\Delta y$ [1000 km]", aspect="equal",
           title="Fig. 2 analogue: position relative to the reference DRO")
    ax.legend(fontsize=7, ncol=2, loc="center left", bbox_to_anchor=(1.02, 0.5))
    return fig


def thrust(case: studies.Case1Sweep, show):
    """Fig. 3 analogue: the thrust norm ``|a|`` and its components over time for the alpha_h indices ``show`` (window shaded)."""
    validation.instance(case, "case", studies.Case1Sweep)
    show = _show(show, len(case.alphas))
    sc, em = case.scenario, case.scenario.system
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.3), sharey=True, layout="constrained")
    scale = em.acceleration_unit_km_s2 * 1e6  # mm/s^2
    for ax, i in zip(axes, show):
        td, _, ud = studies.dense_flight(case, case.best[i])
        days = em.tu_to_days(td)
        ax.axvspan(em.tu_to_days(sc.window[0]), em.tu_to_days(sc.window[1]), color="0.9", label="observation window")
        # |a| first, wide and pale, so the components drawn over it stay visible where one of them carries the thrust
        ax.plot(days, np.linalg.norm(ud, axis=1) * scale, color="0.65", lw=4, label="|a|")
        ax.plot(days, ud[:, 0] * scale, label="$a_x$")
        ax.plot(days, ud[:, 1] * scale, label="$a_y$")
        ax.plot(days, ud[:, 2] * scale, ls="--", label="$a_z$")
        ax.axhline(sc.a_max * scale, color="0.4", ls=":", lw=0.8)
        ax.set(xlabel="time [days]", title=rf"$\alpha_h$ = {case.alphas[i]:g}")
    axes[0].set_ylabel("thrust acceleration [mm/s²]")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=5, fontsize=8, frameon=False)
    fig.suptitle("Fig. 3 analogue: thrust acceleration (dotted: a_max)")
    return fig


def crlb_axes(system, alphas, crlb):
    """Fig. 4 analogue: CRLB position 1-sigma per axis (km) of observer and target over the window."""
    check_system(system)
    alphas = _checks.vector(alphas, "alphas")
    crlb = validation.sequence_of(crlb, "crlb", wj.CRLBResult, "CRLBResult")
    if len(crlb) != alphas.size:
        raise ValueError(f"crlb must hold one CRLBResult per weight ({alphas.size}); got {len(crlb)}")
    cmap = plt.get_cmap("viridis")
    days_w = system.tu_to_days(crlb[0].t)
    fig, axes = plt.subplots(3, 2, figsize=(12, 8), sharex=True)
    for j, (a, c) in enumerate(zip(alphas, crlb)):
        col = cmap(j / max(1, len(alphas) - 1))
        for obj in range(2):
            for ax_i in range(3):
                axes[ax_i, obj].semilogy(days_w, c.sigma_axes_km[obj, :, ax_i], "o-", ms=2, lw=1, color=col,
                                         label=rf"$\alpha_h$={a:g}" if (ax_i == 0 and obj == 1) else None)
    for obj, name in enumerate(("observer", "target")):
        axes[0, obj].set_title(f"{name}")
        for ax_i, ax_name in enumerate("xyz"):
            axes[ax_i, obj].set_ylabel(rf"$\sigma_{ax_name}$ [km]")
        axes[2, obj].set_xlabel("time [days]")
    axes[0, 1].legend(fontsize=7, ncol=1, loc="center left", bbox_to_anchor=(1.02, 0.0))
    fig.suptitle("Fig. 4 analogue: CRLB position 1-sigma per axis over the observation window")
    return fig


def _envelope_layer(ax, front, axis: str, loglog: bool = False) -> None:
    """Every distinct local optimum of a multi-start (grey) and their lower envelope (the front, black line)."""
    y = getattr(front, axis)
    x = np.maximum(front.impulse_mps, 1e-3) if loglog else front.impulse_mps
    other = front.optimum > 0
    ax.plot(x[other], y[other], "x", color="0.55", ms=6, label="other local optima (multi-start)")
    env = front.envelope(axis)
    ax.plot(x[env.index], env.y, "-", color="k", lw=1.3, zorder=1, label="lower envelope over all starts")


def pareto(alphas, impulse_mps, term_obs, term_tgt, front=None):
    """Fig. 5 analogue: total impulse against terminal position RMS, observer and target, labelled by alpha_h.

    With ``front`` (:class:`~cislunar.papers.wolf_jones.global_search.FrontPoints`) the curve is the lower envelope
    of every distinct optimum the multi-start found, the per-weight best plans marked on it and the other optima
    in grey; without it the per-weight plans are joined."""
    v = _same_length(None, alphas=alphas, impulse_mps=impulse_mps, term_obs=term_obs, term_tgt=term_tgt)
    alphas, impulse_mps, term_obs, term_tgt = v["alphas"], v["impulse_mps"], v["term_obs"], v["term_tgt"]
    if front is not None:
        validation.instance(front, "front", global_search.FrontPoints)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
    for ax, term, name, axis in zip(axes, (term_obs, term_tgt), ("observer", "target"), ("rms_obs", "rms_tgt")):
        if front is None:
            ax.plot(impulse_mps, term, "o-")
        else:
            _envelope_layer(ax, front, axis)
            ax.plot(impulse_mps, term, "o", color="C0", label=r"best plan per $\alpha_h$")
            ax.legend(fontsize=7, loc="upper right")
        for a, x_, y_ in zip(alphas, impulse_mps, term):
            ax.annotate(f"{a:g}", (x_, y_), textcoords="offset points", xytext=(4, 4), fontsize=7)
        ax.set(xlabel="total impulse [m/s]", ylabel="position RMS at the window end [km]", title=name, yscale="log")
    fig.suptitle(r"Fig. 5 analogue: Pareto curves over the $\alpha_h$ grid (labels: $\alpha_h$)")
    return fig


def equal_impulse(impulse_mps, term_obs, budget_rows):
    """Solved equal-impulse plans against the sweep grid and its log-linear interpolation (zoom on the baseline)."""
    impulse_mps = _checks.vector(impulse_mps, "impulse_mps", min_size=2)
    term_obs = _checks.vector(term_obs, "term_obs", n=impulse_mps.size)
    if np.any(term_obs <= 0):
        raise ValueError("term_obs must be positive terminal RMS values (km)")
    budget_rows = _checks.sequence(budget_rows, "budget_rows", allow_empty=True)
    for i, r in enumerate(budget_rows):
        validation.instance(r, f"budget_rows[{i}]", studies.BudgetRow, "a BudgetRow")
    fig, ax = plt.subplots(figsize=(7, 4.6), layout="constrained")
    x_hi = max([r.budget for r in budget_rows] + [impulse_mps[1]]) * 1.6  # zoom: the budgets and the next grid point
    zoom = impulse_mps <= x_hi
    xs = np.linspace(impulse_mps[0], impulse_mps[-1], 2000)
    ax.plot(xs, np.exp(np.interp(xs, impulse_mps, np.log(term_obs))), "--", color="0.5", lw=1,
            label="interpolation between grid points (linear in log RMS)")
    ax.plot(impulse_mps, term_obs, "o", color="0.5", label=r"sweep grid ($\alpha_h$ values)")
    for r in budget_rows:  # the gain over interpolation: from the open circle down to the star
        ax.plot([r.impulse] * 2, [r.interp, r.rms_obs], "-", color="C3", lw=0.8)
    if budget_rows:
        ax.plot([r.impulse for r in budget_rows], [r.interp for r in budget_rows], "o", ms=7, mfc="white",
                color="C3", label="interpolation at the solved plan's impulse")
        ax.plot([r.impulse for r in budget_rows], [r.rms_obs for r in budget_rows], "*", ms=13, color="C3",
                label="solved at a prescribed impulse")
    ax.plot(impulse_mps[0], term_obs[0], "s", ms=8, color="k", label=r"baseline $\alpha_h = 0$")
    shown = np.r_[term_obs[zoom], [r.rms_obs for r in budget_rows], [r.interp for r in budget_rows]]
    ax.set(xlabel="total impulse [m/s]", ylabel="observer position RMS at the window end [km]", yscale="log",
           xlim=(-0.5, x_hi), ylim=(shown.min() / 1.25, shown.max() * 1.25),
           title="Equal-impulse comparison near the baseline")
    ax.yaxis.set_major_formatter(plt.FormatStrFormatter("%g"))  # plain numbers at 1, 2, 5 x 10^k km
    ax.yaxis.set_minor_locator(plt.LogLocator(subs=(2.0, 5.0)))
    ax.yaxis.set_minor_formatter(plt.FormatStrFormatter("%g"))
    ax.legend(fontsize=8, loc="upper right")
    return fig


# ==============================================================================================================
# test case 2 (notebook 06)
# ==============================================================================================================
_PLANES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}


def keep_out_motivation(scan: studies.KeepOutScan, keep_out_km: float):
    """MI gain against the closest approach to target 1, with the adopted keep-out."""
    validation.instance(scan, "scan", studies.KeepOutScan)
    keep_out_km = validation.positive(keep_out_km, "keep_out_km")
    fig, ax = plt.subplots(figsize=(6, 3.8))
    ax.semilogx(scan.d_km, scan.gain, "o-")
    ax.axvline(keep_out_km, color="C3", ls="--")
    ax.text(keep_out_km / 1.4, 0.5, f"keep-out {keep_out_km:.0f} km\n(3 prior sigma)", color="C3", ha="right",
            va="center", fontsize=8, transform=ax.get_xaxis_transform())
    ax.set(xlabel="closest approach to target 1 at the middle measurement [km]",
           ylabel=r"$\mathcal{I} - \mathcal{I}_{ballistic}$ [nats]", title="The MI rewards flying through a target")
    return fig


def absolute_trajectory(sc, t, res, alpha):
    """Fig. 6 analogue: single-shooting flight of a plan in three planes (thrust red, coast blue), 10^3 km."""
    validation.instance(sc, "sc", wj.Scenario)
    t = validation.time_grid(t, "t", increasing=True)
    _checks.plan(res, "res", n=t.size)
    alpha = validation.real(alpha, "alpha")
    em = sc.system
    fig, axd = plotting.three_plane_axes(figsize=(15, 4.6))
    tf, xf = wj.fly(sc, t, res.u)
    uf = np.linalg.norm(np.stack([np.interp(tf, t, res.u[:, i]) for i in range(3)], axis=1), axis=1)
    thrust_on = uf > 1e-2 * sc.a_max  # thrust arc: |a| above 1 % of a_max (as in notebook 05's Fig. 1)
    ref = propagate(em, sc.observer_x0, np.linspace(0, sc.period, 400)).x
    k3 = em.length_unit_km / 1e3
    for plane, ax in axd.items():
        i, j = _PLANES[plane]
        ax.plot(ref[:, i] * k3, ref[:, j] * k3, color="k", ls="--", lw=0.8)
        for k in range(tf.size - 1):
            ax.plot(xf[k:k + 2, i] * k3, xf[k:k + 2, j] * k3, color="tab:red" if thrust_on[k] else "tab:blue", lw=1.2)
        ax.set(xlabel=f"{'xyz'[i]} [10$^3$ km]", ylabel=f"{'xyz'[j]} [10$^3$ km]")
    axd["xy"].set_aspect("equal", adjustable="datalim")  # out-of-plane panels keep free aspect: z is small
    handles = [plt.Line2D([], [], color="k", ls="--", lw=0.8), plt.Line2D([], [], color="tab:blue"),
               plt.Line2D([], [], color="tab:red")]
    fig.legend(handles, ["reference DRO", "coast", "thrust"], loc="lower center", ncol=3, fontsize=9,
               bbox_to_anchor=(0.5, -0.02))
    fig.suptitle(rf"Fig. 6 analogue: observer trajectory, $\alpha_h$ = {alpha:g} (rotating frame, barycentric; "
                 r"thrust: |a| above 1 % of $a_{max}$)")
    fig.tight_layout(rect=(0, 0.07, 1, 0.95))
    for plane in ("xz", "yz"):  # data units per pixel horizontally / vertically: how much z is stretched
        ax = axd[plane]
        box = ax.get_window_extent()
        stretch = (np.ptp(ax.get_xlim()) / box.width) / (np.ptp(ax.get_ylim()) / box.height)
        ax.set_title(f"{plane[0]}-{plane[1]}: z stretched {stretch:.0f}x")
    axd["xy"].set_title("x-y: equal scales")
    return fig


def relative_three_planes(case: studies.Case2Sweep, departure_km, show):
    """Fig. 7 analogue: plans of the weights ``show`` relative to the reference DRO in three planes, and the
    largest departure (``departure_km`` per converged weight) against alpha_h."""
    validation.instance(case, "case", studies.Case2Sweep)
    departure_km = _checks.vector(departure_km, "departure_km", n=len(case.ok))
    show = [validation.real(a, f"show[{i}]") for i, a in enumerate(_checks.sequence(show, "show"))]
    sc, t, ok = case.scenario, case.t, case.ok
    em = sc.system
    fig, axs = plt.subplots(1, 4, figsize=(17, 4.6), gridspec_kw={"width_ratios": [1, 1, 1, 0.8]})
    axd = dict(zip(("xy", "xz", "yz"), axs[:3]))
    n_show = 0
    for r in ok:
        if r.alpha not in show:
            continue
        tf, xf = wj.fly(sc, t, r.res.u, refine=4)
        rel = (xf - propagate(em, sc.observer_x0, tf).x) * em.length_unit_km
        for plane, ax in axd.items():
            i, j = _PLANES[plane]
            ax.plot(rel[:, i] / 1e3, rel[:, j] / 1e3, color=("C0", "C4", "C5", "C1", "C3")[n_show % 5], lw=1.1,
                    label=rf"$\alpha_h$ = {r.alpha:g}" if plane == "xy" else None)
            ax.plot(rel[0, i] / 1e3, rel[0, j] / 1e3, "o", color="green", mec="k", ms=6, zorder=5)
            ax.plot(rel[-1, i] / 1e3, rel[-1, j] / 1e3, "o", color="red", mec="k", ms=6, zorder=5)
            ax.set(xlabel=f"{'xyz'[i]} - {'xyz'[i]}$_{{ref}}$ [10$^3$ km]",
                   ylabel=f"{'xyz'[j]} - {'xyz'[j]}$_{{ref}}$ [10$^3$ km]")
        n_show += 1
    binds = np.array([case.binds(r) for r in ok])
    xs = np.arange(len(ok))
    dep = np.array(departure_km)
    axs[3].plot(xs, dep / 1e3, "-", color="0.7", zorder=1)
    axs[3].plot(xs[binds], dep[binds] / 1e3, "o", color="C3", label="keep-out active")
    axs[3].plot(xs[~binds], dep[~binds] / 1e3, "o", mfc="white", color="C0", label="keep-out inactive")
    axs[3].set_xticks(xs, [f"{r.alpha:g}" for r in ok], rotation=45)
    axs[3].set(xlabel=r"$\alpha_h$ (grid) [-]", ylabel="largest departure [10$^3$ km]", title="every weight of the grid")
    axs[3].set_ylim(0, None)
    axs[3].legend(fontsize=8, loc="lower right")
    fig.legend(*axd["xy"].get_legend_handles_labels(), loc="lower center", ncol=5, fontsize=9,
               bbox_to_anchor=(0.4, -0.04))
    fig.suptitle("Fig. 7 analogue: observer relative to the reference DRO (green: start, red: end)")
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    return fig


def z_mirror(sc, t, curves, window_days):
    """z over time of plans ``curves`` (``{(alpha, label): result or exception}``), window shaded."""
    validation.instance(sc, "sc", wj.Scenario)
    t = validation.time_grid(t, "t", increasing=True)
    validation.instance(curves, "curves", dict, "a dict {(alpha, label): result or exception}")
    for key, res in curves.items():
        if not isinstance(res, Exception):
            _checks.plan(res, f"curves[{key!r}]", n=t.size)
    window_days = _window_days(window_days)
    em = sc.system
    fig, ax = plt.subplots(figsize=(11, 4.4))
    for n_, ((a, what), res) in enumerate(curves.items()):
        if isinstance(res, Exception):
            continue
        tf, xf = wj.fly(sc, t, res.u, refine=4)
        ax.plot(em.tu_to_days(tf), xf[:, 2] * em.length_unit_km, lw=1.2, ls="-" if n_ % 2 == 0 else "--",
                color=f"C{n_ // 2}", label=rf"$\alpha_h$ = {a:g}, {what} (cost {res.cost:.3f})")
    ax.axvspan(*window_days, color="0.9", zorder=0)
    ax.set(xlabel="time [days] (observation window shaded)", ylabel="z [km]")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=8)
    ax.set_title("z-mirror: an optimum and its mirror image (full mode: also the +z / -z seeded solutions)")
    fig.tight_layout()
    return fig


def thrust_profiles(sc, t, plans, window_days):
    """Fig. 8 analogue: node accelerations of ``plans`` (``[(alpha, result)]``) in mm/s^2, window shaded."""
    validation.instance(sc, "sc", wj.Scenario)
    t = validation.time_grid(t, "t", increasing=True)
    plans = _checks.sequence(plans, "plans")
    for i, pair in enumerate(plans):
        if not isinstance(pair, (tuple, list)) or len(pair) != 2:
            raise validation.ArgumentTypeError(f"plans[{i}] must be a pair (alpha, result); got {type(pair).__name__}")
        validation.real(pair[0], f"plans[{i}] alpha")
        _checks.plan(pair[1], f"plans[{i}] result", n=t.size)
    window_days = _window_days(window_days)
    em = sc.system
    fig, axes = plt.subplots(1, 2, figsize=(13, 4), sharey=True)
    days = em.tu_to_days(t)
    for ax, (a, res) in zip(axes, plans):
        u = res.u * em.acceleration_unit_km_s2 * 1e6  # mm/s^2
        for i, name in enumerate(("a_x", "a_y", "a_z")):
            ax.plot(days, u[:, i], ".-", lw=1, label=f"${name}$")
        ax.plot(days, np.linalg.norm(u, axis=1), "k-", lw=1.4, label="|a|")
        ax.axhline(sc.a_max * em.acceleration_unit_km_s2 * 1e6, color="0.4", ls=":", lw=1, label="a_max")
        ax.axvspan(*window_days, color="0.9", zorder=0, label="observation window")
        ax.set(xlabel="time [days]", title=rf"$\alpha_h$ = {a:g}")
    axes[0].set_ylabel("thrust acceleration [mm/s$^2$]")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=6, fontsize=8,
               bbox_to_anchor=(0.5, -0.02))
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    return fig


def crlb_objects(system, crlbs):
    """Fig. 9 analogue: position RMS (km) of the observer and each target over the window, ``crlbs`` a dict
    ``alpha -> CRLBResult`` (grey, blue, red in order)."""
    check_system(system)
    validation.instance(crlbs, "crlbs", dict, "a dict {alpha: CRLBResult}")
    if not crlbs:
        raise ValueError("crlbs must hold at least one CRLBResult")
    for a, c in crlbs.items():
        validation.instance(c, f"crlbs[{a!r}]", wj.CRLBResult, "a CRLBResult")
    names = ["observer", "target 1", "target 2", "target 3"]
    fig, axes = plt.subplots(1, 4, figsize=(15, 3.8), sharey=True)
    for i, ax in enumerate(axes):
        for (a, c), color in zip(crlbs.items(), ("0.6", "C0", "C3")):
            ax.semilogy(system.tu_to_days(c.t), c.rms_km[i], "o-", ms=2.5, color=color, label=rf"$\alpha_h$ = {a:g}")
        ax.set(xlabel="time [days]", title=names[i])
    axes[0].set_ylabel("position RMS (CRLB) [km]")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=3, fontsize=8,
               bbox_to_anchor=(0.5, -0.02))
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    return fig


def noise_readings(system, readings: studies.NoiseReadings):
    """Test case 1's ballistic observer RMS under each reading of the process noise."""
    check_system(system)
    validation.instance(readings, "readings", studies.NoiseReadings)
    fig, ax = plt.subplots(figsize=(7, 4))
    for (t, rms), row in zip(readings.curves, readings.rows):
        ax.semilogy(system.tu_to_days(t), rms, "o-", ms=3, label=row[0])
    ax.set(xlabel="time [days]", ylabel="observer position RMS [km]",
           title=r"Test case 1, ballistic observer: CRLB under each reading of Q")
    handles, labels = ax.get_legend_handles_labels()
    ax.legend(handles, [re.sub(r"\^(\d)", r"$^\1$", lab) for lab in labels], fontsize=7, loc="upper left")
    return fig


def pareto_fronts(fr: studies.Front, front=None):
    """Fig. 10 analogue: impulse against terminal RMS (observer, targets), and MI against RMS.

    With ``front`` (:class:`~cislunar.papers.wolf_jones.global_search.FrontPoints`) the observer and target fronts
    are the lower envelopes of every distinct optimum the multi-start found (targets: their mean RMS), the
    per-weight best plans marked and the other optima in grey."""
    validation.instance(fr, "fr", studies.Front)
    if front is not None:
        validation.instance(front, "front", global_search.FrontPoints)
    dvs, rms_obs, rms_tgt, mis = fr.dv, fr.rms_obs, fr.rms_tgt, fr.mi
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    if front is None:
        axes[0].loglog(np.maximum(dvs, 1e-3), rms_obs, "o-")
    else:
        _envelope_layer(axes[0], front, "rms_obs", loglog=True)
        _envelope_layer(axes[1], front, "rms_tgt", loglog=True)
        axes[0].loglog(np.maximum(dvs, 1e-3), rms_obs, "o", color="C0", label=r"best plan per $\alpha_h$")
        axes[0].legend(fontsize=7, loc="upper right")
    for n_, (a, x_, y_) in enumerate(zip(fr.alphas, dvs, rms_obs)):  # every point labelled, alternately up/down
        up = n_ % 2 == 0
        axes[0].annotate(rf"$\alpha_h$ = {a:g}" if n_ == 0 else f"{a:g}", (x_, y_), textcoords="offset points",
                         xytext=(5, 6) if up else (-5, -8), ha="left" if up else "right",
                         va="bottom" if up else "top", fontsize=7)
    axes[0].set(xlabel=r"total impulse $\Delta V$ [m/s]", ylabel="terminal position RMS [km]", title="observer")
    for i, (mk, ls) in enumerate((("o", "-"), ("s", "--"), ("^", ":"))):
        axes[1].loglog(np.maximum(dvs, 1e-3), rms_tgt[:, i], marker=mk, ls=ls if front is None else "none",
                       ms=8 - 2 * i, label=f"target {i + 1}")
    axes[1].set(xlabel=r"total impulse $\Delta V$ [m/s]", ylabel="terminal position RMS [km]",
                title="targets (nearly coincide: see text)")
    axes[1].legend(fontsize=8, loc="upper right")
    axes[2].semilogy(mis, rms_obs, "o-", ms=9, mfc="none", mew=1.5, label="observer")
    axes[2].semilogy(mis, rms_tgt.mean(axis=1), "s--", ms=4, label="targets (mean)")
    axes[2].set(xlabel="mutual information of the window [nats]", ylabel="terminal position RMS [km]",
                title="MI against CRLB")
    axes[2].legend(fontsize=8, loc="upper right")
    for ax in axes:  # room above and below the end points (log axes)
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo / 1.3, hi * 1.3)
    lo_x, hi_x = (dvs.min(), dvs.max()) if front is None else (min(dvs.min(), front.impulse_mps.min()),
                                                               max(dvs.max(), front.impulse_mps.max()))
    for ax in axes[:2]:  # plain impulse ticks (a log axis spanning one decade would print a single label)
        ticks = [v for v in (1, 2, 5, 10, 20, 50, 100, 200) if 0.7 * lo_x <= v <= 1.4 * hi_x]
        ax.set_xticks(ticks, [f"{v:g}" for v in ticks])
        ax.xaxis.set_minor_formatter(plt.NullFormatter())
        ax.set_xlim(0.8 * lo_x, 1.6 * hi_x)
    fig.tight_layout()
    return fig


def keep_out_sweep(radius_rows, neighbours, keep_out_km, alpha):
    """MI and terminal RMS against the keep-out radius at one weight; dashed: the neighbouring weights' optima
    (``neighbours``: PlanRows)."""
    radius_rows = validation.sequence_of(radius_rows, "radius_rows", studies.RadiusRow, "RadiusRow")
    neighbours = _checks.sequence(neighbours, "neighbours", allow_empty=True)
    for i, nb in enumerate(neighbours):
        validation.instance(nb, f"neighbours[{i}]", studies.PlanRow, "a PlanRow")
    keep_out_km = validation.positive(keep_out_km, "keep_out_km")
    alpha = validation.real(alpha, "alpha")
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
    dd = np.array([r.d for r in radius_rows])
    bind = np.array([r.binds for r in radius_rows])
    for ax, key, lab in ((axes[0], "mi", "mutual information of the window [nats]"),
                         (axes[1], "rms", "terminal observer position RMS [km]")):
        yy = np.array([r[key] for r in radius_rows])
        ax.semilogx(dd[bind], yy[bind], "o", ms=7, color="C3", label="keep-out active at the optimum")
        ax.semilogx(dd[~bind], yy[~bind], "o", ms=7, mfc="white", color="C0", label="keep-out inactive")
        for nb in neighbours:  # yardstick: what a step of alpha_h on the grid changes
            v = nb.mi if key == "mi" else nb.crlb.terminal_rms_km[0]
            ax.axhline(v, color="0.5", ls="--", lw=1)
            ax.text(0.99, v, rf"sweep, $\alpha_h$ = {nb.alpha:g}", transform=ax.get_yaxis_transform(), ha="right",
                    va="bottom", fontsize=7, color="0.35")
        ax.axvline(keep_out_km, color="0.5", ls=":", lw=1)
        ax.set(xlabel="keep-out radius $d_{min}$ [km]", ylabel=lab)
        ax.set_xticks(dd, [f"{d:.0f}" for d in dd])  # the radii themselves (the span can be under a decade)
        ax.xaxis.set_minor_formatter(plt.NullFormatter())
        ax.set_xlim(dd.min() / 1.5, dd.max() * 1.5)
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo - 0.08 * (hi - lo), hi + 0.08 * (hi - lo))
    fig.legend(*axes[0].get_legend_handles_labels(), fontsize=8, loc="lower center", ncol=2)
    fig.suptitle(rf"Keep-out radius swept at $\alpha_h$ = {alpha:g} (dotted: adopted 424 km; dashed: the neighbouring "
                 r"$\alpha_h$ of the grid, for scale)")
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return fig


# ------------------------------------------------------------------------------------------------------------
# process-noise readings (notebooks 05 section 8, 06 section 10b; readings_study)
def figure_readings(study: readings_study.ReadingsStudy, system, show_alphas=None):
    """Figs. 9 and 10 under each reading, a small-multiples panel.

    Top row: the observer's CRLB (position RMS, km) over the window (days) for the plans nearest to
    ``show_alphas`` (default: every plan; alpha_h = 0 grey), the alpha_h = 0 ratio in the title; bottom row: MI
    under that reading (nats) against the terminal observer RMS (km), every plan, with the Spearman coefficient.
    ``system`` is the CR3BP of the study's scenario (time units).
    """
    validation.instance(study, "study", readings_study.ReadingsStudy)
    check_system(system, "system")
    alphas = np.array(study.alphas)
    show = alphas if show_alphas is None else validation.as_array(show_alphas, "show_alphas", ndim=(1,), min_size=1)
    idx = [int(np.argmin(np.abs(alphas - a))) for a in show]
    ncol = len(study.rows)
    fig, axes = plt.subplots(2, ncol, figsize=(4.2 * ncol, 6.6), squeeze=False)
    for ax in axes[0, 1:]:
        ax.sharey(axes[0, 0])  # the CRLB levels of the readings on one scale; the MI levels differ by reading
    for ax in axes[1, 1:]:
        ax.sharex(axes[1, 0])  # terminal RMS on one scale, so the literal reading's level shows
    ramp = plt.cm.viridis(np.linspace(0.1, 0.9, max(int(np.sum(alphas > 0)), 2)))
    colors = [(0.6, 0.6, 0.6, 1.0) if a == 0 else ramp[int(np.sum(alphas[:i] > 0))] for i, a in enumerate(alphas)]
    for j, r in enumerate(study.rows):
        name = re.sub(r"\^(\d)", r"$^\1$", r.name)
        ax = axes[0, j]
        days = system.tu_to_days(r.t)
        for i in idx:
            ax.semilogy(days, r.rms_km[i, 0], "o-", ms=2, lw=1, color=colors[i], label=rf"$\alpha_h$ = {alphas[i]:g}")
        wr = study.weak_ratio(r)
        verdict = ("" if study.case != 2 else  # the paper says "weakly observable" of test case 2 only
                   ": weakly observable" if wr >= WEAK_FACTOR else ": not weakly observable")
        ax.set_title("\n".join([name] + ([f"$\\alpha_h$ = 0 ends {wr:.1f}x the worst $\\alpha_h$ > 0{verdict}"]
                                          if np.isfinite(wr) else [])), fontsize=8)
        ax.set(xlabel="time [days]", ylabel="observer position RMS [km]")
        ax = axes[1, j]
        ax.scatter(r.terminal_obs_km, r.mi, color=colors, s=18)
        ax.set_xscale("log")
        c = study.corr(r)
        ax.set_title(f"Spearman(MI, RMS) {c:+.2f}: " + ("correlates well" if c <= CORR_LIMIT else "does not"),
                     fontsize=8)
        ax.set(xlabel="terminal observer RMS [km]", ylabel="MI under this reading [nats]")
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="lower center", ncol=min(len(idx), 10), fontsize=7,
               bbox_to_anchor=(0.5, -0.01))
    figs = "Figs. 9-10" if study.case == 2 else "Figs. 4-5"
    fig.suptitle(f"Test case {study.case}: {figs} (CRLB, MI against RMS) under each reading of Q", fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 0.97))
    return fig


# ------------------------------------------------------------------------------------------------------------
# plan size (notebook 05 section 8b; plan_size_study)
def departure_figure(study: plan_size_study.PlanSizeStudy):
    """Largest departure from the reference DRO against the control-term scale :math:`c`, one curve per
    process-noise reading, one panel per weight; the "not immediately apparent" threshold dashed."""
    validation.instance(study, "study", plan_size_study.PlanSizeStudy)
    fig, axes = plt.subplots(1, len(study.alphas), figsize=(6.0 * len(study.alphas), 4.5), sharey=True,
                             layout="constrained", squeeze=False)
    scales = np.array([study.row(n, study.readings[0], study.alphas[0]).control_scale for n in study.normalisations])
    order = np.argsort(scales)
    for ax, a in zip(axes[0], study.alphas):
        dep = study.departures(a)
        for j, q in enumerate(study.readings):  # the small readings nearly coincide: markers and dashes tell them apart
            ax.plot(scales[order], dep[order, j], marker="osd^v"[j % 5], ls=("-", "--", "-.", ":")[j % 4], lw=1.2,
                    ms=5 + 1.5 * (len(study.readings) - 1 - j), mfc="none", label=q)
        ax.axhline(study.threshold_km, color="k", ls="--", lw=1,
                   label=f"'not immediately apparent': {100 * study.fraction:g} % of the DRO's size")
        ax.axhline(study.baseline.departure_km, color="0.5", ls=":", lw=1, label=r"$\alpha_h$ = 0 plan")
        bad = [i for i in range(len(scales)) if np.all(np.isnan(dep[i]))]
        if bad:
            ax.plot(scales[bad], np.full(len(bad), 0.97), "kx", ms=7, transform=ax.get_xaxis_transform(),
                    label="no converged plan (see the table)")
        ax.set(xscale="log", yscale="log", xlabel="control term / total impulse in LU/TU, c [-]",
               title=rf"$\alpha_h$ = {a:g}")
    axes[0, 0].set_ylabel("largest departure from the reference DRO [km]")
    axes[0, -1].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    # which normalisation each c is: listed beside the panels (labels inside would collide, two c lie close)
    key = "\n".join(f"c = {scales[i]:.3g}: {study.normalisations[i].split(' (')[0]}" for i in order)
    axes[0, -1].text(1.04, 0.0, "control-term scale c\n" + key, transform=axes[0, -1].transAxes, fontsize=7,
                     va="bottom", ha="left")
    return fig


# ------------------------------------------------------------------------------------------------------------
# keep-out diagnosis and remedy (notebook 06 section 11; keep_out_diagnosis)
def figure_keep_out_diagnosis(diagnosis: kod.FreeRunDiagnosis, plain: kod.PassScan, remedy: kod.PassScan,
                              range_scale_km: float, regularised: kod.PassScan | None = None):
    """Left: closest approach of each SCvx reference to a target without a keep-out (km, log), the failure marked.
    Right: along passes at a chosen distance, the position part of the MI gradient (nats/LU) with the paper's
    noise, with the range-dependent noise and (if ``regularised`` is given) with the regularised range-rate
    Jacobian, and the whitened range-rate row (per LU)."""
    validation.instance(diagnosis, "diagnosis", kod.FreeRunDiagnosis)
    validation.instance(plain, "plain", kod.PassScan)
    validation.instance(remedy, "remedy", kod.PassScan)
    rc = validation.positive(range_scale_km, "range_scale_km")
    if regularised is not None:
        validation.instance(regularised, "regularised", kod.PassScan)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 4.6), layout="constrained")
    ref = np.arange(diagnosis.ref_range_km.size)
    ax1.semilogy(ref, diagnosis.ref_range_km, ".-", color="C0", label="closest approach of the reference")
    if diagnosis.failed and ref.size:
        ax1.semilogy(ref[-1], diagnosis.ref_range_km[-1], "x", color="C3", ms=10, mew=2,
                     label=f"last reference: {diagnosis.status or 'failure'}")
    ax1.axhline(424.0, color="0.5", ls="--", lw=0.8, label="the adopted keep-out (424 km), not imposed here")
    ax1.set(xlabel="SCvx reference (accepted step) [-]", ylabel="closest approach to a target [km]",
            title="SCvx without a keep-out")
    ax2.loglog(plain.d_km, plain.grad_position, "o-", color="C3", label=r"$|\partial I/\partial r|$, paper's noise")
    ax2.loglog(remedy.d_km, remedy.grad_position, "s-", color="C2",
               label=rf"$|\partial I/\partial r|$, range noise ($\rho_c$ = {rc:g} km)")
    if regularised is not None:
        ax2.loglog(regularised.d_km, regularised.grad_position, "^--", color="C1", mfc="none",
                   label=rf"$|\partial I/\partial r|$, regularised range-rate Jacobian ($\rho_c$ = {rc:g} km)")
    ax2.loglog(plain.d_km, plain.range_rate_row, ":", color="0.3", label="whitened range-rate row [1/LU]")
    ax2.set(xlabel="pass distance [km]", ylabel="norm [nats/LU or 1/LU]", title="the reward's slope near a target")
    for ax in (ax1, ax2):
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2 if ax is ax1 else 1,
                  frameon=False)
    fig.suptitle("Test case 2 without a keep-out: what the convex subproblem hits, and two remedies")
    return fig
