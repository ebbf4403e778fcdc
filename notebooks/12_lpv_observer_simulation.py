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
# it; observer Eq. 3a. All computation lives in `cislunar.lpv` and `cislunar.observers`.

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

import matplotlib.pyplot as plt
import numpy as np

from cislunar import lpv, plotting
from cislunar.observers import make_measurements, simulate_ekf, simulate_lpv_observer
from cislunar.propagation import propagate
from cislunar.report import ComparisonTable

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
GAMMA = 0.0013
SIGMA_DEG = 0.1
R_BW = 1000.0  # 1/TU, H-infinity bandwidth bound (notebook 11)
KM = lpv.EARTH_MOON.length_unit_km
TU_MIN = lpv.EARTH_MOON.time_unit_s / 60.0
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
sc = lpv.paper_scenario(n_samples=N_ORBIT)
model, box = sc.model, sc.box
V = box.vertices()
des = {"h2": lpv.design_observer(model, V, GAMMA, "h2", sensors=[0, 1]),
       "hinf": lpv.design_observer(model, V, GAMMA, "hinf", sensors=[0, 1], pole_radius=R_BW)}
for n, d in des.items():
    v = lpv.verify_observer(model, d, box, N_VERIFY, rng)
    print(f"{n:4s}: {d.status}; kappa {d.kappa[:2].round(1)}, Eq. 24 noise {d.noise_deg[0]:.4f} deg, "
          f"|L| = {d.gain_norm:.1f}; verified: max Re eig {v.max_real_eig:.2f}, worst {n} {v.worst:.3e} < {GAMMA}: "
          f"{v.passed}")
    table.add(f"{n} gain: solve status and verification", "-", f"{d.status}, |L| = {d.gain_norm:.0f}, worst {n} "
              f"norm {v.worst:.2e}", "beyond paper" if v.passed and d.optimal else "differs: verification failed",
              "Hinf with bandwidth bound R = 1000/TU" if n == "hinf" else "no gain bound")

# %% [markdown]
# ## 2 · What the paper's 0.1 deg means for each design (outcome of notebook 11's sensitivity study)
#
# The H-infinity allowance bounds the noise energy, so it is an angle RMS directly: 0.0765 deg here. The H2
# allowance is a white-noise intensity; a sensor sampled every $\Delta t$ may have per-sample standard deviation
# $\sin^{-1}(1/(\kappa\sqrt{\Delta t}))$. Notebook 11 found: read as an angle, H2 allows *less* than H-infinity (the
# paper's ordering reversed) on every resonant orbit tried; per sample, H2 reaches 0.1 deg only for sampling
# intervals of hours, and H-infinity 0.08 deg only on orbits whose apogee lies at 0.88-0.99 LU from the Earth (the
# 2:1 resonance used here). At this notebook's sampling interval:

# %%
h2_ps = float(des["h2"].noise_per_sample_deg(DT)[0])
hinf_n = float(des["hinf"].noise_deg[0])
print(f"dt = {DT} TU ({DT * TU_MIN:.1f} min): H2 allows {h2_ps:.3f} deg per sample (intensity reading "
      f"{des['h2'].noise_deg[0]:.4f} deg); Hinf allows {hinf_n:.4f} deg RMS")
print(f"the simulated {SIGMA_DEG} deg is {SIGMA_DEG / h2_ps:.2f}x the H2 and {SIGMA_DEG / hinf_n:.2f}x the Hinf "
      "allowance")
table.add("ordering of allowances at the simulated dt", "H2 0.1 > Hinf 0.08 deg", f"H2 {h2_ps:.2f} deg per sample > "
          f"Hinf {hinf_n:.3f} deg" if h2_ps > hinf_n else f"H2 {h2_ps:.3f} < Hinf {hinf_n:.3f} deg",
          "consistent (tuned)" if h2_ps > hinf_n else "differs: reversed",
          f"per-sample reading at dt = {DT * TU_MIN:.1f} min (our choice); as an intensity H2 allows "
          f"{des['h2'].noise_deg[0]:.3f} deg < Hinf (notebook 11)")

