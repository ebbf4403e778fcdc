"""Figures of notebooks 09b and 10 (Greaves & Scheeres 2021) drawn from the study results.

Each function takes a result object of :mod:`cislunar.papers.greaves_scheeres_2021.adaptive_studies` or
:mod:`cislunar.papers.greaves_scheeres_2021.detection_studies` and returns a ``matplotlib.figure.Figure`` (through
pyplot, so that a notebook shows it inline); saving is the caller's (``plotting.save_figure``).  Units as on the axes.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib import ticker
from matplotlib.lines import Line2D
from scipy import stats

from cislunar.estimation import adaptive_ocbe as ad
from cislunar.estimation.ocbe import OCBEResult
from cislunar.papers.greaves_scheeres_2021 import adaptive_studies as ads
from cislunar.papers.greaves_scheeres_2021 import custody as cu
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import detection_studies as dstudies
from cislunar.papers.greaves_scheeres_2021 import panels as ocbe_panels
from cislunar.utils import validation

__all__ = ["variant_figure", "figure_custody", "figure_conditioning", "figure_cadence_cost", "metric_law", "adaptive_errors", "adaptive_control_metric", "delays", "reset_rules", "station_keeping_policy",
           "control_integral_pdfs", "z_vs_maneuver", "pm_j_search", "health_lead", "health_metric", "tuning_map",
           "joint_search", "lead_grid"]

_OUTCOME_COLORS = {"prompt": "C0", "late": "C3", "nearly periapsis": "C1", "not detected": "0.6"}


def _check_setup(setup) -> det.DetectionSetup:
    return validation.instance(setup, "setup", det.DetectionSetup, "a detection.DetectionSetup (detection.make_setup)")


def _names(value, name: str, *, at_most: int | None = None) -> list:
    """A non-empty sequence of str (orbit, policy or setting names; a single str is refused), as a list."""
    if isinstance(value, (str, bytes)):
        raise validation.ArgumentTypeError(f"{name} must be a sequence of names; got a single "
                                           f"{type(value).__name__} {value!r:.60}")
    try:
        names = list(value)
    except TypeError:
        raise validation.ArgumentTypeError(f"{name} must be a sequence of names; got {type(value).__name__}") from None
    if not names:
        raise ValueError(f"{name} must hold at least one name")
    for i, n in enumerate(names):
        validation.instance(n, f"{name}[{i}]", str, "a str")
    if at_most is not None and len(names) > at_most:
        raise ValueError(f"{name} must hold at most {at_most} names (one per panel); got {len(names)}")
    return names


def _cells(value, name: str, keys, what: str) -> dict:
    """A dict holding every key of ``keys`` (``what``: what its values are, for the message)."""
    validation.instance(value, name, dict, f"a dict of {what}")
    missing = [k for k in keys if k not in value]
    if missing:
        raise ValueError(f"{name} has no entry for {missing[0]!r} (of {len(missing)} missing)")
    return value


def _values(value, name: str, *, positive: bool = False) -> np.ndarray:
    """A non-empty 1-D finite array (positive if asked)."""
    v = validation.as_array(value, name, ndim=(1,), min_size=1)
    if positive and np.any(v <= 0):
        raise ValueError(f"{name} must hold positive values; got {v}")
    return v


def _check_run(run) -> ads.AdaptiveRun:
    validation.instance(run, "run", ads.AdaptiveRun, "an adaptive_studies.AdaptiveRun (adaptive_studies.adaptive_run)")
    if run.panels is None:
        raise ValueError("run must be a smoothed adaptive run (adaptive_run(..., smooth=True)): it has no panels")
    return run


def metric_law(null: ads.NullMetricStudy):
    """Histogram and Q-Q plot of the pooled no-maneuver metric against its chi-square law (notebook 09b, Sec. 1)."""
    validation.instance(null, "null", ads.NullMetricStudy, "an adaptive_studies.NullMetricStudy")
    pooled, law, lim = null.metric, ad.metric_law(null.dof), ad.metric_limit(null.dof)
    fig, ax = plt.subplots(1, 2, figsize=(11, 3.8))
    xx = np.linspace(0, 20, 300)
    ax[0].hist(pooled, bins=40, range=(0, 20), density=True, alpha=0.6, histtype="stepfilled",
               label=f"{pooled.size} epochs, {null.n_runs} runs")
    ax[0].plot(xx, law.pdf(xx), "k", lw=1.2, label=rf"$\chi^2_{null.dof}$ (derived)")
    ax[0].axvline(lim, color="C3", ls="--", label=f"99 % limit {lim:.2f}")
    ax[0].set(xlabel="OCBE metric $M$ [-]", ylabel="probability density [-]",
              title=f"no maneuver: KS p = {null.ks_p:.2f}")
    # below the panel: in it, the legend would sit on the vertical limit line
    ax[0].legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=3, fontsize=8)
    srt = np.sort(pooled)
    ax[1].plot(law.ppf((np.arange(srt.size) + 0.5) / srt.size), srt, ".", ms=3)
    ax[1].plot([0, 20], [0, 20], "k", lw=0.8)
    ax[1].set(xlabel=rf"$\chi^2_{null.dof}$ quantile [-]", ylabel="metric quantile [-]", xlim=(0, 20), ylim=(0, 20),
              title="Q-Q plot against the derived law")
    return fig


def _days(setup: det.DetectionSetup, t) -> float:
    return t * setup.system.time_unit_s / 86400.0


def adaptive_errors(setup: det.DetectionSetup, run: ads.AdaptiveRun, title: str):
    """Fig. 6/8 layout of an adaptive run: position and velocity error norms with 3-sigma, forward and smoothed."""
    _check_setup(setup)
    _check_run(run)
    validation.instance(title, "title", str)
    return ocbe_panels.figure_errors(run.panels, title, burn_days=_days(setup, setup.t_maneuver),
                                     detection_days=[_days(setup, d.time) for d in run.detections])


def adaptive_control_metric(setup: det.DetectionSetup, run: ads.AdaptiveRun, title: str):
    """Fig. 7/9 layout of an adaptive run: control norm and normalised metric, forward and smoothed; crosses: what
    the online filter saw before the first reset (its three strikes)."""
    _check_setup(setup)
    _check_run(run)
    validation.instance(title, "title", str)
    dets = run.detections
    return ocbe_panels.figure_control_metric(run.panels, title, burn_days=_days(setup, setup.t_maneuver),
                                             detection_days=[_days(setup, d.time) for d in dets],
                                             first_pass_metric=run.run.metric_first_pass if dets else None,
                                             first_pass_until=dets[0].declared_epoch if dets else None)


def delays(study: ads.DelayStudy):
    """Delay after the burn per size, and stacked outcome bars per size and per angle noise (notebook 09b, Sec. 5)."""
    validation.instance(study, "study", ads.DelayStudy, "an adaptive_studies.DelayStudy")
    mags = list(study.by_size)
    mm = np.array(mags) * 1e3
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    q = np.array([study.by_size[m].quartiles_h for m in mags])
    ax[0].fill_between(mm, q[:, 0], q[:, 1], color="C0", alpha=0.2, label="25-75 % of detected runs")
    ax[0].plot(mm, [study.by_size[m].median_h for m in mags], "C0o-", label="median of detected runs")
    ax[0].axhline(study.late_from_h, color="C1", ls="--", lw=1, label="'nearly periapsis' above this line")
    ax[0].set(xscale="log", xlabel="burn size [mm/s]", ylabel="detection delay [h]",
              title=f"delay after the burn ({study.n_runs} runs per size)")
    ax[0].legend(loc="center right", fontsize=8)
    for j, (groups, labels, title, xlabel) in enumerate((
            (list(study.by_size.values()), [f"{m:g}" for m in mm], "outcome versus burn size (10 urad)",
             "burn size [mm/s]"),
            (list(study.by_noise.values()), [f"{s:g}" for s in study.by_noise],
             "50 mm/s burn: outcome versus angle noise", "angle noise (1 sigma) [urad]"))):
        bottom = np.zeros(len(groups))
        for name in ads.OUTCOMES:
            frac = 100 * np.array([g.fraction(name) for g in groups])
            ax[j + 1].bar(labels, frac, bottom=bottom, color=_OUTCOME_COLORS[name], label=name, width=0.6)
            bottom += frac
        ax[j + 1].set(ylabel="runs [%]", ylim=(0, 100), title=title, xlabel=xlabel)
    handles, labels = ax[1].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, bbox_to_anchor=(0.5, 0.0))
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return fig


def reset_rules(study: ads.ResetRuleStudy):
    """Inconsistent-after-the-burn and re-converged fractions per burn size for each reset rule (notebook 09b)."""
    validation.instance(study, "study", ads.ResetRuleStudy, "an adaptive_studies.ResetRuleStudy")
    mm = np.array(study.magnitudes_m_s) * 1e3
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for j, rule in enumerate(study.rules):
        S = [study.summary(m, rule) for m in study.magnitudes_m_s]
        sty = dict(color=f"C{j}", ls="-" if j == 0 else "--", marker="o" if j == 0 else "s", ms=8 if j == 0 else 5,
                   mfc="none" if j else None, label=f"{rule} rule")
        ax[0].plot(mm, [100 * s["inconsistent"] for s in S], **sty)
        ax[1].plot(mm, [100 * s["final_ok"] for s in S], **sty)
    ax[0].set(xscale="log", xlabel="burn size [mm/s]", ylabel="runs [%]", ylim=(-5, 105),
              title="inconsistent after the burn (NEES)")
    ax[1].set(xscale="log", xlabel="burn size [mm/s]", ylabel="detected runs [%]", ylim=(-5, 105),
              title="final estimate consistent (re-converged)")
    handles, labels = ax[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=2, bbox_to_anchor=(0.5, 0.0))
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Notebook 10
# ---------------------------------------------------------------------------------------------------------------


def station_keeping_policy(magnitudes: dict, policies: dict, uz):
    """Eq. 5 magnitude draws against the truncated-Gaussian PDF per policy, and the k component of Eqs. 3-4 pointing
    against the arcsine law and a uniform sphere.  ``magnitudes``: policy name -> draws [m/s]."""
    validation.dict_of(policies, "policies", det.StationKeepingPolicy, "detection.StationKeepingPolicy")
    if len(policies) > 2:
        raise ValueError(f"policies must hold at most 2 policies (one panel each); got {len(policies)}")
    _cells(magnitudes, "magnitudes", list(policies), "magnitude draws [m/s] per policy")
    for name in policies:
        _values(magnitudes[name], f"magnitudes[{name!r}]")
    uz = _values(uz, "uz")
    if np.any(np.abs(uz) > 1):
        raise ValueError("uz must hold direction components in [-1, 1]")
    fig, ax = plt.subplots(1, 3, figsize=(14, 3.8))
    for name, pol in policies.items():
        m, d = magnitudes[name], pol.magnitude_distribution
        a = ax[0 if name == "active" else 1]
        a.hist(m * 1e3, bins=60, density=True, alpha=0.6, histtype="stepfilled", label="draws")
        zz = np.linspace(d.ppf(0), d.ppf(1), 300)
        a.plot(zz * 1e3, d.pdf(zz) / 1e3, "k", lw=1, label="truncnorm PDF")
        a.set(title=f"{name}: mean {m.mean() * 1e3:.1f}, sd {m.std() * 1e3:.2f} mm/s",
              ylim=(0, 1.35 * d.pdf(d.mean()) / 1e3),  # headroom for the legend
              xlabel="impulse magnitude [mm/s]", ylabel="probability density [1/(mm/s)]")
    ax[2].hist(uz, bins=50, density=True, alpha=0.6, histtype="stepfilled", label="Eqs. 3-4 (paper)")
    ax[2].plot(np.linspace(-0.999, 0.999, 200), stats.arcsine(-1, 2).pdf(np.linspace(-0.999, 0.999, 200)), "k",
               lw=1, label="arcsine PDF")
    ax[2].axhline(0.5, color="C3", ls="--", label="uniform sphere")
    ax[2].set(xlabel=r"$\hat k$ component of the impulse direction [-]", ylabel="probability density [-]",
              ylim=(0, 3), title="pointing")
    ax[0].legend(loc="upper left")
    ax[2].legend(fontsize=8, loc="upper center")
    return fig


def control_integral_pdfs(studies: dict, orbit_names, policy_names):
    """Figs. 14-15 and 18-19 analogues: histograms and KDEs of z under H0 and H1, with z_lim, per orbit (rows) and
    policy (column pairs; active in m/s, quiet in mm/s).  ``studies``: (orbit, policy) -> detection.PolicyStudy."""
    orbit_names = _names(orbit_names, "orbit_names")
    policy_names = _names(policy_names, "policy_names", at_most=2)
    _cells(studies, "studies", [(o, p) for o in orbit_names for p in policy_names], "detection.PolicyStudy")
    for o in orbit_names:
        for p in policy_names:
            validation.instance(studies[o, p], f"studies[{(o, p)!r}]", det.PolicyStudy, "a detection.PolicyStudy")
    fig, ax = plt.subplots(len(orbit_names), 4, figsize=(16, 3.3 * len(orbit_names)), squeeze=False)
    for row, o in enumerate(orbit_names):
        for k, p in enumerate(policy_names):
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
            a_p.set(title=f"z_lim = {st.threshold.z_lim * unit:.4g} {ulab}",
                    ylabel=f"probability density [1/({ulab})]")
    h0h, h0l = ax[0, 0].get_legend_handles_labels()
    h1h, h1l = ax[0, 1].get_legend_handles_labels()
    fig.legend(h0h + h1h + [plt.Line2D([], [], color="k", ls=":", lw=1)], h0l + h1l + ["z_lim"], loc="lower center",
               ncol=5, bbox_to_anchor=(0.5, 0.0))
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    return fig


def z_vs_maneuver(studies: dict, orbit_names, policy_names):
    """Figs. 16-17, 20-21 analogues on the 9:2 NRHO's training runs: z over the pointing, ``z/|dv|`` over the azimuth,
    z against the magnitude (the first two orbits of ``orbit_names`` overlaid)."""
    orbit_names = _names(orbit_names, "orbit_names")
    policy_names = _names(policy_names, "policy_names", at_most=2)
    _cells(studies, "studies", [(o, p) for o in ["9:2 NRHO", *orbit_names[:2]] for p in policy_names],
           "detection.PolicyStudy (the 9:2 NRHO's included)")
    for key in {(o, p) for o in ["9:2 NRHO", *orbit_names[:2]] for p in policy_names}:
        validation.instance(studies[key], f"studies[{key!r}]", det.PolicyStudy, "a detection.PolicyStudy")
    fig, ax = plt.subplots(2, 3, figsize=(15, 8))
    for row, p in enumerate(policy_names):
        h1 = studies["9:2 NRHO", p].h1
        unit, ulab = (1.0, "m/s") if p == "active" else (1e3, "mm/s")
        sc = ax[row, 0].scatter(np.degrees(h1.azimuth), np.degrees(h1.elevation), c=h1.z * unit, s=6,
                                cmap="viridis")
        fig.colorbar(sc, ax=ax[row, 0], label=f"z [{ulab}]")
        ax[row, 0].set(xlabel="azimuth [deg]", ylabel="elevation [deg]", title=f"9:2 NRHO, {p}")
        ax[row, 1].scatter(np.degrees(h1.azimuth), h1.z / h1.magnitude, s=4, alpha=0.5)
        ax[row, 1].set(xlabel="azimuth [deg]", ylabel="z / impulse magnitude [-]", title=f"9:2 NRHO, {p}")
        for o, mk in zip(orbit_names, ("o", "x")):
            s1 = studies[o, p].h1
            ax[row, 2].scatter(s1.magnitude * unit, s1.z * unit, s=4 if mk == "o" else 14, alpha=0.4, marker=mk,
                               linewidths=0.8, label=o)  # crosses larger: at dot size they read as dots
        mm = np.array([0, h1.magnitude.max() * unit])
        ax[row, 2].plot(mm, mm, "k--", lw=1, label="z = magnitude")
        ax[row, 2].set(xlabel=f"impulse magnitude [{ulab}]", ylabel=f"z [{ulab}]",
                       title=f"{p}: z against the magnitude")
        ax[row, 2].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), markerscale=3)
    fig.tight_layout()
    return fig


def pm_j_search(pmj: dict, f_values, noise_urad, offsets_h, f_pm: float, sig_pm: float, active_sample):
    """The +-j search: paired contrast against the angle noise per window factor (burn at apoapsis), per burn time
    at ``f_pm``, and the random-burn runs of the regime ``(f_pm, sig_pm)`` coloured by ``z/|dv|``.
    ``pmj``: (f, noise, offset) -> (z per direction, contrast)."""
    f_values = _values(f_values, "f_values", positive=True)
    noise_urad = _values(noise_urad, "noise_urad", positive=True)
    offsets_h = _values(offsets_h, "offsets_h")
    f_pm = validation.positive(f_pm, "f_pm")
    sig_pm = validation.positive(sig_pm, "sig_pm")
    validation.instance(pmj, "pmj", dict, "a dict (f, noise, offset) -> (z per direction, contrast)")
    if any((f, s, 0.0) not in pmj for f in f_values for s in noise_urad):
        raise ValueError("pmj must hold a cell (f, noise, 0.0) for every f of f_values and noise of noise_urad")
    if any((f_pm, s, off) not in pmj for s in noise_urad for off in offsets_h):
        raise ValueError("pmj must hold a cell (f_pm, noise, offset) for every noise of noise_urad and offset of "
                         "offsets_h (f_pm must be a factor of the search)")
    validation.instance(active_sample, "active_sample", det.MonteCarloSample, "a detection.MonteCarloSample")
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    for f, mk in zip(f_values, "osD^"):
        ax[0].plot(noise_urad, [pmj[f, s, 0.0][1] for s in noise_urad], marker=mk, label=f"f = {f:g}")
    ax[0].axhline(1.0, color="0.5", lw=0.8)
    ax[0].set(xscale="log", xlabel="angle noise [micro-rad]", ylabel="z(+-j) / z(+-i, +-k) [-]",
              title="burn at apoapsis")
    ax[0].legend(fontsize=8, loc="upper left")
    for off, mk in zip(offsets_h, "osD"):
        ax[1].plot(noise_urad, [pmj[f_pm, s, off][1] for s in noise_urad], marker=mk,
                   label=f"burn {off:+g} h from apoapsis")
    ax[1].axhline(1.0, color="0.5", lw=0.8)
    ax[1].set(xscale="log", xlabel="angle noise [micro-rad]", ylabel="z(+-j) / z(+-i, +-k) [-]",
              title=f"f = {f_pm:g}: burn time in the window")
    ax[1].legend(fontsize=8, loc="upper left")
    h = active_sample
    sc = ax[2].scatter(np.degrees(h.azimuth), np.degrees(h.elevation), c=h.z / h.magnitude, s=8, cmap="viridis")
    fig.colorbar(sc, ax=ax[2], label="z / impulse magnitude [-]")
    ax[2].set(xlabel="azimuth [deg]", ylabel="elevation [deg]", title=f"active, f = {f_pm:g}, {sig_pm:g} urad")
    fig.tight_layout()
    return fig


def health_lead(lead: dict):
    """Fig. 22 race: per burn size, the share of runs where the control or the residual test fires first, both at
    the same epoch, or neither within 24 h.  ``lead``: label -> detection.HealthLeadStudy."""
    validation.dict_of(lead, "lead", det.HealthLeadStudy, "detection.HealthLeadStudy")
    fig, ax = plt.subplots(1, len(lead), figsize=(5 * len(lead), 3.8), sharey=True, squeeze=False)
    ax = ax[0]
    for a, (tag, h) in zip(ax, lead.items()):
        fr = h.outcome_fractions()
        x = np.arange(h.magnitudes_m_s.size)
        bottom = np.zeros(x.size)
        for (name, v), col in zip(fr.items(), ("C2", "C0", "C1", "0.85")):  # neither: the light grey
            a.bar(x, 100 * v, bottom=bottom, color=col, label=name, width=0.7)
            bottom += 100 * v
        a.set(xticks=x, xticklabels=[f"{m:g}" for m in h.magnitudes_m_s], xlabel="burn size [m/s]", title=tag)
    ax[0].set(ylabel="runs [%]")
    h_, l_ = ax[0].get_legend_handles_labels()
    fig.legend(h_, l_, loc="lower center", ncol=4, bbox_to_anchor=(0.5, -0.02))
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return fig


def health_metric(setup: det.DetectionSetup, inputs: det.TrialInputs, result, reference, z_m_s: float):
    """Fig. 22 analogue of one run: smoothed position error and 3-sigma, whitened residual norms against the 99 %
    level of a 4-dof residual, and z against the quiet training runs (``reference``: a detection.PolicyStudy)."""
    _check_setup(setup)
    validation.instance(inputs, "inputs", det.TrialInputs, "a detection.TrialInputs (detection.draw_trial)")
    validation.instance(result, "result", OCBEResult, "an ocbe.OCBEResult (detection.run_trial_filter)")
    n = setup.scenario.t.size
    if inputs.truth.shape[0] != n:
        raise ValueError(f"inputs must be drawn on setup (truth of {inputs.truth.shape[0]} epochs, setup {n})")
    if result.x_smooth is None or result.x_smooth.shape[0] != n:
        raise ValueError(f"result must be a smoothed run on setup's {n} epochs")
    validation.instance(reference, "reference", det.PolicyStudy, "a detection.PolicyStudy")
    z_m_s = validation.positive(z_m_s, "z_m_s")
    em = setup.system
    fig, ax = plt.subplots(1, 3, figsize=(15, 3.8))
    hours = setup.scenario.t * em.time_unit_s / 3600
    err = np.linalg.norm(result.x_smooth[:, :3] - inputs.truth[:, :3], axis=1) * em.length_unit_km
    sig = 3 * np.sqrt(np.trace(result.P_smooth[:, :3, :3], axis1=1, axis2=2)) * em.length_unit_km
    ax[0].plot(hours, err, label="smoothed error")
    ax[0].plot(hours, sig, "--", label="3-sigma")
    ax[0].set(xlabel="time from periapsis [h]", ylabel="position error [km]", title="0.5 m/s burn, quiet tuning")
    ax[0].legend(loc="upper right")
    ax[1].plot(hours, result.residual_norms, ".", label="this run")
    ax[1].axhline(np.sqrt(stats.chi2.ppf(0.99, 4)), color="k", ls=":", label="99 % of a 4-dof residual")
    ax[1].set(xlabel="time from periapsis [h]", ylabel="whitened residual norm [-]", title="measurement residuals")
    ax[1].legend(loc="center left")
    ax[2].hist(reference.h0.z, bins=40, alpha=0.6, histtype="stepfilled", label="quiet H0")
    ax[2].hist(reference.h1.z, bins=40, alpha=0.6, histtype="stepfilled", label="quiet H1")
    ax[2].axvline(z_m_s, color="k", label=f"this run: z = {z_m_s:.3f} m/s")
    ax[2].set(xscale="log", xlabel="z [m/s]", ylabel="runs [-]", title="z against the training runs")
    ax[2].legend(fontsize=8, loc="upper left")
    return fig


def tuning_map(tmap: dict, orbit_names, policy_names, variants, base_variant: str, f_grid, f_side, f_c: float,
               f_tune: float, paper_zlim: dict, worst):
    """The tuning map (notebook 10, Section 2): top row all orbits at the paper's window (H1 forward and smoothed
    inconsistent runs, FP + MD); bottom row the 9:2 NRHO per setting (worst cell, z_lim over the paper's, FP + MD).
    ``tmap``: (orbit, policy, f, variant) -> cell dict; ``worst(o, p, f, v)``: worst inconsistent fraction."""
    orbit_names = _names(orbit_names, "orbit_names")
    policy_names = _names(policy_names, "policy_names")
    variants = _names(variants, "variants")
    validation.choice(base_variant, "base_variant", variants)
    f_grid = _values(f_grid, "f_grid", positive=True)
    f_side = _values(f_side, "f_side", positive=True)
    f_c = validation.positive(f_c, "f_c")
    f_tune = validation.positive(f_tune, "f_tune")
    _cells(paper_zlim, "paper_zlim", policy_names, "thresholds [m/s] per policy")
    for p in policy_names:
        validation.positive(paper_zlim[p], f"paper_zlim[{p!r}]")
    validation.callable_(worst, "worst")
    keys = [(o, p, f, base_variant) for o in orbit_names for p in policy_names for f in f_grid]
    keys += [("9:2 NRHO", p, f, v) for v in variants if v != base_variant for p in policy_names for f in f_side]
    _cells(tmap, "tmap", keys, "cells (orbit, policy, f, variant) -> dict")
    fig, ax = plt.subplots(2, 3, figsize=(15, 8.4))
    for o, col in zip(orbit_names, ("C0", "C1", "C2")):
        for p, ls in zip(policy_names, ("-", "--")):
            c = [tmap[o, p, f, base_variant] for f in f_grid]
            lab = f"{o}, {p}"
            ax[0, 0].plot(f_grid, [100 * x["h1"][0] for x in c], ls, color=col, marker="o", ms=3, label=lab)
            ax[0, 1].plot(f_grid, [100 * x["h1"][1] for x in c], ls, color=col, marker="o", ms=3, label=lab)
            ax[0, 2].plot(f_grid, [x["err"] for x in c], ls, color=col, marker="o", ms=3, label=lab)
    for v, col in zip(variants, ("k", "C3", "C4", "C5", "C6", "C7")):
        for p, ls in zip(policy_names, ("-", "--")):
            fs = f_grid if v == base_variant else f_side
            kw = {"color": col, "marker": "o", "ms": 3}
            ax[1, 0].plot(fs, [100 * worst("9:2 NRHO", p, f, v) for f in fs], ls, label=f"{v}, {p}", **kw)
            ax[1, 1].plot(fs, [tmap["9:2 NRHO", p, f, v]["z_lim"] / paper_zlim[p] for f in fs], ls, **kw)
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
        a.axvline(f_c, color="C2", lw=2, alpha=0.3)
        a.axvline(f_tune, color="C1", lw=2, alpha=0.3)
    h, lab = ax[0, 0].get_legend_handles_labels()
    fig.legend(h, lab, loc="upper center", bbox_to_anchor=(0.5, 0.515), ncol=6, fontsize=8)
    h, lab = ax[1, 0].get_legend_handles_labels()
    fig.legend(h, lab, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=4, fontsize=8)
    fig.tight_layout(h_pad=5.0)
    return fig


def joint_search(joint: dstudies.JointSearch):
    """The joint search (issue 23): per screened setting, the larger threshold deviation of the two policies
    against the worst consistency cell (left; one colour per window, filled: rerun at paper size), and the paper-size
    thresholds over the paper's with their bootstrap standard errors (right).  Grey boxes: the screen's and the
    confirmation's criteria."""
    validation.instance(joint, "joint", dstudies.JointSearch)
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.2))
    windows = sorted({k[0] for k in joint.screen})
    for i, w in enumerate(windows):
        keys = [k for k in joint.screen if k[0] == w]
        dev = [100 * max(abs(joint.screen[k][p]["z_lim"] / joint.paper_zlim[p] - 1) for p in joint.policies)
               for k in keys]
        worst = [100 * max(joint.screen[k][p]["worst"] for p in joint.policies) for k in keys]
        filled = [k in joint.confirm for k in keys]
        ax[0].scatter(np.array(dev)[filled], np.array(worst)[filled], color=f"C{i}", s=18, label=f"{w:g} h window")
        ax[0].scatter(np.array(dev)[~np.array(filled)], np.array(worst)[~np.array(filled)], facecolor="none",
                      edgecolor=f"C{i}", s=18)
    for tol, lim, ls in ((dstudies.JOINT_SCREEN_ZLIM_TOL, joint.screen_limit, ":"),
                         (dstudies.JOINT_ZLIM_TOL, dstudies.CONSISTENT_FRACTION, "--")):
        ax[0].plot([0, 100 * tol, 100 * tol], [100 * lim, 100 * lim, 0], color="0.4", ls=ls, lw=1)
    ax[0].set(xlabel="larger |z_lim / paper - 1| of the two policies [%]", ylabel="worst cell: inconsistent runs [%]",
              title=f"screen: {len(joint.screen)} settings ({joint.n_screen[0]} + {joint.n_screen[1]} runs)")
    handles, _ = ax[0].get_legend_handles_labels()
    handles += [Line2D([], [], ls="none", marker="o", ms=4, color="0.3", label="filled: rerun at paper size"),
                Line2D([], [], ls="none", marker="o", ms=4, mfc="none", color="0.3", label="open: screened only"),
                Line2D([], [], color="0.4", ls=":", lw=1, label="screen's box"),
                Line2D([], [], color="0.4", ls="--", lw=1, label="both criteria's box")]
    ax[0].legend(handles=handles, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
    keys = list(joint.confirm)
    for j, p in enumerate(joint.policies):
        r = [joint.confirm[k][p]["z_lim"] / joint.paper_zlim[p] for k in keys]
        e = [2 * joint.confirm[k][p]["z_lim_se"] / joint.paper_zlim[p] for k in keys]
        ax[1].errorbar(np.arange(len(keys)) + 0.15 * (j - 0.5), r, yerr=e, fmt="o" if j == 0 else "s", ms=4,
                       label=f"{p} (+- 2 se)")
    ax[1].axhspan(1 - dstudies.JOINT_ZLIM_TOL, 1 + dstudies.JOINT_ZLIM_TOL, color="0.9", zorder=0)
    ax[1].set(xticks=np.arange(len(keys)), ylabel="z_lim / paper's [-]",
              xlabel="setting [window h, f, noise, base weight km^2/s^3, burn time h]", title=f"paper size ({joint.n_paper[0]} + "
              f"{joint.n_paper[1]} runs); * = both criteria met")
    ax[1].set_xticklabels([("* " if k in joint.passed else "") + f"{k[0]:g} h, f {k[1]:g}\n{k[3]:g} urad, "
                           f"{k[2]:.0e}, {k[4]:+g} h" for k in keys], rotation=90, fontsize=7)
    ax[1].legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
    fig.tight_layout()
    return fig


def lead_grid(grid: dstudies.LeadGrid):
    """The Fig. 22 race over the window weight factor f (x) and the angle noise (one line each): share of the
    judged-size runs whose residual test stays silent (left), whose control test is strictly first (middle), and
    the median z over the burn (right)."""
    validation.instance(grid, "grid", dstudies.LeadGrid)
    fs = sorted({k[0] for k in grid.cells})
    noises = sorted({k[1] for k in grid.cells})
    fig, ax = plt.subplots(1, 3, figsize=(14, 3.8))
    for i, s in enumerate(noises):
        pts = [(f, grid.summary((f, s))) for f in fs if (f, s) in grid.cells]
        x = [f for f, _ in pts]
        for a, key, scale in ((ax[0], "residual_silent", 100), (ax[1], "control_first", 100), (ax[2], "z_ratio", 1)):
            a.plot(x, [scale * d[key] for _, d in pts], "o-", color=f"C{i}", label=f"{s:g} micro-rad")
    for a in ax[:2]:
        a.axhline(50, color="0.5", ls=":", lw=1)
    ax[2].axhline(0.5, color="0.5", ls=":", lw=1)
    ax[0].set(ylabel="residual test silent for 24 h [% of runs]")
    ax[1].set(ylabel="control test strictly first [% of runs]")
    ax[2].set(ylabel="median z / burn [-]")
    for a in ax:
        a.set(xscale="log", xlabel="window weight factor f [-]")
    ax[2].legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
    fig.suptitle(f"{grid.magnitude_m_s:g} m/s burns at the quiet tuning", fontsize=10)
    fig.tight_layout()
    return fig


# ------------------------------------------------------------ notebook 09b: measurement sets and reset rules
def variant_figure(study: ads.VariantStudy):
    """Resets per detection, runs inconsistent after the burn and detected runs re-converged, per burn size, for
    every measurement set (colour) and reset rule (solid: the paper's, dashed: the state-covariance inflation)."""
    validation.instance(study, "study", ads.VariantStudy)
    mm = np.array(study.magnitudes_m_s) * 1e3
    fig, ax = plt.subplots(1, 3, figsize=(14, 4))
    for i, ms in enumerate(ads.MEASUREMENT_SETS):
        for j, rule in enumerate(ads.VARIANT_RULES):
            S = [study.summary(ms, rule, (m,)) for m in study.magnitudes_m_s]
            sty = dict(color=f"C{i}", ls="-" if j == 0 else "--", marker="o" if j == 0 else "s",
                       mfc=None if j == 0 else "none", label=f"{ms}, {rule}")
            ax[0].plot(mm, [s["resets_per_detection"] for s in S], **sty)
            ax[1].plot(mm, [100 * s["inconsistent"] for s in S], **sty)
            ax[2].plot(mm, [100 * s["reconverged"] for s in S], **sty)
    ax[0].set(xscale="log", xlabel="burn size [mm/s]", ylabel="resets per detection [-]",
              title="chain rate")
    ax[1].set(xscale="log", xlabel="burn size [mm/s]", ylabel="runs [%]", ylim=(-5, 105),
              title="inconsistent after the burn (NEES)")
    ax[2].set(xscale="log", xlabel="burn size [mm/s]", ylabel="detected runs [%]", ylim=(-5, 105),
              title="final estimate consistent (re-converged)")
    handles, labels = ax[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, bbox_to_anchor=(0.5, 0.0))
    fig.tight_layout(rect=(0, 0.14, 1, 1))
    return fig


# ------------------------------------------------------------ notebook 09: custody, SRI form, cadence
def figure_custody(studies):
    """Per period: fraction of runs keeping custody and inconsistent (left); worst and median pointing error of the
    predicted estimate against the custody bound (right).  ``studies``: a sequence of :class:`CustodyStudy`."""
    if isinstance(studies, (str, bytes)) or not hasattr(studies, "__iter__"):
        raise validation.ArgumentTypeError(f"studies must be a sequence of CustodyStudy; got {type(studies).__name__}")
    studies = list(studies)
    if not studies:
        raise ValueError("studies must hold at least one CustodyStudy")
    for i, st in enumerate(studies):
        validation.instance(st, f"studies[{i}]", cu.CustodyStudy, "a CustodyStudy (custody_study)")
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8), constrained_layout=True)
    for i, (s, mk) in enumerate(zip(studies, "os^v")):
        k = np.arange(1, s.periods + 1)
        # later studies with larger open markers drawn on top: where two policies coincide (e.g. both at 100 %)
        # both stay visible
        st = dict(marker=mk, ms=5 + 4 * i, mfc=None if i == 0 else "none", zorder=2 + i)
        a1.plot(k, 100 * s.custody_fraction, label=f"custody kept, {s.policy_name}", **st)
        a1.plot(k, 100 * s.inconsistent_fraction, ls="--", label=f"inconsistent, {s.policy_name}", **st)
        pe = np.rad2deg(np.where(np.isfinite(s.max_pointing_rad), s.max_pointing_rad, np.nan))
        a2.semilogy(k, np.nanmax(pe, axis=0), label=f"worst run, {s.policy_name}", **st)
        a2.semilogy(k, np.nanmedian(pe, axis=0), ls="--", label=f"median run, {s.policy_name}", **st)
    a1.axhspan(0, 10, color="0.9", zorder=0)
    a1.set(xlabel="period since hand-off [-]", ylabel="runs [%]", ylim=(-5, 105))
    a2.axhline(np.rad2deg(studies[0].half_angle_rad), color="k", ls=":", label="custody bound")
    a2.set(xlabel="period since hand-off [-]", ylabel="max pointing error [deg]")
    for a in (a1, a2):
        a.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7)
    return fig


