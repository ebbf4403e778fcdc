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
# instead near the Earth-Moon line ($|\sin\theta_3|<0.04$); whether the simulated observers "rapidly converge and
# maintain accurate estimates" by the paper's own yardstick (its error bound $\gamma$); what accuracy the LMIs
# actually *guarantee* for this noise, and why the observers miss it even at the sampling interval where the H2
# design allows exactly the paper's 0.1 deg (the error of the triangulated $\rho$, which the LMIs do not see), and
# what a robust design that treats that error as an input certifies (Section 6, beyond the paper); whether, with no
# range information anywhere in the loop, the observers converge and stay converged (Section 7); and how an
# extended Kalman filter on the same measurements compares (beyond the paper).
#
# **Paper sections followed.** Nychka & Bhattacharya (arXiv 2410.02013) §IV-B, Fig. 3 (a-c) and the text around
# it; observer Eq. 3a and its error dynamics Eq. 5 (Section 6). The methods live in `cislunar.estimation.lpv` and
# `cislunar.estimation.observers`; the chapter's set-ups in `cislunar.papers.nychka_bhattacharya.observer_simulation`
# and, for Section 6, `...robust` (each returns a frozen result), the figures in `...figures` and the claims,
# declared before the runs, in `...claims.observer_simulation`.

# %% [markdown]
# **How to use this chapter.** The next cell (tagged `parameters`) holds everything you might change: the length
# of the simulation, the measurement interval, the angle noise, the size of the initial error and the sample sizes
# of the design. Leave an entry at `None` and the notebook picks it (the values in brackets in the comments: full
# run, and a shorter, coarser one when `QUICK = True`); give a value (edit the cell, or pass `-p NAME=VALUE` to the
# runner) and it is used as given in both modes. The initial-error sweep of Section 4 can run on several processes
# (`WORKERS`) or on a Dask cluster (`SCHEDULER`); its numbers do not depend on where it runs. Numbers quoted in the
# prose are those of a full run with the default parameters; a quick run (half an orbit, coarser sampling) prints
# different ones.
#
# Each section below makes one call to `observer_simulation` (`obs.`), which returns a frozen result, and hands it to
# `readout`, which formats what the section prints and the measurements behind its rows of the closing table;
# `r.judged(CLAIMS)` compares them with the claims declared in `claims.observer_simulation` before any run, so the
# status words are computed from fixed criteria, never typed.

# %% tags=["parameters"]
QUICK = False
SEED = 0  # seed of the verification samples and of the angle noise
OUTPUT_DIR = ""
PERIODS = None  # orbit periods simulated (None: 0.5 quick, 1.0 full)
DT = None  # measurement interval, TU; 0.002 TU is 12.5 min (None: 0.004 quick, 0.002 full)
NOISE_DEG = None  # standard deviation of the angle noise on theta1 and theta2, deg (None: the paper's 0.1)
E0_SCALE = None  # multiplier of the initial estimate error (None: 1, i.e. about 10,900 km and 14 m/s)
N_ORBIT = None  # samples along one period of the orbit that bound rho (None: 600 quick, 4000 full)
N_VERIFY = None  # random interior points of the polytope per gain in the verification (None: 30 quick, 500 full)
N_DRAWS = None  # angle-noise draws per orbit sample measuring the scheduling error of Section 6 (None: 5 quick, 50 full)
N_BISECT = None  # bisection steps for the robust designs' least bound (None: 5 quick, 10 full)
WORKERS = 1  # local processes for the initial-error sweep of Section 4 (1: serial)
SCHEDULER = ""  # address of a Dask scheduler to run that sweep on, e.g. "tcp://10.0.0.5:8786" ("": none)

# %%
import numpy as np

from cislunar.papers.nychka_bhattacharya import figures, readout
from cislunar.papers.nychka_bhattacharya import observer_simulation as obs
from cislunar.papers.nychka_bhattacharya import robust as rb
from cislunar.papers.nychka_bhattacharya.claims.observer_simulation import CLAIMS
from cislunar.papers.nychka_bhattacharya.scenarios import GAMMA, SIGMA_DEG, paper_scenario
from cislunar.publish import plotting
from cislunar.publish.report import ComparisonTable
from cislunar.utils.executors import open_executor

