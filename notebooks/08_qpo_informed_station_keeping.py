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
# # 08 · Informed station keeping on a quasi-periodic orbit about the 9:2 NRHO
#
# **What you will learn.** How a quasi-periodic torus about the Gateway's 9:2 NRHO turns "station keeping" from a
# single target point into a two-parameter *set* of acceptable states; how every point of that set is reached with
# a two-burn transfer (position, then velocity); how Greaves & Scheeres pick, among all those maneuvers, the one most
# aligned with the MMD information-gathering direction (the *informed* maneuver $\mathbf u^*$, Eq. 25); and whether
# that choice really lands in the valley of range uncertainty and avoids the largest fuel costs, checked with numbers
# over the full surface of maneuvers, each with its own covariance analysis. Eq. 25 as printed needs a reading: read
# as an angle, its answer depends on how finely the set is sampled; read as a projection, it does not, and it finds
# the paper's valley at the price of fuel (section 5b). Whether $\mathbf u^*$ "significantly improves" range
# knowledge is tested against baselines a poor pick fails, the edge of its slice's valley and uninformed random
# picks (section 5c), not against doing nothing, which every maneuver beats. Beyond the paper (its own future work),
# a full-filter Monte Carlo with maneuver execution errors tells us how much of the predicted range information
# survives.
#
# **Paper sections followed.** Greaves & Scheeres (AMOS 2023), Secs. 4 (informed station keeping, Eq. 25,
# Figs. 2-3), 5 (simulation and results, Figs. 4-5) and the future work of Sec. 6 (execution errors and a full
# filter, section 7 here). SSAT, $J_\rho$ and MMD are built in notebook 07; the invariant-torus solver is
# `cislunar.cr3bp.torus`.

# %% tags=["parameters"]
QUICK = False  # quick mode: coarser surface, fewer sweep points, fewer Monte Carlo trials (the default sizes below)
SEED = 0  # root seed: Monte Carlo streams [SEED, k], offset directions [SEED, 8], random picks [SEED, 20] and [SEED, 21]
OUTPUT_DIR = ""  # folder for the figures (empty: build-scratch/ by hand, the build under the runner)
N_SURF = None  # ring angles, i.e. arrival times, of the station-keeping surface (None: 14 quick, 40 full; paper: not given)
N_SWEEP = None  # arrival times in the sweep over the unstated scenario inputs (None: 3 quick, 16 full)
N_GRID = None  # ring-angle counts of the resolution study of section 5b (None: 10, 20 quick; 16 ... 640 full)
N_GRID_SLICES = None  # arrival times in the resolution study (None: 3 quick, 5 full)
N_RAISED = None  # arrival samplings (slices over the arrival window) at which the raised points of the u* line are
# counted (None: 7, 14, 28 quick; 16, 20, 24, 32, 40, 48, 60, 80 full; paper: not given)
N_TRIALS = None  # Monte Carlo trials per policy and execution-error level (None: 2 quick, 40 full)
N_RANDOM = None  # uninformed picks per arrival slice, ring angles uniform on [0, 2 pi) (None: 16 quick, 64 full)
MEMBER_CHECK = None  # re-solve the torus for two other readings of "average range" (None: False quick, True full)
WORKERS = None  # local processes for the sweeps and the Monte Carlo, 1 runs serially (None: 1 quick, 2 full)
SCHEDULER = ""  # address of a Dask scheduler to run them on ("" for none; then WORKERS applies)
MEAN_RANGE_KM = None  # mean agent-target range that selects the torus member, km (None: 215.0, the paper's number)
T_BURN_H = None  # first burn, hours from the target's apoapsis (None: -24.0)
T_ARRIVAL_H = None  # window of arrival times (second burn), hours from apoapsis (None: (-12.0, 12.0))
T_FINAL_H = None  # end of the covariance analysis, where sqrt(J_rho) is read, hours from apoapsis (None: 24.0)
AGENT_THETA = None  # the agent starts on the torus trajectory of this ring angle, rad (None: 0.0)
PRE_ARC_H = None  # alternative reading: tracking starts this long before the first burn, hours (None: 24.0)
SWEEP_LEADS_H = None  # first-burn leads before the arrival window swept in section 6, hours (None: 12, 24, 48)
SWEEP_AGENT_PHASES = None  # agent ring angles swept in section 6, fractions of a turn (None: 0, 0.25, 0.5, 0.75)
OFFSET_KM = None  # distances of the agent off the torus in section 6, km (None: 0, 1, 10, 50)
EXEC_ABS_M_S = None  # execution error, absolute part, m/s 1 sigma per axis (None: 1e-3)
EXEC_REL = None  # execution error, part proportional to the burn, fraction 1 sigma per axis (None: 0.01)

# %% [markdown]
# **Changing the chapter.** Every size and every scenario choice the paper leaves open is a parameter of the cell
# above. A parameter left at `None` is chosen in the next cell, from `QUICK` for the sizes (quick mode: a 14 x 14
# surface, 2 Monte Carlo trials, the two extra torus members of section 6 skipped) and from our stated baseline for the scenario (first burn 24 h before apoapsis,
# arrivals within 12 h of it, read-out 24 h after it, agent at ring angle 0); a value you give, in Jupyter or with
# `-p NAME=VALUE` on the command line, is used as given in either mode. The sweeps of sections 5b and 6 (one
# surface per task) and the Monte Carlo of section 7 (one filter run per trial, trial streams `[SEED, k]`) run on
# the executor that `WORKERS` local processes or a Dask `SCHEDULER` provide; the numbers do not depend on it. The
# exercises at the end of the chapter start from here.

# %%
# Every parameter left at None is picked here (sizes from QUICK); a value the reader gave is used as given.
N_SURF = N_SURF if N_SURF is not None else (14 if QUICK else 40)
N_SWEEP = N_SWEEP if N_SWEEP is not None else (3 if QUICK else 16)
N_GRID = tuple(N_GRID if N_GRID is not None else ((10, 20) if QUICK else (16, 40, 80, 160, 320, 640)))
N_GRID_SLICES = N_GRID_SLICES if N_GRID_SLICES is not None else (3 if QUICK else 5)
N_RAISED = tuple(N_RAISED if N_RAISED is not None else ((7, 14, 28) if QUICK else (16, 20, 24, 32, 40, 48, 60, 80)))
N_TRIALS = N_TRIALS if N_TRIALS is not None else (2 if QUICK else 40)
N_RANDOM = N_RANDOM if N_RANDOM is not None else (16 if QUICK else 64)
MEMBER_CHECK = MEMBER_CHECK if MEMBER_CHECK is not None else not QUICK
WORKERS = WORKERS if WORKERS is not None else (1 if QUICK else 2)
# Scenario choices the paper leaves open (stated, then swept in section 6):
MEAN_RANGE_KM = MEAN_RANGE_KM if MEAN_RANGE_KM is not None else 215.0
T_BURN_H = T_BURN_H if T_BURN_H is not None else -24.0
T_ARRIVAL_H = tuple(T_ARRIVAL_H if T_ARRIVAL_H is not None else (-12.0, 12.0))
T_FINAL_H = T_FINAL_H if T_FINAL_H is not None else 24.0
AGENT_THETA = AGENT_THETA if AGENT_THETA is not None else 0.0
PRE_ARC_H = PRE_ARC_H if PRE_ARC_H is not None else 24.0
SWEEP_LEADS_H = tuple(SWEEP_LEADS_H if SWEEP_LEADS_H is not None else (12.0, 24.0, 48.0))
SWEEP_AGENT_PHASES = tuple(SWEEP_AGENT_PHASES if SWEEP_AGENT_PHASES is not None else (0.0, 0.25, 0.5, 0.75))
OFFSET_KM = tuple(OFFSET_KM if OFFSET_KM is not None else (0.0, 1.0, 10.0, 50.0))
EXEC_ABS_M_S = EXEC_ABS_M_S if EXEC_ABS_M_S is not None else 1e-3
EXEC_REL = EXEC_REL if EXEC_REL is not None else 0.01

import time

import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.torus import qpo_for_mean_range
from cislunar.papers.greaves_scheeres_2023 import figures
from cislunar.papers.greaves_scheeres_2023 import station_keeping as sk
from cislunar.papers.greaves_scheeres_2023 import station_keeping_study as study
from cislunar.papers.greaves_scheeres_2023.claims.informed_station_keeping import (
    CLAIMS,
    CONSISTENT,
    PROJECTION_VALLEY_PHASES,
    QUARTER_TURN_PHASES,
)
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.utils.executors import open_executor

plotting.use_style()
out = OUTPUT_DIR or None
table = ComparisonTable("08 QPO and informed station keeping (Greaves & Scheeres AMOS 2023, Secs. 4-5)")
L, HR = em.length_unit_km, 3600.0 / em.time_unit_s
t_start = time.perf_counter()

# %% [markdown]
# ## 1 · The QPO about the 9:2 NRHO and the 215 km member
#
# The target flies the 9:2 southern L2 NRHO; the agent flies a quasi-periodic orbit about it "with the same base
# frequency" (Sec. 4). We compute 2-D invariant tori by the invariant-circle method (`cislunar.cr3bp.torus`): the
# ring $u(\theta)$ at the NRHO's apolune is mapped onto itself by the flow over one NRHO period $T$, rotated by the
# rotation number $\rho$, $\varphi_T(u(\theta)) = u(\theta+\rho)$; the stroboscopic time is fixed to $T$, which is
# what "same base frequency" means. The paper gives one number for its member: "the average range between the
# natural trajectories of the two spacecraft is 215 km".
#
# **Definition of the mean range (our reading).** Target on the NRHO from apolune, agent on the torus trajectory
# through ring angle $\theta_0$ at the same epoch; the range averaged uniformly over all $\theta_0\in[0,2\pi)$ and
# over one period $[0, T)$. For an irrational $\rho/2\pi$ this is the long-time average along any single agent
# trajectory. We **select** the family member whose mean range is 215 km: the number is an *input* here, not a
# prediction, and cannot be "reproduced".

