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
# # 07 · Spacecraft-to-spacecraft absolute tracking and MMD guidance
#
# **What you will learn.** How two spacecraft that only see each other through a camera can estimate *both*
# absolute states (spacecraft-to-spacecraft absolute tracking, SSAT); why the range between them is the weak
# direction of an angles-only estimate; how a linear covariance analysis along the true trajectories measures the
# 1-sigma range uncertainty $\sqrt{J_\rho}$; and how the maximum-measurement-deviation (MMD) policy picks an
# information-gathering burn from a 3x3 eigenproblem. Beyond the paper, we compare MMD with the true minimiser of
# $J_\rho$ over all burn directions and with the "burn perpendicular to the line of sight" heuristic over a range of
# coast times, and say how near-optimal MMD is.
#
# **Paper sections followed.** Greaves & Scheeres, "Autonomous information gathering guidance for
# spacecraft-to-spacecraft tracking with optical sensors" (AMOS 2023): Sec. 3.1 (Eqs. 1-7), 3.2 (Eqs. 8-14),
# 3.3 (Eqs. 15-20), 3.4 (Eqs. 21-24) and the covariance-analysis set-up of Sec. 5. The quasi-periodic orbit and the
# informed station keeping of Secs. 4-5 are notebook 08.

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: a coarser sphere of burn directions and fewer coast times in quick mode.
N_GRID = 600 if QUICK else 3000  # burn directions on the sphere (Fibonacci lattice)
N_PERP = 36 if QUICK else 120  # directions on the circle perpendicular to the line of sight
COAST_HOURS = [1, 4, 12, 24, 48] if QUICK else [1, 2, 4, 8, 12, 18, 24, 36, 48]
DV_M_S = [0.1, 1.0]  # burn magnitudes upsilon, m/s (the paper gives none for this experiment)
LEAD_DAYS = 1.0  # the burn happens this long before the target's apolune
APOLUNE_RANGE_KM = 215.0  # agent-target range at apolune (scale of the paper's scenario)

import matplotlib.pyplot as plt
import numpy as np
from scipy.optimize import brentq

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.propagation import propagate
from cislunar.guidance import ssat
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable

plotting.use_style()
out = OUTPUT_DIR or None
rng = np.random.default_rng(SEED)
table = ComparisonTable("07 SSAT and MMD guidance (Greaves & Scheeres AMOS 2023, Eqs. 1-24)")
L, V = em.length_unit_km, em.velocity_unit_km_s
HR = 3600.0 / em.time_unit_s

# %% [markdown]
# ## 1 · The SSAT state (Eqs. 1-7)
#
# The *inertial* SSAT state stacks the agent and target CR3BP states, $\mathbf x = [\mathbf s_a; \mathbf s_t]$
# (Eq. 1; "inertial" is the paper's name, both states live in the rotating frame). The *relative* SSAT state holds
# their mean and difference, $\tilde{\mathbf x} = [\mathbf s_\alpha; \mathbf s_\rho] = T\mathbf x$ with
# $\mathbf s_\alpha = (\mathbf s_a+\mathbf s_t)/2$, $\mathbf s_\rho = \mathbf s_t - \mathbf s_a$ and
# $T = \begin{bmatrix}\tfrac12 I & \tfrac12 I\\ -I & I\end{bmatrix}$ (Eqs. 3-6); covariances map as
# $\tilde P = TPT^T$ (Eq. 7). The paper also mentions an *agent-based* absolute state
# $\bar{\mathbf x} = [\mathbf s_a; \mathbf s_\rho] = T_a\mathbf x$. We check the identities on random states and
# covariances, and the reason the relative form is useful: the angle measurements of Eqs. 15-18 depend on
# $\mathbf s_\rho$ only, so in both relative coordinate systems the measurement Jacobian is $[0\ \ H_\rho]$, and
# both give the same range variance.

# %%
x_rand = rng.standard_normal((4, 12))
A = rng.standard_normal((12, 12))
P_rand = A @ A.T + 12 * np.eye(12)
T = ssat.transform_matrix()
err_state = np.max(np.abs(ssat.from_relative(ssat.to_relative(x_rand)) - x_rand))
err_cov = np.max(np.abs(ssat.inertial_covariance(ssat.relative_covariance(P_rand)) - P_rand)) / np.max(P_rand)
P_rel, P_agent = ssat.relative_covariance(P_rand), ssat.agent_based_covariance(P_rand)
same_rel_block = np.max(np.abs(P_rel[6:, 6:] - P_agent[6:, 6:])) / np.max(np.abs(P_rel))
J3 = [ssat.range_variance(C, x_rand[0], c) for C, c in ((P_rand, "inertial"), (P_rel, "relative"),
                                                          (P_agent, "agent"))]
print(f"round trip T^-1 T x: {err_state:.1e};  T^-1 (T P T^T) T^-T vs P (relative): {err_cov:.1e}")
print(f"relative block of T P T^T vs T_a P T_a^T: {same_rel_block:.1e};  J_rho in the three coordinates: "
      f"{np.ptp(J3) / np.mean(J3):.1e} relative spread")
print("T B_a (control in relative coordinates) =\n", ssat.control_matrix("relative")[:, 0].reshape(4, 3)[:, 0])

