r"""The studies of the mutual-information chapter (notebook 02): Wolf & Jones Eqs. 9-23 and 44-52 on test case 2.

What is here:

* :func:`scalar_worked_example`: the mutual information of a scalar linear-Gaussian measurement three ways
  (closed form, expected KL divergence of Eq. 11, joint Monte Carlo of the log ratio).
* :func:`constant_velocity_toy`: a 1-D constant-velocity window whose stacked matrices (Eqs. 19-23) are small
  enough to print.
* :func:`case_2_window`: test case 2's observation window :math:`[P_{ref}, 2P_{ref}]` with the observer coasting on
  its initial reference DRO (Table 4's first row corrected into a DRO, the scenario of notebook 06, whose period
  is :math:`P_{ref}`: :func:`reference_period`), linearised with derivatives (the model the gradient needs).  The
  window is notebook 06's, with the same priors, process noise and measurement times: the observer's state at the
  window start is that of 06's ballistic guess.
* :func:`window_crlb`: the CRLB (EKF covariance recursion) along that window, split into total, in-plane and
  out-of-plane position RMS, with the per-measurement information gains (chain rule).
* :class:`Eq18Precision`: Eq. 18 in extended precision and the round-off scale of its float64 dense form (the
  reference the chain rule is judged against).
* :class:`Case1Readings`: test case 1's CRLB under each reading of the printed process noise (is it bounded after
  the transient, as the text of Fig. 4 says?).
* :func:`gradient_check`, :func:`linearisation_check`: the gradient of Eqs. 44-52 against fourth-order central
  differences, and the range over which the first-order model of Eq. 44 holds.
* :func:`baseline_study`: MI and terminal CRLB as an observer leads a target along the same DRO (Markley / Psiaki).
* :func:`timing_study`, :func:`crossover`: dense Eq. 18 against the chain rule, value and gradient.
* ``figure_*``: the chapter's figures from these results.

Units: states and times non-dimensional (LU, LU/TU, TU) unless a name says ``_km``, ``_d`` or ``_s``; frames are the
Earth-Moon rotating frame; information in nats.
"""

from __future__ import annotations

from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, EARTH_MOON, check_system
from cislunar.cr3bp.propagation import find_events, propagate
from cislunar.papers.wolf_jones import _checks
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.sensing import covariance as cov
from cislunar.sensing import information as info
from cislunar.sensing import measurements as meas
from cislunar.sensing.covariance import AugmentedLinearization
from cislunar.utils import validation
from cislunar.utils.montecarlo import map_tasks

__all__ = [
    "OBSERVER_TF_X0",
    "TARGETS_X0",
    "BaselineCurve",
    "Case1Readings",
    "Case2Window",
    "Eq18Precision",
    "GradientCheck",
    "LinearisationCheck",
    "ScalarExample",
    "TimingStudy",
    "ToyWindow",
    "WindowCRLB",
    "baseline_study",
    "case_2_window",
    "constant_velocity_toy",
    "crossover",
    "figure_angular_noise",
    "figure_baseline",
    "figure_crlb",
    "figure_timing",
    "reference_period",
    "gradient_check",
    "linearisation_check",
    "observer_information",
    "scalar_worked_example",
    "timing_study",
    "window_crlb",
]

#: Table 4 ``observer_tf`` DRO as printed (closes as a periodic orbit), LU and LU/TU.  Until 2026-11-26 the window's
#: coasting observer and P_ref came from it (P_ref 16.02 d against notebook 06's 16.17 d); kept for reference.
OBSERVER_TF_X0 = np.array([7.80136159e-1, 0, 0, 0, 5.53104815e-1, 0])
#: Table 4 target DROs of test case 2, one row each, LU and LU/TU.
TARGETS_X0 = np.array([[7.78717734e-1, 0, 0, 0, 5.55157488e-1, 0],
                       [7.79426943e-1, 0, 0, 0, 5.54128887e-1, 0],
                       [7.81554639e-1, 0, 0, 0, 5.51070308e-1, 0]])
OBJECT_NAMES = ("observer", "target 1", "target 2", "target 3")


def _period(system: CR3BP, x0) -> float:
    """Period of a planar symmetric orbit (second y-crossing), TU."""
    return float(find_events(system, x0, 10.0, ("y_crossing",)).t[1])


# ---------------------------------------------------------------------------------------------------------------
# Eqs. 9-11 and 12-23 on small examples
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ScalarExample:
    """Mutual information of ``y = h x + v``, ``x ~ N(0, p)``, ``v ~ N(0, r)``, three ways (nats)."""

    p: float
    h: float
    r: float
    n_samples: int
    closed: float  #: 0.5 ln(1 + h^2 p / r)
    kl_mean: float  #: sample mean of KL(p(y|x) || p(y)) over x (Eq. 11)
    kl_se: float  #: its standard error
    monte_carlo: float  #: joint Monte Carlo mean of ln p(y|x) - ln p(y)
    monte_carlo_se: float

    @property
    def std_ratio(self) -> float:
        """Posterior over prior standard deviation, equal to exp(-I)."""
        return float(np.sqrt(1 / (1 / self.p + self.h**2 / self.r)) / np.sqrt(self.p))


