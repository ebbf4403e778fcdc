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
# # 09b · The adaptive OCBE: a statistical metric, three strikes, and a covariance reset
#
# **What you will learn.** What the OCBE metric of Lubey & Scheeres is (the optimal-control estimator's own cost of
# linking one epoch to the next), why it is $\chi^2_m$-distributed when nothing is mismodelled, and how Greaves &
# Scheeres use it to tune the filter automatically: a maneuver is declared when the metric stays above its 99 %
# limit for three consecutive epochs, dated to the first, and the filter then resets its control uncertainty so
# that the metric at that epoch equals its mean. We reproduce the 3 m/s burn of Figs. 6-7 and the 50 mm/s burn of
# Figs. 8-9 on the 9:2 NRHO, then measure, over many burns, why the paper leaves the adaptive filter for the
# windowed tuning of notebook 10: small burns are detected late or not at all, and the filter is inconsistent in
# the meantime. We also find a case the paper does not discuss, where the literal reset rule breaks.
#
# **Paper sections followed.** J. A. Greaves, D. J. Scheeres, *Observation and Maneuver Detection for Cislunar
# Vehicles*, JAS 68 (2021), "Filter Tuning Strategy: Adaptive OCBE Tuning" (Figs. 6-9), with the metric of D. P.
# Lubey, D. J. Scheeres, JGCD 37(5), 2014 and Lubey's thesis (2015). The OCBE itself (Eqs. 14-32) is
# `cislunar.estimation.ocbe` (notebook 09); the adaptive logic is `cislunar.estimation.adaptive_ocbe`; the scenario (L2 observer,
# angles and angle rates every 2 hours, Earth-radar hand-off at periapsis, burn at apoapsis) is
# `cislunar.papers.greaves_scheeres_2021.tracking` / `cislunar.papers.greaves_scheeres_2021.detection` (notebook 10).

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: quick mode shrinks the Monte Carlo samples, never skips an experiment.
N_NULL = 4 if QUICK else 16  # no-maneuver runs for the metric's law (batched OCBE, one period each)
MAGNITUDES_M_S = [0.05, 0.3, 3.0] if QUICK else [0.05, 0.1, 0.3, 1.0, 3.0]  # burn sizes of the delay study
N_PER_MAGNITUDE = 2 if QUICK else 20  # single-trial adaptive runs per burn size and reset rule
N_DELAY = 8 if QUICK else 200  # batched first-pass runs per burn size and per noise level (detection delays)
NOISE_SWEEP_URAD = [5, 10, 30] if QUICK else [5, 10, 15, 20, 30]  # angle noise (1 sigma) of the 50 mm/s sweep
Q_BASE_KM2_S3 = 1e-18  # the ballistic tuning (notebook 10's q outside the apoapsis window)
MAX_RESETS = 5  # a run needing more resets than this is counted as diverged

import time

import matplotlib.pyplot as plt
import numpy as np
from scipy import stats

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import adaptive_ocbe as ad
from cislunar.estimation import consistency, ocbe
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import panels as ocbe_panels
from cislunar.papers.greaves_scheeres_2021 import tracking
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
table = ComparisonTable("09b Adaptive OCBE (Greaves & Scheeres 2021, Adaptive OCBE Tuning, Figs. 6-9)")
T_START = time.perf_counter()
L_KM, V_MS = em.length_unit_km, em.velocity_unit_km_s * 1e3
ACC_KM_S2 = em.length_unit_km / em.time_unit_s**2
DAY = 86400.0 / em.time_unit_s

nrho = orbits.nrho_9_2(em)
setup = det.make_setup(em, nrho, Q_BASE_KM2_S3, Q_BASE_KM2_S3)  # constant ballistic tuning, start at periapsis
sc = setup.scenario
k_burn = int(np.searchsorted(sc.t, setup.t_maneuver, side="right"))  # first epoch that sees the burn
print(f"9:2 NRHO, period {nrho.period_days:.3f} d; {sc.t.size} epochs every {sc.cadence_hours:.0f} h from periapsis; "
      f"burn at apoapsis t = {setup.t_maneuver / DAY:.3f} d, first seen at epoch {k_burn}")

