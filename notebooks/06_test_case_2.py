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
# All computation lives in `cislunar.papers.wolf_jones.scenarios` (scenario, information model, keep-out, CRLB, sweeps),
# `cislunar.papers.wolf_jones.test_case_studies` (the studies of this chapter, each returning a frozen result),
# `cislunar.papers.wolf_jones.figures` (the figures) and `cislunar.guidance.scvx` (the solver).

# %% [markdown]
# **How to use this chapter.** The next cell (tagged `parameters`) holds everything you might change: the node
# grid and the homotopy weights, the iteration limits, the keep-out radii and the scan of Section 3, the budget of
# Section 11. Leave an entry at `None` and the notebook picks it (the values in brackets in the comments: a
# shorter, coarser run when `QUICK = True`, then the full run); give a value (edit the cell, or pass `-p NAME=VALUE`
# to the runner) and it is used as given in both modes. The independent SCvx runs (the two sweep directions, the
# seeded runs, the other node grids, the keep-out radii and the $a_{max}$ readings) run on `WORKERS` local processes
# or on a Dask cluster (`SCHEDULER`); every run is deterministic, so the numbers do not depend on where they run.

# %% tags=["parameters"]
QUICK = False
SEED = 0  # seed of the random perturbation starts of the multi-start (Section 4); everything else is deterministic
OUTPUT_DIR = ""
N_NODES = None  # Sundman nodes over the three periods, window ends moved onto nodes (None: 16 quick, 30 full)
MAX_ITER = None  # SCvx iteration limit per run (None: 100 quick, 150 full)
N_NODES_ALT = None  # other node grids on which the whole sweep is solved again (None: [12] quick, [24, 27] full)
ALT_DIRECTIONS = None  # homotopy chains of the sweep on those grids (None: ["up"] quick, ["up", "down"] full)
FREE_ITER = None  # iterations granted to the run without keep-out at the Fig. 6 weight (None: 5 quick, 75 full)
SIGMA = 1.0  # Sundman exponent of the node spacing, dt / dtau equal to r_m^sigma (notebook 04)
ALPHAS = None  # homotopy weights alpha_h, increasing in [0, 1] (None: [0, 5e-3, 1e-2] quick; 8 values full)
SEED_ALPHAS = None  # weights solved from +z and -z seeds, Fig. 7's pair (None: [] quick, [5e-3, 7e-3] full)
MIRROR_ALPHA = 5e-3  # weight whose sweep optimum is mirrored in z and solved again (both modes)
D_MIN_KM = None  # keep-out radii solved besides the adopted 424 km, km (None: [1500] quick, 5 radii 10-2500 full)
RADIUS_WARM = None  # radius solves start from the adopted plan (True) or the ballistic guess (None: True quick, False full)
SCAN_POINTS = None  # pass distances of the closest-approach scan of Section 3 (None: 8 quick, 20 full)
SCAN_RANGE_KM = [1e-6, 3000.0]  # closest and farthest pass distance of that scan, km
BUDGET_EXTRA_MPS = 5.0  # impulse budget above the baseline's for the equal-impulse solve of Section 11, m/s
BUDGET_RTOL = 0.02  # a budget counts as met within this relative tolerance (fixed before solving)
SAME_PLAN_KM = 100.0  # two plans are the same if their node positions are never farther apart, km (fixed in advance)
MS_ALPHAS = None  # weights solved from several starts in Section 4, a subset of ALPHAS (None: [1e-2] quick, all full)
MS_RANDOM = None  # random perturbation starts per weight in the multi-start (None: 1 quick, 1 full)
MS_SEEDS_Z = None  # +z and -z seeded starts in the multi-start (None: False quick, True full)
MESH_NODES = None  # node counts of the mesh study besides N_NODES, Section 4 (None: [12] quick, [20, 45, 60] full)
MESH_ALPHAS = None  # weights of the mesh study, in ALPHAS (None: [1e-2], Fig. 6's, quick; [5e-3, 1e-2, 2e-2] full)
MESH_COLD = None  # also solve the mesh study's grids from the ballistic guess (None: no quick, yes full)
MESH_RTOL = 0.05  # a weight's plan has converged in the mesh when impulse, MI and RMS change by at most this much
#                   between the two finest grids (fixed before solving)
DIAG_ALPHA = None  # weight of the diagnosed SCvx run without keep-out, Section 11
#                    (None: 1e-2, the Fig. 6 weight, quick; 2e-2 full)
REMEDY_ALPHAS = None  # weights solved with each remedy (range-dependent noise, regularised range-rate Jacobian)
#                       and no keep-out, Section 11
#                       (None: [1e-2] quick, [5e-3, 1e-2, 2e-2] full)
D_SCAN_KM = None  # closest approaches of the pass scan without keep-out, Section 11, km
#                   (None: [0.3, 3, 30, 424] quick, [0.1, 0.3, 1, 3, 10, 30, 100, 424] full)
REMEDY_RANGE_KM = 141.0  # range scale rho_c of both remedies, km (fixed before any run)
WORKERS = None  # local processes for the independent SCvx runs, 1 runs serially (None: 1 quick, 2 full)
SCHEDULER = ""  # address of a Dask scheduler to run them on, e.g. "tcp://10.0.0.5:8786" ("": none; WORKERS applies)

# %%
n_nodes = N_NODES if N_NODES is not None else (16 if QUICK else 30)
max_iter = MAX_ITER if MAX_ITER is not None else (100 if QUICK else 150)
n_nodes_alt = N_NODES_ALT if N_NODES_ALT is not None else ([12] if QUICK else [24, 27])
alt_directions = ALT_DIRECTIONS if ALT_DIRECTIONS is not None else (["up"] if QUICK else ["up", "down"])
free_iter = FREE_ITER if FREE_ITER is not None else (5 if QUICK else 75)
alphas = ALPHAS if ALPHAS is not None else ([0.0, 5e-3, 1e-2] if QUICK else [0.0, 5e-4, 1e-3, 2e-3, 5e-3, 7e-3, 1e-2,
                                                                              2e-2])
seed_alphas = SEED_ALPHAS if SEED_ALPHAS is not None else ([] if QUICK else [5e-3, 7e-3])
d_min_km = D_MIN_KM if D_MIN_KM is not None else ([1500.0] if QUICK else [10.0, 141.0, 1000.0, 1500.0, 2500.0])
radius_warm = RADIUS_WARM if RADIUS_WARM is not None else QUICK
scan_points = SCAN_POINTS if SCAN_POINTS is not None else (8 if QUICK else 20)
workers = WORKERS if WORKERS is not None else (1 if QUICK else 2)
ms_alphas = MS_ALPHAS if MS_ALPHAS is not None else ([1e-2] if QUICK else list(alphas))
ms_random = MS_RANDOM if MS_RANDOM is not None else 1
ms_seeds_z = MS_SEEDS_Z if MS_SEEDS_Z is not None else not QUICK
mesh_nodes = MESH_NODES if MESH_NODES is not None else ([12] if QUICK else [20, 45, 60])
mesh_alphas = MESH_ALPHAS if MESH_ALPHAS is not None else ([1e-2] if QUICK else [5e-3, 1e-2, 2e-2])
mesh_cold = MESH_COLD if MESH_COLD is not None else not QUICK
diag_alpha = DIAG_ALPHA if DIAG_ALPHA is not None else (1e-2 if QUICK else 2e-2)
d_scan_km = D_SCAN_KM if D_SCAN_KM is not None else ([0.3, 3.0, 30.0, 424.0] if QUICK else
                                                       [0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 424.0])
