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
# # 05 · Test case 1: one observer, one target, relative positions (Wolf & Jones Tables 2-3, Figs. 1-5)
#
# **What you will learn.** How a low-thrust observer on a distant retrograde orbit (DRO) trades propellant for
# tracking accuracy: we plan its trajectory with successive convexification (SCvx) over a grid of homotopy weights
# $\alpha_h$ between "minimum impulse" and "maximum mutual information", check that every plan really flies, and
# judge the plans with the Cramér-Rao lower bound (CRLB) of a sequential estimator. Along the way: why the SCvx
# of the paper creeps with an information reward and what makes it converge, how many local optima the problem has,
# and which of the paper's printed numbers are slips.
#
# **Paper sections followed.** Wolf & Jones (arXiv 2408.17435), "Test Case #1" (Tables 2-3, Figs. 1-5) with the
# objective of Eqs. 42-44 and the SCvx of Eqs. 24-36 (notebook 03); the mutual information and its gradient are
# notebook 02, the node placement notebook 04.

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: fewer nodes and a coarser alpha_h grid in quick mode; the same experiments.
N_NODES = 20 if QUICK else 40  # Sundman-spaced nodes over the two periods (the paper does not give its N)
SIGMA = 1.0  # Sundman exponent (notebook 04)
ALPHAS = ([0.0, 2e-3, 5e-3, 1e-2, 2e-2] if QUICK else
          [0.0, 1e-3, 2e-3, 3e-3, 5e-3, 7e-3, 1e-2, 1.5e-2, 2e-2])
PENALTY_ITER = 25 if QUICK else 80  # iterations granted to the paper's exact-penalty SCvx in section 4

import time

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection
from scipy.stats import spearmanr

from cislunar import covariance as cov
from cislunar import discretization as D
from cislunar import plotting, scvx, wolf_jones
from cislunar.dynamics import EARTH_MOON as em
from cislunar.propagation import ImpactError, propagate
from cislunar.report import ComparisonTable

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)  # not used: every computation here is deterministic
table = ComparisonTable("05 Wolf & Jones test case 1 (Tables 2-3, Figs. 1-5)")
KM_S = em.velocity_unit_km_s
MPS = KM_S * 1e3

# %% [markdown]
# ## 1 · The scenario (Tables 2 and 3)
#
# Observer and target fly neighbouring planar DROs. The observer starts on the DRO of Table 2's $x_{\mathcal S}(t_0)$,
# flies two periods $P_{ref}$ and must end at the printed $x_{\mathcal S}(t_f)$ (a state on a third DRO). Inside the
# observation window $[3P_{ref}/4, 3P_{ref}/2]$ it coasts ($a_{max} = 0$) and measures the target's relative position
# once per day with 100 m noise per axis. Priors: 100 km and 1 cm/s per axis for both spacecraft (Table 3).
#
# **The printed observer state is not a DRO.** Its $\dot y_0 = 0.528996986$ does not close (notebook 01): held at
# the printed $x_0$, the periodic DRO has $\dot y_0 = 0.5559319$, a transcription slip in two digits is the likely
# cause. What would the printed state give? Flown ballistically it leaves the DRO region and **hits the Moon before
# the two periods are over**; reaching $x_{\mathcal S}(t_f)$ from it with the window constraint costs tens of m/s
# (computed below: essentially the 27.6 m/s velocity slip), where the corrected state needs well under 1 m/s
# (section 5). We use the corrected state.
#
# **Process noise.** Table 3 prints $Q = 10^{-11}$ "km/s³". Notebook 06 (and `cislunar.wolf_jones`) tries the
# plausible readings against the paper's statement that the CRLB stays bounded over the window and adopts the
# non-dimensional acceleration PSD $q = 10^{-11}$ LU²/TU³; the literal unit fix $10^{-11}$ km²/s³ would let the
# observer error grow to tens of thousands of km. Section 7 judges the planned trajectories with both readings.

