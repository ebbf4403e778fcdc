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
# itself (Eqs. 14-32) is `cislunar.estimation.ocbe`; the tracking scenario (L2 observer, angles and angle rates every 2 hours,
# Earth-radar hand-off at periapsis) is `cislunar.papers.greaves_scheeres_2021.tracking`; everything specific to detection is
# `cislunar.papers.greaves_scheeres_2021.detection`.
#
# **What the paper does not give.** Tables 1-8 are missing from its text: in particular the measurement noise
# (Table 3) and the OCBE tuning values. We use 10 micro-rad angles (1 sigma) with Eq. 13 rates from 1 s
# differencing (see `cislunar.papers.greaves_scheeres_2021.tracking`). The tuning is the one input every number of this notebook depends on, so
# Section 2 maps it (window weight, angle noise, window length, base weight) and reads it in two ways: from the
# paper's *consistency* claim (an independent prediction of everything else) and from the paper's *thresholds*
# (a tuned reading). Both are carried through and the closing table says which rows rest on which.

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: quick mode shrinks every Monte Carlo; every step still runs.
N_H0 = 8 if QUICK else 500  # non-maneuvering training runs per policy and orbit (paper: 500)
N_H1 = 8 if QUICK else 3000  # maneuvering training runs per policy and orbit (paper: 3000)
N_TEST = 4 if QUICK else 100  # test runs per hypothesis, policy and orbit (paper: 100 + 100)
N_MAP = (8, 8) if QUICK else (150, 250)  # H0, H1 runs per cell of the tuning map (Section 2)
F_GRID = (0.03, 0.1, 0.2, 0.3, 0.5, 1.0)  # window weight factors f (units of the variance-matched weight)
F_SIDE = (0.1, 0.2, 0.3)  # factors of the map's side axes (noise, window length, base weight), 9:2 NRHO
N_SPIKE = 8 if QUICK else 200  # runs per hypothesis of the Figs. 10-11 check (constant tuning)
N_POLICY_DRAWS = 5000 if QUICK else 200000  # draws to check the station-keeping distributions
PM_J_SEEDS = 1 if QUICK else 3  # noise draws per direction in the +-j search (Section 4)
PM_J_F = (0.03, 0.1, 0.3, 1.0)  # window weight factors of the +-j search
PM_J_NOISE_URAD = (10.0, 100.0, 300.0, 1000.0)  # angle noise of the +-j search, micro-rad
PM_J_OFFSET_H = (-3.0, 0.0, 3.0)  # burn time after apoapsis in the +-j search, hours (window: +-4 h)
N_PM_J_MC = 8 if QUICK else 600  # randomly pointed burns per policy where the +-j pattern appears
N_Z05 = 4 if QUICK else 64  # 0.5 m/s burns per tuning factor (health metric, Section 6)
N_LEAD = (10, 2) if QUICK else (200, 48)  # no-burn runs (calibration, validation) and runs per burn size
LEAD_MAGNITUDES = (0.05, 0.1, 0.2, 0.5)  # burn sizes of the control-versus-residual race, m/s
N_BOOT = 4 if QUICK else 40  # bootstrap resamples for the standard errors of z_lim and of the expected error
BATCH = 8  # trials that the batched OCBE filters together, epoch by epoch
WORKERS = 1 if QUICK else 2  # processes for the Monte Carlo

import multiprocessing as mp
import time
from concurrent.futures import ProcessPoolExecutor

import matplotlib.pyplot as plt
import numpy as np
from scipy import stats

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import adaptive_ocbe as ad
from cislunar.estimation import consistency
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import panels as ocbe_panels
from cislunar.papers.greaves_scheeres_2021 import tracking
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
executor = ProcessPoolExecutor(WORKERS, mp_context=mp.get_context("spawn")) if WORKERS > 1 else None
TUNED = "consistent (tuned)"  # agreement that rests on a choice made while looking at the paper
table = ComparisonTable("10 Maneuver detection (Greaves & Scheeres 2021, Eqs. 3-5, 33-35, Figs. 10-22, Tables 5-8)")
OUTER = "stable NRHO (outer band)"
ORBITS = {"9:2 NRHO": orbits.nrho_9_2(em), "stable NRHO": orbits.stable_nrho(em), OUTER: orbits.stable_nrho_outer(em)}
STABLE = ("stable NRHO", OUTER)
OUTER_SIZE = 0.2  # the outer-band candidate (notebook 09) runs a fifth of the training Monte Carlo, half the tests
POLICIES = {"active": det.ACTIVE_POLICY, "quiet": det.QUIET_POLICY}
PAPER_ZLIM = {"active": 0.4106, "quiet": 0.01722}  # m/s (Eq. 35 text)
V_MM = em.velocity_unit_km_s * 1e6  # LU/TU -> mm/s
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
fig, ax = plt.subplots(1, 3, figsize=(14, 3.8))
for name, pol in POLICIES.items():
    m = pol.sample_magnitude(rng, N_POLICY_DRAWS)
    d = pol.magnitude_distribution
    a = ax[0 if name == "active" else 1]
    a.hist(m * 1e3, bins=60, density=True, alpha=0.6, histtype="stepfilled", label="draws")
    zz = np.linspace(d.ppf(0), d.ppf(1), 300)
    a.plot(zz * 1e3, d.pdf(zz) / 1e3, "k", lw=1, label="truncnorm PDF")
    a.set(title=f"{name}: mean {m.mean() * 1e3:.1f}, sd {m.std() * 1e3:.2f} mm/s",
          ylim=(0, 1.35 * d.pdf(d.mean()) / 1e3),  # headroom for the legend
          xlabel="impulse magnitude [mm/s]", ylabel="probability density [1/(mm/s)]")
    print(f"{name}: range [{m.min() * 1e3:.2f}, {m.max() * 1e3:.2f}] mm/s (bounds "
          f"{(pol.mean_m_s - 3 * pol.sd_m_s) * 1e3:.1f}, {(pol.mean_m_s + 3 * pol.sd_m_s) * 1e3:.1f}); "
          f"sd/sigma_u = {m.std() / pol.sd_m_s:.4f} (truncnorm {d.std() / pol.sd_m_s:.4f})")
az, el = det.StationKeepingPolicy.sample_pointing(rng, N_POLICY_DRAWS)
uz = det.pointing_vector(az, el)[:, 2]
ax[2].hist(uz, bins=50, density=True, alpha=0.6, histtype="stepfilled", label="Eqs. 3-4 (paper)")
ax[2].plot(np.linspace(-0.999, 0.999, 200), stats.arcsine(-1, 2).pdf(np.linspace(-0.999, 0.999, 200)), "k", lw=1,
           label="arcsine PDF")
ax[2].axhline(0.5, color="C3", ls="--", label="uniform sphere")
ax[2].set(xlabel=r"$\hat k$ component of the impulse direction [-]", ylabel="probability density [-]", ylim=(0, 3),
          title="pointing")
ax[0].legend(loc="upper left")
ax[2].legend(fontsize=8, loc="upper center")
_ = plotting.save_figure(fig, "10_station_keeping_policy", output_dir=out)
ks_sphere = stats.kstest(uz, stats.uniform(-1, 2).cdf).pvalue
ks_txt = f"= {ks_sphere:.1e}" if ks_sphere > 0 else "< 1e-300"  # below the smallest double: printed as a bound
print(f"KS test of u_z against a uniform sphere: p {ks_txt}; against arcsine: "
      f"p = {stats.kstest(uz, stats.arcsine(-1, 2).cdf).pvalue:.2f}")
table.add_typed("Eq. 5 magnitude stays within mean +- 3 sd (both policies)", "by construction",
          "yes (exact truncnorm draws)", "derived")
_ = table.add_typed("Eqs. 3-4 pointing", "'random pointing', U[-pi,pi] x U[-pi/2,pi/2]",
              f"as written; not uniform on the sphere (KS p {ks_txt})", "derived",
              "uniform elevation over-weights the poles; implemented as the paper writes it")

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
Q_BASE = 1e-18  # km^2/s^3 outside the apoapsis window
WINDOW_HOURS = 8.0
SIGMA_ANGLE = tracking.DEFAULT_SIGMA_ANGLE_RAD
VARIANTS = {"paper window, our noise": {}, "noise 2 urad": dict(sigma_angle_rad=2e-6),
            "noise 20 urad": dict(sigma_angle_rad=20e-6), "4-h window": dict(window_hours=4.0),
            "12-h window": dict(window_hours=12.0), "base 1e-16": dict(q_base=1e-16)}
BASE_VARIANT = "paper window, our noise"


def map_setup(orbit, policy, f, variant):
    v = VARIANTS[variant]
    wh = v.get("window_hours", WINDOW_HOURS)
    return det.make_setup(em, ORBITS[orbit], f * det.window_control_weight(POLICIES[policy], wh),
                          v.get("q_base", Q_BASE), window_hours=wh,
                          sigma_angle_rad=v.get("sigma_angle_rad", SIGMA_ANGLE))


cells = [(o, p, f, BASE_VARIANT) for o in ORBITS for p in POLICIES for f in F_GRID]
cells += [("9:2 NRHO", p, f, v) for v in VARIANTS if v != BASE_VARIANT for p in POLICIES for f in F_SIDE]
tmap = {}
for i, (o, p, f, v) in enumerate(cells):
    k = 0.5 if o == OUTER else 1.0  # the outer band's period is 10 days: half the runs
    st = det.run_policy_study(map_setup(o, p, f, v), POLICIES[p], max(int(k * N_MAP[0]), 4),
                              max(int(k * N_MAP[1]), 4), 0, [SEED, 77, i], batch_size=BATCH, executor=executor,
                              progress=False)
    tmap[o, p, f, v] = dict(z_lim=st.threshold.z_lim, err=st.threshold.total_error, h0=st.h0.inconsistent_runs,
                            h1=st.h1.inconsistent_runs, n=(len(st.h0), len(st.h1)),
                            slope=np.polyfit(st.h1.magnitude, st.h1.z, 1)[0])
