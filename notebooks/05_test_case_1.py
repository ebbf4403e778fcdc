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

# %% [markdown]
# **How to use this chapter.** The next cell (tagged `parameters`) holds everything you might change: the node
# grids, the homotopy weights, the iteration limits and penalty weights granted to the paper's exact-penalty SCvx,
# and the impulse budgets of Section 8. Leave an entry at `None` and the notebook picks it (the values in brackets
# in the comments: a shorter, coarser run when `QUICK = True`, then the full run); give a value (edit the cell, or
# pass `-p NAME=VALUE` to the runner) and it is used as given in both modes. The exact-penalty runs of Section 4
# are independent of one another and run on `WORKERS` local processes or on a Dask cluster (`SCHEDULER`); every
# run is deterministic, so the numbers do not depend on where they run.

# %% tags=["parameters"]
QUICK = False
SEED = 0  # seed of the random perturbation starts of the multi-start (Section 3); everything else is deterministic
OUTPUT_DIR = ""
N_NODES = None  # Sundman-spaced nodes over the two periods; the paper does not give its N (None: 18 quick, 40 full)
N_NODES_ALT = None  # node count of the second grid of the mesh check, Section 5 (None: 20 quick, 28 full)
SIGMA = 1.0  # Sundman exponent of the node spacing, dt / dtau equal to r_m^sigma (notebook 04)
ALPHAS = None  # homotopy weights alpha_h, increasing in [0, 1], must contain 5e-3 (None: [0, 5e-3, 1e-2] quick, 9 full)
PENALTY_ITER = None  # iterations granted to the paper's exact-penalty SCvx in Section 4 (None: 5 quick, 80 full)
PENALTY_ITER_LONG = None  # the same at gamma 1e3 with a larger limit (None: 10 quick, 300 full)
PENALTY_GAMMAS = None  # exact-penalty weights gamma swept, unstated in the paper (None: [1e1, 1e3, 1e5] quick, 1e1-1e5 full)
BUDGETS_EXTRA_MPS = None  # impulse budgets above the baseline's, Section 8, m/s (None: [5] quick, [1, 5, 20] full)
BUDGET_RTOL = 0.02  # a budget counts as met within this relative tolerance (fixed before solving)
FORWARD_HESSIAN = None  # forward (True) or central (False) differences for the MI Hessian (None: True quick, False full)
MS_ALPHAS = None  # weights solved from several starts in Section 3, a subset of ALPHAS (None: [5e-3] quick, all full)
MS_RANDOM = None  # random perturbation starts per weight in the multi-start (None: 1 quick, 1 full)
MS_SEEDS_Z = None  # +z and -z seeded starts in the multi-start (None: False quick, True full)
MESH_NODES = None  # node counts of the mesh study besides N_NODES, Section 3 (None: [14] quick, [20, 30, 60] full)
MESH_ALPHAS = None  # weights of the mesh study, in ALPHAS (None: [5e-3] quick, [5e-3, 2e-2] full)
MESH_COLD = None  # also solve the mesh study's grids from the ballistic guess (None: no quick, yes full)
MESH_RTOL = 0.05  # a weight's plan has converged in the mesh when impulse, MI and RMS change by at most this much
#                   between the two finest grids (fixed before solving)
WORKERS = None  # local processes for the multi-start, the mesh study and the exact-penalty runs, 1 runs serially
#                 (None: 1 quick, 2 full)
SIZE_NORMALISATIONS = None  # control-term normalisations of the plan-size sweep, Section 8b, keys of
#                             plan_size_study.NORMALISATIONS (None: the adopted and "total, m/s" quick, all 6 full)
SIZE_READINGS = None  # process-noise readings of that sweep, keys of scenarios.PROCESS_NOISE_READINGS_KM2_S3
#                       (None: the adopted one quick, all 4 full)
SCHEDULER = ""  # address of a Dask scheduler to run them on, e.g. "tcp://10.0.0.5:8786" ("": none; WORKERS applies)

# %%
n_nodes = N_NODES if N_NODES is not None else (18 if QUICK else 40)
n_nodes_alt = N_NODES_ALT if N_NODES_ALT is not None else (20 if QUICK else 28)
alphas = ALPHAS if ALPHAS is not None else ([0.0, 5e-3, 1e-2] if QUICK else  # quick: the grid's top as right panels
                                            [0.0, 1e-3, 2e-3, 3e-3, 5e-3, 7e-3, 1e-2, 1.5e-2, 2e-2])
penalty_iter = PENALTY_ITER if PENALTY_ITER is not None else (5 if QUICK else 80)
penalty_iter_long = PENALTY_ITER_LONG if PENALTY_ITER_LONG is not None else (10 if QUICK else 300)
penalty_gammas = PENALTY_GAMMAS if PENALTY_GAMMAS is not None else ([1e1, 1e3, 1e5] if QUICK else
                                                                     [1e1, 1e2, 1e3, 1e4, 1e5])
budgets_extra_mps = BUDGETS_EXTRA_MPS if BUDGETS_EXTRA_MPS is not None else ([5.0] if QUICK else [1.0, 5.0, 20.0])
forward_hessian = FORWARD_HESSIAN if FORWARD_HESSIAN is not None else QUICK
workers = WORKERS if WORKERS is not None else (1 if QUICK else 2)
ms_alphas = MS_ALPHAS if MS_ALPHAS is not None else ([5e-3] if QUICK else list(alphas))
ms_random = MS_RANDOM if MS_RANDOM is not None else 1
ms_seeds_z = MS_SEEDS_Z if MS_SEEDS_Z is not None else not QUICK
mesh_nodes = MESH_NODES if MESH_NODES is not None else ([14] if QUICK else [20, 30, 60])
mesh_alphas = MESH_ALPHAS if MESH_ALPHAS is not None else ([5e-3] if QUICK else [5e-3, alphas[-1]])
mesh_cold = MESH_COLD if MESH_COLD is not None else not QUICK
if 5e-3 not in alphas:
    raise ValueError(f"ALPHAS must contain 5e-3 (Figs. 1 and 3, Section 4, the mesh check); got {alphas}")

import dataclasses

