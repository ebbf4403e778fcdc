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
# # 10 · Maneuver detection with the OCBE control policy
#
# **What you will learn.** How Greaves & Scheeres model NRHO station keeping as a randomly pointed impulse at
# apoapsis with a truncated-Gaussian size; why the optimal-control-based estimator (OCBE) is tuned with a raised
# control uncertainty in an 8-hour window around apoapsis, and how a maneuver then shows up as a spike in the
# *smoothed* control estimate; how the integral of the control norm, $z=\int\|\hat{\mathbf u}\|dt$, becomes the
# statistic of a maximum-likelihood binary hypothesis test whose PDFs come from a Monte Carlo analysis; what the
# threshold, false-positive and missed-detection rates and the detection accuracy are for an "active" (1 m/s) and a
# "quiet" (50 mm/s) policy on the 9:2 NRHO and the stable NRHO; and when $z$ is a faster health metric of the filter
# than its measurement residuals.
#
# **Paper sections followed.** J. A. Greaves, D. J. Scheeres, *Observation and Maneuver Detection for Cislunar
# Vehicles*, JAS 68 (2021): "Modeling Definitions" (Eqs. 3-5, Table 2), "Filter Tuning Strategy" (Figs. 10-13),
# "Maneuver Detection" (Eqs. 33-35, Figs. 14-21, Tables 5-8) and "Control as a Health Metric" (Fig. 22). The OCBE
# itself (Eqs. 14-32) is `cislunar.estimation.ocbe`; the tracking scenario (L2 observer, angles and angle rates
# every 2 hours, Earth-radar hand-off at periapsis) is `cislunar.papers.greaves_scheeres_2021.tracking`; everything
# specific to detection is `cislunar.papers.greaves_scheeres_2021.detection`.
#
# **What the paper does not give.** Tables 1-8 are missing from its text: in particular the measurement noise
# (Table 3) and the OCBE tuning values. We use 10 micro-rad angles (1 sigma) with Eq. 13 rates from 1 s
# differencing (see `cislunar.papers.greaves_scheeres_2021.tracking`). The tuning is the one input every number of
# this notebook depends on, so Section 2 maps it (window weight, angle noise, window length, base weight) and
# reads it in two ways: from the paper's *consistency* claim (an independent prediction of everything else) and
# from the paper's *thresholds* (a tuned reading). Both are carried through and the closing table says which rows rest on which.

# %% tags=["parameters"]
QUICK = False  # quick mode: every Monte Carlo shrinks (the sizes below left at None); every step still runs
SEED = 0  # root seed: each sub-study draws from its own child [SEED, k]; one study's sizes leave the others' draws
OUTPUT_DIR = ""  # folder for the figures (empty: build-scratch/ by hand, the build under the runner)
N_H0 = None  # non-maneuvering training runs per policy and orbit (None: 8 quick, 500 full; paper: 500)
N_H1 = None  # maneuvering training runs per policy and orbit (None: 8 quick, 3000 full; paper: 3000)
N_TEST = None  # test runs per hypothesis, policy and orbit (None: 4 quick, 100 full; paper: 100 + 100)
OUTER_SIZE = None  # share of the training runs the outer-band stable NRHO runs; it gets half the tests (None: 0.2)
N_MAP = None  # (H0, H1) runs per cell of the tuning map of Section 2 (None: (6, 6) quick, (150, 250) full)
F_GRID = None  # window weight factors f of the map, units of the variance-matched weight, increasing
#                (None: 0.03, 0.1, 0.2, 0.3, 0.5, 1.0)
F_SIDE = None  # factors of the map's side axes (noise, window length, base weight), 9:2 NRHO
#                (None: 0.1, 0.2 quick; 0.1, 0.2, 0.3 full; must contain 0.1, the threshold reading)
Q_BASE = None  # control weight outside the apoapsis window, km^2/s^3 (None: 1e-18)
WINDOW_HOURS = None  # length of the apoapsis window, hours (None: 8, the paper's)
N_SPIKE = None  # runs per hypothesis of the Figs. 10-11 check (None: 8 quick, 200 full)
N_POLICY_DRAWS = None  # draws that check the station-keeping distributions (None: 5000 quick, 200000 full)
PM_J_SEEDS = None  # noise draws per direction in the +-j search of Section 4 (None: 1 quick, 3 full)
PM_J_F = None  # window weight factors of the +-j search (None: 0.03, 0.3, 1.0 quick; 0.03, 0.1, 0.3, 1.0 full)
PM_J_NOISE_URAD = None  # angle noise of the +-j search, micro-rad (None: 10, 1000 quick; 10, 100, 300, 1000 full)
PM_J_OFFSET_H = None  # burn times after apoapsis in the +-j search, hours, inside the window (None: -3, 0, 3)
N_PM_J_MC = None  # randomly pointed burns per policy where the +-j pattern appears (None: 8 quick, 600 full)
N_Z05 = None  # 0.5 m/s burns per tuning factor for the health metric of Section 6 (None: 4 quick, 64 full)
N_LEAD = None  # (no-burn runs for calibration and validation, runs per burn size) of the race of Section 6
#                (None: (10, 2) quick, (200, 48) full)
LEAD_MAGNITUDES = None  # burn sizes of the control-versus-residual race, m/s (None: 0.05, 0.1, 0.2, 0.5)
JOINT_WINDOWS = None  # window lengths of the joint search of Section 2b, hours (None: 4, 8 quick; 2, 4, 8 full)
JOINT_F = None  # window weight factors of the joint search (None: 0.2 quick; 0.15, 0.2, 0.3 full)
JOINT_Q_BASE = None  # base weights of the joint search, km^2/s^3 (None: 1e-18 quick; 1e-18, 1e-16 full)
JOINT_NOISE_URAD = None  # angle noise of the joint search, micro-rad (None: 10 quick; 5, 10, 20 full)
JOINT_OFFSET_H = None  # burn times after apoapsis in the joint search, hours (None: 0 quick; 0, 1 full)
N_JOINT_SCREEN = None  # (H0, H1) runs per policy of the joint search's screen (None: (6, 6) quick, (24, 48) full)
N_JOINT_PAPER = None  # (H0, H1) runs per policy where the screen passes (None: (8, 8) quick, (500, 3000) full)
JOINT_CONFIRM_WINDOWS = None  # windows whose passing settings are rerun at N_JOINT_PAPER (None: all quick; 8 full)
RACE_F = None  # window weight factors of the Fig. 22 race grid of Section 6 (None: 0.3 quick; 0.1, 0.3, 1 full)
RACE_NOISE_URAD = None  # angle noise of the race grid, micro-rad (None: 20 quick; 20, 30, 50 full)
N_RACE = None  # (no-burn runs for calibration and validation, runs per burn size) of the race grid
#                (None: (10, 2) quick, (100, 48) full)
N_BOOT = None  # bootstrap resamples for the standard errors of z_lim and of FP + MD (None: 4 quick, 40 full)
BATCH = None  # trials the batched OCBE filters together, epoch by epoch (None: 8); results depend on it
WORKERS = None  # local processes for the Monte Carlo, 1 runs serially (None: 1 quick, 2 full)
SCHEDULER = ""  # address of a Dask scheduler to run the Monte Carlo on ("" for none; then WORKERS applies)

# %% [markdown]
# **Changing the chapter.** Every size and setting is a parameter of the cell above. A parameter left at `None` is
# picked in the next cell from `QUICK` (quick mode shrinks every Monte Carlo, never skips a step); a value you
# give, in Jupyter or with `-p NAME=VALUE` on the command line, is used as given in either mode. Each sub-study
# draws from its own child of `SEED`, and trial $i$ of a Monte Carlo always gets child $i$ of its sub-study's seed:
# the numbers depend on the sizes and on `BATCH`, never on the executor that `WORKERS` local processes or a Dask
# `SCHEDULER` provide. The exercises at the end of the chapter start from here.

# %%
# Every parameter left at None is picked here from QUICK; a value the reader gave is used as given.
N_H0 = N_H0 if N_H0 is not None else (8 if QUICK else 500)
N_H1 = N_H1 if N_H1 is not None else (8 if QUICK else 3000)
N_TEST = N_TEST if N_TEST is not None else (4 if QUICK else 100)
OUTER_SIZE = OUTER_SIZE if OUTER_SIZE is not None else 0.2
N_MAP = tuple(N_MAP if N_MAP is not None else ((6, 6) if QUICK else (150, 250)))
F_GRID = tuple(F_GRID if F_GRID is not None else (0.03, 0.1, 0.2, 0.3, 0.5, 1.0))
F_SIDE = tuple(F_SIDE if F_SIDE is not None else ((0.1, 0.2) if QUICK else (0.1, 0.2, 0.3)))
Q_BASE = Q_BASE if Q_BASE is not None else 1e-18
WINDOW_HOURS = WINDOW_HOURS if WINDOW_HOURS is not None else 8.0
N_SPIKE = N_SPIKE if N_SPIKE is not None else (8 if QUICK else 200)
N_POLICY_DRAWS = N_POLICY_DRAWS if N_POLICY_DRAWS is not None else (5000 if QUICK else 200000)
PM_J_SEEDS = PM_J_SEEDS if PM_J_SEEDS is not None else (1 if QUICK else 3)
PM_J_F = tuple(PM_J_F if PM_J_F is not None else ((0.03, 0.3, 1.0) if QUICK else (0.03, 0.1, 0.3, 1.0)))
PM_J_NOISE_URAD = tuple(PM_J_NOISE_URAD if PM_J_NOISE_URAD is not None
                        else ((10.0, 1000.0) if QUICK else (10.0, 100.0, 300.0, 1000.0)))