remedy_alphas = REMEDY_ALPHAS if REMEDY_ALPHAS is not None else ([1e-2] if QUICK else [5e-3, 1e-2, 2e-2])

import time

import numpy as np
from scipy.stats import spearmanr

from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import case_2_closing as closing
from cislunar.papers.wolf_jones import figures, global_search, readings_study
from cislunar.papers.wolf_jones import keep_out_diagnosis as kod
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.papers.wolf_jones import test_case_studies as studies
from cislunar.papers.wolf_jones.claims.keep_out_remedy import CLAIMS as REMEDY_CLAIMS
from cislunar.papers.wolf_jones.claims.keep_out_remedy import CLOSE_PASS_KM, GRADIENT_GROWTH
from cislunar.papers.wolf_jones.claims.process_noise_readings import CLAIMS as READING_CLAIMS
from cislunar.papers.wolf_jones.claims.test_case_2 import CLAIMS
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.utils.executors import open_executor

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)  # the multi-start's random perturbation starts (Section 4)
table = ComparisonTable("06 Test case 2 (Wolf & Jones Tables 4-5, Figs. 6-10)")
t_start = time.perf_counter()

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
print(f"P_ref = {em.tu_to_days(sc.period):.3f} d, scenario {em.tu_to_days(sc.duration):.2f} d, window "
      f"[{ws_d:.2f}, {we_d:.2f}] d with {sc.measurement_times.size} daily range/range-rate pairs per target")
print(f"a_max = {sc.a_max * em.acceleration_unit_km_s2:.1e} km/s^2 = {sc.a_max:.4f} LU/TU^2; "
      f"process-noise PSD q = {sc.q:.0e} LU^2/TU^3 = {sc.q * em.length_unit_km**2 / em.time_unit_s**3:.2e} km^2/s^3")
t, k_ws, k_we = sc.node_times(n_nodes, SIGMA)
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
gc = studies.gradient_check(info, x_ws_ball, em)
g = gc.gradient
print(f"MI on the ballistic guess: {gc.value:.6f} nats (order 0) vs {gc.value_order1:.6f} (order 1)")
print("gradient [nats/LU, nats/(LU/TU)]:", np.round(g, 4), "\ncentral differences:             ",
      np.round(gc.gradient_fd, 4))
print(f"max relative difference {gc.relative_error:.1e}; z components {g[2]:.1e}, {g[5]:.1e} (planar symmetry)")

# %% [markdown]
# **The planar guess is a saddle in z.** By the CR3BP's mirror symmetry $z\to-z$ (and that of range and range
# rate) the MI is an even function of the out-of-plane state at a planar reference: its z-gradient vanishes, but
# its z-curvature is positive: leaving the plane in *either* direction gains information. A linear (Eq. 44) or
# concave model sees nothing to gain in z; the out-of-plane motion of Fig. 6 appears only once the iterates leave
# the plane (solver round-off is enough), and its sign is then an accident, which is the z-mirror of Fig. 7.

# %%
print(f"MI with vz = +1 m/s: {gc.mi_vz_up:+.4f} nats, vz = -1 m/s: {gc.mi_vz_down:+.4f} nats (relative to planar)")
print(f"Hessian diagonal (z, vz): {gc.hessian[2, 2]:.3e}, {gc.hessian[5, 5]:.3e}; "
      f"eigenvalues: {np.array2string(np.linalg.eigvalsh(gc.hessian), precision=2)}")

# %% [markdown]
# ## 3 · Why a keep-out, and how large
#
# The range-rate Jacobian with respect to the relative position is $(\Delta\dot{\mathbf r}-\dot\rho\hat\rho)/\rho$:
# it grows without bound as the range $\rho$ shrinks, and so does the linear-Gaussian MI. Below we move the
# observer's window-start state (Newton on the STM) so that it passes target 1 at a chosen distance at the middle
# measurement of the window and evaluate the MI: nearly flat down to about a hundred metres, the reward then
# grows without bound (like $\ln(1/\rho)$), so a maximiser that finds this region could fly through the target
# (section 11: without a keep-out SCvx fails at some weights, the iterates heading for a target until a convex
# subproblem fails, and only just converges at others; we print how close its iterates come; smaller keep-outs
# are tried there too). Well before
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
scan = studies.keep_out_scan(sc, info, x_ws_ball, scan_points, d_range_km=SCAN_RANGE_KM)
_ = plotting.save_figure(figures.keep_out_motivation(scan, sc.keep_out_km), "06_keep_out_motivation", output_dir=out)
for d_show in (1000.0, 424.0, 1.0, 0.1, 1e-3, 1e-6):
    print(f"pass at {d_show:8.0e} km: MI gain {scan.gain_at(d_show):+.2f} nats")

# %% [markdown]
# ## 4 · SCvx over the homotopy grid, swept both ways
#
# For each $\alpha_h$ the solver (`cislunar.guidance.scvx`: SCvx* augmented Lagrangian on the defects, the convex
# quadratic MI model from the concave part of the Hessian, the keep-out as a linearised constraint) starts from a
# warm start. The problem has several local optima, so we sweep the grid upward (from the ballistic guess at
# $\alpha_h = 0$) and downward (from the ballistic guess at the largest $\alpha_h$) and keep the lower cost per
# $\alpha_h$. The two sweeps are independent: with `WORKERS = 2` they run side by side, together with the
# seeded runs of section 7 and the sweeps on other node grids of section 6 (`test_case_studies.case2_runs`
# queues them all on one executor and collects them). On those other grids `ALT_DIRECTIONS` says which chains run:
# both in the full run, only the upward one in the quick run (half the solves; that grid then reports the upward
# chain's optima, not the better of two).

# %%
solver = wj.ScenarioSolver(sc, t, k_ws, information=info, keep_out=True,
                           settings=scvx.SCvxSettings(max_iter=max_iter))
with open_executor(workers, SCHEDULER) as executor:  # seeded runs (section 7), this sweep, other grids (section 6)
    runs = studies.case2_runs(sc, solver, alphas, x_ball, u_ball, seed_alphas=seed_alphas, alt_nodes=n_nodes_alt,
                              sigma=SIGMA, executor=executor, alt_directions=alt_directions)

# %% [markdown]
# **Several starts per weight.** Two sweeps give at most two starts per weight. `global_search.multi_start`
# solves each weight again from several starts: the ballistic guess, a $+z$ and a $-z$ seed (the planar guess is a
# saddle in $z$, section 2; the seeded runs of section 7 are reused where they exist), random perturbations of the
# control (a Gaussian direction of 5 % of $a_{max}$ per node, drawn from the notebook's generator before anything
# is solved) and, in a second round, the best plan of each neighbouring weight. The sweep's plans count as starts,
# so the multi-start can only match or beat them. Two converged plans are the *same* local optimum when their costs
# agree within $10^{-6}(1+|J|)$ and their node positions (or one's and the other's $z$-mirror, which is an optimum
# with the same cost) never lie more than 100 km apart; otherwise they are *distinct* (tolerances fixed before the
# runs). Per weight: starts, how many converged, how many distinct optima, and the spread of their costs. Where a
# sweep's best plan came from a cold start, it was solved from the ballistic guess: it counts as the ballistic start
# of that weight instead of being solved again (every run is deterministic; same plan, bit for bit).