# %% [markdown]
# `qpo_for_mean_range` continues the torus family in ring size from a small torus and matches the mean range by a
# secant iteration. Printed below: the NRHO's period and apolune radius; the member's ring size (RMS about its
# centre, in position and velocity) and its largest offset from the NRHO's apolune state; the rotation number
# $\rho$; the Jacobi constant of the torus (mean over its circle) next to the NRHO's; the
# invariance error of the circle at the midpoints between its collocation points, the honest measure of how well the
# torus solves $\varphi_T(u(\theta)) = u(\theta+\rho)$; and the range statistics of the member.

# %%
nrho = nrho_9_2(em)
torus, stats = qpo_for_mean_range(nrho, MEAN_RANGE_KM)
print(f"9:2 NRHO: period {nrho.period_days:.4f} d, apolune radius {nrho.apolune_radius_km:.0f} km")
print(f"QPO member: ring size (RMS about its centre) {torus.size_km:.2f} km and {torus.velocity_size_mps:.3f} m/s; "
      f"largest offset from the NRHO apolune state {torus.max_offset_km:.1f} km, {torus.max_velocity_offset_mps:.2f} m/s")
print(f"rotation number rho = {torus.rho:.6f} rad per period ({np.degrees(torus.rho):.3f} deg; "
      f"rho/2pi = {torus.rho / (2 * np.pi):.6f}); Jacobi constant {torus.jacobi:.10f} (NRHO {nrho.jacobi:.10f})")
print(f"invariance error at the circle midpoints {torus.invariance_error():.2e} (non-dimensional)")
print(f"agent-target range: mean {stats.mean_km:.2f} km, min {stats.min_km:.2f} km, max {stats.max_km:.2f} km; "
      f"mean over the apolune ring only {stats.ring_mean_km:.2f} km, RMS {stats.rms_km:.2f} km")

# %% [markdown]
# ## 2 · Fig. 2: the torus surface and the NRHO near apoapsis
#
# Left: the QPO's surface about apoapsis (the paper's Fig. 2 gives no time span; we draw $\pm$1.5 days), with the
# target's NRHO arc in black and the initial ring at apoapsis in red; Moon-centred rotating frame, units of 1000 km.
# At this scale the ring (a few hundred km across) is a thin tube around the 70 000 km NRHO, so the right panel
# shows what the agent actually sees: the ring *relative to the target* at five times from apoapsis, in km with
# equal axis scales (rotating-frame axes, origin at the target).

# %%
_ = plotting.save_figure(figures.torus_and_nrho(em, nrho, torus), "08_fig2_torus_and_nrho", output_dir=out)

# %% [markdown]
# ## 3 · The station-keeping set and the two-burn transfer
#
# A surface point is named by its **initial ring angle** $\theta_0$ (normalised phase $\theta_0/2\pi$, the paper's
# axis) and its **time from apoapsis** $t_a$: the state at $t_a$ of the torus trajectory through $u(\theta_0)$. From
# its state at the first-burn epoch $t_b$ the agent reaches the surface point's *position* at $t_a$ with a first
# burn found by Newton's method on $\mathbf r(t_a) = \mathbf r^\star$ with the STM block $\Phi_{rv}$ (a Lambert
# problem in the CR3BP, all ring angles of one arrival time in one heyoka batch), then matches its *velocity* with
# the second burn. Every maneuver gets its own covariance analysis (notebook 07: hourly azimuth/elevation, Eq. 20
# noise, initial 3-sigma 60 km / 60 cm/s, no execution errors as in the paper) from $t_b$ to $t_f$, where
# $\sqrt{J_\rho}$ is read.
#
# **Open choices (the paper gives none of them; swept in section 6):** the agent starts on the torus trajectory of
# ring angle 0 (so "do nothing" is one of the options, at phase 0); first burn 24 h before apoapsis; arrival times
# from 12 h before to 12 h after apoapsis; $\sqrt{J_\rho}$ read 24 h after apoapsis, so that every maneuver has the
# same measurements and the second burn's effect is included (the paper attributes a local peak to it).

# %% [markdown]
# The call below builds the whole set: `N_SURF` ring angles times `N_SURF` arrival times, each maneuver with its
# two burns and its own covariance analysis. Printed: the run time, the largest position miss of the first burn's
# Newton iteration at arrival (the transfer must land on the torus point), the ranges of both burns and of the
# total fuel, and the range of $\sqrt{J_\rho}$ at $t_f$ over the set, with the no-maneuver value apart (the agent's
# own ring angle, phase 0, where both burns vanish).

# %%
theta = 2 * np.pi * np.arange(N_SURF) / N_SURF
t_arr = np.linspace(*T_ARRIVAL_H, N_SURF) * HR
t0 = time.perf_counter()
S = sk.station_keeping_surface(em, torus, theta, t_arr, T_BURN_H * HR, T_FINAL_H * HR, agent_theta=AGENT_THETA)
print(f"{N_SURF} x {N_SURF} = {N_SURF**2} maneuvers with covariance analyses ({S.t.size} measurement epochs each) "
      f"in {time.perf_counter() - t0:.1f} s")
print(f"largest position miss of the first burn at arrival: {S.transfer_miss.max():.1e} LU "
      f"({S.transfer_miss.max() * L * 1e6:.2f} mm)")
print(f"first burn {S.dv1_m_s.min():.3f}-{S.dv1_m_s.max():.2f} m/s, second burn {S.dv2_m_s.min():.3f}-"
      f"{S.dv2_m_s.max():.2f} m/s, total {S.fuel_m_s.min():.3f}-{S.fuel_m_s.max():.2f} m/s")
print(f"sqrt(J_rho) at t_f: {S.range_sigma_km.min() * 1e3:.1f} m to {S.range_sigma_km.max():.2f} km "
      f"(no maneuver: {S.range_sigma_km[0, 0]:.2f} km; largest over the maneuvers "
      f"{S.range_sigma_km[S.fuel_m_s > 1e-9].max() * 1e3:.0f} m)")

# %% [markdown]
# The figure draws the first and the second burn over the set, with $\mathbf u^*$ under both readings of Eq. 25
# discussed below: the magenta line (the paper's colour) reads Eq. 25 as an angle, the dashed red line as a
# projection (section 5b); `S.reselect("projection")` chooses $\mathbf u^*$ again on the same maneuvers.

# %%
S_proj = S.reselect("projection")  # same maneuvers and covariance analyses, u* chosen by the projection reading
_ = plotting.save_figure(figures.surfaces(S, "burns", projection=S_proj), "08_fig3_burn_surfaces", output_dir=out)

# %% [markdown]
# The first burn vanishes along phase 0 (the agent's own torus trajectory) and grows with the phase distance; it
# also grows as the coast gets shorter (earlier arrival). The angle reading's line hugs phase 0 (the smallest
# burns), the projection reading's sits on the flank of the first-burn hill, at a few metres per second (its first
# burn is 2.7 m/s in the slice nearest apoapsis, printed in section 7; full run). The
# magenta line is $\mathbf u^*$: for each arrival time,
# the MMD direction $\mathbf u_y$ of the coast $t_b\to t_a$ is computed on the unmaneuvered trajectory, the two
# maneuvers with $\theta_u$ closest to 0 and to $\pi$ (Eq. 25) are the candidates, and the one with the smaller
# $J_\rho$ wins.
#
# **Eq. 25 as printed, and our reading.** The paper writes $\theta_u = \cos^{-1}\big(\mathbf u_y^T\mathbf u_{sk} /
# \|\mathbf u_y^T\mathbf u_{sk}\|\big)$: the denominator is the absolute value of the same scalar, so the ratio is
# always $\pm1$ and $\theta_u\in\{0,\pi\}$ for every maneuver, which cannot rank anything. We read it as the angle
# between the two vectors, $\cos\theta_u = \mathbf u_y^T\mathbf u_{sk}/(\|\mathbf u_y\|\|\mathbf u_{sk}\|)$, with
# $\mathbf u_{sk}$ the **first** burn (the paper draws the magenta line "on the first burn", Fig. 3 caption). Three
# further choices the paper leaves open: the MMD coast ends at the arrival $t_a$ (the alternative, $\tau_f = t_f$,
# is in the sweep of section 6); the "quick covariance analysis" between the $\theta_u\approx0$ and
# $\theta_u\approx\pi$ candidates is the same covariance analysis that fills Fig. 4, so the choice of sign uses the
# cost it is judged by (which can only help $\mathbf u^*$); and a random pick of one maneuver per slice would sit at
# the 50th percentile on average, the better of two random picks at about the 33rd. Section 5b takes up a second
# reading (the *projection* of the burn on $\mathbf u_y$) and shows why the angle reading depends on how finely the
# set is sampled.
#
# ## 4 · Fig. 4: range uncertainty over all maneuvers, and Fig. 5: fuel

# %%
_ = plotting.save_figure(figures.surfaces(S, "range_fuel", projection=S_proj), "08_fig4_fig5_range_sigma_and_fuel",
                         output_dir=out)

# %% [markdown]
# The 3-D views follow the paper's Figs. 4 and 5 and are an illustration: perspective makes heights hard to compare
# (in the left panel the no-maneuver wall at phase 0, printed above, is clipped at the largest maneuver value so
# that the relief of the maneuvers shows). Both readings of Eq. 25 are drawn, as in Fig. 3: on the fuel surface
# (Fig. 5) the angle reading runs along the floor next to phase 0, the projection reading climbs the flank. The
# same data as maps, with the colour scale of the range map set by the maneuvers alone (the phase-0 column, where
# the agent does not maneuver, is hatched; magenta circles the angle reading, red crosses the projection reading):

# %%
_ = plotting.save_figure(figures.range_and_fuel_maps(S, projection=S_proj), "08_maps_range_sigma_fuel",
                         output_dir=out)

# %% [markdown]
# ## 5 · The paper's claims, with numbers
#
# *"The informed station keeping maneuvers do in fact fall in the valley of range uncertainty"*: within each
# time-of-arrival slice we rank $\mathbf u^*$ among all maneuvers of the slice by $\sqrt{J_\rho}$ (percentile
# 0 = best). *"The guidance policy avoids the peak fuel cost"*: the percentage of the slice's maneuvers that use more
# fuel than $\mathbf u^*$ (off the peak: at least a quarter of them cost more). We also compare $\mathbf u^*$ with
# the best maneuver of its slice and with the best maneuver that uses at most its fuel.