# %% [markdown]
# ## 1 · The OCBE metric and its law
#
# At epoch $n+1$ the OCBE explains the new measurement by moving the previous estimate (the single-step smoothed
# correction $\boldsymbol\delta_n = \mathbf x_{n|n+1}-\mathbf x_{n|n}$, Eqs. 29-30) and by an optimal control
# $\hat{\mathbf u}$ over the interval (Eq. 32). Its cost, written as a sum of squares, is the **OCBE metric**
#
# $$M_{n+1} = \boldsymbol\delta_n^\top P_{n|n}^{-1}\boldsymbol\delta_n
#   + \int_{t_n}^{t_{n+1}}\hat{\mathbf u}^\top\tilde Q^{-1}\hat{\mathbf u}\,dt
#   + \mathbf r_{n+1}^\top R^{-1}\mathbf r_{n+1}$$
#
# (a-priori, control and measurement terms; $\mathbf r$ the post-fit residual). The control term equals
# $\mathbf w^\top Q^{-1}\mathbf w$, with $\mathbf w$ the state change the control produces and $Q=-\Phi_{xp}
# \Phi_{xx}^\top$ (Eq. 17): the minimum-energy control that moves the state by $\mathbf w$ costs exactly that.
#
# **Derivation of its law.** $M_{n+1}$ is the minimum of a linear least-squares problem in 12 unknowns
# ($\boldsymbol\delta_n$, $\mathbf w$) with $6+6+m$ whitened equations. Completing the square, the minimum is the
# squared Mahalanobis norm of the innovation,
# $M_{n+1} = \delta\mathbf y^\top(H(\Phi P\Phi^\top+Q)H^\top+R)^{-1}\delta\mathbf y = \|\mathbf e_{n+1}\|^2$,
# the residual that the Householder step of the SRI measurement update (Eq. 27) leaves below the information
# array. Under a correct model the innovation is Gaussian with exactly that covariance, so
# $M_{n+1}\sim\chi^2_m$ with mean $m$ and variance $2m$, independent between epochs. Here $m = 4$ (two angles,
# two angle rates): the mean is 4, the 99 % limit $\chi^2_{4,0.99} = 13.28$, the "normalised metric" of Figs. 7
# and 9 is $M/13.28$ and its mean line sits at 0.30. Three consecutive exceedances have probability $10^{-6}$ per
# epoch: over the 79 epochs of one period a false reset has probability below $10^{-4}$.
#
# `tests/estimation/test_adaptive_ocbe.py` checks the three-term identity and the $\chi^2_m$ law exactly on linear systems
# (Kolmogorov-Smirnov, with power against $\chi^2_{m\pm1}$). Here we check it on the nonlinear NRHO scenario
# without a maneuver (batched OCBE, ballistic tuning).

# %%
draws = [det.draw_trial(rng, setup, None) for _ in range(N_NULL)]
res0, q0, metric0, dets0 = ad.adaptive_ocbe_batch(em, sc.t, np.array([d.y for d in draws]), setup.observer_states,
                                                  sc.model, sc.meas_cov, np.array([d.x0 for d in draws]),
                                                  draws[0].P0, setup.control_weight)
pooled = metric0.ravel()
law = ad.metric_law(4)
ks_p = stats.kstest(pooled, law.cdf).pvalue
exceed = np.mean(pooled > ad.metric_limit(4))
n_resets_null = sum(len(d) for d in dets0)
nees0 = np.array([consistency.nees(res0.x_filt[b], res0.P_filt[b], draws[b].truth) for b in range(N_NULL)])
fig, ax = plt.subplots(1, 2, figsize=(11, 3.8))
xx = np.linspace(0, 20, 300)
ax[0].hist(pooled, bins=40, range=(0, 20), density=True, alpha=0.6, histtype="stepfilled",
           label=f"{pooled.size} epochs, {N_NULL} runs")
ax[0].plot(xx, law.pdf(xx), "k", lw=1.2, label=r"$\chi^2_4$ (derived)")
ax[0].axvline(ad.metric_limit(4), color="C3", ls="--", label="99 % limit 13.28")
ax[0].set(xlabel="OCBE metric $M$ [-]", ylabel="probability density [-]", title=f"no maneuver: KS p = {ks_p:.2f}")
ax[0].legend()
srt = np.sort(pooled)
ax[1].plot(law.ppf((np.arange(srt.size) + 0.5) / srt.size), srt, ".", ms=3)
ax[1].plot([0, 20], [0, 20], "k", lw=0.8)
ax[1].set(xlabel=r"$\chi^2_4$ quantile [-]", ylabel="metric quantile [-]", xlim=(0, 20), ylim=(0, 20),
          title="Q-Q plot against the derived law")
_ = plotting.save_figure(fig, "09b_metric_law", output_dir=out)
print(f"pooled metric: mean {pooled.mean():.2f} (law 4, s.e. {np.sqrt(8 / pooled.size):.2f}), "
      f"exceeds the 99 % limit at {100 * exceed:.1f} % of epochs, KS p = {ks_p:.2f}; resets: {n_resets_null}; "
      f"mean NEES {nees0.mean():.2f} (6 if consistent)")
table.add_typed("OCBE metric law without mismodelling", "statistical metric, limit 99 % (law not stated)",
          f"chi2_4: mean {pooled.mean():.2f}, KS p = {ks_p:.2f}, {100 * exceed:.1f} % above the limit", "derived",
          "least-squares minimum = whitened SRI innovation; exact on linear systems (tests)")
_ = table.add_typed("Adaptive filter without a maneuver", "not stated (implied by the 99 % limit and three strikes)",
          f"{n_resets_null} resets in {N_NULL} runs", "derived" if n_resets_null == 0 else "differs: false resets",
          "derived false-reset probability < 1e-4 per track")

# %% [markdown]
# What the angle rates contribute matters below. With 10 micro-rad angles differenced 1 s apart (Eq. 13, notebook
# 09), the rate noise is $\sqrt2\cdot10\,\mu$rad/s, while a 10-km hand-off error changes the rates seen from L2 by
# far less. The ratio of the state-driven spread of each measurement to its noise, at the first epoch:

# %%
val, _, Ht = sc.model.evaluate(setup.observer_states[0][None], sc.x_start)
spread = np.sqrt(np.diag(Ht[0] @ draws[0].P0 @ Ht[0].T) / np.diag(sc.meas_cov))
print("state-driven spread / noise: az %.2g, el %.2g, az-rate %.2g, el-rate %.2g" % tuple(spread))
print("rate noise / state-driven spread: az-rate 10^%.1f, el-rate 10^%.1f" % tuple(-np.log10(spread[2:])))

