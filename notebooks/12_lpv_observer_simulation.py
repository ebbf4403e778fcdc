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
# instead near the Earth-Moon line ($|\sin\theta_3|<0.04$); and how an extended Kalman filter on the same
# measurements compares (beyond the paper).
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
DT = 0.01 if QUICK else 0.0025  # measurement interval, TU (0.01 TU = 1.04 h)
N_ORBIT = 600 if QUICK else 4000  # samples bounding rho
N_VERIFY = 30 if QUICK else 500  # interior samples in the gain verification

import warnings

import matplotlib.pyplot as plt
import numpy as np

from cislunar import lpv, plotting
from cislunar.observers import make_measurements, simulate_ekf, simulate_lpv_observer
from cislunar.propagation import propagate
from cislunar.report import ComparisonTable

warnings.filterwarnings("ignore", message="Solution may be inaccurate")
plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
GAMMA = 0.0013
SIGMA_DEG = 0.1
KM = lpv.EARTH_MOON.length_unit_km
table = ComparisonTable("12 LPV observer simulation (Nychka & Bhattacharya 2024, §IV-B, Fig. 3)")

# %% [markdown]
# ## 1 · Implementable gains
#
# The observer only uses $\sin\theta_1,\cos\theta_1$ (notebook 11: the $\|\beta\|_1$ optimum drops the other
# sensors). The unconstrained H-infinity optimum has an unbounded gain, so both designs here add the pole region
# $|\lambda(A+LC)| < R = 200$/TU at every vertex (beyond the paper; H2 is unchanged by it) and are restricted to
# the two $\theta_1$ channels. Each gain is verified (Hurwitz and norm < gamma on vertices and random samples).

# %%
sc = lpv.paper_scenario(n_samples=N_ORBIT)
model, box = sc.model, sc.box
V = box.vertices()
des = {n: lpv.design_observer(model, V, GAMMA, n, pole_radius=200.0, sensors=[0, 1]) for n in ("h2", "hinf")}
for n, d in des.items():
    v = lpv.verify_observer(model, d, box, N_VERIFY, rng)
    print(f"{n:4s}: kappa {d.kappa[:2].round(1)}, noise {d.noise_deg[:2].round(4)} deg, |L|max {np.abs(d.L).max():.1f};"
          f" verified: max Re eig {v.max_real_eig:.2f}, worst {n} {v.worst:.3e} < {GAMMA}: {v.passed}")
    table.add(f"{n} gain with |lambda| < 200/TU verified", "-", f"worst {n} norm {v.worst:.2e}, noise "
              f"{d.noise_deg[0]:.3f} deg", "beyond paper" if v.passed else "differs: verification failed",
              "pole region added for integrability")

# %% [markdown]
# ## 2 · Truth, measurements, scheduling parameters
#
# Truth: the 2:1 resonant orbit propagated with heyoka (`propagate`). Measurements every `DT` TU:
# $\tilde\theta_i = \theta_i + n_i$, $n_i\sim N(0, (0.1°)^2)$, both angles, held between samples. The observer
# $\dot{\hat x} = (A(\rho)+LC(\rho))\hat x - Ly + b(\rho) + Ld(\rho)$ (Eq. 3a) needs $\rho$; with the Earth-Moon
# baseline of 1 LU the law of sines gives $r_{13} = \sin\theta_2/\sin\theta_3$, $r_{23}=\sin\theta_1/\sin\theta_3$
# and then $x, y$ — singular when $\sin\theta_3\to0$. Where $|\sin\tilde\theta_3|<0.04$ the observer uses
# $\rho(\hat x)$ (paper). Initial estimate error: 0.02 LU (7700 km) in x and y, 0.01 LU/TU (10 m/s) in each
# velocity ("large initial errors", unspecified in the paper).

# %%
t = np.arange(0.0, PERIODS * sc.orbit.period, DT)
truth = model.planar(propagate(model.system, sc.orbit.x0, t).x)
meas = make_measurements(model, t, truth, SIGMA_DEG, rng)
x_hat0 = truth[0] + np.array([0.02, -0.02, 0.01, 0.01])
runs = {n: simulate_lpv_observer(model, d.gain(), meas, x_hat0, truth) for n, d in des.items()}
P0 = np.diag([0.03, 0.03, 0.03, 0.03]) ** 2
runs["ekf"] = simulate_ekf(model, meas, x_hat0, P0, truth, sigma_acc=1e-3)
frac = runs["h2"].rho_from_estimate.mean()
print(f"{t.size} measurements; rho taken from the estimate on {100 * frac:.1f} % of them (|sin th3| < 0.04)")