# %%
sc = wolf_jones.test_case_1()
P = sc.period
print(f"P_ref = {em.tu_to_days(P):.3f} d; scenario {em.tu_to_days(sc.duration):.2f} d; window "
      f"{em.tu_to_days(sc.window[0]):.2f}-{em.tu_to_days(sc.window[1]):.2f} d; {sc.measurement_times.size} "
      f"daily measurements ({em.tu_to_days(sc.measurement_times[0]):.2f} ... "
      f"{em.tu_to_days(sc.measurement_times[-1]):.2f} d)")
print(f"a_max = 1e-6 km/s^2 = {sc.a_max:.4f} LU/TU^2; q = {sc.q:g} LU^2/TU^3; measurement sigma 100 m per axis")
chk = sc.row_checks["observer_t0"]
print(f"observer x_S(t0): printed vy0 = {chk.vy0:.9f}, periodic vy0 = {chk.corrected.x0[4]:.9f} "
      f"(difference {chk.vy0_correction * MPS:.2f} m/s); printed state misses itself by {chk.raw_closure:.2f} LU "
      "after one period")
try:
    propagate(em, sc.observer_x0_printed, [0.0, sc.duration])
    printed_fate = "stays clear of the primaries"
except ImpactError as exc:
    printed_fate = f"hits the {exc.body} on day {em.tu_to_days(exc.time):.1f}"
print("printed observer state, flown ballistically:", printed_fate)
t_tmp, _, _ = sc.node_times(N_NODES, SIGMA)
x_tmp = propagate(em, sc.observer_x0, t_tmp).x
x_tmp[0] = sc.observer_x0_printed  # start from the printed state, guess along the corrected DRO
printed_transfer = scvx.solve_scvx(em, t_tmp, x_tmp, np.zeros((t_tmp.size, 3)), sc.control_bounds(t_tmp),
                                   x_final=sc.observer_xf)
print(f"minimum-impulse transfer (alpha_h = 0) from the printed state to x_S(t_f): "
      f"{printed_transfer.impulse * MPS:.2f} m/s")

# %% [markdown]
# ## 2 · Nodes, thrust bounds and the information model
#
# Nodes are equally spaced in the Sundman variable $dt = r_m^\sigma d\tau$ (Eqs. 37-39, $\sigma = 1$) along the
# ballistic DRO, and the nodes nearest to the window ends are moved onto them. The node controls are accelerations
# with a first-order hold, so the bound of Eqs. 40-41 is $a_{max}$ at every node outside the window (the
# acceleration reading of Eq. 41, notebook 04) and **zero at every node of the window**, ends included: the
# interpolated thrust then vanishes on the whole window. (Notebook 03's first version ignored the window; its
# control peaked on day 16, inside it.)
#
# The information model gives, for the observer state $x_{k^*}$ at the window-start node, the mutual information
# $\mathcal I$ of the window (Eq. 18), its gradient (Eqs. 44-52) and a Hessian by finite differences of the
# gradient; the process noise is held fixed along the ballistic window arc so that value and gradient describe the
# same function (the paper also neglects the sensitivity of $\tilde P$).

# %%
t, k_ws, k_we = sc.node_times(N_NODES, SIGMA)
u_max = sc.control_bounds(t)
x_ball, u_ball = sc.ballistic_guess(t)
info = sc.information_model()
in_window = u_max == 0
print(f"{N_NODES} nodes; window nodes {k_ws}..{k_we} (t = {em.tu_to_days(t[k_ws]):.3f}, {em.tu_to_days(t[k_we]):.3f} d);"
      f" node spacing {em.tu_to_days(np.diff(t)).min():.2f}-{em.tu_to_days(np.diff(t)).max():.2f} d")
print(f"ballistic: I = {info(x_ball[k_ws], 0):.3f} nats; |x(t_f) - x_S(t_f)| = "
      f"{np.linalg.norm(x_ball[-1, :3] - sc.observer_xf[:3]) * em.length_unit_km:.1f} km")