PM_J_OFFSET_H = tuple(PM_J_OFFSET_H if PM_J_OFFSET_H is not None else (-3.0, 0.0, 3.0))
N_PM_J_MC = N_PM_J_MC if N_PM_J_MC is not None else (8 if QUICK else 600)
N_Z05 = N_Z05 if N_Z05 is not None else (4 if QUICK else 64)
N_LEAD = tuple(N_LEAD if N_LEAD is not None else ((10, 2) if QUICK else (200, 48)))
LEAD_MAGNITUDES = tuple(LEAD_MAGNITUDES if LEAD_MAGNITUDES is not None else (0.05, 0.1, 0.2, 0.5))
JOINT_WINDOWS = tuple(JOINT_WINDOWS if JOINT_WINDOWS is not None else ((4.0, 8.0) if QUICK else (2.0, 4.0, 8.0)))
JOINT_F = tuple(JOINT_F if JOINT_F is not None else ((0.2,) if QUICK else (0.15, 0.2, 0.3)))
JOINT_Q_BASE = tuple(JOINT_Q_BASE if JOINT_Q_BASE is not None else ((1e-18,) if QUICK else (1e-18, 1e-16)))
JOINT_NOISE_URAD = tuple(JOINT_NOISE_URAD if JOINT_NOISE_URAD is not None else ((10.0,) if QUICK else (5.0, 10.0, 20.0)))
JOINT_OFFSET_H = tuple(JOINT_OFFSET_H if JOINT_OFFSET_H is not None else ((0.0,) if QUICK else (0.0, 1.0)))
N_JOINT_SCREEN = tuple(N_JOINT_SCREEN if N_JOINT_SCREEN is not None else ((6, 6) if QUICK else (24, 48)))
N_JOINT_PAPER = tuple(N_JOINT_PAPER if N_JOINT_PAPER is not None else ((8, 8) if QUICK else (500, 3000)))
JOINT_CONFIRM_WINDOWS = tuple(JOINT_CONFIRM_WINDOWS if JOINT_CONFIRM_WINDOWS is not None
                              else (JOINT_WINDOWS if QUICK else (8.0,)))
RACE_F = tuple(RACE_F if RACE_F is not None else ((0.3,) if QUICK else (0.1, 0.3, 1.0)))
RACE_NOISE_URAD = tuple(RACE_NOISE_URAD if RACE_NOISE_URAD is not None else ((20.0,) if QUICK else (20.0, 30.0, 50.0)))
N_RACE = tuple(N_RACE if N_RACE is not None else ((10, 2) if QUICK else (100, 48)))
N_BOOT = N_BOOT if N_BOOT is not None else (4 if QUICK else 40)
BATCH = BATCH if BATCH is not None else 8
workers = WORKERS if WORKERS is not None else (1 if QUICK else 2)

import contextlib
import time

import numpy as np
from scipy import stats

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import consistency
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import detection_studies as dstudies
from cislunar.papers.greaves_scheeres_2021 import figures, tracking
from cislunar.papers.greaves_scheeres_2021 import panels as ocbe_panels
from cislunar.papers.greaves_scheeres_2021.claims.maneuver_detection import (
    CLAIMS,
    HEALTH_PLAUSIBLE_FLOOR,
    PAPER_ZLIM,
)
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.utils.executors import open_executor

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
# One executor for the whole chapter, opened here and closed in the last cell: its worker processes compile the
# integrators once and keep them for every Monte Carlo below.
executors = contextlib.ExitStack()
executor = executors.enter_context(open_executor(workers, SCHEDULER))
table = ComparisonTable("10 Maneuver detection (Greaves & Scheeres 2021, Eqs. 3-5, 33-35, Figs. 10-22, Tables 5-8)")
OUTER = "stable NRHO (outer band)"
ORBITS = {"9:2 NRHO": orbits.nrho_9_2(em), "stable NRHO": orbits.stable_nrho(em), OUTER: orbits.stable_nrho_outer(em)}
STABLE = ("stable NRHO", OUTER)
POLICIES = {"active": det.ACTIVE_POLICY, "quiet": det.QUIET_POLICY}
T_START = time.perf_counter()
for name, o in ORBITS.items():
    print(f"{name}: period {o.period_days:.3f} d, perilune {o.perilune_radius_km:.0f} km, "
          f"stability index {o.stability_index:.3f}")

# %% [markdown]
# ## 1 · The station-keeping model (Eqs. 3-5, Table 2)
#
# Every orbit the vehicle may burn at apoapsis. The impulse has azimuth $u_\theta\sim\mathcal U[-\pi,\pi]$
# (Eq. 3), elevation $u_\psi\sim\mathcal U[-\pi/2,\pi/2]$ (Eq. 4) and magnitude
# $u_{mag}\sim\mathcal N(\mu_u,\sigma_u)$ truncated to $\mu_u\pm3\sigma_u$ (Eq. 5); the direction in the rotating
# frame is $(\cos u_\psi\cos u_\theta, \cos u_\psi\sin u_\theta, \sin u_\psi)$. The *active* ("noisy") policy has
# $\mu_u = 1$ m/s, $\sigma_u = 0.3$ m/s; the *quiet* policy 50 mm/s and 15 mm/s.
#
# Two details matter. The truncated Gaussian is drawn exactly (`scipy.stats.truncnorm` with our generator), so its
# standard deviation is about 1.3 % below $\sigma_u$. And a uniform elevation is **not** a uniform direction on
# the sphere: the area element is $\cos u_\psi\,du_\psi\,du_\theta$, so uniform $u_\psi$ over-weights the poles
# $\pm\hat k$ (the $z$ component of the direction is arcsine-distributed instead of uniform on $[-1, 1]$). We
# implement what the paper writes.

# %%
draws = {name: pol.sample_magnitude(rng, N_POLICY_DRAWS) for name, pol in POLICIES.items()}
for name, pol in POLICIES.items():
    m, d = draws[name], pol.magnitude_distribution
    print(f"{name}: range [{m.min() * 1e3:.2f}, {m.max() * 1e3:.2f}] mm/s (bounds "
          f"{(pol.mean_m_s - 3 * pol.sd_m_s) * 1e3:.1f}, {(pol.mean_m_s + 3 * pol.sd_m_s) * 1e3:.1f}); "
          f"sd/sigma_u = {m.std() / pol.sd_m_s:.4f} (truncnorm {d.std() / pol.sd_m_s:.4f})")
az, el = det.StationKeepingPolicy.sample_pointing(rng, N_POLICY_DRAWS)
uz = det.pointing_vector(az, el)[:, 2]
_ = plotting.save_figure(figures.station_keeping_policy(draws, POLICIES, uz), "10_station_keeping_policy",
                         output_dir=out)
ks_sphere = stats.kstest(uz, stats.uniform(-1, 2).cdf).pvalue
ks_txt = f"= {ks_sphere:.1e}" if ks_sphere > 0 else "< 1e-300"  # below the smallest double: printed as a bound
print(f"KS test of u_z against a uniform sphere: p {ks_txt}; against arcsine: "
      f"p = {stats.kstest(uz, stats.arcsine(-1, 2).cdf).pvalue:.2f}")