# %% [markdown]
# The rates' noise exceeds what the state error puts into them by about four orders of magnitude (the exponents
# printed above; the ratios are set by the hand-off covariance, so they are the same in both modes): in this
# scenario the filter is effectively angles-only plus two pure-noise components
# (notebook 09 discusses what that means for the paper's observation-strategy claim). For the metric this is
# harmless (it is still $\chi^2_4$), but it matters for the reset.
#
# ## 2 · Detection and reset
#
# When $M_k, M_{k+1}, M_{k+2}$ all exceed the limit, a maneuver is declared at epoch $k$ (once $k+2$ is
# processed). The reset multiplies the control weight $q_{k-1}$ of the interval ending at $t_k$ by the factor
# $\alpha$ that makes $M_k(\alpha) = 4$. The OCBE reference has zero costate, so $\Phi_{xx}$ does not depend on
# $q$ and $Q$ is linear in it: $M_k(\alpha)$ is a time update with $\alpha Q$ and a measurement update in SRI
# form, no re-propagation; it decreases monotonically and is solved in $\log\alpha$. The filter and smoother are
# re-run with the new weight (epochs before $k$ unchanged) and the search resumes at $k+1$.
#
# **Where the literal rule breaks.** The two rate components hold pure noise whatever $\alpha$ is. When their
# whitened noise alone exceeds the mean 4 (for two $\chi^2_1$ components, probability $e^{-2} = 13.5$ %), no
# reasonable $\alpha$ brings $M_k$ to 4 and the rule drives $\alpha$ up by many orders of magnitude (a velocity
# uncertainty of km/s), after which the linearised filter diverges through a chain of further resets.
# `cislunar.estimation.adaptive_ocbe` therefore also offers `reset="likelihood"`: the $\alpha$ that maximises the Gaussian
# likelihood of the innovation (covariance matching), which inflates only as far as the explainable part of the
# innovation asks. Figs. 6-9 use the paper's rule; Section 4 compares the two.

# %%
def run_adaptive(inputs, reset="mean", smooth=True):
    return ad.adaptive_ocbe(em, sc.t, inputs.y, setup.observer_states, sc.model, sc.meas_cov, inputs.x0,
                            inputs.P0, setup.control_weight, reset=reset, smooth=smooth, max_resets=MAX_RESETS)


def panels_of(a, inputs):
    """The Figs. 6-9 panel series of an adaptive run (cislunar.papers.greaves_scheeres_2021.panels.panel_series)."""
    return ocbe_panels.panel_series(em, a.result, inputs.truth, a.control_weight, inputs.y, setup.observer_states, sc.model,
                           sc.meas_cov)


def error_panels(a, panels, title):
    """Fig. 6/8 layout: position (top) and velocity (bottom) error norms and 3-sigma, forward (left), smoothed."""
    return ocbe_panels.figure_errors(panels, title, burn_days=setup.t_maneuver / DAY,
                            detection_days=[d.time / DAY for d in a.detections])


def control_metric_panels(a, panels, title):
    """Fig. 7/9 layout: control norm (top) and normalised metric (bottom), forward (left) and smoothed (right);
    crosses: what the online filter saw before the first reset (its three strikes)."""
    first = a.detections[0].declared_epoch if a.detections else None
    return ocbe_panels.figure_control_metric(panels, title, burn_days=setup.t_maneuver / DAY,
                                    detection_days=[d.time / DAY for d in a.detections],
                                    first_pass_metric=a.metric_first_pass if a.detections else None,
                                    first_pass_until=first)


def describe(a, inputs):
    r = a.result
    nf = consistency.nees(r.x_filt, r.P_filt, inputs.truth)
    ns = consistency.nees(r.x_smooth, r.P_smooth, inputs.truth)
    lim = stats.chi2.ppf(consistency.NEES_PROBABILITY, 6)
    return dict(nees_f_after=float(np.mean(nf[k_burn:] > lim)), nees_s=float(np.mean(ns > lim)),
                err_final_km=float(np.linalg.norm(r.x_filt[-1, :3] - inputs.truth[-1, :3]) * L_KM))


# %% [markdown]
# ## 3 · A 3 m/s burn at apoapsis (Figs. 6-7)
#
# The track starts at periapsis with the Earth-radar hand-off (10 km, 10 cm/s, 3 sigma), so the filter has half a
# period to shrink its uncertainty before the burn; the burn direction is drawn as in notebook 10 (Eqs. 3-4).

# %%
big = det.draw_trial(rng, setup, magnitude_m_s=3.0)
a_big = run_adaptive(big)
d_big = describe(a_big, big)
first = a_big.detections[0] if a_big.detections else None
for d in a_big.detections:
    print(f"detected at epoch {d.epoch} ({(d.epoch - k_burn) * sc.cadence_hours:.0f} h after the first epoch that sees "
          f"the burn), declared at epoch {d.declared_epoch}; metric {d.metric_before:.1f} -> {d.metric_after:.2f}; "
          f"control weight x {d.factor:.3g}")
print(f"after the reset: {100 * d_big['nees_f_after']:.0f} % of forward epochs and {100 * d_big['nees_s']:.0f} % of "
      f"smoothed epochs have NEES above the 99.9 % chi2_6 quantile; final position error "
      f"{d_big['err_final_km']:.2f} km")
p_big = panels_of(a_big, big)
_ = plotting.save_figure(error_panels(a_big, p_big, "3 m/s"), "09b_fig6_adaptive_3ms_errors", output_dir=out)

# %%
_ = plotting.save_figure(control_metric_panels(a_big, p_big, "3 m/s"), "09b_fig7_adaptive_3ms_control_metric",
                         output_dir=out)

