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
# # 09 · Optical tracking of NRHOs with the square-root-information OCBE: which observation strategy works?
#
# **What you will learn.** How azimuth/elevation angles and their rates measured by a cislunar observer constrain
# a spacecraft on a near-rectilinear halo orbit; how the optimal-control-based estimator (OCBE) turns a
# state/costate transition matrix into a process-noise-like term and is run in square-root-information (SRI) form
# with Householder triangularisations; and how to decide, by Monte Carlo and a consistency test, whether a
# measurement strategy keeps the filter on the truth through perilune.
#
# **Paper sections followed.** Greaves & Scheeres, *Observation and Maneuver Detection for Cislunar Vehicles*
# (JAS 2021): "Measurements" (Eqs. 6-13), "State Estimation" with the SRI OCBE (Eqs. 14-32) and "Observation
# Strategy" (Fig. 4, Table 4, Fig. 5). Section 5d tests the paper's operational statements: the SRI form and the
# re-linearisation ("State Estimation"), the 2-hour "sweet spot" (end of "Observation Strategy") and custody "for an
# indefinite time" (end of "Filter Tuning Strategy", "Proposed OCBE Tuning"). The reference orbits and observer
# sites come from notebook 01.
#
# The paper's Table 3 (measurement noise) and Table 4 (final covariance levels) are missing from its text; what we
# use instead is stated where it is used, and the closing table says where our results differ.

# %% [markdown]
# **How to use this chapter.** The next cell (tagged `parameters`) holds every setting a reader might change: the
# cadences and Monte Carlo sizes, the angle noise and the OCBE control weight, the noise levels of Section 4 and the
# grid of the regime map of Section 5b. Leave an entry at `None` and the notebook picks it (the values in brackets
# in the comments: fewer cadences and runs when `QUICK = True`, then the full run); give a value (edit the cell, or
# pass `-p NAME=VALUE` to the runner) and it is used as given in both modes. The Monte Carlo runs are spread over
# `WORKERS` local processes or a Dask cluster (`SCHEDULER`); run $i$ of a set always draws from child $i$ of the
# set's seed, so the numbers do not depend on where they run.

# %% tags=["parameters"]
QUICK = False
SEED = 0  # root seed of every Monte Carlo set and of the typical run
OUTPUT_DIR = ""
CADENCES_H = None  # measurement cadences, hours (None: [2, 12] quick; [1/60, 10/60, 1, 2, 6, 12] full)
N_RUNS = None  # Monte Carlo runs per (orbit, measurement type, cadence) (None: 2 quick, 20 full)
N_RUNS_ONE_MINUTE = None  # runs at cadences under 0.1 h; 9450 updates per run at 1 min (None: 2 quick, 4 full)
SIGMA_ANGLE_URAD = 10.0  # 1-sigma angle noise of Sections 2-5, micro-rad (rates: sqrt(2) x this per s, Eq. 13)
CONTROL_WEIGHT_KM2_S3 = 1e-20  # OCBE control weight q per axis (acceleration power spectral density), km^2/s^3
TYPICAL_CADENCE_H = 2.0  # cadence of the typical run of Section 2 (Fig. 5), hours
NOISE_LEVELS_URAD = [100.0, 1000.0]  # larger angle noises tried on the 9:2 NRHO at 12 h (Section 4), micro-rad
N_RUNS_FIVE = None  # runs of the five-observer, angles-only experiment (None: 2 quick, 20 full)
NOISES_FIVE_URAD = None  # five-observer runs: angle noises, micro-rad, Fig. 4 a tenth (None: [10] quick; 1-100 full)
HANDOFF_MAP = None  # regime map: hand-off 3-sigma scales (x 10 km, 10 cm/s) (None: [1, 300] quick; 0.1-1000 full)
SIGMA_MAP = None  # regime map: angle noises, rad (None: [10e-6] quick; [1e-6, 10e-6, 100e-6] full)
CADENCE_MAP = None  # regime map: cadences, hours (None: [12] quick; [2, 12] full)
N_MAP = None  # runs per regime-map cell (None: 2 quick, 10 full)
CADENCE_AXES = None  # filter-side axes (Section 5c): cadences, hours (None: [12] quick; 1 h-12 h, 10 and 1 min full)
N_AXES = None  # runs per filter-axis cell (None: 2 quick, 10 full)
N_AXES_ONE_MINUTE = None  # runs per filter-axis cell at the 1-min cadence (None: 2 quick, 4 full)
N_DRAWS_EXAMPLE = 10  # fresh draws per Fig. 4 analogue (the clearest divergence is shown)
CUSTODY_PERIODS = None  # custody tracks (Section 5d): NRHO periods, a burn at every apoapsis (None: 5 quick, 10 full)
N_CUSTODY = None  # custody runs per station-keeping policy (None: 2 quick, 32 full)
CUSTODY_WEAK = None  # also run custody with a window weight 10x weaker, Section 5d (None: no quick, yes full)
LADDER_RUNGS = None  # rungs of the conditioning ladder run, by index 0-3 (None: [0, 2] quick, [0, 1, 2, 3] full)
COST_REPEATS = None  # timed repeats per cadence of the run-time study (None: 1 quick, 3 full)
N_DRAWS_CONDITIONING = None  # Monte Carlo draws per case of the SRI / covariance comparison (None: 20 quick, 50 full)
CADENCES_COST = None  # run time against cadence, hours (None: [2, 6, 12] quick; 1 min, 10 min, 30 min, 1-12 h full)
WORKERS = None  # local processes for the Monte Carlo, 1 runs serially (None: 1 quick, 2 full)
SCHEDULER = ""  # address of a Dask scheduler to run on, e.g. "tcp://10.0.0.5:8786" ("": none; WORKERS applies)

# %%
cadences_full = [1 / 60, 10 / 60, 1.0, 2.0, 6.0, 12.0]  # 1 min, 10 min, 1 h, 2 h, 6 h, 12 h
cadences_h = CADENCES_H if CADENCES_H is not None else ([2.0, 12.0] if QUICK else cadences_full)
n_runs = N_RUNS if N_RUNS is not None else (2 if QUICK else 20)
n_runs_one_minute = N_RUNS_ONE_MINUTE if N_RUNS_ONE_MINUTE is not None else (2 if QUICK else 4)
n_runs_five = N_RUNS_FIVE if N_RUNS_FIVE is not None else (2 if QUICK else 20)
noises_five = NOISES_FIVE_URAD if NOISES_FIVE_URAD is not None else ([10.0] if QUICK else [1.0, 10.0, 100.0])
handoff_full = [0.1, 1.0, 10.0, 100.0, 300.0, 1000.0]  # 1 km to 10,000 km (3 sigma)
handoff_map = HANDOFF_MAP if HANDOFF_MAP is not None else ([1.0, 300.0] if QUICK else handoff_full)
sigma_map = SIGMA_MAP if SIGMA_MAP is not None else ([10e-6] if QUICK else [1e-6, 10e-6, 100e-6])
cadence_map = CADENCE_MAP if CADENCE_MAP is not None else ([12.0] if QUICK else [2.0, 12.0])
n_runs_map = N_MAP if N_MAP is not None else (2 if QUICK else 10)
# the minutes come last: a cell's draws follow its place in the list, so the hour cells keep theirs
cadence_axes = CADENCE_AXES if CADENCE_AXES is not None else ([12.0] if QUICK else [1.0, 2.0, 6.0, 12.0, 10 / 60, 1 / 60])
n_runs_axes = N_AXES if N_AXES is not None else (2 if QUICK else 10)
n_runs_axes_1min = N_AXES_ONE_MINUTE if N_AXES_ONE_MINUTE is not None else (2 if QUICK else 4)
custody_periods = CUSTODY_PERIODS if CUSTODY_PERIODS is not None else (5 if QUICK else 10)
n_custody = N_CUSTODY if N_CUSTODY is not None else (2 if QUICK else 32)
custody_weak_run = CUSTODY_WEAK if CUSTODY_WEAK is not None else not QUICK
ladder_rungs = LADDER_RUNGS if LADDER_RUNGS is not None else ([0, 2] if QUICK else [0, 1, 2, 3])
cost_repeats = COST_REPEATS if COST_REPEATS is not None else (1 if QUICK else 3)
n_draws_conditioning = N_DRAWS_CONDITIONING if N_DRAWS_CONDITIONING is not None else (20 if QUICK else 50)
cadences_cost = CADENCES_COST if CADENCES_COST is not None else (
    [2.0, 6.0, 12.0] if QUICK else [1 / 60, 10 / 60, 0.5, 1.0, 2.0, 4.0, 6.0, 12.0])
workers = WORKERS if WORKERS is not None else (1 if QUICK else 2)
sigma_angle = SIGMA_ANGLE_URAD / 1e6  # rad (division, so that 10.0 gives exactly 10e-6)

import contextlib
import time

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2021 import custody as cu
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import figures, tracking
from cislunar.papers.greaves_scheeres_2021 import observation_strategy as obs
from cislunar.papers.greaves_scheeres_2021.claims.observation_strategy import CLAIMS
from cislunar.papers.greaves_scheeres_2021.claims.operations import CLAIMS as OPS
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.utils.executors import open_executor

plotting.use_style()
out = OUTPUT_DIR or None
# One executor for the whole chapter, opened here and closed before the closing table: its worker processes
# compile the integrators once and keep them for every Monte Carlo set below.
executors = contextlib.ExitStack()
executor = executors.enter_context(open_executor(workers, SCHEDULER))
table = ComparisonTable("09 OCBE observation strategy (Greaves & Scheeres 2021 §Measurements, §State Estimation, "
                        "§Observation Strategy)")
