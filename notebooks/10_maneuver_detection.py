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
# "quiet" (50 mm/s) policy on the 9:2 NRHO and the stable NRHO; and why $z$ is a fast health metric of the filter.
#
# **Paper sections followed.** J. A. Greaves, D. J. Scheeres, *Observation and Maneuver Detection for Cislunar
# Vehicles*, JAS 68 (2021): "Modeling Definitions" (Eqs. 3-5, Table 2), "Filter Tuning Strategy" (Figs. 10-13),
# "Maneuver Detection" (Eqs. 33-35, Figs. 14-21, Tables 5-8) and "Control as a Health Metric" (Fig. 22). The OCBE
# itself (Eqs. 14-32) is `cislunar.ocbe`; the tracking scenario (L2 observer, angles and angle rates every 2 hours,
# Earth-radar hand-off at periapsis) is `cislunar.tracking`; everything specific to detection is
# `cislunar.detection`.
#
# **What the paper does not give.** Tables 1-8 are missing from its text: in particular the measurement noise
# (Table 3) and the OCBE tuning values. We use 10 micro-rad angles (1 sigma) with Eq. 13 rates from 1 s
# differencing (see `cislunar.tracking`) and choose the tuning in Section 2 below; both choices are recorded in
# the closing table.

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: quick mode shrinks every Monte Carlo; every step still runs.
N_H0 = 8 if QUICK else 500  # non-maneuvering training runs per policy and orbit (paper: 500)
N_H1 = 8 if QUICK else 3000  # maneuvering training runs per policy and orbit (paper: 3000)
N_TEST = 4 if QUICK else 100  # test runs per hypothesis, policy and orbit (paper: 100 + 100)
N_PILOT = 4 if QUICK else 64  # runs per hypothesis in the tuning sweep
N_POLICY_DRAWS = 5000 if QUICK else 200000  # draws to check the station-keeping distributions
TUNING_FACTORS = [0.01, 0.1, 1.0]  # sweep of the window control weight, in units of the variance-matched value
PM_J_SEEDS = 1 if QUICK else 3  # noise draws per azimuth in the +-j sweep (Section 4)
BATCH = 8  # trials run in lockstep by the batched OCBE
N_NEES = 2 if QUICK else 24  # runs per (orbit, policy, hypothesis) of the consistency check of the window tuning
WORKERS = 1 if QUICK else 2  # processes for the Monte Carlo

import time
import multiprocessing as mp
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import matplotlib.pyplot as plt
from scipy import stats

from cislunar import adaptive_ocbe as ad, detection as det, orbits, plotting, tracking
from cislunar.dynamics import EARTH_MOON as em
from cislunar.report import ComparisonTable, fmt

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
    ax[0 if name == "active" else 1].hist(m * 1e3, bins=60, density=True, alpha=0.6, histtype="stepfilled",
                                          label="draws")
    zz = np.linspace(d.ppf(0), d.ppf(1), 300)
    ax[0 if name == "active" else 1].plot(zz * 1e3, d.pdf(zz) / 1e3, "k", lw=1, label="truncnorm PDF")
    ax[0 if name == "active" else 1].set(title=f"{name}: mean {m.mean() * 1e3:.1f}, sd {m.std() * 1e3:.2f} mm/s",
                                         xlabel="impulse magnitude [mm/s]", ylabel="probability density [1/(mm/s)]")
    print(f"{name}: range [{m.min() * 1e3:.2f}, {m.max() * 1e3:.2f}] mm/s (bounds {(pol.mean_m_s - 3 * pol.sd_m_s) * 1e3:.1f}, "
          f"{(pol.mean_m_s + 3 * pol.sd_m_s) * 1e3:.1f}); sd/sigma_u = {m.std() / pol.sd_m_s:.4f} "
          f"(truncnorm {d.std() / pol.sd_m_s:.4f})")
az, el = det.StationKeepingPolicy.sample_pointing(rng, N_POLICY_DRAWS)
uz = det.pointing_vector(az, el)[:, 2]
ax[2].hist(uz, bins=50, density=True, alpha=0.6, histtype="stepfilled", label="Eqs. 3-4 (paper)")
ax[2].plot(np.linspace(-0.999, 0.999, 200), stats.arcsine(-1, 2).pdf(np.linspace(-0.999, 0.999, 200)), "k", lw=1,
           label="arcsine PDF")
ax[2].axhline(0.5, color="C3", ls="--", label="uniform sphere")
ax[2].set(xlabel=r"$\hat k$ component of the impulse direction [-]", ylabel="probability density [-]", ylim=(0, 3),
          title="pointing")
ax[0].legend(loc="upper left")
ax[2].legend(fontsize=8)
_ = plotting.save_figure(fig, "10_station_keeping_policy", output_dir=out)
ks_sphere = stats.kstest(uz, stats.uniform(-1, 2).cdf).pvalue
print(f"KS test of u_z against a uniform sphere: p = {ks_sphere:.1e}; against arcsine: "
      f"p = {stats.kstest(uz, stats.arcsine(-1, 2).cdf).pvalue:.2f}")
table.add("Eq. 5 magnitude stays within mean +- 3 sd (both policies)", "by construction",
          "yes (exact truncnorm draws)", "derived")