# %% [markdown]
# ## 2 · Tuning the OCBE: constant versus an apoapsis window
#
# Why not let the filter tune itself? Notebook 09b runs the paper's adaptive OCBE (metric test, three strikes,
# covariance reset): a 3 m/s burn is caught at once, but a 50 mm/s burn, the size of the quiet policy, is caught
# only tens of hours later or not within the period, and the filter is inconsistent meanwhile. That is why the
# paper, and this notebook, raise the control uncertainty where the burns happen instead.
#
# The OCBE absorbs mismodelling in an estimated control $\hat{\mathbf u} = -\tilde Q B^\top\mathbf p$ whose
# uncertainty is the control weight $\tilde Q = qI_3$ (an acceleration power spectral density, km$^2$/s$^3$). Over
# an interval the OCBE's process-noise-like term is $Q=-\Phi_{xp}\Phi_{xx}^\top$ (Eq. 17), i.e. white acceleration
# noise of PSD $q$ mapped through the dynamics. The paper raises $q$ only in an 8-hour window centred on apoapsis,
# where the station-keeping burn happens, and keeps it small elsewhere; its values are not given.
#
# **The unit of the window weight.** White acceleration noise of PSD $q$ over a window $T$ accumulates a velocity
# variance $qT$ per axis. Matching it to the per-axis second moment of the impulse gives the *variance-matched*
# weight $q_\star = E[u_{mag}^2]/(3T)$ ($1.26\times10^{-11}$ km$^2$/s$^3$ active, $3.15\times10^{-14}$ quiet for
# 8 hours). We write the window weight as $q_w = f\,q_\star$: the factor $f$ is the fraction of the burn's velocity
# variance that the window admits. Outside the window $q_b = 10^{-18}$ km$^2$/s$^3$: negligible, but it keeps $Q$
# positive definite.
#
# **The tuning map.** Four inputs are unstated: $f$, the angle noise, the window length and $q_b$. For each
# setting we run a reduced Monte Carlo per policy (the sizes are printed below) and record what the paper's
# statements are about: the fraction of NEES-inconsistent runs of the forward and the smoothed estimates, with and
# without a burn (notebook 09's criterion: a run is inconsistent when more than 5 % of its epochs exceed the
# 99.9 % quantile of $\chi^2_6$), the threshold $z_{lim}$ and the expected error rate $FP + MD$ of the hypothesis
# test of Section 3. $f$ is swept on all three orbits at the paper's window (8 h), our noise and base weight; the
# other three inputs on the 9:2 NRHO for a few factors.
#
# **Two readings of the paper, fixed before the map is computed.**
#
# * *Consistency reading* (independent of the paper's numbers): the paper calls its window tuning consistent
#   (Figs. 12-13). We take $f_c$ = the smallest factor of the grid at which every orbit, policy and hypothesis has
#   at most 10 % of inconsistent runs, forward and smoothed, at the paper's window and our noise and base weight.
#   Everything computed at $f_c$ is a prediction of the paper's numbers.
# * *Threshold reading*: an earlier version of this notebook chose $f = 0.1$ from a three-decade pilot
#   ($f$ = 0.01, 0.1, 1) while the paper's thresholds were in view; at $f = 0.1$ the thresholds agree with the
#   paper's within 25 %. Because $f$ was chosen with those numbers in view, agreement at $f = 0.1$ is marked
#   "consistent (tuned)", never "reproduced". The training Monte Carlo at the paper's sizes (Section 3,
#   Figs. 14-21) is run at $f = 0.1$, so that its figures compare with the paper's at the same scale, and again at
#   $f_c$ for the predictions.

# %%
SIGMA_ANGLE = tracking.DEFAULT_SIGMA_ANGLE_RAD
VARIANTS = {"paper window, our noise": {}, "noise 2 urad": dict(sigma_angle_rad=2e-6),
            "noise 20 urad": dict(sigma_angle_rad=20e-6), "4-h window": dict(window_hours=4.0),
            "12-h window": dict(window_hours=12.0), "base 1e-16": dict(q_base=1e-16)}
BASE_VARIANT = "paper window, our noise"


tmap = dstudies.run_tuning_map(em, ORBITS, POLICIES, VARIANTS, F_GRID, F_SIDE, N_MAP, [SEED, 77], paper_zlim=PAPER_ZLIM,
                               q_base_km2_s3=Q_BASE, window_hours=WINDOW_HOURS, sigma_angle_rad=SIGMA_ANGLE,
                               half_size_orbits=(OUTER,), batch_size=BATCH, executor=executor)
print(f"tuning map: {len(tmap.cells)} settings, {N_MAP[0]} + {N_MAP[1]} runs each (outer band half), "
      f"{(time.perf_counter() - T_START) / 60:.1f} min so far")
F_C, F_TUNE = tmap.f_c, 0.1  # the consistency reading, and the threshold reading
F_MATCH = {p: tmap.f_match(p) for p in POLICIES}
worst = tmap.worst
print(tmap.report(F_TUNE))

# %%
_ = plotting.save_figure(figures.tuning_map(tmap.cells, ORBITS, POLICIES, VARIANTS, BASE_VARIANT, F_GRID, F_SIDE, F_C, F_TUNE,
                                           PAPER_ZLIM, worst), "10_tuning_map", output_dir=out)

# %% [markdown]
# **The tuning map.** Top row: the paper's window, our noise and base weight, all three orbits (solid active,
# dashed quiet): the fraction of burn runs whose forward (left) and smoothed (middle) estimates are inconsistent,
# and the expected error of the test (right). Bottom row: the 9:2 NRHO under the other settings (black: the
# paper's window, as in the top row): the worst cell over hypotheses and passes, the threshold over the paper's
# (grey band: within 25 %) and the expected error. The dotted line marks 10 % of runs; the vertical bands mark
# $f = 0.1$ (red, threshold reading) and $f_c$ (green, consistency reading).
#
# **What the map shows** (full run; the lines above are this run's). Without a burn (H0) every setting is
# consistent: at most 1 % of the runs fail. With a burn the forward filter fails often when $f$ is small: the window
# then admits only the fraction $f$ of the burn's velocity variance, so a typical burn is $1/\sqrt f$ standard
# deviations per axis (3.2 at $f = 0.1$) and the NEES stays above its quantile until the data have absorbed it. The
# smoothed estimate, which sees the data after the burn, fails less often. The rule gives $f_c = 0.3$, where no cell
# exceeds 4 %. Detection survives there: the expected error $FP + MD$ is at most 7 % for $f \le 0.3$ and climbs to
# about 20 % at the variance-matched $f = 1$, because the integral without a burn grows with the window weight. The
# threshold $z_{lim}$ grows with $f$ as well and equals the paper's at $f$ = 0.13 (active) and 0.17 (quiet), below
# $f_c$: at the paper's window, our noise and base weight, the paper's thresholds and its consistency claim cannot
# both hold. The other settings move the edge to $f = 0.2$ (2 micro-rad noise, 4-hour window, a hundred times larger
# base weight) but never to 0.1. The settings of the map where both thresholds lie within 25 % of the paper's *and*
# the 9:2 NRHO is consistent are printed above: in the full run only one, a 4-hour window at $f = 0.2$. More angle
# noise does not do it: at 20 micro-rad the filter is consistent only at $f = 0.3$, where the active threshold lies
# outside the 25 % band (the ratios on the "noise 20 urad" line). In this map the paper's thresholds and its
# consistency claim are therefore met together only with a window half as long as the 8 hours the paper states.
#
# ## 2b · Thresholds and consistency together: a joint search over the unstated inputs
#
# The map varies one input at a time around our base setting. Could some *combination* of the four unstated inputs,
# plus the burn time within the window, give the paper's thresholds and a consistent filter at once, with the
# paper's 8-hour window? `detection_studies.run_joint_search` tries every combination of the window length, the
# factor $f$, the base weight $q_b$, the angle noise and the burn time (hours after apoapsis, inside the window; the
# window stays centred on apoapsis), on the 9:2 NRHO for both policies, in two stages whose criteria were fixed
# before the search ran:
#
# * a *screen* with a small Monte Carlo per setting and policy (sizes printed): both thresholds within 40 % of the
#   paper's and the worst cell (H0/H1, forward/smoothed) at most 10 % inconsistent runs plus two binomial standard
#   errors of the screen's burn runs, wide enough that the small sample does not drop a setting the paper-size run
#   would keep;
# * a *confirmation* at the paper's sizes (500 + 3000 runs per policy) of every setting that passes the screen,
#   with bootstrap standard errors of each threshold: both thresholds within 25 % of the paper's (the threshold
#   reading's band) and every cell at most 10 % inconsistent (the consistency reading's rule).
#
# The screen passes many settings (39 of 108 in the full run), and each confirmation is 7000 runs. The full run
# therefore reruns at paper size only the settings with the paper's 8-hour window, those the closing row asks about
# (`JOINT_CONFIRM_WINDOWS`; set it to `[2, 4, 8]` to confirm every window, about an hour more on two cores).
#
# Every stage runs as one pooled sweep of lockstep groups, so the numbers do not depend on the executor. The closing
# table carries one row: does any 8-hour setting meet both criteria at paper size?

# %%
joint = dstudies.run_joint_search(em, ORBITS["9:2 NRHO"], POLICIES, JOINT_WINDOWS, JOINT_F, JOINT_Q_BASE,
                                  JOINT_NOISE_URAD, JOINT_OFFSET_H, N_JOINT_SCREEN, N_JOINT_PAPER, N_BOOT, [SEED, 95],
                                  paper_zlim=PAPER_ZLIM, batch_size=BATCH, executor=executor,
                                  confirm_windows=JOINT_CONFIRM_WINDOWS)
print(joint.report())
_ = plotting.save_figure(figures.joint_search(joint), "10_joint_search", output_dir=out)

