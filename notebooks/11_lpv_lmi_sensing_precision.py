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
# # 11 · Optimal sensing precision with LPV H2 / H-infinity observers
#
# **What you will learn.** How the planar CR3BP is written *exactly* as an affine parameter-varying (LPV) system
# with celestial-angle sensors; how the paper's two convex programs (Theorem 1, H2; Theorem 2, H-infinity) pick
# the observer gain and the *least* sensor precision that keeps the position error below a bound gamma; which of
# the paper's printed formulas are inconsistent and which form is used here (each derived and tested); and how the
# result is checked without trusting the solver (Hurwitz and frozen-parameter norms on a dense sample of the
# parameter polytope).
#
# **Paper sections followed.** Nychka & Bhattacharya, *Optimal Sensing Precision for Celestial Navigation Systems
# in Cislunar Space using LPV Framework* (arXiv 2410.02013): §III-B..D (Eqs. 1-19, Theorems 1 and 2), §IV-A
# (Eqs. 20-23), §IV-B (Fig. 2, Eq. 24 and the 0.1 deg / 0.08 deg result at gamma = 0.0013). Beyond the paper: the
# independent verification and the trade curve of required precision against gamma.
#
# All computation lives in `cislunar.estimation.lpv`; cells call it and plot.

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: quick mode samples more coarsely but solves and verifies every problem.
N_ORBIT = 600 if QUICK else 4000  # samples along the orbit that bound rho
N_CHECK = 300 if QUICK else 5000  # random states for the exactness checks
N_VERIFY = 20 if QUICK else 1000  # random interior points of the polytope in the verification
N_STUDY = 400 if QUICK else 1000  # samples per orbit period in the sensitivity study
STUDY_ORBITS = [(3, 1, 0.3), (2, 1, 0.3), (2, 1, 0.4)] if QUICK else None  # None: all lpv.RESONANT_CANDIDATES
STUDY_LEVELS = [0.0, 1e-3] if QUICK else [0.0, 1e-4, 1e-3, 1e-2]
N_GAMMA = 4 if QUICK else 13  # gammas on the trade curve
R_LIST = [200.0, 1000.0, 5000.0] if QUICK else [100.0, 200.0, 500.0, 1000.0, 2000.0, 5000.0]  # 1/TU
R_BW = 1000.0  # 1/TU: the H-infinity bandwidth bound used for the comparison (about 1 per 6 min)

import warnings

import matplotlib.pyplot as plt
import matplotlib.ticker as mticker
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from cislunar.estimation import lpv
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
GAMMA = 0.0013  # LU, the paper's bound (about 500 km)
table = ComparisonTable("11 LPV optimal sensing precision (Nychka & Bhattacharya 2024, §III-IV, Fig. 2, Eq. 24)")

# %% [markdown]
# ## 1 · The planar CR3BP in affine LPV form (Eqs. 20, 21, 23)
#
# In the rotating frame (Earth at $(-\mu,0)$, Moon at $(1-\mu,0)$, $\mu=\pi_2$), with $r_{13}$ and $r_{23}$ the
# distances to Earth and Moon,
# $$\ddot x - 2\dot y - x = -\tfrac{1-\mu}{r_{13}^3}(x+\mu) - \tfrac{\mu}{r_{23}^3}(x-1+\mu),\qquad
#   \ddot y + 2\dot x - y = -\tfrac{1-\mu}{r_{13}^3}y - \tfrac{\mu}{r_{23}^3}y .$$
# With $\rho_1 = 1/r_{13}^3$, $\rho_2 = 1/r_{23}^3$ collect the terms in $x$ and the constant:
# $\ddot x = 2\dot y + a\,x + \mu(1-\mu)(\rho_2-\rho_1)$, $\ddot y = -2\dot x + a\,y$ with
# $a = 1-(1-\mu)\rho_1-\mu\rho_2$. This is exactly Eq. 21 (its two matrices add to Eq. 23's $A(\rho)$, with
# $a_{31}=a_{42}=a$) and $b_3 = \pi_2(\rho_1-\rho_2)(\pi_2-1)$ — **Eqs. 20, 21 and 23's $A, b$ agree.**
# The check below evaluates `A(rho) x + b(rho)` against the package's nonlinear vector field at random states.

# %%
model = lpv.CR3BPLPV()
states = np.column_stack([rng.uniform(-1.5, 1.5, (N_CHECK, 2)), rng.uniform(-2, 2, (N_CHECK, 2))])
f_nl = model.f(states)
err_dyn = np.max(np.abs(model.lpv_rhs(states) - f_nl) / np.maximum(1.0, np.abs(f_nl)))
print(f"max relative |A(rho)x + b(rho) - f(x)| over {N_CHECK} states: {err_dyn:.2e}")
EXACT_TOL = 1e-12  # fixed before: "exact" means agreement to rounding, max error below 1e-12
_ = table.add_typed("LPV form Eqs. 21/23 = CR3BP (Eq. 20)", "exact", f"max rel. error {err_dyn:.1e}",
              "reproduced" if err_dyn < EXACT_TOL else "differs: LPV form not exact",
              f"A(rho), b(rho) as printed; checked at random states; tolerance {EXACT_TOL:.0e} fixed before")

# %% [markdown]
# ## 2 · Sensor model (Eq. 22 versus Eq. 23)
#
# $\theta_1$ is the angle at the Earth between the Earth→Moon line and the Earth→spacecraft line, $\theta_2$ the
# angle at the Moon between the Moon→Earth line and the Moon→spacecraft line, $\theta_3=\pi-\theta_1-\theta_2$ the
# angle at the spacecraft. Then $\sin\theta_1 = \rho_3 y$, $\cos\theta_1 = \rho_3 x + \mu\rho_3$,
# $\sin\theta_2 = \rho_4 y$, $\cos\theta_2 = -\rho_4 x + (1-\mu)\rho_4$ with $\rho_3 = 1/r_{13}$,
# $\rho_4 = 1/r_{23}$, and $r_{13}^2 = (x + 2\mu)x + y\,y + \mu^2$, $r_{23}^2 = (x+2\mu-2)x + y\,y + (1-\mu)^2$,
# which is Eq. 22 with $\rho_5 = x$, $\rho_6 = y$ (the paper never defines $\rho_5,\rho_6$; reference notes).
# **Eq. 23 prints a different $d(\rho) = [0,\rho_3,0,-\rho_4,\rho_5+2\pi_2,\rho_5+2\pi_2-2]$**, which repeats a
# column of $C$ and drops the $\pi_2$ factors. Eq. 22's form is used; both are tested below.

