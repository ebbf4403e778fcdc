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
# `cislunar.ocbe` (notebook 09); the adaptive logic is `cislunar.adaptive_ocbe`; the scenario (L2 observer,
# angles and angle rates every 2 hours, Earth-radar hand-off at periapsis, burn at apoapsis) is
# `cislunar.tracking` / `cislunar.detection` (notebook 10).

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: quick mode shrinks the Monte Carlo samples, never skips an experiment.
N_NULL = 4 if QUICK else 16  # no-maneuver runs for the metric's law (batched OCBE, one period each)
MAGNITUDES_M_S = [0.05, 0.3, 3.0] if QUICK else [0.05, 0.1, 0.3, 1.0, 3.0]  # burn sizes of the delay study
N_PER_MAGNITUDE = 2 if QUICK else 10  # burns per size and reset rule
Q_BASE_KM2_S3 = 1e-18  # the ballistic tuning (notebook 10's q outside the apoapsis window)
MAX_RESETS = 5  # a run needing more resets than this is counted as diverged

import time

import matplotlib.pyplot as plt
import numpy as np
from scipy import stats

from cislunar import adaptive_ocbe as ad
from cislunar import detection as det
from cislunar import ocbe, orbits, plotting, tracking
from cislunar.dynamics import EARTH_MOON as em
from cislunar.report import ComparisonTable

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
# `tests/test_adaptive_ocbe.py` checks the three-term identity and the $\chi^2_m$ law exactly on linear systems
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
nees0 = np.array([tracking.nees(res0.x_filt[b], res0.P_filt[b], draws[b].truth) for b in range(N_NULL)])
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
table.add("OCBE metric law without mismodelling", "statistical metric, limit 99 % (law not stated)",
          f"chi2_4: mean {pooled.mean():.2f}, KS p = {ks_p:.2f}, {100 * exceed:.1f} % above the limit", "derived",
          "least-squares minimum = whitened SRI innovation; exact on linear systems (tests)")
