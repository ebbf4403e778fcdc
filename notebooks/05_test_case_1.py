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
# judge the plans with the Cramér-Rao lower bound (CRLB) of a sequential estimator. Along the way: how the printed
# SCvx (L1 exact penalty, linear information model) behaves here with an information reward and what makes our
# solver converge, how many local optima the problem has, and which of the paper's printed numbers are slips.
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
N_NODES = 18 if QUICK else 40  # Sundman-spaced nodes over the two periods (the paper does not give its N)
N_NODES_ALT = 24 if QUICK else 28  # second grid of the mesh check (section 5)
SIGMA = 1.0  # Sundman exponent (notebook 04)
ALPHAS = ([0.0, 5e-3, 1e-2] if QUICK else  # quick: the right panels of Figs. 1 and 3 show the grid's top
          [0.0, 1e-3, 2e-3, 3e-3, 5e-3, 7e-3, 1e-2, 1.5e-2, 2e-2])
PENALTY_ITER = 10 if QUICK else 80  # iterations granted to the paper's exact-penalty SCvx in section 4
PENALTY_ITER_LONG = 20 if QUICK else 300  # the same at gamma = 1e3 with a larger iteration limit
PENALTY_GAMMAS = [1e1, 1e3, 1e5] if QUICK else [1e1, 1e2, 1e3, 1e4, 1e5]  # exact-penalty weights swept (unstated)
BUDGETS_EXTRA_MPS = [5.0] if QUICK else [1.0, 5.0, 20.0]  # impulse budgets above the baseline's (section 8)
BUDGET_RTOL = 0.02  # a budget counts as met within 2 % (fixed before solving)

import time

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection
from scipy.stats import spearmanr

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import ImpactError, propagate
from cislunar.guidance import discretization as D
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import scenarios as wolf_jones
from cislunar.papers.wolf_jones.reference import CLOSURE_TOL
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.sensing import covariance as cov

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
# once per day with 100 m noise per axis. Priors: 100 km and $10^{-2}$ km/s = 10 m/s per axis for both spacecraft
# (Table 3); a 10 m/s velocity error alone moves a position by 864 km in a day, the transient of Fig. 4.
#
# **The printed observer state is not a DRO.** Its $\dot y_0 = 0.528996986$ does not close (notebook 01): held at
# the printed $x_0$, the periodic DRO has $\dot y_0 = 0.5559319$; a transcription slip is the likely cause (the
# two values differ from the second digit on). What would the printed state give? Flown ballistically it leaves the DRO region and **hits the Moon before
# the two periods are over**; reaching $x_{\mathcal S}(t_f)$ from it with the window constraint costs tens of m/s
# (computed below: essentially the 27.6 m/s velocity slip), where the corrected state needs well under 1 m/s
# (section 5). We use the corrected state.
#
# **Which number slipped, $x_0$ or $\dot y_0$?** Both readings give a DRO: hold $x_0$ and correct $\dot y_0$, or hold
# the printed $\dot y_0$ and correct $x_0$. Evidence that does not use the paper's day counts: the paper calls the
# spacecraft's orbits "adjacent" DROs, and the six other printed rows of Tables 2 and 4 (all periodic as printed)
# span a narrow range of $x_0$ and period. The reading whose $x_0$ and period fall inside that span is adopted.
# The day counts of the text ("12 and 23 days" for test case 1's window $[3P/4, 3P/2]$, "roughly 17 and 32 days"
# for test case 2's $[P, 2P]$) are printed for both readings too, with a tolerance of 1 day; they were looked at
# when the reading was first chosen, so the window rows built on it are at best "consistent (tuned)", never
# "reproduced" (test case 1's row even differs: $3P/2$ misses the text's 23 d by more than the tolerance).
#
# **Process noise.** Table 3 prints $Q = 10^{-11}$ "km/s³". Notebook 06 (and `cislunar.papers.wolf_jones.scenarios`) tries the
# plausible readings against the paper's statement that the CRLB stays bounded over the window and adopts the
# non-dimensional acceleration PSD $q = 10^{-11}$ LU²/TU³; the literal unit fix $10^{-11}$ km²/s³ would let the
# observer error grow to tens of thousands of km. Since the reading was picked by the very property the paper
# claims (a bounded CRLB), that claim is no independent test of it: its rows are "consistent (tuned)". Section 7
# judges the planned trajectories with both readings.

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
# the two readings of the slip; independent evidence: the span of the six other (periodic) rows of Tables 2 and 4
vy0_held = orbits.correct_symmetric(em, sc.observer_x0_printed + [0.02, 0, 0, 0, 0, 0], fix="vy0")
readings = {"x0 held (vy0 corrected)": (sc.observer_x0, P),
            "vy0 held (x0 corrected)": (vy0_held.x0, vy0_held.period)}
other_rows = {f"case {n} {lab}": c for n, s_ in ((1, sc), (2, wolf_jones.test_case_2()))
              for lab, c in s_.row_checks.items() if lab != "observer_t0"}
x0_span = (min(c.x0 for c in other_rows.values()), max(c.x0 for c in other_rows.values()))
p_span = (min(em.tu_to_days(c.corrected.period) for c in other_rows.values()),
          max(em.tu_to_days(c.corrected.period) for c in other_rows.values()))
