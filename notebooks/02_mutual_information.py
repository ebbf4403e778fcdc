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
# All computation lives in `cislunar.sensing.measurements`, `cislunar.sensing.covariance` and `cislunar.sensing.information`.

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: quick mode uses fewer samples, baselines and timing sizes; every step still runs.
MC_SAMPLES = 20000 if QUICK else 200000  # Monte Carlo samples for the KL check (Eq. 11)
N_BASELINES = 5 if QUICK else 10  # observer phase offsets in the baseline study
TIMING_SIZES = [5, 9, 17] if QUICK else [5, 9, 17, 33, 65]  # measurement times per window in the timing study
TIMING_MIN_TIME = 0.02 if QUICK else 0.1  # seconds per timing run

import matplotlib.pyplot as plt
import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import find_events, propagate
from cislunar.guidance import scvx
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.sensing import covariance as cov
from cislunar.sensing import information as info
from cislunar.sensing import measurements as meas

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
p, h, r = 4.0, 1.0, 1.0
closed = 0.5 * np.log(1 + h**2 * p / r)
xs = rng.normal(0.0, np.sqrt(p), size=MC_SAMPLES)
kl = info.gaussian_kl((h * xs)[:, None], [[r]], [0.0], [[h**2 * p + r]])  # KL(p(y|x) || p(y)) for each x
mc, se = info.monte_carlo_mutual_information([[p]], np.zeros((0, 1, 1)), np.zeros((0, 1, 1)), [[[h]]], [[r]],
                                             MC_SAMPLES, rng)
print(f"closed form 0.5 ln(1 + h^2 p / r)  = {closed:.5f} nats")
print(f"E_x[KL] over {MC_SAMPLES} samples    = {kl.mean():.5f} +- {kl.std(ddof=1) / np.sqrt(MC_SAMPLES):.5f}")
print(f"joint Monte Carlo of log ratio       = {mc:.5f} +- {se:.5f}")
print(f"posterior/prior std ratio: {np.sqrt(1 / (1 / p + h**2 / r)) / np.sqrt(p):.4f} "
      f"= exp(-I) = {np.exp(-closed):.4f}")

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
dt = 1.0
F_toy = np.tile([[1.0, dt], [0.0, 1.0]], (2, 1, 1))
Q_toy = np.tile(0.01 * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]]), (2, 1, 1))  # Van Loan, PSD 0.01
H_toy = np.tile([[[1.0, 0.0]]], (3, 1, 1))
R_toy = np.tile([[[0.25]]], (3, 1, 1))
P0_toy = np.diag([1.0, 0.5])
Pt, Ht, Rt = info.stacked_matrices(P0_toy, F_toy, Q_toy, H_toy, R_toy)
np.set_printoptions(precision=3, suppress=True)
print("P~ (Eq. 19):\n", Pt, "\nH~ (Eq. 20):\n", Ht, "\nR~ (Eq. 23):\n", Rt)
dense_toy = info.mutual_information_dense(P0_toy, F_toy, Q_toy, H_toy, R_toy)
total_toy, terms_toy = info.mutual_information(P0_toy, F_toy, Q_toy, H_toy, R_toy, return_terms=True)
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

# %%
rho_km = np.logspace(0, 5, 200)  # 1 km up: below it the noise exceeds 4 mrad, of no use for tracking
sig = meas.angular_sigma(rho_km, meas.AMOS_SIGMA_MIN_RAD, meas.AMOS_RESOLUTION_KM)
fig, ax = plt.subplots(figsize=(5.5, 3.5))
ax.loglog(rho_km, sig * 1e6, label=r"$\sqrt{\sigma_{min}^2 + D^2/\rho^2}$ (AMOS Eq. 20)")
ax.axvline(meas.AMOS_RESOLUTION_KM / meas.AMOS_SIGMA_MIN_RAD, color="0.5", ls=":",
           label=r"$\rho = D/\sigma_{min}$ = 400 km")
