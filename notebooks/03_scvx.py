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
# depend on the initial guess. Section 5 then gives the printed method a fair trial with the information reward:
# which of its ingredients (L1 exact penalty, linear information model, a stopping test) is what fails?
#
# **Paper sections followed.** Wolf & Jones (arXiv 2408.17435), "Sequential Convex Programming for Trajectory
# Generation": Linearization (Eqs. 24-26), Discretization (Eqs. 27-33), Trust Region Update (Eqs. 34-36, Table 1),
# and the objective of "Convex Objective Approximation" (Eqs. 42-43). The node placement is notebook 04.
#
# The method lives in `cislunar.guidance.scvx` and `cislunar.guidance.discretization`; the problem, the reading of
# the iteration history, the single-shooting check, the initial-guess study and the figures of this chapter in
# `cislunar.papers.wolf_jones.scvx_study`; the rows of the closing table are claims declared in
# `cislunar.papers.wolf_jones.claims.scvx`, judged at the end.

# %% tags=["parameters"]
QUICK = False  # quick mode: every None below picks its smaller quick-mode value; the same experiments run
SEED = 0  # seed of the notebook's random generator (the random initial guesses of section 4)
OUTPUT_DIR = ""  # folder for the figures (empty: build-scratch/ by hand, the build under the runner)
N_NODES = None  # time nodes of the transfer [-] (None: 24 quick, 60 full)
SIGMA = None  # Sundman exponent of the nodes, notebook 04 [-] (None: 1.0; the DRO is benign, it matters little)
A_MAX_KM_S2 = None  # thrust-acceleration bound outside the window [km/s^2] (None: Table 3's 1e-6)
N_GUESSES = None  # random initial guesses in section 4 [-] (None: 2 quick, 6 full)
GUESS_CONTROL_SCALE = None  # size of the guesses' random controls, fraction of a_max [-] (None: 0.05)
GUESS_MAX_ITER = None  # SCvx iteration limit of each run from a random guess [-] (None: 200)
WORKERS = 1  # processes for the runs of section 4 [-] (1: serial)
SCHEDULER = ""  # address of a Dask scheduler for sections 4 and 5, e.g. "tcp://10.0.0.5:8786" ("": none)
PRINTED_N_NODES = None  # nodes of test case 1 with the information reward, section 5 [-] (None: 10 quick, 40 full)
PRINTED_ITER = None  # iteration limit of every run of section 5 [-] (None: 6 quick, 200 full)
PRINTED_GAMMAS = None  # further penalty weights gamma of the printed method, section 5 [-] (None: 1e1, 1e2, 1e4, 1e5)

# %%
# Every None above is resolved here; a value the reader gave is used as given, in quick and in full mode.
n_nodes = N_NODES if N_NODES is not None else (24 if QUICK else 60)
sigma = SIGMA if SIGMA is not None else 1.0
n_guesses = N_GUESSES if N_GUESSES is not None else (2 if QUICK else 6)
guess_control_scale = GUESS_CONTROL_SCALE if GUESS_CONTROL_SCALE is not None else 0.05
guess_max_iter = GUESS_MAX_ITER if GUESS_MAX_ITER is not None else 200
workers = WORKERS if WORKERS is not None else 1
printed_n_nodes = PRINTED_N_NODES if PRINTED_N_NODES is not None else (10 if QUICK else 40)
printed_iter = PRINTED_ITER if PRINTED_ITER is not None else (6 if QUICK else 200)
printed_gammas = PRINTED_GAMMAS if PRINTED_GAMMAS is not None else [1e1, 1e2, 1e4, 1e5]

import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import scvx_study as study
from cislunar.papers.wolf_jones.claims.scvx import (
    CLAIMS,
    COST_TOL,
    DEFECT_TOL,
    GUESS_DISTANCE_KM,
    INTEGRATOR_ALLOWANCE,
    OPTIMUM_TOL,
    SUPERLINEAR_FACTOR,
    SUPERLINEAR_TAIL,
)
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.utils.executors import open_executor

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
table = ComparisonTable("03 SCvx with first-order hold (Wolf & Jones Eqs. 24-36, 42-43, Table 1)")