# %% [markdown]
# The last line is the first column of $TB_a$, block by block: an impulse $\mathbf u$ on the agent moves the mean
# velocity by $\mathbf u/2$ and the relative velocity by $-\mathbf u$ (Eqs. 13-14 in relative coordinates).
#
# ## 2 · The demonstration scenario and a covariance analysis without maneuvers
#
# The paper does not give the two orbits used for its MMD guidance (that is its Ref. [8]); we need a close,
# naturally bounded pair about the Gateway orbit. **Choice:** the target flies the 9:2 southern L2 NRHO, the agent
# flies the *same* orbit about half an hour behind (the phase lag is printed below), chosen so that their range at
# the target's apolune is 215 km (the scale of the paper's Sec. 4 scenario). The burn happens `LEAD_DAYS` = 1 day
# before apolune, so coasts longer than 24 h straddle apolune (the 48-h coast ends 24 h after it); shorter coasts
# end before it. Measurements (Sec. 3.3, 5): azimuth and elevation
# of the target seen from the agent every hour, with the RMS angular noise of Eq. 20,
# $\sigma_\theta = \sqrt{\sigma_{\theta,min}^2 + D^2/\rho^2}$, $\sigma_{\theta,min}$ = 10 micro-rad, $D$ = 4 m;
# initial 3-sigma of 60 km and 60 cm/s per axis for both vehicles, uncorrelated; no process noise (the paper lists
# none); the covariance is propagated along the true trajectories.
#
# **The covariance analysis and the cost (Eqs. 19-22).** Eq. 19, $\rho^2\sigma_\theta^2 = \rho^2\sigma_{\theta,min}^2 +
# D^2$, adds in quadrature a pointing floor and the angle a 4 m resolution element subtends at range $\rho$; Eq. 20
# solves it for $\sigma_\theta$, the same for both angles ($R_j = \sigma_\theta^2 I_2$). With no process noise, the
# posterior covariance after the measurements up to $t_k$ is
# $P_k = \Phi_k\big(P_0^{-1} + \sum_{j\le k}\Phi_j^TH_j^TR_j^{-1}H_j\Phi_j\big)^{-1}\Phi_k^T$, with the block-diagonal
# STM $\Phi_j = \Phi(t_j, t_0)$ of both vehicles and $H_j = [-H_\theta\ \ H_\theta]$ (Eq. 18 with respect to the inertial
# SSAT state); `ssat.ssat_covariance` evaluates it in square-root information form for a whole batch of agent
# trajectories at once, and `ssat.ssat_covariance_ekf` by the textbook Joseph-form EKF recursion, as a check. The
# cost is the range variance $J_\rho = M_\rho^T\tilde P_fM_\rho$ (Eq. 21) with $M_\rho = [\mathbf 0_6;
# \hat{\boldsymbol\rho}_{\tau_f}; \mathbf 0_3]$ (Eq. 22) picking the range direction out of the relative partition
# of $\tilde P = TPT^T$; in inertial coordinates the same number is $m^TPm$ with $m = T^TM_\rho =
# [-\hat{\boldsymbol\rho}; \mathbf 0; \hat{\boldsymbol\rho}; \mathbf 0]$. $\sqrt{J_\rho}$ is the 1-sigma range
# uncertainty; at $t_0$ a pair of angles says nothing about range, so it is $\sqrt2\times20$ km.

# %%
nrho = nrho_9_2(em)
t_lead = LEAD_DAYS * 86400.0 / em.time_unit_s


def range_at_apolune(lag_hours):
    back = propagate(em, nrho.x0, np.array([0.0, -lag_hours * HR])).x[-1]
    return np.linalg.norm(back[:3] - nrho.x0[:3]) * L - APOLUNE_RANGE_KM


lag_h = brentq(range_at_apolune, 0.05, 2.0, xtol=1e-12)
xt_apo = nrho.x0
xa_apo = propagate(em, nrho.x0, np.array([0.0, -lag_h * HR])).x[-1]
xt0 = propagate(em, xt_apo, np.array([0.0, -t_lead])).x[-1]
xa0 = propagate(em, xa_apo, np.array([0.0, -t_lead])).x[-1]
P0 = ssat.initial_covariance(em)
t = np.arange(0, 24 * 3 + 1) * HR  # three days of hourly measurements
tgt = ssat.propagate_with_impulses(em, xt0, t)
agt = ssat.propagate_with_impulses(em, xa0, t)
base = ssat.ssat_covariance(em, agt, tgt, P0)
print(f"phase lag {lag_h * 60:.2f} min; range at the burn {base.range_km[0, 0]:.1f} km, "
      f"at apolune {base.range_km[0, 24]:.1f} km, after 3 d {base.range_km[0, -1]:.1f} km")
print(f"sqrt(J_rho): {base.range_sigma_km[0, 0]:.2f} km at t0 (= sqrt(2) x 20 km), "
      f"{base.range_sigma_km[0, 24]:.2f} km after 24 h, {base.range_sigma_km[0, -1]:.2f} km after 72 h")
drop_1h = 100 * (1 - base.range_sigma_km[0, 1] / base.range_sigma_km[0, 0])
print(f"first hour of measurements: sqrt(J_rho) {base.range_sigma_km[0, 0]:.2f} -> {base.range_sigma_km[0, 1]:.2f} km "
      f"(-{drop_1h:.0f} %); smallest {base.range_sigma_km[0].min():.2f} km at "
      f"{np.argmin(base.range_sigma_km[0]):d} h")

# the same analysis by the reference Joseph-form EKF recursion, in the three coordinate systems
for coords in ("inertial", "relative", "agent"):
    _, J_ekf = ssat.ssat_covariance_ekf(em, agt, tgt, P0, coordinates=coords)
    print(f"EKF recursion in {coords:8s} coordinates vs square-root information form: "
          f"max relative difference of J_rho {np.max(np.abs(J_ekf / base.J_rho[0] - 1)):.1e}")

# %% [markdown]
# **The equations as printed.** The dynamics (Eqs. 8-12) are the package's CR3BP in non-dimensional units, where
# $G(m_1+m_2) = r_{12} = 1$, so Eq. 12 gives $\boldsymbol\omega_{D/N} = \hat{\mathbf e}_z$ and Eq. 11 reads
# $\mathbf a = -2\boldsymbol\omega\times\mathbf v - \boldsymbol\omega\times(\boldsymbol\omega\times\mathbf r) -
# (1-\mu)\boldsymbol\rho_{b1}/\rho_{b1}^3 - \mu\boldsymbol\rho_{b2}/\rho_{b2}^3$. The measurement (Eqs. 15-17)
# is azimuth $\theta_a = \tan^{-1}(\rho_y/\rho_x)$ (taken in the right quadrant, `arctan2`) and elevation
# $\theta_e = \sin^{-1}(\rho_z/\rho)$ of $\boldsymbol\rho = \mathbf r_t - \mathbf r_a$, with the Jacobian
# $H_\theta$ of Eq. 18 with respect to $\boldsymbol\rho$; with respect to the agent state it is $-H_\theta$. We type
# Eqs. 11 and 18 in from the paper and compare them with the package at the agent's state at the burn epoch (the
# tests do the same on random states).

# %%
from cislunar.sensing.measurements import AZIMUTH_ELEVATION

w_z = np.array([0.0, 0.0, 1.0])
r_, v_ = xa0[:3], xa0[3:]
rho1, rho2 = r_ - [-em.mu, 0, 0], r_ - [1 - em.mu, 0, 0]
a_eq11 = (-2 * np.cross(w_z, v_) - np.cross(w_z, np.cross(w_z, r_)) - (1 - em.mu) * rho1 / np.linalg.norm(rho1) ** 3
          - em.mu * rho2 / np.linalg.norm(rho2) ** 3)
err_eq11 = np.max(np.abs(a_eq11 - np.asarray(em.eom(xa0))[3:])) / np.max(np.abs(a_eq11))
rx, ry, rz = xt0[:3] - xa0[:3]
rr, rxy = np.sqrt(rx**2 + ry**2 + rz**2), np.sqrt(rx**2 + ry**2)
H_eq18 = np.array([[-ry / rxy**2, rx / rxy**2, 0, 0, 0, 0],
                   [-rx * rz / (rr**2 * rxy), -ry * rz / (rr**2 * rxy), rxy / rr**2, 0, 0, 0]])