ax.axvline(215.0, color="C3", ls="--", label="215 km: AMOS mean agent-target range")
ax.set(xlabel="range [km]", ylabel=r"$\sigma_\theta$ [µrad]", title="Angular noise model")
ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=1, frameon=False)  # below the axes
_ = plotting.save_figure(fig, "02_angular_noise_model", output_dir=out)
print(f"sigma_theta at 215 km: "
      f"{meas.angular_sigma(215.0, meas.AMOS_SIGMA_MIN_RAD, meas.AMOS_RESOLUTION_KM) * 1e6:.3f} µrad")

# %% [markdown]
# ## 4 · Test case 2: the observation window and its CRLB
#
# Three targets on the Table 4 DROs and an observer; window $[P_{ref}, 2P_{ref}]$ with one range/range-rate pair
# per target per day, initial errors 100 km and $10^{-2}$ km/s = 10 m/s per axis (Table 5). **Choice:** the printed
# observer row ($\dot y_0$ = 0.528996986) does not close as a periodic orbit (notebook 01), and the paper's
# optimised observer trajectory is not published, so the observer here coasts on the `observer_tf` DRO of Table 4
# (which closes): a coasting stand-in, not the $\alpha_h = 0$ solution of the paper (Table 4's $x_{\mathcal S}(t_0)$ and
# $x_{\mathcal S}(t_f)$ lie on different orbits, so even the minimum-ΔV observer flies a transfer). $P_{ref}$ is the
# period of that DRO; the window $[P_{ref}, 2P_{ref}]$ therefore starts at half its end time.
#
# Process noise: Table 5 prints "$Q$ [km/s³] = $10^{-11}$"; the PSD of an acceleration has units km²/s³. Read as
# $10^{-11}$ km²/s³ the CRLB of test case 1 grows without bound, against the paper's text, so we adopt the same
# number in normalised units — a reading chosen by looking at the paper's result, hence "consistent (tuned)" in
# the table (notebook 06 sweeps the readings) — $q = 10^{-11}$ LU²/TU³ $= 2.80\times10^{-17}$ km²/s³ (the evidence and the other
# readings are in notebook 06), and discretise it *exactly* along each reference trajectory,
# $Q_k = \int\Phi(t_{k+1},\tau)GqG^T\Phi(t_{k+1},\tau)^Td\tau$ (time-varying Van Loan; Gauss-Legendre quadrature of
# heyoka STMs, checked against the Lyapunov ODE in the tests).

# %%
observer_x0 = np.array([7.80136159e-1, 0, 0, 0, 5.53104815e-1, 0])
targets_x0 = np.array([[7.78717734e-1, 0, 0, 0, 5.55157488e-1, 0],
                       [7.79426943e-1, 0, 0, 0, 5.54128887e-1, 0],
                       [7.81554639e-1, 0, 0, 0, 5.51070308e-1, 0]])
P_ref = float(find_events(em, observer_x0, 10.0, ("y_crossing",)).t[1])
start = propagate(em, np.vstack([observer_x0, targets_x0]), [0.0, P_ref]).x[:, -1]
day = float(em.days_to_tu(1.0))
t_win = P_ref + np.arange(0.0, P_ref + 1e-12, day)
P_obj = cov.state_covariance(cov.WOLF_JONES_SIGMA_POS_KM, cov.WOLF_JONES_SIGMA_VEL_KM_S, em)
R_rr = meas.range_range_rate_noise(meas.WOLF_JONES_RANGE_SIGMA_KM, meas.WOLF_JONES_RANGE_RATE_SIGMA_KM_S, em)
q_nd = cov.psd_to_nondimensional(cov.WOLF_JONES_PSD_KM2_S3, em)
lin = cov.linearize_augmented(em, start[0], start[1:], t_win, meas.RANGE_RANGE_RATE, R_rr,
                              cov.block_diag([P_obj] * 4), q=q_nd, derivatives=True)