# %% [markdown]
# ## 1 · The problem
#
# Test case 1's observer starts on the DRO of Table 2 (its printed $\dot y_0$ is corrected in notebook 01) and must
# reach the printed final state $x_{\mathcal S}(t_f)$ on a neighbouring DRO after two periods, with a thrust
# acceleration of at most $a_{max} = 10^{-6}$ km/s² (Table 3; the parameter `A_MAX_KM_S2` changes it) **and none at all inside the observation window
# $[3P/4, 3P/2]$** (12.1-24.3 d): the window ends are moved onto nodes and every node of the window gets the bound
# zero, so the first-order-hold thrust vanishes on the whole window. With $\alpha_h = 0$ the objective of Eq. 42 is
# the total impulse plus the defect penalty.
#
# `scvx_study.transfer_problem` gathers this from the scenario of `cislunar.papers.wolf_jones.scenarios`: the
# corrected initial state, the printed final state, the Sundman node times with the window ends moved onto nodes,
# the bound per node and the ballistic arc sampled at the nodes, which is the initial guess of the first run.

# %%
# The node controls are accelerations (first-order hold, Eq. 27), so the bound is a_max at every node outside the
# window (the acceleration reading of Eqs. 40-41, notebook 04) and zero at the window's nodes.
prob = study.transfer_problem(n_nodes, sigma, a_max_km_s2=A_MAX_KM_S2)  # Sundman nodes, window ends on nodes
t, (k_ws, k_we), A_MAX = prob.t, prob.k_window, prob.scenario.a_max
print(f"transfer time {em.tu_to_days(prob.scenario.duration):.2f} d, {n_nodes} Sundman nodes (sigma = {sigma}), "
      f"a_max = {A_MAX:.4f} LU/TU^2, zero on nodes {k_ws}..{k_we} "
      f"({em.tu_to_days(t[k_ws]):.2f}-{em.tu_to_days(t[k_we]):.2f} d); |x_f - x(T) ballistic| = "
      f"{prob.ballistic_miss:.2e}")

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
#
# `scvx_study.iteration_summary` reads the run's history with these rules: the steps whose predicted decrease lies
# at the noise level (where $\rho$ was set, not measured), the range of $\rho$ over the others, the iterations after
# which the multipliers moved, and the ratio of successive largest defects,
# $q_k = \max_j\|\delta_j^{(k+1)}\| / \max_j\|\delta_j^{(k)}\|$. A superlinear rate means $q_k \to 0$; a ratio
# near 1 is a step that did not close the defects.

# %%
settings = scvx.SCvxSettings()
print(settings)
res = study.solve(prob, settings)  # ballistic initial guess, zero controls
print(f"converged in {len(res.history)} iterations: impulse {res.impulse * em.velocity_unit_km_s * 1e3:.4f} m/s, "
      f"largest defect {res.max_defect:.1e}")
for h in res.history:
    print(f"  it {h['iteration']:2d}: J = {h['cost']:.6e} -> {h['new_cost']:.6e}, predicted {h['predicted']:.2e}, "
          f"rho = {h['rho']:.3f}, eta = {h['eta']:.3g}, {'accepted' if h['accepted'] else 'rejected'}"
          f"{', on the trust-region boundary' if h['tr_active'] else ''}, max defect {h['max_defect']:.1e}"
          f"{', multipliers updated' if h['multiplier_update'] else ''}")
res_pen = study.solve(prob, scvx.SCvxSettings(method="penalty"))
print(f"exact-penalty variant: {len(res_pen.history)} iterations, impulse "
      f"{res_pen.impulse * em.velocity_unit_km_s * 1e3:.4f} m/s (relative difference "
      f"{abs(res_pen.impulse - res.impulse) / res.impulse:.1e})")
window_thrust = float(np.max(np.linalg.norm(res.u[prob.in_window], axis=1)))
print(f"largest thrust at the window nodes: {window_thrust:.1e} LU/TU^2")
it = study.iteration_summary(res, settings)
print(f"{it.n_accepted} of {it.n_steps} steps accepted; {it.n_real} with a predicted decrease above the noise level, "
      f"rho in [{it.rho_range[0]:.3f}, {it.rho_range[1]:.3f}]; rho set to 1 by the noise rule at iterations "
      f"{list(it.forced)} (predicted {', '.join(format(p, '.1e') for p in it.forced_predicted)}; "
      f"{it.forced_negative} negative)")