periods = PERIODS if PERIODS is not None else (0.5 if QUICK else 1.0)
dt = DT if DT is not None else (0.004 if QUICK else 0.002)
sigma = NOISE_DEG if NOISE_DEG is not None else SIGMA_DEG
e0_scale = E0_SCALE if E0_SCALE is not None else 1.0
n_orbit = N_ORBIT if N_ORBIT is not None else (600 if QUICK else 4000)
n_verify = N_VERIFY if N_VERIFY is not None else (30 if QUICK else 500)
n_draws = N_DRAWS if N_DRAWS is not None else (5 if QUICK else 50)
n_bisect = N_BISECT if N_BISECT is not None else (5 if QUICK else 10)
workers = WORKERS if WORKERS is not None else 1

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
sc = paper_scenario(n_samples=n_orbit)
od = obs.observer_designs(sc, n_verify, rng)
r = readout.observer_gains(od, GAMMA)
print(r)
_ = table.add(*r.judged(CLAIMS))

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
# sampling intervals of about 90-400 min at disturbance levels up to $10^{-3}$ (81-312 min for accelerations and
# 7-26 min for state perturbations at level $10^{-2}$; notebook 11's windows in its full run, which alone tries
# level $10^{-2}$). At this notebook's sampling interval:

# %%
al = obs.allowance_at(od, dt)
r = readout.allowance_at_dt(al, sigma, sc.model.system)
print(r)
_ = table.add(*r.judged(CLAIMS))

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
sim = obs.simulate_fig3(sc, od, dt, periods, sigma, rng, initial_error=e0_scale * obs.INITIAL_ERROR)
print(readout.measurements(sim, sc))

# %% [markdown]
# ## 4 · "Rapidly converge and maintain accurate estimates": the paper's yardstick, and what the LMIs guarantee
#
# The paper (§IV-B, after Fig. 3): "despite large initial state estimation errors, the observers rapidly converge
# and maintain accurate estimates with 360 arcseconds (0.1°) of noise". Its designs are built for "a user-specified
# bound on the estimation error", $\gamma = 0.0013$ LU (500 km), and 0.1 deg is the noise it finds allowable for that
# bound with H2 (0.08 deg with H-infinity, which therefore flies 1.25 times its allowance: its error "is expected to
# be larger", the paper says). So, from the paper's own words and digits (`claims.observer_simulation` records the
# reasoning):
# * **accurate**: the RMS position error after the first 10 % of the run (the chapter's settling window) at most the
#   accuracy the paper designs for at 0.1 deg: $\gamma$ = 500 km for H2, $1.25\gamma$ = 625 km for H-infinity
#   (`obs.Fig3Accuracy.paper_level`; the error is linear in the noise);
# * **rapidly**: the error first below that level within 5 % of the orbit period, the one timescale Fig. 3 draws
#   (fixed before the first runs), and settled there: its RMS from 5 to 10 % of the period at most the level (an
#   error that only passes through the level on its way down has not converged).
#
# Both are judged at the two sampling intervals this chapter flies (here and in Section 6). The levels do not depend
# on our sampling interval. The theorems' own guarantee for the simulated noise (`lpv.guaranteed_error_rms`) does,
# and it holds only where its assumptions do; it is printed below as a **diagnostic**, not as the paper's claim:
# the error is linear in the normalised noise $\kappa\,\delta\theta$, so
# * H2: steady-state RMS position error $\le \gamma\,\kappa\,\sigma\sqrt{\Delta t}$ (white noise of intensity
#   $\sigma^2\Delta t$; at this notebook's 12.5 min the 0.1 deg noise is a quarter of the H2 allowance, so the
#   guarantee is well below $\gamma$);
# * H-infinity: time-RMS position error $\le \gamma\,\kappa\,\mathrm{RMS}(\delta\theta)$ (L2 gain), up to the decay
#   of the initial error.
#
# Both assume $\rho$ is known exactly, which the paper's set-up does not give (it triangulates $\rho$ from the noisy
# angles); the same runs are therefore repeated scheduling on the true $\rho$, where the guarantee applies. The
# lines below: each guarantee, when the error first falls below it, the RMS after that (first crossing plus 2 % of
# the period) and the RMS on the true $\rho$.

# %%
with open_executor(workers, SCHEDULER) as executor:
    cv = obs.convergence_study(sc, od, sim, sigma, seed=SEED, executor=executor)
