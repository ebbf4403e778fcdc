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
# # 03 · Successive convexification (SCvx) with first-order hold
#
# **What you will learn.** How SCvx turns a nonconvex low-thrust trajectory problem in the CR3BP into a sequence
# of convex second-order-cone programs: the first-order-hold affine model of each step, the virtual control that
# keeps every subproblem feasible, the trust region that keeps the linearisation honest, and the ratio test of
# Table 1 that accepts or rejects each step. We watch it converge on the boundary conditions of Wolf & Jones' test
# case 1 (minimum impulse, no information reward yet: that is notebook 05) and check that the answer does not
# depend on the initial guess.
#
# **Paper sections followed.** Wolf & Jones (arXiv 2408.17435), "Sequential Convex Programming for Trajectory
# Generation": Linearization (Eqs. 24-26), Discretization (Eqs. 27-33), Trust Region Update (Eqs. 34-36, Table 1),
# and the objective of "Convex Objective Approximation" (Eqs. 42-43). The node placement is notebook 04.

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: fewer nodes and fewer random initial guesses in quick mode; the same experiments.
N_NODES = 24 if QUICK else 60
N_GUESSES = 2 if QUICK else 6
SIGMA = 1.0  # Sundman exponent (notebook 04); the DRO is benign, so its value matters little here

import matplotlib.pyplot as plt
import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate
from cislunar.guidance import discretization as D
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import scenarios as wolf_jones
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
table = ComparisonTable("03 SCvx with first-order hold (Wolf & Jones Eqs. 24-36, 42-43, Table 1)")

# %% [markdown]
# ## 1 · The problem
#
# Test case 1's observer starts on the DRO of Table 2 (its printed $\dot y_0$ is corrected in notebook 01) and must
# reach the printed final state $x_{\mathcal S}(t_f)$ on a neighbouring DRO after two periods, with a thrust
# acceleration of at most $a_{max} = 10^{-6}$ km/s² (Table 3) **and none at all inside the observation window
# $[3P/4, 3P/2]$** (12.1-24.3 d): the window ends are moved onto nodes and every node of the window gets the bound
# zero, so the first-order-hold thrust vanishes on the whole window. With $\alpha_h = 0$ the objective of Eq. 42 is
# the total impulse plus the defect penalty.

# %%
sc = wolf_jones.test_case_1()
dro = sc.row_checks["observer_t0"].corrected
x_final = sc.observer_xf
T = sc.duration
t, k_ws, k_we = sc.node_times(N_NODES, SIGMA)  # Sundman nodes, window ends moved onto nodes
A_MAX = sc.a_max
# The node controls are accelerations (first-order hold, Eq. 27), so the bound is a_max at every node outside the
# window (the acceleration reading of Eqs. 40-41, notebook 04) and zero at the window's nodes.
u_max = sc.control_bounds(t)
in_window = u_max == 0
print(f"transfer time {em.tu_to_days(T):.2f} d, {N_NODES} Sundman nodes (sigma = {SIGMA}), "
      f"a_max = {A_MAX:.4f} LU/TU^2, zero on nodes {k_ws}..{k_we} "
      f"({em.tu_to_days(t[k_ws]):.2f}-{em.tu_to_days(t[k_we]):.2f} d); |x_f - x(T) ballistic| = "
      f"{np.linalg.norm(propagate(em, dro.x0, T).x[-1] - x_final):.2e}")