# %% [markdown]
# As in the paper, the forward uncertainty jumps at the burn and the estimate stays inside it; the control
# estimate spikes at the burn in both passes; the forward metric's outlier is set to its mean by the reset. In
# the smoothed metric (control + measurement terms with the smoothed estimates; its per-epoch law is not
# $\chi^2_4$ but its epoch average is 4, the batch least-squares identity) the burn epoch is not an outlier.

# %% [markdown]
# ## 4 · A 50 mm/s burn (Figs. 8-9): late detection

# %%
small = det.draw_trial(rng, setup, magnitude_m_s=0.05)
a_small = run_adaptive(small)
d_small = describe(a_small, small)
if a_small.detections:
    d = a_small.detections[0]
    print(f"50 mm/s: detected at epoch {d.epoch}, {(d.epoch - k_burn) * sc.cadence_hours:.0f} h after the burn "
          f"({(nrho.period - d.time) / DAY:.2f} d before the next periapsis)")
else:
    print("50 mm/s: not detected within the period")
print(f"forward epochs after the burn above NEES 99.9 %: {100 * d_small['nees_f_after']:.0f} %; final position error "
      f"{d_small['err_final_km']:.2f} km")
p_small = panels_of(a_small, small)
_ = plotting.save_figure(error_panels(a_small, p_small, "50 mm/s"), "09b_fig8_adaptive_50mms_errors", output_dir=out)

# %%
_ = plotting.save_figure(control_metric_panels(a_small, p_small, "50 mm/s"), "09b_fig9_adaptive_50mms_control_metric",
                         output_dir=out)

# %% [markdown]
# The same data with the likelihood reset (Section 2). The detection is the same under both rules (it comes before
# the first reset); what differs is the inflation factor and so the filter after it. The printed lines give, for
# this run, each rule's resets and factors and whether its final estimate is consistent (final NEES below the
# 99.9 % quantile). In the full run both rules inflate the control weight by many orders of magnitude at the first
# reset (presumably because a burn detected this late has left an error that only a large inflation explains); the
# paper's rule inflates far more (the ratio of the first factors is printed) and then needs a chain of further
# resets, the likelihood rule resets once. Rate noise above the mean (Section 2) is a likely reason for the
# difference; this run does not isolate it.

# %%
a_small_ml = run_adaptive(small, reset="likelihood")
d_small_ml = describe(a_small_ml, small)
lim_nees = stats.chi2.ppf(consistency.NEES_PROBABILITY, 6)
final_nees = {rule: float(consistency.nees(a_.result.x_filt[-1], a_.result.P_filt[-1], small.truth[-1]))
              for rule, a_ in (("mean", a_small), ("likelihood", a_small_ml))}
for rule, a_ in (("mean", a_small), ("likelihood", a_small_ml)):
    print(f"{rule:10s} rule: resets at epochs {[d.epoch for d in a_.detections]}, factors "
          f"{[f'{d.factor:.2g}' for d in a_.detections]}; final forward NEES {final_nees[rule]:.1f} "
          f"(99.9 % quantile {lim_nees:.1f})")
if a_small.detections and a_small_ml.detections:
    print(f"first reset factor, paper's rule over likelihood rule: "
          f"{a_small.detections[0].factor / a_small_ml.detections[0].factor:.1e}")
_ = plotting.save_figure(error_panels(a_small_ml, panels_of(a_small_ml, small), "50 mm/s, likelihood reset"),
                         "09b_fig8_adaptive_50mms_errors_likelihood_reset", output_dir=out)

# %% [markdown]
# ## 5 · Why the paper moves to windowed tuning, with numbers
#
# One run per size proves little. We first measure *when* a burn is detected, over burn sizes from 50 mm/s to
# 3 m/s (random pointing, independent noise and hand-off per run). Until its first reset the adaptive filter is
# the plain OCBE with the ballistic tuning, so its first detection does not depend on the reset rule, and one
# batched pass per burn size gives it for many runs (`adaptive_ocbe.first_pass_detections`). The delay counts
# the epochs after the first epoch that sees the burn (one epoch is 2 h). Each run falls into one of four
# outcomes, defined before looking at the results:
#
# * **prompt**: dated within two epochs of the first epoch that sees the burn (the three-epoch window that a
#   large burn needs; a chance exceedance, probability 1 %, just before a large burn dates it one epoch early:
#   the "early" column below counts those);
# * **late**: later, but before the last quarter of the coast from the burn to the next periapsis;
# * **nearly periapsis**: within that last quarter, i.e. within $T/8$ (20 h on the 9:2 NRHO) of the periapsis
#   (our reading of the caption of Fig. 8, "doesn't catch the deviation until nearly periapsis");
# * **not detected** within the period.
#
# The paper's angular noise (its Table 3) is missing, and the delay of a small burn depends on it; so at 50 mm/s we
# also sweep the angle noise (with the rate noise following Eq. 13).

# %%
OUTCOMES = ("prompt", "late", "nearly periapsis", "not detected")
coast = nrho.period - setup.t_maneuver  # burn to the next periapsis, TU
late_from = setup.t_maneuver + 0.75 * coast  # start of the last quarter of the coast, TU
print(f"coast from the burn to periapsis {coast / DAY * 24:.1f} h; 'nearly periapsis' from "
      f"{(late_from - setup.t_maneuver) / DAY * 24:.1f} h after the burn")


