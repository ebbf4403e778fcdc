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
# # 02 · Mutual information of an observation window and its gradient
#
# **What you will learn.** What the *mutual information* between the states of an observer and its targets and
# the measurements it collects means (a expected KL divergence, in nats); how Wolf & Jones stack a whole
# observation window into one linear-Gaussian model (their Eqs. 12-23) and get a closed form (Eq. 18); why the
# same number can be computed measurement by measurement with a Kalman filter at a cost linear in the number of
# measurements; how its gradient with respect to the observer's state (Eqs. 44-52) is built from the second-order
# state transition tensor; and why a longer observer-target baseline makes inter-satellite measurements more
# informative (the Markley / Psiaki argument of the paper's introduction).
#
# **Paper sections followed.** Wolf & Jones, *Information-Based Trajectory Planning for Autonomous Absolute
# Tracking in Cislunar Space* (arXiv 2408.17435): "Problem Formulation: Information-Driven Objective" (Eqs. 9-23),
# "Convex Objective Approximation" (Eqs. 44-52), "Performance Evaluation" (the CRLB by EKF covariance recursion)
# and test case 2 (Tables 4 and 5). Measurement models also follow Greaves & Scheeres 2021 (Eqs. 6-13) and
# their AMOS 2023 paper (Eqs. 15-20).
#
# The methods live in `cislunar.sensing.measurements`, `cislunar.sensing.covariance` and
# `cislunar.sensing.information`; the studies of this chapter (the window, the CRLB, the gradient check, the
# baseline and timing sweeps, and the figures) in `cislunar.papers.wolf_jones.mutual_information_study`; the rows
# of the closing table are claims declared in `cislunar.papers.wolf_jones.claims.mutual_information`.

# %% tags=["parameters"]
QUICK = False  # quick mode: every None below picks its smaller quick-mode value; the same experiments run
SEED = 0  # seed of the notebook's random generator (the Monte Carlo check of section 1)
OUTPUT_DIR = ""  # folder for the figures (empty: build-scratch/ by hand, the build under the runner)
MC_SAMPLES = None  # Monte Carlo samples for the Eq. 11 check [-] (None: 20000 quick, 200000 full)
RANGE_SIGMA_KM = None  # range noise standard deviation [km] (None: Table 5's 0.1 km, i.e. 100 m)
N_BASELINES = None  # observer phase offsets in the baseline study of section 6 [-] (None: 5 quick, 10 full)
BASELINE_MAX_PHASE = None  # longest observer lead in section 6, fraction of the DRO period [-] (None: 0.5)
TIMING_SIZES = None  # measurement times per window in section 7 [-] (None: [5, 9, 17] quick, up to 65 full)
TIMING_MIN_TIME = None  # seconds per timing run in section 7 [s] (None: 0.02 quick, 0.1 full)
WORKERS = 1  # processes for the baseline study [-] (1: serial); the timing study always runs serially
SCHEDULER = ""  # address of a Dask scheduler for the baseline study, e.g. "tcp://10.0.0.5:8786" ("": none)

# %%
# Every None above is resolved here; a value the reader gave is used as given, in quick and in full mode.
mc_samples = MC_SAMPLES if MC_SAMPLES is not None else (20000 if QUICK else 200000)
range_sigma_km = RANGE_SIGMA_KM if RANGE_SIGMA_KM is not None else 0.1
n_baselines = N_BASELINES if N_BASELINES is not None else (5 if QUICK else 10)
baseline_max_phase = BASELINE_MAX_PHASE if BASELINE_MAX_PHASE is not None else 0.5
timing_sizes = TIMING_SIZES if TIMING_SIZES is not None else ([5, 9, 17] if QUICK else [5, 9, 17, 33, 65])
timing_min_time = TIMING_MIN_TIME if TIMING_MIN_TIME is not None else (0.02 if QUICK else 0.1)
workers = WORKERS if WORKERS is not None else 1

import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import mutual_information_study as study
from cislunar.papers.wolf_jones.claims import mutual_information as claims
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.sensing import covariance as cov
from cislunar.sensing import information as info
from cislunar.sensing import measurements as meas
from cislunar.utils.executors import open_executor

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
table = ComparisonTable("02 Mutual information (Wolf & Jones Eqs. 9-23, 44-52, Performance Evaluation)")

# %% [markdown]
# ## 1 · Mutual information as an expected KL divergence (Eqs. 9-11)
#
# For one state $x$ and one measurement $y$, the mutual information is the KL divergence (Eq. 10) between the
# joint density and the product of the marginals (Eq. 9). Marginalising (Eq. 11) it is the *expected* divergence
# between what the measurement says given the state, $p(y|x)$, and what we expect to measure before knowing the
# state, $p(y)$:
#
# $$\mathcal I(x;y) = \mathbb E_x\left[D_{KL}\big(p(y|x)\,\|\,p(y)\big)\right].$$
#
# Worked example: a scalar $x\sim\mathcal N(0, p)$ measured as $y = hx + v$, $v\sim\mathcal N(0,r)$. Then
# $p(y|x)=\mathcal N(hx, r)$, $p(y)=\mathcal N(0, h^2p+r)$ and the closed form is
# $\mathcal I = \tfrac12\ln(1 + h^2p/r)$: the log of the ratio of prior to posterior standard deviation. We check
# it three ways: closed form, the expected KL averaged over samples of $x$ (Eq. 10 for Gaussians), and the joint
# Monte Carlo average of $\ln p(y|x) - \ln p(y)$ from `monte_carlo_mutual_information`.