# %% [markdown]
# ## 2 · One SCvx run, step by step
#
# Each iteration (i) discretises the controlled dynamics about the reference nodes with a first-order hold:
# $x_{k+1} = A_kx_k + B_k^-u_k + B_k^+u_{k+1} + r_k + E_k\epsilon_k$ (Eq. 30b, matrices from heyoka's state and
# parameter sensitivities, notebook 04); (ii) solves the second-order-cone program of Eq. 30 with the trust region
# $\|\delta x_k\|+\|\delta u_k\|\le\eta$ and the virtual control $\epsilon_k$ penalised by $\gamma\|E_k\epsilon_k\|_1$;
# (iii) compares the actual decrease of the nonlinear cost $\mathcal J$ (Eq. 42, with the multiple-shooting defects
# of Eq. 34) with the decrease $\mathcal J - \mathcal L$ predicted by the convex model (Eq. 36).
#
# The defect term is where this package departs from the printed method by default: instead of the L1 exact
# penalty $\gamma\sum_k\Delta t_k\|\nu_k\|_1$ it uses the augmented Lagrangian of SCvx* (Oguri 2023),
# $\sum_k\lambda_k^\top\delta_k + \tfrac w2\|\delta_k\|^2$, whose multipliers $\lambda$ are updated (and weight $w$
# raised) whenever an accepted step changes the cost by less than a shrinking threshold. With an information reward
# the exact penalty creeps (notebook 05 shows it); without one both variants converge, compared below. The
# trust-region rules are those of Table 1:
#
# | $\rho$ | trust region | reference |
# |---|---|---|
# | $\rho<\rho_0$ | $\eta/\beta_{sh}$ | kept (step rejected) |
# | $\rho_0\le\rho<\rho_1$ | $\eta/\beta_{sh}$ | new |
# | $\rho_1\le\rho<\rho_2$ | $\eta$ | new |
# | $\rho_2\le\rho$ | $\beta_{gr}\eta$ | new |
#
# The paper leaves $\rho_{0,1,2}$, $\beta$, $\gamma$ and $\eta_0$ to the user; ours (from Malyuta et al. 2022) are
# printed below. The convex subproblem is built once with `cvxpy.Parameter`s and re-solved by Clarabel.
#
# **Two departures from Table 1** (both in `cislunar.guidance.scvx`, listed in the table at the end):
# (i) *noise rule*: when the predicted decrease is at the subproblem's noise level,
# $|\mathcal J - \mathcal L| \le 10^{-9}(1+|\mathcal J|)$ (`noise_tol`), the ratio is not formed and $\rho$ is set to
# 1, so such a step is accepted even when its prediction is slightly negative, which Eq. 36 and Table 1 would
# reject; (ii) *cap*: the trust region never grows beyond $\eta_{max}$, which Table 1 does not have.

# %%
settings = scvx.SCvxSettings()
print(settings)
x_guess = propagate(em, dro.x0, t).x  # ballistic initial guess
res = scvx.solve_scvx(em, t, x_guess, np.zeros((t.size, 3)), u_max, x_final=x_final, settings=settings)
print(f"converged in {len(res.history)} iterations: impulse {res.impulse * em.velocity_unit_km_s * 1e3:.4f} m/s, "
      f"largest defect {res.max_defect:.1e}")
for h in res.history:
    print(f"  it {h['iteration']:2d}: J = {h['cost']:.6e} -> {h['new_cost']:.6e}, predicted {h['predicted']:.2e}, "
          f"rho = {h['rho']:.3f}, eta = {h['eta']:.3g}, {'accepted' if h['accepted'] else 'rejected'}"
          f"{', on the trust-region boundary' if h['tr_active'] else ''}, max defect {h['max_defect']:.1e}"
          f"{', multipliers updated' if h['multiplier_update'] else ''}")
res_pen = scvx.solve_scvx(em, t, x_guess, np.zeros((t.size, 3)), u_max, x_final=x_final,
                          settings=scvx.SCvxSettings(method="penalty"))
print(f"exact-penalty variant: {len(res_pen.history)} iterations, impulse "
      f"{res_pen.impulse * em.velocity_unit_km_s * 1e3:.4f} m/s (relative difference "
      f"{abs(res_pen.impulse - res.impulse) / res.impulse:.1e})")
window_thrust = float(np.max(np.linalg.norm(res.u[in_window], axis=1)))
print(f"largest thrust at the window nodes: {window_thrust:.1e} LU/TU^2")

n_acc = sum(h["accepted"] for h in res.history)
updates = [h["iteration"] for h in res.history if h["multiplier_update"]]
rhos = [h["rho"] for h in res.history]
noise_level = [abs(h["predicted"]) <= settings.noise_tol * (1 + abs(h["cost"])) for h in res.history]
real = [h for h, nl in zip(res.history, noise_level) if not nl]
forced = [h["iteration"] for h, nl in zip(res.history, noise_level) if nl]
rho_real = [h["rho"] for h in real]
print(f"{n_acc} of {len(res.history)} steps accepted; {len(real)} with a predicted decrease above the noise level, "
      f"rho in [{min(rho_real):.3f}, {max(rho_real):.3f}]; rho set to 1 by the noise rule at iterations {forced} "
      f"(predicted {', '.join(format(res.history[i]['predicted'], '.1e') for i in forced)}; "
      f"{sum(res.history[i]['predicted'] < 0 for i in forced)} negative)")
