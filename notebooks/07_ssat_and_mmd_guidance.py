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
# # 07 · Spacecraft-to-spacecraft absolute tracking and MMD guidance
#
# **What you will learn.** How two spacecraft that only see each other through a camera can estimate *both*
# absolute states (spacecraft-to-spacecraft absolute tracking, SSAT); why the range between them is the weak
# direction of an angles-only estimate; how a linear covariance analysis along the true trajectories measures the
# 1-sigma range uncertainty $\sqrt{J_\rho}$; and how the maximum-measurement-deviation (MMD) policy picks an
# information-gathering burn from a 3x3 eigenproblem. Beyond the paper, we compare MMD with the true minimiser of
# $J_\rho$ over all burn directions and with the "burn perpendicular to the line of sight" heuristic over a range of
# coast times, and say how near-optimal MMD is.
#
# **Paper sections followed.** Greaves & Scheeres, "Autonomous information gathering guidance for
# spacecraft-to-spacecraft tracking with optical sensors" (AMOS 2023): Sec. 3.1 (Eqs. 1-7), 3.2 (Eqs. 8-14),
# 3.3 (Eqs. 15-20), 3.4 (Eqs. 21-24, with the two properties it quotes from its Ref. [8]: the perpendicular
# heuristic and MMD's near-optimality), the two remarks of Sec. 4.1 on MMD (the sign chosen by a quick covariance
# analysis, "exponentially faster computation time") and the covariance-analysis set-up of Sec. 5. The
# quasi-periodic orbit and the informed station keeping of Secs. 4-5 are notebook 08.

# %% tags=["parameters"]
QUICK = False  # quick mode: coarser sphere of burn directions, fewer coast times, arcs and ring angles (sizes below)
SEED = 0  # seed of the random states of the coordinate checks (section 1)
OUTPUT_DIR = ""  # folder for the figures (empty: build-scratch/ by hand, the build under the runner)
N_GRID = None  # burn directions on the Fibonacci sphere (None: 600 quick, 3000 full)
N_PERP = None  # burn directions on the circle perpendicular to the line of sight (None: 36 quick, 120 full)
COAST_HOURS = None  # coast times tau_f - tau_0 swept, whole hours in 1-72 (None: 1, 4, 24, 48 quick; 9 in full)
DV_M_S = None  # burn magnitudes upsilon, m/s, the last one is "the larger burn" (None: [0.1, 1.0])
MAP_COAST_H = None  # coast of the surrogate check, the direction map and the timing, whole hours (None: 12)
LEAD_DAYS = None  # the burn happens this long before the target's apolune, days (None: 1.0)
APOLUNE_RANGE_KM = None  # agent-target range at the target's apolune, km (None: 215.0, the paper's scale)
PRE_ARC_H = None  # tracking arc before the burn in section 4, whole hours (None: 24)
PRE_ARC_SWEEP_H = None  # tracking arcs swept, whole hours (None: 24 quick; 6, 12, 24, 48 full; PRE_ARC_H added)
RING_ANGLES_DEG = None  # agent's initial ring angles on the QPO, deg, with 0 (None: 0, 90 quick; 0, 45, 90, 135 full)
TIMING_REPEAT = None  # runs of the true minimiser timed, best kept (None: 1)
WORKERS = 1  # local processes for the sweeps (1: serial)
SCHEDULER = ""  # address of a Dask scheduler to run the sweeps on ("" for none; then WORKERS applies)

# %% [markdown]
# **Changing the chapter.** Every size and setting of this chapter is a parameter of the cell above. A parameter
# left at `None` is chosen in the next cell, from `QUICK` for the sizes (quick mode: a 600-direction sphere, four
# coast times, one tracking arc and two ring angles on the torus) and from the paper's scale for the scenario (215 km at apolune, burn 1 day before it); a value you
# give, in Jupyter or with `-p NAME=VALUE` on the command line, is used as given in either mode. The three sweeps
# of sections 3 and 4 (burn sizes, tracking arcs, ring angles on the torus) run one task per case on the executor
# that `WORKERS` local processes or a Dask `SCHEDULER` provide; every task is deterministic, so the numbers do not
# depend on where they run. The exercises at the end of the chapter start from here.

# %%
# Every parameter left at None is picked here from QUICK; a value the reader gave is used as given.
N_GRID = N_GRID if N_GRID is not None else (600 if QUICK else 3000)
N_PERP = N_PERP if N_PERP is not None else (36 if QUICK else 120)
COAST_HOURS = list(COAST_HOURS if COAST_HOURS is not None else
                   ([1, 4, 24, 48] if QUICK else [1, 2, 4, 8, 12, 18, 24, 36, 48]))
DV_M_S = list(DV_M_S if DV_M_S is not None else [0.1, 1.0])  # the paper gives no magnitude for this experiment
MAP_COAST_H = MAP_COAST_H if MAP_COAST_H is not None else 12
LEAD_DAYS = LEAD_DAYS if LEAD_DAYS is not None else 1.0
APOLUNE_RANGE_KM = APOLUNE_RANGE_KM if APOLUNE_RANGE_KM is not None else 215.0
PRE_ARC_H = PRE_ARC_H if PRE_ARC_H is not None else 24
PRE_ARC_SWEEP_H = sorted(set(PRE_ARC_SWEEP_H if PRE_ARC_SWEEP_H is not None else
                             ((24,) if QUICK else (6, 12, 24, 48))) | {PRE_ARC_H})
RING_ANGLES_DEG = tuple(RING_ANGLES_DEG if RING_ANGLES_DEG is not None else
                        ((0.0, 90.0) if QUICK else (0.0, 45.0, 90.0, 135.0)))
TIMING_REPEAT = TIMING_REPEAT if TIMING_REPEAT is not None else 1
WORKERS = WORKERS if WORKERS is not None else 1

import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.torus import qpo_for_mean_range
from cislunar.guidance import ssat
from cislunar.papers.greaves_scheeres_2023 import figures
from cislunar.papers.greaves_scheeres_2023 import guidance_study as gs
from cislunar.papers.greaves_scheeres_2023.claims.ssat_guidance import CLAIMS, NEAR_OPTIMAL_PERCENT, SHORT_COAST_HOURS
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.utils.executors import open_executor

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
table = ComparisonTable("07 SSAT and MMD guidance (Greaves & Scheeres AMOS 2023, Eqs. 1-24)")