table.add("Eqs. 3-4 pointing", "'random pointing', U[-pi,pi] x U[-pi/2,pi/2]",
          f"as written; not uniform on the sphere (KS p = {ks_sphere:.0e})", "derived",
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
# **Our choice.** White acceleration noise of PSD $q$ over a window $T$ accumulates a velocity variance $qT$ per
# axis. Matching it to the per-axis second moment of the impulse gives the *variance-matched* weight
# $q_\star = E[u_{mag}^2]/(3T)$ ($1.26\times10^{-11}$ km$^2$/s$^3$ active, $3.15\times10^{-14}$ quiet). We sweep
# $q_w = f\,q_\star$ in a small pilot Monte Carlo on the 9:2 NRHO (seeds independent of the main runs) and look at
# the H0 and H1 means of $z$, the pilot's total error rate and how linearly $z$ follows the impulse magnitude.
# Outside the window $q_b = 10^{-18}$ km$^2$/s$^3$: negligible (results are unchanged at $10^{-20}$), but keeps
# $Q$ positive definite.

# %%
Q_BASE = 1e-18  # km^2/s^3 outside the apoapsis window
WINDOW_HOURS = 8.0
sweep = {}
for pname, pol in POLICIES.items():
    for f in TUNING_FACTORS:
        setup = det.make_setup(em, ORBITS["9:2 NRHO"], f * det.window_control_weight(pol, WINDOW_HOURS), Q_BASE,
                               window_hours=WINDOW_HOURS)
        st = det.run_policy_study(setup, pol, N_PILOT, N_PILOT, 0, [SEED, 99, TUNING_FACTORS.index(f),
                                  list(POLICIES).index(pname)], batch_size=BATCH, executor=executor,
                                  label=f"pilot {pname} f={f}")
        slope, icpt = np.polyfit(st.h1.magnitude, st.h1.z, 1)
        sweep[pname, f] = st
        print(f"{pname:6s} f = {f:5.2f}: q_w = {setup.q_window_km2_s3:.2e} km^2/s^3 | H0 z = "
              f"{st.h0.z.mean() * 1e3:8.2f} +- {st.h0.z.std() * 1e3:6.2f} mm/s | H1 z = {st.h1.z.mean() * 1e3:8.2f}"
              f" +- {st.h1.z.std() * 1e3:6.2f} mm/s | FP + MD = {st.threshold.total_error:.3f} | z vs magnitude:"
              f" slope {slope:.2f}, corr {np.corrcoef(st.h1.magnitude, st.h1.z)[0, 1]:.2f}")

# %% [markdown]
# The sentences below describe the full run (64 runs per hypothesis; the printed lines are this run's). The
# variance-matched weight ($f = 1$) lets the smoother fit so much measurement noise as control that the H0
# integrals reach about half of the H1 ones. Shrinking $q_w$ shrinks H0 roughly as $\sqrt{q_w}$ while the H1
# integral keeps tracking the impulse (slope near 1) down to $f\approx0.1$; at $f = 0.01$ the quiet filter can no
# longer absorb the burn in the window ($z$ decorrelates from the magnitude, the state estimate lags). For the
# active policy alone $f = 0.01$ would separate the hypotheses even better (its 1 m/s burns dwarf the noise), but
# one rule for both policies is simpler to defend: **we use $f = 0.1$ for both policies** — a judgement from this
# sweep, not a value from the paper. Since $z_{lim}$ scales
# with this choice, the $z_{lim}$ comparison below checks consistency, not an independent prediction.
#
# **Figs. 10-13: the same burn under the two tunings.** One quiet-policy run (a 50 mm/s burn along $+\hat j$ at
# apoapsis, start at the periapsis hand-off) is filtered twice: with $q_w$ held constant over the whole period
# (the paper's "increased control uncertainty", Figs. 10-11) and with $q_w$ only in the 8-hour apoapsis window and
# $q_b$ elsewhere (the paper's proposed tuning, Figs. 12-13). For each we draw the paper's two panel sets with
# `cislunar.adaptive_ocbe` (the layout of notebook 09b's Figs. 6-9): position and velocity error norms with their
# 3-sigma bounds, forward (left) and smoothed (right); then the control norm (top) and the normalised OCBE metric
# (bottom; notebook 09b: $\chi^2_4$ under a correct model, limit $\chi^2_{4,0.99} = 13.28$, mean line at
# $4/13.28 = 0.30$; the smoothed metric's epoch average is 4). The paper does not give its burn direction, its
# "small maneuver" size in Figs. 12-13, or the control weights; ours are stated above.

# %%
F_TUNE = 0.1
setups = {(o, p): det.make_setup(em, ORBITS[o], F_TUNE * det.window_control_weight(POLICIES[p], WINDOW_HOURS),
                                 Q_BASE, window_hours=WINDOW_HOURS) for o in ORBITS for p in POLICIES}
s_q = setups["9:2 NRHO", "quiet"]
sc_q = s_q.scenario
demo = det.draw_trial(np.random.default_rng([SEED, 7]), s_q, magnitude_m_s=0.05, direction=(np.pi / 2, 0.0))
q_tunings = {"constant": s_q.control_weight.max(), "apoapsis window": s_q.control_weight}
runs = {name: det.run_trial_filter(s_q, demo, control_weight=q) for name, q in q_tunings.items()}
panels = {name: ad.panel_series(em, r, demo.truth, q_tunings[name], demo.y, s_q.observer_states, sc_q.model,
                                sc_q.meas_cov) for name, r in runs.items()}
burn_days = s_q.t_maneuver * em.time_unit_days
nees_q = stats.chi2.ppf(tracking.NEES_PROBABILITY, 6)
V_MM = em.velocity_unit_km_s * 1e6  # LU/TU -> mm/s
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
_ = plotting.save_figure(ad.figure_errors(panels["constant"], "Fig. 10 analogue, constant q_w", burn_days=burn_days,
                                          velocity_unit="mm/s"), "10_fig10_constant_tuning_errors", output_dir=out)

# %% [markdown]
# **Fig. 10 analogue** (the paper: "both the forwards and smoothed filters produce consistent, but less certain,
# solutions"). Compare the errors (blue) with their 3-sigma bounds (red) and the NEES fractions printed above.

# %%
_ = plotting.save_figure(ad.figure_control_metric(panels["constant"], "Fig. 11 analogue, constant q_w",
                                                  burn_days=burn_days),
                         "10_fig11_constant_tuning_control_metric", output_dir=out)

# %% [markdown]
# **Fig. 11 analogue** (the paper: "the maneuver appears as a spike in estimated control only in the smoothed
# system"). Top: the forward (single-step, Eq. 32) and smoothed control norms; bottom: the normalised metrics.

# %%
_ = plotting.save_figure(ad.figure_errors(panels["apoapsis window"], "Fig. 12 analogue, 8-h apoapsis window",
                                          burn_days=burn_days, velocity_unit="mm/s"),
                         "10_fig12_window_tuning_errors", output_dir=out)

# %% [markdown]
# **Fig. 12 analogue** (the paper: the window-tuned filter "still performs well"). Outside the window the
# control weight is $q_b$, so the bounds shrink as in a ballistic filter and widen only across the window.

# %%
_ = plotting.save_figure(ad.figure_control_metric(panels["apoapsis window"], "Fig. 13 analogue, 8-h apoapsis window",
                                                  burn_days=burn_days),
                         "10_fig13_window_tuning_control_metric", output_dir=out)
fs_c, fs_w = fig_summary["constant"], fig_summary["apoapsis window"]
print(f"smoothed over forward z: constant {fs_c['z_s'] / fs_c['z_f']:.1f}, window {fs_w['z_s'] / fs_w['z_f']:.1f}; "
      f"the window tuning's smoothed z is {fs_w['z_s'] / 50:.2f} of the 50 mm/s burn")

# %% [markdown]
# **Fig. 13 analogue** (the paper: a consistent filter "with a smoothed control spike around apoapsis that is
# indicative of a maneuver"). With the window tuning the control is essentially zero outside the window, so the
# smoothed spike stands alone and its integral $z$ tracks the burn. The forward control rises inside the window
# too (the estimated control is $-\tilde Q B^\top\mathbf p$, so it scales with $q_w$ whether or not there is a
# burn), which is where our Fig. 13 differs from the paper's, whose forward panel shows nothing; the printed spike
# contrasts compare the two passes; with the constant tuning the smoothed control
# also fits measurement noise all along the orbit, so the same burn is a smaller part of a larger $z$. The
# forward metric need not exceed its limit in either case: both tunings absorb the burn as expected control
# instead of flagging it, which is why the paper detects with $z$ and not with the metric.
#
# *Where this reproduction differs from the paper's figures.* The paper's runs are single draws with unstated
# burn direction, noise and control weights, so only the qualitative statements can be compared; the closing
# table lists them with criteria fixed before looking (consistency: at most 5 % of epochs above the 99.9 % NEES
# quantile, notebook 09's run criterion; spike: smoothed $z$ above twice the forward $z$). Our time axis is days
# from the periapsis hand-off (the burn at apoapsis, half a period in); our velocity panels are in mm/s.

# %% [markdown]
# ## 3 · Control-policy distributions (Eq. 33) and the maximum-likelihood test (Eqs. 34-35)
#
# For each orbit and policy: $N_{H0}$ runs without a maneuver and $N_{H1}$ runs with one drawn from the policy
# (500 and 3000 in the paper), each a full OCBE filter and smoother over one period from the periapsis hand-off,
# giving $z = \int_{t_0}^{t_f}\|\hat{\mathbf u}(t)\|dt$ of the smoothed control (Eq. 33, trapezoid rule on 9 points
# per 2-hour interval). Runs go through `cislunar.montecarlo.run_monte_carlo` (batches of 8 runs in lockstep in the
# batched OCBE, which equals the single-run filter to $10^{-10}$; see `tests/test_detection.py`).
#
# The PDFs are Gaussian kernel density estimates with Scott's bandwidth ($n^{-1/5}$ times the sample standard
# deviation). With equal priors and costs the maximum-likelihood rule (Eq. 34) picks H1 where
# $PDF_{H1}(z) > PDF_{H0}(z)$; with a single crossing it is the threshold rule of Eq. 35, $z > z_{lim}$. The
# expected false-positive rate is $\int_{z_{lim}}^\infty PDF_{H0}$ and the missed-detection rate
# $\int_{-\infty}^{z_{lim}} PDF_{H1}$ (Tables 5-6). Then 100 + 100 fresh runs test the rule (Tables 7-8).

# Which stable NRHO the paper used is unknown (its Table 1 is missing). Besides `orbits.stable_nrho` (the inner
# band's edge near the Moon) we run the candidate from the family's outer stable band that notebook 09 finds better
# supported by the paper's Table 4 remark, with a reduced Monte Carlo (a fifth of the training runs, half the
# tests) to bound the run time; its rows say so.

# %%
studies = {}
for i, o in enumerate(ORBITS):
    for j, p in enumerate(POLICIES):
        k = OUTER_SIZE if o == OUTER else 1.0
        studies[o, p] = det.run_policy_study(setups[o, p], POLICIES[p], max(int(k * N_H0), min(N_H0, 20)),
                                             max(int(k * N_H1), min(N_H1, 20)),
                                             max(int(N_TEST * (0.5 if o == OUTER else 1)), min(N_TEST, 10)),
                                             [SEED, i, j], batch_size=BATCH, executor=executor, label=f"{o} {p}")
print(f"Monte Carlo wall time so far: {(time.perf_counter() - T_START) / 60:.1f} min")

# %%
fig, ax = plt.subplots(2, len(studies), figsize=(4 * len(studies), 7))
for col, (key, st) in enumerate(studies.items()):
    unit = 1.0 if key[1] == "active" else 1e3
    ulab = "m/s" if key[1] == "active" else "mm/s"
    lo, hi = 0.0, max(st.h0.z.max(), st.h1.z.max()) * unit * 1.05
    bins = np.linspace(lo, hi, 50)
    ax[0, col].hist(st.h0.z * unit, bins=bins, alpha=0.6, histtype="stepfilled", label="no maneuver (H0)")
    ax[0, col].hist(st.h1.z * unit, bins=bins, alpha=0.6, histtype="stepfilled", label="maneuver (H1)")
    zz = np.linspace(lo, hi, 600)
    ax[1, col].plot(zz, st.threshold.pdf0(zz / unit) / unit, label=r"$PDF_{H0}$")
    ax[1, col].plot(zz, st.threshold.pdf1(zz / unit) / unit, label=r"$PDF_{H1}$")
    for a in ax[:, col]:
        a.axvline(st.threshold.z_lim * unit, color="k", ls=":", lw=1)
    ax[0, col].set(title=f"{key[0]}, {key[1]}\n{len(st.h0)} H0 + {len(st.h1)} H1 runs", ylabel="runs [-]",
                   xlabel=f"z [{ulab}]")
    ax[1, col].set(xlabel=f"z [{ulab}]", ylabel=f"probability density [1/({ulab})]",
                   title=f"z_lim = {st.threshold.z_lim * unit:.4g} {ulab}")
h0h, h0l = ax[0, 0].get_legend_handles_labels()
h1h, h1l = ax[1, 0].get_legend_handles_labels()
fig.legend(h0h + h1h + [plt.Line2D([], [], color="k", ls=":", lw=1)], h0l + h1l + ["z_lim"], loc="lower center",
           ncol=5, fontsize=8, bbox_to_anchor=(0.5, 0.0))
fig.tight_layout(rect=(0, 0.05, 1, 1))
_ = plotting.save_figure(fig, "10_control_integral_pdfs", output_dir=out)

print("Tables 5-6 (expected rates from the PDFs)")
print(f"{'orbit':12s} {'policy':7s} {'z_lim':>12s} {'false pos.':>11s} {'missed det.':>12s} {'crossings':>9s} "
      f"{'H0 mean':>10s} {'H1 mean':>10s}")
for (o, p), st in studies.items():
    th = st.threshold
    print(f"{o:12s} {p:7s} {th.z_lim * 1e3:9.2f} mm/s {th.false_positive:11.4f} {th.missed_detection:12.4f} "
          f"{th.crossings.size:9d} {st.h0.z.mean() * 1e3:7.2f} mm/s {st.h1.z.mean() * 1e3:7.2f} mm/s")

# %% [markdown]
# ## 3b · Is the window-tuned OCBE consistent? (beyond the paper's figures)
#
# The paper shows single runs (Figs. 12-13) whose errors stay inside their 3-sigma bounds. We check the tuning
# statistically: fresh runs with and without a burn for each orbit and policy, through the batched OCBE, and the
# NEES of the forward and the smoothed estimates against the truth (criterion of notebook 09: a run is
# inconsistent when more than 5 % of its epochs exceed the 99.9 % quantile of $\chi^2_6$, 22.5).

# %%
nees_lim = stats.chi2.ppf(tracking.NEES_PROBABILITY, 6)
nees_study = {}
for io, o in enumerate(ORBITS):
    for ip, p in enumerate(POLICIES):
        s_ = setups[o, p]
        sc_ = s_.scenario
        inputs = []  # N_NEES runs without a burn, then N_NEES with one; one lockstep batch sequence for both
        for hyp, pol in (("H0", None), ("H1", POLICIES[p])):
            rng_n = np.random.default_rng([SEED, 55, io, ip, int(hyp == "H1")])
            inputs += [det.draw_trial(rng_n, s_, pol) for _ in range(N_NEES)]
        nf, ns = [], []
        for i0 in range(0, len(inputs), BATCH):
            chunk = inputs[i0:i0 + BATCH]
            rb = det.ocbe_batch(em, sc_.t, np.array([c.y for c in chunk]), s_.observer_states, sc_.model,
                                sc_.meas_cov, np.array([c.x0 for c in chunk]), chunk[0].P0, s_.control_weight,
                                n_sub=s_.n_sub, tol=s_.tol)
            for b, c in enumerate(chunk):
                nf.append(tracking.nees(rb.x_filt[b], rb.P_filt[b], c.truth))
                ns.append(tracking.nees(rb.x_smooth[b], rb.P_smooth[b], c.truth))
        for h, hyp in enumerate(("H0", "H1")):
            f_, s_n = np.array(nf[h * N_NEES:(h + 1) * N_NEES]), np.array(ns[h * N_NEES:(h + 1) * N_NEES])
            nees_study[o, p, hyp] = dict(
                mean_f=float(f_.mean()), mean_s=float(s_n.mean()),
                runs_f=float(np.mean(np.mean(f_ > nees_lim, axis=1) > tracking.DIVERGED_FRACTION)),
                runs_s=float(np.mean(np.mean(s_n > nees_lim, axis=1) > tracking.DIVERGED_FRACTION)))
print(f"{'orbit':12s} {'policy':7s} {'hyp':4s} {'NEES fwd':>9s} {'NEES smo':>9s} {'inconsistent runs fwd / smo':>28s}")
for (o, p, hyp), v in nees_study.items():
    print(f"{o:12s} {p:7s} {hyp:4s} {v['mean_f']:9.2f} {v['mean_s']:9.2f} "
          f"{100 * v['runs_f']:13.0f} % / {100 * v['runs_s']:.0f} %")

# %% [markdown]
# %%
bad_cells = {k: v for k, v in nees_study.items() if max(v["runs_f"], v["runs_s"]) > 0.10}
print("cells with more than 10 % inconsistent runs (forward / smoothed): "
      + ("; ".join(f"{o} {p} {h}: {100 * v['runs_f']:.0f} % / {100 * v['runs_s']:.0f} %"
                   for (o, p, h), v in bad_cells.items()) or "none"))
print(f"every such cell has a burn (H1): {all(h == 'H1' for _, _, h in bad_cells)}")

# %% [markdown]
# In the full run (24 runs per cell) no run without a burn (H0) is inconsistent and the H0 mean NEES stays near 6
# (4.6-7.8): the window tuning costs no consistency when nothing happens. With a burn (H1) the forward filter is
# inconsistent in a fifth to two thirds of the runs for a few epochs after apoapsis (most for the quiet policy):
# the factor $f = 0.1$ of Section 2 gives the window a velocity uncertainty of only $\sqrt{0.1}\approx0.32$ of the
# burn's RMS size, a choice made for detection (it keeps H0's $z$ small), not for consistency. The smoothed
# estimate, which sees the data after the burn, is consistent on the outer-band stable NRHO but not always on the
# 9:2 and the inner-band one (12-17 % of H1 runs). The paper shows single consistent runs (Figs. 12-13); the
# closing table records the worst cell per orbit as "differs" where it exceeds 10 %.

# %% [markdown]
# ## 4 · Sensitivity of $z$ to the maneuver (Figs. 16-17, 20-21)
#
# The paper finds $z$ nearly linear in the impulse magnitude (so it could estimate it) and, for the active policy,
# largest for burns along $\pm\hat j$ (azimuth $\pm90°$, low elevation), where the burn is best aligned with the
# measurement sensitivity at apoapsis; for the quiet policy that pattern is weaker.

# %%
fig, ax = plt.subplots(2, 3, figsize=(15, 8))
for row, p in enumerate(POLICIES):
    h1 = studies["9:2 NRHO", p].h1
    unit, ulab = (1.0, "m/s") if p == "active" else (1e3, "mm/s")
    sc_ = ax[row, 0].scatter(np.degrees(h1.azimuth), np.degrees(h1.elevation), c=h1.z * unit, s=6, cmap="viridis")
    fig.colorbar(sc_, ax=ax[row, 0], label=f"z [{ulab}]")
    ax[row, 0].set(xlabel="azimuth [deg]", ylabel="elevation [deg]", title=f"9:2 NRHO, {p}")
    ax[row, 1].scatter(np.degrees(h1.azimuth), h1.z / h1.magnitude, s=4, alpha=0.5)
    ax[row, 1].set(xlabel="azimuth [deg]", ylabel="z / impulse magnitude [-]")
    for o, mk in zip(ORBITS, ("o", "x")):
        s1 = studies[o, p].h1
        ax[row, 2].scatter(s1.magnitude * unit, s1.z * unit, s=4, alpha=0.4, marker=mk, label=o)
    mm = np.array([0, h1.magnitude.max() * unit])
    ax[row, 2].plot(mm, mm, "k--", lw=1, label="z = magnitude")
    ax[row, 2].set(xlabel=f"impulse magnitude [{ulab}]", ylabel=f"z [{ulab}]")
    ax[row, 2].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), markerscale=3)