print(f"eta {res.history[0]['eta']:g} at the start, {res.history[-1]['eta']:g} (eta_max = {settings.eta_max:g}) "
      f"at the end; multipliers updated (and weight raised) after iterations {updates}")
# convergence rate (the paper cites 'global convergence and superlinear convergence rate', Mao et al. 2018):
# ratio of the largest defect after each step to that after the previous one
defects = np.array([h["max_defect"] for h in res.history])
defect_ratio = defects[1:] / defects[:-1]
print("largest-defect ratio per step:", np.array2string(defect_ratio, precision=2, separator=", "))

fig, axes = plt.subplots(1, 3, figsize=(15, 4.4), layout="constrained")
# J as a sawtooth: each step runs from J before (at x = it) to J after (at x = it + 1); a multiplier/weight update
# then redefines J at the same trajectory (vertical jump at x = it + 1)
for h in res.history:
    it = h["iteration"]
    axes[0].semilogy([it, it + 1], [h["cost"], h["new_cost"]], "-", color="C0", marker="o", ms=3)
for h, nxt in zip(res.history[:-1], res.history[1:]):
    if h["multiplier_update"]:
        axes[0].semilogy([h["iteration"] + 1] * 2, [h["new_cost"], nxt["cost"]], ":", color="C1", lw=1.5)
axes[0].plot([], [], "-o", ms=3, color="C0", label="SCvx step (J does not rise)")
axes[0].plot([], [], ":", lw=1.5, color="C1", label=r"$\lambda$ update, $w$ raised (J redefined)")
axes[0].set(xlabel="iteration [-]", ylabel=r"augmented-Lagrangian cost $\mathcal{J}$ [non-dim.]",
            title="cost per SCvx step")
impulse_hist = np.array([h["impulse"] for h in res.history]) * em.velocity_unit_km_s * 1e3
axes[1].plot([h["iteration"] + 1 for h in res.history], impulse_hist, "o-", color="C2")
axes[1].set(xlabel="iteration [-]", ylabel="total impulse after the step [m/s]",
            title="impulse rises as the defects close")
axes[2].semilogy([h["iteration"] + 1 for h in res.history], [max(h["max_defect"], 1e-16) for h in res.history],
                 "o-", color="C0")
axes[2].axhline(settings.defect_tol, color="0.4", ls="--", lw=0.8, label="convergence tolerance")
axes[2].set(xlabel="iteration [-]", ylabel="largest defect after the step\n[LU or LU/TU]", title="defects")
for ax in axes:
    ax.xaxis.set_major_locator(plt.MaxNLocator(integer=True))
    for it in updates:  # the updates happen between steps: mark them in every panel
        ax.axvline(it + 1, color="C1", lw=0.6, alpha=0.35, zorder=0)
for ax in (axes[0], axes[2]):
    ax.yaxis.set_minor_formatter(plt.NullFormatter())  # decade labels only: no colliding minor tick labels
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), frameon=False)  # below the axes
fig.suptitle("SCvx iterations, minimum-impulse DRO transfer (test case 1 boundary conditions); "
             "faint red lines: multiplier updates")
_ = plotting.save_figure(fig, "03_iterations", output_dir=out)

