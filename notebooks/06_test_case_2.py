# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 06 · Test case 2: an observer and three targets with range and range rate
#
# **What you will learn.** How a low-thrust observer on a distant retrograde orbit (DRO) should move to learn the
# absolute states of itself and three neighbouring spacecraft from range and range-rate measurements alone; why
# the optimiser leaves the orbital plane (and in which direction: the z-mirror question the paper leaves open);
# why the mutual-information reward needs a minimum-range keep-out for range-rate measurements, and how large it
# must be; which readings of the process-noise units of Tables 3 and 5 the paper's text allows; and how the
# trade between impulse and estimation accuracy (the Pareto front) looks when the SCvx solver converges for every
# homotopy weight.
#
# **Paper sections followed.** Wolf & Jones (arXiv 2408.17435), "Numerical Case Studies: Test Case #2" (Tables 4-5,
# Figs. 6-10), with the information objective of "Problem Formulation" (Eqs. 9-23), its gradient (Eqs. 44-52),
# SCvx (Eqs. 24-43) and the CRLB of "Performance Evaluation". Test case 1 is notebook 05, the solver notebook 03,
# the mutual information notebook 02.
#
# All computation lives in `cislunar.papers.wolf_jones.scenarios` (scenario, information model, keep-out, CRLB, sweeps) and
# `cislunar.guidance.scvx` (the solver).

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: quick mode uses fewer SCvx nodes and alphas; the seeds and every study still run.
N_NODES = 16 if QUICK else 30  # Sundman nodes over the three periods (window ends moved onto nodes)
MAX_ITER = 100 if QUICK else 150  # SCvx iteration limit per run
N_NODES_ALT = [14] if QUICK else [24, 27]  # other node grids: the whole sweep again (Fig. 7 robustness, mesh check)
FREE_ITER = 10 if QUICK else 75  # iterations granted to the run without keep-out (it does not converge)
SIGMA = 1.0  # Sundman exponent (notebook 04)
# homotopy grid: 8 values including 0 and the weights of Figs. 6-8 (quick mode: 3; figures asking for an alpha_h
# outside the grid show the nearest one and say so)
ALPHAS = [0.0, 5e-3, 1e-2] if QUICK else [0.0, 5e-4, 1e-3, 2e-3, 5e-3, 7e-3, 1e-2, 2e-2]
SEED_ALPHAS = [] if QUICK else [5e-3, 7e-3]  # Fig. 7's pair, solved from +z and -z seeds (full mode)
MIRROR_ALPHA = 5e-3  # the sweep's optimum there, mirrored and solved again (both modes)
D_MIN_KM = [1500.0] if QUICK else [10.0, 141.0, 1000.0, 1500.0, 2500.0]  # keep-out radii swept (besides 424 km)
SCAN_POINTS = 8 if QUICK else 20  # closest-approach scan of section 3
BUDGET_EXTRA_MPS = 5.0  # impulse budget above the baseline's for the equal-impulse solve (section 11)
BUDGET_RTOL = 0.02  # a budget counts as met within 2 % (fixed before solving)
WORKERS = 2  # processes for the independent upward/downward sweeps and the other independent runs

import multiprocessing
import re
import time
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import matplotlib.pyplot as plt
import numpy as np
from scipy.stats import spearmanr

from cislunar.cr3bp.propagation import propagate, propagate_stm
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.papers.wolf_jones.reference import CLOSURE_TOL
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.sensing import covariance as cov

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)  # no random draws below; kept for the common parameter interface
table = ComparisonTable("06 Test case 2 (Wolf & Jones Tables 4-5, Figs. 6-10)")
t_start = time.perf_counter()

executor = ProcessPoolExecutor(max_workers=WORKERS, mp_context=multiprocessing.get_context("spawn"))

# %% [markdown]
# ## 1 · The scenario (Tables 4 and 5)
#
# Four spacecraft on neighbouring planar DROs: the observer starts on the DRO of the first row of Table 4 and must
# end, three periods later, on the state of the second row; three targets fly the last three rows. Table 4's row
# labels are lost in the paper's text except the last; they are read like Table 2's (observer start, observer end,
# targets 1-3). The first row is the same printed state as in test case 1 and is **not periodic** as printed: its
# $\dot y_0$ is corrected (holding $x_0$) into a DRO. $P_{ref}$ is the period of that corrected DRO.

# %%
sc = wj.test_case_2()
em = sc.system
print(f"{'row':<13}{'x0 [LU]':>14}{'vy0 printed':>14}{'closure printed':>17}{'vy0 correction':>16}{'period [d]':>12}")
for label, chk in sc.row_checks.items():
    print(f"{label:<13}{chk.x0:>14.9f}{chk.vy0:>14.9f}{chk.raw_closure:>17.2e}{chk.vy0_correction:>16.2e}"
          f"{em.tu_to_days(chk.corrected.period):>12.3f}")
ws_d, we_d = em.tu_to_days(np.array(sc.window))
t_meas = sc.measurement_times
print(f"P_ref = {em.tu_to_days(sc.period):.3f} d, scenario {em.tu_to_days(sc.duration):.2f} d, window "
      f"[{ws_d:.2f}, {we_d:.2f}] d with {t_meas.size} daily range/range-rate pairs per target")
print(f"a_max = {sc.a_max * em.acceleration_unit_km_s2:.1e} km/s^2 = {sc.a_max:.4f} LU/TU^2; "
      f"process-noise PSD q = {sc.q:.0e} LU^2/TU^3 = {sc.q * em.length_unit_km**2 / em.time_unit_s**3:.2e} km^2/s^3")
t, k_ws, k_we = sc.node_times(N_NODES, SIGMA)
print(f"{t.size} Sundman nodes (sigma = {SIGMA}); window nodes {k_ws}-{k_we}: "
      f"thrust bound a_max outside, 0 inside (the observer coasts through the window)")
x_ball, u_ball = sc.ballistic_guess(t)
x_ws_ball = x_ball[k_ws]

# %% [markdown]
# ## 2 · The information model and its gradient
#
# During the window the observer coasts, so the mutual information of the window (Eq. 18, computed by the
# chain rule in square-root form, notebook 02) is a function of the observer state at the window start alone. The
# process noise blocks of $\tilde P$ are computed once along the ballistic window arc and held fixed: the value and
# the gradient then describe the same function (the paper's gradient neglects the sensitivity of $\tilde P$; a value
# that recomputed Q along each candidate differs from it only slightly, at most by the relative amount printed in
# section 4, but any mismatch between value and gradient would confuse the ratio test). The gradient is the
# reverse-mode derivative of Eq. 18 computed through the square-root recursion (not the paper's Eqs. 44-52 term by
# term); we check it against fourth-order central differences.

# %%
info = sc.information_model()
I0 = info(x_ws_ball)
I1, g = info(x_ws_ball, 1)
h = 2e-7
g_fd = np.array([(8 * (info(x_ws_ball + h * e) - info(x_ws_ball - h * e))
                  - (info(x_ws_ball + 2 * h * e) - info(x_ws_ball - 2 * h * e))) / (12 * h) for e in np.eye(6)])
grad_err = float(np.max(np.abs(g - g_fd)) / np.max(np.abs(g_fd)))
print(f"MI on the ballistic guess: {I0:.6f} nats (order 0) vs {I1:.6f} (order 1)")
print("gradient [nats/LU, nats/(LU/TU)]:", np.round(g, 4), "\ncentral differences:             ", np.round(g_fd, 4))
print(f"max relative difference {grad_err:.1e}; z components {g[2]:.1e}, {g[5]:.1e} (planar symmetry)")

# %% [markdown]
# **The planar guess is a saddle in z.** By the CR3BP's mirror symmetry $z\to-z$ (and that of range and range
# rate) the MI is an even function of the out-of-plane state at a planar reference: its z-gradient vanishes, but
# its z-curvature is positive: leaving the plane in *either* direction gains information. A linear (Eq. 44) or
# concave model sees nothing to gain in z; the out-of-plane motion of Fig. 6 appears only once the iterates leave
# the plane (solver round-off is enough), and its sign is then an accident, which is the z-mirror of Fig. 7.

# %%
H = info.hessian(x_ws_ball)
dz = np.zeros(6)
dz[5] = 1e-3 / em.velocity_unit_km_s  # 1 m/s in vz
mi_up, mi_down = info(x_ws_ball + dz), info(x_ws_ball - dz)
print(f"MI with vz = +1 m/s: {mi_up - I0:+.4f} nats, vz = -1 m/s: {mi_down - I0:+.4f} nats (relative to planar)")
print(f"Hessian diagonal (z, vz): {H[2, 2]:.3e}, {H[5, 5]:.3e}; "
      f"eigenvalues: {np.array2string(np.linalg.eigvalsh(H), precision=2)}")

# %% [markdown]
# ## 3 · Why a keep-out, and how large
#
# The range-rate Jacobian with respect to the relative position is $(\Delta\dot{\mathbf r}-\dot\rho\hat\rho)/\rho$:
# it grows without bound as the range $\rho$ shrinks, and so does the linear-Gaussian MI. Below we move the
# observer's window-start state (Newton on the STM) so that it passes target 1 at a chosen distance at the middle
# measurement of the window and evaluate the MI: nearly flat down to about a hundred metres, the reward then
# grows without bound (like $\ln(1/\rho)$), so a maximiser that finds this region could fly through the target
# (section 11: without a keep-out SCvx does not converge, its cost sinks below the constrained optimum's while the
# defects stay open, and we print how close its iterates come; smaller keep-outs are tried there too). Well before
# that singularity the reward stops being
# trustworthy: the MI linearises the measurement about the *true* states, while the prior
# uncertainty of the relative position is $\sigma_{rel} = \sqrt2\cdot 100$ km = 141 km per axis; the
# line-of-sight direction that carries the range-rate information is uncertain by about $\sigma_{rel}/\rho$ rad. We
# require the target to lie outside the prior 3-sigma relative-position sphere,
# $d_{min} = 3\sqrt2\,\sigma_p$ = 424 km, at every measurement time (`MinimumRange`, linearised through the
# observer STM: the tangent half-space of the keep-out sphere). The ballistic reference passes no closer than
# about 1500 km inside the window, yet the keep-out is not a mere guard against the singularity: at 424 km the scan
# shows no MI gain from a closer pass (printed below), but the optimiser still presses against the sphere in most
# plans of the sweep (section 4 counts them), so the keep-out shapes the optima, and section 11 sweeps its radius.