nrho, stable, outer = orbits.nrho_9_2(em), orbits.stable_nrho(em), orbits.stable_nrho_outer(em)
ORBITS = {"9:2 NRHO": nrho, "stable NRHO (inner band)": stable, "stable NRHO (outer band)": outer}
for name, o in ORBITS.items():
    print(f"{name:>25}: perilune {o.perilune_radius_km:8.0f} km, period {o.period_days:.3f} d, "
          f"stability index {o.stability_index:.3f}")

# %% [markdown]
# **Which stable NRHO?** The paper's Table 1 (its orbits' states) is missing. `orbits.stable_nrho` takes the member
# where the L2 halo family turns stable next to the 9:2 NRHO, towards the Moon: its perilune is only about 95 km
# above the surface and it sits exactly on the period-doubling boundary (stability index 1). The family has a
# second stable band roughly halfway out (notebook 01 lists its members, with perilune radii from about 13,700 to
# 17,300 km, and shows the band in its stability figure); we add the band's most stable member
# (`orbits.stable_nrho_outer`, perilune printed above) as a third orbit, so every comparison below that involves
# "the stable NRHO" can be read for both candidates: "stable NRHO (inner band)" and "stable NRHO (outer band)".

# %% [markdown]
# ## 1 · Optical measurements (Eqs. 6-13)
#
# With $\boldsymbol\rho = \mathbf r - \mathbf r_{obs}$ the line of sight in the rotating frame, the observer
# measures the azimuth $\theta = \operatorname{atan2}(\rho_j, \rho_i)$ and the elevation
# $\psi = \arcsin(\rho_k/\|\boldsymbol\rho\|)$ (Eqs. 6-8) and their rates (Eqs. 9-11, which the filter uses as
# its measurement model), obtained by differencing two images $\Delta t$ apart (Eq. 12). Differencing two
# independent angles gives the rate noise of Eq. 13,
# $\sigma_{\dot\theta} = \sqrt2\,\sigma_\theta/\Delta t$, with $\Delta t = 1$ s as in the paper.
#
# **Noise level (choice).** Table 3 is missing. The same authors' later paper (J. Greaves, D. Scheeres, "Autonomous
# Information Gathering Guidance for Spacecraft-to-Spacecraft Tracking with Optical Sensors", Advanced Maui Optical
# and Space Surveillance Technologies Conference (AMOS), 2023, Sec. 3.3; notebooks 07-08) sets the angular noise
# to $\sigma_{\theta,min} = 10\ \mu$rad "to emulate a high accuracy sensor", after N. Bradley et al., "Cislunar
# navigation accuracy using optical observations of natural and artificial targets", J. Spacecraft and Rockets
# 57(4), 2020. The 2021 paper says its noise matches "previous studies ... aimed at autonomous optical
# navigation"; its reference list is not in our copy of the text, so we cannot confirm it is the same study. We
# use 10 µrad for the angles and, by Eq. 13, 14.1 µrad/s for the rates; Section 4 also varies it.
# The Jacobians are analytic (`cislunar.sensing.measurements`, tested against finite differences).

# %%
demo = obs.measurement_demo(em, nrho, sigma_angle_rad=sigma_angle)
print(demo.report())
_ = plotting.save_figure(obs.figure_measurements(demo), "09_measurements_from_l2", output_dir=out)

# %% [markdown]
# Seen from L2 the target stays close to the Earth-Moon line (the azimuth only wraps through ±180°), and the line of
# sight turns fastest around perilune (day 3.3), where the rates peak: that is where the dynamics are most
# nonlinear and where, the paper says, linearised filters fail. The grey band is the 1-sigma rate noise of Eq. 13
# with a 1 s baseline (14.1 µrad/s): as printed above, the rates stay below it except briefly at perilune, where
# they peak at about 1.3 times it; what matters to a filter, their *sensitivity* to a 10-km state error, is far
# smaller (at most about $10^{-4}$ of the noise at the periapsis hand-off, notebook 09b Section 1).
#
# ## 2 · The OCBE in square-root-information form (Eqs. 14-32)
#
# The OCBE models unknown accelerations as an optimal control $\mathbf u = -\tilde Q B^\top\mathbf p$ with
# costate $\mathbf p$. Here $B = [0;\ I_3]$ (6x3) feeds an acceleration into the velocity equations, and the
# *control weight* $\tilde Q = q I_3$ is the power spectral density of the acceleration the control may absorb
# (km²/s³): it plays the role of a process-noise intensity. Its 12x12 transition matrix (Eq. 14) propagates state
# and costate deviations together; with $\Phi_{px}=0$ and $\Phi_{pp} = \Phi_{xx}^{-\top}$ the covariance time
# update becomes that of a Kalman filter with process noise $Q = -\Phi_{xp}\Phi_{xx}^\top$ (Eqs. 15-17).
#
# The square-root-information (SRI) form stores the inverse of a square root instead of each covariance:
#
# * $S_x$, the upper-triangular *information square root* of the state, with $P = S_x^{-1}S_x^{-\top}$ (Eq. 21);
# * $S_q$, the same for the OCBE process noise, $Q = S_q^{-1}S_q^{-\top}$ (Eq. 22);
# * $\mathbf b_x$, the *information vector*: the estimated correction to the reference state is
#   $S_x^{-1}\mathbf b_x$ (Eq. 28);
# * $S_y$, the whitening matrix of the measurement noise, $R = S_y^{-1}S_y^{-\top}$ (Eq. 26), so
#   $S_y^{-1}H$ and $S_y^{-1}\delta\mathbf y$ are the measurement partials and residual in units of their noise;
# * $\Gamma$, the matrix that maps the process-noise state into the state (Eq. 18); matching Eq. 18 to Eq. 16, the
#   paper takes $\Gamma = I$ with process-noise covariance $Q$ (Eqs. 19-20).
#
# A Householder transformation (an orthogonal matrix $T$, which leaves the least-squares cost unchanged) brings each
# array to upper-triangular form. The time update (Eqs. 21-23) triangularises
# $\begin{bmatrix} S_q & 0 & 0\\ -S_x\Phi_{xx}^{-1} & S_x\Phi_{xx}^{-1} & 0\end{bmatrix}$, the measurement update
# (Eqs. 24-28) triangularises $\begin{bmatrix}S_x & b_x\\ S_y^{-1}H & S_y^{-1}\delta y\end{bmatrix}$, and a
# single-step smoother (Eqs. 29-30) gives the costate $\mathbf p_{n|n+1} = -P_{n|n}^{-1}(\mathbf x_{n|n+1}-
# \mathbf x_{n|n})$ (Eq. 31) and the control estimate (Eq. 32). `cislunar.estimation.ocbe.ocbe_filter_smoother`
# implements exactly this; its tests show that it equals a covariance-form EKF whose $Q$ is computed independently
# (Lyapunov equation), that the full SRI smoother equals the Rauch-Tung-Striebel smoother, and that
# $Q = -\Phi_{xp}\Phi_{xx}^\top$ equals the exact discretisation of white-noise acceleration of density
# $\tilde Q$.
#
# Here there is no mismodeling (truth and filter share the CR3BP), so the control weight only has to keep $Q$
# positive definite: $\tilde Q = 10^{-20}$ km²/s³ per axis (choice; the paper gives no value for this
# experiment). The hand-off covariance is the paper's Earth-radar one, 3σ = 10 km and 10 cm/s per axis, and the
# tracks start at apoapsis, as in the paper's observation-strategy runs.

# %%
Q_QUIET = CONTROL_WEIGHT_KM2_S3 * em.time_unit_s**3 / em.length_unit_km**2  # km^2/s^3 -> LU^2/TU^3
typical = obs.typical_run(em, nrho, TYPICAL_CADENCE_H, Q_QUIET, np.random.default_rng(SEED),
                          sigma_angle_rad=sigma_angle)
_ = plotting.save_figure(obs.figure_typical_run(typical), "09_typical_run_fig5", output_dir=out)
print(typical.report())

# %% [markdown]
# The errors stay inside their 3σ envelopes. The forward position uncertainty first grows for about a day after
# the hand-off (the dynamics stretch it faster than the first measurements shrink it), then shrinks over the two
# days before perilune (the printed lines give the values); the velocity uncertainty spikes through perilune where
# the dynamics are fastest. The smoother, which uses every measurement at every epoch, is tighter than the forward
# filter at every epoch but the last, where the two coincide: there the smoother has no later data to add (the
# smoothed-over-forward ratios printed above).
#
# ## 3 · Consistency as the divergence test
#
# "Divergence" needs a definition that a computer can apply to thousands of runs. A filter is consistent when its
# normalised estimation error squared, $\epsilon_n = \mathbf e_n^\top P_n^{-1}\mathbf e_n$, is $\chi^2_6$
# distributed: mean 6, and above the 99.9% quantile (22.5) at 0.1% of epochs. We call a run **diverged** when more
# than 5% of its epochs exceed that quantile, or when the filter fails numerically. Each Monte Carlo run draws its
# own measurement noise and hand-off error (`tracking.filter_trial`), from child $i$ of its set's seed, so a run's
# result does not depend on where it runs. The runs of a set share their epochs and observers, so they are
# filtered together, in lockstep (`tracking.filter_trials`: one batched OCBE, `cislunar.estimation.batched_ocbe`,
# whose heyoka integrator carries one run per SIMD lane); each run's numbers equal those of its own single-trial
# filter to round-off, and a run that fails numerically is flagged at the epoch where the single-trial filter would
# have failed, without stopping the others (`tests/estimation/test_batched_ocbe.py`). These batches are the tasks
# of the executor opened at the top (`WORKERS` processes, or the Dask cluster at `SCHEDULER`). The helper below
# fixes what every set of this chapter shares (the system, the control weight, the seed, the sizes and the
# executor) and leaves the measurement type, the noise, the cadences and the orbits to each call.