import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.wolf_jones import figures, global_search, plan_size_study, readings_study
from cislunar.papers.wolf_jones import scenarios as wolf_jones
from cislunar.papers.wolf_jones import test_case_studies as studies
from cislunar.papers.wolf_jones.claims.plan_size import CLAIMS as SIZE_CLAIMS
from cislunar.papers.wolf_jones.claims.process_noise_readings import CLAIMS as READING_CLAIMS
from cislunar.papers.wolf_jones.claims.test_case_1 import CLAIMS
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.utils.executors import open_executor

size_norms = SIZE_NORMALISATIONS if SIZE_NORMALISATIONS is not None else (
    [plan_size_study.ADOPTED_NORMALISATION, "total, m/s"] if QUICK else list(plan_size_study.NORMALISATIONS))
size_reads = SIZE_READINGS if SIZE_READINGS is not None else (
    [plan_size_study.ADOPTED_READING] if QUICK else list(wolf_jones.PROCESS_NOISE_READINGS_KM2_S3))
plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)  # the multi-start's random perturbation starts (Section 3)
table = ComparisonTable("05 Wolf & Jones test case 1 (Tables 2-3, Figs. 1-5)")
MPS = em.velocity_unit_km_s * 1e3

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
P, chk = sc.period, sc.row_checks["observer_t0"]
print(studies.case1_scenario_summary(sc))
slip = studies.table2_slip(sc, wolf_jones.test_case_2(), n_nodes, SIGMA)
print(slip.summary(em))

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
#
# One call (`test_case_studies.sweep_test_case_1`) builds this grid, the bounds, the ballistic guess and the
# information model, and runs the homotopy sweep of the next section on them; it returns them all in one frozen
# result, whose summary (printed in section 3) starts with the node grid and the ballistic guess's MI and terminal
# miss.

# %%
case = studies.sweep_test_case_1(sc, n_nodes, alphas, sigma=SIGMA, forward_hessian=forward_hessian, progress=True)

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
print(case.summary())  # nodes, the ballistic guess, every SCvx run of both sweeps, the best per weight
sweep_best = list(case.best)  # kept to report what the multi-start below changes

# %% [markdown]
# **Several starts per weight.** Two sweeps are two starts per weight at most, both warm starts from neighbouring
# optima. How good is their best? `global_search.multi_start` solves each weight again from several starts: the
# ballistic guess, a $+z$ and a $-z$ seed (a small out-of-plane thrust before the window; the problem is planar, so
# these test whether leaving the plane pays), random perturbations of the control (a Gaussian direction of 5 % of
# $a_{max}$ per node, drawn from the notebook's generator before anything is solved), and, in a second round, the
# best plan of each neighbouring weight. The sweep's plans count as starts too, so the multi-start can only match or
# beat them. Two converged plans are the *same* local optimum when their costs agree within $10^{-6}(1+|J|)$ and
# their node positions (or one's and the other's $z$-mirror) never lie more than 100 km apart; otherwise they are
# *distinct* (tolerances fixed before the runs). The table gives, per weight, how many starts converged, how many
# distinct optima they reached, and the spread of their costs.
#
# Every run here is deterministic, so a problem already solved is not solved again: the upward sweep's first plan
# ($\alpha_h = 0$ from the ballistic DRO) is the multi-start's ballistic start there, and the ballistic starts
# solved here (`from_ballistic`) serve again as the cold run of Section 4 and as the adopted plans of the plan-size
# sweep of Section 8b, which solve the very same problems (the tests check that the reused plans equal fresh
# solves bit for bit).

# %%
known = global_search.known_from_sweep(case.sweep, ms_alphas)
if alphas[0] == 0.0 and case.sweep.source[0] == "up" and 0.0 in ms_alphas:  # the upward sweep's first run is
    known[0.0].append(("ballistic", case.best[0]))  # the ballistic start at alpha_h = 0: not solved twice
with open_executor(workers, SCHEDULER) as executor:
    ms = global_search.multi_start(case.solver, ms_alphas, rng=rng, n_random=ms_random, seeds_z=ms_seeds_z,
                                   known=known, executor=executor)
print(ms.summary())
# plans solved from the ballistic DRO, which sections 4 and 8b solve again: reused there (SCvx is deterministic)
from_ballistic = {o.alpha: o.result for o in ms.outcomes if o.label == "ballistic" and o.converged}
if alphas[0] == 0.0 and case.sweep.source[0] == "up":
    from_ballistic.setdefault(0.0, case.best[0])
ms_better = ms.improvements([sweep_best[alphas.index(a)] for a in ms_alphas])
print("better than the sweep's best: " + ("; ".join(
    f"alpha_h {a:g}: cost {c0:.6f} -> {c1:.6f} (from {lab})" for a, c0, c1, lab in ms_better) or "nowhere"))

# %% [markdown]
# **Mesh study.** Two sweeps and a multi-start all solve one node grid, which the paper does not give.
# `global_search.mesh_study` solves the headline weights (full run: Fig. 1's $5\times10^{-3}$ and the grid's
# largest, $2\times10^{-2}$; quick run: $5\times10^{-3}$) on several Sundman grids (up to 60 nodes in the full run),
# each from the multi-start's best plan interpolated onto the grid and (full run only) from the ballistic guess, and
# keeps the better. A weight's plan counts as converged in the mesh when impulse, MI and terminal RMS change by at
# most `MESH_RTOL` (5 %, fixed before solving) between the two finest grids. The figures use the `N_NODES` grid
# (printed).
#
# **The mesh study's plans as starts on the figures' grid.** `global_search.back_to_grid` moves each weight's plan
# on the finest grid (finer grids only: a coarser plan interpolated in time can cut through a close flyby) back
# onto the figures' nodes and solves it there. Its gain over the multi-start's best,
# $(J_{ms} - J_{back})/(1 + |J_{ms}|)$, is judged against the multi-start's own "same optimum" tolerance
# ($10^{-6}$): a positive gain is an optimum the generic starts did not find on their own grid. The moved-back plans
# then join the multi-start as starts named `mesh <n>` (`global_search.with_starts`), so the plan adopted below is
# the best known on the figures' grid, and the mesh table's row for that grid shows it
# (`global_search.with_moved_back`, start `back <n>`). `global_search.mesh_starts` does all of this in one call.

