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
# # 12 · LPV observers on the nonlinear CR3BP with noisy celestial angles
#
# **What you will learn.** How the LPV observers designed in notebook 11 behave on the *nonlinear* CR3BP when
# they only see the two angles $\theta_1$ (at the Earth) and $\theta_2$ (at the Moon) with 0.1 deg noise; how the
# scheduling parameters $\rho$ are recovered from those angles by triangulation, and why the estimate must be used
# instead near the Earth-Moon line ($|\sin\theta_3|<0.04$); what accuracy the LMIs actually *guarantee* for this
# noise, and whether the simulated observers meet it; and how an extended Kalman filter on the same measurements
# compares (beyond the paper).
#
# **Paper sections followed.** Nychka & Bhattacharya (arXiv 2410.02013) §IV-B, Fig. 3 (a-c) and the text around
# it; observer Eq. 3a. The methods live in `cislunar.estimation.lpv` and `cislunar.estimation.observers`; the
# chapter's set-ups in `cislunar.papers.nychka_bhattacharya.observer_simulation` (each returns a frozen result), the
# figure in `...figures` and the claims, declared before the runs, in `...claims.observer_simulation`.

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: quick mode simulates half a period with a coarser measurement interval.
PERIODS = 0.5 if QUICK else 1.0  # orbit periods simulated
DT = 0.004 if QUICK else 0.002  # measurement interval, TU (0.002 TU = 12.5 min)
N_ORBIT = 600 if QUICK else 4000  # samples bounding rho
N_VERIFY = 30 if QUICK else 500  # interior samples in the gain verification

import numpy as np

from cislunar.papers.nychka_bhattacharya import figures
from cislunar.papers.nychka_bhattacharya import observer_simulation as obs
from cislunar.papers.nychka_bhattacharya.claims.observer_simulation import CLAIMS
from cislunar.papers.nychka_bhattacharya.scenarios import (
    GAMMA,
    SIGMA_DEG,
    paper_scenario,
)
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
table = ComparisonTable("12 LPV observer simulation (Nychka & Bhattacharya 2024, §IV-B, Fig. 3)")

# %% [markdown]
# ## 1 · The gains (notebook 11's designs)
#
# The observer only uses $\sin\theta_1,\cos\theta_1$ (notebook 11: the $\|\beta\|_1$ optimum drops the other
# sensors). H2: Theorem 1 as derived (no gain bound needed). H-infinity: Theorem 2 with the bandwidth bound
# $|\lambda(A+LC)| < R = 1000$/TU (beyond the paper; without it the minimum is not attained and the gain is
# unbounded). Both solves must end `optimal`; each gain is verified (Hurwitz and norm < gamma at the 64 vertices and
# random samples of the box).

# %%
sc = paper_scenario(n_samples=N_ORBIT)
model = sc.model
KM, TU_MIN = model.system.length_unit_km, model.system.time_unit_s / 60.0
od = obs.observer_designs(sc, N_VERIFY, rng)
des = od.designs
for n, d in des.items():
    v = od.verification[n]
    print(f"{n:4s}: {d.status}; kappa {d.kappa[:2].round(1)}, Eq. 24 noise {d.noise_deg[0]:.4f} deg, "
          f"|L| = {d.gain_norm:.1f}; verified: max Re eig {v.max_real_eig:.2f}, worst {n} {v.worst:.3e} < {GAMMA}: "
          f"{v.passed}")
    table.add(CLAIMS[f"{n}_gain"].judge(
        bool(v.passed and d.optimal), shown=f"{d.status}, |L| = {d.gain_norm:.0f}, worst {n} norm {v.worst:.2e}",
        note="Hinf with bandwidth bound R = 1000/TU" if n == "hinf" else "no gain bound"))

