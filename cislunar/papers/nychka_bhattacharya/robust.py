r"""Notebook 12's answer to the scheduling-parameter error (Nychka & Bhattacharya §IV-B, Fig. 3; beyond the paper):
LMIs that account for the error of the parameters triangulated from noisy angles, Fig. 3 re-run at the sampling
interval where the paper's H2 number holds with every guarantee drawn, and a small-initial-error run.

The error the LMIs leave out
----------------------------
The observer (Eq. 3a) is scheduled on :math:`\hat\rho`, triangulated from the noisy angles, not on the true
:math:`\rho`.  Subtracting it from the truth :math:`\dot x = A(\rho)x + b(\rho)`, with the measurement
:math:`y = C(\rho)x + d(\rho) + n`, gives exactly (no linearisation)

.. math:: \dot e = \bigl(A(\hat\rho) + LC(\hat\rho)\bigr)e + \delta_f + L(\delta_y + n),\qquad
   \delta_f = \bigl(A(\rho)-A(\hat\rho)\bigr)x + b(\rho)-b(\hat\rho),\quad
   \delta_y = \bigl(C(\rho)-C(\hat\rho)\bigr)x + d(\rho)-d(\hat\rho).

So the nominal guarantee needs two things the paper does not check: :math:`\hat\rho` inside the polytope (the
error matrix is scheduled on it), and no :math:`\delta_f, \delta_y`.  For the planar CR3BP :math:`\delta_f` is the
error of the gravitational acceleration (rows 3-4 only: an unmodelled acceleration, the channel of :math:`B_d`) and
:math:`\delta_y` on the :math:`\theta_1` channels is :math:`(1 - \hat\rho_3 r_{13})[\sin\theta_1, \cos\theta_1]`
(a relative range error entering like sensor noise).

The robust design (widened polytope + the error as exogenous inputs)
--------------------------------------------------------------------
:func:`scheduling_error` samples the orbit, adds angle noise of the simulated size and measures (i) the box that
contains the true :math:`\rho` and a fraction ``coverage`` of the triangulated :math:`\hat\rho` (per parameter), and
(ii) the RMS sizes :math:`s_f = \mathrm{RMS}|\delta_f|`, :math:`s_y = \mathrm{RMS}|\delta_y|` where the observer
triangulates (:math:`|\sin\hat\theta_3| \ge 0.04`).  :func:`robust_designs` solves Theorems 1 and 2 on the vertices
of that box with two more exogenous inputs, :math:`\delta_f` on the velocity rows (level :math:`s_f`) and
:math:`\delta_y` on the :math:`\theta_1` channels (level :math:`s_y`), beside the default disturbance; for H2 the
levels are intensities (:math:`s\sqrt{\Delta t}`, a sample held over :math:`\Delta t`), for H-infinity RMS values.
With the sensor fixed (0.1 deg per sample at :math:`\Delta t`), it finds by bisection the least :math:`\gamma^*` at
which the precision the LMI requires is no more than the sensor's.  Each of the three input groups (noise,
:math:`\delta_f`, :math:`\delta_y`) then has unit normalised size, so the guaranteed RMS position error is
:math:`\sqrt3\,\gamma^*` (H-infinity: the L2 gain with a normalised input of mean square 3; H2: the largest eigenvalue
of the input intensity is at most its trace, 3).  The guarantee is probabilistic in one respect: the box holds a
fraction ``coverage`` of the triangulated parameters, not all (randomised LPV design, the paper's refs. [9], [10]);
:func:`simulate_window` reports the fraction of samples inside it.

Units: LU, TU, deg; planar rotating-frame states ``[x, y, vx, vy]``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.propagation import propagate
from cislunar.estimation import lpv
from cislunar.estimation.observers import make_measurements, simulate_lpv_observer
from cislunar.papers.nychka_bhattacharya.observer_simulation import INITIAL_ERROR, ObserverDesigns, WindowRerun
from cislunar.papers.nychka_bhattacharya.scenarios import (
    GAMMA,
    POLE_RADIUS,
    SIN3_THRESHOLD,
    THETA1_SENSORS,
    Scenario,
)
from cislunar.utils import validation

__all__ = ["SMALL_E0_SCALE", "SchedulingError", "scheduling_error", "RobustDesigns", "robust_designs",
           "parameter_errors", "WindowStudy", "simulate_window"]

#: Scale of :data:`~.observer_simulation.INITIAL_ERROR` of the small-initial-error run (about 109 km, 0.1 m/s).
SMALL_E0_SCALE = 0.01
#: Number of exogenous input groups of the robust design (noise, gravity error, theta1-channel error).
N_GROUPS = 3


def parameter_errors(model: lpv.CR3BPLPV, states, rho_hat) -> tuple:
    r"""The exact inputs :math:`\delta_f` (..., 4) and :math:`\delta_y` (..., 6) that scheduling on ``rho_hat``
    instead of the true :math:`\rho` of ``states`` (..., 4) adds to the error dynamics (module notes); LU/TU^2 and
    sensor units."""
    model = validation.instance(model, "model", lpv.CR3BPLPV)
    x = validation.as_array(states, "states", last=4, min_size=1)
    rh = validation.as_array(rho_hat, "rho_hat", shape=x.shape[:-1] + (6,))
    return _parameter_errors(model, x, rh)


def _parameter_errors(model, x, rh):
    """Kernel of :func:`parameter_errors` (unchecked)."""
    r = model._rho(x)
    dA = model._affine_kernel("A", r) - model._affine_kernel("A", rh)
    dC = model._affine_kernel("C", r) - model._affine_kernel("C", rh)
    df = np.einsum("...ij,...j->...i", dA, x) + model._affine_kernel("b", r) - model._affine_kernel("b", rh)
    dy = np.einsum("...ij,...j->...i", dC, x) + model._affine_kernel("d", r) - model._affine_kernel("d", rh)
    return df, dy


@dataclass(frozen=True)
class SchedulingError:
    """What the triangulation error does along the orbit, from a Monte Carlo over the angle noise.

    Attributes
    ----------
    sigma_deg : float
        Angle noise on each of theta1, theta2, deg.
    coverage : float
        Fraction of the triangulated parameters (per parameter, both tails) the widened box holds.
    box : ParameterBox
        Widened polytope: the orbit's box joined with the ``coverage`` quantiles of the triangulated rho.
    inside : float
        Fraction of the triangulated parameter vectors (all six components at once) inside ``box``.
    triangulated : float
        Fraction of the draws where the observer triangulates (:math:`|\\sin\\hat\\theta_3|` above the threshold).
    s_f, s_y : float
        RMS of :math:`|\\delta_f|` (LU/TU^2) and of :math:`|\\delta_y|` on the theta1 channels, where triangulated.
    rho_rel_rms : ndarray (6,)
        RMS relative error of each triangulated parameter.
    n_draws : int
        Noise draws per orbit sample.
    """

    sigma_deg: float
    coverage: float
    box: lpv.ParameterBox
    inside: float
    triangulated: float
    s_f: float
    s_y: float
    rho_rel_rms: np.ndarray
    n_draws: int


def scheduling_error(scenario: Scenario, sigma_deg: float, n_draws: int, rng: np.random.Generator, *,
                     coverage: float = 0.999, sin3_threshold: float = SIN3_THRESHOLD) -> SchedulingError:
    """Triangulate rho from the orbit's angles plus N(0, ``sigma_deg``^2) noise, ``n_draws`` times per sample of
    ``scenario.states``, and measure the widened box and the RMS inputs of the module notes."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    sigma = np.radians(validation.positive(sigma_deg, "sigma_deg"))
    n_draws = validation.integer(n_draws, "n_draws", minimum=1)
    rng = validation.rng(rng, "rng")
    coverage = validation.in_range(coverage, "coverage", 0.5, 1.0)
    thr = validation.in_range(sin3_threshold, "sin3_threshold", 0.0, 1.0, closed=False)
    m, x = scenario.model, scenario.states
    t1, t2 = m._angles(x)
    noise = rng.standard_normal((n_draws, x.shape[0], 2)) * sigma
    th1, th2 = t1[None] + noise[..., 0], t2[None] + noise[..., 1]
    ok = np.abs(np.sin(th1 + th2)) >= thr
    rh = m._rho_from_angles(th1[ok], th2[ok])
    xs = np.broadcast_to(x, th1.shape + (4,))[ok]
    df, dy = _parameter_errors(m, xs, rh)
    q = 0.5 * (1.0 - coverage)
    lo = np.minimum(scenario.box.lower, np.quantile(rh, q, axis=0))
    hi = np.maximum(scenario.box.upper, np.quantile(rh, 1.0 - q, axis=0))
    box = lpv.ParameterBox(lo, hi, source=f"{scenario.box.source}; widened to {100 * coverage:g} % of rho "
                                          f"triangulated with {sigma_deg:g} deg noise")
    rho = m._rho(xs)
    return SchedulingError(float(sigma_deg), float(coverage), box, float(np.mean(box.contains(rh))), float(ok.mean()),
                           float(np.sqrt(np.mean(np.sum(df**2, axis=-1)))),
                           float(np.sqrt(np.mean(np.sum(dy[:, list(THETA1_SENSORS)] ** 2, axis=-1)))),
                           np.sqrt(np.mean(((rh - rho) / np.where(rho == 0, 1.0, rho)) ** 2, axis=0)), n_draws)