# %% [markdown]
# `study.slice_statistics` ranks $\mathbf u^*$ within each arrival slice. Its table gives, per arrival time: the
# phase of $\mathbf u^*$, its $\sqrt{J_\rho}$ at $t_f$, the best $\sqrt{J_\rho}$ of the slice, the best among
# the maneuvers that use no more fuel than $\mathbf u^*$ (what the same fuel could have bought), the percentile of
# $\mathbf u^*$, its fuel and the share of maneuvers that use more. Below the table: the medians over the slices,
# the phases of the valley, of $\mathbf u^*$ and of the fuel peak, and Spearman's rank correlation of fuel and
# $\sqrt{J_\rho}$ within a slice (negative: bigger burns buy more range information).

# %%
st = study.slice_statistics(S)
print(st.format(S))
print(f"\nmedian percentile of u* in its slice: {st.median_percentile:.1f} % (valley = low); "
      f"slices with u* in the best quartile: {st.best_quartile_share:.0f} %")
print(f"median share of maneuvers using more fuel than u*: {np.median(st.fuel_percentile):.1f} %; u* at or below the "
      f"slice's median fuel in {st.below_median_fuel * 100:.0f} % of slices, outside its most expensive quarter in "
      f"{st.outside_fuel_peak_share:.0f} %")
print(f"valley of sqrt(J_rho) at median phase {st.valley_phase:.3f}; u* at median phase {st.informed_phase:.3f}; fuel "
      f"peak at phase {st.fuel_peak_phase:.3f}; median rank correlation of fuel and sqrt(J_rho) within slices "
      f"(maneuvers only) {st.rank_correlation:.2f}")
print(f"u* vs doing nothing: sqrt(J_rho) {np.median(S.informed_range_sigma_km) * 1e3:.1f} m vs "
      f"{S.range_sigma_km[0, 0] * 1e3:.0f} m")

# %% [markdown]
# The same comparison drawn per slice. Left: $\sqrt{J_\rho}$ against phase for three arrival slices (the
# no-maneuver point at phase 0 is far off the scale), with $\mathbf u^*$ and the slice's best maneuver marked.
# Right: the percentile of $\mathbf u^*$ in every slice; the valley claim needs it in the best quartile (below 25 %),
# a random pick lands at 50 % on average.

# %%
_ = plotting.save_figure(figures.informed_within_slices(S), "08_informed_within_slices", output_dir=out)

# %% [markdown]
# The paper attributes a local peak on its $\mathbf u^*$ line to the second burn, "not accounted for in our
# prediction". We rerun the covariance analysis of each $\mathbf u^*$ with its first burn only (the agent then coasts
# off the torus) and compare.

# %%
second_effect = S.informed_range_sigma_km / sk.first_burn_only_range_sigma_km(em, S, nrho.x0)
print(f"sqrt(J_rho) of u* with both burns / first burn only: {second_effect.min():.2f}-{second_effect.max():.2f} "
      f"(median {np.median(second_effect):.2f}); slices where the second burn raises it by > 10 %: "
      f"{np.sum(second_effect > 1.1)} of {S.t_arrival.size}")

# %% [markdown]
# **Reading.** Two things shape the surface. (i) In the linear covariance analysis (perfectly known burns) a burn
# made *while tracking* buys range information, because the known kink breaks the scaling symmetry of angles-only
# relative motion. In this baseline the first burn coincides with the start of tracking, where it only moves the
# initial state, so the information comes from the second burn (the ratio printed above): doing nothing leaves about
# 24 km of range uncertainty, every maneuver of the set from about 9 m to about two hundred metres (both printed in
# section 3), and bigger burns tend to buy more (the negative rank correlation of fuel and $\sqrt{J_\rho}$ printed
# above).
# (ii) Eq. 25 read as an angle is a pure *direction* criterion: as the target phase approaches the agent's own phase
# the first burn shrinks to zero while its direction tends to a limit, and when that limit is well aligned with
# $\pm\mathbf u_y$ the informed maneuver is one of the two smallest non-zero burns of the slice (next to phase 0).
# That is what happens here, so $\mathbf u^*$ avoids the fuel peak (as the paper says) but sits far from the valley
# of range uncertainty (unlike the paper's Fig. 4). Section 5b shows that this answer is a property of the grid.
#
# ### The other reading: tracking before the first burn
#
# If the agent has been tracking the target for `PRE_ARC_H` = 24 h when it makes the first burn ($P_0$ at the start
# of tracking), the first burn is also a kink in a tracked arc, as the MMD rationale assumes (notebook 07: there
# MMD is nearly optimal for short coasts). Same surface, same maneuvers, same $\mathbf u_y$; only the covariance
# analyses change.

# %%
S_pre = sk.station_keeping_surface(em, torus, theta, t_arr, T_BURN_H * HR, T_FINAL_H * HR, agent_theta=AGENT_THETA,
                                   t_track_start=(T_BURN_H - PRE_ARC_H) * HR, progress=False)
st_pre = study.slice_statistics(S_pre)
print(f"tracking from {T_BURN_H - PRE_ARC_H:.0f} h: sqrt(J_rho) {S_pre.range_sigma_km.min() * 1e3:.2f} m to "
      f"{S_pre.range_sigma_km.max():.2f} km (no maneuver {S_pre.range_sigma_km[0, 0]:.2f} km)")
print(f"u*: median percentile in its slice {st_pre.median_percentile:.1f} %, best quartile in "
      f"{st_pre.best_quartile_share:.0f} % of slices, at median phase {st_pre.informed_phase:.3f}; valley at median "
      f"phase {st_pre.valley_phase:.3f}")
fig = figures.map_with_percentiles(S_pre, f"tracking from {PRE_ARC_H:.0f} h before the first burn",
                                   [("tracking from the first burn (baseline)", S, "o-"),
                                    (f"tracking from {PRE_ARC_H:.0f} h before it", S_pre, "s--")],
                                   "where u* ranks, both tracking starts (angle reading)")
_ = plotting.save_figure(fig, "08_map_range_sigma_with_tracking_arc", output_dir=out)

# %%
second_effect_pre = S_pre.informed_range_sigma_km / sk.first_burn_only_range_sigma_km(em, S_pre, nrho.x0)
print(f"tracking from {T_BURN_H - PRE_ARC_H:.0f} h: sqrt(J_rho) of u* with both burns / first burn only "
      f"{second_effect_pre.min():.2f}-{second_effect_pre.max():.2f} (median {np.median(second_effect_pre):.2f}); "
      f"slices where the second burn raises it by > 10 %: {np.sum(second_effect_pre > 1.1)} of {S.t_arrival.size}")

# %% [markdown]
# With 24 h of tracking before the first burn, the first burn carries range information of its own, so the second
# burn's share (the ratio just printed) is no longer the whole of it.
#
# ## 5b · Two readings of Eq. 25, and how finely the set is sampled
#
# The paper does not say how many maneuvers its surface holds, and under the angle reading this matters. Near the
# agent's own phase the first burn to ring angle $\theta_0$ shrinks to zero while its *direction* tends to a limit;
# when that limit is the best-aligned direction of the slice, a finer grid of ring angles always offers a grid point
# closer to the agent, with a smaller burn and the same alignment. As the grid is refined, $\mathbf u^*$ then tends to
# "no maneuver" and its $\sqrt{J_\rho}$ to the no-maneuver value: the rule picks a property of the grid, not of
# the set.
#
# A second reading takes the paper's words literally, "projecting the guidance policy $\pm\mathbf u_y$ onto a
# surface of candidate station keeping maneuvers": rank the first burns by their component along the MMD direction,
# $\mathbf u_y^T\Delta\mathbf v_1/\|\mathbf u_y\|$ (the numerator of Eq. 25, normalised by $\mathbf u_y$ only);
# the largest component along $+\mathbf u_y$ and along $-\mathbf u_y$ are the two candidates and the quick
# covariance analysis decides between them, as before. This reading has a limit as the grid is refined. Below, the
# ring-angle grid is refined on a few arrival slices, for the baseline agent (phase 0) and for the agent a quarter
# turn back (phase 0.75; in the sweep of section 6 the angle reading reaches its lowest percentiles with the agent
# a quarter turn away, at phase 0.25 read at $t_f$ and at phase 0.75 read at arrival), and $\mathbf u^*$ is
# followed under both readings.

# %% [markdown]
# `study.grid_resolution_study` builds, for each ring-angle count and agent phase, a surface with equally spaced
# ring angles on `N_GRID_SLICES` arrival slices, and chooses $\mathbf u^*$ under both readings on the same
# maneuvers and covariance analyses. The table gives medians over the slices: the percentile of $\mathbf u^*$ in
# its slice, its $\sqrt{J_\rho}$ at $t_f$, its fuel, the share of maneuvers using more fuel, and the best
# $\sqrt{J_\rho}$ of the slice (a property of the set, which should settle as the grid is refined). Then:
# $\sqrt{J_\rho}$ of $\mathbf u^*$ over the slice's best and over the edge of the slice's valley, its
# 25th-percentile $\sqrt{J_\rho}$ (medians over slices; section 5c), the percentage of slices where
# $\mathbf u^*$ uses at most the slice's median fuel, the percentage of `N_RANDOM` uninformed picks per slice (target
# ring angles uniform on $[0, 2\pi)$, stream `[SEED, 21]`; section 5c) that $\mathbf u^*$ beats, and the percentage
# of slices where $\mathbf u^*$ is off the fuel peak (outside the most expensive quarter of its slice's maneuvers).
# The closing table uses the u*/valley edge, beats-random and off-fuel-peak columns.

# %%
t_grid = np.linspace(*T_ARRIVAL_H, N_GRID_SLICES) * HR
with open_executor(WORKERS, SCHEDULER) as executor:
    grid = study.grid_resolution_study(em, torus, N_GRID, t_grid, T_BURN_H * HR, T_FINAL_H * HR,
                                       rng=np.random.default_rng([SEED, 21]), n_random=N_RANDOM, executor=executor)