# %% [markdown]
# **The joint search** (left: every screened setting, the larger threshold deviation of the two policies against
# the worst consistency cell, one colour per window; filled points were rerun at paper size; the dotted box is the
# screen's criterion, the dashed box the confirmation's. Right: the paper-size thresholds over the paper's, with two
# bootstrap standard errors; the grey band is the 25 % criterion; a star marks the settings meeting both).
#
# **What the search shows** (full run; the lines above are this run's). The grid is 3 windows (2, 4, 8 h) x 3
# factors (0.15, 0.2, 0.3) x 2 base weights ($10^{-18}$, $10^{-16}$) x 3 noise levels (5, 10, 20 micro-rad) x 2 burn
# times (at apoapsis, 1 h after): 108 settings, 24 + 48 runs per policy each. The screen passes 39 of them (11 with
# a 2-hour window, 18 with 4 hours, 10 with 8 hours). At the paper's size none of the ten 8-hour settings meets both
# criteria. The three that are consistent in every cell ($f = 0.2$ at 5 micro-rad, $f = 0.3$ at 20 micro-rad, all
# with $q_b = 10^{-18}$) put the active threshold 32-42 % above the paper's. The only one with both thresholds
# within 25 % ($f = 0.2$, $q_b = 10^{-18}$, 20 micro-rad, burn an hour after apoapsis: +22 % and +6 %) has 18.4 %
# of its quiet burn runs inconsistent; at 10 micro-rad the same setting gives +26 % and +10 % with 13.8 %. A larger
# base weight lowers the active threshold (+13 to +21 %) but raises the quiet one (+25 to +50 %) and leaves 12-26 %
# of the quiet burn runs inconsistent. The thresholds carry
# bootstrap standard errors of 1-5 % of their value, small against the 25 % band. Within this
# search the paper's thresholds and its consistency claim do not hold together at its 8-hour window. The settings
# with shorter windows that pass the screen are not rerun at paper size in the full run (see above); all 29 of them
# (11 with a 2-hour window, 18 with 4 hours) were rerun outside the notebook on 2026-11-26
# (`JOINT_CONFIRM_WINDOWS = [2, 4]`, same seeds, so the numbers are those this notebook prints with that setting;
# 50 minutes on two processes under load). Eight meet both criteria, all with $q_b = 10^{-18}$:
#
# * 4 hours (4 of 18): $f = 0.15$ at 5 micro-rad; $f = 0.2$ at 10 micro-rad with the burn an hour after apoapsis,
#   and at 20 micro-rad with either burn time (thresholds within +23 % / +12 %, worst cell at most 9.1 %);
# * 2 hours (4 of 11): $f = 0.15$ at 5, 10 and 20 micro-rad, and $f = 0.2$ at 20 micro-rad, all with the burn at
#   apoapsis (active threshold +9 to +21 %, quiet -4 to +16 %, worst cell at most 8.4 %). The three 2-hour
#   settings with the burn an hour after apoapsis, on the edge of a window centred on apoapsis, fail: 20-28 % of
#   their active burn runs inconsistent, or both thresholds 38-45 % high.
#
# A window of a quarter to half the paper's, not its 8 hours, reconciles the two claims, as the map suggested.
#
# **Figs. 10-13: the same burn under the two tunings.** One quiet-policy run (a 50 mm/s burn along $+\hat j$ at
# apoapsis, start at the periapsis hand-off) is filtered twice at $f = 0.1$: with $q_w$ held constant over the
# whole period (the paper's "increased control uncertainty", Figs. 10-11) and with $q_w$ only in the 8-hour
# apoapsis window and $q_b$ elsewhere (the paper's proposed tuning, Figs. 12-13). For each we draw the paper's two
# panel sets with `cislunar.estimation.adaptive_ocbe` (the layout of notebook 09b's Figs. 6-9): position and velocity error
# norms with their 3-sigma bounds, forward (left) and smoothed (right); then the control norm (top) and the
# normalised OCBE metric (bottom; notebook 09b: $\chi^2_4$ under a correct model, limit $\chi^2_{4,0.99} = 13.28$,
# mean line at $4/13.28 = 0.30$; the smoothed metric's epoch average is 4). The paper does not give its burn
# direction, its "small maneuver" size in Figs. 12-13, or the control weights. A single run illustrates; the
# paper's statements about these figures are then tested on Monte Carlo runs.

# %%
setups = {(o, p): det.make_setup(em, ORBITS[o], F_TUNE * det.window_control_weight(POLICIES[p], WINDOW_HOURS),
                                 Q_BASE, window_hours=WINDOW_HOURS) for o in ORBITS for p in POLICIES}
setups_c = {(o, p): det.make_setup(em, ORBITS[o], F_C * det.window_control_weight(POLICIES[p], WINDOW_HOURS),
                                   Q_BASE, window_hours=WINDOW_HOURS) for o in ORBITS for p in POLICIES}
s_q = setups["9:2 NRHO", "quiet"]
demo = dstudies.run_tuning_demo(s_q, [SEED, 7], magnitude_m_s=0.05, direction=(np.pi / 2, 0.0))
panels, burn_days = demo.panels, demo.burn_days
print(demo.report())
_ = plotting.save_figure(ocbe_panels.figure_errors(panels["constant"], "Fig. 10 analogue, constant q_w", burn_days=burn_days,
                                          velocity_unit="mm/s"), "10_fig10_constant_tuning_errors", output_dir=out)

# %% [markdown]
# **Fig. 10 analogue** (the paper: "both the forwards and smoothed filters produce consistent, but less certain,
# solutions"). Compare the errors (blue) with their 3-sigma bounds (red) and the NEES fractions printed above.

# %%
_ = plotting.save_figure(ocbe_panels.figure_control_metric(panels["constant"], "Fig. 11 analogue, constant q_w",
                                                  burn_days=burn_days),
                         "10_fig11_constant_tuning_control_metric", output_dir=out)

# %% [markdown]
# **Fig. 11 analogue** (the paper: "the maneuver appears as a spike in estimated control only in the smoothed
# system"). Top: the forward (single-step, Eq. 32) and smoothed control norms; bottom: the normalised metrics.

# %%
_ = plotting.save_figure(ocbe_panels.figure_errors(panels["apoapsis window"], f"Fig. 12 analogue, {WINDOW_HOURS:g}-h apoapsis window",
                                          burn_days=burn_days, velocity_unit="mm/s"),
                         "10_fig12_window_tuning_errors", output_dir=out)
print(demo.fig12_report())

# %% [markdown]
# **Fig. 12 analogue** (the paper: the window-tuned filter "still performs well"). Outside the window the
# control weight is $q_b$ and the filter behaves as a ballistic one; the bounds are raised across the window (the
# forward velocity bound jumps there), and the raised velocity uncertainty then maps into position: the forward
# position bound keeps growing for about a day and a half after the window before it shrinks again (printed
# above). In this run the forward velocity error reaches its 3-sigma bound at the first epoch after the burn and
# stays close to it for a few hours, then falls below half of it within the day: at $f = 0.1$ the window admits a
# tenth of the burn's velocity variance. Later, between days 5 and 6, the position and velocity errors both come
# back to within 20 % of their bounds, and just above them at single epochs (the days and the largest ratios are
# printed above). The NEES, which weighs the error against the full covariance with its correlations, exceeds its
# 99.9 % quantile only at the first epochs after the burn (printed).

# %%
_ = plotting.save_figure(ocbe_panels.figure_control_metric(panels["apoapsis window"], f"Fig. 13 analogue, {WINDOW_HOURS:g}-h apoapsis window",
                                                  burn_days=burn_days),
                         "10_fig13_window_tuning_control_metric", output_dir=out)
print(demo.fig13_report())

# %% [markdown]
# **Fig. 13 analogue** (the paper: a consistent filter "with a smoothed control spike around apoapsis that is
# indicative of a maneuver"). With the window tuning the control is essentially zero outside the window, so the
# smoothed spike stands alone and its integral $z$ tracks the burn. A spike inside the window alone does not indicate
# a burn at this tuning, because the window raises the estimated control without one too: in the 200 runs without a
# burn below (full run) the median smoothed contrast at apoapsis is about 800. What indicates the burn is the
# spike's size, $z$, against its distribution without a burn (Section 3). The same holds for the measure of the
# closing table's Fig. 13 row (smoothed $z$ above twice the forward $z$): in 16 quiet-tuned runs without a burn on
# the 9:2 NRHO, run outside the notebook on 2026-11-26 (`detection.run_detection_monte_carlo`, seed 12345), the
# ratio was at least 6.3 at $f = 0.1$ and at least 2.8 at $f_c$. So the row judges the burn runs and the no-burn
# runs of Section 3's training together, as the Fig. 11 row does ("indicative of a maneuver" needs both): a spike
# that appears without a burn as well makes it differ, and the detection rows (Tables 5-8) say what does reveal
# the burn. (Until a referee's pass on 2026-11-26 this row judged the burn runs alone and said "reproduced".)
#
# The forward control rises inside the window too (the estimated control is $-\tilde Q B^\top\mathbf p$, so it
# scales with $q_w$ whether or not there is a burn);
# the paper's text describes only the smoothed spike for this figure, so it does not tell whether its forward panel
# shows the same rise. The forward control stays far below the smoothed one: in this run the smoothed $z$ is the
# printed multiple of the forward $z$ (window tuning), and over the training runs of Section 3 the median multiple
# is in the closing table's Fig. 13 row. With the constant tuning the smoothed control also fits measurement noise
# all along the orbit, so the same burn is a smaller part of a larger $z$. The forward metric need not exceed its
# limit in either case: both tunings absorb the burn as expected control instead of flagging it, which is why the
# paper detects with $z$ and not with the metric.
#
# **The statements behind Figs. 10-11, on many runs.** $N$ quiet-policy runs with a burn and $N$ without (sizes
# printed) are filtered with both tunings at $f = 0.1$ (the same data for both). Criteria (the Fig. 10 limit revised
# on 2026-11-26, see below): *Fig. 10* ("both the forwards and smoothed filters produce consistent, but less
# certain, solutions") holds if at most 10 % of the runs are NEES-inconsistent, forward and smoothed, with and
# without a burn (the chapter's rule for "consistent", as in the Figs. 12-13 rows), and the constant tuning's
# mean forward 3-sigma position bound is larger than the window tuning's;
# *Fig. 11* holds if in at least 90 % of the burn runs the smoothed control's spike contrast at the burn
# (`detection.control_spike_contrast`: mean norm within 6 h of the burn over the mean elsewhere) is at least 2 and
# above the forward one, and in at least 90 % of the runs without a burn the smoothed contrast stays below 2 ("this
# control spike does not appear if there is no maneuver").

