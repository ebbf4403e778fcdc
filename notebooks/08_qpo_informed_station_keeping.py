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
# # 08 · Informed station keeping on a quasi-periodic orbit about the 9:2 NRHO
#
# **What you will learn.** How a quasi-periodic torus about the Gateway's 9:2 NRHO turns "station keeping" from a
# single target point into a two-parameter *set* of acceptable states; how every point of that set is reached with
# a two-burn transfer (position, then velocity); how Greaves & Scheeres pick, among all those maneuvers, the one most
# aligned with the MMD information-gathering direction (the *informed* maneuver $\mathbf u^*$, Eq. 25); and whether
# that choice really lands in the valley of range uncertainty and avoids the largest fuel costs, checked with numbers
# over the full surface of maneuvers, each with its own covariance analysis. Eq. 25 as printed needs a reading: read
# as an angle, its answer depends on how finely the set is sampled; read as a projection, it does not, and it finds
# the paper's valley at the price of fuel (section 5b). Beyond the paper (its own future work),
# a full-filter Monte Carlo with maneuver execution errors tells us how much of the predicted range information
# survives.
#
# **Paper sections followed.** Greaves & Scheeres (AMOS 2023), Secs. 4 (informed station keeping, Eq. 25,
# Figs. 2-3) and 5 (simulation and results, Figs. 4-5). SSAT, $J_\rho$ and MMD are built in notebook 07; the
# invariant-torus solver is :mod:`cislunar.cr3bp.torus`.

# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
# Sizes derived from QUICK: a coarser surface, fewer sweep points and fewer Monte Carlo trials in quick mode.
N_SURF = 14 if QUICK else 40  # ring angles x arrival times of the station-keeping surface (paper: not given)
N_SWEEP = 10 if QUICK else 16  # arrival times in the sweep over the unstated scenario inputs (ring angles: N_SURF)
N_GRID = (10, 20, 40) if QUICK else (16, 40, 80, 160, 320, 640)  # ring angles in the resolution study (5b)
N_GRID_SLICES = 3 if QUICK else 5  # arrival times in the resolution study
N_TRIALS = 6 if QUICK else 40  # Monte Carlo trials per policy and execution-error level
N_WORKERS = 1 if QUICK else 2  # process pool for the Monte Carlo (1 = serial)
# Scenario choices the paper leaves open (stated, then swept in section 6):
T_BURN_H = -24.0  # first burn, hours from the target's apoapsis
T_ARRIVAL_H = (-12.0, 12.0)  # window of arrival times (second burn), hours from apoapsis
T_FINAL_H = 24.0  # end of the covariance analysis, where sqrt(J_rho) is read, hours from apoapsis
AGENT_THETA = 0.0  # the agent starts on the torus trajectory of this ring angle (rad)
PRE_ARC_H = 24.0  # alternative reading: tracking starts this long before the first burn (baseline: at the burn)
EXEC_ABS_M_S, EXEC_REL = 1e-3, 0.01  # execution errors (1 sigma per axis): 1 mm/s plus 1 % of the burn

import time
from concurrent.futures import ProcessPoolExecutor

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.patches import Rectangle
from matplotlib.ticker import NullFormatter, ScalarFormatter

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.propagation import propagate
from cislunar.cr3bp.torus import qpo_for_mean_range
from cislunar.guidance import ssat
from cislunar.papers.greaves_scheeres_2023 import station_keeping as sk
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.utils.montecarlo import run_monte_carlo

plotting.use_style()
out = OUTPUT_DIR or None
table = ComparisonTable("08 QPO and informed station keeping (Greaves & Scheeres AMOS 2023, Secs. 4-5)")
L, V = em.length_unit_km, em.velocity_unit_km_s
HR = 3600.0 / em.time_unit_s
t_start = time.perf_counter()

# %% [markdown]
# ## 1 · The QPO about the 9:2 NRHO and the 215 km member
#
# The target flies the 9:2 southern L2 NRHO; the agent flies a quasi-periodic orbit about it "with the same base
# frequency" (Sec. 4). We compute 2-D invariant tori by the invariant-circle method (:mod:`cislunar.cr3bp.torus`): the
# ring $u(\theta)$ at the NRHO's apolune is mapped onto itself by the flow over one NRHO period $T$, rotated by the
# rotation number $\rho$, $\varphi_T(u(\theta)) = u(\theta+\rho)$; the stroboscopic time is fixed to $T$, which is
# what "same base frequency" means. The paper gives one number for its member: "the average range between the
# natural trajectories of the two spacecraft is 215 km".
#
# **Definition of the mean range (our reading).** Target on the NRHO from apolune, agent on the torus trajectory
# through ring angle $\theta_0$ at the same epoch; the range averaged uniformly over all $\theta_0\in[0,2\pi)$ and
# over one period $[0, T)$. For an irrational $\rho/2\pi$ this is the long-time average along any single agent
# trajectory. We **select** the family member whose mean range is 215 km: the number is an *input* here, not a
# prediction, and cannot be "reproduced".

# %%
nrho = nrho_9_2(em)
torus, stats = qpo_for_mean_range(nrho, 215.0)
ring_alt = {name: getattr(stats, name) for name in ("mean_km", "ring_mean_km", "rms_km")}
print(f"9:2 NRHO: period {nrho.period_days:.4f} d, apolune radius {nrho.apolune_radius_km:.0f} km")
print(f"QPO member: ring size (RMS about its centre) {torus.size_km:.2f} km and {torus.velocity_size_mps:.3f} m/s; "
      f"largest offset from the NRHO apolune state {torus.max_offset_km:.1f} km, {torus.max_velocity_offset_mps:.2f} m/s")
print(f"rotation number rho = {torus.rho:.6f} rad per period ({np.degrees(torus.rho):.3f} deg; "
      f"rho/2pi = {torus.rho / (2 * np.pi):.6f}); Jacobi constant {torus.jacobi:.10f} (NRHO {nrho.jacobi:.10f})")
print(f"invariance error at the circle midpoints {torus.invariance_error():.2e} (non-dimensional)")
print(f"agent-target range: mean {stats.mean_km:.2f} km, min {stats.min_km:.2f} km, max {stats.max_km:.2f} km; "
      f"mean over the apolune ring only {stats.ring_mean_km:.2f} km, RMS {stats.rms_km:.2f} km")

# %% [markdown]
# ## 2 · Fig. 2: the torus surface and the NRHO near apoapsis
#
# Left: the QPO's surface about apoapsis (the paper's Fig. 2 gives no time span; we draw $\pm$1.5 days), with the
# target's NRHO arc in black and the initial ring at apoapsis in red; Moon-centred rotating frame, units of 1000 km.
# At this scale the ring (a few hundred km across) is a thin tube around the 70 000 km NRHO, so the right panel
# shows what the agent actually sees: the ring *relative to the target* at five times from apoapsis, in km with
# equal axis scales (rotating-frame axes, origin at the target).

# %%
th_plot = np.linspace(0, 2 * np.pi, 49)
fig = plt.figure(figsize=(13, 6))
t_plot = np.linspace(-36.0, 36.0, 61) * HR
surf = em.moon_centred(torus.states(th_plot[:-1], t_plot)) * L / 1e3
surf = np.concatenate([surf, surf[:1]], axis=0)
fwd = em.moon_centred(propagate(em, nrho.x0, t_plot[t_plot >= 0]).x) * L / 1e3
back = em.moon_centred(propagate(em, nrho.x0, -t_plot[t_plot >= 0]).x) * L / 1e3
ax = fig.add_subplot(1, 2, 1, projection="3d")
ax.plot_surface(surf[..., 0], surf[..., 1], surf[..., 2], color="tab:red", alpha=0.3, lw=0, shade=True)
ring0 = em.moon_centred(torus.ring(0.0, 97)) * L / 1e3
ax.plot(ring0[:, 0], ring0[:, 1], ring0[:, 2], color="tab:red", lw=2, label="initial ring (apoapsis)")
for arc in (fwd, back):
    ax.plot(arc[:, 0], arc[:, 1], arc[:, 2], color="k", lw=2)
ax.plot([], [], color="k", label="target: 9:2 NRHO")
ax.set_xlabel("x (1000 km)", labelpad=8)
ax.set_ylabel("y (1000 km)", labelpad=8)
ax.set_zlabel("z (1000 km)", labelpad=8)
ax.set_title("$\\pm$1.5 days about apoapsis")
ax.view_init(elev=18, azim=-60)
ax.legend(loc="upper left")
ax = fig.add_subplot(1, 2, 2, projection="3d")
th_ring = np.linspace(0, 2 * np.pi, 97)
for h, col in ((-24, "C0"), (-12, "C5"), (0, "tab:red"), (12, "C3"), (24, "C4")):
    tgt = propagate(em, nrho.x0, np.array([0.0, h * HR])).x[-1] if h else nrho.x0
    rel = (torus.states(th_ring, [h * HR])[:, 0, :3] - tgt[:3]) * L
    ax.plot(rel[:, 0], rel[:, 1], rel[:, 2], color=col, lw=2 if h == 0 else 1.4,
            label=f"{h:+d} h" + (" (apoapsis)" if h == 0 else ""))