# %%
known = global_search.known_from_sweep(runs.sweep, ms_alphas)
for (a_, z_), r_ in runs.seeded.items():  # section 7's seeded runs are the multi-start's +z / -z starts there
    if a_ in ms_alphas and not isinstance(r_, Exception):
        known.setdefault(a_, []).append(("+z seed" if z_ > 0 else "-z seed", r_))
for a_, rows_ in global_search.known_from_sweep(runs.sweep, ms_alphas, which="ballistic").items():  # a sweep's
    known.setdefault(a_, []).extend(rows_)  # best solved from the ballistic guess is the ballistic start there
with open_executor(workers, SCHEDULER) as executor:
    multi = global_search.multi_start(solver, ms_alphas, rng=rng, n_random=ms_random, seeds_z=ms_seeds_z, known=known,
                                   executor=executor)
print(multi.summary())
sweep_best = dict(zip(alphas, runs.sweep.best))
mps = em.velocity_unit_km_s * 1e3
ms_better = multi.improvements([sweep_best[a] for a in ms_alphas])
print("better than the sweeps' best: " + ("; ".join(
    f"alpha_h {a:g}: cost {c0:.6f} -> {c1:.6f} (from {lab})" for a, c0, c1, lab in ms_better) or "nowhere"))

# %% [markdown]
# **Mesh study.** Does the best plan converge as nodes are added? `global_search.mesh_study` solves the headline
# weights (full run: Fig. 7's $5\times10^{-3}$, Fig. 6's $10^{-2}$ and the sweep's largest, $2\times10^{-2}$; quick
# run: Fig. 6's) on Sundman grids up to 60 nodes (full run), each from the multi-start's best plan interpolated onto
# the grid and (full run only) from the ballistic guess, keeping the better; a plan counts as mesh-converged when
# impulse, MI and terminal RMS change by at most `MESH_RTOL` (5 %, fixed before solving) between the two finest
# grids. The figures use the `N_NODES` grid.
#
# **The mesh study's plans as starts on the figures' grid.** Every grid of the mesh study is one more start for
# the figures' grid: `global_search.back_to_grid` takes each weight's plan on the finest grid (finer grids only: a
# coarser plan interpolated in time can cut through a close flyby), moves it back onto the figures' nodes (states
# and first-order-hold controls interpolated in time) and solves it there. Its gain over the multi-start's best is
# $(J_{ms} - J_{back}) / (1 + |J_{ms}|)$, the multi-start's own measure of "the same optimum" ($10^{-6}$): a
# positive gain is an optimum that the generic starts above did not find on their own grid. The moved-back plans
# then join the multi-start as starts named `mesh <n>` (`global_search.with_starts`), so the best
# plan per weight is the best known on the figures' grid, and the mesh table's row for that grid shows it
# (`global_search.with_moved_back`, start `back <n>`). `global_search.mesh_starts` does all of this in one call.

# %%
with open_executor(workers, SCHEDULER) as executor:
    mesh_st = global_search.mesh_starts(solver, runs.sweep, multi, mesh_alphas, mesh_nodes, sigma=SIGMA,
                                        rtol=MESH_RTOL, cold=mesh_cold, executor=executor)
print(mesh_st.summary(mps))
multi, mstudy = mesh_st.multi, mesh_st.study  # the multi-start with the mesh starts, from here on
ms_better = multi.improvements([sweep_best[a] for a in ms_alphas])

# %% [markdown]
# **Reading (mesh).** In the full run the plans at $5\times10^{-3}$ and $10^{-2}$ converge: between 45 and 60
# nodes the impulse moves by about 2 %, MI and RMS by less; on every grid the plan continued from the multi-start's
# (warm) beats the one solved from the ballistic guess, and moved back onto 30 nodes it lands on the multi-start's
# optimum ($10^{-2}$) or above it ($5\times10^{-3}$). At $2\times10^{-2}$ the multi-start's plan, continued from
# grid to grid, converges too (68.3, 64.6, 62.8, 61.1 m/s on 20, 30, 45, 60 nodes), but on 60 nodes the ballistic
# start finds another local optimum with a lower cost (-4.0914 against -4.0812) and 25 % more impulse (76.6 m/s).
# That optimum is not an artefact of the fine grid: moved back onto the figures' 30 nodes it converges there to a
# cost $3.0\times10^{-3}(1+|J|)$ below the multi-start's best (91.0 against 64.6 m/s, 208.9 against 206.9 nats,
# terminal observer RMS 28.8 against 36.6 km). The generic starts missed the best known optimum of their own grid
# at that weight (closing row "differs"); it is adopted, so from here on every figure and row at $2\times10^{-2}$
# uses this plan, which thrusts at up to 82 % of $a_{max}$ and swings much farther from the DRO (section 6). The
# mesh row keeps each grid's best plan, as declared before the runs, and says "differs": at the largest weight
# the impulse of the best plan found changes by 22-33 % from grid to grid (MI by about 1 %), because the starts
# reach different optima on different grids (the non-convexity of this section again). The figures' headline
# weights $5\times10^{-3}$ and $10^{-2}$ are resolved to a few per cent.

# %% [markdown]
# **The plans used from here on.** Where a start beats the sweeps, its plan replaces theirs at that weight
# (`global_search.adopt`), so every later section, figure and closing row reads the best plan found per weight
# (the table's `sweep` column names the start). The replaced plans' impulse and MI are printed (old -> new).

# %%
case = studies.case2_rows(sc, solver, k_ws, k_we, global_search.adopt(runs.sweep, multi), runs.seconds)
print(case.summary())
ok, by_alpha = case.ok, case.by_alpha
for a, _, _, lab in ms_better:
    old_ = sweep_best[a]
    print(f"alpha_h {a:g}: impulse {old_.impulse * mps:.2f} -> {by_alpha[a].dv:.2f} m/s, MI {old_.information:.2f} -> "
          f"{by_alpha[a].mi:.2f} nats (from {lab})")


def pick(a):
    """The row of alpha a, or of the converged alpha nearest to it (printed), so that no figure is left empty."""
    row, note = case.pick(a)
    if note:
        print(note)
    return row

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
row6 = pick(1e-2)
a6 = row6.alpha
_ = plotting.save_figure(figures.absolute_trajectory(sc, t, row6.res, a6), "06_fig6_absolute_trajectory",
                         output_dir=out)

# %% [markdown]
# ## 6 · Figure 7: motion relative to the reference DRO over the grid
#
# The observer's position minus that of the reference DRO at the same time, with the initial (green) and terminal
# (red) states marked. Drawn for five weights of the grid, among them the paper's pair $5\times10^{-3}$ and
# $7\times10^{-3}$ (all eight curves on top of each other cannot be told apart); the right panel gives, for every $\alpha_h$ of the grid, the largest departure from the reference over the
# scenario, which is what "a larger departure" would mean: a longer observer-target baseline and more dynamical
# differentiation.

# %%
dep_max = [studies.departure_km(sc, t, r.res) for r in ok]
FIG7_SHOW = (0.0, 5e-4, 5e-3, 7e-3, 1e-2)  # weights drawn (those on the grid; 5e-3 and 7e-3: the paper's pair)
_ = plotting.save_figure(figures.relative_three_planes(case, dep_max, FIG7_SHOW), "06_fig7_relative_motion",
                         output_dir=out)