print(readout.convergence(cv, sim))

# %% [markdown]
# **What sets the convergence time.** The criterion "within 5 % of a period" was fixed before the runs, but whether
# it can be met depends on an input the paper does not state: the initial error. The error decays no faster than
# the slowest closed-loop pole of $A(\rho)+LC(\rho)$ along the orbit allows, so falling from the initial error to
# the paper's level takes about $\ln(e_0/\text{level})/|\mathrm{Re}\,\lambda|_{\min}$: the method's own prediction.
# Below: that prediction, an H2 run with no noise and exact $\rho$ (so neither noise nor triangulation can be
# blamed), and a sweep of the initial error (the same direction, scaled) on the noisy H2 runs, all against the
# paper's level.

# %%
print(readout.convergence_time(cv, sim))

# %% [markdown]
# ## 5 · Fig. 3 — trajectories and errors
#
# (a), (b): truth (thick grey) and estimate (blue) over the whole orbit; the first 0.3 TU of the estimate (the
# convergence transient from the 10,900 km initial position error) is drawn in orange, and the insets magnify its first
# 0.1 TU. (c)-(e): position error of each observer on a common scale, thin at each sample and thick as a running
# RMS over 0.1 TU, with the design's guaranteed RMS (dashed; the EKF has none) and the first sample below it
# (triangle), $\gamma$ (dotted: the paper's accuracy level for H2; H-infinity's is 1.25 times it) and the first 5 %
# of the period (grey), the window of the convergence criterion.
# The paper draws the errors of both observers in one panel; here each gets its own, because the H-infinity
# error, several times the H2 error after convergence (the medians are in the table), would hide the H2 trace.

# %%
lc = obs.line_crossings(sim, window=0.1)
fig = figures.fig3_observers(sim, cv, lc, sc.model.system, GAMMA, sigma)
_ = plotting.save_figure(fig, "12_fig3_observers", output_dir=out)

# %% [markdown]
# **Reading the result.** Panels (c) and (d) show the two ways the observers miss the criterion (the numbers are
# printed in Section 4 and, for both intervals, in the table after Section 6; full-run numbers here). The H2 error
# falls slowly from the initial 10,900 km and reaches the paper's 500 km only after about a seventh of the period
# (14.6 %; its slowest closed-loop pole predicts 12.9 %, Section 4), so not "rapidly" from this start; afterwards
# it is accurate by the paper's level (RMS 279 km after the first 10 % of the run), though 2.4 times its own
# guarantee (116 km), with bumps well above it. The H-infinity error drops below its level (625 km) almost at once
# but does not stay there (RMS 698 km over 5-10 % of the period), and its running RMS then hovers above the level,
# and above its guarantee, for most of the orbit (RMS 1,355 km). Both LPV observers have a burst of error where the
# spacecraft crosses the Earth-Moon line ($y = 0$, printed below): there the triangulated $\rho$ is singular and
# $\rho(\hat x)$ is used instead. The guarantee assumes exact $\rho$ (the diagnostic runs on the true $\rho$ show
# what it buys), whereas here $\rho$ comes from noisy angles (its error enters $A(\rho)$, $b(\rho)$ and $d(\rho)$,
# and is amplified near the Earth-Moon line), and the noise is held between samples (white noise only in the
# intensity sense). The EKF, which uses both angles as measurements and the full nonlinear model, is the yardstick:
# it has no burst at the line.

# %%
print(readout.line_crossings(lc, sim))

# %% [markdown]
# ## 6 · Fig. 3 where the paper's H2 number holds, with every guarantee drawn
#
# Section 5 judged the observers at this notebook's `DT`. Notebook 11 found the one sampling interval at which the
# H2 design allows exactly the paper's 0.1 deg per sample, $\Delta t_{0.1} = 1/(\kappa_{H2}\sin 0.1°)^2$ (233 min on
# this orbit): there the H2 guarantee is $\gamma$ itself, 500 km. This section re-flies Fig. 3 there and asks what
# went wrong in Section 5: the LMIs certify the error for the *true* $\rho$, but the observer is scheduled on
# $\hat\rho$ triangulated from noisy angles. Subtracting the observer from the truth gives, exactly,
# $$\dot e = \bigl(A(\hat\rho)+LC(\hat\rho)\bigr)e + \delta_f + L(\delta_y + n),\quad
#   \delta_f = (A(\rho)-A(\hat\rho))x + b(\rho)-b(\hat\rho),\quad \delta_y = (C(\rho)-C(\hat\rho))x + d(\rho)-d(\hat\rho),$$
# so the guarantee needs $\hat\rho$ inside the polytope and no $\delta_f, \delta_y$. Here $\delta_f$ is the error
# of the gravitational acceleration (an unmodelled acceleration) and $\delta_y$ on the $\theta_1$ channels is a
# relative range error times $[\sin\theta_1, \cos\theta_1]$ (an extra sensor noise). First, how large are they?
# A Monte Carlo over the angle noise along the orbit (`rb.scheduling_error`) measures them where the observer
# triangulates, and the box that holds 99.9 % of the triangulated values of each parameter.