# %%
k_mid = t_meas.size // 2
r_tgt = propagate(em, info.targets_x0[0], t_meas[[0, k_mid]]).x[-1, :3]


def observer_passing_at(d_km, x0, iterations=6):
    """Window-start state whose coasting arc passes target 1 at d_km at the middle measurement (Newton, STM)."""
    x = x0.copy()
    r_now = propagate(em, x0, t_meas[[0, k_mid]]).x[-1, :3]
    goal = r_tgt + em.km_to_lu(d_km) * (r_now - r_tgt) / np.linalg.norm(r_now - r_tgt)
    for _ in range(iterations):
        tr = propagate_stm(em, x, t_meas[[0, k_mid]])
        x[:3] += np.linalg.solve(tr.stm[-1][:3, :3], goal - tr.x[-1, :3])
    return x


d_scan = np.geomspace(1e-6, 3000.0, SCAN_POINTS)
mi_scan = np.array([info(observer_passing_at(d, x_ws_ball)) for d in d_scan])
ko = sc.keep_out(k_ws)
fig, ax = plt.subplots(figsize=(6, 3.8))
ax.semilogx(d_scan, mi_scan - I0, "o-")
ax.axvline(sc.keep_out_km, color="C3", ls="--")
ax.text(sc.keep_out_km / 1.4, 0.5, f"keep-out {sc.keep_out_km:.0f} km\n(3 prior sigma)", color="C3", ha="right",
        va="center", fontsize=8, transform=ax.get_xaxis_transform())
ax.set(xlabel="closest approach to target 1 at the middle measurement [km]",
       ylabel=r"$\mathcal{I} - \mathcal{I}_{ballistic}$ [nats]", title="The MI rewards flying through a target")
_ = plotting.save_figure(fig, "06_keep_out_motivation", output_dir=out)
for d_show in (1000.0, 424.0, 1.0, 0.1, 1e-3, 1e-6):
    print(f"pass at {d_show:8.0e} km: MI gain {np.interp(np.log(d_show), np.log(d_scan), mi_scan) - I0:+.2f} nats")

# %% [markdown]
# ## 4 · SCvx over the homotopy grid, swept both ways
#
# For each $\alpha_h$ the solver (`cislunar.guidance.scvx`: SCvx* augmented Lagrangian on the defects, the convex
# quadratic MI model from the concave part of the Hessian, the keep-out as a linearised constraint) starts from a
# warm start. The problem has several local optima, so we sweep the grid upward (from the ballistic guess at
# $\alpha_h = 0$) and downward (from the ballistic guess at the largest $\alpha_h$) and keep the lower cost per
# $\alpha_h$; the two sweeps are independent and run in two processes.

# %%
solver = wj.ScenarioSolver(sc, t, k_ws, information=info, keep_out=True,
                           settings=scvx.SCvxSettings(max_iter=MAX_ITER))
# the seeded runs of section 7 do not depend on the sweep: queue them behind its two chains
seeds = {s: sc.seeded_guess(t, s) for s in (+1, -1)}
seed_jobs = {(a, s): executor.submit(solver, a, *seeds[s]) for a in SEED_ALPHAS for s in (+1, -1)}
t0 = time.perf_counter()
sweep = wj.sweep_both_ways(solver, ALPHAS, x_ball, u_ball, executor=executor)
t_sweep = time.perf_counter() - t0
failed = [a for a in sweep.attempts if not a["converged"]]


def alt_sweep(n_alt):
    """The same two-way sweep on another Sundman grid (its chains queue in the process pool)."""
    t_a, k_a, _ = sc.node_times(n_alt, SIGMA)
    s_a = wj.ScenarioSolver(sc, t_a, k_a, information=info, keep_out=True, settings=solver.settings)
    return t_a, k_a, wj.sweep_both_ways(s_a, ALPHAS, *sc.ballistic_guess(t_a), executor=executor)


# queued behind the seeded runs; collected in section 6 (a thread only waits on the process pool)
waiter = ThreadPoolExecutor(max_workers=len(N_NODES_ALT))
alt_jobs = {n_: waiter.submit(alt_sweep, n_) for n_ in N_NODES_ALT}
print(f"sweeps: {len(sweep.attempts)} runs in {t_sweep:.0f} s, {len(failed)} hit the iteration limit "
      "(" + (", ".join(f"{a['alpha']:g} {a['direction']} {a['start']}" for a in failed) or "none")
      + "; a failed warm start is retried from the ballistic guess)")

dv = lambda res: res.impulse * em.velocity_unit_km_s * 1e3  # noqa: E731 - m/s
rows = []
for a, res, src in zip(ALPHAS, sweep.best, sweep.source):
    if res is None:
        rows.append(None)
        continue
    crlb = wj.evaluate_crlb(sc, res.x[k_ws])
    u_norm = np.linalg.norm(res.u, axis=1)
    rows.append(dict(alpha=a, res=res, source=src, crlb=crlb, dv=dv(res), mi=res.information,
                     miss_km=wj.terminal_miss_km(sc, t, res.u), min_range_km=float(ko.ranges(res.x[k_ws]).min()
                                                                                    * em.length_unit_km),
                     z_max_km=float(np.max(np.abs(res.x[:, 2])) * em.length_unit_km),
                     u_ratio=float(np.max(u_norm[solver.u_max > 0] / solver.u_max[solver.u_max > 0])),
                     u_window=float(np.max(u_norm[k_ws:k_we + 1]))))
ok = [r for r in rows if r is not None]
print(f"{'alpha':>7} {'sweep':>5} {'dV [m/s]':>9} {'MI [nats]':>10} {'RMS obs':>8} {'RMS tgt':>8} {'it':>4} "
      f"{'defect':>8} {'miss [km]':>10} {'min range':>10} {'max|z| km':>10} {'|u|/umax':>9}")
for r in ok:
    print(f"{r['alpha']:>7g} {r['source']:>5} {r['dv']:>9.3f} {r['mi']:>10.3f} {r['crlb'].terminal_rms_km[0]:>8.1f} "
          f"{np.mean(r['crlb'].terminal_rms_km[1:]):>8.1f} {r['res'].iterations:>4d} {r['res'].max_defect:>8.1e} "
          f"{r['miss_km']:>10.2e} {r['min_range_km']:>10.1f} {r['z_max_km']:>10.0f} {r['u_ratio']:>9.3f}")
by_alpha = {r["alpha"]: r for r in ok}
n_bind = sum(r["min_range_km"] <= sc.keep_out_km * (1 + 1e-3) for r in ok if r["alpha"] > 0)
print(f"424 km keep-out active (closest approach within 0.1 % of it) in {n_bind} of "
      f"{sum(r['alpha'] > 0 for r in ok)} plans with alpha_h > 0")
mi_q_rel = max(abs(r["crlb"].mutual_information - r["mi"]) / r["mi"] for r in ok)
print(f"MI with Q held along the ballistic arc (planning) vs Q recomputed along each plan (CRLB): largest relative "
      f"difference {mi_q_rel:.1e}")


def pick(a):
    """The row of alpha a, or of the converged alpha nearest to it (printed), so that no figure is left empty."""
    if a in by_alpha:
        return by_alpha[a]
    near = min(ok, key=lambda r: abs(np.log((r["alpha"] + 1e-6) / (a + 1e-6))))
    print(f"(alpha {a:g} did not converge in either sweep; showing alpha {near['alpha']:g} instead)")
    return near

# %% [markdown]
# ## 5 · Figure 6: absolute motion for $\alpha_h = 10^{-2}$
#
# The converged control flown by single shooting (first-order hold), coloured by thrust (red: $|a|$ above 1 % of
# $a_{max}$, the threshold of notebook 05's Fig. 1) and coast (blue),
# with the reference DRO (the corrected first row of Table 4) dashed, in the three principal planes. The x-y panel
# has equal scales; in the two out-of-plane panels the z axis is stretched (by the factor in each panel title),
# because the excursions of a few thousand km out of the plane would otherwise be a flat line next to an orbit of
# a few hundred thousand km.

# %%
def coast_thrust(ax_dict, res):
    """Single-shooting flight of a converged control, thrust arcs red and coasts blue, in 10^3 km."""
    tf, xf = wj.fly(sc, t, res.u)
    uf = np.linalg.norm(np.stack([np.interp(tf, t, res.u[:, i]) for i in range(3)], axis=1), axis=1)
    thrust = uf > 1e-2 * sc.a_max  # thrust arc: |a| above 1 % of a_max (as in notebook 05's Fig. 1)
    ref = propagate(em, sc.observer_x0, np.linspace(0, sc.period, 400)).x
    k3 = em.length_unit_km / 1e3
    for plane, ax in ax_dict.items():
        i, j = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}[plane]
        ax.plot(ref[:, i] * k3, ref[:, j] * k3, color="k", ls="--", lw=0.8)
        for k in range(tf.size - 1):
            ax.plot(xf[k:k + 2, i] * k3, xf[k:k + 2, j] * k3, color="tab:red" if thrust[k] else "tab:blue", lw=1.2)
        ax.set(xlabel=f"{'xyz'[i]} [10$^3$ km]", ylabel=f"{'xyz'[j]} [10$^3$ km]")
    ax_dict["xy"].set_aspect("equal", adjustable="datalim")  # out-of-plane panels keep free aspect: z is small
    handles = [plt.Line2D([], [], color="k", ls="--", lw=0.8), plt.Line2D([], [], color="tab:blue"),
               plt.Line2D([], [], color="tab:red")]
    return handles, ["reference DRO", "coast", "thrust"]


row6 = pick(1e-2)
a6 = row6["alpha"]
fig, axd = plotting.three_plane_axes(figsize=(15, 4.6))
handles, labels = coast_thrust(axd, row6["res"])
fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=9, bbox_to_anchor=(0.5, -0.02))
fig.suptitle(rf"Fig. 6 analogue: observer trajectory, $\alpha_h$ = {a6:g} (rotating frame, barycentric; "
             r"thrust: |a| above 1 % of $a_{max}$)")