# %% [markdown]
# ## 1 · The SSAT state (Eqs. 1-7)
#
# The *inertial* SSAT state stacks the agent and target CR3BP states, $\mathbf x = [\mathbf s_a; \mathbf s_t]$
# (Eq. 1; "inertial" is the paper's name, both states live in the rotating frame). The *relative* SSAT state holds
# their mean and difference, $\tilde{\mathbf x} = [\mathbf s_\alpha; \mathbf s_\rho] = T\mathbf x$ with
# $\mathbf s_\alpha = (\mathbf s_a+\mathbf s_t)/2$, $\mathbf s_\rho = \mathbf s_t - \mathbf s_a$ and
# $T = \begin{bmatrix}\tfrac12 I & \tfrac12 I\\ -I & I\end{bmatrix}$ (Eqs. 3-6); covariances map as
# $\tilde P = TPT^T$ (Eq. 7). The paper also mentions an *agent-based* absolute state
# $\bar{\mathbf x} = [\mathbf s_a; \mathbf s_\rho] = T_a\mathbf x$. We check the identities on random states and
# covariances, and the reason the relative form is useful: the angle measurements of Eqs. 15-18 depend on
# $\mathbf s_\rho$ only, so in both relative coordinate systems the measurement Jacobian is $[0\ \ H_\rho]$, and
# both give the same range variance.

# %%
cc = gs.coordinate_checks(rng)
print(f"round trip T^-1 T x: {cc.state_round_trip:.1e};  T^-1 (T P T^T) T^-T vs P (relative): "
      f"{cc.covariance_round_trip:.1e}")
print(f"relative block of T P T^T vs T_a P T_a^T: {cc.relative_block:.1e};  J_rho in the three coordinates: "
      f"{cc.range_variance_spread:.1e} relative spread")
print("T B_a (control in relative coordinates) =\n", ssat.control_matrix("relative")[:, 0].reshape(4, 3)[:, 0])

# %% [markdown]
# The last line is the first column of $TB_a$, block by block: an impulse $\mathbf u$ on the agent moves the mean
# velocity by $\mathbf u/2$ and the relative velocity by $-\mathbf u$ (Eqs. 13-14 in relative coordinates).
#
# ## 2 · The demonstration scenario and a covariance analysis without maneuvers
#
# The paper does not give the two orbits used for its MMD guidance (that is its Ref. [8]); we need a close,
# naturally bounded pair about the Gateway orbit. **Choice:** the target flies the 9:2 southern L2 NRHO, the agent
# flies the *same* orbit about half an hour behind (the phase lag is printed below), chosen so that their range at
# the target's apolune is 215 km (the paper's Sec. 4 gives 215 km as the *average* range of its QPO pair; here it
# only sets the scale). The burn happens `LEAD_DAYS` = 1 day
# before apolune, so coasts longer than 24 h straddle apolune (the 48-h coast ends 24 h after it); shorter coasts
# end before it. Measurements (Sec. 3.3, 5): azimuth and elevation
# of the target seen from the agent every hour, with the RMS angular noise of Eq. 20,
# $\sigma_\theta = \sqrt{\sigma_{\theta,min}^2 + D^2/\rho^2}$, $\sigma_{\theta,min}$ = 10 micro-rad, $D$ = 4 m;
# initial 3-sigma of 60 km and 60 cm/s per axis for both vehicles, uncorrelated; no process noise (the paper lists
# none); the covariance is propagated along the true trajectories.
#
# **The covariance analysis and the cost (Eqs. 19-22).** Eq. 19, $\rho^2\sigma_\theta^2 = \rho^2\sigma_{\theta,min}^2 +
# D^2$, adds in quadrature a pointing floor and the angle a 4 m resolution element subtends at range $\rho$; Eq. 20
# solves it for $\sigma_\theta$, the same for both angles ($R_j = \sigma_\theta^2 I_2$). With no process noise, the
# posterior covariance after the measurements up to $t_k$ is
# $P_k = \Phi_k\big(P_0^{-1} + \sum_{j\le k}\Phi_j^TH_j^TR_j^{-1}H_j\Phi_j\big)^{-1}\Phi_k^T$, with the block-diagonal
# STM $\Phi_j = \Phi(t_j, t_0)$ of both vehicles and $H_j = [-H_\theta\ \ H_\theta]$ (Eq. 18 with respect to the inertial
# SSAT state); `ssat.ssat_covariance` evaluates it in square-root information form for a whole batch of agent
# trajectories at once, and `ssat.ssat_covariance_ekf` by the textbook Joseph-form EKF recursion, as a check. The
# cost is the range variance $J_\rho = M_\rho^T\tilde P_fM_\rho$ (Eq. 21) with $M_\rho = [\mathbf 0_6;
# \hat{\boldsymbol\rho}_{\tau_f}; \mathbf 0_3]$ (Eq. 22) picking the range direction out of the relative partition
# of $\tilde P = TPT^T$; in inertial coordinates the same number is $m^TPm$ with $m = T^TM_\rho =
# [-\hat{\boldsymbol\rho}; \mathbf 0; \hat{\boldsymbol\rho}; \mathbf 0]$. $\sqrt{J_\rho}$ is the 1-sigma range
# uncertainty; at $t_0$ a pair of angles says nothing about range, so it is $\sqrt2\times20$ km.

# %%
nrho = nrho_9_2(em)
pair = gs.demonstration_pair(em, nrho, lead_days=LEAD_DAYS, apolune_range_km=APOLUNE_RANGE_KM)
base = pair.baseline.range_sigma_km[0]
print(f"phase lag {pair.lag_hours * 60:.2f} min; range at the burn {pair.baseline.range_km[0, 0]:.1f} km, "
      f"at apolune {pair.baseline.range_km[0, 24]:.1f} km, after 3 d {pair.baseline.range_km[0, -1]:.1f} km")