def first_epochs(setup_, mag, n):
    """First detection epoch (-1: none) of n runs with a burn of ``mag`` m/s, from one batched pass."""
    draws_ = [det.draw_trial(rng, setup_, magnitude_m_s=mag) for _ in range(n)]
    sc_ = setup_.scenario
    return ad.first_pass_detections(em, sc_.t, np.array([d.y for d in draws_]), setup_.observer_states, sc_.model,
                                    sc_.meas_cov, np.array([d.x0 for d in draws_]), draws_[0].P0,
                                    setup_.control_weight)


def outcomes(epochs):
    """Fraction of runs per outcome, delays of the detected runs [h], and false alarms.

    A detection dated up to two epochs before the first epoch that sees the burn is prompt too: a chance
    exceedance (1 %) just before a large burn starts the three-epoch run one epoch early.  Earlier than that it is
    a false alarm (probability about 1e-4 per track)."""
    ep = np.asarray(epochs)
    found = ep >= k_burn - (ad.CONSECUTIVE_EPOCHS - 1)
    t_found = sc.t[np.where(found, ep, 0)]
    prompt = found & (np.abs(ep - k_burn) <= ad.CONSECUTIVE_EPOCHS - 1)
    near = found & (t_found >= late_from)
    delays = (ep[found] - k_burn) * sc.cadence_hours
    return dict(n=ep.size, prompt=np.mean(prompt), late=np.mean(found & ~prompt & ~near), near=np.mean(near),
                undetected=np.mean(ep < 0), false_alarms=int(np.sum((ep >= 0) & ~found)),
                early_by_chance=int(np.sum(found & (ep < k_burn))), delays_h=delays,
                median_h=float(np.median(delays)) if delays.size else np.nan)


t_delay = time.perf_counter()
by_size = {mag: outcomes(first_epochs(setup, mag, N_DELAY)) for mag in MAGNITUDES_M_S}
by_noise = {}
for s_urad in NOISE_SWEEP_URAD:
    if s_urad == 10:  # the default noise: the 50 mm/s runs above
        by_noise[s_urad] = by_size[0.05]
        continue
    setup_s = det.make_setup(em, nrho, Q_BASE_KM2_S3, Q_BASE_KM2_S3, sigma_angle_rad=s_urad * 1e-6)
    by_noise[s_urad] = outcomes(first_epochs(setup_s, 0.05, N_DELAY))
print(f"{N_DELAY} runs per burn size and noise level in {time.perf_counter() - t_delay:.0f} s; one run is "
      f"{100 / N_DELAY:.1f} % of an outcome bar")


def print_outcomes(label, o):
    q = np.percentile(o["delays_h"], [25, 75]) if o["delays_h"].size else (np.nan, np.nan)
    print(f"{label:>16} {100 * o['prompt']:7.0f}% {100 * o['late']:6.0f}% {100 * o['near']:9.0f}% "
          f"{100 * o['undetected']:9.0f}% {o['median_h']:8.0f} h  [{q[0]:3.0f}, {q[1]:3.0f}] h  "
          f"{o['early_by_chance']:5d} {o['false_alarms']:5d}")


print(f"{'':>16} {'prompt':>8} {'late':>7} {'near peri.':>10} {'not det.':>10} {'median':>10}  {'quartiles':>12} "
      f"{'early':>5} {'false':>5}")
for mag, o in by_size.items():
    print_outcomes(f"{mag * 1e3:g} mm/s", o)
for s_urad, o in by_noise.items():
    print_outcomes(f"50 mm/s {s_urad:g} urad", o)
best_noise = max(by_noise, key=lambda s_: by_noise[s_]["near"])
print(f"50 mm/s: 'nearly periapsis' is largest at {best_noise:g} urad, {100 * by_noise[best_noise]['near']:.0f} % of "
      f"runs; not detected there: {100 * by_noise[best_noise]['undetected']:.0f} %")

# %%
colors = {"prompt": "C0", "late": "C3", "nearly periapsis": "C1", "not detected": "0.6"}
keys = {"prompt": "prompt", "late": "late", "nearly periapsis": "near", "not detected": "undetected"}
fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
mm = np.array(MAGNITUDES_M_S) * 1e3
med = [by_size[m]["median_h"] for m in MAGNITUDES_M_S]
q25 = [np.percentile(by_size[m]["delays_h"], 25) if by_size[m]["delays_h"].size else np.nan for m in MAGNITUDES_M_S]
q75 = [np.percentile(by_size[m]["delays_h"], 75) if by_size[m]["delays_h"].size else np.nan for m in MAGNITUDES_M_S]
ax[0].fill_between(mm, q25, q75, color="C0", alpha=0.2, label="25-75 % of detected runs")
ax[0].plot(mm, med, "C0o-", label="median of detected runs")
ax[0].axhline((late_from - setup.t_maneuver) / DAY * 24, color="C1", ls="--", lw=1,
              label="'nearly periapsis' above this line")
ax[0].set(xscale="log", xlabel="burn size [mm/s]", ylabel="detection delay [h]",
          title=f"delay after the burn ({N_DELAY} runs per size)")
ax[0].legend(loc="center right", fontsize=8)
for j, (groups, labels, title, xlabel) in enumerate((
        (list(by_size.values()), [f"{m:g}" for m in mm], "outcome versus burn size (10 urad)", "burn size [mm/s]"),
        (list(by_noise.values()), [f"{s:g}" for s in NOISE_SWEEP_URAD], "50 mm/s burn: outcome versus angle noise",
         "angle noise (1 sigma) [urad]"))):
    bottom = np.zeros(len(groups))
    for name in OUTCOMES:
        frac = 100 * np.array([g[keys[name]] for g in groups])
        ax[j + 1].bar(labels, frac, bottom=bottom, color=colors[name], label=name, width=0.6)
        bottom += frac
    ax[j + 1].set(ylabel="runs [%]", ylim=(0, 100), title=title, xlabel=xlabel)