print(f"the {len(other_rows)} other rows of Tables 2 and 4: x0 {x0_span[0]:.5f}-{x0_span[1]:.5f} LU, periods "
      f"{p_span[0]:.2f}-{p_span[1]:.2f} d, closures <= {max(c.raw_closure for c in other_rows.values()):.1e}")
reading_adjacent, reading_miss, reading_miss23 = {}, {}, {}
for name, (x0_r, P_r) in readings.items():
    pd = em.tu_to_days(P_r)
    w1, w2 = (0.75 * pd, 1.5 * pd), (pd, 2.0 * pd)
    reading_adjacent[name] = x0_span[0] <= x0_r[0] <= x0_span[1] and p_span[0] <= pd <= p_span[1]
    reading_miss[name] = max(abs(w1[0] - 12.0), abs(w2[0] - 17.0), abs(w2[1] - 32.0))
    reading_miss23[name] = abs(w1[1] - 23.0)
    print(f"{name:<26}: x0 = {x0_r[0]:.7f}, vy0 = {x0_r[4]:.7f}, P = {pd:.2f} d (inside the span of the other rows: "
          f"{reading_adjacent[name]}) -> case 1 window {w1[0]:.2f}-{w1[1]:.2f} d, case 2 window "
          f"{w2[0]:.2f}-{w2[1]:.2f} d")
print("largest miss of the paper's 12 (case 1), 17 and 32 days (case 2):",
      {k: round(float(v), 2) for k, v in reading_miss.items()},
      "; miss of its '23 days' (case 1 window end):", {k: round(float(v), 2) for k, v in reading_miss23.items()})

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
# $\mathcal I$ of the window (Eq. 18), its gradient (the reverse-mode derivative of Eq. 18 through the
# square-root recursion, where the paper writes Eqs. 44-52 term by term) and a Hessian by finite differences of the
# gradient; the process noise is held fixed along the ballistic window arc so that value and gradient describe the
# same function (the paper also neglects the sensitivity of $\tilde P$).

# %%
t, k_ws, k_we = sc.node_times(N_NODES, SIGMA)
u_max = sc.control_bounds(t)
x_ball, u_ball = sc.ballistic_guess(t)
info = sc.information_model()
if QUICK:  # quick mode: forward-difference Hessian (6 gradients instead of 12; it only shapes the trust-region model)
    info.hessian_scheme = "forward"
in_window = u_max == 0
print(f"{N_NODES} nodes; window nodes {k_ws}..{k_we} (t = {em.tu_to_days(t[k_ws]):.3f}, "
      f"{em.tu_to_days(t[k_we]):.3f} d); node spacing {em.tu_to_days(np.diff(t)).min():.2f}-"
      f"{em.tu_to_days(np.diff(t)).max():.2f} d")
print(f"ballistic: I = {info(x_ball[k_ws], 0):.3f} nats; |x(t_f) - x_S(t_f)| = "
      f"{np.linalg.norm(x_ball[-1, :3] - sc.observer_xf[:3]) * em.length_unit_km:.1f} km")

# %% [markdown]
# ## 3 · The homotopy sweep, both ways
#
# For every $\alpha_h$ SCvx minimises $(1-\alpha_h)\,\mathrm{impulse} - \alpha_h\mathcal I$ (Eq. 42) subject to the
# dynamics, the bounds and the terminal state. The SCvx here (`cislunar.guidance.scvx`, notebook 03) departs from the printed
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
# whether the step sat on the trust-region boundary. Then the same problem with the printed method: the L1 exact
# penalty on the defects (Eq. 43) and the *linear* information model of Eq. 44. The paper gives neither the
# penalty weight $\gamma$ nor an iteration limit, so both are swept: $\gamma$ over four decades with a fixed number
# of iterations, and $\gamma = 10^3$ once more with a larger limit. A hybrid (exact penalty with our quadratic
# information model, $\gamma = 10^3$) separates the effect of the penalty from that of the information model.

# %%
i5 = ALPHAS.index(5e-3)
cold = solve(5e-3, x_ball, u_ball)
print(f"cold start alpha_h = 5e-3: {cold.iterations} iterations, cost {cold.cost:.9f} (best of sweeps "
      f"{best[i5].cost:.9f})")
print(f"{'it':>3} {'predicted':>10} {'err defect':>11} {'err MI':>10} {'rho':>8} {'eta':>9} {'TR':>3} {'defect':>8}")
for h in cold.history:
    print(f"{h['iteration']:3d} {h['predicted']:10.2e} {h['model_error_defect']:11.2e} {h['model_error_info']:10.2e} "
          f"{h['rho']:8.3f} {h['eta']:9.2e} {'on' if h['tr_active'] else '':>3} {h['max_defect']:8.1e}")


def penalty_run(gamma, max_iter, model):
    """Exact-penalty SCvx at alpha_h = 5e-3 from the ballistic DRO: outcome, history, best accepted cost."""
    st = scvx.SCvxSettings(method="penalty", information_model=model, defect_weight=gamma, max_iter=max_iter)
    try:
        r = scvx.solve_scvx(em, t, x_ball, u_ball, u_max, x_final=sc.observer_xf, info=info, info_node=k_ws,
                            alpha=5e-3, settings=st)
        hist, outcome, ok_ = r.history, f"converged in {r.iterations} iterations (largest defect {r.max_defect:.1e})", True
    except scvx.SCvxError as exc:
        hist, outcome, ok_ = exc.history, exc.reason, False
    acc = [h["new_cost"] for h in hist if h["accepted"]]
    return dict(gamma=gamma, max_iter=max_iter, model=model, converged=ok_, outcome=outcome, history=hist,
                best=min(acc) if acc else np.nan, eta=hist[-1]["eta"] if hist else np.nan)


