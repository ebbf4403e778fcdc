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
# The methods live in `cislunar.estimation.lpv`; the chapter's studies in
# `cislunar.papers.nychka_bhattacharya.sensing_precision` (each returns a frozen result), its figures in
# `...figures` and its claims, declared before comparing, in `...claims.sensing_precision`. Cells call, print and plot.

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
STUDY_ORBITS = [(3, 1, 0.3), (2, 1, 0.3), (2, 1, 0.4)] if QUICK else None  # None: all RESONANT_CANDIDATES
STUDY_LEVELS = [0.0, 1e-3] if QUICK else [0.0, 1e-4, 1e-3, 1e-2]
N_GAMMA = 4 if QUICK else 13  # gammas on the trade curve
R_LIST = [200.0, 1000.0, 5000.0] if QUICK else [100.0, 200.0, 500.0, 1000.0, 2000.0, 5000.0]  # 1/TU

import numpy as np

from cislunar.estimation import lpv
from cislunar.papers.nychka_bhattacharya import figures
from cislunar.papers.nychka_bhattacharya import sensing_precision as sp
from cislunar.papers.nychka_bhattacharya.claims.sensing_precision import CLAIMS
from cislunar.papers.nychka_bhattacharya.scenarios import (
    GAMMA,
    POLE_RADIUS,
    RESONANT_CANDIDATES,
    paper_scenario,
)
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
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
ex = sp.exactness_checks(model, N_CHECK, rng)
print(f"max relative |A(rho)x + b(rho) - f(x)| over {N_CHECK} states: {ex.dynamics:.2e}")
_ = table.add(CLAIMS["lpv_exact"].judge(ex.dynamics, shown=f"max rel. error {ex.dynamics:.1e}",
                                        note="A(rho), b(rho) as printed; checked at random states"))

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
print(f"Eq. 22: max |C x + d - y| = {ex.sensors_eq22:.2e};  Eq. 23 as printed: {ex.sensors_eq23:.3f}")
print(f"rho from the two angles (law of sines): max relative error {ex.triangulation:.1e}")
table.add(CLAIMS["eq22_exact"].judge(ex.sensors_eq22, shown=f"max error {ex.sensors_eq22:.1e}",
                                     note="rho5 = x, rho6 = y (undefined in paper)"),
          CLAIMS["eq23_d"].judge(ex.sensors_eq23, shown=f"error up to {ex.sensors_eq23:.2f}"))

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
sc = paper_scenario(n_samples=N_ORBIT)
box = sc.box
print(box.source)
for name, lo, hi in zip(lpv.RHO_NAMES, box.lower, box.upper):
    print(f"  rho {name:8s}: [{lo:9.4f}, {hi:9.4f}]")
V = box.vertices()
_ = plotting.save_figure(figures.resonant_orbit(sc), "11_resonant_orbit", output_dir=out)
r13 = sc.r13_range
table.add(CLAIMS["orbit"].judge(f"2:1, T = {sc.orbit.period:.4f} TU, r13 {r13[0]:.3f}-{r13[1]:.3f} LU"),
          CLAIMS["vertices"].judge(V.shape[0], shown=f"{V.shape[0]}", note="2^6 box vertices of rho"))

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
D = sp.paper_designs(sc, GAMMA, POLE_RADIUS)
des, des_all = D.theta1, D.all
for norm in sp.NORMS:
    for label, d in (("all sensors", des_all[norm]), ("theta1 only", des[norm])):
        print(f"{norm:4s} {label:12s}: status {d.status}, |L| = {d.gain_norm:7.1f}, kappa(sin, cos th1) = "
              f"{np.array2string(d.kappa[:2], precision=2)}, Eq. 24 noise {d.noise_deg[0]:.5f} deg; sensors used: "
              f"{[n for n, u in zip(lpv.SENSOR_NAMES, d.used) if u]}")