# %%
def study(rates, sigma=sigma_angle, cadences=cadences_h, orbits_=ORBITS, **kw):
    """The Monte Carlo of this chapter over cadences and orbits (the sizes, seed and executor of the parameters)."""
    return obs.strategy_study(em, orbits_, cadences, Q_QUIET, rates=rates, sigma_angle_rad=sigma, seed=SEED,
                              n_runs=kw.pop("n_runs", n_runs), n_runs_one_minute=n_runs_one_minute,
                              executor=executor, **kw)

# %% [markdown]
# ## 4 · Angles only from L2 (the paper: every cadence diverges before perilune)

# %%
angles_only = study(rates=False)
print(angles_only.report(f"angles only, L2 observer, {SIGMA_ANGLE_URAD:g} urad"))

# %%
cells = angles_only.diverged_cells()
print(f"angles only: most runs diverged in {len(cells)} of {len(angles_only.rows)} (orbit, cadence) cells:",
      ", ".join(f"{n} at {c:g} h" for n, c in cells) or "none")

# %% [markdown]
# Compare this with the paper, where *every* angles-only cadence diverged for both orbits. Because the paper's
# noise level is unknown, we repeat a hard case (the 9:2 NRHO at a 12-hour cadence) with noise ten and a hundred
# times larger. Then the paper's two five-observer statements (L2, the DRO observer and the three surface stations,
# hourly as in Fig. 4, each used only when it sees the target): "even with this additional information the ...
# 9:2 NRHO filter nearly always fail[s]" at the paper's noise and its stated hand-off, and, in its Fig. 4 set-up,
# with the measurement noise and the hand-off uncertainty one order of magnitude *smaller*, "the filter estimate
# still diverged". The paper's noise is one value it does not give, so we run both statements at each angle noise
# of a small sweep (`NOISES_FIVE_URAD`, 1, 10 and 100 µrad in the full run; Fig. 4 at a tenth of each); the
# closing table judges each statement at the reading that comes closest to it. (The paper varies the cadence for
# the first statement; we run it hourly only, the Fig. 4 cadence.)

# %%
noisier = {sig: study(rates=False, sigma=sig, cadences=[12.0], orbits_={"9:2 NRHO": nrho}).rows[0]
           for sig in (n / 1e6 for n in NOISE_LEVELS_URAD)}
for sig, row in noisier.items():
    print(f"angles only, 12 h, sigma = {sig * 1e6:g} urad: diverged {100 * row[2]:.0f}%, median NEES {row[3]:.2f}, "
          f"final 3-sigma position {row[4]:.2f} km")
# the paper's noise (one unstated value) read at each noise of the sweep; hand-off as stated, then both / 10
five_stated = {u: study(rates=False, observers="all", sigma=u / 1e6, handoff_scale=1.0, cadences=[1.0],
                        orbits_={"9:2 NRHO": nrho}, n_runs=n_runs_five).rows[0] for u in noises_five}
five_fig4 = {u: study(rates=False, observers="all", sigma=u / 10 / 1e6, handoff_scale=0.1, cadences=[1.0],
                      orbits_={"9:2 NRHO": nrho}, n_runs=n_runs_five).rows[0] for u in noises_five}
for u in noises_five:
    for what, row, sig_u, h_km in (("stated hand-off", five_stated[u], u, 10), ("Fig. 4, both / 10", five_fig4[u],
                                                                               u / 10, 1)):
        print(f"five observers, angles only, hourly, {what}: {sig_u:g} urad, hand-off {h_km} km: diverged "
              f"{100 * row[2]:.0f}%, median NEES {row[3]:.2f}, final 3-sigma position {row[4] * 1e3:.1f} m")

# %% [markdown]
# Where our angles-only runs stay consistent and the paper's diverged, plausible reasons (none checkable from the
# text) are a larger angular noise than we can infer (Table 3 is missing), a control weight large enough to erase
# the dynamical range information angles-only tracking relies on, or integration and linearisation differences
# in the time update through perilune (our STMs agree with finite differences to about 1e-9, notebook 01). Section
# 5b varies the hand-off and noise, Section 5c the filter (control weights up to $10^8$ times ours, a fixed
# reference, a coarse time update). The closing table records each case.
#
# ## 5 · Angles and angle rates from L2 (the paper: consistent at every cadence; Table 4)

# %%
with_rates = study(rates=True)
print(with_rates.report(f"angles and rates, L2 observer, {SIGMA_ANGLE_URAD:g} urad and "
                        f"{np.sqrt(2) * SIGMA_ANGLE_URAD:.1f} urad/s"))
fig = obs.figure_final_uncertainty(with_rates, angles_only, ORBITS)
_ = plotting.save_figure(fig, "09_final_uncertainty_vs_cadence_table4", output_dir=out)
ratio = [ra[4] / an[4] for ra, an in zip(with_rates.rows, angles_only.rows)]
print(f"final 3-sigma position, angles + rates over angles only: {min(ratio):.3f} .. {max(ratio):.3f}")
nos = typical.rate_noise_over_spread()  # the Section 2 run: 9:2 NRHO, apoapsis start
print(f"rate noise over the spread the hand-off error produces in the rates: azimuth rate {nos[0]:.1e}, "
      f"elevation rate {nos[1]:.1e}")

# %% [markdown]
# **Why each orbit's two curves lie on top of each other** (open large markers: angles + rates; small filled
# markers: angles only). The angle rates add essentially no information in this scenario: with a 1 s differencing
# baseline their noise (14.1 µrad/s) is tens of thousands of times the spread that the hand-off error produces in
# them (the last line printed above), so the final uncertainties with and without them agree to the ratio printed
# above (medians over different random runs, so not exactly 1). Whatever stabilising effect the paper attributes
# to the rates cannot act through information here; Section 4 counts how many angles-only runs lose consistency
# without them.

# %%
flagged = {label: obs.flagged_cells(s.rows) for label, s in (("angles only", angles_only),
                                                              ("angles + rates", with_rates))}
for label, cells_ in flagged.items():
    print(f"{label}: cells with more than 10% inconsistent runs:",
          ", ".join(f"{n} {c:g} h ({100 * d:.0f}%)" for n, c, d in cells_) or "none")

# %%
long_gap = [c for c in cadences_h if c >= 6.0]
print("orbits with a cell above 10 % inconsistent runs: "
      + "; ".join(f"{k}: {', '.join(sorted({n for n, _, _ in v})) or 'none'}" for k, v in flagged.items()))
print(f"at the long cadences ({', '.join(f'{c:g} h' for c in long_gap)}), inconsistent runs (angles + rates) "
      "per orbit: " + "; ".join(f"{name} {100 * with_rates.diverged_fraction(name, long_gap):.0f} %"
                                for name in ORBITS))

# %% [markdown]
# The paper reports consistent filters at every cadence once the rates are added. Compare the "diverged" columns:
# with 20 runs per cell (full mode; 2 in quick mode), one or two flagged runs are within chance for a consistent
# filter, while a cell where many runs are flagged points at a real problem. In the full run every such cell (the
# lines above list them) belongs to the inner-band stable NRHO at a long cadence: without rates its 6-h and 12-h
# cells, with rates its 6-h cell, while its 12-h cell sits on the 10 % flag. Taken over 6 and 12 h together, the
# inner-band member with rates has many more inconsistent runs than the 9:2 NRHO and the outer-band member, which
# stay consistent there (the per-orbit fractions printed last). The likely reason, supported by Section 5b (the
# inner-band member's failures at small hand-offs start at perilune): a perilune only about 95 km above the
# surface, passed with measurements 6-12 hours apart, leaves the linearised time update through perilune too
# coarse. The rates add no *accuracy* once the angles are 10 µrad: their noise, by Eq. 13 with a 1 s baseline, is
# large; the paper makes the same remark ("the presence of angular rate measurements is not meant to add
# significant information").

# %% [markdown]
# ## 5b · Where does the paper's claim hold? A regime map
#
# The paper's explanation is not information: rates "stabilise" the linearised updates against nonlinearity near
# periapsis, a mechanism that should depend on how large the initial error is. We therefore map the fraction of
# diverged runs (the NEES criterion of Section 3) for angles only and for angles + rates over the hand-off
# uncertainty (3-sigma 1 km to 10,000 km, i.e. the paper's 10 km, 10 cm/s scaled by 0.1-1000), the angle noise
# (1, 10 and 100 µrad: the paper's Fig. 4 experiment divided its noise by ten), the cadence, on all three orbits.
#
# With the paper's 1-s differencing baseline the rates carry no information (Section 5), so a contrast could only
# come from their "stabilising" role. To see whether *informative* rates would create it, the map adds a second
# reading of Eq. 13 (beyond the paper): $\Delta t = 1$ in the filter's non-dimensional time unit instead of 1 s,
# i.e. a rate noise $\sqrt2\,\sigma_\theta$ per TU, numerically "roughly equivalent to angular measurements" as the
# paper says, and $3.75\times10^5$ times smaller than with 1 s. The spread/noise ratios below show what each
# reading means at the Earth-radar hand-off (apoapsis start). In the map figure each panel is one orbit, cadence
# and noise; where curves coincide, the open square and diamond sit on the filled circle, and the dash-dotted
# line marks the paper's 10-km hand-off.