def scalar_worked_example(n_samples: int, rng: np.random.Generator, *, p: float = 4.0, h: float = 1.0,
                          r: float = 1.0) -> ScalarExample:
    """The scalar worked example of Eq. 11: closed form, expected KL over ``n_samples`` draws of ``x`` and the
    joint Monte Carlo estimate, in that order of random draws from ``rng``."""
    n = validation.integer(n_samples, "n_samples", minimum=2)
    validation.instance(rng, "rng", np.random.Generator)
    p, r = validation.positive(p, "p"), validation.positive(r, "r")
    h = float(validation.real(h, "h"))
    closed = 0.5 * np.log(1 + h**2 * p / r)
    xs = rng.normal(0.0, np.sqrt(p), size=n)
    kl = info.gaussian_kl((h * xs)[:, None], [[r]], [0.0], [[h**2 * p + r]])  # KL(p(y|x) || p(y)) for each x
    mc, se = info.monte_carlo_mutual_information([[p]], np.zeros((0, 1, 1)), np.zeros((0, 1, 1)), [[[h]]], [[r]],
                                                 n, rng)
    return ScalarExample(p, h, r, n, float(closed), float(kl.mean()), float(kl.std(ddof=1) / np.sqrt(n)), mc, se)


@dataclass(frozen=True)
class ToyWindow:
    """A linear window: prior ``P0``, transitions ``F``, process noises ``Q``, Jacobians ``H``, noises ``R``."""

    P0: np.ndarray
    F: np.ndarray
    Q: np.ndarray
    H: np.ndarray
    R: np.ndarray

    @property
    def arrays(self) -> tuple:
        return self.P0, self.F, self.Q, self.H, self.R


def constant_velocity_toy(dt: float = 1.0, n_times: int = 3, *, psd: float = 0.01, r: float = 0.25) -> ToyWindow:
    """1-D constant velocity (position, velocity), position measured at ``n_times`` times ``dt`` apart with noise
    variance ``r``; process noise of PSD ``psd`` discretised exactly (Van Loan); prior ``diag(1, 0.5)``."""
    dt = validation.positive(dt, "dt")
    n = validation.integer(n_times, "n_times", minimum=2)
    psd = validation.positive(psd, "psd", allow_zero=True)
    r = validation.positive(r, "r")
    F = np.tile([[1.0, dt], [0.0, 1.0]], (n - 1, 1, 1))
    Q = np.tile(psd * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]]), (n - 1, 1, 1))
    H = np.tile([[[1.0, 0.0]]], (n, 1, 1))
    R = np.tile([[[r]]], (n, 1, 1))
    return ToyWindow(np.diag([1.0, 0.5]), F, Q, H, R)


# ---------------------------------------------------------------------------------------------------------------
# Test case 2 window and its CRLB
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Case2Window:
    """Test case 2's observation window with a coasting observer.

    Attributes
    ----------
    P_ref : float
        Period of the observer's DRO, TU; the window is ``[P_ref, 2 P_ref]``.
    start : ndarray, shape (4, 6)
        Observer and the three targets at the window start (rotating frame, LU, LU/TU).
    t : ndarray
        Measurement times (daily), TU.
    day : float
        One day, TU.
    P_obj, R, q : per-object prior covariance, range/range-rate noise covariance, process-noise PSD (LU^2/TU^3).
    lin : AugmentedLinearization
        The window linearised with derivatives with respect to the observer's window-start state.
    target_periods_d : tuple of float
        Periods of the three target DROs, days.
    """

    system: CR3BP
    P_ref: float
    start: np.ndarray
    t: np.ndarray
    day: float
    P_obj: np.ndarray
    R: np.ndarray
    q: float
    lin: AugmentedLinearization
    target_periods_d: tuple

    @property
    def days(self) -> np.ndarray:
        return np.asarray(self.system.tu_to_days(self.t))


def reference_period(system: CR3BP = EARTH_MOON) -> float:
    """P_ref of test case 2, TU: the period of the observer's initial reference DRO (Table 4's first row, its vy0
    corrected holding x0), the same as notebook 06's ``test_case_2().period``."""
    check_system(system)
    return float(wj.test_case_2(system).period)


