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
# it; observer Eq. 3a. All computation lives in `cislunar.estimation.lpv` and `cislunar.estimation.observers`.

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
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from cislunar.cr3bp.propagation import propagate
from cislunar.estimation import lpv
from cislunar.estimation.observers import (
    make_measurements,
    simulate_ekf,
    simulate_lpv_observer,
)
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable

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
    table.add_typed(f"{n} gain: solve status and verification", "-", f"{d.status}, |L| = {d.gain_norm:.0f}, worst {n} "
              f"norm {v.worst:.2e}", "beyond paper" if v.passed and d.optimal else "differs: verification failed",
              "Hinf with bandwidth bound R = 1000/TU" if n == "hinf" else "no gain bound")

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
_ = table.add_typed("ordering of allowances at the simulated dt", "H2 0.1 > Hinf 0.08 deg", f"H2 {h2_ps:.2f} deg per sample > "
              f"Hinf {hinf_n:.3f} deg" if h2_ps > hinf_n else f"H2 {h2_ps:.3f} < Hinf {hinf_n:.3f} deg",
              f"differs: only the ordering agrees; H2 allows {h2_ps:.2f} deg per sample, {h2_ps / 0.1:.1f}x the paper's "
              "0.1 deg" if h2_ps > hinf_n else "differs: reversed",
              f"per-sample reading at dt = {DT * TU_MIN:.1f} min (our choice), outside notebook 11's window where both "
              f"numbers hold; H2 = 0.1 deg per sample at dt = {DT_01 * TU_MIN:.0f} min (Section 6 simulates it); as an "
              f"intensity H2 allows {des['h2'].noise_deg[0]:.3f} deg < Hinf (notebook 11)")

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
t = np.arange(0.0, PERIODS * sc.orbit.period, DT)
truth = model.planar(propagate(model.system, sc.orbit.x0, t).x)
meas = make_measurements(model, t, truth, SIGMA_DEG, rng)
x_hat0 = truth[0] + np.array([0.02, -0.02, 0.01, 0.01])
runs = {n: simulate_lpv_observer(model, d.gain(), meas, x_hat0, truth) for n, d in des.items()}
P0 = np.diag([0.03, 0.03, 0.03, 0.03]) ** 2
exact = {n: simulate_lpv_observer(model, d.gain(), meas, x_hat0, truth, exact_rho=True) for n, d in des.items()}
runs["ekf"] = simulate_ekf(model, meas, x_hat0, P0, truth, sigma_acc=1e-3)
frac = runs["h2"].rho_from_estimate.mean()
e0 = float(runs["h2"].position_error[0])
th1_rate = np.abs(np.gradient(np.unwrap(model.angles(truth)[0]), t))  # rad/TU
print(f"{t.size} measurements; rho taken from the estimate on {100 * frac:.1f} % of them (|sin th3| < 0.04)")
print(f"initial position error {e0 * KM:.0f} km ({abs(x_hat0[0] - truth[0, 0]) * KM:.0f} km per axis)")
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
          f"({first[n] / span * 100:.1f} % of the period); RMS after {rms[n] * KM:7.1f} km; "
          "with exact rho (diagnostic) "
          f"{rms_exact[n] * KM:7.1f} km")
ekf_rms = float(np.sqrt(np.mean(runs["ekf"].position_error[settle] ** 2)))

# %% [markdown]
# **What sets the convergence time.** The criterion "within 5 % of a period" was fixed before the runs, but whether
# it can be met depends on an input the paper does not state: the initial error. The error decays no faster than
# the slowest closed-loop pole of $A(\rho)+LC(\rho)$ along the orbit allows, so falling from the initial error to
# the guarantee takes about $\ln(e_0/\text{bound})/|\mathrm{Re}\,\lambda|_{\min}$. Below: that prediction, a run
# with no noise and exact $\rho$ (so neither noise nor triangulation can be blamed), and a sweep of the initial error
# (the same direction, scaled) on the noisy runs.

# %%
decay = {}
for n, d in des.items():
    Lg = d.gain()
    ev = np.array([np.linalg.eigvals(model.A(r) + Lg @ model.C(r)).real.max() for r in sc.rho[::10]])
    decay[n] = float(-ev.max())  # slowest decay rate along the orbit, 1/TU