print(f"eta {it.eta_start:g} at the start, {it.eta_end:g} (eta_max = {settings.eta_max:g}) "
      f"at the end; multipliers updated (and weight raised) after iterations {list(it.updates)}")
# the paper cites 'global convergence and superlinear convergence rate' (Mao et al. 2018)
print("largest-defect ratio per step:", np.array2string(it.defect_ratio, precision=2, separator=", "))
fig = study.figure_iterations(res, settings, em.velocity_unit_km_s)
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
# The "superlinear" row of the closing table tests whether the ratios tend to zero over the steps above the solver's
# round-off floor ($5\times10^{-10}$ LU, its defect tolerance; the last step of the full run, between two defects
# below it, is left out); it reads "differs" because a step with a ratio near 1 comes after the fast ones (full run:
# the last three ratios above the floor are 1.00, 0.204 and 1.01). That is a statement about our SCvx* variant, not
# evidence against the cited theorem, which is for Mao's penalty SCvx; the exact-penalty variant above reaches the
# floor in one step, too few to show any rate.

# %% [markdown]
# ## 3 · Is the converged trajectory real?
#
# The virtual control is a modelling device: at convergence it must vanish. The solver says it does (its largest
# defect, printed above), but that number comes from the solver's own bookkeeping: heyoka's integration of each
# interval inside the discretisation. So we measure the defects again with nothing of the solver's:
# `scvx_study.NodeDefects` re-propagates every interval of the converged plan from its node state under the
# first-order-hold acceleration of Eq. 27 with scipy's DOP853 (relative and absolute tolerance $10^{-13}$) on the
# CR3BP vector field, and compares the end with the next node. A second pass at $10^{-12}$ estimates the
# integrator's own error. If the solver flew a different control than the one it returns, discretised the
# dynamics wrongly or under-counted its defects, these independent defects would show it.

# %%
node_defects = study.NodeDefects.of(em, res.t, res.x, res.u)
print(f"largest node defect re-measured by DOP853: {node_defects.largest:.2e} (solver's own {res.max_defect:.2e}); "
      f"DOP853 at {node_defects.check_rtol:g} vs {node_defects.rtol:g}: at most "
      f"{node_defects.integrator_spread.max():.1e} per interval")

# %% [markdown]
# The independent defects agree with the solver's to a few digits, far below the allowance of the table's row for
# the two integrators' error ($10^{-11}$). The first-order-hold control, fed to the *nonlinear* dynamics from the
# initial state alone (single shooting), must then also reach the terminal state, up to the growth of those small
# defects over 32 days of free flight. `scvx_study.single_shooting` integrates $\dot x = f(x) + u(t)$ with the
# first-order-hold $u(t)$ of Eq. 27 from $x(t_0)$ and measures the position and velocity miss at $t_f$.

# %%
shot = study.single_shooting(prob, res.u)
print(f"single shooting with the converged control misses x_f by {shot.miss_km:.2e} km and "
      f"{shot.miss_mm_s:.2e} mm/s")
fig = study.figure_converged_control(prob, res.u, shot)
_ = plotting.save_figure(fig, "03_converged_control", output_dir=out)

# %% [markdown]
# ## 4 · Independence from the initial guess
#
# SCvx converges to a local optimum; for this mildly nonlinear transfer we expect the same one from different
# starting points: a straight blend between the forward and backward ballistic arcs with random controls (5% of
# $a_{max}$; from much rougher guesses the trust region shrinks and progress becomes slow, a known SCvx trait).
# With $s = t/t_f$, the guess is $x^{(0)}(t) = (1-s)\,x_{fwd}(t) + s\,x_{bwd}(t)$, where $x_{fwd}$ coasts from
# $x_{\mathcal S}(t_0)$ and $x_{bwd}$ coasts backwards from $x_{\mathcal S}(t_f)$; the spread of the converged
# impulses is measured relative to the run of section 2. "The same optimum" is fixed before looking at the plans: an
# impulse within the solver's own cost tolerance of the section-2 run, $|J_i - J| \le 10^{-8}(1+|J|)$ (the solver
# cannot resolve costs closer than its stopping test), and a plan whose nodes all lie within 1 km of the section-2
# plan (the accuracy asked of a single-shooting re-flight in section 3).
#
# `guess_study` draws every guess's random controls from the notebook's generator first, guess after guess, and
# only then solves: the `N_GUESSES` SCvx runs are independent and go to the executor opened from `WORKERS` and
# `SCHEDULER` (serial by default), with the same impulses whichever runs them. `GUESS_CONTROL_SCALE` sets how
# rough the guesses are and `GUESS_MAX_ITER` how long each run may take to recover.