def case_2_window(system: CR3BP = EARTH_MOON, t: np.ndarray | None = None, *,
                  range_sigma_km: float = meas.WOLF_JONES_RANGE_SIGMA_KM,
                  range_rate_sigma_km_s: float = meas.WOLF_JONES_RANGE_RATE_SIGMA_KM_S) -> Case2Window:
    """Linearise test case 2's window ``[P_ref, 2 P_ref]`` about the observer coasting on its initial reference DRO
    and the three target DROs (Table 4 rows corrected into periodic orbits, as in
    :func:`cislunar.papers.wolf_jones.scenarios.test_case_2`; notebook 06's window and ballistic observer).

    ``t`` (TU) replaces the scenario's daily measurement times; the states are those at the window start
    ``P_ref`` and ``t[0]`` is taken as that epoch (the CR3BP is autonomous).  Range and range rate with noise
    standard deviations ``range_sigma_km`` (km) and ``range_rate_sigma_km_s`` (km/s; default Table 5's 100 m and
    10 m/s), Table 5 priors, the scenario's process noise (the adopted normalised reading, 1e-11 LU^2/TU^3).
    """
    check_system(system)
    range_sigma_km = validation.positive(range_sigma_km, "range_sigma_km")
    range_rate_sigma_km_s = validation.positive(range_rate_sigma_km_s, "range_rate_sigma_km_s")
    sc = wj.test_case_2(system)
    P_ref = sc.period
    start = propagate(system, np.vstack([sc.observer_x0, sc.targets_x0]), [0.0, sc.window[0]]).x[:, -1]
    day = float(system.days_to_tu(1.0))
    t_win = sc.measurement_times if t is None else np.asarray(t, dtype=float)
    P_obj = cov.state_covariance(sc.sigma_pos_km, sc.sigma_vel_km_s, system)
    R_rr = meas.range_range_rate_noise(range_sigma_km, range_rate_sigma_km_s, system)
    q_nd = sc.q
    lin = cov.linearize_augmented(system, start[0], start[1:], t_win, meas.RANGE_RANGE_RATE, R_rr,
                                  cov.block_diag([P_obj] * 4), q=q_nd, derivatives=True)
    periods = tuple(float(system.tu_to_days(_period(system, x))) for x in sc.targets_x0)
    return Case2Window(system, P_ref, start, t_win, day, P_obj, R_rr, q_nd, lin, periods)


@dataclass(frozen=True)
class WindowCRLB:
    """CRLB along the window, per object (rows: observer, targets 1-3), position RMS in km.

    ``total``, ``prior``: sqrt of the trace of the position block after / before each update; ``in_plane``: over
    x and y; ``out_of_plane``: z alone.  ``gains``: information gain of each measurement (chain rule), nats.
    """

    days: np.ndarray
    total: np.ndarray
    prior: np.ndarray
    in_plane: np.ndarray
    out_of_plane: np.ndarray
    gains: np.ndarray
    mi_dense: float
    mi_chain: float
    largest_z_jacobian: float  #: largest ``|dH/dz|``, ``|dH/dvz|`` entry over the window

    @property
    def relative_difference(self) -> float:
        """``|dense - chain rule| / dense`` for Eq. 18."""
        return abs(self.mi_dense - self.mi_chain) / self.mi_dense

    @property
    def transient(self) -> np.ndarray:
        """Per object: in-plane RMS after the second update above that after the first."""
        return self.in_plane[:, 1] > self.in_plane[:, 0]

    @property
    def out_of_plane_share(self) -> float:
        """Out-of-plane share of the summed terminal position variance."""
        return float(np.sum(self.out_of_plane[:, -1]**2) / np.sum(self.total[:, -1]**2))

    @property
    def observer_below_targets(self) -> bool:
        """The observer's mean total RMS over the window is below the targets' mean."""
        return bool(self.total[0].mean() < self.total[1:].mean())


def window_crlb(window: Case2Window) -> WindowCRLB:
    """The CRLB of the window by the EKF covariance recursion (Joseph form), with Eq. 18 dense and by chain rule."""
    validation.instance(window, "window", Case2Window)
    lin, em = window.lin, window.system
    mi_dense = info.window_information(lin, method="dense")
    mi_chain, gains = info.mutual_information(*lin.arrays, return_terms=True)
    hist = cov.covariance_analysis(*lin.arrays)

    def sig(P, axes=(0, 1, 2)):
        return np.array([cov.position_sigma_km(P, i, em, axes=axes) for i in range(4)])

    z_cols = np.abs(lin.H[..., [6 * i + j for i in range(4) for j in (2, 5)]]).max()
    return WindowCRLB(window.days, sig(hist.posterior), sig(hist.prior), sig(hist.posterior, (0, 1)),
                      sig(hist.posterior, (2,)), np.asarray(gains), float(mi_dense), float(mi_chain), float(z_cols))


# ---------------------------------------------------------------------------------------------------------------
# Eq. 18 in extended precision: the reference the chain rule is judged against
# ---------------------------------------------------------------------------------------------------------------


def _logdet_extended(A) -> np.longdouble:
    """``ln|A|`` of a symmetric positive-definite matrix by a Cholesky (LDL^T) sweep in ``np.longdouble``."""
    A = np.array(A, dtype=np.longdouble)
    total = np.longdouble(0)
    for k in range(A.shape[0]):
        p = A[k, k]
        if not p > 0:
            raise ValueError("the stacked innovation covariance is not positive definite in extended precision")
        total += np.log(p)
        A[k + 1:, k + 1:] -= np.outer(A[k + 1:, k] / p, A[k, k + 1:])
    return total