# %% [markdown]
# ## 3 · Truth, measurements, scheduling parameters
#
# Truth: the 2:1 resonant orbit propagated with heyoka (`propagate`). Measurements every `DT` TU:
# $\tilde\theta_i = \theta_i + n_i$, $n_i\sim N(0, (0.1°)^2)$, both angles. The sensor output is continuous and
# each noise sample is held over `DT` (the white-noise model of intensity $\sigma^2\Delta t$ behind the H2
# per-sample reading; `observers.simulate_lpv_observer(hold="noise")`). Holding the whole measurement instead would
# make the observers lag the truth by about $|\dot\theta|\Delta t$, up to 1.5 deg near perigee at 25 min — far
# more than the noise. The observer $\dot{\hat x} = (A(\rho)+LC(\rho))\hat x - Ly + b(\rho) + Ld(\rho)$ (Eq. 3a) needs
# $\rho$; with the Earth-Moon baseline of 1 LU the law of sines gives $r_{13} = \sin\theta_2/\sin\theta_3$,
# $r_{23}=\sin\theta_1/\sin\theta_3$ and then $x, y$ — singular when $\sin\theta_3\to0$. Where
# $|\sin\tilde\theta_3|<0.04$ the observer uses $\rho(\hat x)$ (paper). Initial estimate error: 0.02 LU (7700 km)
# in x and y, 0.01 LU/TU (10 m/s) in each velocity ("large initial errors", unspecified in the paper).

# %%
t = np.arange(0.0, PERIODS * sc.orbit.period, DT)
truth = model.planar(propagate(model.system, sc.orbit.x0, t).x)
meas = make_measurements(model, t, truth, SIGMA_DEG, rng)
x_hat0 = truth[0] + np.array([0.02, -0.02, 0.01, 0.01])
runs = {n: simulate_lpv_observer(model, d.gain(), meas, x_hat0, truth) for n, d in des.items()}
P0 = np.diag([0.03, 0.03, 0.03, 0.03]) ** 2
exact = {n: simulate_lpv_observer(model, d.gain(), meas, x_hat0, truth, exact_rho=True) for n, d in des.items()}
runs["ekf"] = simulate_ekf(model, meas, x_hat0, P0, truth, sigma_acc=1e-3)
frac = runs["h2"].rho_from_estimate.mean()
print(f"{t.size} measurements; rho taken from the estimate on {100 * frac:.1f} % of them (|sin th3| < 0.04)")

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
dth = np.degrees(np.angle(np.exp(1j * (np.stack([meas.theta1, meas.theta2]) - np.stack(model.angles(truth))))))
noise_rms = float(np.sqrt(np.mean(dth[0] ** 2)))
bound = {"h2": lpv.guaranteed_error_rms(des["h2"], SIGMA_DEG, DT), "hinf": lpv.guaranteed_error_rms(des["hinf"],
                                                                                                    noise_rms)}
span = sc.orbit.period  # the reference time scale of the criterion


def first_and_rms(run, b):
    """First time the error falls below ``b`` and the RMS error from 2 % of a period after it (inf if never)."""
    below = run.position_error < b
    if not below.any():
        return np.inf, np.inf
    t_first = float(t[np.argmax(below)])
    after = t > t_first + 0.02 * span
    return t_first, float(np.sqrt(np.mean(run.position_error[after] ** 2))) if after.any() else np.inf


first, rms, rms_exact = {}, {}, {}
for n in bound:
    first[n], rms[n] = first_and_rms(runs[n], bound[n])
    rms_exact[n] = first_and_rms(exact[n], bound[n])[1]
settle = t > 0.1 * (t[-1] - t[0])
for n in bound:
    print(f"{n:4s}: guaranteed RMS {bound[n] * KM:7.1f} km; first below at {first[n]:.3f} TU "
          f"({first[n] / span * 100:.1f} % of the period); RMS after {rms[n] * KM:7.1f} km; with exact rho (diagnostic) "
          f"{rms_exact[n] * KM:7.1f} km")
ekf_rms = float(np.sqrt(np.mean(runs["ekf"].position_error[settle] ** 2)))

# %% [markdown]
# ## 5 · Fig. 3 — trajectories and errors
#
# (a), (b): truth and estimate; the first 0.3 TU of the estimate (the convergence transient from the 7700 km
# initial error) is drawn in red, with insets magnifying it. (c): position error of both observers (thin: raw,
# thick: running RMS over 0.1 TU) with each design's guaranteed RMS (dashed) and gamma.

# %%
fig, ax = plt.subplots(1, 3, figsize=(16, 5))
n_tr = int(np.searchsorted(t, 0.3))
for a, n, title in ((ax[0], "h2", "(a) H2 observer"), (ax[1], "hinf", r"(b) H$_\infty$ observer")):
    xh = runs[n].x_hat
    a.plot(truth[:, 0], truth[:, 1], color="k", lw=1.2, label="truth")
    a.plot(xh[:, 0], xh[:, 1], color="C0", lw=0.8, alpha=0.8, label="estimate")
    a.plot(xh[:n_tr, 0], xh[:n_tr, 1], color="C3", lw=1.2, label="estimate, first 0.3 TU")
    a.plot(*xh[0, :2], "o", color="C3", ms=5, label="initial estimate")
    plotting.plot_primaries(a, model.system)
    a.set_xlabel("x [LU]")
    a.set_ylabel("y [LU]")
    a.set_aspect("equal")
    a.set_ylim(-1.05, 0.75)
    a.set_title(f"{title}, {SIGMA_DEG} deg noise")
    a.legend(loc="upper right", fontsize=7)
    ins = a.inset_axes([0.6, 0.05, 0.37, 0.37])
    ins.plot(truth[:n_tr, 0], truth[:n_tr, 1], color="k", lw=1.2)
    ins.plot(xh[:n_tr, 0], xh[:n_tr, 1], color="C3", lw=1.0)
    ins.plot(*xh[0, :2], "o", color="C3", ms=4)
    cx, cy = truth[0, :2]
    ins.set_xlim(cx - 0.04, cx + 0.04)
    ins.set_ylim(cy - 0.05, cy + 0.05)
    ins.tick_params(labelsize=6)
    ins.set_title("transient", fontsize=7)