for norm, how in (("h2", "Clarabel, no gain bound needed"), ("hinf", "Clarabel; Hinf with bandwidth bound R = 1000/TU")):
    _ = table.add(CLAIMS[f"{norm}_status"].judge(
        des_all[norm].optimal and des[norm].optimal, note=how,
        shown=f"{des_all[norm].status} (6 sensors), {des[norm].status} (theta1); |L| = {des[norm].gain_norm:.0f}"))

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
checks = sp.solver_independence(sc, D)
for norm in sp.NORMS:
    dev, st = checks.deviation[norm], checks.statuses[norm]
    print(f"{norm:4s}: tol 1e-9 / eps 1e-9 / scale 3: statuses {st}, max relative change of kappa {dev:.1e}")
    table.add(CLAIMS[f"{norm}_solver"].judge(dev, shown=f"max rel. change {dev:.0e} ({', '.join(st)})",
                                             note="tolerance 1e-9, margin 1e-9, variable scale 3"))
bw = sp.bandwidth_study(sc, R_LIST, GAMMA)
for R, nd, g, st in zip(bw.radii, bw.noise_deg, bw.gain_norm, bw.status):
    print(f"R = {R:7.0f}/TU: {st:18s} noise {nd:.5f} deg, |L| = {g:9.1f}")
_ = plotting.save_figure(figures.bandwidth(bw), "11_hinf_bandwidth", output_dir=out)
_ = table.add(CLAIMS["bandwidth"].judge(
    bw.noise_deg[-1], shown=f"{bw.noise_deg[0]:.4f} deg (R={bw.radii[0]:.0f}) -> {bw.noise_deg[-1]:.4f} deg "
    f"(R={bw.radii[-1]:.0f}); limit {bw.limit_deg:.4f} deg", note="the unbounded optimum is an infimum: gain grows like R"))

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
_ = plotting.save_figure(figures.precision_per_sensor(D), "11_fig2_precision", output_dir=out)

# %%
ver = sp.verify_designs(sc, D, N_VERIFY, rng)
for key, v in ver.items():
    print(f"{key:16s}: {v.n_vertices} vertices + {v.n_samples} samples; max Re eig = {v.max_real_eig:.3f} /TU; "
          f"worst H2 = {v.worst_h2:.4e}, worst Hinf = {v.worst_hinf:.4e} (gamma {GAMMA}); passed: {v.passed}")
for norm in sp.NORMS:
    v, v6 = ver[norm], ver[f"{norm} (6 sensors)"]
    table.add(CLAIMS[f"{norm}_verified"].judge(
        v.passed and v6.passed, shown=f"max Re eig {max(v.max_real_eig, v6.max_real_eig):.2f}, worst {norm} norm "
        f"{max(v.worst, v6.worst):.4e}", note=f"theta1-only and 6-sensor gains; {v.n_vertices} vertices + "
        f"{v.n_samples} samples"))

# %% [markdown]
# **The objective norm is a choice.** The paper writes $\min\|\beta\|_p$ without fixing $p$; only a Remark says
# that $p=1$ gives sparse solutions. Fig. 2's two-sensor pattern therefore follows from picking $p=1$, made while
# looking at the paper's figure. The same six-sensor problems with $p=2$ and $p=\infty$ show what the other
# readings give (the $p=\infty$ H-infinity problem may end `optimal_inaccurate`: printed). Criteria fixed before
# comparing: a sensor is "used" if $\beta_i > 10^{-4}\max\beta$; "identical" means
# $|\kappa_{\sin}/\kappa_{\cos}-1| < 10^{-3}$.

# %%
obj = sp.objective_norm_study(sc, D, sparsity_tol=1e-4, same_tol=1e-3)
for (o, n), d in obj.designs.items():
    print(f"p = {o[1:]:3s} {n:4s}: {d.status:18s} kappa "
          f"{np.array2string(d.kappa, formatter={'float_kind': lambda v: f'{v:.1f}'})}; used: "
          f"{', '.join(nm for nm, u in zip(lpv.SENSOR_NAMES, d.used) if u)}; kappa sin/cos th1 - 1 = "
          f"{d.kappa[0] / d.kappa[1] - 1:+.1e}")