_, H_agent, H_target = AZIMUTH_ELEVATION.evaluate(xa0, xt0)
err_eq18 = max(np.max(np.abs(H_target - H_eq18)), np.max(np.abs(H_agent + H_eq18))) / np.max(np.abs(H_eq18))
print(f"Eq. 11 typed in vs package equations of motion: {err_eq11:.1e} relative;  Eq. 18 typed in vs package "
      f"Jacobian (target block = H_theta, agent block = -H_theta): {err_eq18:.1e} relative")

# %%
fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
hours = (t - t[0]) / HR
for s, lab, c, ls in ((tgt.x[0], "target (9:2 NRHO)", "k", "-"),
                      (agt.x[0], f"agent, same orbit {lag_h * 60:.0f} min behind", "tab:red", "--")):
    m = em.moon_centred(s) * L / 1e3
    axes[0].plot(m[:, 1], m[:, 2], color=c, lw=1.5, ls=ls, label=lab)
axes[0].set_xlabel("y, Moon-centred (1000 km)")
axes[0].set_ylabel("z (1000 km)")
axes[0].set_title("three days about apolune")
axes[0].legend(loc="upper right", fontsize=8)
axes[1].plot(hours, base.range_km[0], color="tab:blue")
axes[1].set_xlabel("time since the burn epoch (h)")
axes[1].set_ylabel("agent-target range (km)", color="tab:blue")
ax2 = axes[1].twinx()
ax2.plot(hours, base.sigma_theta_rad[0] * 1e6, color="tab:orange")
ax2.set_ylabel(r"$\sigma_\theta$ (Eq. 20) [µrad]", color="tab:orange")
ax2.grid(False)  # one grid (the range axis'); a second one would not line up
axes[1].axvline(LEAD_DAYS * 24, color="0.6", ls=":", lw=1)
axes[1].text(LEAD_DAYS * 24 + 1, 0.5, "apolune", transform=axes[1].get_xaxis_transform(), va="center", fontsize=8,
             color="0.4")
axes[2].semilogy(hours, base.range_sigma_km[0], color="k")
axes[2].yaxis.set_major_formatter(plt.matplotlib.ticker.ScalarFormatter())
axes[2].yaxis.set_minor_formatter(plt.matplotlib.ticker.NullFormatter())
axes[2].set_yticks([12, 15, 20, 25, 30, 35])
axes[2].set_xlabel("time since the burn epoch (h)")
axes[2].set_ylabel(r"$\sqrt{J_\rho}$, 1-sigma range (km)")
axes[2].set_title("no maneuver")
fig.tight_layout()
_ = plotting.save_figure(fig, "07_ssat_scenario", output_dir=out)

# %% [markdown]
# Even without a burn the first hour of measurements cuts $\sqrt{J_\rho}$ by about a fifth (28.3 to 22.7 km,
# printed above): with velocities known to 20 cm/s, a range error needs a proportional relative-velocity error to
# stay invisible in the angles, and the prior limits that. After that the range is only weakly observable: the
# uncertainty falls slowly to its smallest value near apolune, where the range is smallest, and then grows with the
# range itself. Both forms of the covariance analysis (square-root information referred to $t_0$, batched; Joseph-form
# EKF recursion) agree, in all three SSAT coordinate systems.
#
# ## 3 · MMD guidance (Eqs. 23-24)
#
# For a burn $\mathbf u$ at $\tau_0$ the linearised change of the measurement at the end of the coast $\tau_f$ is
# $\delta\mathbf y_f = H_f\Phi(\tau_f,\tau_0)B_a\mathbf u$. MMD maximises $\|\delta\mathbf y_f\|^2 =
# \mathbf u^TQ\mathbf u$, $Q = B_a^T\Phi^TH_f^TH_f\Phi B_a$ (Eq. 24), over $\|\mathbf u\| = \upsilon$: the
# eigenvector of the largest eigenvalue. **Deviation from the print:** Eq. 23 reads
# $\mathbf u_y = \pm\upsilon\max(\mathrm{eig}(Q))$, literally a multiple of the largest *eigenvalue* (a scalar); the
# text ("the solution to an eigen-problem", a maneuver) and the Rayleigh quotient both say it is the unit
# *eigenvector* of that eigenvalue, which we implement. In Eq. 24, $H_f$ must be the Jacobian with respect to the
# 12-dimensional inertial SSAT state, $[-H_\theta\ \ H_\theta]$ at $\tau_f$ (Eq. 18 is written for the relative
# state); with $B_a$ only the agent block $-H_\theta$ survives, and the sign drops out of $Q$. $Q$ has rank 2 (two
# angles), so its null direction is the burn that leaves the final line of sight unchanged. The sign is not determined by the eigenproblem; as in the paper we
# run both and keep the smaller $J_\rho$. Beyond the paper, for each coast time we evaluate $J_\rho$ for every
# direction of a Fibonacci sphere (`N_GRID` directions, one batched covariance analysis each), refine the best one
# with Nelder-Mead (the *true minimiser*), and scan the circle perpendicular to the initial line of sight (the
# heuristic of Ref. [8], reported as best / median / worst over the circle, since it is a set, not a policy).

# %% [markdown]
# First, the surrogate itself: for the 12-h coast the eigenvector must be the direction on the sphere that maximises
# $\mathbf u^TQ\mathbf u$ and, for a small burn (where the surrogate is the linearisation), the one that maximises
# the *nonlinear* change of the final angles; both found here by brute force over a dense Fibonacci sphere.

# %%
k_mmd = 12
nom12 = ssat.propagate_with_impulses(em, np.vstack([xa0, xt0]), t[:k_mmd + 1])
_, Ha12, _ = AZIMUTH_ELEVATION.evaluate(nom12.x[0, -1], nom12.x[1, -1])
Q12 = ssat.mmd_matrix(nom12.stm[0, -1], Ha12)
e12 = ssat.mmd_direction(Q12)
D_bf = ssat.fibonacci_sphere(N_GRID)
quad = np.einsum("ni,ij,nj->n", D_bf, Q12, D_bf)
x_bf = np.tile(xa0, (N_GRID, 1))
x_bf[:, 3:6] += 1e-4 / (V * 1e3) * D_bf  # 0.1 mm/s: the linear regime of the surrogate
y_bf = AZIMUTH_ELEVATION(propagate(em, x_bf, t[:k_mmd + 1]).x[:, -1], nom12.x[1, -1])
dev = np.linalg.norm(AZIMUTH_ELEVATION.residual(y_bf, AZIMUTH_ELEVATION(nom12.x[0, -1], nom12.x[1, -1])), axis=-1)
spacing_deg = np.degrees(np.sqrt(4 * np.pi / N_GRID))
ang_quad = np.degrees(np.arccos(min(1.0, abs(D_bf[np.argmax(quad)] @ e12))))
ang_dev = np.degrees(np.arccos(min(1.0, abs(D_bf[np.argmax(dev)] @ e12))))
print(f"eigenvalues of Q: {np.linalg.eigvalsh(Q12)} (rank 2)")
print(f"angle between the MMD eigenvector and the brute-force maximiser of u^T Q u: {ang_quad:.2f} deg, of the "
      f"nonlinear angle change: {ang_dev:.2f} deg (grid spacing {spacing_deg:.1f} deg)")