print(f"{N_GRID_SLICES} arrival slices from {T_ARRIVAL_H[0]:+.0f} h to {T_ARRIVAL_H[1]:+.0f} h; medians over the slices")
print(grid.format())
_ = plotting.save_figure(figures.grid_resolution(grid, S.range_sigma_km[0, 0] * 1e3), "08_eq25_readings_vs_grid",
                         output_dir=out)

# %% [markdown]
# The projection reading on the full surface of sections 3-5 (same maneuvers, same covariance analyses; only the
# choice of $\mathbf u^*$ changes):

# %%
st_proj = study.slice_statistics(S_proj)
second_effect_proj = S_proj.informed_range_sigma_km / sk.first_burn_only_range_sigma_km(em, S_proj, nrho.x0)
print(f"projection reading: u* at median phase {st_proj.informed_phase:.3f} (valley at {st.valley_phase:.3f}); median "
      f"percentile {st_proj.median_percentile:.1f} %, best quartile in {st_proj.best_quartile_share:.0f} % of slices; "
      f"sqrt(J_rho) {np.median(S_proj.informed_range_sigma_km) * 1e3:.1f} m (best of slice "
      f"{np.median(S_proj.best_range_sigma_km) * 1e3:.1f} m)")
print(f"fuel: u* {np.median(S_proj.informed_fuel_m_s):.2f} m/s (median over slices), "
      f"{np.median(st_proj.fuel_percentile):.1f} % of maneuvers cost more; at or below the slice's median fuel in "
      f"{st_proj.below_median_fuel * 100:.0f} % of slices, outside its most expensive quarter in "
      f"{st_proj.outside_fuel_peak_share:.0f} %; largest fuel of the set {S.fuel_m_s.max():.2f} m/s")
print(f"second burn: sqrt(J_rho) of u* with both burns / first burn only {second_effect_proj.min():.3f}-"
      f"{second_effect_proj.max():.3f}")
fig = figures.map_with_percentiles(S_proj, "projection reading: u* on the range map",
                                   [("angle reading", S, "o-"), ("projection reading", S_proj, "s--")],
                                   "where u* ranks, both readings", reading="projection")
_ = plotting.save_figure(fig, "08_projection_reading", output_dir=out)

# %% [markdown]
# ### The "single point raised by a small local peak"
#
# The paper sees one point of its $\mathbf u^*$ line raised above its neighbours in Fig. 4 and blames the second
# burn. `study.slice_statistics` lists the *raised slices* of a line: interior arrival slices whose
# $\sqrt{J_\rho}$ of $\mathbf u^*$ exceeds that of both neighbouring slices by more than 10 %. Below, for both
# readings: the raised slices, and for each the neighbours' values, the phase of $\mathbf u^*$ there and next to
# it (a jump means another ring angle was picked), and the ratio of $\sqrt{J_\rho}$ with both burns to the first
# burn only (above 1 would mean the second burn raised it, the paper's explanation).

# %%
for name, surf, slice_st, effect in (("angle", S, st, second_effect),
                                    ("projection", S_proj, st_proj, second_effect_proj)):
    sig_u = surf.informed_range_sigma_km * 1e3
    print(f"{name} reading: {len(slice_st.raised_slices)} raised slice(s) of {surf.t_arrival.size}")
    for j in slice_st.raised_slices:
        print(f"   arrival {surf.t_arrival_hours[j]:+.1f} h: {sig_u[j]:.1f} m against {sig_u[j - 1]:.1f} / "
              f"{sig_u[j + 1]:.1f} m; u* phase {surf.phase[surf.informed[j]]:.3f} (neighbours "
              f"{surf.phase[surf.informed[j - 1]]:.3f} / {surf.phase[surf.informed[j + 1]]:.3f}); both burns / first "
              f"only {effect[j]:.4f}")

# %% [markdown]
# Where the projection line has its raised point (in the full run one slice, 6.5 h after apoapsis), the pick jumps
# to another ring angle (phase 0.800 against 0.750 and 0.725 in the neighbouring slices): the slice's most aligned
# burn changes, and the one chosen there is a worse maneuver
# than its neighbours'. The second burn is not the cause: without it the same maneuver is far worse (the ratio
# printed is well below 1, as in every slice, because in this baseline the second burn is where the range
# information comes from). So the paper's picture, a valley line with one raised point, is what the projection
# reading gives on this sampling; the paper's explanation of the point is not.
#
# How many points of a line are raised depends on where the line is sampled, and the paper does not say at which
# arrival times its surface was computed. Below, the same arrival window is sampled with each number of slices in
# `N_RAISED` (the surface of section 3 is reused where the number is `N_SURF`; the others are new surfaces on the same
# ring angles, so only the arrival sampling changes), and the raised points of the projection line are counted at
# each. Printed per sampling: the spacing of the arrival times, the number of raised points, and where they are.

# %%
raised_by_n = {}  # slices over the arrival window -> (spacing h, projection surface at that sampling, raised slices)
for n_t in N_RAISED:
    surf_n = S_proj if n_t == N_SURF else sk.station_keeping_surface(
        em, torus, theta, np.linspace(*T_ARRIVAL_H, n_t) * HR, T_BURN_H * HR, T_FINAL_H * HR,
        agent_theta=AGENT_THETA, progress=False).reselect("projection")
    raised_by_n[n_t] = ((T_ARRIVAL_H[1] - T_ARRIVAL_H[0]) / (n_t - 1), surf_n,
                        study.slice_statistics(surf_n).raised_slices)
    spacing, _, r_n = raised_by_n[n_t]
    print(f"{n_t:3d} arrival slices ({spacing:.2f} h apart): {len(r_n)} raised point(s) of the projection line"
          + "".join(f"; {surf_n.t_arrival_hours[j]:+.2f} h, {surf_n.informed_range_sigma_km[j] * 1e3:.1f} m against "
                    f"{surf_n.informed_range_sigma_km[j - 1] * 1e3:.1f} / {surf_n.informed_range_sigma_km[j + 1] * 1e3:.1f}"
                    f" m, u* phase {surf_n.phase[surf_n.informed[j]]:.3f}" for j in r_n))
raised_counts = np.array([len(v[2]) for v in raised_by_n.values()])

# %% [markdown]
# In the full run the raised point is narrow: every sampling with 32 slices or more (0.77 h apart or closer) shows
# exactly one raised point, always between +6.4 and +6.7 h where $\mathbf u^*$ jumps to another ring angle, and never
# two; the coarser samplings (16 to 24 slices, 1.04 h apart or more) step over it and show none. "A single raised
# point" is therefore what this reading gives whenever the arrival times are about 45 minutes apart or closer, and
# nothing when they are an hour apart; the paper's sampling is not given, so the closing table judges the count at
# every sampling (it must be 1 at each).

# %% [markdown]
# **Reading.** The angle reading is what Eq. 25's symbols say (a cosine), but on this set it has no limit: refining
# the grid drives $\mathbf u^*$ towards the agent's own phase and, for the baseline agent, its range uncertainty
# up towards the no-maneuver value (the table above, full run: the median $\sqrt{J_\rho}$ of $\mathbf u^*$ grows
# from 24 m with 16 ring angles to about 600 m with 320 and 640, not quite monotonically at the last step).
# Its percentile in the slice, and the factor by which it beats doing nothing, are therefore set by the grid
# spacing, which the paper does not give. The projection reading does not move with the
# grid. For the baseline agent it puts $\mathbf u^*$ in the valley (a few percent, next to the slice's best
# maneuver on the map), which is what the paper's Fig. 4 shows; for the agent a quarter turn back it ranks it near
# the 36th percentile, better than a random pick but outside the best quartile. It gets there by choosing a large
# burn along $\pm\mathbf u_y$ (about 5.5 m/s of the 0-18 m/s range), so it pays for the information with fuel near
# the middle of the slice's distribution. We let the paper's Fig. 4 decide between the readings; because that choice
# is made while looking at the paper's figure, the valley row of the projection reading is *consistent (tuned)*, not
# reproduced. Both readings keep $\mathbf u^*$ off the fuel peak (outside the most expensive quarter of its slice),
# the angle reading with the smallest burns, the projection reading near the median fuel; only the projection
# reading adds the valley.

# %% [markdown]
# ## 5c · Does $\mathbf u^*$ improve range knowledge? Two baselines that can fail
#
# The paper concludes that the informed maneuver "significantly improves" range knowledge. Against doing nothing
# that cannot fail here: in the linear covariance analysis every maneuver of the set cuts $\sqrt{J_\rho}$ from
# about 24 km to between about 9 m and 200 m (section 3), so "better than no maneuver" says nothing about the
# choice.
# Two comparisons that a poor choice does fail:
#
# - **Against the valley of its slice:** the paper's words are "fall in the valley of range uncertainty", so the
#   yardstick is the surface itself, not a factor of ours. The valley of a slice is its best quartile of maneuvers
#   (the chapter's one reading of the word, that of the valley rows), and its *edge* the slice's 25th-percentile
#   $\sqrt{J_\rho}$ (`study.valley_edge_ratio`). The row divides $\sqrt{J_\rho}$ of $\mathbf u^*$ by that edge
#   and asks for the median over the slices to be at most 1, at every ring-angle grid. Printed next to it: the
#   ratio to the slice's best, and where the edge sits above the best (until 2026-11-26 the row asked for
#   $\mathbf u^*$ within 1.5 times the best, a number of ours; in the full run the edge is tighter than that in 32
#   of the 40 slices).
# - **Against an uninformed pick:** the station keeping the informed choice replaces picks a point of the torus
#   without regard to information. `study.random_pick_study` draws `N_RANDOM` target ring angles uniformly on
#   $[0, 2\pi)$ (stream `[SEED, 20]`; the same angles for every arrival slice; continuous, so the baseline does not
#   depend on the ring-angle grid), flies the two-burn transfer to each (its direction and size follow from the
#   point drawn) and runs its covariance analysis. The criterion: $\mathbf u^*$ beats at least 75 % of the random
#   picks, three in four over all (slice, pick) pairs. A pick at random beats half of them on average.
#
# The grid study of section 5b applies both comparisons at every ring-angle grid (its own random picks, stream
# `[SEED, 21]`, on its slices), because the angle reading's answer depends on the grid.