# %%
se = rb.scheduling_error(sc, sigma, n_draws, rng)
print(readout.scheduling_error(se, sc.model.system))

# %% [markdown]
# **The robust design (beyond the paper).** The gravity error alone is hundreds of times the disturbance the
# nominal design assumes. `rb.robust_designs` re-solves both theorems on the widened box with $\delta_f$ (on the
# velocity rows, RMS size $s_f$) and $\delta_y$ (on the $\theta_1$ channels, size $s_y$) as two more exogenous inputs;
# for H2 their sizes are intensities ($s\sqrt{\Delta t}$), for H-infinity RMS values. Instead of asking for the
# least precision at the paper's $\gamma$ (the sensor is given: 0.1 deg per sample), it finds by bisection the least
# bound $\gamma^*$ at which the sensor is precise enough. Each of the three inputs (noise, $\delta_f$, $\delta_y$)
# then has unit normalised size, so the guaranteed RMS position error is $\sqrt3\,\gamma^*$. The guarantee is
# probabilistic in one respect: the box holds 99.9 % of the triangulated parameters per component, not all of them
# (a randomised LPV design, as in the paper's refs. [9], [10]); the simulation reports how often $\hat\rho$ left it.
# Each robust gain is verified like the nominal ones, on the widened box.

# %%
rd = rb.robust_designs(sc, se, al.dt_01, n_verify, rng, iters=n_bisect)
print(readout.robust_designs(rd, sc.model.system))

# %% [markdown]
# **Fig. 3 at 233 min.** The same truth and noisy angles feed three observers of each kind: the nominal design on
# the triangulated $\hat\rho$ (the paper's set-up), the nominal design on the true $\rho$ (what its LMI certifies)
# and the robust design on $\hat\rho$; each from the large initial error of Section 3 and from one a hundred times
# smaller (about 109 km), so that the steady error and the transient can be told apart. Printed: the RMS error
# after the first 10 % of the run against each design's guarantee (diagnostics, beyond the paper). Then the two
# rows of the paper's claim, "rapidly converge and maintain accurate estimates", judged at both intervals against
# the paper's level (Section 4), from the large start.

# %%
ws = rb.simulate_window(sc, od, rd, periods, np.random.default_rng(SEED + 1))
r = readout.window(ws, rd, od, sc.model.system)
print(r)
_ = plotting.save_figure(figures.fig3_window(ws, sc.model.system), "12_fig3_233min", output_dir=out)
tu_min = sc.model.system.time_unit_s / 60.0
at_dt, at_233 = f"{sim.dt * tu_min:.1f} min", f"{ws.dt * tu_min:.0f} min"
acc = obs.Fig3Accuracy.measure(
    {at_dt: (sim.t, {n: sim.runs[n].position_error for n in od.designs}),
     at_233: (ws.t, {n: ws.errors[("nominal", n, "large")] for n in od.designs})}, cv.level, sim.period,
    reference={at_dt: (sim.t, {n: sim.exact[n].position_error for n in od.designs}),
               at_233: (ws.t, {n: ws.errors[("nominal, exact rho", n, "large")] for n in od.designs})})
_ = table.add(*readout.converges(cv, sim, sc.model.system, acc=acc).judged(CLAIMS))
_ = table.add(*r.judged(CLAIMS))