fig.tight_layout(rect=(0, 0.07, 1, 0.95))
for plane in ("xz", "yz"):  # data units per pixel horizontally / vertically: how much z is stretched
    ax = axd[plane]
    box = ax.get_window_extent()
    stretch = (np.ptp(ax.get_xlim()) / box.width) / (np.ptp(ax.get_ylim()) / box.height)
    ax.set_title(f"{plane[0]}-{plane[1]}: z stretched {stretch:.0f}x")
axd["xy"].set_title("x-y: equal scales")
_ = plotting.save_figure(fig, "06_fig6_absolute_trajectory", output_dir=out)

# %% [markdown]
# ## 6 · Figure 7: motion relative to the reference DRO over the grid
#
# The observer's position minus that of the reference DRO at the same time, with the initial (green) and terminal
# (red) states marked. Drawn for five weights of the grid, among them the paper's pair $5\times10^{-3}$ and
# $7\times10^{-3}$ (all eight curves on top of each other cannot be told apart); the right panel gives, for every $\alpha_h$ of the grid, the largest departure from the reference over the
# scenario, which is what "a larger departure" would mean: a longer observer-target baseline and more dynamical
# differentiation.

# %%
fig, axs = plt.subplots(1, 4, figsize=(17, 4.6), gridspec_kw={"width_ratios": [1, 1, 1, 0.8]})
axd = dict(zip(("xy", "xz", "yz"), axs[:3]))
FIG7_SHOW = (0.0, 5e-4, 5e-3, 7e-3, 2e-2)  # weights drawn (those on the grid; 5e-3 and 7e-3: the paper's pair)
dep_max = []
n_show = 0
for r in ok:
    tf, xf = wj.fly(sc, t, r["res"].u, refine=4)
    rel = (xf - propagate(em, sc.observer_x0, tf).x) * em.length_unit_km
    dep_max.append(float(np.max(np.linalg.norm(rel[:, :3], axis=1))))
    if r["alpha"] not in FIG7_SHOW:
        continue
    for plane, ax in axd.items():
        i, j = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}[plane]
        ax.plot(rel[:, i] / 1e3, rel[:, j] / 1e3, color=("C0", "C4", "C5", "C1", "C3")[n_show % 5], lw=1.1,
                label=rf"$\alpha_h$ = {r['alpha']:g}" if plane == "xy" else None)
        ax.plot(rel[0, i] / 1e3, rel[0, j] / 1e3, "o", color="green", mec="k", ms=6, zorder=5)
        ax.plot(rel[-1, i] / 1e3, rel[-1, j] / 1e3, "o", color="red", mec="k", ms=6, zorder=5)
        ax.set(xlabel=f"{'xyz'[i]} - {'xyz'[i]}$_{{ref}}$ [10$^3$ km]",
               ylabel=f"{'xyz'[j]} - {'xyz'[j]}$_{{ref}}$ [10$^3$ km]")
    n_show += 1
binds7 = np.array([r["min_range_km"] <= sc.keep_out_km * (1 + 1e-3) for r in ok])
xs7 = np.arange(len(ok))
axs[3].plot(xs7, np.array(dep_max) / 1e3, "-", color="0.7", zorder=1)
axs[3].plot(xs7[binds7], np.array(dep_max)[binds7] / 1e3, "o", color="C3", label="keep-out active")
axs[3].plot(xs7[~binds7], np.array(dep_max)[~binds7] / 1e3, "o", mfc="white", color="C0", label="keep-out inactive")
axs[3].set_xticks(xs7, [f"{r['alpha']:g}" for r in ok], rotation=45)
axs[3].set(xlabel=r"$\alpha_h$ (grid) [-]", ylabel="largest departure [10$^3$ km]", title="every weight of the grid")
axs[3].set_ylim(0, None)
axs[3].legend(fontsize=8, loc="lower right")
fig.legend(*axd["xy"].get_legend_handles_labels(), loc="lower center", ncol=5, fontsize=9,
           bbox_to_anchor=(0.4, -0.04))
fig.suptitle("Fig. 7 analogue: observer relative to the reference DRO (green: start, red: end)")
fig.tight_layout(rect=(0, 0.05, 1, 1))
_ = plotting.save_figure(fig, "06_fig7_relative_motion", output_dir=out)
rho_dep = spearmanr([r["alpha"] for r in ok], dep_max).statistic
print("largest departure from the reference [km]:",
      ", ".join(f"{r['alpha']:g}: {d_:.0f}" for r, d_ in zip(ok, dep_max)))
drops = [(ok[n_]["alpha"], ok[n_ + 1]["alpha"]) for n_ in range(len(ok) - 1) if dep_max[n_ + 1] < dep_max[n_]]
print(f"Spearman rank correlation of alpha_h and the largest departure: {rho_dep:.2f}; departure drops between "
      f"consecutive weights: " + (", ".join(f"{a_:g} -> {b_:g}" for a_, b_ in drops) or "none"))
# robustness: the same sweep on other node grids (which local optimum a weight lands in can change)
rho_grids = {N_NODES: float(rho_dep)}
mesh_rows = []  # node-grid check at the Fig. 6 weight
for n_alt, job in alt_jobs.items():
    t_a, k_a, sw_a = job.result()
    al_a, dep_a = [], []
    for a, res in zip(ALPHAS, sw_a.best):
        if res is None:
            continue
        tf_a, xf_a = wj.fly(sc, t_a, res.u, refine=4)
        rel_a = (xf_a - propagate(em, sc.observer_x0, tf_a).x)[:, :3] * em.length_unit_km
        al_a.append(a)
        dep_a.append(float(np.max(np.linalg.norm(rel_a, axis=1))))
        if a == a6:
            mesh_rows.append((n_alt, dv(res), res.information, wj.evaluate_crlb(sc, res.x[k_a]).terminal_rms_km[0]))
    rho_grids[n_alt] = float(spearmanr(al_a, dep_a).statistic) if len(al_a) > 2 else np.nan
    print(f"{n_alt} nodes: {len(al_a)}/{len(ALPHAS)} weights converged; largest departure [km] "
          + ", ".join(f"{a:g}: {d_:.0f}" for a, d_ in zip(al_a, dep_a)) + f"; Spearman {rho_grids[n_alt]:.2f}")
waiter.shutdown()
dep_pass = sum(v > 0.8 for v in rho_grids.values())
print(f"Spearman(alpha_h, departure) above 0.8 on {dep_pass} of {len(rho_grids)} node grids: "
      + ", ".join(f"{n_} nodes {v:.2f}" for n_, v in rho_grids.items()))

# %% [markdown]
# **Reading.** Whether the departure grows with $\alpha_h$ is read from the right panel and the numbers above, not
# from the curves. It does not grow step by step: neighbouring weights can land in different local optima of this
# non-convex problem (section 4 keeps the lower cost of two sweeps per weight), and a drop between consecutive
# weights (printed above) is such a change of optimum, not an effect of the weight. The paper's "generally" is
# therefore judged by the rank correlation (closing table, threshold 0.8), on this node grid and on the other node
# grids of the robustness check (whole sweep re-solved there; printed above, so the row does not rest on one grid's
# choice of local optima). More weight on information also shows
# in larger out-of-plane excursions and more impulse (table of section 4).

# ## 7 · The z-mirror question of Fig. 7
#
# The paper sees near-mirror images for $\alpha_h = 5\times10^{-3}$ and $7\times10^{-3}$ ("symmetry across the z
# axis") and postulates a family of symmetric optima. We read the symmetry as the reflection $z\to-z$ (across the
# plane $z = 0$, the horizontal axis of the x-z and y-z panels): it is the only reflection of the rotating frame
# that maps solutions of this problem onto solutions at the same times ($x\to-x$ is no symmetry of the CR3BP, and
# $y\to-y$ needs time reversal, which the fixed start and end states forbid). First the paper's own comparison:
# the sweep's optima at the two weights, the sign of their out-of-plane excursion and the distance between one and
# the mirror image of the other. The CR3BP, the planar DROs of all four spacecraft and range/range-rate
# measurements are all invariant under $z\to-z$, $\dot z\to-\dot z$; so for every optimum its mirror image is an
# optimum with exactly the same cost. We start SCvx from $+z$ and $-z$ seeds (a small out-of-plane thrust before
# the window) at both weights and compare the two answers: equal costs and mirror-image trajectories answer the
# question with numbers. A sharper check runs in both modes: the sweep's optimum at $\alpha_h = 5\times10^{-3}$,
# mirrored ($z, \dot z, a_z \to -z, -\dot z, -a_z$) and handed to SCvx as its guess, must be accepted as an
# optimum with the same cost. (Quick mode runs only this check; the seeded runs are full mode.)

# %%
mirror = np.diag([1, 1, -1, 1, 1, -1.0])
pair = [pick(a) for a in (5e-3, 7e-3)]
if pair[0]["alpha"] != pair[1]["alpha"]:
    xa, xb = pair[0]["res"].x, pair[1]["res"].x
    zsign = [float(x_[k_we, 2] * em.length_unit_km) for x_ in (xa, xb)]  # z at the window end, km
    d_mir = float(np.max(np.linalg.norm((xa - xb @ mirror)[:, :3], axis=1)) * em.length_unit_km)
    d_same = float(np.max(np.linalg.norm((xa - xb)[:, :3], axis=1)) * em.length_unit_km)
    print(f"sweep optima: z at the window end: alpha {pair[0]['alpha']:g}: {zsign[0]:+.0f} km, alpha "
          f"{pair[1]['alpha']:g}: {zsign[1]:+.0f} km; largest distance between the first and the mirror image of the "
          f"second {d_mir:.0f} km (without mirroring {d_same:.0f} km)")
else:
    zsign, d_mir, d_same = None, np.nan, np.nan
seed_alphas = SEED_ALPHAS  # submitted to the pool in section 4
seeded = {}
for key, fut in seed_jobs.items():
    try:
        seeded[key] = fut.result()
    except scvx.SCvxError as exc:
        seeded[key] = exc