handles, labels = ax[1].get_legend_handles_labels()
fig.legend(handles, labels, loc="lower center", ncol=4, bbox_to_anchor=(0.5, 0.0))
fig.tight_layout(rect=(0, 0.07, 1, 1))
_ = plotting.save_figure(fig, "09b_adaptive_delay_vs_burn", output_dir=out)

# %% [markdown]
# **Reading the delays** (the table above is this run's; the stacked bars are its outcome fractions, and one run is
# the share of a bar printed above, half a percent in the full run, so a fraction of a few percent is a handful of
# runs). Burns of 1 m/s and more are caught at once: the first epoch that sees them already has a metric far above
# the limit. Below a few hundred mm/s the burn moves the measurements by little more than their noise for many
# epochs, and the detection comes only when the error has grown along the coast towards periapsis, where the
# dynamics amplify it. At 50 mm/s the outcome is spread: some runs are caught a day or two after the burn, some in
# the last quarter before periapsis (like the paper's Fig. 8 run), many not within the period at all. More angle
# noise delays the detection further: runs move from "late" to "nearly periapsis" and, above all, to "not detected",
# so the "nearly periapsis" fraction peaks at an intermediate noise (the line printed above) and is never the
# typical outcome. The paper's single 50 mm/s run is therefore one of the possible outcomes, not the typical one.
#
# ### The reset rules after the detection
#
# Whether the filter is right after the detection does depend on the reset rule. We rerun the single-trial
# adaptive filter (forward pass) over the same burn sizes with both rules and record, per run, whether it was
# inconsistent after the burn (more than 5 % of epochs above the 99.9 % NEES quantile, the criterion of notebook
# 09), whether its final estimate is consistent (final NEES below that quantile: the filter has re-converged),
# and how many resets it made. A run that needs more than five resets, or that fails numerically, counts as
# diverged. In the figure the likelihood rule (dashed line, open squares) is drawn over the paper's rule (solid
# line, filled circles), so where the two give the same fraction the square sits on the circle; the line printed
# under the table lists the burn sizes where they do.

# %%
rows = []
lim_nees = stats.chi2.ppf(consistency.NEES_PROBABILITY, 6)
t_mc = time.perf_counter()
for mag in MAGNITUDES_M_S:
    for i in range(N_PER_MAGNITUDE):
        inputs = det.draw_trial(rng, setup, magnitude_m_s=mag)
        for rule in ad.RESET_RULES:
            try:
                a = run_adaptive(inputs, reset=rule, smooth=False)
            except (ad.ResetError, ocbe.FilterDivergenceError):
                rows.append((mag, rule, True, 1.0, True, MAX_RESETS + 1, False))
                continue
            nf = consistency.nees(a.result.x_filt, a.result.P_filt, inputs.truth)
            frac = float(np.mean(nf[k_burn:] > lim_nees))
            rows.append((mag, rule, bool(a.detections), frac, frac > tracking.DIVERGED_FRACTION, len(a.detections),
                         bool(nf[-1] < lim_nees)))
print(f"{len(rows)} adaptive runs in {time.perf_counter() - t_mc:.0f} s")


def summary(mag, rule):
    sel = [r for r in rows if r[0] == mag and r[1] == rule]
    found = [r for r in sel if r[2]]
    return dict(n=len(sel), n_detected=len(found), inconsistent=float(np.mean([r[4] for r in sel])),
                resets=float(np.mean([r[5] for r in sel])), chains=sum(r[5] > 1 for r in found),
                final_ok=float(np.mean([r[6] for r in found])) if found else np.nan)


print(f"{'burn':>8} {'rule':>10} {'inconsistent':>12} {'resets':>6} {'chains':>6} {'final NEES ok (detected)':>25}")
for mag in MAGNITUDES_M_S:
    for rule in ad.RESET_RULES:
        s_ = summary(mag, rule)
        print(f"{mag * 1e3:6.0f}mm/s {rule:>10} {100 * s_['inconsistent']:11.0f}% {s_['resets']:6.1f} "
              f"{s_['chains']:3d}/{s_['n_detected']:<2d} {100 * s_['final_ok']:20.0f}%")

fig, ax = plt.subplots(1, 2, figsize=(11, 4))
for j, rule in enumerate(ad.RESET_RULES):
    S = [summary(m, rule) for m in MAGNITUDES_M_S]
    sty = dict(color=f"C{j}", ls="-" if j == 0 else "--", marker="o" if j == 0 else "s", ms=8 if j == 0 else 5,
               mfc="none" if j else None, label=f"{rule} rule")
    ax[0].plot(mm, [100 * s_["inconsistent"] for s_ in S], **sty)
    ax[1].plot(mm, [100 * s_["final_ok"] for s_ in S], **sty)
ax[0].set(xscale="log", xlabel="burn size [mm/s]", ylabel="runs [%]", ylim=(-5, 105),
          title="inconsistent after the burn (NEES)")
ax[1].set(xscale="log", xlabel="burn size [mm/s]", ylabel="detected runs [%]", ylim=(-5, 105),
          title="final estimate consistent (re-converged)")