# %%
y_nl = model.measure(states)
rho_s = model.rho(states)
err_22 = np.max(np.abs(model.lpv_measure(states) - y_nl))
y_23 = np.einsum("nij,nj->ni", model.C(rho_s), states) + model.d_as_printed_eq23(rho_s)
err_23 = np.max(np.abs(y_23 - y_nl))
err_tri = np.max(np.abs(model.rho_from_angles(*model.angles(states)) - rho_s) / np.abs(rho_s).clip(1e-3))
print(f"Eq. 22: max |C x + d - y| = {err_22:.2e};  Eq. 23 as printed: {err_23:.3f}")
print(f"rho from the two angles (law of sines): max relative error {err_tri:.1e}")
table.add_typed("sensor model Eq. 22 = geometry", "exact", f"max error {err_22:.1e}",
          "reproduced" if err_22 < EXACT_TOL else "differs: sensor model not exact",
          f"rho5 = x, rho6 = y (undefined in paper); tolerance {EXACT_TOL:.0e} fixed before")
_ = table.add_typed("Eq. 23 d(rho) as printed", "same model as Eq. 22", f"error up to {err_23:.2f}",
              "differs: Eq. 23's d(rho) is a misprint; Eq. 22 used", "Eq. 23 repeats a C column, drops pi2 factors")

# %% [markdown]
# ## 3 · The scheduling polytope from a planar resonant orbit
#
# The paper bounds $\rho$ on "a planar Earth-Moon resonant orbit" (its introduction, ref. [1], Frueh et al. 2021)
# without giving it. This reproduction uses the **planar 2:1 resonant orbit** (the spacecraft circles the Earth twice
# per synodic month, like TESS's lunar-resonant orbit), computed by single shooting from a Keplerian guess with
# perigee 0.3 LU on the far side of the Earth (`lpv.resonant_orbit`); the corrected orbit's perigee moves to the
# smallest $r_{13}$ printed below, on the Moon side. The box $[\min\rho_i, \max\rho_i]$ over one
# period gives $2^6 = 64$ vertices. The choice matters: Section 6 shows the H-infinity precision is set by the
# largest Earth distance on the orbit, and Section 9 repeats the whole design over eight planar resonant orbits
# (four resonances, several perigees).

# %%
sc = lpv.paper_scenario(n_samples=N_ORBIT)
box = sc.box
print(box.source)
for name, lo, hi in zip(lpv.RHO_NAMES, box.lower, box.upper):
    print(f"  rho {name:8s}: [{lo:9.4f}, {hi:9.4f}]")
V = box.vertices()
r13 = 1.0 / sc.rho[:, 2]
fig, ax = plt.subplots(figsize=(5.5, 5))
plotting.plot_rotating(ax, model.spatial(sc.states), label="2:1 resonant orbit")
plotting.plot_primaries(ax, model.system)
ax.legend(loc="upper right")
ax.set_title(f"scheduling box from this orbit: r13 in [{r13.min():.3f}, {r13.max():.3f}] LU")
_ = plotting.save_figure(fig, "11_resonant_orbit", output_dir=out)
table.add_typed("resonant orbit (planar)", "not stated", f"2:1, T = {sc.orbit.period:.4f} TU, r13 {r13.min():.3f}-"
          f"{r13.max():.3f} LU", "not in paper", "choice of this reproduction (paper gives no orbit)")
_ = table.add_typed("polytope vertices", "not stated", f"{V.shape[0]}", "derived", "2^6 box vertices of rho")

# %% [markdown]
# ## 4 · Theorems 1 and 2 as derived (and where the printed text disagrees)
#
# Error dynamics (Eq. 5): with $e = x - \hat x$ and the observer (3a),
# $\dot e = (A+LC)e + (B_{\bar w} + L D_{\bar w})\bar w$, $\epsilon = C_z e$ (Eq. 6 prints $LC_z$: a typo for
# $LC_y$; $D_{\bar w} = [D_dS_d\ S_n]$, Eq. 6 prints $B_dS_d$).
#
# * **Noise scaling.** The physical noise is $n = S_n\bar n$ and the precision is $\kappa_i = 1/\|n_i\|$, so
#   $S_n = \mathrm{diag}(1/\kappa_i)$ (the text says $\mathrm{diag}(\kappa_i)$). Then $(S_nS_n^T)^{-1} =
#   \mathrm{diag}(\kappa_i^2) = \mathrm{diag}(\beta)$, which is exactly the $-\mathrm{diag}(\beta)$ block of Eq. 12:
#   the printed LMI is right, the sentence defining $S_n$ is not.
# * **H2 (Theorem 1).** $\|G\|_2<\gamma$ iff $\exists P\succ0$: $(A+LC)P + P(A+LC)^T + (B_{\bar w}+LD_{\bar w})
#   (B_{\bar w}+LD_{\bar w})^T\prec0$ (the $LD_{\bar w}$ term carries the noise, hence $\beta$),
#   $\mathrm{tr}(C_zPC_z^T) < \gamma^2$ (Eq. 8b prints $<\gamma$; Eq. 13 uses $\gamma^2$, which is right).
#   $X=P^{-1}$, $Y = XL$ and two Schur complements give Eqs. 12-13.
# * **H-infinity (Theorem 2).** Bounded-real lemma $\mathrm{sym}(X(A+LC)) + C_z^TC_z + \gamma^{-2}X(B_{\bar w}+LD_{\bar w})
#   (B_{\bar w}+LD_{\bar w})^TX\prec0$ (Eq. 15 prints $C_zC_z^T$, dimensionally impossible). Eq. 18-19 lead to the block
#   $-\gamma^2\mathrm{diag}(\beta)$ with $\beta = (S_nS_n^T)^{-1} = \kappa^2$, so **$\kappa_i = \sqrt{\beta_i}$**;
#   the printed $\kappa_i=\sqrt{\beta_i/\gamma}$ does not follow (it would make the noise $1/\sqrt\gamma\approx28$
#   times smaller). Section 6 confirms $\sqrt{\beta}$ independently (the verified H-infinity norm equals gamma).
# * **Conditioning.** At $\gamma=0.0013$ the printed forms mix $10^{-6}$ and $10^{6}$. Both are solved in scaled
#   variables where $\gamma$ only scales $S_d\to S_d/\gamma$, with an order-one variable magnitude: for H2 the
#   variables $\tilde X=\gamma^2X$, $\tilde Y=\gamma^2 Y$, $\tilde\beta=\gamma^2\beta$; for H-infinity the
#   congruence $\mathrm{diag}(I, I/\gamma, I, I)$ of Eq. 19, which leaves $X$ (and $Y$) unchanged and gives
#   $\tilde\beta=\gamma^2\beta$. If Clarabel does not end `optimal`, the same problem
#   is re-solved under other equivalent scalings until it does (`PrecisionLMI.solve`). Section 5 shows that the
#   answer does not move with the tolerance, the strictness margin or the scaling.
# * **Well-posedness of Theorem 2.** Without a bound on the gain the H-infinity minimum is *not attained*: the
#   least precision is approached only as $\|L\|\to\infty$ (the earlier version of this notebook ended
#   `optimal_inaccurate` with $\|L\|\approx3\times10^7$). We add (beyond the paper) the bandwidth bound
#   $|\lambda(A(\rho)+LC(\rho))| < R$ at every vertex, an LMI in the same variables, with $R = 1000$/TU
#   (about one e-fold per 6 minutes); Section 5 shows how the precision tends to the unbounded limit as $R$ grows.
#   H2 needs no bound (its optimum has $\|L\|\approx 21$).
# * **Disturbance.** The paper never gives $B_d, S_d, D_d$. Default here: $B_d = [0;I_2]$, $S_d = 10^{-3}I$
#   LU/TU², $D_d=0$: three to eleven times below the solar tidal acceleration $2GM_\odot r/d_\odot^3$ that the CR3BP
#   ignores (both printed below in km/s²); Section 9's level $10^{-2}$ is of the solar-tide order.
#
# The LMIs are affine in $\rho$ (constant $X, Y$), so imposing them at the 64 vertices covers the whole box.
# Objective $\|\beta\|_1$ (sparse sensor selection); Clarabel. Two problems per norm: all six sensors offered
# (Fig. 2: which sensors does the optimum keep?) and only the $\theta_1$ channels it keeps (the comparison rows;
# their LMIs depend on $\rho_1,\rho_2,\rho_3$ only, 8 distinct vertices, and give the same precision).