# %%
with open_executor(workers, SCHEDULER) as executor:
    mesh_st = global_search.mesh_starts(case.solver, case.sweep, ms, mesh_alphas, mesh_nodes, sigma=SIGMA,
                                        rtol=MESH_RTOL, cold=mesh_cold, executor=executor)
print(mesh_st.summary(MPS))
ms, mstudy = mesh_st.multi, mesh_st.study  # the multi-start with the mesh starts, from here on
ms_better = ms.improvements([sweep_best[alphas.index(a)] for a in ms_alphas])

# %% [markdown]
# **Reading (mesh).** Impulse is the quantity that moves most with the grid: the plans are a few near-impulsive
# thrust spikes, and where a spike can sit depends on the nodes; MI and RMS, which depend only on the window-start
# state, move less. The changes are printed per pair of consecutive grids; the closing table records whether the
# finest pair meets the tolerance, and whether a plan moved back from the finest grid beat the multi-start.
#
# In the full run both headline weights converge: between 40 and 60 nodes the impulse moves by 0.1 % at
# $5\times10^{-3}$ and 0.6 % at $2\times10^{-2}$, MI and RMS by less than half a per cent. Moved back onto the
# figures' 40 nodes, the 60-node plans re-converge to the multi-start's own optimum (relative cost differences of
# order $10^{-11}$ and $10^{-10}$, far inside the $10^{-6}$ that separates two optima), even the one solved from the
# ballistic guess at $2\times10^{-2}$: on test case 1 the multi-start's best is the best plan any grid found.
# Test case 2 (notebook 06) is less kind: at its largest weight a finer grid leads to a lower optimum of the
# figures' own grid, which the generic starts had missed.

# %% [markdown]
# **What the rest of the chapter uses.** Where a start beats the sweep, its plan replaces the sweep's best at that
# weight (`global_search.adopt`): every later section, figure and closing row reads the best plan found per weight.
# The impulse and information of the replaced plans are printed (old -> new), so the sweep's numbers stay on record.

# %%
case = dataclasses.replace(case, sweep=global_search.adopt(case.sweep, ms))
best, impulse_mps, mi = case.best, case.impulse_mps, case.mi
for a, _, _, lab in ms_better:
    i_ = alphas.index(a)
    print(f"alpha_h {a:g}: impulse {sweep_best[i_].impulse * MPS:.3f} -> {impulse_mps[i_]:.3f} m/s, MI "
          f"{sweep_best[i_].information:.3f} -> {mi[i_]:.3f} nats (from {lab})")

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
i5 = alphas.index(5e-3)
with open_executor(workers, SCHEDULER) as executor:
    pen = studies.penalty_study(case, penalty_gammas, penalty_iter, penalty_iter_long, alpha=5e-3, executor=executor,
                                cold=from_ballistic.get(5e-3))
print(pen.summary(best[i5].cost))
_ = plotting.save_figure(figures.convergence(pen), "05_convergence", output_dir=out)

# %% [markdown]
# **Reading.** None of the exact-penalty runs, at any $\gamma$ of the sweep or with the larger iteration limit,
# meets our strict stopping test; the trust region
# shrinks (last $\eta$ printed) while the cost creeps towards our solver's optimum. In the full run no best accepted
# cost reaches the adopted optimum (-0.543793, found by a random start of the multi-start); at $\gamma = 10^2$ it
# comes within $10^{-5}$ of it and lies *below* our solver's own cold-start plan from the same ballistic guess
# (-0.543784 against -0.543750), but with defects still open, so it is not a feasible improvement. The hybrid with
# our quadratic
# information model does not converge within its limit either. The strict test, though, cannot stop *any* method
# with Eq. 44's linear information model: it asks for an inactive trust region, and a linear model's step always
# ends on the trust-region boundary. Notebook 03 (section 5) therefore judges the paper's method on this same
# problem (test case 1, $\alpha_h = 5\times10^{-3}$, 40 nodes) under a practical stopping rule fixed before its runs:
# at $\gamma = 10^3$ the L1 penalty still creeps, but at $\gamma = 10^2$ the printed method stops (113 iterations in
# the full run, at the optimum this notebook's multi-start adopts), and the augmented Lagrangian with the linear
# model stops too. The closing table here keeps the strict-test sweep as a record and judges our modified solver
# (which converges on the whole grid); the verdict on the printed method is 03's.

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
fl = studies.reflight(case)
print(fl.summary(case))
mesh = studies.mesh_check(case, n_nodes_alt, 5e-3, sigma=SIGMA)
print(mesh.summary())

# %% [markdown]
# ## 6 · Figures 1-3: trajectories and thrust
#
# Between nodes the control is linear in time, so a dense re-flight with linearly interpolated controls is the
# same trajectory. Thrust arcs (|a| above 1 % of $a_{max}$) are red, coasts blue, as in the paper. Fig. 3 shows
# the magnitude and all three components; the paper plots $a_x$ and $a_y$ only, since the problem is planar, and
# $a_z$ stays at zero here too (its largest value is printed below the figure).

# %%
show = [alphas.index(5e-3), len(alphas) - 1]  # the paper's 5e-3 and 2e-2 (quick mode: the grid's largest)
_ = plotting.save_figure(figures.trajectories(case, show), "05_fig1_trajectories", output_dir=out)
rel_km, departure_km = studies.departures_km(case)
_ = plotting.save_figure(figures.relative_motion(alphas, rel_km), "05_fig2_relative_motion", output_dir=out)
departure_monotone = bool(np.all(np.diff(departure_km) >= 0))
print("largest departure from the reference DRO [km]:", ", ".join(f"{a:g}: {d:.0f}" for a, d in
                                                                   zip(alphas, departure_km)))
_ = plotting.save_figure(figures.thrust(case, show), "05_fig3_thrust", output_dir=out)
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
# Fig. 5's curve is the **lower envelope over every distinct optimum the multi-start of Section 3 found**
# (`global_search.lower_envelope`: the plans no other plan beats on both impulse and RMS, monotone by construction);
# grey crosses are the other local optima, dots the best-cost plan per weight. A best-cost plan need not lie on
# the envelope: the cost weighs MI against impulse, not the RMS, so a costlier optimum can end with a lower RMS.
#
# Observer and target panels look alike, and should: a relative-position measurement fixes
# $x_{\mathcal T} - x_{\mathcal S}$ to 100 m, so the absolute errors of the two spacecraft move together and their
# RMS values agree to a fraction of a kilometre; what the dynamics must supply is the common absolute part.