ax.plot([0], [0], [0], "k*", ms=10, label="target")
ax.set_aspect("equal")
ax.set_xlabel("x - x$_{target}$ (km)", labelpad=6)
ax.set_ylabel("y - y$_{target}$ (km)", labelpad=6)
ax.set_zlabel("z - z$_{target}$ (km)", labelpad=6)
ax.set_title("the ring relative to the target")
ax.view_init(elev=22, azim=-60)
ax.legend(loc="upper left", fontsize=8)
fig.tight_layout()
_ = plotting.save_figure(fig, "08_fig2_torus_and_nrho", output_dir=out)

# %% [markdown]
# ## 3 · The station-keeping set and the two-burn transfer
#
# A surface point is named by its **initial ring angle** $\theta_0$ (normalised phase $\theta_0/2\pi$, the paper's
# axis) and its **time from apoapsis** $t_a$: the state at $t_a$ of the torus trajectory through $u(\theta_0)$. From
# its state at the first-burn epoch $t_b$ the agent reaches the surface point's *position* at $t_a$ with a first
# burn found by Newton's method on $\mathbf r(t_a) = \mathbf r^\star$ with the STM block $\Phi_{rv}$ (a Lambert
# problem in the CR3BP, all ring angles of one arrival time in one heyoka batch), then matches its *velocity* with
# the second burn. Every maneuver gets its own covariance analysis (notebook 07: hourly azimuth/elevation, Eq. 20
# noise, initial 3-sigma 60 km / 60 cm/s, no execution errors as in the paper) from $t_b$ to $t_f$, where
# $\sqrt{J_\rho}$ is read.
#
# **Open choices (the paper gives none of them; swept in section 6):** the agent starts on the torus trajectory of
# ring angle 0 (so "do nothing" is one of the options, at phase 0); first burn 24 h before apoapsis; arrival times
# from 12 h before to 12 h after apoapsis; $\sqrt{J_\rho}$ read 24 h after apoapsis, so that every maneuver has the
# same measurements and the second burn's effect is included (the paper attributes a local peak to it).

# %%
theta = 2 * np.pi * np.arange(N_SURF) / N_SURF
t_arr = np.linspace(*T_ARRIVAL_H, N_SURF) * HR
t0 = time.perf_counter()
S = sk.station_keeping_surface(em, torus, theta, t_arr, T_BURN_H * HR, T_FINAL_H * HR, agent_theta=AGENT_THETA)
t_surface = time.perf_counter() - t0
print(f"{N_SURF} x {N_SURF} = {N_SURF**2} maneuvers with covariance analyses ({S.t.size} measurement epochs each) "
      f"in {t_surface:.1f} s")
print(f"largest position miss of the first burn at arrival: {S.transfer_miss.max():.1e} LU "
      f"({S.transfer_miss.max() * L * 1e6:.2f} mm)")
print(f"first burn {S.dv1_m_s.min():.3f}-{S.dv1_m_s.max():.2f} m/s, second burn {S.dv2_m_s.min():.3f}-"
      f"{S.dv2_m_s.max():.2f} m/s, total {S.fuel_m_s.min():.3f}-{S.fuel_m_s.max():.2f} m/s")
print(f"sqrt(J_rho) at t_f: {S.range_sigma_km.min() * 1e3:.1f} m to {S.range_sigma_km.max():.2f} km "
      f"(no maneuver: {S.range_sigma_km[0, 0]:.2f} km; largest over the maneuvers "
      f"{S.range_sigma_km[S.fuel_m_s > 1e-9].max() * 1e3:.0f} m)")


# %%
def informed_segments(surf=None):
    """Index runs of the u* line without jumps of more than a quarter turn in phase."""
    surf = S if surf is None else surf
    ph = surf.phase[surf.informed]
    cuts = np.flatnonzero(np.abs(np.diff(ph)) > 0.25) + 1
    return np.split(np.arange(ph.size), cuts)


def surface_plot(ax, Z, title, zlabel, line=None, log=False, flip=False):
    """3-D surface over (normalised phase, time from apoapsis) with the informed line in magenta."""
    P, H = np.meshgrid(S.phase, S.t_arrival_hours)
    Zp = np.log10(Z) if log else Z
    ax.plot_surface(P, H, Zp, cmap="viridis", lw=0, alpha=0.85, rcount=60, ccount=60)
    rows = np.arange(S.t_arrival.size)
    zl = Zp[rows, S.informed] if line is None else line
    for seg in informed_segments():  # break the line where u* jumps across phase 0 = 1
        ax.plot(S.phase[S.informed][seg], S.t_arrival_hours[seg], zl[seg], color="magenta", lw=2.5, marker="o",
                ms=3)
    ax.set_xlabel("normalised phase $\\theta_0/2\\pi$ [-]", labelpad=6)
    ax.set_ylabel("time from apoapsis (h)", labelpad=6)
    ax.set_zlabel(zlabel, labelpad=6)
    ax.set_title(title)
    if flip:
        ax.invert_yaxis()


fig = plt.figure(figsize=(13, 5.5))
ax1 = fig.add_subplot(1, 2, 1, projection="3d")
surface_plot(ax1, S.dv1_m_s, "first burn (u* in magenta)", r"$\|\Delta v_1\|$ (m/s)")
ax2 = fig.add_subplot(1, 2, 2, projection="3d")
surface_plot(ax2, S.dv2_m_s, "second burn", r"$\|\Delta v_2\|$ (m/s)")
fig.tight_layout()
_ = plotting.save_figure(fig, "08_fig3_burn_surfaces", output_dir=out)

# %% [markdown]
# The first burn vanishes along phase 0 (the agent's own torus trajectory) and grows with the phase distance; it
# also grows as the coast gets shorter (earlier arrival). The magenta line is $\mathbf u^*$: for each arrival time,
# the MMD direction $\mathbf u_y$ of the coast $t_b\to t_a$ is computed on the unmaneuvered trajectory, the two
# maneuvers with $\theta_u$ closest to 0 and to $\pi$ (Eq. 25) are the candidates, and the one with the smaller
# $J_\rho$ wins.
#
# **Eq. 25 as printed, and our reading.** The paper writes $\theta_u = \cos^{-1}\big(\mathbf u_y^T\mathbf u_{sk} /
# \|\mathbf u_y^T\mathbf u_{sk}\|\big)$: the denominator is the absolute value of the same scalar, so the ratio is
# always $\pm1$ and $\theta_u\in\{0,\pi\}$ for every maneuver, which cannot rank anything. We read it as the angle
# between the two vectors, $\cos\theta_u = \mathbf u_y^T\mathbf u_{sk}/(\|\mathbf u_y\|\|\mathbf u_{sk}\|)$, with
# $\mathbf u_{sk}$ the **first** burn (the paper draws the magenta line "on the first burn", Fig. 3 caption). Three
# further choices the paper leaves open: the MMD coast ends at the arrival $t_a$ (the alternative, $\tau_f = t_f$,
# is in the sweep of section 6); the "quick covariance analysis" between the $\theta_u\approx0$ and
# $\theta_u\approx\pi$ candidates is the same covariance analysis that fills Fig. 4, so the choice of sign uses the
# cost it is judged by (which can only help $\mathbf u^*$); and a random pick of one maneuver per slice would sit at
# the 50th percentile on average, the better of two random picks at about the 33rd. Section 5b takes up a second
# reading (the *projection* of the burn on $\mathbf u_y$) and shows why the angle reading depends on how finely the
# set is sampled.
#
# ## 4 · Fig. 4: range uncertainty over all maneuvers, and Fig. 5: fuel

# %%
still = S.fuel_m_s < 1e-9  # the agent's own torus point (phase 0): no maneuver
log_sig = np.log10(S.range_sigma_km * 1e3)
z_top = log_sig[~still].max()  # z range from the maneuvers; the no-maneuver column is clipped to it
fig = plt.figure(figsize=(13, 5.5))
ax1 = fig.add_subplot(1, 2, 1, projection="3d")
surface_plot(ax1, np.minimum(log_sig, z_top), "Fig. 4: range uncertainty at $t_f$ (phase-0 wall clipped)",
             r"$\log_{10}\sqrt{J_\rho}$ (m)")
ax1.set_zlim(log_sig[~still].min(), z_top)
ax2 = fig.add_subplot(1, 2, 2, projection="3d")
surface_plot(ax2, S.fuel_m_s, "Fig. 5: total fuel (time axis flipped)", r"$\|\Delta v_1\|+\|\Delta v_2\|$ (m/s)",
             flip=True)
fig.tight_layout()
_ = plotting.save_figure(fig, "08_fig4_fig5_range_sigma_and_fuel", output_dir=out)