@dataclass(frozen=True)
class RobustDesigns:
    r"""Robust H2 and H-infinity designs (keys ``"h2"``, ``"hinf"``) for a sensor of ``sigma_deg`` sampled every
    ``dt`` TU.

    Attributes
    ----------
    designs : dict of str to ObserverDesign
        The designs at :math:`\gamma^*`.
    gamma_star : dict of str to float
        Least bound (LU) at which the sensor's precision suffices.
    guarantee : dict of str to float
        Guaranteed RMS position error, :math:`\sqrt3\,\gamma^*`, LU.
    kappa_sensor : dict of str to float
        Precision of the sensor in each theorem's sense (H2: :math:`1/(\sin\sigma\sqrt{\Delta t})`; H-infinity:
        :math:`1/\sin\sigma`).
    verification : dict of str to Verification
        Each robust gain checked at the widened box's vertices and random points (Hurwitz, norm).
    box : ParameterBox
        The widened polytope the designs hold on.
    s_f, s_y : float
        RMS sizes of the two scheduling-error inputs (:class:`SchedulingError`).
    dt, sigma_deg : float
    """

    designs: dict
    gamma_star: dict
    guarantee: dict
    kappa_sensor: dict
    verification: dict
    box: lpv.ParameterBox
    s_f: float
    s_y: float
    dt: float
    sigma_deg: float