handles, labels = ax[0].get_legend_handles_labels()
fig.legend(handles, labels, loc="lower center", ncol=2, bbox_to_anchor=(0.5, 0.0))
fig.tight_layout(rect=(0, 0.08, 1, 1))
_ = plotting.save_figure(fig, "09b_adaptive_reset_rules", output_dir=out)
for key, what in (("inconsistent", "inconsistent after the burn"), ("final_ok", "final estimate consistent")):
    v = {rule: [summary(m, rule)[key] for m in MAGNITUDES_M_S] for rule in ad.RESET_RULES}
    same = [f"{m * 1e3:g}" for m, a_, b_ in zip(MAGNITUDES_M_S, v["mean"], v["likelihood"]) if np.isclose(a_, b_)]
    better = sum((b_ > a_) if key == "final_ok" else (b_ < a_) for a_, b_ in zip(v["mean"], v["likelihood"]))
    print(f"{what}: the two rules agree at {', '.join(same) or 'no'} mm/s; the likelihood rule does better at "
          f"{better} of {len(MAGNITUDES_M_S)} burn sizes")

# %%
s_small, s_small_ml = summary(MAGNITUDES_M_S[0], "mean"), summary(MAGNITUDES_M_S[0], "likelihood")
large = [m for m in MAGNITUDES_M_S if m >= 1.0]
print(f"50 mm/s (paper's rule): {100 * s_small['inconsistent']:.0f} % of runs inconsistent after the burn; of the "
      f"{s_small['n_detected']} detected, {100 * s_small['final_ok']:.0f} % end consistent "
      f"(likelihood rule {100 * s_small_ml['final_ok']:.0f} %)")
for m in large:
    print(f"{m:g} m/s: inconsistent after the burn, mean rule {100 * summary(m, 'mean')['inconsistent']:.0f} %, "
          f"likelihood rule {100 * summary(m, 'likelihood')['inconsistent']:.0f} %")
# the inconsistent large-burn runs of the paper's rule: how many went through a chain of resets?
bad_large = [r for r in rows if r[0] in large and r[1] == "mean" and r[4]]
chained_large = sum(r[5] > 1 for r in bad_large)
print(f"{'/'.join(f'{m:g}' for m in large)} m/s, paper's rule: {len(bad_large)} inconsistent runs, {chained_large} of "
      f"them with a chain of resets, {len(bad_large) - chained_large} with a single reset or none")

# %% [markdown]
# **Reading.** The numbers above make the argument of the paper's "Adaptive OCBE Tuning" section quantitative (the
# sentences describe the full run: 200 runs per size for the delays, 20 per size and rule for the resets; quick mode
# runs 8 and 2). A large burn is detected at once, and one reset usually restores a consistent filter, as in
# Figs. 6-7; with the paper's rule not always, though (the printed lines above). Some of the inconsistent runs fell
# into a chain of resets (Section 2; the last line above counts them); for the others we have a likely reason that
# we did not measure: a reset is sized on the innovation of the first epoch after the burn, which can be small when
# the burn has barely shown in the angles yet, so the inflation then falls short. A 50 mm/s burn is detected late or
# not at all, and the filter is inconsistent from the burn until the detection (the first column of the table
# above). Because NRHO station keeping is tens of mm/s per revolution (the paper's quiet policy), an adaptive filter
# would spend much of every orbit inconsistent; the windowed tuning of notebook 10 instead raises the control
# uncertainty where burns happen (8 h around apoapsis), so the estimate stays consistent and the maneuver shows up
# afterwards in the smoothed control.
#
# The comparison of the two reset rules is beyond the paper. With the paper's rule some runs diverge after the
# detection through a chain of resets (the "chains" column), most likely for the reason given in Section 2 (rate
# noise that no reasonable inflation can explain): the share of detections that chain is close to the $e^{-2}$ that
# mechanism predicts (printed with the closing table). The likelihood rule avoids most of those failures, and
# detection does not depend on the rule until the first reset. In the figure the two rules agree only at the
# smallest burns (the sizes printed under the table), where both leave every run inconsistent because those burns
# are detected late, and never in the re-convergence panel, where the likelihood rule ends consistent more often at
# every size. Neither rule cures late detection: a reset inflates one 2-hour interval, while the error of a burn
# detected a day or two late has grown along the whole arc since, so after a late detection the filter often stays
# over-confident to the end (the last column; compare the two rules' final NEES on the Fig. 8 run above).

# %%
# Criteria below were fixed before the comparison: "prompt" and "nearly periapsis" as defined in Section 5, the
# 10 % flag of notebook 09 for consistency, and "most runs" for the paper's single-run statements.
o_small = by_size[MAGNITUDES_M_S[0]]
table.add_typed("3 m/s burn (Fig. 6 run): detected promptly (within two epochs of the burn)", "detected, uncertainty raised at the burn (Fig. 6)",
          f"epoch +{first.epoch - k_burn}" if first else "not detected",
          "reproduced" if first is not None and first.epoch - k_burn <= 2 else "differs: late or no detection",
          "criterion: dated within two epochs of the first epoch that sees the burn")
table.add_typed("3 m/s burn (Fig. 6 run): forward filter consistent after the reset", "consistent (Fig. 6)",
          f"{100 * d_big['nees_f_after']:.0f} % of epochs above NEES 99.9 %",
          "reproduced" if d_big["nees_f_after"] <= tracking.DIVERGED_FRACTION else "differs: inconsistent",
          "criterion: at most 5 % of epochs above the quantile (notebook 09's divergence test)")