# %% [markdown]
# The 3-D views follow the paper's Figs. 4 and 5 and are an illustration: perspective makes heights hard to compare
# (in the left panel the no-maneuver wall at phase 0, printed above, is clipped at the largest maneuver value so
# that the relief of the maneuvers shows). The same data as maps, with the colour scale of the range map set by the
# maneuvers alone (the phase-0 column, where the agent does not maneuver, is hatched):

# %%
def range_map(ax, surf, fig):
    """Map of sqrt(J_rho) over a surface: colours from the maneuvers only, no-maneuver cells hatched, u* and the
    best maneuver of each slice as open markers (the cells underneath stay visible)."""
    none = surf.fuel_m_s < 1e-9
    sig_m = surf.range_sigma_km * 1e3
    norm = LogNorm(vmin=sig_m[~none].min(), vmax=sig_m[~none].max())
    im = ax.pcolormesh(surf.phase, surf.t_arrival_hours, np.ma.masked_where(none, sig_m), shading="nearest",
                       cmap="viridis", norm=norm)
    cb = fig.colorbar(im, ax=ax, label=r"$\sqrt{J_\rho}$ at $t_f$ (m)")
    cb.set_ticks([t for t in (10, 20, 50, 100, 200, 500, 1000) if norm.vmin <= t <= norm.vmax])
    cb.ax.yaxis.set_major_formatter(ScalarFormatter())
    cb.ax.yaxis.set_minor_formatter(NullFormatter())
    dp, dt = surf.phase[1] - surf.phase[0], surf.t_arrival_hours[1] - surf.t_arrival_hours[0]
    for i in np.flatnonzero(none.all(axis=0)):  # columns without a maneuver in any slice
        ax.add_patch(Rectangle((surf.phase[i] - dp / 2, surf.t_arrival_hours[0] - dt / 2), dp,
                               np.ptp(surf.t_arrival_hours) + dt, facecolor="0.85", edgecolor="0.3", hatch="////",
                               lw=0.5, label=f"no maneuver: {sig_m[none].min() / 1e3:.1f} km"))
    informed_markers(ax, surf)
    ax.set_xlabel(r"normalised phase $\theta_0/2\pi$ [-]")
    ax.set_ylabel("time from apoapsis (h)")


def informed_markers(ax, surf):
    """u* (magenta open circles) and the best maneuver of each slice (orange open squares) on a map."""
    for n_seg, seg in enumerate(informed_segments(surf)):
        ax.plot(surf.phase[surf.informed][seg], surf.t_arrival_hours[seg], "o", color="magenta", mfc="none", ms=5,
                mew=1.2, label="u* (informed)" if n_seg == 0 else None)
    ax.plot(surf.phase[surf.best], surf.t_arrival_hours, "s", color="tab:orange", mfc="none", mew=1.2, ms=5,
            label="best of each slice")


fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
range_map(axes[0], S, fig)
axes[0].set_title("Fig. 4 as a map: range uncertainty (maneuvers only)")
im = axes[1].pcolormesh(S.phase, S.t_arrival_hours, S.fuel_m_s, shading="nearest", cmap="viridis")
fig.colorbar(im, ax=axes[1], label="total fuel (m/s)")
informed_markers(axes[1], S)
axes[1].set_title("Fig. 5 as a map: total fuel")
axes[1].set_xlabel(r"normalised phase $\theta_0/2\pi$ [-]")
axes[1].set_ylabel("time from apoapsis (h)")
fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=3, fontsize=8)
fig.tight_layout(rect=(0, 0.07, 1, 1))
_ = plotting.save_figure(fig, "08_maps_range_sigma_fuel", output_dir=out)

# %% [markdown]
# ## 5 · The paper's claims, with numbers
#
# *"The informed station keeping maneuvers do in fact fall in the valley of range uncertainty"*: within each
# time-of-arrival slice we rank $\mathbf u^*$ among all maneuvers of the slice by $\sqrt{J_\rho}$ (percentile
# 0 = best). *"The guidance policy avoids the peak fuel cost"*: the percentage of the slice's maneuvers that use more
# fuel than $\mathbf u^*$. We also compare $\mathbf u^*$ with the best maneuver of its slice and with the cheapest
# maneuvers of at most its fuel.

# %%
pct = S.informed_percentile
fpct = S.informed_fuel_percentile
rows = np.arange(S.t_arrival.size)
best_sig = S.best_range_sigma_km
cheaper = np.array([S.range_sigma_km[j, S.fuel_m_s[j] <= S.informed_fuel_m_s[j] + 1e-12].min() for j in rows])
print("arrival h | u* phase | u* sqrt(J) m | best m | best with <= fuel m | percentile | fuel m/s | more fuel %")
for j in rows:
    print(f" {S.t_arrival_hours[j]:8.2f} | {S.phase[S.informed[j]]:8.3f} | {S.informed_range_sigma_km[j] * 1e3:12.2f} | "
          f"{best_sig[j] * 1e3:6.2f} | {cheaper[j] * 1e3:19.2f} | {pct[j]:10.1f} | {S.informed_fuel_m_s[j]:8.3f} | "
          f"{fpct[j]:6.1f}")
print(f"\nmedian percentile of u* in its slice: {np.median(pct):.1f} % (valley = low); "
      f"slices with u* in the best quartile: {np.mean(pct < 25) * 100:.0f} %")
print(f"median share of maneuvers using more fuel than u*: {np.median(fpct):.1f} %; u* at or below the slice's "
      f"median fuel in {np.mean(S.informed_fuel_m_s <= np.median(S.fuel_m_s, axis=1)) * 100:.0f} % of slices")
from scipy.stats import spearmanr

valley_phase = np.median(S.phase[S.best])
ustar_phase = np.median(S.phase[S.informed])
moving = S.fuel_m_s > 1e-9
rank_corr = np.median([spearmanr(S.fuel_m_s[j, moving[j]], S.range_sigma_km[j, moving[j]])[0] for j in rows])
print(f"valley of sqrt(J_rho) at median phase {valley_phase:.3f}; u* at median phase {ustar_phase:.3f}; fuel peak at "
      f"phase {np.median(S.phase[np.argmax(S.fuel_m_s, axis=1)]):.3f}; median rank correlation of fuel and "
      f"sqrt(J_rho) within slices (maneuvers only) {rank_corr:.2f}")
print(f"u* vs doing nothing: sqrt(J_rho) {np.median(S.informed_range_sigma_km) * 1e3:.1f} m vs "
      f"{S.range_sigma_km[0, 0] * 1e3:.0f} m")


# %% [markdown]
# The same comparison drawn per slice. Left: $\sqrt{J_\rho}$ against phase for three arrival slices (the
# no-maneuver point at phase 0 is far off the scale), with $\mathbf u^*$ and the slice's best maneuver marked.
# Right: the percentile of $\mathbf u^*$ in every slice; the valley claim needs it in the best quartile (below 25 %),
# a random pick lands at 50 % on average.

# %%
def slice_profiles(ax, surf, n_show=3):
    """sqrt(J_rho) over phase (maneuvers only) for n_show arrival slices, u* and the slice best marked."""
    moving = surf.fuel_m_s > 1e-9
    for n, j in enumerate(np.linspace(0, surf.t_arrival.size - 1, n_show).round().astype(int)):
        col = f"C{n}"
        m = moving[j]
        ax.plot(surf.phase[m], surf.range_sigma_km[j, m] * 1e3, ".-", color=col, ms=3, lw=1,
                label=f"arrival {surf.t_arrival_hours[j]:+.1f} h")
        ax.plot(surf.phase[surf.informed[j]], surf.informed_range_sigma_km[j] * 1e3, "o", ms=10, mfc="none",
                mec="magenta", mew=2)
        ax.plot(surf.phase[surf.best[j]], surf.best_range_sigma_km[j] * 1e3, "s", ms=8, mfc="none", mec="k",
                mew=1.5)
    ax.plot([], [], "o", ms=10, mfc="none", mec="magenta", mew=2, label="u* (informed)")
    ax.plot([], [], "s", ms=8, mfc="none", mec="k", mew=1.5, label="best of the slice")
    ax.set_yscale("log")
    lo, hi = ax.get_ylim()
    ax.set_yticks([t for t in (5, 10, 20, 50, 100, 200, 500, 1000) if lo <= t <= hi])
    ax.yaxis.set_major_formatter(ScalarFormatter())
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel(r"normalised phase $\theta_0/2\pi$ [-]")
    ax.set_ylabel(r"$\sqrt{J_\rho}$ at $t_f$ (m)")