# %%
ACC_KMS2 = model.system.length_unit_km / model.system.time_unit_s**2  # 1 LU/TU^2 in km/s^2
GM_SUN, D_SUN = 1.32712440018e11, 1.495978707e8  # km^3/s^2, km
tide = 2 * GM_SUN * np.array([0.3, 1.0]) * model.system.length_unit_km / D_SUN**3  # km/s^2 at r13 = 0.3, 1 LU
print(f"default S_d = 1e-3 LU/TU^2 = {1e-3 * ACC_KMS2:.1e} km/s^2; solar tide 2 GM_sun r / d^3 at r13 = 0.3-1 LU: "
      f"{tide[0]:.1e}-{tide[1]:.1e} km/s^2 = {tide[0] / ACC_KMS2:.4f}-{tide[1] / ACC_KMS2:.4f} LU/TU^2")
lmi = {"h2": lpv.PrecisionLMI.for_cr3bp(model, V, "h2"),
       "hinf": lpv.PrecisionLMI.for_cr3bp(model, V, "hinf", pole_radius=R_BW)}
des_all = {norm: lmi[norm].solve(GAMMA) for norm in lmi}
lmi1 = {"h2": lpv.PrecisionLMI.for_cr3bp(model, V, "h2", sensors=[0, 1]),
        "hinf": lpv.PrecisionLMI.for_cr3bp(model, V, "hinf", sensors=[0, 1], pole_radius=R_BW)}
des = {norm: lmi1[norm].solve(GAMMA) for norm in lmi1}
for norm in des:
    for label, d in (("all sensors", des_all[norm]), ("theta1 only", des[norm])):
        print(f"{norm:4s} {label:12s}: status {d.status}, |L| = {d.gain_norm:7.1f}, kappa(sin, cos th1) = "
              f"{np.array2string(d.kappa[:2], precision=2)}, Eq. 24 noise {d.noise_deg[0]:.5f} deg; sensors used: "
              f"{[n for n, u in zip(lpv.SENSOR_NAMES, d.used) if u]}")
for norm in des:
    table.add_typed(f"{norm} LMI at gamma = 0.0013: solver status", "-", f"{des_all[norm].status} (6 sensors), "
              f"{des[norm].status} (theta1); |L| = {des[norm].gain_norm:.0f}", "beyond paper",
              "Clarabel; Hinf with bandwidth bound R = 1000/TU" if norm == "hinf" else "Clarabel, no gain bound needed")

# %% [markdown]
# ## 5 · The solves are well posed: the numbers belong to the problem, not to the solver
#
# Two checks. (a) The $\theta_1$-only problems re-solved with a tighter tolerance (1e-9 instead of Clarabel's 1e-8),
# a tenfold smaller strictness margin and another variable scaling must return the same precision (the tests fix
# 1e-4 relative; SCS agrees to 2e-6 on the H2 problem but needs over two minutes, so it runs in
# `tests/estimation/test_lpv.py` on request, `CISLUNAR_SCS_TEST=1`). (b) The H-infinity precision against the bandwidth
# bound $R$: it rises towards the unbounded-gain limit $\sin^{-1}(\gamma/\max r_{13})$ while the gain grows
# like $R$ — the limit is the infimum of Theorem 2 as printed, and is never attained. (The curve stops at 5000/TU:
# beyond it the strictness margin of the scaled problem starts to act as a gain bound and the optimum stops growing.)

# %%
checks = {}
for norm, kw in (("h2", {}), ("hinf", {"pole_radius": R_BW})):
    alt = [lmi1[norm].solve(GAMMA, tol=1e-9),
           lpv.PrecisionLMI.for_cr3bp(model, V, norm, sensors=[0, 1], eps=1e-9, **kw).solve(GAMMA),
           lpv.PrecisionLMI.for_cr3bp(model, V, norm, sensors=[0, 1], variable_scale=3.0, **kw).solve(GAMMA)]
    dev = max(abs(a.kappa[0] / des[norm].kappa[0] - 1) for a in alt)
    checks[norm] = (dev, [a.status for a in alt])
    print(f"{norm:4s}: tol 1e-9 / eps 1e-9 / scale 3: statuses {checks[norm][1]}, max relative change of kappa "
          f"{dev:.1e}")
    table.add_typed(f"{norm} precision independent of solver settings", "-", f"max rel. change {dev:.0e} "
              f"({', '.join(checks[norm][1])})", "beyond paper" if dev < 1e-4 else "differs: solver-dependent",
              "tolerance 1e-9, margin 1e-9, variable scale 3 (criterion 1e-4 fixed before)")

r13max = 1.0 / box.lower[2]
limit = float(np.degrees(np.arcsin(GAMMA / r13max)))
lmi_R = {R: lpv.PrecisionLMI.for_cr3bp(model, V, "hinf", sensors=[0, 1], pole_radius=R) for R in R_LIST}
dR = {R: l.solve(GAMMA) for R, l in lmi_R.items()}
for R, d in dR.items():
    print(f"R = {R:7.0f}/TU: {d.status:18s} noise {d.noise_deg[0]:.5f} deg, |L| = {d.gain_norm:9.1f}")