# %% [markdown]
# ## 3 · The homotopy sweep, both ways
#
# For every $\alpha_h$ SCvx minimises $(1-\alpha_h)\,\mathrm{impulse} - \alpha_h\mathcal I$ (Eq. 42) subject to the
# dynamics, the bounds and the terminal state. The SCvx here (`cislunar.scvx`, notebook 03) departs from the printed
# method where the printed method does not converge, each departure documented: an augmented Lagrangian on the
# defects (SCvx*, Oguri 2023) instead of the L1 exact penalty, a convex quadratic information model built from
# the concave part of the MI Hessian instead of Eq. 44's linear one, a predicted decrease at round-off level
# counted as $\rho = 1$, tight Clarabel tolerances, and a stop only on an accepted step with small defects, small
# cost change and an inactive trust region; a collapsing trust region raises an error.
#
# The problem has several local optima, so the grid is swept upward (each $\alpha_h$ warm-started from the
# previous solution, the first from the ballistic DRO) and downward (from the top solution), and the lower cost
# per $\alpha_h$ is kept.

# %%
settings = scvx.SCvxSettings()


def solve(alpha, x_guess, u_guess):
    return scvx.solve_scvx(em, t, x_guess, u_guess, u_max, x_final=sc.observer_xf, info=info, info_node=k_ws,
                           alpha=alpha, settings=settings)


t0 = time.perf_counter()
sweep = scvx.homotopy_sweep(solve, ALPHAS, x_ball, u_ball, progress=True)
sweep_seconds = time.perf_counter() - t0
n_iter = sum(a["iterations"] for a in sweep.attempts)
print(f"{len(sweep.attempts)} SCvx runs, {n_iter} iterations, {sweep_seconds:.0f} s "
      f"({sweep_seconds / n_iter:.2f} s per iteration)")
print(f"{'alpha_h':>8} {'dir':>5} {'ok':>3} {'iter':>5} {'cost':>14}")
for a in sweep.attempts:
    print(f"{a['alpha']:8.4f} {a['direction']:>5} {'y' if a['converged'] else 'n':>3} {a['iterations']:5d} "
          f"{a['cost']:14.9f} {a['error'][:60]}")
best = sweep.best
assert all(b is not None for b in best), "an alpha_h without any converged run"
impulse_mps = sweep.column("impulse") * MPS
mi = sweep.column("information")
print("best of sweeps: impulse [m/s]", np.round(impulse_mps, 3))
print("                MI [nats]    ", np.round(mi, 3))
print("                from         ", sweep.source)
monotone = bool(np.all(np.diff(impulse_mps) >= -1e-6 * impulse_mps.max()) and np.all(np.diff(mi) >= -1e-6))
cost_gap = max(abs(min(r["cost"] for r in sweep.attempts if r["alpha"] == a and r["converged"])
                   - max(r["cost"] for r in sweep.attempts if r["alpha"] == a and r["converged"])) for a in ALPHAS)
print(f"impulse and MI non-decreasing in alpha_h: {monotone}; largest up/down cost difference {cost_gap:.1e}")

# %% [markdown]
# ## 4 · One convergence history, and the exact penalty for comparison
#
# The per-iteration log of $\alpha_h = 5\times10^{-3}$ (cold start from the ballistic DRO): predicted decrease, the
# two parts of the model error (defects; information), the ratio $\rho$, the trust-region radius $\eta$ and
# whether the step sat on the trust-region boundary. Then the same problem with the paper's L1 exact penalty
# ($\gamma = 10^3$) and the same quadratic information model, given a fixed number of iterations.

# %%
i5 = ALPHAS.index(5e-3)
cold = solve(5e-3, x_ball, u_ball)
print(f"cold start alpha_h = 5e-3: {cold.iterations} iterations, cost {cold.cost:.9f} (best of sweeps "
      f"{best[i5].cost:.9f})")
print(f"{'it':>3} {'predicted':>10} {'err defect':>11} {'err MI':>10} {'rho':>8} {'eta':>9} {'TR':>3} {'defect':>8}")
for h in cold.history:
    print(f"{h['iteration']:3d} {h['predicted']:10.2e} {h['model_error_defect']:11.2e} {h['model_error_info']:10.2e} "
          f"{h['rho']:8.3f} {h['eta']:9.2e} {'on' if h['tr_active'] else '':>3} {h['max_defect']:8.1e}")