print(f"tuning map: {len(cells)} settings, {N_MAP[0]} + {N_MAP[1]} runs each (outer band half), "
      f"{(time.perf_counter() - T_START) / 60:.1f} min so far")
print(f"{'orbit':25s} {'policy':7s} {'setting':24s} {'f':>5s} {'z_lim':>11s} {'FP+MD':>6s} "
      f"{'inconsistent runs H0 fwd/smo, H1 fwd/smo':>42s}")
for (o, p, f, v), c in tmap.items():
    print(f"{o:25s} {p:7s} {v:24s} {f:5.2f} {c['z_lim'] * 1e3:8.2f} mm/s {c['err']:6.3f} "
          f"{100 * c['h0'][0]:9.0f} % / {100 * c['h0'][1]:3.0f} %, "
          f"{100 * c['h1'][0]:3.0f} % / {100 * c['h1'][1]:3.0f} %")


def worst(o, p, f, v=BASE_VARIANT):
    """Largest fraction of inconsistent runs over hypotheses and passes of one map cell."""
    c = tmap[o, p, f, v]
    return max(*c["h0"], *c["h1"])


consistent_f = [f for f in F_GRID if all(worst(o, p, f) <= 0.10 for o in ORBITS for p in POLICIES)]
F_C = consistent_f[0] if consistent_f else F_GRID[-1]
F_TUNE = 0.1  # the threshold reading


def f_match(p, v=BASE_VARIANT):
    """Factor at which the 9:2 z_lim of the map equals the paper's (log-log interpolation; NaN outside the grid)."""
    fs = [f for f in (F_GRID if v == BASE_VARIANT else F_SIDE)]
    zl = np.array([tmap["9:2 NRHO", p, f, v]["z_lim"] for f in fs])
    order = np.argsort(zl)
    lz, lf = np.log(zl[order]), np.log(np.array(fs)[order])
    x = np.log(PAPER_ZLIM[p])
    return float(np.exp(np.interp(x, lz, lf))) if lz[0] <= x <= lz[-1] else float("nan")


F_MATCH = {p: f_match(p) for p in POLICIES}
print(f"consistency reading: f_c = {F_C:g} (every orbit, policy and hypothesis at most 10 % inconsistent runs; "
      f"factors meeting it: {consistent_f})")
print("threshold reading: the 9:2 z_lim of the map equals the paper's at f = "
      + ", ".join(f"{F_MATCH[p]:.2f} ({p})" for p in POLICIES) + f"; the training runs below use f = {F_TUNE}")
both = [(v, f) for v in VARIANTS for f in (F_GRID if v == BASE_VARIANT else F_SIDE)
        if all(worst("9:2 NRHO", p, f, v) <= 0.10
               and abs(tmap["9:2 NRHO", p, f, v]["z_lim"] / PAPER_ZLIM[p] - 1) <= 0.25 for p in POLICIES)]
print("9:2 NRHO settings that are consistent (both policies) with both thresholds within 25 % of the paper's: "
      + (", ".join(f"{v} at f = {f:g}" for v, f in both) or "none"))
print("9:2 NRHO settings consistent at f = 0.1: "
      + (", ".join(v for v in VARIANTS if all(worst("9:2 NRHO", p, 0.1, v) <= 0.10 for p in POLICIES)) or "none"))
for v in VARIANTS:
    if v == BASE_VARIANT:
        continue
    ok = [f for f in F_SIDE if all(worst("9:2 NRHO", p, f, v) <= 0.10 for p in POLICIES)]
    print(f"9:2 NRHO, {v:14s}: consistent (both policies) at f = {ok or 'none of ' + str(F_SIDE)}; z_lim / paper at "
          "f = " + ", ".join(f"{f:g}: " + " / ".join(f"{tmap['9:2 NRHO', p, f, v]['z_lim'] / PAPER_ZLIM[p]:.2f}"
                                                    for p in POLICIES) for f in F_SIDE) + " (active / quiet)")

# %%
fig, ax = plt.subplots(2, 3, figsize=(15, 8.4))
for o, col in zip(ORBITS, ("C0", "C1", "C2")):
    for p, ls in zip(POLICIES, ("-", "--")):
        c = [tmap[o, p, f, BASE_VARIANT] for f in F_GRID]
        lab = f"{o}, {p}"
        ax[0, 0].plot(F_GRID, [100 * x["h1"][0] for x in c], ls, color=col, marker="o", ms=3, label=lab)
        ax[0, 1].plot(F_GRID, [100 * x["h1"][1] for x in c], ls, color=col, marker="o", ms=3, label=lab)
        ax[0, 2].plot(F_GRID, [x["err"] for x in c], ls, color=col, marker="o", ms=3, label=lab)
for v, col in zip(VARIANTS, ("k", "C3", "C4", "C5", "C6", "C7")):
    for p, ls in zip(POLICIES, ("-", "--")):
        fs = F_GRID if v == BASE_VARIANT else F_SIDE
        kw = dict(color=col, marker="o", ms=3)
        ax[1, 0].plot(fs, [100 * worst("9:2 NRHO", p, f, v) for f in fs], ls, label=f"{v}, {p}", **kw)
        ax[1, 1].plot(fs, [tmap["9:2 NRHO", p, f, v]["z_lim"] / PAPER_ZLIM[p] for f in fs], ls, **kw)
        ax[1, 2].plot(fs, [tmap["9:2 NRHO", p, f, v]["err"] for f in fs], ls, **kw)
for a in (ax[0, 0], ax[0, 1], ax[1, 0]):
    a.axhline(10, color="0.5", lw=0.8, ls=":")
ax[1, 1].axhspan(0.75, 1.25, color="0.85", zorder=0)
ax[1, 1].axhline(1.0, color="0.4", lw=0.8)
titles = (("burn runs (H1): forward inconsistent", "inconsistent runs [%]"),
          ("burn runs (H1): smoothed inconsistent", "inconsistent runs [%]"),
          ("expected error of the test", "FP + MD [-]"),
          ("9:2 NRHO: worst cell (H0/H1, fwd/smo)", "inconsistent runs [%]"),
          ("9:2 NRHO: threshold over the paper's", "z_lim / paper z_lim [-]"),
          ("9:2 NRHO: expected error of the test", "FP + MD [-]"))
for a, (t, yl) in zip(ax.ravel(), titles):
    a.set(xscale="log", xlabel="window weight factor f [-]", ylabel=yl, title=t)
    a.axvline(F_C, color="C2", lw=2, alpha=0.3)
    a.axvline(F_TUNE, color="C1", lw=2, alpha=0.3)
h, lab = ax[0, 0].get_legend_handles_labels()
fig.legend(h, lab, loc="upper center", bbox_to_anchor=(0.5, 0.515), ncol=6, fontsize=8)
h, lab = ax[1, 0].get_legend_handles_labels()
fig.legend(h, lab, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=4, fontsize=8)
fig.tight_layout(h_pad=5.0)
_ = plotting.save_figure(fig, "10_tuning_map", output_dir=out)

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
sc_q = s_q.scenario
demo = det.draw_trial(np.random.default_rng([SEED, 7]), s_q, magnitude_m_s=0.05, direction=(np.pi / 2, 0.0))
q_tunings = {"constant": s_q.control_weight.max(), "apoapsis window": s_q.control_weight}
runs = {name: det.run_trial_filter(s_q, demo, control_weight=q) for name, q in q_tunings.items()}
panels = {name: ocbe_panels.panel_series(em, r, demo.truth, q_tunings[name], demo.y, s_q.observer_states, sc_q.model,
                                sc_q.meas_cov) for name, r in runs.items()}
burn_days = s_q.t_maneuver * em.time_unit_days
nees_q = stats.chi2.ppf(consistency.NEES_PROBABILITY, 6)
fig_summary = {}
for name, r in runs.items():
    pn = panels[name]
    over = np.mean(pn.nees > nees_q, axis=1)  # fraction of epochs above the 99.9 % NEES quantile, fwd / smoothed
    m_norm = pn.normalized_metric[0]
    fig_summary[name] = dict(over=over, z_f=r.z_step * V_MM, z_s=r.z_smooth * V_MM,
                             metric_over=int(np.sum(m_norm > 1)), trigger=ad.first_detection(pn.metric[0], pn.limit),
                             sig_final=(pn.position_3sigma_km[0, -1], pn.velocity_3sigma_m_s[0, -1] * 1e3),
                             contrast=pn.spike_contrast(burn_days))
    print(f"{name:16s}: z forward {r.z_step * V_MM:6.2f} mm/s, smoothed {r.z_smooth * V_MM:6.2f} mm/s | epochs above "
          f"NEES 99.9 %: forward {100 * over[0]:.0f} %, smoothed {100 * over[1]:.0f} % | forward metric above its "
          f"limit at {fig_summary[name]['metric_over']} of {m_norm.size} epochs (adaptive rule "
          f"{'would' if fig_summary[name]['trigger'] is not None else 'would not'} fire) | final forward 3-sigma "
          f"{fig_summary[name]['sig_final'][0]:.2f} km, {fig_summary[name]['sig_final'][1]:.1f} mm/s | control spike "
          f"contrast at the burn: forward {fig_summary[name]['contrast'][0]:.3g}, smoothed "
          f"{fig_summary[name]['contrast'][1]:.3g}")
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
_ = plotting.save_figure(ocbe_panels.figure_errors(panels["apoapsis window"], "Fig. 12 analogue, 8-h apoapsis window",
                                          burn_days=burn_days, velocity_unit="mm/s"),
                         "10_fig12_window_tuning_errors", output_dir=out)