fig.tight_layout()
_ = plotting.save_figure(fig, "10_z_vs_maneuver", output_dir=out)


def azimuth_contrast(h1):
    """Mean z/magnitude for |azimuth| within 30 deg of 90 over that within 30 deg of 0 or 180 (low elevation)."""
    r, a, e = h1.z / h1.magnitude, np.abs(np.degrees(h1.azimuth)), np.abs(np.degrees(h1.elevation))
    low = e < 45
    side = low & (np.abs(a - 90) < 30)
    axial = low & ((a < 30) | (a > 150))
    return r[side].mean() / r[axial].mean() if side.any() and axial.any() else np.nan  # NaN: a sector is empty


def ratio_text(v):
    return "no burn in a sector (small sample)" if np.isnan(v) else f"{v:.2f}"


lin = {}
for (o, p), st in studies.items():
    h1 = st.h1
    slope = np.polyfit(h1.magnitude, h1.z, 1)[0]
    lin[o, p] = (slope, np.corrcoef(h1.magnitude, h1.z)[0, 1], azimuth_contrast(h1), stats.skew(h1.z))
    print(f"{o:12s} {p:7s}: z vs magnitude slope {slope:.2f}, corr {lin[o, p][1]:.3f}; z/|dv| at azimuth +-90 "
          f"over 0/180 (|el| < 45 deg) = {ratio_text(lin[o, p][2])}; skewness of H1 z = {lin[o, p][3]:.2f}")