o_large = [by_size[m] for m in large]
n_large = sum(o["n"] for o in o_large)
prompt_large = sum(o["prompt"] * o["n"] for o in o_large) / n_large
sizes = "/".join(f"{m:g}" for m in large)
table.add_typed(f"Burns of {sizes} m/s detected at once", "'near optimal' above 1 m/s",
          f"prompt in {100 * prompt_large:.1f} % of {n_large} runs ("
          + ", ".join(f"{m:g} m/s {100 * o['prompt']:.1f} %" for m, o in zip(large, o_large)) + ")",
          "reproduced" if prompt_large >= 0.95 else "differs: some large burns are detected late",
          "criterion: at least 95 % of runs prompt (dated within two epochs of the burn)")
s_large = {rule: [summary(m, rule) for m in large] for rule in ad.RESET_RULES}
incons_large = {rule: sum(x["inconsistent"] * x["n"] for x in v) / sum(x["n"] for x in v)
                for rule, v in s_large.items()}
n_rules_large = sum(x["n"] for x in s_large["mean"])
table.add_typed(f"Burns of {sizes} m/s: filter consistent after the reset", "'near optimal' above 1 m/s",
          f"{100 * incons_large['mean']:.0f} % of {n_rules_large} runs inconsistent after the burn ("
          + ", ".join(f"{m:g} m/s {100 * x['inconsistent']:.0f} %" for m, x in zip(large, s_large["mean"]))
          + f"); likelihood rule {100 * incons_large['likelihood']:.0f} %",
          "reproduced" if incons_large["mean"] <= 0.10 else
          "differs: the paper's reset rule leaves some runs inconsistent",
          f"criterion: at most 10 % of runs inconsistent (notebook 09's flag; s.e. about "
          f"{100 * np.sqrt(0.1 * 0.9 / max(n_rules_large, 1)):.0f} %); mean rule, reset read as a raised control "
          f"weight on one interval; of the {len(bad_large)} inconsistent runs {chained_large} went through a chain of "
          "resets (measured); for the others a likely cause, not measured: a reset sized on a first innovation that "
          "barely shows the burn")
table.add_typed("50 mm/s burn: detection late (Figs. 8-9)", "late",
          f"prompt in {100 * o_small['prompt']:.0f} % of {o_small['n']} runs; median delay of the detected "
          f"{o_small['median_h']:.0f} h; {100 * o_small['undetected']:.0f} % not detected in the period",
          "reproduced" if o_small["prompt"] < 0.5 else "differs: most runs detected promptly",
          "criterion: most runs not prompt; 10 urad angles")
table.add_typed("50 mm/s burn: detected 'nearly periapsis' (Fig. 8 caption)", "nearly periapsis (one run)",
          f"{100 * o_small['near']:.0f} % of runs at 10 urad; at most {100 * by_noise[best_noise]['near']:.0f} % over "
          f"{min(NOISE_SWEEP_URAD):g}-{max(NOISE_SWEEP_URAD):g} urad (at {best_noise:g} urad)",
          "reproduced" if o_small["near"] > 0.5 else
          "differs: a possible but not the typical outcome at any angle noise",
          "criterion: most runs detected in the last quarter of the coast (within T/8 of periapsis); more noise "
          "turns late detections into misses")
table.add_typed("50 mm/s: filter re-converges after the late detection (Fig. 8)", "re-converges",
          f"final NEES consistent in {100 * s_small['final_ok']:.0f} % of {s_small['n_detected']} detected runs "
          f"(likelihood rule {100 * s_small_ml['final_ok']:.0f} %)",
          "reproduced" if s_small["final_ok"] >= 0.9 else
          "differs: after a late detection the filter often stays inconsistent",
          "criterion: at least 90 % of detected runs end with NEES below its 99.9 % quantile (paper's rule)")
table.add_typed("Filter inconsistent while a small burn is undetected", "implied (reason to move to windowed tuning)",
          "runs inconsistent after the burn: "
          + "; ".join(f"{m * 1e3:g} mm/s {100 * summary(m, 'mean')['inconsistent']:.0f} %"
                      for m in MAGNITUDES_M_S if m < 1.0), "derived", "NEES criterion of notebook 09")
chain = {rule: (sum(summary(m, rule)["chains"] for m in MAGNITUDES_M_S),
                sum(summary(m, rule)["n_detected"] for m in MAGNITUDES_M_S)) for rule in ad.RESET_RULES}
print("detected runs needing more than one reset (a divergence chain): "
      + ", ".join(f"{r} rule {c[0]}/{c[1]} ({100 * c[0] / max(c[1], 1):.0f} %)" for r, c in chain.items())
      + f"; Section 2's mechanism predicts about {100 * np.exp(-2):.1f} % for the paper's (mean) rule")
table.add_typed("Reset rule 'metric equal to its mean' breaks when rate noise exceeds it", "not discussed",
          "detected runs with a chain of resets: " + ", ".join(f"{r} rule {c[0]}/{c[1]}" for r, c in chain.items()),
          "beyond paper", "angle rates carry no state information here, so their noise exceeds the mean with "
          "probability e^-2 per detection (derived, Section 2); chains counted, their cause not isolated run by run")
table.add_typed("Base (ballistic) control weight", "not given", f"{Q_BASE_KM2_S3:g} km^2/s^3", "not in paper",
          "our choice: notebook 10's q outside the apoapsis window; the law of the metric does not depend on it")
print(f"notebook wall time: {(time.perf_counter() - T_START) / 60:.1f} min")
table.display()