# %%
ex = study.scalar_worked_example(mc_samples, rng, p=4.0, h=1.0, r=1.0)
print(f"closed form 0.5 ln(1 + h^2 p / r)  = {ex.closed:.5f} nats")
print(f"E_x[KL] over {mc_samples} samples    = {ex.kl_mean:.5f} +- {ex.kl_se:.5f}")
print(f"joint Monte Carlo of log ratio       = {ex.monte_carlo:.5f} +- {ex.monte_carlo_se:.5f}")
print(f"posterior/prior std ratio: {ex.std_ratio:.4f} = exp(-I) = {np.exp(-ex.closed):.4f}")

# %% [markdown]
# ## 2 · The stacked window (Eqs. 12-23) on a toy problem
#
# Over a window the measurements at $t_0,\dots,t_{N-1}$ depend linearly (after linearisation) on the initial state
# error and the process noises, $X=[x_0; w_1; \dots; w_{N-1}]$, with block-diagonal prior covariance
# $\tilde P = \mathrm{diag}(P_0, Q_1, \dots)$ (Eq. 19). Row $j$ of the stacked Jacobian $\tilde H$ (Eq. 20) contains
# $H_j\Phi(t_j,t_k)$ for every noise injected at $t_k\le t_j$ (Eqs. 21-22); $\tilde R$ is block diagonal (Eq. 23).
# Then $Y\sim\mathcal N(\bar Y, \tilde H\tilde P\tilde H^T+\tilde R)$ and $Y|X\sim\mathcal N(\tilde HX, \tilde R)$
# (Eqs. 16-17), so the expected KL divergence is Eq. 18:
#
# $$\mathcal I(X;Y) = \tfrac12\ln\frac{|\tilde H\tilde P\tilde H^T + \tilde R|}{|\tilde R|}.$$
#
# A 1-D constant-velocity toy (state: position, velocity; position measured at three times) shows the stacked
# matrices. The block lower-triangular shape of $\tilde H$ is what makes the dense form cost $O(N^3)$.

# %%
toy = study.constant_velocity_toy(dt=1.0, n_times=3, psd=0.01, r=0.25)
Pt, Ht, Rt = info.stacked_matrices(*toy.arrays)
np.set_printoptions(precision=3, suppress=True)
print("P~ (Eq. 19):\n", Pt, "\nH~ (Eq. 20):\n", Ht, "\nR~ (Eq. 23):\n", Rt)
dense_toy = info.mutual_information_dense(*toy.arrays)
total_toy, terms_toy = info.mutual_information(*toy.arrays, return_terms=True)
print(f"Eq. 18 dense: {dense_toy:.12f} nats; chain rule: {total_toy:.12f} nats = sum of {np.round(terms_toy, 4)}")

# %% [markdown]
# **The chain rule.** $\mathcal I(X;Y) = \sum_k \mathcal I(X; y_k\,|\,y_{0:k-1})$. Given the earlier measurements,
# $y_k = H_kx_k + v_k$ with $x_k\sim\mathcal N(\cdot, \bar P_k)$ — the Kalman filter's *prior* covariance — so each
# term is the information gain of one Kalman update,
# $\mathcal I_k = \tfrac12\ln|I + R_k^{-1/2}H_k\bar P_kH_k^TR_k^{-T/2}|$. The determinant of the stacked innovation
# covariance factorises into the product of the per-step innovation covariances (block LDL), so the sum equals
# Eq. 18 exactly, at a cost linear in $N$. The first measurement carries the largest single share here (it
# collapses the prior; printed above), later ones add less.

# %% [markdown]
# ## 3 · Measurement models and noise (test case 2; Greaves & Scheeres)
#
# Wolf & Jones test case 2 measures range $\rho = \|\Delta\mathbf r\|$ and range rate
# $\dot\rho = \Delta\dot{\mathbf r}\cdot\Delta\mathbf r/\rho$ with $\Delta = x_{\mathcal T}-x_{\mathcal S}$, noise
# 100 m and 10 m/s (Table 5). Their Jacobians with respect to the relative state are
# $[\hat\rho^T\ 0]$ and $[(\Delta\dot{\mathbf r}-\dot\rho\hat\rho)^T/\rho\ \ \hat\rho^T]$; the observer's Jacobian
# is the negative (Eq. 21 puts both in $H_{\mathcal A}$). Optical angles (G&S 2021 Eqs. 7-8, AMOS Eqs. 15-18) use
# the RMS model $\sigma_\theta = \sqrt{\sigma_{min}^2 + D^2/\rho^2}$ (AMOS Eq. 20, $\sigma_{min}$ = 10 µrad,
# $D$ = 4 m = 0.004 km): resolution dominates below $D/\sigma_{min}$ = 0.004 km / 10 µrad = 400 km, pointing above.
# The range noise of the test-case-2 window below is the parameter `RANGE_SIGMA_KM` (Table 5's 100 m unless the
# reader sets it); the range-rate noise stays at Table 5's 10 m/s.

# %%
fig = study.figure_angular_noise(mean_range_km=215.0)
_ = plotting.save_figure(fig, "02_angular_noise_model", output_dir=out)
print(f"sigma_theta at 215 km: "
      f"{meas.angular_sigma(215.0, meas.AMOS_SIGMA_MIN_RAD, meas.AMOS_RESOLUTION_KM) * 1e6:.3f} µrad")