# %%
rand = study.random_pick_study(em, torus, t_arr, T_BURN_H * HR, T_FINAL_H * HR, np.random.default_rng([SEED, 20]),
                               n_draws=N_RANDOM, agent_theta=AGENT_THETA)
print(f"{N_RANDOM} random picks per slice: sqrt(J_rho) {rand.range_sigma_km.min() * 1e3:.1f}-"
      f"{rand.range_sigma_km.max() * 1e3:.0f} m (median {np.median(rand.range_sigma_km) * 1e3:.1f} m), fuel "
      f"{rand.fuel_m_s.min():.2f}-{rand.fuel_m_s.max():.2f} m/s")
edge_best = np.percentile(S.range_sigma_km, study.VALLEY_PERCENT, axis=1) / S.best_range_sigma_km  # same maneuvers
print(f"valley edge ({study.VALLEY_PERCENT:.0f}th-percentile sqrt(J_rho) of a slice) / slice best: median "
      f"{np.median(edge_best):.2f} ({edge_best.min():.2f}-{edge_best.max():.2f} over the slices)")
vs_best, vs_edge, vs_rand = {}, {}, {}
for name, surf in (("angle", S), ("projection", S_proj)):
    vs_best[name] = float(np.median(surf.informed_range_sigma_km / surf.best_range_sigma_km))
    vs_edge[name] = float(np.median(study.valley_edge_ratio(surf)))
    vs_rand[name] = rand.beaten_percent(surf)
    print(f"{name} reading: u* / valley edge {vs_edge[name]:.2f}, u* / slice best {vs_best[name]:.2f} (medians over "
          f"slices); u* beats {vs_rand[name]:.0f} % of the random picks; at every grid of section 5b "
          f"({'/'.join(str(n) for n in N_GRID)} ring angles): u* / valley edge "
          f"{'/'.join(f'{v:.2f}' for v in grid.series(0.0, name, 'ratio_valley'))}, u* / best "
          f"{'/'.join(f'{v:.2f}' for v in grid.series(0.0, name, 'ratio_best'))}, beats "
          f"{'/'.join(f'{v:.0f}' for v in grid.series(0.0, name, 'beats_random'))} % of random picks")
print(f"for scale: random picks better than doing nothing ({S.range_sigma_km[0, 0] * 1e3:.0f} m): "
      f"{np.mean(rand.range_sigma_km < S.range_sigma_km[0, 0]) * 100:.0f} %")

# %% [markdown]
# **Reading.** The angle reading's $\mathbf u^*$ beats about a quarter of the random picks on the coarsest grid
# (16 ring angles, full run) and almost none on the finer ones (it tends to no maneuver), and it sits ever farther
# above its slice's valley as the grid is refined; the projection reading's $\mathbf u^*$ is within a few percent of
# the slice's best, below the valley's edge, and beats about nine
# random picks in ten or more, on every grid. So "significantly improves" holds in a form that could have failed
# for the projection reading (tuned, since that reading was chosen looking at the paper's Fig. 4), not for the
# angle reading.

# %% [markdown]
# ## 6 · In which regime does the "valley" claim hold? A sweep over the unstated inputs
#
# Our baseline reading puts $\mathbf u^*$ where it is printed above. The paper's Figs. 3-5 do not give the burn
# epoch, the arrival window, the agent's starting phase or where $J_\rho$ is read, so we sweep them: the first-burn
# lead time before the arrival window, the agent's initial ring angle, whether tracking starts at the first burn or
# `PRE_ARC_H` before it, and $\sqrt{J_\rho}$ read at $t_f$ (common
# final time) or at each maneuver's own arrival. For each setting: the median percentile of $\mathbf u^*$ within its
# slices and the share of slices where it is in the best quartile, under both readings of Eq. 25, on the ring-angle
# grid of sections 3-5 (`N_SURF` ring angles, so that the angle reading is compared at the same spacing) and
# `N_SWEEP` arrival times.

# %% [markdown]
# `study.scenario_sweep` computes one surface per setting (24 settings: two tracking starts, three burn leads,
# four agent ring angles). Its table gives, for the angle reading, the median percentile and the share of
# best-quartile slices with $\sqrt{J_\rho}$ read at $t_f$ and at each maneuver's arrival, and the share of
# maneuvers using more fuel than $\mathbf u^*$; then the same percentile and fuel share for the projection
# reading. Below it, the MMD horizon at $t_f$ and `study.offset_study`: the agent displaced from the torus at the
# first burn by 1, 10 and 50 km, with a velocity offset in the ring's velocity-to-position ratio (three random
# directions each, from the stream `[SEED, 8]`).

# %%
t_arr_s = np.linspace(*T_ARRIVAL_H, N_SWEEP) * HR
with open_executor(WORKERS, SCHEDULER) as executor:
    sweep = study.scenario_sweep(em, torus, theta, t_arr_s, T_ARRIVAL_H[0], T_FINAL_H * HR, pre_arcs_h=(0.0, PRE_ARC_H),
                                 leads_h=SWEEP_LEADS_H, agent_thetas=tuple(2 * np.pi * p for p in SWEEP_AGENT_PHASES),
                                 executor=executor)
    offsets = study.offset_study(em, torus, theta, t_arr_s, T_BURN_H * HR, T_FINAL_H * HR,
                                 np.random.default_rng([SEED, 8]), distances_km=OFFSET_KM, agent_theta=AGENT_THETA,
                                 executor=executor)
print(study.format_sweep(sweep))
n_valley_angle, n_valley_proj = sum(r.pct_tf < 25 for r in sweep), sum(r.pct_proj < 25 for r in sweep)
print(f"settings with the median percentile below 25 % (the valley tolerance): angle reading {n_valley_angle} of "
      f"{len(sweep)}, projection reading {n_valley_proj} of {len(sweep)}")
# the projection reading by agent phase: at phase 0 or 1/2, and a quarter turn away (1/4 or 3/4)
at_phase = lambda phases: [r for r in sweep if np.any(np.isclose(r.agent_phase, phases))]
sw_valley, sw_quarter = at_phase(PROJECTION_VALLEY_PHASES), at_phase(QUARTER_TURN_PHASES)
for label, rows in (("0 or 1/2", sw_valley), ("1/4 or 3/4", sw_quarter)):
    if rows:
        print(f"projection reading, agent phase {label}: median percentile {min(r.pct_proj for r in rows):.0f}-"
              f"{max(r.pct_proj for r in rows):.0f} %, in the valley in {sum(r.pct_proj <= 25 for r in rows)} of "
              f"{len(rows)} settings")
s_h = sk.station_keeping_surface(em, torus, theta, t_arr_s, T_BURN_H * HR, T_FINAL_H * HR, agent_theta=AGENT_THETA,
                                 mmd_horizon="final", progress=False)
pct_horizon = np.median(s_h.informed_percentile)
print(f"\nMMD coast to t_f instead of the arrival (baseline otherwise): median percentile {pct_horizon:.1f} %, best "
      f"quartile in {np.mean(s_h.informed_percentile < 25) * 100:.0f} % of slices")
for d_km, vals in offsets.items():
    print(f"agent {d_km:4.0f} km / {d_km * torus.velocity_size_mps / torus.size_km * 1e3:4.0f} mm/s off the torus: median "
          f"percentile of u* {', '.join(f'{v:.0f}' for v in vals)} % (3 random offset directions)")
pct_offset_all = np.concatenate([v for d, v in offsets.items() if d > 0])
best_setting = min(sweep, key=lambda r: r.pct_tf)
print(f"\nmost favourable setting for the angle reading: pre-arc {best_setting.pre_h:.0f} h, lead "
      f"{best_setting.lead_h:.0f} h, agent phase {best_setting.agent_phase:.2f}: median percentile "
      f"{best_setting.pct_tf:.1f} %")

# %% [markdown]
# The last unstated input is the paper's one number, "the average range ... is 215 km". Our member matches the
# torus average over ring angle and one period; the same member has a different mean over the apolune ring alone
# and a different RMS (section 1). Members chosen so that those two readings equal 215 km instead (each a torus
# solved again by continuation, the costliest check of quick mode, where `MEMBER_CHECK` skips it):

# %%
member_check = (study.member_study(em, nrho, theta, t_arr, T_BURN_H * HR, T_FINAL_H * HR, target_km=MEAN_RANGE_KM,
                                   agent_theta=AGENT_THETA) if MEMBER_CHECK else {})
member_note = lambda reading: (f"members matching {MEAN_RANGE_KM:g} km as ring mean / RMS: "
                               f"{member_check['ring_mean_km'][reading][0]:.0f} / {member_check['rms_km'][reading][0]:.0f} %"
                               if member_check else "other members not solved (MEMBER_CHECK = False)")
for stat, row in member_check.items():
    print(f"member with {stat[:-3]} = {MEAN_RANGE_KM:g} km: torus mean {row['mean_km']:.0f} km, ring size {row['size_km']:.0f} km; "
          f"u* median percentile angle {row['angle'][0]:.1f} % / projection {row['projection'][0]:.1f} %; "
          f"at or below median fuel in {row['angle'][1]:.0f} % / {row['projection'][1]:.0f} % of slices")