# %%
RATE_MODELS = {"angles + rates (1 s)": 1.0, "angles + rates (dt = 1 TU)": em.time_unit_s}  # Eq. 13 baseline [s]
sc_map = tracking.make_scenario(em, nrho, 2.0, start="apoapsis", rates=True)
_, P0_map = tracking.initial_estimate(em, sc_map.x_start, np.random.default_rng(0))
_, _, H_map = sc_map.model.evaluate(sc_map.observers[0], sc_map.x_start)
for mname, base in RATE_MODELS.items():
    R_map = tracking.angles_rates_covariance(em, sigma_angle, base)
    spread = np.sqrt(np.diag(H_map[0] @ P0_map @ H_map[0].T) / np.diag(R_map))
    print(f"{mname:>28}: state-driven spread / noise of the rates {spread[2]:.2g}, {spread[3]:.2g} "
          f"(angles {spread[0]:.2g}, {spread[1]:.2g})")

# %%
t_map = time.perf_counter()
regime = obs.regime_map(em, ORBITS, cadence_map, sigma_map, handoff_map, RATE_MODELS, Q_QUIET, n_runs=n_runs_map,
                        seed=SEED, executor=executor)
print(f"regime map: {len(regime.cells) * n_runs_map} runs in {time.perf_counter() - t_map:.0f} s")
print(regime.table_report())

# %%
_ = plotting.save_figure(obs.figure_regime_map(regime), "09_regime_map", output_dir=out)

# %%
print(regime.analysis_report())

# %% [markdown]
# **Fig. 4 analogues: two divergences, in the regimes where they happen.** The paper's Fig. 4 is a 9:2 NRHO run.
# Among the 9:2 NRHO's angles-only cells in which most runs diverge we take the one closest to the paper's
# set-up (smallest hand-off, then the largest diverged fraction); a second figure takes, at the paper's own
# 10-km hand-off, the angles-only cell of any orbit with the most diverged runs. Each shows the clearest of ten
# fresh draws (largest mean NEES). A third panel shows the NEES against its 99.9 % quantile, since the norms of
# the error and of the 3-sigma bound (the paper's layout) hide part of what makes a run inconsistent; the dotted
# line marks perilune.

# %%
cell_92, cell_paper = regime.divergence_cells()
for cell, name, what in ((cell_92, "09_fig4_typical_divergence", "9:2 NRHO divergence closest to the paper's set-up"),
                         (cell_paper, "09_fig4_divergence_at_papers_handoff", "Divergence at the paper's hand-off")):
    example = obs.divergence_example(em, ORBITS[cell[0]], regime, cell, Q_QUIET, seed=SEED, n_draws=N_DRAWS_EXAMPLE)
    if example.result is not None:
        _ = plotting.save_figure(obs.figure_divergence(example, what), name, output_dir=out)
    print(example.report(what))

# %% [markdown]
# **Reading the map** (the printed lines above are this run's; the sentences below describe the full run, 10 runs
# per cell, so one run is 10 %).
#
# * *Which regime did the paper use?* It states its hand-off (10 km, 10 cm/s, 3-sigma) and a cadence range; only
#   the noise is missing. At the stated hand-off our angles-only filters stay consistent on the 9:2 NRHO and on
#   the outer-band stable NRHO at every noise and cadence of the map; only the inner-band member, whose perilune
#   grazes the Moon, loses runs there (mostly at the 12-h cadence), and then with the paper's rates about as
#   often as without. Most angles-only runs of the 9:2 NRHO diverge only from a hand-off a hundred times the
#   paper's or more (the "most of them diverge from" lines above). In the regime the paper describes, its
#   angles-only divergence does not appear here on the 9:2 NRHO. Since the paper's claim is made at one noise,
#   the closing table asks, per orbit, whether *any* noise of the map makes most runs diverge at both cadences at
#   the stated hand-off (full run: none does on any orbit; the inner-band member comes closest at 100 µrad, where
#   most runs diverge at 12 h but none at 2 h).
# * *Two different failures.* The onset lines tell where each diverged run first left its 99.9 % NEES bound.
#   With a hand-off of thousands of km the filter is inconsistent from the very first measurement update: a
#   prior that wide makes the linearised angle update itself wrong, whatever the dynamics. The inner-band
#   member's failures at small hand-offs start at perilune instead: the paper's mechanism, a time update through
#   the fast, strongly nonlinear perilune passage (passed here only 95 km above the surface, measured 2-12 hours
#   apart). Neither is cured by the rates.
# * *Does the contrast appear anywhere?* No (the verdict line). Among the cells where most angles-only runs
#   diverge (their number is printed), most runs with the paper's 1-s rates diverge too in all but a few; the
#   exceptions are listed with both fractions, and in none do the rates bring the diverged runs down to the 10 %
#   the contrast needs. This is what rates without information should give: over the map the mean difference
#   between the two diverged fractions is nil (the "largest drop" line for 1 s), cells where the rates lower the
#   fraction by 30 points or more are about as many as cells where they raise it by as much, and a 30-point
#   difference is little more than one standard error of two 10-run fractions (printed). The largest drop with 1-s
#   rates is an isolated cell: at the neighbouring hand-offs of the same orbit, cadence and noise it disappears
#   (printed).
# * *Would informative rates help?* Against a wide prior, no: with the $\Delta t = 1$ TU reading the rates are
#   informative (the spread/noise ratios above), and the filters diverge at smaller hand-offs than without them;
#   a more confident filter meets the nonlinearity of a large initial error sooner. Against the perilune failure
#   they do help: the "largest drop" line shows the inner-band member at the long cadence and large noise, where
#   most angles-only runs diverge at the paper's hand-off and far fewer with informative rates. That is the
#   nearest the map comes to the paper's contrast, and it needs the inner-band orbit and a rate noise the paper's
#   stated 1-s differencing does not give; even there, more runs diverge than the paper's "consistent" allows.
#
# What else could produce the paper's result? Not the stated inputs, not a hand-off up to a thousand times
# larger, and not the paper's reading of the rate noise. The one mechanism that behaves as the paper describes,
# a time update through perilune that rates can steady, appears only on the inner-band orbit and only with rates
# far more precise than 1-s differencing gives. Beyond that, what remains is what the text does not describe:
# how its time update through perilune is implemented (integration, re-linearisation of the reference) and how
# its angles-only measurement update is. A linearised (non-extended) filter would be a candidate, but the paper
# says it re-linearises, and we have no second description to test against. The closing table records the
# counts; the two Fig. 4 analogues show the two failures (the first at the first update, the second at
# perilune; their printed lines give the day each run first leaves its bound).

# %% [markdown]
# ## 5c · The filter, not the scenario: four filter-side axes
#
# Every cell of the map varies the scenario; the filter stays the extended SRI OCBE of Section 2. The paper's own
# mechanism (rates steady the linearised updates against nonlinearity near periapsis) points at how the filter is
# built, which its text does not fully describe. We therefore rerun the map's key cells (9:2 NRHO, the paper's
# 10-km hand-off, 10 µrad, tracks from apoapsis, angles only against angles + the paper's 1-s rates) with four
# changes to the filter, each an option of the package's batched OCBE (`ocbe_batch`) with a default that leaves
# every earlier section unchanged:
#
# * **azimuth wrapping** (`wrap_azimuth=False`): residuals taken as the plain difference instead of wrapped to
#   $[-\pi, \pi)$. Seen from L2 the target starts on the azimuth's $\pm 180°$ cut, so a measurement on the
#   other branch gives a $2\pi$ residual. This is a bug, not a design choice, but one the paper's filter could have;
# * **a fixed reference** (`relinearize=False`): a linearised Kalman filter about the trajectory of the hand-off
#   mean, never re-linearised about the updated estimate (equal to ours on a linear system);
# * **the control weight**: the OCBE weight scaled by 0.01, 100 and $10^8$ (a process noise far too small or
#   large);
# * **a coarse time update** (`coarse_stm=True`): one state/costate transition per update interval with the
#   Jacobian frozen at its start, $\Phi = \exp(M\,\Delta t)$, instead of the integrated one; through perilune
#   at long cadences this ignores how fast the dynamics change.
#
# Every filter sees the same draws (measurement noise and hand-off), so a difference between rows is the filter's.
# The full run covers the paper's whole range of cadences, 1 minute to 12 hours: 10 runs per cell from 10 minutes
# up and 4 at 1 minute (about 9450 updates per run, `N_AXES_ONE_MINUTE`), so a 1-minute fraction moves in steps of
# 25 points.
# The contrast reads as in the map: most angles-only runs diverge, at most 10 % of the runs with rates do. The figure
# shows the diverged fractions against cadence, angles only on the left and with rates on the right, one curve per
# filter; the shaded band is the 10 % a consistent filter is allowed, the dotted line the 50 % of "most runs".

# %%
t_axes = time.perf_counter()
axes_study = obs.filter_axes_study(em, {"9:2 NRHO": nrho}, cadence_axes, Q_QUIET, n_runs=n_runs_axes,
                                   n_runs_one_minute=n_runs_axes_1min, seed=SEED,
                                   sigma_angle_rad=sigma_angle, executor=executor)
print(f"filter axes: {axes_study.total_runs} runs in {time.perf_counter() - t_axes:.0f} s")
print(axes_study.report())
_ = plotting.save_figure(obs.figure_filter_axes(axes_study), "09_filter_axes", output_dir=out)