def percentile_panel(ax, surfaces):
    """Percentile of u* within its slice against the arrival time, one line per (label, surface)."""
    for label, surf, style in surfaces:
        ax.plot(surf.t_arrival_hours, surf.informed_percentile, style, ms=4, label=label)
    ax.axhspan(0, 25, color="tab:green", alpha=0.15, lw=0)
    ax.text(0.02, 12.5, "valley: best quartile", transform=ax.get_yaxis_transform(), va="center", fontsize=8)
    ax.axhline(50, color="0.4", ls="--", lw=1)
    ax.text(0.02, 52, "random pick (average)", transform=ax.get_yaxis_transform(), va="bottom", fontsize=8)
    ax.set_ylim(0, 100)
    ax.set_xlabel("time from apoapsis of the arrival (h)")
    ax.set_ylabel("percentile of u* in its slice [%]")


fig, axes = plt.subplots(1, 2, figsize=(12, 4.4))
slice_profiles(axes[0], S)
axes[0].set_title("three arrival slices (maneuvers only)")
axes[0].legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3, fontsize=8)
percentile_panel(axes[1], [("tracking from the first burn (baseline)", S, "o-")])
axes[1].set_title("where u* ranks (0 % = best of its slice)")
axes[1].legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), fontsize=8)
fig.tight_layout()
_ = plotting.save_figure(fig, "08_informed_within_slices", output_dir=out)

# %% [markdown]
# The paper attributes a local peak on its $\mathbf u^*$ line to the second burn, "not accounted for in our
# prediction". We rerun the covariance analysis of each $\mathbf u^*$ with its first burn only (the agent then coasts
# off the torus) and compare.

# %%
second_effect = S.informed_range_sigma_km / sk.first_burn_only_range_sigma_km(em, S, nrho.x0)
print(f"sqrt(J_rho) of u* with both burns / first burn only: {second_effect.min():.2f}-{second_effect.max():.2f} "
      f"(median {np.median(second_effect):.2f}); slices where the second burn raises it by > 10 %: "
      f"{np.sum(second_effect > 1.1)} of {rows.size}")

# %% [markdown]
# **Reading.** Two things shape the surface. (i) In the linear covariance analysis (perfectly known burns) a burn
# made *while tracking* buys range information, because the known kink breaks the scaling symmetry of angles-only
# relative motion. In this baseline the first burn coincides with the start of tracking, where it only moves the
# initial state, so the information comes from the second burn (the ratio printed above): doing nothing leaves about
# 24 km of range uncertainty, every maneuver of the set from about 9 m to about two hundred metres (both printed in
# section 3), and bigger burns tend to buy more (the negative rank correlation of fuel and $\sqrt{J_\rho}$ printed
# above).
# (ii) Eq. 25 read as an angle is a pure *direction* criterion: as the target phase approaches the agent's own phase
# the first burn shrinks to zero while its direction tends to a limit, and when that limit is well aligned with
# $\pm\mathbf u_y$ the informed maneuver is one of the two smallest non-zero burns of the slice (next to phase 0).
# That is what happens here, so $\mathbf u^*$ avoids the fuel peak (as the paper says) but sits far from the valley
# of range uncertainty (unlike the paper's Fig. 4). Section 5b shows that this answer is a property of the grid.
#
# ### The other reading: tracking before the first burn
#
# If the agent has been tracking the target for `PRE_ARC_H` = 24 h when it makes the first burn ($P_0$ at the start
# of tracking), the first burn is also a kink in a tracked arc, as the MMD rationale assumes (notebook 07: there
# MMD is nearly optimal for short coasts). Same surface, same maneuvers, same $\mathbf u_y$; only the covariance
# analyses change.

# %%
S_pre = sk.station_keeping_surface(em, torus, theta, t_arr, T_BURN_H * HR, T_FINAL_H * HR, agent_theta=AGENT_THETA,
                                   t_track_start=(T_BURN_H - PRE_ARC_H) * HR, progress=False)
pct_pre = S_pre.informed_percentile
print(f"tracking from {T_BURN_H - PRE_ARC_H:.0f} h: sqrt(J_rho) {S_pre.range_sigma_km.min() * 1e3:.2f} m to "
      f"{S_pre.range_sigma_km.max():.2f} km (no maneuver {S_pre.range_sigma_km[0, 0]:.2f} km)")
print(f"u*: median percentile in its slice {np.median(pct_pre):.1f} %, best quartile in {np.mean(pct_pre < 25) * 100:.0f} % "
      f"of slices, at median phase {np.median(S_pre.phase[S_pre.informed]):.3f}; valley at median phase "
      f"{np.median(S_pre.phase[S_pre.best]):.3f}")
fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
range_map(axes[0], S_pre, fig)
axes[0].set_title(f"tracking from {PRE_ARC_H:.0f} h before the first burn")
axes[0].legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=8)
percentile_panel(axes[1], [("tracking from the first burn (baseline)", S, "o-"),
                           (f"tracking from {PRE_ARC_H:.0f} h before it", S_pre, "s--")])
axes[1].set_title("where u* ranks, both readings")
axes[1].legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), fontsize=8)
fig.tight_layout()
_ = plotting.save_figure(fig, "08_map_range_sigma_with_tracking_arc", output_dir=out)

# %%
second_effect_pre = S_pre.informed_range_sigma_km / sk.first_burn_only_range_sigma_km(em, S_pre, nrho.x0)
print(f"tracking from {T_BURN_H - PRE_ARC_H:.0f} h: sqrt(J_rho) of u* with both burns / first burn only "
      f"{second_effect_pre.min():.2f}-{second_effect_pre.max():.2f} (median {np.median(second_effect_pre):.2f}); "
      f"slices where the second burn raises it by > 10 %: {np.sum(second_effect_pre > 1.1)} of {rows.size}")

# %% [markdown]
# With 24 h of tracking before the first burn, the first burn carries range information of its own, so the second
# burn's share (the ratio just printed) is no longer the whole of it.
#
# ## 5b · Two readings of Eq. 25, and how finely the set is sampled
#
# The paper does not say how many maneuvers its surface holds, and under the angle reading this matters. Near the
# agent's own phase the first burn to ring angle $\theta_0$ shrinks to zero while its *direction* tends to a limit;
# when that limit is the best-aligned direction of the slice, a finer grid of ring angles always offers a grid point
# closer to the agent, with a smaller burn and the same alignment. As the grid is refined, $\mathbf u^*$ then tends to
# "no maneuver" and its $\sqrt{J_\rho}$ to the no-maneuver value: the rule picks a property of the grid, not of
# the set.
#
# A second reading takes the paper's words literally, "projecting the guidance policy $\pm\mathbf u_y$ onto a
# surface of candidate station keeping maneuvers": rank the first burns by their component along the MMD direction,
# $\mathbf u_y^T\Delta\mathbf v_1/\|\mathbf u_y\|$ (the numerator of Eq. 25, normalised by $\mathbf u_y$ only);
# the largest component along $+\mathbf u_y$ and along $-\mathbf u_y$ are the two candidates and the quick
# covariance analysis decides between them, as before. This reading has a limit as the grid is refined. Below, the
# ring-angle grid is refined on a few arrival slices, for the baseline agent (phase 0) and for the agent a quarter
# turn back (phase 0.75, the most favourable setting of the angle reading in the sweep of section 6, printed
# there), and $\mathbf u^*$ is followed under both readings.

# %%
t_grid = np.linspace(*T_ARRIVAL_H, N_GRID_SLICES) * HR
grid_study = []
for agent_phase in (0.0, 0.75):
    for n in N_GRID:
        s_g = sk.station_keeping_surface(em, torus, 2 * np.pi * np.arange(n) / n, t_grid, T_BURN_H * HR,
                                         T_FINAL_H * HR, agent_theta=2 * np.pi * agent_phase, progress=False)
        for crit in ("angle", "projection"):
            r = s_g.reselect(crit)
            grid_study.append(dict(agent=agent_phase, n=n, crit=crit, pct=np.median(r.informed_percentile),
                                   sig_m=np.median(r.informed_range_sigma_km) * 1e3,
                                   fuel=np.median(r.informed_fuel_m_s), more=np.median(r.informed_fuel_percentile),
                                   best_m=np.median(r.best_range_sigma_km) * 1e3))
print(f"{N_GRID_SLICES} arrival slices from {T_ARRIVAL_H[0]:+.0f} h to {T_ARRIVAL_H[1]:+.0f} h; medians over the slices")
print("agent phase | ring angles | reading    | percentile of u* % | sqrt(J) of u* m | fuel of u* m/s | more fuel % "
      "| best of slice m")
for g in grid_study:
    print(f" {g['agent']:10.2f} | {g['n']:11d} | {g['crit']:10s} | {g['pct']:18.1f} | {g['sig_m']:15.1f} | "
          f"{g['fuel']:14.3f} | {g['more']:11.1f} | {g['best_m']:15.1f}")


def grid_series(agent, crit, key):
    """One column of the resolution study for an agent phase and a reading."""
    return np.array([g[key] for g in grid_study if g["agent"] == agent and g["crit"] == crit])