# %% [markdown]
# ## 2 · What the paper's 0.1 deg means for each design (outcome of notebook 11's sensitivity study)
#
# The H-infinity allowance bounds the noise energy, so it is an angle RMS directly: 0.0765 deg here. The H2
# allowance is a white-noise intensity; a sensor sampled every $\Delta t$ may have per-sample standard deviation
# $\sin^{-1}(1/(\kappa\sqrt{\Delta t}))$. Notebook 11 found: read as an angle, H2 allows *less* than H-infinity (the
# paper's ordering reversed) on every resonant orbit tried; per sample, H2 reaches 0.1 deg only for sampling
# intervals of hours, except with a large disturbance (down to minutes at notebook 11's largest level), and
# H-infinity 0.08 deg only on orbits whose apogee lies at 0.88-0.99 LU from the Earth (the
# 2:1 resonance used here); both of the paper's numbers and its ordering hold together on that orbit only for
# sampling intervals of roughly 100-400 min at disturbance levels up to $10^{-3}$ (81-312 min for accelerations and
# 7-26 min for state perturbations at level $10^{-2}$; notebook 11's windows). At this notebook's sampling interval:

# %%
h2_ps = float(des["h2"].noise_per_sample_deg(DT)[0])
hinf_n = float(des["hinf"].noise_deg[0])
DT_01 = float(1.0 / (des["h2"].kappa[0] * np.sin(np.radians(0.1))) ** 2)  # H2 allows exactly 0.1 deg per sample
print(f"dt = {DT} TU ({DT * TU_MIN:.1f} min): H2 allows {h2_ps:.3f} deg per sample (intensity reading "
      f"{des['h2'].noise_deg[0]:.4f} deg); Hinf allows {hinf_n:.4f} deg RMS")
print(f"the simulated {SIGMA_DEG} deg is {SIGMA_DEG / h2_ps:.2f}x the H2 and {SIGMA_DEG / hinf_n:.2f}x the Hinf "
      "allowance")
_ = table.add(CLAIMS["ordering_dt"].judge(
    h2_ps, shown=f"H2 {h2_ps:.2f} deg per sample > Hinf {hinf_n:.3f} deg" if h2_ps > hinf_n else
    f"H2 {h2_ps:.3f} < Hinf {hinf_n:.3f} deg",
    reason=f"only the ordering agrees; H2 allows {h2_ps:.2f} deg per sample, {h2_ps / 0.1:.1f}x the paper's 0.1 deg"
    if h2_ps > hinf_n else "reversed",
    note=f"per-sample reading at dt = {DT * TU_MIN:.1f} min (our choice), outside notebook 11's window where both "
    f"numbers hold; H2 = 0.1 deg per sample at dt = {DT_01 * TU_MIN:.0f} min (Section 6 simulates it); as an "
    f"intensity H2 allows {des['h2'].noise_deg[0]:.3f} deg < Hinf (notebook 11)"))

# %% [markdown]
# ## 3 · Truth, measurements, scheduling parameters
#
# Truth: the 2:1 resonant orbit propagated with heyoka (`propagate`). Measurements every `DT` TU:
# $\tilde\theta_i = \theta_i + n_i$, $n_i\sim N(0, (0.1°)^2)$, both angles. The sensor output is continuous and
# each noise sample is held over `DT` (the white-noise model of intensity $\sigma^2\Delta t$ behind the H2
# per-sample reading; `observers.simulate_lpv_observer(hold="noise")`). Holding the whole measurement instead would
# make the observers lag the truth by about $|\dot\theta|\Delta t$, largest near perigee (printed below for this
# `DT`) — far more than the noise. The observer $\dot{\hat x} = (A(\rho)+LC(\rho))\hat x - Ly + b(\rho) + Ld(\rho)$ (Eq. 3a) needs
# $\rho$; with the Earth-Moon baseline of 1 LU the law of sines gives $r_{13} = \sin\theta_2/\sin\theta_3$,
# $r_{23}=\sin\theta_1/\sin\theta_3$ and then $x, y$ — singular when $\sin\theta_3\to0$. Where
# $|\sin\tilde\theta_3|<0.04$ the observer uses $\rho(\hat x)$ (paper). Initial estimate error: 0.02 LU (about
# 7,700 km) in each of x and y, i.e. a position error of about 10,900 km (printed below), and 0.01 LU/TU (10 m/s)
# in each velocity ("large initial errors", unspecified in the paper; Section 4 sweeps it).