rho_dep = spearmanr([r.alpha for r in ok], dep_max).statistic
print("largest departure from the reference [km]:", ", ".join(f"{r.alpha:g}: {d_:.0f}" for r, d_ in zip(ok, dep_max)))
drops = [(ok[n_].alpha, ok[n_ + 1].alpha) for n_ in range(len(ok) - 1) if dep_max[n_ + 1] < dep_max[n_]]
print(f"Spearman rank correlation of alpha_h and the largest departure: {rho_dep:.2f}; departure drops between "
      f"consecutive weights: " + (", ".join(f"{a_:g} -> {b_:g}" for a_, b_ in drops) or "none"))
rho_grids, mesh_rows = {n_nodes: float(rho_dep)}, []  # robustness on other node grids; mesh check at a6
for n_alt, alt in runs.alt.items():
    gd = studies.grid_departures(sc, *alt, a6)
    rho_grids[n_alt] = gd.spearman
    mesh_rows += [(n_alt, *gd.at_weight)] if gd.at_weight else []
    print(f"{n_alt} nodes: {len(gd.alphas)}/{len(alphas)} weights converged; largest departure [km] "
          + ", ".join(f"{a:g}: {d_:.0f}" for a, d_ in zip(gd.alphas, gd.departure_km)) + f"; Spearman {gd.spearman:.2f}")
dep = closing.Departures(dep_max, float(rho_dep), rho_grids, mesh_rows)
dep_pass = dep.dep_pass
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
# in larger out-of-plane excursions and more impulse (table of section 4). In the full run the $2\times10^{-2}$
# plan (the one adopted from the mesh study, section 4) departs about 30,200 km from the reference, more than three
# times any other weight, and is the only plan with $\alpha_h > 0$ whose keep-out is inactive (open marker; closest
# approach 1050 km): the right panel shows it, the three left panels leave it out (their curves, up to Fig. 6's
# $10^{-2}$, would shrink to a third of the frame beside it).

# %% [markdown]
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
ms = studies.mirror_study(case, [pick(a) for a in (5e-3, 7e-3)], pick(MIRROR_ALPHA),
                          runs.seeded)
print(ms.summary())
_ = plotting.save_figure(figures.z_mirror(sc, t, ms.curves(), (ws_d, we_d)), "06_z_mirror", output_dir=out)

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
plans8 = [(r.alpha, r.res) for r in map(pick, (5e-3, 2e-2))]
_ = plotting.save_figure(figures.thrust_profiles(sc, t, plans8, (ws_d, we_d)), "06_fig8_thrust_profiles",
                         output_dir=out)

# %% [markdown]
# ## 9 · Figure 9: CRLB over the window, and the process-noise units
#
# The EKF covariance recursion along the true trajectories (the paper's "Performance Evaluation"), with the process
# noise recomputed along each trajectory: position RMS $\sqrt{\mathrm{tr}P_{rr}}$ of the observer and each target
# over the window, for $\alpha_h = 5\times10^{-3}$ and $2\times10^{-2}$, and the minimum-$\Delta V$ case
# $\alpha_h = 0$ in grey (weakly observable: range and range rate from a coplanar observer leave directions
# unobserved).

# %%
fig9_alphas = [float(pick(a).alpha) for a in (0.0, 5e-3, 2e-2)]
_ = plotting.save_figure(figures.crlb_objects(em, {a: by_alpha[a].crlb for a in fig9_alphas}), "06_fig9_crlb",
                         output_dir=out)
obs_mean = {a: float(np.mean(by_alpha[a].crlb.rms_km[0])) for a in fig9_alphas[1:]}
tgt_mean = {a: float(np.mean(by_alpha[a].crlb.rms_km[1:])) for a in fig9_alphas[1:]}
print("mean RMS over the window, observer vs targets [km]:",
      {a: (round(obs_mean[a], 1), round(tgt_mean[a], 1)) for a in obs_mean})
common = {a: studies.relative_rms_km(sc, by_alpha[a].res.x[k_ws]) for a in fig9_alphas}
for a, (ab, rl, cm) in common.items():
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
nr = studies.noise_readings(sc, x_ws_ball, row6.res.x[k_ws], wj.test_case_1())
_ = plotting.save_figure(figures.noise_readings(em, nr), "06_process_noise_readings", output_dir=out)
print(f"{'reading':<48}{'q [km^2/s^3]':>13}{'TC1 end':>10}{'TC1 peak':>10}{'TC2 a=0 end':>12}"
      f"{'TC2 a=' + format(a6, 'g') + ' end':>15}")
for label, q_km, e1, p1, e2b, e2i in nr.rows:
    print(f"{label:<48}{q_km:>13.2e}{e1:>10.0f}{p1:>10.0f}{e2b:>12.0f}{e2i:>15.1f}")
q_spread = nr.spread
print(f"spread of the terminal RMS over the {sum(r_[1] < 1e-12 for r_ in nr.rows)} small readings: test case 1 "
      f"{q_spread[0]:.1f}x, test case 2 (alpha_h = {a6:g}) {q_spread[1]:.1f}x")

# %% [markdown]
# ## 10 · Figure 10: the Pareto fronts
#
# Total impulse (trapezoid of Eq. 42; the paper's "average impulse" is not defined further, any constant divisor
# leaves the front's shape unchanged) against the terminal position RMS at the window end, observer (left) and
# targets (right). The front drawn is the **lower envelope over every distinct optimum of the multi-start**
# (section 4; `global_search.lower_envelope`: the plans no other plan beats on both impulse and RMS, monotone by
# construction); grey crosses are the other local optima, dots the best-cost plan per weight, which need not lie
# on it (the cost weighs MI, not the RMS). The "front monotone" row of the closing table still judges the
# best-cost plans per weight, as the paper's one curve per weight would. The MI itself is plotted against the same RMS to test the paper's claim that "the mutual
# information correlates well with the expected performance of a sequential estimator".

# %%
fr = studies.front(ok)
dvs, rms_obs, mis, dominated = fr.dv, fr.rms_obs, fr.mi, fr.dominated
fp = global_search.front_points(multi, sc, k_ws, others={r.alpha: r.res for r in ok})  # every distinct optimum
env = fp.envelope()
_ = plotting.save_figure(figures.pareto_fronts(fr, front=fp), "06_fig10_pareto", output_dir=out)
print(fp.summary())
print(f"Spearman rank correlation MI vs terminal RMS: observer {fr.rank_obs:.3f}, targets {fr.rank_tgt:.3f}; "
      f"impulse non-decreasing in alpha: {fr.mono_dv}; MI non-decreasing: {fr.mono_mi}")
print("plans worse on both axes than a cheaper plan (observer): " + (", ".join(
    f"alpha {a:g} ({dvs[i_]:.2f} m/s, {rms_obs[i_]:.1f} km) vs alpha {b:g} ({dvs[j_]:.2f} m/s, {rms_obs[j_]:.1f} km)"
    for a, i_, b, j_ in dominated) or "none"))