mirror_u = np.diag([1, 1, -1.0])
row_m = pick(MIRROR_ALPHA)
twin = solver(row_m["alpha"], row_m["res"].x @ mirror, row_m["res"].u @ mirror_u)
twin_dcost = abs(twin.cost - row_m["res"].cost) / abs(row_m["res"].cost)
twin_km = float(np.max(np.linalg.norm((twin.x - row_m["res"].x @ mirror)[:, :3], axis=1)) * em.length_unit_km)
print(f"mirrored optimum of alpha {row_m['alpha']:g}: {twin.iterations} iterations, relative cost difference "
      f"{twin_dcost:.1e}, largest distance from the exact mirror {twin_km:.3f} km")
mirror_rows = []
for a in seed_alphas:
    p, m = seeded[(a, +1)], seeded[(a, -1)]
    if isinstance(p, scvx.SCvxError) or isinstance(m, scvx.SCvxError):
        print(f"alpha {a:g}: a seeded run failed ({p if isinstance(p, Exception) else m})")
        continue
    mis_km = float(np.max(np.linalg.norm((p.x - m.x @ mirror)[:, :3], axis=1)) * em.length_unit_km)
    dcost = abs(p.cost - m.cost) / abs(p.cost)
    best_sweep = by_alpha[a]["res"].cost if a in by_alpha else np.nan  # NaN: no sweep converged there
    mirror_rows.append((a, p.x[k_we, 2] * em.length_unit_km, m.x[k_we, 2] * em.length_unit_km, dcost, mis_km,
                        min(p.cost, m.cost), best_sweep))
    print(f"alpha {a:g}: z at window end {p.x[k_we, 2] * em.length_unit_km:+.0f} km (+z seed) / "
          f"{m.x[k_we, 2] * em.length_unit_km:+.0f} km (-z seed); relative cost difference {dcost:.1e}; "
          f"largest distance between one and the mirror of the other {mis_km:.2f} km; "
          f"cost {min(p.cost, m.cost):.6f} vs best of sweeps {best_sweep:.6f}")
if mirror_rows:
    print("seeded optimum costlier than the sweep's (a different, worse local optimum) at every seeded weight: "
          f"{all(m_[5] > m_[6] for m_ in mirror_rows)}")
fig, ax = plt.subplots(figsize=(11, 4.4))
curves = {(row_m["alpha"], "sweep optimum"): row_m["res"], (row_m["alpha"], "its mirror, re-solved"): twin}
curves.update({(a, f"{'+' if s_ > 0 else '-'}z seed"): res for (a, s_), res in seeded.items()})
for n_, ((a, what), res) in enumerate(curves.items()):
    if isinstance(res, Exception):
        continue
    tf, xf = wj.fly(sc, t, res.u, refine=4)
    ax.plot(em.tu_to_days(tf), xf[:, 2] * em.length_unit_km, lw=1.2, ls="-" if n_ % 2 == 0 else "--",
            color=f"C{n_ // 2}", label=rf"$\alpha_h$ = {a:g}, {what} (cost {res.cost:.3f})")
ax.axvspan(ws_d, we_d, color="0.9", zorder=0)
ax.set(xlabel="time [days] (observation window shaded)", ylabel="z [km]")
ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=8)
ax.set_title("z-mirror: an optimum and its mirror image (full mode: also the +z / -z seeded solutions)")
fig.tight_layout()
_ = plotting.save_figure(fig, "06_z_mirror", output_dir=out)

# %% [markdown]
# **Reading.** The mirrored sweep optimum is accepted again as an optimum with the same cost: the mirror of an
# optimum is an optimum, so Fig. 7's near-mirror pairs need no family of their own. In full mode the $+z$ and $-z$
# seeds also converge to exact mirror images of each other (equal costs, printed above), but not to the sweep's
# optimum: at both weights they land in a *different* local optimum with a higher cost (legend and printout), so
# a pair of mirror images says nothing about which local optimum it belongs to. In full mode the sweep's own optima
# at the paper's pair of weights are printed first in this section: whether they form a near-mirror pair, as in
# the paper's Fig. 7, is then a matter of which side round-off sent each one to (closing table).

# %% [markdown]
# ## 8 · Figure 8: thrust profiles for $\alpha_h = 5\times10^{-3}$ and $2\times10^{-2}$
#
# The node accelerations (first-order hold in between), each component and the magnitude, with the bound and the
# observation window (zero thrust imposed) shaded. Out-of-plane thrust $a_z$ appears in both.

# %%
fig, axes = plt.subplots(1, 2, figsize=(13, 4), sharey=True)
days = em.tu_to_days(t)
for ax, a_want in zip(axes, (5e-3, 2e-2)):
    a = pick(a_want)["alpha"]
    u = by_alpha[a]["res"].u * em.acceleration_unit_km_s2 * 1e6  # mm/s^2
    for i, name in enumerate(("a_x", "a_y", "a_z")):
        ax.plot(days, u[:, i], ".-", lw=1, label=f"${name}$")
    ax.plot(days, np.linalg.norm(u, axis=1), "k-", lw=1.4, label="|a|")
    ax.axhline(sc.a_max * em.acceleration_unit_km_s2 * 1e6, color="0.4", ls=":", lw=1, label="a_max")
    ax.axvspan(ws_d, we_d, color="0.9", zorder=0, label="observation window")
    ax.set(xlabel="time [days]", title=rf"$\alpha_h$ = {a:g}")
axes[0].set_ylabel("thrust acceleration [mm/s$^2$]")
fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=6, fontsize=8, bbox_to_anchor=(0.5, -0.02))
fig.tight_layout(rect=(0, 0.08, 1, 1))
_ = plotting.save_figure(fig, "06_fig8_thrust_profiles", output_dir=out)

# %% [markdown]
# ## 9 · Figure 9: CRLB over the window, and the process-noise units
#
# The EKF covariance recursion along the true trajectories (the paper's "Performance Evaluation"), with the process
# noise recomputed along each trajectory: position RMS $\sqrt{\mathrm{tr}P_{rr}}$ of the observer and each target
# over the window, for $\alpha_h = 5\times10^{-3}$ and $2\times10^{-2}$, and the minimum-$\Delta V$ case
# $\alpha_h = 0$ in grey (weakly observable: range and range rate from a coplanar observer leave directions
# unobserved).

# %%
names = ["observer", "target 1", "target 2", "target 3"]
fig, axes = plt.subplots(1, 4, figsize=(15, 3.8), sharey=True)
fig9_alphas = [pick(a)["alpha"] for a in (0.0, 5e-3, 2e-2)]
for i, ax in enumerate(axes):
    for a, color in zip(fig9_alphas, ("0.6", "C0", "C3")):
        c = by_alpha[a]["crlb"]
        ax.semilogy(em.tu_to_days(c.t), c.rms_km[i], "o-", ms=2.5, color=color, label=rf"$\alpha_h$ = {a:g}")
    ax.set(xlabel="time [days]", title=names[i])
axes[0].set_ylabel("position RMS (CRLB) [km]")
fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=3, fontsize=8, bbox_to_anchor=(0.5, -0.02))
fig.tight_layout(rect=(0, 0.08, 1, 1))
_ = plotting.save_figure(fig, "06_fig9_crlb", output_dir=out)
obs_mean = {a: float(np.mean(by_alpha[a]["crlb"].rms_km[0])) for a in fig9_alphas[1:]}
tgt_mean = {a: float(np.mean(by_alpha[a]["crlb"].rms_km[1:])) for a in fig9_alphas[1:]}
print("mean RMS over the window, observer vs targets [km]:",
      {a: (round(obs_mean[a], 1), round(tgt_mean[a], 1)) for a in obs_mean})


def relative_rms_km(x_window_start):
    """Terminal position RMS (km) of each object, of each target relative to the observer, and of the mean
    position of all four (the common part), from the same CRLB recursion as Fig. 9."""
    tm = sc.measurement_times
    lin = cov.linearize_augmented(em, x_window_start, sc.targets_at([tm[0]])[:, 0], tm, sc.model, sc.noise,
                                  sc.prior_covariance, q=sc.q)
    P = cov.covariance_analysis(*lin.arrays).posterior[-1]
    sel = lambda w: np.hstack([wi * np.hstack([np.eye(3), np.zeros((3, 3))]) for wi in w])  # noqa: E731
    rms = lambda w: float(np.sqrt(np.trace(sel(w) @ P @ sel(w).T)) * em.length_unit_km)  # noqa: E731
    n = sc.n_targets + 1
    return (np.array([rms(np.eye(n)[i]) for i in range(n)]),
            np.array([rms(np.eye(n)[0] - np.eye(n)[i]) for i in range(1, n)]), rms(np.full(n, 1.0 / n)))


common = {}
for a in fig9_alphas:
    ab, rl, cm = relative_rms_km(by_alpha[a]["res"].x[k_ws])
    common[a] = (ab, rl, cm)
    print(f"alpha {a:g}, window end: position RMS {np.round(ab, 1)} km (observer, targets); target relative to "
          f"observer {np.round(rl, 1)} km; mean position of all four {cm:.1f} km")

# %% [markdown]
# **Why the four panels look alike.** Range and range rate measure relative positions only. With $\alpha_h > 0$
# they pin each target's position relative to the observer far more tightly than any absolute position (printed
# above: the relative RMS is a small fraction of the absolute one), so the four spacecraft carry almost the same
# absolute error, the error of their common mean position, which only the differences in their dynamics reveal.
# At $\alpha_h = 0$ (grey) the reason differs: all four fly planar DROs and no measurement reaches the
# out-of-plane errors (notebook 02), which grow alike from the identical priors; the relative RMS is then not
# small. The same holds for the target curves of Fig. 10 below, which lie on the observer's.

# %% [markdown]
# **Process-noise units.** Tables 3 and 5 print "$Q$ [km/s³] = $10^{-11}$". The candidate readings (an
# acceleration PSD has units km²/s³): the literal value with the square restored, the same number in the code's
# normalised units LU²/TU³, in SI m²/s³, or as a square-root PSD. The paper's test case 1 text says that after the
# initial transient "subsequent measurements serve to bound the expected error". Below, the CRLB of test case 1's
# ballistic observer (where the evidence is sharpest) and the terminal RMS of this case's ballistic and
# $\alpha_h = 10^{-2}$ trajectories under each reading. The 1e-11 km²/s³ reading lets test case 1's errors grow to
# tens of thousands of km (a one-day velocity random walk of 0.9 m/s, comparable to test case 1's 0.4 m/s minimum-impulse budget);
# the three small readings stay bounded, but not alike: their terminal RMS values differ by the factors printed
# below the table. We adopt the normalised one (`PROCESS_NOISE_PSD_ND`), choosing it *because* it keeps the
# CRLB bounded as the paper says, so the "bounded" claims are no independent test of it ("consistent (tuned)" in
# the closing tables). The paper's text cannot decide among the three small readings (all stay bounded, which is
# all it says); the choice sets the level of every absolute RMS in notebooks 05 and 06.