fig, axes = plt.subplots(1, 2, figsize=(12, 4.4))
for agent, col in ((0.0, "C0"), (0.75, "C1")):
    for crit, mk, ls in (("angle", "o", "-"), ("projection", "s", "--")):
        lab = f"agent phase {agent:.2f}, {crit} reading"
        axes[0].plot(N_GRID, grid_series(agent, crit, "pct"), ls, marker=mk, color=col, label=lab)
        axes[1].plot(N_GRID, grid_series(agent, crit, "sig_m"), ls, marker=mk, color=col, label=lab)
axes[1].axhline(S.range_sigma_km[0, 0] * 1e3, color="k", ls=":", lw=1.2)
axes[1].text(N_GRID[0], S.range_sigma_km[0, 0] * 1e3 / 1.4, "no maneuver (agent phase 0)", fontsize=8, va="top")
for ax in axes:
    ax.set_xscale("log")
    ax.set_xticks(N_GRID, [str(n) for n in N_GRID])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("ring angles in the set [-]")
axes[0].axhspan(0, 25, color="tab:green", alpha=0.15, lw=0)
axes[0].set_ylim(0, 100)
axes[0].set_ylabel("median percentile of u* in its slice [%]")
axes[0].set_title("where u* ranks (0 % = best of its slice)")
axes[1].set_yscale("log")
axes[1].set_ylabel(r"median $\sqrt{J_\rho}$ of u* at $t_f$ (m)")
axes[1].yaxis.set_major_formatter(ScalarFormatter())
axes[1].set_title("range uncertainty of u*")
fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8)
fig.tight_layout(rect=(0, 0.12, 1, 1))
_ = plotting.save_figure(fig, "08_eq25_readings_vs_grid", output_dir=out)

# %% [markdown]
# The projection reading on the full surface of sections 3-5 (same maneuvers, same covariance analyses; only the
# choice of $\mathbf u^*$ changes):

# %%
S_proj = S.reselect("projection")
pct_proj = S_proj.informed_percentile
fpct_proj = S_proj.informed_fuel_percentile
fuel_ok_proj_share = np.mean(S_proj.informed_fuel_m_s <= np.median(S_proj.fuel_m_s, axis=1))
second_effect_proj = S_proj.informed_range_sigma_km / sk.first_burn_only_range_sigma_km(em, S_proj, nrho.x0)
print(f"projection reading: u* at median phase {np.median(S_proj.phase[S_proj.informed]):.3f} (valley at "
      f"{valley_phase:.3f}); median percentile {np.median(pct_proj):.1f} %, best quartile in "
      f"{np.mean(pct_proj < 25) * 100:.0f} % of slices; sqrt(J_rho) {np.median(S_proj.informed_range_sigma_km) * 1e3:.1f} m "
      f"(best of slice {np.median(S_proj.best_range_sigma_km) * 1e3:.1f} m)")
print(f"fuel: u* {np.median(S_proj.informed_fuel_m_s):.2f} m/s (median over slices), {np.median(fpct_proj):.1f} % of "
      f"maneuvers cost more; at or below the slice's median fuel in {fuel_ok_proj_share * 100:.0f} % of slices; "
      f"largest fuel of the set {S.fuel_m_s.max():.2f} m/s")
print(f"second burn: sqrt(J_rho) of u* with both burns / first burn only {second_effect_proj.min():.3f}-"
      f"{second_effect_proj.max():.3f}")
fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
range_map(axes[0], S_proj, fig)
axes[0].set_title("projection reading: u* on the range map")
axes[0].legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=8)
percentile_panel(axes[1], [("angle reading", S, "o-"), ("projection reading", S_proj, "s--")])
axes[1].set_title("where u* ranks, both readings")
axes[1].legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), fontsize=8)
fig.tight_layout()
_ = plotting.save_figure(fig, "08_projection_reading", output_dir=out)

# %% [markdown]
# **Reading.** The angle reading is what Eq. 25's symbols say (a cosine), but on this set it has no limit: refining
# the grid drives $\mathbf u^*$ towards the agent's own phase and, for the baseline agent, its range uncertainty
# towards the no-maneuver value (the table above: the median $\sqrt{J_\rho}$ of $\mathbf u^*$ roughly doubles with
# every doubling of the grid). Its percentile in the slice, and the factor by which it beats doing nothing, are
# therefore set by the grid spacing, which the paper does not give. The projection reading does not move with the
# grid. For the baseline agent it puts $\mathbf u^*$ in the valley (a few percent, next to the slice's best
# maneuver on the map), which is what the paper's Fig. 4 shows; for the agent a quarter turn back it ranks it near
# the 36th percentile, better than a random pick but outside the best quartile. It gets there by choosing a large
# burn along $\pm\mathbf u_y$ (about 5.5 m/s of the 0-18 m/s range), so it pays for the information with fuel near
# the middle of the slice's distribution. We let the paper's Fig. 4 decide between the readings; because that choice
# is made while looking at the paper's figure, the valley row of the projection reading is *consistent (tuned)*, not
# reproduced. Neither reading gives both of the paper's statements (in the valley *and* away from the fuel peak,
# with "away" read as "at or below the slice's median fuel") at once.

# %% [markdown]
# ## 6 · In which regime does the "valley" claim hold? A sweep over the unstated inputs
#
# Our baseline reading puts $\mathbf u^*$ where it is printed above. The paper's Figs. 3-5 do not give the burn
# epoch, the arrival window, the agent's starting phase or where $J_\rho$ is read, so we sweep them: the first-burn
# lead time before the arrival window, the agent's initial ring angle, whether tracking starts at the first burn or
# `PRE_ARC_H` before it, and $\sqrt{J_\rho}$ read at $t_f$ (common
# final time) or at each maneuver's own arrival. For each setting: the median percentile of $\mathbf u^*$ within its
# slices and the share of slices where it is in the best quartile, under both readings of Eq. 25, on the ring-angle
# grid of sections 3-5 (`N_SURF` ring angles, so that the angle reading is compared at the same spacing) and
# `N_SWEEP` arrival times.

# %%
sweep = []
theta_s = theta
t_arr_s = np.linspace(*T_ARRIVAL_H, N_SWEEP) * HR
settings = [(pre_h, lead_h, ang) for pre_h in (0.0, PRE_ARC_H) for lead_h in (12.0, 24.0, 48.0)
            for ang in (0.0, np.pi / 2, np.pi, 3 * np.pi / 2)]
for pre_h, lead_h, agent_theta in settings:
    t_b = (T_ARRIVAL_H[0] - lead_h) * HR
    s = sk.station_keeping_surface(em, torus, theta_s, t_arr_s, t_b, T_FINAL_H * HR, agent_theta=agent_theta,
                                   t_track_start=t_b - pre_h * HR, progress=False)
    sig_a = s.range_sigma_at_arrival_km
    arr_pct = 100 * np.mean(sig_a < sig_a[np.arange(s.t_arrival.size), s.informed][:, None], axis=1)
    sp = s.reselect("projection")
    sweep.append(dict(pre_h=pre_h, lead_h=lead_h, agent_phase=agent_theta / (2 * np.pi),
                      pct_tf=np.median(s.informed_percentile), q_tf=np.mean(s.informed_percentile < 25) * 100,
                      pct_arr=np.median(arr_pct), q_arr=np.mean(arr_pct < 25) * 100,
                      fuel_pct=np.median(s.informed_fuel_percentile), pct_proj=np.median(sp.informed_percentile),
                      fuel_pct_proj=np.median(sp.informed_fuel_percentile)))
print("angle reading" + " " * 57 + "| projection reading")
print("pre-arc h | lead h | agent phase | median pct (t_f) | best-quartile % (t_f) | median pct (arrival) | best-quartile % "
      "(arrival) | more-fuel % | median pct (t_f) | more-fuel %")
for r in sweep:
    print(f" {r['pre_h']:8.0f} | {r['lead_h']:5.0f} | {r['agent_phase']:11.2f} | {r['pct_tf']:16.1f} | {r['q_tf']:21.0f} | "
          f"{r['pct_arr']:20.1f} | {r['q_arr']:26.0f} | {r['fuel_pct']:11.1f} | {r['pct_proj']:16.1f} | "
          f"{r['fuel_pct_proj']:10.1f}")
best_setting = min(sweep, key=lambda r: r["pct_tf"])
n_valley_angle = sum(r["pct_tf"] < 25 for r in sweep)
n_valley_proj = sum(r["pct_proj"] < 25 for r in sweep)
print(f"settings with the median percentile below 25 % (the valley tolerance): angle reading {n_valley_angle} of "
      f"{len(sweep)}, projection reading {n_valley_proj} of {len(sweep)}")
# the other readings: the MMD coast ending at t_f instead of the arrival, and an agent that has drifted off the torus
# (station keeping "returns" the agent: a position offset of d km and a velocity offset of d x 7.2 mm/s, the ring's
# velocity-to-position size ratio, in random directions, at the first burn)
s_h = sk.station_keeping_surface(em, torus, theta_s, t_arr_s, T_BURN_H * HR, T_FINAL_H * HR, agent_theta=AGENT_THETA,
                                 mmd_horizon="final", progress=False)