k = {key: d.kappa for key, d in obj.designs.items()}
other_p = "; ".join(f"p = {o[1:]}: {'all six' if obj.all_used(o) else 'other'} sensors used" for o in ("l2", "linf"))
table.add(CLAIMS["objective"].judge("p = 1"),
          CLAIMS["sensors"].judge(obj.only_theta1, shown=", ".join(
              n for n, u in zip(lpv.SENSOR_NAMES, des_all["h2"].used & des_all["hinf"].used) if u),
              note=f"both theorems; used = beta_i > 1e-04 max beta (fixed before); {other_p}"),
          CLAIMS["sin_cos_equal"].judge(
              obj.same_theta1("l1"), shown=f"H2 {k[('l1', 'h2')][0]:.1f}/{k[('l1', 'h2')][1]:.1f}, "
              f"Hinf {k[('l1', 'hinf')][0]:.1f}/{k[('l1', 'hinf')][1]:.1f} (p = 1)",
              note=f"p = 2: H2 {k[('l2', 'h2')][0]:.0f}/{k[('l2', 'h2')][1]:.0f}, Hinf {k[('l2', 'hinf')][0]:.0f}/"
              f"{k[('l2', 'hinf')][1]:.0f} ({'equal' if obj.same_theta1('l2') else 'not equal'}); p = inf: six "
              f"{'equal' if obj.six_equal_linf else 'unequal'}, H2 {k[('linf', 'h2')][0]:.1f}, Hinf "
              f"{k[('linf', 'hinf')][0]:.1f} ({obj.designs[('linf', 'hinf')].status})"))
rel = {n: abs(des[n].kappa[0] / des_all[n].kappa[0] - 1) for n in sp.NORMS}
_ = table.add(CLAIMS["theta1_only"].judge(max(rel.values()), shown=f"rel. diff. H2 {rel['h2']:.0e}, Hinf "
                                          f"{rel['hinf']:.0e}", note="the comparison rows use the theta1-only problems"))

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
al = sp.allowances(D, model.system)
TU_MIN = al.minutes_per_tu
print(f"H2: {al.h2_deg:.4f} deg (intensity reading);  Hinf: {al.hinf_deg:.4f} deg")
print(f"H2 per sample = 0.1 deg at dt = {al.dt_01:.4f} TU ({al.dt_01 * TU_MIN:.0f} min); H2 > Hinf per sample for "
      f"dt < {al.dt_eq:.4f} TU ({al.dt_eq * TU_MIN:.0f} min)")
print(f"Eq. 8b literal (trace < gamma): H2 {al.h2_literal_deg:.3f} deg;  printed kappa = sqrt(beta/gamma): Hinf "
      f"{al.hinf_literal_deg:.4f} deg")
kp, kb = al.kappa_paper, al.kappa_band_hinf
print(f"kappa implied by Eq. 24 and the paper's 0.1 / 0.08 deg: H2 {kp['h2']:.0f}, Hinf {kp['hinf']:.0f}; "
      f"here H2 {al.kappa_h2:.0f}, Hinf {al.kappa_hinf:.0f}")