try:
    pen = scvx.solve_scvx(em, t, x_ball, u_ball, u_max, x_final=sc.observer_xf, info=info, info_node=k_ws,
                          alpha=5e-3, settings=scvx.SCvxSettings(method="penalty", max_iter=PENALTY_ITER))
    pen_history, pen_outcome = pen.history, f"converged in {pen.iterations} iterations"
except scvx.SCvxError as exc:
    pen_history, pen_outcome = exc.history, f"no convergence: {exc.reason}"
pen_best = min(h["new_cost"] for h in pen_history if h["accepted"])
print(f"exact penalty: {pen_outcome}; best accepted cost {pen_best:.6f} vs {best[i5].cost:.6f}; last rho "
      f"{pen_history[-1]['rho']:.2f}, eta {pen_history[-1]['eta']:.1e}")

fig, axes = plt.subplots(1, 3, figsize=(14, 3.8))
ha = cold.history
its = [h["iteration"] for h in ha]
axes[0].semilogy(its, [max(abs(h["predicted"]), 1e-16) for h in ha], "o-", ms=3, label="augmented Lagrangian")
axes[0].semilogy([h["iteration"] for h in pen_history], [max(abs(h["predicted"]), 1e-16) for h in pen_history],
                 ".-", ms=3, color="C3", label="exact penalty")
axes[0].set(xlabel="iteration", ylabel="|predicted decrease|")
axes[0].legend(fontsize=8, loc="upper right")
axes[1].semilogy(its, [h["eta"] for h in ha], "o-", ms=3)
axes[1].semilogy([h["iteration"] for h in pen_history], [h["eta"] for h in pen_history], ".-", ms=3, color="C3")
axes[1].set(xlabel="iteration", ylabel=r"trust-region radius $\eta$")
axes[2].semilogy(its, [max(h["max_defect"], 1e-16) for h in ha], "o-", ms=3)
axes[2].semilogy([h["iteration"] for h in pen_history], [max(h["max_defect"], 1e-16) for h in pen_history], ".-",
                 ms=3, color="C3")
axes[2].set(xlabel="iteration", ylabel="largest defect [LU, LU/TU]")
fig.suptitle(r"SCvx on test case 1, $\alpha_h = 5\times10^{-3}$, from the ballistic DRO")
_ = plotting.save_figure(fig, "05_convergence", output_dir=out)

# %% [markdown]
# ## 5 · Does every plan fly? (beyond the paper)
#
# Each converged trajectory is re-flown by single shooting: its first-order-hold control alone, from $x_{\mathcal
# S}(t_0)$, through the nonlinear CR3BP. The terminal miss measures how real the plan is; the defects and bounds are
# checked as in the tests.

# %%
miss_km, miss_mm_s, max_ratio, window_thrust = [], [], [], []
for r in best:
    xs = D.propagate_foh(em, sc.observer_x0, t, r.u)
    miss_km.append(np.linalg.norm(xs[-1, :3] - sc.observer_xf[:3]) * em.length_unit_km)
    miss_mm_s.append(np.linalg.norm(xs[-1, 3:] - sc.observer_xf[3:]) * KM_S * 1e6)
    un = np.linalg.norm(r.u, axis=1)
    max_ratio.append(float(np.max(un[~in_window] / u_max[~in_window])))
    window_thrust.append(float(np.max(un[in_window])))
print(f"{'alpha_h':>8} {'impulse m/s':>12} {'MI nats':>9} {'iter':>5} {'defect':>8} {'miss km':>9} {'miss mm/s':>9} "
      f"{'max|u|/umax':>11}")
for a, r, mk, mv, mr in zip(ALPHAS, best, miss_km, miss_mm_s, max_ratio):
    print(f"{a:8.4f} {r.impulse * MPS:12.4f} {r.information:9.4f} {r.iterations:5d} {r.max_defect:8.1e} {mk:9.1e} "
          f"{mv:9.1e} {mr:11.4f}")
print(f"largest thrust inside the window: {max(window_thrust):.1e} LU/TU^2")