@dataclass(frozen=True)
class Eq18Precision:
    r"""Eq. 18 of a window evaluated densely in extended precision, and the round-off scale of the float64 dense form.

    The reference is :math:`\tfrac12(\ln|\tilde S| - \ln|\tilde R|)` with :math:`\tilde S = \tilde H\tilde P
    \tilde H^T + \tilde R` formed and factorised in ``np.longdouble`` (unit round-off ``extended_eps / 2``; on
    platforms where it is float64 the reference is only as good as the dense form) from the same float64 stacked
    matrices: an evaluation of Eq. 18 that shares nothing with the Kalman recursion but its inputs.

    ``bound`` is the first-order round-off scale of the float64 dense form, :math:`\tfrac12\,n\,u\,\kappa_2(\tilde
    S)` nats, with :math:`n` the dimension of :math:`\tilde S` and :math:`u = 2^{-53}`: a backward-stable formation
    and Cholesky factorisation return the exact log-determinant of :math:`\tilde S + \Delta S` with
    :math:`\|\Delta S\|_2 \lesssim u\|\tilde S\|_2`, and :math:`|\Delta\ln|\tilde S|| = |\mathrm{tr}(\tilde S^{-1}
    \Delta S)| \le n\,\|\tilde S^{-1}\|_2\|\Delta S\|_2`; the MI is half the log-determinant.  The constant of the
    backward error (a modest multiple of :math:`n` in the worst case) is taken as 1: an order-of-magnitude scale.

    Attributes
    ----------
    reference : float
        Eq. 18 in extended precision, nats.
    dense : float
        Eq. 18 in float64 (:func:`cislunar.sensing.information.mutual_information_dense`), nats.
    condition : float
        :math:`\kappa_2(\tilde S)` (float64 singular values).
    size : int
        Dimension of :math:`\tilde S` (measurements times measurement dimension).
    extended_eps : float
        Machine epsilon of ``np.longdouble``.
    """

    reference: float
    dense: float
    condition: float
    size: int
    extended_eps: float

    @property
    def bound(self) -> float:
        r"""Round-off scale of the float64 dense Eq. 18, :math:`\tfrac12 n u \kappa_2(\tilde S)`, nats."""
        return 0.5 * self.size * (np.finfo(np.float64).eps / 2) * self.condition

    def ratio(self, value) -> float:
        """``|value - reference| / bound`` for a value of Eq. 18 (nats): at most 1 when ``value`` is Eq. 18 to the
        precision of the float64 dense form."""
        v = validation.real(value, "value")
        return abs(float(v) - self.reference) / self.bound

    @classmethod
    def of(cls, P0, F, Q, H, R) -> "Eq18Precision":
        """Evaluate Eq. 18 of the window ``(P0, F, Q, H, R)`` (as :func:`cislunar.sensing.information.stacked_matrices`)
        in extended precision and in float64."""
        Pt, Ht, Rt = info.stacked_matrices(P0, F, Q, H, R)
        S = Ht @ Pt @ Ht.T + Rt
        S = 0.5 * (S + S.T)
        L = np.longdouble
        Hl = Ht.astype(L)
        Sl = Hl @ Pt.astype(L) @ Hl.T + Rt.astype(L)
        reference = 0.5 * (_logdet_extended(0.5 * (Sl + Sl.T)) - _logdet_extended(Rt))
        return cls(float(reference), float(info.mutual_information_dense(P0, F, Q, H, R)),
                   float(np.linalg.cond(S)), int(S.shape[0]), float(np.finfo(L).eps))


# ---------------------------------------------------------------------------------------------------------------
# The printed process noise (Tables 3 and 5): which readings keep test case 1's CRLB bounded
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Case1Readings:
    """Test case 1's CRLB under each reading of the printed process noise "Q [km/s^3] = 1e-11" (Tables 3 and 5).

    The observer coasts on its initial DRO (Table 2's row corrected, notebook 01) to the window ``[3P/4, 3P/2]``,
    where the paper commands no thrust; the target flies its DRO; relative position every day, 100 m per axis;
    Table 3 priors (the same statement, :func:`cislunar.papers.wolf_jones.scenarios.evaluate_crlb`, that notebook 05
    applies to its solved plans).  The coasting observer is a stand-in for the alpha_h = 0 plan, whose window start
    differs.

    Attributes
    ----------
    labels : tuple of str
        Keys of :data:`cislunar.papers.wolf_jones.scenarios.PROCESS_NOISE_READINGS_KM2_S3`, in its order.
    q_km2_s3 : ndarray (n_readings,)
        Acceleration PSD of each reading, km^2/s^3.
    rms_km : ndarray (n_readings, 2, N)
        Position RMS (CRLB) of observer (row 0) and target after each of the N measurements, km.
    """

    labels: tuple
    q_km2_s3: np.ndarray
    rms_km: np.ndarray

    @staticmethod
    def growth_of(rms_km) -> float:
        """The Fig. 4 test (notebook 05's, fixed there before comparing): the largest, over the objects, window-end
        position RMS over the RMS after the 2nd measurement.  At most 1: the measurements bound the error after the
        initial transient.  ``rms_km``: (objects, N >= 2), km."""
        r = validation.as_array(rms_km, "rms_km", ndim=(2,))
        if r.shape[1] < 2 or not np.all(r[:, 1] > 0):
            raise ValueError(f"rms_km must have at least two positive columns (objects, N >= 2); got shape {r.shape}")
        return float(np.max(r[:, -1] / r[:, 1]))

    @property
    def growth(self) -> np.ndarray:
        """:meth:`growth_of` of each reading."""
        return np.array([self.growth_of(r) for r in self.rms_km])

    @property
    def adopted(self) -> int:
        """Index of the adopted reading (1e-11 LU^2/TU^3)."""
        return next(i for i, label in enumerate(self.labels) if "adopted" in label)

    @classmethod
    def of(cls, system: CR3BP = EARTH_MOON) -> "Case1Readings":
        """Evaluate the CRLB of test case 1's coasting observer and its target under every reading."""
        check_system(system)
        sc = wj.test_case_1(system)
        x_ws = propagate(system, sc.observer_x0, [0.0, sc.window[0]]).x[-1]
        labels = tuple(wj.PROCESS_NOISE_READINGS_KM2_S3)
        q = np.array([wj.PROCESS_NOISE_READINGS_KM2_S3[k] for k in labels])
        rms = np.stack([wj.evaluate_crlb(sc, x_ws, q=cov.psd_to_nondimensional(qk, system)).rms_km for qk in q])
        return cls(labels, q, rms)