# %% [markdown]
# **Reading the filter axes** (the printed lines above are this run's; the sentences below describe the full run,
# 10 runs per cell from 10 minutes to 12 hours and 4 at 1 minute.)
#
# * *The chapter's filter and every control weight* from 0.01 to $10^8$ times the chapter's: no diverged run at any
#   cadence, with or without rates. The truth carries no unmodelled acceleration, so a smaller weight is not wrong,
#   and a larger one only makes the filter more cautious.
# * *The unwrapped azimuth:* a fifth to seven tenths of the runs diverge, with rates about as often as without, and
#   every one of them at the first update. At apoapsis the L2 observer sees the target on the $\pm 180°$ cut, and
#   a measurement on the other branch gives a $2\pi$ residual that no update absorbs. Whether a run fails depends
#   on the branch its first noisy azimuth falls on, not on the measurement set.
# * *The fixed reference:* a third of the runs diverge at 1-2 h, almost none at 6-12 h, with rates as often as
#   without. At 10 minutes half the angles-only runs diverge and six in ten with rates; at 1 minute every run,
#   with rates or without. The runs leave their bound on the approach to perilune, where the deviation from the
#   hand-off reference has grown enough for the neglected second-order terms to matter; denser tracking makes the
#   filter more confident, and so more sensitive to them.
# * *The coarse time update:* every run diverges, with rates and without, from 10 minutes to 12 hours, on the
#   approach to perilune, where a Jacobian frozen over the interval misstates how fast the dynamics change. At
#   1 minute each frozen step errs least, but there are about 9450 of them: every run with rates and two of the
#   four without still diverge (with rates slightly more often, the opposite of the paper's contrast).
#
# Each change to the filter either leaves it consistent or breaks it with and without rates alike. None produces
# the paper's contrast in any cell. With the paper's 1-s differencing the rates carry too little information
# (Section 5) to steady any of these failures. The closing table counts, for each filter, the cadences at which
# the contrast holds.

# %% [markdown]
# **Which stable NRHO, by evidence.** The paper says its stable NRHO gives "qualitatively similar but quantitatively
# better" results than the 9:2 and that every cadence gives a consistent filter. We test both candidates on both
# remarks: the fraction of cadences at which the final 3-sigma position (angles + rates, median over runs) is
# smaller than the 9:2 NRHO's, and the inconsistent runs at the long cadences (Section 5).

# %%
cand = obs.compare_stable_candidates(with_rates, "9:2 NRHO", ("stable NRHO (inner band)", "stable NRHO (outer band)"),
                                     cadences_h)
print(cand.report())

# %% [markdown]
# In the full run the outer-band member is better determined than the 9:2 NRHO at every cadence (final 3-sigma
# 0.64-0.79 of the 9:2's) and stays consistent at 6-12 h, while the inner-band member is worse determined at
# every cadence and is the orbit whose long-cadence runs lose consistency; the printed lines give this run's
# numbers. The paper's stable NRHO is therefore most likely a member of the outer band. `orbits.stable_nrho` still
# names the inner band's edge (notebook 01 shows both), and the closing tables of this notebook and of notebook 10
# keep both candidates. Because the outer band was singled out for matching this remark, its row below is
# "consistent (tuned)", not an independent reproduction.

# %% [markdown]
# ## 5d · Operational claims: custody over many periods, the SRI form, re-linearisation, cadence and run time
#
# The paper ends its tuning section with an operational promise: with one L2 observer, angles and rates every
# 2 hours and the control weight raised for 8 hours around apoapsis, "an observer can use this strategy to
# maintain custody of the craft for an indefinite time as it performs station keeping maneuvers on a NRHO". It
# also says that the square-root-information form is there "to reduce numerical instability", that
# re-linearisation is "extremely important" because without it the filter can fail "within a single orbit", and
# that 2 hours "balances filter accuracy and algorithm run-time, and appears to be a sweet spot". None of these
# was tested above. The definitions used below were written down, with every tolerance, before the first run
# (`cislunar.papers.greaves_scheeres_2021.custody`, module docstring; the claims in
# `cislunar.papers.greaves_scheeres_2021.claims.operations`).
#
# **Custody, defined before looking.** A tracking camera is pointed along the line of sight of the filter's
# *prediction* for the next image. Custody is kept at an epoch when the angle between that line of sight and the
# true one is within the camera's half field of view, which we take as 0.5° (a 1° narrow-field camera: our choice,
# the paper names no sensor); custody through a period means at every epoch so far (a lost target is not
# re-acquired), and a numerical failure loses it. Consistency is judged period by period with the chapter's run
# rule (a run is inconsistent in a period when more than 5 % of that period's epochs have a NEES above the 99.9 %
# quantile).
#
# **The scenario.** The paper's final strategy on the 9:2 NRHO: the Earth-radar hand-off at periapsis, one L2
# observer, angles and rates every 2 h, and a station-keeping burn at *every* apoapsis, drawn from the paper's
# policies (Eqs. 3-5, Table 2: random pointing, truncated-Gaussian magnitude): the quiet one (50 ± 15 mm/s, the
# paper's "often on the order of 10's of mm/s") and the active one (1 ± 0.3 m/s). The filter does not know the
# burns; its control weight is raised over 8 h around every apoapsis to the white-noise acceleration whose
# velocity variance over the window matches the policy's burn (`detection.window_control_weight`, notebook 10),
# and is notebook 10's $10^{-18}$ km²/s³ elsewhere. The runs are batched OCBE lock-steps, one executor task per
# 16 runs.

# %%
t_custody = time.perf_counter()
custody = {p.name: cu.custody_study(em, nrho, periods=custody_periods, policy=p, n_runs=n_custody, seed=SEED,
                                    sigma_angle_rad=sigma_angle, executor=executor)
           for p in (det.QUIET_POLICY, det.ACTIVE_POLICY)}
print(f"custody: {2 * n_custody} runs of {custody_periods} periods in {time.perf_counter() - t_custody:.0f} s")
custody_weak = None if not custody_weak_run else cu.custody_study(
    em, nrho, periods=custody_periods, policy=det.QUIET_POLICY, n_runs=n_custody, seed=SEED,
    q_window_km2_s3=0.1 * det.window_control_weight(det.QUIET_POLICY), sigma_angle_rad=sigma_angle, executor=executor)
for c in custody.values():
    print(c.report())
if custody_weak is not None:  # full mode only
    print("the same quiet-policy runs with the window weight ten times weaker (notebook 10's threshold reading):")
    print(custody_weak.report())
_ = plotting.save_figure(figures.figure_custody(custody.values()), "09_custody_multi_period", output_dir=out)

# %% [markdown]
# **Reading the custody runs** (the sentences describe the full run, 32 runs of 10 periods per policy; the printed lines
# are this run's). Every run keeps custody through every period with either policy, and by a wide margin: the worst
# pointing error of the prediction (right panel) is set by the hand-off in the first period (0.011°: about 13 km across
# the line of sight seen from about 65,000 km, the hand-off error of the worst run) and then stays at 0.001-0.002° with
# the quiet burns and 0.005-0.007° with the active ones. The worst error over the whole track is thus about forty
# times inside the 0.5° bound (70 to 250 times after the first period): a camera would have to be about forty times
# narrower before custody were at risk. The runs also stay consistent (left panel, dashed): at
# most one run in 32 (3 %) is inconsistent in the first period and none afterwards, with either policy; the raised
# window lets the filter absorb each burn, and with the quiet policy the filter's 3-sigma position returns to 1.5-2 km
# by the end of every period. With the active policy the same holds for seven periods; then the 3-sigma position at the
# end of a period grows (median 7, 11 and 34 km in periods 8-10) and the worst error reaches about 130 km. The burns are
# randomly pointed, as in the paper's Eqs. 3-5, not station keeping: after several 1-m/s kicks the true track has left
# the NRHO, and the filter follows it with less favourable geometry. On this evidence the paper's "indefinitely" holds
# for as long as we ran it, for either policy, while the active-policy runs show that "indefinitely" also needs the
# burns to keep the craft on its orbit.
#
# The tuning matters more than the bound: the window weight is matched to the burns (the white-noise acceleration
# whose velocity variance over 8 h equals the burn's), a choice we settled after a first probe with a weaker
# weight, so the consistency rows are marked tuned. With a window ten times weaker
# (notebook 10's threshold reading, the last printed block in full mode, the same draws) the runs still keep custody, but
# 34-69 % of them are inconsistent in each period: custody is the easier of the two promises.
#
# **The SRI form under ill-conditioning.** The OCBE's numerical form is tested on a problem where the exact answer
# is known: the 9:2 NRHO linearised about its reference (transition matrices and measurement Jacobians of the
# reference, angles and rates from L2, one period from apoapsis), a linear Gauss-Markov problem, so every filter
# below solves exactly the same equations and differs only in arithmetic. Three forms of the same Kalman filter run
# on the same draws: the SRI form (`cislunar.estimation.srif.filter_smoother`, the kernels of the OCBE), the
# *Joseph* covariance form $P^+ = (I-KH)P^-(I-KH)^\top + KRK^\top$ (as in filterpy's `KalmanFilter`, against
# which the tests check it), and the *conventional* form $P^+ = (I-KH)P^-$, neither symmetrised. A ladder of cases
# makes the information matrix ill-conditioned the classic way: a wider prior, a long gap without measurements
# (three days, so the dynamics stretch the prior), then dense precise updates, with tiny process noise. Each form
# has *lost symmetry* when $\max|P-P^\top| > 10^{-8}\max|P|$, *lost positive definiteness* when a Cholesky
# factorisation of $P$ fails, and *lost consistency* when the mean NEES over the draws leaves its 99.9 % band at
# more than 5 % of the epochs (the SRI form's NEES is computed from its square root, $\|R\,e\|^2$).