print(f"sqrt(J_rho): {base[0]:.2f} km at t0 (= sqrt(2) x 20 km), {base[24]:.2f} km after 24 h, {base[-1]:.2f} km "
      "after 72 h")
print(f"first hour of measurements: sqrt(J_rho) {base[0]:.2f} -> {base[1]:.2f} km (-{pair.first_hour_drop_percent:.0f} "
      f"%); smallest {base.min():.2f} km at {np.argmin(base):d} h")
for coords, diff in pair.ekf_difference.items():
    print(f"EKF recursion in {coords:8s} coordinates vs square-root information form: "
          f"max relative difference of J_rho {diff:.1e}")

# %% [markdown]
# **The equations as printed.** The dynamics (Eqs. 8-12) are the package's CR3BP in non-dimensional units, where
# $G(m_1+m_2) = r_{12} = 1$, so Eq. 12 gives $\boldsymbol\omega_{D/N} = \hat{\mathbf e}_z$ and Eq. 11 reads
# $\mathbf a = -2\boldsymbol\omega\times\mathbf v - \boldsymbol\omega\times(\boldsymbol\omega\times\mathbf r) -
# (1-\mu)\boldsymbol\rho_{b1}/\rho_{b1}^3 - \mu\boldsymbol\rho_{b2}/\rho_{b2}^3$. The measurement (Eqs. 15-17)
# is azimuth $\theta_a = \tan^{-1}(\rho_y/\rho_x)$ (taken in the right quadrant, `arctan2`) and elevation
# $\theta_e = \sin^{-1}(\rho_z/\rho)$ of $\boldsymbol\rho = \mathbf r_t - \mathbf r_a$, with the Jacobian
# $H_\theta$ of Eq. 18 with respect to $\boldsymbol\rho$; with respect to the agent state it is $-H_\theta$. We type
# Eqs. 11 and 18 in from the paper and compare them with the package at the agent's state at the burn epoch (the
# tests do the same on random states).

# %%
eq = gs.equation_checks(em, pair.agent_x0, pair.target_x0)
print(f"Eq. 11 typed in vs package equations of motion: {eq.eq11:.1e} relative;  Eq. 18 typed in vs package "
      f"Jacobian (target block = H_theta, agent block = -H_theta): {eq.eq18:.1e} relative")

# %%
_ = plotting.save_figure(figures.ssat_scenario(em, pair), "07_ssat_scenario", output_dir=out)

# %% [markdown]
# Even without a burn the first hour of measurements cuts $\sqrt{J_\rho}$ by about a fifth (28.3 to 22.7 km,
# printed above): with velocities known to 20 cm/s, a range error needs a proportional relative-velocity error to
# stay invisible in the angles, and the prior limits that. After that the range is only weakly observable: the
# uncertainty falls slowly to its smallest value near apolune, where the range is smallest, and then grows with the
# range itself. Both forms of the covariance analysis (square-root information referred to $t_0$, batched; Joseph-form
# EKF recursion) agree, in all three SSAT coordinate systems.
#
# ## 3 · MMD guidance (Eqs. 23-24)
#
# For a burn $\mathbf u$ at $\tau_0$ the linearised change of the measurement at the end of the coast $\tau_f$ is
# $\delta\mathbf y_f = H_f\Phi(\tau_f,\tau_0)B_a\mathbf u$. MMD maximises $\|\delta\mathbf y_f\|^2 =
# \mathbf u^TQ\mathbf u$, $Q = B_a^T\Phi^TH_f^TH_f\Phi B_a$ (Eq. 24), over $\|\mathbf u\| = \upsilon$: the
# eigenvector of the largest eigenvalue. **Deviation from the print:** Eq. 23 reads
# $\mathbf u_y = \pm\upsilon\max(\mathrm{eig}(Q))$, literally a multiple of the largest *eigenvalue* (a scalar); the
# text ("the solution to an eigen-problem", a maneuver) and the Rayleigh quotient both say it is the unit
# *eigenvector* of that eigenvalue, which we implement. In Eq. 24, $H_f$ must be the Jacobian with respect to the
# 12-dimensional inertial SSAT state, $[-H_\theta\ \ H_\theta]$ at $\tau_f$ (Eq. 18 is written for the relative
# state); with $B_a$ only the agent block $-H_\theta$ survives, and the sign drops out of $Q$. $Q$ has rank 2 (two
# angles), so its null direction is the burn that leaves the final line of sight unchanged. The sign is not determined by the eigenproblem; as in the paper we
# run both and keep the smaller $J_\rho$. Beyond the paper, for each coast time we evaluate $J_\rho$ for every
# direction of a Fibonacci sphere (`N_GRID` directions, one batched covariance analysis each), refine the best one
# with Nelder-Mead (the *true minimiser*), and scan the circle perpendicular to the initial line of sight (the
# heuristic of Ref. [8], reported as the best and the worst direction of the circle, since it is a set, not a
# policy).

# %% [markdown]
# First, the surrogate itself: for the 12-h coast the eigenvector must be the direction on the sphere that maximises
# $\mathbf u^TQ\mathbf u$ and, for a small burn (where the surrogate is the linearisation), the one that maximises
# the *nonlinear* change of the final angles; both found here by brute force over a dense Fibonacci sphere.

# %%
sur = gs.surrogate_check(em, pair, coast_hours=MAP_COAST_H, n_grid=N_GRID)
print(f"eigenvalues of Q: {sur.eigenvalues} (rank 2)")
print(f"angle between the MMD eigenvector and the brute-force maximiser of u^T Q u: {sur.angle_quadratic_deg:.2f} deg, "
      f"of the nonlinear angle change: {sur.angle_nonlinear_deg:.2f} deg (grid spacing {sur.spacing_deg:.1f} deg)")