# %% [markdown]
# **Reading.** Under the angle reading, with $\sqrt{J_\rho}$ read at $t_f$ as in the rows of the closing table, the
# informed maneuver is in the valley in none of the settings (the count printed above): its median percentile stays
# far above the best quartile, even with the agent a quarter turn away on the ring or with the tracking arc starting
# before the first burn. Read at each maneuver's own arrival instead, it does reach the best quartile in two
# settings of the full run (tracking from the first burn, 48-h lead, agent at phase 0.25 or 0.75: 22 % and 14 %), the
# only regime found where the angle reading gives the valley. Within a slice that comparison is still fair (its
# maneuvers arrive together), but the paper calls its surface the "final range uncertainties", which we read as
# $t_f$. Neither the MMD horizon nor an agent that has
# drifted off the torus (so that no maneuver of the set is near zero and the angle cannot simply pick the smallest
# burn) changes the verdict: a drift moves $\mathbf u^*$ towards the middle of the distribution, i.e. towards what a
# random pick achieves, not into the valley. The member chosen by another reading of "average range" changes nothing
# either. Under the projection reading the verdict depends on one unstated input, the agent's own ring angle: with
# the agent at phase 0 or 0.5, $\mathbf u^*$ is in the valley at every burn lead and tracking start; a quarter turn
# away (0.25 or 0.75) it sits between about the 30th and 45th percentile. So the valley of the paper's Fig. 4 is reached by the
# projection reading for half of the agent phases, and by the angle reading for none at $t_f$; the angle reading
# always avoids the fuel peak, and the projection reading stays near the median fuel, well off the peak, though
# rarely below the median. The two valley rows of the closing table carry these numbers.
#
# ## 7 · Beyond the paper: a full-filter Monte Carlo with execution errors
#
# The paper's covariance analysis assumes perfectly executed burns and a filter that does not diverge; its
# conclusions list both as future work. Here an iterated EKF (`cislunar.papers.greaves_scheeres_2023.station_keeping.filter_trial`;
# 10 relinearisations per update, because a single-linearisation EKF is inconsistent at the start of an
# angles-only track with 20 km of position uncertainty at a few hundred km range) processes simulated measurements
# of the true trajectories, including execution errors of **1 mm/s plus 1 % of the burn (1 sigma per axis)** that
# the filter knows statistically. Four policies for the arrival slice closest to apoapsis: the informed maneuver
# $\mathbf u^*$ under each reading of Eq. 25, an *uninformed* choice (a ring angle drawn uniformly at random in each
# trial), and doing nothing; the maneuvers with perfect burns, with the nominal execution errors and with ten times
# smaller ones (0.1 mm/s + 0.1 %), to see what execution accuracy the information gain needs. Doing nothing makes no
# burn, so it has no execution error and is run once. Consistency: mean NEES of the 12-dimensional SSAT state at $t_f$ against
# its 95 % chi-square band; accuracy: RMS of the achieved range error along the line of sight at $t_f$.

# %% [markdown]
# `study.filter_monte_carlo` builds one filter scenario per policy and execution level from the surface (the burns
# of the chosen maneuver, the target at the start of tracking, the initial covariance of notebook 07) and runs
# `N_TRIALS` trials of each with the trial streams `[SEED, k]`, so that the numbers do not depend on the process
# pool. The printed table gives per policy and level: failed runs, the mean NEES at $t_f$
# ($\mathbf e^T P^{-1}\mathbf e$ of the 12-dimensional SSAT state, computed by the package's one NEES), the RMS of
# the achieved range error, the filter's RMS 1-sigma, and the covariance analysis' prediction with perfect burns
# (for the uninformed choice, the RMS over the slice's maneuvers).

# %%
INF, INFP, UNI, NONE = study.POLICIES
j_mc = int(np.argmin(np.abs(S.t_arrival_hours)))
for name, idx in (("informed u*, angle reading", S.informed[j_mc]), ("informed u*, projection", S_proj.informed[j_mc]),
                  ("largest uninformed pick", int(np.argmax(S.dv1_m_s[j_mc])))):
    d1, d2 = S.dv1_m_s[j_mc, idx], S.dv2_m_s[j_mc, idx]
    e1, e2 = (1e3 * sk.execution_sigma(np.array([d, 0.0, 0.0]), EXEC_ABS_M_S, EXEC_REL) for d in (d1, d2))
    print(f"{name}: burns {d1:.3f} + {d2:.3f} m/s; nominal execution error (1 sigma per axis) {e1:.1f} and {e2:.1f} mm/s")
with open_executor(WORKERS, SCHEDULER) as executor:
    mcs = study.filter_monte_carlo(em, S, S_proj, nrho.x0, n_trials=N_TRIALS, seed=SEED, exec_abs_m_s=EXEC_ABS_M_S,
                                   exec_rel=EXEC_REL, executor=executor)
summary, (lo, hi) = mcs.summary, mcs.band
print(mcs.format())

# %% [markdown]
# **Reading.** With perfectly executed burns the filter comes close to what the covariance analysis predicts (in the
# full run, 40 trials: RMS error about 15 % above the predicted $\sqrt{J_\rho}$ for both informed choices, mean
# NEES inside the band near its upper edge: printed above), so the paper's linear analysis is the accuracy a filter that does not diverge
# approaches (its "upper bound on filter performance", a lower bound on the error). Execution errors of 1 mm/s + 1 % (a few mm/s per axis for the
# sub-metre-per-second burns of the angle reading's $\mathbf u^*$, a few cm/s for the larger burns of the projection
# reading and the large uninformed picks: printed above the table) are unknown velocity kicks of the agent and wipe out most
# of the maneuver's range information: the range error grows to kilometres, and which maneuver was chosen matters
# much less than how well it was executed, which quantifies the paper's remark that accelerometers would be needed.
# With perfect burns, the ratios printed below compare the informed choices with an uninformed one: in the full run
# (40 trials per policy) the angle reading's $\mathbf u^*$ is clearly *worse* than a random pick, in line with
# section 5 (it is one of the smallest maneuvers of its slice, and in this linear-information regime bigger burns buy
# more), while the projection reading's is clearly better, as its place in the valley predicts; quick mode's few
# trials are too few to decide these comparisons. Without any maneuver the range stays nearly unobservable and the
# iterated EKF *diverges*: its mean NEES is far above the band and its range error ends larger than the 28 km range
# 1-sigma of the prior (printed above), while it believes it knows the range to about 20 km. With any maneuver the
# mean NEES is back inside the band or just above it (the uninformed pick with nominal execution errors).
#
# In the figure each marker is the RMS of the achieved range error over the runs of one policy and execution level,
# the black tick at the same position the filter's own 1-sigma (where they coincide the filter is honest), and the dotted line
# the covariance analysis with perfect burns (for the uninformed choice, the RMS over the slice's maneuvers). Doing
# nothing has no burn to execute, so it is run once, with "perfect" (absent) burns.

# %%
ratio_pu, ratio_ppu = mcs.ratio(INF), mcs.ratio(INFP)
for name, ratio in (("angle", ratio_pu), ("projection", ratio_ppu)):
    print(f"perfect burns: RMS range error of the informed choice ({name} reading) / the uninformed one = "
          f"{ratio:.2f} ({'informed better' if ratio < 1 else 'uninformed better'})")
_ = plotting.save_figure(figures.monte_carlo_range_errors(mcs), "08_monte_carlo_range_errors", output_dir=out)

# %% [markdown]
# ## 8 · Paper vs reproduction

# %% [markdown]
# Every row below is a claim declared, with its criterion, in
# `cislunar.papers.greaves_scheeres_2023.claims.informed_station_keeping` before anything here is compared; the
# status word is computed from the criterion, never typed. The criteria, in the order of the rows:
#
# - **The 215 km member** is selected by that number, so the row is *derived*; its criterion (within 0.01 km) only
#   checks that the selection converged. Ring size, rotation number and range extremes are *not in paper*.
# - **The two-burn transfer** must reach the torus point to $10^{-9}$ LU (0.4 mm), a check the paper does not
#   make.
# - **The valley (Fig. 4).** The median over the arrival slices of the percentile of $\mathbf u^*$ within its slice
#   (the share of the slice's maneuvers with a smaller $\sqrt{J_\rho}$ at $t_f$) must be at most 25 %, the best
#   quartile; a random pick sits at 50 % on average. The angle reading of Eq. 25 is the independent prediction; the
#   projection reading was adopted while looking at the paper's Fig. 4, so its rows are *tuned*. The projection
#   reading holds only for some agent phases (section 6), so it has two rows that name the condition: the agent at
#   ring phase 0 or 1/2 (the worst of the baseline and the sweep settings there) and a quarter turn away (the best
#   sweep setting at phase 1/4 or 3/4).
# - **The fuel peak (Fig. 5).** The paper asks "if the guidance policy selects the largest maneuvers" and answers
#   that it "avoids the peak fuel cost ... does not simply select large maneuvers". We read "the peak" as the most
#   expensive quarter of a slice's maneuvers (the mirror of the valley's best quartile): $\mathbf u^*$ must be
#   outside it (at least 25 % of the slice's maneuvers cost more) in at least 90 % of the slices, on the surface of
#   section 3 and at every ring-angle grid of section 5b. Until 2026-11-26 the row asked for more than the paper
#   says (at or below the slice's median fuel, with a fuel that settles as the grid is refined), which the projection
#   reading failed while far below the peak and the angle reading failed because its pick tends to no maneuver. The
#   criterion was loosened after those values were seen and the quartile is our reading, so both fuel rows are
#   *tuned*; the note of each row gives the least share of maneuvers costing more than $\mathbf u^*$, which shows
#   how far the verdict is from the quartile.
# - **The second burn's local peak.** The paper says the second burn raises $\sqrt{J_\rho}$ at one point of the
#   $\mathbf u^*$ line; the criterion asks for a ratio (both burns over first burn only) above 1 in some slice. The
#   paper's line is the line of its Fig. 4, which the chapter identifies with the projection reading, so the row is
#   judged on that reading's $\mathbf u^*$ (until 2026-11-26 on the angle reading's); the angle reading's ratio is
#   measured as well and printed in the row, with its own verdict.
#   The raised point itself is tested on the projection line: exactly one slice whose $\sqrt{J_\rho}$ exceeds both
#   neighbours' by more than 10 %, at every arrival sampling of `N_RAISED` (how many points are raised depends on
#   the sampling, which the paper does not give; until 2026-11-26 only the `N_SURF` slices of section 3 were
#   counted).
# - **"Significantly improves"**, against baselines that can fail (section 5c): $\sqrt{J_\rho}$ of
#   $\mathbf u^*$ at most the edge of its slice's valley, the slice's 25th-percentile $\sqrt{J_\rho}$ (median over
#   slices; until 2026-11-26: at most 1.5 times the slice's best, a number of ours, where the paper's words "in the
#   valley" give the surface's own yardstick), and $\mathbf u^*$ better than at least
#   75 % of uninformed picks (ring angles uniform on $[0, 2\pi)$, seeded); both at every ring-angle grid of section
#   5b as well (the worst grid is compared). Against doing nothing every maneuver passes, so that comparison is
#   printed in section 5c but is not a row.
# - **The full-filter rows** are beyond the paper (its future work). The NEES row, the 10x-smaller-errors row and
#   the no-maneuver row ask whether the filter is consistent at $t_f$: the two-sided chi-square tail probability
#   of each policy's mean NEES (12 states times the runs that did not fail, `study.nees_p_value`) must be at least
#   0.05, i.e. every mean NEES inside its 95 % band (10.5-13.6 for 40 runs), fixed by the run count and the state
#   dimension alone (until 2026-11-26 these rows carried no criterion and could not fail). Without a maneuver the
#   filter is expected to fail it, and does (section 7): the paper's covariance analysis assumes a filter "that does
#   not diverge". The RMS row compares policies and only reports.
#
# The cell first gathers what the rows compare: `fuel_test` applies the Fig. 5 criterion to one reading (the
# baseline surface and every grid of section 5b); `worst_edge` (the ratio to the valley's edge) and
# `worst_rand` take the least favourable of the baseline surface and the grids for the two "improves" comparisons
# of section 5c; `second_raises` applies `study.second_burn_raises` to the ratio of each reading (the projection
# reading's is judged, the angle reading's printed with its own verdict); `p_exec`, `p_small` and `p_none` are the
# smallest chi-square tail probabilities of the mean NEES over the policies of the three full-filter rows that carry
# the consistency criterion (`mcs.p_value`, runs that did not fail only); `raised` lists the raised slices of the projection line
# on the surface of section 3, each with its neighbours, the phases picked there and the second burn's ratio, and
# `raised_reason` says at which samplings of `N_RAISED` the count is not 1; the quarter-turn row is built only
# when the sweep of section 6 has agent phases 1/4 or 3/4, and the projection row at phase 0 or 1/2 takes the worst
# of the baseline and the sweep settings at those phases.