_ = table.add("Adaptive filter without a maneuver", "not stated (implied by the 99 % limit and three strikes)",
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

# %% [markdown]
# The rates are noise by four to five orders of magnitude (the ratios above, set by the hand-off covariance, are
# the same in both modes): in this scenario the filter is effectively angles-only plus two pure-noise components
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
# uncertainty of km/s), after which the linearised filter diverges through a chain of further resets. The package
# therefore also offers `reset="likelihood"`: the $\alpha$ that maximises the Gaussian likelihood of the
# innovation (covariance matching), which inflates only as far as the explainable part of the innovation asks.
# Figs. 6-9 use the paper's rule; Section 4 compares the two.

# %%
def run_adaptive(inputs, reset="mean", smooth=True):
    return ad.adaptive_ocbe(em, sc.t, inputs.y, setup.observer_states, sc.model, sc.meas_cov, inputs.x0,
                            inputs.P0, setup.control_weight, reset=reset, smooth=smooth, max_resets=MAX_RESETS)


def panels_of(a, inputs):
    """The Figs. 6-9 panel series of an adaptive run (cislunar.adaptive_ocbe.panel_series)."""
    return ad.panel_series(em, a.result, inputs.truth, a.control_weight, inputs.y, setup.observer_states, sc.model,
                           sc.meas_cov)


def error_panels(a, panels, title):
    """Fig. 6/8 layout: position (top) and velocity (bottom) error norms and 3-sigma, forward (left), smoothed."""
    return ad.figure_errors(panels, title, burn_days=setup.t_maneuver / DAY,
                            detection_days=[d.time / DAY for d in a.detections])


def control_metric_panels(a, panels, title):
    """Fig. 7/9 layout: control norm (top) and normalised metric (bottom), forward (left) and smoothed (right);
    crosses: what the online filter saw before the first reset (its three strikes)."""
    first = a.detections[0].declared_epoch if a.detections else None
    return ad.figure_control_metric(panels, title, burn_days=setup.t_maneuver / DAY,
                                    detection_days=[d.time / DAY for d in a.detections],
                                    first_pass_metric=a.metric_first_pass if a.detections else None,
                                    first_pass_until=first)


def describe(a, inputs):
    r = a.result
    nf = tracking.nees(r.x_filt, r.P_filt, inputs.truth)
    ns = tracking.nees(r.x_smooth, r.P_smooth, inputs.truth)
    lim = stats.chi2.ppf(tracking.NEES_PROBABILITY, 6)
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
for d in a_big.detections:
    print(f"detected at epoch {d.epoch} ({(d.epoch - k_burn) * sc.cadence_hours:.0f} h after the first epoch that sees "
          f"the burn), declared at epoch {d.declared_epoch}; metric {d.metric_before:.1f} -> {d.metric_after:.2f}; "
          f"control weight x {d.factor:.3g}")
print(f"after the reset: {100 * d_big['nees_f_after']:.0f} % of forward epochs and {100 * d_big['nees_s']:.0f} % of "
      f"smoothed epochs have NEES above the 99.9 % chi2_6 quantile; final position error {d_big['err_final_km']:.2f} km")
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

# %%
n_det = len(a_big.detections)
first = a_big.detections[0] if n_det else None
table.add("3 m/s burn: detected within three epochs", "detected, uncertainty raised at the burn (Fig. 6)",
          f"epoch +{first.epoch - k_burn}" if first else "not detected",
          "reproduced" if first is not None and first.epoch - k_burn <= 2 else "differs: late or no detection")
_ = table.add("3 m/s burn: forward filter consistent after the reset", "consistent (Fig. 6)",
          f"{100 * d_big['nees_f_after']:.0f} % of epochs above NEES 99.9 %",
          "reproduced" if d_big["nees_f_after"] <= tracking.DIVERGED_FRACTION else "differs: inconsistent")

# %% [markdown]
# ## 4 · A 50 mm/s burn (Figs. 8-9): late detection

# %%
small = det.draw_trial(rng, setup, magnitude_m_s=0.05)
a_small = run_adaptive(small)
d_small = describe(a_small, small)
if a_small.detections:
    d = a_small.detections[0]
    print(f"50 mm/s: detected at epoch {d.epoch}, {(d.epoch - k_burn) * sc.cadence_hours:.0f} h after the burn "
          f"({(sc.t[-1] - d.time) / DAY:.2f} d before the next periapsis)")
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
# The same data with the likelihood reset (Section 2). Where the paper's rule needed a single reset the two runs
# are identical; where its reset met rate noise above the mean, the paper's rule inflated the control weight by
# many orders of magnitude and the filter did not recover.

# %%
a_small_ml = run_adaptive(small, reset="likelihood")
d_small_ml = describe(a_small_ml, small)
lim_nees = stats.chi2.ppf(tracking.NEES_PROBABILITY, 6)
final_nees = {rule: float(tracking.nees(a_.result.x_filt[-1], a_.result.P_filt[-1], small.truth[-1]))
              for rule, a_ in (("mean", a_small), ("likelihood", a_small_ml))}
for rule, a_ in (("mean", a_small), ("likelihood", a_small_ml)):
    print(f"{rule:10s} rule: resets at epochs {[d.epoch for d in a_.detections]}, factors "
          f"{[f'{d.factor:.2g}' for d in a_.detections]}; final forward NEES {final_nees[rule]:.1f} "
          f"(99.9 % quantile {lim_nees:.1f})")
_ = plotting.save_figure(error_panels(a_small_ml, panels_of(a_small_ml, small), "50 mm/s, likelihood reset"),
                         "09b_fig8_adaptive_50mms_errors_likelihood_reset", output_dir=out)

# %% [markdown]
# ## 5 · Why the paper moves to windowed tuning, with numbers
#
# One run per size proves little, so we repeat the experiment over burn sizes from 50 mm/s to 3 m/s (random
# pointing, independent noise and hand-off per run) with both reset rules, on the single-trial filter (forward
# pass only). For each run we record the detection delay (epochs after the first epoch that sees the burn; one
# epoch is 2 h), whether the burn went undetected within the period, and whether the filter was inconsistent
# after the burn (more than 5 % of epochs above the 99.9 % NEES quantile, the criterion of notebook 09). A run
# that needs more than five resets, or that fails numerically, counts as diverged.

# %%
rows = []
t_mc = time.perf_counter()
for mag in MAGNITUDES_M_S:
    for i in range(N_PER_MAGNITUDE):
        inputs = det.draw_trial(rng, setup, magnitude_m_s=mag)
        for rule in ad.RESET_RULES:
            try:
                a = run_adaptive(inputs, reset=rule, smooth=False)
            except (ad.ResetError, ocbe.FilterDivergenceError):
                # the first detection is that of the plain (first-pass) filter: recover it for the delay
                plain = ocbe.ocbe_filter_smoother(em, sc.t, inputs.y, setup.observer_states, sc.model, sc.meas_cov,
                                                  inputs.x0, inputs.P0, setup.control_weight, smooth=False)
                m_plain, dof_plain = ad.forward_metric(plain, sc.model)
                k0 = ad.first_detection(m_plain, ad.metric_limit(dof_plain))
                rows.append((mag, rule, np.nan if k0 is None else k0 - k_burn, 1.0, True, MAX_RESETS + 1))
                continue
            nf = tracking.nees(a.result.x_filt, a.result.P_filt, inputs.truth)
            frac = float(np.mean(nf[k_burn:] > stats.chi2.ppf(tracking.NEES_PROBABILITY, 6)))
            delay = a.detections[0].epoch - k_burn if a.detections else np.nan
            rows.append((mag, rule, delay, frac, frac > tracking.DIVERGED_FRACTION, len(a.detections)))
print(f"{len(rows)} adaptive runs in {time.perf_counter() - t_mc:.0f} s")
rows_a = np.array([(r[0], ad.RESET_RULES.index(r[1]), r[2], r[3], r[4], r[5]) for r in rows], float)


def summary(mag, rule):
    sel = rows_a[(rows_a[:, 0] == mag) & (rows_a[:, 1] == ad.RESET_RULES.index(rule))]
    delays = sel[:, 2]
    return dict(n=len(sel), undetected=float(np.mean(np.isnan(delays))),
                median_delay_h=float(np.nanmedian(delays) * sc.cadence_hours) if np.any(~np.isnan(delays)) else np.nan,
                max_delay_h=float(np.nanmax(delays) * sc.cadence_hours) if np.any(~np.isnan(delays)) else np.nan,
                inconsistent=float(np.mean(sel[:, 4])), resets=float(np.mean(sel[:, 5])))


print(f"{'burn':>8} {'rule':>10} {'undetected':>10} {'median delay':>12} {'max delay':>9} {'inconsistent':>12} "
      f"{'resets':>6}")
for mag in MAGNITUDES_M_S:
    for rule in ad.RESET_RULES:
        s = summary(mag, rule)
        print(f"{mag * 1e3:6.0f}mm/s {rule:>10} {100 * s['undetected']:9.0f}% {s['median_delay_h']:10.0f} h "
              f"{s['max_delay_h']:7.0f} h {100 * s['inconsistent']:11.0f}% {s['resets']:6.1f}")

fig, ax = plt.subplots(1, 3, figsize=(15, 4))
for j, rule in enumerate(ad.RESET_RULES):
    S = [summary(m, rule) for m in MAGNITUDES_M_S]
    mm = np.array(MAGNITUDES_M_S) * 1e3
    sty = dict(color=f"C{j}", ls="-" if j == 0 else "--", marker="o" if j == 0 else "s", ms=8 if j == 0 else 5,
               mfc="none" if j else None)
    ax[0].plot(mm, [s["median_delay_h"] for s in S], label=f"{rule} rule: median", **sty)
    ax[0].plot(mm, [s["max_delay_h"] for s in S], **{**sty, "ls": ":", "marker": "^"}, label=f"{rule} rule: max")
    ax[1].plot(mm, [100 * s["undetected"] for s in S], label=f"{rule} rule", **sty)
    ax[2].plot(mm, [100 * s["inconsistent"] for s in S], label=f"{rule} rule", **sty)
ax[0].set(xscale="log", xlabel="burn size [mm/s]", ylabel="detection delay [h]", title="delay (detected runs)")
ax[1].set(xscale="log", xlabel="burn size [mm/s]", ylabel="runs [%]", ylim=(-5, 105),
          title="undetected within the period")
ax[2].set(xscale="log", xlabel="burn size [mm/s]", ylabel="runs [%]", ylim=(-5, 105),
          title="inconsistent after the burn (NEES)")
handles, labels = ax[0].get_legend_handles_labels()
fig.legend(handles, labels, loc="lower center", ncol=4, bbox_to_anchor=(0.5, -0.03))
fig.tight_layout(rect=(0, 0.08, 1, 1))
_ = plotting.save_figure(fig, "09b_adaptive_delay_vs_burn", output_dir=out)

# %%
s_small, s_big = summary(MAGNITUDES_M_S[0], "mean"), summary(MAGNITUDES_M_S[-1], "mean")
s_small_ml, s_big_ml = summary(MAGNITUDES_M_S[0], "likelihood"), summary(MAGNITUDES_M_S[-1], "likelihood")
print(f"50 mm/s (paper's rule): {100 * s_small['undetected']:.0f} % undetected, median delay "
      f"{s_small['median_delay_h']:.0f} h, {100 * s_small['inconsistent']:.0f} % inconsistent; "
      f"3 m/s: median delay {s_big['median_delay_h']:.0f} h, {100 * s_big['inconsistent']:.0f} % inconsistent")

# %% [markdown]
# **Reading.** The numbers above are the argument of the paper's "Adaptive OCBE Tuning" section made quantitative;
# the sentences below describe the full run (10 burns per size and rule; quick mode runs 2). A 3 m/s burn is
# caught at once (delay 0-2 h) and the reset restores a consistent filter, as in Figs. 6-7. A
# 50 mm/s burn moves the measurements by little more than their noise for many epochs: it is detected late (tens
# of hours, often near the next periapsis, as in Figs. 8-9) or not at all within the period, and the filter is
# inconsistent from the burn until the detection. Because NRHO station keeping is tens of mm/s per revolution
# (the paper's quiet policy), an adaptive filter would spend much of every orbit inconsistent; the windowed tuning
# of notebook 10 instead raises the control uncertainty where burns happen (8 h around apoapsis), so the estimate
# stays consistent and the maneuver shows up afterwards in the smoothed control.
#
# The comparison of the two reset rules is beyond the paper: with the paper's rule a fraction of runs diverges
# after detection for the reason given in Section 2 (the rate noise the reset cannot explain); the likelihood rule
# avoids that failure while leaving the detection delays unchanged (detection does not depend on the rule until
# the first reset, so where one reset suffices the two rules' curves coincide: solid circles and dashed squares
# drawn on top of each other). The count of runs that needed a chain of resets is printed above. Neither rule is
# a cure for late detection: a reset inflates one 2-hour interval, while the error of a burn detected a day or two
# late has grown along the whole arc since; the likelihood rule, which only explains the current innovation, can
# then leave the filter over-confident (compare the final NEES of the two rules on the 50 mm/s run above).

# %%
table.add("50 mm/s burn: detection delayed (Figs. 8-9)", "late, 'nearly periapsis'",
          f"median {s_small['median_delay_h']:.0f} h after the burn, {100 * s_small['undetected']:.0f} % not "
          f"detected in the period ({s_small['n']} runs)",
          "reproduced" if (s_small["undetected"] > 0 or s_small["median_delay_h"] > 6) else
          "differs: detected promptly")
table.add("50 mm/s: filter re-converges after the late detection (Fig. 8)", "re-converges",
          f"final forward NEES: paper's rule {final_nees['mean']:.1f}, likelihood rule {final_nees['likelihood']:.1f}",
          "reproduced" if final_nees["mean"] < lim_nees else
          "differs: the paper's reset rule diverged on this run (Section 2)" +
          ("; the likelihood rule re-converges" if final_nees["likelihood"] < lim_nees else ""),
          "criterion: final NEES below its 99.9 % quantile")
table.add("Large burns detected promptly", "'near optimal' above 1 m/s",
          f"3 m/s: median delay {s_big['median_delay_h']:.0f} h, {100 * s_big['undetected']:.0f} % undetected",
          "reproduced" if s_big["undetected"] == 0 and s_big["median_delay_h"] <= 4 else "differs: see delays")
table.add("Filter inconsistent while a small burn is undetected", "implied (reason to move to windowed tuning)",
          f"50 mm/s: {100 * s_small['inconsistent']:.0f} % of runs inconsistent; 3 m/s: "
          f"{100 * s_big['inconsistent']:.0f} %", "derived", "NEES criterion of notebook 09")
chain = {rule: rows_a[(rows_a[:, 1] == ad.RESET_RULES.index(rule)) & ~np.isnan(rows_a[:, 2])] for rule in ad.RESET_RULES}
chain = {rule: (int(np.sum(v[:, 5] > 1)), len(v)) for rule, v in chain.items()}
print("detected runs needing more than one reset (a divergence chain): "
      + ", ".join(f"{r} rule {c[0]}/{c[1]}" for r, c in chain.items()))
table.add("Reset rule 'metric equal to its mean' breaks when rate noise exceeds it", "not discussed",
          "detected runs with a chain of resets: " + ", ".join(f"{r} rule {c[0]}/{c[1]}" for r, c in chain.items()),
          "beyond paper", "angle rates carry no state information here; probability e^-2 per detection")
table.add("Base (ballistic) control weight", "not given", f"{Q_BASE_KM2_S3:g} km^2/s^3", "derived",
          "notebook 10's q outside the apoapsis window; the law of the metric does not depend on it")
print(f"notebook wall time: {(time.perf_counter() - T_START) / 60:.1f} min")
table.display()