# %% [markdown]
# The sweep over coast times (`gs.policy_study`, one `ssat.compare_burn_policies` per burn size) prints, for every
# coast $\tau_f-\tau_0$: $\sqrt{J_\rho(\tau_f)}$ in km without a burn ("none"); with the MMD burn of the selected
# sign and of the rejected one ("MMD(-)"); with the true minimiser (sphere plus Nelder-Mead); the median over the
# sphere of directions (what a burn in a random direction achieves); the best and the worst direction of the circle
# perpendicular to the line of sight at the burn; the percentage of sphere directions that beat MMD ("MMD pct",
# 0 % = none does); and the angle between the MMD axis and the true minimiser. All burns are impulses of magnitude
# $\upsilon$ at the first epoch, where $P_0$ applies; every coast is a prefix of the same hourly measurement grid,
# so the sphere and the circle are propagated once for the longest coast.

# %%
with open_executor(WORKERS, SCHEDULER) as executor:
    study = gs.policy_study(em, pair, COAST_HOURS, DV_M_S, n_grid=N_GRID, n_perp=N_PERP, executor=executor)
for dv, r in study.results.items():
    print(f"\nupsilon = {dv} m/s")
    print(" coast h | none   | MMD    | MMD(-) | optimum | median dir | perp best/worst | MMD pct | MMD-opt deg")
    for i, h in enumerate(r.coast_hours):
        print(f" {h:7.0f} | {r.none[i]:6.2f} | {r.mmd[i]:6.2f} | {r.mmd_other[i]:6.2f} | {r.optimum[i]:7.2f} | "
              f"{r.grid_median[i]:10.2f} | {r.perp_best[i]:6.2f}/{r.perp_worst[i]:6.2f}  | {r.mmd_percentile[i]:6.1f}% | "
              f"{r.angle_mmd_optimum_deg[i]:6.1f}")

# %% [markdown]
# The figure draws every policy as the change of $\sqrt{J_\rho(\tau_f)}$ against doing nothing (percent; the dashed
# zero line is "no burn", the absolute values are in the tables above), each burn size on its own scale.

# %%
_ = plotting.save_figure(figures.policies_vs_coast(study), "07_mmd_vs_optimum", output_dir=out)

# %% [markdown]
# ### The cost over the sphere of burn directions
#
# One coast time (12 h) and the larger burn: each dot is a burn direction (rotating-frame azimuth and elevation of
# $\mathbf u$), coloured by $\sqrt{J_\rho}$. The MMD axis ($\pm$), the true minimiser, the line of sight at the burn
# (both senses, as rings) and the great circle perpendicular to it are marked. For this coast the minimiser sits
# next to the line of sight, far from the perpendicular circle (the angle is printed below the map).

# %%
dmap = gs.direction_map(em, pair, study, coast_hours=MAP_COAST_H, n_grid=N_GRID)
print(f"{MAP_COAST_H}-h coast, {dmap.dv_m_s} m/s: the true minimiser is {dmap.los_angle_deg:.1f} deg from the line of sight at the "
      f"burn, {'towards' if dmap.towards_target else 'away from'} the target ({dmap.optimum_perp_angle_deg:.1f} deg "
      "out of the perpendicular plane)")
_ = plotting.save_figure(figures.cost_over_directions(dmap), "07_cost_over_burn_directions", output_dir=out)

# %% [markdown]
# ## 4 · How near-optimal is MMD?
#
# Three numbers per coast time: MMD's excess over the true minimiser (percent of $\sqrt{J_\rho}$), the fraction of
# the achievable improvement over a random direction that MMD captures, and the percentile of MMD among all
# directions of the sphere (0 % would mean no direction is better).

# %%
for dv, r in study.results.items():
    print(f"upsilon = {dv} m/s: MMD excess over optimum {np.round(r.mmd_excess_percent, 1)} %")
    print(f"   fraction of the possible gain captured {np.round(r.mmd_gain_fraction, 2)}")
    print(f"   directions better than MMD {np.round(r.mmd_percentile, 1)} %")
    print(f"   angle between optimum and the perpendicular plane {np.round(r.optimum_perp_angle_deg, 1)} deg")
    print(f"   angle between optimum and the line of sight (either sense) "
          f"{np.round(90 - r.optimum_perp_angle_deg, 1)} deg")
    print(f"   perpendicular-circle best vs optimum: {np.round(100 * (r.perp_best / r.optimum - 1), 1)} %")
    print(f"   sign choice matters: rejected sign worse by {np.round(study.sign_percent(dv), 1)} %")
for dv, r in study.results.items():
    s, a = study.sign_percent(dv), r.angle_mmd_optimum_deg
    print(f"upsilon = {dv} m/s: rejected sign worse by {s.min():.1f}-{s.max():.1f} %; "
          f"MMD axis to true minimiser {a.min():.1f}-{a.max():.1f} deg")

# %% [markdown]
# **Reading.** The sign choice of the quick covariance analysis matters for the larger burn: at 1 m/s the rejected
# sign of the MMD axis is worse by up to a few tens of percent in $\sqrt{J_\rho}$, at 0.1 m/s by a few percent at
# most (ranges printed above). Only for the shortest coast (1 h) does the best burn lie in the plane
# perpendicular to the line of sight, as Ref. [8] states, with the best direction on that circle equal to the
# optimum. The optimum leaves the plane quickly: for coasts of a few hours it is tens of degrees out of it, and for
# the 12-h coast of the map above it points within a few degrees of the line of sight itself (towards the target),
# the opposite of the heuristic; only for the longest coasts does it return towards the plane (angles printed
# above). With the smaller burn the best direction on the circle stays within a few percent of the optimum for
# longer, but only because every direction, doing nothing included, does: at 0.1 m/s the cost hardly depends on
# the burn. The circle also contains the worst directions, so even where it holds the heuristic is a *set* that
# contains the answer, not a policy.
# MMD is a policy, but with the burn at the first epoch (where $P_0$ applies) it is clearly suboptimal: it captures only part of the achievable range
# information and a sizeable fraction of random directions beat it (numbers above). The surrogate maximises the
# size of the measurement change at $\tau_f$ alone, whereas $J_\rho$ integrates all measurements of the coast and
# projects on the final line of sight. The two do not agree in direction: at both burn sizes the MMD axis is
# between 68 and 90 deg from the true minimiser (printed above; full run), nearly orthogonal to it. This is the
# honest form of the
# paper's "nearly optimal" (stated there for its Ref. [8] scenarios, which are not given).