pw = panels["apoapsis window"]
k_b12 = int(np.searchsorted(pw.t_days, burn_days, side="right"))  # first epoch after the burn
hours_after = (pw.t_days[k_b12:] - burn_days) * 24
k_top12 = k_b12 + int(np.argmax(pw.position_3sigma_km[0, k_b12:]))
v_ratio = pw.velocity_error_m_s[0, k_b12:] / pw.velocity_3sigma_m_s[0, k_b12:]
p_ratio = pw.position_error_km[0, k_b12:] / pw.position_3sigma_km[0, k_b12:]
near = v_ratio > 0.8  # velocity error within 20 % of its 3-sigma bound (or above it)
k_end = int(np.argmin(near)) if not near.all() else near.size - 1  # end of the stretch right after the burn
below_half = np.flatnonzero(v_ratio < 0.5)
print(f"forward velocity error / its 3-sigma bound after the burn: {v_ratio[0]:.2f} at +{hours_after[0]:.0f} h, above "
      f"0.8 at the first {k_end} epoch(s), below 0.5 from "
      + (f"+{hours_after[below_half[0]]:.0f} h" if below_half.size else "never"))
for what, r_ in (("velocity", v_ratio), ("position", p_ratio)):
    later = np.flatnonzero(r_ > 0.8)
    later = later[later >= k_end]
    print(f"forward {what} error above 0.8 of its 3-sigma bound at {later.size} epochs from +{hours_after[k_end]:.0f} h"
          + (f", between day {pw.t_days[k_b12 + later[0]]:.2f} and {pw.t_days[k_b12 + later[-1]]:.2f}; largest "
             f"ratio {r_[later].max():.2f}" if later.size else ""))
over12 = pw.nees[0, k_b12:] > nees_q
print(f"forward NEES above its 99.9 % quantile at {int(over12.sum())} epochs after the burn, the first "
      f"{int(np.argmin(over12)) if not over12.all() else over12.size} of them in a row")
print(f"forward 3-sigma position: {pw.position_3sigma_km[0, k_b12]:.2f} km just after the burn, rising to "
      f"{pw.position_3sigma_km[0, k_top12]:.2f} km at day {pw.t_days[k_top12]:.2f} (burn at day {burn_days:.2f}), "
      f"{pw.position_3sigma_km[0, -1]:.2f} km at the end")

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
_ = plotting.save_figure(ocbe_panels.figure_control_metric(panels["apoapsis window"], "Fig. 13 analogue, 8-h apoapsis window",
                                                  burn_days=burn_days),
                         "10_fig13_window_tuning_control_metric", output_dir=out)
fs_c, fs_w = fig_summary["constant"], fig_summary["apoapsis window"]
print(f"smoothed over forward z: constant {fs_c['z_s'] / fs_c['z_f']:.1f}, window {fs_w['z_s'] / fs_w['z_f']:.1f}; "
      f"the window tuning's smoothed z is {fs_w['z_s'] / 50:.2f} of the 50 mm/s burn")

# %% [markdown]
# **Fig. 13 analogue** (the paper: a consistent filter "with a smoothed control spike around apoapsis that is
# indicative of a maneuver"). With the window tuning the control is essentially zero outside the window, so the
# smoothed spike stands alone and its integral $z$ tracks the burn. The forward control rises inside the window too
# (the estimated control is $-\tilde Q B^\top\mathbf p$, so it scales with $q_w$ whether or not there is a burn);
# the paper's text describes only the smoothed spike for this figure, so it does not tell whether its forward panel
# shows the same rise. The forward control stays far below the smoothed one: in this run the smoothed $z$ is the
# printed multiple of the forward $z$ (window tuning), and over the training runs of Section 3 the median multiple
# is in the closing table's Fig. 13 row. With the constant tuning the smoothed control also fits measurement noise
# all along the orbit, so the same burn is a smaller part of a larger $z$. The forward metric need not exceed its
# limit in either case: both tunings absorb the burn as expected control instead of flagging it, which is why the
# paper detects with $z$ and not with the metric.
#
# **The statements behind Figs. 10-11, on many runs.** $N$ quiet-policy runs with a burn and $N$ without (sizes
# printed) are filtered with both tunings at $f = 0.1$ (the same data for both). Criteria fixed before running:
# *Fig. 10* holds if at most 10 % of the runs are NEES-inconsistent, forward and smoothed, with and without a
# burn, and the constant tuning's mean forward 3-sigma position bound is larger than the window tuning's;
# *Fig. 11* holds if in at least 90 % of the burn runs the smoothed control's spike contrast at the burn
# (`detection.control_spike_contrast`: mean norm within 6 h of the burn over the mean elsewhere) is at least 2 and
# above the forward one, and in at least 90 % of the runs without a burn the smoothed contrast stays below 2 ("this
# control spike does not appear if there is no maneuver").

# %%
s_const = det.make_setup(em, ORBITS["9:2 NRHO"], s_q.q_window_km2_s3, s_q.q_window_km2_s3, window_hours=WINDOW_HOURS)
spike_in = {h: [det.draw_trial(r, s_q, pol) for r in np.random.default_rng([SEED, 41, j]).spawn(N_SPIKE)]
            for j, (h, pol) in enumerate((("H0", None), ("H1", det.QUIET_POLICY)))}
spike = {}
for tuning, s_ in (("constant", s_const), ("apoapsis window", s_q)):
    for h, inputs in spike_in.items():
        r = det.filter_trials(s_, inputs)
        nf = np.array([consistency.nees(r.x_filt[b], r.P_filt[b], c.truth) for b, c in enumerate(inputs)])
        ns = np.array([consistency.nees(r.x_smooth[b], r.P_smooth[b], c.truth) for b, c in enumerate(inputs)])
        frac = lambda n: float(np.mean(np.mean(n > nees_q, axis=1) > tracking.DIVERGED_FRACTION))  # noqa: E731
        k_b = int(np.searchsorted(sc_q.t, s_q.t_maneuver, side="right"))
        exc = nf > nees_q
        spike[tuning, h] = dict(
            inc=(frac(nf), frac(ns)), contrast=det.control_spike_contrast(s_, r),
            sig_km=float(np.mean(3 * np.sqrt(np.trace(r.P_filt[:, :, :3, :3], axis1=2, axis2=3)))) * em.length_unit_km,
            # share of the forward exceedances that fall in the day after the burn (the first 12 epochs after it)
            after_burn=float(exc[:, k_b:k_b + 12].sum() / max(exc.sum(), 1)))
print(f"{N_SPIKE} quiet-policy runs without a burn (H0) and {N_SPIKE} with one (H1), each filtered with both tunings")
for (tuning, h), v in spike.items():
    c = v["contrast"]
    print(f"{tuning:16s} {h}: inconsistent runs fwd {100 * v['inc'][0]:4.1f} %, smo {100 * v['inc'][1]:4.1f} % | mean "
          f"forward 3-sigma position {v['sig_km']:6.2f} km | spike contrast median fwd {np.median(c[:, 0]):7.3g}, smo "
          f"{np.median(c[:, 1]):7.3g} | runs with smoothed contrast >= 2 and above forward: "
          f"{100 * np.mean((c[:, 1] >= 2) & (c[:, 1] > c[:, 0])):.0f} % | forward NEES exceedances in the day after "
          f"the burn: {100 * v['after_burn']:.0f} %")
fig10_ok = (max(*spike["constant", "H0"]["inc"], *spike["constant", "H1"]["inc"]) <= 0.10
            and spike["constant", "H1"]["sig_km"] > spike["apoapsis window", "H1"]["sig_km"])
c1, c0 = spike["constant", "H1"]["contrast"], spike["constant", "H0"]["contrast"]
fig11_h1 = float(np.mean((c1[:, 1] >= 2) & (c1[:, 1] > c1[:, 0])))
fig11_h0 = float(np.mean(c0[:, 1] < 2))

# %% [markdown]
# **Figs. 10-11 on many runs** (the sizes and results printed above). The constant tuning keeps every run without a
# burn consistent and puts its forward 3-sigma bound at more than twice the window tuning's (12.9 against 5.6 km):
# the "consistent, but less certain" of Fig. 10 holds, except that with a burn 10.5 % of the smoothed runs are
# inconsistent, just above the 10 % of the criterion, so the row says "differs". The smoothed spike of Fig. 11
# appears without a burn in 2 % of the runs only, but with a burn it stands out (contrast at least 2 and above the
# forward one) in three runs out of four: in the others the smoother, which may fit control everywhere, does not
# concentrate the burn in the 12 hours around it. With the window tuning at $f = 0.1$ the forward filter is
# inconsistent in 56 % of the burn runs, and 69 % of its NEES exceedances fall in the day after the burn.
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


studies, studies_c = {}, {}
for i, o in enumerate(ORBITS):
    for j, p in enumerate(POLICIES):
        studies[o, p] = det.run_policy_study(setups[o, p], POLICIES[p], *sizes(o), [SEED, i, j], batch_size=BATCH,
                                             executor=executor, label=f"{o} {p}")
        studies_c[o, p] = det.run_policy_study(setups_c[o, p], POLICIES[p], *sizes(o), [SEED, 200 + i, j],
                                               batch_size=BATCH, executor=executor, label=f"{o} {p} f_c")
boot = {(key, which): det.threshold_bootstrap(st.h0.z, st.h1.z, N_BOOT, np.random.default_rng([SEED, 90, n, w]))
        for w, (which, group) in enumerate((("f = 0.1", studies), ("f_c", studies_c)))
        for n, (key, st) in enumerate(group.items())}
print(f"Monte Carlo wall time so far: {(time.perf_counter() - T_START) / 60:.1f} min")