# %%
LADDER = {"well conditioned (the chapter's case)": dict(),
          "prior x1e3, 0.1 urad, 3-day gap": dict(prior_scale=1e3, sigma_angle_rad=1e-7, gap_hours=72.0,
                                                  q_km2_s3=1e-24),
          "prior x1e4, 10 nrad, 3-day gap": dict(prior_scale=1e4, sigma_angle_rad=1e-8, gap_hours=72.0,
                                                 q_km2_s3=1e-26),
          "prior x1e5, 10 nrad, 3-day gap": dict(prior_scale=1e5, sigma_angle_rad=1e-8, gap_hours=72.0,
                                                 q_km2_s3=1e-26)}
ladder = [list(LADDER)[i] for i in ladder_rungs]
rng_cond = np.random.default_rng([SEED, 95])
conditioning = {name: cu.conditioning_case(cu.linear_problem(em, nrho, **LADDER[name]), n_draws_conditioning,
                                           rng_cond, label=name) for name in ladder}
for case in conditioning.values():
    print(case.report())
worst = conditioning[ladder[-1]]
_ = plotting.save_figure(figures.figure_conditioning(worst), "09_sri_vs_covariance_form", output_dir=out)

# %% [markdown]
# **Reading the ladder** (the printed lines; the figure shows the last case). On the chapter's own case the three forms
# agree to about $10^{-11}$ of the covariance scale, and all are consistent: there is nothing for the SRI form to fix at
# 10 µrad and the paper's hand-off, even though the information matrix already has a condition number near $10^9$. As
# the ladder climbs, the conventional form loses symmetry and positive definiteness first (at an information condition
# number near $10^{12}$) and then consistency (near $10^{16}$: once its covariance stops being positive definite, its
# mean NEES leaves the band, by many orders of magnitude on that rung); the Joseph form holds longer, then loses
# symmetry (near $10^{16}$) and positive definiteness (near $10^{18}$) while its estimates stay consistent; the SRI form
# keeps all three on every rung. The covariance it reports is formed only for display, from its square root, and is
# symmetric by construction (its smallest eigenvalue may round to $-10^{-16}$ of the largest, as the figure's red cross
# shows, but a Cholesky factor exists throughout). So the SRI form is more stable, as the paper says, but only where the
# information is conditioned far worse than in the paper's own scenario.
#
# **Re-linearisation.** The fixed-reference filter of Section 5c keeps the hand-off trajectory as its reference
# for the whole track (a linearised Kalman filter), where the paper's filter re-linearises about every update. The
# closing table reads the Section 5c numbers with rates: the paper's claim holds if the fixed reference fails in
# more than 10 % of the runs at some cadence while the re-linearised filter fails in at most 10 % at every one.
#
# **Run time against cadence.** The chapter's filter (single trial, forward pass, angles and rates, one period
# from apoapsis) is timed at each cadence (CPU time, best of up to three runs after a warm-up, one in quick
# mode); accuracy is its final 3-sigma position (the Table 4 quantity). A "sweet spot" of such a trade curve is
# read as its *knee*, where accuracy stops coming cheaply. On log-log axes a pure power law of accuracy in run time
# is a straight line, so we compare the curve with its chord, the line through its ends (12 h and 1 minute, the
# paper's range): the *depth* of a cadence is how far its final 3-sigma lies below the chord (in natural log, so
# 0.1 means about 10 % more accurate than the power law through the ends would give for its run time), and the knee
# is the deepest cadence (the standard "Kneedle" definition). The 2-h cadence is a sweet spot when the knee is 1, 2
# or 4 h. This reading replaces a first one, written before the runs, that asked every step from 12 h to the knee
# to gain accuracy at least as fast, in log, as it adds run time (elasticity $-\Delta\log A/\Delta\log C \ge 1$): a
# filter whose accuracy grows as the square root of its number of updates reaches an elasticity of only 1/2 once
# the updates dominate its run time, so that bar could hardly be met by any filter. The revision was made after the
# full run had been seen and the paper gives no number, so the closing row is declared tuned. The seconds depend on
# the machine and its load; the ratios between cadences carry the result.

# %%
t_cost = time.perf_counter()
cost = cu.cadence_cost_study(em, nrho, cadences_cost, CONTROL_WEIGHT_KM2_S3, seed=SEED, sigma_angle_rad=sigma_angle,
                             repeats=cost_repeats)
print(f"cadence costs measured in {time.perf_counter() - t_cost:.0f} s")
print(cost.report())
_ = plotting.save_figure(figures.figure_cadence_cost(cost), "09_cadence_run_time", output_dir=out)

# %% [markdown]
# **Reading the cost curve** (the full run: 1 minute to 12 hours; the printed lines are this run's, and the
# seconds are this process's CPU time, less disturbed by other work on the machine than the wall clock, while the
# ratios carry the result). Between 12 h and 4 h the run time grows slowly (about 1.8 times for three times the
# updates: integrating the transition through the period costs about as much as the updates); from 2 h down to one
# minute it grows almost in proportion to the number of updates (about 100 times for 121 times the updates), while
# the final 3-sigma position falls only about like the inverse square root of that number (0.95 km at 2 h, 0.10 km
# at 1 min). The curve bends only gently: the elasticity of the steps falls from about 0.8 between 12 h and 6 h to
# about 0.5 from 2 h on (full run, rep8 build: 0.79, 0.69, 0.66, 0.53, 0.51, 0.50, 0.45), so under the first
# reading, which asked for 1, no step pays and the knee was 12 h. Measured against the chord, two full runs (the
# rep8 build and a run of 2026-11-26g, on a loaded machine) both put the knee at 1 h, with a depth of 0.21 and
# 0.22, but 30 minutes (0.20 in both) and 2 h (0.20 and 0.16) are nearly as deep:
# the bend is shallow and spread over 30 minutes to 2 hours, where the run time stops being dominated by the
# integration of the transition and starts growing with the number of updates. So 2 hours sits in the knee of the
# curve, as the paper says, but the curve singles out a region rather than a cadence, and timing noise of a few
# per cent (the sparse cadences take only a few hundredths of a second) can move the deepest point between 2 h,
# 1 h and 30 minutes: a run that puts it at 30 minutes reads "differs". The printed table above gives this run's
# depths; the closing row quotes its knee, the depth at 2 h and the deepest cadence outside 1-4 h. With the three
# cadences of quick mode the only interior point is 6 h, so the quick row cannot pass.

# %% [markdown]
# ## 6 · Paper versus reproduction
#
# Every row is a claim declared before the runs, with its criterion, in
# `cislunar.papers.greaves_scheeres_2021.claims.observation_strategy`; the notebook measures and calls `judge`, and
# the status word follows from one rule. The criteria, in words:
#
# * *"diverges"* (angles only, at each noise level, in Fig. 4's five-observer set-up, at the stated hand-off) is
#   read as *most runs of a cell diverged*, more than 50 %, with a run diverged when more than 5 % of its epochs
#   exceed the 99.9 % NEES quantile (Section 3);
# * the paper states its angles-only results at its own measurement noise, one value it does not give (Table 3 is
#   missing), so each such row says which noise reading it is judged at. The L2 row over all cadences is judged at
#   our 10 µrad, exactly as the paper words it: most runs diverge *before the first perilune* at every cadence, on
#   the 9:2 NRHO and on at least one of the two stable-NRHO candidates (the paper has one stable orbit, we do not
#   know which). The three hand-off rows ask whether *some* noise of the regime map's sweep makes most runs
#   diverge at every cadence of the map at the stated 10-km hand-off (the paper's "every strategy" at its one
#   noise), and name the closest reading. The five-observer rows are judged at the noise of their sweep that comes
#   closest: "nearly always fail" as at least 90 % of the runs diverged, Fig. 4's "still diverged" as most runs.
#   The hand-off and five-observer rows were re-scoped to a noise sweep after their numbers were seen
#   (2026-11-26h), so they are declared tuned: the word would show only if one of them passed;
# * *"consistent"* (angles + rates, the stable NRHOs at the long cadences) as *at most 10 % of the runs
#   inconsistent*: for 20 runs of a consistent filter, one or two flagged runs are chance (at 1 minute, 4 runs per
#   cell in the full run, a single flagged run already exceeds it). The angles + rates row over all cadences asks
#   it, like the angles-only row, of the paper's two orbits: the 9:2 NRHO and at least one stable candidate. It
#   asked all three of ours until 2026-11-26h; the inner band's 6-h cell (30 % inconsistent) had been seen, so the
#   re-scoped row is declared tuned;
# * the typical run must have at most 5 % of its epochs above the quantile, forward and smoothed, and, since the
#   paper calls it typical, its Monte Carlo cell (9:2 NRHO, 2 h) must be consistent by the rule above;
# * the regime row asks for the paper's contrast (most angles-only runs diverge, at most 10 % with the paper's
#   1-s rates) in every cell of the map;
# * the filter-axes row asks for the same contrast at every cadence tried, for at least one of the filters of
#   Section 5c (the unwrapped-azimuth filter counts: the paper's filter may have had that bug);
# * "quantitatively better" is read as a smaller median final 3-sigma position than the 9:2 NRHO's at half of the
#   cadences or more. The outer-band rows are marked tuned, since that orbit was chosen for fitting the remarks;
# * the operational rows of Section 5d use the definitions written there before the runs: custody "indefinitely"
#   holds when every run keeps the prediction within the camera's 0.5° half field of view through every period,
#   and the filter stays consistent when at most 10 % of the runs are inconsistent in any period (one row each per
#   station-keeping policy); the SRI row asks that the SRI form stay consistent on every rung where a covariance
#   form fails, and that the forms agree on the chapter's case; the re-linearisation row asks that the
#   fixed-reference filter fail in more than 10 % of the runs with rates at some cadence while the re-linearised
#   one does not; the sweet-spot row asks that the knee of the accuracy-against-run-time curve (its deepest point
#   below the chord of the log-log curve) be 1, 2 or 4 h; that reading was revised after the full run, so the row
#   is tuned.
#
# The Table 4 rows have no paper value (the table is missing from the text) and only record our medians.