def figure_conditioning(case: cu.ConditioningCase):
    """The three forms on one case: smallest eigenvalue ratio of P (left) and mean NEES over the draws (right)."""
    validation.instance(case, "case", cu.ConditioningCase, "a ConditioningCase (conditioning_case)")
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8), constrained_layout=True)
    days = case.t * 0 + np.arange(case.t.size)
    for f, ls in zip(case.forms, ("-", "--", ":")):
        a1.semilogy(days, np.abs(case.min_eig_ratio[f]), ls=ls, label=f"|min/max eigenvalue|, {f}")
        neg = case.min_eig_ratio[f] < 0
        if neg.any():
            a1.semilogy(days[neg], np.abs(case.min_eig_ratio[f][neg]), "x", label=f"negative eigenvalue, {f}")
        a2.semilogy(days, np.where(case.nees_mean[f] > 0, case.nees_mean[f], np.nan), ls=ls, label=f)
    a2.axhspan(*case.band, color="0.85", zorder=0, label="99.9 % band (consistent)")
    a1.set(xlabel="epoch index (-)", ylabel="eigenvalue ratio of P (-)")
    a2.set(xlabel="epoch index (-)", ylabel="mean NEES over draws (-)")
    _plain_log_ticks(a2)
    for a in (a1, a2):
        a.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7)
    fig.suptitle(case.label, fontsize=9)
    return fig