pct_horizon = np.median(s_h.informed_percentile)
print(f"\nMMD coast to t_f instead of the arrival (baseline otherwise): median percentile {pct_horizon:.1f} %, best "
      f"quartile in {np.mean(s_h.informed_percentile < 25) * 100:.0f} % of slices")
rng_off = np.random.default_rng([SEED, 8])
vel_per_km = torus.velocity_size_mps / torus.size_km  # m/s per km
offset_sweep = {}
for d_km in (0.0, 1.0, 10.0, 50.0):
    vals = []
    for _ in range(3):
        dr, dv_ = rng_off.standard_normal(3), rng_off.standard_normal(3)
        off = np.r_[d_km * dr / np.linalg.norm(dr) / L, d_km * vel_per_km * 1e-3 * dv_ / np.linalg.norm(dv_) / V]
        s_o = sk.station_keeping_surface(em, torus, theta_s, t_arr_s, T_BURN_H * HR, T_FINAL_H * HR,
                                         agent_theta=AGENT_THETA, agent_offset=off, progress=False)
        vals.append(np.median(s_o.informed_percentile))
    offset_sweep[d_km] = vals
    print(f"agent {d_km:4.0f} km / {d_km * vel_per_km * 1e3:4.0f} mm/s off the torus: median percentile of u* "
          f"{', '.join(f'{v:.0f}' for v in vals)} % (3 random offset directions)")
pct_offset_all = np.concatenate([v for d, v in offset_sweep.items() if d > 0])
print(f"\nmost favourable setting for the angle reading: pre-arc {best_setting['pre_h']:.0f} h, lead "
      f"{best_setting['lead_h']:.0f} h, agent phase "
      f"{best_setting['agent_phase']:.2f}: median percentile {best_setting['pct_tf']:.1f} %")

# %% [markdown]
# The last unstated input is the paper's one number, "the average range ... is 215 km". Our member matches the
# torus average over ring angle and one period; the same member has a different mean over the apolune ring alone
# and a different RMS (section 1). Members chosen so that those two readings equal 215 km instead:

# %%
member_check = {}
for stat in ("ring_mean_km", "rms_km"):
    tor_alt, st_alt = qpo_for_mean_range(nrho, 215.0, statistic=stat)
    s_alt = sk.station_keeping_surface(em, tor_alt, theta, t_arr, T_BURN_H * HR, T_FINAL_H * HR,
                                       agent_theta=AGENT_THETA, progress=False)
    row = {}
    for crit in ("angle", "projection"):
        r = s_alt.reselect(crit)
        row[crit] = (np.median(r.informed_percentile),
                     np.mean(r.informed_fuel_m_s <= np.median(r.fuel_m_s, axis=1)) * 100)
    member_check[stat] = row
    print(f"member with {stat[:-3]} = 215 km: torus mean {st_alt.mean_km:.0f} km, ring size {tor_alt.size_km:.0f} km; "
          f"u* median percentile angle {row['angle'][0]:.1f} % / projection {row['projection'][0]:.1f} %; "
          f"at or below median fuel in {row['angle'][1]:.0f} % / {row['projection'][1]:.0f} % of slices")

# %% [markdown]
# **Reading.** Under the angle reading the informed maneuver is in the valley in none of the settings (the count
# printed above): its median percentile stays far above the best quartile, even with the agent a quarter turn away on
# the ring or with the tracking arc starting before the first burn. Neither the MMD horizon nor an agent that has
# drifted off the torus (so that no maneuver of the set is near zero and the angle cannot simply pick the smallest
# burn) changes the verdict: a drift moves $\mathbf u^*$ towards the middle of the distribution, i.e. towards what a
# random pick achieves, not into the valley. The member chosen by another reading of "average range" changes nothing
# either. Under the projection reading the verdict depends on one unstated input, the agent's own ring angle: with
# the agent at phase 0 or 0.5, $\mathbf u^*$ is in the valley at every burn lead and tracking start; a quarter turn
# away (0.25 or 0.75) it sits between about the 30th and 45th percentile. So the valley of the paper's Fig. 4 is reached by the
# projection reading for half of the agent phases, and by the angle reading for none; the angle reading always avoids
# the fuel peak, the projection reading never goes below the median fuel. The two valley rows of the closing table
# carry these numbers.
#
# ## 7 · Beyond the paper: a full-filter Monte Carlo with execution errors
#
# The paper's covariance analysis assumes perfectly executed burns and a filter that does not diverge; its
# conclusions list both as future work. Here an iterated EKF (:func:`cislunar.papers.greaves_scheeres_2023.station_keeping.filter_trial`;
# 10 relinearisations per update, because a single-linearisation EKF is inconsistent at the start of an
# angles-only track with 20 km of position uncertainty at a few hundred km range) processes simulated measurements
# of the true trajectories, including execution errors of **1 mm/s plus 1 % of the burn (1 sigma per axis)** that
# the filter knows statistically. Four policies for the arrival slice closest to apoapsis: the informed maneuver
# $\mathbf u^*$ under each reading of Eq. 25, an *uninformed* choice (a ring angle drawn uniformly at random in each
# trial), and doing nothing; the maneuvers with perfect burns, with the nominal execution errors and with ten times
# smaller ones (0.1 mm/s + 0.1 %), to see what execution accuracy the information gain needs. Doing nothing makes no
# burn, so it has no execution error and is run once. Consistency: mean NEES of the 12-dimensional SSAT state at $t_f$ against
# its 95 % chi-square band; accuracy: RMS of the achieved range error along the line of sight at $t_f$.

# %%
from scipy.stats import chi2

INF, INFP = "informed u*\n(angle reading)", "informed u*\n(projection)"
UNI, NONE = "uninformed\n(random phase)", "no maneuver"
j_mc = int(np.argmin(np.abs(S.t_arrival_hours)))
tgt_b = propagate(em, nrho.x0, np.array([0.0, S.t[0]])).x[-1]  # target at the start of tracking
zero = int(np.argmin(S.fuel_m_s[j_mc]))  # phase 0: no maneuver
policies = {}
LEVELS = {"perfect": (0.0, 0.0), "small": (EXEC_ABS_M_S / 10, EXEC_REL / 10), "exec": (EXEC_ABS_M_S, EXEC_REL)}
for tag, (exec_abs, exec_rel) in LEVELS.items():
    mk = lambda i, lab: sk.filter_scenario(S, j_mc, i, tgt_b, em, exec_sigma_abs_m_s=exec_abs,  # noqa: E731
                                           exec_sigma_rel=exec_rel, label=lab)
    policies[(INF, tag)] = (sk.filter_trial, (mk(S.informed[j_mc], "informed"),))
    policies[(INFP, tag)] = (sk.filter_trial, (mk(S_proj.informed[j_mc], "informed, projection"),))
    policies[(UNI, tag)] = (
        sk.random_choice_trial, (tuple(mk(i, "random") for i in range(S.theta.size) if i != zero),))
    if tag == "perfect":  # no burn, nothing to execute: the same at every execution-error level
        policies[(NONE, tag)] = (sk.filter_trial, (mk(zero, "none"),))

for name, idx in (("informed u*, angle reading", S.informed[j_mc]), ("informed u*, projection", S_proj.informed[j_mc]),
                  ("largest uninformed pick", int(np.argmax(S.dv1_m_s[j_mc])))):
    d1, d2 = S.dv1_m_s[j_mc, idx], S.dv2_m_s[j_mc, idx]
    e1, e2 = (1e3 * sk.execution_sigma(np.array([d, 0.0, 0.0]), EXEC_ABS_M_S, EXEC_REL) for d in (d1, d2))
    print(f"{name}: burns {d1:.3f} + {d2:.3f} m/s; nominal execution error (1 sigma per axis) {e1:.1f} and {e2:.1f} mm/s")
executor = ProcessPoolExecutor(max_workers=N_WORKERS) if N_WORKERS > 1 else None
mc = {}
t0 = time.perf_counter()
for n_key, (key, (fn, args)) in enumerate(policies.items()):
    mc[key] = run_monte_carlo(fn, N_TRIALS, [SEED, n_key], args=args, executor=executor,
                              desc=f"{key[0].replace(chr(10), ' ')}, {key[1]}")
if executor is not None:
    executor.shutdown()
t_mc = time.perf_counter() - t0
lo, hi = chi2.ppf([0.025, 0.975], 12 * N_TRIALS) / N_TRIALS
print(f"{len(policies)} x {N_TRIALS} filter runs in {t_mc:.1f} s; 95 % band of the mean NEES: [{lo:.2f}, {hi:.2f}]")
print("policy                      | burns   | failed | mean NEES(t_f) | RMS range error m | filter sigma m | "
      "cov. analysis m")