# %%
cr = studies.crlb_study(case)
crlb, term_obs, term_tgt, lit = cr.crlb, cr.term_obs, cr.term_tgt, cr.literal
_ = plotting.save_figure(figures.crlb_axes(em, alphas, crlb), "05_fig4_crlb", output_dir=out)
fp = global_search.front_points(ms, sc, case.k_ws, others=dict(zip(alphas, best)))  # every distinct optimum
env = fp.envelope()
_ = plotting.save_figure(figures.pareto(alphas, impulse_mps, term_obs, term_tgt, front=fp), "05_fig5_pareto",
                         output_dir=out)
print(fp.summary())
for a, imp, mo, mt, m1, m2 in zip(alphas, impulse_mps, term_obs, term_tgt, mi, cr.mi_eval):
    print(f"alpha_h {a:7.4f}: {imp:8.3f} m/s  terminal RMS observer {mo:7.3f} km, target {mt:7.3f} km;  "
          f"MI {m1:.3f} (planning Q) / {m2:.3f} nats (Q along the trajectory)")
print(f"with q = 1e-11 km^2/s^3 = {cr.q_literal:.3g} LU^2/TU^3 instead of {sc.q:g}: terminal RMS "
      f"alpha_h = 0: {lit[0].terminal_rms_km[0]:.0f} / {lit[0].terminal_rms_km[1]:.0f} km, alpha_h = {alphas[-1]:g}: "
      f"{lit[1].terminal_rms_km[0]:.0f} / {lit[1].terminal_rms_km[1]:.0f} km (observer / target); growth over the "
      f"window after the transient: {cr.literal_growth[1]:.1f} x")
lit_text = "; ".join(f"alpha_h = {alphas[i]:g}: {c.rms_km[0, 1]:.0f} -> {c.rms_km[0, -1]:.0f} km ({g_:.3f} x)"
                     for i, c, g_ in zip((0, len(alphas) - 1), lit, cr.literal_growth))
print("literal Q, observer RMS at the 2nd measurement -> window end: " + lit_text)

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
rho_obs, rho_tgt = cr.spearman(mi)
print(f"Spearman rank correlation of MI with terminal RMS: observer {rho_obs:+.3f}, target {rho_tgt:+.3f}")
i_best = int(np.argmax(mi))
print(f"baseline alpha_h = 0: {impulse_mps[0]:.3f} m/s, terminal RMS observer {term_obs[0]:.2f} km, target "
      f"{term_tgt[0]:.2f} km, I = {mi[0]:.2f} nats")
print(f"best information plan alpha_h = {alphas[i_best]:g}: {impulse_mps[i_best]:.2f} m/s, observer "
      f"{term_obs[i_best]:.2f} km, target {term_tgt[i_best]:.2f} km, I = {mi[i_best]:.2f} nats")
budget_rows, budget_msgs = studies.budget_study(case, term_obs, budgets_extra_mps, rtol=BUDGET_RTOL)
print("\n".join(budget_msgs))
_ = plotting.save_figure(figures.equal_impulse(impulse_mps, term_obs, budget_rows), "05_equal_impulse",
                         output_dir=out)

# %% [markdown]
# **Reading the figure.** Against the baseline every extra m/s pays off strongly (the "x baseline" ratios printed
# above). Against interpolation the solved plans gain most next to the baseline, where the grid's first interval
# is long compared with how fast the front bends: the front drops more steeply just above the baseline than the
# straight segment between its first two grid points, so interpolation understates what a small extra impulse
# buys. Farther out the grid follows the front closely and interpolation is nearly right (ratios near 1).

# %% [markdown]
# **Does the correlation depend on the process-noise reading?** The plans above were solved under the adopted
# reading of Table 3's "$Q$ [km/s³] = $10^{-11}$" (1e-11 LU²/TU³). Notebook 06 (section 9) lists three other
# readings. Here every plan's CRLB and MI are recomputed along it under each of the four (the plans are not re-solved:
# the question is whether this row's verdict rests on the unit); the criterion, a Spearman coefficient of at most
# $-0.8$, is the one above, fixed before.

# %%
rd1 = readings_study.case1_readings(case)
print(rd1.summary())
_ = plotting.save_figure(figures.figure_readings(rd1, em), "05_mi_crlb_readings", output_dir=out)

# %% [markdown]
# **Reading.** Test case 1 measures the relative position directly, so every extra nat of information tightens the
# terminal CRLB under any of the four readings: in the quick and the full run (2026-11-26) the ranks agree
# perfectly (Spearman -1 in each panel), even under the literal reading, where the absolute RMS reach thousands of
# km. The row is then "reproduced": it does not rest on the chosen unit. (The ratio of the $\alpha_h = 0$ terminal
# RMS to the worst information plan's, in the panel titles, is printed for comparison with test case 2's "weakly
# observable"; the paper makes no such claim for test case 1.)

# %% [markdown]
# ## 8b · How large are the plans? Fig. 1's "not immediately apparent" (beyond the paper)
#
# The paper writes of Fig. 1, which draws the whole reference DRO: "While not immediately apparent, we notice that
# the right trajectory [$\alpha_h = 2\times10^{-2}$] departs from the reference to a higher degree than the left
# [$5\times10^{-3}$]". Our $2\times10^{-2}$ plan is anything but subtle: it spends about 100 m/s and swings far
# outside the DRO (the departures printed in section 6). How much impulse a nat of information is worth, and
# therefore how large the plan of a given $\alpha_h$ is, depends on two things the paper does not state:
#
# * **the normalisation of the control term** of Eq. 42: its unit (LU/TU, km/s or m/s) and whether it is the
#   total impulse or an average (per node, per day; Fig. 5's axis says "average impulse"). Each reading multiplies
#   the control term by a constant $c$ (`scenarios.control_scale`; we have used $c = 1$, total impulse in LU/TU),
#   which is the same as dividing the information weight by $c$;
# * **the process-noise reading** of Table 3 (the adopted $10^{-11}$ LU²/TU³, two other small readings and the
#   literal $10^{-11}$ km²/s³), which sets how much information the window holds.
#
# **The test, fixed before the sweep was first run.** Fig. 1's scale is the DRO's size, its largest distance from
# the Moon $R_{DRO}$. A departure is "not immediately apparent" when it is at most 5 % of $R_{DRO}$ (a few line
# widths on the panel) at *both* weights; a combination *fits the text* when, in addition, the $2\times10^{-2}$
# plan departs further and spends more impulse than the $5\times10^{-3}$ plan (the text's "departs to a higher
# degree" and "increasing the homotopy accumulates a higher total impulse"). Each combination is solved at both
# weights from the ballistic DRO; the minimum-impulse plan ($\alpha_h = 0$), the same for every combination, is
# shown for scale: it too leaves the reference DRO, since it must end on the printed $x_{\mathcal S}(t_f)$, a state
# on a third DRO. A combination whose SCvx iterates fly into the Moon gives no plan (listed as failed). The
# combinations are the parameters `SIZE_NORMALISATIONS` and `SIZE_READINGS`: quick mode solves two normalisations
# under the adopted reading only, the full run 6 normalisations x 4 readings.