# ---------------------------------------------------------------------------------------------------------------
# Eqs. 44-52: gradient and the range of the first-order model
# ---------------------------------------------------------------------------------------------------------------


def observer_information(window: Case2Window, x) -> float:
    """Eq. 18 (chain rule) of the window re-propagated from observer window-start state ``x`` (LU, LU/TU), with the
    process noise held at the reference's (as the paper's gradient assumes)."""
    validation.instance(window, "window", Case2Window)
    x = validation.as_state(x, "x", batch=False)
    lin = window.lin
    return info.window_information(cov.linearize_augmented(window.system, x, window.start[1:], window.t,
                                                           meas.RANGE_RANGE_RATE, window.R, lin.P0, Q=lin.Q))


@dataclass(frozen=True)
class GradientCheck:
    """Gradient of Eq. 18 with respect to the observer's window-start state (nats/LU, nats/(LU/TU))."""

    value: float
    structured: np.ndarray
    dense: np.ndarray
    finite_difference: np.ndarray
    step: float

    @property
    def error(self) -> float:
        """``max |structured - FD| / max |FD|``."""
        return float(np.max(np.abs(self.structured - self.finite_difference)) / np.max(np.abs(self.finite_difference)))

    @property
    def dense_error(self) -> float:
        """``max |structured - dense| / max |dense|``."""
        return float(np.max(np.abs(self.structured - self.dense)) / np.max(np.abs(self.dense)))


def gradient_check(window: Case2Window, step: float = 1e-6) -> GradientCheck:
    """Structured (reverse-mode square-root) and dense (Eqs. 47-50) gradients against fourth-order central
    differences of :func:`observer_information` at ``step`` (non-dimensional)."""
    validation.instance(window, "window", Case2Window)
    h = validation.positive(step, "step")
    value, g_struct = info.window_information(window.lin, gradient=True)
    _, g_dense = info.window_information(window.lin, gradient=True, method="dense")
    x0 = window.start[0]

    def f(x):
        return observer_information(window, x)

    g_fd = np.array([(8 * (f(x0 + h * e) - f(x0 - h * e)) - (f(x0 + 2 * h * e) - f(x0 - 2 * h * e))) / (12 * h)
                     for e in np.eye(6)])
    return GradientCheck(float(value), np.asarray(g_struct), np.asarray(g_dense), g_fd, h)


@dataclass(frozen=True)
class LinearisationCheck:
    """True MI against Eq. 44 along the unit gradient direction; steps in km-equivalent (norm of the 6-vector)."""

    steps_km: np.ndarray
    dx: np.ndarray  #: (n, 6) steps, LU and LU/TU
    true: np.ndarray
    linear: np.ndarray

    @property
    def error(self) -> np.ndarray:
        return np.abs(self.true - self.linear)


def linearisation_check(window: Case2Window, gradient: GradientCheck,
                        steps_km=(1.0, 10.0, 100.0, 1000.0)) -> LinearisationCheck:
    """Step the observer along the unit structured gradient by each of ``steps_km`` (km converted to LU) and compare
    the re-propagated MI with ``I + grad . dx`` (Eq. 44)."""
    validation.instance(window, "window", Case2Window)
    validation.instance(gradient, "gradient", GradientCheck)
    steps = _checks.vector(steps_km, "steps_km")
    direction = gradient.structured / np.linalg.norm(gradient.structured)
    dx = np.array([direction * window.system.km_to_lu(s) for s in steps])
    true = np.array([observer_information(window, window.start[0] + d) for d in dx])
    linear = np.array([gradient.value + gradient.structured @ d for d in dx])
    return LinearisationCheck(steps, dx, true, linear)