# %% [markdown]
# **Looking for the $\pm\hat j$ pattern.** Where could the paper's bimodality come from? We fire 1 m/s burns in
# the orbit plane at azimuths 0°, 90°, 180° and 270° (same noise draws for every azimuth) on the 9:2 NRHO and
# vary the two unpublished inputs that shape how a burn shows up in $z$: the window weight factor $f$ and the
# angle noise. The contrast is mean $z$ at $\pm90°$ over mean $z$ at 0°/180° (1 = no preference).

# %%
pmj = {}
AZ = np.radians([0.0, 90.0, 180.0, 270.0])
for f_ in (0.1, 1.0):
    for sig_ in (10e-6, 100e-6):
        s_pm = det.make_setup(em, ORBITS["9:2 NRHO"], f_ * det.window_control_weight(det.ACTIVE_POLICY, WINDOW_HOURS),
                              Q_BASE, window_hours=WINDOW_HOURS, sigma_angle_rad=sig_)
        inputs = [det.draw_trial(np.random.default_rng([SEED, 31, k]), s_pm, magnitude_m_s=1.0, direction=(az, 0.0))
                  for k in range(PM_J_SEEDS) for az in AZ]
        zs = []
        for i0 in range(0, len(inputs), BATCH):
            chunk = inputs[i0:i0 + BATCH]
            rb = det.ocbe_batch(em, s_pm.scenario.t, np.array([c.y for c in chunk]), s_pm.observer_states,
                                s_pm.scenario.model, s_pm.scenario.meas_cov, np.array([c.x0 for c in chunk]),
                                chunk[0].P0, s_pm.control_weight, n_sub=s_pm.n_sub, tol=s_pm.tol)
            zs.extend(rb.z_smooth * em.velocity_unit_km_s * 1e3)
        zs = np.array(zs).reshape(PM_J_SEEDS, AZ.size).mean(axis=0)
        pmj[f_, sig_] = (zs, (zs[1] + zs[3]) / (zs[0] + zs[2]))
        print(f"f = {f_:4.1f}, sigma = {sig_ * 1e6:5.0f} urad: z at 0/90/180/270 deg = "
              + " / ".join(f"{z:.3f}" for z in zs) + f" m/s; +-j contrast {pmj[f_, sig_][1]:.2f}")