# %%
span = f"{obs.cadence_label(min(cadences_h))}-{obs.cadence_label(max(cadences_h))}"
flag_a, flag_r = flagged["angles only"], flagged["angles + rates"]
n_cells = len(angles_only.rows)
t_perilune_h = {n: o.period / 2 * em.time_unit_s / 3600 for n, o in ORBITS.items()}  # tracks start at apoapsis
early = angles_only.orbits_diverging_before(t_perilune_h)
n_early = len(angles_only.cells_diverged_before(t_perilune_h))
table.add(obs.filled(CLAIMS["angles_only_l2"], span=span).judge(
    "9:2 NRHO" in early and any(n.startswith("stable") for n in early),
    reason=("in no (orbit, cadence) cell did most angles-only runs diverge" if not cells else
            "most runs diverged before perilune at every cadence only on " + (", ".join(early) or "no orbit")),
    shown=f"{SIGMA_ANGLE_URAD:g} urad: most runs diverged in {len(cells)} of {n_cells} (orbit, cadence) cells, before "
    f"perilune in {n_early}; "
    "cells above 10% inconsistent runs: " + ("; ".join(f"{n} {c:g} h: {100 * d:.0f}%" for n, c, d in flag_a)
                                             or "none"),
    note="same 10% flag as the angles + rates row; the paper's stable NRHO is one of our two candidates; other "
    "noise levels, cadences and hand-offs in Section 4 and the regime map (Section 5b), whose hand-off rows judge "
    "the claim at each noise of the sweep"))
for sig, row in noisier.items():
    table.add(obs.filled(CLAIMS["angles_only_noise"], noise=f"{sig * 1e6:g}").judge(
        bool(row[2] > 0.5), shown=f"{100 * row[2]:.0f}% diverged", note="noise level varied"))
for key, rows5, what in (("five_observers_stated", five_stated, "hand-off 10 km"),
                         ("five_observers", five_fig4, "a tenth of each noise, hand-off 1 km")):
    best5 = max(rows5, key=lambda u: rows5[u][2])  # the noise reading closest to the paper's statement
    div5 = rows5[best5][2]
    noise5 = "/".join(f"{(u if key == 'five_observers_stated' else u / 10):g}" for u in rows5)
    table.add(obs.filled(CLAIMS[key], noises=noise5).judge(
        div5 if key == "five_observers_stated" else bool(div5 > 0.5),
        shown=f"{100 * div5:.0f}% diverged"
        + ("" if len(rows5) == 1 else " at every reading" if div5 == 0 else
           f" (best reading {best5 if key == 'five_observers_stated' else best5 / 10:g} urad)"),
        note=f"{what}; per reading ({noise5} urad): " + "/".join(f"{100 * r[2]:.0f}" for r in rows5.values())
        + " % diverged, median NEES " + "/".join(f"{r[3]:.1f}" for r in rows5.values())
        + f"; {n_runs_five} runs each"))
flagged_orbits_rates = sorted({n for n, _, _ in flag_r})
n_runs_rates = sum(len(v) for v in with_rates.runs.values())
frac_rates = np.mean([r.diverged for v in with_rates.runs.values() for r in v])
clean_rates = [n for n in ORBITS if n not in flagged_orbits_rates]  # orbits with no cell above the 10 % flag
table.add(obs.filled(CLAIMS["angles_rates_l2"], span=span).judge(
    "9:2 NRHO" in clean_rates and any(n.startswith("stable") for n in clean_rates),
    shown=f"{100 * frac_rates:.1f}% of {n_runs_rates} runs inconsistent; no cell above 10% on "
    + (", ".join(clean_rates) or "no orbit"),
    reason="some cadences have many inconsistent runs on " + ", ".join(flagged_orbits_rates),
    note="cells above 10% inconsistent runs: " + ("; ".join(f"{n} {c:g} h: {100 * d:.0f}%" for n, c, d in flag_r)
                                                  or "none")
    + "; the paper's stable NRHO is one of our two candidates (the inner band judged unlike it: 'Which stable NRHO, "
    "by evidence')"))
tf, ts = typical.forward, typical.smoothed
cell_runs = with_rates.runs.get(("9:2 NRHO", TYPICAL_CADENCE_H), [])  # its Monte Carlo cell (Section 5)
cell_bad = float(np.mean([r.diverged for r in cell_runs])) if cell_runs else 1.0
table.add(CLAIMS["typical_run"].judge(
    not (tf.diverged or ts.diverged) and cell_bad <= 0.10,
    shown=f"mean NEES forward {tf.nees_mean:.1f}, smoothed {ts.nees_mean:.1f}; epochs over 99.9 %: "
    f"{100 * tf.inconsistent_fraction:.1f} % / {100 * ts.inconsistent_fraction:.1f} %; its cell: "
    + (f"{100 * cell_bad:.0f} % of {len(cell_runs)} runs inconsistent" if cell_runs else "not run (CADENCES)"),
    note="one run (Section 3) and the Monte Carlo cell of its set-up (Section 5)"))
r92, rst, rso = (with_rates.by_cadence(n) for n in ORBITS)
for cad in sorted(r92):
    table.add(obs.filled(CLAIMS["table4"], cadence=obs.cadence_label(cad)).judge(
        r92[cad][4], shown=f"9:2 {r92[cad][4]:.3g} km / {r92[cad][5]:.3g} m/s; stable inner band {rst[cad][4]:.3g} "
        f"km / {rst[cad][5]:.3g} m/s; stable outer band {rso[cad][4]:.3g} km / {rso[cad][5]:.3g} m/s",
        note="median over runs; angles + rates from L2"))
n_contrast = {m: len(v) for m, v in regime.contrast.items()}
n_map = len(regime.map_cells)
table.add(CLAIMS["regime_contrast"].judge(
    n_contrast[regime.rates_paper] == n_map, shown="; ".join(f"{m}: {n} of {n_map} cells" for m, n in
                                                               n_contrast.items()),
    reason=("no cell shows the contrast, with the paper's 1-s rates"
            + (" or with informative (dt = 1 TU) rates" if len(regime.model_names) > 2 else "")
            if sum(n_contrast.values()) == 0 else "no cell shows the contrast with the paper's 1-s rates"
            if n_contrast[regime.rates_paper] == 0 else "the contrast holds only in part of the map"),
    note=f"map over hand-off {10 * min(handoff_map):g}-{10 * max(handoff_map):g} km, noise "
    f"{'/'.join(f'{sg * 1e6:g}' for sg in sigma_map)} urad, cadence {'/'.join(f'{c:g}' for c in cadence_map)} h, "
    f"all three orbits; {n_runs_map} runs per cell; the dt = 1 TU rate reading is beyond the paper"))
map_noises = "/".join(f"{sg * 1e6:g}" for sg in sigma_map)
map_cads = "/".join(f"{c:g}" for c in cadence_map)
for key, o in zip(("9_2", "inner", "outer"), ORBITS):
    readings, works, ons = regime.noise_readings(o), regime.diverging_noises(o), regime.onset_km(o)
    closest = max(readings, key=lambda sg: (min(readings[sg]), sum(readings[sg]), sg))  # nearest to the claim
    per_noise = "; ".join(f"{sg * 1e6:g} urad " + "/".join(f"{100 * v:.0f}" for v in fr) + " %"
                          for sg, fr in readings.items())
    table.add(obs.filled(CLAIMS[f"handoff_{key}"], cadences=map_cads, noises=map_noises).judge(
        bool(works), shown=(f"most runs diverge at every cadence with {', '.join(f'{sg * 1e6:g}' for sg in works)} "
                            "urad" if works else "no noise reading" + (f" (closest: {closest * 1e6:g} urad)"
                                                                        if max(map(max, readings.values())) > 0
                                                                        else ""))
        + f"; diverged at 10 km, per noise ({map_cads} h): {per_noise}",
        reason=("at no noise reading of the sweep do most angles-only runs diverge at every cadence at the stated "
                "hand-off" + (" (none diverge at any)" if max(map(max, readings.values())) == 0 else "")),
        note="the sweep is the regime map (Section 5b); most angles-only runs diverge from a hand-off of "
        + (f"{ons:g} km" if ons is not None else f"none up to {10 * max(handoff_map):g} km")
        + " (smallest over noise and cadence)"))