# %% [markdown]
# ## 10b · Figures 9 and 10 under every reading of the process noise
#
# Section 9 showed that the reading of Tables 3 and 5's "$Q$ [km/s³] = $10^{-11}$" sets the level of every absolute
# RMS. Two statements of Figs. 9 and 10 are qualitative and could survive any reading: "$\alpha_h = 0$ is weakly
# observable" (its terminal observer RMS at least five times that of every $\alpha_h > 0$) and "the mutual
# information correlates well with the expected performance of a sequential estimator" (Spearman rank correlation of
# MI against the terminal RMS at most $-0.8$); both criteria are those of section 12, fixed before the readings were
# compared. The plans are the ones above, solved once under the adopted reading: the notebook does not re-plan per
# reading, because the question is whether *these* rows depend on an unstated unit, and a re-plan would ask another
# one (what the method plans under another reading) at four times the cost of the sweep. For each reading
# `readings_study.case2_readings` recomputes along every plan the CRLB and the MI with that reading's $Q$ (the paper
# evaluates both with one $Q$); the MI the planner maximised is printed beside it.

# %%
rd2 = readings_study.case2_readings(case)
print(rd2.summary())
_ = plotting.save_figure(figures.figure_readings(rd2, em), "06_fig9_10_readings", output_dir=out)

# %% [markdown]
# **Reading the panels.** Top row: the observer's CRLB over the window for every plan (grey: $\alpha_h = 0$) under
# each reading, with the ratio of the $\alpha_h = 0$ terminal RMS to the worst information plan's in the title.
# Bottom row: MI under that reading against the terminal observer RMS, one point per plan, with the Spearman
# coefficient. In the full run the three small readings move the RMS of the information plans by the spread printed
# last, but keep both statements (the quick run's three plans are too few for a rank correlation to reach $-0.8$
# under any reading); under the literal $10^{-11}$ km²/s³ the process noise swamps what the window's measurements
# teach: every plan, $\alpha_h = 0$ included, ends with 3,000-9,200 km (full run), and more MI no longer means a smaller
# RMS. A statement that holds under every reading is "reproduced"; one that holds only under some rests on the
# reading we chose while looking at the paper's figures and is "consistent (tuned)", its note naming the readings it
# fails under (the rule of `claims.process_noise_readings`).

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
# Without any keep-out the run at the Fig. 6 weight is on a knife edge (on the last full run it converged in 73 of
# its 75 iterations, its references passing 13 km from a target on the way, numbers not printed here because the
# notebook prints a converged run's plan only; earlier runs ended with defects still open), and at 2e-2 it fails
# (the diagnosis below); when the run fails, the closest approach to a target of its successive references
# (recorded along the run, printed below) shows whether they head for the close-approach singularity. Which local
# optimum a solve finds is fragile: the planar guess is a saddle
# (section 2) and round-off picks the way out of it, so a change as small as another evaluation order of the MI
# gradient can move a run of this section, or of the sweep, to a neighbouring optimum. In the figure each radius is
# a separate solve, so its points are not joined (neighbouring radii can land in different local optima); the dashed
# lines give the sweep's optima at the neighbouring weights of the $\alpha_h$ grid as a yardstick for the size of the
# differences.
#
# **a_max readings.** One run at the Fig. 6 weight under each reading of Table 5's "1x5^-7" (warm-started from
# the adopted solution).

# %%
base, cheap = by_alpha.get(0.0), next((r for r in ok if r.alpha > 0), None)
best = min(ok, key=lambda r: r.crlb.terminal_rms_km[0])
rms0 = base.crlb.terminal_rms_km[0] if base else np.nan
if base and cheap:
    print(f"baseline alpha 0: dV {base.dv:.2f} m/s, observer RMS {rms0:.0f} km; alpha {cheap.alpha:g}: dV "
          f"{cheap.dv:.2f} m/s (+{cheap.dv - base.dv:.2f}), RMS {cheap.crlb.terminal_rms_km[0]:.0f} km "
          f"({rms0 / cheap.crlb.terminal_rms_km[0]:.0f}x better); best alpha {best.alpha:g}: dV {best.dv:.2f} m/s, "
          f"RMS {best.crlb.terminal_rms_km[0]:.1f} km")
with open_executor(workers, SCHEDULER) as executor:  # other radii and a_max readings queued; the rest runs here
    jobs = studies.queue_keep_out_runs(case, row6, d_min_km, warm=radius_warm, x_guess=x_ball, u_guess=u_ball,
                                       executor=executor)
    budget_row, budget_msg = studies.case2_budget(case, BUDGET_EXTRA_MPS, rtol=BUDGET_RTOL)
    free = studies.free_run(sc, t, k_ws, info, a6, x_ball, u_ball, free_iter)  # no keep-out, references recorded
    ko = jobs.collect(free)
print(budget_msg)
print(ko.summary(row6, d_min_km, sc.keep_out_km, SAME_PLAN_KM))
radius_rows, amax_rows = ko.radius_rows, ko.amax_rows
i6 = next(n_ for n_, r in enumerate(ok) if r.alpha == a6)
neighbours = [ok[n_] for n_ in (i6 - 1, i6 + 1) if 0 <= n_ < len(ok)]  # the sweep's optima at the adjacent weights
_ = plotting.save_figure(figures.keep_out_sweep(radius_rows, neighbours, sc.keep_out_km, a6), "06_keep_out_sweep",
                         output_dir=out)
dominated_note = studies.dominated_note(case, dominated, row6, radius_rows, amax_rows)
print("front:", dominated_note)

# %% [markdown]
# ### Without a keep-out: what the convex subproblem hits, and two remedies that are not a keep-out
#
# The run without a keep-out above is one run at one weight; whether it converges depends on the path its iterates
# take (on a full run today the Fig. 6 weight converged in 73 of its 75 iterations, passing 13 km from a target on
# the way). At $\alpha_h = 2\times10^{-2}$ it does not: the iterates head for a target and a convex subproblem
# fails. `keep_out_diagnosis.free_run_diagnosis` repeats such a run (the solver of section 4 without the keep-out)
# and records every reference: its closest approach to a target, the position part of the MI gradient there, the
# largest curvature of the MI (Hessian eigenvalue, at the last references), and the ratio of the information term's
# largest coefficient in the convex subproblem, $\alpha_h\max(|g|,\|\nabla^2\mathcal I\|)$, to the largest impulse
# weight $(1-\alpha_h)\Delta t/2$. No constraint of a subproblem can be infeasible: the reference itself, with the
# virtual control equal to its defects, satisfies the linearised dynamics, the thrust bounds and the trust region.
# So a failure is the solver's, and the question is what it could not resolve.

# %%
diag = kod.free_run_diagnosis(sc, t, k_ws, info, diag_alpha, x_ball, u_ball, max_iter)
print(f"alpha_h = {diag_alpha:g}, {t.size} nodes, at most {max_iter} iterations")
print(diag.summary())
g_ball = float(np.linalg.norm(info(x_ws_ball, 1)[1][:3]))
print(f"MI gradient (position) on the ballistic guess: {g_ball:.3g} nats/LU; at the last reference "
      f"{diag.grad_position[-1]:.3g} ({diag.grad_position[-1] / g_ball:.0f}x)")