# %% [markdown]
# ## 4 · Test case 2: the observation window and its CRLB
#
# Three targets on the Table 4 DROs and an observer; window $[P_{ref}, 2P_{ref}]$ with one range/range-rate pair
# per target per day, initial errors 100 km and $10^{-2}$ km/s = 10 m/s per axis (Table 5). **Choice:** the paper's
# optimised observer trajectory is not published, so the observer here coasts on its initial reference DRO: the
# printed first row of Table 4 ($\dot y_0$ = 0.528996986 does not close as a periodic orbit, notebook 01) with
# $\dot y_0$ corrected holding $x_0$, exactly as in notebook 06 (`scenarios.test_case_2`). This is a coasting
# stand-in, notebook 06's ballistic guess, not the $\alpha_h = 0$ solution of the paper (Table 4's
# $x_{\mathcal S}(t_0)$ and $x_{\mathcal S}(t_f)$ lie on different orbits, so even the minimum-ΔV observer flies a
# transfer). $P_{ref}$ is the period of that DRO, the paper's "reference DRO"; the window $[P_{ref}, 2P_{ref}]$
# therefore starts at half its end time. (Until 2026-11-26 this chapter took the observer and $P_{ref}$ from the
# `observer_tf` row instead, 16.02 d against notebook 06's 16.17 d for the same window; the two chapters now share
# one window, and its MI on the coasting observer is the value notebook 06 prints for its ballistic guess.)
#
# Process noise: Table 5 prints "$Q$ [km/s³] = $10^{-11}$"; the PSD of an acceleration has units km²/s³. Read as
# $10^{-11}$ km²/s³ the CRLB of test case 1 grows without bound, against the paper's text, so we adopt the same
# number in normalised units — a reading chosen by looking at the paper's result, hence "consistent (tuned)" in
# the table; the check itself runs at the end of this section, and notebook 06 sweeps the readings through its
# plans — $q = 10^{-11}$ LU²/TU³ $= 2.80\times10^{-17}$ km²/s³, and discretise it *exactly* along each reference trajectory,
# $Q_k = \int\Phi(t_{k+1},\tau)GqG^T\Phi(t_{k+1},\tau)^Td\tau$ (time-varying Van Loan; Gauss-Legendre quadrature of
# heyoka STMs, checked against the Lyapunov ODE in the tests).
#
# In code, `case_2_window` propagates the four spacecraft to the window start, lays out the daily measurement
# times and linearises the augmented 24-state system with the derivatives the gradient of section 5 needs;
# `window_crlb` then runs the covariance recursion once and returns, per object and time, the total, in-plane and
# out-of-plane position RMS, together with Eq. 18 evaluated both ways and the chain-rule gains.

# %%
win = study.case_2_window(em, range_sigma_km=range_sigma_km)
lin, days = win.lin, win.days
print(f"P_ref = {em.tu_to_days(win.P_ref):.3f} d; window {days[0]:.2f}-{days[-1]:.2f} d, "
      f"{win.t.size} measurement times, state dim {lin.P0.shape[0]}")
# any [P, 2P] window on these DROs starts at about 16 d: the periods of the three target DROs
print("target DRO periods [d]:", np.round(win.target_periods_d, 2))
print(f"q = {win.q:.4e} LU^2/TU^3; one-day Q_S velocity sigma = "
      f"{np.sqrt(lin.Q[0, 3, 3]) * em.velocity_unit_km_s * 1e3:.3f} m/s "
      f"(sqrt(q dt) = {np.sqrt(cov.WOLF_JONES_PSD_KM2_S3 * 86400) * 1e3:.3f} m/s)")
crlb = study.window_crlb(win)
print(f"I(X;Y): dense Eq. 18 = {crlb.mi_dense:.9f} nats, chain rule = {crlb.mi_chain:.9f} nats "
      f"(rel. diff {crlb.relative_difference:.1e})")

# %% [markdown]
# **Is the chain rule right, or only close?** The two values printed above differ in the sixth digit. Both are
# float64 evaluations of one formula, so which is off, and is the gap round-off? `Eq18Precision` evaluates Eq. 18
# densely once more, forming $\tilde S$ and its Cholesky factor in extended precision (`np.longdouble`, machine
# epsilon about $10^{-19}$ on this machine) from the same float64 matrices: a reference that shares nothing with the
# Kalman recursion but its inputs. It also states how much round-off the float64 dense form can carry: a
# backward-stable formation and factorisation perturb $\tilde S$ by about $u\|\tilde S\|$ ($u = 2^{-53}$), which
# moves $\ln|\tilde S|$ by up to $n\,u\,\kappa_2(\tilde S)$ ($n$ the dimension of $\tilde S$), so the MI by half
# that. The window's $\tilde S$ is badly conditioned (measurements of 100 m against a prior of 100 km), so this scale
# is far from negligible. The table's row asks that the chain rule agree with the reference within it: a recursion
# that agrees to that level is as good a value of Eq. 18 as the dense form can be, and a wrong recursion (a dropped
# process noise is worth about 15 nats here) fails by orders of magnitude.

# %%
eq18 = study.Eq18Precision.of(*lin.arrays)
print(f"Eq. 18 in extended precision: {eq18.reference:.9f} nats (n = {eq18.size}, kappa_2(S~) = {eq18.condition:.2e}, "
      f"longdouble eps {eq18.extended_eps:.1e})")
print(f"round-off scale of the float64 dense form: {eq18.bound:.2e} nats")
print(f"float64 dense off by {abs(eq18.dense - eq18.reference):.1e} nats ({eq18.ratio(eq18.dense):.1e} of the scale); "
      f"chain rule off by {abs(crlb.mi_chain - eq18.reference):.1e} nats ({eq18.ratio(crlb.mi_chain):.1e})")