best_pmj = max(pmj.items(), key=lambda kv: kv[1][1])

# %% [markdown]
# ## 5 · Detection tests on independent data (Tables 7-8)
#
# Fresh runs (seeds independent of the training runs) are classified with Eq. 35 and the $z_{lim}$ above.

# %%
acc = {k: st.score.accuracy for k, st in studies.items()}
print(f"{'orbit':12s} {'policy':7s} {'H0 -> H0':>9s} {'H0 -> H1':>9s} {'H1 -> H1':>9s} {'H1 -> H0':>9s} {'accuracy':>9s}")
for (o, p), st in studies.items():
    s = st.score
    print(f"{o:12s} {p:7s} {s.true_negative:9d} {s.false_positive:9d} {s.true_positive:9d} {s.missed_detection:9d} "
          f"{100 * s.accuracy:8.1f}%")

# %% [markdown]
# **The two stable candidates, side by side.** Detection accuracy (Tables 7-8) and the worst window-tuning NEES cell
# (Section 3b) per orbit:

# %%
for o in ORBITS:
    worst = [max(v[r] for k, v in nees_study.items() if k[0] == o) for r in ("runs_f", "runs_s")]
    print(f"{o:25s}: accuracy active {100 * acc[o, 'active']:.1f} %, quiet {100 * acc[o, 'quiet']:.1f} % "
          f"({studies[o, 'active'].score.n} tests each); worst cell inconsistent runs forward {100 * worst[0]:.0f} %, "
          f"smoothed {100 * worst[1]:.0f} %")