# %% [markdown]
# **What grows as the observer nears a target.** We pass the target nearest the ballistic arc at chosen distances
# (Newton on the STM, `keep_out_diagnosis.pass_scan`) and read the whitened Jacobian of that target's range and
# range-rate at the pass, and the MI gradient. The range row is flat; the range-rate row grows like $1/\rho$ (its
# position part is $(\Delta\dot{\mathbf r}-\dot\rho\hat\rho)^T/\rho$), and so does the MI gradient: the log-log
# slopes below 10 km are printed (whether the first causes the second is tested below, with a remedy that
# regularises that row alone: it does not). The whitened Jacobian is *not* ill-conditioned there (its two rows are orthogonal,
# and the range row, whitened by its 0.1 km noise, stays the larger of the two down to 0.1 km): its condition number
# falls. What the convex solver meets is the size of the information term: a gradient of 1e5-1e6 nats/LU and a
# curvature of 1e12 nats/LU$^2$ against impulse weights of order 0.1, eleven orders of magnitude apart.
#
# **A remedy that is not a keep-out.** The MI model trusts range-rate measurements at any range, but the line of
# sight that carries their information is uncertain by about $\sigma_{rel}/\rho$ (prior relative-position
# uncertainty $\sigma_{rel} = \sqrt2\cdot100$ km = 141 km). A noise that grows as the range shrinks,
# $\sigma(\rho) = \sigma\sqrt{1+(\rho_c/\rho)^2}$ with $\rho_c = \sigma_{rel}$ (fixed before any run), on every
# measurement of a target (`cislunar.sensing.information.range_noise_scale`; the MI and its exact gradient,
# product rule through the noise, in `keep_out_diagnosis.RangeNoiseInformation`), leaves the MI unchanged far from
# the targets and makes a target's information vanish like $\rho/\rho_c$ instead of diverging.
#
# **A narrower remedy, which tests the diagnosis.** If the range-rate row's $1/\rho$ is what fails, regularising
# that one term should be enough: `keep_out_diagnosis.RegularisedJacobianInformation` keeps the paper's noise and
# every other entry of the Jacobians and replaces only the $1/\rho$ of the range-rate row's position part by
# $1/\sqrt{\rho^2+\rho_c^2}$ (`cislunar.sensing.information.regularised_range_rate_jacobian`, same $\rho_c$, exact
# gradient). The same passes with both remedies:

# %%
d_scan = np.array(d_scan_km, dtype=float)
remedy_info = kod.RangeNoiseInformation(info, REMEDY_RANGE_KM)
scan_plain = kod.pass_scan(sc, info, x_ws_ball, d_scan)
scan_remedy = kod.pass_scan(sc, remedy_info, x_ws_ball, d_scan)
reg_info = kod.RegularisedJacobianInformation(info, REMEDY_RANGE_KM)
scan_reg = kod.pass_scan(sc, reg_info, x_ws_ball, d_scan)
for name, s_ in (("paper's model", scan_plain), (f"range noise, rho_c = {REMEDY_RANGE_KM:g} km", scan_remedy),
                 (f"regularised range-rate Jacobian, rho_c = {REMEDY_RANGE_KM:g} km", scan_reg)):
    print(f"{name}: |dI/dr| [nats/LU] " + ", ".join(f"{d_:g} km: {g_:.3g}" for d_, g_ in zip(d_scan, s_.grad_position))
          + f"; log-log slope below 10 km {s_.slope('grad_position'):+.2f}; MI at {d_scan[0]:g} km "
          f"{s_.mi[0] - s_.mi[-1]:+.3f} nats against the {d_scan[-1]:g} km pass")
reg_reward = studies.keep_out_scan(sc, reg_info, x_ws_ball, scan_points, d_range_km=SCAN_RANGE_KM)  # section 3's reward scan, regularised
print("reward of a close pass (section 3's scan), paper's model -> regularised range-rate Jacobian: " + ", ".join(
    f"{d_:g} km {scan.gain_at(d_):+.2f} -> {reg_reward.gain_at(d_):+.2f} nats" for d_ in (1.0, 1e-3, 1e-6)
    if SCAN_RANGE_KM[0] <= d_ <= SCAN_RANGE_KM[1]))
print(f"whitened range-rate row slope {scan_plain.slope('range_rate_row'):+.2f}, range row slope "
      f"{scan_plain.slope('range_row'):+.2f}, condition number " + ", ".join(
          f"{d_:g} km: {c_:.3g}" for d_, c_ in zip(d_scan, scan_plain.jacobian_cond)))
_ = plotting.save_figure(figures.figure_keep_out_diagnosis(diag, scan_plain, scan_remedy, REMEDY_RANGE_KM,
                                                          regularised=scan_reg), "06_keep_out_diagnosis",
                         output_dir=out)

# %% [markdown]
# **Test case 2 with the remedies and no keep-out.** Each weight is solved from the ballistic guess with the
# solver of section 4, the MI replaced by each remedy's MI and no keep-out (`keep_out_diagnosis.remedy_runs`). For
# each plan the table gives its impulse, its MI under the paper's model and under its remedy's, its closest
# approach, the observer's terminal CRLB RMS and the paper's cost $(1-\alpha_h)\,\mathrm{impulse}-\alpha_h\mathcal I$
# with the paper's MI, the yardstick by which it is compared with the keep-out plan of section 4 at the same weight
# (printed beside it).

# %%
remedy = kod.remedy_runs(sc, t, k_ws, info, REMEDY_RANGE_KM, remedy_alphas, x_ball, u_ball, max_iter=max_iter,
                         keep_out=False, remedies=("range noise", "regularised J"))
print(kod.remedy_table(remedy))
for r_ in remedy:
    row_ = by_alpha.get(r_.alpha)
    if row_ is not None and r_.converged:
        cost_ko = (1 - r_.alpha) * row_.dv / mps - r_.alpha * row_.mi
        print(f"alpha_h {r_.alpha:g}: keep-out plan {row_.dv:.2f} m/s, MI {row_.mi:.3f}, closest "
              f"{row_.min_range_km:.1f} km, RMS {row_.crlb.terminal_rms_km[0]:.2f} km, paper cost {cost_ko:.6f}; "
              f"{r_.model} plan paper cost {r_.cost:.6f} ({'lower' if r_.cost < cost_ko else 'higher'})")
print(f"notebook compute time {time.perf_counter() - t_start:.0f} s")

# %% [markdown]
# **Reading.** Without a keep-out the failing run's last reference passes a target at a fraction of a kilometre,
# where the MI gradient is a thousand times its ballistic value and the curvature 1e12 nats/LU$^2$: the convex
# solver fails numerically (Clarabel reports a failure, not infeasibility) on an objective whose information
# term is eleven orders of magnitude larger than its impulse term. The range-dependent noise removes the
# divergence where it starts (the gradient no longer grows below $\rho_c$), and with it test case 2 converges
# without any keep-out at the weights printed above. Its plans are other local optima than the keep-out ones:
# compare impulse, MI, closest approach and RMS row by row; the paper's cost says which of the two is the better
# plan under the paper's own objective.
#
# The narrower remedy tests which ingredient matters. Regularising the range-rate row's $1/\rho$ alone removes the
# *reward's* divergence (a pass at a millimetre (1e-6 km) gains 10 nats under the paper's model and nothing with the
# regularised row, printed above) but not the *gradient's*: $|\partial\mathcal I/\partial\mathbf r|$ still grows
# like $1/\rho$ (log-log slope -1.00 below 10 km), because the line of sight, the direction both rows share,
# turns at a rate $\propto 1/\rho$ as the observer nears a target. In the full run SCvx with it converges at
# $5\times10^{-3}$ (its plan passes 15 km from a target at a measurement) and $10^{-2}$, and does not converge at
# $2\times10^{-2}$ within the iteration limit (closing row "differs"). That failure is an iteration-limit stop (largest
# defect 2e-7 when it stopped), not a failed subproblem at a close pass, so this run alone does not show where its
# iterates went. What the scans do show: bounding the range-rate Jacobian's size does not bound the
# gradient, which the linear-Gaussian model of a target's measurements, trusted at any range, feeds through the line
# of sight; only a model that discounts the whole target near the observer, the range-dependent noise, bounds the
# gradient, and with it SCvx converges at every weight tried. Under the paper's own cost every remedy plan of the
# full run is worse than the keep-out plan at the same weight (printed above: "higher").