# %% [markdown]
# So the sixth-digit gap is the dense form's: the chain rule agrees with the extended-precision value several
# orders of magnitude more closely (down to what the reference itself can resolve), which is why the package
# evaluates Eq. 18 in square-root form.
#
# **Which reading of the process noise keeps the CRLB bounded?** The paper says of test case 1 (text on Fig. 4):
# "Following the initial transient response, subsequent measurements serve to bound the expected error." Tables 3
# and 5 print the same "$Q$ [km/s³] = $10^{-11}$", so the statement can test the readings of that number
# (`wolf_jones.PROCESS_NOISE_READINGS_KM2_S3`) cheaply: `Case1Readings` runs test case 1's covariance recursion
# (observer coasting on its initial DRO into the thrust-free window $[3P/4, 3P/2]$, target on its DRO, relative
# position once a day at 100 m per axis, Table 3's priors) under each reading. Bounded means notebook 05's test,
# fixed there before comparing: the window-end position RMS is at most the RMS after the 2nd measurement, for
# observer and target. The coasting observer stands in for the $\alpha_h = 0$ plan (which enters the window from a
# transfer); notebook 05 applies the same test to its solved plans.

# %%
readings = study.Case1Readings.of(em)
for label, q_km, g, r in zip(readings.labels, readings.q_km2_s3, readings.growth, readings.rms_km):
    print(f"{label:48s} q = {q_km:.2e} km^2/s^3: observer RMS {r[0, 1]:7.0f} km after the 2nd measurement, "
          f"{r[0, -1]:7.0f} km at the window end; growth {g:.3f} ({'bounded' if g <= 1 else 'grows'})")

# %% [markdown]
# The literal reading, $10^{-11}$ km²/s³, lets the error grow by about thirty times over the window: the process
# noise it adds in a day (a velocity sigma of about 1 m/s, $\sqrt{q\,\Delta t}$) outruns what a daily 100 m
# position fix can remove. The adopted normalised reading and the two smaller readings are bounded. So the statement rejects the literal
# reading but does not single out ours; the row in the closing table says so, and stays "consistent (tuned)"
# because the reading was chosen with this very statement in view.

# %% [markdown]
# **Performance evaluation (CRLB).** Linearised about the true trajectories, the EKF covariance recursion
# $\bar P_{k+1} = \Phi\hat P_k\Phi^T + Q$, $\hat P_k = (I-K_kH_k)\bar P_k$ (Joseph form here) gives the CRLB
# (Taylor 1978), as in the paper's "Performance Evaluation". The same recursion produced the per-measurement
# information gains above.
#
# **Why the four position RMS curves coincide.** Here all four spacecraft fly planar DROs, so every relative
# position lies in the $x$-$y$ plane and the range and range-rate Jacobians have zero $z$ and $\dot z$ columns
# (printed below). In the CR3BP the out-of-plane motion about a planar orbit is decoupled from the in-plane motion
# to first order, so no measurement reaches the $z$ errors: each object's $\sigma_z$ is its free-flight
# propagation of the identical prior (100 km, 10 m/s), an oscillation with the orbit that is nearly the same on
# the four neighbouring DROs. It dominates the total RMS once the measurements have shrunk the in-plane error. This
# is the paper's remark that the minimum-ΔV case of test case 2 is "weakly observable" and that range needs
# out-of-plane observer motion. The figure therefore splits the RMS: total (as in Fig. 9), in-plane per object,
# and the out-of-plane part; the middle panel compares each target's in-plane RMS with the observer's, which is
# where the paper's "the observer exhibits a smaller position RMS, as it gains information from all three targets"
# could show.

# %%
names = study.OBJECT_NAMES
print(f"largest |dH/dz|, |dH/dvz| over the window: {crlb.largest_z_jacobian:.1e} (out-of-plane errors unobserved)")
fig = study.figure_crlb(crlb)
_ = plotting.save_figure(fig, "02_test_case_2_crlb_and_gains", output_dir=out)
print("terminal position RMS [km]:", dict(zip(names, np.round(crlb.total[:, -1], 3).tolist())))
print("mean position RMS over the window [km]:", dict(zip(names, np.round(crlb.total.mean(axis=1), 3).tolist())))
print("mean in-plane RMS over the window [km]:", dict(zip(names, np.round(crlb.in_plane.mean(axis=1), 3).tolist())))
print(f"out-of-plane share of the summed position variance at the window end: {crlb.out_of_plane_share:.2%}")
print("in-plane RMS after the 1st / 2nd update [km]:",
      {n: (round(float(a), 1), round(float(b), 1)) for n, a, b in zip(names, *crlb.in_plane[:, :2].T)},
      f"; largest in-plane RMS over the window {crlb.in_plane.max():.0f} km")