# %%
fig, ax = plt.subplots(len(ORBITS), 4, figsize=(16, 3.3 * len(ORBITS)))
for row, o in enumerate(ORBITS):
    for k, p in enumerate(POLICIES):
        st = studies[o, p]
        unit, ulab = (1.0, "m/s") if p == "active" else (1e3, "mm/s")
        lo, hi = 0.0, max(st.h0.z.max(), st.h1.z.max()) * unit * 1.05
        bins = np.linspace(lo, hi, 50)
        a_h, a_p = ax[row, 2 * k], ax[row, 2 * k + 1]
        a_h.hist(st.h0.z * unit, bins=bins, alpha=0.6, histtype="stepfilled", label="no maneuver (H0)")
        a_h.hist(st.h1.z * unit, bins=bins, alpha=0.6, histtype="stepfilled", label="maneuver (H1)")
        zz = np.linspace(lo, hi, 600)
        a_p.plot(zz, st.threshold.pdf0(zz / unit) / unit, label=r"$PDF_{H0}$")
        a_p.plot(zz, st.threshold.pdf1(zz / unit) / unit, label=r"$PDF_{H1}$")
        for a in (a_h, a_p):
            a.axvline(st.threshold.z_lim * unit, color="k", ls=":", lw=1)
            a.set(xlabel=f"z [{ulab}]")
        a_h.set(title=f"{o}, {p}: {len(st.h0)} H0 + {len(st.h1)} H1 runs", ylabel="runs [-]")
        a_p.set(title=f"z_lim = {st.threshold.z_lim * unit:.4g} {ulab}", ylabel=f"probability density [1/({ulab})]")
h0h, h0l = ax[0, 0].get_legend_handles_labels()
h1h, h1l = ax[0, 1].get_legend_handles_labels()
fig.legend(h0h + h1h + [plt.Line2D([], [], color="k", ls=":", lw=1)], h0l + h1l + ["z_lim"], loc="lower center",
           ncol=5, bbox_to_anchor=(0.5, 0.0))
fig.tight_layout(rect=(0, 0.04, 1, 1))
_ = plotting.save_figure(fig, "10_control_integral_pdfs", output_dir=out)


def se(key, which, col):
    return float(boot[key, which][:, col].std(ddof=1))


for which, group in (("f = 0.1", studies), (f"f_c = {F_C:g}", studies_c)):
    w = "f = 0.1" if which == "f = 0.1" else "f_c"
    print(f"Tables 5-6 at {which} (expected rates from the PDFs; bootstrap standard errors)")
    print(f"{'orbit':25s} {'policy':7s} {'z_lim':>18s} {'false pos.':>11s} {'missed det.':>12s} {'FP + MD':>15s} "
          f"{'crossings':>9s} {'H0 mean':>10s} {'H1 mean':>10s}")
    for (o, p), st in group.items():
        th = st.threshold
        print(f"{o:25s} {p:7s} {th.z_lim * 1e3:8.2f} +- {se((o, p), w, 0) * 1e3:5.2f} mm/s {th.false_positive:11.4f} "
              f"{th.missed_detection:12.4f} {th.total_error:7.4f} +- {se((o, p), w, 1):.4f} {th.crossings.size:9d} "
              f"{st.h0.z.mean() * 1e3:7.2f} mm/s {st.h1.z.mean() * 1e3:7.2f} mm/s")

# %% [markdown]
# **Figs. 14-15 and 18-19 analogues** at $f = 0.1$: histograms (left of each pair) and kernel density estimates
# (right) of $z$ without (blue) and with (red) a maneuver; the dotted line is $z_{lim}$, where the two PDFs cross.
# Rows are the three orbits, the left pair the active policy (m/s), the right pair the quiet policy (mm/s).
#
# ## 3b · Is the window-tuned OCBE consistent? (beyond the paper's figures)
#
# The paper shows single runs (Figs. 12-13) whose errors stay inside their 3-sigma bounds. Every training run of
# Section 3 recorded the NEES of its forward and smoothed estimates against its truth, so the consistency of each
# tuning is measured on all of them: per policy, 500 runs without and 3000 with a burn on the 9:2 and the inner-band
# stable NRHO, a fifth of that on the outer band (the counts are printed below; criterion of notebook 09:
# a run is inconsistent when more than 5 % of its epochs exceed the 99.9 % quantile of $\chi^2_6$, 22.5).

# %%
nees_rows = {}
print("training runs per policy (H0 + H1, each tuning): "
      + "; ".join(f"{o} {len(studies[o, 'active'].h0)} + {len(studies[o, 'active'].h1)}" for o in ORBITS))
print(f"{'orbit':25s} {'policy':7s} {'hyp':4s} {'f = 0.1: inconsistent fwd / smo, mean NEES fwd / smo':>52s} "
      f"{'f_c: inconsistent fwd / smo':>30s}")
for (o, p) in studies:
    for hyp in ("H0", "H1"):
        a = getattr(studies[o, p], hyp.lower())
        b = getattr(studies_c[o, p], hyp.lower())
        nees_rows[o, p, hyp] = dict(tune=a.inconsistent_runs, c=b.inconsistent_runs,
                                    mean=(float(a.nees_mean_fwd.mean()), float(a.nees_mean_smooth.mean())))
        r = nees_rows[o, p, hyp]
        print(f"{o:25s} {p:7s} {hyp:4s} {100 * r['tune'][0]:14.1f} % / {100 * r['tune'][1]:4.1f} %, "
              f"{r['mean'][0]:6.2f} / {r['mean'][1]:5.2f} {100 * r['c'][0]:19.1f} % / {100 * r['c'][1]:4.1f} %")
bad_cells = {k: v["tune"] for k, v in nees_rows.items() if max(v["tune"]) > 0.10}
print("cells with more than 10 % inconsistent runs at f = 0.1 (forward / smoothed): "
      + ("; ".join(f"{o} {p} {h}: {100 * v[0]:.1f} % / {100 * v[1]:.1f} %" for (o, p, h), v in bad_cells.items())
         or "none"))
print(f"every such cell has a burn (H1): {all(h == 'H1' for _, _, h in bad_cells)}; worst cell at f_c: "
      f"{100 * max(max(v['c']) for v in nees_rows.values()):.1f} % of runs")

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
fig, ax = plt.subplots(2, 3, figsize=(15, 8))
for row, p in enumerate(POLICIES):
    h1 = studies["9:2 NRHO", p].h1
    unit, ulab = (1.0, "m/s") if p == "active" else (1e3, "mm/s")
    sc_ = ax[row, 0].scatter(np.degrees(h1.azimuth), np.degrees(h1.elevation), c=h1.z * unit, s=6, cmap="viridis")
    fig.colorbar(sc_, ax=ax[row, 0], label=f"z [{ulab}]")
    ax[row, 0].set(xlabel="azimuth [deg]", ylabel="elevation [deg]", title=f"9:2 NRHO, {p}")
    ax[row, 1].scatter(np.degrees(h1.azimuth), h1.z / h1.magnitude, s=4, alpha=0.5)
    ax[row, 1].set(xlabel="azimuth [deg]", ylabel="z / impulse magnitude [-]", title=f"9:2 NRHO, {p}")
    for o, mk in zip(ORBITS, ("o", "x")):
        s1 = studies[o, p].h1
        ax[row, 2].scatter(s1.magnitude * unit, s1.z * unit, s=4, alpha=0.4, marker=mk, label=o)
    mm = np.array([0, h1.magnitude.max() * unit])
    ax[row, 2].plot(mm, mm, "k--", lw=1, label="z = magnitude")
    ax[row, 2].set(xlabel=f"impulse magnitude [{ulab}]", ylabel=f"z [{ulab}]", title=f"{p}: z against the magnitude")
    ax[row, 2].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), markerscale=3)
fig.tight_layout()
_ = plotting.save_figure(fig, "10_z_vs_maneuver", output_dir=out)


def ratio_text(v):
    return "no burn in a sector (small sample)" if np.isnan(v) else f"{v:.2f}"


lin = {}
for group, tag in ((studies, "f = 0.1"), (studies_c, "f_c")):
    for (o, p), st in group.items():
        h1 = st.h1
        slope = np.polyfit(h1.magnitude, h1.z, 1)[0]
        lin[o, p, tag] = (slope, np.corrcoef(h1.magnitude, h1.z)[0, 1], det.azimuth_contrast(h1), stats.skew(h1.z))
        print(f"{tag:7s} {o:25s} {p:7s}: z vs magnitude slope {slope:.2f}, corr {lin[o, p, tag][1]:.3f}; z/|dv| at "
              f"azimuth +-90 over 0/180 (|el| < 45 deg) = {ratio_text(lin[o, p, tag][2])}; skewness of H1 z = "
              f"{lin[o, p, tag][3]:.2f}")

# %% [markdown]
# **Looking for the $\pm\hat j$ pattern.** Where could the paper's bimodality come from? We fire 1 m/s burns along
# $\pm\hat\imath$, $\pm\hat\jmath$, $\pm\hat k$ (the same noise draws for every direction,
# `detection.direction_response`) on the 9:2 NRHO and vary what shapes how well a burn is seen: the window weight
# factor $f$, the angle noise (up to 100 times ours; the paper's Table 3 is missing), and the burn time within the
# 8-hour window (3 hours before apoapsis, at it, 3 hours after). The contrast is the mean $z$ of the
# $\pm\hat\jmath$ burns over that of the four others (1 = no preference). The line of sight from the L2 observer
# to apoapsis is printed: a burn along it changes only the range, which angles do not measure.

# %%
DIRS = {"+i": (0.0, 0.0), "-i": (180.0, 0.0), "+j": (90.0, 0.0), "-j": (-90.0, 0.0), "+k": (0.0, 90.0),
        "-k": (0.0, -90.0)}
dirs_rad = np.radians(np.array(list(DIRS.values())))
truth_nom = tracking.simulate_truth(em, sc_q.x_start, sc_q.t, [])
k_apo = int(np.argmin(np.abs(sc_q.t - s_q.t_maneuver)))
los = truth_nom[k_apo, :3] - s_q.observer_states[k_apo, :3]
print(f"line of sight L2 observer -> apoapsis (rotating frame): {np.round(los / np.linalg.norm(los), 3)}, range "
      f"{np.linalg.norm(los) * em.length_unit_km:.0f} km")