# %%
with open_executor(workers, SCHEDULER) as executor:
    guesses = study.guess_study(prob, n_guesses, rng, res.impulse, control_scale=guess_control_scale,
                                max_iter=guess_max_iter, executor=executor)
print("impulses from random guesses [m/s]:", np.round(guesses.impulses * em.velocity_unit_km_s * 1e3, 6),
      f"relative spread {guesses.spread:.1e}; iterations {list(guesses.iterations)}")
guess_gap, guess_km = guesses.impulse_gap(res.impulse), em.lu_to_km(guesses.plan_distance(res.x))
print(f"largest impulse gap to section 2's run {guess_gap:.1e} (1 + |J|) (tolerance {COST_TOL:g}); largest node "
      f"distance to its plan {guess_km:.1e} km (tolerance {GUESS_DISTANCE_KM:g} km)")

# %% [markdown]
# ## 5 · The printed method, fairly
#
# The sections above use the package's default SCvx, which departs from the printed method in two ingredients: the
# augmented Lagrangian on the defects instead of the L1 exact penalty of Eqs. 42-43, and a concave-quadratic
# information model instead of the *linear* model of Eq. 44 (the paper's $\mathcal I_{approx}$ is the value plus
# the gradient times the step: linear). A third ingredient is ours alone: the paper prints no stopping test, and
# ours is strict (an accepted step with defects below $5\times10^{-10}$, a cost change below $10^{-8}(1+|J|)$ *and
# an inactive trust region*). Notebook 05 finds that the printed method "never converges"; here we ask which of the
# three is to blame, on test case 1 with the information reward at $\alpha_h = 5\times10^{-3}$ (the weight of
# notebook 05's section 4), from the ballistic DRO, with every run granted the same iteration limit.
#
# The trust region of a linear model is where the trouble starts: a linear reward has no interior maximum, so each
# step runs to the trust-region boundary and the strict test, which asks for a step *inside* the trust region,
# can never hold. So we add a **practical stopping rule** (`scvx.PracticalStop`, passed to `solve_scvx` as
# `practical_stop`; off by default, so every other result of the package is unchanged): stop after $k$ consecutive
# accepted steps that each leave the largest defect below a tolerance and change the cost by less than a relative
# tolerance, whether or not the step sat on the trust-region boundary; rejected steps in between neither count nor reset the count, and the rule never stops
# with open defects (a test checks both). Its settings, $k = 5$, defects $\le 10^{-8}$ (3.8 m, 1 cm/s) and a cost
# change $\le 10^{-8}(1+|J|)$, were fixed before any run (`scvx_study.PRACTICAL_STOP`).
#
# `scvx_study.printed_method_study` solves the problem five ways: the package's default (the reference optimum),
# the augmented Lagrangian with the linear model under the strict test and under the practical rule, and the L1
# exact penalty ($\gamma = 10^3$, as in notebook 05) with the linear model (the printed method) and with the
# quadratic model, both under the practical rule. The paper does not print $\gamma$ either, so the printed method
# also runs at the other weights of `PRINTED_GAMMAS` (by default those of notebook 05's sweep, $10^1$-$10^5$), under
# the same practical rule and iteration limit; notebook 05's own sweep uses the strict test, which no linear model
# can meet, so it cannot say whether some $\gamma$ lets the printed method stop. The runs are independent and go to
# the executor of section 4.

# %%
with open_executor(workers, SCHEDULER) as executor:
    printed = study.printed_method_study(printed_n_nodes, alpha=5e-3, max_iter=printed_iter, gammas=printed_gammas,
                                         executor=executor)
print(printed.summary())
pr = printed.runs
fig = study.figure_printed_method(printed)
_ = plotting.save_figure(fig, "03_printed_method", output_dir=out)