# %%
ia, ipa, ua = summary[(INF, "exec")], summary[(INFP, "exec")], summary[(UNI, "exec")]
ip, ipp, nm = summary[(INF, "perfect")], summary[(INFP, "perfect")], summary[(NONE, "perfect")]
isml, ispm, usml = summary[(INF, "small")], summary[(INFP, "small")], summary[(UNI, "small")]
grids = "/".join(str(n) for n in N_GRID)
series = lambda crit, key, f: "/".join(f.format(v) for v in grid.series(0.0, crit, key))
none_km = S.range_sigma_km[0, 0]
sweep_range = lambda key: f"{min(getattr(r, key) for r in sweep):.0f}-{max(getattr(r, key) for r in sweep):.0f}"


def fuel_test(reading, stats):
    """The Fig. 5 criterion: u* outside the most expensive quarter of its slice's maneuvers in >= 90 % of the slices,
    on this surface and at every grid of section 5b.  Returns the verdict, the shares at the grids (percent of
    slices) and the median fuel of u* at the grids (m/s)."""
    shares, fuel = grid.series(0.0, reading, "outside_peak_share"), grid.series(0.0, reading, "fuel_m_s")
    return bool(stats.outside_fuel_peak_share >= 90 and np.all(shares >= 90)), shares, fuel


fuel_ok = {"angle": fuel_test("angle", st), "projection": fuel_test("projection", st_proj)}
worst_edge = {name: max(vs_edge[name], *grid.series(0.0, name, "ratio_valley")) for name in vs_edge}
second_raises = {"angle": study.second_burn_raises(second_effect),
                 "projection": study.second_burn_raises(second_effect_proj)}
# the full-filter rows: the smallest chi-square tail probability of the mean NEES over the row's policies
p_exec = min(mcs.p_value(INF, "exec"), mcs.p_value(INFP, "exec"))
p_small = min(mcs.p_value(pol, "small") for pol in (INF, INFP, UNI))
p_none = mcs.p_value(NONE, "perfect")
worst_rand = {name: min(vs_rand[name], *grid.series(0.0, name, "beats_random")) for name in vs_rand}
raised = st_proj.raised_slices
raised_txt = "; ".join(f"{S_proj.t_arrival_hours[j]:+.1f} h: {S_proj.informed_range_sigma_km[j] * 1e3:.1f} m vs "
                       f"{S_proj.informed_range_sigma_km[j - 1] * 1e3:.1f} / {S_proj.informed_range_sigma_km[j + 1] * 1e3:.1f} m, "
                       f"u* phase {S_proj.phase[S_proj.informed[j]]:.3f} (neighbours "
                       f"{S_proj.phase[S_proj.informed[j - 1]]:.3f} / {S_proj.phase[S_proj.informed[j + 1]]:.3f}), both "
                       f"burns / first only {second_effect_proj[j]:.4f}" for j in raised)
raised_ns = "/".join(str(n) for n in raised_by_n)
ones = [(n, sp) for n, (sp, _, r_n) in raised_by_n.items() if len(r_n) == 1]
raised_reason = ("the number of raised points depends on the arrival sampling, which the paper does not give: "
                 + (f"exactly one with {'/'.join(str(n) for n, _ in ones)} slices over the window "
                    f"({min(sp for _, sp in ones):.2f}-{max(sp for _, sp in ones):.2f} h apart); " if ones else "")
                 + "; ".join(f"{len(r_n)} with {n} ({sp:.2f} h apart)" for n, (sp, _, r_n) in raised_by_n.items()
                             if len(r_n) != 1))
quarter_rows = []  # the projection reading a quarter turn away (absent if the sweep has no such agent phase)
if sw_quarter:
    best_q = min(sw_quarter, key=lambda r: r.pct_proj)
    quarter_rows.append(CLAIMS["valley_projection_quarter"].judge(best_q.pct_proj,
        shown=f"{best_q.pct_proj:.0f} % (best of {len(sw_quarter)} settings; worst "
              f"{max(r.pct_proj for r in sw_quarter):.0f} %)",
        note=f"best setting: tracking from {best_q.pre_h:.0f} h before the first burn, lead {best_q.lead_h:.0f} h, agent "
             f"phase {best_q.agent_phase:.2f}; in the valley in {sum(r.pct_proj <= 25 for r in sw_quarter)} of "
             f"{len(sw_quarter)} settings at agent phase 1/4 or 3/4 (section 6)"))