pmj = {}
for f_ in PM_J_F:
    for sig_ in PM_J_NOISE_URAD:
        s_pm = det.make_setup(em, ORBITS["9:2 NRHO"], f_ * det.window_control_weight(det.ACTIVE_POLICY, WINDOW_HOURS),
                              Q_BASE, window_hours=WINDOW_HOURS, sigma_angle_rad=sig_ * 1e-6)
        for off in PM_J_OFFSET_H:
            zs = det.direction_response(s_pm, dirs_rad, 1.0, PM_J_SEEDS, [SEED, 31], burn_offset_hours=off).mean(0)
            pmj[f_, sig_, off] = (zs, zs[2:4].mean() / np.r_[zs[:2], zs[4:]].mean())
print("z of 1 m/s burns [m/s] (" + ", ".join(DIRS) + ") and the +-j contrast")
for (f_, sig_, off), (zs, c) in pmj.items():
    print(f"f = {f_:4.2f}, noise {sig_:6.0f} urad, burn {off:+.0f} h: " + " ".join(f"{z:.3f}" for z in zs)
          + f" | contrast {c:.2f}")
best_pmj = max(((k, v) for k, v in pmj.items() if k[2] == 0.0), key=lambda kv: kv[1][1])  # burn at apoapsis
f_pm, sig_pm, off_pm = best_pmj[0]
print(f"largest contrast with the burn at apoapsis {best_pmj[1][1]:.2f} at f = {f_pm:g}, {sig_pm:g} urad (over all "
      f"burn times {max(c for z, c in pmj.values()):.2f}); at our noise "
      f"(10 urad) the contrast stays within {min(c for (f_, s_, o_), (z, c) in pmj.items() if s_ == 10.0):.2f}-"
      f"{max(c for (f_, s_, o_), (z, c) in pmj.items() if s_ == 10.0):.2f}")
for sig_ in (10.0, sig_pm):  # our noise, and the noise where the pattern is strongest
    print(f"at {sig_:g} urad, per f: change of the contrast with the burn time (max - min over "
          f"{', '.join(f'{o_:+g}' for o_ in PM_J_OFFSET_H)} h) and range of z of the 1 m/s burns [m/s]: "
          + "; ".join(f"f = {f_:g}: {np.ptp([pmj[f_, sig_, o_][1] for o_ in PM_J_OFFSET_H]):.2f}, z "
                      f"{min(pmj[f_, sig_, o_][0].min() for o_ in PM_J_OFFSET_H):.2f}-"
                      f"{max(pmj[f_, sig_, o_][0].max() for o_ in PM_J_OFFSET_H):.2f}" for f_ in PM_J_F))

# %% [markdown]
# Where the pattern is strongest we run the paper's experiment itself: randomly pointed burns from both policies
# (Eqs. 3-5; the sizes printed), and the same statistic as for the training runs above (mean $z/|\Delta v|$ at
# azimuth $\pm90°$ over that at 0°/180°, elevations below 45°).

# %%
pm_mc = {}
for j, (p, pol) in enumerate(POLICIES.items()):
    s_pm = det.make_setup(em, ORBITS["9:2 NRHO"], f_pm * det.window_control_weight(pol, WINDOW_HOURS), Q_BASE,
                          window_hours=WINDOW_HOURS, sigma_angle_rad=sig_pm * 1e-6)
    pm_mc[p] = det.run_detection_monte_carlo(s_pm, pol, N_PM_J_MC, [SEED, 33, j], batch_size=BATCH,
                                             executor=executor, progress=False)
    h = pm_mc[p]
    print(f"{p:6s}: {len(h.z)} randomly pointed burns, f = {f_pm:g}, noise {sig_pm:g} urad: Fig. 16 statistic "
          f"{ratio_text(det.azimuth_contrast(h))}; mean z/|dv| {np.mean(h.z / h.magnitude):.2f}; corr(z, |dv|) "
          f"{np.corrcoef(h.magnitude, h.z)[0, 1]:.2f}")
fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
for f_, mk in zip(PM_J_F, "osD^"):
    ax[0].plot(PM_J_NOISE_URAD, [pmj[f_, s_, 0.0][1] for s_ in PM_J_NOISE_URAD], marker=mk, label=f"f = {f_:g}")
ax[0].axhline(1.0, color="0.5", lw=0.8)
ax[0].set(xscale="log", xlabel="angle noise [micro-rad]", ylabel="z(+-j) / z(+-i, +-k) [-]",
          title="burn at apoapsis")
ax[0].legend(fontsize=8, loc="upper left")
for off, mk in zip(PM_J_OFFSET_H, "osD"):
    ax[1].plot(PM_J_NOISE_URAD, [pmj[f_pm, s_, off][1] for s_ in PM_J_NOISE_URAD], marker=mk,
               label=f"burn {off:+g} h from apoapsis")
ax[1].axhline(1.0, color="0.5", lw=0.8)
ax[1].set(xscale="log", xlabel="angle noise [micro-rad]", ylabel="z(+-j) / z(+-i, +-k) [-]",
          title=f"f = {f_pm:g}: burn time in the window")
ax[1].legend(fontsize=8, loc="upper left")
h = pm_mc["active"]
sc_ = ax[2].scatter(np.degrees(h.azimuth), np.degrees(h.elevation), c=h.z / h.magnitude, s=8, cmap="viridis")
fig.colorbar(sc_, ax=ax[2], label="z / impulse magnitude [-]")
ax[2].set(xlabel="azimuth [deg]", ylabel="elevation [deg]", title=f"active, f = {f_pm:g}, {sig_pm:g} urad")
fig.tight_layout()
_ = plotting.save_figure(fig, "10_pm_j_search", output_dir=out)

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
acc = {(k, "f = 0.1"): st.score.accuracy for k, st in studies.items()}
acc.update({(k, "f_c"): st.score.accuracy for k, st in studies_c.items()})
for tag, group in (("f = 0.1", studies), (f"f_c = {F_C:g}", studies_c)):
    print(f"{tag}: {'orbit':25s} {'policy':7s} {'H0 -> H0':>9s} {'H0 -> H1':>9s} {'H1 -> H1':>9s} {'H1 -> H0':>9s} "
          f"{'accuracy':>9s}")
    for (o, p), st in group.items():
        s = st.score
        print(f"{'':{len(tag) + 2}s}{o:25s} {p:7s} {s.true_negative:9d} {s.false_positive:9d} {s.true_positive:9d} "
              f"{s.missed_detection:9d} {100 * s.accuracy:8.1f}%")

# %% [markdown]
# **The two stable candidates, side by side** (both tunings): detection accuracy, the expected error of the test
# with its bootstrap standard error (a finer measure than 200 test runs) and the worst consistency cell.

# %%
for o in ORBITS:
    for tag, group in (("f = 0.1", studies), ("f_c", studies_c)):
        errs = " / ".join(f"{group[o, p].threshold.total_error:.4f} +- {se((o, p), tag, 1):.4f}" for p in POLICIES)
        worst_c = max(max(nees_rows[o, p, h]["tune" if tag == "f = 0.1" else "c"]) for p in POLICIES
                      for h in ("H0", "H1"))
        print(f"{o:25s} {tag:8s}: accuracy active {100 * acc[(o, 'active'), tag]:.1f} %, quiet "
              f"{100 * acc[(o, 'quiet'), tag]:.1f} % ({group[o, 'active'].score.n} tests each); expected FP + MD "
              f"active / quiet {errs}; worst consistency cell {100 * worst_c:.0f} % of runs")

# %%
res_stable = {(o, tag): [abs(g[o, p].threshold.total_error - g["9:2 NRHO", p].threshold.total_error)
                         / np.hypot(se((o, p), tag, 1), se(("9:2 NRHO", p), tag, 1)) for p in POLICIES]
              for o in STABLE for tag, g in (("f = 0.1", studies), ("f_c", studies_c))}
print("difference of the expected error from the 9:2 NRHO's, in combined standard errors (active, quiet): "
      + "; ".join(f"{o} {tag}: {v[0]:.1f}, {v[1]:.1f}" for (o, tag), v in res_stable.items()))

# %% [markdown]
# At either tuning the accuracies of the three orbits lie within a few test runs of each other, and the expected
# errors, a finer measure than 200 test runs, differ from the 9:2 NRHO's by less than two combined standard errors
# (printed above): "marginally better" can be neither confirmed nor refuted with the paper's sample sizes. At
# $f = 0.1$ the window-tuned filter is least consistent on the inner-band orbit; at $f_c$ all three are
# consistent. Detection therefore does not decide between the candidates; notebook 09's determination and
# consistency results do (the outer band), and both stay in the table.

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
fig, ax = plt.subplots(1, 3, figsize=(15, 3.8))
hours = sc_q.t * em.time_unit_s / 3600
err = np.linalg.norm(rh.x_smooth[:, :3] - health.truth[:, :3], axis=1) * em.length_unit_km
sig = 3 * np.sqrt(np.trace(rh.P_smooth[:, :3, :3], axis1=1, axis2=2)) * em.length_unit_km
ax[0].plot(hours, err, label="smoothed error")
ax[0].plot(hours, sig, "--", label="3-sigma")
ax[0].set(xlabel="time from periapsis [h]", ylabel="position error [km]", title="0.5 m/s burn, quiet tuning")
ax[0].legend(loc="upper right")
ax[1].plot(hours, rh.residual_norms, ".", label="this run")
ax[1].axhline(np.sqrt(stats.chi2.ppf(0.99, 4)), color="k", ls=":", label="99 % of a 4-dof residual")
ax[1].set(xlabel="time from periapsis [h]", ylabel="whitened residual norm [-]", title="measurement residuals")
ax[1].legend(loc="center left")
ax[2].hist(ref.h0.z, bins=40, alpha=0.6, histtype="stepfilled", label="quiet H0")
ax[2].hist(ref.h1.z, bins=40, alpha=0.6, histtype="stepfilled", label="quiet H1")
ax[2].axvline(z_h, color="k", label=f"this run: z = {z_h:.3f} m/s")
ax[2].set(xscale="log", xlabel="z [m/s]", ylabel="runs [-]", title="z against the training runs")
ax[2].legend(fontsize=8, loc="upper left")
_ = plotting.save_figure(fig, "10_health_metric", output_dir=out)
print(f"impulse 0.5 m/s (azimuth {np.degrees(health.azimuth):.0f} deg, elevation {np.degrees(health.elevation):.0f} "
      f"deg): z = {z_h:.4f} m/s = {(z_h - ref.h1.z.mean()) / ref.h1.z.std():.0f} sigma of quiet H1")