# %% [markdown]
# In the full run the accuracies of all three orbits lie within two or three test runs of each other (97-100 %),
# which the 100 + 100 tests (50 + 50 for the outer band) cannot separate; the window-tuned filter is most
# consistent on the outer-band member (no inconsistent smoothed run), least on the inner-band one. Detection
# therefore does not decide between the candidates; notebook 09's determination and consistency results do (the
# outer band), and both stay in the table.

# %% [markdown]
# ## 6 · Control as a health metric (Fig. 22)
#
# The filter is tuned for the quiet policy but the vehicle burns 0.5 m/s (ten times the quiet mean). The paper
# reports that the smoothed estimate diverges while the measurement residuals look benign, and that
# $z = 0.4761$ m/s, "approximately at 30 sigma of the maneuvering distribution of Z" — a fast, sensitive health
# metric. We run the same experiment (random pointing) and express $z$ in standard deviations of our quiet H1
# and H0 distributions on the 9:2 NRHO.

# %%
health = det.draw_trial(np.random.default_rng([SEED, 8]), s_q, magnitude_m_s=0.5)
rh = det.run_trial_filter(s_q, health)
ref = studies["9:2 NRHO", "quiet"]
z_h = rh.z_smooth * em.velocity_unit_km_s * 1e3
sig_h1 = (z_h - ref.h1.z.mean()) / ref.h1.z.std()
sig_h0 = (z_h - ref.h0.z.mean()) / ref.h0.z.std()
nees_h = tracking.nees(rh.x_smooth, rh.P_smooth, health.truth)
fig, ax = plt.subplots(1, 3, figsize=(15, 3.8))
hours = sc_q.t * em.time_unit_s / 3600
err = np.linalg.norm(rh.x_smooth[:, :3] - health.truth[:, :3], axis=1) * em.length_unit_km
sig = 3 * np.sqrt(np.trace(rh.P_smooth[:, :3, :3], axis1=1, axis2=2)) * em.length_unit_km
ax[0].semilogy(hours, err, label="smoothed error")
ax[0].semilogy(hours, sig, "--", label="3-sigma")
ax[0].set(xlabel="time from periapsis [h]", ylabel="position error [km]", title="0.5 m/s burn, quiet tuning")
ax[0].legend(loc="lower center")
ax[1].plot(hours, rh.residual_norms, ".")
ax[1].axhline(np.sqrt(stats.chi2.ppf(0.99, 4)), color="k", ls=":", label="99% of a 4-dof residual")
ax[1].set(xlabel="time from periapsis [h]", ylabel="whitened residual norm [-]", title="measurement residuals")
ax[1].legend()
ax[2].hist(ref.h1.z, bins=40, alpha=0.6, histtype="stepfilled", label="quiet H1")
ax[2].hist(ref.h0.z, bins=40, alpha=0.6, histtype="stepfilled", label="quiet H0")
ax[2].axvline(z_h, color="C3", label=f"this run: z = {z_h:.3f} m/s")
ax[2].set(xscale="log", xlabel="z [m/s]", ylabel="runs [-]")
ax[2].legend(fontsize=8)
_ = plotting.save_figure(fig, "10_health_metric", output_dir=out)
print(f"impulse 0.5 m/s (azimuth {np.degrees(health.azimuth):.0f} deg, elevation {np.degrees(health.elevation):.0f} deg):"
      f" z = {z_h:.4f} m/s = {sig_h1:.0f} sigma of quiet H1, {sig_h0:.0f} sigma of quiet H0")
print(f"smoothed NEES mean {nees_h.mean():.0f} (6 if consistent); residual norms: median {np.median(rh.residual_norms):.2f},"
      f" max {rh.residual_norms.max():.2f}; fraction above the 99% level "
      f"{np.mean(rh.residual_norms > np.sqrt(stats.chi2.ppf(0.99, 4))):.2f}")

# %% [markdown]
# **Does the control react before the residuals? (Fig. 22's claim, measured.)** Both tests below are online (they
# use only data up to the current epoch) and both have a false-alarm rate of about 1 % per track:
#
# * *control test*: the running forward control integral $z_{fwd}(t_n) = \int_{t_0}^{t_n}\|\hat{\mathbf u}\|dt$
#   (single-step smoothed control, Eq. 32) exceeds the 99 % quantile of the whole-track forward integral of the
#   quiet H0 runs (a partial integral of a positive integrand never exceeds the whole, so this is conservative);
# * *residual test*: the adaptive OCBE's rule of notebook 09b (the whitened innovation, $\chi^2_4$, above its 99 %
#   limit at three consecutive epochs), declared at the third epoch.

# %%
zf_cum = np.concatenate([[0.0], np.cumsum(np.trapezoid(np.linalg.norm(rh.control_step, axis=-1), rh.t_sub, axis=-1))])
zf_cum *= em.velocity_unit_km_s * 1e3  # m/s at each epoch
zf_lim = float(np.quantile(ref.h0.z_step, 0.99))
k_burn_h = int(np.searchsorted(s_q.scenario.t, s_q.t_maneuver, side="right"))
over = np.flatnonzero(zf_cum > zf_lim)
k_ctrl = int(over[0]) if over.size else None
m_h, dof_h = ad.forward_metric(rh, s_q.scenario.model)
k_first = ad.first_detection(m_h, ad.metric_limit(dof_h))
k_res = None if k_first is None else k_first + ad.CONSECUTIVE_EPOCHS - 1
cad_h = s_q.scenario.cadence_hours


def after_burn(k):
    return "never" if k is None else f"{(k - k_burn_h) * cad_h:+.0f} h"


print(f"control test fires {after_burn(k_ctrl)} after the first epoch that sees the burn (threshold "
      f"{zf_lim * 1e3:.1f} mm/s); residual test: first exceedance of the run that confirms it {after_burn(k_first)}, "
      f"declared {after_burn(k_res)}")
# the paper's claim is that the control deviates *before* the residuals do: compare with the residuals' first
# exceedance (the 3-strike declaration adds two epochs of confirmation by construction)
lead_ok = k_ctrl is not None and (k_first is None or k_ctrl < k_first)