# ---------------------------------------------------------------------------------------------------------------
# Baseline (Markley / Psiaki)
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BaselineCurve:
    """MI and terminal CRLB against the observer-target baseline for one measurement type.

    Arrays per baseline: ``baseline`` (mean separation, LU), ``mi`` (nats), terminal position RMS in km of the
    observer (``obs``: total, ``obs_z``: z, ``obs_xy``: in-plane) and target (``tgt``, ``tgt_xy``).
    """

    name: str
    baseline: np.ndarray
    mi: np.ndarray
    obs: np.ndarray
    tgt: np.ndarray
    obs_z: np.ndarray
    obs_xy: np.ndarray
    tgt_xy: np.ndarray
    length_unit_km: float

    @property
    def baseline_km(self) -> np.ndarray:
        return self.baseline * self.length_unit_km

    @property
    def gain(self) -> float:
        """Largest MI gain over the shortest baseline, nats."""
        return float(self.mi.max() - self.mi[0])

    @property
    def peak_km(self) -> float:
        """Baseline of the MI peak, km."""
        return float(self.baseline_km[np.argmax(self.mi)])

    @property
    def best(self) -> int:
        """Index of the smallest in-plane observer RMS."""
        return int(np.argmin(self.obs_xy))

    @property
    def same_peak(self) -> bool:
        return int(np.argmax(self.mi)) == self.best

    @property
    def rms_drop(self) -> float:
        """In-plane observer RMS at the shortest baseline over its minimum."""
        return float(self.obs_xy[0] / self.obs_xy.min())

    @property
    def rebound(self) -> float:
        """In-plane observer RMS at the longest baseline over its minimum (> 1: worse again)."""
        return float(self.obs_xy[-1] / self.obs_xy[self.best])

    @property
    def mi_drop(self) -> float:
        return float(self.mi.max() - self.mi[-1])

    @property
    def out_of_plane_share(self) -> float:
        """Mean over baselines of the out-of-plane share of the observer's terminal variance."""
        return float(np.mean(self.obs_z**2 / self.obs**2))

    @property
    def observer_above_target_km(self) -> list:
        """Baselines (km, as text) where the observer's total RMS exceeds the target's by more than 5 %."""
        return [f"{b:.0f}" for b, o, g in zip(self.baseline_km, self.obs, self.tgt) if o > 1.05 * g]

    @property
    def step_improves(self) -> np.ndarray:
        """Per step to the next longer baseline: the MI rises and the observer's in-plane RMS falls (both strictly)."""
        return (np.diff(self.mi) > 0) & (np.diff(self.obs_xy) < 0)

    @property
    def improving_until(self) -> int:
        """Index of the longest baseline reached from the shortest with every step improving (last index: all do)."""
        bad = np.flatnonzero(~self.step_improves)
        return int(bad[0]) if bad.size else self.mi.size - 1

    @property
    def end_to_end_drop(self) -> float:
        """In-plane observer RMS at the shortest baseline over that at the longest."""
        return float(self.obs_xy[0] / self.obs_xy[-1])

    def improves_throughout(self, min_drop: float = 1.5) -> bool:
        """Every step to a longer baseline raises the MI and lowers the in-plane observer RMS, and that RMS falls by
        more than ``min_drop`` from the shortest to the longest baseline."""
        return bool(np.all(self.step_improves) and self.end_to_end_drop > min_drop)


def _baseline_row(task) -> tuple:
    """One (measurement type, observer start) cell of the baseline study, for
    :func:`cislunar.utils.montecarlo.map_tasks`: mean baseline (LU), MI (nats) and five terminal RMS (km)."""
    em, model, noise, xo, tgt, t_base, P0_pair, q = task
    lb = cov.linearize_augmented(em, xo, tgt[None], t_base, model, noise, P0_pair, q=q)
    P_end = cov.covariance_analysis(*lb.arrays).posterior[-1]
    return tuple(float(v) for v in (
        np.mean(np.linalg.norm(lb.targets[0, :, :3] - lb.observer[:, :3], axis=1)),
        info.mutual_information(*lb.arrays), cov.position_sigma_km(P_end, 0, em),
        cov.position_sigma_km(P_end, 1, em), cov.position_sigma_km(P_end, 0, em, axes=(2,)),
        cov.position_sigma_km(P_end, 0, em, axes=(0, 1)), cov.position_sigma_km(P_end, 1, em, axes=(0, 1))))