#: Largest bound (LU) the search for gamma* tries before giving up: a guaranteed RMS position error of an Earth-Moon
#: distance guarantees nothing.  From the default start (4 GAMMA) the search tries 0.0052, 0.021, 0.083, 0.33
#: and 1.33 LU, then stops (five solves, about a second for an infeasible LMI).
_GAMMA_SEARCH_MAX = 1.0


def _least_gamma(lmi, kappa_sensor, lo, hi, iters, why):
    """Bisection (in log gamma) for the least gamma whose required theta1 precision is <= ``kappa_sensor``;
    returns ``(gamma, design)`` at the feasible end.

    The upper end grows fourfold until it is feasible; once it exceeds :data:`_GAMMA_SEARCH_MAX` a ``ValueError``
    says why no gamma works (the LMI infeasible, or the sensor's precision never enough), followed by ``why``
    (the caller's arguments that set the problem)."""
    last = {}

    def ok(g):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                d = lmi.solve(g)
            except lpv.InfeasibleLMIError as exc:
                last["failure"] = f"the {lmi.norm} LMI is infeasible ({exc.status})"
                return None
        need = float(np.max(d.kappa[list(THETA1_SENSORS)]))
        last["failure"] = f"the {lmi.norm} design needs a theta1 precision {need:.4g} > the sensor's {kappa_sensor:.4g}"
        return d if need <= kappa_sensor else None

    d_hi = ok(hi)
    while d_hi is None:
        if hi > _GAMMA_SEARCH_MAX:
            raise ValueError(f"no gamma up to {hi:.3g} LU makes the robust {lmi.norm} design work: at that gamma "
                             f"{last['failure']}; {why}")
        lo, hi = hi, 4.0 * hi
        d_hi = ok(hi)
    for _ in range(iters):
        mid = np.sqrt(lo * hi)
        d = ok(mid)
        if d is None:
            lo = mid
        else:
            hi, d_hi = mid, d
    return float(hi), d_hi