# %% [markdown]
# **Reading.** The table lists for each run how it ended (`strict`, `practical` or `no` with the error), its
# iterations, the cost of its last accepted iterate and its distance to the reference, the largest defect there, the
# last trust-region radius and the share of the steps that ended on the trust-region boundary. The linear model
# under the augmented Lagrangian reaches the reference optimum (the left panel falls to round-off) with nearly every
# step on the trust-region boundary: under the strict test it stalls there (the stall guard ends it), under the
# practical rule it stops. The exact-penalty runs bring the defects down to a few $10^{-8}$ (right panel; an
# exploratory run of 300 iterations, not part of this notebook, reached $7\times10^{-9}$) but keep creeping towards
# the optimum with a tiny trust region, with either information model: the second-order defects of a step of size
# $\eta$ cost $\gamma\,O(\eta^2)$ in the L1 penalty against a predicted gain $O(\eta)$, so $\rho$ hovers between
# $\rho_1$ and $\rho_2$ (0.1-0.2) and $\eta$ stays at $1$-$4\times10^{-4}$, nearly every step accepted. At the limit
# the cost still falls by a few $10^{-6}$ per step (relative), hundreds of times the rule's cost tolerance, so a
# rule with a tolerance that small does not stop it, and one loose enough to stop it stops it away from the optimum
# (the gap printed). The augmented Lagrangian's quadratic penalty charges those second-order defects only
# $O(\eta^4)$. So at $\gamma = 10^3$, of the paper's three ingredients, the **L1 exact penalty** is the one that fails
# (it converges too slowly to meet any tight test); the **linear MI model** works once the **stopping test** does not
# ask for an inactive trust region.
#
# **Other penalty weights** (the last lines of the table). The verdict on the exact penalty depends on the unstated
# $\gamma$. In the full run (40 nodes, 200 iterations) the printed method at $\gamma = 10^2$ *does* stop under the
# practical rule, after 113 iterations, at a cost $4.2\times10^{-5}$ *below* our solver's cold start: the better
# local optimum that notebook 05's multi-start adopts (-0.543793). At $\gamma = 10$ the penalty is too weak to close
# the defects ($3\times10^{-3}$ left); at $10^4$ it creeps as at $10^3$, farther from the optimum; at $10^5$ the
# defects fall below $10^{-9}$ but the cost still moves by more than the rule's tolerance, $2\times10^{-2}$ from the
# optimum. So the printed method converges in a window of $\gamma$ around $10^2$; the table's rows on the printed
# method are judged at $\gamma = 10^3$ only (the first one's label says so, its note lists the other weights).
# Notebook 05's sweep of $\gamma$ uses the strict test, which no linear model can meet, so it could not see this.

# %% [markdown]
# ## 6 · Paper versus reproduction
#
# The paper reports no standalone SCvx run; its numbers come with the information reward (notebooks 05-06). The rows
# below check what the method section states. Each is a claim declared, with its criterion, in
# `cislunar.papers.wolf_jones.claims.scvx` before the run (one exception: the cost tolerance $10^{-6}$ of "reaches
# the optimum" in the rows on section 5's runs was fixed after a first exploratory run; the module's docstring says
# so and shows that every tolerance from $10^{-8}$ to $3\times10^{-5}$ gives the same verdicts): the node defects,
# re-measured by an independent integrator (section 3), must lie below the solver's defect tolerance,
# $5\times10^{-10}$ LU (0.19 m), plus $10^{-11}$ for the integrators' error (until 2026-11-26h this row read the
# solver's own defect against $10^{-9}$: its own stopping test, which could not fail); the single-shooting miss
# below 1 km (node defects below $5\times10^{-10}$ LU grow over 32 days of free flight); the runs from random guesses
# must reach the same optimum as defined in section 4 (impulse within $10^{-8}(1+|J|)$, nodes within 1 km; the row
# had no criterion until 2026-11-26h); a superlinear rate means that the largest-defect ratios $q_k$ tend to
# zero, tested above a round-off floor fixed from the solver's own defect tolerance (`defect_tol`,
# $5\times10^{-10}$ LU; a ratio with an end below it measures nothing): over the last three accepted steps above the
# floor each $q_k < 1$ and each at most half the one before (the rows' module says why; a linear rate, with ratios
# settling at a constant, fails); the window thrust must be exactly zero. The two documented departures from the
# printed method (the augmented Lagrangian and the trust-region rules) are rows that differ by construction, with
# the reason in the note.
#
# Mind the scope of the first and third rows: they judge the package's default SCvx (augmented Lagrangian) without
# an information reward. With the reward and the printed L1 exact penalty (section 5) the defects stop at a few
# $10^{-8}$ LU, above the first row's tolerance; that setting is judged by the rows on section 5's runs.