# %% [markdown]
# ## 6 · Figures 1-3: trajectories and thrust
#
# Between nodes the control is linear in time, so a dense re-flight with linearly interpolated controls is the
# same trajectory. Thrust arcs (|a| above 1 % of $a_{max}$) are red, coasts blue, as in the paper.

# %%
def dense_flight(res, n=600):
    td = np.union1d(t, np.linspace(0.0, t[-1], n))
    ud = np.stack([np.interp(td, t, res.u[:, i]) for i in range(3)], axis=1)
    return td, D.propagate_foh(em, sc.observer_x0, td, ud), ud


t_dense = np.linspace(0.0, sc.duration, 600)
ref_dro = propagate(em, sc.observer_x0, t_dense).x
show = [ALPHAS.index(5e-3), ALPHAS.index(2e-2)]
fig, axes = plt.subplots(1, 2, figsize=(12, 5.2))
for ax, i in zip(axes, show):
    td, xd, ud = dense_flight(best[i])
    pos = (xd[:, :2] - [1 - em.mu, 0]) * em.length_unit_km / 1e3
    thrust = np.linalg.norm(ud, axis=1) > 0.01 * sc.a_max
    segs = np.stack([pos[:-1], pos[1:]], axis=1)
    ax.add_collection(LineCollection(segs, colors=np.where(thrust[:-1] | thrust[1:], "tab:red", "tab:blue"), lw=1.6))
    rp = (ref_dro[:, :2] - [1 - em.mu, 0]) * em.length_unit_km / 1e3
    ax.plot(rp[:, 0], rp[:, 1], "k--", lw=0.9, label="reference DRO")
    ax.plot([], [], color="tab:blue", label="coast")
    ax.plot([], [], color="tab:red", label="thrust")
    ax.plot(0, 0, "o", color="0.5", ms=5, label="Moon")
    ax.set(xlabel="x - x_Moon [1000 km]", ylabel="y [1000 km]", aspect="equal",
           title=rf"$\alpha_h$ = {ALPHAS[i]:g}: {best[i].impulse * MPS:.1f} m/s, I = {best[i].information:.1f} nats")
handles, labels = axes[0].get_legend_handles_labels()
fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8, bbox_to_anchor=(0.5, -0.04))
fig.suptitle("Fig. 1 analogue: observer trajectory, Moon-centred rotating frame")
_ = plotting.save_figure(fig, "05_fig1_trajectories", output_dir=out)

fig, ax = plt.subplots(figsize=(6.5, 5.5))
cmap = plt.get_cmap("viridis")
for j, (a, r) in enumerate(zip(ALPHAS, best)):
    td, xd, _ = dense_flight(r, 400)
    rel = (xd[:, :3] - propagate(em, sc.observer_x0, td).x[:, :3]) * em.length_unit_km / 1e3
    ax.plot(rel[:, 0], rel[:, 1], color=cmap(j / max(1, len(ALPHAS) - 1)), lw=1.2, label=rf"$\alpha_h$={a:g}")
ax.plot(0, 0, "o", color="C2", ms=6, label="start")
ax.set(xlabel=r"$\Delta x$ [1000 km]", ylabel=r"$\Delta y$ [1000 km]", aspect="equal",
       title="Fig. 2 analogue: position relative to the reference DRO")
ax.legend(fontsize=7, ncol=2, loc="center left", bbox_to_anchor=(1.02, 0.5))
_ = plotting.save_figure(fig, "05_fig2_relative_motion", output_dir=out)

fig, axes = plt.subplots(1, 2, figsize=(13, 4), sharey=True)
for ax, i in zip(axes, show):
    td, _, ud = dense_flight(best[i])
    days = em.tu_to_days(td)
    scale = em.acceleration_unit_km_s2 * 1e9  # um/s^2
    ax.axvspan(em.tu_to_days(sc.window[0]), em.tu_to_days(sc.window[1]), color="0.9", label="observation window")
    ax.plot(days, ud[:, 0] * scale, label="$a_x$")
    ax.plot(days, ud[:, 1] * scale, label="$a_y$")
    ax.plot(days, np.linalg.norm(ud, axis=1) * scale, "k", lw=1.0, label="|a|")
    ax.axhline(sc.a_max * scale, color="0.4", ls=":", lw=0.8)
    ax.set(xlabel="time [days]", title=rf"$\alpha_h$ = {ALPHAS[i]:g}")