print(f"P_ref = {em.tu_to_days(P_ref):.3f} d; window {em.tu_to_days(t_win[0]):.2f}-{em.tu_to_days(t_win[-1]):.2f} d, "
      f"{t_win.size} measurement times, state dim {lin.P0.shape[0]}")
# any [P, 2P] window on these DROs starts at about 16 d: the periods of the three target DROs
P_targets_d = [float(em.tu_to_days(find_events(em, x, 10.0, ("y_crossing",)).t[1])) for x in targets_x0]
print("target DRO periods [d]:", np.round(P_targets_d, 2))
print(f"q = {q_nd:.4e} LU^2/TU^3; one-day Q_S velocity sigma = "
      f"{np.sqrt(lin.Q[0, 3, 3]) * em.velocity_unit_km_s * 1e3:.3f} m/s "
      f"(sqrt(q dt) = {np.sqrt(cov.WOLF_JONES_PSD_KM2_S3 * 86400) * 1e3:.3f} m/s)")
mi_dense = info.window_information(lin, method="dense")
mi_struct, gains = info.mutual_information(*lin.arrays, return_terms=True)
print(f"I(X;Y): dense Eq. 18 = {mi_dense:.9f} nats, chain rule = {mi_struct:.9f} nats "
      f"(rel. diff {abs(mi_dense - mi_struct) / mi_dense:.1e})")

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
hist = cov.covariance_analysis(*lin.arrays)
days = em.tu_to_days(t_win)
names = ["observer", "target 1", "target 2", "target 3"]
sig_post = np.array([cov.position_sigma_km(hist.posterior, i, em) for i in range(4)])
sig_prior = np.array([cov.position_sigma_km(hist.prior, i, em) for i in range(4)])
sig_z = np.array([cov.position_sigma_km(hist.posterior, i, em, axes=(2,)) for i in range(4)])  # out of plane
sig_xy = np.array([cov.position_sigma_km(hist.posterior, i, em, axes=(0, 1)) for i in range(4)])  # in-plane
z_cols = np.abs(lin.H[..., [6 * i + j for i in range(4) for j in (2, 5)]]).max()
print(f"largest |dH/dz|, |dH/dvz| over the window: {z_cols:.1e} (out-of-plane errors unobserved)")
fig, (ax1, ax2, ax3) = plt.subplots(1, 3, figsize=(14, 4.0), layout="constrained")
for i, name in enumerate(names):
    ax1.semilogy(days, sig_post[i], "-", lw=2.5, color="0.8", label="total, all four (coincide)" if i == 0 else None,
                 zorder=1)
for i, name in enumerate(names):
    ax1.semilogy(days, sig_xy[i], "o-", ms=3, lw=1, color=f"C{i}", label=f"in-plane, {name}", zorder=3)
ax1.semilogy(days, sig_z[0], "k--", lw=1, label=r"out-of-plane $\sigma_z$ (free flight)", zorder=2)
ax1.set(xlabel="time [days]", ylabel="position RMS (CRLB) [km]", title="CRLB along the window (cf. Fig. 9)")
ax1.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=2, frameon=False)
for i in range(1, 4):
    ax2.plot(days, sig_xy[i] / sig_xy[0], "o-", ms=3, lw=1, color=f"C{i}", label=names[i])
ax2.axhline(1.0, color="0.4", lw=0.8, ls=":")
ax2.set(xlabel="time [days]", ylabel="in-plane RMS, target / observer [-]",
        title="above 1: observer better determined")