t0 = time.perf_counter()
pen_runs = [penalty_run(g, PENALTY_ITER, "linear") for g in PENALTY_GAMMAS]
pen_runs.append(penalty_run(1e3, PENALTY_ITER_LONG, "linear"))
pen_hybrid = penalty_run(1e3, PENALTY_ITER, "quadratic")
print(f"printed method (L1 exact penalty, linear MI model of Eq. 44), alpha_h = 5e-3, from the ballistic DRO "
      f"({time.perf_counter() - t0:.0f} s for {len(pen_runs) + 1} runs); best of sweeps: cost {best[i5].cost:.6f}")
for r in pen_runs + [pen_hybrid]:
    print(f"  gamma {r['gamma']:7.0e}, {r['model']:>9} MI model, limit {r['max_iter']:3d}: {r['outcome']}; best "
          f"accepted cost {r['best']:.6f}; last eta {r['eta']:.1e}")
pen_printed = next(r for r in pen_runs if r["gamma"] == 1e3 and r["max_iter"] == PENALTY_ITER)
pen_history = pen_printed["history"]
pen_any = any(r["converged"] for r in pen_runs)

fig, axes = plt.subplots(1, 3, figsize=(14, 3.8))
ha = cold.history
its = [h["iteration"] for h in ha]
axes[0].semilogy(its, [max(abs(h["predicted"]), 1e-16) for h in ha], "o-", ms=3, label="augmented Lagrangian")
axes[0].semilogy([h["iteration"] for h in pen_history], [max(abs(h["predicted"]), 1e-16) for h in pen_history],
                 ".-", ms=3, color="C3", label=r"printed: L1 penalty, linear MI ($\gamma = 10^3$)")
axes[0].set(xlabel="iteration [-]", ylabel="|predicted decrease| [-]")
axes[1].semilogy(its, [h["eta"] for h in ha], "o-", ms=3)
axes[1].semilogy([h["iteration"] for h in pen_history], [h["eta"] for h in pen_history], ".-", ms=3, color="C3")
axes[1].set(xlabel="iteration [-]", ylabel=r"trust-region radius $\eta$ [-]")
axes[2].semilogy(its, [max(h["max_defect"], 1e-16) for h in ha], "o-", ms=3)
axes[2].semilogy([h["iteration"] for h in pen_history], [max(h["max_defect"], 1e-16) for h in pen_history], ".-",
                 ms=3, color="C3")
axes[2].set(xlabel="iteration [-]", ylabel="largest defect [LU, LU/TU]")
fig.suptitle(r"SCvx on test case 1, $\alpha_h = 5\times10^{-3}$, from the ballistic DRO")
fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8)
fig.tight_layout(rect=(0, 0.08, 1, 1))
_ = plotting.save_figure(fig, "05_convergence", output_dir=out)

# %% [markdown]
# **Reading.** Whether the printed method converges is read from the printed outcomes: none of the exact-penalty
# runs, at any $\gamma$ of the sweep or with the larger iteration limit, meets the stopping test; the trust region
# shrinks (last $\eta$ printed) while the cost creeps towards our solver's optimum (a best accepted cost slightly
# *below* it, as at one $\gamma$ of the sweep, comes with defects still open, so it is not a feasible
# improvement). The hybrid with our quadratic
# information model does not converge within its limit either: the quadratic model alone does not make the printed
# method converge (whether the augmented Lagrangian alone would, with Eq. 44's linear model, is not checked here).
# The closing table therefore separates the printed method (which does
# not converge here) from our modified solver (which converges on the whole grid).

# %% [markdown]
# ## 5 · Does every plan fly, and does it depend on the node grid? (beyond the paper)
#
# Each converged trajectory is re-flown by single shooting: its first-order-hold control alone, from $x_{\mathcal
# S}(t_0)$, through the nonlinear CR3BP. The terminal miss measures how real the plan is; the defects and bounds are
# checked as in the tests.
#
# **Mesh check.** The thrust bound never binds (largest $|u|/a_{max}$ below 1 in the table), so the optimal thrust
# is a few single-node spikes: the plans are nearly impulsive and the node grid, which the paper does not give,
# could move their impulse. We solve $\alpha_h = 5\times10^{-3}$ again on a second Sundman grid (warm-started from
# the first solution interpolated onto it) and compare impulse, information and terminal RMS.

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

t_alt, k_alt, _ = sc.node_times(N_NODES_ALT, SIGMA)
x_alt = np.stack([np.interp(t_alt, t, best[i5].x[:, j]) for j in range(6)], axis=1)
u_alt = np.stack([np.interp(t_alt, t, best[i5].u[:, j]) for j in range(3)], axis=1)
mesh_solver = wolf_jones.ScenarioSolver(sc, t_alt, k_alt, information=info, settings=settings)
mesh = mesh_solver(5e-3, x_alt, u_alt)
mesh_rms = [wolf_jones.evaluate_crlb(sc, r.x[k]).terminal_rms_km[0] for r, k in ((best[i5], k_ws), (mesh, k_alt))]
mesh_dimp = abs(mesh.impulse - best[i5].impulse) / best[i5].impulse
print(f"alpha_h = 5e-3 on {N_NODES} nodes: {best[i5].impulse * MPS:.2f} m/s, I = {best[i5].information:.3f} nats, "
      f"observer RMS {mesh_rms[0]:.2f} km; on {N_NODES_ALT} nodes: {mesh.impulse * MPS:.2f} m/s, "
      f"I = {mesh.information:.3f} nats, RMS {mesh_rms[1]:.2f} km (impulse change {100 * mesh_dimp:.1f} %)")