# %%
s_const = det.make_setup(em, ORBITS["9:2 NRHO"], s_q.q_window_km2_s3, s_q.q_window_km2_s3, window_hours=WINDOW_HOURS)
spike_study = dstudies.run_spike_study(s_const, s_q, N_SPIKE, [SEED, 42], executor=executor)
print(spike_study.report())
spike, fig10_ok, fig11_h1, fig11_h0 = spike_study.cells, spike_study.fig10_ok, spike_study.fig11_h1, spike_study.fig11_h0

# %% [markdown]
# **Figs. 10-11 on many runs** (the sizes and results printed above). The constant tuning keeps every run without a
# burn consistent and puts its forward 3-sigma bound at more than twice the window tuning's (12.9 against 5.6 km):
# the "consistent, but less certain" of Fig. 10 holds. With a burn 7 % of the forward and 8 % of the smoothed runs
# are inconsistent, inside the 10 % of notebook 09's rule. *How these runs were drawn.* A first draw (seed
# `[SEED, 41]`, an earlier full run) gave 10.5 % smoothed: above 10 % by a quarter of one binomial standard
# error of 200 runs (2.1 points). The row's limit was then widened to 10 % plus two such errors (14.2 %), with
# 10.5 % in view, and the runs were drawn once more with a new seed (`[SEED, 42]`, commit of 2026-11-26 04:27),
# which the row judges. A referee's pass (2026-11-26, later) put the limit back to the chapter's 10 %: a widening
# decided after seeing 10.5 % is a choice made while looking, and no other consistency row of the chapter widens
# its 10 %. The new draw passes the 10 % rule too (full run: at most 8.0 % in any cell). But it is a second draw,
# made after the first had missed this very limit, so the row says so: it is "consistent (tuned)", because the
# constant weight is the window weight at $f = 0.1$ and because the judged runs are the redraw. The smoothed
# spike of Fig. 11 appears without a burn in 2 % of the runs only, but with a burn it stands out (contrast at least
# 2 and above the forward one) in about two runs out of three (64 %; the first draw: 74 %): in the others the
# smoother, which may fit control everywhere, does not concentrate the burn in the 12 hours around it. With the
# window tuning at $f = 0.1$ the forward filter is inconsistent in 58 % of the burn runs, and 69 % of its NEES
# exceedances fall in the day after the burn.
#
# ## 3 · Control-policy distributions (Eq. 33) and the maximum-likelihood test (Eqs. 34-35)
#
# For each orbit and policy: $N_{H0}$ runs without a maneuver and $N_{H1}$ runs with one drawn from the policy
# (500 and 3000 in the paper), each a full OCBE filter and smoother over one period from the periapsis hand-off,
# giving $z = \int_{t_0}^{t_f}\|\hat{\mathbf u}(t)\|dt$ of the smoothed control (Eq. 33, trapezoid rule on 9 points
# per 2-hour interval). Runs go through `cislunar.utils.montecarlo.run_monte_carlo`; the batched OCBE filters 8 runs at a
# time, advancing all of them through the same epochs together, and equals the single-run filter to $10^{-10}$
# (`tests/papers/greaves_scheeres_2021/test_detection.py`).
# Every run also records the NEES of its forward and smoothed estimates, so the same runs measure the consistency
# of the tuning (Section 3b).
#
# The PDFs are Gaussian kernel density estimates with Scott's bandwidth ($n^{-1/5}$ times the sample standard
# deviation). With equal priors and costs the maximum-likelihood rule (Eq. 34) picks H1 where
# $PDF_{H1}(z) > PDF_{H0}(z)$; with a single crossing it is the threshold rule of Eq. 35, $z > z_{lim}$. The
# expected false-positive rate is $\int_{z_{lim}}^\infty PDF_{H0}$ and the missed-detection rate
# $\int_{-\infty}^{z_{lim}} PDF_{H1}$ (Tables 5-6); their Monte Carlo standard errors come from a bootstrap of the
# training runs (`detection.threshold_bootstrap`). Then 100 + 100 fresh runs test the rule (Tables 7-8).
#
# Which stable NRHO the paper used is unknown (its Table 1 is missing). Besides `orbits.stable_nrho` (the inner
# band's edge near the Moon) we run the candidate from the family's outer stable band that notebook 09 finds better
# supported by the paper's Table 4 remark, with a reduced Monte Carlo (a fifth of the training runs, half the
# tests) to bound the run time; its rows say so.
#
# The whole study runs twice: at $f = 0.1$ (threshold reading; the figures) and at $f_c$ (consistency reading; the
# predictions), with independent seeds.

# %%
def sizes(o):
    k = OUTER_SIZE if o == OUTER else 1.0
    return (max(int(k * N_H0), min(N_H0, 20)), max(int(k * N_H1), min(N_H1, 20)),
            max(int(N_TEST * (0.5 if o == OUTER else 1)), min(N_TEST, 10)))


train = dstudies.run_training_studies(setups, setups_c, POLICIES, {o: sizes(o) for o in ORBITS}, SEED, N_BOOT,
                                      batch_size=BATCH, executor=executor)
studies, studies_c, se, nees_rows, lin = train.tuned, train.predicted, train.se, train.nees_rows, train.lin
print(f"Monte Carlo wall time so far: {(time.perf_counter() - T_START) / 60:.1f} min")

# %%
_ = plotting.save_figure(figures.control_integral_pdfs(studies, ORBITS, POLICIES), "10_control_integral_pdfs",
                         output_dir=out)

print(train.tables_report(F_C))

# %% [markdown]
# **Figs. 14-15 and 18-19 analogues** at $f = 0.1$: histograms (left of each pair) and kernel density estimates
# (right) of $z$ without (blue) and with (red) a maneuver; the dotted line is $z_{lim}$, where the two PDFs cross.
# Rows are the three orbits, the left pair the active policy (m/s), the right pair the quiet policy (mm/s).
#
# **How the thresholds are judged.** The paper prints $z_{lim}$ = 0.4106 m/s (active) and 17.22 mm/s (quiet), each
# from its own 500 + 3000 runs: a Monte Carlo estimate with a sampling error the paper does not print, like ours. At
# $f_c$ (the predictions) the tolerance is therefore half a unit of the paper's last printed digit plus two standard
# errors of the *difference*: our bootstrap error and the paper's in quadrature. The paper's is estimated from ours:
# our relative error at the paper's value, scaled to its sample sizes (equal to ours in the full run; a kernel
# density threshold's spread falls as $n^{-2/5}$,
# `detection_studies.paper_threshold_standard_error`). The rule follows from the sample sizes and the printed
# digits, not from our $z_{lim}$. (Until a referee's pass on 2026-11-26 the tolerance used our error alone.) In the
# full run the predictions lie far outside it either way: active 613.88 mm/s against 410.6, with standard errors of
# 13.68 (ours) and 9.15 (the paper's, estimated) mm/s, combined 16.46, a difference of 12.4 combined standard
# errors (tolerance 33.0 mm/s); quiet 22.24 against 17.22 mm/s, errors 0.50 and 0.39, combined 0.63, 7.9 standard
# errors (tolerance 1.27 mm/s). Under the old rule they were 14.9 and 10.0 of our errors off. At $f = 0.1$
# the thresholds are judged within the 25 % band of the threshold reading (tuned), far wider than either error.
#
# ## 3b · Is the window-tuned OCBE consistent? (beyond the paper's figures)
#
# The paper shows single runs (Figs. 12-13) whose errors stay inside their 3-sigma bounds. Every training run of
# Section 3 recorded the NEES of its forward and smoothed estimates against its truth, so the consistency of each
# tuning is measured on all of them: per policy, 500 runs without and 3000 with a burn on the 9:2 and the inner-band
# stable NRHO, a fifth of that on the outer band (the counts are printed below; criterion of notebook 09:
# a run is inconsistent when more than 5 % of its epochs exceed the 99.9 % quantile of $\chi^2_6$, 22.5).

# %%
print(train.nees_report(ORBITS))