def baseline_study(window: Case2Window, n_baselines: int, *, min_phase: float = 0.002,
                   max_phase: float = 0.5, executor=None) -> tuple:
    """Observer on the first Table 4 target's DRO, ahead by a phase (fraction of the period, geometric from
    ``min_phase`` to ``max_phase``); one period of daily measurements, relative position (100 m per axis) and
    range + range rate (the window's noise).  Returns one :class:`BaselineCurve` per measurement type.

    The ``2 n_baselines`` covariance analyses are independent; they run through ``executor``
    (:func:`cislunar.utils.montecarlo.map_tasks`; ``None``: serially) with the same result either way.
    """
    validation.instance(window, "window", Case2Window)
    n = validation.integer(n_baselines, "n_baselines", minimum=2)
    min_phase = validation.in_range(min_phase, "min_phase", 0.0, 1.0, closed=False)
    max_phase = validation.in_range(max_phase, "max_phase", min_phase, 1.0, closed=False)
    em = window.system
    tgt = TARGETS_X0[0]
    P_tgt = _period(em, tgt)
    phases = np.geomspace(min_phase, max_phase, n)
    obs_starts = propagate(em, tgt, np.r_[0.0, phases * P_tgt]).x[1:]
    t_base = np.arange(0.0, P_tgt + 1e-12, window.day)
    P0_pair = cov.block_diag([window.P_obj] * 2)
    models = {"relative position (100 m)": (meas.RELATIVE_POSITION, meas.relative_position_noise(0.1, em)),
              "range + range rate": (meas.RANGE_RANGE_RATE, window.R)}
    tasks = [(em, model, noise, xo, tgt, t_base, P0_pair, window.q)
             for model, noise in models.values() for xo in obs_starts]
    rows = map_tasks(_baseline_row, tasks, executor=executor, progress=False, desc="baseline study")
    curves = []
    for k, name in enumerate(models):
        block = rows[k * n:(k + 1) * n]
        cols = [np.array([r[j] for r in block]) for j in range(7)]
        curves.append(BaselineCurve(name, *cols, em.length_unit_km))
    return tuple(curves)


# ---------------------------------------------------------------------------------------------------------------
# Cost of dense Eq. 18 against the chain rule
# ---------------------------------------------------------------------------------------------------------------


def crossover(sizes, ratios) -> str:
    """Window size at which the dense/structured time ratio first reaches 1 (log-log interpolation), as text."""
    _checks.vector(sizes, "sizes")
    sizes, ratios = list(sizes), _checks.vector(ratios, "ratios")
    if len(sizes) != ratios.size:
        raise ValueError(f"sizes and ratios must be of equal length; got {len(sizes)} and {ratios.size}")
    if np.any(ratios <= 0):
        raise ValueError("ratios must be positive (time ratios)")
    if ratios[0] >= 1.0:
        return f"at or below N = {sizes[0]}"
    j = int(np.argmax(ratios >= 1.0))
    if ratios[j] < 1.0:
        return f"above N = {sizes[-1]} (not reached)"
    n_star = np.exp(np.interp(0.0, np.log(ratios[j - 1:j + 1]), np.log(sizes[j - 1:j + 1])))
    return f"N = {n_star:.0f} (between {sizes[j - 1]} and {sizes[j]})"


@dataclass(frozen=True)
class TimingStudy:
    """Best-of-3 times (s) per evaluation for each window size (``results[i]`` for ``sizes[i]``)."""

    sizes: tuple
    results: tuple

    def at(self, n: int) -> info.TimingResult:
        return self.results[self.sizes.index(n)]

    @property
    def crossover_value(self) -> str:
        return crossover(self.sizes, [r.ratio_value for r in self.results])

    @property
    def crossover_gradient(self) -> str:
        return crossover(self.sizes, [r.ratio_gradient for r in self.results])


def timing_study(window: Case2Window, sizes, *, min_time: float = 0.1, repeat: int = 3) -> TimingStudy:
    """Time dense Eq. 18 and the chain rule (value, value + gradient) on one DRO period of the window's geometry
    with ``N`` equally spaced measurement times for each ``N`` in ``sizes``."""
    validation.instance(window, "window", Case2Window)
    sizes = _checks.integers(sizes, "sizes", minimum=2)
    min_time = validation.positive(min_time, "min_time")
    repeat = validation.integer(repeat, "repeat", minimum=1)
    results = []
    for n in sizes:
        t_n = np.linspace(window.P_ref, 2 * window.P_ref, n)
        ln = cov.linearize_augmented(window.system, window.start[0], window.start[1:], t_n, meas.RANGE_RANGE_RATE,
                                     window.R, window.lin.P0, q=window.q, derivatives=True)
        results.append(info.time_evaluations(*ln.arrays, ln.dF, ln.dH, repeat=repeat, min_time=min_time))
    return TimingStudy(sizes, tuple(results))


# ---------------------------------------------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------------------------------------------


def figure_angular_noise(mean_range_km: float = 215.0):
    """AMOS Eq. 20 angular noise against range, with the resolution/pointing crossover and the AMOS mean range."""
    mean_range_km = validation.positive(mean_range_km, "mean_range_km")
    rho_km = np.logspace(0, 5, 200)  # 1 km up: below it the noise exceeds 4 mrad, of no use for tracking
    sig = meas.angular_sigma(rho_km, meas.AMOS_SIGMA_MIN_RAD, meas.AMOS_RESOLUTION_KM)
    fig, ax = plt.subplots(figsize=(5.5, 3.5))
    ax.loglog(rho_km, sig * 1e6, label=r"$\sqrt{\sigma_{min}^2 + D^2/\rho^2}$ (AMOS Eq. 20)")
    ax.axvline(meas.AMOS_RESOLUTION_KM / meas.AMOS_SIGMA_MIN_RAD, color="0.5", ls=":",
               label=r"$\rho = D/\sigma_{min}$ = 400 km")
    ax.axvline(mean_range_km, color="C3", ls="--", label=f"{mean_range_km:g} km: AMOS mean agent-target range")
    ax.set(xlabel="range [km]", ylabel=r"$\sigma_\theta$ [µrad]", title="Angular noise model")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=1, frameon=False)  # below the axes
    return fig