# %% [markdown]
# ### Computation time
#
# The paper (Sec. 4.1) says the loss of optimality "comes with exponentially faster computation time". It gives no
# number; we measure the two on this machine for the 12-h coast and the 1 m/s burn, in the same run. MMD proper is
# Eq. 24 and one 3x3 eigenproblem, given the nominal STM and the final measurement Jacobian (timed as the best of
# many repetitions, since it takes microseconds); the full MMD policy adds the propagation of the nominal pair with
# its STM and the two-run covariance analysis that picks the sign. The true minimiser of section 3 is the
# `N_GRID`-direction sphere (one batched propagation and covariance analysis) followed by Nelder-Mead, one covariance
# analysis per cost evaluation (`ssat.minimize_range_sigma`).

# %%
timing = gs.timing_study(em, pair, sur, DV_M_S[-1], n_grid=N_GRID, repeat_optimum=TIMING_REPEAT)
print(f"MMD, Eq. 24 + eigenvector: {timing.mmd_core * 1e6:.1f} us (best of 200); full MMD policy with propagation "
      f"and sign check: {timing.mmd_policy * 1e3:.1f} ms (best of 3)")
print(f"true minimiser ({N_GRID}-direction sphere + Nelder-Mead): {timing.optimum:.2f} s; its sqrt(J_rho) "
      f"{timing.optimum_range_sigma_km:.2f} km (section 3: {study.optimum_at(DV_M_S[-1], MAP_COAST_H):.2f} km)")
print(f"ratio minimiser / MMD: {timing.ratio_core:.1e} (Eq. 24 + eigenvector), {timing.ratio_policy:.0f} "
      "(full MMD policy)")

# %% [markdown]
# MMD's linear algebra is several thousand times faster than the search, and the full policy, propagation and sign
# check included, still over a hundred times (ratios printed above; the timings depend on the machine). Both
# answers are fast here, because the search is one batched covariance analysis of all `N_GRID` directions plus a
# short Nelder-Mead refinement. "Exponentially" is not something a single problem size can show, and nothing in this
# problem grows exponentially with its size; the measured claim is the ratio.

# %% [markdown]
# ### A burn in the middle of a tracking arc
#
# So far the burn happens at the first epoch of the covariance analysis, where $P_0$ applies. In a linear covariance
# analysis a burn at that instant only moves the initial state: its information comes from the changed geometry
# alone. A burn *during* tracking adds a kink that angles-only measurements before and after it can see, and that
# kink breaks the scaling symmetry that makes range unobservable. The paper does not say which case its Ref. [8]
# comparison uses, so we repeat the 1 m/s comparison with `PRE_ARC_H` = 24 h of tracking before the burn ($P_0$ at
# the start of the arc).

# %%
with open_executor(WORKERS, SCHEDULER) as executor:
    arcs = gs.tracking_arc_study(em, pair, PRE_ARC_SWEEP_H, COAST_HOURS, DV_M_S[-1], n_grid=N_GRID, n_perp=N_PERP,
                                 executor=executor)
res_pre = arcs.results[PRE_ARC_H]
print(f"burn of {DV_M_S[-1]} m/s after {PRE_ARC_H} h of tracking")
print(" coast h | none   | MMD    | optimum | median dir | perp best/worst | MMD pct | MMD excess")
for i, h in enumerate(res_pre.coast_hours):
    print(f" {h:7.0f} | {res_pre.none[i]:6.2f} | {res_pre.mmd[i]:6.2f} | {res_pre.optimum[i]:7.3f} | "
          f"{res_pre.grid_median[i]:10.3f} | {res_pre.perp_best[i]:6.3f}/{res_pre.perp_worst[i]:6.2f} | "
          f"{res_pre.mmd_percentile[i]:6.1f}% | {res_pre.mmd_excess_percent[i]:6.0f} %")

# %% [markdown]
# **Reading.** With a tracking arc before it, the same burn is worth far more (compare "none" with any burn: the
# kink, not the geometry, carries the information), and for coasts of up to about half a day MMD is then essentially
# the optimal direction, as the paper states (within 2 % up to 12 h in the full run); for longer coasts it is well
# off again (13 % at 18 h, 200 % at 24 h, the coast that ends at apolune, then 35-52 %: printed above).
#
# The 24-h arc is our choice (the paper does not say how long the agent has tracked before the burn), so we sweep
# it: for each arc length, the longest coast up to which MMD stays within 5 % of the optimum for every coast, and
# the worst excess beyond it.

# %%
for h_pre, r in arcs.results.items():
    beyond = r.mmd_excess_percent[arcs.leading_run(h_pre):]
    print(f"tracking arc {h_pre:3d} h before the burn: MMD excess {np.round(r.mmd_excess_percent, 0)} %; within 5 % "
          f"for every coast <= {arcs.within_hours(h_pre):.0f} h" + (f", worst beyond {beyond.max():.0f} %" if beyond.size else ""))

# %% [markdown]
# The setting in which "nearly optimal" holds is therefore: a burn during tracking and a short coast (up to about
# half a day for every arc length swept, printed above).
#
# ### Does the verdict depend on the demonstration pair?
#
# The pair above is one choice among many. As a second, independent geometry we put the agent on the quasi-periodic
# torus of notebook 08 (the member about the 9:2 NRHO whose mean range to the target is 215 km, `cislunar.cr3bp.torus`)
# at four initial ring angles, burn 1 day before apolune, and repeat the comparison with the 1 m/s burn. The torus
# relative motion is not along-track: the line of sight sweeps around the target. The ring angles are 0, 45, 90 and
# 135 deg, not spread over the full circle: a ring angle 180 deg away puts the agent at nearly the mirrored relative
# position, which angles-only tracking sees almost identically (both checked below for 0 vs 180 deg), so antipodal
# angles would not be independent cases.

# %%
qpo, _ = qpo_for_mean_range(nrho, 215.0)
with open_executor(WORKERS, SCHEDULER) as executor:
    qp = gs.qpo_pair_study(em, qpo, pair, RING_ANGLES_DEG, COAST_HOURS, DV_M_S[-1], n_grid=N_GRID, n_perp=N_PERP,
                           executor=executor)