ax2.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=3, frameon=False)
ax3.bar(days, gains, width=0.6)
ax3.set(xlabel="time [days]", ylabel="information gain [nats]", title=r"per-measurement $\mathcal{I}_k$ (chain rule)")
_ = plotting.save_figure(fig, "02_test_case_2_crlb_and_gains", output_dir=out)
print("terminal position RMS [km]:", dict(zip(names, np.round(sig_post[:, -1], 3).tolist())))
print("mean position RMS over the window [km]:", dict(zip(names, np.round(sig_post.mean(axis=1), 3).tolist())))
print("mean in-plane RMS over the window [km]:", dict(zip(names, np.round(sig_xy.mean(axis=1), 3).tolist())))
print(f"out-of-plane share of the summed position variance at the window end: "
      f"{np.sum(sig_z[:, -1]**2) / np.sum(sig_post[:, -1]**2):.2%}")
# in-plane RMS after the second update above that after the first (the total is the free-flight sigma_z, which
# grows whatever P0 is, so it cannot show the effect)
transient = sig_xy[:, 1] > sig_xy[:, 0]
print("in-plane RMS after the 1st / 2nd update [km]:",
      {n: (round(float(a), 1), round(float(b), 1)) for n, a, b in zip(names, sig_xy[:, 0], sig_xy[:, 1])},
      f"; largest in-plane RMS over the window {sig_xy.max():.0f} km")


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
I0, g_struct = info.window_information(lin, gradient=True)
_, g_dense = info.window_information(lin, gradient=True, method="dense")


def mi_of_observer(x):
    return info.window_information(cov.linearize_augmented(em, x, start[1:], t_win, meas.RANGE_RANGE_RATE, R_rr,
                                                           lin.P0, Q=lin.Q))


hfd = 1e-6
g_fd = np.array([(8 * (mi_of_observer(start[0] + hfd * e) - mi_of_observer(start[0] - hfd * e))
                  - (mi_of_observer(start[0] + 2 * hfd * e) - mi_of_observer(start[0] - 2 * hfd * e))) / (12 * hfd)
                 for e in np.eye(6)])
grad_err = np.max(np.abs(g_struct - g_fd)) / np.max(np.abs(g_fd))
print("gradient [nats/LU, nats/(LU/TU)]\n structured:", g_struct, "\n dense:     ", g_dense, "\n central FD:",
      np.round(g_fd, 3) + 0.0)
print(f"max |structured - FD| / max |FD| = {grad_err:.1e}; structured vs dense "
      f"{np.max(np.abs(g_struct - g_dense)) / np.max(np.abs(g_dense)):.1e}")

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
direction = g_struct / np.linalg.norm(g_struct)
steps_km = np.array([1.0, 10.0, 100.0, 1000.0])
true_mi, lin_mi = [], []
for s_km in steps_km:
    dx = direction * em.km_to_lu(s_km)
    true_mi.append(mi_of_observer(start[0] + dx))
    lin_mi.append(I0 + g_struct @ dx)
lin_err = np.abs(np.array(true_mi) - np.array(lin_mi))
for s_km, a, b in zip(steps_km, true_mi, lin_mi):
    dx = direction * em.km_to_lu(s_km)
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

# %%
tgt = targets_x0[0]
P_tgt = float(find_events(em, tgt, 10.0, ("y_crossing",)).t[1])
phases = np.geomspace(0.002, 0.5, N_BASELINES)  # fraction of the period the observer leads by
obs_starts = propagate(em, tgt, np.r_[0.0, phases * P_tgt]).x[1:]
t_base = np.arange(0.0, P_tgt + 1e-12, day)
P0_pair = cov.block_diag([P_obj] * 2)
models = {"relative position (100 m)": (meas.RELATIVE_POSITION, meas.relative_position_noise(0.1, em)),
          "range + range rate": (meas.RANGE_RANGE_RATE, R_rr)}
study = {name: {"baseline": [], "mi": [], "obs": [], "tgt": [], "obs_z": [], "obs_xy": [], "tgt_xy": []}
         for name in models}