fig, ax = plt.subplots(1, 2, figsize=(10, 3.6))
ax[0].semilogx(R_LIST, [dR[R].noise_deg[0] for R in R_LIST], "o-", label="bandwidth-bounded optimum")
ax[0].axhline(limit, color="k", ls="--", lw=0.8, label=rf"limit $\sin^{{-1}}(\gamma/\max r_{{13}})$ = {limit:.4f}°")
ax[0].set_xlabel("bandwidth bound R [1/TU]")
ax[0].set_ylabel(r"allowable $\theta_1$ noise [deg]")
ax[0].legend(loc="lower right")
ax[1].loglog(R_LIST, [dR[R].gain_norm for R in R_LIST], "s-", color="C1")
ax[1].set_xlabel("bandwidth bound R [1/TU]")
ax[1].set_ylabel(r"gain norm $\|L\|_2$ [non-dim.]")
fig.suptitle(r"H$_\infty$ (Theorem 2) at $\gamma$ = 0.0013 LU: precision and gain against the bandwidth bound")
for a in ax:
    a.xaxis.set_minor_formatter(mticker.NullFormatter())
_ = plotting.save_figure(fig, "11_hinf_bandwidth", output_dir=out)
_ = table.add_typed("Hinf precision vs bandwidth bound R", "-", f"{dR[R_LIST[0]].noise_deg[0]:.4f} deg (R={R_LIST[0]:.0f}) "
              f"-> {dR[R_LIST[-1]].noise_deg[0]:.4f} deg (R={R_LIST[-1]:.0f}); limit {limit:.4f} deg",
              "beyond paper", "the unbounded optimum is an infimum: gain grows like R")

# %% [markdown]
# ## 6 · Fig. 2 — optimal precision per sensor, and verification beyond the solver's word
#
# With all six sensors offered, the $\|\beta\|_1$ optimum keeps only $\sin\theta_1$ and $\cos\theta_1$ (the
# others get $\beta_i$ below $10^{-4}$ of the largest and are removed), as in the paper. The reason is visible in
# Eq. 22: once $\rho_3=1/r_{13}$ is scheduled, $\sin\theta_1$ and $\cos\theta_1$ measure $y$ and $x$ directly.
# Unused sensors are drawn as "unused", not as bars.
#
# Then, for each gain: eigenvalues of $A(\rho)+LC(\rho)$ and the frozen-parameter H2 norm (Lyapunov equation) and
# H-infinity norm (Hamiltonian level-set iteration; both checked against python-control in `tests/estimation/test_lpv.py`) of
# the error system with noise $1/\kappa_i$, at the 64 vertices and at `N_VERIFY` uniform random points in the box.

# %%
fig, ax = plt.subplots(figsize=(7.5, 3.8))
w = 0.38
xs = np.arange(6)
for i, (norm, label) in enumerate((("h2", "H2 (Thm 1)"), (
        "hinf", rf"H$_\infty$ (Thm 2, R = {R_BW:.0f}/TU)"))):
    d = des_all[norm]
    pos = xs + (i - 0.5) * w
    ax.bar(pos[d.used], d.kappa[d.used], w, label=label, color=f"C{i}")
    for x in pos[~d.used]:
        ax.text(x, 1.5, "unused", rotation=90, ha="center", va="bottom", fontsize=8, color=f"C{i}")
ax.set_yscale("log")
ax.set_ylim(1, 2e4)
ax.set_xticks(xs, lpv.SENSOR_NAMES)
ax.set_xlabel("sensor [-]")
ax.set_ylabel(r"precision $\kappa_i = \sqrt{\beta_i}$" "\n" r"[H$_\infty$: per unit output; H2: TU$^{-1/2}$]")
ax.set_title(rf"Fig. 2 analogue: optimal sensing precision, $\gamma$ = {GAMMA} LU, $\|\beta\|_1$")
ax.legend(loc="upper right")
_ = plotting.save_figure(fig, "11_fig2_precision", output_dir=out)

# %%
ver = {}
for key, d in (("h2", des["h2"]), ("hinf", des["hinf"]), ("h2 (6 sensors)", des_all["h2"]),
               ("hinf (6 sensors)", des_all["hinf"])):
    v = lpv.verify_observer(model, d, box, N_VERIFY, rng, L=d.L)
    ver[key] = v
    print(f"{key:16s}: {v.n_vertices} vertices + {v.n_samples} samples; max Re eig = {v.max_real_eig:.3f} /TU; "
          f"worst H2 = {v.worst_h2:.4e}, worst Hinf = {v.worst_hinf:.4e} (gamma {GAMMA}); passed: {v.passed}")
for norm in ("h2", "hinf"):
    v, v6 = ver[norm], ver[f"{norm} (6 sensors)"]
    table.add_typed(f"{norm} design verified (Hurwitz, norm < gamma)", "guaranteed by LMI",
              f"max Re eig {max(v.max_real_eig, v6.max_real_eig):.2f}, worst {norm} norm "
              f"{max(v.worst, v6.worst):.4e}", "beyond paper" if v.passed and v6.passed else
              "differs: verification failed", f"theta1-only and 6-sensor gains; {v.n_vertices} vertices + "
              f"{v.n_samples} samples")


# %% [markdown]
# **The objective norm is a choice.** The paper writes $\min\|\beta\|_p$ without fixing $p$; only a Remark says
# that $p=1$ gives sparse solutions. Fig. 2's two-sensor pattern therefore follows from picking $p=1$, made while
# looking at the paper's figure. The same six-sensor problems with $p=2$ and $p=\infty$ show what the other
# readings give (the $p=\infty$ H-infinity problem may end `optimal_inaccurate`: printed). Criteria fixed before
# comparing: a sensor is "used" if $\beta_i > 10^{-4}\max\beta$; "identical" means
# $|\kappa_{\sin}/\kappa_{\cos}-1| < 10^{-3}$.

# %%
SPARSE_TOL, SAME_TOL = 1e-4, 1e-3
des_p = {("l1", n): des_all[n] for n in des_all}
with warnings.catch_warnings():
    warnings.simplefilter("ignore", UserWarning)  # p = inf, Hinf: status printed below instead
    for obj in ("l2", "linf"):
        for n, kw in (("h2", {}), ("hinf", {"pole_radius": R_BW})):
            des_p[(obj, n)] = lpv.PrecisionLMI.for_cr3bp(model, V, n, objective=obj, **kw).solve(
                GAMMA, sparsity_tol=SPARSE_TOL)


def used_names(d):
    return ", ".join(nm for nm, u in zip(lpv.SENSOR_NAMES, d.used) if u)


def same_th1(d):
    return abs(d.kappa[0] / d.kappa[1] - 1) < SAME_TOL