table.add(
    CLAIMS["h2_intensity"].judge(al.h2_deg, shown=f"{al.h2_deg:.4f} deg", note="2:1 orbit; Section 9 tries other "
                                 f"orbits and disturbances; Eq. 8b read literally (trace < gamma) gives "
                                 f"{al.h2_literal_deg:.3f} deg, also outside"),
    CLAIMS["h2_per_sample"].judge(float(des["h2"].noise_per_sample_deg(al.dt_01)[0]),
                                  shown=f"0.1 deg at dt = {al.dt_01 * TU_MIN:.0f} min"),
    CLAIMS["hinf_noise"].judge(al.hinf_deg, shown=f"{al.hinf_deg:.4f} deg (R = {POLE_RADIUS:.0f}/TU; limit "
                               f"{bw.limit_deg:.4f})", note=f"= asin(gamma / max r13) in the limit; max r13 = "
                               f"{bw.r13_max:.3f} LU on the 2:1 orbit (Section 9 counts the resonances in the band)"),
    CLAIMS["ordering"].judge(bool(al.h2_deg > al.hinf_deg), shown=f"intensity reading: H2 {al.h2_deg:.3f} < Hinf "
                             f"{al.hinf_deg:.3f}; per sample: H2 > Hinf iff dt < {al.dt_eq * TU_MIN:.0f} min"),
    CLAIMS["hinf_formula"].judge("kappa = sqrt(beta)", note="verified norm equals gamma with sqrt(beta); the printed "
                                 f"formula would give {al.hinf_literal_deg:.4f} deg, not 0.08"),
    CLAIMS["kappa_implied"].judge(
        al.kappa_h2, shown=f"H2 {al.kappa_h2:.0f}, Hinf {al.kappa_hinf:.0f}",
        note=f"H2 {al.kappa_h2 / kp['h2']:.1f}x the implied value; Hinf "
        f"{'inside' if kb[0] < al.kappa_hinf <= kb[1] else 'outside'} the band ({kb[0]:.0f}, {kb[1]:.0f}] of the "
        "printed digits of 0.08 deg; the paper prints no kappa: 1/sin(0.1 deg), 1/sin(0.08 deg)"))

# %% [markdown]
# ## 8 · Beyond the paper: required precision against gamma
#
# The $\theta_1$-only problems are built once; `gamma` enters only through a `cp.Parameter` ($S_d/\gamma$), so the
# sweep re-uses the canonicalised problems. Without disturbance $\kappa\gamma$ would be exactly constant (the
# scaled problem does not depend on $\gamma$); the small $S_d$ bends the H2 curve only at small gamma, where
# $S_d/\gamma$ is largest.

# %%
tc = sp.trade_curve(D, np.geomspace(3e-4, 3e-2, N_GAMMA))
_ = plotting.save_figure(figures.trade_curve(tc, GAMMA, model.system.length_unit_km), "11_tradecurve", output_dir=out)
print("log-log slope of kappa against gamma: " + ", ".join(f"{n} {s:.3f}" for n, s in tc.slope.items()))
_ = table.add(CLAIMS["trade_curve"].judge(tc.slope["h2"], shown=f"slopes H2 {tc.slope['h2']:.2f}, Hinf "
                                          f"{tc.slope['hinf']:.2f}", note=f"{N_GAMMA} gammas from 115 to 11500 km"))

# %% [markdown]
# ## 9 · Where do the paper's numbers come from? A sweep over what the paper leaves unstated
#
# The paper states neither its orbit, nor its disturbance, nor a sampling interval. `sp.sensitivity_study` solves
# both $\theta_1$-only theorems at $\gamma = 0.0013$ for eight planar Earth-Moon resonant orbits (4:1, 3:1, 5:2,
# 2:1 with several perigee radii), two disturbance structures (accelerations on the velocities; independent
# perturbations of all four states) and disturbance levels $0$ to $10^{-2}$ (LU/TU² for accelerations); each
# (orbit, structure, norm) problem is built once and the level is a `cp.Parameter`. The sampling interval enters
# afterwards, through the per-sample conversion of Section 7. We ask: where does H-infinity allow
# $[0.075, 0.085)$ deg, H2 per sample $[0.05, 0.15)$ deg, and H2 more than H-infinity?

# %%
study = sp.sensitivity_study(GAMMA, orbits=STUDY_ORBITS or RESONANT_CANDIDATES, levels=STUDY_LEVELS,
                             pole_radius=POLE_RADIUS, n_samples=N_STUDY, progress=True)