# %%
sim = obs.simulate_fig3(sc, od, DT, PERIODS, SIGMA_DEG, rng)
t, truth, runs, span, e0 = sim.t, sim.truth, sim.runs, sim.period, sim.initial_error
frac = runs["h2"].rho_from_estimate.mean()
th1_rate = np.abs(np.gradient(np.unwrap(model.angles(truth)[0]), t))  # rad/TU
print(f"{t.size} measurements; rho taken from the estimate on {100 * frac:.1f} % of them (|sin th3| < 0.04)")
print(f"initial position error {e0 * KM:.0f} km ({abs(sim.x_hat0[0] - truth[0, 0]) * KM:.0f} km per axis)")
print(f"lag |dtheta1/dt| DT if the whole measurement were held: up to {np.degrees(th1_rate.max() * DT):.2f} deg "
      f"at DT = {DT * TU_MIN:.1f} min")

# %% [markdown]
# ## 4 · The accuracy the LMIs guarantee (the criterion for Fig. 3's claim, fixed before looking)
#
# The paper claims the observers "rapidly converge and maintain accurate estimates". We judge "accurate" by the
# bound each theorem guarantees for the simulated noise (`lpv.guaranteed_error_rms`): the error is linear in the
# normalised noise $\kappa\,\delta\theta$, so
# * H2: steady-state RMS position error $\le \gamma\,\kappa\,\sigma\sqrt{\Delta t}$ (white noise of intensity
#   $\sigma^2\Delta t$);
# * H-infinity: time-RMS position error $\le \gamma\,\kappa\,\mathrm{RMS}(\delta\theta)$ (L2 gain), up to the decay
#   of the initial error.
#
# Both assume $\rho$ is known exactly; as a diagnostic the same runs are repeated scheduling on the true $\rho$.
# "Converge rapidly": the error first falls below the bound within 5 % of the orbit period. "Stay accurate": the
# RMS error after that (first crossing plus 2 % of the period) is below the bound.

# %%
cv = obs.convergence_study(sc, od, sim, SIGMA_DEG, seed=SEED)
for n in cv.bound:
    print(f"{n:4s}: guaranteed RMS {cv.bound[n] * KM:7.1f} km; first below at {cv.first[n]:.3f} TU "
          f"({cv.first[n] / span * 100:.1f} % of the period); RMS after {cv.rms[n] * KM:7.1f} km; "
          f"with exact rho (diagnostic) {cv.rms_exact[n] * KM:7.1f} km")
ekf_rms = float(np.sqrt(np.mean(runs["ekf"].position_error[sim.settled] ** 2)))

# %% [markdown]
# **What sets the convergence time.** The criterion "within 5 % of a period" was fixed before the runs, but whether
# it can be met depends on an input the paper does not state: the initial error. The error decays no faster than
# the slowest closed-loop pole of $A(\rho)+LC(\rho)$ along the orbit allows, so falling from the initial error to
# the guarantee takes about $\ln(e_0/\text{bound})/|\mathrm{Re}\,\lambda|_{\min}$. Below: that prediction, a run
# with no noise and exact $\rho$ (so neither noise nor triangulation can be blamed), and a sweep of the initial error
# (the same direction, scaled) on the noisy runs.

# %%
for n in des:
    print(f"{n:4s}: slowest closed-loop decay on the orbit {cv.decay[n]:.2f}/TU; predicted time from {e0 * KM:.0f} km "
          f"to {cv.bound[n] * KM:.0f} km: {cv.t_pred[n]:.2f} TU ({100 * cv.t_pred[n] / span:.1f} % of the period)")
print(f"h2 , no noise, exact rho: first below the guarantee at {cv.first_clean:.3f} TU "
      f"({100 * cv.first_clean / span:.1f} % of the period)")