t_pred = {n: float(np.log(e0 / bound[n]) / decay[n]) for n in des}
meas_clean = make_measurements(model, t, truth, 0.0, np.random.default_rng(SEED))
clean = simulate_lpv_observer(model, des["h2"].gain(), meas_clean, x_hat0, truth, exact_rho=True)
first_clean = first_and_rms(clean, bound["h2"])[0]
for n in des:
    print(f"{n:4s}: slowest closed-loop decay on the orbit {decay[n]:.2f}/TU; predicted time from {e0 * KM:.0f} km "
          f"to {bound[n] * KM:.0f} km: {t_pred[n]:.2f} TU ({100 * t_pred[n] / span:.1f} % of the period)")
print(f"h2 , no noise, exact rho: first below the guarantee at {first_clean:.3f} TU "
      f"({100 * first_clean / span:.1f} % of the period)")
E0_SCALES = [0.003, 0.01, 0.03, 0.1, 0.3, 1.0]  # times the default initial error
first_sweep = []
for f_ in E0_SCALES:
    x0_f = truth[0] + f_ * (x_hat0 - truth[0])
    first_sweep.append(first_and_rms(simulate_lpv_observer(model, des["h2"].gain(), meas, x0_f, truth), bound["h2"])[0])
first_sweep = np.array(first_sweep)
for f_, tf in zip(E0_SCALES, first_sweep):
    print(f"h2 , initial error {f_ * e0 * KM:7.0f} km: first below the guarantee at {tf:.3f} TU "
          f"({100 * tf / span:.1f} % of the period)")
ok_e0 = [f_ * e0 * KM for f_, tf in zip(E0_SCALES, first_sweep) if tf <= 0.05 * span]
e0_max_ok = max(ok_e0) if ok_e0 else float("nan")

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
fig = plt.figure(figsize=(8.5, 9.4), layout="constrained")
top, bottom = fig.subfigures(2, 1, height_ratios=[1.62, 1.0])
ax_orb = top.subplots(1, 2)
n_tr = int(np.searchsorted(t, 0.3))
n_in = int(np.searchsorted(t, 0.1))
xlim = (-0.45, 1.08)  # the Moon (x = 0.99) in view; the empty right half holds the legend and the inset
ymax = 1.08 * max(np.abs(truth[:, 1]).max(), *(np.abs(runs[n].x_hat[:, 1]).max() for n in ("h2", "hinf")))
for a, n, title in ((ax_orb[0], "h2", "(a) H2 observer"), (ax_orb[1], "hinf", r"(b) H$_\infty$ observer")):
    xh = runs[n].x_hat
    a.plot(truth[:, 0], truth[:, 1], color="0.7", lw=3.0, label="truth", zorder=1)
    a.plot(xh[:, 0], xh[:, 1], color="C0", lw=0.7, label="estimate", zorder=2)
    a.plot(xh[:n_tr, 0], xh[:n_tr, 1], color="C3", lw=1.4, label="estimate, first 0.3 TU", zorder=3)
    a.plot(*xh[0, :2], "o", color="C3", ms=5, label="initial estimate", zorder=4)
    plotting.plot_primaries(a, model.system)
    a.set_xlabel("x [LU]")
    a.set_ylabel("y [LU]")
    a.set_aspect("equal")
    a.set_xlim(*xlim)
    a.set_ylim(-ymax, ymax)
    a.set_title(title, fontsize=10)
    a.legend(loc="upper right", fontsize=8)
    box = (0.52, 0.08, 0.45, 0.37)  # inset position, fraction of the axes
    ins = a.inset_axes(box)
    seg = np.vstack([truth[:n_in, :2], xh[:n_in, :2]])
    mid, half = seg.mean(axis=0), 0.6 * np.ptp(seg, axis=0)
    shape = box[3] * 2 * ymax / (box[2] * np.ptp(xlim))  # height / width of the inset in the parent's data units
    half = np.array([max(half[0], half[1] / shape), max(half[1], half[0] * shape)])  # same scale on x and y
    ins.plot(truth[:n_in, 0], truth[:n_in, 1], color="0.6", lw=2.5)
    ins.plot(xh[:n_in, 0], xh[:n_in, 1], color="C3", lw=1.0)
    ins.plot(*xh[0, :2], "o", color="C3", ms=4)
    ins.set_xlim(mid[0] - half[0], mid[0] + half[0])
    ins.set_ylim(mid[1] - half[1], mid[1] + half[1])
    ins.tick_params(labelsize=6.5)
    ins.xaxis.set_major_locator(plt.MaxNLocator(3))
    ins.yaxis.set_major_locator(plt.MaxNLocator(4))
    ins.set_title("first 0.1 TU, magnified", fontsize=7.5)
    a.indicate_inset_zoom(ins, edgecolor="0.3")