# %% [markdown]
# **Which cells fail, and why.** At $f = 0.1$ no cell without a burn (H0) has more than 1.2 % inconsistent runs;
# the mean forward NEES without a burn is 4.7-5.1 (below 6: the hand-off covariance is conservative), the mean
# smoothed NEES on the inner-band stable NRHO is about 8 (slightly optimistic, without making runs fail). Every
# failing cell has a burn: the forward filter fails in 12-58 % of the burn runs, more for the quiet policy than
# for the active one, and the smoothed estimate in 10-19 % of the quiet burn runs on the 9:2 and the inner-band
# stable NRHO.
# The forward failures are expected: at $f = 0.1$ the window admits a tenth of the burn's velocity variance, so
# until the measurements have pulled the estimate over, the error is several standard deviations. At $f_c$ every
# cell of all three orbits stays at or below 3.2 % of its runs: the window tuning *can* be consistent, as the
# paper says, at the price of a larger $z$ without a burn.
#
# ## 4 · Sensitivity of $z$ to the maneuver (Figs. 16-17, 20-21)
#
# The paper finds $z$ nearly linear in the impulse magnitude (so it could estimate it) and, for the active policy,
# largest for burns along $\pm\hat j$ (azimuth $\pm90°$, low elevation), where the burn is best aligned with the
# measurement sensitivity at apoapsis; for the quiet policy that pattern is weaker. The figure shows the 9:2
# NRHO's training runs at $f = 0.1$: $z$ over the pointing (left), $z/|\Delta v|$ over the azimuth (middle) and
# $z$ against the magnitude (right; circles 9:2, crosses the inner stable NRHO, drawn over each other: the two
# clouds coincide).

# %%
_ = plotting.save_figure(figures.z_vs_maneuver(studies, ORBITS, POLICIES), "10_z_vs_maneuver", output_dir=out)

print(train.lin_report())

# %% [markdown]
# **Looking for the $\pm\hat j$ pattern.** Where could the paper's bimodality come from? We fire 1 m/s burns along
# $\pm\hat\imath$, $\pm\hat\jmath$, $\pm\hat k$ (the same noise draws for every direction,
# `detection.direction_response`) on the 9:2 NRHO and vary what shapes how well a burn is seen: the window weight
# factor $f$, the angle noise (up to 100 times ours; the paper's Table 3 is missing), and the burn time within the
# 8-hour window (3 hours before apoapsis, at it, 3 hours after). The contrast is the mean $z$ of the
# $\pm\hat\jmath$ burns over that of the four others (1 = no preference). The line of sight from the L2 observer
# to apoapsis is printed: a burn along it changes only the range, which angles do not measure.

# %%
pm_j = dstudies.run_pm_j_search(em, ORBITS["9:2 NRHO"], PM_J_F, PM_J_NOISE_URAD, PM_J_OFFSET_H, PM_J_SEEDS, [SEED, 31],
                                q_base_km2_s3=Q_BASE, window_hours=WINDOW_HOURS, executor=executor)
print(pm_j.report())
pmj, ((f_pm, sig_pm, _), _) = pm_j.cells, pm_j.best

# %% [markdown]
# Where the pattern is strongest we run the paper's experiment itself: randomly pointed burns from both policies
# (Eqs. 3-5; the sizes printed), and the same statistic as for the training runs above (mean $z/|\Delta v|$ at
# azimuth $\pm90°$ over that at 0°/180°, elevations below 45°).

# %%
# both policies' Monte Carlos in one pooled sweep (the same trials as one run_detection_monte_carlo per policy)
pm_jobs = [(det.make_setup(em, ORBITS["9:2 NRHO"], f_pm * det.window_control_weight(pol, WINDOW_HOURS), Q_BASE,
                           window_hours=WINDOW_HOURS, sigma_angle_rad=sig_pm * 1e-6), pol, N_PM_J_MC, [SEED, 33, j])
           for j, pol in enumerate(POLICIES.values())]
pm_mc = dict(zip(POLICIES, det.run_detection_monte_carlos(pm_jobs, batch_size=BATCH, executor=executor)))
for p, h in pm_mc.items():
    print(f"{p:6s}: {len(h.z)} randomly pointed burns, f = {f_pm:g}, noise {sig_pm:g} urad: Fig. 16 statistic "
          f"{dstudies.ratio_text(det.azimuth_contrast(h))}; mean z/|dv| {np.mean(h.z / h.magnitude):.2f}; corr(z, |dv|) "
          f"{np.corrcoef(h.magnitude, h.z)[0, 1]:.2f}")
_ = plotting.save_figure(figures.pm_j_search(pmj, PM_J_F, PM_J_NOISE_URAD, PM_J_OFFSET_H, f_pm, sig_pm, pm_mc["active"]),
                         "10_pm_j_search", output_dir=out)

# %% [markdown]
# **The $\pm\hat j$ search** (left: burn at apoapsis, per window factor; middle: the burn time within the window at
# the factor where the pattern is strongest; right: the random-burn runs of that regime, coloured by
# $z/|\Delta v|$). At our noise the paired contrast stays between 1.01 and 1.10 whatever $f$ and the burn time:
# every direction is seen. There $z$ of a 1 m/s burn never falls short of it; it lies above it, the more so the
# larger $f$ (up to about 1.6 m/s at $f = 1$; the ranges are printed above), because the control also fits noise and
# the integral without a burn grows with the window weight. The burn time within the window moves the contrast by
# less than a tenth at our noise (up to 0.08, at $f$ = 0.3 and 1) and by a few hundredths where the pattern is
# strongest (both printed above). The pattern appears only when the angles see the burn poorly: from 300 micro-rad
# with a small window weight, reaching 1.7 at 1000 micro-rad and $f = 0.03$. The mechanism is the paper's own: the
# line of sight from L2 to apoapsis (printed) lies in the $\hat\imath$-$\hat k$ plane, so a burn along $\hat k$ or
# $\hat\imath$ partly changes the range, which angles do not measure, while $\hat\jmath$ is perpendicular to it; the
# smoother then puts less of a poorly seen burn into the control. With random pointing in that regime the Fig. 16
# statistic is 1.2 for the active policy and 1.0 for the quiet one, as the paper describes. But there $z$ recovers
# only about a quarter of the burn, correlates weakly with its size, and quiet burns vanish in the noise (both
# printed above): Figs. 17 and 21 and the 97 % quiet detection fail. No regime searched shows the pattern together
# with the paper's other results.
#
# ## 5 · Detection tests on independent data (Tables 7-8)
#
# Fresh runs (seeds independent of the training runs) are classified with Eq. 35 and the $z_{lim}$ above, at both
# tunings.

# %%
acc = {(k, t): train.accuracy(k, t) for t in dstudies.TAGS for k in train.studies[t]}
print(train.accuracy_report(F_C))

# %% [markdown]
# **How the accuracies are judged.** Table 7 prints whole percent, so the paper's 100 % means at least 99.5 % and
# its 97 % lies in [96.5, 97.5] %. The paper's accuracies are counts over its own 100 + 100 test runs, Monte Carlo
# estimates like ours. The tolerance of each accuracy row is that half point plus two standard errors of the
# difference: the binomial errors of an accuracy over our 200 test runs and over the paper's 200, in quadrature,
# each taken at the end of the paper's interval nearer one half (where the error is largest): 0.5 + 2 x 0.71 = 1.9
# points at 100 %, 0.5 + 2 x 1.84 = 4.2 points at 97 %. History: a rule with a floor of one point per standard
# error gave a 2-point tolerance at 100 % that neither the printed digits nor 200 runs support; under it a 98.0 %
# sat exactly on the edge. It was replaced (after the 98.0 % was seen, but stricter) by half a point plus two of
# our binomial errors alone, 1.5 points at 100 %, which left out the paper's own sampling error; a referee's pass
# (2026-11-26, later) added it, a widening fixed by the two sample sizes and the printed digits, not by our counts,
# under which 98.0 % still differs (by 0.1 point). The normal
# approximation behind a binomial standard error is poor next to 100 %, so each accuracy row also carries two exact
# tests in its note: the binomial probability of at least our number of errors if the true accuracy sat at the
# edge of the paper's printed interval, and Fisher's exact test of our counts against the paper's own 100 + 100 test
# runs. For 196 of 200 against 100 % (full run, $f_c$, active) the row misses by 0.1 point: $-2.0$ points against a
# 1.9-point tolerance. The exact binomial probability of so many errors at 99.5 % accuracy is 1.9 %, below the
# 2.3 % one-sided level of two standard errors, so that test agrees with the row. Fisher's test of our counts
# against the paper's gives p = 0.12: the paper's own 200 runs could not tell 98 % from 100 %, and the row's miss is
# narrow. The status is the declared rule's; the row says by how much it misses.
#
# **The two stable candidates, side by side** (both tunings): detection accuracy, the expected error of the test
# with its bootstrap standard error (a finer measure than 200 test runs) and the worst consistency cell.

# %%
print(train.candidates_report(ORBITS, POLICIES))

# %%
print(train.stable_difference_report(STABLE, POLICIES))

# %% [markdown]
# At either tuning the accuracies of the three orbits lie within a few test runs of each other, and the expected
# errors, a finer measure than 200 test runs, differ from the 9:2 NRHO's by less than two combined standard errors
# (printed above). At $f_c$ the test runs even repeat the paper's pattern (full run: quiet 99.0 % on the inner-band
# stable NRHO against 96.0 % on the 9:2, the paper's 200/200 against 194/200; active 98.0 % on both), but the expected
# errors show that gap to be the noise of 200 test runs. What "marginally better" can be tested for at these sizes:
# that the stable orbit is not worse (the 9:2 NRHO is not resolved better) and not better by more than the paper's own
# largest gap, 3 accuracy points, i.e. 0.06 in FP + MD. What it cannot: the sign of a difference smaller than two
# combined standard errors, about 0.013 in FP + MD (0.65 accuracy points) on the inner band and 0.018 on the outer
# band's reduced Monte Carlo; "better" itself is not confirmed. The closing table judges the two-sided reading and
# marks it tuned (it was written after the values were seen, and an unresolved difference passes it). At
# $f = 0.1$ the window-tuned filter is least consistent on the inner-band orbit; at $f_c$ all three are consistent.
# Detection therefore does not decide between the candidates; notebook 09's determination and consistency results do
# (the outer band), and both stay in the table.