# %% [markdown]
# ## 5 · The gradient with respect to the observer (Eqs. 44-52)
#
# With the observer coasting through the window, every observer state is a function of its state at the window
# start, $x_{\mathcal S,k^*}$, so $\tilde H$ depends on it through (i) the measurement Jacobians evaluated at the
# propagated states (their Hessians times the STM, first term of Eq. 50) and (ii) the transition matrices inside
# $\tilde H$ (the second-order STT, second term of Eq. 50, Eqs. 51-52). With the determinant derivative (Eq. 46):
#
# $$\frac{\partial\mathcal I}{\partial\xi} = \tfrac12\mathrm{tr}\Big(\tilde S^{-1}\big(\partial_\xi\tilde H\,
# \tilde P\tilde H^T + \tilde H\tilde P\,\partial_\xi\tilde H^T\big)\Big)\quad\text{(Eqs. 47-48)}.$$
#
# **Typos in the printed equations.** Eq. 45 as printed differentiates $\tfrac12(\ln|\tilde H\tilde P\tilde H| -
# \ln|\tilde R|)$: the transpose and the $+\tilde R$ of Eq. 18 are missing (as printed the matrix is not even square
# in general). The Kalman gain of "Performance Evaluation", $K = \bar PH^T(H\bar PH + R)^{-1}$, lacks the same
# transpose. We use Eq. 18 and $K = \bar PH^T(H\bar PH^T+R)^{-1}$.
#
# As the paper says, $\tilde P$ (the process noise) is held fixed. The structured gradient differentiates the
# square-root Kalman recursion itself in reverse mode (one forward sweep that keeps the triangular factors, one
# backward sweep of adjoints; its cost does not grow with the number of parameters), so it keeps the accuracy of
# the square-root value. The forward-mode derivative of the same recursion (one tangent per parameter) is kept as
# `method="sqrt-forward"`, the reference it is tested against; the reverse-mode derivative of the covariance form is
# kept as `method="adjoint"` but loses ~5 digits on ill-conditioned windows (test case 2's optimised windows,
# notebook 06). Both structured and dense gradients are compared with fourth-order central differences of the full
# re-propagated MI, evaluated with the structured (square-root) value: the dense log-determinant carries too few
# digits for differences at a step of $10^{-6}$ (its gradient itself differs from the structured one at the level
# printed below).

# %%
grad = study.gradient_check(win, step=1e-6)
print("gradient [nats/LU, nats/(LU/TU)]\n structured:", grad.structured, "\n dense:     ", grad.dense,
      "\n central FD:", np.round(grad.finite_difference, 3) + 0.0)
print(f"max |structured - FD| / max |FD| = {grad.error:.1e}; structured vs dense {grad.dense_error:.1e}")

# %% [markdown]
# **How far does the linearisation of Eq. 44 hold?** Step the observer's initial state along the unit gradient
# direction of the non-dimensional 6-vector, with one scale factor: a step labelled "$s$ km-equivalent" has norm
# $s$ km converted to LU, shared between position (LU) and velocity (LU/TU) as the gradient is (both parts are
# printed). Compare the true MI with $\mathcal I + \nabla\mathcal I\cdot\delta x$. A trust region built on Eq. 44
# alone (the package's `information_model="linear"`) would have to keep steps in the range where the two agree.
# The package's SCvx does not rely on that by default: its default `information_model="quadratic"` adds a concave
# curvature term to the information model, and its trust region starts far beyond this range (radii printed below);
# notebook 05 compares the linear and quadratic models.

# %%
lc = study.linearisation_check(win, grad, steps_km=[1.0, 10.0, 100.0, 1000.0])
for s_km, dx, a, b in zip(lc.steps_km, lc.dx, lc.true, lc.linear):
    print(f"|dx| = {s_km:7.1f} km-equivalent (position {np.linalg.norm(dx[:3]) * em.length_unit_km:.1f} km, velocity "
          f"{np.linalg.norm(dx[3:]) * em.velocity_unit_km_s * 1e6:.3f} mm/s): true {a:.4f}, Eq. 44 {b:.4f}, "
          f"error {abs(a - b):.2e} nats")
scvx_defaults = scvx.SCvxSettings()
print(f"package SCvx defaults: information_model = {scvx_defaults.information_model!r}, trust region eta0 = "
      f"{scvx_defaults.eta0:g} LU ({em.lu_to_km(scvx_defaults.eta0):,.0f} km), eta_max = {scvx_defaults.eta_max:g} LU "
      f"({em.lu_to_km(scvx_defaults.eta_max):,.0f} km)")

# %% [markdown]
# ## 6 · Baseline and information (the Markley / Psiaki argument)
#
# Inter-satellite measurements inform *absolute* states only through the difference of the gravitational
# accelerations the two spacecraft feel — like two accelerometers at a long baseline (Psiaki 1999). The longer the
# baseline, the more the two dynamics differ, and the more observable the pair becomes. Test: a target on the
# first Table 4 DRO and an observer on the *same* DRO, ahead by a phase $\tau$ (so no new orbit is needed and the
# baseline grows with $\tau$); one period, daily measurements; relative position (test case 1, 100 m per axis)
# and range/range-rate (test case 2). We report MI and the terminal CRLB, both total and in-plane
# ($\sqrt{P_{xx}+P_{yy}}$). Expect a difference between the two: relative position measures the full baseline
# vector, while in-plane range and range rate leave the out-of-plane errors unobserved — the paper notes that
# range needs out-of-plane observer motion (test case 2, Fig. 6) — so for them only the in-plane CRLB can respond
# to the baseline.
#
# The $2\times$`N_BASELINES` covariance analyses (two measurement types, one per observer phase) do not depend
# on each other: `baseline_study` hands them to the executor opened from `WORKERS` and `SCHEDULER` (serial unless
# the reader asks for processes or a Dask cluster), and the curves are the same whichever runs them. The phases
# are spaced geometrically from 0.002 of the period up to `BASELINE_MAX_PHASE` (half a period by default, the
# longest baseline a DRO offers).

# %%
with open_executor(workers, SCHEDULER) as executor:  # relative position, then range + range rate
    curves = study.baseline_study(win, n_baselines, max_phase=baseline_max_phase, executor=executor)