# %%
coast_idx = [int(round(h)) for h in COAST_HOURS]
results = {}
for dv in DV_M_S:
    results[dv] = ssat.compare_burn_policies(em, xa0, xt0, t, coast_idx, dv * 1e-3 / V, P0, n_grid=N_GRID,
                                             n_perp=N_PERP)
for dv, r in results.items():
    print(f"\nupsilon = {dv} m/s")
    print(" coast h | none   | MMD    | MMD(-) | optimum | median dir | perp best/worst | MMD pct | MMD-opt deg")
    for i, h in enumerate(r.coast_hours):
        print(f" {h:7.0f} | {r.none[i]:6.2f} | {r.mmd[i]:6.2f} | {r.mmd_other[i]:6.2f} | {r.optimum[i]:7.2f} | "
              f"{r.grid_median[i]:10.2f} | {r.perp_best[i]:6.2f}/{r.perp_worst[i]:6.2f}  | {r.mmd_percentile[i]:6.1f}% | "
              f"{r.angle_mmd_optimum_deg[i]:6.1f}")

# %% [markdown]
# The figure draws every policy as the change of $\sqrt{J_\rho(\tau_f)}$ against doing nothing (percent; the dashed
# zero line is "no burn", the absolute values are in the tables above), each burn size on its own scale.

# %%
fig, axes = plt.subplots(1, len(DV_M_S), figsize=(12, 4.8), sharey=False)
for ax, (dv, r) in zip(np.atleast_1d(axes), results.items()):
    h = r.coast_hours
    rel = lambda v: 100 * (v / r.none - 1)  # noqa: E731 (percent change of sqrt(J_rho) against no burn)
    ax.fill_between(h, rel(r.perp_best), rel(r.perp_worst), color="tab:green", alpha=0.2, lw=0,
                    label="perpendicular to LOS (range over the circle)")
    ax.axhline(0, color="k", ls="--", lw=1.2, label="no burn")
    ax.plot(h, rel(r.grid_median), color="0.5", label="median random direction")
    ax.plot(h, rel(r.mmd), "o-", color="magenta", label="MMD (selected sign)")
    ax.plot(h, rel(r.mmd_other), "x:", color="magenta", label="MMD (rejected sign)")
    ax.plot(h, rel(r.optimum), "s-", color="tab:blue", ms=4, label="true minimiser")
    ax.set_xscale("log")
    ax.set_xticks(h, [f"{x:g}" for x in h])
    ax.minorticks_off()
    ax.set_xlabel("coast time $\\tau_f-\\tau_0$ (h)")
    ax.set_ylabel(r"$\sqrt{J_\rho(\tau_f)}$ relative to no burn [%]")
    ax.set_title(f"burn magnitude {dv} m/s")
handles, labels = np.atleast_1d(axes)[0].get_legend_handles_labels()
fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, bbox_to_anchor=(0.5, 0.0))
fig.tight_layout(rect=(0, 0.12, 1, 1))
_ = plotting.save_figure(fig, "07_mmd_vs_optimum", output_dir=out)

# %% [markdown]
# ### The cost over the sphere of burn directions
#
# One coast time (12 h) and the larger burn: each dot is a burn direction (rotating-frame azimuth and elevation of
# $\mathbf u$), coloured by $\sqrt{J_\rho}$. The MMD axis ($\pm$), the true minimiser, the line of sight at the burn
# (both senses, as rings) and the great circle perpendicular to it are marked. For this coast the minimiser sits
# next to the line of sight, far from the perpendicular circle (the angle is printed below the map).

# %%
k12 = int(round(12))
dv_map = DV_M_S[-1]
D = ssat.fibonacci_sphere(N_GRID)
grid12 = ssat.range_sigma_over_directions(em, xa0, None, t[:k12 + 1], dv_map * 1e-3 / V, D, P0,
                                          target=ssat.ImpulsiveTrajectory(t[:k12 + 1], tgt.x[:, :k12 + 1],
                                                                          tgt.stm[:, :k12 + 1]))
r12 = results[dv_map]
i12 = list(r12.coast_hours).index(12.0) if 12.0 in list(r12.coast_hours) else int(np.argmin(abs(r12.coast_hours - 12)))


def azel_deg(v):
    v = np.atleast_2d(v)
    return np.degrees(np.arctan2(v[:, 1], v[:, 0])), np.degrees(np.arcsin(np.clip(v[:, 2], -1, 1)))


fig, ax = plt.subplots(figsize=(9, 4.5))
az, el = azel_deg(D)
sc = ax.scatter(az, el, c=grid12.range_sigma_km[:, -1], s=8, cmap="viridis")
fig.colorbar(sc, ax=ax, label=r"$\sqrt{J_\rho}$ after 12 h (km)")
los0 = (xt0[:3] - xa0[:3]) / np.linalg.norm(xt0[:3] - xa0[:3])
pc = ssat.perpendicular_directions(los0, 361)
paz, pel = azel_deg(pc)
order = np.argsort(paz)
ax.plot(paz[order], pel[order], "-", color="k", lw=1.2, label="perpendicular to the LOS")
for sgn, mk in ((1, "^"), (-1, "v")):
    a, e = azel_deg(sgn * r12.mmd_direction[i12])
    ax.plot(a, e, mk, color="magenta", ms=11, mec="k", label="MMD axis" if sgn == 1 else None)
for sgn, lab in ((1, "line of sight (towards the target)"), (-1, "away from the target")):
    a, e = azel_deg(sgn * los0)  # drawn as rings, so that a minimiser next to them stays visible
    ax.plot(a, e, "o", mfc="none", mec="cyan" if sgn == 1 else "k", mew=2, ms=18, label=lab)