# %% [markdown]
# ## 6 · Figures 1-3: trajectories and thrust
#
# Between nodes the control is linear in time, so a dense re-flight with linearly interpolated controls is the
# same trajectory. Thrust arcs (|a| above 1 % of $a_{max}$) are red, coasts blue, as in the paper. Fig. 3 shows
# the magnitude and all three components; the paper plots $a_x$ and $a_y$ only, since the problem is planar, and
# $a_z$ stays at zero here too (its largest value is printed below the figure).

# %%
def dense_flight(res, n=600):
    td = np.union1d(t, np.linspace(0.0, t[-1], n))
    ud = np.stack([np.interp(td, t, res.u[:, i]) for i in range(3)], axis=1)
    return td, D.propagate_foh(em, sc.observer_x0, td, ud), ud


t_dense = np.linspace(0.0, sc.duration, 600)
ref_dro = propagate(em, sc.observer_x0, t_dense).x
show = [ALPHAS.index(5e-3), len(ALPHAS) - 1]  # the paper's 5e-3 and 2e-2 (quick mode: the grid's largest)
fig, axes = plt.subplots(1, 2, figsize=(10, 5.6))
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
fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8, bbox_to_anchor=(0.5, 0.0))
fig.suptitle("Fig. 1 analogue: observer trajectory, Moon-centred rotating frame (thrust: |a| above 1 % of a_max)")
fig.tight_layout(rect=(0, 0.06, 1, 1))
_ = plotting.save_figure(fig, "05_fig1_trajectories", output_dir=out)

fig, ax = plt.subplots(figsize=(6.5, 5.5))
cmap = plt.get_cmap("viridis")
departure_km = []  # largest distance from the reference DRO over the scenario, per alpha_h
for j, (a, r) in enumerate(zip(ALPHAS, best)):
    td, xd, _ = dense_flight(r, 400)
    rel = (xd[:, :3] - propagate(em, sc.observer_x0, td).x[:, :3]) * em.length_unit_km / 1e3
    departure_km.append(float(np.max(np.linalg.norm(rel, axis=1))) * 1e3)
    ax.plot(rel[:, 0], rel[:, 1], color=cmap(j / max(1, len(ALPHAS) - 1)), lw=1.2, label=rf"$\alpha_h$={a:g}")
ax.plot(0, 0, "o", color="C2", ms=6, label="start")
ax.set(xlabel=r"$\Delta x$ [1000 km]", ylabel=r"$\Delta y$ [1000 km]", aspect="equal",
       title="Fig. 2 analogue: position relative to the reference DRO")
ax.legend(fontsize=7, ncol=2, loc="center left", bbox_to_anchor=(1.02, 0.5))
_ = plotting.save_figure(fig, "05_fig2_relative_motion", output_dir=out)
departure_monotone = bool(np.all(np.diff(departure_km) >= 0))
print("largest departure from the reference DRO [km]:", ", ".join(f"{a:g}: {d:.0f}" for a, d in
                                                                   zip(ALPHAS, departure_km)))

fig, axes = plt.subplots(1, 2, figsize=(13, 4.3), sharey=True, layout="constrained")
for ax, i in zip(axes, show):
    td, _, ud = dense_flight(best[i])
    days = em.tu_to_days(td)
    scale = em.acceleration_unit_km_s2 * 1e6  # mm/s^2
    ax.axvspan(em.tu_to_days(sc.window[0]), em.tu_to_days(sc.window[1]), color="0.9", label="observation window")
    # |a| first, wide and pale, so the components drawn over it stay visible where one of them carries the thrust
    ax.plot(days, np.linalg.norm(ud, axis=1) * scale, color="0.65", lw=4, label="|a|")
    ax.plot(days, ud[:, 0] * scale, label="$a_x$")
    ax.plot(days, ud[:, 1] * scale, label="$a_y$")
    ax.plot(days, ud[:, 2] * scale, ls="--", label="$a_z$")
    ax.axhline(sc.a_max * scale, color="0.4", ls=":", lw=0.8)
    ax.set(xlabel="time [days]", title=rf"$\alpha_h$ = {ALPHAS[i]:g}")
axes[0].set_ylabel("thrust acceleration [mm/s²]")
handles, labels = axes[0].get_legend_handles_labels()
fig.legend(handles, labels, loc="outside lower center", ncol=5, fontsize=8, frameon=False)
fig.suptitle("Fig. 3 analogue: thrust acceleration (dotted: a_max)")
_ = plotting.save_figure(fig, "05_fig3_thrust", output_dir=out)
az_share = max(float(np.max(np.abs(r.u[:, 2])) / np.max(np.linalg.norm(r.u, axis=1))) for r in best)
print(f"largest |a_z| / largest |a| over the grid: {az_share:.1e} (planar problem: the paper plots a_x, a_y only)")