w = max(1, int(round(0.1 / DT)))
kern = np.ones(w) / w
for n, label, c in (("h2", "H2", "C0"), ("hinf", r"H$_\infty$", "C1"), ("ekf", "EKF (beyond paper)", "C2")):
    e = runs[n].position_error * KM
    ax[2].semilogy(t, e, lw=0.4, color=c, alpha=0.35)
    ax[2].semilogy(t, np.sqrt(np.convolve(e**2, kern, mode="same")), lw=1.6, color=c, label=f"{label} (running RMS)")
    if n in bound:
        ax[2].axhline(bound[n] * KM, color=c, ls="--", lw=1.0, label=f"{label} guaranteed RMS")
ax[2].axhline(GAMMA * KM, color="k", ls=":", lw=0.8, label=r"$\gamma$ = 0.0013 LU")
ax[2].set_xlabel("t [TU]")
ax[2].set_ylabel("position error [km]")
ax[2].set_title("(c) error comparison")
ax[2].legend(loc="upper right", fontsize=7, ncol=2)
ax[2].set_ylim(bottom=max(1.0, 0.3 * min(np.min(runs[n].position_error) for n in runs) * KM), top=1e6)
_ = plotting.save_figure(fig, "12_fig3_observers", output_dir=out)

# %% [markdown]
# **Reading the result.** Whether the observers converge and then stay within the LMI's guarantee is printed above
# and in the table. The guarantee assumes exact $\rho$ (the diagnostic runs on the true $\rho$ show what it buys), whereas here $\rho$ comes from noisy angles (its error enters $A(\rho)$, $b(\rho)$ and $d(\rho)$, and
# is amplified near the Earth-Moon line, where the estimate is used instead), and the measurement is held between
# samples. The EKF, which uses both angles as measurements and the full nonlinear model, is the yardstick.

# %%
for n, label in (("h2", "H2"), ("hinf", "Hinf")):
    conv_ok = first[n] <= 0.05 * span
    stay_ok = rms[n] <= bound[n]
    why = "; ".join(w for w, bad in (("not below the guarantee within 5 % of a period", not conv_ok),
                                     ("RMS after convergence above the guarantee", not stay_ok)) if bad)
    table.add(f"{label}: converges rapidly and stays accurate", "yes (Fig. 3)",
              f"first below guarantee at {first[n]:.2f} TU ({100 * first[n] / span:.1f} % of period); RMS after "
              f"{rms[n] * KM:.0f} km vs guaranteed {bound[n] * KM:.0f} km",
              "reproduced" if conv_ok and stay_ok else f"differs: {why}",
              "criterion fixed before: first below the bound within 5 % of a period, RMS after it below the bound; "
              f"the bound assumes exact rho (with true rho: RMS {rms_exact[n] * KM:.0f} km), here rho comes from "
              "noisy angles")
med = {n: float(np.median(runs[n].position_error[settle])) for n in runs}
table.add("Hinf error larger than H2", "yes (Fig. 3c)", f"median {med['hinf'] * KM:.0f} vs {med['h2'] * KM:.0f} km "
          "after 10 % of the run", "reproduced" if med["hinf"] > med["h2"] else "differs: H2 error not smaller here",
          f"both runs use {SIGMA_DEG} deg: {SIGMA_DEG / h2_ps:.2f}x the H2 and {SIGMA_DEG / hinf_n:.2f}x the Hinf "
          "allowance")
table.add("rho from estimate where |sin th3| < 0.04", "used", f"{100 * frac:.1f} % of samples", "reproduced",
          "triangulation singular near the Earth-Moon line")
table.add("EKF on same angles", "-", f"RMS {ekf_rms * KM:.0f} km after 10 % of the run", "beyond paper",
          "continuous-discrete EKF, sigma_acc = 1e-3 LU/TU^2")
table.add("measurement interval", "not stated", f"{DT} TU ({DT * TU_MIN:.1f} min)", "not in paper",
          "choice of this reproduction; continuous sensor, noise held over each interval")

# %%
table.display()