a, e = azel_deg(r12.optimum_direction[i12])
ax.plot(a, e, "*", color="tab:red", ms=13, mec="k", label="true minimiser")
los_angle12 = 90.0 - r12.optimum_perp_angle_deg[i12]
towards12 = float(r12.optimum_direction[i12] @ los0) > 0
print(f"12-h coast, {dv_map} m/s: the true minimiser is {los_angle12:.1f} deg from the line of sight at the burn, "
      f"{'towards' if towards12 else 'away from'} the target ({r12.optimum_perp_angle_deg[i12]:.1f} deg out of the "
      f"perpendicular plane)")
ax.set_title(f"12-h coast, {dv_map} m/s: the true minimiser lies {los_angle12:.0f} deg from the line of sight")
ax.set_xlabel("burn azimuth in the rotating frame (deg)")
ax.set_ylabel("burn elevation (deg)")
ax.set_xlim(-180, 180)
ax.set_ylim(-90, 90)
ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=3, fontsize=8, markerscale=0.6, labelspacing=1.0)
fig.tight_layout()
_ = plotting.save_figure(fig, "07_cost_over_burn_directions", output_dir=out)

# %% [markdown]
# ## 4 · How near-optimal is MMD?
#
# Three numbers per coast time: MMD's excess over the true minimiser (percent of $\sqrt{J_\rho}$), the fraction of
# the achievable improvement over a random direction that MMD captures, and the percentile of MMD among all
# directions of the sphere (0 % would mean no direction is better).

# %%
for dv, r in results.items():
    print(f"upsilon = {dv} m/s: MMD excess over optimum {np.round(r.mmd_excess_percent, 1)} %")
    print(f"   fraction of the possible gain captured {np.round(r.mmd_gain_fraction, 2)}")
    print(f"   directions better than MMD {np.round(r.mmd_percentile, 1)} %")
    print(f"   angle between optimum and the perpendicular plane {np.round(r.optimum_perp_angle_deg, 1)} deg")
    print(f"   angle between optimum and the line of sight (either sense) "
          f"{np.round(90 - r.optimum_perp_angle_deg, 1)} deg")
    print(f"   perpendicular-circle best vs optimum: {np.round(100 * (r.perp_best / r.optimum - 1), 1)} %")
    print(f"   sign choice matters: rejected sign worse by {np.round(100 * (r.mmd_other / r.mmd - 1), 1)} %")
sign_pct = {dv: 100 * (r.mmd_other / r.mmd - 1) for dv, r in results.items()}
ang_mo = {dv: r.angle_mmd_optimum_deg for dv, r in results.items()}
for dv in DV_M_S:
    print(f"upsilon = {dv} m/s: rejected sign worse by {sign_pct[dv].min():.1f}-{sign_pct[dv].max():.1f} %; "
          f"MMD axis to true minimiser {ang_mo[dv].min():.1f}-{ang_mo[dv].max():.1f} deg")

# %% [markdown]
# **Reading.** The sign choice of the quick covariance analysis matters for the larger burn: at 1 m/s the rejected
# sign of the MMD axis is worse by up to a few tens of percent in $\sqrt{J_\rho}$, at 0.1 m/s by a few percent at
# most (ranges printed above). Only for the shortest coast (1 h) does the best burn lie in the plane
# perpendicular to the line of sight, as Ref. [8] states, with the best direction on that circle equal to the
# optimum. The optimum leaves the plane quickly: for coasts of a few hours it is tens of degrees out of it, and for
# the 12-h coast of the map above it points within a few degrees of the line of sight itself (towards the target),
# the opposite of the heuristic; only for the longest coasts does it return towards the plane (angles printed
# above). With the smaller burn the best direction on the circle stays within a few percent of the optimum for
# longer, but only because every direction, doing nothing included, does: at 0.1 m/s the cost hardly depends on
# the burn. The circle also contains the worst directions, so even where it holds the heuristic is a *set* that
# contains the answer, not a policy.
# MMD is a policy, but with the burn at the first epoch (where $P_0$ applies) it is clearly suboptimal: it captures only part of the achievable range
# information and a sizeable fraction of random directions beat it (numbers above). The surrogate maximises the
# size of the measurement change at $\tau_f$ alone, whereas $J_\rho$ integrates all measurements of the coast and
# projects on the final line of sight. The two do not agree in direction: at both burn sizes the MMD axis is
# between 68 and 90 deg from the true minimiser (printed above), nearly orthogonal to it. This is the honest form of the
# paper's "nearly optimal" (stated there for its Ref. [8] scenarios, which are not given).

# %% [markdown]
# ### Computation time
#
# The paper (Sec. 4.1) says the loss of optimality "comes with exponentially faster computation time". It gives no
# number; we measure the two on this machine for the 12-h coast and the 1 m/s burn, in the same run. MMD proper is
# Eq. 24 and one 3x3 eigenproblem, given the nominal STM and the final measurement Jacobian (timed as the best of
# many repetitions, since it takes microseconds); the full MMD policy adds the propagation of the nominal pair with
# its STM and the two-run covariance analysis that picks the sign. The true minimiser of section 3 is the
# `N_GRID`-direction sphere (one batched propagation and covariance analysis) followed by Nelder-Mead, one covariance
# analysis per cost evaluation (`ssat.minimize_range_sigma`).

# %%
import time


def best_time(fn, repeat):
    """Smallest wall-clock time (s) of ``repeat`` calls of ``fn`` (and the last result)."""
    best, res = np.inf, None
    for _ in range(repeat):
        t_start = time.perf_counter()
        res = fn()
        best = min(best, time.perf_counter() - t_start)
    return best, res


t12 = t[:k12 + 1]
dv12 = dv_map * 1e-3 / V
t_mmd_core, e_timed = best_time(lambda: ssat.mmd_direction(ssat.mmd_matrix(nom12.stm[0, -1], Ha12)), 200)
t_mmd_policy, _ = best_time(lambda: ssat.mmd_policy(em, xa0, xt0, t12, dv12, P0), 3)
t_opt, (d_timed, J_timed) = best_time(lambda: ssat.minimize_range_sigma(em, xa0, xt0, t12, dv12, P0, n_grid=N_GRID),
                                      1 if not QUICK else 2)
ratio_core, ratio_policy = t_opt / t_mmd_core, t_opt / t_mmd_policy
print(f"MMD, Eq. 24 + eigenvector: {t_mmd_core * 1e6:.1f} us (best of 200); full MMD policy with propagation and "
      f"sign check: {t_mmd_policy * 1e3:.1f} ms (best of 3)")
print(f"true minimiser ({N_GRID}-direction sphere + Nelder-Mead): {t_opt:.2f} s; its sqrt(J_rho) "
      f"{np.sqrt(J_timed) * L:.2f} km (section 3: {r12.optimum[i12]:.2f} km)")