# %% [markdown]
# ## 6 · Control as a health metric (Fig. 22)
#
# The filter is tuned for the quiet policy but the vehicle burns 0.5 m/s (ten times the quiet mean). The paper
# reports that the smoothed estimate diverges while the measurement residuals look benign, and that
# $z = 0.4761$ m/s, "approximately at 30 sigma of the maneuvering distribution of Z" — a fast, sensitive health
# metric. We first run the same experiment once (random pointing) at $f = 0.1$ and draw the paper's panels.

# %%
health = det.draw_trial(np.random.default_rng([SEED, 8]), s_q, magnitude_m_s=0.5)
rh = det.run_trial_filter(s_q, health)
ref = studies["9:2 NRHO", "quiet"]
z_h = rh.z_smooth * em.velocity_unit_km_s * 1e3
nees_h = consistency.nees(rh.x_smooth, rh.P_smooth, health.truth)
_ = plotting.save_figure(figures.health_metric(s_q, health, rh, ref, z_h), "10_health_metric", output_dir=out)
print(f"impulse 0.5 m/s (azimuth {np.degrees(health.azimuth):.0f} deg, elevation {np.degrees(health.elevation):.0f} "
      f"deg): z = {z_h:.4f} m/s = {(z_h - ref.h1.z.mean()) / ref.h1.z.std():.0f} sigma of quiet H1")
print(f"smoothed NEES mean {nees_h.mean():.0f} (6 if consistent); residual norms: median "
      f"{np.median(rh.residual_norms):.2f}, max {rh.residual_norms.max():.2f}; fraction above the 99% level "
      f"{np.mean(rh.residual_norms > np.sqrt(stats.chi2.ppf(0.99, 4))):.2f}")

# %% [markdown]
# **The single run** (full run: a 0.5 m/s burn at azimuth 93°, elevation 50°; the lines above are this run's). Its
# $z$ = 0.448 m/s lies 30 standard deviations above the mean of the quiet training runs, as the paper reports, and
# the smoothed estimate diverges (mean NEES 270, against 6 for a consistent filter; left panel). But the residuals
# are not benign. Under a correct model the whitened residual norm is the square root of a $\chi^2_4$ variable: its
# median is 1.83 and 1 % of the epochs lie above the dotted 99 % level, 3.64. In this run the median over the track
# is 3.25 and 47 % of the epochs lie above that level, every one of them after the burn, starting at the first
# epoch after it (middle panel). At our noise the left half of Fig. 22 (the estimate diverges, $z$ catches the
# burn) holds and the right half (residuals that miss the burn) does not. Whether this run is typical is measured
# below on all the 0.5 m/s runs of this section, and the race measures when each test reacts.
#
# **Is $z$ of a given burn independent of the tuning?** One would expect $z$ of a 0.5 m/s burn to be about 0.5 m/s
# whatever the window weight. We fly the same $N$ randomly pointed 0.5 m/s burns (sizes printed) through the quiet
# tuning at every factor of the grid. The paper's value is one run, so the tolerance of the comparison is fixed
# from our single-run spread: agreement when 0.4761 m/s lies within half its last printed digit ($5\times10^{-5}$)
# plus two standard errors of the difference between one run and our mean of $n$ runs, $sd\sqrt{1 + 1/n}$ ($sd$ the
# single-run standard deviation; until 2026-11-26 two $sd$, which left out our mean's own error, 0.8 % of the
# tolerance at 64 runs). The paper's "about 30 sigma" has one significant digit: agreement
# when our level rounds to 30, i.e. lies in [25, 35). The level is (mean $z$ of the 0.5 m/s burns $-$ mean of the
# quiet H1 training runs) / their standard deviation, both at the same tuning.

# %%
z05_study = dstudies.run_burn_z_study(s_q, ORBITS["9:2 NRHO"], set(F_GRID) | {F_C, F_TUNE}, 0.5, N_Z05, [SEED, 8],
                                      q_base_km2_s3=Q_BASE, window_hours=WINDOW_HOURS, executor=executor)
z05 = z05_study.z
print(z05_study.report())
sig_level = {}
for tag, f_, group in (("f = 0.1", F_TUNE, studies), ("f_c", F_C, studies_c)):
    h1q = group["9:2 NRHO", "quiet"].h1.z
    sig_level[tag] = z05_study.sigma_level(f_, h1q)
    print(f"{tag}: 0.5 m/s burns sit at {sig_level[tag]:.1f} sigma of the quiet H1 training distribution "
          f"(mean {h1q.mean() * 1e3:.1f} mm/s, sd {h1q.std() * 1e3:.1f} mm/s)")

# %% [markdown]
# **$z$ of a given burn depends on the tuning.** The quiet window makes control expensive, so the smoother puts
# only part of a 0.5 m/s burn into it: about 0.34 m/s at $f = 0.03$, 0.43 at $f = 0.1$, 0.47 at $f = 0.3$ and
# 0.49 at $f = 1$, with a single-run spread that shrinks as $f$ grows (printed above). The paper's 0.4761 m/s lies
# within two single-run standard deviations at $f = 0.1$ and at $f_c$, and the 0.5 m/s burns sit at 29 and 31
# sigma of the quiet training runs. At $f_c$, which no number of the paper chose, both are predictions.
#
# **Fig. 22 over many runs.** The paper shows one run, but reads it as the typical behaviour ("most common filters
# ... would miss this filter divergence"). So we ask whether the paper's run is a plausible draw at our noise: the
# $N$ 0.5 m/s burns above, at both readings of $f$, are refiltered to keep what the figure plots, and each run is
# checked for the combination: the estimate diverges (mean smoothed NEES above 20) while the residuals stay benign.
# Benign means that the residual monitor of the race below (a squared whitened residual above the 3-sigma tail of
# its $\chi^2_4$ law) stays silent for the 24 hours after the burn. A lenient reading, the median residual norm over
# the whole track below 3 (the test first applied to the single run), is printed too: half of the track's epochs
# precede the burn, so that median hardly sees it. The paper's run is a plausible draw when the share of runs with
# the combination is not resolved below 5 %, i.e. is at least 5 % less two binomial standard errors of a 5 % share
# over our runs (fixed before the share was computed; the claims module records that the benign test was tightened
# from the lenient one after the lenient share had been seen).

# %%
# the same 0.5 m/s burns as the z study above (seed [SEED, 8]), refiltered at both readings to keep NEES and residuals
runs05 = det.draw_trials(np.random.default_rng([SEED, 8]).spawn(N_Z05), s_q, magnitude_m_s=0.5)
s_cq = setups_c["9:2 NRHO", "quiet"]
res05 = det.filter_trial_sets([(s_q, runs05), (s_cq, runs05)], executor=executor)
health_runs = {}
for tag, f_, s_, r in zip(dstudies.TAGS, (F_TUNE, F_C), (s_q, s_cq), res05):
    np.testing.assert_allclose(r.z_smooth * em.velocity_unit_km_s * 1e3, z05[f_], rtol=1e-9)  # the z study's runs
    health_runs[tag] = dstudies.HealthRuns.from_filter(s_, runs05, r)
    print(f"{tag}: combination in {health_runs[tag].text()}")
hr_all = dstudies.HealthRuns.pooled(health_runs.values())
print(f"pooled: {100 * hr_all.share:.1f} % of {len(hr_all)} runs; the floor less two standard errors: "
      f"{100 * (HEALTH_PLAUSIBLE_FLOOR - 2 * hr_all.floor_standard_error):.2f} %")

# %% [markdown]
# **The paper's run is not a typical draw at our noise** (full run, 64 + 64 runs; the lines above are this run's).
# The estimate diverges in every run, but the residual monitor fires within 24 hours of the burn in all 64 runs at
# $f = 0.1$ and 63 of 64 at $f_c$: 1 run of 128 (0.8 %) shows the paper's combination, below the floor (1.1 %; the
# exact binomial probability of so few if the true share were 5 % is 1 %). The lenient whole-track median stays
# below 3 in 91 % and 100 % of the runs, which is why one run near its limit looked like a borderline case: the
# figure's run (median 3.25, drawn apart from these) falls among the 9 % at $f = 0.1$ where even the lenient reading
# sees the burn.
#
# **Does the control react before the residuals? (Fig. 22's claim, measured.)** The paper's statistic is the
# smoothed control integral; an analyst can recompute it at every epoch on the data received so far. After an
# unexpected burn we race two online tests, evaluated at every epoch of the 24 hours after the burn and both set
# to the same per-epoch false-alarm probability, the 3-sigma tail (0.135 %), of their no-burn distributions
# (`detection.health_lead_study`):
#
# * *control test*: the smoothed $z$ of the arc received so far (the smoother rerun at each epoch) above the
#   3-sigma tail of a log-normal law fitted to no-burn runs at the same epoch;
# * *residual test*: the squared whitened innovation (the forward OCBE metric, $\chi^2_4$ under a correct model)
#   above its 3-sigma tail.
#
# Randomly pointed burns of 0.05 to 0.5 m/s are raced at the quiet tuning ($f = 0.1$ and $f_c$) with our noise,
# and at $f = 0.1$ with a ten times larger angle noise. The false-alarm rates over the 24 hours are measured on
# independent no-burn runs.