# %% [markdown]
# ## 7 · Figures 4-5: CRLB over the window and the Pareto curves
#
# The CRLB of the paper's "Performance Evaluation" is the EKF covariance recursion along the true trajectories,
# with the process noise now computed along each planned trajectory (planning held it fixed). Fig. 4 shows the
# position 1-sigma per axis for observer and target; Fig. 5 the total impulse against the position RMS after the
# last measurement of the window. The paper's x-axis "average impulse" is not defined; any per-node or per-day
# average is the total divided by a constant, which does not change the shape of the curve. Finally the plans of
# $\alpha_h = 0$ and the largest $\alpha_h$ are judged again with the literal unit fix of Table 3's process noise.
#
# Observer and target panels look alike, and should: a relative-position measurement fixes
# $x_{\mathcal T} - x_{\mathcal S}$ to 100 m, so the absolute errors of the two spacecraft move together and their
# RMS values agree to a fraction of a kilometre; what the dynamics must supply is the common absolute part.

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
lit_growth = [c.rms_km[0, -1] / c.rms_km[0, 1] for c in lit]  # window end over the 2nd measurement (Fig. 4 test)
print("literal Q, observer RMS at the 2nd measurement -> window end: " + "; ".join(
    f"alpha_h = {ALPHAS[i]:g}: {c.rms_km[0, 1]:.0f} -> {c.rms_km[0, -1]:.0f} km ({g_:.3f} x)"
    for i, c, g_ in zip((0, len(ALPHAS) - 1), lit, lit_growth)))
bounded = bool(np.all(np.array([c.rms_km[:, -1] <= c.rms_km[:, 1] for c in crlb])))
transient = bool(np.all(np.array([c.rms_km[:, 1] > c.rms_km[:, 0] for c in crlb])))

# %% [markdown]
# ## 8 · Beyond the paper: MI against the CRLB, and the baseline at equal impulse
#
# "The mutual information correlates well with the expected performance of a sequential estimator": over the grid,
# the Spearman rank correlation between $\mathcal I$ and the terminal RMS (perfect agreement: -1).
#
# Then the paper's baseline claim, "substantial improvement over a baseline comparison which utilizes solely
# control effort". The minimum-impulse plan ($\alpha_h = 0$) spends the least impulse there is, so "better at equal
# impulse" can only mean: what does each *additional* m/s buy? SCvx has no impulse constraint, but the
# weighted-sum objective traces the Pareto front, and its impulse grows with $\alpha_h$; solving for the
# $\alpha_h$ whose optimum spends a prescribed budget (`wolf_jones.solve_for_impulse`: bracketed secant on
# $\alpha_h$, warm starts from the neighbouring sweep solutions, budget met within 2 %, fixed before solving)
# imposes the budget with the solver as it is. Each such plan is the most informative one for its impulse, and we
# compare it with the baseline and with what interpolation between the grid points of the front would have
# claimed. The interpolation is linear in the logarithm of the RMS (the front falls roughly exponentially with
# impulse; notebook 06 uses the same convention), so on the figure's logarithmic axis it is the straight dashed
# segment between grid points, evaluated at the impulse the solved plan actually spends.

# %%
rho_obs = float(spearmanr(mi, term_obs).statistic)
rho_tgt = float(spearmanr(mi, term_tgt).statistic)
print(f"Spearman rank correlation of MI with terminal RMS: observer {rho_obs:+.3f}, target {rho_tgt:+.3f}")
i_best = int(np.argmax(mi))
print(f"baseline alpha_h = 0: {impulse_mps[0]:.3f} m/s, terminal RMS observer {term_obs[0]:.2f} km, target "
      f"{term_tgt[0]:.2f} km, I = {mi[0]:.2f} nats")
print(f"best information plan alpha_h = {ALPHAS[i_best]:g}: {impulse_mps[i_best]:.2f} m/s, observer "
      f"{term_obs[i_best]:.2f} km, target {term_tgt[i_best]:.2f} km, I = {mi[i_best]:.2f} nats")
budget_rows = []
for extra in BUDGETS_EXTRA_MPS:
    b = impulse_mps[0] + extra
    j = int(np.searchsorted(impulse_mps, b))
    if j >= len(ALPHAS):
        print(f"budget {b:.2f} m/s lies beyond the grid's largest impulse; not solved")
        continue  # bracket on the sweep: impulse_mps[j-1] < b <= impulse_mps[j]
    try:
        hit = wolf_jones.solve_for_impulse(solve, b / MPS, (ALPHAS[j - 1], best[j - 1]), (ALPHAS[j], best[j]),
                                           rtol=BUDGET_RTOL)
    except wolf_jones.ImpulseBudgetError as exc:
        print(f"budget {b:.2f} m/s not reached: {exc.reason}")
        continue
    c = wolf_jones.evaluate_crlb(sc, hit.result.x[k_ws])
    interp = float(np.exp(np.interp(hit.result.impulse * MPS, impulse_mps, np.log(term_obs))))  # log-linear
    budget_rows.append(dict(budget=b, alpha=hit.alpha, impulse=hit.result.impulse * MPS, rms_obs=c.terminal_rms_km[0],
                            rms_tgt=c.terminal_rms_km[1], mi=hit.result.information, interp=interp,
                            solves=len(hit.solves)))
    print(f"budget {b:6.2f} m/s (baseline + {extra:g}): alpha_h = {hit.alpha:.3e} spends {hit.result.impulse * MPS:.2f}"
          f" m/s ({len(hit.solves)} solves); terminal RMS observer {c.terminal_rms_km[0]:.2f} km, target "
          f"{c.terminal_rms_km[1]:.2f} km = {c.terminal_rms_km[0] / term_obs[0]:.2f} x baseline "
          f"(log-interpolation on the grid said {interp:.2f} km at that impulse: "
          f"{c.terminal_rms_km[0] / interp:.2f} x)")