full_axes = axes_study.axes_with_full_contrast
n_axes_cells = len(axes_study.cadences)
table.add(obs.filled(CLAIMS["filter_axes_contrast"], axes=", ".join(axes_study.axes),
                     cadences=", ".join(obs.cadence_label(c) for c in axes_study.cadences)).judge(
    bool(full_axes), shown="; ".join(f"{a}: {len(ks)} of {n_axes_cells}" for a, ks in axes_study.contrast.items()),
    reason=("no filter tried shows the contrast at any cadence" if not any(axes_study.contrast.values()) else
            "no filter tried shows the contrast at every cadence"),
    note=f"cadences with the contrast, per filter; {n_runs_axes} runs per cell, the same draws for every filter"
    + (f"; the contrast holds at every cadence only with: {', '.join(full_axes)}" if full_axes else "")))
b_in, b_out = cand.better["stable NRHO (inner band)"], cand.better["stable NRHO (outer band)"]
ratio_outer = cand.ratio["stable NRHO (outer band)"]
table.add(CLAIMS["outer_better"].judge(b_out, shown=f"smaller final sigma at {100 * b_out:.0f}% of cadences (ratio "
                                       f"{min(ratio_outer):.2f}-{max(ratio_outer):.2f}; perilune "
                                       f"{outer.perilune_radius_km:.0f} km)"))
for key, name in (("inner", "stable NRHO (inner band)"), ("outer", "stable NRHO (outer band)")):
    claim = CLAIMS[f"{key}_consistent_long"]
    table.add(obs.filled(claim, cadences="-".join(f"{c:g}" for c in long_gap)).judge(
        cand.inconsistent[name], shown=f"{100 * cand.inconsistent[name]:.0f} % of runs inconsistent (9:2 NRHO: "
        f"{100 * cand.inconsistent['9:2 NRHO']:.0f} %)", note="criterion fixed in advance (notebook 09's flag)"))
table.add(CLAIMS["inner_better"].judge(b_in, shown=f"smaller final sigma at {100 * b_in:.0f}% of cadences",
                                       note="final epoch at apoapsis after one period; the paper's Table 4 values "
                                       "are not available to compare"))
quiet_c = custody[det.QUIET_POLICY.name]
for pname, c in custody.items():
    fields = dict(periods=c.periods, runs=c.n_runs, policy=pname)
    table.add(obs.filled(OPS["custody_indefinite"], **fields).judge(
        c.kept_throughout, shown=f"custody kept in {100 * c.custody_fraction[-1]:.0f} % of runs through period "
        f"{c.periods}; worst pointing error {np.rad2deg(np.max(c.max_pointing_rad)):.4f} deg",
        note=f"bound 0.5 deg (1-deg camera, our choice); burns {1e3 * c.burn_m_s.min():.0f}-{1e3 * c.burn_m_s.max():.0f}"
        f" mm/s, one per apoapsis; window weight matched to the policy; 2-h cadence, periapsis hand-off; median "
        f"3-sigma at the end of the last three periods " + ", ".join(
            f"{v:.0f}" for v in np.nanmedian(c.sigma_end_km, axis=0)[-3:]) + f" km, worst filtered error "
        f"{np.nanmax(c.max_error_km[np.isfinite(c.max_error_km)]):.0f} km: 'indefinitely' is judged over "
        f"{c.periods} periods only"))
    table.add(obs.filled(OPS["custody_consistent"], **fields).judge(
        c.worst_inconsistent_fraction, shown=f"{100 * c.worst_inconsistent_fraction:.0f} % of runs inconsistent in "
        f"the worst period; median mean NEES {np.nanmedian(c.nees_mean):.1f}", note=f"{c.n_runs} runs per period"))
lost_cov = {n: any(k.lost(f)[p] for f in ("Joseph", "conventional") for p in k.lost(f))
            for n, k in conditioning.items()}
sri_ok = all(not any(k.lost("SRI").values()) for n, k in conditioning.items() if lost_cov[n])
well = conditioning[ladder[0]]
table.add(OPS["sri_stable"].judge(
    bool(sri_ok and well.max_diff < 1e-8 and any(lost_cov.values())),
    shown="; ".join(f"{n}: covariance form lost "
                    + (", ".join(sorted({p for f in ('Joseph', 'conventional') for p, v in k.lost(f).items() if v}))
                       or "nothing") + ", SRI " + (", ".join(p for p, v in k.lost("SRI").items() if v) or "nothing")
                    for n, k in conditioning.items()),
    reason=("no rung of the ladder made a covariance form fail" if not any(lost_cov.values()) else ""),
    note=f"linearised 9:2 NRHO, {n_draws_conditioning} draws per case; forms agree to {well.max_diff:.0e} on the "
    "chapter's case; the paper's own case is well conditioned enough for either form; what the covariance forms lose "
    "is listed per rung (the Joseph form loses symmetry and positive definiteness, not the estimate's "
    "consistency): SRI's advantage is covariance hygiene"))
ax_worst = {a: axes_study.worst_cadence(a, "9:2 NRHO", "angles+rates") for a in ("baseline", "fixed reference")}
ax_rates = {a: axes_study.cells[a, "9:2 NRHO", c, "angles+rates"] for a, c in ax_worst.items()}
n_worst = axes_study.runs_at(ax_worst["fixed reference"])
table.add(obs.filled(OPS["relinearization_needed"], cadences=", ".join(obs.cadence_label(c)
                                                                          for c in axes_study.cadences)).judge(
    bool(ax_rates["fixed reference"] > 0.10 and ax_rates["baseline"] <= 0.10),
    shown=f"diverged runs, worst cadence: fixed reference {100 * ax_rates['fixed reference']:.0f} %, re-linearised "
    f"{100 * ax_rates['baseline']:.0f} %", note=f"Section 5c, {n_runs_axes} runs per cell ({axes_study.runs_at(1 / 60)} "
    f"at cadences under 6 min), the same draws; at the fixed reference's worst cadence, "
    f"{obs.cadence_label(ax_worst['fixed reference'])}, {round(ax_rates['fixed reference'] * n_worst)} of {n_worst} "
    f"runs diverged"))
band = np.isin(cost.cadences_h, (1.0, 2.0, 4.0))
depth = cost.chord_depth
out_i = int(np.argmax(np.where(band, -np.inf, depth)))
table.add(obs.filled(OPS["cadence_sweet_spot"], cadences=f"{obs.cadence_label(min(cost.cadences_h))}-"
                     f"{obs.cadence_label(max(cost.cadences_h))}").judge(
    bool(cost.has_knee and cost.knee_h in (1.0, 2.0, 4.0)),
    shown=(f"knee at {obs.cadence_label(cost.knee_h)} (depth below the chord {depth.max():.2f})"
           if cost.has_knee else "no knee (no cadence below the chord)")
    + (f"; 2 h {depth[list(cost.cadences_h).index(2.0)]:.2f}" if 2.0 in cost.cadences_h else "")
    + f"; deepest outside 1-4 h: {obs.cadence_label(cost.cadences_h[out_i])} {depth[out_i]:.2f}"
    + (f"; 2 h costs {1 / cost.cost_ratio()[0]:.2f}x the {obs.cadence_label(cost.cadences_h[0])} run for "
       f"{cost.sigma3_km[list(cost.cadences_h).index(2.0)] / cost.sigma3_km[0]:.2f}x its 3-sigma"
       if 2.0 in cost.cadences_h else ""),
    reason=(f"the knee is at {obs.cadence_label(cost.knee_h)}, outside 1-4 h" if cost.has_knee else
            "no cadence lies below the chord: the curve does not bend towards diminishing returns"),
    note="depth: natural log of the final 3-sigma position below the chord of the log-log curve (0.1 = 10 % more "
    f"accurate than the power law through the end points); first definition (elasticity >= 1): knee at "
    f"{obs.cadence_label(cost.elasticity_knee_h)}, elasticity {np.nanmin(cost.elasticity):.2f}-"
    f"{np.nanmax(cost.elasticity):.2f}; CPU time of the single-trial filter per period, best of up to "
    f"{cost_repeats} runs; a shallow bend (depths within a few hundredths) can move with timing noise"))
executors.close()  # shuts the worker processes down
table.display()

# %% [markdown]
# ## Exercises
#
# Each exercise asks you to change one entry of the parameters cell, to predict what will happen before running,
# and then to check. The worked solutions are functions of `cislunar.papers.greaves_scheeres_2021.exercises`, run
# at small sizes (a few seconds each); each returns the numbers that answer the exercise and an `answer` paragraph.
#
# 1. **Noisier angles.** Set `SIGMA_ANGLE_URAD = 100` (ten times the default). Before running, use the information
#    form of the measurement update (information adds as $H^\top R^{-1} H$, and $R \propto \sigma^2$) to predict
#    the factor by which the Table 4 rows' final 3-sigma positions grow, and whether the angles-only runs of
#    Section 4 start to diverge. Worked solution: `exercises.exercise_09_angle_noise`.
# 2. **Denser tracking.** Add a 1-hour cadence to quick mode, `CADENCES_H = [1.0, 2.0, 12.0]`. If every measurement
#    were independent information about a fixed state, the standard deviation would fall as the square root of
#    their number: predict the 1-h row's final 3-sigma position from the 12-h one, then compare; is the gain more
#    or less than the square root, and why? Worked solution: `exercises.exercise_09_cadence`.
# 3. **A wider hand-off.** Set `HANDOFF_MAP = [1.0, 30.0, 300.0]` (10 km, 300 km and 3000 km, 3-sigma) and
#    `N_MAP = 4`. Predict where most angles-only runs start to diverge, and whether the *filter's own* final
#    3-sigma position (which the Table 4 rows report) shows it. Worked solution: `exercises.exercise_09_handoff`.