print(f"ratio minimiser / MMD: {ratio_core:.1e} (Eq. 24 + eigenvector), {ratio_policy:.0f} (full MMD policy)")

# %% [markdown]
# MMD's linear algebra is several thousand times faster than the search, and the full policy, propagation and sign
# check included, still over a hundred times (ratios printed above; the timings depend on the machine). Both
# answers are fast here, because the search is one batched covariance analysis of all `N_GRID` directions plus a
# short Nelder-Mead refinement. "Exponentially" is not something a single problem size can show, and nothing in this
# problem grows exponentially with its size; the measured claim is the ratio.

# %% [markdown]
# ### A burn in the middle of a tracking arc
#
# So far the burn happens at the first epoch of the covariance analysis, where $P_0$ applies. In a linear covariance
# analysis a burn at that instant only moves the initial state: its information comes from the changed geometry
# alone. A burn *during* tracking adds a kink that angles-only measurements before and after it can see, and that
# kink breaks the scaling symmetry that makes range unobservable. The paper does not say which case its Ref. [8]
# comparison uses, so we repeat the 1 m/s comparison with `PRE_ARC_H` = 24 h of tracking before the burn ($P_0$ at
# the start of the arc).

# %%
PRE_ARC_H = 24
xa_pre = propagate(em, xa0, np.array([0.0, -PRE_ARC_H * HR])).x[-1]
xt_pre = propagate(em, xt0, np.array([0.0, -PRE_ARC_H * HR])).x[-1]
t_pre = np.arange(0, PRE_ARC_H + int(max(COAST_HOURS)) + 1) * HR
res_pre = ssat.compare_burn_policies(em, xa_pre, xt_pre, t_pre, [PRE_ARC_H + k for k in coast_idx],
                                     DV_M_S[-1] * 1e-3 / V, P0, burn_index=PRE_ARC_H, n_grid=N_GRID, n_perp=N_PERP)
print(f"burn of {DV_M_S[-1]} m/s after {PRE_ARC_H} h of tracking")
print(" coast h | none   | MMD    | optimum | median dir | perp best/worst | MMD pct | MMD excess")
for i, h in enumerate(res_pre.coast_hours):
    print(f" {h:7.0f} | {res_pre.none[i]:6.2f} | {res_pre.mmd[i]:6.2f} | {res_pre.optimum[i]:7.3f} | "
          f"{res_pre.grid_median[i]:10.3f} | {res_pre.perp_best[i]:6.3f}/{res_pre.perp_worst[i]:6.2f} | "
          f"{res_pre.mmd_percentile[i]:6.1f}% | {res_pre.mmd_excess_percent[i]:6.0f} %")

# %% [markdown]
# **Reading.** With a tracking arc before it, the same burn is worth far more (compare "none" with any burn: the
# kink, not the geometry, carries the information), and for coasts of up to about half a day MMD is then essentially
# the optimal direction, as the paper states; for longer coasts its excess grows again.
#
# The 24-h arc is our choice (the paper does not say how long the agent has tracked before the burn), so we sweep
# it: for each arc length, the longest coast up to which MMD stays within 5 % of the optimum for every coast, and
# the worst excess beyond it.

# %%
PRE_ARC_SWEEP_H = (6, 12, 24, 48)
pre_sweep = {}
for h_pre in PRE_ARC_SWEEP_H:
    if h_pre == PRE_ARC_H:
        pre_sweep[h_pre] = res_pre
        continue
    xa_p = propagate(em, xa0, np.array([0.0, -h_pre * HR])).x[-1]
    xt_p = propagate(em, xt0, np.array([0.0, -h_pre * HR])).x[-1]
    t_p = np.arange(0, h_pre + int(max(COAST_HOURS)) + 1) * HR
    pre_sweep[h_pre] = ssat.compare_burn_policies(em, xa_p, xt_p, t_p, [h_pre + k for k in coast_idx],
                                                  DV_M_S[-1] * 1e-3 / V, P0, burn_index=h_pre, n_grid=N_GRID,
                                                  n_perp=N_PERP)
sweep_ok_h = {}
for h_pre, r in pre_sweep.items():
    ok = r.mmd_excess_percent <= 5.0
    n = ok.size if ok.all() else int(np.argmin(ok))
    sweep_ok_h[h_pre] = r.coast_hours[n - 1] if n else 0.0
    beyond = r.mmd_excess_percent[n:]
    print(f"tracking arc {h_pre:3d} h before the burn: MMD excess {np.round(r.mmd_excess_percent, 0)} %; within 5 % "
          f"for every coast <= {sweep_ok_h[h_pre]:.0f} h"
          + (f", worst beyond {beyond.max():.0f} %" if beyond.size else ""))

# %% [markdown]
# The setting in which "nearly optimal" holds is therefore: a burn during tracking and a short coast (up to about
# half a day for every arc length swept, printed above).
#
# ### Does the verdict depend on the demonstration pair?
#
# The pair above is one choice among many. As a second, independent geometry we put the agent on the quasi-periodic
# torus of notebook 08 (the member about the 9:2 NRHO whose mean range to the target is 215 km, :mod:`cislunar.cr3bp.torus`)
# at four initial ring angles, burn 1 day before apolune, and repeat the comparison with the 1 m/s burn. The torus
# relative motion is not along-track: the line of sight sweeps around the target. The ring angles are 0, 45, 90 and
# 135 deg, not spread over the full circle: a ring angle 180 deg away puts the agent at nearly the mirrored relative
# position, which angles-only tracking sees almost identically (both checked below for 0 vs 180 deg), so antipodal
# angles would not be independent cases.

# %%
from cislunar.cr3bp.torus import qpo_for_mean_range

qpo, _ = qpo_for_mean_range(nrho, 215.0)


def qpo_comparison(ring_angle):
    xa_q = qpo.states([ring_angle], [-t_lead])[0, 0]
    return ssat.compare_burn_policies(em, xa_q, xt0, t, coast_idx, DV_M_S[-1] * 1e-3 / V, P0, n_grid=N_GRID,
                                      n_perp=N_PERP)


def pct0(a):
    """An array printed as whole numbers (no scientific notation)."""
    return np.array2string(np.round(a), formatter={"float_kind": lambda v: f"{v:.0f}"}, max_line_width=200)


RING_ANGLES_DEG = (0.0, 45.0, 90.0, 135.0)
pairs = {np.radians(a): qpo_comparison(np.radians(a)) for a in RING_ANGLES_DEG}
print(f"agent on the 215-km QPO, burn {DV_M_S[-1]} m/s, coast times {COAST_HOURS} h")
for ang, r in pairs.items():
    print(f"ring angle {np.degrees(ang):5.0f} deg: MMD excess {pct0(r.mmd_excess_percent)} %;"
          f" directions better than MMD {pct0(r.mmd_percentile)} %")