# %%
with open_executor(workers, SCHEDULER) as executor:
    size = plan_size_study.plan_size_sweep(n_nodes, normalisations=size_norms, readings=size_reads, sigma=SIGMA,
                                           forward_hessian=forward_hessian, executor=executor, known=from_ballistic)
print(size.summary())

# %% [markdown]
# The figure draws, for each weight, the largest departure against the control-term scale $c$ (log axes), one curve
# per process-noise reading; the dashed line is the 5 % threshold, the dotted line the $\alpha_h = 0$ plan. A
# larger $c$ makes information cheaper to forgo: the departure falls towards the minimum-impulse plan's.

# %%
_ = plotting.save_figure(figures.departure_figure(size), "05_plan_size", output_dir=out)
ad_rows = [size.row(plan_size_study.ADOPTED_NORMALISATION, plan_size_study.ADOPTED_READING, a) for a in size.alphas]
size_ratio = max(r.departure_km for r in ad_rows) / size.dro_size_km
print(f"adopted readings: departure {ad_rows[0].departure_km:,.0f} km at alpha_h = {size.alphas[0]:g}, "
      f"{ad_rows[-1].departure_km:,.0f} km at {size.alphas[-1]:g} ({100 * size_ratio:.0f} % of R_DRO = "
      f"{size.dro_size_km:,.0f} km); Moon distance up to {ad_rows[-1].moon_distance_km:,.0f} km")
b0 = size.baseline
print(f"combinations that fit Fig. 1's text ({len(size.fitting)} of {len(size.normalisations) * len(size.readings)}):")
for n_, q_ in size.fitting:
    hi = size.row(n_, q_, size.alphas[-1])
    print(f"  {n_} / {q_}: {hi.impulse_mps:.2f} m/s and {hi.departure_km:,.0f} km at alpha_h = {size.alphas[-1]:g} "
          f"(alpha_h = 0: {b0.impulse_mps:.2f} m/s, {b0.departure_km:,.0f} km)")

# %% [markdown]
# **Reading.** With the adopted normalisation (total impulse in LU/TU, the unit the solver works in) the plans are
# far too large for "not immediately apparent" under every process-noise reading: tens of thousands of km at
# $5\times10^{-3}$, about the DRO's own size at $2\times10^{-2}$. Normalisations that make impulse *cheaper*
# ($c < 1$: per node or per day in LU/TU or km/s) make the plans larger still, so large that SCvx's iterates reach
# the Moon. Normalisations in m/s ($c$ of 25 to 1000) shrink them. Which of those fit, and how, is in the list
# above; compare each fitting plan's impulse with the $\alpha_h = 0$ plan's. A fit whose $2\times10^{-2}$ plan spends
# hardly more than the minimum-impulse plan passes the test only because the information term then barely acts,
# which sits oddly with the paper's Figs. 2 and 5, where the weights give visibly different plans. In the full run
# the m/s averages (per day, per node) under the small readings are the closest non-trivial candidates: a few m/s
# at $2\times10^{-2}$, with departures just above the 5 % line. Any fitting normalisation is chosen by looking at
# Fig. 1's text, so the closing table marks that agreement "consistent (tuned)", never "reproduced". The paper's
# $\alpha_h$ values mean something only together with that normalisation. Our Pareto fronts (Fig. 5 analogue) do
# not change as curves, since every normalisation traces the same weighted-sum front with $\alpha_h$ relabelled.

# %% [markdown]
# ## 9 · Paper versus reproduction
#
# Tolerances fixed before comparing: "reproduced" for a qualitative claim means the stated behaviour holds for
# every $\alpha_h$ of the grid (criterion in the row); day counts of the text within 1 day; "bounded" CRLB means a
# window-end RMS no larger than at the 2nd measurement; "correlates well" a Spearman rank correlation below -0.8.
# Rows resting on a reading chosen with the paper's claim in view (process noise, the slip in Table 2) are at best
# "consistent (tuned)"; the growth of impulse and MI with $\alpha_h$ is "derived" (any set of global optima of a
# weighted sum has it); the solver rows separate the printed method from ours. The paper prints no number for test
# case 1 beyond its inputs (Tables 2-3), so the quantitative rows are "not in paper" or "beyond paper". Slips in
# the paper are listed with what we used.
#
# Every row below is a claim declared, with its criterion, in `cislunar.papers.wolf_jones.claims.test_case_1`
# before anything is compared; the notebook only measures and calls `judge`, and the status word follows from the
# one rule of `cislunar.publish.claims` (a criterion that holds is "reproduced", or "consistent (tuned)" when the
# comparison rests on a choice made while looking at the paper; one that fails "differs", with its reason).
#
# ### The inputs: Tables 2 and 3 and the readings they need
#
# A printed DRO state is periodic when one period of flight brings it back to itself: the closure after one period
# must stay below the tolerance of notebook 01 (`CLOSURE_TOL`), which nine printed digits allow. The observer's
# starting row fails by a whole length unit, so its row differs and the corrected state is used. Which of its two
# numbers slipped is settled by adjacency (section 1): the adopted reading's $x_0$ and period must fall inside the
# span of the six other rows and the rejected one's outside (a "derived" row that would turn to "differs" if the
# test failed). The window row measures the larger miss of the text's 12 and 23 days against the 1-day tolerance;
# Fig. 3's $\alpha_h$ is compared with the text's printed value; the process-noise rows ask whether the CRLB stays
# bounded under each reading; the zero thrust in the window is an imposed input, checked to round-off.