# %% [markdown]
# **Reading the result.** With the true $\rho$ the nominal observers stay inside their guarantees: the LMIs are
# right about what they certify. With the triangulated $\hat\rho$ the same gains exceed them from either start, so
# the shortfall is the scheduling error, not the transient. Against the paper's own level the picture is the same
# here, since at this interval the H2 level *is* its guarantee (500 km) and the H-infinity level (625 km) is close to
# its guarantee: neither observer is accurate at 233 min with the triangulated $\rho$ (full run: H2 642 km, H-infinity
# 1,499 km), while both are on the true $\rho$ (239 and 488 km). So, by the paper's yardstick (full run), the H2
# observer is accurate at 12.5 min but does not settle "rapidly" from our 10,900 km start at either interval (at
# 12.5 min the sweep of Section 4 settles within 5 % of the period from starts up to 3,262 km; the paper states
# none), and it is not accurate at 233 min; the H-infinity observer drops below its level at once but does not stay
# there, and is accurate at neither interval. Accuracy holds at both intervals where $\rho$ is exact (the "same
# with rho from the truth" row), i.e. where the theorems' assumptions hold: the triangulated $\rho$ is what the
# paper's set-up adds and what its claim does not survive. The robust designs hold their guarantee, but it is
# about ten times the paper's 500 km: with $\theta_1$ and $\theta_2$ at 0.1 deg every 233 min, accounting for the
# error of the scheduling parameters, the LMIs certify several thousand kilometres, and the simulated error lies
# well inside that (the bound is loose: one quadratic Lyapunov function over the widened box, and an RMS gravity
# error dominated by the few samples near perigee).
#
# **Why both H-infinity runs print the same RMS from both starts.** The H-infinity gains are large: $\|L\|\,\Delta t$
# is about thirty at 233 min (the row's note below), so within one interval the estimate is pulled onto the
# position that the held pair of angles triangulates, and its error at each sample is the error of the angle-only
# fix of the sample before (`WindowStudy.fix_following`: correlation and RMS ratio printed above, row "Hinf at
# 233 min" below).
# Neither the gain's details (nominal or robust) nor the initial error matter then: at this interval the
# H-infinity observer is an angle-only triangulator, and its RMS is close to the fixes' RMS (the RMS ratio above),
# not its LMI's. The row
# "Hinf at 233 min" tests exactly that model, $e_{k+1} = f_k + d_k$ (error vector at sample $k+1$ = the fix's error
# vector at sample $k$ plus an error of the observer's own): it holds when the RMS of $d_k = e_{k+1} - f_k$ is no
# larger than the nominal H-infinity guarantee, the size the LMI certifies for the observer's own error (a limit
# fixed from the model, not from a run: `WindowStudy.fix_residual`, printed above next to the same sample's fix for
# contrast; in fairness, the residual itself was looked at while choosing what to measure, as the claim's comment in
# `claims.observer_simulation` records).
#
# ## 7 · "The observers can function without range sensors"
#
# The paper's sentence after Fig. 3 makes two claims: "The results in Fig.3 confirm that the H2 and H-infinity
# observers can function without range sensors. *Additionally*, despite large initial state estimation errors, the
# observers rapidly converge and maintain accurate estimates". The second, accuracy, is judged by the H2 and
# H-infinity rows above against the paper's own level. The first is what is specific to dropping the range sensors:
# with no range information anywhere in the loop (the gains' columns for $r_{13}^2$, $r_{23}^2$ are zero, and $\rho$ is
# triangulated from $\theta_1$, $\theta_2$ alone) does the observer still *work*, i.e. converge from the large
# initial error and stay there rather than lose the spacecraft? The criterion, fixed before this statistic was
# looked at (`claims.observer_simulation` records what had been seen): for both observers at both sampling
# intervals, the largest position error after the first 10 % of the run stays below the initial position error. It
# is judged on the worst sample, not an average, so a single excursion back to the starting error (near the
# Earth-Moon line, where $\rho$ comes from the estimate) fails it. For contrast, the same observers scheduled on
# the true $\rho$ (what a range sensor would add to the scheduling) are printed beside them.

# %%
err = {at_dt: (sim.t, {n: sim.runs[n].position_error for n in od.designs}),
       at_233: (ws.t, {n: ws.errors[("nominal", n, "large")] for n in od.designs})}
ref = {at_dt: (sim.t, {n: sim.exact[n].position_error for n in od.designs}),
       at_233: (ws.t, {n: ws.errors[("nominal, exact rho", n, "large")] for n in od.designs})}