anti = qpo_comparison(np.pi)  # the antipode of ring angle 0
d_q0, d_q180 = (qpo.states([a_], [-t_lead])[0, 0, :3] - xt0[:3] for a_ in (0.0, np.pi))
print(f"relative position at the burn, ring angle 0 deg: {np.round(d_q0 * L, 1)} km, 180 deg: "
      f"{np.round(d_q180 * L, 1)} km (|sum| / |d| = {np.linalg.norm(d_q0 + d_q180) / np.linalg.norm(d_q0):.3f})")
r_q0 = pairs[0.0]
anti_opt = np.max(np.abs(anti.optimum / r_q0.optimum - 1)) * 100
anti_pct = np.max(np.abs(anti.mmd_percentile - r_q0.mmd_percentile))
anti_mmd = np.max(np.abs(anti.mmd / r_q0.mmd - 1)) * 100
print(f"antipodal check, ring angle 180 vs 0 deg, over all coasts: sqrt(J_rho) of the optimum differs by at most "
      f"{anti_opt:.1f} %, of MMD by at most {anti_mmd:.1f} %; MMD percentile by at most {anti_pct:.1f} points")
pct_all = np.concatenate([r.mmd_percentile for r in pairs.values()])
exc_all = np.concatenate([r.mmd_excess_percent for r in pairs.values()])
print(f"over all QPO pairs and coasts: median percentile {np.median(pct_all):.0f} %, median excess "
      f"{np.median(exc_all):.0f} %, MMD in the best 10 % of directions in {np.mean(pct_all < 10) * 100:.0f} % of cases")

# %% [markdown]
# **Reading.** The verdict is geometry- and horizon-dependent: for some torus pairs MMD is essentially optimal for
# coasts of a few hours (within 2 % up to 4 h at ring angle 0 deg), for others it is 9 % off already at 1 h; in every
# pair its excess over the optimum grows with the coast time, to hundreds of percent or more for coasts beyond a day
# (at every step of the coast time except 36 to 48 h at 90 deg, printed above), because the
# surrogate looks at the measurement change at $\tau_f$ only while $J_\rho$ accumulates all measurements of the
# coast. "Nearly optimal" holds for short coasts in favourable geometries, not in general.

# %%
within = res_pre.mmd_excess_percent <= 5.0
n_ok = within.size if within.all() else int(np.argmin(within))  # leading run of coasts within the tolerance
ok_coast = res_pre.coast_hours[n_ok - 1] if n_ok else 0.0
near = np.concatenate([r.mmd_excess_percent for r in pairs.values()]) <= 5.0
coast_all = np.concatenate([r.coast_hours for r in pairs.values()])
r1 = results[DV_M_S[-1]]
r0 = results[DV_M_S[0]]
short = 0


def leading_hours(r, ok):
    """Longest coast (h) up to which ``ok`` holds for every coast (0 if not even the first)."""
    n = ok.size if ok.all() else int(np.argmin(ok))
    return r.coast_hours[n - 1] if n else 0.0


perp_ok_h = {dv: leading_hours(r, r.perp_best <= 1.02 * r.optimum) for dv, r in results.items()}
table.add_typed("Eq. 7: T P T^T and its inverse (identity)", "exact", f"{err_cov:.1e} rel. error", "derived")
table.add_typed("agent-based absolute state equivalent (same relative block, same J_rho)", "stated, not shown",
          f"{same_rel_block:.1e} / {np.ptp(J3) / np.mean(J3):.1e}", "derived",
          "angles depend on s_rho only: Jacobian [0 H_rho] in both relative systems (tested)")
table.add_typed("initial 1-sigma range uncertainty from 3-sigma 60 km per axis, both vehicles", "-",
          f"{base.range_sigma_km[0, 0]:.2f} km", "derived", "sqrt(2) x 20 km")
table.add_typed("covariance analysis: SRI batch form vs EKF recursion", "-",
          f"{np.max(np.abs(ssat.ssat_covariance_ekf(em, agt, tgt, P0)[1] / base.J_rho[0] - 1)):.1e} rel.",
          "beyond paper", "two independent implementations agree")
table.add_typed("sqrt(J_rho) without maneuver after 24 h / 72 h (demonstration pair)", "-",
          f"{base.range_sigma_km[0, 24]:.1f} / {base.range_sigma_km[0, -1]:.1f} km", "not in paper",
          "the paper's MMD scenario (its Ref. [8]) is not given; our pair: same 9:2 NRHO, 215 km at apolune")
table.add_typed("MMD (Eq. 23 read as the eigenvector) = brute-force maximiser of its surrogate",
          "u_y = +/- upsilon max(eig(Q)) (Eq. 23)",
          f"{ang_quad:.2f} deg (u^T Q u) / {ang_dev:.2f} deg (nonlinear angle change)", "derived",
          f"12-h coast, {N_GRID}-direction sphere (spacing {spacing_deg:.1f} deg); Eq. 23 as printed is the eigenvalue "
          "(a scalar); the text ('solution to an eigen-problem') means the unit eigenvector of that eigenvalue")
in_plane_h = r1.coast_hours[r1.optimum_perp_angle_deg <= 5.0]
off_plane_small = np.max(r0.optimum_perp_angle_deg[r0.coast_hours <= perp_ok_h[DV_M_S[0]]])
table.add_typed("Ref. [8]: perpendicular-to-LOS set contains the optimum (tested at the shortest coast)",
          "stated", f"best on circle {r1.perp_best[short]:.2f} vs optimum {r1.optimum[short]:.2f} km "
          f"({r1.coast_hours[short]:.0f} h, {DV_M_S[-1]} m/s)",
          "reproduced" if r1.perp_best[short] <= 1.02 * r1.optimum[short] else "differs: see note",
          "tolerance fixed before comparing: within 2 %; optimum off the perpendicular plane by "
          f"{r1.optimum_perp_angle_deg[short]:.1f} deg. Holds only for the shortest coast: tolerance met for coasts "
          f"<= {perp_ok_h[DV_M_S[-1]]:.0f} h ({DV_M_S[-1]} m/s); optimum within 5 deg of the plane at "
          f"{', '.join(f'{x:g}' for x in in_plane_h)} h only, and at 12 h {los_angle12:.0f} deg from the line of "
          f"sight ({'towards' if towards12 else 'away from'} the target). At {DV_M_S[0]} m/s the 2 % is met up to "
          f"{perp_ok_h[DV_M_S[0]]:.0f} h with the optimum up to {off_plane_small:.0f} "
          "deg out of the plane: the cost hardly depends on a burn that small")