# %% [markdown]
# ## Paper versus reproduction
#
# Statuses follow the guide's rule: *reproduced* only for an independent prediction within a tolerance fixed before
# comparing; *consistent (tuned)* where agreement rests on a choice made while looking at the paper (here the
# window-weight factor behind $z_{lim}$); *differs* with the reason otherwise. Two inputs are our choices because
# the paper's tables are missing: the measurement noise (10 micro-rad angles, Eq. 13 rates with 1 s differencing)
# and the tuning ($q_w = 0.1\,E[u_{mag}^2]/(3T)$ in the 8-hour window, $10^{-18}$ km$^2$/s$^3$ elsewhere). The
# thresholds scale with the tuning, so they are a consistency check, not an independent prediction.

# %%
def close(a, b, rel):
    return abs(a / b - 1) <= rel


zl_a = studies["9:2 NRHO", "active"].threshold.z_lim
zl_q = studies["9:2 NRHO", "quiet"].threshold.z_lim
table.add("Measurement noise (Table 3)", "missing from the text", "10 micro-rad angles; rates sqrt(2)*10 micro-rad/s",
          "not in paper", "value the same authors use in their AMOS 2023 paper (cislunar.tracking)")
table.add("OCBE tuning (8-h apoapsis window)", "values missing",
          f"q_w = 0.1 E[u^2]/(3T): active {setups['9:2 NRHO', 'active'].q_window_km2_s3:.2e}, quiet "
          f"{setups['9:2 NRHO', 'quiet'].q_window_km2_s3:.2e} km^2/s^3; base 1e-18", "not in paper",
          "factor 0.1 chosen from the pilot sweep in Section 2")
table.add("Monte Carlo sizes (H0 / H1 / tests per hypothesis)", "500 / 3000 / 100", f"{N_H0} / {N_H1} / {N_TEST}",
          "derived: the paper's sizes" if not QUICK else "differs: quick mode",
          "per policy and orbit; an input; the outer-band stable NRHO runs a fifth (training) and half (tests)")
sig_mean = {k: float(np.mean(panels[k].position_3sigma_km[0])) for k in panels}
for fig_no, name, claim in ((10, "constant", "consistent, but less certain (forward and smoothed)"),
                            (12, "apoapsis window", "consistent (forward and smoothed)")):
    fs = fig_summary[name]
    ok = max(fs["over"]) <= tracking.DIVERGED_FRACTION and (name != "constant" or
                                                            sig_mean["constant"] > sig_mean["apoapsis window"])
    table.add(f"Fig. {fig_no}: {name} tuning, 50 mm/s burn", claim,
              f"epochs above NEES 99.9 %: forward {100 * fs['over'][0]:.0f} %, smoothed {100 * fs['over'][1]:.0f} %; "
              f"mean forward 3-sigma position {sig_mean[name]:.2f} km",
              "reproduced" if ok else "differs: see the NEES fractions and the bounds",
              "one run (+j burn); criterion fixed in advance: at most 5 % of epochs above the quantile"
              + (" and larger bounds than the window tuning" if name == "constant" else ""))
for fig_no, name in ((11, "constant"), (13, "apoapsis window")):
    cf, cs = fig_summary[name]["contrast"]
    table.add(f"Fig. {fig_no}: {name} tuning, control spike at the burn in the smoothed control only",
              "spike only in the smoothed system", f"spike contrast: smoothed {cs:.3g}, forward {cf:.3g}",
              "reproduced" if cs >= 2 and cs > cf else "differs: " + ("no smoothed spike" if cs < 2 else
                                                                       "the forward control spikes as much"),
              "contrast = mean control norm within 6 h of the burn over the mean elsewhere "
              "(PanelSeries.spike_contrast); criterion: smoothed at least 2 and above the forward one (chosen after "
              "seeing the figures, so a description rather than a test)")
table.add("Smoothed control spike at apoapsis with window tuning (Figs. 12-13)", "spike in smoothed control only",
          f"z smoothed {runs['apoapsis window'].z_smooth * em.velocity_unit_km_s * 1e6:.1f} mm/s vs forward "
          f"{runs['apoapsis window'].z_step * em.velocity_unit_km_s * 1e6:.1f} mm/s for a 50 mm/s burn",
          "reproduced" if runs["apoapsis window"].z_smooth > 2 * runs["apoapsis window"].z_step else
          "differs: the forward control sees the burn as much as the smoothed one",
          "criterion fixed in advance: smoothed z above twice the forward z")
for key, paper, tol in ((("9:2 NRHO", "active"), 0.4106, 0.25), (("9:2 NRHO", "quiet"), 0.01722, 0.25)):
    zl = studies[key].threshold.z_lim
    st_ = TUNED if close(zl, paper, tol) else \
        f"differs: {100 * (zl / paper - 1):+.0f} %; z_lim scales with the unpublished tuning and noise"
    table.add(f"z_lim, {key[0]}, {key[1]} (Eq. 35)", f"{paper * 1e3:.2f} mm/s", f"{zl * 1e3:.2f} mm/s", st_,
              f"{100 * (zl / paper - 1):+.0f} %; within 25 % counts as agreement; conditional on the window weight "
              "factor f = 0.1 chosen from the pilot sweep (Section 2): z_lim scales with f, so this is a consistency "
              "check, not an independent prediction")
for key in ((o, p) for o in STABLE for p in POLICIES):
    table.add(f"z_lim, {key[0]}, {key[1]}", "not given", f"{studies[key].threshold.z_lim * 1e3:.2f} mm/s",
              "not in paper", "the paper omits the stable-NRHO plots and values"
              + ("; outer-band candidate (notebook 09), reduced Monte Carlo" if key[0] == OUTER else ""))
for (o, p), st in studies.items():
    table.add(f"Expected FP / MD, {o}, {p} (Tables 5-6)", "tables missing",
              f"{st.threshold.false_positive:.4f} / {st.threshold.missed_detection:.4f}", "not in paper",
              f"{st.threshold.crossings.size} PDF crossing(s)")