fig, ax = plt.subplots(figsize=(7, 4.6), layout="constrained")
x_hi = max([r["budget"] for r in budget_rows] + [impulse_mps[1]]) * 1.6  # zoom: the budgets and the next grid point
zoom = impulse_mps <= x_hi
xs = np.linspace(impulse_mps[0], impulse_mps[-1], 2000)
ax.plot(xs, np.exp(np.interp(xs, impulse_mps, np.log(term_obs))), "--", color="0.5", lw=1,
        label="interpolation between grid points (linear in log RMS)")
ax.plot(impulse_mps, term_obs, "o", color="0.5", label=r"sweep grid ($\alpha_h$ values)")
for r in budget_rows:  # the gain over interpolation: from the open circle down to the star
    ax.plot([r["impulse"]] * 2, [r["interp"], r["rms_obs"]], "-", color="C3", lw=0.8)
if budget_rows:
    ax.plot([r["impulse"] for r in budget_rows], [r["interp"] for r in budget_rows], "o", ms=7, mfc="white",
            color="C3", label="interpolation at the solved plan's impulse")
    ax.plot([r["impulse"] for r in budget_rows], [r["rms_obs"] for r in budget_rows], "*", ms=13, color="C3",
            label="solved at a prescribed impulse")
ax.plot(impulse_mps[0], term_obs[0], "s", ms=8, color="k", label=r"baseline $\alpha_h = 0$")
shown = np.r_[term_obs[zoom], [r["rms_obs"] for r in budget_rows], [r["interp"] for r in budget_rows]]
ax.set(xlabel="total impulse [m/s]", ylabel="observer position RMS at the window end [km]", yscale="log",
       xlim=(-0.5, x_hi), ylim=(shown.min() / 1.25, shown.max() * 1.25),
       title="Equal-impulse comparison near the baseline")
ax.yaxis.set_major_formatter(plt.FormatStrFormatter("%g"))  # plain numbers at 1, 2, 5 x 10^k km
ax.yaxis.set_minor_locator(plt.LogLocator(subs=(2.0, 5.0)))
ax.yaxis.set_minor_formatter(plt.FormatStrFormatter("%g"))
ax.legend(fontsize=8, loc="upper right")
_ = plotting.save_figure(fig, "05_equal_impulse", output_dir=out)

# %% [markdown]
# **Reading the figure.** Against the baseline every extra m/s pays off strongly (the "x baseline" ratios printed
# above). Against interpolation the solved plans gain most next to the baseline, where the grid's first interval
# is long compared with how fast the front bends: the front drops more steeply just above the baseline than the
# straight segment between its first two grid points, so interpolation understates what a small extra impulse
# buys. Farther out the grid follows the front closely and interpolation is nearly right (ratios near 1).


# %% [markdown]
# ## 9 · Paper versus reproduction
#
# Tolerances fixed before comparing: "reproduced" for a qualitative claim means the stated behaviour holds for
# every $\alpha_h$ of the grid (criterion in the row); day counts of the text within 1 day; "bounded" CRLB means a
# window-end RMS no larger than at the 2nd measurement; "correlates well" a Spearman rank correlation below -0.8.
# Rows resting on a reading chosen with the paper's claim in view (process noise, the slip in Table 2) are at best
# "consistent (tuned)"; the solver rows separate the printed method from ours. The paper prints no number for test
# case 1 beyond its inputs (Tables 2-3), so the quantitative rows are "not in paper" or "beyond paper". Slips in
# the paper are listed with what we used.

# %%
table.add_typed("observer x_S(t0) (Table 2) is a DRO", "vy0 = 0.528996986",
          f"not periodic (misses itself by {chk.raw_closure:.2f} LU); periodic vy0 = {chk.corrected.x0[4]:.7f}",
          "differs: printed vy0 is a slip", f"as printed it {printed_fate}; corrected state used (notebook 01)")
for lab, name in (("observer_tf", "observer x_S(t_f)"), ("target1_t0", "target x_T(1)(t0)")):
    c_ = sc.row_checks[lab]
    table.add_typed(f"Table 2 {name} is a periodic DRO", "implied (DRO family)",
              f"closure after one period {c_.raw_closure:.1e}; period {em.tu_to_days(c_.corrected.period):.2f} d",
              "reproduced" if c_.raw_closure < CLOSURE_TOL else "differs: the printed row does not close",
              f"criterion: closure < {CLOSURE_TOL:g} (nine printed digits allow ~1e-8)")