for name, (model, noise) in models.items():
    for xo in obs_starts:
        lb = cov.linearize_augmented(em, xo, tgt[None], t_base, model, noise, P0_pair, q=q_nd)
        hb = cov.covariance_analysis(*lb.arrays)
        study[name]["baseline"].append(np.mean(np.linalg.norm(lb.targets[0, :, :3] - lb.observer[:, :3], axis=1)))
        study[name]["mi"].append(info.mutual_information(*lb.arrays))
        study[name]["obs"].append(cov.position_sigma_km(hb.posterior[-1], 0, em))
        study[name]["tgt"].append(cov.position_sigma_km(hb.posterior[-1], 1, em))
        study[name]["obs_z"].append(cov.position_sigma_km(hb.posterior[-1], 0, em, axes=(2,)))  # observer's sigma_z
        # in-plane terminal RMS sqrt(P_xx + P_yy)
        study[name]["obs_xy"].append(cov.position_sigma_km(hb.posterior[-1], 0, em, axes=(0, 1)))
        study[name]["tgt_xy"].append(cov.position_sigma_km(hb.posterior[-1], 1, em, axes=(0, 1)))
study = {k: {kk: np.array(vv) for kk, vv in v.items()} for k, v in study.items()}
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6))
for k, (name, res) in enumerate(study.items()):
    b_km = em.lu_to_km(res["baseline"])
    ax1.semilogx(b_km, res["mi"] - res["mi"][0], "o-", color=f"C{k}",
                 label=f"{name} (I at shortest = {res['mi'][0]:.1f} nats)")
    # in-plane RMS: target first, as large open squares, so the observer's filled dots stay visible where they meet
    ax2.loglog(b_km, res["tgt_xy"], "s", ms=9, mfc="none", mew=1.2, color=f"C{k}")
    ax2.loglog(b_km, res["obs_xy"], "o-", ms=4, color=f"C{k}", zorder=3)
    ax2.loglog(b_km, res["obs"], ":", lw=1.2, color=f"C{k}", zorder=2)  # observer's total RMS
ax1.set(xlabel="mean baseline [km]", ylabel=r"$\mathcal{I} - \mathcal{I}_{shortest}$ [nats]",
        title="MI gain vs baseline")
ax2.set(xlabel="mean baseline [km]", ylabel="terminal position RMS [km]", title="CRLB vs baseline (colours as left)")
ax1.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), frameon=False)  # legends below the axes
roles = [plt.Line2D([], [], marker="o", ms=4, color="0.3", label="observer, in-plane"),
         plt.Line2D([], [], marker="s", ms=9, mfc="none", ls="none", color="0.3", label="target, in-plane"),
         plt.Line2D([], [], ls=":", lw=1.2, color="0.3", label="observer, total (incl. out-of-plane)")]
ax2.legend(handles=roles, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2, frameon=False)
_ = plotting.save_figure(fig, "02_baseline_study", output_dir=out)
for name, res in study.items():
    print(name, "\n  baseline [km]:", np.round(em.lu_to_km(res["baseline"])), "\n  MI [nats]:", np.round(res["mi"], 2),
          "\n  observer RMS [km]:", np.round(res["obs"], 3), "\n  target RMS [km]:  ", np.round(res["tgt"], 3),
          "\n  observer sigma_z [km]:", np.round(res["obs_z"], 3),
          "\n  observer in-plane RMS [km]:", np.round(res["obs_xy"], 3),
          "\n  target in-plane RMS [km]:  ", np.round(res["tgt_xy"], 3))
gain = {name: float(res["mi"].max() - res["mi"][0]) for name, res in study.items()}
# the status below uses the observer's in-plane terminal RMS: for range + range rate the total is ~all sigma_z
rms_drop = {name: float(res["obs_xy"][0] / res["obs_xy"].min()) for name, res in study.items()}
peak = {name: float(em.lu_to_km(res["baseline"][np.argmax(res["mi"])])) for name, res in study.items()}
same_peak = {name: int(np.argmax(res["mi"])) == int(np.argmin(res["obs_xy"])) for name, res in study.items()}
for name, res in study.items():
    print(f"{name}: MI peak at {peak[name]:.0f} km, in-plane CRLB minimum at "
          f"{em.lu_to_km(res['baseline'][np.argmin(res['obs_xy'])]):.0f} km "
          f"({'the same baseline' if same_peak[name] else 'different baselines'})")