def _plain_log_ticks(ax, which: str = "y") -> None:
    """Label a log axis (``which``: "x" or "y") that spans less than two decades at 1, 2 and 5 times a power of ten,
    in plain numbers (matplotlib would otherwise label its minor ticks as 2x10^0, 3x10^0, ... and crowd the axis)."""
    lo, hi = ax.get_xlim() if which == "x" else ax.get_ylim()
    axis = ax.xaxis if which == "x" else ax.yaxis
    if lo > 0 and hi / lo < 100:
        axis.set_major_locator(ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(ticker.NullFormatter())


def _cadence_label(hours):
    return f"{hours * 60:.0f} min" if hours < 1 else f"{hours:g} h"


def figure_cadence_cost(cost: cu.CadenceCost):
    """Final 3-sigma position against run time per period, one point per cadence (log-log), with the chord between
    the sparsest and densest cadence whose deepest point below it is the knee (:attr:`CadenceCost.knee_h`)."""
    validation.instance(cost, "cost", cu.CadenceCost, "a CadenceCost (cadence_cost_study)")
    fig, ax = plt.subplots(figsize=(6.5, 4.2), constrained_layout=True)
    ax.loglog(cost.seconds, cost.sigma3_km, "o-", label="OCBE filter, one period")
    for c, s, a in zip(cost.cadences_h, cost.seconds, cost.sigma3_km):
        ax.annotate(_cadence_label(c), (s, a), textcoords="offset points", xytext=(8, 6), fontsize=7)  # clear of the knee box
    i = int(np.argmin(np.abs(cost.cadences_h - cost.knee_h)))
    ax.loglog(cost.seconds[i], cost.sigma3_km[i], "s", ms=10, mfc="none", label=f"knee ({_cadence_label(cost.knee_h)})")
    ends = [0, -1]  # the chord of CadenceCost.chord_depth: first to last cadence of the study (its two ends)
    ax.loglog(cost.seconds[ends], cost.sigma3_km[ends], ":", color="0.5",
              label="chord of the end cadences\n(the knee lies deepest below it)")
    ax.set(xlabel="filter CPU time per tracking period (s)", ylabel="final 3-sigma position (km)")
    _plain_log_ticks(ax, "x")
    _plain_log_ticks(ax, "y")
    ax.legend(loc="upper right", fontsize=7)  # the curve falls from upper left to lower right: that corner is free
    return fig