for (obj, n), d in des_p.items():
    k_txt = np.array2string(d.kappa, formatter={"float_kind": lambda v: f"{v:.1f}"})
    print(f"p = {obj[1:]:3s} {n:4s}: {d.status:18s} kappa {k_txt}; used: "
          f"{used_names(d)}; kappa sin/cos th1 - 1 = {d.kappa[0] / d.kappa[1] - 1:+.1e}")
table.add_typed("objective norm p in min ||beta||_p", "not stated (Remark: p = 1 gives sparse solutions)", "p = 1",
          "not in paper", "chosen for the sparse pattern of Fig. 2; p = 2 and p = inf solved for comparison")
only_th1 = all((des_all[n].used[:2].all() and not des_all[n].used[2:].any()) for n in des_all)
other_p = "; ".join(f"p = {o[1:]}: {'all six' if all(des_p[(o, n)].used.all() for n in des_all) else 'other'} "
                    "sensors used" for o in ("l2", "linf"))
table.add_typed("sensors needed", "sin th1, cos th1 only", ", ".join(
    n for n, u in zip(lpv.SENSOR_NAMES, des_all["h2"].used & des_all["hinf"].used) if u),
    "consistent (tuned): only with p = 1" if only_th1 else "differs: other sensors selected with p = 1",
    f"both theorems; used = beta_i > {SPARSE_TOL:.0e} max beta (fixed before); {other_p}")
same_p = {o: all(same_th1(des_p[(o, n)]) for n in des_all) for o in ("l1", "l2", "linf")}
six_equal = all(np.ptp(des_p[("linf", n)].kappa) < SAME_TOL * des_p[("linf", n)].kappa.max() for n in des_all)
table.add_typed("precision sin th1 = cos th1", "identical",
          f"H2 {des_all['h2'].kappa[0]:.1f}/{des_all['h2'].kappa[1]:.1f}, "
          f"Hinf {des_all['hinf'].kappa[0]:.1f}/{des_all['hinf'].kappa[1]:.1f} (p = 1)",
          "consistent (tuned): only with p = 1 or p = inf" if same_p["l1"] and not same_p["l2"] else
          ("consistent (tuned): with p = 1" if same_p["l1"] else "differs: sin and cos th1 differ with p = 1"),
          f"identical = relative difference < {SAME_TOL:.0e} (fixed before); p = 2: H2 "
          f"{des_p[('l2', 'h2')].kappa[0]:.0f}/{des_p[('l2', 'h2')].kappa[1]:.0f}, Hinf "
          f"{des_p[('l2', 'hinf')].kappa[0]:.0f}/{des_p[('l2', 'hinf')].kappa[1]:.0f} "
          f"({'equal' if same_p['l2'] else 'not equal'}); p = inf: six "
          f"{'equal' if six_equal else 'unequal'}, H2 "
          f"{des_p[('linf', 'h2')].kappa[0]:.1f}, Hinf {des_p[('linf', 'hinf')].kappa[0]:.1f} "
          f"({des_p[('linf', 'hinf')].status})")
_ = table.add_typed("theta1-only = 6-sensor precision", "-", f"rel. diff. H2 "
              f"{abs(des['h2'].kappa[0] / des_all['h2'].kappa[0] - 1):.0e}, Hinf "
              f"{abs(des['hinf'].kappa[0] / des_all['hinf'].kappa[0] - 1):.0e}", "derived",
              "the comparison rows use the theta1-only problems")

# %% [markdown]
# **Reading the H-infinity result.** Its limit equals $\max r_{13}/\gamma$ in precision: the least precision is the
# one at which simply inverting the $\theta_1$ measurement ($x+\mu = r_{13}\cos\theta_1$, $y=r_{13}\sin\theta_1$)
# at the farthest point of the orbit gives error $\gamma$. So the paper's H-infinity number is set by the orbit's
# apogee distance. The H2 result has a moderate gain but is limited by one quadratic Lyapunov function having to
# serve the whole box ($\rho_1$ varies by a factor of ~40).

# %% [markdown]
# ## 7 · Allowable angle noise (Eq. 24) against the paper — and what the two numbers mean
#
# Eq. 24 converts the precision of the sine (or cosine) channel to an angle: $\delta\theta = \sin^{-1}(1/\kappa)$
# (its second form $\pi/2-\cos^{-1}(1/\kappa)$ is the same number). **The two norms give different kinds of
# number.** For H-infinity $1/\kappa$ bounds the noise *energy* (L2), so the time-RMS of any noise signal may reach
# $\delta\theta$. For H2, $1/\kappa^2$ is a white-noise *intensity* (rad²·TU): a sensor sampled every $\Delta t$
# with independent samples held over $\Delta t$ has intensity $\sigma^2\Delta t$, so it may have per-sample
# standard deviation $\sigma = \sin^{-1}(1/(\kappa\sqrt{\Delta t}))$. The paper compares the two directly and
# states no $\Delta t$. Read directly (intensity as if it were an angle), H2 allows *less* noise than H-infinity —
# the **reverse** of the paper's ordering; read per sample, H2 allows more than H-infinity for every
# $\Delta t$ below $\Delta t_= = 1/(\kappa_{H2}\sin\delta\theta_{H\infty})^2$ and exactly 0.1 deg at
# $\Delta t_{0.1} = 1/(\kappa_{H2}\sin 0.1°)^2$.
#
# Tolerances fixed before comparing, from the printed digits: "0.08°" means $[0.075, 0.085)$, "around 0.1°"
# (one significant digit) $[0.05, 0.15)$.

# %%
TU_MIN = model.system.time_unit_s / 60.0
noise = {norm: float(np.min(d.noise_deg[:2])) for norm, d in des.items()}
k2 = float(np.min(des["h2"].kappa[:2]))
dt_01 = 1.0 / (k2 * np.sin(np.radians(0.1))) ** 2
dt_eq = 1.0 / (k2 * np.sin(np.radians(noise["hinf"]))) ** 2
print(f"H2: {noise['h2']:.4f} deg (intensity reading);  Hinf: {noise['hinf']:.4f} deg")
print(f"H2 per sample = 0.1 deg at dt = {dt_01:.4f} TU ({dt_01 * TU_MIN:.0f} min); H2 > Hinf per sample for "
      f"dt < {dt_eq:.4f} TU ({dt_eq * TU_MIN:.0f} min)")
