r"""Maneuver detection with the OCBE control-policy integral (Greaves & Scheeres 2021, §Maneuver Detection).

Pieces, in the order of the paper:

* **Station-keeping policy** (Eqs. 3-5).  An impulse at apoapsis with azimuth :math:`u_\theta\sim\mathcal
  U[-\pi,\pi]`, elevation :math:`u_\psi\sim\mathcal U[-\pi/2,\pi/2]` and magnitude from a Gaussian
  :math:`\mathcal N(\mu_u,\sigma_u)` truncated to :math:`\mu_u\pm3\sigma_u`.  The direction is
  :math:`(\cos u_\psi\cos u_\theta,\ \cos u_\psi\sin u_\theta,\ \sin u_\psi)` in the rotating frame.  Drawing the
  elevation uniformly is what the paper writes; it is *not* uniform on the sphere (the density of directions is
  higher near the poles :math:`\pm\hat k`; a uniform sphere would need :math:`\sin u_\psi\sim\mathcal U[-1,1]`).
  Active ("noisy") policy: 1 m/s +- 0.3 m/s; quiet policy: 50 mm/s +- 15 mm/s (Table 2).
* **Monte Carlo trial**: truth from periapsis over one period with the impulse at the first apoapsis, angle and
  angle-rate measurements from the L2 observer every 2 hours, a hand-off error drawn from the Earth-radar
  covariance, the SRI OCBE (:func:`cislunar.estimation.ocbe.ocbe_filter_smoother`) with control weight raised in an 8-hour
  window around apoapsis, and the test statistic :math:`z = \int\|\hat{\mathbf u}\|dt` (Eq. 33) of the *smoothed*
  control (the spike "appears only in the smoothed system", Figs. 10-13).
* **Batched OCBE** (:func:`ocbe_batch`): the same filter and smoother for ``B`` trials in lockstep, heyoka batch
  integrators for the transitions and stacked numpy QR/Cholesky for the square-root-information algebra.  It
  integrates only the three non-zero 6x6 blocks of the transition (:func:`cislunar.estimation.ocbe.block_integrator`,
  about four times cheaper than the full 12x12 variational system) and equals the single-trial filter to round-off
  (``tests/estimation/test_batched_ocbe.py``, ``tests/papers/greaves_scheeres_2021/test_detection.py``);
  :func:`run_detection_monte_carlo` runs several batches per lockstep call (``benchmarks/bench_detection.py``).
  Every Monte Carlo trial also records the NEES of its forward and smoothed estimates against its truth, so each
  training or test set doubles as a consistency check of the tuning (:attr:`MonteCarloSample.inconsistent_runs`).
* **Hypothesis test** (Eqs. 34-35): Gaussian kernel density estimates of :math:`z` under :math:`\mathcal H_0`
  (no maneuver) and :math:`\mathcal H_1` (maneuver), the threshold :math:`z_{lim}` where the two PDFs cross,
  false-positive rate :math:`\int_{z_{lim}}^\infty PDF_{\mathcal H_0}` and missed-detection rate
  :math:`\int_{-\infty}^{z_{lim}} PDF_{\mathcal H_1}`, and accuracy on independent test sets.
* **Studies beyond the paper's runs**: the control integral of burns in chosen directions, at a chosen time in the
  window (:func:`direction_response`, the conditions of the paper's :math:`\pm\hat j` pattern, Fig. 16), and the
  "health metric" race between the control integral and the measurement residuals after an unexpected burn
  (:func:`health_lead_study`, Fig. 22; the smoothed control integral of every growing data arc from one forward
  filter pass, ``smooth_ends`` of :func:`ocbe_batch`).

Units: maneuver magnitudes and :math:`z` in m/s in all results; control weights given in km^2/s^3 (acceleration
power spectral density) and converted to LU^2/TU^3 for the filter; angles in rad.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.orbits import PeriodicOrbit
from cislunar.cr3bp.propagation import DEFAULT_TOL, _check_tol, propagate
from cislunar.estimation import batched_ocbe, ocbe
from cislunar.estimation.batched_ocbe import BatchOCBEResult, ocbe_batch
from cislunar.estimation.consistency import _nees, nees_limit
from cislunar.papers.greaves_scheeres_2021 import tracking
from cislunar.sensing import measurements
from cislunar.utils import validation
from cislunar.utils.montecarlo import (
    MonteCarloError,
    TrialFailure,
    map_tasks,
    run_monte_carlo,
)

__all__ = [
    "StationKeepingPolicy",
    "ACTIVE_POLICY",
    "QUIET_POLICY",
    "pointing_vector",
    "window_control_weight",
    "DetectionSetup",
    "make_setup",
    "TrialInputs",
    "TrialResult",
    "MonteCarloSample",
    "draw_trial",
    "draw_trials",
    "run_trial_filter",
    "detection_trial",
    "detection_trial_batch",
    "run_detection_monte_carlo",
    "run_detection_monte_carlos",
    "fit_pdf",
    "pdf_crossings",
    "error_rates",
    "DetectionThreshold",
    "ml_threshold",
    "threshold_bootstrap",
    "decide",
    "DetectionScore",
    "detection_accuracy",
    "PolicyStudy",
    "run_policy_study",
    "run_policy_studies",
    "filter_trials",
    "filter_trial_sets",
    "control_spike_contrast",
    "azimuth_contrast",
    "direction_response",
    "direction_trials",
    "HealthLeadStudy",
    "health_lead_study",
]

# ---------------------------------------------------------------------------------------------------------------
# Station-keeping policy (Eqs. 3-5, Table 2)
# ---------------------------------------------------------------------------------------------------------------


def _size(size):
    """``None``, a non-negative int or a tuple of them (numpy's ``size`` argument)."""
    if size is None:
        return None
    if isinstance(size, tuple):
        return tuple(validation.integer(v, "size", minimum=0) for v in size)
    return validation.integer(size, "size", minimum=0)


def _check_policy(policy, name: str = "policy", *, optional: bool = False):
    if policy is None and optional:
        return None
    return validation.instance(policy, name, StationKeepingPolicy,
                            "a cislunar.papers.greaves_scheeres_2021.detection.StationKeepingPolicy" + (" or None" if optional else ""))


def _check_setup(setup, name: str = "setup"):
    return validation.instance(setup, name, DetectionSetup, "a cislunar.papers.greaves_scheeres_2021.detection.DetectionSetup (make_setup)")


@functools.lru_cache(maxsize=32)
def _truncnorm(n_sigma: float, mean: float, sd: float):
    """Frozen truncated Gaussian, built once per parameter set (freezing costs more than a draw)."""
    return stats.truncnorm(-n_sigma, n_sigma, loc=mean, scale=sd)


@dataclass(frozen=True)
class StationKeepingPolicy:
    """Randomly pointed apoapsis impulse with a truncated-Gaussian magnitude (Eqs. 3-5).

    Parameters
    ----------
    name : str
        Label for plots and tables.
    mean_m_s : float
        :math:`\\mu_u`, mean magnitude of the untruncated Gaussian, m/s.
    sd_m_s : float
        :math:`\\sigma_u`, its standard deviation, m/s.
    n_sigma : float
        Truncation half-width in units of :math:`\\sigma_u` (3 in the paper).
    """

    name: str
    mean_m_s: float
    sd_m_s: float
    n_sigma: float = 3.0

    def __post_init__(self):
        if not isinstance(self.name, str):
            raise validation.ArgumentTypeError(f"name must be a str; got {type(self.name).__name__}")
        validation.positive(self.mean_m_s, "mean_m_s")
        validation.positive(self.sd_m_s, "sd_m_s")
        validation.positive(self.n_sigma, "n_sigma")
        if self.mean_m_s - self.n_sigma * self.sd_m_s < 0:
            raise ValueError("mean_m_s - n_sigma * sd_m_s must be non-negative (magnitudes cannot be negative)")

    @property
    def magnitude_distribution(self):
        """Frozen :class:`scipy.stats.truncnorm` of the magnitude, m/s (Eq. 5); shared by equal policies."""
        return _truncnorm(float(self.n_sigma), float(self.mean_m_s), float(self.sd_m_s))

    def sample_magnitude(self, rng: np.random.Generator, size=None) -> np.ndarray:
        """Magnitudes (m/s) drawn from the truncated Gaussian with the caller's generator."""
        validation.rng(rng)
        size = _size(size)
        return self.magnitude_distribution.rvs(size=size, random_state=rng)

    @staticmethod
    def sample_pointing(rng: np.random.Generator, size=None) -> tuple[np.ndarray, np.ndarray]:
        """Azimuth :math:`\\mathcal U[-\\pi,\\pi]` and elevation :math:`\\mathcal U[-\\pi/2,\\pi/2]` (Eqs. 3-4), rad."""
        validation.rng(rng)
        size = _size(size)
        return rng.uniform(-np.pi, np.pi, size), rng.uniform(-np.pi / 2, np.pi / 2, size)

    def sample(self, rng: np.random.Generator, size=None):
        """``(magnitude_m_s, azimuth_rad, elevation_rad)``: magnitude first, then pointing."""
        mag = self.sample_magnitude(rng, size)
        az, el = self.sample_pointing(rng, size)
        return mag, az, el

    def second_moment_m2_s2(self) -> float:
        """:math:`E[u_{mag}^2]` of the truncated Gaussian, (m/s)^2."""
        d = self.magnitude_distribution
        return float(d.var() + d.mean() ** 2)


#: Active ("noisy") station keeping: 1 m/s mean, 0.3 m/s standard deviation (Table 2).
ACTIVE_POLICY = StationKeepingPolicy("active", 1.0, 0.3)
#: Quiet station keeping: 50 mm/s mean, 15 mm/s standard deviation (Table 2).
QUIET_POLICY = StationKeepingPolicy("quiet", 0.05, 0.015)


def pointing_vector(azimuth, elevation) -> np.ndarray:
    """Unit vector(s) :math:`(\\cos\\psi\\cos\\theta, \\cos\\psi\\sin\\theta, \\sin\\psi)` in the rotating frame.

    Parameters
    ----------
    azimuth, elevation : array_like
        Angles in rad (broadcast together).

    Returns
    -------
    ndarray, shape (..., 3)
    """
    th = validation.as_array(azimuth, "azimuth")
    ps = validation.as_array(elevation, "elevation")
    return np.stack(np.broadcast_arrays(np.cos(ps) * np.cos(th), np.cos(ps) * np.sin(th), np.sin(ps)), axis=-1)


def window_control_weight(policy: StationKeepingPolicy, window_hours: float = 8.0) -> float:
    """Control weight (km^2/s^3) that makes white-noise acceleration over the window match the policy's impulse.

    White acceleration noise of power spectral density :math:`q` accumulates a velocity variance :math:`qT` per
    axis over a window of length :math:`T`.  Setting it equal to the per-axis second moment of the impulse,
    :math:`E[u_{mag}^2]/3`, gives :math:`q = E[u_{mag}^2]/(3T)`.  The paper does not give its tuning values; this
    is our documented choice.

    Parameters
    ----------
    policy : StationKeepingPolicy
    window_hours : float
        Window length, hours (8 in the paper).
    """
    _check_policy(policy)
    T = validation.positive(window_hours, "window_hours") * 3600.0
    return policy.second_moment_m2_s2() * 1e-6 / (3.0 * T)


# ---------------------------------------------------------------------------------------------------------------
# Scenario and trials
# ---------------------------------------------------------------------------------------------------------------


def _km2_s3_to_nd(system: CR3BP, q_km2_s3: float) -> float:
    """Acceleration PSD km^2/s^3 -> LU^2/TU^3."""
    return q_km2_s3 * system.time_unit_s**3 / system.length_unit_km**2


@dataclass(frozen=True)
class DetectionSetup:
    """Everything fixed across the trials of one Monte Carlo (picklable).

    Attributes
    ----------
    scenario : TrackingScenario
        Track from periapsis, measurement epochs, observer, measurement model and noise.
    control_weight : ndarray, shape (N-1,)
        Per-interval OCBE control weight :math:`q_n`, LU^2/TU^3.
    t_maneuver : float
        Time of the station-keeping impulse (first apoapsis of the track), TU.
    q_base_km2_s3, q_window_km2_s3 : float
        The tuning in km^2/s^3 (outside / inside the apoapsis window).
    window_hours : float
        Window length, hours.
    n_sub : int
        Sub-grid points per interval for the control integral.
    tol : float
        Integrator tolerance.
    """

    scenario: tracking.TrackingScenario
    control_weight: np.ndarray
    t_maneuver: float
    q_base_km2_s3: float
    q_window_km2_s3: float
    window_hours: float
    n_sub: int = 9
    tol: float = DEFAULT_TOL

    @property
    def system(self) -> CR3BP:
        return self.scenario.system

    @property
    def observer_states(self) -> np.ndarray:
        """The single (L2) observer's state at each epoch, shape (N, 6)."""
        obs = self.scenario.observers
        return obs[:, 0] if obs.ndim == 3 else obs


def make_setup(system: CR3BP, orbit: PeriodicOrbit, q_window_km2_s3: float, q_base_km2_s3: float, *,
               cadence_hours: float = 2.0, window_hours: float = 8.0, periods: float = 1.0, n_sub: int = 9,
               tol: float = DEFAULT_TOL, sigma_angle_rad: float = tracking.DEFAULT_SIGMA_ANGLE_RAD) -> DetectionSetup:
    """Detection scenario of the paper: hand-off at periapsis, one period, L2 observer, apoapsis tuning window.

    Parameters
    ----------
    system : CR3BP
    orbit : PeriodicOrbit
        Target reference orbit (9:2 NRHO or the stable NRHO).
    q_window_km2_s3, q_base_km2_s3 : float
        OCBE control weights inside and outside the window around apoapsis, km^2/s^3.  A constant tuning is
        ``q_window == q_base``.
    cadence_hours : float
        Measurement cadence (2 h in the paper).
    window_hours : float
        Length of the raised-uncertainty window centred on apoapsis (8 h in the paper).
    periods : float
        Track length in periods (must contain an apoapsis; the track starts at periapsis).
    n_sub : int
        Points per interval for the control evaluation.
    tol : float
        Integrator tolerance.
    sigma_angle_rad : float
        Angular noise (1 sigma), rad.
    """
    check_system(system)
    validation.instance(orbit, "orbit", PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit")
    qw = validation.positive(q_window_km2_s3, "q_window_km2_s3")
    qb = validation.positive(q_base_km2_s3, "q_base_km2_s3")
    wh = validation.positive(window_hours, "window_hours")
    n_sub = validation.integer(n_sub, "n_sub", minimum=2)
    tol = _check_tol(tol)
    sc = tracking.make_scenario(system, orbit, cadence_hours, start="periapsis", periods=periods,
                                sigma_angle_rad=sigma_angle_rad)
    if sc.t_apoapsis.size == 0:
        raise ValueError("periods must be long enough for the track to contain an apoapsis")
    if np.ndim(sc.observers) == 3 and sc.observers.shape[1] != 1:
        raise ValueError("the detection scenario uses the single L2 observer")
    if not np.all(getattr(sc, "available", True)):
        raise ValueError("the L2 observer must see the target at every epoch")
    return _retuned(sc, qw, qb, wh, int(n_sub), tol)


def _retuned(sc, qw, qb, wh, n_sub, tol) -> DetectionSetup:
    """The setup of :func:`make_setup` on an already built (and checked) scenario ``sc``: only the tuning (window
    and base weights in km^2/s^3, window length in hours) is new; unchecked.  Studies that tune one track many ways
    (:mod:`cislunar.papers.greaves_scheeres_2021.detection_studies`) build the scenario once through it."""
    q = tracking.apoapsis_window_weights(sc.t, sc.t_apoapsis[:1], _km2_s3_to_nd(sc.system, qb),
                                         _km2_s3_to_nd(sc.system, qw), wh, sc.system)
    return DetectionSetup(sc, q, float(sc.t_apoapsis[0]), qb, qw, wh, n_sub, tol)


@dataclass(frozen=True)
class TrialInputs:
    """Random inputs of one trial and the resulting truth and data.

    Attributes
    ----------
    magnitude_m_s, azimuth, elevation : float
        Maneuver parameters (magnitude 0 and angles NaN when there is no maneuver), m/s and rad.
    truth : ndarray, shape (N, 6)
        True states at the measurement epochs.
    y : ndarray, shape (N, m)
        Measurements.
    x0, P0 : ndarray
        Hand-off estimate (6,) and its covariance (6, 6).
    """

    magnitude_m_s: float
    azimuth: float
    elevation: float
    truth: np.ndarray
    y: np.ndarray
    x0: np.ndarray
    P0: np.ndarray


@dataclass(frozen=True)
class TrialResult:
    """Output of one detection trial: the test statistic and the maneuver that produced it.

    Attributes
    ----------
    z_m_s : float
        Eq. 33 on the smoothed control, m/s.
    z_step_m_s : float
        Eq. 33 on the single-step-smoothed (forward) control, m/s.
    magnitude_m_s, azimuth, elevation : float
        Maneuver parameters (0 and NaN without a maneuver), m/s and rad.
    nees_over_fwd, nees_over_smooth : float
        Fraction of epochs whose NEES (6 dof, forward / smoothed estimate against the truth) exceeds its
        :data:`cislunar.estimation.consistency.NEES_PROBABILITY` chi-square quantile; the run is inconsistent when it is above
        :data:`cislunar.papers.greaves_scheeres_2021.tracking.DIVERGED_FRACTION` (notebook 09's criterion).
    nees_mean_fwd, nees_mean_smooth : float
        Mean NEES over the epochs (6 for a consistent filter).
    """

    z_m_s: float
    z_step_m_s: float
    magnitude_m_s: float
    azimuth: float
    elevation: float
    nees_over_fwd: float = np.nan
    nees_over_smooth: float = np.nan
    nees_mean_fwd: float = np.nan
    nees_mean_smooth: float = np.nan


def draw_trial(rng: np.random.Generator, setup: DetectionSetup, policy: StationKeepingPolicy | None = None, *,
               magnitude_m_s: float | None = None, direction=None, burn_offset_hours: float = 0.0) -> TrialInputs:
    """Draw one trial: maneuver (if any), truth, measurements, hand-off estimate, in that order.

    Parameters
    ----------
    rng : numpy.random.Generator
    setup : DetectionSetup
    policy : StationKeepingPolicy or None
        ``None``: no maneuver (hypothesis H0).
    magnitude_m_s : float, optional
        Override the drawn magnitude (the pointing is still drawn unless ``direction`` is given), m/s.
    direction : array_like (2,), optional
        ``(azimuth, elevation)`` in rad overriding the drawn pointing.
    burn_offset_hours : float
        Time of the burn after the apoapsis (``setup.t_maneuver``), hours; the tuning window stays where it is.
        The burn must fall strictly inside the track.  The draws do not depend on it.
    """
    validation.rng(rng)
    return draw_trials([rng], setup, policy, magnitude_m_s=magnitude_m_s, direction=direction,
                       burn_offset_hours=burn_offset_hours)[0]


def draw_trials(rngs, setup: DetectionSetup, policy: StationKeepingPolicy | None = None, *,
                magnitude_m_s: float | None = None, direction=None, burn_offset_hours: float = 0.0) -> list:
    """:func:`draw_trial` for several generators at once (one trial per generator, the same draws).

    Each generator is consumed exactly as by :func:`draw_trial` (magnitude, pointing, measurement noise, hand-off
    error, in that order), so trial ``b`` equals ``draw_trial(rngs[b], ...)``: the random numbers bit for bit, the
    truth to round-off.  What is shared: the magnitudes come from one vectorised inverse CDF of the truncated
    Gaussian (the algorithm of :meth:`scipy.stats.rv_continuous.rvs`, bit-identical), the arc before the burn is
    propagated once, the arcs after it in one batched (SIMD) propagation, and the measurements in one call.

    Parameters
    ----------
    rngs : sequence of numpy.random.Generator
    setup, policy, magnitude_m_s, direction, burn_offset_hours
        As in :func:`draw_trial`, the same for every trial.

    Returns
    -------
    list of TrialInputs
        One per generator, in order.
    """
    try:
        rngs = list(rngs)
    except TypeError:
        raise validation.ArgumentTypeError(f"rngs must be a sequence of numpy.random.Generator; got "
                                           f"{type(rngs).__name__}") from None
    if not rngs:
        raise ValueError("rngs must hold at least one generator")
    for r in rngs:
        validation.rng(r, "rngs")
    _check_setup(setup)
    _check_policy(policy, optional=True)
    em, sc = setup.system, setup.scenario
    t_burn = setup.t_maneuver + validation.real(burn_offset_hours, "burn_offset_hours") * 3600.0 / em.time_unit_s
    if not sc.t[0] < t_burn < sc.t[-1]:
        raise ValueError(f"burn_offset_hours puts the burn outside the track; got {burn_offset_hours!r}")
    if magnitude_m_s is not None:
        magnitude_m_s = validation.positive(magnitude_m_s, "magnitude_m_s", allow_zero=True)
    if direction is not None:
        direction = validation.as_array(direction, "direction", shape=(2,))
        if policy is None and magnitude_m_s is None:
            raise ValueError("direction is given but no burn is drawn (policy and magnitude_m_s are None), so it would "
                             "be ignored: pass a policy or magnitude_m_s, or leave direction None")
    return _draw_trials(rngs, setup, policy, magnitude_m_s, direction, t_burn)


def _draw_trials(rngs, setup, policy, magnitude_m_s, direction, t_burn) -> list:
    """:func:`draw_trials` after its checks (``t_burn`` in TU inside the track)."""
    em, sc = setup.system, setup.scenario
    B, t = len(rngs), sc.t
    maneuver = policy is not None or magnitude_m_s is not None
    y_shape = np.broadcast_shapes(sc.observers.shape[:-1], (t.size, 1)) + (sc.model.dim,)  # simulate_measurements
    u, az, el = np.empty(B), np.full(B, np.nan), np.full(B, np.nan)
    noise, e0 = np.empty((B,) + y_shape), np.empty((B, 6))
    for b, rng in enumerate(rngs):  # every generator in the order of draw_trial's calls
        if maneuver:
            if policy is not None:
                u[b] = rng.uniform()  # scipy's rvs: the inverse CDF of one uniform draw
            az[b], el[b] = rng.uniform(-np.pi, np.pi), rng.uniform(-np.pi / 2, np.pi / 2)  # Eqs. 3-4
        noise[b] = rng.standard_normal(y_shape)  # tracking.simulate_measurements
        e0[b] = rng.standard_normal(6)  # tracking.initial_estimate
    mag = np.zeros(B)
    if maneuver:
        if policy is not None:
            mag = policy.magnitude_distribution.ppf(u)  # Eq. 5, as StationKeepingPolicy.sample_magnitude
        if magnitude_m_s is not None:
            mag = np.full(B, magnitude_m_s)
        if direction is not None:
            az, el = np.full(B, direction[0]), np.full(B, direction[1])
    truth = _truths(setup, t_burn, pointing_vector(az, el) * mag[:, None] * 1e-3 / em.velocity_unit_km_s
                    if maneuver else None)
    y = _measurements(sc, truth, noise)
    y = y[:, :, 0] if y.ndim == 4 else y  # one observer
    truth = np.broadcast_to(truth, (B,) + truth.shape[1:])  # without a burn one truth serves every trial (read-only)
    sp = em.km_to_lu(tracking.HANDOFF_3SIGMA_KM / 3.0)  # tracking.initial_estimate
    sv = tracking.HANDOFF_3SIGMA_KM_S / 3.0 / em.velocity_unit_km_s
    P0 = np.diag(np.r_[np.full(3, sp**2), np.full(3, sv**2)])
    x0 = truth[:, 0] + e0 * np.sqrt(np.diag(P0))
    return [TrialInputs(float(mag[b]), float(az[b]), float(el[b]), truth[b], y[b], x0[b], P0.copy())
            for b in range(B)]


def _truths(setup, t_burn, dv) -> np.ndarray:
    """True states (B, N, 6) of :func:`tracking.simulate_truth` with one impulse ``dv`` (B, 3) at ``t_burn`` (or
    none: ``dv=None``, one truth (1, N, 6) for every trial): the arc before the burn is propagated once, the arcs
    after it together (batched)."""
    em, sc = setup.system, setup.scenario
    t = sc.t
    if dv is None:
        return tracking.simulate_truth(em, sc.x_start, t)[None]
    B = dv.shape[0]
    j = int(np.searchsorted(t, t_burn, side="right"))  # epochs up to and including the burn see the first arc
    out = np.empty((B, t.size, 6))
    out[:, :j] = propagate(em, sc.x_start, t[:j]).x if j > 1 else sc.x_start
    x_burn = propagate(em, sc.x_start, [t[0], t_burn]).x[-1]
    after = np.repeat(x_burn[None], B, axis=0)
    after[:, 3:] += dv
    out[:, j:] = propagate(em, after if B > 1 else after[0], np.r_[t_burn, t[j:]]).x[..., 1:, :]
    return out


def _measurements(sc, truth, noise) -> np.ndarray:
    """:func:`tracking.simulate_measurements` for truths (B, N, 6) with the standard normal draws ``noise``."""
    y = sc.model(sc.observers, truth[:, :, None, :])
    y = y + noise * np.sqrt(np.diag(sc.meas_cov))
    y[..., 0] = measurements.wrap_angle(y[..., 0])
    y[:, ~sc.available] = np.nan
    return y


def run_trial_filter(setup: DetectionSetup, inputs: TrialInputs, control_weight=None) -> ocbe.OCBEResult:
    """Single-trial OCBE (:func:`cislunar.estimation.ocbe.ocbe_filter_smoother`) on one trial's data.

    ``control_weight`` (LU^2/TU^3, scalar or per interval) overrides the setup's tuning.
    """
    _check_setup(setup)
    validation.instance(inputs, "inputs", TrialInputs, "a cislunar.papers.greaves_scheeres_2021.detection.TrialInputs (draw_trial)")
    sc = setup.scenario
    q = setup.control_weight if control_weight is None else control_weight
    return ocbe.ocbe_filter_smoother(setup.system, sc.t, inputs.y, setup.observer_states, sc.model, sc.meas_cov,
                                     inputs.x0, inputs.P0, q, n_sub=setup.n_sub, smooth=True, tol=setup.tol)


#: 99.9 % quantile of the 6-dof chi-square law: an epoch's NEES above it counts as inconsistent.
_NEES_LIMIT = nees_limit()


def _result(setup, inputs, z_smooth, z_step, x_filt, P_filt, x_smooth, P_smooth) -> TrialResult:
    v = setup.system.velocity_unit_km_s * 1e3
    nf, ns = _nees(x_filt, P_filt, inputs.truth), _nees(x_smooth, P_smooth, inputs.truth)
    return TrialResult(float(z_smooth) * v, float(z_step) * v, inputs.magnitude_m_s, inputs.azimuth,
                       inputs.elevation, float(np.mean(nf > _NEES_LIMIT)), float(np.mean(ns > _NEES_LIMIT)),
                       float(np.mean(nf)), float(np.mean(ns)))


def _results(setup, inputs, res) -> list:
    """:func:`_result` of every trial of a batch (``res`` from :func:`ocbe_batch` on ``inputs``), the NEES of all
    trials and epochs at once."""
    v = setup.system.velocity_unit_km_s * 1e3
    truth = np.array([i.truth for i in inputs])
    nf, ns = _nees(res.x_filt, res.P_filt, truth), _nees(res.x_smooth, res.P_smooth, truth)  # (B, N)
    cols = np.stack([res.z_smooth * v, res.z_step * v, np.mean(nf > _NEES_LIMIT, axis=1),
                     np.mean(ns > _NEES_LIMIT, axis=1), np.mean(nf, axis=1), np.mean(ns, axis=1)], axis=1).tolist()
    return [TrialResult(c[0], c[1], inp.magnitude_m_s, inp.azimuth, inp.elevation, *c[2:])
            for c, inp in zip(cols, inputs)]


def detection_trial(rng: np.random.Generator, setup: DetectionSetup,
                    policy: StationKeepingPolicy | None = None) -> TrialResult:
    """One Monte Carlo trial (module level, picklable): draw, filter with the single-trial OCBE, return z.

    Parameters
    ----------
    rng : numpy.random.Generator
    setup : DetectionSetup
    policy : StationKeepingPolicy or None
        Maneuver policy, or ``None`` for a non-maneuvering trial.
    """
    inputs = draw_trial(rng, setup, policy)
    res = run_trial_filter(setup, inputs)
    return _result(setup, inputs, res.z_smooth, res.z_step, res.x_filt, res.P_filt, res.x_smooth, res.P_smooth)


def detection_trial_batch(rng: np.random.Generator, setup: DetectionSetup, policy: StationKeepingPolicy | None,
                          batch_size: int) -> list:
    """``batch_size`` trials in lockstep through :func:`ocbe_batch` (module level, picklable).

    Sub-trial ``j`` draws its inputs with child ``j`` of ``rng.spawn(batch_size)``, so it equals
    :func:`detection_trial` called with that child generator (to round-off).

    Returns
    -------
    list of TrialResult
    """
    validation.rng(rng)
    _check_setup(setup)
    _check_policy(policy, optional=True)
    B = validation.integer(batch_size, "batch_size", minimum=1)
    return _detection_batches([rng], setup, policy, B)[0]


def _detection_batches(rngs, setup, policy, batch_size) -> list:
    """Several :func:`detection_trial_batch` batches (one per generator) in one lockstep :func:`ocbe_batch` call.

    Batch ``k`` draws its sub-trials with the children of ``rngs[k]`` exactly as :func:`detection_trial_batch`;
    every trial of the batched OCBE is computed on its own (stacked per-trial algebra, one integrator lane per
    trial), so the results equal those of separate calls.  Returns one list of :class:`TrialResult` per generator.
    """
    B = batch_size
    children = [child for rng in rngs for child in rng.spawn(B)]
    inputs = _draw_trials(children, setup, policy, None, None, setup.t_maneuver)
    sc = setup.scenario
    res = ocbe_batch(setup.system, sc.t, np.array([i.y for i in inputs]), setup.observer_states, sc.model, sc.meas_cov,
                     np.array([i.x0 for i in inputs]), np.array([i.P0 for i in inputs]), setup.control_weight,
                     n_sub=setup.n_sub, tol=setup.tol)
    flat = _results(setup, inputs, res)
    return [flat[k * B:(k + 1) * B] for k in range(len(rngs))]


#: Trials per lockstep call of the batched OCBE in :func:`run_detection_monte_carlo` (several batches together;
#: the numpy algebra's per-call overhead is shared by more trials, ``benchmarks/bench_detection.py``).
LOCKSTEP_TRIALS = 128


@dataclass(frozen=True)
class MonteCarloSample:
    """Monte Carlo results as arrays (one entry per trial).

    Attributes
    ----------
    z : ndarray
        Smoothed control integral (Eq. 33), m/s.
    z_step : ndarray
        Forward (single-step smoothed) control integral, m/s.
    magnitude, azimuth, elevation : ndarray
        Maneuver parameters, m/s and rad (0 and NaN without maneuver).
    nees_over_fwd, nees_over_smooth : ndarray
        Per run, the fraction of epochs whose forward / smoothed NEES exceeds its 99.9 % quantile.
    nees_mean_fwd, nees_mean_smooth : ndarray
        Per run, the mean NEES over the epochs.
    """

    z: np.ndarray
    z_step: np.ndarray
    magnitude: np.ndarray
    azimuth: np.ndarray
    elevation: np.ndarray
    nees_over_fwd: np.ndarray
    nees_over_smooth: np.ndarray
    nees_mean_fwd: np.ndarray
    nees_mean_smooth: np.ndarray

    @classmethod
    def from_results(cls, results) -> "MonteCarloSample":
        cols = np.array([[r.z_m_s, r.z_step_m_s, r.magnitude_m_s, r.azimuth, r.elevation, r.nees_over_fwd,
                          r.nees_over_smooth, r.nees_mean_fwd, r.nees_mean_smooth] for r in results])
        return cls(*cols.T.copy())

    def __len__(self) -> int:
        return self.z.size

    @property
    def inconsistent_runs(self) -> tuple[float, float]:
        """Fractions of runs that are NEES-inconsistent, ``(forward, smoothed)``.

        A run is inconsistent when more than :data:`cislunar.papers.greaves_scheeres_2021.tracking.DIVERGED_FRACTION` of its epochs exceed the
        99.9 % quantile of the 6-dof chi-square law (notebook 09's criterion).
        """
        lim = tracking.DIVERGED_FRACTION
        return float(np.mean(self.nees_over_fwd > lim)), float(np.mean(self.nees_over_smooth > lim))


def run_detection_monte_carlo(setup: DetectionSetup, policy: StationKeepingPolicy | None, n_trials: int, seed, *,
                              batch_size: int = 8, executor=None, progress: bool = True,
                              desc: str | None = None) -> MonteCarloSample:
    """Monte Carlo of the control integral through :func:`cislunar.utils.montecarlo.run_monte_carlo`.

    Trials run in batches of ``batch_size`` (:func:`detection_trial_batch`): batch ``i`` is trial ``i`` of
    ``run_monte_carlo``, seeded by child ``i`` of ``SeedSequence(seed)``; the sub-trials of a batch are its
    children.  Results therefore depend on ``seed`` and ``batch_size`` only, not on the executor.  The last batch
    is trimmed to ``n_trials``.  Consecutive batches (about :data:`LOCKSTEP_TRIALS` trials, at least four tasks
    per run) go through the batched OCBE together as one vectorized task; this changes the speed only, every
    trial being computed on its own.  ``batch_size=1`` with :func:`detection_trial` semantics is available
    by passing ``batch_size=0``, which runs the single-trial OCBE per trial.

    Parameters
    ----------
    setup : DetectionSetup
    policy : StationKeepingPolicy or None
        ``None`` for the non-maneuvering (H0) runs.
    n_trials : int
    seed : int
    batch_size : int
        Trials per lockstep batch (0: no batching, :func:`detection_trial` per trial).
    executor : concurrent.futures-style executor, optional
    progress : bool
    desc : str, optional
        Progress-bar label.

    Raises
    ------
    cislunar.utils.montecarlo.MonteCarloError
        A trial failed; with batches it names the first trial of the failing batch, the batch's seed and its
        trial range, and ``completed`` holds the finished trials by trial index.
    """

    _check_setup(setup)
    _check_policy(policy, optional=True)
    n = validation.integer(n_trials, "n_trials", minimum=1)
    B = validation.integer(batch_size, "batch_size", minimum=0)
    validation.seed_entropy(seed, "seed")
    label = desc or f"{'H0' if policy is None else policy.name} MC"
    if B == 0:
        res = run_monte_carlo(detection_trial, n, seed, args=(setup, policy), executor=executor, chunk_size=None,
                              progress=progress, desc=label)
    else:
        n_batches = -(-n // B)
        try:
            group = max(1, min(LOCKSTEP_TRIALS // B, -(-n_batches // 4)))
            chunks = run_monte_carlo(_detection_batches, n_batches, seed, args=(setup, policy, B), executor=executor,
                                     chunk_size=group, progress=progress, desc=label, vectorized=True)
        except MonteCarloError as exc:  # name the trials of the failing batch; keep completed trials by index
            k = exc.trial_index
            f = exc.failure
            where = f"{f.seed}; batch {k} of {B} trials: trials {k * B}-{min(k * B + B, n) - 1}"
            done = {b * B + j: r for b, rs in exc.completed.items() for j, r in enumerate(rs) if b * B + j < n}
            raise MonteCarloError(TrialFailure(k * B, where, f.error, f.traceback), done, n) from exc
        res = [r for chunk in chunks for r in chunk][:n]
    return MonteCarloSample.from_results(res)


def run_detection_monte_carlos(jobs, *, batch_size: int = 8, executor=None, progress: bool = False,
                               desc: str = "detection MC") -> list:
    """Several :func:`run_detection_monte_carlo` runs at once, their lockstep groups pooled in one sweep.

    ``jobs`` is a sequence of ``(setup, policy, n_trials, seed)``; result ``k`` equals
    ``run_detection_monte_carlo(*jobs[k], batch_size=batch_size)`` (the same batches, seeded by the same children
    of ``SeedSequence(seed)``, each trial computed on its own).  What changes is the scheduling: every job is cut
    into lockstep groups of about :data:`LOCKSTEP_TRIALS` trials and all groups of all jobs go to ``executor``
    together, so the workers do not wait at the end of each job and small jobs still filter many trials per
    lockstep call.

    Parameters
    ----------
    jobs : sequence of tuple
        ``(setup, policy, n_trials, seed)``: a DetectionSetup, a StationKeepingPolicy or None (H0), a positive int
        and an int or sequence of ints.
    batch_size : int
        Trials per batch (at least 1): the seeding unit, as in :func:`run_detection_monte_carlo`.
    executor : concurrent.futures-style executor, optional
    progress : bool
    desc : str
        Progress-bar label.

    Returns
    -------
    list of MonteCarloSample
        One per job, in order.

    Raises
    ------
    cislunar.utils.montecarlo.MonteCarloError
        A trial failed: the failing job is rerun alone through :func:`run_detection_monte_carlo`, whose error names
        the trial, its batch and seed.
    """
    try:
        jobs = [tuple(j) for j in jobs]
    except TypeError:
        raise validation.ArgumentTypeError("jobs must be a sequence of (setup, policy, n_trials, seed) tuples") from None
    B = validation.integer(batch_size, "batch_size", minimum=1)
    validation.boolean(progress, "progress")
    validation.instance(desc, "desc", str)
    segments = {}  # filter key -> [(job, setup, policy, root, first batch, end batch)] in job order
    for k, job in enumerate(jobs):
        if len(job) != 4:
            raise ValueError(f"jobs[{k}] must be (setup, policy, n_trials, seed); got {len(job)} items")
        setup, policy, n, seed = job
        _check_setup(setup, f"jobs[{k}] setup")
        _check_policy(policy, f"jobs[{k}] policy", optional=True)
        n = validation.integer(n, f"jobs[{k}] n_trials", minimum=1)
        root = validation.seed_entropy(seed, f"jobs[{k}] seed")
        root = root if isinstance(root, np.random.SeedSequence) else np.random.SeedSequence(root)
        segments.setdefault(_filter_key(setup), []).append((k, setup, policy, root, 0, -(-n // B)))
    # lockstep groups of about LOCKSTEP_TRIALS trials; jobs that share the epochs, observer and noise share groups
    # (the control weight is per trial), so that small jobs still fill a lockstep call
    per_group = max(1, LOCKSTEP_TRIALS // B)
    tasks = []
    for segs in segments.values():
        group, room = [], per_group
        for k, setup, policy, root, a, end in segs:
            while a < end:
                b = min(end, a + room)
                group.append((k, setup, policy, root, a, b))
                room -= b - a
                a = b
                if room == 0:
                    tasks.append((B, group))
                    group, room = [], per_group
        if group:
            tasks.append((B, group))
    try:
        parts = map_tasks(_monte_carlo_group, tasks, executor=executor, progress=progress, desc=desc)
    except MonteCarloError as exc:  # rerun the jobs of the failing group alone: the first to fail names its trial
        for k in dict.fromkeys(seg[0] for seg in tasks[exc.trial_index][1]):
            setup, policy, n, seed = jobs[k]
            run_detection_monte_carlo(setup, policy, n, seed, batch_size=B, progress=False)
        raise  # pragma: no cover - a failure that does not repeat alone
    results = {k: {} for k in range(len(jobs))}
    for (_, group), part in zip(tasks, parts):
        for (k, _, _, _, a, _), res in zip(group, part):
            results[k][a] = res
    return [MonteCarloSample.from_results([r for a in sorted(results[k]) for r in results[k][a]][:job[2]])
            for k, job in enumerate(jobs)]


def _filter_key(setup) -> tuple:
    """What trials must share to be filtered in one lockstep call: system, epochs, observer, measurement model and
    noise, sub-grid and tolerance (the control weight and the truth may differ per trial)."""
    sc, em = setup.scenario, setup.system
    return (em.mu, em.length_unit_km, em.time_unit_s, sc.t.tobytes(), np.ascontiguousarray(setup.observer_states)
            .tobytes(), sc.model.name, np.ascontiguousarray(sc.meas_cov).tobytes(), setup.n_sub, setup.tol)


def _monte_carlo_group(task) -> list:
    """One lockstep group of :func:`run_detection_monte_carlos`: for each segment ``(job, setup, policy, root, a,
    b)`` the batches ``a`` to ``b - 1`` of that job's :func:`run_detection_monte_carlo` run, drawn on its own setup,
    all filtered in one :func:`ocbe_batch` call; returns one list of :class:`TrialResult` per segment."""
    B, group = task
    inputs, setups, sizes = [], [], []
    for _, setup, policy, root, a, b in group:
        base, offset = tuple(root.spawn_key), root.n_children_spawned  # the children run_monte_carlo gives batch i
        rngs = [np.random.default_rng(np.random.SeedSequence(root.entropy, spawn_key=base + (offset + i,),
                                                             pool_size=root.pool_size)) for i in range(a, b)]
        children = [child for rng in rngs for child in rng.spawn(B)]
        inputs += _draw_trials(children, setup, policy, None, None, setup.t_maneuver)
        setups.append(setup)
        sizes.append(len(children))
    s0, sc = setups[0], setups[0].scenario
    q = np.concatenate([np.broadcast_to(s.control_weight, (m, s.control_weight.size)) for s, m in zip(setups, sizes)])
    res = ocbe_batch(s0.system, sc.t, np.array([i.y for i in inputs]), s0.observer_states, sc.model, sc.meas_cov,
                     np.array([i.x0 for i in inputs]), np.array([i.P0 for i in inputs]), q, n_sub=s0.n_sub,
                     tol=s0.tol)
    flat = _results(s0, inputs, res)
    out, start = [], 0
    for m in sizes:
        out.append(flat[start:start + m])
        start += m
    return out


# ---------------------------------------------------------------------------------------------------------------
# Batched OCBE: B trials in lockstep
# ---------------------------------------------------------------------------------------------------------------


# ---------------------------------------------------------------------------------------------------------------
# Hypothesis test (Eqs. 34-35)
# ---------------------------------------------------------------------------------------------------------------


def _check_bandwidth(bandwidth) -> None:
    """A KDE bandwidth rule: ``"scott"``, ``"silverman"`` or a positive finite factor (:func:`fit_pdf`)."""
    ok = (isinstance(bandwidth, str) and bandwidth in ("scott", "silverman")) or (
        isinstance(bandwidth, (int, float)) and not isinstance(bandwidth, bool) and np.isfinite(bandwidth)
        and bandwidth > 0)
    if not ok:
        raise ValueError(f"bandwidth must be 'scott', 'silverman' or a positive factor; got {bandwidth!r:.60}")


def fit_pdf(samples, bandwidth="scott") -> stats.gaussian_kde:
    """Numerical PDF of a sample: Gaussian kernel density estimate.

    Parameters
    ----------
    samples : array_like, shape (n,)
        Values of the test statistic (any unit; the PDF is per that unit).
    bandwidth : {"scott", "silverman"} or float
        :class:`scipy.stats.gaussian_kde` ``bw_method``.  Default Scott's rule: kernel standard deviation
        :math:`n^{-1/5}` times the sample standard deviation.
    """
    z = validation.as_array(samples, "samples", ndim=(1,))
    if z.size < 2 or np.std(z) == 0:
        raise ValueError("samples must hold at least two distinct values")
    _check_bandwidth(bandwidth)
    return stats.gaussian_kde(z, bw_method=bandwidth)


def _pdf(dist):
    return dist.pdf if hasattr(dist, "pdf") else dist


def _cdf(dist, z) -> float:
    """CDF of a frozen scipy distribution or of a ``gaussian_kde`` at ``z``."""
    if isinstance(dist, stats.gaussian_kde):
        return float(dist.integrate_box_1d(-np.inf, z))
    return float(dist.cdf(z))


def pdf_crossings(pdf0, pdf1, lo: float, hi: float, *, n_grid: int = 4001) -> np.ndarray:
    """Points in ``[lo, hi]`` where two PDFs are equal (sign changes of ``pdf0 - pdf1`` refined by ``brentq``).

    Parameters
    ----------
    pdf0, pdf1 : callable or object with ``pdf``
        Densities (e.g. ``gaussian_kde`` or frozen scipy distributions).
    lo, hi : float
        Search interval (lo < hi).
    n_grid : int
        Grid points for bracketing.
    """
    lo = validation.real(lo, "lo")
    hi = validation.real(hi, "hi")
    if not hi > lo:
        raise ValueError(f"lo and hi must be finite with lo < hi; got lo={lo}, hi={hi}")
    n_grid = validation.integer(n_grid, "n_grid", minimum=3)
    f0, f1 = _pdf(pdf0), _pdf(pdf1)
    validation.callable_(f0, "pdf0")
    validation.callable_(f1, "pdf1")

    def g(z):
        return float(np.asarray(f0(z)).ravel()[0] - np.asarray(f1(z)).ravel()[0])

    grid = np.linspace(lo, hi, int(n_grid))
    d = np.asarray(f0(grid)).ravel() - np.asarray(f1(grid)).ravel()
    if np.all(np.abs(d) <= 1e-14 * np.max(np.abs(np.asarray(f0(grid))))):
        raise ValueError("pdf0 and pdf1 coincide on [lo, hi]: no crossing to place a threshold at")
    out = []
    for i in np.flatnonzero(np.sign(d[:-1]) * np.sign(d[1:]) < 0):
        out.append(optimize.brentq(g, grid[i], grid[i + 1], xtol=1e-14 * max(1.0, abs(hi)), rtol=1e-14))
    out.extend(grid[np.flatnonzero(d == 0)])
    return np.sort(np.array(out, dtype=float))


def error_rates(z_lim: float, dist0, dist1) -> tuple[float, float]:
    """False-positive and missed-detection rates of the rule "H1 if z > z_lim" (Eq. 35).

    False positive :math:`\\int_{z_{lim}}^\\infty PDF_{\\mathcal H_0}`; missed detection
    :math:`\\int_{-\\infty}^{z_{lim}} PDF_{\\mathcal H_1}`.

    Parameters
    ----------
    z_lim : float
    dist0, dist1 : gaussian_kde or frozen scipy distribution
        Densities under H0 and H1.
    """
    zl = validation.real(z_lim, "z_lim")
    for name, dist in (("dist0", dist0), ("dist1", dist1)):
        if not (isinstance(dist, stats.gaussian_kde) or callable(getattr(dist, "cdf", None))):
            raise validation.ArgumentTypeError(f"{name} must be a scipy.stats.gaussian_kde or a frozen scipy "
                                            f"distribution; got {type(dist).__name__}")
    return 1.0 - _cdf(dist0, zl), _cdf(dist1, zl)


@dataclass(frozen=True)
class DetectionThreshold:
    """Maximum-likelihood threshold of Eq. 35 and its expected error rates.

    Attributes
    ----------
    z_lim : float
        Threshold (same unit as the samples).
    false_positive, missed_detection : float
        Expected rates (probabilities) from integrating the PDFs.
    crossings : ndarray
        All PDF crossings found in the search range (the paper finds exactly one).
    pdf0, pdf1 : gaussian_kde
        Numerical PDFs under H0 and H1.
    """

    z_lim: float
    false_positive: float
    missed_detection: float
    crossings: np.ndarray
    pdf0: object = field(repr=False)
    pdf1: object = field(repr=False)

    @property
    def total_error(self) -> float:
        """False-positive plus missed-detection rate (twice the expected error with equal priors)."""
        return self.false_positive + self.missed_detection


def ml_threshold(z_h0, z_h1, *, bandwidth="scott", n_grid: int = 4001) -> DetectionThreshold:
    """Fit PDFs to the H0 and H1 samples and place :math:`z_{lim}` where they cross (Eqs. 34-35).

    The PDFs are Gaussian KDEs (:func:`fit_pdf`).  Crossings are searched between the smallest and largest sample
    of both sets.  With equal priors and costs the single-threshold rule that minimises the error
    (false positive + missed detection) sits at a crossing (its derivative there is :math:`PDF_1 - PDF_0 = 0`);
    with several crossings we take the one of least total error, so the paper's single-crossing case is
    unaffected.

    Parameters
    ----------
    z_h0, z_h1 : array_like, shape (n0,), (n1,)
        Test statistic without and with maneuvers.
    bandwidth : str or float
        KDE bandwidth rule (see :func:`fit_pdf`).
    n_grid : int
        Grid points bracketing the crossings (:func:`pdf_crossings`); each crossing is then refined to round-off.
    """
    z0 = validation.as_array(z_h0, "z_h0", ndim=(1,))
    z1 = validation.as_array(z_h1, "z_h1", ndim=(1,))
    for name, z in (("z_h0", z0), ("z_h1", z1)):
        if z.size < 2 or np.std(z) == 0:
            raise ValueError(f"{name} must hold at least two distinct values; got {z.size} value(s)")
    k0, k1 = fit_pdf(z0, bandwidth), fit_pdf(z1, bandwidth)
    lo, hi = min(z0.min(), z1.min()), max(z0.max(), z1.max())
    cross = pdf_crossings(k0, k1, lo, hi, n_grid=n_grid)
    if cross.size == 0:
        raise ValueError("the H0 and H1 PDFs do not cross between the samples: no maximum-likelihood threshold")
    errs = np.array([sum(error_rates(c, k0, k1)) for c in cross])
    z_lim = float(cross[np.argmin(errs)])
    fp, md = error_rates(z_lim, k0, k1)
    return DetectionThreshold(z_lim, fp, md, cross, k0, k1)


def threshold_bootstrap(z_h0, z_h1, n_resamples: int, rng: np.random.Generator, *, bandwidth="scott",
                        n_grid: int = 1001) -> np.ndarray:
    """Bootstrap of the maximum-likelihood threshold and its expected error (Monte Carlo standard errors).

    Each resample draws the H0 and H1 sets with replacement (same sizes) and refits :func:`ml_threshold`.

    Parameters
    ----------
    z_h0, z_h1 : array_like, shape (n0,), (n1,)
        Training samples of the test statistic.
    n_resamples : int
    rng : numpy.random.Generator
    bandwidth : str or float
        KDE bandwidth rule (:func:`fit_pdf`).
    n_grid : int
        Bracketing grid of the crossings (coarser than :func:`ml_threshold`'s default for speed; crossings are
        refined to round-off either way).

    Returns
    -------
    ndarray, shape (n_resamples, 2)
        Columns: :math:`z_{lim}` (unit of the samples) and the total expected error (false positive + missed
        detection).  Their standard deviations over the rows are the standard errors.
    """
    z0 = validation.as_array(z_h0, "z_h0", ndim=(1,), min_size=2)
    z1 = validation.as_array(z_h1, "z_h1", ndim=(1,), min_size=2)
    n = validation.integer(n_resamples, "n_resamples", minimum=2)
    validation.rng(rng)
    out = np.empty((n, 2))
    for i in range(n):
        th = ml_threshold(rng.choice(z0, z0.size), rng.choice(z1, z1.size), bandwidth=bandwidth, n_grid=n_grid)
        out[i] = th.z_lim, th.total_error
    return out


def decide(z, z_lim: float) -> np.ndarray:
    """Eq. 35: ``True`` (H1, maneuver) where ``z > z_lim``, ``False`` (H0) otherwise."""
    return validation.as_array(z, "z") > validation.real(z_lim, "z_lim")


@dataclass(frozen=True)
class DetectionScore:
    """Confusion counts of a detection test (Tables 7-8).

    Attributes
    ----------
    true_negative, false_positive : int
        Non-maneuvering data sets declared H0 / H1.
    true_positive, missed_detection : int
        Maneuvering data sets declared H1 / H0.
    """

    true_negative: int
    false_positive: int
    true_positive: int
    missed_detection: int

    @property
    def n(self) -> int:
        return self.true_negative + self.false_positive + self.true_positive + self.missed_detection

    @property
    def accuracy(self) -> float:
        """Fraction of correct decisions."""
        return (self.true_negative + self.true_positive) / self.n


def detection_accuracy(z_test_h0, z_test_h1, z_lim: float) -> DetectionScore:
    """Apply Eq. 35 to independent non-maneuvering (``z_test_h0``) and maneuvering (``z_test_h1``) test sets."""
    d0 = decide(validation.as_array(z_test_h0, "z_test_h0", ndim=(1,), min_size=1), z_lim)
    d1 = decide(validation.as_array(z_test_h1, "z_test_h1", ndim=(1,), min_size=1), z_lim)
    return DetectionScore(int(np.sum(~d0)), int(np.sum(d0)), int(np.sum(d1)), int(np.sum(~d1)))


# ---------------------------------------------------------------------------------------------------------------
# One policy on one orbit: training Monte Carlo, threshold, independent detection test
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PolicyStudy:
    """Monte Carlo, maximum-likelihood threshold and detection test for one policy on one orbit.

    Attributes
    ----------
    h0, h1 : MonteCarloSample
        Training runs without / with maneuvers (the PDFs are fitted to these).
    test_h0, test_h1 : MonteCarloSample or None
        Independent test runs.
    threshold : DetectionThreshold
        z_lim and expected error rates (Tables 5-6).
    score : DetectionScore or None
        Decisions on the test runs (Tables 7-8).
    """

    h0: MonteCarloSample
    h1: MonteCarloSample
    test_h0: MonteCarloSample | None
    test_h1: MonteCarloSample | None
    threshold: DetectionThreshold
    score: DetectionScore | None


def run_policy_study(setup: DetectionSetup, policy: StationKeepingPolicy, n_h0: int, n_h1: int, n_test: int,
                     seed, *, batch_size: int = 8, executor=None, bandwidth="scott", progress: bool = True,
                     label: str = "") -> PolicyStudy:
    """Training Monte Carlo (H0 and H1), threshold (Eq. 35) and independent test sets for one policy and orbit.

    The four sets use the independent seeds ``[*seed, k]`` with ``k = 0, 1, 2, 3`` (H0 train, H1 train, H0 test,
    H1 test), ``seed`` being an int or a list of ints.

    Parameters
    ----------
    setup : DetectionSetup
    policy : StationKeepingPolicy
    n_h0, n_h1 : int
        Training runs without / with maneuvers (500 and 3000 in the paper).
    n_test : int
        Test runs per hypothesis (100 in the paper); 0 skips the test.
    seed : int or list of int
    batch_size, executor, progress
        See :func:`run_detection_monte_carlo`.
    bandwidth : str or float
        KDE bandwidth rule (:func:`fit_pdf`).
    label : str
        Progress-bar prefix.
    """
    _check_setup(setup)
    _check_policy(policy)
    base = validation.int_seed_list(seed, "seed", why="the four sets append an index")
    validation.integer(n_h0, "n_h0", minimum=2)
    validation.integer(n_h1, "n_h1", minimum=2)
    n_test = validation.integer(n_test, "n_test", minimum=0)
    validation.integer(batch_size, "batch_size", minimum=0)
    _check_bandwidth(bandwidth)  # before the Monte Carlo runs rather than after them

    def mc(pol, n, k, what):
        return run_detection_monte_carlo(setup, pol, n, base + [k], batch_size=batch_size, executor=executor,
                                         progress=progress, desc=f"{label} {what}".strip())

    h0 = mc(None, n_h0, 0, "H0 train")
    h1 = mc(policy, n_h1, 1, "H1 train")
    th = ml_threshold(h0.z, h1.z, bandwidth=bandwidth)
    t0 = t1 = score = None
    if n_test:
        t0 = mc(None, n_test, 2, "H0 test")
        t1 = mc(policy, n_test, 3, "H1 test")
        score = detection_accuracy(t0.z, t1.z, th.z_lim)
    return PolicyStudy(h0, h1, t0, t1, th, score)


def run_policy_studies(jobs, *, batch_size: int = 8, executor=None, bandwidth="scott", progress: bool = False,
                       desc: str = "policy studies") -> list:
    """Several :func:`run_policy_study` at once: every Monte Carlo of every job pooled in one sweep.

    ``jobs`` is a sequence of ``(setup, policy, n_h0, n_h1, n_test, seed)``; result ``k`` equals
    ``run_policy_study(*jobs[k], batch_size=batch_size, bandwidth=bandwidth)`` (the same seeds ``[*seed, 0..3]``,
    the same trials), the Monte Carlo going through :func:`run_detection_monte_carlos` so that the workers of
    ``executor`` stay busy across jobs.

    Parameters
    ----------
    jobs : sequence of tuple
        ``(setup, policy, n_h0, n_h1, n_test, seed)`` as the arguments of :func:`run_policy_study`.
    batch_size : int
        Trials per batch (at least 1).
    executor, bandwidth, progress, desc
        See :func:`run_detection_monte_carlos` and :func:`fit_pdf`.

    Returns
    -------
    list of PolicyStudy
    """
    try:
        jobs = [tuple(j) for j in jobs]
    except TypeError:
        raise validation.ArgumentTypeError("jobs must be a sequence of (setup, policy, n_h0, n_h1, n_test, seed) "
                                           "tuples") from None
    validation.integer(batch_size, "batch_size", minimum=1)
    validation.boolean(progress, "progress")
    validation.instance(desc, "desc", str)
    _check_bandwidth(bandwidth)  # before the Monte Carlo runs rather than after them
    runs, plan = [], []
    for k, job in enumerate(jobs):
        if len(job) != 6:
            raise ValueError(f"jobs[{k}] must be (setup, policy, n_h0, n_h1, n_test, seed); got {len(job)} items")
        setup, policy, n_h0, n_h1, n_test, seed = job
        _check_setup(setup, f"jobs[{k}] setup")
        _check_policy(policy, f"jobs[{k}] policy")
        base = validation.int_seed_list(seed, f"jobs[{k}] seed", why="the four sets append an index")
        validation.integer(n_h0, f"jobs[{k}] n_h0", minimum=2)
        validation.integer(n_h1, f"jobs[{k}] n_h1", minimum=2)
        n_test = validation.integer(n_test, f"jobs[{k}] n_test", minimum=0)
        sets = [(None, n_h0, 0), (policy, n_h1, 1)] + ([(None, n_test, 2), (policy, n_test, 3)] if n_test else [])
        plan.append(len(sets))
        runs += [(setup, pol, n, base + [i]) for pol, n, i in sets]
    samples = iter(run_detection_monte_carlos(runs, batch_size=batch_size, executor=executor, progress=progress,
                                              desc=desc))
    out = []
    for n_sets in plan:
        h0, h1 = next(samples), next(samples)
        th = ml_threshold(h0.z, h1.z, bandwidth=bandwidth)
        t0 = t1 = score = None
        if n_sets == 4:
            t0, t1 = next(samples), next(samples)
            score = detection_accuracy(t0.z, t1.z, th.z_lim)
        out.append(PolicyStudy(h0, h1, t0, t1, th, score))
    return out


# ---------------------------------------------------------------------------------------------------------------
# Studies beyond the paper's runs: filtering given trials, burn directions, the health-metric race (Fig. 22)
# ---------------------------------------------------------------------------------------------------------------


def _check_inputs(inputs, name: str = "inputs") -> list:
    return validation.sequence_of(inputs, name, TrialInputs, "cislunar.papers.greaves_scheeres_2021.detection.TrialInputs (draw_trial)")


def filter_trials(setup: DetectionSetup, inputs, *, n_epochs: int | None = None) -> BatchOCBEResult:
    """The batched OCBE (:func:`ocbe_batch`) on given trials, in lockstep groups of :data:`LOCKSTEP_TRIALS`.

    Parameters
    ----------
    setup : DetectionSetup
    inputs : sequence of TrialInputs
        Trials drawn with :func:`draw_trial` for this setup.
    n_epochs : int, optional
        Filter and smooth only the first ``n_epochs`` epochs (at least 2): the estimate an analyst has at epoch
        ``n_epochs - 1``, e.g. to follow the smoothed control integral as the data arrive.  Default: the whole
        track.

    Returns
    -------
    BatchOCBEResult
        One entry per trial on the leading axis, in the order of ``inputs``.
    """
    _check_setup(setup)
    items = _check_inputs(inputs)
    sc = setup.scenario
    N = sc.t.size if n_epochs is None else validation.integer(n_epochs, "n_epochs", minimum=2, maximum=sc.t.size)
    parts = []
    for a in range(0, len(items), LOCKSTEP_TRIALS):
        chunk = items[a:a + LOCKSTEP_TRIALS]
        parts.append(ocbe_batch(setup.system, sc.t[:N], np.array([i.y[:N] for i in chunk]),
                                setup.observer_states[:N], sc.model, sc.meas_cov, np.array([i.x0 for i in chunk]),
                                np.array([i.P0 for i in chunk]), setup.control_weight[:N - 1], n_sub=setup.n_sub,
                                tol=setup.tol))
    if len(parts) == 1:
        return parts[0]
    return _concat_results(parts)


def filter_trial_sets(sets, *, executor=None, progress: bool = False) -> list:
    """:func:`filter_trials` on several sets of trials, each on its own setup, in pooled lockstep groups.

    ``sets`` is a sequence of ``(setup, inputs)``.  Sets whose setups share the epochs, observer, measurement
    noise, sub-grid and tolerance are filtered together in lockstep groups of up to :data:`LOCKSTEP_TRIALS` trials,
    each trial with its own setup's control weight (e.g. one set of burns under several tunings); the groups go
    through ``executor`` when given.  Result ``k`` equals ``filter_trials(*sets[k])`` (each trial is computed on
    its own).

    Parameters
    ----------
    sets : sequence of (DetectionSetup, sequence of TrialInputs)
    executor : concurrent.futures-style executor, optional
    progress : bool

    Returns
    -------
    list of BatchOCBEResult
        One per set, trials in the order of its inputs.
    """
    try:
        sets = [tuple(x) for x in sets]
    except TypeError:
        raise validation.ArgumentTypeError("sets must be a sequence of (setup, inputs) pairs") from None
    validation.boolean(progress, "progress")
    keyed = {}
    for k, pair in enumerate(sets):
        if len(pair) != 2:
            raise ValueError(f"sets[{k}] must be a (setup, inputs) pair; got {len(pair)} items")
        setup, inputs = pair
        _check_setup(setup, f"sets[{k}] setup")
        items = _check_inputs(inputs, f"sets[{k}] inputs")
        if not items:
            raise ValueError(f"sets[{k}] inputs must hold at least one trial")
        keyed.setdefault(_filter_key(setup), []).append((k, setup, items))
    tasks = []
    for members in keyed.values():
        group, room = [], LOCKSTEP_TRIALS
        for k, setup, items in members:
            a = 0
            while a < len(items):
                b = min(len(items), a + room)
                group.append((k, a, setup, items[a:b]))
                room -= b - a
                a = b
                if room == 0:
                    tasks.append(group)
                    group, room = [], LOCKSTEP_TRIALS
        if group:
            tasks.append(group)
    parts = map_tasks(_filter_group, tasks, executor=executor, progress=progress, desc="filter sets")
    pieces = {k: [] for k in range(len(sets))}
    for group, part in zip(tasks, parts):
        for (k, a, _, _), res in zip(group, part):
            pieces[k].append((a, res))
    return [_concat_results([r for _, r in sorted(pieces[k], key=lambda ar: ar[0])]) for k in range(len(sets))]


def _filter_group(group) -> list:
    """One lockstep group of :func:`filter_trial_sets`: ``[(set, first, setup, inputs), ...]`` -> one
    BatchOCBEResult per member."""
    s0 = group[0][2]
    sc = s0.scenario
    inputs = [i for *_, items in group for i in items]
    q = np.concatenate([np.broadcast_to(s.control_weight, (len(items), s.control_weight.size))
                        for _, _, s, items in group])
    res = ocbe_batch(s0.system, sc.t, np.array([i.y for i in inputs]), s0.observer_states, sc.model, sc.meas_cov,
                     np.array([i.x0 for i in inputs]), np.array([i.P0 for i in inputs]), q, n_sub=s0.n_sub,
                     tol=s0.tol)
    out, start = [], 0
    for *_, items in group:
        out.append(_slice_result(res, start, start + len(items)))
        start += len(items)
    return out


def _slice_result(res, a, b) -> BatchOCBEResult:
    fields = {f: (getattr(res, f) if f == "t_sub" or getattr(res, f) is None else getattr(res, f)[a:b])
              for f in BatchOCBEResult.__dataclass_fields__}
    return BatchOCBEResult(**fields)


def _concat_results(parts) -> BatchOCBEResult:
    if len(parts) == 1:
        return parts[0]
    fields = {f: (getattr(parts[0], f) if f == "t_sub" or getattr(parts[0], f) is None
                  else np.concatenate([getattr(p, f) for p in parts]))
              for f in BatchOCBEResult.__dataclass_fields__}
    return BatchOCBEResult(**fields)


def control_spike_contrast(setup: DetectionSetup, result: BatchOCBEResult, *, half_width_hours: float = 6.0,
                           burn_offset_hours: float = 0.0) -> np.ndarray:
    """How much the estimated control stands out at the burn time, per trial: forward and smoothed.

    The contrast is the mean control norm on the sub-grid points within ``half_width_hours`` of the burn time over
    the mean farther away (1: no spike), the definition of
    :meth:`cislunar.estimation.panels.PanelSeries.spike_contrast` (Figs. 11 and 13: a maneuver "appears as a spike in
    estimated control only in the smoothed system").  The default half width covers the intervals that touch an
    8-hour window centred on the burn at a 2-hour cadence.

    Parameters
    ----------
    setup : DetectionSetup
    result : BatchOCBEResult
        Output of :func:`filter_trials` (or :func:`ocbe_batch`) on the setup's epochs.
    half_width_hours : float
    burn_offset_hours : float
        Burn time after the apoapsis, hours (for runs without a burn: the time the test looks at).

    Returns
    -------
    ndarray, shape (B, 2)
        Column 0 the forward (single-step, Eq. 32) control, column 1 the smoothed control.
    """
    _check_setup(setup)
    validation.instance(result, "result", BatchOCBEResult, "a cislunar.papers.greaves_scheeres_2021.batched_ocbe.BatchOCBEResult (filter_trials)")
    hw = validation.positive(half_width_hours, "half_width_hours") * 3600.0 / setup.system.time_unit_s
    t_b = setup.t_maneuver + validation.real(burn_offset_hours, "burn_offset_hours") * 3600.0 / setup.system.time_unit_s
    near = np.abs(result.t_sub - t_b) <= hw
    if not near.any() or near.all():
        raise ValueError("half_width_hours and burn_offset_hours must select some but not all of the track")
    norms = np.stack([np.linalg.norm(u, axis=-1) for u in (result.control_step, result.control_smooth)], axis=1)
    return ocbe.spike_contrast(result.t_sub, norms, t_b, hw)


def azimuth_contrast(sample: MonteCarloSample, *, half_width_deg: float = 30.0,
                     max_elevation_deg: float = 45.0) -> float:
    """The paper's Fig. 16 pattern in one number: is :math:`z/|\\Delta v|` larger for burns along :math:`\\pm\\hat j`?

    Mean of :math:`z/|\\Delta v|` over the maneuvering runs whose azimuth is within ``half_width_deg`` of
    :math:`\\pm 90°`, over its mean for azimuths within ``half_width_deg`` of 0° or 180°, both restricted to
    elevations below ``max_elevation_deg`` in magnitude.  1 means no preference; NaN when a sector is empty.

    Parameters
    ----------
    sample : MonteCarloSample
        Runs with a maneuver (H1).
    half_width_deg, max_elevation_deg : float
        Sector half width and elevation cut, deg.
    """
    validation.instance(sample, "sample", MonteCarloSample, "a cislunar.papers.greaves_scheeres_2021.detection.MonteCarloSample")
    hw = validation.in_range(half_width_deg, "half_width_deg", 0.0, 90.0, closed=False)
    emax = validation.in_range(max_elevation_deg, "max_elevation_deg", 0.0, 90.0, closed=False)
    if not np.all(sample.magnitude > 0):
        raise ValueError("sample must hold maneuvering runs only (positive magnitudes)")
    r = sample.z / sample.magnitude
    a, e = np.abs(np.degrees(sample.azimuth)), np.abs(np.degrees(sample.elevation))
    low = e < emax
    side = low & (np.abs(a - 90.0) < hw)
    axial = low & ((a < hw) | (a > 180.0 - hw))
    return float(r[side].mean() / r[axial].mean()) if side.any() and axial.any() else float("nan")


def direction_response(setup: DetectionSetup, directions, magnitude_m_s: float, n_repeats: int, seed, *,
                       burn_offset_hours: float = 0.0) -> np.ndarray:
    """Smoothed control integral :math:`z` (m/s) of burns of one size in given directions.

    Repeat ``k`` draws its measurement noise and hand-off error with the generator ``[*seed, k]``, the same for
    every direction, so that directions are compared on the same data noise (paired comparison).

    Parameters
    ----------
    setup : DetectionSetup
    directions : array_like, shape (n, 2)
        ``(azimuth, elevation)`` pairs in the rotating frame, rad.
    magnitude_m_s : float
        Burn size, m/s (positive).
    n_repeats : int
        Noise draws per direction.
    seed : int or list of int
    burn_offset_hours : float
        Burn time after the apoapsis, hours (:func:`draw_trial`).

    Returns
    -------
    ndarray, shape (n_repeats, n)
    """
    _check_setup(setup)
    dirs = validation.as_array(directions, "directions", ndim=(2,), last=2, min_size=2)
    mag = validation.positive(magnitude_m_s, "magnitude_m_s")
    n_rep = validation.integer(n_repeats, "n_repeats", minimum=1)
    base = validation.int_seed_list(seed, "seed", why="repeats append an index")
    off = validation.real(burn_offset_hours, "burn_offset_hours")
    inputs = _direction_trials(setup, dirs, mag, n_rep, base, off)
    z = filter_trials(setup, inputs).z_smooth * setup.system.velocity_unit_km_s * 1e3
    return z.reshape(n_rep, len(dirs))


def direction_trials(setup: DetectionSetup, directions, magnitude_m_s: float, n_repeats: int, seed, *,
                     burn_offset_hours: float = 0.0) -> list:
    """The trials :func:`direction_response` filters, repeat-major (repeat ``k`` of every direction draws with the
    generator ``[*seed, k]``), e.g. to filter them under several tunings with :func:`filter_trial_sets`.

    Parameters are those of :func:`direction_response`; returns a list of ``n_repeats * n`` TrialInputs.
    """
    _check_setup(setup)
    dirs = validation.as_array(directions, "directions", ndim=(2,), last=2, min_size=2)
    mag = validation.positive(magnitude_m_s, "magnitude_m_s")
    n_rep = validation.integer(n_repeats, "n_repeats", minimum=1)
    base = validation.int_seed_list(seed, "seed", why="repeats append an index")
    return _direction_trials(setup, dirs, mag, n_rep, base, validation.real(burn_offset_hours, "burn_offset_hours"))


def _direction_trials(setup, dirs, mag, n_rep, base, off) -> list:
    """:func:`direction_trials` after its checks."""
    t_burn = setup.t_maneuver + off * 3600.0 / setup.system.time_unit_s
    if not setup.scenario.t[0] < t_burn < setup.scenario.t[-1]:
        raise ValueError(f"burn_offset_hours puts the burn outside the track; got {off!r}")
    per_dir = [_draw_trials([np.random.default_rng(base + [k]) for k in range(n_rep)], setup, None, mag,
                            np.asarray(d, float), t_burn) for d in dirs]
    return [per_dir[j][k] for k in range(n_rep) for j in range(len(dirs))]


@dataclass(frozen=True)
class HealthLeadStudy:
    """Which reacts first to an unexpected burn: the control integral or the measurement residuals? (Fig. 22)

    Both tests are online (they use only the data received so far) and are evaluated at the epochs following
    the burn, up to a horizon; each fires at the first epoch where its statistic passes the same per-epoch tail
    probability ``tail_probability`` of its no-burn distribution:

    * *control test*: the smoothed control integral over the arc received so far,
      :math:`z_k = \\int_{t_0}^{t_k}\\|\\hat{\\mathbf u}\\|dt` (the fixed-interval smoother rerun on the data up to
      epoch :math:`k`), above the upper ``tail_probability`` quantile of a log-normal law fitted to the
      no-burn (H0) calibration runs at the same epoch;
    * *residual test*: the squared whitened innovation of epoch :math:`k` (the forward OCBE metric,
      :math:`\\chi^2_m` for a correct model) above its ``tail_probability`` quantile.

    Attributes
    ----------
    magnitudes_m_s : ndarray, shape (M,)
        Burn sizes, m/s (random pointing, Eqs. 3-4).
    delay_hours : ndarray, shape (K,)
        Time from the burn to each epoch of the horizon, hours.
    control_epoch, residual_epoch : ndarray of int, shape (M, n_h1)
        Index into ``delay_hours`` of the epoch at which each test first fires, -1 if it does not fire within the
        horizon.
    false_alarm_control, false_alarm_residual : float
        Fraction of independent no-burn validation runs in which the test fires within the horizon.
    z_final_m_s : ndarray, shape (M, n_h1)
        Smoothed control integral of the whole track, m/s (the paper's health value, Eq. 33).
    z_h0_final_m_s : ndarray, shape (n_h0,)
        The same for the no-burn calibration runs.
    tail_probability : float
    """

    magnitudes_m_s: np.ndarray
    delay_hours: np.ndarray
    control_epoch: np.ndarray
    residual_epoch: np.ndarray
    false_alarm_control: float
    false_alarm_residual: float
    z_final_m_s: np.ndarray
    z_h0_final_m_s: np.ndarray
    tail_probability: float

    def outcome_fractions(self) -> dict:
        """Per burn size, the fractions of runs in which the control test fires first, the residual test fires
        first, both fire at the same epoch, or neither fires within the horizon (each an array of shape (M,))."""
        c, r = self.control_epoch, self.residual_epoch
        big = np.iinfo(np.int64).max
        cc, rr = np.where(c >= 0, c, big), np.where(r >= 0, r, big)
        return {"control first": np.mean(cc < rr, axis=1), "residual first": np.mean(rr < cc, axis=1),
                "same epoch": np.mean((cc == rr) & (c >= 0), axis=1),
                "neither": np.mean((c < 0) & (r < 0), axis=1)}

    def median_delay_hours(self, test: str) -> np.ndarray:
        """Median time from the burn to the firing of ``test`` ('control' or 'residual') among the runs in which
        it fires, per burn size, hours (NaN when it never fires)."""
        test = validation.choice(test, "test", ("control", "residual"))
        k = self.control_epoch if test == "control" else self.residual_epoch
        out = np.full(k.shape[0], np.nan)
        for i, row in enumerate(k):
            if np.any(row >= 0):
                out[i] = float(np.median(self.delay_hours[row[row >= 0]]))
        return out


def _first_true(mask) -> np.ndarray:
    """Index of the first True along the last axis, -1 where there is none."""
    mask = np.asarray(mask, bool)
    return np.where(mask.any(axis=-1), np.argmax(mask, axis=-1), -1)


def health_lead_study(setup: DetectionSetup, magnitudes_m_s, n_h0: int, n_h1: int, seed, *,
                      horizon_hours: float = 24.0, tail_probability: float = float(stats.norm.sf(3.0)),
                      executor=None, progress: bool = False) -> HealthLeadStudy:
    """Race between the control integral and the residuals after a burn the tuning does not expect (Fig. 22).

    ``n_h0`` no-burn runs calibrate the control test (seed ``[*seed, 0]``), ``n_h0`` more measure both tests'
    false alarms (``[*seed, 1]``), and ``n_h1`` randomly pointed burns of each size (``[*seed, 2, i]``) are
    followed epoch by epoch over the horizon; see :class:`HealthLeadStudy` for the two tests.  The smoother is
    rerun on the growing data arc at every epoch of the horizon: one forward filter pass over the track serves
    every arc (the filter on an arc is the start of the filter on the track) and each arc gets its own backward
    pass (``smooth_ends`` of :func:`cislunar.estimation.batched_ocbe.ocbe_batch`; bit for bit the filter and
    smoother rerun on each arc, ``tests/papers/greaves_scheeres_2021/test_detection.py``).  The runs go through
    ``executor`` in lockstep groups of :data:`LOCKSTEP_TRIALS` (results identical whatever the executor).

    Parameters
    ----------
    setup : DetectionSetup
        Scenario and tuning (e.g. the quiet policy's window tuning).
    magnitudes_m_s : array_like, shape (M,)
        Burn sizes, m/s (positive).
    n_h0, n_h1 : int
        Runs per no-burn set (calibration and validation; at least 10) and per burn size.
    seed : int or list of int
    horizon_hours : float
        How long after the burn the tests are followed, hours; the horizon must end inside the track.
    tail_probability : float
        Per-epoch tail probability of both tests under no burn (default: the 3-sigma tail, 0.00135).
    executor : concurrent.futures-style executor, optional
    progress : bool
    """

    _check_setup(setup)
    mags = validation.as_array(magnitudes_m_s, "magnitudes_m_s", ndim=(1,), min_size=1)
    if np.any(mags <= 0):
        raise ValueError("magnitudes_m_s must be positive")
    n0 = validation.integer(n_h0, "n_h0", minimum=10)
    n1 = validation.integer(n_h1, "n_h1", minimum=1)
    base = validation.int_seed_list(seed, "seed", why="the sets append an index")
    horizon = validation.positive(horizon_hours, "horizon_hours")
    p = validation.in_range(tail_probability, "tail_probability", 0.0, 0.5, closed=False)
    validation.boolean(progress, "progress")
    sc, em = setup.scenario, setup.system
    hours = (sc.t - setup.t_maneuver) * em.time_unit_s / 3600.0
    k0 = int(np.searchsorted(sc.t, setup.t_maneuver, side="right"))  # first epoch that sees the burn
    ks = np.flatnonzero((hours > 0) & (hours <= horizon))
    if ks.size == 0 or ks[-1] >= sc.t.size - 1 or ks[0] != k0:
        raise ValueError(f"horizon_hours must leave the horizon inside the track; got {horizon_hours!r}")
    cal = _draw_trials(np.random.default_rng(base + [0]).spawn(n0), setup, None, None, None, setup.t_maneuver)
    val = _draw_trials(np.random.default_rng(base + [1]).spawn(n0), setup, None, None, None, setup.t_maneuver)
    burns = [inp for i, m in enumerate(mags) for inp in _draw_trials(np.random.default_rng(base + [2, i]).spawn(n1),
                                                                        setup, None, float(m), None, setup.t_maneuver)]
    everything = cal + val + burns
    # lockstep groups of whole integrator lane groups (so that every trial keeps the lanes filter_trials gives it),
    # about four per study so that an executor has work to share, at most LOCKSTEP_TRIALS trials each
    lanes = batched_ocbe._LANES
    per = min(LOCKSTEP_TRIALS, lanes * -(-len(everything) // (4 * lanes)))
    tasks = [(setup, everything[a:a + per], ks) for a in range(0, len(everything), per)]
    arcs = map_tasks(_arc_statistics, tasks, executor=executor, progress=progress, desc="health arcs")
    z_arc = np.concatenate([a[0] for a in arcs])  # (runs, K) smoothed z of the arc up to each epoch, m/s
    z_full = np.concatenate([a[1] for a in arcs])
    resid2 = np.concatenate([a[2] for a in arcs])
    r2 = resid2[:, ks]  # squared whitened innovations at the horizon epochs
    logz = np.log(z_arc[:n0])
    lim_c = np.exp(logz.mean(axis=0) + stats.norm.isf(p) * logz.std(axis=0, ddof=1))
    lim_r = stats.chi2.isf(p, sc.model.dim)
    fire_c, fire_r = _first_true(z_arc > lim_c), _first_true(r2 > lim_r)
    v = slice(n0, 2 * n0)
    b = slice(2 * n0, None)
    M = mags.size
    return HealthLeadStudy(mags, hours[ks], fire_c[b].reshape(M, n1), fire_r[b].reshape(M, n1),
                           float(np.mean(fire_c[v] >= 0)), float(np.mean(fire_r[v] >= 0)),
                           z_full[b].reshape(M, n1), z_full[:n0], p)


def _arc_statistics(task):
    """One lockstep group of :func:`health_lead_study`: ``task = (setup, inputs, ends)`` (at most
    :data:`LOCKSTEP_TRIALS` trials, end epochs ``ends``).  Returns ``(z of each arc t[0] .. t[e], shape (B, E);
    z of the whole track, (B,); squared whitened innovations, (B, N))``, z in m/s, from one forward pass."""
    setup, inputs, ends = task
    sc = setup.scenario
    res = ocbe_batch(setup.system, sc.t, np.array([i.y for i in inputs]), setup.observer_states, sc.model,
                     sc.meas_cov, np.array([i.x0 for i in inputs]), np.array([i.P0 for i in inputs]),
                     setup.control_weight, n_sub=setup.n_sub, tol=setup.tol, smooth_ends=ends)
    v = setup.system.velocity_unit_km_s * 1e3
    return res.z_smooth_ends * v, res.z_smooth * v, res.residual_norms**2