top.suptitle(f"Truth and estimate, {SIGMA_DEG} deg angle noise", fontsize=11)
ax_err = bottom.subplots(1, 3, sharey=True)
w = max(1, int(round(0.1 / DT)))  # samples in the 0.1 TU running window
n_win = np.convolve(np.ones(t.size), np.ones(w), mode="same")  # fewer samples in the windows at the ends
run_rms = {n: np.sqrt(np.convolve(runs[n].position_error**2, np.ones(w), mode="same") / n_win) for n in runs}
for a, (n, title, c) in zip(ax_err, (("h2", "(c) H2", "C0"), ("hinf", r"(d) H$_\infty$", "C1"),
                                     ("ekf", "(e) EKF (beyond paper)", "C2"))):
    a.axvspan(0.0, 0.05 * span, color="0.85", lw=0, zorder=0)
    a.semilogy(t, runs[n].position_error * KM, lw=0.4, color=c, alpha=0.4, zorder=1)
    a.semilogy(t, run_rms[n] * KM, lw=1.6, color=c, zorder=3)
    if n in bound:
        a.axhline(bound[n] * KM, color="k", ls="--", lw=1.0, zorder=4)
        if np.isfinite(first[n]):
            a.plot(first[n], bound[n] * KM, "v", color="k", ms=6, zorder=5)
    a.axhline(GAMMA * KM, color="k", ls=":", lw=0.8, zorder=2)
    a.set_xlabel("t [TU]")
    a.set_title(title, fontsize=10)
ax_err[0].set_ylabel("position error [km]")
ax_err[0].set_ylim(5.0, 5e4)
key = [Line2D([], [], color="0.4", lw=0.6, alpha=0.6, label="error at each sample"),
       Line2D([], [], color="0.4", lw=1.6, label="running RMS over 0.1 TU"),
       Line2D([], [], color="k", ls="--", lw=1.0, label=r"guaranteed RMS (LMI, exact $\rho$)"),
       Line2D([], [], color="k", ls="", marker="v", label="first below the guarantee"),
       Line2D([], [], color="k", ls=":", lw=0.8, label=r"$\gamma$ = 0.0013 LU"),
       Patch(color="0.85", label="first 5 % of the period")]
bottom.legend(handles=key, loc="outside lower center", ncol=3, fontsize=8)
bottom.suptitle("Position error (colour: observer)", fontsize=11)
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
on_line = runs["h2"].rho_from_estimate  # samples with |sin th3| < 0.04 (same measurements for every observer)
starts = t[on_line & ~np.r_[False, on_line[:-1]]]
near = np.zeros(t.size, dtype=bool)
for t0 in starts:
    near |= np.abs(t - t0) < 0.1
print("Earth-Moon line crossed (rho from the estimate) from t =", ", ".join(f"{t0:.2f}" for t0 in starts), "TU")
for n in runs:
    at_line = run_rms[n][near & settle]
    print(f"{n:4s}: after 10 % of the run, running RMS within 0.1 TU of a crossing up to "
          f"{at_line.max() * KM if at_line.size else np.nan:6.0f} km; median elsewhere "
          f"{np.median(run_rms[n][~near & settle]) * KM:5.0f} km")

# %%
for n, label in (("h2", "H2"), ("hinf", "Hinf")):
    conv_ok = first[n] <= 0.05 * span
    stay_ok = rms[n] <= bound[n]
    why = "; ".join(w for w, bad in (("not below the guarantee within 5 % of a period", not conv_ok),
                                     ("RMS after convergence above the guarantee", not stay_ok)) if bad)
    if not conv_ok:
        why += (f" (set by the initial error {e0 * KM:.0f} km and the slowest pole {decay[n]:.1f}/TU: predicted "
                f"{t_pred[n]:.2f} TU" + (f"; no noise, exact rho {first_clean:.2f} TU" if n == "h2" else "") + ")")
    table.add_typed(f"{label}: converges rapidly and stays accurate", "yes (Fig. 3)",
              f"first below guarantee at {first[n]:.2f} TU ({100 * first[n] / span:.1f} % of period); RMS after "
              f"{rms[n] * KM:.0f} km vs guaranteed {bound[n] * KM:.0f} km",
              "reproduced" if conv_ok and stay_ok else f"differs: {why}",
              "criterion fixed before: first below the bound within 5 % of a period, RMS after it below the bound; "
              f"the bound assumes exact rho (with true rho: RMS {rms_exact[n] * KM:.0f} km), here rho comes from "
              "noisy angles" + (f"; initial error unstated in the paper: sweep {E0_SCALES[0] * e0 * KM:.0f}-"
                                f"{e0 * KM:.0f} km meets 5 % up to {e0_max_ok:.0f} km" if n == "h2" else ""))