# %% [markdown]
# ## 12 · Paper versus reproduction
#
# Tolerances fixed before comparing: the window ends to the paper's "roughly" (±1 day); "out-of-plane motion" means
# more than 100 km out of plane; "weakly observable at $\alpha_h = 0$" means a terminal observer RMS at least five
# times that of every $\alpha_h > 0$; "correlates well" means a Spearman rank correlation of MI against terminal RMS
# below -0.8; the observer "on average" better than the targets means a window-mean RMS at least 10 % lower than
# the targets' mean; the front is monotone if no plan has both more impulse and a higher RMS than another. Rows
# resting on a reading chosen with the paper's claim in view (process noise, the Table 2/4 slip, and Figs. 9-10's
# "weakly observable" and "correlates well", which fail under the literal 1e-11 km²/s³) are at best
# "consistent (tuned)"; imposed inputs (zero thrust in the window) and what optimality implies (impulse and MI
# growing with $\alpha_h$, true of any set of global optima of a weighted sum) are "derived", not predictions.
#
# Every row is a claim declared, with its criterion, in `cislunar.papers.wolf_jones.claims.test_case_2` before
# anything is compared. One call gathers the measured values from the results above
# (`cislunar.papers.wolf_jones.case_2_closing.measurements`: value, how it is shown, the row's context); the cells
# below judge them claim by claim, and the status word follows from the one rule of `cislunar.publish.claims`.
#
# ### The inputs: Tables 4 and 5
#
# A printed DRO row is periodic when its closure after one period stays below notebook 01's tolerance; the first
# row (the same slip as Table 2's) fails, the others pass. Table 5's title names test case 1 while its parameters
# are test case 2's; its $a_{max}$ "1x5^-7" is read (a derived row, with the other readings solved beside it); the
# process-noise reading is judged by whether it keeps test case 1's ballistic CRLB bounded after the transient, the
# very property it was chosen by (so "consistent (tuned)" at best); the window ends must lie within a day of the
# text's "roughly 17 and 32 days" (largest miss measured).

# %%
rows = closing.measurements(case, row6, n_nodes=n_nodes, sigma=SIGMA, gc=gc, ms=ms, ko=ko, nr=nr, fr=fr,
                            departures=dep, obs_mean=obs_mean, tgt_mean=tgt_mean, common=common,
                            budget_row=budget_row, extra_mps=BUDGET_EXTRA_MPS, rtol=BUDGET_RTOL,
                            diagnosed={diag_alpha: diag})


def judge(*keys):
    """Judge the measured rows of these claims (a row that does not apply in this run is absent)."""
    for key in (k for k in keys if k in rows):
        m = rows[key]
        table.add(CLAIMS[key].judge(m.value, shown=m.shown, note=m.note, reason=m.reason))


judge("observer_t0_periodic", "other_rows_periodic", "table5_title", "a_max", "process_noise", "window")

# %% [markdown]
# ### The solver rows
#
# The paper's figures imply a solver that converges for every $\alpha_h$ without any keep-out. Our modified
# solver is asked exactly that at every weight this chapter runs without a keep-out: the Fig. 6 weight (the run of
# section 11, its iteration limit fixed in the parameters cell) and the diagnosed weight of section 11 (full run:
# $2\times10^{-2}$): a yes/no, so the row differs when one of them fails, with the smaller keep-outs that failed as
# well listed beside it. (Until a referee's pass this row judged the Fig. 6 weight alone and said "reproduced";
# the diagnosed failure at $2\times10^{-2}$ was in another row.) With the adopted 424 km keep-out the whole grid must converge (a "beyond paper"
# row that would turn to "differs" if one weight had no converged plan), and the re-flight gives the largest
# terminal miss of the single-shooting flights. The last four rows come from the diagnosis of section 11
# (`claims.keep_out_remedy`, criteria fixed before any run): whether the diagnosed run without keep-out fails at a
# close pass (last reference within `CLOSE_PASS_KM` of a target, MI gradient at least `GRADIENT_GROWTH` times the
# ballistic one), whether every weight converges without keep-out under the range-dependent noise and under the
# regularised range-rate Jacobian alone, and the record of the range-noise plans beside the keep-out plans.

# %%
judge("no_keep_out", "keep_out_converges", "reflight")
free_fail = bool(diag.failed and diag.status == "failed" and diag.ref_range_km.size > 0
                 and diag.ref_range_km[-1] < CLOSE_PASS_KM and diag.grad_position[-1] >= GRADIENT_GROWTH * g_ball)
table.add(REMEDY_CLAIMS["free_failure"].judge(
    free_fail, shown=(f"alpha_h {diag_alpha:g}: {kod.brief_outcome(diag.outcome)}; last reference {diag.ref_range_km[-1]:.2g} km "
                      f"from a target, MI gradient {diag.grad_position[-1] / g_ball:.0f}x the ballistic one, "
                      f"curvature {diag.hessian_norm[-1]:.1e}"),
    note=(f"information/impulse coefficient ratio {diag.information_scale[-1]:.0e}; MI gradient slope "
          f"{scan_plain.slope('grad_position'):+.2f} below 10 km (range-rate row "
          f"{scan_plain.slope('range_rate_row'):+.2f})")))
remedy_noise = [r_ for r_ in remedy if r_.model == "range noise"]
remedy_reg = [r_ for r_ in remedy if r_.model == "regularised J"]
table.add(REMEDY_CLAIMS["remedy_converges"].judge(
    all(r_.converged for r_ in remedy_noise),
    shown="; ".join(f"alpha_h {r_.alpha:g}: " + (f"{r_.outcome}, closest {r_.closest_km:.0f} km" if r_.converged
                                                 else f"fails ({kod.brief_outcome(r_.outcome)})") for r_ in remedy_noise),
    note=f"rho_c = {REMEDY_RANGE_KM:g} km fixed before any run; gradient slope below 10 km "
         f"{scan_remedy.slope('grad_position'):+.2f} (paper's noise {scan_plain.slope('grad_position'):+.2f})"))
table.add(REMEDY_CLAIMS["jacobian_remedy_converges"].judge(
    all(r_.converged for r_ in remedy_reg),
    shown="; ".join(f"alpha_h {r_.alpha:g}: " + (f"{r_.outcome}, closest {r_.closest_km:.2g} km" if r_.converged
                                                 else f"fails ({kod.brief_outcome(r_.outcome)})") for r_ in remedy_reg),
    note=f"same rho_c; MI gradient slope below 10 km {scan_reg.slope('grad_position'):+.2f} (paper's model "
         f"{scan_plain.slope('grad_position'):+.2f}); MI gain of a {d_scan[0]:g} km pass "
         f"{scan_reg.mi[0] - scan_reg.mi[-1]:+.3f} nats (paper's model {scan_plain.mi[0] - scan_plain.mi[-1]:+.3f})"))