# %%
sc1 = wj.test_case_1()
x1_ws = propagate(em, sc1.observer_x0, [0.0, sc1.window[0]]).x[-1]
fig, ax = plt.subplots(figsize=(7, 4))
noise_rows = []
for n_, (label, q_km) in enumerate(wj.PROCESS_NOISE_READINGS_KM2_S3.items()):
    q_nd = cov.psd_to_nondimensional(q_km, em)
    c1 = wj.evaluate_crlb(sc1, x1_ws, q=q_nd)
    ax.semilogy(em.tu_to_days(c1.t), c1.rms_km[0], "o-", ms=3, label=label)
    c2b = wj.evaluate_crlb(sc, x_ws_ball, q=q_nd).terminal_rms_km[0]
    c2i = wj.evaluate_crlb(sc, row6["res"].x[k_ws], q=q_nd).terminal_rms_km[0]
    noise_rows.append((label, q_km, c1.terminal_rms_km[0], float(np.max(c1.rms_km[0])), c2b, c2i))
ax.set(xlabel="time [days]", ylabel="observer position RMS [km]",
       title=r"Test case 1, ballistic observer: CRLB under each reading of Q")
handles_q, labels_q = ax.get_legend_handles_labels()
ax.legend(handles_q, [re.sub(r"\^(\d)", r"$^\1$", lab) for lab in labels_q], fontsize=7, loc="upper left")
_ = plotting.save_figure(fig, "06_process_noise_readings", output_dir=out)
print(f"{'reading':<48}{'q [km^2/s^3]':>13}{'TC1 end':>10}{'TC1 peak':>10}{'TC2 a=0 end':>12}{'TC2 a=' + format(a6, 'g') + ' end':>15}")
for label, q_km, e1, p1, e2b, e2i in noise_rows:
    print(f"{label:<48}{q_km:>13.2e}{e1:>10.0f}{p1:>10.0f}{e2b:>12.0f}{e2i:>15.1f}")
small = [r_ for r_ in noise_rows if r_[1] < 1e-12]  # the three small readings
q_spread = (max(r_[2] for r_ in small) / min(r_[2] for r_ in small), max(r_[5] for r_ in small) / min(r_[5] for r_ in small))
print(f"spread of the terminal RMS over the {len(small)} small readings: test case 1 {q_spread[0]:.1f}x, test case 2 "
      f"(alpha_h = {a6:g}) {q_spread[1]:.1f}x")

# %% [markdown]
# ## 10 · Figure 10: the Pareto fronts
#
# Total impulse (trapezoid of Eq. 42; the paper's "average impulse" is not defined further, any constant divisor
# leaves the front's shape unchanged) against the terminal position RMS at the window end, observer (left) and
# targets (right). The MI itself is plotted against the same RMS to test the paper's claim that "the mutual
# information correlates well with the expected performance of a sequential estimator".

# %%
dvs = np.array([r["dv"] for r in ok])
rms_obs = np.array([r["crlb"].terminal_rms_km[0] for r in ok])
rms_tgt = np.array([r["crlb"].terminal_rms_km[1:] for r in ok])
mis = np.array([r["mi"] for r in ok])
fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
axes[0].loglog(np.maximum(dvs, 1e-3), rms_obs, "o-")
for n_, (r, x_, y_) in enumerate(zip(ok, dvs, rms_obs)):  # every point labelled, alternately above and below
    up = n_ % 2 == 0
    axes[0].annotate(rf"$\alpha_h$ = {r['alpha']:g}" if n_ == 0 else f"{r['alpha']:g}", (x_, y_),
                     textcoords="offset points", xytext=(5, 6) if up else (-5, -8), ha="left" if up else "right",
                     va="bottom" if up else "top", fontsize=7)
axes[0].set(xlabel=r"total impulse $\Delta V$ [m/s]", ylabel="terminal position RMS [km]", title="observer")
for i, (mk, ls) in enumerate((("o", "-"), ("s", "--"), ("^", ":"))):
    axes[1].loglog(np.maximum(dvs, 1e-3), rms_tgt[:, i], marker=mk, ls=ls, ms=8 - 2 * i, label=f"target {i + 1}")
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
for ax in axes[:2]:  # plain impulse ticks (a log axis spanning one decade would print a single label)
    ticks = [v for v in (1, 2, 5, 10, 20, 50, 100, 200) if 0.7 * dvs.min() <= v <= 1.4 * dvs.max()]
    ax.set_xticks(ticks, [f"{v:g}" for v in ticks])
    ax.xaxis.set_minor_formatter(plt.NullFormatter())
    ax.set_xlim(0.8 * dvs.min(), 1.6 * dvs.max())
fig.tight_layout()
_ = plotting.save_figure(fig, "06_fig10_pareto", output_dir=out)
rank_obs = spearmanr(mis, rms_obs).statistic
rank_tgt = spearmanr(mis, rms_tgt.mean(axis=1)).statistic
mono_dv = bool(np.all(np.diff(dvs) >= -1e-9 * np.max(dvs)))
mono_mi = bool(np.all(np.diff(mis) >= -1e-9 * np.max(mis)))
print(f"Spearman rank correlation MI vs terminal RMS: observer {rank_obs:.3f}, targets {rank_tgt:.3f}; "
      f"impulse non-decreasing in alpha: {mono_dv}; MI non-decreasing: {mono_mi}")
dominated = []  # (alpha, index, alpha of a cheaper plan with lower or equal RMS, its index)
for i_ in range(len(ok)):
    j_ = next((j_ for j_ in range(len(ok)) if dvs[j_] < dvs[i_] and rms_obs[j_] <= rms_obs[i_]), None)
    if j_ is not None:
        dominated.append((ok[i_]["alpha"], i_, ok[j_]["alpha"], j_))
print("plans worse on both axes than a cheaper plan (observer): " + (", ".join(
    f"alpha {a:g} ({dvs[i_]:.2f} m/s, {rms_obs[i_]:.1f} km) vs alpha {b:g} ({dvs[j_]:.2f} m/s, {rms_obs[j_]:.1f} km)"
    for a, i_, b, j_ in dominated) or "none"))

# %% [markdown]
# ## 11 · Beyond the paper
#
# **Re-flight.** Each converged control is flown by single shooting from the initial state (table in section 4:
# terminal miss in km), so the trajectories are real and not an artefact of the virtual control.
#
# **Baseline against information trajectories, at equal impulse.** The paper claims "substantial improvement over
# a baseline comparison which utilizes solely control effort". The $\alpha_h = 0$ baseline is the minimum-impulse
# transfer: nothing spends less, so the fair question is what a given *extra* impulse buys. SCvx has no impulse
# constraint, but the weighted-sum front's impulse grows with $\alpha_h$, so solving for the $\alpha_h$ whose
# optimum spends a prescribed budget (`wolf_jones.solve_for_impulse`, budget met within 2 %, fixed before
# solving) gives the most informative plan at that impulse. We do it for the baseline's impulse plus 5 m/s.
#
# **The keep-out radius, swept.** The 424 km keep-out is our choice, not the paper's, and it is active in several
# solutions of the sweep (section 4: closest approach 424.3 km). Which of the paper's claims rest on it? At the
# Fig. 6 weight we solve from the ballistic guess with other radii, and once without any keep-out: does the
# optimum follow the keep-out towards the target as it shrinks, and what happens to impulse, information and
# terminal RMS? The answers are printed below the radius table, one line per radius: a radius well below 424 km
# whose solve converges, inactive, to the 424 km plan would show that the active keep-out only nudges a local
# optimum that exists without it; trajectories more than 100 km apart anywhere (compared node by node, a threshold
# fixed in advance) mean another local optimum; a radius whose solve fails
# leaves the question open there.
# Without any keep-out the iterates reach a cost below the constrained optimum's with defects still open; the
# closest approach to a target of its successive references (recorded along the run, printed below) shows whether
# they head for the close-approach singularity. Which local optimum a solve finds is fragile: the planar guess is a saddle
# (section 2) and round-off picks the way out of it, so a change as small as another evaluation order of the MI
# gradient can move a run of this section, or of the sweep, to a neighbouring optimum. In the figure each radius is
# a separate solve, so its points are not joined (neighbouring radii can land in different local optima); the dashed
# lines give the sweep's optima at the neighbouring weights of the $\alpha_h$ grid as a yardstick for the size of the
# differences.
#
# **a_max readings.** One run at the Fig. 6 weight under each reading of Table 5's "1x5^-7" (warm-started from
# the adopted solution).

# %%
base = by_alpha.get(0.0)
cheap = next((r for r in ok if r["alpha"] > 0), None)
best = min(ok, key=lambda r: r["crlb"].terminal_rms_km[0])
if base and cheap:
    print(f"baseline alpha 0: dV {base['dv']:.2f} m/s, observer RMS {base['crlb'].terminal_rms_km[0]:.0f} km; "
          f"alpha {cheap['alpha']:g}: dV {cheap['dv']:.2f} m/s (+{cheap['dv'] - base['dv']:.2f}), RMS "
          f"{cheap['crlb'].terminal_rms_km[0]:.0f} km ({base['crlb'].terminal_rms_km[0] / cheap['crlb'].terminal_rms_km[0]:.0f}x "
          f"better); best alpha {best['alpha']:g}: dV {best['dv']:.2f} m/s, RMS {best['crlb'].terminal_rms_km[0]:.1f} km")
# queue the independent runs (keep-out off, other radii, a_max readings); the budget search runs meanwhile here
radius_solvers = {d: wj.ScenarioSolver(sc, t, k_ws, information=info, keep_out=True, d_min_km=d,
                                       settings=solver.settings) for d in D_MIN_KM}