axes[0].set_ylabel("thrust acceleration [µm/s²]")
handles, labels = axes[0].get_legend_handles_labels()
fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8, bbox_to_anchor=(0.5, -0.06))
fig.suptitle("Fig. 3 analogue: thrust acceleration (dotted: a_max)")
_ = plotting.save_figure(fig, "05_fig3_thrust", output_dir=out)

# %% [markdown]
# ## 7 · Figures 4-5: CRLB over the window and the Pareto curves
#
# The CRLB of the paper's "Performance Evaluation" is the EKF covariance recursion along the true trajectories,
# with the process noise now computed along each planned trajectory (planning held it fixed). Fig. 4 shows the
# position 1-sigma per axis for observer and target; Fig. 5 the total impulse against the position RMS after the
# last measurement of the window. The paper's x-axis "average impulse" is not defined; any per-node or per-day
# average is the total divided by a constant, which does not change the shape of the curve. Finally the plans of
# $\alpha_h = 0$ and the largest $\alpha_h$ are judged again with the literal unit fix of Table 3's process noise.

# %%
crlb = [wolf_jones.evaluate_crlb(sc, r.x[k_ws]) for r in best]
term_obs = np.array([c.terminal_rms_km[0] for c in crlb])
term_tgt = np.array([c.terminal_rms_km[1] for c in crlb])
mi_eval = np.array([c.mutual_information for c in crlb])
days_w = em.tu_to_days(crlb[0].t)
fig, axes = plt.subplots(3, 2, figsize=(12, 8), sharex=True)
for j, (a, c) in enumerate(zip(ALPHAS, crlb)):
    col = cmap(j / max(1, len(ALPHAS) - 1))
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
_ = plotting.save_figure(fig, "05_fig4_crlb", output_dir=out)

fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
for ax, term, name in zip(axes, (term_obs, term_tgt), ("observer", "target")):
    ax.plot(impulse_mps, term, "o-")
    for a, x_, y_ in zip(ALPHAS, impulse_mps, term):
        ax.annotate(f"{a:g}", (x_, y_), textcoords="offset points", xytext=(4, 4), fontsize=7)
    ax.set(xlabel="total impulse [m/s]", ylabel="position RMS at the window end [km]", title=name, yscale="log")
fig.suptitle(r"Fig. 5 analogue: Pareto curves over the $\alpha_h$ grid (labels: $\alpha_h$)")
_ = plotting.save_figure(fig, "05_fig5_pareto", output_dir=out)
for a, imp, mo, mt, m1, m2 in zip(ALPHAS, impulse_mps, term_obs, term_tgt, mi, mi_eval):
    print(f"alpha_h {a:7.4f}: {imp:8.3f} m/s  terminal RMS observer {mo:7.3f} km, target {mt:7.3f} km;  "
          f"MI {m1:.3f} (planning Q) / {m2:.3f} nats (Q along the trajectory)")
# the process-noise reading: the same plans judged with the literal unit fix of Table 3 (1e-11 km^2/s^3)
q_literal = cov.psd_to_nondimensional(1e-11, em)
lit = [wolf_jones.evaluate_crlb(sc, best[i].x[k_ws], q=q_literal) for i in (0, len(ALPHAS) - 1)]
print(f"with q = 1e-11 km^2/s^3 = {q_literal:.3g} LU^2/TU^3 instead of {sc.q:g}: terminal RMS "
      f"alpha_h = 0: {lit[0].terminal_rms_km[0]:.0f} / {lit[0].terminal_rms_km[1]:.0f} km, alpha_h = {ALPHAS[-1]:g}: "
      f"{lit[1].terminal_rms_km[0]:.0f} / {lit[1].terminal_rms_km[1]:.0f} km (observer / target); growth over the "
      f"window after the transient: {lit[1].rms_km[0, -1] / lit[1].rms_km[0, 1]:.1f} x")