table.add(REMEDY_CLAIMS["remedy_plans"].judge(
    "; ".join(f"alpha_h {r_.alpha:g}: {r_.dv_mps:.1f} m/s, MI {r_.mi:.2f}, RMS {r_.rms_km:.1f} km"
              for r_ in remedy_noise if r_.converged) or "no converged plan",
    note="; ".join(f"keep-out plan at {a_:g}: {by_alpha[a_].dv:.1f} m/s, MI {by_alpha[a_].mi:.2f}, RMS "
                   f"{by_alpha[a_].crlb.terminal_rms_km[0]:.1f} km" for a_ in remedy_alphas if a_ in by_alpha)))

# %% [markdown]
# ### Figures 6 to 8
#
# Out-of-plane motion is the largest $|z|$ of the Fig. 6 plan, at least 100 km. "Departure grows with $\alpha_h$"
# must hold on every node grid of the robustness check (Spearman rank correlation of weight and largest departure
# above 0.8 on each), since one grid's choice of local optima can make or break it. The mirror rows separate the
# paper's observation (its two optima are near-mirror images: one must be closer to the other's mirror than to the
# other) from the symmetry itself (a mirrored optimum is re-accepted with the same cost, within 1e-6 relative and
# 1 km; and, in full mode, the $\pm z$ seeds give mirror images within the same bounds). Zero thrust in the window is
# an imposed input, checked to round-off; out-of-plane thrust must appear in every plan with $\alpha_h > 0$.

# %%
judge("out_of_plane", "departure", "mirror_pair", "mirror_optimum", "seeds", "window_thrust", "a_z_used")

# %% [markdown]
# ### Figures 9 and 10
#
# "Weakly observable" at $\alpha_h = 0$: a terminal observer RMS at least five times that of every other weight,
# judged under each of the four readings of $Q$ (section 10b), like "correlates well" below: "reproduced" only if
# it holds under every reading, "consistent (tuned)" with the readings it fails under named if only under some.
# The observer is better known "on average" when its window-mean RMS lies at least 10 % below the targets' mean, for
# both weights of Fig. 9 (the smaller of the two relative gaps is measured). The MI "correlates well" with the CRLB
# when the larger of the two Spearman correlations (observer, targets) over the grid is at most $-0.8$; the front
# grows when impulse and MI never decrease with $\alpha_h$, and it is monotone when no plan spends more impulse and
# ends with a higher observer RMS than another.

# %%
judge("observer_below_targets", "front_grows", "front_monotone")
for key, m in rd2.measurements().items():  # "weakly observable" and "correlates well" under each reading (10b)
    table.add(READING_CLAIMS[key].judge(m.value, shown=m.shown, note=m.note, reason=m.reason))

# %% [markdown]
# ### Beyond the paper
#
# The values of the front (which the paper only plots), the node-grid check, the plan solved at a prescribed
# impulse (the fair form of "substantial improvement over a baseline"), the keep-out radius sweep and the check
# of the MI gradient against central differences (at most $10^{-5}$ relative, else "differs") have nothing in the
# paper to compare with; their numbers are the record a later reproduction would compare with.

# %%
judge("values", "mesh", "budget", "cheap", "keep_out_radius", "gradient")
table.add(CLAIMS["distinct_optima"].judge(max(multi.n_distinct), shown="optima found per alpha_h: " + ", ".join(
    f"{a:g}: {n_}" for a, n_ in zip(multi.alphas, multi.n_distinct)), note=f"{len(multi.outcomes)} starts; cost "
    "range per alpha_h: " + ", ".join(f"{a:g}: {hi - lo:.1e}" for a, (lo, hi) in zip(multi.alphas, multi.cost_range))
    + "; same optimum: cost within 1e-6 (1 + |J|), plans (or z-mirrors) within 100 km"))
table.add(CLAIMS["multi_start"].judge(len(ms_better), shown=(
    f"better than the sweeps at {len(ms_better)} of {len(multi.alphas)} weights"
    + ("" if not ms_better else ": " + "; ".join(
        f"{a:g}: {sweep_best[a].impulse * mps:.2f} -> {by_alpha[a].dv:.2f} m/s, cost {c0:.5f} -> {c1:.5f}"
        for a, c0, c1, _ in ms_better))), note="the figures and rows above use the best plan per weight"))
off_env = [a for i_, a in enumerate(fp.alpha) if fp.optimum[i_] == 0 and i_ not in set(env.index.tolist())]
table.add(CLAIMS["envelope"].judge(len(env.index), shown=f"{len(env.index)} of {len(fp.alpha)} distinct optima "
                                   f"on the envelope; {env.x[0]:.2f} -> {env.x[-1]:.1f} m/s, observer RMS "
                                   f"{env.y[0]:.0f} -> {env.y[-1]:.1f} km", note=(
    "best-cost plans off the envelope (dominated by another optimum): " + ("at alpha_h "
        + ", ".join(f"{a:g}" for a in off_env) if off_env else "none"))))
table.add(CLAIMS["mesh_study"].judge(all(mstudy.converged(a) for a in mstudy.alphas), shown="; ".join(
    f"alpha_h {a:g}: " + ", ".join(f"{r.n_nodes} nodes {r.impulse_mps:.1f} m/s / {r.rms_km:.1f} km"
                                   for r in mstudy.table(a) if r.converged) for a in mstudy.alphas),
    note=f"figures use {mstudy.figure_nodes} nodes; largest change between the two finest grids (and the start of "
         "the finest grid's best plan): " + ", ".join(
        f"{a:g}: {100 * mstudy.finest_change(a):.1f} % ({mstudy.table(a)[-1].start})" for a in mstudy.alphas)))
if (back_row := mesh_st.back_measurement()) is not None:  # a finer grid converged (not in the quick run)
    table.add(CLAIMS["mesh_back"].judge(**back_row))
else:
    print("not judged in this run: no mesh grid finer than the figures' converged, so no plan was moved back")
table.display()

# %% [markdown]
# ## Exercises
#
# Each exercise asks you to change one entry of the parameters cell, to predict what will happen before running,
# and then to check. The worked solutions are functions of `cislunar.papers.wolf_jones.exercises`, run at small
# sizes (a few seconds each); each returns the numbers that answer the exercise and an `answer` paragraph.
#
# 1. **How fast does the reward blow up?** Set `SCAN_RANGE_KM = [1e-6, 1e-2]` (passes between a millimetre and
#    ten metres) and `SCAN_POINTS = 7`. Before running, use the range-rate Jacobian of Section 3, which grows like
#    $1/\rho$, to predict how many nats each factor of 10 closer adds to the MI of the window; then read the
#    figure `06_keep_out_motivation`. Worked solution: `exercises.exercise_06_close_pass_scan`.
# 2. **No keep-out, more patience.** Raise `FREE_ITER` (5 in quick mode) to 30. Will SCvx without a keep-out
#    converge if it is given more iterations? Predict its best accepted cost and its largest defect (the
#    "without the keep-out" lines of Section 11 and the row "SCvx converges for every alpha_h without a
#    keep-out"). Worked solution: `exercises.exercise_06_free_run_iterations` (10 and 30 iterations on 12 nodes).