table.add_typed("MMD near-optimal, burn at the start of tracking (first pair; excess over the true minimiser)",
          "'nearly optimal'",
          f"{r1.mmd_excess_percent.min():.0f}-{r1.mmd_excess_percent.max():.0f} % ({DV_M_S[-1]} m/s); "
          f"{r0.mmd_excess_percent.min():.0f}-{r0.mmd_excess_percent.max():.0f} % ({DV_M_S[0]} m/s)",
          "differs: see note" if r1.mmd_excess_percent.max() > 5 else "reproduced",
          f"directions better than MMD: {r1.mmd_percentile.min():.0f}-{r1.mmd_percentile.max():.0f} %; gain captured "
          f"{r1.mmd_gain_fraction.min() + 0.0:.2f} to {r1.mmd_gain_fraction.max() + 0.0:.2f}; paper's claim rests on Ref. [8] "
          "scenarios not given here. Tolerance fixed before comparing: within 5 % of the optimum. At "
          f"{DV_M_S[0]} m/s the 5 % is met but is no test: doing nothing is itself within "
          f"{np.max(100 * (r0.none / r0.optimum - 1)):.0f} % of the optimum and MMD captures only "
          f"{r0.mmd_gain_fraction.min() + 0.0:.2f}-{r0.mmd_gain_fraction.max() + 0.0:.2f} of the possible gain")
table.add_typed(f"MMD near-optimal, burn at the start of tracking, agent on the 215-km QPO ({len(pairs)} ring angles "
          f"{', '.join(f'{a:g}' for a in RING_ANGLES_DEG)} deg, {DV_M_S[-1]} m/s)",
          "'nearly optimal'",
          f"median excess {np.median(exc_all):.0f} %, median percentile {np.median(pct_all):.0f} %",
          "differs: see note" if np.median(exc_all) > 5 else "beyond paper",
          f"MMD in the best 10 % of burn directions in {np.mean(pct_all < 10) * 100:.0f} % of the "
          f"{pct_all.size} (pair, coast) cases ({len(pairs)} ring angles x {len(coast_idx)} coasts); within 5 % of "
          f"the optimum (tolerance) in {near.sum()} cases, all with coasts <= "
          f"{coast_all[near].max() if near.any() else 0:.0f} h. Antipodal ring angles are not independent cases: "
          f"180 deg gives the sqrt(J_rho) of 0 deg within {anti_opt:.1f} % (optimum) and {anti_mmd:.1f} % (MMD)")
# the mid-arc burn: the coasts within the 5 % tolerance (leading run) and the rest, each with its own status
pre_exc, pre_pct, pre_h = res_pre.mmd_excess_percent, res_pre.mmd_percentile, res_pre.coast_hours
pre_label = f"MMD near-optimal, burn after {PRE_ARC_H} h of tracking (first pair, {DV_M_S[-1]} m/s)"
tuned_why = (f"tolerance fixed before comparing: within 5 % of the optimum; nothing in the computation was fitted, "
             f"but the setting was: the mid-arc burn ({PRE_ARC_H} h of tracking before it) was adopted after the "
             f"start-of-tracking comparison missed the paper's 'nearly optimal', a choice made while looking at the "
             f"paper's claim, hence not 'reproduced'")
if n_ok:
    table.add_typed(f"{pre_label}, coasts <= {ok_coast:.0f} h", "'nearly optimal'",
              f"excess {pre_exc[:n_ok].min():.0f}-{pre_exc[:n_ok].max():.0f} %, percentile "
              f"{pre_pct[:n_ok].min():.1f}-{pre_pct[:n_ok].max():.1f} %", "consistent (tuned)",
              f"{tuned_why}. Not specific to the 24-h arc: with {', '.join(f'{h:g}' for h in PRE_ARC_SWEEP_H)} h of "
              f"tracking before the burn the 5 % holds for every coast <= {min(sweep_ok_h.values()):.0f} h. A mid-arc "
              f"burn cuts sqrt(J_rho) from {res_pre.none[n_ok - 1]:.1f} km (no burn) to "
              f"{res_pre.optimum[n_ok - 1]:.3f} km (best) after {ok_coast:.0f} h")
if n_ok < pre_h.size:
    rest = slice(n_ok, None)
    bad = pre_exc[rest] > 5.0
    table.add_typed(f"{pre_label}, coasts {pre_h[rest][0]:.0f}-{pre_h[rest][-1]:.0f} h", "'nearly optimal'",
              f"excess {pre_exc[rest].min():.0f}-{pre_exc[rest].max():.0f} %, percentile "
              f"{pre_pct[rest].min():.1f}-{pre_pct[rest].max():.1f} %",
              (f"differs: excess {pre_exc[rest][bad].min():.0f}-{pre_exc[rest][bad].max():.0f} %" if bad.any()
               else "consistent (tuned)"),
              "tolerance 5 % (as above) exceeded at "
              f"{', '.join(f'{h:g}' for h in pre_h[rest][bad])} h: MMD maximises the measurement change at tau_f "
              "only, while J_rho accumulates every measurement of the coast; the paper's Ref. [8] scenarios (burn "
              "timing, coast, geometry) are not given, the sweep here covers coast time, burn timing (start of "
              "tracking, previous rows; tracking arc before the burn "
              f"{', '.join(f'{h:g}' for h in PRE_ARC_SWEEP_H)} h: every arc length fails beyond "
              f"{max(sweep_ok_h.values()):.0f} h, worst excess "
              f"{min(r.mmd_excess_percent.max() for r in pre_sweep.values()):.0f}-"
              f"{max(r.mmd_excess_percent.max() for r in pre_sweep.values()):.0f} %) and geometry (QPO row)")
table.add_typed("+/- sign choice by quick covariance analysis", "needed",
          "; ".join(f"rejected sign worse by {sign_pct[dv].min():.1f}-{sign_pct[dv].max():.1f} % ({dv} m/s)"
                    for dv in DV_M_S[::-1]), "beyond paper", "first pair, burn at the start of tracking, all coasts")
table.add_typed("computation time: true minimiser / MMD (Sec. 4.1: 'exponentially faster')", "no number",
          f"{ratio_core:.1e} (Eq. 24 + eigenvector), {ratio_policy:.0f} (full MMD policy)", "beyond paper",
          f"12-h coast, {DV_M_S[-1]} m/s, this machine: {t_opt:.2f} s ({N_GRID}-direction sphere + Nelder-Mead) vs "
          f"{t_mmd_core * 1e6:.0f} us (best of 200) / {t_mmd_policy * 1e3:.1f} ms with propagation and sign check "
          "(best of 3); a timing ratio, not a test of 'exponentially'")
table.display()