def robust_designs(scenario: Scenario, serr: SchedulingError, dt: float, n_verify: int, rng: np.random.Generator, *,
                   pole_radius: float = POLE_RADIUS, iters: int = 12) -> RobustDesigns:
    """Solve both theorems on ``serr.box`` with the scheduling error as exogenous inputs (module notes) and find the
    least guaranteed bound for the sensor of ``serr.sigma_deg`` sampled every ``dt`` TU (``iters`` bisection steps,
    relative resolution about ``4**(2**-iters)``); verify
    each robust gain at ``n_verify`` random points of the widened box (``rng``)."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    serr = validation.instance(serr, "serr", SchedulingError)
    dt = validation.positive(dt, "dt")
    n_verify = validation.integer(n_verify, "n_verify", minimum=1)
    rng = validation.rng(rng, "rng")
    R = validation.positive(pole_radius, "pole_radius")
    iters = validation.integer(iters, "iters", minimum=1)
    m = scenario.model
    sin_s = np.sin(np.radians(serr.sigma_deg))
    Bd0, Sd0, _ = lpv.default_disturbance()
    kap, found = {}, {}
    # H-infinity first: its bandwidth bound (pole_radius) is what most often makes the problem infeasible, and it
    # then fails before the H2 bisection; the solves are deterministic, so the order changes nothing else
    for norm in ("hinf", "h2"):
        scale = np.sqrt(dt) if norm == "h2" else 1.0
        kap[norm] = float(1.0 / (sin_s * scale))
        Bd = np.zeros((4, 6))
        Bd[:, :2] = Bd0
        Bd[2, 2] = Bd[3, 3] = 1.0
        Dd = np.zeros((6, 6))
        Dd[THETA1_SENSORS[0], 4] = Dd[THETA1_SENSORS[1], 5] = 1.0
        # per-axis levels whose two axes together have the RMS size s (unit normalised mean square per group)
        Sd = np.diag([Sd0[0, 0], Sd0[1, 1]] + [serr.s_f * scale / np.sqrt(2)] * 2 + [serr.s_y * scale / np.sqrt(2)] * 2)
        kw = {"pole_radius": R} if norm == "hinf" else {}
        lmi = lpv.PrecisionLMI.for_cr3bp(m, serr.box.vertices(), norm, disturbance=(Bd, Sd, Dd),
                                         sensors=THETA1_SENSORS, **kw)
        why = (f"check pole_radius={pole_radius!r} (the bandwidth bound; the nominal designs use {POLE_RADIUS:g}), "
               if norm == "hinf" else "check ")
        why += (f"the sensor (serr.sigma_deg={serr.sigma_deg:g} deg sampled every dt={dt:g} TU) and the scheduling "
                f"error of serr (s_f={serr.s_f:.3g}, s_y={serr.s_y:.3g}, box {serr.box.source!r:.80})")
        found[norm] = _least_gamma(lmi, kap[norm], GAMMA, 4 * GAMMA, iters, why)
    designs, g_star, ver = {}, {}, {}
    for norm in ("h2", "hinf"):  # verified in this order (rng)
        g_star[norm], designs[norm] = found[norm]
        ver[norm] = lpv.verify_observer(m, designs[norm], serr.box, n_verify, rng)
    guarantee = {n: float(np.sqrt(N_GROUPS) * g) for n, g in g_star.items()}
    return RobustDesigns(designs, g_star, guarantee, {n: kap[n] for n in designs}, ver, serr.box, serr.s_f, serr.s_y,
                         float(dt), serr.sigma_deg)


@dataclass(frozen=True)
class WindowStudy:
    """Fig. 3 re-run at the sampling interval ``dt``: nominal and robust gains on triangulated rho (and the nominal
    ones on the true rho), from the large and a small initial error.

    Attributes
    ----------
    t : ndarray (m,)
        Times, TU.
    truth : ndarray (m, 4)
    errors : dict of (str, str, str) to ndarray (m,)
        Position error (LU) keyed ``(design, norm, start)``: design ``"nominal"``, ``"nominal, exact rho"`` or
        ``"robust"``; norm ``"h2"``/``"hinf"``; start ``"large"``/``"small"``.
    guarantee : dict of (str, str) to float
        Guaranteed RMS (LU) keyed ``(design, norm)``: nominal (exact rho, :func:`lpv.guaranteed_error_rms`) and
        robust (:math:`\\sqrt3\\gamma^*`).
    posterior : dict of str to float
        Robust bound from the inputs realised in this run, LU (module notes).
    inside : float
        Fraction of samples whose scheduling parameters (triangulated, or the estimate's near the Earth-Moon
        line, robust H2 run) lie in the widened box.
    e0 : dict of str to float
        Initial position errors, LU.
    dt, period : float
    fix_error : ndarray (m,)
        Position error (LU) of the fix triangulated from each sample's two noisy angles alone (law of sines on the
        Earth-Moon baseline; ``nan`` where :math:`|\\sin\\theta_3|` < the triangulation threshold).
    fix_vector : ndarray (m, 2)
        The same as vectors, fix minus truth in the rotating frame (x, y), LU (``nan`` rows as ``fix_error``).
    error_vectors : dict of (str, str, str) to ndarray (m, 2)
        Position error vectors, estimate minus truth (x, y), LU, keyed like ``errors``.
    """

    t: np.ndarray
    truth: np.ndarray
    errors: dict
    guarantee: dict
    posterior: dict
    inside: float
    e0: dict
    dt: float
    period: float
    fix_error: np.ndarray | None = None
    fix_vector: np.ndarray | None = None
    error_vectors: dict | None = None

    def fix_following(self, design: str, norm: str, start: str = "large") -> tuple:
        """How closely a run's error follows the angle-only fix of the sample before, after 10 % of the run.

        A gain with :math:`\\|L\\|\\,\\Delta t \\gg 1` pulls the estimate onto the position the held angles
        triangulate within one interval, so its error at sample k+1 is the fix error of sample k, whatever the
        gain or the initial error.  Returns ``(correlation, rms_ratio)``: the correlation of the run's error at
        k+1 with the fix error at k, and the run's RMS over the fixes' RMS (same samples; fixes near the
        Earth-Moon line left out).
        """
        key = (design, norm, start)
        if key not in self.errors:
            raise ValueError(f"(design, norm, start) must be one of {sorted(self.errors)}; got {key}")
        if self.fix_error is None:
            raise ValueError("this WindowStudy carries no fix_error (built without simulate_window)")
        run, fix = self.errors[key][1:], self.fix_error[:-1]
        keep = self.settled[1:] & np.isfinite(fix)
        run, fix = run[keep], fix[keep]
        return float(np.corrcoef(run, fix)[0, 1]), float(np.sqrt(np.mean(run**2) / np.mean(fix**2)))

    def fix_residual(self, design: str, norm: str, start: str = "large", lag: int = 1) -> float:
        r"""RMS of the vector difference between a run's error at sample k + ``lag`` and the angle-only fix error
        at sample k, after 10 % of the run, LU.

        If the estimate at sample k+1 were the fix of sample k plus an error :math:`d_k` of its own,
        :math:`e_{k+1} = f_k + d_k`, this is :math:`\mathrm{RMS}|d_k|` (``lag=1``); ``lag=0`` compares with the
        fix of the same sample (the contrast).  Samples whose fix is undefined (near the Earth-Moon line) are
        left out.
        """
        key = (design, norm, start)
        if key not in self.errors:
            raise ValueError(f"(design, norm, start) must be one of {sorted(self.errors)}; got {key}")
        lag = validation.integer(lag, "lag", minimum=0)
        if self.fix_vector is None or self.error_vectors is None:
            raise ValueError("this WindowStudy carries no fix_vector/error_vectors (built without simulate_window)")
        m = self.t.size
        if lag >= m:
            raise ValueError(f"lag must be below the number of samples {m}; got {lag}")
        run, fix = self.error_vectors[key][lag:], self.fix_vector[:m - lag]
        keep = self.settled[lag:] & np.all(np.isfinite(fix), axis=-1)
        return float(np.sqrt(np.mean(np.sum((run[keep] - fix[keep]) ** 2, axis=-1))))

    @property
    def settled(self) -> np.ndarray:
        """Samples after the first 10 % of the run."""
        return self.t > 0.1 * (self.t[-1] - self.t[0])

    def rms(self, design: str, norm: str, start: str = "large") -> float:
        """RMS position error after 10 % of the run, LU."""
        key = (design, norm, start)
        if key not in self.errors:
            raise ValueError(f"(design, norm, start) must be one of {sorted(self.errors)}; got {key}")
        return float(np.sqrt(np.mean(self.errors[key][self.settled] ** 2)))

    def as_rerun(self) -> WindowRerun:
        """The nominal runs from the large start as the :class:`WindowRerun` of notebook 12's comparison rows."""
        return WindowRerun(self.dt, int(self.t.size), {n: float(np.median(self.errors[("nominal", n, "large")][
            self.settled])) for n in ("h2", "hinf")})

    def holds(self, design: str, norm: str, start: str = "large") -> bool:
        """Settled RMS within the design's guarantee."""
        return self.rms(design, norm, start) <= self.guarantee[(design.split(",")[0], norm)]