print(f"smoothed NEES mean {nees_h.mean():.0f} (6 if consistent); residual norms: median "
      f"{np.median(rh.residual_norms):.2f}, max {rh.residual_norms.max():.2f}; fraction above the 99% level "
      f"{np.mean(rh.residual_norms > np.sqrt(stats.chi2.ppf(0.99, 4))):.2f}")

# %% [markdown]
# **Is $z$ of a given burn independent of the tuning?** One would expect $z$ of a 0.5 m/s burn to be about 0.5 m/s
# whatever the window weight. We fly the same $N$ randomly pointed 0.5 m/s burns (sizes printed) through the quiet
# tuning at every factor of the grid. The paper's value is one run, so the tolerance of the comparison is fixed
# from our single-run spread: agreement when 0.4761 m/s (printed to $5\times10^{-5}$, negligible) lies within two
# single-run standard deviations of our mean. The paper's "about 30 sigma" has one significant digit: agreement
# when our level rounds to 30, i.e. lies in [25, 35). The level is (mean $z$ of the 0.5 m/s burns $-$ mean of the
# quiet H1 training runs) / their standard deviation, both at the same tuning.

# %%
z05_in = [det.draw_trial(r, s_q, magnitude_m_s=0.5) for r in np.random.default_rng([SEED, 8]).spawn(N_Z05)]
z05 = {}
for f_ in sorted(set(F_GRID) | {F_C, F_TUNE}):
    s_f = det.make_setup(em, ORBITS["9:2 NRHO"], f_ * det.window_control_weight(det.QUIET_POLICY, WINDOW_HOURS), Q_BASE,
                         window_hours=WINDOW_HOURS)
    z05[f_] = det.filter_trials(s_f, z05_in).z_smooth * em.velocity_unit_km_s * 1e3
    print(f"f = {f_:4.2f}: z of a 0.5 m/s burn {z05[f_].mean():.4f} +- {z05[f_].std(ddof=1):.4f} m/s (mean +- "
          f"single-run sd, {N_Z05} runs), range {z05[f_].min():.3f}-{z05[f_].max():.3f}")
sig_level = {}
for tag, f_, group in (("f = 0.1", F_TUNE, studies), ("f_c", F_C, studies_c)):
    h1q = group["9:2 NRHO", "quiet"].h1.z
    sig_level[tag] = (z05[f_].mean() - h1q.mean()) / h1q.std()
    print(f"{tag}: 0.5 m/s burns sit at {sig_level[tag]:.1f} sigma of the quiet H1 training distribution "
          f"(mean {h1q.mean() * 1e3:.1f} mm/s, sd {h1q.std() * 1e3:.1f} mm/s)")

# %% [markdown]
# **$z$ of a given burn depends on the tuning.** The quiet window makes control expensive, so the smoother puts
# only part of a 0.5 m/s burn into it: about 0.34 m/s at $f = 0.03$, 0.43 at $f = 0.1$, 0.47 at $f = 0.3$ and
# 0.49 at $f = 1$, with a single-run spread that shrinks as $f$ grows (printed above). The paper's 0.4761 m/s lies
# within two single-run standard deviations at $f = 0.1$ and at $f_c$, and the 0.5 m/s burns sit at 29 and 31
# sigma of the quiet training runs. At $f_c$, which no number of the paper chose, both are predictions.
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
for tag, h in lead.items():
    fr = h.outcome_fractions()
    mc_, mr_ = h.median_delay_hours("control"), h.median_delay_hours("residual")
    print(f"{tag}: false alarms over 24 h: control {100 * h.false_alarm_control:.1f} %, residual "
          f"{100 * h.false_alarm_residual:.1f} % ({N_LEAD[0]} no-burn runs)")
    for m, mag in enumerate(h.magnitudes_m_s):
        print(f"   {mag:4.2f} m/s: control first {100 * fr['control first'][m]:3.0f} %, same epoch "
              f"{100 * fr['same epoch'][m]:3.0f} %, residual first {100 * fr['residual first'][m]:3.0f} %, neither "
              f"{100 * fr['neither'][m]:3.0f} % | median delay control "
              f"{(f'{mc_[m]:4.1f} h' if np.isfinite(mc_[m]) else 'none (never detected)')}, residual "
              f"{(f'{mr_[m]:4.1f} h' if np.isfinite(mr_[m]) else 'none (never detected)')} | "
              f"z over the whole track {np.median(h.z_final_m_s[m]):.4f} m/s (median)")
fig, ax = plt.subplots(1, len(lead), figsize=(5 * len(lead), 3.8), sharey=True)
for a, (tag, h) in zip(ax, lead.items()):
    fr = h.outcome_fractions()
    x = np.arange(h.magnitudes_m_s.size)
    bottom = np.zeros(x.size)
    for (name, v), col in zip(fr.items(), ("C2", "0.6", "C1", "0.85")):
        a.bar(x, 100 * v, bottom=bottom, color=col, label=name, width=0.7)
        bottom += 100 * v
    a.set(xticks=x, xticklabels=[f"{m:g}" for m in h.magnitudes_m_s], xlabel="burn size [m/s]", title=tag)
ax[0].set(ylabel="runs [%]")
h_, l_ = ax[0].get_legend_handles_labels()
fig.legend(h_, l_, loc="lower center", ncol=4, bbox_to_anchor=(0.5, -0.02))
fig.tight_layout(rect=(0, 0.07, 1, 1))
_ = plotting.save_figure(fig, "10_health_lead", output_dir=out)

# %%
for tag, h in lead.items():
    fr = h.outcome_fractions()
    lead_sizes = [f"{m:g}" for m, c in zip(h.magnitudes_m_s, fr["control first"]) if c > 0.5]
    i5 = int(np.argmin(np.abs(h.magnitudes_m_s - 0.5)))
    r_or_same = fr["residual first"][i5] + fr["same epoch"][i5]
    print(f"{tag}: control strictly first in most runs at {', '.join(lead_sizes) or 'no'} m/s; for 0.5 m/s the "
          f"residual test fires first or at the same epoch in {100 * r_or_same:.0f} % of the runs, neither fires "
          f"within 24 h in {100 * fr['neither'][i5]:.0f} %")

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
def binom_tol(paper, n):
    """Tolerance of an accuracy over n tests: 2 binomial standard errors at the paper's rate (at least 2 points)."""
    return max(0.02, 2 * np.sqrt(paper * (1 - paper) / n) + 1 / (2 * n))


table.add_typed("Measurement noise (Table 3)", "missing from the text", "10 micro-rad angles; rates sqrt(2)*10 micro-rad/s",
          "not in paper", "our choice: the value the same authors use in J. Greaves, D. Scheeres, 'Autonomous "
          "Information Gathering Guidance for Spacecraft-to-Spacecraft Tracking with Optical Sensors', AMOS "
          "Conference 2023, Sec. 3.3 (cislunar.papers.greaves_scheeres_2021.tracking; notebook 09, Section 1); Section 2 maps 2-20 micro-rad")
table.add_typed("OCBE tuning (8-h apoapsis window)", "values missing",
          f"q_w = f E[u^2]/(3T), base 1e-18 km^2/s^3; f_c = {F_C:g} (consistency reading), f = {F_TUNE:g} (threshold "
          f"reading): quiet q_w {setups_c['9:2 NRHO', 'quiet'].q_window_km2_s3:.2e} / "
          f"{setups['9:2 NRHO', 'quiet'].q_window_km2_s3:.2e} km^2/s^3", "not in paper",
          "f_c by a rule fixed before the map (Section 2); f = 0.1 chosen earlier with the paper's thresholds in view")
table.add_typed("Monte Carlo sizes (H0 / H1 / tests per hypothesis)", "500 / 3000 / 100", f"{N_H0} / {N_H1} / {N_TEST}",
          "derived: an input taken from the paper, not a result" if not QUICK else "differs: quick mode",
          ("input, as in the paper: per policy on the 9:2 and the inner-band stable NRHO, at both tunings; the "
           "outer-band stable NRHO (our added candidate) runs reduced sizes, "
           + " / ".join(str(n) for n in sizes(OUTER))) if not QUICK else
          "quick mode shrinks every Monte Carlo; the full run uses the paper's sizes")
# --- Figs. 10-13
c_inc = [100 * x for h in ("H0", "H1") for x in spike["constant", h]["inc"]]
fig10_why = [f"{h} {w} {100 * x:.1f} % inconsistent" for h in ("H0", "H1")
             for w, x in zip(("forward", "smoothed"), spike["constant", h]["inc"]) if x > 0.10]
if spike["constant", "H1"]["sig_km"] <= spike["apoapsis window", "H1"]["sig_km"]:
    fig10_why.append("bound not larger than the window tuning's")