pct0 = lambda a: np.array2string(np.round(a), formatter={"float_kind": lambda v: f"{v:.0f}"}, max_line_width=200)
print(f"agent on the 215-km QPO, burn {DV_M_S[-1]} m/s, coast times {COAST_HOURS} h")
for ang, r in qp.results.items():
    print(f"ring angle {ang:5.0f} deg: MMD excess {pct0(r.mmd_excess_percent)} %; directions better than MMD "
          f"{pct0(r.mmd_percentile)} %")
anti_opt, anti_mmd, anti_pct = qp.antipode_differences()
print(f"relative position at the burn, ring angle 0 deg: {np.round(qp.offset_0, 1)} km, 180 deg: "
      f"{np.round(qp.offset_180, 1)} km (|sum| / |d| = {qp.mirror_ratio:.3f})")
print(f"antipodal check, ring angle 180 vs 0 deg, over all coasts: sqrt(J_rho) of the optimum differs by at most "
      f"{anti_opt:.1f} %, of MMD by at most {anti_mmd:.1f} %; MMD percentile by at most {anti_pct:.1f} points")
pct_all, exc_all = qp.percentile, qp.excess_percent
print(f"over all QPO pairs and coasts: median percentile {np.median(pct_all):.0f} %, median excess "
      f"{np.median(exc_all):.0f} %, MMD in the best 10 % of directions in {np.mean(pct_all < 10) * 100:.0f} % of cases")

# %% [markdown]
# **Reading.** The verdict is geometry- and horizon-dependent: for some torus pairs MMD is essentially optimal for
# coasts of a few hours (in the full run within 2 % up to 4 h at ring angle 0 deg), for others it is 9 % off already
# at 1 h (90 deg); in every pair its excess over the optimum grows with the coast time, to hundreds of percent or
# more for coasts beyond a day (at every step of the coast time except 36 to 48 h at 90 deg, printed above), because
# the surrogate looks at the measurement change at $\tau_f$ only while $J_\rho$ accumulates all measurements of the
# coast. "Nearly optimal" holds for short coasts in favourable geometries, not in general.

# %% [markdown]
# ## 5 · Paper vs reproduction
#
# Every row of the closing table is a claim declared, with its criterion, in
# `cislunar.papers.greaves_scheeres_2023.claims.ssat_guidance` before anything here is compared; the status word
# is computed from the criterion, never typed. The criteria, in the order of the rows:
#
# - **Identities (Eq. 7, the agent-based state).** Exact algebra, so the relative error must be at round-off,
#   at most $10^{-12}$; these rows are *derived* (the paper states them, it shows no number).
# - **Initial range uncertainty.** $\sqrt{J_\rho(t_0)}$ must equal $\sqrt2\times20$ km to $10^{-6}$ relative:
#   a pair of angles carries no range information, so the prior of both vehicles is all there is.
# - **Two implementations of the covariance analysis** (square-root information batch and Joseph-form EKF) must
#   agree to $10^{-6}$ relative: a check the paper does not make (*beyond paper*).
# - **MMD is the eigenvector.** Both brute-force maximisers of the surrogate (the quadratic form and the nonlinear
#   change of the final angles) must lie within one spacing of the Fibonacci sphere from the eigenvector, which is
#   as close as a grid of that size can resolve.
# - **The perpendicular heuristic of Ref. [8]** is stated "for short coasting periods", without a length: the best
#   direction of the perpendicular circle must be within 2 % of the true minimiser's $\sqrt{J_\rho}$ at every coast
#   read as short. The sweep over coast times (section 4) shows that, with the 1 m/s burn, it holds at the 1-h coast
#   only, so "short" is read as 1 h, a reading made after seeing the sweep: the row is *tuned*, and it prints where
#   the heuristic holds and by how much it misses at every longer coast (with the 0.1 m/s burn it holds longer, only
#   because the cost hardly depends on a burn that small).
# - **"Nearly optimal".** Within 5 % of the true minimiser's $\sqrt{J_\rho}$, for every coast (the worst coast is
#   what is compared). Four settings: the burn at the start of tracking (the first pair), the same on the torus
#   (the *median* over ring angles and coasts, a milder statistic than the worst coast, in a *beyond paper* check
#   that turns to *differs* when it fails), and the mid-arc burn split into the leading run of coasts within the
#   tolerance and the rest. Since the first part's coasts are, by construction, those within the tolerance, that
#   row could not fail as a verdict: it is a *beyond paper* record of *where* MMD is near-optimal (the mid-arc
#   setting was, besides, adopted after the first comparison missed), and the test is the row after it (the longer
#   coasts), which fails.
# - **Where MMD is near-optimal.** The paper's "nearly optimal" carries no condition, so one summary row counts,
#   over every case swept with the larger burn (the burn at the start of tracking at each coast, the burn after
#   each tracking arc at each coast, the agent on the torus at each ring angle and coast), the share in which MMD
#   is within 5 % of the true minimiser; a general property would hold in at least 90 % of them. The row prints
#   the cases where it holds and the spread of the excess where it does not.
# - **The sign choice and the computation time** are measured, not compared: the paper asks for the sign check
#   and gives no timing number.
#
# Percentages are of $\sqrt{J_\rho}$ at the end of the coast, the 1-sigma range uncertainty; the notes carry the
# context that decides how far each verdict reaches (burn size, coast time, geometry).
# The timing row depends on the machine and varies from run to run; it is a ratio, not a test of a rate.