bounded = bool(np.all(np.array([c.rms_km[:, -1] <= c.rms_km[:, 1] for c in crlb])))
transient = bool(np.all(np.array([c.rms_km[:, 1] > c.rms_km[:, 0] for c in crlb])))

# %% [markdown]
# ## 8 · Beyond the paper: does the mutual information rank the plans like the CRLB?
#
# "The mutual information correlates well with the expected performance of a sequential estimator": over the grid,
# the Spearman rank correlation between $\mathcal I$ and the terminal RMS (perfect agreement: -1). And the paper's
# baseline claim: against the minimum-impulse plan ($\alpha_h = 0$), how much do the information plans buy, and what
# does the Pareto curve say about equal impulse? Every point of the curve is the most information obtainable for
# its impulse (a weighted-sum scalarisation), so at the baseline's impulse the baseline itself is the best plan;
# what matters is the price of each improvement, read off the curve by interpolation.

# %%
rho_obs = float(spearmanr(mi, term_obs).statistic)
rho_tgt = float(spearmanr(mi, term_tgt).statistic)
print(f"Spearman rank correlation of MI with terminal RMS: observer {rho_obs:+.3f}, target {rho_tgt:+.3f}")
i_best = int(np.argmax(mi))
print(f"baseline alpha_h = 0: {impulse_mps[0]:.3f} m/s, terminal RMS observer {term_obs[0]:.2f} km, target "
      f"{term_tgt[0]:.2f} km, I = {mi[0]:.2f} nats")
print(f"best information plan alpha_h = {ALPHAS[i_best]:g}: {impulse_mps[i_best]:.2f} m/s, observer "
      f"{term_obs[i_best]:.2f} km, target {term_tgt[i_best]:.2f} km, I = {mi[i_best]:.2f} nats")
budgets = [b for b in (1.0, 5.0, 10.0, 30.0) if impulse_mps[0] < b <= impulse_mps[-1]]
for b in budgets:
    print(f"  at {b:5.1f} m/s (interpolated on the front): target RMS {np.interp(b, impulse_mps, term_tgt):.2f} km "
          f"({np.interp(b, impulse_mps, term_tgt) / term_tgt[0]:.2f} x baseline), observer "
          f"{np.interp(b, impulse_mps, term_obs):.2f} km")

# %% [markdown]
# ## 9 · Paper versus reproduction
#
# Tolerances fixed before comparing: "reproduced" for a qualitative claim means the stated behaviour holds for
# every $\alpha_h$ of the grid; the paper prints no number for test case 1 beyond its inputs (Tables 2-3), so the
# quantitative rows are "not in paper" or "beyond paper". Slips in the paper are listed with what we used.

# %%
table.add("observer x_S(t0) (Table 2) is a DRO", "vy0 = 0.528996986",
          f"not periodic (misses itself by {chk.raw_closure:.2f} LU); periodic vy0 = {chk.corrected.x0[4]:.7f}",
          "differs: printed vy0 is a slip", f"as printed it {printed_fate}; corrected state used (notebook 01)")
table.add("observation window", "[3P/4, 3P/2]; text: '12 and 23 days'",
          f"{em.tu_to_days(sc.window[0]):.2f}-{em.tu_to_days(sc.window[1]):.2f} d",
          "differs: text's 23 d is a slip", "3P/2 = 24.26 d for P = 16.17 d; the last daily measurement is at "
          f"{em.tu_to_days(sc.measurement_times[-1]):.2f} d")
table.add("Fig. 3 alpha_h of the left panel", "text: 5e-2; caption and Fig. 1: 5e-3", "5e-3 shown",
          "differs: text's 5e-2 is a slip", "5e-2 lies outside the paper's grid (up to 2e-2)")
table.add("process noise Q (Table 3)", "1e-11 'km/s^3'", f"q = {sc.q:g} LU^2/TU^3 (acceleration PSD)",
          "derived", "reading chosen by the CRLB-boundedness test of notebook 06 / cislunar.wolf_jones")