# %%
table.add(CLAIMS["observer_t0_periodic"].judge(
    chk.raw_closure, shown=f"not periodic (misses itself by {chk.raw_closure:.2f} LU); periodic vy0 = "
    f"{chk.corrected.x0[4]:.7f}", note=f"as printed it {slip.printed_fate}; corrected state used (notebook 01)"))
for key, lab in (("observer_tf_periodic", "observer_tf"), ("target1_t0_periodic", "target1_t0")):
    c_ = sc.row_checks[lab]
    table.add(CLAIMS[key].judge(c_.raw_closure, shown=f"closure after one period {c_.raw_closure:.1e}; period "
                                f"{em.tu_to_days(c_.corrected.period):.2f} d", note="nine printed digits allow ~1e-8"))
ad, rj, vh = slip.ADOPTED, slip.REJECTED, slip.readings[slip.REJECTED]
table.add(CLAIMS["slip_reading"].judge(slip.x0_wins, shown=(
    f"x0 held: x0 = {sc.observer_x0[0]:.5f}, P = {em.tu_to_days(P):.2f} d; vy0 held: x0 = {vh[0][0]:.5f}, P = "
    f"{em.tu_to_days(vh[1]):.2f} d; other rows: x0 {slip.x0_span[0]:.5f}-{slip.x0_span[1]:.5f}, P "
    f"{slip.period_span_days[0]:.2f}-{slip.period_span_days[1]:.2f} d"), note=(
    "the text's day counts were looked at first (largest miss of 12/17/32 d: " + ", ".join(
        f"{k.split(' (')[0]} {v:.2f} d" for k, v in slip.miss_days.items()) + "; of '23 d': " + ", ".join(
        f"{k.split(' (')[0]} {v:.2f} d" for k, v in slip.miss23_days.items()) + ")")))
w_start, w_end = em.tu_to_days(sc.window[0]), em.tu_to_days(sc.window[1])
table.add(CLAIMS["window"].judge(max(abs(w_start - 12.0), abs(w_end - 23.0)), shown=f"{w_start:.2f}-{w_end:.2f} d",
                                 note=f"3P/2 misses 23 d by {abs(w_end - 23.0):.2f} d; P = {em.tu_to_days(P):.2f} d "
                                 f"of the adopted reading; the rejected reading misses 23 d by "
                                 f"{slip.miss23_days[rj]:.2f} d; last daily measurement at "
                                 f"{em.tu_to_days(sc.measurement_times[-1]):.2f} d"))
table.add(CLAIMS["fig3_alpha"].judge(alphas[show[0]], shown="5e-3 shown"))
table.add(CLAIMS["process_noise"].judge(cr.bounded, shown=f"q = {sc.q:g} LU^2/TU^3 (acceleration PSD)", note=(
    "notebook 06, section 9; the SI reading 1e-11 m^2/s^3 and the square-root-PSD reading (1e-11)^2 km^2/s^3 "
    "would pass the same test")))
table.add(CLAIMS["literal_q_bounded"].judge(
    not any(g_ > 1.0 for g_ in cr.literal_growth), shown=lit_text + f" (adopted q: {crlb[0].rms_km[0, 1]:.0f} -> "
    f"{term_obs[0]:.0f} km and {crlb[-1].rms_km[0, 1]:.0f} -> {term_obs[-1]:.1f} km)", note=(
        f"levels too: {lit[0].terminal_rms_km[0]:.0f} km at alpha_h = 0 is "
        f"{lit[0].terminal_rms_km[0] / wolf_jones.SIGMA_POS_KM:.0f} prior sigmas")))
table.add(CLAIMS["window_thrust"].judge(max(fl.window_thrust), shown=f"max |u| in the window "
                                        f"{max(fl.window_thrust):.0e}", note="imposed input (u_k = 0 at every "
                                        "window node), not a prediction"))

# %% [markdown]
# ### The solver rows
#
# The paper implies that its SCvx converges: Figs. 2 and 5 show converged trajectories for every weight. The
# printed method is the L1 exact penalty on the defects (Eq. 43) with the linear information model of Eq. 44;
# whether it converges is measured as a yes/no (does any run of the $\gamma$ sweep of section 4 meet the stopping
# test?), so the row differs as soon as no run does. The long run at $\gamma = 10^3$ and the hybrid are listed
# beyond the paper: they say *why* it fails (the trust region shrinks while defects stay open), not whether.
# Our modified solver is held to its own criterion, fixed before the sweep: every run converges with defects at
# most $10^{-9}$; a failure would turn that "beyond paper" row into "differs".

# %%
pen_summary = "; ".join(f"gamma {r['gamma']:.0e}, {r['max_iter']} it: " + (
    "converged" if r["converged"] else f"not converged, last defect {r['history'][-1]['max_defect']:.0e}, eta "
    f"{r['eta']:.0e}") for r in pen.runs)
table.add(CLAIMS["printed_scvx"].judge(pen_summary, note=(
    "gamma and the iteration limit are unstated: swept (section 4); best accepted cost at gamma 1e3: "
    f"{pen.printed['best']:.5f} vs {best[i5].cost:.5f} of our solver; the strict test asks for an inactive trust "
    "region, which a linear MI model's step never has (notebook 03, section 5, where the printed method stops at "
    "gamma = 1e2 under the practical rule)")))
table.add(CLAIMS["printed_scvx_long"].judge(pen.long_run["outcome"], note=(
    f"gamma 1e3, {pen.long_run['max_iter']} iterations; best accepted cost {pen.long_run['best']:.5f}; last trust "
    f"radius {pen.long_run['eta']:.1e}; hybrid (L1 penalty, quadratic MI, {pen.hybrid['max_iter']} it): "
    f"{pen.hybrid['outcome']}")))
att = case.sweep.attempts
table.add(CLAIMS["modified_scvx"].judge(
    all(a["converged"] for a in att) and max(r.max_defect for r in best) <= 1e-9,
    shown=f"{sum(a['converged'] for a in att)}/{len(att)} runs, largest defect {max(r.max_defect for r in best):.0e}",
    note="augmented Lagrangian + quadratic MI model + changed acceptance (section 3)"))