adopted, rejected = "x0 held (vy0 corrected)", "vy0 held (x0 corrected)"
x0_wins = reading_adjacent[adopted] and not reading_adjacent[rejected]
table.add_typed("which number of x_S(t0) slipped (x0 or vy0)", "orbits called 'adjacent'; six other rows printed",
          f"x0 held: x0 = {sc.observer_x0[0]:.5f}, P = {em.tu_to_days(P):.2f} d; vy0 held: x0 = "
          f"{vy0_held.x0[0]:.5f}, P = {em.tu_to_days(vy0_held.period):.2f} d; other rows: x0 {x0_span[0]:.5f}-"
          f"{x0_span[1]:.5f}, P {p_span[0]:.2f}-{p_span[1]:.2f} d",
          "derived" if x0_wins else "differs: adjacency does not single out one reading",
          "criterion: x0 and period inside the span of the other rows; the text's day counts were looked at first "
          "(largest miss of 12/17/32 d: " + ", ".join(f"{k.split(' (')[0]} {v:.2f} d" for k, v in reading_miss.items())
          + "; of '23 d': " + ", ".join(f"{k.split(' (')[0]} {v:.2f} d" for k, v in reading_miss23.items()) + ")")
w_start, w_end = em.tu_to_days(sc.window[0]), em.tu_to_days(sc.window[1])
table.add_typed("observation window", "[3P/4, 3P/2]; text: '12 and 23 days'", f"{w_start:.2f}-{w_end:.2f} d",
          "consistent (tuned)" if abs(w_start - 12.0) <= 1.0 and abs(w_end - 23.0) <= 1.0 else
          f"differs: 3P/2 misses the text's 23 d by {abs(w_end - 23.0):.2f} d",
          f"tolerance 1 day; P = {em.tu_to_days(P):.2f} d of the adopted reading (chosen with the day counts in view, "
          f"so at best 'consistent (tuned)'); the rejected reading misses 23 d by {reading_miss23[rejected]:.2f} d; "
          f"last daily measurement at {em.tu_to_days(sc.measurement_times[-1]):.2f} d")
table.add_typed("Fig. 3 alpha_h of the left panel", "text: 5e-2; Fig. 3 caption and Fig. 1: 5e-3", "5e-3 shown",
          "differs: text's 5e-2 is a slip", "the caption of Fig. 3 itself and Fig. 1 give 5e-3")
table.add_typed("process noise Q (Table 3)", "1e-11 'km/s^3'", f"q = {sc.q:g} LU^2/TU^3 (acceleration PSD)",
          "consistent (tuned)", "reading chosen as one that keeps this case's CRLB bounded, which is the paper's "
          "Fig. 4 claim (notebook 06, section 9); the SI reading 1e-11 m^2/s^3 would pass the same test")
lit_grows = [g_ > 1.0 for g_ in lit_growth]
table.add_typed("CRLB under the literal Q = 1e-11 km^2/s^3: bounded after the transient?", "bounded (Fig. 4)",
          "; ".join(f"alpha_h = {ALPHAS[i]:g}: {c.rms_km[0, 1]:.0f} -> {c.rms_km[0, -1]:.0f} km ({g_:.3f} x)"
                    for i, c, g_ in zip((0, len(ALPHAS) - 1), lit, lit_growth))
          + f" (adopted q: {crlb[0].rms_km[0, 1]:.0f} -> {term_obs[0]:.0f} km and {crlb[-1].rms_km[0, 1]:.0f} -> "
            f"{term_obs[-1]:.1f} km)",
          "differs: literal reading grows (rejected)" if any(lit_grows) else "consistent (tuned)",
          "criterion as in the Fig. 4 row: window-end RMS at most the 2nd measurement's, for alpha_h = 0 and the "
          f"largest; levels too: {lit[0].terminal_rms_km[0]:.0f} km at alpha_h = 0 is "
          f"{lit[0].terminal_rms_km[0] / wolf_jones.SIGMA_POS_KM:.0f} prior sigmas")
table.add_typed("zero thrust in the observation window", "a_max = 0 in the window",
          f"max |u| in the window {max(window_thrust):.0e}", "derived",
          "imposed input (u_k = 0 at every window node), not a prediction; checked |u| <= 1e-12: "
          f"{max(window_thrust) <= 1e-12}")
pen_summary = "; ".join(f"gamma {r['gamma']:.0e}, {r['max_iter']} it: "
                        + ("converged" if r["converged"] else
                           f"not converged, last defect {r['history'][-1]['max_defect']:.0e}, eta {r['eta']:.0e}")
                        for r in pen_runs)
table.add_typed("printed SCvx (L1 exact penalty, linear MI of Eq. 44) converges, alpha_h = 5e-3", "implied (Figs. 2, 5)",
          pen_summary, "reproduced" if pen_any else "differs: the printed formulation does not converge here",
          "gamma and the iteration limit are unstated: swept (printed in section 4, full reasons there); "
          f"best accepted cost at gamma 1e3: {pen_printed['best']:.5f} vs {best[i5].cost:.5f} of our solver"
          + ("" if pen_any else "; what converges: augmented Lagrangian on the defects, convex quadratic MI model, "
             "round-off-level predicted decrease counted as rho = 1 (row 'modified SCvx')"))
long_run = pen_runs[-1]
table.add_typed(f"printed SCvx at gamma 1e3 with {long_run['max_iter']} iterations", "-", long_run["outcome"],
          "beyond paper", f"best accepted cost {long_run['best']:.5f}; last trust radius {long_run['eta']:.1e}; "
          f"hybrid (L1 penalty, quadratic MI, {pen_hybrid['max_iter']} it): {pen_hybrid['outcome']}")