def simulate_window(scenario: Scenario, nominal: ObserverDesigns, robust: RobustDesigns, periods: float,
                    rng: np.random.Generator, *, small_scale: float = SMALL_E0_SCALE) -> WindowStudy:
    """Truth over ``periods`` periods sampled every ``robust.dt`` TU, angles with ``robust.sigma_deg`` noise
    (``rng``), and the runs of :class:`WindowStudy` from ``INITIAL_ERROR`` and ``small_scale`` times it."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    nominal = validation.instance(nominal, "nominal", ObserverDesigns)
    robust = validation.instance(robust, "robust", RobustDesigns)
    periods = validation.positive(periods, "periods")
    rng = validation.rng(rng, "rng")
    small_scale = validation.positive(small_scale, "small_scale")
    m, dt = scenario.model, robust.dt
    t = np.arange(0.0, periods * scenario.orbit.period, dt)
    truth = m.planar(propagate(m.system, scenario.orbit.x0, t).x)
    meas = make_measurements(m, t, truth, robust.sigma_deg, rng)
    starts = {"large": truth[0] + INITIAL_ERROR, "small": truth[0] + small_scale * INITIAL_ERROR}
    errors, vectors, runs = {}, {}, {}
    for start, x0 in starts.items():
        for norm in ("h2", "hinf"):
            gn, gr = nominal.designs[norm].gain(), robust.designs[norm].gain()
            runs[(norm, start)] = simulate_lpv_observer(m, gr, meas, x0, truth)
            for design, run in (("nominal", simulate_lpv_observer(m, gn, meas, x0, truth)),
                                ("nominal, exact rho", simulate_lpv_observer(m, gn, meas, x0, truth, exact_rho=True)),
                                ("robust", runs[(norm, start)])):
                errors[(design, norm, start)] = run.position_error
                vectors[(design, norm, start)] = run.x_hat[:, :2] - truth[:, :2]
    dth = np.angle(np.exp(1j * (meas.theta1 - m._angles(truth)[0])))
    noise_rms = float(np.degrees(np.sqrt(np.mean(dth**2))))
    guarantee = {("nominal", "h2"): lpv.guaranteed_error_rms(nominal.designs["h2"], robust.sigma_deg, dt),
                 ("nominal", "hinf"): lpv.guaranteed_error_rms(nominal.designs["hinf"], noise_rms)}
    guarantee.update({("robust", n): g for n, g in robust.guarantee.items()})
    # inputs realised on the triangulated samples: normalised mean square of each group -> a posteriori bound
    run = runs[("h2", "large")]
    rho_hat = np.where(run.rho_from_estimate[:, None], m._rho(run.x_hat), m._rho_from_angles(
        meas.theta1, meas.theta2, np.where(run.rho_from_estimate, 1.0, np.sin(meas.theta1 + meas.theta2))))
    df, dy = _parameter_errors(m, truth, rho_hat)
    dy1 = dy[:, list(THETA1_SENSORS)]
    ms = (float(np.mean((np.sin(dth) / np.sin(np.radians(robust.sigma_deg))) ** 2))
          + float(np.mean(np.sum(df**2, axis=-1))) / robust.s_f**2 + float(np.mean(np.sum(dy1**2, axis=-1))) / robust.s_y**2)
    posterior = {n: float(g * np.sqrt(ms)) for n, g in robust.gamma_star.items()}
    inside = float(np.mean(robust.box.contains(rho_hat)))
    e0 = {s: float(np.hypot(*(x0 - truth[0])[:2])) for s, x0 in starts.items()}
    s3 = np.sin(meas.theta1 + meas.theta2)
    fixes = m._rho_from_angles(meas.theta1, meas.theta2, np.where(np.abs(s3) < SIN3_THRESHOLD, 1.0, s3))[:, 4:6]
    fix_vector = np.where((np.abs(s3) < SIN3_THRESHOLD)[:, None], np.nan, fixes - truth[:, :2])
    fix_error = np.hypot(*fix_vector.T)
    return WindowStudy(t, truth, errors, guarantee, posterior, inside, e0, float(dt), float(scenario.orbit.period),
                       fix_error, fix_vector, vectors)