# The paper's own alternatives, printed as they stand: Eq. 8b literally (trace < gamma, not gamma^2) is the H2
# problem at bound sqrt(gamma); the printed kappa = sqrt(beta / gamma) divides our H-infinity kappa by sqrt(gamma).
h2_lit = float(lmi1["h2"].solve(np.sqrt(GAMMA)).noise_deg[0])
hinf_lit = float(np.degrees(np.arcsin(np.sqrt(GAMMA) / des["hinf"].kappa[0])))
k_paper = {"h2": 1.0 / np.sin(np.radians(0.1)), "hinf": 1.0 / np.sin(np.radians(0.08))}
print(f"Eq. 8b literal (trace < gamma): H2 {h2_lit:.3f} deg;  printed kappa = sqrt(beta/gamma): Hinf {hinf_lit:.4f} deg")
print(f"kappa implied by Eq. 24 and the paper's 0.1 / 0.08 deg: H2 {k_paper['h2']:.0f}, Hinf {k_paper['hinf']:.0f}; "
      f"here H2 {k2:.0f}, Hinf {des['hinf'].kappa[0]:.0f}")
in_h2 = lambda v: 0.05 <= v < 0.15  # noqa: E731
in_hinf = lambda v: 0.075 <= v < 0.085  # noqa: E731
table.add_typed("allowable theta1 noise, H2, intensity read as an angle", "0.1 deg", f"{noise['h2']:.4f} deg",
          "reproduced" if in_h2(noise["h2"]) else "differs: a white-noise intensity, not a per-sample angle",
          f"2:1 orbit; criterion [0.05, 0.15) deg fixed before; Section 9 tries other orbits and disturbances; Eq. 8b "
          f"read literally (trace < gamma) gives {h2_lit:.3f} deg, also outside")
table.add_typed("allowable theta1 noise, H2, per sample", "0.1 deg", f"0.1 deg at dt = {dt_01 * TU_MIN:.0f} min",
          "consistent (tuned)", "sampling interval chosen to match the paper's number (paper states none)")
table.add_typed("allowable theta1 noise, Hinf, gamma = 0.0013", "0.08 deg", f"{noise['hinf']:.4f} deg (R = {R_BW:.0f}/TU; "
          f"limit {limit:.4f})", "consistent (tuned)" if in_hinf(noise["hinf"]) else "differs: depends on max r13",
          f"= asin(gamma / max r13) in the limit; max r13 = {r13max:.3f} LU on the 2:1 orbit, an orbit choice not "
          "independent of the paper's number (Section 9 counts the resonances that fall in [0.075, 0.085))")
table.add_typed("ordering H2 > Hinf", "H2 0.1 > Hinf 0.08 deg",
          f"intensity reading: H2 {noise['h2']:.3f} < Hinf {noise['hinf']:.3f}; per sample: H2 > Hinf iff dt < "
          f"{dt_eq * TU_MIN:.0f} min", "differs: reversed unless the H2 number is read per sample",
          "the paper compares an intensity with an energy bound without a sampling interval")
table.add_typed("Hinf precision formula", "kappa = sqrt(beta/gamma)", "kappa = sqrt(beta)",
          "differs: printed formula does not follow from Eq. 18-19", "verified norm equals gamma with sqrt(beta); "
          f"the printed formula would give {hinf_lit:.4f} deg, not 0.08")
k_band = 1.0 / np.sin(np.radians([0.085, 0.075]))  # kappa band implied by the printed digits of 0.08 deg
_ = table.add_typed("kappa implied by Eq. 24 and the paper's 0.1 / 0.08 deg", f"H2 {k_paper['h2']:.0f}, Hinf {k_paper['hinf']:.0f}",
              f"H2 {k2:.0f}, Hinf {des['hinf'].kappa[0]:.0f}",
              (f"differs: H2 {k2 / k_paper['h2']:.1f}x the implied value (intensity reading)" if not in_h2(noise["h2"])
               else "consistent (tuned): H2 within the printed digits") + (
                  "; Hinf inside the band of the printed digits (orbit choice, see above)"
                  if k_band[0] < des["hinf"].kappa[0] <= k_band[1] else "; Hinf outside the band"),
              f"the paper prints no kappa: 1/sin(0.1 deg), 1/sin(0.08 deg); band for 0.08 deg [0.075, 0.085) is kappa "
              f"({k_band[0]:.0f}, {k_band[1]:.0f}]")

# %% [markdown]
# ## 8 · Beyond the paper: required precision against gamma
#
# The $\theta_1$-only problems are built once; `gamma` enters only through a `cp.Parameter` ($S_d/\gamma$), so the
# sweep re-uses the canonicalised problems. Without disturbance $\kappa\gamma$ would be exactly constant (the
# scaled problem does not depend on $\gamma$); the small $S_d$ bends the H2 curve only at small gamma, where
# $S_d/\gamma$ is largest.

# %%
gammas = np.geomspace(3e-4, 3e-2, N_GAMMA)
sweep = {norm: lpv.gamma_sweep(lmi1[norm], gammas) for norm in lmi1}
fig, ax = plt.subplots(1, 2, figsize=(8.5, 3.8), layout="constrained")
for norm, label in (("h2", "H2"), ("hinf", r"H$_\infty$")):
    k = np.array([np.nan if d is None else d.kappa[0] for d in sweep[norm]])
    nd = np.array([np.nan if d is None else d.noise_deg[0] for d in sweep[norm]])
    ax[0].loglog(gammas * model.system.length_unit_km, k, "o-", label=label)
    ax[1].loglog(gammas * model.system.length_unit_km, nd, "o-", label=label)
for a in ax:
    a.axvline(GAMMA * model.system.length_unit_km, color="k", lw=0.8, ls=":",
              label=rf"paper's $\gamma$ = {GAMMA} LU ({GAMMA * model.system.length_unit_km:.0f} km)")
    a.set_xlabel(r"$\gamma$ [km]")
fig.legend(*ax[0].get_legend_handles_labels(), loc="outside lower center", ncol=3)
ax[0].set_ylabel(r"required precision $\kappa_{\sin\theta_1}$" "\n" r"[H$_\infty$: per unit output; H2: TU$^{-1/2}$]")
ax[1].set_ylabel(r"Eq. 24 allowance $\sin^{-1}(1/\kappa)$" "\n" r"[H$_\infty$: deg RMS; H2: intensity, deg$\sqrt{\rm TU}$]")
fig.suptitle("trade curve: precision needed for a position-error bound")
_ = plotting.save_figure(fig, "11_tradecurve", output_dir=out)
slope = {n: np.polyfit(np.log(gammas), np.log([d.kappa[0] for d in sweep[n]]), 1)[0] for n in sweep}
print("log-log slope of kappa against gamma: " + ", ".join(f"{n} {s:.3f}" for n, s in slope.items()))
_ = table.add_typed("trade curve kappa(gamma)", "-", f"slopes H2 {slope['h2']:.2f}, Hinf {slope['hinf']:.2f}",
              "beyond paper", f"{N_GAMMA} gammas from 115 to 11500 km")