rd = sp.read_sensitivity(study)
h2i, hinf, j = study.h2_intensity_deg, study.hinf_deg, rd.level_index
print(f"{2 * study.h2_kappa.size} solves in {study.seconds:.0f} s; {rd.n_optimal} ended optimal")
print(f"{'orbit':20s} {'max r13':>8s} {'Hinf deg':>9s} {'H2 int. deg (acc, lvl 1e-3)':>28s} "
      f"{'dt for H2 = 0.1 deg [min]':>26s} {'H2 > Hinf for dt < [min]':>25s}")
for i, nm in enumerate(rd.names):
    print(f"{nm:20s} {study.r13_max[i]:8.3f} {hinf[i, 0, j]:9.4f} {h2i[i, 0, j]:28.4f} "
          f"{rd.dt_01[i, 0, j] * TU_MIN:26.0f} {rd.dt_eq[i, 0, j] * TU_MIN:25.0f}")

# %%
# Where do both of the paper's numbers hold?  Per orbit, structure and level: the dt window in which the H2
# per-sample allowance lies in [0.05, 0.15) deg and exceeds the H-infinity allowance, given Hinf in [0.075, 0.085).
print(f"{rd.hinf_in_band[:, 0, 0].sum()} of {len(rd.names)} orbits give Hinf in [0.075, 0.085) deg; "
      f"{len(rd.hits)} of {rd.all_hold.size} (orbit, structure, level) cases admit a sampling interval for the rest:")
for h in rd.hits:
    print(f"  {h[0]:20s} {h[1]:13s} level {h[2]:<7g}: dt in [{h[3]:.0f}, {h[4]:.0f}) min")
for l_i, lvl in enumerate(study.levels):  # the short intervals need a large disturbance
    print(f"dt for H2 = 0.1 deg per sample at level {lvl:g}: {np.nanmin(rd.dt_01[:, :, l_i]) * TU_MIN:.0f}-"
          f"{np.nanmax(rd.dt_01[:, :, l_i]) * TU_MIN:.0f} min over orbits and structures")
b = rd.r13_band
dt_range = f"{np.nanmin(rd.dt_01) * TU_MIN:.0f}-{np.nanmax(rd.dt_01) * TU_MIN:.0f} min"
table.add(
    CLAIMS["study"].judge(rd.n_optimal, shown=f"{len(rd.names)} orbits x {len(study.structures)} structures x "
                          f"{len(study.levels)} levels, {study.seconds:.0f} s, {rd.n_optimal}/{2 * study.h2_kappa.size}"
                          " optimal", note="theta1-only LMIs, Clarabel"),
    CLAIMS["where_hinf"].judge(len(rd.orbits_in_band), shown=f"{len(rd.orbits_in_band)} of {len(rd.names)} orbits: "
                               f"{', '.join(rd.orbits_in_band) or 'none'}", note=f"band [0.075, 0.085) fixed before; "
                               f"needs max r13 in [{b[0]:.3f}, {b[1]:.3f}] LU (unbounded-gain limit); disturbance "
                               f"structure and level change it by at most {rd.hinf_spread:.0e} (relative)"),
    CLAIMS["where_h2"].judge(rd.h2_intensity_in_band, shown=f"{'in' if rd.h2_intensity_in_band else 'never in'} "
                             f"[0.05, 0.15) deg as an intensity (max {rd.h2_intensity_max:.3f} deg); per sample at dt "
                             f"= {dt_range}", note="band [0.05, 0.15) fixed before; range over orbits, structures and "
                             "levels; the per-sample reading needs a sampling interval, which the paper does not state"),
    CLAIMS["both"].judge(len(rd.hits), shown=f"{len(rd.hits)} of {rd.all_hold.size} cases, e.g. " + (
        f"{rd.hits[0][0]}, dt {rd.hits[0][3]:.0f}-{rd.hits[0][4]:.0f} min" if rd.hits else "none"),
        note=f"only with the per-sample reading of H2, on an orbit with max r13 in [{b[0]:.2f}, {b[1]:.2f}] LU, for the "
        "dt windows listed"))

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
_ = plotting.save_figure(figures.sensitivity(study, rd, GAMMA, POLE_RADIUS), "11_sensitivity", output_dir=out)

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