table.add_typed("modified SCvx converges for every alpha_h of the grid", "-",
          f"{sum(a['converged'] for a in sweep.attempts)}/{len(sweep.attempts)} runs, largest defect "
          f"{max(r.max_defect for r in best):.0e}", "beyond paper",
          "augmented Lagrangian + quadratic MI model + changed acceptance (section 3); criterion: every run converges "
          f"with defects <= 1e-9: {all(a['converged'] for a in sweep.attempts) and max(r.max_defect for r in best) <= 1e-9}")
table.add_typed("larger alpha_h -> larger departure from the DRO (Fig. 2)", "yes",
          "largest distance from the DRO " + ", ".join(f"{a:g}: {d / 1e3:.1f}" for a, d in zip(ALPHAS, departure_km))
          + " (10^3 km)", "reproduced" if departure_monotone else "differs: departure not monotone",
          "criterion: non-decreasing over the grid; best of upward and downward sweeps of the modified solver")
table.add_typed("impulse and MI grow with alpha_h (Fig. 5)", "yes",
          f"impulse {impulse_mps[0]:.2f} -> {impulse_mps[-1]:.1f} m/s, MI {mi[0]:.1f} -> {mi[-1]:.1f} nats",
          "reproduced" if monotone else "differs: non-monotone front",
          "criterion: both non-decreasing over the grid (1e-6 relative)")
table.add_typed("CRLB transient at the window start (Fig. 4)", "yes", f"RMS grows from the 1st to the 2nd measurement: "
          f"{transient} (alpha_h = 0: {crlb[0].rms_km[0, 0]:.0f} -> {crlb[0].rms_km[0, 1]:.0f} km)",
          "reproduced" if transient else "differs: no transient",
          "criterion, every alpha_h; diagonal prior, no correlations (paper's explanation)")
table.add_typed("CRLB bounded after the transient (Fig. 4)", "yes", f"window end <= 2nd-measurement RMS: {bounded}",
          "consistent (tuned)" if bounded else "differs: see Fig. 4 analogue",
          "criterion, every alpha_h; the process-noise reading was chosen by this very property, so not independent")
table.add_typed("more information -> lower terminal RMS (Figs. 4-5)", "observer and target",
          f"observer {term_obs[0]:.1f} -> {term_obs[-1]:.1f} km, target {term_tgt[0]:.1f} -> {term_tgt[-1]:.1f} km",
          "reproduced" if term_obs[-1] < term_obs[0] and term_tgt[-1] < term_tgt[0] else "differs: no gain",
          f"alpha_h = 0 vs {ALPHAS[-1]:g}; holds under the literal Q too ({lit[0].terminal_rms_km[0]:.0f} -> "
          f"{lit[1].terminal_rms_km[0]:.0f} km)")
table.add_typed("MI correlates with estimator performance", "'correlates well'",
          f"Spearman(MI, terminal RMS): observer {rho_obs:+.2f}, target {rho_tgt:+.2f}",
          "reproduced" if rho_obs < -0.8 and rho_tgt < -0.8 else "differs: weak rank correlation",
          f"criterion: Spearman below -0.8 (as in notebook 06), over the {len(ALPHAS)} alpha_h of the grid")
table.add_typed("single-shooting re-flight of every plan", "-", f"largest terminal miss {max(miss_km):.1e} km",
          "beyond paper", "FOH control alone from x_S(t0), nonlinear CR3BP")
table.add_typed("node grid (mesh check, alpha_h = 5e-3)", "N not given",
          f"{N_NODES} nodes: {best[i5].impulse * MPS:.2f} m/s, RMS {mesh_rms[0]:.2f} km; {N_NODES_ALT} nodes: "
          f"{mesh.impulse * MPS:.2f} m/s, RMS {mesh_rms[1]:.2f} km", "beyond paper",
          f"impulse changes by {100 * mesh_dimp:.1f} %, RMS by {100 * abs(mesh_rms[1] / mesh_rms[0] - 1):.0f} %: "
          f"near-impulsive plans (|u|/a_max <= {max(max_ratio):.2f})")
for r in budget_rows:
    table.add_typed(f"baseline vs information plan at {r['budget']:.1f} m/s (solved)", "'substantial improvement'",
              f"alpha_h = {r['alpha']:.2e} spends {r['impulse']:.2f} m/s: observer RMS {r['rms_obs']:.1f} km vs "
              f"{term_obs[0]:.1f} km at {impulse_mps[0]:.2f} m/s ({r['rms_obs'] / term_obs[0]:.2f} x)",
              "beyond paper", f"budget met within {100 * BUDGET_RTOL:g} %; log-interpolation on the grid at the "
              f"spent impulse said {r['interp']:.1f} km")
table.add_typed("Pareto values (impulse, terminal RMS)", "plotted only (Fig. 5), no numbers",
          f"{impulse_mps[-1]:.1f} m/s -> target {term_tgt[-1]:.2f} km at alpha_h = {ALPHAS[-1]:g}", "not in paper",
          "the paper's axes are not quantitatively readable; N and sigma of the nodes are not given either")
distinct = cost_gap > 1e-8 * (1 + max(abs(b.cost) for b in best))
table.add_typed("upward vs downward sweep (local optima)", "not discussed",
          f"largest cost difference {cost_gap:.0e}: " + ("distinct local optima found" if distinct else
                                                         "both sweeps reach the same optimum on this grid"),
          "beyond paper", "best cost per alpha_h kept; differences below 1e-8 relative are solver round-off")
table.display()