# %%
table.add(CLAIMS["defects"].judge(
    node_defects.largest,
    shown=(f"{len(res.history)} iterations, largest node defect re-measured by DOP853 {node_defects.largest:.1e} "
           f"(solver's own {res.max_defect:.1e})"),
    note=(f"section 3: each interval re-flown from its node by scipy DOP853 (rtol = atol = {node_defects.rtol:g}); "
          f"tolerance = the solver's defect_tol {DEFECT_TOL:g} LU ({em.lu_to_km(DEFECT_TOL) * 1e3:.2f} m) + "
          f"{INTEGRATOR_ALLOWANCE:g} for the integrators; DOP853 at {node_defects.check_rtol:g} vs "
          f"{node_defects.rtol:g}: at most "
          f"{node_defects.integrator_spread.max():.0e}; until 2026-11-26h the solver's own defect against 1e-9")))
it_pen = study.iteration_summary(res_pen, scvx.SCvxSettings(method="penalty"))
tail = it.rate_ratios[-SUPERLINEAR_TAIL:]
table.add(CLAIMS["superlinear"].judge(
    it.superlinear(SUPERLINEAR_TAIL, SUPERLINEAR_FACTOR),
    shown=(f"{it.rate_ratios.size} steps above the floor {it.rate_floor:g} LU; last {tail.size} ratios "
           + ", ".join(f"{q:.3g}" for q in tail)),
    note=(f"package default (augmented Lagrangian); ratios per step over all steps {it.defect_ratio.min():.1e} to "
          f"{it.defect_ratio.max():.1e}; the exact-penalty variant (the SCvx the theorem covers) converges in "
          f"{it_pen.n_steps} steps with {it_pen.rate_ratios.size} ratio(s) above the floor, too few to show a rate; "
          "until 2026-11-26g the test was 'every ratio <= 0.5', round-off steps included")))
table.add(CLAIMS["single_shooting"].judge(
    shot.miss_km, shown=f"miss {shot.miss_km:.1e} km, {shot.miss_mm_s:.1e} mm/s",
    note="position miss in km; node defects below 5e-10 LU (0.2 m) grow over 32 days of free flight"))
table.add(CLAIMS["trust_region_parameters"].judge(
    f"rho = {settings.rho0}/{settings.rho1}/{settings.rho2}, beta = {settings.beta_shrink}/{settings.beta_grow}, "
    f"eta0 = {settings.eta0:g}, eta_max = {settings.eta_max:g}, w0 = {settings.penalty_weight0:g}"))
table.add(CLAIMS["minimum_impulse"].judge(res.impulse * em.velocity_unit_km_s * 1e3,
                                          shown=f"{res.impulse * em.velocity_unit_km_s * 1e3:.4f} m/s"))
table.add(CLAIMS["initial_guess"].judge(
    guesses.same_optimum(res.impulse, res.x, cost_tol=COST_TOL, distance=em.km_to_lu(GUESS_DISTANCE_KM)),
    shown=(f"relative impulse spread {guesses.spread:.0e}; largest gap to section 2's run {guess_gap:.0e} (1 + |J|), "
           f"largest node distance {guess_km:.0e} km"),
    note=f"{n_guesses} random guesses, all converged; until 2026-11-26h no criterion"))
table.add(CLAIMS["window_thrust"].judge(window_thrust, shown=f"largest window thrust {window_thrust:.0e}"))
table.add(CLAIMS["defect_handling"].judge(
    "augmented Lagrangian (SCvx*); exact penalty kept as an option",
    note=f"without an information reward both agree (impulse difference "
         f"{abs(res_pen.impulse - res.impulse) / res.impulse:.0e})"))