# %%
lead = {}
for i, (tag, f_, sig_) in enumerate((("f = 0.1, 10 urad", F_TUNE, 10.0), (f"f_c = {F_C:g}, 10 urad", F_C, 10.0),
                                     ("f = 0.1, 100 urad", F_TUNE, 100.0))):
    s_l = det.make_setup(em, ORBITS["9:2 NRHO"], f_ * det.window_control_weight(det.QUIET_POLICY, WINDOW_HOURS), Q_BASE,
                         window_hours=WINDOW_HOURS, sigma_angle_rad=sig_ * 1e-6)
    lead[tag] = det.health_lead_study(s_l, LEAD_MAGNITUDES, N_LEAD[0], N_LEAD[1], [SEED, 60, i], executor=executor)
print(dstudies.lead_report(lead, N_LEAD[0]))
_ = plotting.save_figure(figures.health_lead(lead), "10_health_lead", output_dir=out)

# %%
print(dstudies.lead_reading(lead))


# %% [markdown]
# **The race** (bars: per burn size, the share of runs in which the control test fires first, the residual test
# fires first, both at the same epoch, or neither within 24 hours). At our noise the control test fires strictly
# first in most runs for burns of 0.05-0.1 m/s, one to two times the quiet policy's mean, where the residuals stay
# inside their tail for hours: the paper's "fast acting" health metric holds for burns near the expected size.
# For the 0.5 m/s burn of Fig. 22 it does not: both tests fire within an epoch or two, the residuals first or at
# the same epoch in more than nine runs out of ten, because ten quiet means of unexpected velocity move the
# angles by several noise standard deviations within two hours. With ten times our noise the residuals do stay
# silent for 24 hours in most 0.5 m/s runs, as in the paper's figure, but then the control test misses them too:
# the quiet window absorbs only about a fifth of the burn (median $z$ printed above), far from the paper's
# "appropriate estimate of the maneuver size". None of the three settings gives the paper's combination of
# benign residuals and a $z$ close to the burn.

# %% [markdown]
# **The race over noise and window weight.** The three settings above leave a gap between 10 and 100 micro-rad and
# between the factors. The paper's figure needs two things at once: residuals that stay benign after the
# unexpected burn, and a control integral that both reacts and recovers the burn. More noise helps the first and
# hurts the second; a larger $f$ helps the second. So the race is rerun with the 0.5 m/s burn of Fig. 22 (and
# 0.1 m/s for contrast) on a grid of angle noise from 20 to 50 micro-rad and of window factors (sizes printed;
# `detection_studies.run_lead_grid`). A cell shows the paper's combination when, for the 0.5 m/s burns, the residual
# test stays silent for 24 hours in more than half of the runs, the control test fires within 24 hours and strictly
# first in more than half, and the median $z$ is at least half the burn: criteria fixed before the grid ran.

# %%
race = dstudies.run_lead_grid(em, ORBITS["9:2 NRHO"], RACE_F, RACE_NOISE_URAD, (0.1, 0.5), N_RACE[0], N_RACE[1],
                              [SEED, 61], q_base_km2_s3=Q_BASE, window_hours=WINDOW_HOURS, executor=executor)
print(race.report())
_ = plotting.save_figure(figures.lead_grid(race), "10_race_grid", output_dir=out)

# %% [markdown]
# **The race grid** (per window factor, one line per noise level: left, the share of 0.5 m/s runs whose residual
# test stays silent for 24 hours; middle, the share in which the control test fires strictly first; right, the
# median $z$ over the burn; dotted: the criteria).
#
# **What the grid shows** (full run: $f$ = 0.1, 0.3, 1 and 20, 30, 50 micro-rad; 48 burns per size and cell,
# 100 no-burn runs each to calibrate and to validate; the lines above are this run's). The residual test stays
# silent for 24 hours in at most a third of the 0.5 m/s runs (33 % at $f = 1$ and 50 micro-rad; 0-25 % elsewhere),
# never in more than half: within this range of noise a burn of ten quiet means moves the angles visibly within a
# few epochs. Its silence grows with the noise and with $f$ (a larger window weight lets the filter absorb the burn
# as control instead of as residual). The control test fires within 24 hours in 83-100 % of the runs, but strictly
# first in more than half only at $f = 1$ and 50 micro-rad (52 %). The median $z$ recovers 40-95 % of the burn,
# more with larger $f$ and less with more noise. The false alarms over 24 hours stay at or below 4 % (residual) and
# 0 % (control). No cell shows the paper's combination; the nearest, $f = 1$ at 50 micro-rad, fails on the benign
# residuals. At the 100 micro-rad of the first race the residuals are benign but $z$ recovers a fifth of the burn at
# $f = 0.1$: the two halves of the paper's Fig. 22 statement pull the noise in opposite directions, and a large
# window weight moves the crossing only slowly. Two extra cells at $f = 1$, run outside the notebook on 2026-11-26
# with the same sizes (set `RACE_F = [1]`, `RACE_NOISE_URAD = [75, 100]` to rerun them), show where it goes: at 75
# micro-rad the residuals stay silent in 54 % of the 0.5 m/s runs, but the control test then fires within 24 hours
# in only 65 % and first in 33 % ($z$ recovers 66 % of the burn); at 100 micro-rad 69 %, 46 % and 31 %. Once the
# residuals are benign, the control test is no longer the fast one.

# %% [markdown]
# ## Paper versus reproduction
#
# Every closing table of this reproduction uses the same status words, and the legend printed under the table says
# what each one means. In short: *reproduced* only for an independent prediction within a tolerance fixed before
# comparing (stated in the row); *consistent (tuned)* where agreement rests on a choice made while looking at the
# paper (here the window-weight factor $f = 0.1$ of the threshold reading); *differs* with the reason otherwise;
# *derived*, *not in paper* and *beyond paper* for what the paper gives no number for, our own inputs, and checks
# the paper does not attempt.
# Predictions come from the consistency reading $f_c$. Two inputs are our choices because the paper's tables are
# missing: the measurement noise (10 micro-rad angles, Eq. 13 rates with 1 s differencing) and the base weight
# ($10^{-18}$ km$^2$/s$^3$); Section 2 maps both.

# %%
J = dstudies.closing_rows(  # claim key -> the keyword arguments of Claim.judge (measured value, how shown, context)
    ks_text=ks_txt, tmap=tmap, f_tune=F_TUNE, counts=dict(
        n_h0=N_H0, n_h1=N_H1, n_test=N_TEST, outer_sizes=sizes(OUTER), n_spike=N_SPIKE, n_z05=N_Z05, n_lead=N_LEAD,
        n_pm_j_mc=N_PM_J_MC, pm_j_seeds=PM_J_SEEDS),
    q_window_quiet=(setups["9:2 NRHO", "quiet"].q_window_km2_s3, setups_c["9:2 NRHO", "quiet"].q_window_km2_s3),
    spike=spike_study, train=train, pm_j=pm_j, pm_mc=pm_mc, burn_z=z05_study, sig_level=sig_level, lead=lead,
    health_nees_mean=float(nees_h.mean()), health_residual_norms=rh.residual_norms, sigma_angle_rad=SIGMA_ANGLE,
    joint=joint, lead_grid=race, health_runs=health_runs)
assert set(J) == set(CLAIMS), set(J) ^ set(CLAIMS)  # every declared claim is judged, none is typed
for key, row in J.items():
    table.add(CLAIMS[key].judge(**row))
executors.close()  # shuts the worker processes down
print(f"notebook wall time: {(time.perf_counter() - T_START) / 60:.1f} min")
table.display()

# %% [markdown]
# ## Exercises
#
# Each exercise changes one parameter of the `parameters` cell at the top; rerun the chapter (in Jupyter, or with
# `python -m cislunar.publish.notebooks --quick 10 -p NAME=VALUE`), write down your prediction first, then compare.
# The worked solutions are functions of `cislunar.papers.greaves_scheeres_2021.exercises` that answer each question
# at a small size in a few seconds and return the numbers with a one-paragraph answer.
#
# 1. **The window weight.** Set `F_GRID = [0.03, 0.3, 1.0]`. Before running: how do the mean $z$ without a burn,
#    the mean $z$ with one and the threshold $z_{lim}$ change as $f$ grows (what does the smoother fit as control
#    when the window makes control cheap)? Does the test gain or lose power, and where does the tuning map put
#    $f_c$? Check the map's table and figure in Section 2. Worked solution: `exercise_10_window_factor`.
# 2. **Where the $\pm\hat\jmath$ pattern lives.** Set `PM_J_NOISE_URAD = [10, 3000]`. Predict the $\pm\hat\jmath$
#    contrast at each noise level from the geometry printed in Section 4 (the line of sight from L2 to apoapsis),
#    and what happens to $z$ of a 1 m/s burn when the angles barely see it. Worked solution:
#    `exercise_10_pm_j_noise`.