summary = {}
for (pol, tag), res in mc.items():
    ok = [r for r in res if not r.failure]
    nees_f = np.mean([r.nees[-1] for r in ok])
    rms = np.sqrt(np.mean([r.range_error_km[-1] ** 2 for r in ok])) * 1e3
    fsig = np.sqrt(np.mean([r.range_sigma_km[-1] ** 2 for r in ok])) * 1e3
    ca = {INF: S.informed_range_sigma_km[j_mc], INFP: S_proj.informed_range_sigma_km[j_mc],
          NONE: S.range_sigma_km[j_mc, zero],
          UNI: np.sqrt(np.mean(np.delete(S.range_sigma_km[j_mc], zero) ** 2))}[pol] * 1e3
    summary[(pol, tag)] = dict(nees=nees_f, rms=rms, fsig=fsig, ca=ca, failed=len(res) - len(ok))
    print(f"{pol.replace(chr(10), ' '):27s} | {tag:7s} | {len(res) - len(ok):6d} | {nees_f:14.2f} | {rms:17.1f} | "
          f"{fsig:14.1f} | {ca:15.1f}")
M0 = ssat.range_projection(np.r_[S.agent_x0, tgt_b])
prior_range_m = np.sqrt(M0 @ ssat.initial_covariance(em) @ M0) * L * 1e3
print(f"range 1-sigma of the prior at the start of tracking: {prior_range_m:.0f} m")

# %% [markdown]
# **Reading.** With perfectly executed burns the filter comes close to what the covariance analysis predicts (RMS
# error about 15 % above the predicted $\sqrt{J_\rho}$ for both informed choices, mean NEES inside the band
# near its upper edge: printed above), so the paper's linear analysis is the accuracy a filter that does not diverge
# approaches (its "upper bound on filter performance", a lower bound on the error). Execution errors of 1 mm/s + 1 % (a few mm/s per axis for the
# sub-metre-per-second burns of the angle reading's $\mathbf u^*$, a few cm/s for the larger burns of the projection
# reading and the large uninformed picks: printed above the table) are unknown velocity kicks of the agent and wipe out most
# of the maneuver's range information: the range error grows to kilometres, and which maneuver was chosen matters
# much less than how well it was executed, which quantifies the paper's remark that accelerometers would be needed.
# With perfect burns, the ratios printed below compare the informed choices with an uninformed one: in the full run
# (40 trials per policy) the angle reading's $\mathbf u^*$ is clearly *worse* than a random pick, in line with
# section 5 (it is one of the smallest maneuvers of its slice, and in this linear-information regime bigger burns buy
# more), while the projection reading's is clearly better, as its place in the valley predicts; quick mode's few
# trials are too few to decide these comparisons. Without any maneuver the range stays nearly unobservable and the
# iterated EKF *diverges*: its mean NEES is far above the band and its range error ends larger than the 28 km range
# 1-sigma of the prior (printed above), while it believes it knows the range to about 20 km. With any maneuver the
# mean NEES is back inside the band or just above it (the uninformed pick with nominal execution errors).
#
# In the figure each marker is the RMS of the achieved range error over the runs of one policy and execution level,
# the black tick at the same position the filter's own 1-sigma (where they coincide the filter is honest), and the dotted line
# the covariance analysis with perfect burns (for the uninformed choice, the RMS over the slice's maneuvers). Doing
# nothing has no burn to execute, so it is run once, with "perfect" (absent) burns.

# %%
ratio_pu = summary[(INF, "perfect")]["rms"] / summary[(UNI, "perfect")]["rms"]
ratio_ppu = summary[(INFP, "perfect")]["rms"] / summary[(UNI, "perfect")]["rms"]
for name, ratio in (("angle", ratio_pu), ("projection", ratio_ppu)):
    print(f"perfect burns: RMS range error of the informed choice ({name} reading) / the uninformed one = "
          f"{ratio:.2f} ({'informed better' if ratio < 1 else 'uninformed better'})")
fig, ax = plt.subplots(figsize=(8.5, 4.6))
labels = list(dict.fromkeys(p for p, _ in mc))
xpos = np.arange(len(labels))
for off, tag, col, mk in ((-0.2, "perfect", "tab:blue", "o"), (0.0, "small", "tab:green", "D"),
                          (0.2, "exec", "tab:orange", "^")):
    a, r = LEVELS[tag]
    for n, p in enumerate(labels):
        if (p, tag) not in summary:  # no maneuver: nothing to execute
            ax.text(xpos[n] + off, summary[(p, "perfect")]["ca"] / 1.5, "no burn", rotation=90, ha="center",
                    va="top", fontsize=8, color=col)
            continue
        ax.plot(xpos[n] + off, summary[(p, tag)]["rms"], mk, color=col, ms=8,
                label=("perfect burns" if tag == "perfect" else f"execution errors {a * 1e3:g} mm/s + {r * 100:g} %")
                if n == 0 else None)
        ax.plot(xpos[n] + off, summary[(p, tag)]["fsig"], "_", color="k", ms=16, mew=1.5, zorder=4,
                label="filter 1-sigma" if (n, tag) == (0, "perfect") else None)
for n, p in enumerate(labels):  # the covariance analysis (perfect burns) the filter is compared with
    ax.hlines(summary[(p, "perfect")]["ca"], xpos[n] - 0.32, xpos[n] + 0.32, color="k", ls=":", lw=1.5,
              label="covariance analysis (perfect burns)" if n == 0 else None)
ax.set_yscale("log")
ax.set_xticks(xpos, labels, fontsize=8)
ax.set_xlim(-0.5, len(labels) - 0.5)
ax.set_xlabel("choice of the burns [-]")
ax.set_ylabel("RMS range error at $t_f$ [m]")
ax.set_title(f"iterated EKF, {N_TRIALS} runs each")
ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=3, fontsize=8)
fig.tight_layout()
_ = plotting.save_figure(fig, "08_monte_carlo_range_errors", output_dir=out)

# %% [markdown]
# ## 8 · Paper vs reproduction

# %%
ia, ipa = summary[(INF, "exec")], summary[(INFP, "exec")]
ua = summary[(UNI, "exec")]
ip, ipp = summary[(INF, "perfect")], summary[(INFP, "perfect")]
nm = summary[(NONE, "perfect")]
ga = {g["n"]: g for g in grid_study if g["agent"] == 0.0 and g["crit"] == "angle"}
gp = {g["n"]: g for g in grid_study if g["agent"] == 0.0 and g["crit"] == "projection"}
grid_txt = lambda d, key, f: "/".join(f.format(d[n][key]) for n in N_GRID)  # noqa: E731
table.add_typed("QPO member: mean agent-target range", "215 km", f"{stats.mean_km:.2f} km", "derived",
          "the 215 km was used to SELECT the member (torus average over ring angle and one period); an input, "
          f"not a prediction. Same member read as apolune-ring mean: {stats.ring_mean_km:.1f} km, RMS {stats.rms_km:.1f} km")
table.add_typed("QPO ring size (RMS about centre)", "-", f"{torus.size_km:.2f} km / {torus.velocity_size_mps:.3f} m/s",
          "not in paper", "the paper gives no torus parameters")
table.add_typed("QPO rotation number (rad per NRHO period)", "-", f"{torus.rho:.6f}", "not in paper",
          "stroboscopic time = NRHO period (same base frequency)")
table.add_typed("agent-target range min / max on the torus", "-", f"{stats.min_km:.1f} / {stats.max_km:.1f} km",
          "not in paper", "min/max over all ring angles and one period")
table.add_typed("Fig. 2: torus surface about the NRHO near apoapsis", "figure", "08_fig2_torus_and_nrho", "derived",
          "closed viewing geometry: the torus surrounds the NRHO arc")
table.add_typed("two-burn transfer reaches the torus point", "-", f"{S.transfer_miss.max():.1e} LU",
          "beyond paper", "test requires 1e-9 LU in position and velocity")
table.add_typed("Fig. 3: first / second burn ranges over the surface", "figure (values not printed)",
          f"{S.dv1_m_s.min():.2f}-{S.dv1_m_s.max():.2f} / {S.dv2_m_s.min():.2f}-{S.dv2_m_s.max():.2f} m/s",
          "not in paper", "depends on the unstated burn epoch and arrival window (section 3)")