# %% [markdown]
# **Reading the iterations.** The augmented-Lagrangian cost $\mathcal J$ is not one fixed function over the run:
# each multiplier update moves $\lambda$ and raises $w$, which raises $\mathcal J$ at the *same* trajectory (dotted
# red jumps in the left panel). No SCvx step raises the $\mathcal J$ it was taken on (solid segments; steps whose
# predicted decrease is below the noise level leave it unchanged), so the rise of $\mathcal J$ over the run is not
# divergence; it is the price of closing the defects. The ballistic
# guess misses $x_f$ (printed above), so the cheapest trajectory under a small weight leaves defects open and
# spends almost nothing; as $w$ grows the defects close (right panel) and the impulse climbs to the converged value
# (middle panel), which is the quantity the run minimises once the defects vanish. Every step is accepted
# (printed above): the steps with a real predicted decrease have $\rho$ close to 1 (the convex model is accurate at
# this scale); the others, below the noise level, get $\rho = 1$ from the noise rule, not from the ratio test. The
# trust region grows to its cap $\eta_{max}$ after the first step and stays there, so its history is only printed.
# The largest defect does not fall steadily (printed ratios, several near 1): its progress is paced by the multiplier
# and weight updates, so this run says nothing about the superlinear rate the paper cites from Mao et al. (2018).

# %% [markdown]
# ## 3 · Is the converged trajectory real?
#
# The virtual control is a modelling device: at convergence it must vanish, and the first-order-hold control, fed
# to the *nonlinear* dynamics from the initial state alone (single shooting), must reach the terminal state.

# %%
x_single = D.propagate_foh(em, dro.x0, t, res.u)
terminal_miss_km = float(np.linalg.norm(x_single[-1, :3] - x_final[:3]) * em.length_unit_km)
terminal_miss_mm_s = float(np.linalg.norm(x_single[-1, 3:] - x_final[3:]) * em.velocity_unit_km_s * 1e6)
print(f"single shooting with the converged control misses x_f by {terminal_miss_km:.2e} km and "
      f"{terminal_miss_mm_s:.2e} mm/s")
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.6), layout="constrained")
unorm = np.linalg.norm(res.u, axis=1) * em.acceleration_unit_km_s2 * 1e9  # µm/s²
a_max_um = A_MAX * em.acceleration_unit_km_s2 * 1e9
ax1.axvspan(em.tu_to_days(t[k_ws]), em.tu_to_days(t[k_we]), color="0.9", label="observation window (no thrust)")
ax1.plot(em.tu_to_days(t), unorm, ".-", label="|u| at the nodes")
ax1.set(xlabel="time [days]", ylabel="thrust acceleration [µm/s²]", ylim=(0, None),
        title=f"converged control ($a_{{max}}$ = {a_max_um:.0f} µm/s², off the scale)")
ax1.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.15), frameon=False)  # below the axes
rel_km = (x_single - propagate(em, dro.x0, t).x)[:, :2] * em.length_unit_km
plotting.plot_rotating(ax2, (x_single - propagate(em, dro.x0, t).x)[None], em, "xy", units="km", marker=".")
ax2.plot(*rel_km[0], "o", color="C2", ms=7, zorder=3, label="start (same state)")
ax2.plot(*rel_km[-1], "s", color="C3", ms=7, zorder=3, label=r"end: $x_f$ on the neighbouring DRO")
ax2.set(xlabel=r"$\Delta x$ [km]", ylabel=r"$\Delta y$ [km]",
        title="converged minus initial DRO, at the nodes (rotating frame)")
ax2.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=2, frameon=False)
_ = plotting.save_figure(fig, "03_converged_control", output_dir=out)

# %% [markdown]
# ## 4 · Independence from the initial guess
#
# SCvx converges to a local optimum; for this mildly nonlinear transfer we expect the same one from different
# starting points: a straight blend between the forward and backward ballistic arcs with random controls (5% of
# $a_{max}$; from much rougher guesses the trust region shrinks and progress becomes slow, a known SCvx trait).

# %%
impulses, iterations = [], []
for _ in range(N_GUESSES):
    back = propagate(em, x_final, t[::-1]).x[::-1]
    s = (t / t[-1])[:, None]
    guess = (1 - s) * x_guess + s * back
    r = scvx.solve_scvx(em, t, guess, 0.05 * A_MAX * rng.standard_normal((t.size, 3)) * (u_max > 0)[:, None], u_max,
                        x_final=x_final,
                        settings=scvx.SCvxSettings(max_iter=200))
    impulses.append(r.impulse)
    iterations.append(len(r.history))