# %% [markdown]
# ## 3 · Fig. 3 — trajectories and errors

# %%
fig, ax = plt.subplots(1, 3, figsize=(15, 4.6))
for a, n, title in ((ax[0], "h2", "(a) H2 observer"), (ax[1], "hinf", r"(b) H$_\infty$ observer")):
    plotting.plot_rotating(a, model.spatial(truth), color="k", lw=1.2, label="truth")
    plotting.plot_rotating(a, model.spatial(runs[n].x_hat), color="C1", lw=0.8, alpha=0.8, label="estimate")
    plotting.plot_primaries(a, model.system)
    a.set_title(f"{title}, {SIGMA_DEG} deg noise")
    a.legend(loc="upper right")
for n, label in (("h2", "H2"), ("hinf", r"H$_\infty$"), ("ekf", "EKF (beyond paper)")):
    ax[2].semilogy(t, runs[n].position_error * KM, lw=0.8, label=label)
ax[2].axhline(GAMMA * KM, color="k", ls=":", lw=0.8, label=r"$\gamma$ = 0.0013 LU")
ax[2].set_xlabel("t [TU]")
ax[2].set_ylabel("position error [km]")
ax[2].set_title("(c) error comparison")
ax[2].legend()
plotting.save_figure(fig, "12_fig3_observers", output_dir=out)

# %%
settle = t > 0.1 * PERIODS * sc.orbit.period  # after the initial transient
stats = {n: (np.median(r.position_error[settle]) * KM, np.sqrt(np.mean(r.position_error[settle] ** 2)) * KM,
             np.max(r.position_error[settle]) * KM) for n, r in runs.items()}
conv = {n: t[np.argmax(r.position_error < GAMMA)] for n, r in runs.items()}
below = {n: float(np.mean(r.position_error[settle] < GAMMA)) for n, r in runs.items()}  # after settling
for n, (med, rms, mx) in stats.items():
    print(f"{n:4s}: median {med:7.1f} km, rms {rms:7.1f} km, max {mx:8.1f} km; first below gamma at t = {conv[n]:.3f} TU")

# %% [markdown]
# **Reading the result.** Both LPV observers converge from a 10,900 km initial error and then stay at the level
# printed above, but their error is *not* bounded by gamma everywhere: the LMIs treat $\rho$ as
# exactly known, while here it comes from noisy angles (its error enters $A(\rho)$, $b(\rho)$ and $d(\rho)$), and
# near the Earth-Moon line it comes from the estimate. The EKF, which uses both angles as measurements and the
# full nonlinear model, is more accurate on the same data (numbers in the table).

# %%
table.add("observers converge from large initial error", "yes (Fig. 3c)",
          f"first below gamma at {conv['h2']:.2f} TU (H2), {conv['hinf']:.2f} TU (Hinf); after settling below gamma "
          f"{100 * below['h2']:.0f}% (H2) and {100 * below['hinf']:.0f}% (Hinf) of the time",
          "reproduced" if min(below["h2"], below["hinf"]) > 0.5 else
          "differs: after the first dip the error stays above gamma most of the time",
          "initial error 0.028 LU, 0.014 LU/TU (our choice); rho comes from noisy angles, which the LMIs do not model")
table.add("H2 position error after convergence", "small (Fig. 3c, no number)",
          f"median {stats['h2'][0]:.0f} km, max {stats['h2'][2]:.0f} km", "derived", f"{SIGMA_DEG} deg on both angles")
table.add("Hinf error larger than H2", "yes (Fig. 3c)", f"median {stats['hinf'][0]:.0f} vs {stats['h2'][0]:.0f} km",
          "reproduced" if stats["hinf"][0] > stats["h2"][0] else "differs: H2 error not smaller here",
          "both runs use 0.1 deg: about 5x the H2 allowance and 1.4x the Hinf allowance of notebook 11")
table.add("rho from estimate where |sin th3| < 0.04", "used", f"{100 * frac:.1f} % of samples", "reproduced",
          "triangulation singular near the Earth-Moon line")
table.add("EKF on same angles", "-", f"median {stats['ekf'][0]:.0f} km, max {stats['ekf'][2]:.0f} km",
          "beyond paper", "continuous-discrete EKF, sigma_acc = 1e-3 LU/TU^2")
table.add("measurement interval", "not stated", f"{DT} TU ({DT * lpv.EARTH_MOON.time_unit_s / 60:.0f} min)",
          "not in paper", "choice of this reproduction")

# %%
table.display()