table.add(CLAIMS["trust_region_update"].judge(
    False, shown=f"noise rule at iterations {list(it.forced)}; eta capped at eta_max = {settings.eta_max:g}",
    note=f"rho = 1 when |predicted| <= {settings.noise_tol:g} (1 + |J|), which accepted {it.forced_negative} step(s) "
         f"with a negative prediction that Eq. 36 would reject; steps with a real predicted decrease had rho in "
         f"[{it.rho_range[0]:.3f}, {it.rho_range[1]:.3f}]"))
pp, al_lin = pr["L1 + linear, practical"], pr["AL + linear, practical"]
other_gammas = "; ".join(
    f"{g:.0e}: " + (f"stops after {r.iterations} it., cost {r.cost - printed.reference:+.1e} from the optimum"
                    if r.converged else f"no stop, defect {r.max_defect:.0e}")
    for g, r in printed.gamma_runs.items()) or "none run"
table.add(CLAIMS["printed_stops"].judge(
    pp.converged, shown=(f"{pp.outcome}; cost {printed.gap(pp.label):+.1e} from the optimum, largest defect "
                         f"{pp.max_defect:.0e}, last eta {pp.eta:.0e}"),
    note=(f"{printed.n_nodes} nodes, gamma = 1e3, at most {printed.max_iter} iterations; section 5; other gammas, "
          f"same rule and limit (a negative cost gap: a better local optimum than our solver's cold start): "
          f"{other_gammas}")))
table.add(CLAIMS["printed_gap"].judge(abs(printed.gap(pp.label)), shown=f"{printed.gap(pp.label):+.1e}",
                                      note=f"reference: our solver's optimum {printed.reference:.8f}"))
table.add(CLAIMS["al_linear"].judge(
    bool(al_lin.converged and abs(printed.gap(al_lin.label)) <= OPTIMUM_TOL),
    shown=f"{al_lin.outcome}; cost {printed.gap(al_lin.label):+.1e} from the optimum",
    note=(f"under the strict test: {pr['AL + linear, strict'].outcome}; steps on the trust-region boundary "
          f"{al_lin.tr_active:.0%}")))
table.add(CLAIMS["stopping_test"].judge("strict by default; practical rule as an option",
                                        note="section 5: the strict test never stops a linear model"))
table.add(CLAIMS["failing_ingredient"].judge(
    bool(not pp.converged and not pr["L1 + quadratic, practical"].converged and al_lin.converged),
    shown="L1 exact penalty" if not pp.converged and al_lin.converged else "not the L1 penalty alone",
    note=(f"L1 + quadratic: {pr['L1 + quadratic, practical'].outcome}, cost "
          f"{printed.gap('L1 + quadratic, practical'):+.1e} from the optimum; the printed method (L1 + linear) stops "
          "under the same rule at gamma = " + (", ".join(f"{g:.0e}" for g, r in printed.gamma_runs.items()
                                                        if r.converged) or "none of the other weights run")
          + ": the unstated penalty weight decides whether the L1 penalty fails")))
table.display()

# %% [markdown]
# ## Exercises
#
# Change one parameter in the `parameters` cell (or pass it to the runner, e.g.
# `python -m cislunar.publish.notebooks --quick 03 -p N_NODES=12`), predict, then rerun and compare. The worked
# solutions are functions of `cislunar.papers.wolf_jones.exercises`, run at small sizes.
#
# 1. **Halve the node count.** Set `N_NODES` to half its value. The node controls are the only freedom of the
#    first-order-hold control: will the converged minimum impulse of section 2 rise, fall or stay? Does the
#    single-shooting check of section 3 still pass? Worked solution: `exercise_03_node_count` (fewer nodes, a
#    coarser piecewise-linear thrust and a costlier transfer: about 0.56 m/s on 12 nodes against 0.42 m/s on 24,
#    every run closing its defects).
# 2. **Tighten the thrust bound.** Set `A_MAX_KM_S2 = 1e-8`, a hundredth of Table 3's value. Look first at the
#    converged control of section 3: how close does it come to the bound? Predict the impulse, then check.
#    Worked solution: `exercise_03_thrust_bound` (the largest converged thrust is a fraction of a percent of
#    Table 3's bound of 1000 µm/s²: about 1.5 µm/s² (0.15 %) in quick mode, 3.9 µm/s² (0.4 %) in the full run's
#    figure; so a bound 100x tighter, 10 µm/s², is still inactive and the optimum does not move).