# %% [markdown]
# ### The figure claims (Figs. 2, 4 and 5)
#
# Each qualitative statement of the text is measured as a yes/no over the whole $\alpha_h$ grid, with the test
# written in the claim: the largest distance from the DRO (Fig. 2) and the impulse and MI (Fig. 5) never decrease
# as $\alpha_h$ grows; the CRLB rises from the first to the second measurement (the transient of Fig. 4) and ends
# the window no higher than at the second measurement ("bounded"); the largest weight ends with a lower terminal
# RMS than $\alpha_h = 0$ for observer and target. "Correlates well" is the larger of the two Spearman rank
# correlations between MI and terminal RMS, at most $-0.8$, judged under each of the four readings of $Q$
# (section 8; `claims.process_noise_readings`: "reproduced" only if it holds under every reading). The "bounded"
# row, like the process-noise row above, is "consistent (tuned)" at best, because the reading of $Q$ was picked by
# this very property. Fig. 1's "not immediately apparent" is tested as in section 8b (largest departure at most
# 5 % of the DRO's size at both weights): under the adopted normalisation, and whether any normalisation and
# reading fits the text (at best "consistent (tuned)", since such a fit is chosen by looking at the text).

# %%
table.add(CLAIMS["departure"].judge(departure_monotone, shown="largest distance from the DRO " + ", ".join(
    f"{a:g}: {d / 1e3:.1f}" for a, d in zip(alphas, departure_km)) + " (10^3 km)",
    note="best of upward and downward sweeps of the modified solver"))
table.add(CLAIMS["front_monotone"].judge(case.monotone, shown=f"impulse {impulse_mps[0]:.2f} -> {impulse_mps[-1]:.1f}"
                                         f" m/s, MI {mi[0]:.1f} -> {mi[-1]:.1f} nats"))
table.add(CLAIMS["transient"].judge(cr.transient, shown=f"RMS grows from the 1st to the 2nd measurement: "
                                    f"{cr.transient} (alpha_h = 0: {crlb[0].rms_km[0, 0]:.0f} -> "
                                    f"{crlb[0].rms_km[0, 1]:.0f} km)", note="diagonal prior, no correlations "
                                    "(paper's explanation)"))
table.add(CLAIMS["bounded"].judge(cr.bounded, shown=f"window end <= 2nd-measurement RMS: {cr.bounded}"))
table.add(CLAIMS["information_gain"].judge(
    bool(term_obs[-1] < term_obs[0] and term_tgt[-1] < term_tgt[0]), shown=f"observer {term_obs[0]:.1f} -> "
    f"{term_obs[-1]:.1f} km, target {term_tgt[0]:.1f} -> {term_tgt[-1]:.1f} km", note=(
        f"alpha_h = 0 vs {alphas[-1]:g}; holds under the literal Q too ({lit[0].terminal_rms_km[0]:.0f} -> "
        f"{lit[1].terminal_rms_km[0]:.0f} km)")))
for key, m in rd1.measurements().items():  # "correlates well" under each reading of Q (section 8)
    table.add(READING_CLAIMS[key].judge(m.value, shown=m.shown, note=m.note + f"; over the {len(alphas)} alpha_h "
                                        "of the grid, as in notebook 06", reason=m.reason))
ad_text = ", ".join(f"{r.alpha:g}: {r.departure_km:,.0f} km, {r.impulse_mps:.1f} m/s" for r in ad_rows)
table.add(SIZE_CLAIMS["fig1_size_adopted"].judge(size_ratio, shown=(
    f"largest departure {max(r.departure_km for r in ad_rows):,.0f} km = {100 * size_ratio:.0f} % of the DRO's "
    f"{size.dro_size_km:,.0f} km ({ad_text})"),
    note=f"threshold fixed before the sweep: {100 * size.fraction:g} % of the DRO's largest Moon distance; "
         f"{size.n_nodes} nodes, q = 1e-11 LU^2/TU^3"))
table.add(SIZE_CLAIMS["fig1_size_some_reading"].judge(bool(size.fitting), shown=(
    "fit: " + ("; ".join(f"{n} / {q.split(' (')[0]}" for n, q in size.fitting) if size.fitting else "none")
    + f" (of {len(size.normalisations)} normalisations x {len(size.readings)} readings)"),
    note=f"impulse at {size.alphas[-1]:g} of each fit: " + (", ".join(
        f"{size.row(n_, q_, size.alphas[-1]).impulse_mps:.3f} m/s" for n_, q_ in size.fitting) or "-")
    + f" (alpha_h = 0: {size.baseline.impulse_mps:.3f} m/s); control term = c x total impulse in LU/TU, c: "
    + ", ".join(f"{n.split(' (')[0]} {size.row(n, size.readings[0], size.alphas[0]).control_scale:.3g}"
                for n in size.normalisations)))

# %% [markdown]
# ### Beyond the paper
#
# The remaining rows have nothing in the paper to compare with: the single-shooting re-flight (how real the plans
# are), the mesh check on a second node grid (the paper gives no $N$), the plans solved at a prescribed impulse (the
# fair form of the "substantial improvement over a baseline" claim, section 8), the Pareto values themselves (the
# paper's axes are not readable), the comparison of the upward and downward sweeps (whether the grid meets distinct
# local optima) and the record of the plan-size sweep of section 8b. They carry no criterion; their numbers are what
# a later reproduction would compare with.

# %%
table.add(CLAIMS["reflight"].judge(max(fl.miss_km), shown=f"largest terminal miss {max(fl.miss_km):.1e} km",
                                   note="FOH control alone from x_S(t0), nonlinear CR3BP"))
table.add(CLAIMS["mesh"].judge(mesh.impulse_change, shown=(
    f"{n_nodes} nodes: {mesh.impulse_mps[0]:.2f} m/s, RMS {mesh.rms_km[0]:.2f} km; {n_nodes_alt} nodes: "
    f"{mesh.impulse_mps[1]:.2f} m/s, RMS {mesh.rms_km[1]:.2f} km"), note=(
    f"impulse changes by {100 * mesh.impulse_change:.1f} %, RMS by {100 * mesh.rms_change:.0f} %: near-impulsive "
    f"plans (|u|/a_max <= {max(fl.max_ratio):.2f})")))