# %% [markdown]
# ## 9 · Where do the paper's numbers come from? A sweep over what the paper leaves unstated
#
# The paper states neither its orbit, nor its disturbance, nor a sampling interval. `lpv.sensitivity_study` solves
# both $\theta_1$-only theorems at $\gamma = 0.0013$ for eight planar Earth-Moon resonant orbits (4:1, 3:1, 5:2,
# 2:1 with several perigee radii), two disturbance structures (accelerations on the velocities; independent
# perturbations of all four states) and disturbance levels $0$ to $10^{-2}$ (LU/TU² for accelerations); each
# (orbit, structure, norm) problem is built once and the level is a `cp.Parameter`. The sampling interval enters
# afterwards, through the per-sample conversion of Section 7. We ask: where does H-infinity allow
# $[0.075, 0.085)$ deg, H2 per sample $[0.05, 0.15)$ deg, and H2 more than H-infinity?

# %%
study = lpv.sensitivity_study(GAMMA, orbits=STUDY_ORBITS or lpv.RESONANT_CANDIDATES, levels=STUDY_LEVELS,
                              pole_radius=R_BW, n_samples=N_STUDY, progress=True)
h2i, hinf = study.h2_intensity_deg, study.hinf_deg
n_opt = int(np.sum(study.h2_status == "optimal") + np.sum(study.hinf_status == "optimal"))
print(f"{2 * study.h2_kappa.size} solves in {study.seconds:.0f} s; {n_opt} ended optimal")
names = [f"{p}:{q} guess-rp {rp:.2f}" for p, q, rp in study.orbits]
print(f"{'orbit':20s} {'max r13':>8s} {'Hinf deg':>9s} {'H2 int. deg (acc, lvl 1e-3)':>28s} "
      f"{'dt for H2 = 0.1 deg [min]':>26s} {'H2 > Hinf for dt < [min]':>25s}")
j = int(np.argmin(np.abs(study.levels - 1e-3)))
dt01 = study.dt_for_h2(0.1)
dteq = 1.0 / (study.h2_kappa * np.sin(np.radians(hinf))) ** 2
for i, nm in enumerate(names):
    print(f"{nm:20s} {study.r13_max[i]:8.3f} {hinf[i, 0, j]:9.4f} {h2i[i, 0, j]:28.4f} "
          f"{dt01[i, 0, j] * TU_MIN:26.0f} {dteq[i, 0, j] * TU_MIN:25.0f}")

# %%
# Where do both of the paper's numbers hold?  Per orbit, structure and level: the dt window in which the H2
# per-sample allowance lies in [0.05, 0.15) deg and exceeds the H-infinity allowance, given Hinf in [0.075, 0.085).
lo = 1.0 / (study.h2_kappa * np.sin(np.radians(0.15))) ** 2
hi = np.minimum(1.0 / (study.h2_kappa * np.sin(np.radians(0.05))) ** 2, dteq)
ok_hinf = (hinf >= 0.075) & (hinf < 0.085)
ok_all = ok_hinf & (hi > lo)
hits = [(names[i], study.structures[s_], study.levels[l_], lo[i, s_, l_] * TU_MIN, hi[i, s_, l_] * TU_MIN)
        for i, s_, l_ in zip(*np.nonzero(ok_all))]
print(f"{ok_hinf[:, 0, 0].sum()} of {len(names)} orbits give Hinf in [0.075, 0.085) deg; "
      f"{len(hits)} of {ok_all.size} (orbit, structure, level) cases admit a sampling interval for the rest:")
for h in hits:
    print(f"  {h[0]:20s} {h[1]:13s} level {h[2]:<7g}: dt in [{h[3]:.0f}, {h[4]:.0f}) min")
never = float(np.nanmax(h2i))
# Per-sample sampling interval for H2 = 0.1 deg, split by disturbance level (the short intervals need a large one)
for l_i, lvl in enumerate(study.levels):
    print(f"dt for H2 = 0.1 deg per sample at level {lvl:g}: {np.nanmin(dt01[:, :, l_i]) * TU_MIN:.0f}-"
          f"{np.nanmax(dt01[:, :, l_i]) * TU_MIN:.0f} min over orbits and structures")
table.add_typed("sensitivity study (orbit, disturbance, dt)", "not stated", f"{len(names)} orbits x "
          f"{len(study.structures)} structures x {len(study.levels)} levels, {study.seconds:.0f} s, "
          f"{n_opt}/{2 * study.h2_kappa.size} optimal", "beyond paper", "theta1-only LMIs, Clarabel")
band = (GAMMA / np.sin(np.radians(0.085)), GAMMA / np.sin(np.radians(0.075)))
spread = float(np.nanmax(np.abs(hinf / hinf[:, :1, :1] - 1)))
n_hinf_ok = int(ok_hinf[:, 0, 0].sum())
table.add_typed("where Hinf = 0.08 deg", "0.08 deg", f"{n_hinf_ok} of {len(names)} orbits: "
          f"{', '.join(names[i] for i in np.nonzero(ok_hinf[:, 0, 0])[0]) or 'none'}",
          "consistent (tuned): only on the orbits listed" if n_hinf_ok else "differs: on no orbit tried",
          f"band [0.075, 0.085) fixed before; needs max r13 in [{band[0]:.3f}, {band[1]:.3f}] LU (unbounded-gain "
          f"limit); disturbance structure and level change it by at most {spread:.0e} (relative)")
h2_int_ok = bool(np.any((h2i >= 0.05) & (h2i < 0.15)))
table.add_typed("where H2 = 0.1 deg", "0.1 deg", f"{'in' if h2_int_ok else 'never in'} [0.05, 0.15) deg as an intensity "
          f"(max {never:.3f} deg); per sample at dt = {np.nanmin(dt01) * TU_MIN:.0f}-{np.nanmax(dt01) * TU_MIN:.0f} min",
          "differs: never as an intensity; matches only per sample at a chosen dt (consistent (tuned) there)"
          if not h2_int_ok else "consistent (tuned): as an intensity on some orbits/disturbances",
          "band [0.05, 0.15) fixed before; range over orbits, structures and levels; the per-sample reading needs a "
          "sampling interval, which the paper does not state")
_ = table.add_typed("both numbers and H2 > Hinf together", "yes", f"{len(hits)} of {ok_all.size} cases, e.g. "
              + (f"{hits[0][0]}, dt {hits[0][3]:.0f}-{hits[0][4]:.0f} min" if hits else "none"),
              "consistent (tuned): only in the cases listed" if hits else "differs: no tried combination reproduces both",
              f"only with the per-sample reading of H2, on an orbit with max r13 in [{band[0]:.2f}, {band[1]:.2f}] LU, "
              "for the dt windows listed")