fig = study.figure_baseline(curves)
_ = plotting.save_figure(fig, "02_baseline_study", output_dir=out)
for c in curves:
    print(c.name, "\n  baseline [km]:", np.round(c.baseline_km), "\n  MI [nats]:", np.round(c.mi, 2),
          "\n  observer RMS [km]:", np.round(c.obs, 3), "\n  target RMS [km]:  ", np.round(c.tgt, 3),
          "\n  observer sigma_z [km]:", np.round(c.obs_z, 3), "\n  observer in-plane RMS [km]:", np.round(c.obs_xy, 3),
          "\n  target in-plane RMS [km]:  ", np.round(c.tgt_xy, 3))
for c in curves:
    print(f"{c.name}: MI peak at {c.peak_km:.0f} km, in-plane CRLB minimum at {c.baseline_km[c.best]:.0f} km "
          f"({'the same baseline' if c.same_peak else 'different baselines'})")
print("baselines [km] where the observer's total RMS exceeds the target's by > 5%:",
      {c.name: c.observer_above_target_km for c in curves})

# %% [markdown]
# **Reading the right panel.** With relative position the observer's and the target's RMS agree to a fraction of a
# kilometre (printed above): the measurement fixes $x_{\mathcal T} - x_{\mathcal S}$ to 100 m, so the absolute
# error that remains is shared. With range and range rate on one planar DRO the out-of-plane errors are not observed
# at all (section 4): the total terminal RMS (dotted) is the free-flight $\sigma_z$ of the identical prior and hides
# the effect of the baseline. The observer's total departs from the target's only at the longest baselines (listed
# above), where a spacecraft starting at another point of the DRO ends the period at another phase of its $z$
# oscillation. The in-plane RMS, which the measurements do reach, falls steeply with the baseline for both
# measurement types (range and range rate: by an order of magnitude) and reaches its minimum where the MI peaks
# (whether the two baselines coincide is printed above; in the full run they do for both types): the MI tracks the
# observable part of the CRLB, including its rise at the longest, half-period baseline.

# %% [markdown]
# ## 7 · Cost: dense Eq. 18 versus the chain rule
#
# The same test-case-2 geometry, one DRO period, with the cadence changed so the window holds $N$ measurement
# times. The dense form builds $\tilde H$ ($6N\times24N$) and factorises $\tilde S$: $O(N^3)$. The chain rule runs
# $N$ Kalman steps on $24\times24$ matrices: $O(N)$, in square-root form (two QR factorisations per step, which
# keep the ~10 digits the covariance form lost on test case 2's windows). A QR costs more than the Cholesky update
# it replaces, so for short enough windows the dense form could be the faster one; the cell below looks for the
# window size at which the chain rule overtakes it (the *crossover*, interpolated between the sizes run on log-log
# axes, for the value alone and for value plus gradient) from this run's own times — if the chain rule is already
# faster at the smallest size run, the crossover is only bounded from above — and compares with test case 2's
# $N$ = 17. Times are best-of-3 wall clock on one BLAS thread (the machine is shared, so absolute numbers vary by
# tens of percent, and the crossover moves with them).
#
# `timing_study` re-linearises the window for each size and times the four evaluations in interleaved rounds, so
# that a change of load on the machine affects the dense and the structured times alike. It runs serially
# whatever `WORKERS` says: times measured beside other work would not compare the two forms fairly. The table row
# is read at $N$ = 17 (or at the size of `TIMING_SIZES` nearest to it, when the reader leaves 17 out).

# %%
timing = study.timing_study(win, timing_sizes, min_time=timing_min_time, repeat=3)
fig = study.figure_timing(timing)
_ = plotting.save_figure(fig, "02_timing_dense_vs_structured", output_dir=out)
for N, r in zip(timing.sizes, timing.results):
    print(f"N = {N:3d}: MI {r.ratio_value:5.1f}x, MI + gradient {r.ratio_gradient:5.1f}x faster structured "
          f"(dense {1e3 * r.dense_gradient:.2f} ms, structured {1e3 * r.structured_gradient:.2f} ms)")
n_ref = min(timing.sizes, key=lambda n: abs(n - 17))  # 17, or the size run nearest to it
r17 = timing.at(n_ref)
print(f"chain rule faster than dense from {timing.crossover_value} for the MI, from {timing.crossover_gradient} for "
      f"MI + gradient; at N = {n_ref}: {r17.ratio_value:.1f}x and {r17.ratio_gradient:.1f}x")