for f_, tf in zip(cv.e0_scales, cv.first_sweep):
    print(f"h2 , initial error {f_ * e0 * KM:7.0f} km: first below the guarantee at {tf:.3f} TU "
          f"({100 * tf / span:.1f} % of the period)")

# %% [markdown]
# ## 5 · Fig. 3 — trajectories and errors
#
# (a), (b): truth (thick grey) and estimate (blue) over the whole orbit; the first 0.3 TU of the estimate (the
# convergence transient from the 10,900 km initial position error) is drawn in orange, and the insets magnify its first
# 0.1 TU. (c)-(e): position error of each observer on a common scale, thin at each sample and thick as a running
# RMS over 0.1 TU, with the design's guaranteed RMS (dashed; the EKF has none), the first sample below it
# (triangle), $\gamma$ (dotted) and the first 5 % of the period (grey), the window of the convergence criterion.
# The paper draws the errors of both observers in one panel; here each gets its own, because the H-infinity
# error, several times the H2 error after convergence (the medians are in the table), would hide the H2 trace.

# %%
lc = obs.line_crossings(sim, window=0.1)
fig = figures.fig3_observers(sim, cv, lc, model.system, GAMMA, SIGMA_DEG)
_ = plotting.save_figure(fig, "12_fig3_observers", output_dir=out)

# %% [markdown]
# **Reading the result.** Panels (c) and (d) show the two ways the observers miss the criterion (the numbers are
# printed in Section 4 and in the table). The H2 error falls slowly from the initial 10,900 km and first reaches
# its guarantee only after about a fifth of the period, as its slowest closed-loop pole predicts (Section 4);
# afterwards its running RMS stays near the guarantee with bumps
# well above it. The H-infinity error drops below its own, larger guarantee almost at once, but its running RMS then
# hovers above that guarantee for most of the orbit. Both LPV observers have a burst of error where the spacecraft
# crosses the Earth-Moon line ($y = 0$, printed below): there the triangulated $\rho$ is singular and $\rho(\hat x)$
# is used instead. The guarantee assumes exact $\rho$ (the diagnostic runs on the true $\rho$ show what it buys),
# whereas here $\rho$ comes from noisy angles (its error enters $A(\rho)$, $b(\rho)$ and $d(\rho)$, and is
# amplified near the Earth-Moon line), and the noise is held between samples (white noise only in the intensity
# sense). The EKF, which uses both
# angles as measurements and the full nonlinear model, is the yardstick: it has no burst at the line.

# %%
print("Earth-Moon line crossed (rho from the estimate) from t =", ", ".join(f"{t0:.2f}" for t0 in lc.starts), "TU")
for n in runs:
    at_line = lc.running_rms[n][lc.near & sim.settled]
    print(f"{n:4s}: after 10 % of the run, running RMS within 0.1 TU of a crossing up to "
          f"{at_line.max() * KM if at_line.size else np.nan:6.0f} km; median elsewhere "
          f"{np.median(lc.running_rms[n][~lc.near & sim.settled]) * KM:5.0f} km")

# %%
for n, label in (("h2", "H2"), ("hinf", "Hinf")):
    conv_ok, stay_ok = cv.converges(n, span), cv.stays(n)
    why = "; ".join(w for w, bad in (("not below the guarantee within 5 % of a period", not conv_ok),
                                     ("RMS after convergence above the guarantee", not stay_ok)) if bad)
    if not conv_ok:
        why += (f" (set by the initial error {e0 * KM:.0f} km and the slowest pole {cv.decay[n]:.1f}/TU: predicted "
                f"{cv.t_pred[n]:.2f} TU" + (f"; no noise, exact rho {cv.first_clean:.2f} TU" if n == "h2" else "") + ")")
    table.add(CLAIMS[f"{n}_converges"].judge(
        conv_ok and stay_ok, reason=why, shown=f"first below guarantee at {cv.first[n]:.2f} TU "
        f"({100 * cv.first[n] / span:.1f} % of period); RMS after {cv.rms[n] * KM:.0f} km vs guaranteed "
        f"{cv.bound[n] * KM:.0f} km", note=f"the bound assumes exact rho (with true rho: RMS {cv.rms_exact[n] * KM:.0f} "
        "km), here rho comes from noisy angles" + (f"; initial error unstated in the paper: sweep "
        f"{cv.e0_scales[0] * e0 * KM:.0f}-{e0 * KM:.0f} km meets 5 % up to {cv.e0_max_ok(e0 * KM, span):.0f} km"
        if n == "h2" else "")))