for r in budget_rows:
    table.add(CLAIMS["budget"].judge(r.rms_obs, shown=(
        f"{r.budget:.1f} m/s: alpha_h = {r.alpha:.2e} spends {r.impulse:.2f} m/s: observer RMS {r.rms_obs:.1f} km "
        f"vs {term_obs[0]:.1f} km at {impulse_mps[0]:.2f} m/s ({r.rms_obs / term_obs[0]:.2f} x)"), note=(
        f"budget met within {100 * BUDGET_RTOL:g} %; log-interpolation on the grid at the spent impulse said "
        f"{r.interp:.1f} km")))
table.add(CLAIMS["pareto_values"].judge(term_tgt[-1], shown=f"{impulse_mps[-1]:.1f} m/s -> target "
                                        f"{term_tgt[-1]:.2f} km at alpha_h = {alphas[-1]:g}"))
table.add(CLAIMS["local_optima"].judge(case.cost_gap, shown=f"largest cost difference {case.cost_gap:.0e}: " + (
    "distinct local optima found" if case.distinct_optima else "both sweeps reach the same optimum on this grid"),
    note="best cost per alpha_h kept; differences below 1e-8 relative are solver round-off"))
table.add(CLAIMS["distinct_optima"].judge(max(ms.n_distinct), shown="optima found per alpha_h: " + ", ".join(
    f"{a:g}: {n_}" for a, n_ in zip(ms.alphas, ms.n_distinct)), note=f"{len(ms.outcomes)} starts; cost range per "
    "alpha_h: " + ", ".join(f"{a:g}: {hi - lo:.1e}" for a, (lo, hi) in zip(ms.alphas, ms.cost_range))
    + "; same optimum: cost within 1e-6 (1 + |J|), plans within 100 km"))
table.add(CLAIMS["multi_start"].judge(len(ms_better), shown=(
    f"better than the sweeps at {len(ms_better)} of {len(ms.alphas)} weights"
    + ("" if not ms_better else ": " + "; ".join(
        f"{a:g}: {sweep_best[alphas.index(a)].impulse * MPS:.2f} -> {impulse_mps[alphas.index(a)]:.2f} m/s, cost "
        f"{c0:.5f} -> {c1:.5f}" for a, c0, c1, _ in ms_better))),
    note="the figures and rows above use the best plan per weight"))
off_env = [a for i_, a in enumerate(fp.alpha) if fp.optimum[i_] == 0 and i_ not in set(env.index.tolist())]
table.add(CLAIMS["envelope"].judge(len(env.index), shown=f"{len(env.index)} of {len(fp.alpha)} distinct optima "
                                   f"on the envelope; {impulse_mps[0]:.2f} -> {env.x[-1]:.1f} m/s, observer RMS "
                                   f"{env.y[0]:.1f} -> {env.y[-1]:.2f} km", note=(
    "best-cost plans off the envelope (a costlier optimum ends with a lower RMS): " + ("at alpha_h "
        + ", ".join(f"{a:g}" for a in off_env) if off_env else "none"))))
table.add(CLAIMS["mesh_study"].judge(all(mstudy.converged(a) for a in mstudy.alphas), shown="; ".join(
    f"alpha_h {a:g}: " + ", ".join(f"{r.n_nodes} nodes {r.impulse_mps:.2f} m/s / {r.rms_km:.1f} km"
                                   for r in mstudy.table(a) if r.converged) for a in mstudy.alphas),
    note=f"figures use {mstudy.figure_nodes} nodes; largest change between the two finest grids: " + ", ".join(
        f"{a:g}: {100 * mstudy.finest_change(a):.1f} %" for a in mstudy.alphas)))
if (back_row := mesh_st.back_measurement()) is not None:  # a finer grid converged (not in the quick run)
    table.add(CLAIMS["mesh_back"].judge(**back_row))
else:
    print("not judged in this run: no mesh grid finer than the figures' converged, so no plan was moved back")
size_failed = [r for r in size.rows if not r.converged]
table.add(SIZE_CLAIMS["plan_size_sweep"].judge(len(size.rows) - len(size_failed), shown=(
    f"{len(size.rows) - len(size_failed)}/{len(size.rows)} solves converged; departure at {size.alphas[-1]:g} from "
    f"{np.nanmin(size.departures(size.alphas[-1])):,.0f} to {np.nanmax(size.departures(size.alphas[-1])):,.0f} km"),
    note=f"alpha_h = 0 plan departs {size.baseline.departure_km:,.0f} km (it must reach x_S(t_f) on a third DRO); "
         f"{size.seconds:.0f} s" + ("; no plan (" + size_failed[0].error[:40] + "...): " + ", ".join(sorted(
             {r.normalisation for r in size_failed})) if size_failed else "")))
table.display()

# %% [markdown]
# ## Exercises
#
# Each exercise asks you to change one entry of the parameters cell, to predict what will happen before running,
# and then to check. The worked solutions are functions of `cislunar.papers.wolf_jones.exercises`, run at small
# sizes (a few seconds each); each returns the numbers that answer the exercise and an `answer` paragraph.
#
# 1. **Fewer nodes.** Set `N_NODES = 10` (quick mode uses 18, full mode 40) and rerun. Before you do: will the
#    minimum-impulse plan ($\alpha_h = 0$, the first row of the table in Section 3 and the left end of Fig. 5) cost
#    more or less impulse, and will its terminal RMS move as much? Think of what a first-order-hold control can
#    represent on a coarser grid. Worked solution: `exercises.exercise_05_node_count`, which solves
#    $\alpha_h = 0$ on 10, 14 and 18 nodes.
# 2. **Patience for the printed method.** Raise `PENALTY_ITER_LONG` (10 in quick mode) to 60. Does the paper's
#    exact-penalty SCvx converge if it is only given more iterations? Predict what happens to its largest defect,
#    its best accepted cost and its trust-region radius (the long-run line of Section 4 and the row "printed SCvx
#    at gamma 1e3 with a larger iteration limit"). Worked solution: `exercises.exercise_05_penalty_iterations`
#    (10 and 30 iterations on a 10-node grid).