# %% [markdown]
# ## 8 · Paper versus reproduction
#
# Each row is a claim declared, with its criterion, in `cislunar.papers.wolf_jones.claims.mutual_information`
# before anything is compared; here it is only judged. The scalar check holds within 3 Monte Carlo standard errors
# of the closed form; the gradient within $10^{-5}$ (largest relative difference) of the central differences; each
# end of the window within 1 day of the text's "roughly 17 and 32 days"; the baseline argument ("increasing the
# baseline ... increases the navigation accuracy", Introduction) when over the whole range swept every step to a
# longer baseline raises the MI and lowers the observer's in-plane terminal RMS, which falls by more than 1.5x from
# the shortest to the longest baseline; the observer "on average" below the targets when its window-mean RMS is at
# least 10 % lower than the targets' mean (notebook 06's criterion for the same sentence); the chain rule when it
# agrees with Eq. 18 in extended precision within the round-off scale of the float64 dense form, $n u
# \kappa_2(\tilde S)/2$ (section 4); the process noise when, under the adopted reading, test case 1's CRLB is bounded
# after the transient (notebook 05's test of the text on Fig. 4, section 4). The process-noise reading was chosen
# while looking at the paper's result, and with that very statement in view, so its row is at best consistent
# (tuned), and would read "differs" if the adopted reading let the CRLB grow; so was the in-plane measure of the
# baseline rows (the total RMS, which includes the unobservable z, failed first), so they are at best consistent
# (tuned). (Until 2026-11-26h the process-noise row compared our q with itself and the chain-rule row had no
# criterion: neither could fail.)
#
# Two rows deserve a caution when you read their verdicts. The two baseline rows show the *same* shape in section
# 6: the MI and the in-plane CRLB improve up to about 150 000 km and then both turn at the half-period baseline, so
# both read "differs", with the range where the argument holds in the reason. (Until 2026-11-26 the test judged the
# MI only up to its peak and allowed the in-plane RMS a rebound of up to 1.2x at the longest baseline; the full run's
# relative-position rebound, 1.199x, passed it by 0.1 % while the range/range-rate one, 3.1x, failed: two verdicts
# for one shape. The turn is part of the measurement, so the test now asks for improvement at every step. Full-run
# numbers.) And the in-plane growth row tests a symptom that Table 5's prior makes nearly certain: a velocity error
# of 10 m/s per axis moves a position by about 860 km in one day, against the ~110 km the first update leaves, so the
# row cannot tell whether the paper's cause (a diagonal $P_0$) is the right one.

# %%
table.add(claims.CLAIMS["eq11_scalar"].judge(
    ex.monte_carlo, standard_error=ex.monte_carlo_se, note="our worked example (p = 4, h = r = 1)",
    shown=f"Monte Carlo {ex.monte_carlo:.4f} +- {ex.monte_carlo_se:.4f} vs closed form {ex.closed:.4f} nats"))
table.add(claims.CLAIMS["eq18_dense"].judge(crlb.mi_dense, shown=f"{crlb.mi_dense:.4f} nats",
                                     note="no numerical MI values are printed in the paper"))
table.add(claims.CLAIMS["eq18_chain_rule"].judge(
    eq18.ratio(crlb.mi_chain),
    shown=(f"|chain - Eq. 18 in extended precision| {abs(crlb.mi_chain - eq18.reference):.1e} nats = "
           f"{eq18.ratio(crlb.mi_chain):.1e} of the round-off scale {eq18.bound:.2f} nats"),
    note=(f"scale n u kappa_2(S~) / 2 of the float64 dense form (n = {eq18.size}, kappa_2 = {eq18.condition:.1e}); "
          f"the float64 dense Eq. 18 is off by {abs(eq18.dense - eq18.reference):.1e} nats (rel. diff. dense vs chain "
          f"{crlb.relative_difference:.1e}: the dense log-determinant loses digits when the measurements are far "
          "more precise than the prior); same value at O(N) cost, square-root form; until 2026-11-26h no criterion")))
table.add(claims.CLAIMS["gradient"].judge(
    grad.error,
    shown=f"structured vs FD {grad.error:.1e}; structured vs dense Eq. 48 {grad.dense_error:.1e} (max rel.)",
    note="P~ held fixed as in the paper; FD of the structured value (the dense log-determinant has too few digits for "
         "differences at step 1e-6), so the dense gradient agrees only to the level shown"))
table.add(claims.CLAIMS["eq44_linearisation"].judge(
    lc.error[2], shown=f"{lc.error[1]:.2e} / {lc.error[2]:.2e} nats",
    note=f"the range where Eq. 44 alone holds; the package's SCvx uses a quadratic information model by default and "
         f"a trust region of {em.lu_to_km(scvx_defaults.eta0):,.0f}-{em.lu_to_km(scvx_defaults.eta_max):,.0f} km "
         "(notebook 05 compares linear and quadratic)"))
table.add(claims.CLAIMS["process_noise"].judge(
    readings.growth[readings.adopted],
    shown=(f"{win.q:.1e} LU^2/TU^3 = {cov.WOLF_JONES_PSD_KM2_S3:.2e} km^2/s^3: test case 1 window-end / 2nd-measurement "
           f"RMS {readings.growth[readings.adopted]:.2f}"),
    note=("the test is notebook 05's for Fig. 4, here with the observer coasting on its initial DRO (a stand-in for the "
          "alpha_h = 0 plan); the other readings: " + ", ".join(
              f"{q_km:.0e} km^2/s^3 {g:.2f} ({'bounded' if g <= 1 else 'grows'})"
              for i, (q_km, g) in enumerate(zip(readings.q_km2_s3, readings.growth)) if i != readings.adopted)
          + ": the statement rejects the literal reading but does not single out ours; notebook 06 sweeps the "
            "readings through its plans; until 2026-11-26h judged on q in units of the adopted reading (could not "
            "fail)")))
table.add(claims.CLAIMS["window"].judge(
    max(abs(days[0] - 17.0), abs(days[-1] - 32.0)),
    shown=f"P_ref = {em.tu_to_days(win.P_ref):.2f} d, window {days[0]:.2f}-{days[-1]:.2f} d",
    note="P_ref: period of the observer's initial reference DRO (Table 4 row 1, vy0 corrected), as in notebook 06. "
         "The paper's own definition forces the start to be half the end "
         f"(~16 d; target DRO periods {', '.join(f'{p:.2f}' for p in win.target_periods_d)} d), so 'roughly 17' is "
         f"loose: our start is {17.0 - days[0]:.2f} d earlier"))
table.add(claims.CLAIMS["observer_trajectory"].judge(
    "coasting on its initial DRO (Table 4 row 1, vy0 corrected)", note="notebook 06's ballistic guess; a coasting stand-in, not the alpha_h = 0 solution (Table 4's x_S(t0) and "
    "x_S(tf) are different orbits, so alpha_h = 0 still needs a transfer)"))