amax_solvers = {label: wj.ScenarioSolver(wj.test_case_2(a_max_km_s2=a_km), t, k_ws, information=info, keep_out=True,
                                         settings=solver.settings)
                for label, a_km in wj.A_MAX_READINGS_CASE2_KM_S2.items() if a_km != wj.A_MAX_CASE2_KM_S2}
jobs = {}
# radii solved from the ballistic guess (quick mode: warm from the adopted solution, cheaper)
d_guess = (row6["res"].x, row6["res"].u) if QUICK else (x_ball, u_ball)
jobs.update({("d_min", d): executor.submit(s_, a6, *d_guess) for d, s_ in radius_solvers.items()})
jobs.update({label: executor.submit(s_, a6, row6["res"].x, row6["res"].u) for label, s_ in amax_solvers.items()})

budget_row = None
if base:
    b_mps = base["dv"] + BUDGET_EXTRA_MPS
    j = next((i for i, r in enumerate(ok) if r["dv"] >= b_mps), None)
    if j is None or j == 0:
        print(f"budget {b_mps:.2f} m/s outside the swept front; not solved")
    else:
        try:
            hit = wj.solve_for_impulse(solver, b_mps / (em.velocity_unit_km_s * 1e3),
                                       (ok[j - 1]["alpha"], ok[j - 1]["res"]), (ok[j]["alpha"], ok[j]["res"]),
                                       rtol=BUDGET_RTOL)
            c_hit = wj.evaluate_crlb(sc, hit.result.x[k_ws])
            budget_row = dict(budget=b_mps, alpha=hit.alpha, dv=dv(hit.result), rms=c_hit.terminal_rms_km[0],
                              rms_tgt=float(np.mean(c_hit.terminal_rms_km[1:])), solves=len(hit.solves),
                              interp=float(np.exp(np.interp(dv(hit.result), [r["dv"] for r in ok],
                                                            np.log([r["crlb"].terminal_rms_km[0] for r in ok])))))
            print(f"budget {b_mps:.2f} m/s (baseline + {BUDGET_EXTRA_MPS:g}): alpha_h = {hit.alpha:.3e} spends "
                  f"{budget_row['dv']:.2f} m/s ({budget_row['solves']} solves); observer RMS {budget_row['rms']:.1f} km"
                  f" vs {base['crlb'].terminal_rms_km[0]:.0f} km at the baseline's {base['dv']:.2f} m/s "
                  f"(log-interpolation on the grid at the spent impulse said {budget_row['interp']:.1f} km)")
        except (wj.ImpulseBudgetError, scvx.SCvxError) as exc:
            print(f"budget {b_mps:.2f} m/s not reached: {exc}")



class RecordingInformation:
    """The information model, recording the window-start state of every gradient call (= every SCvx reference)."""

    def __init__(self, inner):
        self.inner, self.refs = inner, []

    def __call__(self, x, order=0):
        if order >= 1:
            self.refs.append(np.array(x, dtype=float))
        return self.inner(x, order)

    def __getattr__(self, name):
        return getattr(self.inner, name)


# the run without keep-out here in the main process, so that its references can be recorded
rec_info = RecordingInformation(info)
free = wj.ScenarioSolver(sc, t, k_ws, information=rec_info, keep_out=False,
                         settings=scvx.SCvxSettings(max_iter=FREE_ITER))
try:
    nk = free(a6, x_ball, u_ball)
except scvx.SCvxError as exc:
    nk = exc
nk_ref_range = np.array([ko.ranges(x_).min() for x_ in rec_info.refs]) * em.length_unit_km
extra = {"no keep-out": nk}
for key, fut in jobs.items():
    try:
        extra[key] = fut.result()
    except scvx.SCvxError as exc:
        extra[key] = exc
nk = extra["no keep-out"]
nk_cost = np.nan
if isinstance(nk, scvx.SCvxError):
    nk_range = np.nan
    acc = [h["new_cost"] for h in nk.history if h.get("accepted")]
    nk_cost = min(acc) if acc else np.nan
    print(f"without the keep-out SCvx did not converge: {nk.reason}; best accepted cost {nk_cost:.5f} (defects not "
          f"yet closed) vs {row6['res'].cost:.5f} of the constrained optimum")
    print(f"closest approach to a target at a measurement over its {nk_ref_range.size} references: last "
          f"{nk_ref_range[-1]:.1f} km, smallest {nk_ref_range.min():.1f} km (first {nk_ref_range[0]:.0f} km)")
else:
    nk_range = float(ko.ranges(nk.x[k_ws]).min() * em.length_unit_km)
    print(f"without the keep-out (alpha {a6:g}): closest approach {nk_range:.3f} km at a measurement, MI "
          f"{nk.information:.2f} nats vs {row6['mi']:.2f} with it")
radius_rows = [dict(d=sc.keep_out_km, src="sweep", dv=row6["dv"], mi=row6["mi"], rms=row6["crlb"].terminal_rms_km[0],
                    x=row6["res"].x,
                    closest=row6["min_range_km"], z=row6["z_max_km"])]
for d in D_MIN_KM:
    res = extra[("d_min", d)]
    if isinstance(res, scvx.SCvxError):
        print(f"keep-out {d:g} km: no convergence ({res.reason})")
        continue
    radius_rows.append(dict(d=d, src="warm" if QUICK else "cold", dv=dv(res), mi=res.information,
                            rms=wj.evaluate_crlb(sc, res.x[k_ws]).terminal_rms_km[0],
                            closest=float(ko.ranges(res.x[k_ws]).min() * em.length_unit_km), x=res.x,
                            z=float(np.max(np.abs(res.x[:, 2])) * em.length_unit_km)))
radius_rows.sort(key=lambda r: r["d"])
print(f"alpha_h = {a6:g}: {'keep-out [km]':>13} {'start':>6} {'dV [m/s]':>9} {'MI [nats]':>10} {'RMS obs [km]':>13} "
      f"{'closest [km]':>13} {'binds':>6} {'max|z| [km]':>11}")
SAME_PLAN_KM = 100.0  # two plans count as the same if their node positions are never farther apart (fixed in advance)
for r in radius_rows:
    r["binds"] = r["closest"] <= r["d"] * (1 + 1e-3)
    r["apart"] = float(np.max(np.linalg.norm((r["x"] - row6["res"].x)[:, :3], axis=1)) * em.length_unit_km)
    print(f"{'':>14}{r['d']:>13.0f} {r['src']:>6} {r['dv']:>9.2f} {r['mi']:>10.2f} {r['rms']:>13.1f} "
          f"{r['closest']:>13.1f} {str(r['binds']):>6} {r['z']:>11.0f}")
for d in D_MIN_KM:
    if d >= sc.keep_out_km:
        continue
    r = next((r_ for r_ in radius_rows if r_["d"] == d), None)
    if r is None:
        print(f"keep-out {d:g} km (below the adopted one): solve failed, question open at this radius")
    else:
        same_plan = r["apart"] <= SAME_PLAN_KM
        print(f"keep-out {d:g} km (below the adopted one): {'active' if r['binds'] else 'inactive'} at its optimum, "
              f"impulse {r['dv']:.2f} vs {row6['dv']:.2f} m/s, closest approach {r['closest']:.0f} vs "
              f"{row6['min_range_km']:.0f} km, max|z| {r['z']:.0f} vs {row6['z_max_km']:.0f} km, RMS {r['rms']:.1f} vs "
              f"{row6['crlb'].terminal_rms_km[0]:.1f} km; the two trajectories lie up to {r['apart']:.0f} km apart: "
              + (f"the 424 km plan (within {SAME_PLAN_KM:g} km)" if same_plan else
                 f"a neighbouring local optimum (more than {SAME_PLAN_KM:g} km apart)"))
fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
dd = np.array([r["d"] for r in radius_rows])
i6 = next(n_ for n_, r in enumerate(ok) if r["alpha"] == a6)
neighbours = [ok[n_] for n_ in (i6 - 1, i6 + 1) if 0 <= n_ < len(ok)]  # the sweep's optima at the adjacent weights
for ax, key, lab in ((axes[0], "mi", "mutual information of the window [nats]"),
                     (axes[1], "rms", "terminal observer position RMS [km]")):
    yy = np.array([r[key] for r in radius_rows])
    bind = np.array([r["binds"] for r in radius_rows])
    ax.semilogx(dd[bind], yy[bind], "o", ms=7, color="C3", label="keep-out active at the optimum")
    ax.semilogx(dd[~bind], yy[~bind], "o", ms=7, mfc="white", color="C0", label="keep-out inactive")
    for nb in neighbours:  # yardstick: what a step of alpha_h on the grid changes
        v = nb["mi"] if key == "mi" else nb["crlb"].terminal_rms_km[0]
        ax.axhline(v, color="0.5", ls="--", lw=1)
        ax.text(0.99, v, rf"sweep, $\alpha_h$ = {nb['alpha']:g}", transform=ax.get_yaxis_transform(), ha="right",
                va="bottom", fontsize=7, color="0.35")
    ax.axvline(sc.keep_out_km, color="0.5", ls=":", lw=1)
    ax.set(xlabel="keep-out radius $d_{min}$ [km]", ylabel=lab)
    ax.set_xticks(dd, [f"{d:.0f}" for d in dd])  # the radii themselves (the span can be under a decade)
    ax.xaxis.set_minor_formatter(plt.NullFormatter())
    ax.set_xlim(dd.min() / 1.5, dd.max() * 1.5)
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo - 0.08 * (hi - lo), hi + 0.08 * (hi - lo))
fig.legend(*axes[0].get_legend_handles_labels(), fontsize=8, loc="lower center", ncol=2)
fig.suptitle(rf"Keep-out radius swept at $\alpha_h$ = {a6:g} (dotted: adopted 424 km; dashed: the neighbouring "
             r"$\alpha_h$ of the grid, for scale)")
fig.tight_layout(rect=(0, 0.07, 1, 1))
_ = plotting.save_figure(fig, "06_keep_out_sweep", output_dir=out)
amax_rows = []
for label, res in extra.items():
    if label not in amax_solvers:
        continue
    s_ = amax_solvers[label]
    if isinstance(res, scvx.SCvxError):
        print(f"a_max {label}: failed ({res.reason})")
        continue
    u_norm = np.linalg.norm(res.u, axis=1)
    ratio = float(np.max(u_norm[s_.u_max > 0] / s_.u_max[s_.u_max > 0]))
    rms = wj.evaluate_crlb(sc, res.x[k_ws]).terminal_rms_km[0]
    amax_rows.append((label, dv(res), rms, ratio))
    print(f"a_max {label}: dV {dv(res):.2f} m/s, observer RMS {rms:.1f} km, largest |u|/a_max {ratio:.2f}")