obs_above = {name: [f"{b:.0f}" for b, o, g in zip(em.lu_to_km(res["baseline"]), res["obs"], res["tgt"]) if o > 1.05 * g]
             for name, res in study.items()}
print("baselines [km] where the observer's total RMS exceeds the target's by > 5%:", obs_above)

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

# %%
timings = []
for N in TIMING_SIZES:
    t_n = np.linspace(P_ref, 2 * P_ref, N)
    ln = cov.linearize_augmented(em, start[0], start[1:], t_n, meas.RANGE_RANGE_RATE, R_rr, lin.P0, q=q_nd,
                                 derivatives=True)
    timings.append(info.time_evaluations(*ln.arrays, ln.dF, ln.dH, repeat=3, min_time=TIMING_MIN_TIME))
fig, ax = plt.subplots(figsize=(5.5, 3.8))
ax.loglog(TIMING_SIZES, [1e3 * r.dense_value for r in timings], "o-", label="dense Eq. 18")
ax.loglog(TIMING_SIZES, [1e3 * r.structured_value for r in timings], "s-", label="chain rule")
ax.loglog(TIMING_SIZES, [1e3 * r.dense_gradient for r in timings], "o--", label="dense Eq. 18 + Eqs. 47-50")
ax.loglog(TIMING_SIZES, [1e3 * r.structured_gradient for r in timings], "s--",
          label="chain rule + gradient (square-root reverse mode)")
ax.set(xlabel="measurement times N [-]", ylabel="time per evaluation [ms]", title="Evaluation cost")
ax.set_xticks(TIMING_SIZES, [str(n) for n in TIMING_SIZES])  # plain labels at the sizes run, no minor labels
ax.xaxis.set_minor_formatter(plt.NullFormatter())
ax.yaxis.set_major_locator(plt.LogLocator(subs=(1.0, 2.0, 5.0)))
ax.yaxis.set_major_formatter(plt.FormatStrFormatter("%g"))
ax.yaxis.set_minor_formatter(plt.NullFormatter())
ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=2, frameon=False)  # below the axes
_ = plotting.save_figure(fig, "02_timing_dense_vs_structured", output_dir=out)
for N, r in zip(TIMING_SIZES, timings):
    print(f"N = {N:3d}: MI {r.ratio_value:5.1f}x, MI + gradient {r.ratio_gradient:5.1f}x faster structured "
          f"(dense {1e3 * r.dense_gradient:.2f} ms, structured {1e3 * r.structured_gradient:.2f} ms)")
r17 = timings[TIMING_SIZES.index(17)]


def crossover(sizes, ratios):
    """Window size where the dense/structured time ratio first reaches 1 (log-log interpolation), as text."""
    ratios = np.asarray(ratios)
    if ratios[0] >= 1.0:
        return f"at or below N = {sizes[0]}"
    j = int(np.argmax(ratios >= 1.0))
    if ratios[j] < 1.0:
        return f"above N = {sizes[-1]} (not reached)"
    n_star = np.exp(np.interp(0.0, np.log(ratios[j - 1:j + 1]), np.log(sizes[j - 1:j + 1])))
    return f"N = {n_star:.0f} (between {sizes[j - 1]} and {sizes[j]})"


cross_value = crossover(TIMING_SIZES, [r.ratio_value for r in timings])
cross_gradient = crossover(TIMING_SIZES, [r.ratio_gradient for r in timings])
print(f"chain rule faster than dense from {cross_value} for the MI, from {cross_gradient} for MI + gradient; "
      f"at N = 17: {r17.ratio_value:.1f}x and {r17.ratio_gradient:.1f}x")