table.add_typed("Fig. 10: constant tuning consistent but less certain", "consistent, less certain (one run)",
          f"inconsistent runs H0 fwd/smo {c_inc[0]:.1f}/{c_inc[1]:.1f} %, H1 {c_inc[2]:.1f}/{c_inc[3]:.1f} %; mean "
          f"forward 3-sigma {spike['constant', 'H1']['sig_km']:.2f} km vs "
          f"{spike['apoapsis window', 'H1']['sig_km']:.2f} km (window)",
          "reproduced" if fig10_ok else "differs: " + "; ".join(fig10_why) + " (criterion 10 %)",
          f"{N_SPIKE} + {N_SPIKE} quiet runs at f = 0.1; criterion fixed before running: at most 10 % inconsistent "
          "runs in every cell and a larger bound than the window tuning")
table.add_typed("Fig. 11: constant tuning, control spike at the burn in the smoothed control only",
          "spike only in the smoothed system",
          f"H1 runs with smoothed contrast >= 2 and above the forward one: {100 * fig11_h1:.0f} %; H0 runs without a "
          f"smoothed spike: {100 * fig11_h0:.0f} %", "reproduced" if fig11_h1 >= 0.9 and fig11_h0 >= 0.9 else
          "differs: " + (f"no distinct smoothed spike in {100 * (1 - fig11_h1):.0f} % of the burn runs"
                         if fig11_h1 < 0.9 else
                         "the smoothed control also spikes without a burn"),
          "contrast = mean control norm within 6 h of the burn over the mean elsewhere; criterion fixed before "
          "running: at least 90 % of the runs of each hypothesis")
zr = studies["9:2 NRHO", "quiet"].h1.z / studies["9:2 NRHO", "quiet"].h1.z_step
zr_c = studies_c["9:2 NRHO", "quiet"].h1.z / studies_c["9:2 NRHO", "quiet"].h1.z_step
table.add_typed("Fig. 13: window tuning, smoothed control spike at the burn",
          "'a smoothed control spike around apoapsis that is indicative of a maneuver'",
          f"quiet H1 runs with smoothed z above twice the forward z: {100 * np.mean(zr > 2):.1f} % (f = 0.1), "
          f"{100 * np.mean(zr_c > 2):.1f} % (f_c); median ratio {np.median(zr):.0f} / {np.median(zr_c):.0f}",
          "reproduced" if min(np.mean(zr > 2), np.mean(zr_c > 2)) >= 0.9 else
          "differs: the forward control sees the burn as much as the smoothed one",
          "9:2 NRHO training runs; the status refers to the criterion fixed in advance: smoothed z above twice the "
          "forward z in at least 90 % of the runs; the forward control does rise inside the window (it scales with "
          "q_w), by the median ratios given it stays well below the smoothed one")
# --- consistency of the window tuning
edge = {v: next((f for f in (F_GRID if v == BASE_VARIANT else F_SIDE)
                  if all(worst("9:2 NRHO", p, f, v) <= 0.10 for p in POLICIES)), None) for v in VARIANTS}
table.add_typed("Window-tuned OCBE consistent (Figs. 12-13): where it holds", "consistent (single runs)",
          f"every orbit, policy and hypothesis at most 10 % inconsistent runs for f >= {F_C:g} (map); at f_c the "
          f"paper-size runs' worst cell is {100 * max(max(v['c']) for v in nees_rows.values()):.1f} %", TUNED,
          "holds only in part of the unstated tuning range, so agreement rests on choosing f (by this very claim); "
          "smallest consistent f on the 9:2 NRHO by setting: "
          + ", ".join(f"{v} {edge[v] if edge[v] is not None else '> ' + str(F_SIDE[-1])}" for v in VARIANTS))
for o in ORBITS:
    wf = max(nees_rows[o, p, h]["tune"][0] for p in POLICIES for h in ("H0", "H1"))
    ws = max(nees_rows[o, p, h]["tune"][1] for p in POLICIES for h in ("H0", "H1"))
    bad = [f"{p} {h}" for p in POLICIES for h in ("H0", "H1") if max(nees_rows[o, p, h]["tune"]) > 0.10]
    table.add_typed(f"Window-tuned OCBE consistent at f = 0.1, {o} (NEES, forward / smoothed)",
              "consistent (Figs. 12-13, single runs)",
              f"worst cell: {100 * wf:.1f} % / {100 * ws:.1f} % of runs inconsistent"
              + (f" ({', '.join(bad)})" if bad else ""),
              "reproduced" if max(wf, ws) <= 0.10 else
              "differs: with a burn the window admits a tenth of its velocity variance",
              f"all training runs (up to {N_H0} H0 + {N_H1} H1 per policy); criterion fixed in advance: at most 10 % "
              "inconsistent runs per cell")
# --- thresholds
for p in POLICIES:
    paper = PAPER_ZLIM[p]
    zl = studies["9:2 NRHO", p].threshold.z_lim
    table.add_typed(f"z_lim, 9:2 NRHO, {p}, f = 0.1 (Eq. 35)", f"{paper * 1e3:.2f} mm/s", f"{zl * 1e3:.2f} mm/s",
              TUNED if abs(zl / paper - 1) <= 0.25 else f"differs: {100 * (zl / paper - 1):+.0f} %",
              f"{100 * (zl / paper - 1):+.0f} %; within 25 % counts as agreement; f = 0.1 chosen with this number in "
              f"view; the map's z_lim equals the paper's at f = {F_MATCH[p]:.2f}")
    zc, sc_ = studies_c["9:2 NRHO", p].threshold.z_lim, se(("9:2 NRHO", p), "f_c", 0)
    table.add_typed(f"z_lim, 9:2 NRHO, {p}, f_c = {F_C:g} (prediction)", f"{paper * 1e3:.2f} mm/s",
              f"{zc * 1e3:.2f} +- {sc_ * 1e3:.2f} mm/s",
              "reproduced" if abs(zc - paper) <= 2 * sc_ else
              f"differs: {100 * (zc / paper - 1):+.0f} %",
              "tolerance fixed in advance: 2 bootstrap standard errors (the paper's digits are finer); the map's z_lim "
              f"equals the paper's at f = {F_MATCH[p]:.2f}, "
              + ("below f_c, where our filter is not consistent with a burn" if F_MATCH[p] < F_C else
                 "inside the consistent range"))
for o in STABLE:
    for p in POLICIES:
        table.add_typed(f"z_lim, {o}, {p}", "not given",
                  f"{studies[o, p].threshold.z_lim * 1e3:.2f} mm/s (f = 0.1), "
                  f"{studies_c[o, p].threshold.z_lim * 1e3:.2f} mm/s (f_c)", "not in paper",
                  "the paper omits the stable-NRHO plots and values"
                  + ("; outer-band candidate (notebook 09), reduced Monte Carlo" if o == OUTER else ""))
for (o, p), st in studies_c.items():
    table.add_typed(f"Expected FP / MD, {o}, {p}, f_c (Tables 5-6)", "tables missing",
              f"{st.threshold.false_positive:.4f} / {st.threshold.missed_detection:.4f} (f = 0.1: "
              f"{studies[o, p].threshold.false_positive:.4f} / {studies[o, p].threshold.missed_detection:.4f})",
              "not in paper", f"{st.threshold.crossings.size} PDF crossing(s); FP + MD standard error "
              f"{se((o, p), 'f_c', 1):.4f} (bootstrap)")
n_cross = [st.threshold.crossings.size for g in (studies, studies_c) for st in g.values()]
table.add_typed("H0 and H1 PDFs cross once", "yes (Figs. 15, 19)", f"crossings per case (both tunings): {n_cross}",
          "reproduced" if all(c == 1 for c in n_cross) else "differs: KDE tails of the finite sample add crossings",
          "criterion fixed in advance: exactly one crossing in every case; z_lim is the crossing of least total error")
# --- detection accuracy
for p, paper in (("active", 1.00), ("quiet", 0.97)):
    n = 2 * studies["9:2 NRHO", p].score.n // 2
    a, a_c = acc[("9:2 NRHO", p), "f = 0.1"], acc[("9:2 NRHO", p), "f_c"]
    tol = binom_tol(paper, n)
    floor = (f"; at the paper's {100 * paper:.0f} % the binomial standard error is "
             f"{100 * np.sqrt(paper * (1 - paper) / n):.1f} points, so the tolerance is the 2-point floor"
             if 2 * np.sqrt(paper * (1 - paper) / n) + 1 / (2 * n) < 0.02 else "")

    def edge(x):
        return "; our value lies exactly on the tolerance" if np.isclose(abs(x - paper), tol) else ""

    table.add_typed(f"Detection accuracy, 9:2 NRHO, {p}, f = 0.1 (Table 7)", f"{100 * paper:.0f} %", f"{100 * a:.1f} %",
              TUNED if abs(a - paper) <= tol + 1e-9 else "differs: see FP/MD",
              f"{n} test runs; tolerance {100 * tol:.1f} points (2 binomial standard errors, at least 2){floor}"
              f"{edge(a)}; f = 0.1 chosen with the paper's thresholds in view")
    table.add_typed(f"Detection accuracy, 9:2 NRHO, {p}, f_c = {F_C:g} (Table 7, prediction)", f"{100 * paper:.0f} %",
              f"{100 * a_c:.1f} %", "reproduced" if abs(a_c - paper) <= tol + 1e-9 else
              f"differs: {100 * (a_c - paper):+.1f} points, beyond the tolerance",
              f"{n} test runs; tolerance {100 * tol:.1f} points, fixed in advance (2 binomial standard errors at the "
              f"paper's rate, at least 2 points){floor}{edge(a_c)}")