valley_proj_worst = max([st_proj.median_percentile] + [r.pct_proj for r in sw_valley])
table.add(
    CLAIMS["mean_range"].judge(stats.mean_km, shown=f"{stats.mean_km:.2f} km",
        note=f"the {MEAN_RANGE_KM:g} km was used to SELECT the member (torus average over ring angle and one period); an input, not a "
             f"prediction. Same member read as apolune-ring mean: {stats.ring_mean_km:.1f} km, RMS {stats.rms_km:.1f} km"),
    CLAIMS["ring_size"].judge(torus.size_km, shown=f"{torus.size_km:.2f} km / {torus.velocity_size_mps:.3f} m/s"),
    CLAIMS["rotation_number"].judge(torus.rho, shown=f"{torus.rho:.6f}"),
    CLAIMS["range_extremes"].judge(stats.max_km, shown=f"{stats.min_km:.1f} / {stats.max_km:.1f} km"),
    CLAIMS["fig2"].judge("08_fig2_torus_and_nrho", note="closed viewing geometry: the torus surrounds the NRHO arc"),
    CLAIMS["transfer_miss"].judge(S.transfer_miss.max(), shown=f"{S.transfer_miss.max():.1e} LU",
                                  note="test requires 1e-9 LU in position and velocity"),
    CLAIMS["fig3_burns"].judge(S.fuel_m_s.max(), shown=f"{S.dv1_m_s.min():.2f}-{S.dv1_m_s.max():.2f} / "
                                                       f"{S.dv2_m_s.min():.2f}-{S.dv2_m_s.max():.2f} m/s"),
    CLAIMS["valley_angle"].judge(st.median_percentile,
        shown=f"{st.median_percentile:.0f} % (best quartile in {st.best_quartile_share:.0f} % of slices)",
        note=f"With 24 h of tracking before the first burn: {st_pre.median_percentile:.0f} % (best quartile in "
             f"{st_pre.best_quartile_share:.0f} % of slices). Sweep (section 6) over tracking start, burn lead 12-48 h, "
             f"agent phase and read-out time: median percentile {sweep_range('pct_tf')} % at t_f, "
             f"{sweep_range('pct_arr')} % at arrival. Valley at phase {st.valley_phase:.3f}, u* at {st.informed_phase:.3f} "
             f"(next to the agent's own phase 0, the smallest burns); rank correlation of fuel and sqrt(J_rho) within "
             f"slices {st.rank_correlation:.2f}. MMD coast to t_f instead of the arrival: {pct_horizon:.0f} %. Agent "
             f"drifted 1-50 km off the torus (3 directions each): {pct_offset_all.min():.0f}-{pct_offset_all.max():.0f} %. "
             f"Tolerance met in {n_valley_angle} of {len(sweep)} sweep settings (read at t_f; "
             f"{sum(r.pct_arr < 25 for r in sweep)} read at arrival). {member_note('angle')[0].upper() + member_note('angle')[1:]}. "
             f"Grid-dependent: with {grids} ring angles (section 5b) {series('angle', 'percentile', '{:.1f}')} %, "
             "tending to 100 % (u* tends to no maneuver)"),
    CLAIMS["valley_projection"].judge(valley_proj_worst,
        shown=f"{valley_proj_worst:.0f} % (baseline {st_proj.median_percentile:.0f} %, best quartile in "
              f"{st_proj.best_quartile_share:.0f} % of slices)",
        note=f"Tolerance met in {sum(r.pct_proj <= 25 for r in sw_valley)} of {len(sw_valley)} sweep settings at agent "
             f"phase 0 or 1/2 and {sum(r.pct_proj <= 25 for r in sw_quarter)} of {len(sw_quarter)} at 1/4 or 3/4 "
             f"({n_valley_proj} of {len(sweep)} in all, section 6). Grid-independent: with {grids} ring angles "
             f"{series('projection', 'percentile', '{:.0f}')} %; {member_note('projection')}"),
    *quarter_rows,
    CLAIMS["fuel_angle"].judge(fuel_ok["angle"][0],
        shown=f"u* outside the slice's most expensive quarter in {st.outside_fuel_peak_share:.0f} % of slices "
              f"({'/'.join(f'{v:.0f}' for v in fuel_ok['angle'][1])} % with {grids} ring angles)",
        note=f"at least {st.fuel_percentile.min():.0f} % (median {np.median(st.fuel_percentile):.0f} %) of a slice's "
             f"maneuvers cost more than u* on the {N_SURF}-angle surface, so the verdict does not hang on the quartile; "
             f"at or below the slice median fuel in {st.below_median_fuel * 100:.0f} % of slices. u* avoids the peak by "
             "picking a burn next to the agent's own phase, whose fuel falls with the grid spacing (median fuel "
             f"{'/'.join(f'{v:.2f}' for v in fuel_ok['angle'][2])} m/s with {grids} ring angles: u* tends to no "
             "maneuver); that is why it fails the valley rows, not this one"),
    CLAIMS["fuel_projection"].judge(fuel_ok["projection"][0],
        shown=f"u* outside the slice's most expensive quarter in {st_proj.outside_fuel_peak_share:.0f} % of slices "
              f"({'/'.join(f'{v:.0f}' for v in fuel_ok['projection'][1])} % with {grids} ring angles)",
        note=f"at least {st_proj.fuel_percentile.min():.0f} % (median {np.median(st_proj.fuel_percentile):.0f} %) of a "
             f"slice's maneuvers cost more than u* on the {N_SURF}-angle surface; its median fuel "
             f"{'/'.join(f'{v:.2f}' for v in fuel_ok['projection'][2])} m/s with {grids} ring angles (settles with the "
             f"grid), at most {S.fuel_m_s.max():.2f} m/s in the set: well below the peak, near the middle of the "
             f"distribution (at or below the slice median fuel in {st_proj.below_median_fuel * 100:.0f} % of slices)"),
    CLAIMS["second_burn_peak"].judge(second_raises["projection"],
        shown=f"ratio both burns / first only {second_effect_proj.min():.4f}-{second_effect_proj.max():.4f} "
              f"(projection reading; angle reading {second_effect.min():.3f}-{second_effect.max():.3f})",
        note=f"the second burn raises sqrt(J_rho) of u* in some slice: projection reading (adopted for Fig. 4, the "
             f"status) {'yes' if second_raises['projection'] else 'no'}, angle reading "
             f"{'yes' if second_raises['angle'] else 'no'}" + (", the same verdict under both readings" if
             second_raises["angle"] == second_raises["projection"] else ", the readings disagree") +
             f"; the projection line's raised point (next row) included. Tracking 24 h before the first burn (angle "
             f"reading): {second_effect_pre.min():.2f}-{second_effect_pre.max():.2f} (raised by > 10 % in "
             f"{np.sum(second_effect_pre > 1.1)} of {S.t_arrival.size} slices)"),
    CLAIMS["raised_point_projection"].judge(raised_counts,
        shown=f"{'/'.join(str(c) for c in raised_counts)} raised point(s) with {raised_ns} arrival slices",
        reason=raised_reason,
        note=f"on the {N_SURF}-slice surface of section 3: {len(raised)} raised slice(s)" + (f" ({raised_txt})" if raised
             else "") + f"; angle reading: {len(st.raised_slices)} raised slice(s). The point is raised because u* "
             "jumps to another ring angle there, not by the second burn (ratio well below 1: without it the same "
             "maneuver is far worse)"),
    CLAIMS["vs_best_angle"].judge(worst_edge["angle"],
        shown=f"{worst_edge['angle']:.2f} (worst grid; u* {np.median(S.informed_range_sigma_km) * 1e3:.1f} m vs best "
              f"{np.median(S.best_range_sigma_km) * 1e3:.1f} m, median over slices)",
        note=f"{vs_edge['angle']:.2f} on the {N_SURF}-angle surface (u* / slice best {vs_best['angle']:.2f}; the valley's "
             f"edge lies a median {np.median(edge_best):.2f} times above the best); u* / valley edge "
             f"{series('angle', 'ratio_valley', '{:.2f}')} with {grids} ring angles, growing as the grid is refined "
             f"(u* / best {series('angle', 'ratio_best', '{:.2f}')}). Doing nothing: {none_km * 1e3:.0f} m (every "
             "maneuver beats it)"),
    CLAIMS["vs_best_projection"].judge(worst_edge["projection"],
        shown=f"{worst_edge['projection']:.2f} (worst grid; u* {np.median(S_proj.informed_range_sigma_km) * 1e3:.1f} m "
              f"vs best {np.median(S.best_range_sigma_km) * 1e3:.1f} m, median over slices)",
        note=f"{vs_edge['projection']:.2f} on the {N_SURF}-angle surface (u* / slice best {vs_best['projection']:.2f}; "
             f"the valley's edge lies a median {np.median(edge_best):.2f} times above the best); u* / valley edge "
             f"{series('projection', 'ratio_valley', '{:.2f}')} with {grids} ring angles (u* / best "
             f"{series('projection', 'ratio_best', '{:.2f}')}; grid-independent)"),
    CLAIMS["vs_random_angle"].judge(worst_rand["angle"],
        shown=f"{worst_rand['angle']:.0f} % (worst grid)",
        note=f"{vs_rand['angle']:.0f} % of {N_RANDOM} random picks per slice on the {N_SURF}-angle surface (stream "
             f"[SEED, 20]); {series('angle', 'beats_random', '{:.0f}')} % with {grids} ring angles ({N_RANDOM} picks per "
             "slice, stream [SEED, 21]); a random pick beats 50 % on average"),
    CLAIMS["vs_random_projection"].judge(worst_rand["projection"],
        shown=f"{worst_rand['projection']:.0f} % (worst grid)",
        note=f"{vs_rand['projection']:.0f} % of {N_RANDOM} random picks per slice on the {N_SURF}-angle surface; "
             f"{series('projection', 'beats_random', '{:.0f}')} % with {grids} ring angles"),
    CLAIMS["filter_nees"].judge(p_exec, shown=f"{ia['nees']:.2f} / {ipa['nees']:.2f} (band {lo:.1f}-{hi:.1f})",
        note=f"{CONSISTENT}; tail probability {mcs.p_value(INF, 'exec'):.2f} / {mcs.p_value(INFP, 'exec'):.2f}; iterated "
             f"EKF, {N_TRIALS} runs; perfect burns: {ip['nees']:.2f} / {ipp['nees']:.2f}"),
    CLAIMS["filter_no_maneuver"].judge(p_none, shown=f"{nm['nees']:.1f}; {nm['rms'] / 1e3:.1f} vs {nm['fsig'] / 1e3:.1f} km",
        note=f"{CONSISTENT}; tail probability {p_none:.2g}" + (" (below the float range)" if p_none == 0 else "") +
             f" (band {lo:.1f}-{hi:.1f}); prior range 1-sigma "
             f"{mcs.prior_range_m / 1e3:.1f} km"),
    CLAIMS["filter_small_errors"].judge(p_small, shown=f"{isml['rms']:.0f} / {ispm['rms']:.0f} / {usml['rms']:.0f} m",
        note=f"{EXEC_ABS_M_S * 1e2:g} mm/s + {EXEC_REL * 10:g} % per axis; NEES {isml['nees']:.1f} / {ispm['nees']:.1f} / "
             f"{usml['nees']:.1f} (band {lo:.1f}-{hi:.1f}); {CONSISTENT}; tail probability "
             + " / ".join(f"{mcs.p_value(pol, 'small'):.2f}" for pol in (INF, INFP, UNI))),
    CLAIMS["filter_rms"].judge(ia["rms"], shown=f"{ia['rms']:.0f} / {ipa['rms']:.0f} / {ua['rms']:.0f} / {nm['rms']:.0f} m",
        note=f"execution errors {EXEC_ABS_M_S * 1e3:.0f} mm/s + {EXEC_REL * 100:.0f} % per axis; perfect burns: informed "
             f"{ip['rms']:.1f} / {ipp['rms']:.1f} m (covariance analysis {ip['ca']:.1f} / {ipp['ca']:.1f} m), uninformed "
             f"{summary[(UNI, 'perfect')]['rms']:.1f} m; informed/uninformed = {ratio_pu:.2f} / {ratio_ppu:.2f}"),
)
print(f"notebook run time so far: {time.perf_counter() - t_start:.0f} s")
table.display()

# %% [markdown]
# ## Exercises
#
# Each exercise changes one parameter of the `parameters` cell at the top; rerun the notebook (in Jupyter, or with
# `python -m cislunar.publish.notebooks --quick 08 -p NAME=VALUE`), write down your prediction first, then compare.
# The worked solutions are functions of `cislunar.papers.greaves_scheeres_2023.exercises` that answer each question at
# a small size in a few seconds and return the numbers with a one-paragraph answer.
#
# 1. **Sample the set more finely.** Double `N_SURF` (28 in quick mode). Before running: which reading of Eq. 25
#    moves, the angle or the projection? Predict the direction in which the angle reading's $\mathbf u^*$ moves in
#    phase, in fuel and in $\sqrt{J_\rho}$, and what happens to its percentile in the valley row of the closing table.
#    Compare with the resolution study of section 5b. Worked solution: `exercise_08_ring_grid`.
# 2. **Better or worse thrusters.** Multiply both `EXEC_ABS_M_S` and `EXEC_REL` by 10, then divide them by 10.
#    Predict how the RMS range error of the informed maneuvers in the Monte Carlo of section 7 scales, and whether
#    the filter stays consistent (mean NEES inside its band). Worked solution: `exercise_08_execution_errors`.
# 3. **Where the agent starts.** Set `AGENT_THETA = 1.5708` (a quarter turn, $\pi/2$ rad). Predict whether the
#    projection reading still puts $\mathbf u^*$ in the valley (best quartile), and compare with the rows of the
#    sweep of section 6 at agent phase 0.25. Worked solution: `exercise_08_agent_phase`.