# %% [markdown]
# ## 8 · Paper versus reproduction

# %%
table.add_typed("Eq. 11: I = E_X[KL(p(Y|X)||p(Y))] (scalar worked example)", "formula only (Eq. 11)",
          f"Monte Carlo {mc:.4f} +- {se:.4f} vs closed form {closed:.4f} nats",
          "beyond paper" if abs(mc - closed) < 3 * se else "differs: Monte Carlo outside 3 standard errors",
          "our worked example (p = 4, h = r = 1); tolerance: 3 standard errors of the Monte Carlo mean")
table.add_typed("Eq. 18 on test case 2 window (dense)", "formula only", f"{mi_dense:.4f} nats", "derived",
          "no numerical MI values are printed in the paper")
table.add_typed("Eq. 18 by chain rule (Kalman recursion)", "not in paper",
          f"rel. diff {abs(mi_dense - mi_struct) / mi_dense:.1e}",
          "beyond paper", "same value at O(N) cost; square-root form (the dense log-determinant loses digits when "
          "the measurements are far more precise than the prior)")
grad_dense_err = float(np.max(np.abs(g_struct - g_dense)) / np.max(np.abs(g_dense)))
table.add_typed("Eqs. 44-52 gradient vs central differences", "formula only",
          f"structured vs FD {grad_err:.1e}; structured vs dense Eq. 48 {grad_dense_err:.1e} (max rel.)",
          "beyond paper" if grad_err < 1e-5 else "differs: gradient disagrees with finite differences",
          "tolerance 1e-5 on structured vs FD; P~ held fixed as in the paper; FD of the structured value (the dense "
          "log-determinant has too few digits for differences at step 1e-6), so the dense gradient agrees only to "
          "the level shown")
table.add_typed("Eq. 44 linearisation error at 10 km / 100 km steps", "not in paper",
          f"{lin_err[1]:.2e} / {lin_err[2]:.2e} nats", "beyond paper",
          f"the range where Eq. 44 alone holds; the package's SCvx uses a quadratic information model by default and a "
          f"trust region of {em.lu_to_km(scvx_defaults.eta0):,.0f}-{em.lu_to_km(scvx_defaults.eta_max):,.0f} km "
          "(notebook 05 compares linear and quadratic)")
table.add_typed("Process-noise PSD (Table 5)", "1e-11 km/s^3",
          f"{q_nd:.1e} LU^2/TU^3 = {cov.WOLF_JONES_PSD_KM2_S3:.2e} km^2/s^3", "consistent (tuned)",
          "normalised reading, chosen because 1e-11 km^2/s^3 would let test case 1's CRLB grow without bound, "
          "against the paper's text; notebook 06 sweeps the readings")
win_tol_d = 1.0  # tolerance on each end of the window, days
win_ok = abs(days[0] - 17.0) <= win_tol_d and abs(days[-1] - 32.0) <= win_tol_d
table.add_typed("Reference DRO period / observation window", "window roughly 17-32 days (Fig. 8 text); [P_ref, 2 P_ref]",
          f"P_ref = {em.tu_to_days(P_ref):.2f} d, window {days[0]:.2f}-{days[-1]:.2f} d",
          "reproduced" if win_ok else "differs: window ends more than 1 d from the paper's",
          f"tolerance +-{win_tol_d:g} d on each end; P_ref from the Table 4 observer_tf DRO. The paper's own definition "
          f"forces the start to be half the end (~16 d; target DRO periods {', '.join(f'{p:.2f}' for p in P_targets_d)}"
          f" d), so 'roughly 17' is loose: our start is {17.0 - days[0]:.2f} d earlier")