spread = float((max(impulses) - min(impulses)) / res.impulse)
print("impulses from random guesses [m/s]:", np.round(np.array(impulses) * em.velocity_unit_km_s * 1e3, 6),
      f"relative spread {spread:.1e}; iterations {iterations}")

# %% [markdown]
# ## 5 · Paper versus reproduction
#
# The paper reports no standalone SCvx run; its numbers come with the information reward (notebooks 05-06). The
# rows below check what the method section states.

# %%
table.add_typed("SCvx converges with defects driven to zero (Eqs. 30, 42)", "yes (method)",
          f"{len(res.history)} iterations, largest defect {res.max_defect:.0e}",
          "reproduced" if res.max_defect < 1e-9 else "differs: defects remain",
          f"tolerance: largest node defect < 1e-9 LU ({em.lu_to_km(1e-9) * 1e3:.2f} m)")
table.add_typed("global convergence and superlinear rate (Mao et al. 2018, cited)", "stated, not shown",
          f"largest-defect ratio per step {defect_ratio.min():.1e} to {defect_ratio.max():.1e}",
          "differs: no superlinear rate seen",
          "global convergence is consistent with this run (the ballistic guess and the random guesses of section 4 "
          "all converge), but the largest defect falls irregularly (ratios near 1 for several steps), paced by the "
          "multiplier and weight updates of our SCvx* variant, not superlinearly; the cited theorem is for Mao's "
          "penalty SCvx, whose printed form does not converge on test case 1 (notebook 05)")
table.add_typed("converged FOH control flies the nonlinear dynamics to x_f", "implied",
          f"miss {terminal_miss_km:.1e} km, {terminal_miss_mm_s:.1e} mm/s", "reproduced" if terminal_miss_km < 1.0
          else "differs: single-shooting miss too large",
          "tolerance 1 km, fixed before the run: node defects below 5e-10 LU (0.2 m) grow over 32 days of free flight")
table.add_typed("trust-region parameters (Table 1)", "user-defined, not given",
          f"rho = {settings.rho0}/{settings.rho1}/{settings.rho2}, beta = {settings.beta_shrink}/{settings.beta_grow}, "
          f"eta0 = {settings.eta0:g}, eta_max = {settings.eta_max:g}, w0 = {settings.penalty_weight0:g}",
          "not in paper", "typical values from Malyuta et al. 2022 and Oguri 2023")
table.add_typed("minimum impulse, test case 1 boundary conditions", "not reported (alpha_h = 0 not shown)",
          f"{res.impulse * em.velocity_unit_km_s * 1e3:.4f} m/s", "not in paper",
          "corrected x_S(t0) (notebook 01) to printed x_S(tf), two periods")
table.add_typed("same optimum from different initial guesses", "-", f"relative impulse spread {spread:.0e}",
          "beyond paper", f"{N_GUESSES} random guesses")
table.add_typed("zero thrust in the observation window [3P/4, 3P/2]", "a_max = 0 there (test case 1)",
          f"largest window thrust {window_thrust:.0e}", "reproduced" if window_thrust == 0 else
          "differs: thrust in the window", "zero bound at every window node (FOH: zero on the whole window)")
table.add_typed("defect handling", "L1 exact penalty, trapezoid over node defects (Eqs. 42-43)",
          "augmented Lagrangian (SCvx*); exact penalty kept as an option",
          "differs: documented choice", "the exact penalty creeps with an information reward (notebook 05); without "
          f"one both agree (impulse difference {abs(res_pen.impulse - res.impulse) / res.impulse:.0e}); the penalty "
          "uses one weight dt_k per interval: Eq. 42's trapezoid needs a defect at the last node, where none exists")
table.add_typed("trust-region update (Table 1)", "rho < rho0 rejects; growth by beta_gr without cap",
          f"noise rule at iterations {forced}; eta capped at eta_max = {settings.eta_max:g}",
          "differs: documented choice",
          f"rho = 1 when |predicted| <= {settings.noise_tol:g} (1 + |J|), which accepted "
          f"{sum(res.history[i]['predicted'] < 0 for i in forced)} step(s) with a negative prediction that Eq. 36 "
          f"would reject; steps with a real predicted decrease had rho in [{min(rho_real):.3f}, {max(rho_real):.3f}]")
table.display()