# %% [markdown]
# **The study in one figure.** All three rows share the orbit axis, sorted by the largest Earth distance
# $\max r_{13}$; the shaded column marks the orbits whose H-infinity allowance falls in the paper's band.
# (a) The H-infinity allowance (accelerations, level $10^{-3}$; the other disturbances change it by the relative
# amount printed in the table) against its unbounded-gain limit $\sin^{-1}(\gamma/\max r_{13})$. (b) The H2
# allowance read directly as an angle, for every disturbance structure (marker) and level (colour), side by side
# within each orbit's slot. (c) The H2 allowance per sample: the sampling intervals at which it equals 0.1 deg
# (dot) or lies in the paper's printed range (bar), and the interval below which it exceeds the H-infinity one
# (red dash).

# %%
order = np.argsort(study.r13_max)
xo = np.arange(order.size)
n_s, n_l = len(study.structures), study.levels.size
fig, ax = plt.subplots(3, 1, figsize=(7.5, 9.0), sharex=True, layout="constrained")
for a in ax:
    for x in xo[ok_hinf[order, 0, j]]:
        a.axvspan(x - 0.45, x + 0.45, color="C7", alpha=0.15, lw=0, zorder=0)
# (a) H-infinity: optimum against its unbounded-gain limit
ax[0].axhspan(0.075, 0.085, color="C2", alpha=0.2, lw=0)
ax[0].plot(xo, hinf[order, 0, j], "o", color="C1", ms=6, zorder=3)
ax[0].plot(xo, np.degrees(np.arcsin(GAMMA / study.r13_max[order])), "_", color="k", ms=16, mew=1.2, zorder=4)
ax[0].set_ylabel(r"H$_\infty$ allowable noise [deg]")
ax[0].set_title(r"(a) H$_\infty$ (energy bound, an angle RMS directly)", fontsize=10, loc="left")
ax[0].legend(handles=[
    Line2D([], [], color="C1", marker="o", ls="", label=rf"optimum, R = {R_BW:.0f}/TU"),
    Line2D([], [], color="k", marker="_", ms=12, mew=1.2, ls="", label=r"limit $\sin^{-1}(\gamma/\max r_{13})$"),
    Patch(color="C2", alpha=0.2, label="paper's 0.08 deg (printed digits)"),
    Patch(color="C7", alpha=0.15, label=r"orbit with H$_\infty$ in the paper's band")],
    loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
# (b) H2 read directly: every structure and level, side by side within an orbit's slot
slot = 0.8 / (n_s * n_l)
colours = plt.cm.viridis(np.linspace(0.0, 0.8, n_l))
for s_i in range(n_s):
    for l_i in range(n_l):
        dx = (s_i * n_l + l_i + 0.5) * slot - 0.4
        ax[1].plot(xo + dx, h2i[order, s_i, l_i], ["o", "s"][s_i % 2], color=colours[l_i], ms=4.5,
                   mfc=colours[l_i] if s_i == 0 else "none", mew=1.2, ls="", zorder=3)
ax[1].axhspan(0.05, 0.15, color="C2", alpha=0.2, lw=0)
ax[1].set_yscale("log")
ax[1].set_ylabel("H2 allowance read\nas an angle [deg]")
ax[1].set_title("(b) H2 read directly (a white-noise intensity, not an angle)", fontsize=10, loc="left")
key = [Line2D([], [], color="0.3", marker="o", ls="", label="accelerations"),
       Line2D([], [], color="0.3", marker="s", mfc="none", mew=1.2, ls="", label="all four states")]
key += [Patch(color=colours[l_i], label=f"level {lvl:g}") for l_i, lvl in enumerate(study.levels)]
key += [Patch(color="C2", alpha=0.2, label="paper's 0.1 deg (printed digits)")]
ax[1].legend(handles=key, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8, title="disturbance on",
             title_fontsize=8)
# (c) H2 per sample: the sampling intervals that give the paper's number
k0 = (order, 0, j)
ax[2].vlines(xo, study.dt_for_h2(0.15)[k0] * TU_MIN, study.dt_for_h2(0.05)[k0] * TU_MIN,
             color="C0", lw=5, alpha=0.35, zorder=2)
ax[2].plot(xo, dt01[k0] * TU_MIN, "o", color="C0", ms=6, zorder=3)
ax[2].plot(xo, dteq[k0] * TU_MIN, "_", color="C1", ms=18, mew=2.0, zorder=2.5)
ax[2].set_yscale("log")
ax[2].set_ylabel(r"sampling interval $\Delta t$ [min]")
ax[2].set_title(f"(c) H2 per sample (accelerations, level {study.levels[j]:g})", fontsize=10, loc="left")
ax[2].legend(handles=[Line2D([], [], color="C0", lw=5, alpha=0.35, label="per-sample noise 0.05-0.15 deg"),
                      Line2D([], [], color="C0", marker="o", ls="", label="per-sample noise 0.1 deg"),
                      Line2D([], [], color="C1", marker="_", ms=14, mew=2.0, ls="",
                             label=r"H2 > H$_\infty$ for $\Delta t$ below")],
             loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
ax[2].set_xticks(xo, [f"{study.orbits[i][0]}:{study.orbits[i][1]}\nrp {study.orbits[i][2]:.2f}\n"
                      f"{study.r13_max[i]:.2f}" for i in order], fontsize=8)
ax[2].set_xlim(-0.5, order.size - 0.5)
ax[2].set_xlabel(r"resonant orbit p:q, perigee $r_p$ of the Keplerian guess [LU], $\max r_{13}$ [LU]; "
                 r"sorted by $\max r_{13}$")
fig.suptitle(r"Allowable $\theta_1$ noise at $\gamma$ = 0.0013 LU over the inputs the paper leaves unstated",
             fontsize=11)
for a in ax[1:]:  # plain numbers at 1-2-5 steps: readable whether the data span one decade or several
    a.yaxis.set_major_locator(mticker.LogLocator(subs=(1.0, 2.0, 5.0)))
    a.yaxis.set_major_formatter(mticker.FuncFormatter(lambda v, _: f"{v:g}"))
    a.yaxis.set_minor_formatter(mticker.NullFormatter())
_ = plotting.save_figure(fig, "11_sensitivity", output_dir=out)

# %% [markdown]
# **Reading it.** The H-infinity allowance sits on or just below its limit for every orbit, so it is a statement
# about the orbit's apogee, and only the orbit(s) in the shaded column give the paper's 0.08 deg. Read directly,
# the H2 allowance never reaches the paper's 0.1 deg band on any orbit, structure or level, and a larger
# disturbance only lowers it (most for perturbations of all four states at the largest level). Per sample, 0.1 deg
# needs sampling intervals of hours, except with a large disturbance: the largest level tried brings the interval
# down to minutes (the ranges per level are printed above); both of the paper's numbers and its ordering hold
# together only where, in the
# shaded column, the bar reaches below the red dash: the windows printed above.

# %%
table.display()