table.add_typed("Observer trajectory in the window", "SCvx-optimised (not published)", "coasting on observer_tf DRO",
          "not in paper: our choice; the optimised trajectory is not given and the printed observer_t0 row is not "
          "periodic", "a coasting stand-in, not the alpha_h = 0 solution (Table 4's x_S(t0) and x_S(tf) are "
          "different orbits, so alpha_h = 0 still needs a transfer)")
table.add_typed("In-plane RMS growth after the first update (test case 2 analogue of the Fig. 4 remark)",
          "noticeable growth at the window start (attributed to a diagonal P0)",
          f"in-plane RMS grows from the 1st to the 2nd update for {int(transient.sum())} of 4 objects "
          f"(observer {sig_xy[0, 0]:.0f} -> {sig_xy[0, 1]:.0f} km)",
          "reproduced" if transient.any() else "differs: no initial growth in this geometry",
          "criterion: in-plane RMS after the 2nd update above that after the 1st for at least one object; symptom "
          "only, the cause (diagonal P0) is not tested; the paper's Fig. 4 is test case 1 (notebook 05)")
obs_better = sig_post[0].mean() < sig_post[1:].mean()
table.add_typed("Observer RMS below targets on average (Fig. 9)", "yes",
          f"observer {sig_post[0].mean():.2f} km vs targets {sig_post[1:].mean():.2f} km (mean over window)",
          "reproduced" if obs_better else "differs: observer is not better determined than the targets here",
          "un-manoeuvred observer, so only qualitative; the total is the unobserved out-of-plane error, the same "
          f"for all four; in-plane: observer {sig_xy[0].mean():.1f} km vs targets "
          f"{', '.join(f'{v:.1f}' for v in sig_xy[1:].mean(axis=1))} km")
for name, res in study.items():
    b_km, obs_xy, mi = em.lu_to_km(res["baseline"]), res["obs_xy"], res["mi"]
    k_best = int(np.argmin(obs_xy))
    improves = gain[name] > 0 and rms_drop[name] > 1.5
    rebound = float(obs_xy[-1] / obs_xy[k_best])  # > 1: the in-plane CRLB gets worse again at the longest baselines
    mi_drop = float(mi.max() - mi[-1])
    status = ("reproduced" if improves and rebound < 1.2 else
              f"differs: improves up to about {b_km[k_best]:.0f} km, then the in-plane CRLB worsens "
              f"({rebound:.1f}x) and the MI drops" if improves else
              "differs: the in-plane CRLB gains little from the baseline")
    table.add_typed(f"MI and CRLB improve with baseline ({name})", "yes (Markley/Psiaki argument, qualitative)",
              f"MI +{gain[name]:.2f} nats up to {peak[name]:.0f} km (then -{mi_drop:.2f}); observer in-plane RMS "
              f"{obs_xy[0]:.1f} -> {obs_xy[k_best]:.1f} km at {b_km[k_best]:.0f} km, {obs_xy[-1]:.1f} km at "
              f"{b_km[-1]:.0f} km, rebound {obs_xy[-1] / obs_xy[k_best]:.3f}x (threshold 1.2x)", status,
              "criterion fixed before comparing: MI gain > 0, in-plane RMS drop > 1.5x, rebound at the longest "
              "baseline < 1.2x; observer phase-shifted on the target's DRO; MI peak and in-plane CRLB minimum at "
              f"{'the same' if same_peak[name] else 'different'} baselines; out-of-plane share of the observer's "
              f"terminal variance {np.mean(res['obs_z']**2 / res['obs']**2):.0%} (mean over baselines)")
table.add_typed("Structured vs dense speed at test-case-2 size (N = 17)", "not in paper",
          f"MI {r17.ratio_value:.1f}x, MI + gradient {r17.ratio_gradient:.1f}x", "beyond paper",
          f"crossover from this run's times: {cross_value} (MI), {cross_gradient} (MI + gradient); O(N) against "
          "O(N^3) shows at larger N (timing figure)")
table.display()
