r"""Wolf & Jones test cases 1 and 2 as data, and the information model that SCvx maximises.

What is here:

* :func:`test_case_1`, :func:`test_case_2` build a :class:`Scenario` from the paper's Tables 2-5: the observer and
  target DROs (printed rows from ``data/wolf_jones_dros.csv``, each corrected into an exactly periodic orbit by
  :func:`cislunar.papers.wolf_jones.reference.verify_table_row`), the scenario length (two or three periods of the observer's initial
  DRO), the observation window (:math:`[3P/4, 3P/2]` or :math:`[P, 2P]`), the measurement model and its noise,
  the prior covariances, the process noise, :math:`a_{max}`, node times and per-node thrust bounds.
* :class:`WindowInformation`: the mutual information of the window (Eq. 18) as a function of the observer state
  at the window start, with its gradient (Eqs. 44-52, reverse mode of the square-root recursion) and a Hessian by
  central differences of the gradient, in the protocol of :func:`cislunar.guidance.scvx.solve_scvx` (``info(x, order)`` and ``info.hessian(x)``).
  Value and gradient describe **the same function**: the augmented process noise :math:`\tilde P`'s Q blocks are
  computed once along a reference (the ballistic guess) and held fixed, exactly what the paper's gradient assumes
  ("this formulation does not account for the sensitivity of the process noise covariance").
* :class:`MinimumRange`: a keep-out :math:`\|\mathbf r_{\mathcal S}(t_k) - \mathbf r^{(i)}_{\mathcal T}(t_k)\| \ge
  d_{min}` at every measurement time, linearised through the observer STM (the ``constraints`` protocol of SCvx).
* :func:`evaluate_crlb`: the CRLB (EKF covariance recursion along the true trajectories, process noise recomputed
  along them) with per-axis and RMS position errors, for Figs. 4, 5, 9 and 10.
* :class:`ScenarioSolver` (one SCvx solve per alpha_h, picklable), :func:`sweep_both_ways` (upward and downward
  warm-started homotopy chains, optionally in two processes, best cost kept per alpha_h),
  :func:`solve_for_impulse` (the plan of most information at a prescribed total impulse: a root-find on alpha_h
  along the weighted-sum Pareto front), :func:`fly` and
  :func:`terminal_miss_km` (single-shooting re-flight of a first-order-hold control).

Process-noise units (Tables 3 and 5)
------------------------------------
The tables print "Q [km/s^3] = 1e-11".  An acceleration PSD has units km^2/s^3; the candidate readings are
``PROCESS_NOISE_READINGS_KM2_S3``.  The CRLB of the ballistic (alpha_h = 0) observer of test case 1 grows without
bound over the window for 1e-11 km^2/s^3 (to ~3e4 km) and 1e-13 km^2/s^3, against the paper's statement that
"subsequent measurements serve to bound the expected error"; 1e-11 in the code's normalised units (LU^2/TU^3 =
2.80e-17 km^2/s^3), 1e-11 m^2/s^3 (1e-17 km^2/s^3) and the square-root reading (1e-22 km^2/s^3) all stay bounded.
We adopt the normalised reading, :data:`PROCESS_NOISE_PSD_ND` (notebook 06 shows the sensitivity).

:math:`a_{max}` of Table 5, printed "1x5^-7" km/s^2, is read as 5e-7 km/s^2 (:data:`A_MAX_CASE2_KM_S2`); the
literal :math:`5^{-7}` = 1.28e-5 km/s^2 would be 13 times test case 1's bound.

Minimum-range keep-out (test case 2)
------------------------------------
Range-rate Jacobians scale as :math:`1/\rho`, so the linear-Gaussian MI grows without bound as the observer
approaches a target at a measurement time: the optimiser would fly through a target.  The MI is only meaningful
where the measurement is close to linear over the prior relative-position uncertainty.  With 1-sigma
:math:`\sigma_p` = 100 km per axis for observer and target, the relative position has
:math:`\sigma_{rel} = \sqrt2\,\sigma_p` = 141 km per axis; the line-of-sight direction :math:`\hat\rho`, which
carries the range-rate sensitivity, is then uncertain by about :math:`\sigma_{rel}/\rho` rad.  Requiring the target
to lie outside the prior 3-sigma relative-position sphere (:math:`\sigma_{rel}/\rho \le 1/3`) gives
:math:`d_{min} = 3\sqrt2\,\sigma_p` = 424 km (:func:`keep_out_radius_km`).  The ballistic reference stays beyond
1500 km of every target inside the window, so the keep-out only removes the spurious close-approach optima.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, EARTH_MOON, check_system
from cislunar.cr3bp.propagation import propagate, propagate_stm
from cislunar.guidance.discretization import propagate_foh, sundman_nodes
from cislunar.guidance.scvx import (
    SCvxError,
    SCvxSettings,
    SCvxWorkspace,
    SweepResult,
    impulse,  # noqa: F401 - re-exported: the trapezoid impulse of Eq. 42 has one home (scvx)
    solve_scvx,
)
from cislunar.papers.wolf_jones import _checks
from cislunar.papers.wolf_jones.reference import load_wolf_jones_table, verify_table_row
from cislunar.sensing import covariance as cov
from cislunar.sensing import information as info
from cislunar.sensing import measurements as meas
from cislunar.utils import validation

__all__ = [
    "PROCESS_NOISE_PSD_ND",
    "PROCESS_NOISE_READINGS_KM2_S3",
    "A_MAX_CASE1_KM_S2",
    "A_MAX_CASE2_KM_S2",
    "A_MAX_READINGS_CASE2_KM_S2",
    "SIGMA_POS_KM",
    "SIGMA_VEL_KM_S",
    "KEEP_OUT_SIGMAS",
    "keep_out_radius_km",
    "Scenario",
    "test_case_1",
    "test_case_2",
    "WindowInformation",
    "MinimumRange",
    "CRLBResult",
    "evaluate_crlb",
    "impulse",
    "node_times_with_window",
    "CONTROL_UNITS",
    "CONTROL_AVERAGES",
    "control_scale",
    "ScenarioSolver",
    "sweep_both_ways",
    "ImpulseBudgetError",
    "ImpulseSolve",
    "solve_for_impulse",
    "fly",
    "terminal_miss_km",
]

#: Process-noise PSD adopted for Tables 3 and 5: 1e-11 in LU^2/TU^3 (see the module docstring).
PROCESS_NOISE_PSD_ND = 1e-11
#: Candidate readings of Table 3's "Q [km/s^3] = 1e-11", converted to km^2/s^3 (the nondimensional reading uses
#: the Earth-Moon units of :data:`cislunar.cr3bp.dynamics.EARTH_MOON`).
PROCESS_NOISE_READINGS_KM2_S3 = {
    "1e-11 km^2/s^3 (unit label missing a square)": 1e-11,
    "1e-11 LU^2/TU^3 (normalised units, adopted)": 1e-11 * EARTH_MOON.length_unit_km**2 / EARTH_MOON.time_unit_s**3,
    "1e-11 m^2/s^3 (SI value, km label)": 1e-17,
    "(1e-11)^2 km^2/s^3 (value is a sqrt-PSD)": 1e-22,
}
#: Table 3 maximum thrust acceleration, km/s^2.
A_MAX_CASE1_KM_S2 = 1e-6
#: Table 5 maximum thrust acceleration ("1x5^-7" read as 5e-7), km/s^2.
A_MAX_CASE2_KM_S2 = 5e-7
#: Candidate readings of Table 5's "1x5^-7", km/s^2.
A_MAX_READINGS_CASE2_KM_S2 = {"5x10^-7 (adopted)": 5e-7, "1x10^-7": 1e-7, "literal 5^-7": 5.0**-7}
#: Tables 3 and 5: initial 1-sigma position (km) and velocity (km/s) per axis, every object.
SIGMA_POS_KM = 100.0
SIGMA_VEL_KM_S = 1e-2
#: Keep-out radius in prior relative-position standard deviations.
KEEP_OUT_SIGMAS = 3.0


def keep_out_radius_km(sigma_pos_km: float = SIGMA_POS_KM, n_sigma: float = KEEP_OUT_SIGMAS) -> float:
    """:math:`d_{min} = n_\\sigma\\sqrt2\\,\\sigma_p` (km): the target outside the prior n-sigma relative-position
    sphere."""
    s = validation.positive(sigma_pos_km, "sigma_pos_km")
    k = validation.positive(n_sigma, "n_sigma")
    return float(k * np.sqrt(2.0) * s)


def node_times_with_window(t_nodes, window) -> tuple[np.ndarray, int, int]:
    """Move the interior nodes nearest to the window ends onto them.

    Parameters
    ----------
    t_nodes : array_like (N,)
        Strictly increasing node times (e.g. Sundman nodes), TU.
    window : (float, float)
        Start and end of the observation window, inside ``(t_nodes[0], t_nodes[-1])``.

    Returns
    -------
    t : ndarray (N,)
        Node times with ``t[k_start] = window[0]`` and ``t[k_end] = window[1]``.
    k_start, k_end : int
    """
    t = validation.time_grid(t_nodes, "t_nodes", increasing=True).copy()
    ws, we = validation.as_array(window, "window", shape=(2,))
    if not t[0] < ws < we < t[-1]:
        raise ValueError(f"window must satisfy t0 < start < end < tf; got {window} for [{t[0]}, {t[-1]}]")
    if t.size < 4:
        raise ValueError(f"need at least 4 nodes (n_nodes) to place both window ends; got {t.size}")
    out = []
    for b in (ws, we):
        free = np.ones(t.size, bool)
        free[[0, -1]] = False
        for k in out:
            free[k] = False
        idx = np.flatnonzero(free)
        k = int(idx[np.argmin(np.abs(t[idx] - b))])
        t[k] = b
        out.append(k)
    if not np.all(np.diff(t) > 0):
        raise ValueError("too few nodes to place both window ends: increase n_nodes")
    return t, out[0], out[1]


@dataclass(frozen=True)
class Scenario:
    """One Wolf & Jones test case (all states non-dimensional, Earth-Moon rotating frame, barycentric).

    Attributes
    ----------
    number : int
        1 or 2.
    system : CR3BP
    observer_x0 : ndarray (6,)
        Observer initial state: the printed Table 2/4 row corrected into a periodic DRO (``x0`` held).
    observer_x0_printed : ndarray (6,)
        The row as printed (not periodic: its ``vy0`` is off by 0.027 LU/TU).
    observer_xf : ndarray (6,)
        Terminal state :math:`x_{\\mathcal S}(t_f)` as printed (it closes as a DRO to 2e-8).
    targets_x0 : ndarray (N_T, 6)
        Target initial states (corrected rows; the printed ones close to ~1e-8).
    period : float
        :math:`P_{ref}`, period of the observer's initial DRO, TU.
    n_periods : int
        Scenario length in periods.
    window_fraction : (float, float)
        Observation window in units of :math:`P_{ref}`.
    model : MeasurementModel
    noise : ndarray (m, m)
        Measurement noise covariance of one target (non-dimensional).
    q : float
        Acceleration PSD of every object, LU^2/TU^3.
    a_max : float
        Maximum thrust acceleration, LU/TU^2.
    sigma_pos_km, sigma_vel_km_s : float
        Prior 1-sigma per axis of every object.
    row_checks : dict
        :class:`cislunar.papers.wolf_jones.reference.RowCheck` of each printed row used (label -> check).
    """

    number: int
    system: CR3BP
    observer_x0: np.ndarray
    observer_x0_printed: np.ndarray
    observer_xf: np.ndarray
    targets_x0: np.ndarray
    period: float
    n_periods: int
    window_fraction: tuple
    model: meas.MeasurementModel
    noise: np.ndarray
    q: float
    a_max: float
    sigma_pos_km: float = SIGMA_POS_KM
    sigma_vel_km_s: float = SIGMA_VEL_KM_S
    row_checks: dict = field(default_factory=dict, repr=False)

    # ---------------------------------------------------------------- derived quantities
    @property
    def n_targets(self) -> int:
        return int(self.targets_x0.shape[0])

    @property
    def duration(self) -> float:
        """Scenario length :math:`t_f`, TU."""
        return self.n_periods * self.period

    @property
    def window(self) -> tuple[float, float]:
        """Observation window (start, end), TU."""
        return self.window_fraction[0] * self.period, self.window_fraction[1] * self.period

    @property
    def measurement_times(self) -> np.ndarray:
        """Daily measurement times from the window start to its end (inclusive when it falls on a day), TU."""
        ws, we = self.window
        day = float(self.system.days_to_tu(1.0))
        return ws + np.arange(0.0, we - ws + 1e-9, day)

    @property
    def prior_covariance(self) -> np.ndarray:
        """Augmented :math:`P_{\\mathcal A,0}` at the window start (diagonal, Tables 3 and 5)."""
        P = cov.state_covariance(self.sigma_pos_km, self.sigma_vel_km_s, self.system)
        return cov.block_diag([P] * (self.n_targets + 1))

    @property
    def keep_out_km(self) -> float:
        """Keep-out radius from the prior (:func:`keep_out_radius_km`), km."""
        return keep_out_radius_km(self.sigma_pos_km)

    def targets_at(self, t) -> np.ndarray:
        """Target states at times ``t`` (TU, from 0), shape (N_T, len(t), 6)."""

        t = np.atleast_1d(validation.as_array(t, "t", ndim=(0, 1)))
        if t.size == 0 or t[0] < 0 or np.any(np.diff(t) <= 0):
            raise ValueError("t must hold one or more non-negative, strictly increasing times (TU)")
        grid = np.r_[0.0, t] if t[0] > 0 else t
        x = propagate(self.system, self.targets_x0, grid).x
        return x[:, 1:] if t[0] > 0 else x

    # ---------------------------------------------------------------- nodes, bounds, guesses
    def node_times(self, n_nodes: int, sigma: float = 1.0) -> tuple[np.ndarray, int, int]:
        """Sundman-spaced nodes (Eqs. 37-39) along the ballistic observer, window ends moved onto nodes.

        Returns ``(t_nodes, k_window_start, k_window_end)``.
        """

        n = validation.integer(n_nodes, "n_nodes", minimum=4)
        s = validation.real(sigma, "sigma")
        t, _ = sundman_nodes(self.system, self.observer_x0, self.duration, n, s)
        return node_times_with_window(t, self.window)

    def control_bounds(self, t_nodes) -> np.ndarray:
        """Per-node acceleration bound (LU/TU^2): :math:`a_{max}` outside the window and 0 inside it (ends included).

        The node controls are accelerations with first-order hold, so the trapezoid form of Eqs. 40-41,
        :math:`(u_{max,k}+u_{max,k+1})/2 = a_{max}`, holds with the uniform bound; see notebook 04 for the printed
        (impulse-unit) reading of Eq. 41.
        """
        t = validation.time_grid(t_nodes, "t_nodes", increasing=True)
        ws, we = self.window
        u = np.full(t.size, self.a_max)
        u[(t >= ws - 1e-12) & (t <= we + 1e-12)] = 0.0
        return u

    def ballistic_guess(self, t_nodes) -> tuple[np.ndarray, np.ndarray]:
        """The observer coasting on its initial DRO: ``(x (N, 6), u (N, 3) zeros)``."""

        t = validation.time_grid(t_nodes, "t_nodes", increasing=True)
        return propagate(self.system, self.observer_x0, t).x, np.zeros((t.size, 3))

    def seeded_guess(self, t_nodes, z_sign: float, fraction: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
        """A guess pushed out of the plane: :math:`u_z = \\pm` ``fraction`` :math:`a_{max}` before the window, flown.

        The planar guess is a saddle of the MI in z (its z-gradient vanishes by symmetry), so SCvx started there
        stays planar; +z and -z seeds break the symmetry in opposite directions (Fig. 7's mirror question).
        """

        t = validation.time_grid(t_nodes, "t_nodes", increasing=True)
        s = float(np.sign(validation.real(z_sign, "z_sign"))) or 1.0
        f = validation.in_range(fraction, "fraction", 0.0, 1.0)
        u = np.zeros((t.size, 3))
        u[t < self.window[0] - 1e-12, 2] = s * f * self.a_max
        return propagate_foh(self.system, self.observer_x0, t, u), u

    # ---------------------------------------------------------------- information and constraints
    def information_model(self, x_reference=None, *, q: float | None = None) -> "WindowInformation":
        """:class:`WindowInformation` of this window, process noise fixed along ``x_reference``.

        ``x_reference`` (6,) is the observer state at the window start used for the observer's Q blocks
        (default: the ballistic guess's).  ``q`` overrides the scenario PSD (sensitivity studies).
        """

        if x_reference is None:
            x_reference = propagate(self.system, self.observer_x0, [0.0, self.window[0]]).x[-1]
        x_reference = validation.as_state(x_reference, "x_reference", batch=False)
        q = self.q if q is None else validation.positive(q, "q", allow_zero=True)
        targets = self.targets_at([self.window[0]])[:, 0]
        return WindowInformation(self.system, self.measurement_times, targets, self.model, self.noise,
                                 self.prior_covariance, q=q, x_reference=x_reference)

    def keep_out(self, node: int, d_min_km: float | None = None) -> "MinimumRange":
        """:class:`MinimumRange` for the window starting at node ``node`` (default radius: :attr:`keep_out_km`)."""
        node = validation.integer(node, "node", minimum=0)
        d = self.keep_out_km if d_min_km is None else validation.positive(d_min_km, "d_min_km")
        targets = self.targets_at([self.window[0]])[:, 0]
        return MinimumRange(self.system, self.measurement_times, targets, self.system.km_to_lu(d), node)


def _corrected_rows(system: CR3BP, table: int) -> dict:

    return {r.label: verify_table_row(system, r) for r in load_wolf_jones_table() if r.table == table}


def _build(number, system, q, a_max_km_s2, table, target_labels, n_periods, window, model, noise):
    rows = _corrected_rows(system, table)
    obs = rows["observer_t0"]
    return Scenario(
        number=number, system=system, observer_x0=obs.corrected.x0.copy(),
        observer_x0_printed=np.array([obs.x0, 0, 0, 0, obs.vy0, 0.0]),
        observer_xf=np.array([rows["observer_tf"].x0, 0, 0, 0, rows["observer_tf"].vy0, 0.0]),
        targets_x0=np.array([rows[lab].corrected.x0 for lab in target_labels]), period=float(obs.corrected.period),
        n_periods=n_periods, window_fraction=window, model=model, noise=noise,
        q=validation.positive(q, "q", allow_zero=True),
        a_max=validation.positive(a_max_km_s2, "a_max_km_s2", allow_zero=True) / system.acceleration_unit_km_s2,
        row_checks=rows)


def test_case_1(system: CR3BP = EARTH_MOON, *, q: float = PROCESS_NOISE_PSD_ND,
                a_max_km_s2: float = A_MAX_CASE1_KM_S2) -> Scenario:
    """Test case 1 (Tables 2-3): one target, relative position at 100 m per axis, two periods, window [3P/4, 3P/2].

    ``q`` is the acceleration PSD in LU^2/TU^3 (default: the adopted reading of Table 3).
    """
    check_system(system, "system")
    q = validation.positive(q, "q", allow_zero=True)
    a_max_km_s2 = validation.positive(a_max_km_s2, "a_max_km_s2", allow_zero=True)
    noise = meas.relative_position_noise(meas.WOLF_JONES_RELPOS_SIGMA_KM, system)
    return _build(1, system, q, a_max_km_s2, 2, ["target1_t0"], 2, (0.75, 1.5), meas.RELATIVE_POSITION, noise)


test_case_1.__test__ = False  # not a pytest test despite the name


def test_case_2(system: CR3BP = EARTH_MOON, *, q: float = PROCESS_NOISE_PSD_ND,
                a_max_km_s2: float = A_MAX_CASE2_KM_S2) -> Scenario:
    """Test case 2 (Tables 4-5): three targets, range and range rate (100 m, 10 m/s), three periods, window [P, 2P].

    Table 4's row labels are lost except the last; they are read as in Table 2 (``data/wolf_jones_dros.csv``).
    """
    check_system(system, "system")
    q = validation.positive(q, "q", allow_zero=True)
    a_max_km_s2 = validation.positive(a_max_km_s2, "a_max_km_s2", allow_zero=True)
    noise = meas.range_range_rate_noise(meas.WOLF_JONES_RANGE_SIGMA_KM, meas.WOLF_JONES_RANGE_RATE_SIGMA_KM_S,
                                        system)
    return _build(2, system, q, a_max_km_s2, 4, ["target1_t0", "target2_t0", "target3_t0"], 3, (1.0, 2.0),
                  meas.RANGE_RANGE_RATE, noise)


test_case_2.__test__ = False


# --------------------------------------------------------------------------------------------------------------
# the information model (scvx protocol)
# --------------------------------------------------------------------------------------------------------------
class WindowInformation:
    """Mutual information of one observation window as a function of the observer state at its start.

    Implements the protocol of :func:`cislunar.guidance.scvx.solve_scvx`: ``model(x, 0) -> I`` (nats),
    ``model(x, 1) -> (I, dI/dx)`` and ``model.hessian(x) -> (6, 6)``.  The observer coasts through the window
    (zero thrust there), so every observer state in it is a function of ``x``.

    Parameters
    ----------
    system : CR3BP
    t : array_like (N,)
        Measurement times, TU; ``t[0]`` is the window start.
    targets_x0 : array_like (N_T, 6)
        Target states at ``t[0]``.
    model : MeasurementModel
    noise : array_like (m, m)
        Measurement noise of one target (non-dimensional).
    P0 : array_like (n, n)
        Augmented prior at ``t[0]``.
    q : float
        Acceleration PSD (LU^2/TU^3) used to compute the fixed process noise.
    x_reference : array_like (6,)
        Observer state at ``t[0]`` along which the observer's Q blocks are computed once and then held fixed
        (the targets' blocks are exact: the targets do not depend on ``x``).
    hessian_step : float
        Finite-difference step of :meth:`hessian` (non-dimensional, all six components).
    hessian_scheme : {"forward", "central"}

    Notes
    -----
    The targets are propagated once; each call propagates only the observer (with its STT for ``order=1``).
    The window's fixed ingredients (measurement model and noise, P0, target arcs, the fixed Q, and the P0, Q, R of
    Eq. 18 with R's Cholesky factors and Q's square roots) are checked once, at construction
    (:class:`cislunar.sensing.covariance.WindowAssembler`, :class:`cislunar.sensing.information.InformationKernel`);
    values and gradients are bit-for-bit those of the public ``assemble_augmented`` and
    ``mutual_information[_gradient]``.  The last few linearisations and Hessians are cached by the bytes of ``x``
    (SCvx asks for value, gradient and Hessian at the same point; the upward and downward sweeps start from the
    same guess).
    """

    def __init__(self, system: CR3BP, t, targets_x0, model, noise, P0, *, q: float, x_reference,
                 hessian_step: float = 1e-6, hessian_scheme: str = "central"):
        if not isinstance(system, CR3BP):
            raise ValueError(f"system must be a CR3BP; got {type(system).__name__}")
        if not isinstance(model, meas.MeasurementModel):
            raise ValueError(f"model must be a MeasurementModel; got {type(model).__name__}")
        self.system = system
        self.t = validation.time_grid(t, "t", increasing=True)
        xt = validation.as_array(targets_x0, "targets_x0", last=6)
        self.targets_x0 = xt[None] if xt.ndim == 1 else xt
        self.model = model
        self.noise = cov.check_spd(validation.as_array(noise, "noise", shape=(model.dim, model.dim)), "noise")
        n = 6 * (self.targets_x0.shape[0] + 1)
        self.P0 = cov.check_spd(validation.as_array(P0, "P0", shape=(n, n)), "P0")
        self.q = validation.positive(q, "q", allow_zero=True)
        self.x_reference = validation.as_state(x_reference, "x_reference", batch=False).copy()
        self.hessian_step = validation.positive(hessian_step, "hessian_step")
        if hessian_scheme not in ("forward", "central"):
            raise ValueError(f"hessian_scheme must be 'forward' or 'central'; got {hessian_scheme!r}")
        self.hessian_scheme = hessian_scheme
        self._targets = cov.propagate_arcs(system, self.targets_x0, self.t, q=self.q)
        ref = cov.propagate_arcs(system, self.x_reference, self.t, q=self.q)
        self.Q = cov.block_diag(np.moveaxis(np.concatenate([ref.Q, self._targets.Q], axis=0), 0, 1))
        # the window's fixed ingredients (model, noise, P0, target arcs, Q; and P0, Q, R of Eq. 18) are checked
        # once here; each evaluation checks only what depends on x (bit-for-bit the values of the public
        # assemble_augmented and mutual_information[_gradient], which re-check them on every call)
        self._assemble = cov.WindowAssembler(self.model, self.noise, self.P0, self._targets, Q=self.Q)
        lin = self._assemble(ref)
        self._kernel = info.InformationKernel(lin.P0, lin.Q, lin.R, self.t.size)
        self._cache: dict = {}
        self._hessians: dict = {}

    # ---------------------------------------------------------------- linearisations
    def linearization(self, x, derivatives: bool = False) -> cov.AugmentedLinearization:
        """The augmented linearisation (fixed Q) for observer state ``x`` (6,) at the window start."""
        x = validation.as_state(x, "x", batch=False)
        key = (x.tobytes(), validation.boolean(derivatives, "derivatives"))
        if key in self._cache:
            return self._cache[key]
        arcs = cov.propagate_arcs(self.system, x, self.t, order=2 if derivatives else 1)
        lin = self._assemble(arcs)
        if len(self._cache) >= 8:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = lin
        return lin

    def __call__(self, x, order: int = 0):
        """``order=0``: MI (nats); ``order=1``: (MI, gradient (6,)) in nats per LU and per LU/TU."""
        order = validation.integer(order, "order", minimum=0, maximum=1)
        if order == 0:
            lin = self.linearization(x)
            return self._kernel.value(lin.F, lin.H)
        lin = self.linearization(x, derivatives=True)
        value, grad = self._kernel.value_gradient(lin.F, lin.H, lin.dF, lin.dH)
        return float(value), grad

    def hessian(self, x) -> np.ndarray:
        """Symmetrised finite differences of the (square-root, reverse-mode) gradient, (6, 6), nats per unit^2.

        ``hessian_scheme="central"`` (default) uses twelve perturbed observers (error O(h^2)); ``"forward"`` six
        plus the gradient at ``x`` (error O(h), half the cost, but on test case 2 its error made SCvx creep: the
        MI is log-like in the out-of-plane amplitude, with curvature up to 1e12 nats/LU^2 at the plane).  The
        perturbed observers are propagated in one batch (heyoka batch mode).
        """
        x = validation.as_state(x, "x", batch=False)
        key = x.tobytes()
        if key in self._hessians:  # e.g. the up and down sweeps both start from the ballistic guess
            return self._hessians[key].copy()
        h = self.hessian_step
        central = self.hessian_scheme == "central"
        X0 = np.concatenate([x + h * np.eye(6), x - h * np.eye(6)], axis=0) if central else x + h * np.eye(6)
        arcs = cov.propagate_arcs(self.system, X0, self.t, order=2)
        G = np.empty((X0.shape[0], 6))
        for j in range(X0.shape[0]):
            lin = self._assemble(arcs, j)
            G[j] = self._kernel.value_gradient(lin.F, lin.H, lin.dF, lin.dH)[1]
        if central:
            Hm = (G[:6] - G[6:]).T / (2.0 * h)  # column i: d grad / d x_i
        else:
            Hm = (G - self(x, 1)[1]).T / h
        Hs = 0.5 * (Hm + Hm.T)
        if len(self._hessians) >= 4:
            self._hessians.pop(next(iter(self._hessians)))
        self._hessians[key] = Hs
        return Hs.copy()

    def concave_model(self, x) -> tuple[float, np.ndarray, np.ndarray]:
        """``(I, g, H_-)``: value, gradient and the concave part of the Hessian (eigenvalues clipped to <= 0).

        :math:`\\mathcal I(x+\\delta) \\approx \\mathcal I + g^T\\delta + \\tfrac12\\delta^TH_-\\delta` is concave, so
        :math:`-\\alpha_h` times it is a convex cost model.
        """
        value, grad = self(x, 1)
        w, V = np.linalg.eigh(self.hessian(x))
        return value, grad, (V * np.minimum(w, 0.0)) @ V.T


# --------------------------------------------------------------------------------------------------------------
# minimum-range keep-out (scvx constraints protocol)
# --------------------------------------------------------------------------------------------------------------
class MinimumRange:
    """Keep-out :math:`c_{ik}(x) = d_{min} - \\|\\mathbf r_{\\mathcal S}(t_k; x) - \\mathbf r^{(i)}_{\\mathcal T}(t_k)\\|
    \\le 0` at every measurement time, as a function of the observer state ``x`` at the window start.

    The Jacobian is :math:`-\\hat\\rho_{ik}^T\\,\\Phi_{\\mathcal S}(t_k, t_0)_{r,:}`; SCvx's linearisation
    :math:`c + C\\delta x \\le s` is, in the observer's position at :math:`t_k`, the half-space tangent to the
    keep-out sphere (a conservative convexification there), mapped to the window-start state through the STM.

    Attributes
    ----------
    node : int
        Index (into SCvx's node times) of the window start.
    size : int
        N_T times the number of measurement times.
    d_min : float
        Radius, LU.
    """

    def __init__(self, system: CR3BP, t, targets_x0, d_min: float, node: int):

        if not isinstance(system, CR3BP):
            raise ValueError(f"system must be a CR3BP; got {type(system).__name__}")
        self.system = system
        self.t = validation.time_grid(t, "t", increasing=True)
        xt = validation.as_array(targets_x0, "targets_x0", last=6)
        xt = xt[None] if xt.ndim == 1 else xt
        self.d_min = validation.positive(d_min, "d_min")
        self.node = validation.integer(node, "node", minimum=0)
        tr = propagate(system, xt, self.t).x
        self.target_positions = (tr if tr.ndim == 3 else tr[None])[:, :, :3]  # (N_T, N, 3)
        self.size = int(self.target_positions.shape[0] * self.t.size)

    def ranges(self, x) -> np.ndarray:
        """Observer-target ranges (N_T, N), LU."""

        r = propagate(self.system, validation.as_state(x, "x", batch=False), self.t).x[:, :3]
        return np.linalg.norm(r[None] - self.target_positions, axis=-1)

    def __call__(self, x):
        """``(c (size,), C (size, 6))``: constraint values (<= 0 required) and their Jacobian w.r.t. ``x``."""

        x = validation.as_state(x, "x", batch=False)
        tr = propagate_stm(self.system, x, self.t)
        rel = tr.x[None, :, :3] - self.target_positions  # (N_T, N, 3): observer minus target
        rho = np.linalg.norm(rel, axis=-1)
        c = self.d_min - rho
        C = -np.einsum("ika,kab->ikb", rel / rho[..., None], tr.stm[:, :3, :])
        return c.reshape(-1), C.reshape(-1, 6)


# --------------------------------------------------------------------------------------------------------------
# performance evaluation (CRLB)
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class CRLBResult:
    """CRLB over the observation window (EKF covariance recursion along the true trajectories).

    Attributes
    ----------
    t : ndarray (N,)
        Measurement times, TU.
    sigma_axes_km : ndarray (N_T + 1, N, 3)
        Posterior 1-sigma per position axis (x, y, z), km; object 0 is the observer.
    rms_km : ndarray (N_T + 1, N)
        Posterior position RMS :math:`\\sqrt{\\mathrm{tr}P_{rr}}`, km.
    mutual_information : float
        Eq. 18 with the process noise computed along the same trajectories, nats.
    """

    t: np.ndarray
    sigma_axes_km: np.ndarray
    rms_km: np.ndarray
    mutual_information: float

    @property
    def terminal_rms_km(self) -> np.ndarray:
        """Position RMS of each object after the last measurement of the window (Figs. 5 and 10), km."""
        return self.rms_km[:, -1]


def evaluate_crlb(scenario: Scenario, x_window_start, *, q: float | None = None) -> CRLBResult:
    """CRLB of observer and targets over the window for an observer at ``x_window_start`` (6,) at its start.

    The process noise is recomputed along the actual trajectories (this is the performance evaluation of the
    paper's "Performance Evaluation" section, not the planning model); ``q`` overrides the scenario PSD.
    """
    if not isinstance(scenario, Scenario):
        raise ValueError(f"scenario must be a Scenario; got {type(scenario).__name__}")
    x = validation.as_state(x_window_start, "x_window_start", batch=False)
    sysm = scenario.system
    t = scenario.measurement_times
    targets = scenario.targets_at([t[0]])[:, 0]
    lin = cov.linearize_augmented(sysm, x, targets, t, scenario.model, scenario.noise, scenario.prior_covariance,
                                  q=scenario.q if q is None else validation.positive(q, "q", allow_zero=True))
    hist = cov.covariance_analysis(*lin.arrays)
    n_obj = scenario.n_targets + 1
    diag = np.diagonal(hist.posterior, axis1=-2, axis2=-1)  # (N, n)
    sig = np.stack([np.sqrt(diag[:, 6 * i:6 * i + 3]) for i in range(n_obj)]) * sysm.length_unit_km
    rms = np.sqrt(np.sum(sig**2, axis=-1))
    return CRLBResult(t=t, sigma_axes_km=sig, rms_km=rms, mutual_information=info.mutual_information(*lin.arrays))


# --------------------------------------------------------------------------------------------------------------
# solving: one alpha, homotopy sweeps (optionally in parallel), re-flight
# --------------------------------------------------------------------------------------------------------------
#: Units in which the control term of Eq. 42 may be measured (the paper does not say): the non-dimensional
#: velocity unit (adopted), km/s or m/s.
CONTROL_UNITS = ("LU/TU", "km/s", "m/s")
#: What the control term of Eq. 42 may be (the paper does not say): the total trapezoid impulse (adopted), its
#: average per node (total / N) or per day of the scenario (total / duration in days).
CONTROL_AVERAGES = ("total", "node", "day")


def control_scale(scenario: Scenario, t_nodes, *, unit: str = "LU/TU", average: str = "total") -> float:
    """Factor :math:`c` of a reading of Eq. 42's control term: :math:`c\times` the total impulse in LU/TU.

    Parameters
    ----------
    scenario : Scenario
        Supplies the velocity unit and, for ``average="day"``, the duration :attr:`Scenario.duration`.
    t_nodes : array_like (N,)
        Node times, TU (``average="node"`` divides by N).
    unit : {"LU/TU", "km/s", "m/s"}
        Unit of the impulse (:data:`CONTROL_UNITS`).
    average : {"total", "node", "day"}
        Total impulse, impulse per node, or impulse per day of the scenario (:data:`CONTROL_AVERAGES`).

    Returns
    -------
    float
        :math:`c` (1.0 exactly for the adopted reading ``("LU/TU", "total")``).
    """
    if not isinstance(scenario, Scenario):
        raise ValueError(f"scenario must be a Scenario; got {type(scenario).__name__}")
    t = validation.time_grid(t_nodes, "t_nodes", increasing=True)
    unit = validation.choice(unit, "unit", CONTROL_UNITS)
    average = validation.choice(average, "average", CONTROL_AVERAGES)
    return _control_scale(scenario, t.size, unit, average)


def _control_scale(scenario: Scenario, n_nodes: int, unit: str, average: str) -> float:

    vu = scenario.system.velocity_unit_km_s
    c = {"LU/TU": 1.0, "km/s": vu, "m/s": vu * 1e3}[unit]
    if average == "node":
        c = c / n_nodes
    elif average == "day":
        c = c / float(scenario.system.tu_to_days(scenario.duration))
    return float(c)


class _ScaledInformation:
    """``info / c`` in the ``info(x, order)`` / ``info.hessian(x)`` protocol of SCvx (picklable)."""

    def __init__(self, information, scale: float):
        self.information = information
        self.scale = scale

    def __call__(self, x, order: int = 0):
        if order == 0:
            return self.information(x, 0) / self.scale
        value, grad = self.information(x, 1)
        return value / self.scale, grad / self.scale

    def hessian(self, x):
        return self.information.hessian(x) / self.scale


class ScenarioSolver:
    """``solver(alpha, x_guess, u_guess) -> SCvxResult`` for one scenario and node grid (picklable, for
    :func:`cislunar.guidance.scvx.homotopy_sweep` and process pools).

    Parameters
    ----------
    scenario : Scenario
    t_nodes : array_like (N,)
        Node times with the window ends on nodes (:meth:`Scenario.node_times`).
    k_window : int
        Index of the window-start node.
    information : WindowInformation, optional
        Default: :meth:`Scenario.information_model` (process noise fixed along the ballistic window arc).
    keep_out : bool
        Impose :meth:`Scenario.keep_out` (test case 2).
    d_min_km : float, optional
        Keep-out radius, km (default :attr:`Scenario.keep_out_km`; used with ``keep_out=True``).
    settings : cislunar.guidance.scvx.SCvxSettings, optional
    control_unit : {"LU/TU", "km/s", "m/s"}
        Unit of the control term of Eq. 42 (keyword-only; default: LU/TU, as before).
    control_average : {"total", "node", "day"}
        Total impulse, or its average per node or per day (keyword-only; default: total, as before).

    Notes
    -----
    The paper does not say how Eq. 42's control term is normalised.  With :math:`c` =
    :func:`control_scale` of the two options the solver minimises :math:`\\mathcal J_c = (1-\\alpha_h)\\,c\\,
    \\mathrm{impulse} - \\alpha_h\\mathcal I` (impulse in LU/TU, :math:`\\mathcal I` in nats).  SCvx is run on
    :math:`\\mathcal J_c / c` (the information model divided by :math:`c`; same minimisers), and the returned result
    carries ``cost`` = :math:`\\mathcal J_c` and ``information`` in nats (:meth:`cost`); its ``history`` is in the
    units of :math:`\\mathcal J_c / c`.  With the default (:math:`c = 1`) the solve is the unscaled one, bit for bit.
    """

    def __init__(self, scenario: Scenario, t_nodes, k_window: int, *, information=None, keep_out: bool = False,
                 d_min_km: float | None = None, settings=None, control_unit: str = "LU/TU",
                 control_average: str = "total"):
        if not isinstance(scenario, Scenario):
            raise ValueError(f"scenario must be a Scenario; got {type(scenario).__name__}")
        self.scenario = scenario
        self.t = validation.time_grid(t_nodes, "t_nodes", increasing=True)
        self.k_window = validation.integer(k_window, "k_window", minimum=1, maximum=self.t.size - 2)
        if not np.isclose(self.t[self.k_window], scenario.window[0]):
            raise ValueError(f"k_window must index the window-start node; got {k_window}")
        self.information = (scenario.information_model() if information is None
                            else validation.callable_(information, "information"))
        d_min = None if d_min_km is None else validation.positive(d_min_km, "d_min_km")
        self.constraints = ((scenario.keep_out(self.k_window, d_min),) if validation.boolean(keep_out, "keep_out")
                            else ())
        if settings is not None:

            validation.instance(settings, "settings", SCvxSettings)
        self.settings = settings
        self.u_max = scenario.control_bounds(self.t)
        self.control_unit = validation.choice(control_unit, "control_unit", CONTROL_UNITS)
        self.control_average = validation.choice(control_average, "control_average", CONTROL_AVERAGES)
        #: c of the control term: J_c = (1 - alpha) c impulse - alpha I (1.0 for the default reading)
        self.control_scale = _control_scale(scenario, self.t.size, self.control_unit, self.control_average)
        # every run of this solver has the same subproblem structure: canonicalised once per thread and process
        self.workspace = SCvxWorkspace()

    def cost(self, x, u, alpha: float) -> float:
        """:math:`\\mathcal J_c = (1-\\alpha_h)\\,c\\,\\mathrm{impulse}(u) - \\alpha_h\\mathcal I(x_{k^*})` of nodes
        ``x`` (N, 6) and ``u`` (N, 3) (the default reading's :math:`c = 1`; without information at
        :math:`\\alpha_h = 0`, as SCvx)."""
        x = validation.as_array(x, "x", shape=(self.t.size, 6))
        u = validation.as_array(u, "u", shape=(self.t.size, 3))
        a = validation.in_range(alpha, "alpha", 0.0, 1.0)
        control = (1.0 - a) * (self.control_scale * impulse(self.t, u))
        return float(control - a * self.information(x[self.k_window], 0)) if a > 0 else float(control)

    def __call__(self, alpha: float, x_guess, u_guess):

        sc = self.scenario
        c = self.control_scale
        info_model = self.information if c == 1.0 else _ScaledInformation(self.information, c)
        res = solve_scvx(sc.system, self.t, x_guess, u_guess, self.u_max, x_final=sc.observer_xf,
                         info=info_model, info_node=self.k_window, constraints=self.constraints,
                         alpha=float(alpha), settings=self.settings, workspace=self.workspace)
        if c == 1.0:
            return res
        return replace(res, cost=self.cost(res.x, res.u, alpha),
                       information=float(self.information(res.x[self.k_window], 0)))


def _chain(solver, alphas, x_guess, u_guess, direction):
    """One warm-started homotopy chain; a warm start that fails is retried from the cold guess."""

    order = range(len(alphas)) if direction == "up" else range(len(alphas) - 1, -1, -1)
    results = [None] * len(alphas)
    attempts = []
    guess, is_cold = (x_guess, u_guess), True
    for i in order:
        starts = [("cold", guess)] if is_cold else [("warm", guess), ("cold", (x_guess, u_guess))]
        for kind, g in starts:
            try:
                res = solver(float(alphas[i]), g[0], g[1])
            except SCvxError as exc:
                attempts.append(dict(alpha=float(alphas[i]), direction=direction, start=kind, converged=False,
                                     cost=np.nan, iterations=len(exc.history), error=exc.reason))
                continue
            attempts.append(dict(alpha=float(alphas[i]), direction=direction, start=kind, converged=True,
                                 cost=res.cost, iterations=res.iterations, error=""))
            results[i] = res
            guess, is_cold = (res.x, res.u), False
            break
    return results, attempts


def sweep_both_ways(solver: ScenarioSolver, alphas, x_guess, u_guess, *, executor=None,
                    directions=("up", "down")):
    """Upward and downward homotopy sweeps from the same guess, best cost kept per alpha.

    The upward chain starts at the smallest alpha, the downward at the largest, both from ``(x_guess,
    u_guess)``, each warm-started from its previous solution; a warm start that fails (:class:`SCvxError`) is
    retried from ``(x_guess, u_guess)`` (on test case 2 warm starts from a neighbouring optimum with an active
    keep-out sometimes creep where the cold start converges).  The two chains are independent, so an executor
    (``submit``) can run them side by side.  ``directions`` (a non-empty subset of ``("up", "down")``, run in
    that order) runs only some chains: ``("up",)`` is the cheaper one-way sweep of a quick run.

    Returns
    -------
    cislunar.guidance.scvx.SweepResult
        ``best``/``source`` merge the chains (``source`` is ``"up"`` or ``"down"``); ``attempts`` lists every run
        with its ``direction``, ``start`` (warm or cold), convergence, cost, iterations and error.
    """

    validation.callable_(solver, "solver")
    a = validation.as_array(alphas, "alphas", ndim=(1,))
    if a.size < 1 or np.any(np.diff(a) <= 0) or a[0] < 0 or a[-1] > 1:
        raise ValueError("alphas must be strictly increasing within [0, 1]")
    x_guess = validation.as_array(x_guess, "x_guess", ndim=(2,), last=6)
    u_guess = validation.as_array(u_guess, "u_guess", shape=(x_guess.shape[0], 3))
    directions = _checks.directions(directions, "directions")
    if executor is None:
        chains = [_chain(solver, a, x_guess, u_guess, d) for d in directions]
    else:
        if not callable(getattr(executor, "submit", None)):
            raise ValueError(f"executor must have a submit method; got {type(executor).__name__}")
        futs = [executor.submit(_chain, solver, a, x_guess, u_guess, d) for d in directions]
        chains = [f.result() for f in futs]
    best, source = [], []
    for i in range(a.size):
        cands = [(res[i], d) for (res, _), d in zip(chains, directions) if res[i] is not None]
        if not cands:
            best.append(None)
            source.append("")
            continue
        b, d = min(cands, key=lambda c: c[0].cost)
        best.append(b)
        source.append(d)
    return SweepResult(a, best, source, [att for _, atts in chains for att in atts])


class ImpulseBudgetError(RuntimeError):
    """:func:`solve_for_impulse` did not reach the budget (the front jumps across it, or a solve failed).

    Attributes
    ----------
    reason : str
    budget : float
        Requested total impulse, LU/TU.
    solves : list of (float, float)
        ``(alpha_h, impulse)`` of every converged solve, in order.
    """

    def __init__(self, reason: str, budget: float = float("nan"), solves=()):
        self.reason = str(reason)
        self.budget = float(budget)
        self.solves = [tuple(map(float, s)) for s in solves]
        super().__init__(f"{self.reason} (budget {self.budget:.6g} LU/TU; solves (alpha_h, impulse): "
                         f"{[(round(a, 8), round(i, 8)) for a, i in self.solves]})")

    def __reduce__(self):
        return (type(self), (self.reason, self.budget, self.solves))


@dataclass(frozen=True)
class ImpulseSolve:
    """A plan solved at a prescribed total impulse (:func:`solve_for_impulse`).

    Attributes
    ----------
    alpha : float
        Homotopy weight :math:`\\alpha_h` whose optimum spends the budget.
    result : cislunar.guidance.scvx.SCvxResult
        That optimum (``result.impulse`` within ``rtol`` of the budget).
    budget : float
        Requested total impulse, LU/TU.
    solves : list of (float, float)
        ``(alpha_h, impulse)`` of every solve made by the search.
    """

    alpha: float
    result: object
    budget: float
    solves: list


def solve_for_impulse(solver, budget: float, lower, upper, *, rtol: float = 0.02, max_solves: int = 8):
    """The maximum-information plan that spends a prescribed total impulse.

    SCvx has no impulse constraint, but the weighted-sum objective of Eq. 42 traces the Pareto front: the optimum
    of :math:`\\alpha_h` spends the least impulse for its information and gathers the most information for its
    impulse, and the impulse grows with :math:`\\alpha_h`.  Solving for the :math:`\\alpha_h` whose optimum spends
    ``budget`` therefore imposes the budget with the solver as it is.  The search is a bracketed secant (Illinois
    regula falsi) on :math:`\\alpha_h`, each solve warm-started from the bracketing solution nearer in impulse.

    Parameters
    ----------
    solver : callable
        ``solver(alpha, x_guess, u_guess) -> SCvxResult`` (e.g. :class:`ScenarioSolver`).
    budget : float
        Total impulse to spend (trapezoid of Eq. 42), LU/TU.
    lower, upper : (float, SCvxResult)
        Two converged solutions ``(alpha_h, result)`` bracketing the budget (``lower`` spends less, ``upper``
        more), e.g. neighbours on a homotopy sweep.
    rtol : float
        Accept when ``|impulse - budget| <= rtol * budget`` (fixed before solving; default 2 %).
    max_solves : int
        Largest number of solves.

    Returns
    -------
    ImpulseSolve

    Raises
    ------
    ImpulseBudgetError
        The budget was not reached within ``max_solves`` (e.g. the front jumps across it between local optima)
        or a solve failed; carries every ``(alpha_h, impulse)`` tried.
    ValueError, TypeError
        Bad arguments, or a bracket that does not contain the budget.
    """

    validation.callable_(solver, "solver")
    b = validation.positive(budget, "budget")
    tol = validation.in_range(rtol, "rtol", 0.0, 1.0, closed=False)
    n_max = validation.integer(max_solves, "max_solves", minimum=1)
    ends = []
    for name, end in (("lower", lower), ("upper", upper)):
        if not isinstance(end, (tuple, list)) or len(end) != 2 or not hasattr(end[1], "impulse"):
            raise validation.ArgumentTypeError(f"{name} must be a pair (alpha_h, SCvxResult); got "
                                            f"{type(end).__name__}")
        ends.append([validation.in_range(end[0], f"{name}[0] (alpha_h)", 0.0, 1.0), end[1]])
    (a_lo, r_lo), (a_hi, r_hi) = ends
    if not (a_lo < a_hi and r_lo.impulse <= b <= r_hi.impulse):
        raise ValueError(f"lower and upper must bracket the budget: alpha_h {a_lo:g} < {a_hi:g} and impulse "
                         f"{r_lo.impulse:.6g} <= budget {b:.6g} <= {r_hi.impulse:.6g} (LU/TU)")
    for a, r in ((a_lo, r_lo), (a_hi, r_hi)):
        if abs(r.impulse - b) <= tol * b:
            return ImpulseSolve(alpha=a, result=r, budget=b, solves=[(a, r.impulse)])
    f_lo, f_hi = r_lo.impulse - b, r_hi.impulse - b
    solves = []
    side = 0
    for _ in range(n_max):
        a = a_lo - f_lo * (a_hi - a_lo) / (f_hi - f_lo)
        a = min(max(a, a_lo + 1e-3 * (a_hi - a_lo)), a_hi - 1e-3 * (a_hi - a_lo))
        warm = r_lo if abs(f_lo) <= abs(f_hi) else r_hi
        try:
            res = solver(a, warm.x, warm.u)
        except SCvxError as exc:
            raise ImpulseBudgetError(f"the solve at alpha_h = {a:.6g} failed: {exc.reason}", b, solves) from exc
        solves.append((a, res.impulse))
        f = res.impulse - b
        if abs(f) <= tol * b:
            return ImpulseSolve(alpha=float(a), result=res, budget=b, solves=solves)
        if f < 0:
            a_lo, r_lo, f_lo = a, res, f
            if side == -1:
                f_hi /= 2.0  # Illinois: halve the stale end's weight
            side = -1
        else:
            a_hi, r_hi, f_hi = a, res, f
            if side == +1:
                f_lo /= 2.0
            side = +1
    raise ImpulseBudgetError(f"budget not reached within {n_max} solves (the front may jump across it)", b, solves)


def fly(scenario: Scenario, t_nodes, u_nodes, *, refine: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Single-shooting re-flight from :attr:`Scenario.observer_x0` with the first-order-hold control.

    The FOH control is linear between nodes, so interpolating it onto a grid refined ``refine`` times reproduces
    it exactly: the returned dense trajectory is the nonlinear flight of the converged control (for plots and the
    terminal miss).  Returns ``(t_fine, x_fine)``.
    """

    t = validation.time_grid(t_nodes, "t_nodes", increasing=True)
    u = validation.as_array(u_nodes, "u_nodes", shape=(t.size, 3))
    if not isinstance(scenario, Scenario):
        raise ValueError(f"scenario must be a Scenario; got {type(scenario).__name__}")
    r = validation.integer(refine, "refine", minimum=1)
    tf = np.concatenate([np.linspace(t[k], t[k + 1], r + 1)[:-1] for k in range(t.size - 1)] + [t[-1:]])
    uf = np.stack([np.interp(tf, t, u[:, i]) for i in range(3)], axis=1)
    return tf, propagate_foh(scenario.system, scenario.observer_x0, tf, uf)


def terminal_miss_km(scenario: Scenario, t_nodes, u_nodes) -> float:
    """Position miss (km) at :math:`t_f` of the single-shooting re-flight against :attr:`Scenario.observer_xf`."""
    _, x = fly(scenario, t_nodes, u_nodes, refine=1)
    return float(np.linalg.norm(x[-1, :3] - scenario.observer_xf[:3]) * scenario.system.length_unit_km)