# %%
r0, r1 = study.results[DV_M_S[0]], study.results[DV_M_S[-1]]
perp_h = {dv: study.perpendicular_hours(dv) for dv in DV_M_S}
in_plane_h = ", ".join(f"{x:g}" for x in r1.coast_hours[r1.optimum_perp_angle_deg <= 5.0])
off_plane_small = np.max(r0.optimum_perp_angle_deg[r0.coast_hours <= perp_h[DV_M_S[0]]], initial=0.0)
near = exc_all <= 5.0
n_ok, exc, pct, hrs = arcs.leading_run(PRE_ARC_H), res_pre.mmd_excess_percent, res_pre.mmd_percentile, res_pre.coast_hours
arc_list = ", ".join(f"{h:g}" for h in PRE_ARC_SWEEP_H)
arc_rows = []  # the mid-arc burn split at the leading run of coasts within the tolerance (either part may be empty)
if n_ok:
    arc_rows.append(CLAIMS["mmd_near_optimal_arc_short"].judge(exc[:n_ok].max(),
        shown=f"excess {exc[:n_ok].min():.0f}-{exc[:n_ok].max():.0f} %, percentile {pct[:n_ok].min():.1f}-"
              f"{pct[:n_ok].max():.1f} %",
        note=f"coasts <= {hrs[n_ok - 1]:.0f} h. Not specific to the {PRE_ARC_H:g}-h arc: with {arc_list} h of tracking before "
             f"the burn the 5 % holds for every coast <= {min(map(arcs.within_hours, PRE_ARC_SWEEP_H)):.0f} h. A mid-arc "
             f"burn cuts sqrt(J_rho) from {res_pre.none[n_ok - 1]:.1f} km (no burn) to {res_pre.optimum[n_ok - 1]:.3f} "
             f"km (best) after {hrs[n_ok - 1]:.0f} h"))
if n_ok < exc.size:
    arc_rows.append(CLAIMS["mmd_near_optimal_arc_long"].judge(exc[n_ok:].max(),
        shown=f"excess {exc[n_ok:].min():.0f}-{exc[n_ok:].max():.0f} %, percentile {pct[n_ok:].min():.1f}-"
              f"{pct[n_ok:].max():.1f} %",
        note=f"coasts {hrs[n_ok]:.0f}-{hrs[-1]:.0f} h; tolerance exceeded at "
             f"{', '.join(f'{h:g}' for h in hrs[n_ok:][exc[n_ok:] > 5.0])} h. The sweep here covers coast time, burn "
             f"timing (start of tracking, previous rows; tracking arc before the burn {arc_list} h: every arc length "
             f"fails beyond {max(map(arcs.within_hours, PRE_ARC_SWEEP_H)):.0f} h, worst excess "
             f"{arcs.worst_excess_percent.min():.0f}-{arcs.worst_excess_percent.max():.0f} %) and geometry (QPO row)"))
# where MMD is within the tolerance: every (setting, coast) case swept with the larger burn
case_sets = {"start of tracking": (r1.coast_hours, r1.mmd_excess_percent),
             **{f"{h:g}-h arc": (r.coast_hours, r.mmd_excess_percent) for h, r in arcs.results.items()},
             **{f"QPO {a:g} deg": (r.coast_hours, r.mmd_excess_percent) for a, r in qp.results.items()}}
tol_near = NEAR_OPTIMAL_PERCENT
n_cases = sum(e.size for _, e in case_sets.values())
n_near = sum(int(np.sum(e <= tol_near)) for _, e in case_sets.values())
near_where = "; ".join(f"{k}: {np.sum(e <= tol_near)} of {e.size}"
                       + (f" (coasts {', '.join(f'{x:g}' for x in h[e <= tol_near])} h)" if np.any(e <= tol_near) else "")
                       for k, (h, e) in case_sets.items())
far = np.concatenate([e[e > tol_near] for _, e in case_sets.values()])
# the perpendicular heuristic over every coast swept (the larger burn)
short = r1.coast_hours <= SHORT_COAST_HOURS + 1e-6  # coasts read as "short" (the shortest swept if none is)
short[0] = True
perp_excess = 100 * (r1.perp_best / r1.optimum - 1)
long_h = r1.coast_hours[~short]
perp_sweep = (f"; at {long_h.min():g}-{long_h.max():g} h the best direction of the circle is "
              f"{perp_excess[~short].min():.0f}-{perp_excess[~short].max():.0f} % above the optimum" if long_h.size else "")