def figure_crlb(crlb: WindowCRLB):
    """Total / in-plane / out-of-plane RMS along the window, target over observer in-plane RMS, and the gains."""
    validation.instance(crlb, "crlb", WindowCRLB)
    days = crlb.days
    fig, (ax1, ax2, ax3) = plt.subplots(1, 3, figsize=(14, 4.0), layout="constrained")
    for i in range(4):
        ax1.semilogy(days, crlb.total[i], "-", lw=2.5, color="0.8",
                     label="total, all four (coincide)" if i == 0 else None, zorder=1)
    for i, name in enumerate(OBJECT_NAMES):
        ax1.semilogy(days, crlb.in_plane[i], "o-", ms=3, lw=1, color=f"C{i}", label=f"in-plane, {name}", zorder=3)
    ax1.semilogy(days, crlb.out_of_plane[0], "k--", lw=1, label=r"out-of-plane $\sigma_z$ (free flight)", zorder=2)
    ax1.set(xlabel="time [days]", ylabel="position RMS (CRLB) [km]", title="CRLB along the window (cf. Fig. 9)")
    ax1.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=2, frameon=False)
    for i in range(1, 4):
        ax2.plot(days, crlb.in_plane[i] / crlb.in_plane[0], "o-", ms=3, lw=1, color=f"C{i}", label=OBJECT_NAMES[i])
    ax2.axhline(1.0, color="0.4", lw=0.8, ls=":")
    ax2.set(xlabel="time [days]", ylabel="in-plane RMS, target / observer [-]",
            title="above 1: observer better determined")
    ax2.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=3, frameon=False)
    ax3.bar(days, crlb.gains, width=0.6)
    ax3.set(xlabel="time [days]", ylabel="information gain [nats]",
            title=r"per-measurement $\mathcal{I}_k$ (chain rule)")
    return fig


def figure_baseline(curves):
    """MI gain and terminal CRLB (in-plane and total) against the mean baseline, one colour per measurement type."""
    curves = validation.sequence_of(curves, "curves", BaselineCurve, "BaselineCurve")
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6))
    for k, c in enumerate(curves):
        b_km = c.baseline_km
        ax1.semilogx(b_km, c.mi - c.mi[0], "o-", color=f"C{k}", label=f"{c.name} (I at shortest = {c.mi[0]:.1f} nats)")
        # in-plane RMS: target first, as large open squares, so the observer's filled dots stay visible where they meet
        ax2.loglog(b_km, c.tgt_xy, "s", ms=9, mfc="none", mew=1.2, color=f"C{k}")
        ax2.loglog(b_km, c.obs_xy, "o-", ms=4, color=f"C{k}", zorder=3)
        ax2.loglog(b_km, c.obs, ":", lw=1.2, color=f"C{k}", zorder=2)  # observer's total RMS
    ax1.set(xlabel="mean baseline [km]", ylabel=r"$\mathcal{I} - \mathcal{I}_{shortest}$ [nats]",
            title="MI gain vs baseline")
    ax2.set(xlabel="mean baseline [km]", ylabel="terminal position RMS [km]",
            title="CRLB vs baseline (colours as left)")
    ax1.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), frameon=False)  # legends below the axes
    roles = [plt.Line2D([], [], marker="o", ms=4, color="0.3", label="observer, in-plane"),
             plt.Line2D([], [], marker="s", ms=9, mfc="none", ls="none", color="0.3", label="target, in-plane"),
             plt.Line2D([], [], ls=":", lw=1.2, color="0.3", label="observer, total (incl. out-of-plane)")]
    ax2.legend(handles=roles, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2, frameon=False)
    return fig


def figure_timing(timing: TimingStudy):
    """Time per evaluation against the number of measurement times, log-log."""
    validation.instance(timing, "timing", TimingStudy)
    sizes, res = list(timing.sizes), timing.results
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    ax.loglog(sizes, [1e3 * r.dense_value for r in res], "o-", label="dense Eq. 18")
    ax.loglog(sizes, [1e3 * r.structured_value for r in res], "s-", label="chain rule")
    ax.loglog(sizes, [1e3 * r.dense_gradient for r in res], "o--", label="dense Eq. 18 + Eqs. 47-50")
    ax.loglog(sizes, [1e3 * r.structured_gradient for r in res], "s--",
              label="chain rule + gradient (square-root reverse mode)")
    ax.set(xlabel="measurement times N [-]", ylabel="time per evaluation [ms]", title="Evaluation cost")
    ax.set_xticks(sizes, [str(n) for n in sizes])  # plain labels at the sizes run, no minor labels
    ax.xaxis.set_minor_formatter(plt.NullFormatter())
    ax.yaxis.set_major_locator(plt.LogLocator(subs=(1.0, 2.0, 5.0)))
    ax.yaxis.set_major_formatter(plt.FormatStrFormatter("%g"))
    ax.yaxis.set_minor_formatter(plt.NullFormatter())
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=2, frameon=False)  # below the axes
    return fig