for o in STABLE:
    for p in POLICIES:
        e_s, e_n = studies_c[o, p].threshold.total_error, studies_c["9:2 NRHO", p].threshold.total_error
        se_d = np.hypot(se((o, p), "f_c", 1), se(("9:2 NRHO", p), "f_c", 1))
        a_s = acc[(o, p), "f_c"]
        extra = ""
        if p == "quiet":
            tol = binom_tol(1.0, studies_c[o, p].score.n)
            extra = (f"; accuracy vs the paper's 200/200: {100 * a_s:.1f} % ("
                     f"{'within' if 1.0 - a_s <= tol + 1e-9 else 'outside'} {100 * tol:.1f} points)")
        table.add_typed(f"Stable NRHO marginally better than the 9:2, {o}, {p}, f_c (Table 8)",
                  "marginally better" + (" (quiet: 200/200)" if p == "quiet" else ""),
                  f"expected FP + MD {e_s:.4f} vs 9:2 {e_n:.4f} (difference {e_s - e_n:+.4f} +- {se_d:.4f}); test "
                  f"accuracy {100 * a_s:.1f} % of {studies_c[o, p].score.n}",
                  "reproduced" if e_n - e_s > 2 * se_d else
                  ("differs: worse than the 9:2 NRHO" if e_s - e_n > 2 * se_d else
                   "differs: not resolved, the difference is within 2 standard errors"),
                  "criterion fixed in advance: lower expected error by more than 2 bootstrap standard errors"
                  + ("; outer-band candidate, reduced Monte Carlo" if o == OUTER else "") + extra)
# --- sensitivity of z (Figs. 15-17, 20-21)
for p in POLICIES:
    sl, cr, _, _ = lin["9:2 NRHO", p, "f_c"]
    sl1, cr1, _, _ = lin["9:2 NRHO", p, "f = 0.1"]
    table.add_typed(f"z nearly linear in the magnitude, {p} (Figs. 17, 21)", "apparently linear",
              f"f_c: slope {sl:.2f}, corr {cr:.3f} (f = 0.1: {sl1:.2f}, {cr1:.3f})",
              "reproduced" if cr > 0.8 else "differs: weak correlation",
              "criterion fixed in advance: correlation above 0.8 at the prediction tuning f_c")
table.add_typed("H1 z approximately Gaussian, active (Fig. 15)", "approximately Gaussian",
          f"skewness {lin['9:2 NRHO', 'active', 'f_c'][3]:.2f} "
          f"(f = 0.1: {lin['9:2 NRHO', 'active', 'f = 0.1'][3]:.2f})",
          "reproduced" if abs(lin["9:2 NRHO", "active", "f_c"][3]) < 0.5 else "differs: skewed",
          "criterion fixed in advance: |skewness| below 0.5")
ctr = {(p, t): lin["9:2 NRHO", p, t][2] for p in POLICIES for t in ("f = 0.1", "f_c")}
c10 = [c for (f_, s_, o_), (z, c) in pmj.items() if s_ == 10.0]
table.add_typed("Largest z for burns at azimuth +-90 deg, active (Fig. 16)", "bimodal, peaks at +-j",
          f"z/|dv| at +-90 deg over 0/180 deg: {ratio_text(ctr['active', 'f_c'])} (f_c), "
          f"{ratio_text(ctr['active', 'f = 0.1'])} (f = 0.1)",
          "reproduced" if ctr["active", "f_c"] > 1.1 else
          f"differs: no +-j preference at our noise (paired 1 m/s burns: contrast {min(c10):.2f}-{max(c10):.2f} over "
          "f and burn time)", "criterion fixed in advance: ratio above 1.1")
pm_a, pm_q = det.azimuth_contrast(pm_mc["active"]), det.azimuth_contrast(pm_mc["quiet"])
ratio_a, ratio_q = (float(np.mean(pm_mc[p].z / pm_mc[p].magnitude)) for p in ("active", "quiet"))
corr_a = float(np.corrcoef(pm_mc["active"].magnitude, pm_mc["active"].z)[0, 1])
burn_time_effect = max(abs(pmj[f_pm, sig_pm, o_][1] - pmj[f_pm, sig_pm, 0.0][1]) for o_ in PM_J_OFFSET_H)
table.add_typed("Conditions for the +-j pattern (f, angle noise, burn time in the window)", "not discussed",
          f"largest paired contrast {best_pmj[1][1]:.2f} at f = {f_pm:g}, {sig_pm:g} micro-rad (burn at apoapsis; "
          f"a burn 3 h before or after apoapsis moves it by at most {burn_time_effect:.2f}); there the Fig. 16 "
          f"statistic is {ratio_text(pm_a)} (active), but z/|dv| averages {ratio_a:.2f} and corr(z, |dv|) is "
          f"{corr_a:.2f}", "beyond paper",
          f"{PM_J_SEEDS} noise draws per direction; {N_PM_J_MC} random burns per policy in that regime; the pattern "
          "needs burns that the angles see poorly (noise far above ours): then z falls short of the burn, least "
          "along +-j, perpendicular to the line of sight")
table.add_typed("Quiet policy: pattern less bimodal (Fig. 20)", "more uniform",
          f"where the pattern appears ({sig_pm:g} micro-rad, f = {f_pm:g}): quiet {ratio_text(pm_q)} vs active "
          f"{ratio_text(pm_a)}; at our noise {ratio_text(ctr['quiet', 'f_c'])} vs {ratio_text(ctr['active', 'f_c'])}",
          TUNED if pm_a > 1.1 and pm_q < pm_a and ratio_q > 0.5 else
          "differs: " + ("no +-j pattern to weaken in any regime searched" if pm_a <= 1.1 else
                         "the quiet policy shows the pattern as much" if pm_q >= pm_a else
                         f"there quiet burns are lost in the noise (mean z/|dv| {ratio_q:.2f}), so the quiet "
                         "detection of Table 7 fails"),
          "the regime was chosen because the active pattern appears there; a status of agreement would need the "
          "quiet burns to stay visible (mean z/|dv| above 0.5)")
# --- health metric (Fig. 22)
for tag, f_ in (("f = 0.1", F_TUNE), ("f_c", F_C)):
    m, s1 = z05[f_].mean(), z05[f_].std(ddof=1)
    ok = abs(0.4761 - m) <= 2 * s1
    table.add_typed(f"Health metric: z for a 0.5 m/s burn, quiet tuning, {tag}", "0.4761 m/s (one run)",
              f"{m:.4f} +- {s1:.4f} m/s (mean +- single-run sd, {N_Z05} runs)",
              ("reproduced" if tag == "f_c" else TUNED) if ok else
              f"differs: {(0.4761 - m) / s1:+.1f} single-run sd from our mean",
              "tolerance fixed in advance: 2 single-run standard deviations (the paper's digits are finer); z depends "
              f"on f: {z05[F_GRID[0]].mean():.3f} m/s at f = {F_GRID[0]:g} to {z05[F_GRID[-1]].mean():.3f} at "
              f"f = {F_GRID[-1]:g}")
    table.add_typed(f"Health metric: sigma level in the quiet H1 distribution, {tag}", "about 30 sigma",
              f"{sig_level[tag]:.1f} sigma",
              ("reproduced" if tag == "f_c" else TUNED) if 25 <= sig_level[tag] < 35 else "differs: outside [25, 35)",
              "tolerance from the printed digit, fixed in advance: [25, 35); mean z of the 0.5 m/s burns against the "
              "quiet H1 training runs at the same tuning")
for tag, h in lead.items():
    fr = h.outcome_fractions()
    i5 = int(np.argmin(np.abs(h.magnitudes_m_s - 0.5)))
    ok = fr["control first"][i5] > 0.5
    holds = [f"{m:g}" for m, c in zip(h.magnitudes_m_s, fr["control first"]) if c > 0.5]
    table.add_typed(f"Control test reacts before a residual test (Fig. 22), {tag}", "yes (deviations before the residuals)",
              "0.5 m/s: control first {:.0f} %, same epoch {:.0f} %, residual first {:.0f} %; control first at "
              "{}".format(100 * fr["control first"][i5], 100 * fr["same epoch"][i5], 100 * fr["residual first"][i5],
                          ", ".join(f"{m:g} m/s {100 * c:.0f} %" for m, c in zip(h.magnitudes_m_s,
                                                                                   fr["control first"]))),
              ("reproduced" if tag.startswith("f_c") else TUNED if tag == "f = 0.1, 10 urad" else "beyond paper")
              if ok else "differs: at 0.5 m/s the control test is not first in most runs; "
              + (f"it is for {', '.join(holds)} m/s burns" if holds else "nor for any burn size raced")
              + (f"; the quiet window absorbs a median {np.median(h.z_final_m_s[i5]):.2f} m/s of the 0.5 m/s burn"
                 if "100" in tag else ""),
              f"{N_LEAD[1]} burns per size; both tests online at a per-epoch tail of 0.135 %; false alarms over 24 h "
              f"control {100 * h.false_alarm_control:.1f} %, residual {100 * h.false_alarm_residual:.1f} %; "
              "criterion fixed in advance: control strictly first in more than half of the 0.5 m/s runs"
              + ("; noise ten times ours: a regime searched for the claim" if "100" in tag else ""))
l100 = lead["f = 0.1, 100 urad"]
i5 = int(np.argmin(np.abs(l100.magnitudes_m_s - 0.5)))
table.add_typed("Health metric: residuals benign while the estimate diverges (Fig. 22)", "yes",
          f"one run at 10 micro-rad: smoothed NEES mean {nees_h.mean():.0f}, residual median "
          f"{np.median(rh.residual_norms):.2f}; at 100 micro-rad the residual test stays silent for 24 h in "
          f"{100 * (l100.residual_epoch[i5] < 0).mean():.0f} % of 0.5 m/s runs, the control test too in "
          f"{100 * l100.outcome_fractions()['neither'][i5]:.0f} %",
          "reproduced" if nees_h.mean() > 20 and np.median(rh.residual_norms) < 3 else
          "differs: at our noise the residuals show the burn at once",
          f"of the noise levels raced, the residuals look benign only at {100e-6 / SIGMA_ANGLE:g} times our angle "
          "noise, and then z misses the burn as well (Section 6)")
if executor is not None:
    executor.shutdown()
print(f"notebook wall time: {(time.perf_counter() - T_START) / 60:.1f} min")
table.display()