table.add(claims.CLAIMS["in_plane_growth"].judge(
    bool(crlb.transient.any()),
    shown=f"in-plane RMS grows from the 1st to the 2nd update for {int(crlb.transient.sum())} of 4 objects "
          f"(observer {crlb.in_plane[0, 0]:.0f} -> {crlb.in_plane[0, 1]:.0f} km)",
    note="symptom only, the cause (diagonal P0) is not tested; the paper's Fig. 4 is test case 1 (notebook 05)"))
table.add(claims.CLAIMS["observer_below_targets"].judge(
    1 - crlb.total[0].mean() / crlb.total[1:].mean(),
    shown=f"observer {crlb.total[0].mean():.2f} km vs targets {crlb.total[1:].mean():.2f} km (mean over window, "
          f"{100 * (1 - crlb.total[0].mean() / crlb.total[1:].mean()):.1f} % lower)",
    note="un-manoeuvred observer, so only qualitative; the total is the unobserved out-of-plane error, the same for "
         f"all four; in-plane: observer {crlb.in_plane[0].mean():.1f} km vs targets "
         f"{', '.join(f'{v:.1f}' for v in crlb.in_plane[1:].mean(axis=1))} km"))
for key, c in zip(("baseline_relative_position", "baseline_range_rate"), curves):
    b_km, j = c.baseline_km, c.improving_until
    turns = j < b_km.size - 1  # a step after baseline j fails: MI falls or the in-plane RMS rises
    table.add(claims.CLAIMS[key].judge(
        c.improves_throughout(claims.BASELINE_MIN_DROP),
        shown=(f"MI {c.mi[0]:.2f} -> {c.mi[j]:.2f} nats, observer in-plane RMS {c.obs_xy[0]:.1f} -> {c.obs_xy[j]:.1f} "
               f"km from {b_km[0]:.0f} to {b_km[j]:.0f} km, improving at every step"
               + (f"; then at {b_km[-1]:.0f} km MI {c.mi[-1]:.2f} nats, RMS {c.obs_xy[-1]:.1f} km" if turns else "")
               + f" (end to end: RMS {c.end_to_end_drop:.1f}x lower)"),
        reason=(f"both improve at every step up to {b_km[j]:.0f} km, then turn: from {b_km[j]:.0f} to "
                f"{b_km[j + 1]:.0f} km the MI changes by {c.mi[j + 1] - c.mi[j]:+.2f} nats and the in-plane RMS by "
                f"{c.obs_xy[j + 1] / c.obs_xy[j]:.2f}x ({int((~c.step_improves).sum())} of {b_km.size - 1} steps fail; "
                f"the longest baseline leads by {baseline_max_phase:g} of a period); the rule holds over "
                f"{b_km[0]:.0f}-{b_km[j]:.0f} km of the sweep and the turn lies between {b_km[j]:.0f} and "
                f"{b_km[j + 1]:.0f} km") if turns else "",
        note=f"MI peak and in-plane CRLB minimum at {'the same' if c.same_peak else 'different'} baselines; "
             f"out-of-plane share of the observer's terminal variance {c.out_of_plane_share:.0%} (mean over "
             "baselines); until 2026-11-26g judged up to the MI peak with a 1.2x allowance for the rebound"))
table.add(claims.CLAIMS["timing"].judge(
    r17.ratio_value, shown=(f"at N = {n_ref}: " if n_ref != 17 else "") + f"MI {r17.ratio_value:.1f}x, MI + gradient {r17.ratio_gradient:.1f}x",
    note=f"crossover from this run's times: {timing.crossover_value} (MI), {timing.crossover_gradient} (MI + "
         "gradient); O(N) against O(N^3) shows at larger N (timing figure)"))
table.display()

# %% [markdown]
# ## Exercises
#
# Change one parameter in the `parameters` cell at the top (or pass it to the runner, e.g.
# `python -m cislunar.publish.notebooks --quick 02 -p MC_SAMPLES=80000`), write down a prediction, then rerun and
# compare. The worked solutions are functions of `cislunar.papers.wolf_jones.exercises` that run the same
# computation at a small size and explain the answer.
#
# 1. **Samples and the standard error.** Multiply `MC_SAMPLES` by four. How should the "+-" of the joint Monte
#    Carlo estimate of section 1 change, and can the first row of the table change its verdict? Worked solution:
#    `exercise_02_monte_carlo_samples` (the estimate is a mean of independent samples, so its standard error
#    falls as $1/\sqrt n$: by 2x; the tolerance of 3 standard errors tightens with it and the verdict stays).
# 2. **Halve the range noise.** Set `RANGE_SIGMA_KM = 0.05`. Before running, bound the change of
#    $\mathcal I(X;Y)$ in section 4: write Eq. 18 with whitened measurements, $\tfrac12\ln|I + W|$, and ask what
#    halving the noise does to the range rows of $W$ and how much one measurement can gain at most. Compare
#    (3 targets) x (17 days) x $\ln 2$ = 35.4 nats with the printed change, and use the chain-rule gains of the
#    figure in section 4 to say which days reach the bound. Worked solution: `exercise_02_range_noise` (the MI
#    rises by at most $\ln 2$ nats per range measurement; the first four days gain exactly that, 100 m against a
#    100 km prior, the later days about half of it, because the filter has by then pinned down much of what a
#    range measurement sees: 22.7 of the 35.4 nats in all).