med = {n: float(np.median(runs[n].position_error[settle])) for n in runs}

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
t_w = np.arange(0.0, PERIODS * sc.orbit.period, DT_01)
truth_w = model.planar(propagate(model.system, sc.orbit.x0, t_w).x)
meas_w = make_measurements(model, t_w, truth_w, SIGMA_DEG, np.random.default_rng(SEED + 1))
x0_w = truth_w[0] + (x_hat0 - truth[0])
settle_w = t_w > 0.1 * (t_w[-1] - t_w[0])
med_w = {}
for n, d in des.items():
    r_w = simulate_lpv_observer(model, d.gain(), meas_w, x0_w, truth_w)
    med_w[n] = float(np.median(r_w.position_error[settle_w]))
print(f"dt = {DT_01:.4f} TU ({DT_01 * TU_MIN:.0f} min), {t_w.size} samples: H2 allows "
      f"{des['h2'].noise_per_sample_deg(DT_01)[0]:.3f} deg per sample, Hinf {hinf_n:.4f} deg; median error after 10 % "
      f"of the run: H2 {med_w['h2'] * KM:.0f} km, Hinf {med_w['hinf'] * KM:.0f} km")
table.add_typed("Hinf error larger than H2", "yes (Fig. 3c)", f"median {med['hinf'] * KM:.0f} vs {med['h2'] * KM:.0f} km "
          f"at dt = {DT * TU_MIN:.1f} min; {med_w['hinf'] * KM:.0f} vs {med_w['h2'] * KM:.0f} km at dt = "
          f"{DT_01 * TU_MIN:.0f} min",
          "reproduced" if med["hinf"] > med["h2"] and med_w["hinf"] > med_w["h2"] else
          "differs: H2 error not smaller at one of the two dt",
          "criterion fixed before: median position error after 10 % of the run larger for Hinf, at both dt; "
          f"0.1 deg noise is {SIGMA_DEG / h2_ps:.2f}x (dt {DT * TU_MIN:.1f} min) and "
          f"{SIGMA_DEG / des['h2'].noise_per_sample_deg(DT_01)[0]:.2f}x (dt {DT_01 * TU_MIN:.0f} min) the H2 and "
          f"{SIGMA_DEG / hinf_n:.2f}x the Hinf allowance")
table.add_typed("rho from estimate where |sin th3| < 0.04", "used", f"{100 * frac:.1f} % of samples", "derived",
          "threshold 0.04 taken from the paper; triangulation singular near the Earth-Moon line")
ok_no_range = all(not d.used[4:].any() and not np.any(d.gain()[:, 4:]) for d in des.values())
conv = {n: med[n] < 0.1 * e0 for n in ("h2", "hinf")}
table.add_typed("observers function without range sensors", "yes (Fig. 3)",
          f"gain columns of r13^2, r23^2 {'zero' if ok_no_range else 'non-zero'}; median error after 10 % of the run "
          f"H2 {med['h2'] * KM:.0f}, Hinf {med['hinf'] * KM:.0f} km from {e0 * KM:.0f} km",
          "reproduced" if ok_no_range and all(conv.values()) else "differs: range channels used or no convergence",
          "criterion fixed before: no range channel in the gains and the median error after 10 % of the run below "
          "a tenth of the initial error; only theta1, theta2 measured")
table.add_typed("EKF on same angles", "-", f"RMS {ekf_rms * KM:.0f} km after 10 % of the run", "beyond paper",
          "continuous-discrete EKF, sigma_acc = 1e-3 LU/TU^2")
_ = table.add_typed("measurement interval", "not stated", f"{DT} TU ({DT * TU_MIN:.1f} min)", "not in paper",
              "choice of this reproduction; continuous sensor, noise held over each interval")

# %%
table.display()