print(f"a_max 5e-7 (adopted): dV {row6['dv']:.2f} m/s, observer RMS "
      f"{row6['crlb'].terminal_rms_km[0]:.1f} km, largest |u|/a_max {row6['u_ratio']:.2f}")
rank_radii = (float(spearmanr([r["mi"] for r in radius_rows], [r["rms"] for r in radius_rows]).statistic)
              if len(radius_rows) >= 3 else None)  # fewer than 3 radii: no rank correlation worth the name
print(f"across keep-out radii at alpha_h = {a6:g}: Spearman(MI, terminal RMS) "
      + (f"{rank_radii:+.2f}" if rank_radii is not None else f"not computed ({len(radius_rows)} radii)"))
radii_text = (f"{rank_radii:+.2f} across keep-out radii at alpha {a6:g}" if rank_radii is not None else
              f"across keep-out radii not computed ({len(radius_rows)} radii)")
bound_rms = row6["crlb"].terminal_rms_km[0]
better_resolves = ([f"keep-out {r['d']:.0f} km: {r['rms']:.1f} km at {r['dv']:.2f} m/s" for r in radius_rows
                    if r["d"] != sc.keep_out_km and r["rms"] < bound_rms]
                   + [f"a_max {lab}: {r_:.1f} km at {d:.2f} m/s" for lab, d, r_, q_ in amax_rows if r_ < bound_rms])
dominated_note = "no dominated plan"
if dominated:
    dominated_note = ("closest approach at the dominated weights " + ", ".join(
        f"{a:g}: {by_alpha[a]['min_range_km']:.0f} km" for a, _, _, _ in dominated)
        + f" (keep-out {sc.keep_out_km:.0f} km, binding if equal)")
    if a6 in [a for a, _, _, _ in dominated] and better_resolves:
        dominated_note += (f"; re-solves at alpha {a6:g} reach a lower RMS than the sweep's {bound_rms:.1f} km: "
                           + "; ".join(better_resolves) + "; the Fig. 6/10 plan there is a keep-out-bound local "
                           "optimum")
print("front:", dominated_note)
executor.shutdown()
print(f"notebook compute time {time.perf_counter() - t_start:.0f} s")

# %% [markdown]
# ## 12 · Paper versus reproduction
#
# Tolerances fixed before comparing: the window ends to the paper's "roughly" (±1 day); "out-of-plane motion" means
# more than 100 km out of plane; "weakly observable at $\alpha_h = 0$" means a terminal observer RMS at least five
# times that of every $\alpha_h > 0$; "correlates well" means a Spearman rank correlation of MI against terminal RMS
# below -0.8; the observer "on average" better than the targets means a window-mean RMS at least 10 % lower than
# the targets' mean; the front is monotone if no plan has both more impulse and a higher RMS than another. Rows
# resting on a reading chosen with the paper's claim in view (process noise, the Table 2/4 slip) are at best
# "consistent (tuned)"; imposed inputs (zero thrust in the window) are "derived", not predictions.

# %%
chk_obs = sc.row_checks["observer_t0"]
u_bind = max(r["u_ratio"] for r in ok)
table.add_typed("Table 4 observer x_S(t0) is a periodic DRO", "implied (DRO family)",
          f"closure after one period {chk_obs.raw_closure:.2f} (non-dimensional); vy0 off by "
          f"{chk_obs.vy0_correction:+.4f} LU/TU", "differs: printed vy0 is not periodic",
          f"corrected holding x0 (same row as Table 2; notebook 05 argues this reading from the span of the other "
          f"rows); period {em.tu_to_days(chk_obs.corrected.period):.2f} d")
others = [c for lab, c in sc.row_checks.items() if lab != "observer_t0"]
table.add_typed("Table 4 other rows periodic", "implied", f"closures <= {max(c.raw_closure for c in others):.1e}",
          "reproduced" if max(c.raw_closure for c in others) < CLOSURE_TOL else "differs: a row does not close",
          f"criterion: closure < {CLOSURE_TOL:g} (nine printed digits allow ~1e-8)")
table.add_typed("Table 5 title", '"Scenario Parameters for Test Case #1"', "parameters are test case 2's",
          "differs: title slip", "range/range-rate noise and three targets belong to test case 2")
table.add_typed("Table 5 a_max", '"1x5^-7" km/s^2', f"5e-7 km/s^2; others: " + "; ".join(
    f"{lab}: dV {d:.1f} m/s, RMS {r_:.1f} km, |u|/a_max {q_:.2f}" for lab, d, r_, q_ in amax_rows),
    "derived", "read as 5x10^-7 (half of test case 1's; the literal 5^-7 = 1.28e-5 km/s^2 is 13x case 1's); "
    + (f"at 5e-7 the bound never binds on the grid (largest |u|/a_max {u_bind:.2f}), so a larger reading changes "
       "nothing but the local optimum found, a smaller one binds" if u_bind < 0.99 else
       f"at 5e-7 the bound binds (largest |u|/a_max {u_bind:.2f})"))
table.add_typed("Table 3/5 process noise Q", '1e-11 "km/s^3"', "1e-11 LU^2/TU^3 = 2.80e-17 km^2/s^3", "consistent (tuned)",
          "chosen as a reading that keeps test case 1's CRLB bounded, the paper's own claim (section 9); 1e-11 "
          f"km^2/s^3 makes it grow to {noise_rows[0][2]:.0f} km; the three small readings all stay bounded and give "
          f"terminal RMS values {q_spread[0]:.1f}x (case 1) and {q_spread[1]:.1f}x (case 2) apart")
table.add_typed("Observation window", "roughly 17-32 days", f"[P, 2P] = {ws_d:.2f}-{we_d:.2f} d",
          "consistent (tuned)" if abs(ws_d - 17) <= 1 and abs(we_d - 32) <= 1 else "differs: window ends",
          "tolerance +-1 day ('roughly'); P of the corrected observer DRO, whose reading (x0 held) was first chosen "
          "with these day counts in view; notebook 05 supports it independently (x0 and period inside the span of "
          f"the other rows) and lists the text's '23 days' of test case 1, missed by "
          f"{abs(1.5 * em.tu_to_days(sc.period) - 23.0):.2f} d")
nk_failed = isinstance(nk, scvx.SCvxError)
small_fail = [d for d in D_MIN_KM if isinstance(extra[("d_min", d)], scvx.SCvxError)]
table.add_typed("SCvx converges for every alpha_h without a keep-out (our modified solver)", "implied (Figs. 7, 10)",
          f"alpha_h = {a6:g} without keep-out: " + (nk.reason.split(":")[0] if nk_failed else "converged")
          + ("; keep-out " + ", ".join(f"{d:g} km" for d in small_fail) + ": no convergence" if small_fail else ""),
          "differs: without a keep-out even our modified solver does not converge (convex subproblem fails)"
          if nk_failed else "reproduced",
          "the paper has no keep-out; our solver departs from the printed one (augmented Lagrangian, quadratic MI "
          "model, changed acceptance); the printed formulation was not run on this case (notebook 05: the printed "
          "L1 penalty does not converge on test case 1)")
table.add_typed("modified SCvx with a 424 km keep-out converges for every alpha_h", "-",
          f"{len(ok)}/{len(ALPHAS)} alphas; {len(failed)} of {len(sweep.attempts)} runs failed; largest defect "
          f"{max(r['res'].max_defect for r in ok):.0e}", "beyond paper",
          f"keep-out active in {n_bind} of {sum(r['alpha'] > 0 for r in ok)} plans with alpha_h > 0")
table.add_typed("Single-shooting re-flight of the converged controls", "not in paper",
          f"largest terminal miss {max(r['miss_km'] for r in ok):.1e} km", "beyond paper",
          "first-order-hold control flown from x_S(t0)")
z6 = row6["z_max_km"]
table.add_typed("Fig. 6: out-of-plane motion at alpha_h = 1e-2", "yes", f"max |z| = {z6:.0f} km (alpha {a6:g})",
          "reproduced" if z6 > 100 else "differs: the solution stays (nearly) planar", "threshold 100 km")
same_free = [r for r in radius_rows if r["d"] < sc.keep_out_km and not r["binds"] and r["apart"] <= SAME_PLAN_KM]
robust = dep_pass == len(rho_grids)
table.add_typed("Fig. 7: departure grows with alpha_h", "generally", f"Spearman(alpha, max departure) = {rho_dep:.2f}; "
          + ", ".join(f"{r['alpha']:g}: {d_ / 1e3:.1f}" for r, d_ in zip(ok, dep_max)) + " (10^3 km); other node "
          "grids: " + ", ".join(f"{n_} nodes {v:.2f}" for n_, v in rho_grids.items() if n_ != N_NODES),
          ("reproduced" if robust else f"differs: not robust, Spearman above 0.8 on {dep_pass} of "
           f"{len(rho_grids)} node grids"),
          "largest distance from the reference DRO over the scenario; threshold Spearman 0.8 on every node grid "
          "(fixed in advance); which local optimum a weight lands in moves with the grid and with round-off "
          "(fixed in advance); which local optimum a weight lands in moves with the grid and with round-off (an "
          "earlier run with a gradient differing by ~1e-8 relative gave 0.69), so one grid's value alone is fragile")
if zsign is not None:
    table.add_typed("Fig. 7: the 5e-3 and 7e-3 solutions are near-mirror images across z = 0", "yes (Fig. 7)",
              f"z at the window end {zsign[0]:+.0f} km ({pair[0]['alpha']:g}), {zsign[1]:+.0f} km "
              f"({pair[1]['alpha']:g}); largest distance to the other's mirror {d_mir:.0f} km, unmirrored "
              f"{d_same:.0f} km", "reproduced" if d_mir < d_same else
              "differs: the sweep's two optima lie closer to each other than to each other's mirror",
              "criterion: one closer to the mirror of the other than to the other itself; which side an optimum "
              "leaves the plane on is picked by round-off (planar guess is a saddle), so either outcome is an "
              "accident of the run, and the seeded rows below make the mirror pair on purpose")