med = {n: sim.median_settled(n) for n in runs}

# %% [markdown]
# ## 6 · The same comparison at a sampling interval where the paper's numbers hold
#
# At this notebook's `DT` the H2 design allows far more than 0.1 deg per sample (Section 2). Notebook 11's window where both of the
# paper's numbers and its ordering hold on this orbit is roughly 100-400 min at the default disturbance level; at
# $\Delta t_{0.1} =
# 1/(\kappa_{H2}\sin 0.1°)^2$ (inside it) H2 allows exactly 0.1 deg per sample. Both observers are re-run there with
# the same 0.1 deg noise, initial error and criterion for "Hinf error larger than H2" (median position error after
# 10 % of the run, fixed before).

# %%
ww = obs.window_rerun(sc, od, sim, DT_01, PERIODS, SIGMA_DEG, np.random.default_rng(SEED + 1))
med_w = ww.median
print(f"dt = {DT_01:.4f} TU ({DT_01 * TU_MIN:.0f} min), {ww.n} samples: H2 allows "
      f"{des['h2'].noise_per_sample_deg(DT_01)[0]:.3f} deg per sample, Hinf {hinf_n:.4f} deg; median error after 10 % "
      f"of the run: H2 {med_w['h2'] * KM:.0f} km, Hinf {med_w['hinf'] * KM:.0f} km")
ok_no_range = all(not d.used[4:].any() and not np.any(d.gain()[:, 4:]) for d in des.values())
table.add(
    CLAIMS["hinf_larger"].judge(
        bool(med["hinf"] > med["h2"] and med_w["hinf"] > med_w["h2"]),
        shown=f"median {med['hinf'] * KM:.0f} vs {med['h2'] * KM:.0f} km at dt = {DT * TU_MIN:.1f} min; "
        f"{med_w['hinf'] * KM:.0f} vs {med_w['h2'] * KM:.0f} km at dt = {DT_01 * TU_MIN:.0f} min",
        note=f"0.1 deg noise is {SIGMA_DEG / h2_ps:.2f}x (dt {DT * TU_MIN:.1f} min) and "
        f"{SIGMA_DEG / des['h2'].noise_per_sample_deg(DT_01)[0]:.2f}x (dt {DT_01 * TU_MIN:.0f} min) the H2 and "
        f"{SIGMA_DEG / hinf_n:.2f}x the Hinf allowance"),
    CLAIMS["rho_from_estimate"].judge(frac, shown=f"{100 * frac:.1f} % of samples", note="threshold 0.04 taken from "
                                      "the paper; triangulation singular near the Earth-Moon line"),
    CLAIMS["no_range"].judge(
        bool(ok_no_range and med["h2"] < 0.1 * e0 and med["hinf"] < 0.1 * e0),
        shown=f"gain columns of r13^2, r23^2 {'zero' if ok_no_range else 'non-zero'}; median error after 10 % of the "
        f"run H2 {med['h2'] * KM:.0f}, Hinf {med['hinf'] * KM:.0f} km from {e0 * KM:.0f} km",
        note="only theta1, theta2 measured"),
    CLAIMS["ekf"].judge(ekf_rms, shown=f"RMS {ekf_rms * KM:.0f} km after 10 % of the run",
                        note="continuous-discrete EKF, sigma_acc = 1e-3 LU/TU^2"),
    CLAIMS["dt"].judge(DT, shown=f"{DT} TU ({DT * TU_MIN:.1f} min)"))

# %%
table.display()