table.add(
    CLAIMS["eq7_identity"].judge(cc.covariance_round_trip, shown=f"{cc.covariance_round_trip:.1e} rel. error"),
    CLAIMS["agent_based_equivalent"].judge(max(cc.relative_block, cc.range_variance_spread),
        shown=f"{cc.relative_block:.1e} / {cc.range_variance_spread:.1e}",
        note="angles depend on s_rho only: Jacobian [0 H_rho] in both relative systems (tested)"),
    CLAIMS["initial_range_sigma"].judge(base[0], shown=f"{base[0]:.2f} km", note="sqrt(2) x 20 km"),
    CLAIMS["sri_vs_ekf"].judge(pair.ekf_difference["inertial"], shown=f"{pair.ekf_difference['inertial']:.1e} rel.",
                               note="two independent implementations agree"),
    CLAIMS["no_maneuver_sigma"].judge(base[24], shown=f"{base[24]:.1f} / {base[-1]:.1f} km"),
    CLAIMS["mmd_is_eigenvector"].judge(sur.within_grid,
        shown=f"{sur.angle_quadratic_deg:.2f} deg (u^T Q u) / {sur.angle_nonlinear_deg:.2f} deg (nonlinear angle change)",
        note=f"{MAP_COAST_H}-h coast, {N_GRID}-direction sphere (spacing {sur.spacing_deg:.1f} deg); Eq. 23 as printed is the "
             "eigenvalue (a scalar); the text ('solution to an eigen-problem') means the unit eigenvector of that eigenvalue"),
    CLAIMS["perpendicular_contains_optimum"].judge(float(np.max(perp_excess[short])),
        shown=f"{np.max(perp_excess[short]):.1f} % at {r1.coast_hours[short].max():g} h (best on circle "
              f"{r1.perp_best[0]:.2f} vs optimum {r1.optimum[0]:.2f} km, {DV_M_S[-1]} m/s); holds for coasts <= "
              f"{perp_h[DV_M_S[-1]]:.0f} h only" + perp_sweep,
        note=f"optimum off the perpendicular plane by {r1.optimum_perp_angle_deg[0]:.1f} deg at {r1.coast_hours[0]:.0f} h. "
             f"Tolerance met for coasts <= {perp_h[DV_M_S[-1]]:.0f} h ({DV_M_S[-1]} m/s; coasts swept "
             f"{', '.join(f'{h:g}' for h in r1.coast_hours)} h); optimum "
             f"within 5 deg of the plane at {in_plane_h} h only, and at 12 h {dmap.los_angle_deg:.0f} deg from the line "
             f"of sight ({'towards' if dmap.towards_target else 'away from'} the target). At {DV_M_S[0]} m/s the 2 % is "
             f"met up to {perp_h[DV_M_S[0]]:.0f} h with the optimum up to {off_plane_small:.0f} deg out of the plane: "
             "the cost hardly depends on a burn that small"),
    CLAIMS["mmd_near_optimal_start"].judge(r1.mmd_excess_percent.max(),
        shown=f"{r1.mmd_excess_percent.min():.0f}-{r1.mmd_excess_percent.max():.0f} % ({DV_M_S[-1]} m/s); "
              f"{r0.mmd_excess_percent.min():.0f}-{r0.mmd_excess_percent.max():.0f} % ({DV_M_S[0]} m/s)",
        note=f"directions better than MMD: {r1.mmd_percentile.min():.0f}-{r1.mmd_percentile.max():.0f} %; gain captured "
             f"{r1.mmd_gain_fraction.min() + 0.0:.2f} to {r1.mmd_gain_fraction.max() + 0.0:.2f}. At {DV_M_S[0]} m/s the 5 % "
             f"is met but is no test: doing nothing is itself within {np.max(100 * (r0.none / r0.optimum - 1)):.0f} % of "
             f"the optimum and MMD captures only {r0.mmd_gain_fraction.min() + 0.0:.2f}-"
             f"{r0.mmd_gain_fraction.max() + 0.0:.2f} of the possible gain"),
    CLAIMS["mmd_near_optimal_qpo"].judge(np.median(exc_all),
        shown=f"median excess {np.median(exc_all):.0f} %, median percentile {np.median(pct_all):.0f} %",
        note=f"MMD in the best 10 % of burn directions in {np.mean(pct_all < 10) * 100:.0f} % of the {pct_all.size} "
             f"(pair, coast) cases ({len(qp.results)} ring angles x {len(COAST_HOURS)} coasts); within 5 % of the "
             f"optimum in {near.sum()} cases, all with coasts <= {qp.coast_hours[near].max() if near.any() else 0:.0f} h. "
             f"Antipodal ring angles are not independent cases: 180 deg gives the sqrt(J_rho) of 0 deg within "
             f"{anti_opt:.1f} % (optimum) and {anti_mmd:.1f} % (MMD)"),
    *arc_rows,
    CLAIMS["mmd_near_optimal_cases"].judge(100 * n_near / n_cases,
        shown=f"{n_near} of {n_cases} cases ({100 * n_near / n_cases:.0f} %); elsewhere {far.min():.0f}-{far.max():.0f} % "
              f"above the optimum (median {np.median(far):.0f} %)" if far.size else f"{n_near} of {n_cases} cases",
        note=f"{DV_M_S[-1]} m/s; within {tol_near:g} %: {near_where}. With the burn at the start of tracking MMD is "
             f"{r1.mmd_excess_percent.min():.0f}-{r1.mmd_excess_percent.max():.0f} % above the optimum"),
    CLAIMS["sign_choice"].judge(study.sign_percent(DV_M_S[-1]).max(),
        shown="; ".join(f"rejected sign worse by {study.sign_percent(dv).min():.1f}-{study.sign_percent(dv).max():.1f} "
                        f"% ({dv} m/s)" for dv in DV_M_S[::-1]),
        note="first pair, burn at the start of tracking, all coasts"),
    CLAIMS["computation_time"].judge(timing.ratio_core,
        shown=f"{timing.ratio_core:.1e} (Eq. 24 + eigenvector), {timing.ratio_policy:.0f} (full MMD policy)",
        note=f"{MAP_COAST_H}-h coast, {DV_M_S[-1]} m/s, this machine: {timing.optimum:.2f} s ({N_GRID}-direction sphere + "
             f"Nelder-Mead) vs {timing.mmd_core * 1e6:.0f} us (best of 200) / {timing.mmd_policy * 1e3:.1f} ms with "
             "propagation and sign check (best of 3); a timing ratio, not a test of 'exponentially'"),
)
table.display()

# %% [markdown]
# ## Exercises
#
# Each exercise changes one parameter of the `parameters` cell at the top; rerun the notebook (in Jupyter, or with
# `python -m cislunar.publish.notebooks --quick 07 -p NAME=VALUE`), write down your prediction first, then compare.
# The worked solutions are functions of `cislunar.papers.greaves_scheeres_2023.exercises` that answer each question at
# a small size in a few seconds and return the numbers with a one-paragraph answer.
#
# 1. **The size of the burn.** Set `DV_M_S = [0.5, 2.0]`. Before running: does the MMD *direction* change with
#    $\upsilon$ (look at Eq. 24: which quantities does $Q$ contain)? Does the gain of the MMD burn over doing nothing
#    change, and how? Check the MMD columns of the tables of section 3 and the angle between the MMD axis and the true
#    minimiser. Worked solution: `exercise_07_burn_magnitude`.
# 2. **A burn inside a tracked arc.** Set `PRE_ARC_H = 6` and `PRE_ARC_SWEEP_H = [6]`, then `PRE_ARC_H = 48`. Predict
#    whether MMD gets closer to or further from the true minimiser for short coasts than with the burn at the start of
#    tracking, and why the no-burn column barely changes while the best burn gains a factor of a hundred (hint: what
#    does a known kink do to the scaling symmetry of angles-only relative motion?). Worked solution:
#    `exercise_07_tracking_arc`.
# 3. **How fine must the sphere be?** Set `N_GRID = 150`. Predict which numbers move: the true minimiser is refined
#    by Nelder-Mead from the best grid direction, the MMD percentile is counted on the grid itself, and the
#    surrogate check is judged against the grid spacing. Which closing-table rows would you expect to keep their
#    status? Worked solution: `exercise_07_sphere_resolution`.