table.add_typed("Fig. 7 z-mirror: the mirror of an optimum is an optimum", "postulated family of symmetric optima",
          f"alpha {row_m['alpha']:g}: mirrored optimum re-solved in {twin.iterations} iterations, cost difference "
          f"{twin_dcost:.0e}, distance to the exact mirror {twin_km:.2f} km", "beyond paper",
          "exact z-symmetry of CR3BP, planar DROs and range/range-rate; criterion: cost within 1e-6 relative and "
          f"trajectory within 1 km of the mirror: {twin_dcost <= 1e-6 and twin_km <= 1.0}")
if mirror_rows:
    worst_mis = max(m_[4] for m_ in mirror_rows)
    worst_dc = max(m_[3] for m_ in mirror_rows)
    same = worst_mis <= 1.0 and worst_dc <= 1e-6
    table.add_typed("Fig. 7: +z and -z seeds at alpha_h = 5e-3 and 7e-3", "near-mirror solutions (Fig. 7)",
              ("seeds converge to mirror images" if same else "seeds converge to different local optima")
              + f": cost difference {worst_dc:.0e}, distance to mirror {worst_mis:.2f} km; seeded costs "
              + ", ".join(f"{m_[5]:.4f} (sweep best {m_[6]:.4f})" for m_ in mirror_rows), "beyond paper",
              "criterion: within 1 km and 1e-6 relative cost; the planar guess is a saddle, the sign is picked by "
              "round-off or the seed")
table.add_typed("Fig. 8: zero thrust in the window", "a_max = 0 in the window",
          f"max |u| in window {max(r['u_window'] for r in ok):.0e}", "derived",
          "imposed input (zero bound at every window node), not a prediction")
az_used = [np.max(np.abs(r["res"].u[:, 2])) > 1e-3 * sc.a_max for r in ok if r["alpha"] > 0]
table.add_typed("Fig. 8: out-of-plane thrust a_z used", "yes", f"a_z above 0.1 % of a_max in {sum(az_used)} of "
          f"{len(az_used)} plans with alpha_h > 0", "reproduced" if all(az_used) else "differs: some plans stay planar",
          "criterion: max |a_z| > 1e-3 a_max in every plan with alpha_h > 0")
if base:
    other = [r["crlb"].terminal_rms_km[0] for r in ok if r["alpha"] > 0]
    weak = base["crlb"].terminal_rms_km[0] >= 5 * max(other)
    table.add_typed("Fig. 9: alpha_h = 0 weakly observable (grey)", "yes",
              f"terminal observer RMS {base['crlb'].terminal_rms_km[0]:.0f} km vs <= {max(other):.0f} km",
              "reproduced" if weak else "differs: the baseline is not much worse", "factor 5 fixed in advance")
if obs_mean:
    gap_mean = {a: 1 - obs_mean[a] / tgt_mean[a] for a in obs_mean}
    gap_end = {a: 1 - common[a][0][0] / np.mean(common[a][0][1:]) for a in obs_mean}
    better = all(g_ >= 0.10 for g_ in gap_mean.values())
    table.add_typed("Fig. 9: observer RMS below the targets' on average", "yes",
              "; ".join(f"alpha {a:g}: window mean {obs_mean[a]:.1f} vs {tgt_mean[a]:.1f} km "
                        f"({100 * gap_mean[a]:.0f} % lower), window end {common[a][0][0]:.1f} vs "
                        f"{np.mean(common[a][0][1:]):.1f} km ({100 * gap_end[a]:.1f} %)" for a in obs_mean),
              "reproduced" if better else
              f"differs: observer at most {100 * max(gap_mean.values()):.0f} % lower (window mean), threshold 10 %",
              "criterion fixed in advance: observer's window-mean RMS at least 10 % below the targets' mean; the "
              "means are dominated by the transient; relative measurements tie the four errors together (section 9)")
table.add_typed("Fig. 10: MI correlates with estimator performance", "'correlates well'",
          f"Spearman(MI, RMS) = {rank_obs:.2f} observer, {rank_tgt:.2f} targets over the alpha grid; "
          + radii_text,
          "reproduced" if rank_obs < -0.8 and rank_tgt < -0.8 else "differs: weak rank correlation",
          "criterion: Spearman below -0.8 over the alpha grid (best of both sweeps), as in notebook 05; across "
          "keep-out radii at fixed alpha_h (not the paper's front) MI and RMS need not move together: see the "
          "keep-out row")
table.add_typed("Fig. 10: impulse and MI grow with alpha_h", "yes",
          f"impulse {dvs[0]:.1f}-{dvs[-1]:.1f} m/s, MI {mis[0]:.1f}-{mis[-1]:.1f} nats, monotone: "
          f"{mono_dv and mono_mi}", "reproduced" if mono_dv and mono_mi else "differs: not monotone",
          "best of the upward and downward sweeps")
table.add_typed("Fig. 10: front monotone in (impulse, RMS): more impulse, lower RMS", "a trade-off front",
          "dominated points: " + (", ".join(f"alpha {a:g} ({dvs[i]:.2f} m/s, {rms_obs[i]:.1f} km) by alpha {b:g} "
                                            f"({dvs[j]:.2f} m/s, {rms_obs[j]:.1f} km)" for a, i, b, j in dominated)
                                  or "none"),
          "reproduced" if not dominated else "differs: a plan is worse on both axes than a cheaper one",
          "criterion: no plan has both more impulse and a higher observer terminal RMS than another; "
          + dominated_note)
table.add_typed("Impulse and terminal RMS values (Figs. 8-10)", "plotted, no numbers printed",
          f"alpha 0: {dvs[0]:.2f} m/s, {rms_obs[0]:.0f} km; alpha {ok[-1]['alpha']:g}: {dvs[-1]:.1f} m/s, "
          f"{rms_obs[-1]:.1f} km", "not in paper", "the figures carry no readable values in the text version")
table.add_typed("node grid (unstated N and sigma), alpha_h = " + f"{a6:g}", "N, sigma not given",
          f"{N_NODES} nodes: {row6['dv']:.2f} m/s, RMS {row6['crlb'].terminal_rms_km[0]:.1f} km; "
          + "; ".join(f"{n_} nodes: {d:.2f} m/s, RMS {r_:.1f} km" for n_, d, i_, r_ in mesh_rows),
          "beyond paper", f"whole sweep re-solved on each grid (sigma = {SIGMA:g}); RMS changes by up to "
          + (f"{100 * max(abs(r_ / row6['crlb'].terminal_rms_km[0] - 1) for _, _, _, r_ in mesh_rows):.0f} %"
             if mesh_rows else "n/a (no converged plan at this weight on the other grids)"))
if base and budget_row:
    table.add_typed(f"Improvement over the minimum-impulse baseline at {budget_row['budget']:.1f} m/s (solved)",
              "substantial", f"alpha_h = {budget_row['alpha']:.2e} spends {budget_row['dv']:.2f} m/s: observer RMS "
              f"{budget_row['rms']:.1f} km vs {base['crlb'].terminal_rms_km[0]:.0f} km for the baseline's "
              f"{base['dv']:.2f} m/s ({base['crlb'].terminal_rms_km[0] / budget_row['rms']:.0f}x lower)",
              "beyond paper", f"budget = baseline + {BUDGET_EXTRA_MPS:g} m/s, met within {100 * BUDGET_RTOL:g} %; "
              f"log-interpolation on the grid at the spent impulse said {budget_row['interp']:.1f} km")
elif base and cheap:
    table.add_typed("Improvement over the minimum-impulse baseline", "substantial",
              f"alpha {cheap['alpha']:g}: +{cheap['dv'] - base['dv']:.1f} m/s buys "
              f"{base['crlb'].terminal_rms_km[0] / cheap['crlb'].terminal_rms_km[0]:.0f}x lower observer RMS",
              "beyond paper", "cheapest information trajectory against the alpha_h = 0 transfer (budget solve failed)")
rms_span = max(r["rms"] for r in radius_rows) / min(r["rms"] for r in radius_rows)
weak_all = base is not None and all(base["crlb"].terminal_rms_km[0] >= 5 * r["rms"] for r in radius_rows)
table.add_typed("Keep-out radius (unstated input), swept at the Fig. 6 weight", "not in paper",
          "; ".join(f"{r['d']:.0f} km: {r['dv']:.1f} m/s, MI {r['mi']:.2f} nats, RMS {r['rms']:.1f} km, closest "
                    f"{r['closest']:.0f} km" + (" (binds)" if r["binds"] else "") for r in radius_rows)
          + "; none: " + (f"closest approach {nk_range:.2f} km" if np.isfinite(nk_range) else
                          f"no convergence ({nk.reason.split(':')[0]}); closest approach of its last reference "
                          f"{nk_ref_range[-1]:.1f} km"),
          "beyond paper", (f"across radii more MI goes with a higher RMS (Spearman(MI, RMS) {rank_radii:+.2f}), "
                           "against 'MI correlates well'" if rank_radii is not None and rank_radii > 0 else
                           "MI against RMS " + radii_text)
          + f"; terminal RMS varies {rms_span:.1f}x over the radii; "
          f"the alpha_h = 0 baseline stays >= 5x worse at every radius: {weak_all}; inactive radii: "
          + (", ".join(f"{r['d']:.0f} km (closest {r['closest']:.0f} km, up to {r['apart']:.0f} km from the 424 km "
                       "plan)" for r in radius_rows if not r["binds"]) or "none")
          + (f"; no keep-out: best accepted cost {nk_cost:.4f} (defects open) vs {row6['res'].cost:.4f} constrained"
             if np.isfinite(nk_cost) else "") + "; adopted 424 km = target outside the prior 3-sigma sphere")
table.add_typed("MI gradient (reverse mode of Eq. 18) vs central differences, case 2 window", "Eqs. 44-52 (formula only)",
          f"max rel. difference {grad_err:.1e}", "beyond paper" if grad_err < 1e-5 else
          "differs: gradient and value disagree", "differentiates the square-root recursion, not Eqs. 44-52 term "
          "by term; process noise held fixed in both (same function)")
table.display()