rf = obs.RangeFree.measure(od, err, reference=ref)
km = sc.model.system.length_unit_km
print(rf.text(km))
print("Earth-Moon line crossings (rho from the estimate) begin at t =", ", ".join(f"{t0:.3f}" for t0 in lc.starts), "TU")
held = [lab for lab in err if all(rf.bounded(lab, n) for n in od.designs)]
where = (f"; holds at {', '.join(held)}" if held else "") + (
    f"; the bound is our initial error: a start above {max(rf.peak.values()) * km:,.0f} km would lift it over the "
    "excursions, which come long after the start's transient; the paper states neither the interval nor the initial "
    "error")
_ = table.add(CLAIMS["no_range"].judge(
    rf.holds, shown=rf.shown(),
    note=f"only theta1, theta2 measured; initial error {sim.initial_error * km:,.0f} km; accuracy (the paper's "
         "level gamma) is the separate claim of the H2 / Hinf rows (Fig. 3's 'Additionally'); the gain columns are "
         "zero by construction here (notebook 11's free optimum drops the range sensors)",
    reason=(rf.why(km) + ": rho triangulated from the angles near the Earth-Moon line" + where) if not rf.holds else ""))

# %% [markdown]
# **Reading the result** (full run; the quick run's half orbit ends at the first line crossing after settling and
# prints different numbers). The H2 observer stays far below its starting error at both intervals (at most 0.15 and
# 0.26 of it). The H-infinity observer at 12.5 min does not: where the spacecraft crosses the Earth-Moon line (the
# crossings printed above; its largest error comes at the one at the end of the run, and it also passes its initial
# error at the one half-way) its error comes back to about 22,900 km, twice the initial 10,900 km, while the same
# gain scheduled on the true $\rho$ (what a range sensor would supply) stays within about 1,400 km. Its large gain
# follows the noisy angles closely, and just outside $|\sin\theta_3| < 0.04$ the triangulation is still poorly
# conditioned: 0.1 deg on each angle moves $\theta_3 \approx 2.3°$ by about 0.14 deg, a range error of about 6 %.
# So without range sensors both observers converge, but one of them loses the spacecraft again at the line
# crossings of this run, and the row differs. It would pass at 233 min, or with a starting error larger than the
# excursion (our 10,900 km is a choice: the paper says only "large initial state estimation errors").

# %% [markdown]
# The error comparison of Fig. 3c at both intervals, with the nominal runs above:

# %%
r = readout.comparison(sim, ws.as_rerun(), od, al, sigma)
print(r)
_ = table.add(*r.judged(CLAIMS))

# %%
table.display()

# %% [markdown]
# ## Exercises
#
# Each exercise changes one entry of the `parameters` cell. Predict first, then rerun (quick mode is enough:
# `-p QUICK=True -p NAME=VALUE`) and compare. The worked solutions are functions of
# `cislunar.papers.nychka_bhattacharya.exercises`; each flies a short version of the experiment in a few seconds and
# returns the numbers together with an `answer` paragraph.
#
# 1. **Double the noise.** Set `NOISE_DEG = 0.2`. Section 4 says the guaranteed RMS is linear in the noise: predict
#    both guarantees, and the RMS error once the initial error has decayed. Does the convergence row get better or
#    worse, and why can a *noisier* sensor make the error reach its guarantee *sooner*? Worked solution:
#    `exercise_12_noise(factor=2.0)`.
# 2. **Start closer.** Set `E0_SCALE = 0.1` (an initial error of about 1,090 km). Using the slowest closed-loop pole
#    printed in Section 4, predict how much earlier the H2 error first falls below a fixed level (the shift,
#    $\ln(1/0.1)/$decay, does not depend on the level; the worked solution uses the guarantee), and whether the
#    `h2_converges` row's 5 % part can then be met at 12.5 min. Worked solution:
#    `exercise_12_initial_error(scale=0.1)`.
# 3. **Sample twice as often.** Set `DT` to half its value. Predict the H2 allowance per sample printed in
#    Section 2 (it scales like $1/\sqrt{\Delta t}$), the H2 guarantee (like $\sqrt{\Delta t}$) and the H-infinity
#    allowance (unchanged: it bounds the noise energy, not a per-sample spread). Worked solution:
#    `exercise_12_interval(factor=0.5)`.