valley_ok = np.median(pct) < 25
table.add_typed("Fig. 4: u* lies in the valley of sqrt(J_rho) (median percentile within slices)", "in the valley",
          f"{np.median(pct):.0f} % (best quartile in {np.mean(pct < 25) * 100:.0f} % of slices)",
          "reproduced" if valley_ok else "differs: see note",
          "tolerance fixed before comparing: median percentile < 25 %. With 24 h of tracking before the first burn: "
          f"{np.median(pct_pre):.0f} % (best quartile in {np.mean(pct_pre < 25) * 100:.0f} % of slices). "
          "Sweep (section 6) over tracking start, burn lead 12-48 h, "
          f"agent phase and read-out time: median percentile {min(r['pct_tf'] for r in sweep):.0f}-"
          f"{max(r['pct_tf'] for r in sweep):.0f} % at t_f, {min(r['pct_arr'] for r in sweep):.0f}-"
          f"{max(r['pct_arr'] for r in sweep):.0f} % at arrival. Valley at phase {valley_phase:.3f}, u* at "
          f"{ustar_phase:.3f} (next to the agent's own phase 0, the smallest burns); rank correlation of fuel and "
          f"sqrt(J_rho) within slices {rank_corr:.2f}. MMD coast to t_f instead of the arrival: {pct_horizon:.0f} %. "
          f"Agent drifted 1-50 km off the torus (3 directions each): {pct_offset_all.min():.0f}-"
          f"{pct_offset_all.max():.0f} %. Tolerance met in {n_valley_angle} of {len(sweep)} sweep settings. Members "
          f"matching 215 km as ring mean / RMS: {member_check['ring_mean_km']['angle'][0]:.0f} / "
          f"{member_check['rms_km']['angle'][0]:.0f} %. A random pick: 50 % on average. Eq. 25 read as the angle "
          "between u_y and the first burn (the printed denominator makes every angle 0 or pi). Grid-dependent: with "
          f"{'/'.join(str(n) for n in N_GRID)} ring angles (section 5b) {grid_txt(ga, 'pct', '{:.1f}')} %, "
          "tending to 100 % (u* tends to no maneuver)")
table.add_typed("Fig. 4: u* in the valley, Eq. 25 read as the projection of the burn on u_y", "in the valley",
          f"{np.median(pct_proj):.0f} % (best quartile in {np.mean(pct_proj < 25) * 100:.0f} % of slices)",
          "consistent (tuned)" if np.median(pct_proj) < 25 else "differs: see note",
          "same tolerance (median percentile < 25 %); this reading was chosen because it matches the paper's Fig. 4 "
          "(hence tuned). Grid-independent: with "
          f"{'/'.join(str(n) for n in N_GRID)} ring angles {grid_txt(gp, 'pct', '{:.0f}')} %. Sweep (section 6): "
          f"{min(r['pct_proj'] for r in sweep):.0f}-{max(r['pct_proj'] for r in sweep):.0f} %, tolerance met in "
          f"{n_valley_proj} of {len(sweep)} settings; members matching 215 km as ring mean / RMS: "
          f"{member_check['ring_mean_km']['projection'][0]:.0f} / {member_check['rms_km']['projection'][0]:.0f} %")
fuel_ok = np.mean(S.informed_fuel_m_s <= np.median(S.fuel_m_s, axis=1)) >= 0.9
table.add_typed("Fig. 5: guidance avoids the largest fuel costs (angle reading)", "avoids the peak",
          f"u* below the slice median fuel in {np.mean(S.informed_fuel_m_s <= np.median(S.fuel_m_s, axis=1)) * 100:.0f} % "
          f"of slices; median {np.median(fpct):.0f} % of maneuvers cost more",
          "reproduced" if fuel_ok else "differs: see note",
          "tolerance fixed before comparing: u* at or below the slice's median fuel in >= 90 % of slices. It does, "
          "but because Eq. 25 read as an angle picks maneuvers next to the agent's own phase, i.e. the smallest "
          f"burns; on finer grids even smaller (median fuel of u* {grid_txt(ga, 'fuel', '{:.2f}')} m/s with "
          f"{'/'.join(str(n) for n in N_GRID)} ring angles)")
fuel_ok_proj = fuel_ok_proj_share >= 0.9
table.add_typed("Fig. 5: guidance avoids the largest fuel costs (projection reading)", "avoids the peak",
          f"u* below the slice median fuel in {fuel_ok_proj_share * 100:.0f} % of slices; median "
          f"{np.median(fpct_proj):.0f} % of maneuvers cost more", "reproduced" if fuel_ok_proj else "differs: see note",
          "same tolerance as the row above. The projection reading buys its place in the valley with a large burn "
          f"along u_y: median {np.median(S_proj.informed_fuel_m_s):.2f} m/s against at most "
          f"{S.fuel_m_s.max():.2f} m/s in the set, i.e. near the middle of the fuel distribution, below the peak but "
          "not below the median; neither reading gives the valley and low fuel together")
table.add_typed("second burn's effect on sqrt(J_rho) of u* ('small local peak')", "raises one point",
          f"ratio both burns / first only {second_effect.min():.3f}-{second_effect.max():.3f}", "differs: see note",
          "rerun of u* without its second burn: when tracking starts at the first burn, the second burn (a kink in a "
          "tracked arc) is where the range information comes from, so it lowers sqrt(J_rho) everywhere. Tracking "
          f"24 h before the first burn: {second_effect_pre.min():.2f}-{second_effect_pre.max():.2f} (raised by > 10 % "
          f"in {np.sum(second_effect_pre > 1.1)} of {rows.size} slices); projection reading: "
          f"{second_effect_proj.min():.3f}-{second_effect_proj.max():.3f}. The paper's peak location is not given")
improves_all = all(ga[n]["sig_m"] < 0.5e3 * S.range_sigma_km[0, 0] for n in N_GRID)
table.add_typed("u* improves range knowledge vs no maneuver (covariance analysis, angle reading)", "'significantly improves'",
          f"{np.median(S.informed_range_sigma_km) * 1e3:.1f} m vs {S.range_sigma_km[0, 0] * 1e3:.0f} m",
          "reproduced" if np.median(S.informed_range_sigma_km) < 0.5 * S.range_sigma_km[0, 0] and improves_all
          else "differs: see note",
          "tolerance fixed before comparing: at least a factor 2 at every ring-angle grid of section 5b; any "
          f"maneuver does this in the linear analysis. Grid-dependent: {grid_txt(ga, 'sig_m', '{:.0f}')} m with "
          f"{'/'.join(str(n) for n in N_GRID)} ring angles, tending to the no-maneuver value as the grid is refined")
table.add_typed("u* improves range knowledge vs no maneuver (projection reading)", "'significantly improves'",
          f"{np.median(S_proj.informed_range_sigma_km) * 1e3:.1f} m vs {S.range_sigma_km[0, 0] * 1e3:.0f} m",
          "reproduced" if np.median(S_proj.informed_range_sigma_km) < 0.5 * S.range_sigma_km[0, 0] else "differs: see note",
          f"same tolerance; grid-independent ({grid_txt(gp, 'sig_m', '{:.0f}')} m with "
          f"{'/'.join(str(n) for n in N_GRID)} ring angles); the best maneuver of a slice reaches "
          f"{np.median(S.best_range_sigma_km) * 1e3:.1f} m")
table.add_typed("full filter: NEES at t_f, informed (angle / projection), execution errors", "future work",
          f"{ia['nees']:.2f} / {ipa['nees']:.2f} (band {lo:.1f}-{hi:.1f})", "beyond paper",
          f"iterated EKF, {N_TRIALS} runs; perfect burns: {ip['nees']:.2f} / {ipp['nees']:.2f}")
table.add_typed("full filter: no maneuver (NEES at t_f; RMS range error vs filter 1-sigma)", "future work",
          f"{nm['nees']:.1f}; {nm['rms'] / 1e3:.1f} vs {nm['fsig'] / 1e3:.1f} km", "beyond paper",
          "range nearly unobservable without a maneuver: the iterated EKF diverges (NEES far above the band, error "
          f"larger than the prior's {prior_range_m / 1e3:.1f} km range 1-sigma)")
isml, ispm, usml = summary[(INF, "small")], summary[(INFP, "small")], summary[(UNI, "small")]
table.add_typed("full filter: RMS range error at t_f with 10x smaller execution errors, informed (angle / projection) / "
          "uninformed", "future work", f"{isml['rms']:.0f} / {ispm['rms']:.0f} / {usml['rms']:.0f} m", "beyond paper",
          f"{EXEC_ABS_M_S * 1e2:g} mm/s + {EXEC_REL * 10:g} % per axis; NEES {isml['nees']:.1f} / {ispm['nees']:.1f} / "
          f"{usml['nees']:.1f}")
table.add_typed("full filter: RMS range error at t_f, informed (angle / projection) vs uninformed (exec. errors) vs none",
          "future work", f"{ia['rms']:.0f} / {ipa['rms']:.0f} / {ua['rms']:.0f} / {nm['rms']:.0f} m", "beyond paper",
          f"execution errors {EXEC_ABS_M_S * 1e3:.0f} mm/s + {EXEC_REL * 100:.0f} % per axis; perfect burns: "
          f"informed {ip['rms']:.1f} / {ipp['rms']:.1f} m (covariance analysis {ip['ca']:.1f} / {ipp['ca']:.1f} m), "
          f"uninformed {summary[(UNI, 'perfect')]['rms']:.1f} m; informed/uninformed = {ratio_pu:.2f} / "
          f"{ratio_ppu:.2f}")
print(f"notebook run time so far: {time.perf_counter() - t_start:.0f} s")
table.display()