for o in ORBITS:
    worst_f = max(v["runs_f"] for k, v in nees_study.items() if k[0] == o)
    worst_s = max(v["runs_s"] for k, v in nees_study.items() if k[0] == o)
    table.add(f"Window-tuned OCBE consistent, {o} (NEES, forward / smoothed)", "consistent (Figs. 12-13, single runs)",
              f"worst cell: {100 * worst_f:.0f} % / {100 * worst_s:.0f} % of runs inconsistent",
              "reproduced" if max(worst_f, worst_s) <= 0.10 else
              "differs: some policy/hypothesis cells have many inconsistent runs",
              f"{N_NEES} runs per policy and hypothesis; criterion fixed in advance: at most 10 % inconsistent runs")
n_cross = [st.threshold.crossings.size for st in studies.values()]
table.add("H0 and H1 PDFs cross once", "yes (Figs. 15, 19)", f"crossings per case: {n_cross}",
          "reproduced" if all(c == 1 for c in n_cross) else "differs: KDE tails of the finite sample add crossings",
          "z_lim is the crossing of least total error")
for key, paper in ((("9:2 NRHO", "active"), 1.00), (("9:2 NRHO", "quiet"), 0.97)):
    a = acc[key]
    ok = abs(a - paper) <= max(0.02, 2 * np.sqrt(paper * (1 - paper) / N_TEST / 2) + 1 / (2 * N_TEST))
    table.add(f"Detection accuracy, {key[0]}, {key[1]} (Table 7)", f"{100 * paper:.0f} %", f"{100 * a:.1f} %",
              "reproduced" if ok else "differs: see FP/MD; depends on the unpublished tuning and noise",
              f"{2 * N_TEST} test runs; tolerance: 2 binomial standard errors (at least 2 points), fixed in advance; "
              "conditional on the tuning f = 0.1, chosen for low pilot error, not to match this number")
for o in STABLE:
    for p in POLICIES:
        a_s, a_n = acc[o, p], acc["9:2 NRHO", p]
        n_s, n_n = studies[o, p].score.n, studies["9:2 NRHO", p].score.n
        se = np.sqrt(max(a_s * (1 - a_s), 1 / n_s) / n_s + max(a_n * (1 - a_n), 1 / n_n) / n_n)
        table.add(f"Detection accuracy, {o}, {p} (Table 8)",
                  "marginally better than 9:2" + (" (quiet: 200/200)" if p == "quiet" else ""),
                  f"{100 * a_s:.1f} % of {n_s} tests (9:2: {100 * a_n:.1f} % of {n_n})",
                  "reproduced" if a_s >= a_n else
                  "differs: not better than the 9:2, but within 2 standard errors of it" if a_n - a_s <= 2 * se else
                  "differs: worse than the 9:2 NRHO",
                  ("outer-band candidate, half the test runs; " if o == OUTER else "")
                  + f"standard error of the difference {100 * se:.1f} points; 'marginally better' cannot be resolved "
                  "with this many tests")
for p in POLICIES:
    sl, cr, ctr, sk = lin["9:2 NRHO", p]
    table.add(f"z nearly linear in the magnitude, {p} (Figs. 17, 21)", "apparently linear",
              f"slope {sl:.2f}, corr {cr:.3f}", "reproduced" if cr > 0.8 else "differs: weak correlation")
ctr_a, ctr_q = lin["9:2 NRHO", "active"][2], lin["9:2 NRHO", "quiet"][2]
table.add("Largest z for burns at azimuth +-90 deg, active (Fig. 16)", "bimodal, peaks at +-j",
          f"z/|dv| at +-90 deg over 0/180 deg: {ratio_text(ctr_a)}",
          "reproduced" if ctr_a > 1.1 else "differs: no clear +-j preference in our runs")
table.add("Conditions for the +-j pattern (sweep over f and angle noise, 1 m/s in-plane burns)", "not discussed",
          f"largest contrast {best_pmj[1][1]:.2f} at f = {best_pmj[0][0]:g}, {best_pmj[0][1] * 1e6:g} urad; "
          f"range {min(v[1] for v in pmj.values()):.2f}-{max(v[1] for v in pmj.values()):.2f}", "beyond paper",
          f"{PM_J_SEEDS} noise draw(s) per azimuth; a contrast near 1 means no +-j preference")
table.add("Quiet policy: pattern less bimodal (Fig. 20)", "more uniform",
          f"ratio {ratio_text(ctr_q)} (active {ratio_text(ctr_a)})",
          "reproduced" if ctr_a > 1.1 and ctr_q < ctr_a else
          "differs: neither policy shows the +-j pattern clearly, so there is nothing to weaken")
table.add("H1 z approximately Gaussian, active (Fig. 15)", "approximately Gaussian",
          f"skewness {lin['9:2 NRHO', 'active'][3]:.2f}",
          "reproduced" if abs(lin["9:2 NRHO", "active"][3]) < 0.5 else "differs: skewed")
table.add("Health metric: z for 0.5 m/s burn, quiet tuning", "0.4761 m/s", f"{z_h:.4f} m/s",
          "reproduced" if close(z_h, 0.4761, 0.25) else "differs: depends on the pointing and tuning",
          "one run, random pointing")
table.add("Health metric: sigma level in the quiet H1 distribution", "about 30 sigma", f"{sig_h1:.0f} sigma",
          TUNED if 20 <= sig_h1 <= 45 else "differs: our quiet H1 spread differs from the paper's",
          "the quiet H1 spread scales with the window-weight factor f = 0.1 chosen in Section 2")
table.add("Control metric reacts before a residual test (Fig. 22)", "yes (deviations before the residuals)",
          f"control test {after_burn(k_ctrl)}; residuals above their limit {after_burn(k_first)} (3-strike "
          f"declaration {after_burn(k_res)}) after the burn",
          "reproduced" if lead_ok else "differs: the residuals exceed their limit no later than the control test",
          "one run; both tests online; the control test has about 1 % false alarms per track")
table.add("Health metric: residuals benign while the estimate diverges (Fig. 22)", "yes",
          f"NEES mean {nees_h.mean():.0f}; residual median {np.median(rh.residual_norms):.2f}",
          "reproduced" if nees_h.mean() > 20 and np.median(rh.residual_norms) < 3 else
          "differs: our filter is " + ("consistent" if nees_h.mean() <= 20 else "diverged with visible residuals"))
if executor is not None:
    executor.shutdown()
print(f"notebook wall time: {(time.perf_counter() - T_START) / 60:.1f} min")
table.display()