table.add("CRLB bounded over the window under Q = 1e-11 km^2/s^3 (literal)", "bounded (Fig. 4)",
          f"observer {lit[1].rms_km[0, 1]:.0f} -> {lit[1].rms_km[0, -1]:.0f} km over the window, vs "
          f"{crlb[-1].rms_km[0, 1]:.0f} -> {crlb[-1].rms_km[0, -1]:.1f} km with q = 1e-11 LU^2/TU^3 "
          f"(alpha_h = {ALPHAS[-1]:g})", "differs: literal reading rejected" if lit[1].rms_km[0, -1] >
          lit[1].rms_km[0, 1] else "reproduced", "why the non-dimensional reading is used")
table.add("zero thrust in the observation window", "a_max = 0 in the window",
          f"max |u| in the window {max(window_thrust):.0e}", "reproduced" if max(window_thrust) == 0 else
          "differs: thrust in the window", "enforced as u_k = 0 at every window node")
table.add("SCvx converges for every alpha_h of the grid", "implied (Figs. 2, 5)",
          f"{sum(a['converged'] for a in sweep.attempts)}/{len(sweep.attempts)} runs, largest defect "
          f"{max(r.max_defect for r in best):.0e}",
          "reproduced" if all(a["converged"] for a in sweep.attempts) else "differs: some runs fail",
          "augmented Lagrangian + quadratic MI model; the printed L1 penalty creeps (next row)")
table.add("printed SCvx (L1 exact penalty) at alpha_h = 5e-3", "method of Eqs. 42-43", pen_outcome[:60],
          "beyond paper", f"best accepted cost {pen_best:.5f} vs {best[i5].cost:.5f}; gamma = 1e3")
table.add("larger alpha_h -> larger departure from the DRO (Fig. 2)", "yes",
          f"impulse {impulse_mps[0]:.2f} -> {impulse_mps[-1]:.1f} m/s, monotone: {monotone}",
          "reproduced" if monotone else "differs: non-monotone front", "best of upward and downward sweeps")
table.add("CRLB transient at the window start, then bounded (Fig. 4)", "yes",
          f"transient: {transient}; final <= second-step RMS: {bounded}",
          "reproduced" if transient and bounded else "differs: see Fig. 4 analogue",
          "diagonal prior, no correlations (paper's explanation)")
table.add("more information -> lower terminal RMS (Figs. 4-5)", "observer and target",
          f"observer {term_obs[0]:.1f} -> {term_obs[-1]:.1f} km, target {term_tgt[0]:.1f} -> {term_tgt[-1]:.1f} km",
          "reproduced" if term_obs[-1] < term_obs[0] and term_tgt[-1] < term_tgt[0] else "differs: no gain",
          f"alpha_h = 0 vs {ALPHAS[-1]:g}")
table.add("MI correlates with estimator performance", "'correlates well'",
          f"Spearman(MI, terminal RMS): observer {rho_obs:+.2f}, target {rho_tgt:+.2f}", "beyond paper",
          f"{len(ALPHAS)} alpha_h values")
table.add("single-shooting re-flight of every plan", "-", f"largest terminal miss {max(miss_km):.1e} km",
          "beyond paper", "FOH control alone from x_S(t0), nonlinear CR3BP")
table.add("Pareto values (impulse, terminal RMS)", "plotted only (Fig. 5), no numbers",
          f"{impulse_mps[-1]:.1f} m/s -> target {term_tgt[-1]:.2f} km at alpha_h = {ALPHAS[-1]:g}", "not in paper",
          "the paper's axes are not quantitatively readable; N and sigma of the nodes are not given either")
distinct = cost_gap > 1e-8 * (1 + max(abs(b.cost) for b in best))
table.add("upward vs downward sweep (local optima)", "not discussed",
          f"largest cost difference {cost_gap:.0e}: " + ("distinct local optima found" if distinct else
                                                         "both sweeps reach the same optimum on this grid"),
          "beyond paper", "best cost per alpha_h kept; differences below 1e-8 relative are solver round-off")
table.display()
